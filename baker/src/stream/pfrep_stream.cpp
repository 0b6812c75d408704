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
#include "lodbake/pfrep/pfrep_region.h"
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

// Per vertex of LOD0's decoded stream, its input vertex's position bits as a label (input vertices
// with equal bits are one point of the build, chainPoints). Empty when a decoded vertex stands for
// input vertices at two positions.
std::vector<uint32_t> inputLabels(const Mesh& mesh, const DecodedLevelStream& decoded) {
    const size_t n = decoded.mesh.positions.size();
    if (decoded.new_vertex_of.size() != mesh.positions.size()) return {};
    std::vector<PositionKey> keys(mesh.positions.size());
    for (size_t x = 0; x < keys.size(); ++x) keys[x] = positionKey(mesh.positions[x]);
    std::vector<PositionKey> distinct = keys;
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
    std::vector<uint32_t> label(n, UINT32_MAX);
    for (size_t x = 0; x < keys.size(); ++x) {
        const uint32_t v = decoded.new_vertex_of[x];
        if (v >= n) return {};
        const uint32_t l = uint32_t(std::lower_bound(distinct.begin(), distinct.end(), keys[x]) - distinct.begin());
        if (label[v] != UINT32_MAX && label[v] != l) return {};
        label[v] = l;
    }
    for (size_t v = 0; v < n; ++v) // a decoded vertex without an input one: a point of its own
        if (label[v] == UINT32_MAX) label[v] = uint32_t(distinct.size() + v);
    return label;
}

// Per vertex, the lowest vertex with its position bits (the welds of lodrt::pfrepNumberLod0).
std::vector<uint32_t> positionWelds(const std::vector<Vec3f>& positions) {
    const auto order = pointIndex(positions); // by position bits, then vertex id
    std::vector<uint32_t> weld(positions.size());
    for (size_t k = 0; k < order.size(); ++k)
        weld[order[k].second] =
            k > 0 && order[k].first == order[k - 1].first ? weld[order[k - 1].second] : order[k].second;
    return weld;
}

