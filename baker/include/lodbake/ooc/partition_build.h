#pragma once
// The partition job of the out-of-core bake (docs/pipeline.md, "Partition jobs"): one partition file
// (lodbake/ooc/partition.h) in, its cluster hierarchy out, as a file named by content hash, so that a
// job can run in any process and a later step can merge neighbouring partitions' roots.
//
// The partition's border with the other partitions is locked. A partition edge shared with a
// triangle of another partition is used by one triangle of this partition (on a manifold input), so
// it is an open boundary of the partition mesh (not so for a non-manifold edge or point that the cut
// leaves with a whole manifold piece on one side: such inputs can crack), and buildClusterLod's group simplification
// (lock_border) never moves or removes an open-boundary point: every level of every partition keeps
// the border edge for edge, and cuts of independently built partitions meet without cracks. The
// input's own open boundaries are locked the same way, as in the in-memory build. The hierarchy
// stops where the locked border stops it: the remaining roots and the border (global ids, positions,
// edges) are recorded for the merge step.
//
// Memory formula (bytes; V vertices and T triangles of the partition):
//   bound = 16 V + 12 T                          (the partition read back: ids, positions, triangles)
//         + kClusterBuildBytesPerTriangle * T    (buildClusterLod's working set and its output)
//         + 1 MiB                                (the output file's write buffer)
// A limit below the bound is a ResourceLimit error naming the file and the minimum.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"

namespace lodbake::ooc {

/// Bytes per partition triangle allowed for buildClusterLod, output included: welded points and
/// triangles, every level's cluster layouts and the graph of a level, the flattened hierarchy (about
/// twice LOD0's triangles over all levels), and the groups simplified at once. An allowance with
/// about a factor of two of margin over the resident memory of whole jobs (ooc_bench --cluster),
/// not a proven bound: the builder's arrays depend on how the levels shrink.
constexpr uint64_t kClusterBuildBytesPerTriangle = 256;

/// The memory formula's bytes per triangle whatever the partition (at most 3 vertices per
/// triangle): the value for PartitionOptions::build_bytes_per_triangle, so that partitions are sized
/// for this job under the same limit (its 1 MiB write buffer is within the partitioner's per-job
/// 1 MiB + 64 KiB).
constexpr uint64_t kPartitionBuildBytesPerTriangle = 16 * 3 + 12 + kClusterBuildBytesPerTriangle;

struct PartitionBuildOptions {
    std::string work_dir; // where the output goes; created if missing
    uint64_t memory_limit_bytes = uint64_t(1) << 30;
    ClusterLodOptions cluster;
};

/// What a job wrote.
struct PartitionLodFile {
    std::string path; // <work_dir>/<content hash, hex><kPartitionLodExtension>
    uint64_t content_hash = 0;
    uint64_t source_hash = 0; // content hash of the partition file it was built from
    uint32_t triangle_count = 0; // the partition's
    uint32_t cluster_count = 0, group_count = 0, root_count = 0, level_count = 0;
    uint32_t border_vertex_count = 0, border_edge_count = 0;
    bool reached_single_group = false;
    uint64_t memory_bound_bytes = 0;    // the formula above
    uint64_t accounted_peak_bytes = 0;  // the arrays held, with the builder at its per-triangle bound
};

/// Builds the partition at `partition_path`. Deterministic for any thread count (buildClusterLod is).
/// Errors name the file: a truncated or corrupted partition (its bytes must hash to its name when the
/// name is a content hash) is InvalidInput; no output is left behind on any error.
Result<PartitionLodFile> buildPartition(const std::string& partition_path, const PartitionBuildOptions& options,
                                        Diagnostics& diagnostics);

/// A partition's hierarchy read back.
struct PartitionLod {
    uint64_t source_hash = 0;
    ClusterLodHierarchy hierarchy;
    std::vector<uint32_t> border_ids;    // global ids of the border's vertices, increasing
    std::vector<Vec3f> border_positions; // their positions (unchanged at every level)
    std::vector<uint32_t> border_edges;  // 2 per edge, indices into border_ids (smaller first), sorted
};

/// Reads and checks a file written by buildPartition (layout in docs/pipeline.md, "Partition jobs").
Result<PartitionLod> readPartitionLodFile(const std::string& path);

} // namespace lodbake::ooc
