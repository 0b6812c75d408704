// Batch benchmark (issue #9 bars), each figure next to its anchor measured in the same run:
//  1. the batch of all shared scans (`lodbake bake ALL -o DIR/`), --threads 2 against --threads 1:
//     speedup, bar >= 1.7; the packs of both runs must be byte-identical. Besides the best-of-N wall
//     times (which on a shared machine mostly measure the other jobs) it prints an estimate from CPU
//     accounting: 1-thread CPU time over max(2-thread CPU time / 2, longest pack's critical path
//     from the report's threadCpuTimings), with the load average;
//  2. the same batch re-baked with a warm --cache-dir against the cold (cache-filling) bake: ratio,
//     bar <= 5 %;
//  3. peak memory (getrusage ru_maxrss of the child) of baking the largest shared scan, per input
//     triangle: bar <= 300 B/triangle; anchor: the peak of `lodbake info` reading the same file;
//  4. with --allowance, for every mesh baked with the preset and with the preset plus --clusters:
//     the memory allowance of --memory-limit (lodbake/bake/memory_budget.h, read from the CLI's
//     refusal at a 1 MiB limit) against the bake's peak RSS; bar: allowance >= peak for every row.
// Every bake is a separate `lodbake` process, as a build system runs it.
//
// Bars (docs/pipeline.md, docs/bake.md): speedup >= 1.7 on wall time; packs of both thread counts and
// of the warm re-bake byte-identical; warm/cold <= 5 %; peak <= 300 B per input triangle.
//
// usage: batch_bench [--runs N] [--preset FILE] [--only MESH,...] [--skip-threads] [--skip-cache] [--skip-memory]
//                    [--allowance] [--check]
// Defaults: 1 run (the 1-thread batch takes minutes), configs/desktop.json, every shared mesh.
// Not a ctest: these machines are noisy, so with N runs the run of median wall time is compared.
// --check: exit 1 when a bar is not met.

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "shared_mesh_list.h"

namespace {

namespace fs = std::filesystem;

// The largest shared scan by triangle count (1,067,852).
constexpr const char* kLargest = "dragon_poisson.ply";

struct ChildRun {
    int exit_code = -1;
    double seconds = 0;
    double cpu_seconds = 0; // user + system of the child, all its threads
    long maxrss_kb = 0;
};

// Runs argv as a child process (stdout/stderr to `log`), timing it and reading its peak RSS.
ChildRun runChild(const std::vector<std::string>& argv, const std::string& log) {
    ChildRun r;
    std::fflush(stdout); // or the child's freopen flushes our buffered lines a second time
    const auto t0 = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid == 0) {
        std::freopen(log.c_str(), "w", stdout);
        std::freopen(log.c_str(), "a", stderr);
        std::vector<char*> args;
        for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
        args.push_back(nullptr);
        ::execv(args[0], args.data());
        ::_exit(127);
    }
    int status = 0;
    struct rusage usage {};
    ::wait4(pid, &status, 0, &usage);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.maxrss_kb = usage.ru_maxrss;
    r.cpu_seconds = double(usage.ru_utime.tv_sec) + 1e-6 * double(usage.ru_utime.tv_usec) +
                    double(usage.ru_stime.tv_sec) + 1e-6 * double(usage.ru_stime.tv_usec);
    return r;
}

