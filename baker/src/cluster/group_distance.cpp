// A group's error: the two-sided Hausdorff distance between its merged input clusters and its
// simplification, measured Metro-style as measureSurfaceDistance does (area-uniform samples on each
// surface plus every vertex, exact point-to-triangle distance to the other surface through
// DistanceIndex), with what is known to lie on the other surface left out: the locked border and every
// point the simplifier did not touch are vertices of both meshes, and a triangle of the merge that is
// still in the output is part of both surfaces, so their distances are exactly zero. Leaving them
// out changes no maximum and saves the queries of every vertex a group keeps in place (the locked
// border and the points no collapse reached), which are a good part of both meshes' vertices.

#include <algorithm>
#include <array>
#include <cmath>

#include "cluster/cluster_internal.h"
#include "lodbake/simplify/mesh_distance.h"
#include "simplify/surface_sampling.h"

namespace lodbake::cluster_detail {

namespace {

using detail::pointOnTriangle;
using detail::splitmix64;
using detail::toUnit;

using TriangleKey = std::array<uint32_t, 3>; // a triangle's point ids, ascending

TriangleKey keyOf(uint32_t a, uint32_t b, uint32_t c) {
    TriangleKey k{a, b, c};
    std::sort(k.begin(), k.end());
    return k;
}

double triangleArea(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    return 0.5 * length(cross(b - a, c - a));
}

// One side: the largest squared distance from the points of `from` (its samples on the triangles
// not in `skip_triangle`, and its vertices not in `skip_vertex`) to the surface indexed by `to`.
// The samples of a triangle: area times the side's density, the fraction drawn by a hash of the
// triangle, at hashed barycentric positions (deterministic, independent of the thread).
double oneSide(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
               const std::vector<uint8_t>& skip_triangle, const std::vector<uint8_t>& skip_vertex,
               double sample_count, uint64_t key, const DistanceIndex& to) {
    const size_t tri_count = indices.size() / 3;
    std::vector<double> area(tri_count);
    double total = 0;
    for (size_t t = 0; t < tri_count; ++t) {
        area[t] = triangleArea(toDouble(positions[indices[t * 3]]), toDouble(positions[indices[t * 3 + 1]]),
                               toDouble(positions[indices[t * 3 + 2]]));
        total += area[t];
    }
    const double density = total > 0 ? sample_count / total : 0.0;
    std::vector<Vec3d> points;
    std::vector<uint8_t> visited(positions.size(), 0);
    for (size_t t = 0; t < tri_count; ++t) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = indices[t * 3 + k];
            if (visited[v] || skip_vertex[v]) continue;
            visited[v] = 1;
            points.push_back(toDouble(positions[v]));
        }
        if (skip_triangle[t]) continue;
        const uint64_t base = splitmix64(key ^ uint64_t(t) * 0x9e3779b97f4a7c15ull);
        const double expected = area[t] * density;
        const size_t n = size_t(expected) + (toUnit(base) < expected - std::floor(expected) ? 1 : 0);
        const Vec3d a = toDouble(positions[indices[t * 3]]), b = toDouble(positions[indices[t * 3 + 1]]);
        const Vec3d c = toDouble(positions[indices[t * 3 + 2]]);
        for (size_t i = 0; i < n; ++i) {
            const double u1 = toUnit(splitmix64(base + 2 * i + 1)), u2 = toUnit(splitmix64(base + 2 * i + 2));
            points.push_back(pointOnTriangle(a, b, c, u1, u2));
        }
    }
    // Queried in Morton order, so that each starts near the last one's answer (the cursor).
    Vec3d lo(HUGE_VAL, HUGE_VAL, HUGE_VAL), hi = lo * -1.0;
    for (const Vec3d& p : points)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    const double extent = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z, 1e-300});
    std::vector<std::pair<uint64_t, uint32_t>> order(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        uint64_t code = 0;
        for (int a = 0; a < 3; ++a) {
            const uint64_t q = uint64_t(std::min((points[i][a] - lo[a]) / extent * 1023.0, 1023.0));
            for (int b = 0; b < 10; ++b) code |= ((q >> b) & 1) << (3 * b + a);
        }
        order[i] = {code, uint32_t(i)};
    }
    std::sort(order.begin(), order.end());
    DistanceIndex::Cursor cursor;
    double worst = 0;
    for (const auto& o : order) worst = std::max(worst, to.closestDistanceSq(points[o.second], cursor));
    return worst;
}

} // namespace

