// Batch progress. Each stage is a fixed share of a job, set from the stages' wall times on the
// shared scans (docs/benchmarks.md, "Bake timeline": the LOD chain and the error measurement take
// most of it, the PFRep build runs beside the measurement); a job's share is its weight over the
// total. A stage that runs several times (the measurement in two parts, the coding once per level)
// earns its share a run at a time, and never more than its share.
#include "lodbake/bake/progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iterator>

namespace lodbake {

namespace {

constexpr double kStageShare[size_t(BakeStage::Count)] = {
    0.01,  // Load
    0.09,  // Repair (and the range-view merge, when it runs)
    0.36,  // LodChain
    0.30,  // Measure: two runs, the reference sides then the rest
    0.07,  // Pfrep: beside the measurement's first run
    0.01,  // Textures
    0.15,  // Encode: one run per level
    0.007, // Pack
    0.003, // Write
};

// How many runs of `stage` one input reports , so each earns its part of the share.
size_t stageRuns(BakeStage stage, size_t levels) {
    if (stage == BakeStage::Measure) return 2;
    if (stage == BakeStage::Encode) return std::max<size_t>(1, levels);
    return 1;
}

} // namespace

double processCpuSeconds() {
#if defined(CLOCK_PROCESS_CPUTIME_ID)
    timespec ts{};
    if (::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) == 0) return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
#endif
    return double(std::clock()) / CLOCKS_PER_SEC;
}

double threadCpuSeconds() {
#if defined(CLOCK_THREAD_CPUTIME_ID)
    timespec ts{};
    if (::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) == 0) return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
#endif
    return 0; // unknown: reported as 0
}

const char* bakeStageName(BakeStage stage) {
    switch (stage) {
    case BakeStage::Load:
        return "load";
    case BakeStage::Repair:
        return "repair";
    case BakeStage::LodChain:
        return "lod_chain";
    case BakeStage::Measure:
        return "measure";
    case BakeStage::Pfrep:
        return "pfrep";
    case BakeStage::Textures:
        return "textures";
    case BakeStage::Encode:
        return "encode";
    case BakeStage::Pack:
        return "pack";
    case BakeStage::Write:
        return "write";
    case BakeStage::Count:
        break;
    }
    return "?";
}

BatchProgress::BatchProgress(std::vector<double> job_weights, std::vector<size_t> job_inputs,
                             std::vector<std::string> job_names, std::vector<size_t> job_levels)
    : weights_(std::move(job_weights)), inputs_(std::move(job_inputs)), names_(std::move(job_names)),
      levels_(std::move(job_levels)), done_(weights_.size(), 0.0) {
    for (double& w : weights_) {
        if (!(w > 0)) w = 1;
        total_weight_ += w;
    }
    inputs_.resize(weights_.size(), 1);
    names_.resize(weights_.size());
    levels_.resize(weights_.size(), 1);
}

void BatchProgress::stageDone(size_t job, size_t input, BakeStage stage) {
    if (job >= done_.size() || stage == BakeStage::Count) return;
    const double inputs = double(input == kWholePack ? 1 : std::max<size_t>(1, inputs_[job]));
    auto earn = [&](BakeStage s, double part) {
        const double share = kStageShare[size_t(s)] / inputs;
        double& earned = stage_done_[{job, input, s}];
        const double gained = std::min(share - earned, part * share);
        if (gained <= 0) return;
        earned += gained;
        done_[job] = std::min(0.99, done_[job] + gained);
    };
    // The texture levels follow the measurement's last run, which some inputs split in two and
    // others do not: whatever of the measurement's share is left is earned here.
    if (stage == BakeStage::Textures) earn(BakeStage::Measure, 1.0);
    earn(stage, 1.0 / double(stageRuns(stage, levels_[job])));
    last_job_ = job;
    last_stage_ = stage;
}

void BatchProgress::stageRunning(size_t job, size_t /*input*/, BakeStage stage, bool running) {
    if (job >= done_.size() || stage == BakeStage::Count) return;
    int& count = running_[{job, stage}];
    count = running ? count + 1 : std::max(0, count - 1);
    if (running) last_job_ = job;
}

BakeStage BatchProgress::shownStage() const {
    BakeStage shown = last_stage_;
    double largest = -1;
    for (const auto& [key, count] : running_)
        if (key.first == last_job_ && count > 0 && kStageShare[size_t(key.second)] > largest) {
            largest = kStageShare[size_t(key.second)];
            shown = key.second;
        }
    return shown;
}

void BatchProgress::jobDone(size_t job) {
    for (auto it = running_.begin(); it != running_.end();)
        it = it->first.first == job ? running_.erase(it) : std::next(it);
    if (job >= done_.size() || done_[job] >= 1.0) return;
    done_[job] = 1.0;
    ++jobs_done_;
}

double BatchProgress::fraction() const {
    if (total_weight_ <= 0) return 1.0;
    double sum = 0;
    for (size_t j = 0; j < done_.size(); ++j) sum += weights_[j] * done_[j];
    return std::min(1.0, sum / total_weight_);
}

double BatchProgress::etaSeconds(double elapsed_seconds) const {
    const double f = fraction();
    if (f < 0.02 || elapsed_seconds < 0.5) return -1;
    return elapsed_seconds * (1.0 - f) / f;
}

std::string BatchProgress::formatDuration(double seconds) {
    const long s = long(std::lround(std::max(0.0, seconds)));
    char buf[32];
    if (s >= 3600)
        std::snprintf(buf, sizeof(buf), "%ld:%02ld:%02ld", s / 3600, (s / 60) % 60, s % 60);
    else
        std::snprintf(buf, sizeof(buf), "%ld:%02ld", s / 60, s % 60);
    return buf;
}

std::string BatchProgress::barLine(double elapsed_seconds, size_t width) const {
    const double f = fraction();
    char pct[16];
    std::snprintf(pct, sizeof(pct), "%3d%%", int(std::floor(f * 100.0 + 1e-9)));
    std::string tail = std::string("  ") + pct + "  " + std::to_string(jobs_done_) + "/" + std::to_string(jobCount());
    if (last_job_ < names_.size()) tail += std::string("  ") + bakeStageName(shownStage()) + " " + names_[last_job_];
    const double eta = etaSeconds(elapsed_seconds);
    tail += "  ETA " + (eta < 0 ? std::string("--:--") : formatDuration(eta));
    const size_t bar_cells = width > tail.size() + 12 ? std::min<size_t>(40, width - tail.size() - 2) : 10;
    const size_t filled = size_t(std::floor(f * double(bar_cells)));
    std::string line = "[" + std::string(filled, '#') + std::string(bar_cells - filled, '.') + "]" + tail;
    if (width > 0 && line.size() > width) line.resize(width);
    return line;
}

} // namespace lodbake
