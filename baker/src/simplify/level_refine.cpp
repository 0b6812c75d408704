// Final vertex-position refinement of a coarse level. At a few hundred triangles one vertex
// decides the Hausdorff error and the collapse order decides where every vertex sits; each input
// point is then measured to its nearest level face and pulls that face's corners along its normal
// by its signed distance, weighted by its barycentric coordinates (a Jacobi step of the
// point-to-plane least-squares fit, damped by half). The engine's state is not touched: the level
// is a snapshot, so the chain's continuation (and every later level) is the same with or without it.
#include "simplify/level_refine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "lodbake/core/bvh.h"
#include "lodbake/core/math.h"
#include "lodbake/simplify/mesh_distance.h"

namespace lodbake::detail {

namespace {

// Relaxation steps and the share of each step's pull that is applied, tuned on the late (2 % and
// 0.5 %) levels of the shared scans: damping keeps a point from overshooting while its neighbours
// move too (simplification results: docs/benchmarks.md, "Simplification against meshoptimizer").
constexpr int kLevelRefineIterations = 3;
constexpr double kDamping = 0.5;
// Input points used per step: every k-th referenced vertex so that at most this many are used
// (bounds the cost on million-triangle inputs).
constexpr size_t kMaxRefinePoints = 65536;
// On a level with UVs refinement may not change a face's area by more than a factor 1.25 either way
// from the snapshot's (squared: the cross products' squared lengths are compared): squeezing or
// stretching a face in 3D distorts its texture. Unbounded, refinement can multiply a textured level's
// texture stretch; within this bound it does not add to it.
constexpr double kMinAreaRatio2 = 0.64;
constexpr double kMaxAreaRatio2 = 1.5625;
// Samples per task of the parallel nearest-face searches (fixed: nothing depends on the thread count).
constexpr size_t kRefineChunk = 1024;
constexpr size_t kRefineBlock = 16 * kRefineChunk;

// Position groups: vertices with bit-identical positions (seams) move together. Groups on an edge
// used by other than two faces (open border, non-manifold) are fixed: they stay in place.
struct PositionGroups {
    std::vector<uint32_t> of_vertex;
    uint32_t count = 0;
    std::vector<uint8_t> fixed;
};

PositionGroups groupPositions(const Mesh& level) {
    const size_t n = level.positions.size();
    PositionGroups pg;
    std::vector<std::pair<std::array<uint32_t, 3>, uint32_t>> keys(n);
    for (size_t v = 0; v < n; ++v) {
        std::memcpy(keys[v].first.data(), &level.positions[v], 12);
        keys[v].second = uint32_t(v);
    }
    std::sort(keys.begin(), keys.end());
    std::vector<uint32_t>& group = pg.of_vertex;
    group.resize(n);
    uint32_t groups = 0;
    for (size_t i = 0; i < n; ++i) {
        if (i > 0 && keys[i].first != keys[i - 1].first) ++groups;
        group[keys[i].second] = groups;
    }
    ++groups;
    pg.count = groups;
    pg.fixed.assign(groups, 0);
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    edges.reserve(level.indices.size());
    for (size_t f = 0; f < level.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = group[level.indices[f * 3 + k]], b = group[level.indices[f * 3 + (k + 1) % 3]];
            edges.emplace_back(std::min(a, b), std::max(a, b));
        }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i]) ++j;
        if (j - i != 2) pg.fixed[edges[i].first] = pg.fixed[edges[i].second] = 1;
        i = j;
    }
    return pg;
}

// The samples: every stride-th referenced input vertex, at most about kMaxRefinePoints of them.
std::vector<uint32_t> sampleVertices(const Mesh& input) {
    std::vector<uint8_t> referenced(input.positions.size(), 0);
    size_t referenced_count = 0;
    for (uint32_t i : input.indices) {
        referenced_count += referenced[i] ? 0 : 1;
        referenced[i] = 1;
    }
    const size_t stride = std::max<size_t>(1, (referenced_count + kMaxRefinePoints - 1) / kMaxRefinePoints);
    std::vector<uint32_t> sample_vertex;
    size_t seen = 0;
    for (size_t i = 0; i < input.positions.size(); ++i)
        if (referenced[i] && seen++ % stride == 0) sample_vertex.push_back(uint32_t(i));
    return sample_vertex;
}

