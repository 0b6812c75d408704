#pragma once
// Steps of the cluster LOD builder shared by its source files (baker/src/cluster/).

#include <cstdint>
#include <vector>

#include "lodbake/core/math.h"
#include "lodbake/core/status.h"

namespace lodbake::cluster_detail {

/// Splits triangles (3 point ids each, indexing `points`) into spatially compact clusters of at most
/// max_triangles triangles over at most max_vertices distinct points: recursive median splits of
/// the triangle centroids along the longest axis of their bounds, with part sizes chosen so the
/// leaves come out about equally full. Returns each cluster's triangle indices (into `triangles`/3).
/// Deterministic: the order used is total (coordinate, then triangle index).
std::vector<std::vector<uint32_t>> splitIntoClusters(const std::vector<Vec3f>& points,
                                                     const std::vector<uint32_t>& triangles, uint32_t max_triangles,
                                                     uint32_t max_vertices);

/// Undirected weighted graph in compressed rows (both directions stored), no self loops.
struct WeightedGraph {
    std::vector<uint32_t> row_begin; // vertex_count + 1
    std::vector<uint32_t> neighbour;
    std::vector<uint32_t> weight;
    std::vector<uint32_t> vertex_weight;
};

/// Partitions the graph into about vertex_count / group_size parts with METIS (recursive bisection, fixed seed),
/// then merges parts below min_size into the neighbouring part they share the most weight with when
/// it stays within max_size, and cuts parts above max_size. Returns each part's vertices, ascending,
/// parts ordered by their smallest vertex. Falls back to a chunked order when METIS reports an error.
Result<std::vector<std::vector<uint32_t>>> partitionGraph(const WeightedGraph& graph, uint32_t group_size,
                                                          uint32_t min_size, uint32_t max_size, uint64_t seed);

/// A group's merge and its simplification, with the point id of every vertex (kNewPointId for an
/// output vertex at no point of the merge).
inline constexpr uint32_t kNewPointId = 0x80000000u;
struct GroupMeshes {
    const std::vector<Vec3f>& merged_positions;
    const std::vector<uint32_t>& merged_indices;
    const std::vector<uint32_t>& merged_point;
    const std::vector<Vec3f>& out_positions;
    const std::vector<uint32_t>& out_indices;
    const std::vector<uint32_t>& out_point;
};

/// Two-sided Hausdorff distance between the merge and its simplification (group_distance.cpp):
/// about samples_per_triangle area-uniform samples per merged triangle on each side plus every
/// vertex, less the vertices and triangles both meshes share (their distance is zero). Infinite when
/// the output has no triangle. Fails only when resources run out.
Result<double> groupDistance(const GroupMeshes& meshes, double samples_per_triangle, uint64_t seed);

/// Sphere enclosing points (centre of their box, largest distance), radius rounded up so the float
/// sphere still contains every point.
void boundingSphere(const Vec3f* points, const uint32_t* ids, size_t count, float center[3], float& radius);

/// Sphere enclosing spheres (centre of their boxes), with a relative margin so a float distance test
/// against it is never closer than against any of them (the cut's monotonicity relies on it).
void enclosingSphere(const std::vector<const float*>& centers, const std::vector<float>& radii, float center[3],
                     float& radius);

} // namespace lodbake::cluster_detail
