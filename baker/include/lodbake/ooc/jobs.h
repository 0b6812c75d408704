#pragma once
// The out-of-core bake as a list of jobs that read and write files only (docs/pipeline.md, "Job
// list"), so that a build farm can run them as separate processes on other machines:
//
//  - planOutOfCore() runs the partitioner (the one read of the input) into a work folder and writes
//    the job list, <work>/plan.json: one partition job per partition file. The merge rounds depend on
//    the sizes of the files the jobs before them wrote (mergeAll's grouping), so the plan is
//    incremental: once every listed job has run, planOutOfCore() again (it reads the plan, not the
//    input) appends the next round's merge jobs, and after the last merge the pages job. Each step
//    adds exactly the jobs buildOutOfCore runs, with the same options, so the last job's files are
//    the bytes buildOutOfCore writes.
//  - runJob() runs one listed job from the files alone: its inputs are files named by content hash or
//    the outputs of the jobs it depends on, found through their records; it writes its output (named
//    by content hash) and then its record, <work>/job-<id>.json, through a temporary renamed into
//    place, so a job that fails or is killed leaves no record and the job simply runs again.
//
// The in-process driver (lodbake/ooc/driver.h) runs the same job functions (runPartitionJob,
// runMergeJob, runPagesJob) and the same round planning on TBB under one MemoryGate.
//
// Errors name the file: a plan or record that is not what this version writes, a job whose inputs
// are missing, an input whose bytes do not hash to its name. Library code: nothing is printed.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/driver.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/ooc/tree_pages.h"

