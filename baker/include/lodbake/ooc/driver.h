#pragma once
// The in-process out-of-core driver (docs/pipeline.md, "The out-of-core driver"): one call that runs
// the out-of-core jobs over a scan under one memory limit: the partitioner (lodbake/ooc/partition.h),
// the partition jobs (partition_build.h) side by side on TBB, the merge rounds (partition_merge.h,
// the independent merges of a round side by side) and the streamed pages of the merge tree
// (tree_pages.h) into the output file the caller names.
//
// Memory: every job states its bound before it runs and reserves it at one MemoryGate
// (lodbake/core/memory_gate.h) whose limit is options.memory_limit_bytes, so the bounds of the jobs
// running at once never sum above the limit; the partitioner and the page writer run alone, each
// within the limit by its own formula. A job whose bound alone exceeds the limit is a ResourceLimit
// error naming its input and the minimum.
//
// Determinism: what shapes the tree (the leaf size, the merge grouping, the levels per job) comes
// from the options, never from the limit or the thread count, which decide only how many jobs run
// at once and whether the run is refused: the output is the same bytes for any thread count and
// any limit at which it runs.
//
// Failure: on any error or a cancel every file the run created is removed (partitions, hierarchy
// and merge files, the page spill, the output) and the work folder is left as it was; on success the
// intermediate files are removed too, unless keep_intermediate is set.

#include <atomic>
#include <cstdint>
#include <string>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/ooc/tree_pages.h"

namespace lodbake::ooc {

/// The default target triangles per partition: a partition job's bound is then about 250 MiB
/// (kPartitionBuildBytesPerTriangle), so two run side by side under a 1 GiB limit beside the
/// partitioner's fixed buffers.
constexpr uint64_t kDefaultLeafTriangles = uint64_t(800) << 10;

/// The default bound a merge job's grouped files must fit (MergeOptions::group_bytes): the same
/// size of job as a partition of kDefaultLeafTriangles.
constexpr uint64_t kDefaultMergeGroupBytes = kPartitionBuildBytesPerTriangle * kDefaultLeafTriangles;

struct OutOfCoreOptions {
    std::string work_dir;                          // partitions, hierarchy and merge files; created if missing
    uint64_t memory_limit_bytes = uint64_t(1) << 30;
    int threads = 0;                               // jobs at once at most; 0: TBB's default
    uint64_t leaf_triangles = kDefaultLeafTriangles;      // shapes the tree (PartitionOptions::leaf_triangles)
    uint64_t merge_group_bytes = kDefaultMergeGroupBytes; // shapes the tree (MergeOptions::group_bytes)
    ClusterLodOptions cluster;                     // every job's (max_levels: the top merge's)
    StreamReadOptions read;
    uint64_t sample_cap = uint64_t(1) << 20;       // shapes the tree (PartitionOptions::sample_cap)
    ClusterPackStreamOptions pages;                // the page writer's (its cancel is set from `cancel`)
    const std::atomic<bool>* cancel = nullptr;     // set to stop: the run fails and removes its files
    bool keep_intermediate = false;                // leave the partitions, hierarchy and merge files
};

/// One stage's wall time and what it went through.
struct OutOfCoreStage {
    double seconds = 0;
    uint64_t jobs = 0;
};

struct OutOfCoreResult {
    std::string output;              // the pages blob of LODBAKE_cluster_lod (the spill, renamed)
    std::vector<uint8_t> table;      // the extension's table blob
    ClusterPackStats stats;
    uint64_t triangle_count = 0, vertex_count = 0;
    uint64_t partition_count = 0, merge_count = 0, merge_rounds = 0, cluster_count = 0;
    // The largest total of bytes accounted at one time: the partitioner's accounted peak, the sum of
    // the running jobs' bounds at the gate, the table's and the page writer's accounted peaks.
    uint64_t accounted_peak_bytes = 0;
    uint64_t partition_peak_bytes = 0, jobs_peak_bytes = 0, pages_peak_bytes = 0;
    OutOfCoreStage partition, build, merge, pages;
    MergeTree tree; // the files it names are gone unless keep_intermediate was set
};

/// Bakes `input` (.ply or .obj) out of core into the LODBAKE_cluster_lod pages at `output_path`.
/// Errors as the jobs' (each names its file); a cancel is an error naming the input.
Result<OutOfCoreResult> buildOutOfCore(const std::string& input, const std::string& output_path,
                                       const OutOfCoreOptions& options, Diagnostics& diagnostics);

} // namespace lodbake::ooc
