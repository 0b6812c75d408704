// lodbake bake: one pack from many inputs (-o OUT.glb), one pack per input (-o DIR/), or the packs
// a manifest lists (--manifest). Build-system manners (docs/pipeline.md): exit codes, atomic
// outputs that a signal never leaves half-written, --depfile, --cache-dir, --quiet, a progress bar
// on a TTY only, --report with per-stage timings.

#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/bake/batch.h"
#include "lodbake/bake/depfile.h"
#include "lodbake/bake/memory_budget.h"
#include "lodbake/bake/progress.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/config/bake_manifest.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/core/temp_files.h"

#include "cli_common.h"
#include "cmd_bake_jobs.h"
#include "cmd_bake_ooc.h"

namespace lodbake::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* kBakeHelp =
    R"(usage: lodbake bake IN... -o OUT.glb [--preset NAME|FILE] [options]   one pack from all inputs
       lodbake bake IN... -o DIR/ [options]                          one pack per input: DIR/<stem>.glb
       lodbake bake --manifest FILE [-o DIR/] [options]              the packs a manifest lists

Per input: repair -> LOD chain (errors measured against the repaired input, switch distances) ->
texture levels (each level's textures downscaled to its on-screen size) -> one GLB pack. Each input
(each mesh node of a glTF scene) becomes a LOD group: an MSFT_lod node (highest detail first) with
MSFT_screencoverage in its extras and LODBAKE_lod_metrics; every level is a plain glTF mesh. Packs
of a batch are baked in parallel;
their bytes do not depend on the thread count, the schedule, the current directory or input paths.
See docs/bake.md and docs/pipeline.md.

options:
  -o, --output PATH     OUT.glb, or a folder (ending in '/' or existing) for one pack per input
  --manifest FILE       bake the packs listed in FILE (schemas/config/bake_manifest.schema.json)
  --preset NAME|FILE    bake preset: a bundled one by name (desktop, mobile, vr, archive; installed
                        in share/lodbake/presets) or a preset file (a path: contains '/' or '.')
  --threads N           worker threads (default: all; the output bytes do not depend on it)
  --memory-limit MIB    resident memory the bakes of this run may be allowed together (default: half
                        of physical memory); a pack whose allowance alone exceeds it fails, packs
                        baked side by side wait for room; an in-memory bake's bytes do not
                        depend on it. With --clusters, one PLY or OBJ input over it is baked out
                        of core: the MSFT_lod chain then starts at the finest level that fits
  --work-dir DIR        where an out-of-core bake keeps its partitions (a hidden folder inside DIR,
                        removed at the end; default: the output's folder)
  --levels LIST         override lod_ratios: comma-separated triangle ratios in (0, 1]
  --pixels P            override pixel_threshold
  --min-switch-ratio K  keep a level only when the next coarser level is taken more than K times
                        farther, else drop it as dead weight (default 1.05; 0 keeps every level;
                        preset key lod_min_switch_ratio)
  --compact             compressed-only pack: valence streams replace the plain level data
  --web                 web pack: every level quantized and EXT_meshopt_compression-compressed
                        (Babylon.js, three.js), no LODBAKE_ streams; not with --compact (preset key web)
  --no-progressive-fans do not embed LOD0's PFRep blob (preset key progressive_fans)
  --pfrep-from-chain    build that blob from the LOD chain's own collapses: one simplification
                        instead of two (about 1 s less on a 1 M-triangle scan), coarser PFRep
                        levels (preset key pfrep_from_chain; on in desktop, mobile, vr)
  --no-pfrep-from-chain  build it from a half-edge simplification of its own: more accurate PFRep
                        levels (archive's default)
  --pfrep-format F      4 (default): that blob coded against LOD0's own stream, decoded by the
                        runtime once LOD0 is resident (--compact packs; format 3 otherwise); 3: range-
                        coded, decoded whole by the runtime; 2: the uncompressed blob, streamed as a
                        growing prefix; 5: the uncompressed blob cut into region blocks, of which the
                        runtime loads those a view needs (preset key pfrep_format)
  --pfrep-region-block N  format 5: vertices per region block, 64 to 65536 (default 1024; smaller
                        blocks load less beside what a view refines, at 40 directory bytes and one
                        bounds test per view and frame each; preset key pfrep_region_block)
  --clusters            add LOD0's cluster LOD hierarchy (LODBAKE_cluster_lod: clusters, groups and
                        pages a runtime cuts per view; preset key cluster_lod; docs/cluster_lod.md)
  --adaptive-precision  levels after LOD0 coded with position/normal bits from their own measured
                        error (preset key stream_precision.adaptive; on in desktop, mobile, vr)
  --no-adaptive-precision  every level coded with LOD0's bits (archive's default)
  --remove-covered-components  levels may drop a whole component that lies within their accepted
                        error of the rest, e.g. merged overlapping scans (preset key
                        remove_covered_components; off in every shipped preset; docs/simplify.md)
  --merge auto|poisson|off  merge aligned range views into one surface before the chain: auto
                        (default) when the input's components overlap as sheets, poisson
                        always, off never (preset key merge; docs/bake.md "Merging range scans")
  --keep-unreadable-images  ship an image that is not a decodable PNG/JPEG byte for byte in every
                        level (with a warning) instead of failing (preset key
                        textures.keep_unreadable_images)
  --merge-scene         glTF scenes: every mesh node into one LOD group, node transforms applied
                        (preset key merge_scene); without it each mesh node is its own LOD group
                        and the hierarchy, names, transforms and instancing are kept (docs/bake.md
                        "Scenes")
  --report R.json       write per-level metrics, texture sizes, cache use and stage timings as JSON
  --depfile OUT.d       write a Makefile-syntax depfile listing every file read
  --cache-dir DIR       reuse packs whose inputs, settings and baker version are unchanged
  --quiet               print only warnings and errors
  --print-config        print the resolved settings (sorted keys) and exit

out-of-core job list (docs/pipeline.md "Job list"; docs/cli.md):
  --plan --work-dir DIR  IN --clusters: partition IN into DIR and write DIR/plan.json; again (IN
                        optional): add the jobs whose inputs are now done. Prints the plan, then
                        the ids of the jobs that can run now
  --run-job ID --work-dir DIR  run one job of DIR/plan.json from its files; prints its record

exit status: 0 ok, 1 a bake failed (every other pack is still written), 2 usage error.
)";

