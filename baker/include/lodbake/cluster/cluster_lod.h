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

} // namespace lodbake
