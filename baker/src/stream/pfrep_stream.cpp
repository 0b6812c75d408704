// The LODBAKE_progressive_fans stream (schemas/LODBAKE_progressive_fans): LOD0's PFRep blob and the
// PFRep level matching each level of the chain, on the full-detail mesh. The pfrep module builds the
// extension object; this wraps it into a PackExtension.
#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/pfrep/pfrep_compress.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

namespace lodbake {

namespace {

// Leaves in the extension object's `levels` (LOD0's entry, then one per chain level of `ratios`,
// the chain as prepared) the entries of the levels `chain` still holds.
void keepChainLevels(JsonNode& json, const std::vector<double>& ratios, const LodChain& chain) {
    const JsonNode* levels = json.find("levels");
    if (!levels || chain.levels.size() == ratios.size() || levels->items().size() != ratios.size() + 1) return;
    JsonNode kept = JsonNode::array();
    kept.push(levels->items()[0]);
    size_t next = 0; // the next chain level to find
    for (size_t i = 0; i < ratios.size(); ++i)
        if (next < chain.levels.size() && chain.levels[next].target_ratio == ratios[i]) {
            kept.push(levels->items()[i + 1]);
            ++next;
        }
    json.set("levels", std::move(kept));
}

using PositionKey = std::array<uint32_t, 3>;

PositionKey positionKey(const Vec3f& p) {
    PositionKey k;
    std::memcpy(k.data(), &p.x, 12);
    return k;
}

// Position bits -> point id, sorted for lookup (points have distinct bits by construction).
std::vector<std::pair<PositionKey, uint32_t>> pointIndex(const std::vector<Vec3f>& points) {
    std::vector<std::pair<PositionKey, uint32_t>> index(points.size());
    for (uint32_t p = 0; p < points.size(); ++p) index[p] = {positionKey(points[p]), p};
    std::sort(index.begin(), index.end());
    return index;
}

uint32_t findPoint(const std::vector<std::pair<PositionKey, uint32_t>>& index, const Vec3f& position) {
    const PositionKey key = positionKey(position);
    const auto it = std::lower_bound(index.begin(), index.end(), std::make_pair(key, uint32_t(0)));
    return it != index.end() && it->first == key ? it->second : UINT32_MAX;
}

// Triangles (3 ids each) mapped through `map` (null: as they are), each rotated to start at its
// lowest id (orientation kept), sorted.
std::vector<PositionKey> canonicalTriangles(const std::vector<uint32_t>& triangles, const std::vector<uint32_t>* map) {
    std::vector<PositionKey> out(triangles.size() / 3);
    for (size_t t = 0; t < out.size(); ++t) {
        uint32_t c[3];
        for (int k = 0; k < 3; ++k) c[k] = map ? (*map)[triangles[t * 3 + k]] : triangles[t * 3 + k];
        const int m = c[0] < c[1] ? (c[0] < c[2] ? 0 : 2) : (c[1] < c[2] ? 1 : 2);
        out[t] = {c[m], c[(m + 1) % 3], c[(m + 2) % 3]};
    }
    std::sort(out.begin(), out.end());
    return out;
}

// LOD0's points (chainPoints of `mesh`, the build's numbering) -> the points of its decoded stream
// (lodrt::pfrepNumberLod0), through the vertices the stream kept: empty when they are not one to one
// or the triangles differ (quantization welded two points, or made a triangle degenerate).
std::vector<uint32_t> streamPointOf(const Mesh& mesh, const std::vector<Vec3f>& points,
                                    const std::vector<uint32_t>& triangles, const DecodedLevelStream& decoded,
                                    const std::vector<Vec3f>& stream_points,
                                    const std::vector<uint32_t>& stream_triangles) {
    if (points.size() != stream_points.size() || triangles.size() != stream_triangles.size()) return {};
    const auto index = pointIndex(points), stream_index = pointIndex(stream_points);
    std::vector<uint32_t> point_of(points.size(), UINT32_MAX);
    std::vector<uint8_t> taken(points.size(), 0);
    for (uint32_t x : mesh.indices) {
        const uint32_t p = findPoint(index, mesh.positions[x]);
        if (p == UINT32_MAX) continue; // on degenerate faces only
        if (x >= decoded.new_vertex_of.size() || decoded.new_vertex_of[x] >= decoded.mesh.positions.size()) return {};
        const uint32_t q = findPoint(stream_index, decoded.mesh.positions[decoded.new_vertex_of[x]]);
        if (q == UINT32_MAX) return {};
        if (point_of[p] == UINT32_MAX) {
            if (taken[q]) return {};
            taken[q] = 1;
            point_of[p] = q;
        } else if (point_of[p] != q) {
            return {};
        }
    }
    for (uint32_t q : point_of)
        if (q == UINT32_MAX) return {};
    if (canonicalTriangles(triangles, &point_of) != canonicalTriangles(stream_triangles, nullptr)) return {};
    return point_of;
}

// Format 4 against LOD0's own LODBAKE_valence_compression stream, as the runtime has it once LOD0 is
// resident (docs/format/pfrep.md "In a glTF pack"). No value when LOD0's stream cannot stand for it
// (several primitives, or a topology its quantization changed): the bake then writes format 3.
Result<std::optional<std::vector<uint8_t>>> codeAgainstStream(const PfrepExtensionObject& object,
                                                              const ValenceStreamOptions& valence,
                                                              const LodChain& chain, const Mesh& mesh) {
    using NoBlob = std::optional<std::vector<uint8_t>>;
    LODBAKE_ASSIGN_OR_RETURN(std::optional<DecodedLevelStream> decoded, decodedLevelStream(valence, chain, 0, mesh));
    if (!decoded || decoded->mesh.positions.size() >= lodrt::format::kPfrepMaxVertices) return NoBlob();
    const Mesh& d = decoded->mesh;
    const uint32_t vertex_count = uint32_t(d.positions.size()), triangle_count = uint32_t(d.faceCount());
    std::vector<Vec3f> stream_points(vertex_count);
    std::vector<uint32_t> stream_triangles(size_t(triangle_count) * 3);
    std::vector<uint64_t> scratch((lodrt::pfrepNumberLod0ScratchBytes(vertex_count) + 7) / 8);
    lodrt::PfrepLod0 lod0;
    const lodrt::Result r = lodrt::pfrepNumberLod0(
        d.positions.empty() ? nullptr : &d.positions[0].x, vertex_count, d.indices.data(), triangle_count,
        stream_points.empty() ? nullptr : &stream_points[0].x, stream_points.size() * 3, stream_triangles.data(),
        stream_triangles.size(), scratch.data(), scratch.size() * 8, &lod0);
    if (r != lodrt::Result::Ok)
        return internalError(std::string("pfrep: LOD0's decoded stream: ") + lodrt::resultName(r));
    stream_points.resize(lod0.point_count);
    stream_triangles.resize(size_t(lod0.triangle_count) * 3);
    std::vector<Vec3f> points;
    std::vector<uint32_t> triangles;
    LODBAKE_RETURN_IF_ERROR(chainPoints(mesh, points, triangles));
    const std::vector<uint32_t> point_of =
        streamPointOf(mesh, points, triangles, *decoded, stream_points, stream_triangles);
    if (point_of.empty()) return NoBlob();
    PfrepBuild build;
    build.blob = object.blob;
    build.rank_point = object.rank_point;
    build.rank_kept = object.rank_kept;
    build.stored_triangles = object.stored_triangles;
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> blob,
                             compressPfrepFormat4(build, stream_points, stream_triangles, point_of));
    return NoBlob(std::move(blob));
}

// The blob in the format the settings ask for (format 4 falls back to 3, see codeAgainstStream);
// returns the format written.
Result<uint32_t> codeBlob(PfrepExtensionObject& object, uint32_t format, const ValenceStreamOptions& valence,
                          const LodChain& chain, const Mesh& mesh) {
    if (format == lodrt::format::kPfrepVersionLod0) {
        LODBAKE_ASSIGN_OR_RETURN(std::optional<std::vector<uint8_t>> blob,
                                 codeAgainstStream(object, valence, chain, mesh));
        if (blob) {
            object.blob = std::move(*blob);
            return format;
        }
        format = lodrt::format::kPfrepVersionCompressed;
    }
    if (format == lodrt::format::kPfrepVersionCompressed) {
        LODBAKE_ASSIGN_OR_RETURN(object.blob, compressPfrep(object.blob));
    }
    return format;
}

} // namespace

