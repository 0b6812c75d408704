#pragma once
// Cluster LOD hierarchy (docs/cluster_lod.md): LOD0 split into small, spatially compact clusters,
// then, level after level until one group remains, neighbouring clusters grouped by a graph
// partition (METIS, weighted by shared edges), each group merged, simplified to about half with its
// outer border locked (so it still meets its neighbours edge for edge), measured, and split into new
// clusters. The result is a DAG whose errors and LOD spheres are monotonic, so every view has a
// crack-free cut (lodrt/cluster_lod.h selects it).
//
// Error of a group: a conservative bound on the two-sided distance of its output clusters to LOD0,
// the largest error of its input clusters plus the measured two-sided Hausdorff distance between its
// merged inputs and its simplified output (Metro-style samples and vertices through DistanceIndex,
// mesh_distance.h; the triangle inequality makes the sum a bound; it is monotonic by construction).
//
// Deterministic: identical input and options give identical output for any thread count (groups are
// simplified in parallel into slots indexed by group and committed in group order; METIS runs on
// one thread with a fixed seed).

#include <cstdint>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/math.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodrt/cluster_lod.h"

namespace lodbake {

struct ClusterLodOptions {
    uint32_t max_triangles = lodrt::ClusterLodCluster::kMaxTriangles; // per cluster, at most the format's 128
    uint32_t max_vertices = lodrt::ClusterLodCluster::kMaxVertices;   // per cluster, at most the format's 255
    uint32_t group_size = 8; // clusters per group the partition aims at; doubled (up to max_group_size)
                             // for a level that stops shrinking, which is then built again
    uint32_t min_group_size = 4;       // smaller parts are merged into a neighbouring group when one has room
    uint32_t max_group_size = 32;      // larger parts are cut
    float simplify_ratio = 0.5f;       // triangles a group keeps after simplification
    float samples_per_triangle = 0.5f; // area-uniform samples per triangle measuring a group's error
                                       // (every vertex is measured too)
    uint64_t seed = 1;                 // METIS seed and distance sampling seed
    uint32_t max_levels = 48;          // guard against a hierarchy that stops shrinking
    float min_level_reduction = 0.05f; // a level that keeps more than (1 - this) of the triangles has
                                       // stalled: regrouped larger, or the build stops
};

/// The hierarchy as plain arrays, in the runtime's layout (lodrt/cluster_lod.h). Clusters are stored
/// level by level (LOD0's first); groups in the order they were built (depth ascending).
struct ClusterLodHierarchy {
    std::vector<lodrt::ClusterLodCluster> clusters;
    std::vector<lodrt::ClusterLodGroup> groups;
    std::vector<uint32_t> group_children; // each group's input clusters, in one range
    std::vector<uint32_t> roots;          // clusters without a parent group
    std::vector<Vec3f> positions;         // cluster vertices, each cluster's in one range
    std::vector<uint8_t> indices;         // 3 per triangle, indices local to the cluster's vertex range
    uint32_t lod0_cluster_count = 0;      // clusters[0, lod0_cluster_count) cover LOD0
    uint32_t level_count = 0;             // levels of groups built
    bool reached_single_group = false;    // false: a level stopped shrinking and several roots remain

    /// A view for the runtime; valid while this object lives and is unchanged.
    lodrt::ClusterLodView view() const;
};

/// Builds the hierarchy of `lod0` (positions and triangles; attributes are not carried). Vertices
/// with bit-identical positions are one point. Fails (InvalidInput) on an index out of range, a
/// non-finite position, no triangle, or options outside their ranges.
Result<ClusterLodHierarchy> buildClusterLod(const MeshView& lod0, const ClusterLodOptions& options,
                                            Diagnostics& diagnostics);

/// Clusters to continue a hierarchy from (continueClusterLod): the roots of one or more hierarchies
/// built elsewhere, such as neighbouring out-of-core partitions, over points whose identity the
/// caller has settled (two vertices are one point when the caller gives them one id; positions may
/// repeat across ids).
struct ClusterLodSeed {
    std::vector<Vec3f> points;
    std::vector<uint32_t> triangles; // 3 point ids per triangle, each cluster's in one range
    struct Cluster {
        uint32_t first_triangle = 0;
        uint32_t triangle_count = 0; // 1..128, over at most 255 distinct points
        // What the groups above it must respect for monotonicity: its error and LOD sphere (its
        // self group's, or 0 and its bounding sphere for an LOD0 cluster), the culling sphere of
        // everything below and including it, and its self group's depth (0 for LOD0).
        float error = 0;
        float lod_center[3] = {};
        float lod_radius = 0;
        float bounds_center[3] = {};
        float bounds_radius = 0;
        uint32_t depth = 0;
    };
    std::vector<Cluster> clusters;
};

/// Builds on from `seed` as buildClusterLod builds on from LOD0's clusters: the seed clusters are
/// the first level (clusters[0, seed.clusters.size()) of the result, in order, with lod0_cluster_count
/// their number; their self_group is none, their errors and spheres are the caller's to keep), grouped
/// by shared point pairs, simplified with lock_border, measured and split, level by level until one
/// cluster remains or a level stalls. A group's error is its measured distance plus its inputs'
/// largest error, its LOD sphere encloses theirs, its culling sphere their culling spheres and its
/// outputs, and its depth is one more than its deepest input's. Deterministic for any thread count.
/// Fails (InvalidInput) on a seed cluster outside the limits or its ranges, a point id out of range,
/// or a non-finite position, error or sphere.
Result<ClusterLodHierarchy> continueClusterLod(const ClusterLodSeed& seed, const ClusterLodOptions& options,
                                               Diagnostics& diagnostics);

} // namespace lodbake
