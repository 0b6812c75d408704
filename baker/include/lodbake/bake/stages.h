#pragma once
// The stages of a bake, for progress display and per-stage timings (--report). Observing a bake
// never changes its output.

#include <chrono>
#include <cstddef>
#include <functional>

namespace lodbake {

enum class BakeStage {
    Load,     // reading the input files (batch runner)
    Repair,   // repairMesh
    LodChain, // simplification of every level
    Measure,  // error measurement of every level against LOD0 (switch distances)
    Pfrep,    // the streams built from LOD0 alone (StreamNeeds::lod0_only: the LODBAKE_progressive_fans
              // blob, its own half-edge simplification or a replay of the chain's collapses)
    Textures, // texture levels
    Encode,   // the streams of every level (LODBAKE_valence_compression)
    Pack,     // GLB serialisation of the whole pack
    Write,    // atomic write of the outputs (batch runner)
    Count
};

/// Stable lower-case name ("load", "repair", "lod_chain", "measure", "pfrep", "textures", "encode",
/// "pack", "write").
const char* bakeStageName(BakeStage stage);

/// Sentinel input index for stages that concern the whole pack (Pack, Write).
constexpr size_t kWholePack = size_t(-1);

/// CPU seconds used so far by the whole process (all threads) and by the calling thread.
double processCpuSeconds();
double threadCpuSeconds();

/// What one stage cost. Stages of one input run one after the other except Measure, Textures and
/// Encode, which run beside Pfrep (docs/bake.md); inputs of a pack and packs of a batch run
/// concurrently. So `cpu_seconds` (the whole process's CPU time during the stage) is the stage's own
/// cost only when nothing else runs; `thread_cpu_seconds` (CPU time of the thread that ran the stage)
/// is exact for single-threaded stages (Pfrep, Encode, LodChain) and a lower bound otherwise.
struct StageTime {
    double wall_seconds = 0;
    double cpu_seconds = 0;
    double thread_cpu_seconds = 0;
    /// When this run of the stage began, and the LOD level it worked on (kNoLevel: several or none).
    /// Not summed: sums of StageTime (BakeJobResult::stage_times) leave them at their defaults.
    std::chrono::steady_clock::time_point start{};
    size_t level = kNoLevel;
    static constexpr size_t kNoLevel = size_t(-1);
};

/// Observers of bake(). Called from worker threads, concurrently: the callee synchronises.
struct BakeHooks {
    /// `stage` of input `input` (or kWholePack) finished.
    std::function<void(size_t input, BakeStage stage, const StageTime& time)> stage_done;
    /// A run of `stage` began (running = true) or ended, finished or with nothing done (false), so a
    /// progress display can name what is running. Optional.
    std::function<void(size_t input, BakeStage stage, bool running)> stage_running;
    /// A large working set inside a stage was just freed and the next one is about to be built (for
    /// instance between coding a level and decoding it for the check). A program whose allocator
    /// keeps freed pages resident can return them here, so the two do not add up; the bake itself
    /// never touches the allocator's policy. Optional.
    std::function<void()> release_memory;
};

/// Reports a stage's wall and CPU time to the hooks when it goes out of scope (or at finish()).
class StageTimer {
public:
    StageTimer(const BakeHooks& hooks, size_t input, BakeStage stage, size_t level = StageTime::kNoLevel)
        : hooks_(hooks), input_(input), stage_(stage), level_(level), start_(std::chrono::steady_clock::now()),
          cpu_start_(processCpuSeconds()), thread_cpu_start_(threadCpuSeconds()) {
        if (hooks_.stage_running) hooks_.stage_running(input_, stage_, true);
    }
    ~StageTimer() { finish(); }
    /// Reports no time (a run that did no work, e.g. an encoder that codes LOD0 only, asked for another level).
    void cancel() {
        if (!done_ && hooks_.stage_running) hooks_.stage_running(input_, stage_, false);
        done_ = true;
    }
    void finish() {
        if (done_) return;
        done_ = true;
        if (hooks_.stage_running) hooks_.stage_running(input_, stage_, false);
        if (!hooks_.stage_done) return;
        StageTime time;
        time.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        time.cpu_seconds = processCpuSeconds() - cpu_start_;
        time.thread_cpu_seconds = threadCpuSeconds() - thread_cpu_start_;
        time.start = start_;
        time.level = level_;
        hooks_.stage_done(input_, stage_, time);
    }

private:
    const BakeHooks& hooks_;
    size_t input_;
    BakeStage stage_;
    size_t level_;
    std::chrono::steady_clock::time_point start_;
    double cpu_start_;
    double thread_cpu_start_;
    bool done_ = false;
};

} // namespace lodbake