Result<double> groupDistance(const GroupMeshes& m, double samples_per_triangle, uint64_t seed) {
    const size_t merged_tris = m.merged_indices.size() / 3, out_tris = m.out_indices.size() / 3;
    // Points of the merge still in the output, and triangles present in both (by point ids).
    std::vector<uint32_t> kept;
    for (uint32_t p : m.out_point) if (p != kNewPointId) kept.push_back(p);
    std::sort(kept.begin(), kept.end());
    std::vector<uint8_t> merged_vertex_kept(m.merged_positions.size(), 0), out_vertex_kept(m.out_point.size(), 0);
    for (size_t v = 0; v < m.merged_point.size(); ++v)
        merged_vertex_kept[v] = std::binary_search(kept.begin(), kept.end(), m.merged_point[v]);
    for (size_t v = 0; v < m.out_point.size(); ++v) out_vertex_kept[v] = m.out_point[v] != kNewPointId;
    std::vector<TriangleKey> out_keys;
    std::vector<uint8_t> out_shared(out_tris, 0), merged_shared(merged_tris, 0);
    for (size_t t = 0; t < out_tris; ++t) {
        const uint32_t* f = &m.out_indices[t * 3];
        if (out_vertex_kept[f[0]] && out_vertex_kept[f[1]] && out_vertex_kept[f[2]])
            out_keys.push_back(keyOf(m.out_point[f[0]], m.out_point[f[1]], m.out_point[f[2]]));
    }
    std::sort(out_keys.begin(), out_keys.end());
    std::vector<TriangleKey> merged_keys;
    for (size_t t = 0; t < merged_tris; ++t) {
        const uint32_t* f = &m.merged_indices[t * 3];
        const TriangleKey k = keyOf(m.merged_point[f[0]], m.merged_point[f[1]], m.merged_point[f[2]]);
        merged_shared[t] = std::binary_search(out_keys.begin(), out_keys.end(), k);
        if (merged_shared[t]) merged_keys.push_back(k);
    }
    std::sort(merged_keys.begin(), merged_keys.end());
    for (size_t t = 0; t < out_tris; ++t) {
        const uint32_t* f = &m.out_indices[t * 3];
        if (out_vertex_kept[f[0]] && out_vertex_kept[f[1]] && out_vertex_kept[f[2]])
            out_shared[t] = std::binary_search(merged_keys.begin(), merged_keys.end(),
                                               keyOf(m.out_point[f[0]], m.out_point[f[1]], m.out_point[f[2]]));
    }

    LODBAKE_ASSIGN_OR_RETURN(DistanceIndex merged_index, DistanceIndex::build(m.merged_positions, m.merged_indices));
    LODBAKE_ASSIGN_OR_RETURN(DistanceIndex out_index, DistanceIndex::build(m.out_positions, m.out_indices));
    // Both sides draw as many samples in all as measureSurfaceDistance's sample_count would.
    const double samples = std::ceil(double(merged_tris) * samples_per_triangle);
    const double to_out = oneSide(m.merged_positions, m.merged_indices, merged_shared, merged_vertex_kept, samples,
                                  splitmix64(seed ^ 0x5265664d65736821ull), out_index);
    const double to_merged = oneSide(m.out_positions, m.out_indices, out_shared, out_vertex_kept, samples,
                                     splitmix64(seed ^ 0x417070726f782121ull), merged_index);
    return std::sqrt(std::max(to_out, to_merged));
}

} // namespace lodbake::cluster_detail