struct CliOverrides {
    bool has_threads = false;
    uint32_t threads = 0;
    bool has_memory_limit = false;
    uint32_t memory_limit_mib = 0;
    bool has_levels = false;
    std::vector<double> levels;
    bool has_pixels = false;
    double pixels = 0;
    bool has_min_switch_ratio = false;
    double min_switch_ratio = 0;
    bool compact = false;
    bool web = false;
    bool no_progressive_fans = false;
    bool pfrep_from_chain = false;
    bool no_pfrep_from_chain = false;
    uint32_t pfrep_format = 0; // 0: the preset's
    uint32_t pfrep_region_block = 0; // 0: the preset's
    bool clusters = false;
    bool adaptive_precision = false;
    bool no_adaptive_precision = false;
    bool remove_covered_components = false;
    bool has_merge = false;
    MergeMode merge = MergeMode::Auto;
    bool keep_unreadable_images = false;
    bool merge_scene = false;
};

void applyOverrides(const CliOverrides& o, BakeSettings& s) {
    if (o.has_threads) s.threads = o.threads;
    if (o.has_memory_limit) s.memory_limit_mib = o.memory_limit_mib;
    if (o.has_levels) s.lod_ratios = o.levels;
    if (o.has_pixels) s.pixel_threshold = o.pixels;
    if (o.has_min_switch_ratio) s.lod_min_switch_ratio = o.min_switch_ratio;
    if (o.compact) s.compact = true;
    if (o.web) s.web = true;
    if (o.no_progressive_fans) s.progressive_fans = false;
    if (o.pfrep_from_chain) s.pfrep_from_chain = true;
    if (o.no_pfrep_from_chain) s.pfrep_from_chain = false;
    if (o.pfrep_format != 0) s.pfrep_format = o.pfrep_format;
    if (o.pfrep_region_block != 0) s.pfrep_region_block = o.pfrep_region_block;
    if (o.clusters) s.cluster_lod = true;
    if (o.adaptive_precision) s.stream_precision.adaptive = true;
    if (o.no_adaptive_precision) s.stream_precision.adaptive = false;
    if (o.remove_covered_components) s.remove_covered_components = true;
    if (o.has_merge) s.merge = o.merge;
    if (o.keep_unreadable_images) s.textures.keep_unreadable_images = true;
    if (o.merge_scene) s.merge_scene = true;
}

