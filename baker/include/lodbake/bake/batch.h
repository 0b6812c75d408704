#pragma once
// The batch runner behind `lodbake bake`: many independent packs ("jobs"), baked in parallel with a
// fixed decomposition (one task per job, each writing only its own output and result slot), so the
// bytes of every pack are those a one-job, one-thread run writes. Optionally served from and stored
// into the content-hash cache (cache.h).

#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <string>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/bake/stages.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// One pack: its inputs (each a LOD group named after the file stem), its output and settings.
struct BakeJob {
    std::vector<std::string> inputs;
    std::string output; // .glb path, written atomically
    BakeSettings settings;
};

/// What an out-of-core bake (BatchOptions::out_of_core) made: the pack, already written to the path
/// it was given, and its report.
struct OutOfCorePack {
    uint64_t pack_bytes = 0;
    BakeAssetReport report; // the chain's metrics (metrics.input_triangles set: where it starts)
    /// Wall seconds of what ran, in order (the driver's stages as LodChain, the levels as Encode, the
    /// GLB as Pack).
    std::vector<std::pair<BakeStage, double>> stage_seconds;
};

/// Bakes `job` (one PLY or OBJ input, settings.cluster_lod) out of core within `memory_limit_bytes`
/// with at most `threads` workers (0: all), writing its pack to `glb_path` (a temporary the runner
/// stages for job.output). Leaves no file behind on an error.
using OutOfCoreBake = std::function<Result<OutOfCorePack>(const BakeJob& job, const std::string& glb_path,
                                                          uint64_t memory_limit_bytes, uint32_t threads,
                                                          Diagnostics& diagnostics)>;

/// True when `job` may be baked out of core: one input, PLY or OBJ, settings.cluster_lod, not --web.
bool outOfCoreEligible(const BakeJob& job);

struct BatchOptions {
    std::string cache_dir; // content-hash cache folder; empty: no cache
    uint32_t threads = 0;  // worker threads for the whole batch; 0: all cores (job settings.threads is ignored)
    ReadOptions read;      // reader limits for every input (a pack that reads fine does not depend on them)
    // Resident memory the jobs running side by side may be allowed together (memory_budget.h); a job
    // whose allowance alone exceeds it fails (ResourceLimit). 0: no limit. Never changes a pack's bytes.
    uint64_t memory_limit_bytes = 0;
    // Set: a job whose allowance exceeds memory_limit_bytes and that outOfCoreEligible() accepts is
    // baked by this instead of refused (lodbake/ooc/ooc_pack.h behind it in the CLI), holding the
    // whole limit while it runs. Unset, or an ineligible job: refused as before.
    OutOfCoreBake out_of_core;
};

struct BakeJobResult {
    Status status = Status::okStatus();
    Diagnostics diagnostics; // warnings of this job, in stage order
    bool cache_hit = false;
    std::string cache_key;   // on a hit: the key of the cache entry (packs/<key>.bin)
    bool unchanged = false;  // on a hit: the output already held the pack's bytes, so it is left untouched
    std::string cache_warning;           // a cache store that failed (the pack itself is fine)
    std::vector<std::string> files_read; // every input file read (inputs, MTL, textures, scans...)
    std::string report_json;             // bakeReportJson of the pack
    std::string summary;                 // bakeSummaryText of the pack
    uint64_t pack_bytes = 0;
    StageTime stage_times[size_t(BakeStage::Count)] = {}; // summed over the job's inputs
    /// Every run of a stage in the order they began (an input's stages, each level's coding, the
    /// measurement's parts...): the job's timeline, for seeing what ran side by side and what idled.
    struct StageRun {
        BakeStage stage = BakeStage::Load;
        size_t input = kWholePack;        // input index, or kWholePack
        size_t level = StageTime::kNoLevel; // the level worked on, when one
        double start_seconds = 0;         // since the job began
        double wall_seconds = 0;
        double thread_cpu_seconds = 0;
    };
    std::vector<StageRun> timeline;
    double wall_seconds = 0;
    /// The pack, written to its temporary but not yet renamed into place (null on failure): the
    /// caller commits it (after staging its own report and depfile), or drops it to discard the pack.
    std::unique_ptr<AtomicFileWriter> staged;
};

/// Observers of runBakeJobs, called from worker threads (the callee synchronises).
struct BatchHooks {
    std::function<void(size_t job, size_t input, BakeStage stage, const StageTime& time)> stage_done;
    std::function<void(size_t job, size_t input, BakeStage stage, bool running)> stage_running; // BakeHooks'
    std::function<void(size_t job, const BakeJobResult& result)> job_done;
    std::function<void()> release_memory; // passed to bake() as BakeHooks::release_memory
};

/// Bakes every job (each reads its inputs, bakes them into one pack and stages `output` in
/// BakeJobResult::staged; nothing is renamed into place here, so an interrupted run leaves no
/// output), at most options.threads workers. Jobs start largest first (by input bytes), so the
/// longest one does not start last and leave the other workers idle at the end. Under a memory
/// limit a job waits, before it loads, until the running jobs leave room for its allowance. Results come back in job order; one
/// failing job does not stop the others. The caller checks outputs for clashes with inputs and with each other
/// beforehand.
std::vector<BakeJobResult> runBakeJobs(const std::vector<BakeJob>& jobs, const BatchOptions& options,
                                       const BatchHooks& hooks);

/// Group name of an input path: its file name without the last extension.
std::string inputGroupName(const std::string& path);

/// One line per asset: "<name>: <input triangles> triangles -> <n> levels: <triangles per level>".
std::string bakeSummaryText(const BakeOutput& output);

} // namespace lodbake