// The nearest level face of samples [block, block_end) into hits[0, block_end - block), in parallel
// over fixed chunks of samples (each chunk starts its cursor afresh: where a search starts changes
// only its speed, and which of several equally near faces it returns, never the distance).
Status findNearestFaces(const Mesh& input, const Mesh& level, const DistanceIndex& index,
                        const std::vector<uint32_t>& sample_vertex, size_t block, size_t block_end,
                        std::vector<ClosestHit>& hits) {
    return parallelForChunks(block_end - block, kRefineChunk, [&](size_t, size_t chunk_first, size_t chunk_last) {
        const size_t first = block + chunk_first, last = block + chunk_last;
        DistanceIndex::Cursor cursor;
        for (size_t slot = first; slot < last; ++slot) {
            const Vec3d x(input.positions[sample_vertex[slot]]);
            ClosestHit hit;
            hit.distance_sq = index.closestDistanceSq(x, cursor);
            if (cursor.hint != DistanceIndex::kNoHint) {
                const uint32_t f = index.faceOfSlot(cursor.hint);
                hit.face = FaceId(f);
                hit.point = closestPointOnTriangle(x, Vec3d(level.positions[level.indices[f * 3]]),
                                                   Vec3d(level.positions[level.indices[f * 3 + 1]]),
                                                   Vec3d(level.positions[level.indices[f * 3 + 2]]));
            }
            hits[slot - block] = hit;
        }
    });
}

// Adds the pulls of samples [block, block_end) in sample order: each pulls its nearest face's corner
// groups along the face normal by its signed distance, weighted by its barycentric coordinates.
void addPulls(const Mesh& input, const Mesh& level, const std::vector<uint32_t>& sample_vertex,
              const std::vector<uint32_t>& group, const std::vector<ClosestHit>& hits, size_t block,
              size_t block_end, std::vector<Vec3d>& delta, std::vector<double>& weight) {
    for (size_t slot = block; slot < block_end; ++slot) {
        const ClosestHit& hit = hits[slot - block];
        if (!hit.isFound()) continue;
        const Vec3d x(input.positions[sample_vertex[slot]]);
        const uint32_t f = hit.face.value;
        const Vec3d a(level.positions[level.indices[f * 3]]), b(level.positions[level.indices[f * 3 + 1]]),
            c(level.positions[level.indices[f * 3 + 2]]);
        const Vec3d normal = cross(b - a, c - a);
        const double area2 = dot(normal, normal);
        if (!(area2 > 0.0)) continue;
        const Vec3d& q = hit.point;
        const double b0 = dot(cross(b - q, c - q), normal) / area2;
        const double b1 = dot(cross(c - q, a - q), normal) / area2;
        const double bary[3] = {b0, b1, 1.0 - b0 - b1};
        const Vec3d unit = normal * (1.0 / std::sqrt(area2));
        const double s = dot(x - q, unit);
        for (int k = 0; k < 3; ++k) {
            const uint32_t g = group[level.indices[f * 3 + k]];
            const double w = std::max(0.0, bary[k]);
            delta[g] += unit * (s * w);
            weight[g] += w;
        }
    }
}