std::optional<PackStreamEncoder> progressiveFansStream(const StreamSettings& settings) {
    if (!settings.progressive_fans) return std::nullopt;
    StreamNeeds needs;
    needs.lod0_only = true;
    // pfrep_from_chain: the blob is built from the chain's own pass, read as vertex removals
    // (docs/bake.md); otherwise it runs a half-edge simplification of its own.
    needs.collapse_record = settings.pfrep_from_chain;
    StreamCost cost;
    cost.bytes_per_triangle = 190; // its own simplifier or the replay of the chain's collapses
    return makeStreamEncoder(
        lodrt::format::kExtProgressiveFans, needs, cost,
        [format = settings.pfrep_format, valence = settings.valence](const LodChain& chain, size_t level_index,
                                                                     const Mesh& mesh) -> Result<PackStreamCommit> {
            if (level_index != 0 || mesh.faceCount() == 0) return PackStreamCommit();
            Diagnostics diagnostics; // notes only (e.g. nothing removable); the blob is valid either way
            // From the chain's own collapses when it recorded them (LodChain::removals), else its own
            // half-edge simplification; either reads LOD0's geometry only, as a view (MeshView).
            LODBAKE_ASSIGN_OR_RETURN(PfrepExtensionObject object,
                                     buildPfrepExtension(mesh, chain, PfrepOptions{}, diagnostics));
            // Format 3: the same table range-coded; format 4: coded against LOD0's decoded stream;
            // the runtime decodes either whole into the format 2 bytes. `format` is written only for
            // them, so a format 2 object reads as before.
            LODBAKE_ASSIGN_OR_RETURN(const uint32_t written, codeBlob(object, format, valence, chain, mesh));
            if (written != lodrt::format::kPfrepVersion)
                object.json.set(lodrt::format::kPfrepExtensionFormatMember, uint64_t(written));
            object.rank_point = {};
            object.rank_kept = {};
            auto e = std::make_shared<PackExtension>();
            e->name = lodrt::format::kExtProgressiveFans;
            e->json = std::move(object.json);
            e->blobs.push_back(std::move(object.blob));
            e->blob_view_members.push_back(kPfrepExtensionViewMember);
            // Extra data beside the plain levels, never a replacement for them: a viewer that
            // ignores it loses nothing, so it is not a stream --compact makes required.
            e->is_stream = false;
            // The bake may drop dead levels from the chain after this prepare (docs/bake.md, "Dead
            // levels"); `levels` has one entry per pack level, so the commit keeps those of the levels
            // the chain still holds when it runs (chain levels are told apart by their ratio).
            std::vector<double> ratios;
            for (const LodLevel& l : chain.levels) ratios.push_back(l.target_ratio);
            return PackStreamCommit([e, ratios, &chain](PackLevel& level) {
                keepChainLevels(e->json, ratios, chain);
                level.mesh_extensions.push_back(std::move(*e));
                return Status::okStatus();
            });
        });
}

} // namespace lodbake
