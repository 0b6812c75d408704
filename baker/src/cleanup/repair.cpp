// The default repair pipeline (see repair.h and docs/repair.md).
#include "lodbake/cleanup/repair.h"

#include <algorithm>
#include <functional>
#include <string>

#include "mesh_edit.h"

namespace lodbake {

namespace {

// Lengths of the boundary loops that are not attribute seams (descending), and the face counts of
// the components with UV islands joined across seams (descending).
void openRimsAndSurfaces(const Mesh& mesh, std::vector<uint32_t>& rims, std::vector<uint32_t>& surfaces) {
    using namespace cleanup_detail;
    const std::vector<uint32_t> weld = positionWeldMap(mesh);
    const EdgeTable table = buildEdgeTable(mesh);
    const std::vector<uint8_t> seam = seamCorners(mesh, table, weld);
    for (const BoundaryLoop& loop : findBoundaryLoops(mesh, table))
        if (std::none_of(loop.corners.begin(), loop.corners.end(), [&](uint32_t c) { return seam[c] != 0; }))
            rims.push_back(uint32_t(loop.vertices.size()));
    UnionFind uf(mesh.vertexCount());
    for (uint32_t c = 0; c < seam.size(); ++c)
        if (seam[c]) {
            uf.unite(halfStart(mesh, c), weld[halfStart(mesh, c)]);
            uf.unite(halfEnd(mesh, c), weld[halfEnd(mesh, c)]);
        }
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        uf.unite(mesh.indices[3 * f], mesh.indices[3 * f + 1]);
        uf.unite(mesh.indices[3 * f], mesh.indices[3 * f + 2]);
    }
    std::vector<uint32_t> faces_of_root(mesh.vertexCount(), 0);
    for (size_t f = 0; f < mesh.faceCount(); ++f) ++faces_of_root[uf.find(mesh.indices[3 * f])];
    for (uint32_t count : faces_of_root)
        if (count) surfaces.push_back(count);
    std::sort(rims.begin(), rims.end(), std::greater<uint32_t>());
    std::sort(surfaces.begin(), surfaces.end(), std::greater<uint32_t>());
}

bool hasSharedPositions(const Mesh& mesh) {
    const std::vector<uint32_t> weld = cleanup_detail::positionWeldMap(mesh);
    for (uint32_t v = 0; v < weld.size(); ++v)
        if (weld[v] != v) return true;
    return false;
}

std::string lengthsList(const std::vector<uint32_t>& lengths, size_t max_items = 10) {
    std::string s;
    for (size_t i = 0; i < lengths.size() && i < max_items; ++i) s += (i ? ", " : "") + std::to_string(lengths[i]);
    if (lengths.size() > max_items) s += ", ... (" + std::to_string(lengths.size()) + " in all)";
    return s;
}

} // namespace

Result<RepairReport> repairMesh(Mesh& mesh, const RepairOptions& options, const std::string& name,
                                Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    RepairReport report;
    report.before = validate(mesh);
    auto add = [&](const char* pass, PassCounters counters) {
        report.passes.push_back({pass, std::move(counters), {}});
        return &report.passes.back();
    };
    if (options.weld) add("weld", weldVertices(mesh, options.weld_options).counters());
    if (options.remove_degenerate)
        add("degenerate", removeDegenerateFaces(mesh, options.degenerate_options).counters());
    add("unreferenced", removeUnreferencedVertices(mesh).counters());
    if (options.make_manifold) add("manifold", makeManifold(mesh, options.manifold_options).counters());
    if (options.orient) add("orient", orientFaces(mesh, options.orient_options).counters());
    if (options.remove_small_components) {
        add("small_components", removeSmallComponents(mesh, options.component_options).counters());
        const UnreferencedReport u = removeUnreferencedVertices(mesh);
        report.passes.back().counters.push_back({"vertices_removed", u.vertices_removed});
    }
    if (options.fill_holes) {
        const HoleFillReport h = fillHoles(mesh, options.hole_options);
        PassSummary* s = add("holes", h.counters());
        if (!h.filled_lengths.empty())
            s->notes.push_back("filled holes of " + lengthsList(h.filled_lengths) + " edges");
        if (!h.skipped_lengths.empty())
            s->notes.push_back("left open (over " + std::to_string(options.hole_options.max_hole_edges) +
                               " edges): " + lengthsList(h.skipped_lengths));
    }
    if (options.denoise) {
        const DenoiseReport d = denoise(mesh, options.denoise_options);
        PassSummary* s = add("denoise", d.counters());
        s->notes.push_back("roughness (mean dihedral deviation) " + std::to_string(d.roughness_before_deg) + " -> " +
                           std::to_string(d.roughness_after_deg) + " degrees");
    }
    if (options.normals) add("normals", computeNormals(mesh, options.normal_options).counters());
    report.after = validate(mesh);
    if (hasSharedPositions(mesh)) {
        ValidateOptions welded;
        welded.weld_by_position = true;
        report.after_welded = validate(mesh, welded);
    } else {
        report.after_welded = report.after; // nothing to weld
    }

    const TopologyStats& t = report.after.topology;
    auto unresolved = [&](const std::string& what) {
        report.unresolved.push_back(what);
        diagnostics.warn(name + ": repair: " + what);
    };
    if (t.face_count == 0) unresolved("no triangles left");
    if (t.non_manifold_edge_count) unresolved(std::to_string(t.non_manifold_edge_count) + " non-manifold edges remain");
    if (t.non_manifold_vertex_count)
        unresolved(std::to_string(t.non_manifold_vertex_count) + " non-manifold vertices remain");
    if (t.inconsistent_edge_count)
        unresolved(std::to_string(t.inconsistent_edge_count) + " edges with inconsistent orientation remain");
    // Rims and components are judged with attribute seams joined: UV islands are not holes or pieces.
    std::vector<uint32_t> rims, surfaces;
    openRimsAndSurfaces(mesh, rims, surfaces);
    if (!rims.empty())
        unresolved(std::to_string(rims.size()) + " boundary loops left open (" + lengthsList(rims) + " edges)");
    if (surfaces.size() > 1)
        unresolved(std::to_string(surfaces.size()) + " components remain (faces: " + lengthsList(surfaces, 5) +
                   "); separate pieces and overlapping sheets are not joined");
    if (t.degenerate_face_count) unresolved(std::to_string(t.degenerate_face_count) + " degenerate faces remain");
    if (t.duplicate_face_count) unresolved(std::to_string(t.duplicate_face_count) + " duplicate faces remain");
    return report;
}

} // namespace lodbake
