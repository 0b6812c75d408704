#pragma once
// Progress accounting for a batch of bakes: the fraction done and the ETA from stage events, and
// the text of a one-line progress bar. It only formats: the CLI decides where (and whether) to print.
// Not thread-safe: the caller serialises calls.

#include <cstddef>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "lodbake/bake/stages.h"

namespace lodbake {

class BatchProgress {
public:
    /// `job_weights[j]`: relative cost of job j (e.g. its input bytes; zeros count as 1);
    /// `job_inputs[j]`: its input count; `job_names[j]`: a short name (the output file name);
    /// `job_levels[j]`: its LOD level count (the coding reports one run per level; default 1).
    BatchProgress(std::vector<double> job_weights, std::vector<size_t> job_inputs, std::vector<std::string> job_names,
                  std::vector<size_t> job_levels = {});

    /// A stage of one input (or of the whole job, kWholePack) finished.
    void stageDone(size_t job, size_t input, BakeStage stage);
    /// A run of a stage began (running) or ended (BakeHooks::stage_running): the bar names the stage
    /// that is running, the one with the largest share when several run side by side.
    void stageRunning(size_t job, size_t input, BakeStage stage, bool running);
    /// The stage the bar names for the job it names: running, else the last one finished.
    BakeStage shownStage() const;
    /// The job finished (baked, served from the cache, or failed).
    void jobDone(size_t job);

    double fraction() const; // in [0, 1]
    size_t jobsDone() const { return jobs_done_; }
    size_t jobCount() const { return weights_.size(); }
    /// Seconds left, extrapolated from `elapsed_seconds`; negative while too little is known.
    double etaSeconds(double elapsed_seconds) const;

    /// "[#########...........]  45%  3/7  measure bunny.glb  ETA 0:42", at most `width` columns.
    std::string barLine(double elapsed_seconds, size_t width) const;

    /// "m:ss" (or "h:mm:ss").
    static std::string formatDuration(double seconds);

private:
    std::vector<double> weights_;
    std::vector<size_t> inputs_;
    std::vector<std::string> names_;
    std::vector<size_t> levels_;
    std::vector<double> done_;       // per job, fraction in [0, 1]
    std::map<std::tuple<size_t, size_t, BakeStage>, double> stage_done_; // (job, input, stage): share earned
    std::map<std::pair<size_t, BakeStage>, int> running_;                   // (job, stage): runs under way
    double total_weight_ = 0;
    size_t jobs_done_ = 0;
    size_t last_job_ = size_t(-1);
    BakeStage last_stage_ = BakeStage::Load;
};

} // namespace lodbake