namespace lodbake::ooc {

/// The version of plan.json and of the job records this code reads and writes.
constexpr uint32_t kJobListVersion = 1;

enum class JobKind : uint32_t { Partition = 0, Merge = 1, Pages = 2 };

/// "partition", "merge" or "pages".
const char* jobKindName(JobKind kind);

/// One input of a job: a file of the work folder named by content hash (`file`, a partition job's
/// partition), or the output of the job `job` (its record names the file).
struct JobInput {
    std::string file;
    std::string job;
};

/// A job of the plan. Ids: partition-<leaf> (leaf order), merge-<tree node> (the merge tree's nodes
/// in preorder, node 0 the top), pages.
struct JobSpec {
    std::string id;
    JobKind kind = JobKind::Partition;
    // partition: one file; merge: two jobs (the left and right subtree); pages: every partition job in
    // leaf order, then every merge job in the order they were planned (the last one is the top).
    std::vector<JobInput> inputs;
    ClusterLodOptions cluster; // partition and merge: max_levels is this job's
    ClusterPackOptions pack;   // pages
    uint64_t hash = 0;         // of the job's JSON (what a record is checked against)
};

/// The options of a plan that shape the output (OutOfCoreOptions' fields of the same names).
struct JobPlanOptions {
    uint64_t leaf_triangles = kDefaultLeafTriangles;
    uint64_t merge_group_bytes = kDefaultMergeGroupBytes;
    uint64_t sample_cap = uint64_t(1) << 20;
    ClusterLodOptions cluster;
    ClusterPackOptions pack;
};

/// The job list, as plan.json holds it.
struct JobPlan {
    std::string input; // as given to planOutOfCore (informational)
    uint64_t vertex_count = 0, triangle_count = 0;
    JobPlanOptions options;
    uint32_t merge_rounds = 0; // planned so far
    bool complete = false;     // the pages job is listed: nothing more will be added
    std::vector<JobSpec> jobs; // in the order buildOutOfCore runs them
    const JobSpec* find(const std::string& id) const;
};

/// What a finished job wrote, as its record (job-<id>.json) holds it. File names are relative to the
/// work folder.
struct JobRecord {
    std::string id;
    JobKind kind = JobKind::Partition;
    uint64_t job_hash = 0;          // JobSpec::hash of the job it ran
    std::vector<std::string> inputs; // the input files (content-hash names), in the job's order
    std::string output;             // partition: .lbplod, merge: .lbpmrg, pages: .lbpages
    uint64_t output_hash = 0, output_bytes = 0;
    MergeInputSize size;            // partition and merge: what the output adds to a merge's bound
    std::string table;              // pages: the table blob, .lbtable
    uint64_t table_hash = 0, table_bytes = 0;
    uint32_t cluster_count = 0;     // pages
    ClusterPackStats stats;         // pages
};

/// Runs the partitioner over `input` into `work_dir` (created if missing; options.work_dir is not
/// used) and writes the plan with one partition job per partition. When `work_dir` already holds a
/// plan, reads it instead (not the input) and, once every job it lists has a valid record, appends
/// the next round of merge jobs or, after the top merge, the pages job; the plan's options must be
/// `options`' and `input`, unless empty, the plan's (InvalidInput naming the plan otherwise). The plan
/// is written through a temporary.
Result<JobPlan> planOutOfCore(const std::string& input, const std::string& work_dir, const OutOfCoreOptions& options,
                              Diagnostics& diagnostics);

struct JobRunOptions {
    uint64_t memory_limit_bytes = uint64_t(1) << 30; // the job refuses to start when its bound exceeds it
    size_t pages_in_flight = 0;                      // pages job (ClusterPackStreamOptions); no effect on bytes
    int threads = 0;                                 // worker threads; 0: TBB's default; no effect on bytes
    const std::atomic<bool>* cancel = nullptr;
};

/// Runs job `job_id` of the plan in `work_dir` from files alone and writes its record. Every input
/// must be there: a job input's record (InvalidInput naming the missing record), its file, and the
/// bytes of every input file must hash to its name (InvalidInput naming the file). A job that already
/// has a record runs again and writes the same bytes.
Result<JobRecord> runJob(const std::string& work_dir, const std::string& job_id, const JobRunOptions& options,
                         Diagnostics& diagnostics);

/// The plan and record files of a work folder.
std::string jobPlanPath(const std::string& work_dir);
std::string jobRecordPath(const std::string& work_dir, const std::string& job_id);

/// Parses a plan (text of plan.json; `path` names it in errors) or a record. Every field is checked:
/// a document that is not what this version writes is InvalidInput naming `path`, never a crash.
Result<JobPlan> parseJobPlan(const std::string& text, const std::string& path);
Result<JobRecord> parseJobRecord(const std::string& text, const std::string& path);
Result<JobPlan> readJobPlan(const std::string& path);
Result<JobRecord> readJobRecord(const std::string& path);
/// The JSON text of a plan or record (what planOutOfCore and runJob write).
std::string jobPlanJson(const JobPlan& plan);
std::string jobRecordJson(const JobRecord& record);

/// The hash of a job's JSON (JobSpec::hash), and whether two plans' options are the same.
uint64_t jobSpecHash(const JobSpec& job);
bool sameJobPlanOptions(const JobPlanOptions& a, const JobPlanOptions& b);

/// Where the jobs of a plan stand: done (a record of the listed job is there) or ready (not done,
/// every job it depends on done).
struct JobProgress {
    std::vector<std::string> done, ready;
    size_t total = 0;
};
JobProgress jobProgress(const std::string& work_dir, const JobPlan& plan);

/// The result of a finished plan as buildOutOfCore returns it (output: the pages blob's file; table:
/// the table blob read back; the merge tree over the jobs' files), from the records alone. What the
/// GLB writer of an out-of-core bake takes; InvalidInput naming the plan when it is not complete.
Result<OutOfCoreResult> plannedResult(const std::string& work_dir);

/// Removes every file of the plan in `work_dir`: each job's input files, output, table and record
/// (those that are there), then plan.json; what was not removed is left quietly (the work folder is
/// the caller's). What a finished bake does once its GLB is written.
void removePlannedFiles(const std::string& work_dir);

// The job functions, shared by runJob and the in-process driver.

/// A partition job's output: the hierarchy file and what it adds to a merge's bound.
struct PartitionJobOutput {
    PartitionLodFile file;
    MergeInputSize size;
};

/// The partition at `partition_path` built (buildPartition) into `work_dir` with `cluster`.
Result<PartitionJobOutput> runPartitionJob(const std::string& partition_path, const std::string& work_dir,
                                           const ClusterLodOptions& cluster, uint64_t memory_limit_bytes,
                                           Diagnostics& diagnostics);

/// Two hierarchies merged (mergePartitionLods) into `work_dir` with `cluster` (max_levels: the
/// levels this merge builds).
Result<MergeFile> runMergeJob(const std::string& left, const std::string& right, const std::string& work_dir,
                              const ClusterLodOptions& cluster, uint64_t memory_limit_bytes, Diagnostics& diagnostics);

/// The pages of `tree` (writeTreeClusterPages) spilled beside `output_path`; the caller renames the
/// spill (result.pack.pages) into place.
Result<TreePagesResult> runPagesJob(const MergeTree& tree, const std::string& output_path,
                                    const TreePagesOptions& options);

/// The cluster options of a partition job in a plan of `partitions` partitions: every level when
/// there is one partition (it is the top), else kLevelsPerJob at most.
ClusterLodOptions partitionJobCluster(const ClusterLodOptions& cluster, size_t partitions);

/// The merge options the rounds are chosen with (roundNodes, as mergeAll's): grouped by
/// `merge_group_bytes`, or by `memory_limit_bytes` when that is 0 (not in a plan).
MergeOptions planMergeOptions(const ClusterLodOptions& cluster, uint64_t merge_group_bytes,
                              uint64_t memory_limit_bytes);

/// The partitioner's options of an out-of-core bake (the driver's and the plan's): leaves of
/// options.leaf_triangles sized for the partition job.
PartitionOptions outOfCorePartitionOptions(const OutOfCoreOptions& options);

} // namespace lodbake::ooc
