// The LODBAKE_progressive_fans mesh extension object: the PFRep blob of a pack's full-detail level
// and, for each level of the discrete chain, the PFRep level with a matching triangle budget.
// Schema and rules: schemas/LODBAKE_progressive_fans/README.md.
#include "lodbake/pfrep/pfrep_extension.h"

#include <algorithm>
#include <cmath>

#include "lodrt/format.h"


namespace lodbake {

namespace {

PfrepExtensionObject finishObject(PfrepBuild build, PfrepExtensionObject out) {
    JsonNode levels = JsonNode::array();
    for (const PfrepExtensionLevel& level : out.levels)
        levels.push(JsonNode::object().set("removals", uint64_t(level.removals)).set("triangles", level.triangles));
    out.json = JsonNode::object();
    out.json.set("levels", std::move(levels));
    out.json.set("removedCount", uint64_t(out.removed_count));
    out.json.set("triangleCount", out.triangle_count);
    out.json.set("vertexCount", uint64_t(out.vertex_count));
    out.blob = std::move(build.blob);
    out.rank_point = std::move(build.rank_point);
    out.rank_kept = std::move(build.rank_kept);
    out.stored_triangles = build.stored_triangles;
    return out;
}

PfrepExtensionObject headerObject(const PfrepBuild& build) {
    PfrepExtensionObject out;
    out.vertex_count = uint32_t(build.rank_point.size());
    out.removed_count = uint32_t(build.removed);
    out.triangle_count = build.level0_triangles;
    return out;
}

} // namespace

Result<PfrepExtensionObject> buildPfrepExtension(const MeshView& lod0, const std::vector<double>& level_ratios,
                                                 const PfrepOptions& options, Diagnostics& diagnostics) {
    for (size_t l = 0; l < level_ratios.size(); ++l)
        if (!(level_ratios[l] > 0.0 && level_ratios[l] <= 1.0))
            return invalidInput(std::string(lodrt::format::kExtProgressiveFans) + ": level " + std::to_string(l) +
                                ": ratio: expected a value in (0, 1]");
    if (lod0.faceCount() == 0) return invalidInput(std::string(lodrt::format::kExtProgressiveFans) + ": the mesh has no triangle");
    // The blob stores positions only, so its collapse order is chosen on the geometry alone: the
    // attributes' quadrics and seams would cost time and memory (per-wedge quadrics of the whole
    // full-detail mesh) and only steer the order towards data the blob does not keep. Materials go
    // too: the blob is one set of triangles. The simplifier takes a Mesh, so the half-edge pass gets
    // its own copy of the geometry.
    Mesh geometry;
    geometry.positions.assign(lod0.positions.begin(), lod0.positions.end());
    geometry.indices.assign(lod0.indices.begin(), lod0.indices.end());
    LODBAKE_ASSIGN_OR_RETURN(PfrepBuild build, buildPfrep(geometry, options, diagnostics));
    PfrepExtensionObject out = headerObject(build);
    const std::vector<uint32_t>& counts = build.level_triangles;
    for (double ratio : level_ratios) {
        const double budget = ratio * double(out.triangle_count);
        // level_triangles does not increase with k (every removal deletes at least one triangle),
        // so the first level within the budget is found by bisection.
        const auto it = std::partition_point(counts.begin(), counts.end(),
                                             [budget](uint32_t t) { return double(t) > budget; });
        const uint32_t k = it == counts.end() ? uint32_t(counts.size() - 1) : uint32_t(it - counts.begin());
        out.levels.push_back({k, counts[k]});
    }
    return finishObject(std::move(build), std::move(out));
}

Result<PfrepExtensionObject> buildPfrepExtension(const MeshView& lod0, const LodChain& chain, const PfrepOptions& options,
                                                 Diagnostics& diagnostics) {
    if (!chain.removals_complete) {
        std::vector<double> ratios{1.0};
        for (const LodLevel& level : chain.levels) ratios.push_back(level.target_ratio);
        return buildPfrepExtension(lod0, ratios, options, diagnostics);
    }
    if (lod0.faceCount() == 0) return invalidInput(std::string(lodrt::format::kExtProgressiveFans) + ": the mesh has no triangle");
    LODBAKE_ASSIGN_OR_RETURN(PfrepBuild build, buildPfrepFromChain(lod0, chain.removals, diagnostics));
    // Level k of the blob has the chain's faces after k collapses: each chain level is the blob level
    // at its collapse count, with exactly its triangles.
    PfrepExtensionObject out = headerObject(build);
    out.levels.push_back({0, build.level0_triangles});
    for (const LodLevel& level : chain.levels) {
        const size_t k = level.collapse_count;
        if (k >= build.level_triangles.size() || build.level_triangles[k] != level.mesh.faceCount())
            return internalError(std::string(lodrt::format::kExtProgressiveFans) + ": PFRep level " + std::to_string(k) +
                                 " does not have the chain level's " + std::to_string(level.mesh.faceCount()) +
                                 " triangles");
        out.levels.push_back({uint32_t(k), build.level_triangles[k]});
    }
    return finishObject(std::move(build), std::move(out));
}

} // namespace lodbake