// LOD0 numbered as lodrt::pfrepNumberLod0 numbers it, from the welds (after the split list): points
// by first use by the triangles with three distinct welds. Per vertex its point (UINT32_MAX: on no
// such triangle) into vertex_point, the points' positions and the triangles.
void numberWelds(const Mesh& d, const std::vector<uint32_t>& weld, std::vector<uint32_t>& vertex_point,
                 std::vector<Vec3f>& points, std::vector<uint32_t>& triangles) {
    std::vector<uint32_t> id(weld.size(), UINT32_MAX);
    points.clear();
    triangles.clear();
    for (size_t t = 0; t + 2 < d.indices.size(); t += 3) {
        const uint32_t w[3] = {weld[d.indices[t]], weld[d.indices[t + 1]], weld[d.indices[t + 2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            if (id[w[k]] == UINT32_MAX) {
                id[w[k]] = uint32_t(points.size());
                points.push_back(d.positions[w[k]]);
            }
            triangles.push_back(id[w[k]]);
        }
    }
    vertex_point.resize(weld.size());
    for (size_t v = 0; v < weld.size(); ++v) vertex_point[v] = id[weld[v]];
}

// LOD0's points (chainPoints of `mesh`, the build's numbering) -> the points of its decoded stream
// (`vertex_point`: per decoded vertex its point), through the vertices the stream kept: empty when
// they are not one to one or the triangles differ (a weld the split list left, or a triangle made
// degenerate).
std::vector<uint32_t> streamPointOf(const Mesh& mesh, const std::vector<Vec3f>& points,
                                    const std::vector<uint32_t>& triangles, const DecodedLevelStream& decoded,
                                    const std::vector<uint32_t>& vertex_point, size_t stream_point_count,
                                    const std::vector<uint32_t>& stream_triangles) {
    if (points.size() != stream_point_count || triangles.size() != stream_triangles.size()) return {};
    const auto index = pointIndex(points);
    std::vector<uint32_t> point_of(points.size(), UINT32_MAX);
    std::vector<uint8_t> taken(points.size(), 0);
    for (uint32_t x : mesh.indices) {
        const uint32_t p = findPoint(index, mesh.positions[x]);
        if (p == UINT32_MAX) continue; // on degenerate faces only
        if (x >= decoded.new_vertex_of.size() || decoded.new_vertex_of[x] >= vertex_point.size()) return {};
        const uint32_t q = vertex_point[decoded.new_vertex_of[x]];
        if (q >= points.size()) return {};
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

// LOD0 as the runtime numbers it from its decoded stream `d` with `split_list` (lodrt::
// pfrepNumberLod0Split), checked against numberWelds of `weld` (the welds the list leaves).
Status numberStreamLod0(const Mesh& d, const std::vector<uint8_t>& split_list, const std::vector<uint32_t>& weld,
                        std::vector<uint32_t>& vertex_point, std::vector<Vec3f>& stream_points,
                        std::vector<uint32_t>& stream_triangles) {
    const uint32_t vertex_count = uint32_t(d.positions.size()), triangle_count = uint32_t(d.faceCount());
    std::vector<Vec3f> points(vertex_count);
    std::vector<uint32_t> triangles(size_t(triangle_count) * 3);
    std::vector<uint64_t> scratch((lodrt::pfrepNumberLod0ScratchBytes(vertex_count) + 7) / 8);
    lodrt::PfrepLod0 lod0;
    const lodrt::Result r = lodrt::pfrepNumberLod0Split(
        split_list.empty() ? nullptr : split_list.data(), split_list.size(),
        d.positions.empty() ? nullptr : &d.positions[0].x, vertex_count, d.indices.data(), triangle_count,
        points.empty() ? nullptr : &points[0].x, points.size() * 3, triangles.data(), triangles.size(),
        scratch.data(), scratch.size() * 8, &lod0);
    if (r != lodrt::Result::Ok)
        return internalError(std::string("pfrep: LOD0's decoded stream: ") + lodrt::resultName(r));
    points.resize(lod0.point_count);
    triangles.resize(size_t(lod0.triangle_count) * 3);
    numberWelds(d, weld, vertex_point, stream_points, stream_triangles);
    if (stream_triangles != triangles || stream_points.size() != points.size() ||
        (!points.empty() && std::memcmp(points.data(), stream_points.data(), points.size() * sizeof(Vec3f)) != 0))
        return internalError("pfrep: format 4's split list does not number LOD0 as the bake does");
    return Status::okStatus();
}

// Format 4 against LOD0's own LODBAKE_valence_compression stream, as the runtime has it once LOD0 is
// resident (docs/format/pfrep.md "In a glTF pack"). Points of the build that the stream's
// quantization welds are told apart by the blob's split list. No value when LOD0's stream cannot
// stand for it (several primitives, or a topology the split list cannot restore): the bake then
// writes format 3.
Result<std::optional<std::vector<uint8_t>>> codeAgainstStream(const PfrepExtensionObject& object,
                                                              const ValenceStreamOptions& valence,
                                                              const LodChain& chain, const Mesh& mesh) {
    using NoBlob = std::optional<std::vector<uint8_t>>;
    LODBAKE_ASSIGN_OR_RETURN(std::optional<DecodedLevelStream> decoded, decodedLevelStream(valence, chain, 0, mesh));
    if (!decoded || decoded->mesh.positions.size() >= lodrt::format::kPfrepMaxVertices) return NoBlob();
    const Mesh& d = decoded->mesh;
    const std::vector<uint32_t> labels = inputLabels(mesh, *decoded);
    if (labels.size() != d.positions.size()) return NoBlob();
    std::vector<uint32_t> weld = positionWelds(d.positions);
    std::vector<uint8_t> split_list;
    for (size_t v = 0; v < weld.size() && split_list.empty(); ++v)
        if (labels[v] != labels[weld[v]]) split_list = codePfrepSplitList(weld, labels);
    std::vector<uint32_t> vertex_point, stream_triangles;
    std::vector<Vec3f> stream_points;
    LODBAKE_RETURN_IF_ERROR(numberStreamLod0(d, split_list, weld, vertex_point, stream_points, stream_triangles));
    std::vector<Vec3f> points;
    std::vector<uint32_t> triangles;
    LODBAKE_RETURN_IF_ERROR(chainPoints(mesh, points, triangles));
    const std::vector<uint32_t> point_of =
        streamPointOf(mesh, points, triangles, *decoded, vertex_point, stream_points.size(), stream_triangles);
    if (point_of.empty()) return NoBlob();
    PfrepBuild build;
    build.blob = object.blob;
    build.rank_point = object.rank_point;
    build.rank_kept = object.rank_kept;
    build.stored_triangles = object.stored_triangles;
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> blob,
                             compressPfrepFormat4(build, stream_points, stream_triangles, point_of, split_list));
    return NoBlob(std::move(blob));
}

// The blob in the format the settings ask for (format 4 falls back to 3, see codeAgainstStream;
// format 5 is the region container of the format 2 table); returns the format written.
Result<uint32_t> codeBlob(PfrepExtensionObject& object, uint32_t format, const PfrepRegionOptions& regions,
                          const ValenceStreamOptions& valence, const LodChain& chain, const Mesh& mesh) {
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
    } else if (format == lodrt::format::kPfrepFormatRegions) {
        LODBAKE_ASSIGN_OR_RETURN(object.blob, writePfrepRegions(object.blob, regions));
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
        [format = settings.pfrep_format, regions = settings.pfrep_regions, valence = settings.valence](
            const LodChain& chain, size_t level_index, const Mesh& mesh) -> Result<PackStreamCommit> {
            if (level_index != 0 || mesh.faceCount() == 0) return PackStreamCommit();
            Diagnostics diagnostics; // notes only (e.g. nothing removable); the blob is valid either way
            // From the chain's own collapses when it recorded them (LodChain::removals), else its own
            // half-edge simplification; either reads LOD0's geometry only, as a view (MeshView).
            LODBAKE_ASSIGN_OR_RETURN(PfrepExtensionObject object,
                                     buildPfrepExtension(mesh, chain, PfrepOptions{}, diagnostics));
            // Format 3: the same table range-coded; format 4: coded against LOD0's decoded stream;
            // the runtime decodes either whole into the format 2 bytes. `format` is written only for
            // them, so a format 2 object reads as before.
            LODBAKE_ASSIGN_OR_RETURN(const uint32_t written, codeBlob(object, format, regions, valence, chain, mesh));
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