std::string readAll(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::vector<std::string> split(const std::string& list) {
    std::vector<std::string> out;
    std::stringstream ss(list);
    std::string item;
    while (std::getline(ss, item, ','))
        if (!item.empty()) out.push_back(item);
    return out;
}

double loadAverage() {
    double l[3] = {0, 0, 0};
    return ::getloadavg(l, 3) > 0 ? l[0] : -1;
}

// The number after `"key":` in text, searching from `from`; 0 when absent.
double numberAfter(const std::string& text, size_t from, const std::string& key) {
    const size_t at = text.find("\"" + key + "\":", from);
    return at == std::string::npos ? 0 : std::atof(text.c_str() + at + key.size() + 3);
}

// The critical path of each pack in a --report of a batch, in CPU seconds of the threads that ran
// its stages (threadCpuTimings): the single-threaded stages add up; `pfrep` runs beside `measure`,
// `textures` and `encode` (docs/bake.md, Concurrency), so the longer of the two lanes counts. The
// largest of them bounds the batch's wall time however many threads it has.
double longestPackPath(const std::string& report, std::string& which) {
    double longest = 0;
    for (size_t at = report.find("\"threadCpuTimings\""); at != std::string::npos;
         at = report.find("\"threadCpuTimings\"", at + 1)) {
        auto t = [&](const char* key) { return numberAfter(report, at, key); };
        const double path = t("load") + t("repair") + t("lod_chain") +
                            std::max(t("pfrep"), t("measure") + t("textures") + t("encode")) + t("pack") + t("write");
        if (path > longest) {
            longest = path;
            const size_t name = report.rfind("\"output\":", at);
            which = name == std::string::npos ? "?" : report.substr(name + 10, report.find(',', name) - name - 10);
        }
    }
    return longest;
}

struct BatchRun {
    double best_seconds = 1e300; // wall time of the run of median wall time
    double cpu_seconds = 0;      // of that run
    std::string report;          // --report of that run
};

// The run of median wall time of `runs` batch bakes (each with --report); every run must succeed.
bool bestBatch(const std::vector<std::string>& base, const std::string& out_dir, int runs, const std::string& log,
               BatchRun& best) {
    std::vector<BatchRun> all;
    for (int i = 0; i < runs; ++i) {
        fs::remove_all(out_dir);
        std::vector<std::string> argv = base;
        argv.push_back("-o");
        argv.push_back(out_dir + "/");
        argv.push_back("--report");
        argv.push_back(out_dir + ".report.json");
        const ChildRun r = runChild(argv, log);
        if (r.exit_code != 0) {
            std::fprintf(stderr, "batch_bench: bake failed (%d), see %s\n", r.exit_code, log.c_str());
            return false;
        }
        all.push_back(BatchRun{r.seconds, r.cpu_seconds, readAll(out_dir + ".report.json")});
    }
    std::sort(all.begin(), all.end(),
              [](const BatchRun& a, const BatchRun& b) { return a.best_seconds < b.best_seconds; });
    best = std::move(all[all.size() / 2]);
    return true;
}

bool bestBatch(const std::vector<std::string>& base, const std::string& out_dir, int runs, const std::string& log,
               double& best_seconds) {
    BatchRun best;
    if (!bestBatch(base, out_dir, runs, log, best)) return false;
    best_seconds = best.best_seconds;
    return true;
}

// Part 4: the allowance --memory-limit gives each bake, against the bake's measured peak.
bool measureAllowances(const std::string& cli, const std::vector<std::string>& meshes, const std::string& preset,
                       const std::string& work, lodbake_bench::Bars& bars) {
    double lowest = INFINITY;
    std::string lowest_row;
    std::printf("allowance: %-34s %-10s %10s %10s %6s\n", "mesh", "options", "peak MiB", "allowed", "ratio");
    for (const std::string& m : meshes) {
        const std::string mesh = std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + m;
        for (const bool clusters : {false, true}) {
            std::vector<std::string> args = {cli, "bake", mesh, "-o", work + "/allowance.glb", "--preset", preset,
                                             "--threads", "2", "--quiet"};
            if (clusters) args.push_back("--clusters");
            std::vector<std::string> refused = args;
            refused.insert(refused.end(), {"--memory-limit", "1"});
            const ChildRun limit = runChild(refused, work + "/allowance_refused.log");
            const std::string message = readAll(work + "/allowance_refused.log");
            const size_t at = message.find(" is allowed ");
            const ChildRun bake = runChild(args, work + "/allowance.log");
            if (limit.exit_code != 1 || at == std::string::npos || bake.exit_code != 0) {
                std::fprintf(stderr, "batch_bench: %s: no allowance or the bake failed, see %s and %s\n", m.c_str(),
                             (work + "/allowance_refused.log").c_str(), (work + "/allowance.log").c_str());
                return false;
            }
            const double allowed_mib = std::atof(message.c_str() + at + 12);
            const double peak_mib = double(bake.maxrss_kb) / 1024.0;
            const double ratio = allowed_mib / peak_mib;
            std::printf("allowance: %-34s %-10s %10.1f %10.0f %6.2f\n", m.c_str(), clusters ? "+clusters" : "preset",
                        peak_mib, allowed_mib, ratio);
            if (ratio < lowest) {
                lowest = ratio;
                lowest_row = m + (clusters ? " --clusters" : "");
            }
        }
    }
    bars.absolute("lowest memory allowance / bake peak RSS (" + lowest_row + ")", lowest, 1.0,
                  lodbake_bench::Limit::AtLeast);
    return true;
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars bars("batch_bench");
    using lodbake_bench::Limit;
    int runs = 1;
    std::string preset = std::string(LODBAKE_BENCH_SOURCE_DIR) + "/configs/desktop.json";
    std::vector<std::string> meshes = lodbake_test::allSharedMeshNames();
    bool do_threads = true, do_cache = true, do_memory = true, do_allowance = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--runs" && i + 1 < argc)
            runs = std::max(1, std::atoi(argv[++i]));
        else if (a == "--preset" && i + 1 < argc)
            preset = argv[++i];
        else if (a == "--only" && i + 1 < argc)
            meshes = split(argv[++i]);
        else if (a == "--skip-threads")
            do_threads = false;
        else if (a == "--skip-cache")
            do_cache = false;
        else if (a == "--skip-memory")
            do_memory = false;
        else if (a == "--allowance")
            do_allowance = true;
        else {
            std::fprintf(stderr, "usage: batch_bench [--runs N] [--preset FILE] [--only MESH,...] [--skip-threads] "
                                 "[--skip-cache] [--skip-memory] [--allowance] [--check]\n");
            return 2;
        }
    }
    const std::string cli = LODBAKE_BENCH_CLI;
    const std::string work = std::string(LODBAKE_BENCH_OUT_DIR) + "/batch_bench_out";
    fs::create_directories(work);
    std::vector<std::string> base = {cli, "bake"};
    for (const std::string& m : meshes) base.push_back(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + m);
    base.insert(base.end(), {"--preset", preset, "--quiet"});
    std::printf("batch_bench: %zu meshes, preset %s, median of %d; load average at start %.1f on %ld cores\n",
                meshes.size(), preset.c_str(), runs, loadAverage(), ::sysconf(_SC_NPROCESSORS_ONLN));

    if (do_threads) {
        BatchRun t1, t2;
        std::vector<std::string> one = base, two = base;
        one.insert(one.end(), {"--threads", "1"});
        two.insert(two.end(), {"--threads", "2"});
        const double load_before = loadAverage();
        if (!bestBatch(one, work + "/t1", runs, work + "/t1.log", t1) ||
            !bestBatch(two, work + "/t2", runs, work + "/t2.log", t2))
            return 1;
        size_t differing = 0;
        for (const auto& e : fs::directory_iterator(work + "/t1")) {
            const std::string name = e.path().filename().string();
            if (readAll(e.path().string()) != readAll(work + "/t2/" + name)) {
                std::printf("  DIFFERENT BYTES: %s\n", name.c_str());
                ++differing;
            }
        }
        const double speedup = t1.best_seconds / t2.best_seconds;
        std::printf(
            "threads: 1 thread %.2f s, 2 threads %.2f s, speedup %.2fx (bar >= 1.70: %s); packs identical: %s\n",
            t1.best_seconds, t2.best_seconds, speedup, speedup >= 1.7 ? "met" : "NOT met",
            differing == 0 ? "yes" : "NO");
        // On a loaded machine the wall times say more about the other jobs than about ours. CPU time
        // hardly depends on the load: the 2-thread batch cannot finish before its CPU time over 2,
        // nor before its longest pack's critical path, so the speedup an idle machine would show is
        // the 1-thread CPU time over the larger of the two.
        std::string longest_pack;
        const double path = longestPackPath(t2.report, longest_pack);
        const double bound = std::max(t2.cpu_seconds / 2.0, path);
        std::printf("threads (CPU accounting): 1 thread %.2f s CPU (%.0f %% of its wall), 2 threads %.2f s CPU "
                    "(%.0f %% of 2 x wall); longest pack %s, critical path %.2f s; estimated idle 2-thread wall "
                    "%.2f s, speedup %.2fx (bar >= 1.70: %s); load average %.1f before, %.1f after\n",
                    t1.cpu_seconds, 100.0 * t1.cpu_seconds / t1.best_seconds, t2.cpu_seconds,
                    50.0 * t2.cpu_seconds / t2.best_seconds, longest_pack.c_str(), path, bound, t1.cpu_seconds / bound,
                    t1.cpu_seconds / bound >= 1.7 ? "met" : "NOT met", load_before, loadAverage());
        bars.ratio("batch speedup, 1-thread s / 2-thread s (" + std::to_string(meshes.size()) + " meshes, wall)",
                   t1.best_seconds, t2.best_seconds, 1.7, Limit::AtLeast);
        bars.absolute("packs differing between 1 and 2 threads", double(differing), 0, Limit::AtMost);
    }

    if (do_cache) {
        const std::string cache = work + "/cache";
        fs::remove_all(cache);
        std::vector<std::string> cached = base;
        cached.insert(cached.end(), {"--threads", "2", "--cache-dir", cache});
        double cold = 0, warm = 0;
        if (!bestBatch(cached, work + "/cold", 1, work + "/cold.log", cold)) return 1;
        if (!bestBatch(cached, work + "/warm", runs, work + "/warm.log", warm)) return 1;
        size_t differing = 0;
        for (const auto& e : fs::directory_iterator(work + "/cold"))
            if (readAll(e.path().string()) != readAll(work + "/warm/" + e.path().filename().string())) ++differing;
        const double ratio = warm / cold;
        std::printf("cache: cold %.2f s, warm %.3f s, warm/cold %.2f %% (bar <= 5 %%: %s); warm packs identical: %s\n",
                    cold, warm, 100.0 * ratio, ratio <= 0.05 ? "met" : "NOT met", differing == 0 ? "yes" : "NO");
        bars.ratio("warm --cache-dir re-bake / cold bake (s)", warm, cold, 0.05, Limit::AtMost);
        bars.absolute("packs differing between the cold and the warm bake", double(differing), 0, Limit::AtMost);
    }

    if (do_memory) {
        const std::string mesh = std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + kLargest;
        const std::string report = work + "/largest_report.json";
        const ChildRun info = runChild({cli, "info", mesh}, work + "/info.log");
        const ChildRun bake = runChild({cli, "bake", mesh, "-o", work + "/largest.glb", "--preset", preset, "--threads",
                                        "2", "--quiet", "--report", report},
                                       work + "/largest.log");
        if (bake.exit_code != 0 || info.exit_code != 0) {
            std::fprintf(stderr, "batch_bench: %s failed, see %s\n", kLargest, (work + "/largest.log").c_str());
            return 1;
        }
        // inputTriangles from the report (the first asset).
        const std::string text = readAll(report);
        const size_t at = text.find("\"inputTriangles\":");
        const double triangles = at == std::string::npos ? 0 : std::atof(text.c_str() + at + 17);
        const double per_tri = triangles > 0 ? double(bake.maxrss_kb) * 1024.0 / triangles : 0;
        std::printf("memory: %s, %.0f triangles: bake peak %.1f MiB = %.0f B/triangle (bar <= 300: %s); "
                    "anchor `lodbake info` peak %.1f MiB = %.0f B/triangle, ratio %.2fx\n",
                    kLargest, triangles, bake.maxrss_kb / 1024.0, per_tri, per_tri <= 300 ? "met" : "NOT met",
                    info.maxrss_kb / 1024.0, triangles > 0 ? info.maxrss_kb * 1024.0 / triangles : 0,
                    info.maxrss_kb > 0 ? double(bake.maxrss_kb) / double(info.maxrss_kb) : 0);
        bars.absolute(std::string("bake peak RSS per input triangle, ") + kLargest +
                          ", 2 threads (B; anchor: lodbake info)",
                      triangles > 0 ? per_tri : NAN, 300, Limit::AtMost,
                      triangles > 0 ? info.maxrss_kb * 1024.0 / triangles : NAN);
    }
    if (do_allowance && !measureAllowances(cli, meshes, preset, work, bars)) return 1;
    std::printf("load average at end %.1f\n", loadAverage());
    return bars.finish(check);
}