bool isFolderTarget(const std::string& out) {
    if (!out.empty() && (out.back() == '/' || out.back() == '\\')) return true;
    struct stat st {};
    return ::stat(out.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

uint64_t fileSize(const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 ? uint64_t(st.st_size) : 0;
}

size_t terminalWidth() {
    struct winsize ws {};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 20) return ws.ws_col;
    return 80;
}

// Progress on stderr: a redrawn bar on a terminal, otherwise one plain line per finished pack.
class ProgressPrinter {
public:
    ProgressPrinter(const std::vector<BakeJob>& jobs, bool quiet)
        : quiet_(quiet), tty_(!quiet && ::isatty(STDERR_FILENO) == 1), start_(Clock::now()),
          progress_(weights(jobs), inputCounts(jobs), names(jobs), levelCounts(jobs)), names_(names(jobs)) {}

    void stageDone(size_t job, size_t input, BakeStage stage) {
        std::lock_guard<std::mutex> lock(mutex_);
        progress_.stageDone(job, input, stage);
        redraw(false);
    }

    void stageRunning(size_t job, size_t input, BakeStage stage, bool running) {
        std::lock_guard<std::mutex> lock(mutex_);
        const BakeStage shown = progress_.shownStage();
        progress_.stageRunning(job, input, stage, running);
        // A new stage is drawn at once: it may run for a long time with no event to redraw on.
        redraw(progress_.shownStage() != shown);
    }

    void jobDone(size_t job, const BakeJobResult& r) {
        std::lock_guard<std::mutex> lock(mutex_);
        progress_.jobDone(job);
        if (quiet_) return;
        if (tty_) {
            redraw(true);
            return;
        }
        if (r.cache_hit) return; // its one line comes with the summaries (printSummaries)
        const char* what = r.status.ok() ? "baked" : "failed";
        std::fprintf(stderr, "lodbake: [%zu/%zu] %s: %s in %.2f s%s\n", progress_.jobsDone(), progress_.jobCount(),
                     names_[job].c_str(), what, r.wall_seconds, slowestStages(r).c_str());
        std::fflush(stderr);
    }

    // Removes the bar so that the lines printed next start on a clean row.
    void finish() {
        std::lock_guard<std::mutex> lock(mutex_);
        if (tty_ && drawn_) {
            std::fprintf(stderr, "\r\033[K");
            std::fflush(stderr);
        }
    }

private:
    // " (lod_chain 2.21 s, measure 2.27 s, encode 1.91 s)": the three stages with the most wall time,
    // summed over their runs, so a log shows where a pack's time went.
    static std::string slowestStages(const BakeJobResult& r) {
        std::vector<size_t> stages;
        for (size_t s = 0; s < size_t(BakeStage::Count); ++s)
            if (r.stage_times[s].wall_seconds > 0) stages.push_back(s);
        std::stable_sort(stages.begin(), stages.end(), [&](size_t a, size_t b) {
            return r.stage_times[a].wall_seconds > r.stage_times[b].wall_seconds;
        });
        std::string text;
        char buf[64];
        for (size_t i = 0; i < stages.size() && i < 3; ++i) {
            std::snprintf(buf, sizeof(buf), "%s%s %.2f s", i ? ", " : " (", bakeStageName(BakeStage(stages[i])),
                          r.stage_times[stages[i]].wall_seconds);
            text += buf;
        }
        return text.empty() ? text : text + ")";
    }
    static std::vector<size_t> levelCounts(const std::vector<BakeJob>& jobs) {
        std::vector<size_t> n;
        for (const BakeJob& j : jobs) n.push_back(j.settings.lod_ratios.size() + 1);
        return n;
    }
    static std::vector<double> weights(const std::vector<BakeJob>& jobs) {
        std::vector<double> w;
        for (const BakeJob& j : jobs) {
            double bytes = 0;
            for (const std::string& in : j.inputs) bytes += double(fileSize(in));
            w.push_back(bytes);
        }
        return w;
    }
    static std::vector<size_t> inputCounts(const std::vector<BakeJob>& jobs) {
        std::vector<size_t> n;
        for (const BakeJob& j : jobs) n.push_back(j.inputs.size());
        return n;
    }
    static std::vector<std::string> names(const std::vector<BakeJob>& jobs) {
        std::vector<std::string> n;
        for (const BakeJob& j : jobs) n.push_back(fs::path(j.output).filename().string());
        return n;
    }

    void redraw(bool force) {
        if (!tty_) return;
        const Clock::time_point now = Clock::now();
        if (!force && drawn_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
        last_draw_ = now;
        drawn_ = true;
        const double elapsed = std::chrono::duration<double>(now - start_).count();
        std::fprintf(stderr, "\r\033[K%s", progress_.barLine(elapsed, terminalWidth() - 1).c_str());
        std::fflush(stderr);
    }

    std::mutex mutex_;
    bool quiet_;
    bool tty_;
    Clock::time_point start_;
    Clock::time_point last_draw_{};
    bool drawn_ = false;
    BatchProgress progress_;
    std::vector<std::string> names_;
};

// The pack report (bakeReportJson, an object) with this run's fields in front of its own keys.
std::string jobReport(const BakeJob& job, const BakeJobResult& r) {
    JsonWriter j;
    j.beginObject();
    j.field("output", job.output);
    j.field("cache", std::string(r.cache_hit ? "hit" : "miss"));
    j.key("timings").beginObject();
    for (size_t s = 0; s < size_t(BakeStage::Count); ++s)
        j.field(bakeStageName(BakeStage(s)), r.stage_times[s].wall_seconds);
    j.field("total", r.wall_seconds);
    j.endObject();
    // CPU time per stage (lodbake/bake/stages.h: StageTime): the process's during the stage, and
    // that of the thread that ran it; their ratio to the wall time shows what ran in parallel.
    j.key("cpuTimings").beginObject();
    for (size_t s = 0; s < size_t(BakeStage::Count); ++s)
        j.field(bakeStageName(BakeStage(s)), r.stage_times[s].cpu_seconds);
    j.endObject();
    j.key("threadCpuTimings").beginObject();
    for (size_t s = 0; s < size_t(BakeStage::Count); ++s)
        j.field(bakeStageName(BakeStage(s)), r.stage_times[s].thread_cpu_seconds);
    j.endObject();
    // Every run of a stage as it began (docs/pipeline.md, "Reading the timings").
    j.key("timeline").beginArray();
    for (const BakeJobResult::StageRun& run : r.timeline) {
        j.beginObject();
        j.field("stage", std::string(bakeStageName(run.stage)));
        if (run.input != kWholePack) j.field("input", uint64_t(run.input));
        if (run.level != StageTime::kNoLevel) j.field("level", uint64_t(run.level));
        j.field("start", run.start_seconds);
        j.field("seconds", run.wall_seconds);
        j.field("threadCpuSeconds", run.thread_cpu_seconds);
        j.endObject();
    }
    j.endArray();
    j.endObject();
    std::string head = j.str();
    const size_t close = head.find_last_of('}');
    std::string body = r.report_json;
    const size_t open = body.find('{');
    if (close == std::string::npos || open == std::string::npos) return head;
    head.resize(close);
    while (!head.empty() && (head.back() == '\n' || head.back() == ' ')) head.pop_back();
    return head + "," + body.substr(open + 1);
}

// A step of runBake that may end the run: kContinue, or the exit code to return.
constexpr int kContinue = -1;

// The jobs of a run and the settings files each read (presets and the manifest: read, so listed in
// the depfile).
struct JobList {
    std::vector<BakeJob> jobs;
    std::vector<std::string> settings_files;
    std::vector<std::vector<std::string>> job_settings_files; // per job, the asset presets of a manifest
};

// The command-line flags that override the preset and the manifest.
int parseOverrides(Args& args, CliOverrides& overrides) {
    if (args.values.count("--threads")) {
        double n = 0;
        if (!parseNumber(args.values["--threads"], n) || n < 0 || n > 1024 || n != std::floor(n))
            return usageError("--threads expects an integer in [0, 1024], got '" + args.values["--threads"] + "'");
        overrides.has_threads = true;
        overrides.threads = uint32_t(n);
    }
    if (args.values.count("--memory-limit")) {
        double n = 0;
        if (!parseNumber(args.values["--memory-limit"], n) || n < 0 || n > double(1u << 30) || n != std::floor(n))
            return usageError("--memory-limit expects an integer number of MiB in [0, 1073741824], got '" +
                              args.values["--memory-limit"] + "'");
        overrides.has_memory_limit = true;
        overrides.memory_limit_mib = uint32_t(n);
    }
    if (args.values.count("--levels")) {
        std::vector<double> ratios;
        if (!parseList(args.values["--levels"], ratios) || ratios.empty())
            return usageError("--levels expects comma-separated numbers, got '" + args.values["--levels"] + "'");
        for (double r : ratios)
            if (!(r > 0.0 && r <= 1.0))
                return usageError("--levels: every ratio must lie in (0, 1], got '" + args.values["--levels"] + "'");
        overrides.has_levels = true;
        overrides.levels = ratios;
    }
    if (args.values.count("--pixels")) {
        double p = 0;
        if (!parseNumber(args.values["--pixels"], p) || !(p > 0))
            return usageError("--pixels expects a positive number, got '" + args.values["--pixels"] + "'");
        overrides.has_pixels = true;
        overrides.pixels = p;
    }
    if (args.values.count("--min-switch-ratio")) {
        double k = 0;
        if (!parseNumber(args.values["--min-switch-ratio"], k) || !isValidMinSwitchRatio(k))
            return usageError("--min-switch-ratio expects 0 or a number in [1.001, 100], got '" +
                              args.values["--min-switch-ratio"] + "'");
        overrides.has_min_switch_ratio = true;
        overrides.min_switch_ratio = k;
    }
    overrides.compact = args.flags.count("--compact") > 0;
    overrides.web = args.flags.count("--web") > 0;
    overrides.no_progressive_fans = args.flags.count("--no-progressive-fans") > 0;
    overrides.pfrep_from_chain = args.flags.count("--pfrep-from-chain") > 0;
    overrides.no_pfrep_from_chain = args.flags.count("--no-pfrep-from-chain") > 0;
    if (args.values.count("--pfrep-format")) {
        const std::string& f = args.values["--pfrep-format"];
        if (f != "2" && f != "3" && f != "4" && f != "5")
            return usageError("--pfrep-format expects 2, 3, 4 or 5, got '" + f + "'");
        overrides.pfrep_format = uint32_t(f[0] - '0');
    }
    if (args.values.count("--pfrep-region-block")) {
        double n = 0;
        const std::string& v = args.values["--pfrep-region-block"];
        if (!parseNumber(v, n) || n < kMinPfrepRegionBlock || n > kMaxPfrepRegionBlock || n != std::floor(n))
            return usageError("--pfrep-region-block expects an integer in [" + std::to_string(kMinPfrepRegionBlock) +
                              ", " + std::to_string(kMaxPfrepRegionBlock) + "], got '" + v + "'");
        overrides.pfrep_region_block = uint32_t(n);
    }
    overrides.clusters = args.flags.count("--clusters") > 0;
    overrides.adaptive_precision = args.flags.count("--adaptive-precision") > 0;
    overrides.no_adaptive_precision = args.flags.count("--no-adaptive-precision") > 0;
    overrides.remove_covered_components = args.flags.count("--remove-covered-components") > 0;
    if (args.values.count("--merge")) {
        if (!parseMergeMode(args.values["--merge"], overrides.merge))
            return usageError("--merge expects auto, poisson or off, got '" + args.values["--merge"] + "'");
        overrides.has_merge = true;
    }
    overrides.keep_unreadable_images = args.flags.count("--keep-unreadable-images") > 0;
    overrides.merge_scene = args.flags.count("--merge-scene") > 0;
    if (overrides.adaptive_precision && overrides.no_adaptive_precision)
        return usageError("--adaptive-precision and --no-adaptive-precision exclude each other");
    if (overrides.pfrep_from_chain && overrides.no_pfrep_from_chain)
        return usageError("--pfrep-from-chain and --no-pfrep-from-chain exclude each other");
    return kContinue;
}

// The jobs: from the manifest, one per input (-o DIR/), or one for every input (-o OUT.glb).
int collectJobs(Args& args, const BakeSettings& base, const CliOverrides& overrides, const std::string& out,
                JobList& list) {
    std::vector<BakeJob>& jobs = list.jobs;
    if (args.values.count("--manifest")) {
        if (!args.positional.empty()) return usageError("--manifest takes no input files on the command line");
        if (!out.empty() && !isFolderTarget(out))
            return usageError("with --manifest, -o names a folder (end it with '/'), got '" + out + "'");
        const std::string manifest_path = args.values["--manifest"];
        Result<BakeManifest> manifest = readBakeManifest(manifest_path, base, out);
        if (!manifest.ok()) return reportError(manifest.status());
        list.settings_files.push_back(manifest_path);
        for (ManifestAsset& a : manifest->assets) {
            BakeJob job;
            job.inputs = a.inputs;
            job.output = a.output;
            job.settings = a.settings;
            applyOverrides(overrides, job.settings); // command-line flags win over the manifest
            list.job_settings_files.push_back(a.settings_files);
            jobs.push_back(std::move(job));
        }
    } else if (args.flags.count("--print-config")) {
        std::fputs(settingsToJson(base).c_str(), stdout);
        return kExitOk;
    } else {
        if (args.positional.empty()) return usageError("bake needs at least one input file (or --manifest)");
        if (out.empty()) return usageError("bake needs -o OUT.glb or -o DIR/");
        if (isFolderTarget(out)) {
            std::map<std::string, std::string> stems;
            for (const std::string& in : args.positional) {
                BakeJob job;
                job.inputs = {in};
                job.output = joinPath(out, inputGroupName(in) + ".glb");
                job.settings = base;
                const auto [it, inserted] = stems.emplace(job.output, in);
                if (!inserted)
                    return usageError("'" + in + "' and '" + it->second + "' would both be baked into '" + job.output +
                                      "'; use --manifest to name the outputs");
                jobs.push_back(std::move(job));
            }
        } else {
            if (lowerExtension(out) != ".glb") return usageError("bake writes a .glb pack, got '" + out + "'");
            BakeJob job;
            job.inputs = args.positional;
            job.output = out;
            job.settings = base;
            jobs.push_back(std::move(job));
        }
    }
    return kContinue;
}

// --print-config with a manifest: one resolved settings document per pack, keyed by output path.
void printJobConfigs(const std::vector<BakeJob>& jobs) {
    std::string text = "{";
    for (size_t i = 0; i < jobs.size(); ++i) {
        std::string settings = settingsToJson(jobs[i].settings);
        while (!settings.empty() && settings.back() == '\n') settings.pop_back();
        text += std::string(i ? "," : "") + "\n" + JsonWriter::escape(jobs[i].output) + ": " + settings;
    }
    std::fputs((text + "\n}\n").c_str(), stdout);
}

// No output may be an input; batch and manifest outputs go into folders the run creates (as a
// build system's output tree).
int checkOutputs(Args& args, const std::vector<BakeJob>& jobs, const std::string& out) {
    for (const BakeJob& job : jobs)
        for (const std::string& in : job.inputs)
            if (isSameFile(in, job.output)) return usageError("output '" + job.output + "' is also an input");
    if (args.values.count("--manifest") || (!out.empty() && isFolderTarget(out))) {
        std::set<std::string> folders;
        for (const BakeJob& job : jobs) folders.insert(parentDirectory(job.output));
        for (const std::string& folder : folders) {
            std::error_code ec;
            if (!folder.empty()) fs::create_directories(folder, ec);
            if (ec) return reportError(ioError(folder + ": cannot create the output folder: " + ec.message()));
        }
    }
    return kContinue;
}

// Every job's diagnostics and errors, in job order whatever order the jobs finished in. Returns the
// run's exit code so far.
int printJobDiagnostics(const std::vector<BakeJob>& jobs, const std::vector<BakeJobResult>& results, bool quiet) {
    int exit_code = kExitOk;
    for (size_t i = 0; i < jobs.size(); ++i) {
        const BakeJobResult& r = results[i];
        if (quiet) {
            Diagnostics warnings; // --quiet keeps warnings and errors only
            for (const Diagnostic& diagnostic : r.diagnostics.items())
                if (diagnostic.severity == Severity::Warning) warnings.warn(diagnostic.message);
            printDiagnostics(warnings);
        } else {
            printDiagnostics(r.diagnostics);
        }
        if (!r.cache_warning.empty()) std::fprintf(stderr, "warning: cache: %s\n", r.cache_warning.c_str());
        if (!r.status.ok()) exit_code = reportError(r.status);
    }
    return exit_code;
}

// Stages `text` for `path` unless the file already holds it: a re-run that changes nothing (a
// cache hit) leaves its outputs and their time stamps alone.
Status stageUnlessUnchanged(AtomicFileWriter& writer, const std::string& path, const std::string& text) {
    std::error_code ec;
    if (fs::file_size(path, ec) == text.size() && !ec) {
        Result<std::vector<uint8_t>> existing = readFileBytes(path);
        if (existing.ok() && std::string(existing->begin(), existing->end()) == text) return Status::okStatus();
    }
    return writer.add(path, text);
}

// The packs, then the report and depfile that describe them, committed together.
Status writeOutputs(Args& args, const JobList& list, const std::vector<BakeJobResult>& results, const std::string& out,
                    int exit_code, double total_seconds, double total_cpu_seconds) {
    const std::vector<BakeJob>& jobs = list.jobs;
    // A failed pack fails the run, but the packs that were baked are still written (the report and
    // depfile only when every pack succeeded: a build system must re-run the failed ones).
    AtomicFileWriter writer;
    Status status = Status::okStatus();
    std::string report, depfile;
    if (exit_code == kExitOk && args.values.count("--report")) {
        if (jobs.size() == 1 && !args.values.count("--manifest") && !isFolderTarget(out)) {
            report = jobReport(jobs[0], results[0]);
        } else {
            std::string packs;
            for (size_t i = 0; i < jobs.size(); ++i) packs += (i ? ",\n" : "") + jobReport(jobs[i], results[i]);
            report = "{\n\"totalSeconds\": " + JsonWriter::formatNumber(total_seconds) +
                     ",\n\"totalCpuSeconds\": " + JsonWriter::formatNumber(total_cpu_seconds) + ",\n\"packs\": [\n" +
                     packs + "\n]\n}\n";
        }
        status = stageUnlessUnchanged(writer, args.values["--report"], report);
    }
    if (exit_code == kExitOk && status.ok() && args.values.count("--depfile")) {
        std::vector<DepfileRule> rules;
        for (size_t i = 0; i < jobs.size(); ++i) {
            DepfileRule rule;
            rule.target = jobs[i].output;
            rule.prerequisites = list.settings_files;
            if (i < list.job_settings_files.size())
                rule.prerequisites.insert(rule.prerequisites.end(), list.job_settings_files[i].begin(),
                                          list.job_settings_files[i].end());
            rule.prerequisites.insert(rule.prerequisites.end(), results[i].files_read.begin(),
                                      results[i].files_read.end());
            rules.push_back(std::move(rule));
        }
        depfile = formatDepfile(rules);
        status = stageUnlessUnchanged(writer, args.values["--depfile"], depfile);
    }
    // Packs first, then the report and depfile that describe them.
    for (size_t i = 0; i < results.size() && status.ok(); ++i)
        if (results[i].staged) status = results[i].staged->commit();
    if (status.ok()) status = writer.commit();
    return status;
}

void printSummaries(const std::vector<BakeJob>& jobs, const std::vector<BakeJobResult>& results, bool quiet) {
    for (size_t i = 0; i < jobs.size() && !quiet; ++i) {
        const BakeJobResult& r = results[i];
        if (!r.status.ok()) continue;
        if (r.cache_hit) { // one line: the pack came from the cache
            std::printf("cache hit: %s (%llu bytes, key %s, %s)\n", jobs[i].output.c_str(),
                        static_cast<unsigned long long>(r.pack_bytes), r.cache_key.c_str(),
                        r.unchanged ? "file unchanged" : "written");
            continue;
        }
        std::fputs(r.summary.c_str(), stdout);
        std::printf("wrote %s (%llu bytes)\n", jobs[i].output.c_str(), static_cast<unsigned long long>(r.pack_bytes));
    }
}

} // namespace

int runBake(int argc, char** argv) {
    Args args;
    int code = 0;
    if (!parseArgs(argc, argv, 2,
                   {{"--output", "-o", true},
                    {"--manifest", nullptr, true},
                    {"--preset", nullptr, true},
                    {"--threads", nullptr, true},
                    {"--memory-limit", nullptr, true},
                    {"--work-dir", nullptr, true},
                    {"--levels", nullptr, true},
                    {"--pixels", nullptr, true},
                    {"--min-switch-ratio", nullptr, true},
                    {"--compact", nullptr, false},
                    {"--web", nullptr, false},
                    {"--no-progressive-fans", nullptr, false},
                    {"--pfrep-from-chain", nullptr, false},
                    {"--no-pfrep-from-chain", nullptr, false},
                    {"--pfrep-format", nullptr, true},
                    {"--pfrep-region-block", nullptr, true},
                    {"--clusters", nullptr, false},
                    {"--adaptive-precision", nullptr, false},
                    {"--no-adaptive-precision", nullptr, false},
                    {"--remove-covered-components", nullptr, false},
                    {"--merge", nullptr, true},
                    {"--keep-unreadable-images", nullptr, false},
                    {"--merge-scene", nullptr, false},
                    {"--report", nullptr, true},
                    {"--depfile", nullptr, true},
                    {"--cache-dir", nullptr, true},
                    {"--quiet", "-q", false},
                    {"--print-config", nullptr, false},
                    {"--plan", nullptr, false},
                    {"--run-job", nullptr, true},
                    {"--help", "-h", false}},
                   args, code))
        return code;
    if (args.flags.count("--help")) {
        std::fputs(kBakeHelp, stdout);
        std::fputs(kReaderLimitHelp, stdout);
        return kExitOk;
    }
    const bool quiet = args.flags.count("--quiet") > 0;
    BakeSettings base;
    std::vector<std::string> settings_files; // presets and the manifest: read, so listed in the depfile
    if (args.values.count("--preset")) {
        std::string preset;
        if (const int c = resolvePreset(args.values["--preset"], &preset); c != kExitOk) return c;
        const Status status = applyPresetFile(preset, base);
        if (!status.ok()) return reportError(status);
        settings_files.push_back(preset);
    }
    CliOverrides overrides;
    if (const int c = parseOverrides(args, overrides); c != kContinue) return c;
    applyOverrides(overrides, base);
    if (isBakeJobCommand(args)) return runBakeJobCommand(args, base); // the out-of-core job list

    // The jobs.
    JobList list;
    list.settings_files = std::move(settings_files);
    const std::string out = args.values.count("--output") ? args.values["--output"] : std::string();
    if (const int c = collectJobs(args, base, overrides, out, list); c != kContinue) return c;
    const std::vector<BakeJob>& jobs = list.jobs;
    if (args.flags.count("--print-config")) {
        printJobConfigs(jobs);
        return kExitOk;
    }
    if (const int c = checkOutputs(args, jobs, out); c != kContinue) return c;

    // From here on an interrupted bake removes its temporaries before dying by the signal.
    installTempFileSignalCleanup();
    BatchOptions options;
    options.threads = overrides.has_threads ? overrides.threads : base.threads;
    // Like --threads, one limit for the whole run (a manifest's per-asset value is ignored).
    const uint32_t limit_mib = overrides.has_memory_limit ? overrides.memory_limit_mib : base.memory_limit_mib;
    options.memory_limit_bytes = limit_mib > 0 ? uint64_t(limit_mib) << 20 : defaultBakeMemoryLimit();
    options.read = args.read;
    if (args.values.count("--cache-dir")) options.cache_dir = args.values["--cache-dir"];
    options.out_of_core = outOfCoreBaker(args.values.count("--work-dir") ? args.values["--work-dir"] : "", args.read);
    ProgressPrinter printer(jobs, quiet);
    BatchHooks hooks;
    hooks.stage_done = [&](size_t job, size_t input, BakeStage stage, const StageTime&) {
        printer.stageDone(job, input, stage);
    };
    hooks.stage_running = [&](size_t job, size_t input, BakeStage stage, bool running) {
        printer.stageRunning(job, input, stage, running);
    };
    hooks.job_done = [&](size_t job, const BakeJobResult& r) { printer.jobDone(job, r); };
    const Clock::time_point start = Clock::now();
    const double cpu_start = processCpuSeconds();
    std::vector<BakeJobResult> results = runBakeJobs(jobs, options, hooks);
    const double total_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    const double total_cpu_seconds = processCpuSeconds() - cpu_start;
    printer.finish();

    int exit_code = printJobDiagnostics(jobs, results, quiet);
    const Status status = writeOutputs(args, list, results, out, exit_code, total_seconds, total_cpu_seconds);
    if (!status.ok()) return reportError(status);
    printSummaries(jobs, results, quiet);
    return exit_code;
}

} // namespace lodbake::cli