// The bounds on one step (see refineLevelPositions): a group whose move would turn any of its faces by
// more than the bound from the snapshot (or make it lose its area, or on a textured level take it
// beyond the area factor of the snapshot's) stays put, and so do, round by round, the groups of faces
// that staying put turns too far. `next` holds the stepped positions on entry.
void keepWithinBounds(const Mesh& level, const std::vector<uint32_t>& group, uint32_t groups,
                      const std::vector<Vec3d>& snapshot_normal, double cos2, bool textured,
                      std::vector<Vec3f>& next) {
    const size_t n = level.positions.size();
    std::vector<uint8_t> stays(groups, 0);
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t f = 0; f < level.faceCount(); ++f) {
            const uint32_t* c = &level.indices[f * 3];
            const Vec3d& n0 = snapshot_normal[f];
            const Vec3d n1 = cross(Vec3d(next[c[1]]) - Vec3d(next[c[0]]), Vec3d(next[c[2]]) - Vec3d(next[c[0]]));
            const double l0 = dot(n0, n0), l1 = dot(n1, n1);
            if (!(l0 > 0.0)) continue; // without area in the snapshot: no normal to keep
            const double d = dot(n0, n1);
            const bool area_kept = !textured || (l1 >= kMinAreaRatio2 * l0 && l1 <= kMaxAreaRatio2 * l0);
            if (l1 > 0.0 && area_kept && d > 0.0 && d * d >= cos2 * l0 * l1) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t g = group[c[k]];
                if (stays[g]) continue;
                stays[g] = 1;
                changed = true;
            }
            for (int k = 0; k < 3; ++k) next[c[k]] = level.positions[c[k]];
        }
        if (changed)
            for (size_t v = 0; v < n; ++v)
                if (stays[group[v]]) next[v] = level.positions[v];
    }
}

} // namespace

void refineLevelPositions(const Mesh& input, Mesh& level, float max_normal_change_deg) {
    const size_t n = level.positions.size();
    const double cos_bound = std::cos(double(max_normal_change_deg) * (kPi / 180.0));
    const double cos2 = cos_bound * cos_bound;
    const bool textured = !level.uvs.empty();
    if (n == 0 || level.faceCount() == 0) return;
    const PositionGroups pg = groupPositions(level);
    const std::vector<uint32_t>& group = pg.of_vertex;
    const std::vector<uint32_t> sample_vertex = sampleVertices(input);
    const size_t sample_count = sample_vertex.size();
    std::vector<ClosestHit> hits(std::min(sample_count, kRefineBlock));
    std::vector<Vec3d> delta(pg.count);
    std::vector<double> weight(pg.count);
    // The snapshot's face normals (unnormalised): the rotation bound, and on textured levels the
    // area bound, are relative to them, so three steps cannot add up to more than one step may do.
    std::vector<Vec3d> snapshot_normal(level.faceCount());
    for (size_t f = 0; f < level.faceCount(); ++f) {
        const uint32_t* c = &level.indices[f * 3];
        snapshot_normal[f] = cross(Vec3d(level.positions[c[1]]) - Vec3d(level.positions[c[0]]),
                                   Vec3d(level.positions[c[2]]) - Vec3d(level.positions[c[0]]));
    }
    for (int it = 0; it < kLevelRefineIterations; ++it) {
        // The nearest-face index of the error measurement (mesh_distance.h): exact minimum distances,
        // each query starting from the previous one's path (the samples are in input order, so
        // neighbouring points follow each other).
        Result<DistanceIndex> index = DistanceIndex::build(level.positions, level.indices);
        if (!index.ok()) return; // out of resources: the level stays as the engine left it
        std::fill(delta.begin(), delta.end(), Vec3d());
        std::fill(weight.begin(), weight.end(), 0.0);
        // A block of samples at a time, so the hits buffer stays small; the pulls are added in sample
        // order, as a serial loop adds them.
        for (size_t block = 0; block < sample_count; block += kRefineBlock) {
            const size_t block_end = std::min(block + kRefineBlock, sample_count);
            if (!findNearestFaces(input, level, *index, sample_vertex, block, block_end, hits).ok())
                return; // out of resources: the level keeps the previous step
            addPulls(input, level, sample_vertex, group, hits, block, block_end, delta, weight);
        }
        // The step, then the normal-rotation and area bounds.
        std::vector<Vec3f> next(level.positions);
        for (size_t v = 0; v < n; ++v) {
            const uint32_t g = group[v];
            if (pg.fixed[g] || !(weight[g] > 0.0)) continue;
            next[v] = Vec3f(Vec3d(level.positions[v]) + delta[g] * (kDamping / weight[g]));
        }
        keepWithinBounds(level, group, pg.count, snapshot_normal, cos2, textured, next);
        level.positions = std::move(next);
    }
}

} // namespace lodbake::detail
