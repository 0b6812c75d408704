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
    LodChain, // simplification and error measurement of every level
    Textures, // texture levels
    Encode,   // compressed streams (PFRep, valence, ...)
    Pack,     // GLB serialisation of the whole pack
    Write,    // atomic write of the outputs (batch runner)
    Count
};

/// Stable lower-case name ("load", "repair", "lod_chain", "textures", "encode", "pack", "write").
const char* bakeStageName(BakeStage stage);

/// Sentinel input index for stages that concern the whole pack (Pack, Write).
constexpr size_t kWholePack = size_t(-1);

/// Observers of bake(). Called from worker threads, concurrently: the callee synchronises.
struct BakeHooks {
    /// `stage` of input `input` (or kWholePack) finished after `seconds` of wall time.
    std::function<void(size_t input, BakeStage stage, double seconds)> stage_done;
};

/// Reports a stage's wall time to the hooks when it goes out of scope (or at finish()).
class StageTimer {
public:
    StageTimer(const BakeHooks& hooks, size_t input, BakeStage stage)
        : hooks_(hooks), input_(input), stage_(stage), start_(std::chrono::steady_clock::now()) {}
    ~StageTimer() { finish(); }
    void finish() {
        if (done_ || !hooks_.stage_done) return;
        done_ = true;
        hooks_.stage_done(input_, stage_,
                          std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count());
    }

private:
    const BakeHooks& hooks_;
    size_t input_;
    BakeStage stage_;
    std::chrono::steady_clock::time_point start_;
    bool done_ = false;
};

} // namespace lodbake
