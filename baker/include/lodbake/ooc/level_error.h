#pragma once
// A level's error against the input, measured out of core (docs/pipeline.md, "Errors against the
// input"): the two-sided surface distance of measureSurfaceDistance (lodbake/simplify/mesh_distance.h,
// the measurement behind LODBAKE_lod_metrics) between the input, read one partition file
// (lodbake/ooc/partition.h) at a time, and one level mesh held in memory.
//
// The points are the ones measureSurfaceDistance draws with the input's triangles in partition order
// (the partitions in the order given, each file's triangles in file order) and its vertices once each:
//  - input -> level: the area-uniform stratified samples over the input's area CDF (accumulated
//    partition after partition exactly as one pass over the whole mesh would), then every input
//    vertex once (the first partition holding it measures it), each measured against the level's index
//    while its partition is loaded;
//  - level -> input: the level's own samples and vertices, each measured against every partition
//    whose bounds are within its current nearest distance (started from a subsample of the input's
//    triangles, so that the partitions far from a point are skipped); the nearest over all
//    partitions is exactly the nearest over the whole input.
// The level side is therefore bit for bit the in-memory measurement's; the input side is the same
// points and the same distances summed in another order (equal up to the rounding of the sums; its
// maximum and count exactly). Deterministic for any thread count.
//
// Memory formula (bytes; T_L triangles and P_L measured points of the level (sample_count plus its
// referenced vertices), S subsample triangles, I the largest input global id + 1, V_p and T_p a
// partition's vertices and triangles, the largest over the partitions):
//   pass 1  (areas)      48 S + 16 V_p + 12 T_p
//   level               128 S + 88 T_L + 52 P_L + I / 8
//   pass 2  (distances)  88 T_L + 40 P_L + I / 8 + 20 V_p + 100 T_p
// With several levels (measureLevelErrors) the level terms are summed over them. The bound is the
// largest of the three (the caller's level mesh aside); a limit below it is a ResourceLimit error naming the first
// partition file and the minimum. 80 bytes per triangle is an allowance for a DistanceIndex and its
// build, and 8 per triangle the partition's area CDF.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/simplify/mesh_distance.h"

namespace lodbake::ooc {

/// Bytes a DistanceIndex and its build hold per triangle (allowance): corners, slots, nodes and the
/// build's sort keys.
constexpr uint64_t kDistanceIndexBytesPerTriangle = 80;

struct LevelErrorOptions {
    DistanceOptions distance; // as the in-memory measurement's (the bake sets sample_count to error_samples)
    uint64_t memory_limit_bytes = uint64_t(1) << 30;
    int threads = 0;                    // 0: TBB's default
    uint32_t bound_triangles = 1u << 18; // S at most: the subsample that starts the level side's search
    const std::atomic<bool>* cancel = nullptr; // set to stop: the measurement fails
};

struct LevelErrorResult {
    DistanceResult distance; // what the in-memory level metrics record (LodLevel::distance)
    uint64_t partition_count = 0;
    uint64_t input_triangles = 0;
    uint64_t input_vertices = 0;     // distinct global ids over the partitions
    uint64_t level_points = 0;       // P_L
    uint64_t level_queries = 0;      // level points measured against a partition (P_L at least)
    uint64_t subsample_triangles = 0; // S
    uint64_t memory_bound_bytes = 0;   // the formula above
    uint64_t accounted_peak_bytes = 0; // the largest total of the arrays above held at one time
};

/// Measures `level` against the input held by `partition_files` (partitioner output, .lbpart, in leaf
/// order). Every file is read whole twice (its areas, then its distances), one at a time, and checked:
/// a missing, truncated or corrupted file (its bytes must hash to its name when the name is a content
/// hash), or one changed between the two reads, is an InvalidInput or IoError naming it. A bad level
/// or options fail as measureSurfaceDistance does.
Result<LevelErrorResult> measureLevelError(const std::vector<std::string>& partition_files, const Mesh& level,
                                           const LevelErrorOptions& options);

/// Several levels in one pass over the files: each file is read twice and indexed once for all of them.
/// results[i] is bit for bit what measureLevelError(partition_files, *levels[i], options) returns,
/// except the memory figures, which are the whole run's (the level terms of the formula summed over
/// the levels). Pointers must not be null.
Result<std::vector<LevelErrorResult>> measureLevelErrors(const std::vector<std::string>& partition_files,
                                                         const std::vector<const Mesh*>& levels,
                                                         const LevelErrorOptions& options);

/// The memory bound of measureLevelErrors(partition_files, levels, options) (the formula above), from
/// the files' headers and the levels alone, whatever options.memory_limit_bytes: what a caller
/// reserves at a MemoryGate before running it. Fails as the measurement does for a bad level, options
/// or header.
Result<uint64_t> levelErrorBound(const std::vector<std::string>& partition_files, const std::vector<const Mesh*>& levels,
                                 const LevelErrorOptions& options);

/// The same over a partitioner's set (its files in leaf order).
Result<LevelErrorResult> measureLevelError(const PartitionSet& set, const Mesh& level, const LevelErrorOptions& options);

/// The partition files (.lbpart) a merge tree's partition hierarchies were built from, in leaf order:
/// `<folder of the hierarchy file>/<its source hash, hex>.lbpart`, read from each hierarchy file's
/// header (what buildOutOfCore leaves with keep_intermediate). A file that is missing or not a
/// partition hierarchy is an error naming it.
Result<std::vector<std::string>> partitionFilesOf(const MergeTree& tree);

} // namespace lodbake::ooc
