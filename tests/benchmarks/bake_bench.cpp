// Bake benchmark: `lodbake bake MESH --preset configs/desktop.json --threads 2` (the whole CLI run:
// read, repair, 5-level chain with measured errors, texture levels, pack writing) against native
// meshopt_simplify (Debian libmeshoptimizer, options 0, no error limit) building the same 5 levels
// from the original on 2 threads, in the same run. Prints both times and the ratio; the bar
// (docs/bake.md) is ≤ 3 on the median of --runs runs of each side, alternating.
//
// usage: bake_bench [--runs N] [--stages] [--bar-only] [--cli PATH] [--check] [MESH]
//        (default dragon_poisson.ply from ../shared/meshes; --bar-only skips the in-process breakdown;
//        --cli: the lodbake program to run instead of this build's, e.g. an older build to compare;
//        --check: exit 1 when the bar is not met)
// The peak resident size of every CLI run (the child's maximum RSS) is printed with the times.
// --stages: instead, every stage of a bake run on its own in process, at 1 and 2 threads, with its
// wall time, process and thread CPU time and peak resident size (what each stage costs alone).
// Not a ctest: these machines are noisy, so the median of N runs of each side is compared.

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cfloat>
#include <fstream>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <meshoptimizer.h>

#include "bench_bar.h"
#include "core/parallel.h"
#include "lodbake/bake/bake.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/pack.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/stream/stream.h"

namespace {

double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Runs `args` (args[0] is the program) with stdout and stderr on /dev/null and waits for it. Returns
// false when it could not run or did not exit with 0; `peak_mib` receives its maximum resident size.
bool runChild(const std::vector<std::string>& args, double& peak_mib) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) return false;
    if (pid == 0) {
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) {
            ::dup2(null, STDOUT_FILENO);
            ::dup2(null, STDERR_FILENO);
        }
        ::execv(argv[0], argv.data());
        ::_exit(127);
    }
    int status = 0;
    rusage usage{};
    if (::wait4(pid, &status, 0, &usage) != pid) return false;
    peak_mib = double(usage.ru_maxrss) / 1024.0; // KiB on Linux
    return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

// The preset's levels with meshopt_simplify, each from the original, levels spread over 2 threads.
double nativeSeconds(const lodbake::Mesh& mesh, const std::vector<double>& ratios, std::vector<size_t>& triangles) {
    triangles.assign(ratios.size(), 0);
    const double start = now();
    auto work = [&](size_t first) {
        std::vector<unsigned int> destination(mesh.indices.size());
        for (size_t i = first; i < ratios.size(); i += 2) {
            const size_t target = size_t(double(mesh.faceCount()) * ratios[i]) * 3;
            triangles[i] =
                meshopt_simplify(destination.data(), mesh.indices.data(), mesh.indices.size(), &mesh.positions[0].x,
                                 mesh.positions.size(), sizeof(lodbake::Vec3f), target, FLT_MAX, 0, nullptr) /
                3;
        }
    };
    std::thread other(work, 1);
    work(0);
    other.join();
    return now() - start;
}

double cpuClock(clockid_t id) {
    timespec ts{};
    ::clock_gettime(id, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// Resident set size fields of /proc/self/status in MiB ("VmRSS", "VmHWM").
double statusMiB(const char* field) {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind(field, 0) == 0) return std::atof(line.c_str() + std::string(field).size() + 1) / 1024.0;
    return 0;
}

// Resets the peak resident size to the current one (Linux: write 5 to clear_refs).
void resetPeak() {
    std::ofstream out("/proc/self/clear_refs");
    out << "5";
}

// One step of the in-process breakdown: wall, process CPU (all threads), CPU of this thread, and
// the peak resident size reached during the step. The bench gives free pages back first, so a
// step's peak does not include what earlier steps left in the heap (an attribution of this
// in-process breakdown only: the CLI runs above leave the allocator alone).
template <class F> void step(const char* name, F&& f) {
#if defined(__GLIBC__)
    malloc_trim(0);
#endif
    resetPeak();
    const double rss0 = statusMiB("VmRSS:");
    const double w0 = now(), p0 = cpuClock(CLOCK_PROCESS_CPUTIME_ID), t0 = cpuClock(CLOCK_THREAD_CPUTIME_ID);
    f();
    const double w = now() - w0, p = cpuClock(CLOCK_PROCESS_CPUTIME_ID) - p0,
                 t = cpuClock(CLOCK_THREAD_CPUTIME_ID) - t0;
    std::printf("  %-34s wall %7.3f s  cpu %7.3f s  this thread %7.3f s  peak RSS %7.1f MiB (start %7.1f)\n", name, w,
                p, t, statusMiB("VmHWM:"), rss0);
    std::fflush(stdout);
}

// Every stage of a bake separately, in process, so that CPU time and memory can be attributed.
void stageBreakdown(const lodbake::Mesh& input, const lodbake::BakeSettings& settings, size_t threads) {
    using namespace lodbake;
    ScopedThreadLimit limit(threads);
    std::printf("stage breakdown (in process, %zu threads):\n", threads);
    Diagnostics d;
    Mesh mesh;
    step("copy input", [&] { mesh = input; });
    step("repair", [&] { (void)repairMesh(mesh, RepairOptions{}, "bench", d); });
    LodChainOptions chain_options;
    chain_options.ratios = settings.lod_ratios;
    chain_options.record_collapses = false;
    chain_options.measure_error = false;
    Result<LodChain> chain = invalidInput("not built");
    step("lod chain (no measurement)", [&] { chain = buildLodChain(mesh, chain_options, d); });
    if (!chain.ok()) return;
    std::vector<double> ratios{1.0};
    for (const LodLevel& l : chain->levels) ratios.push_back(l.target_ratio);
    // In the bake's order (docs/bake.md, "Concurrency"): PFRep, the measurement, then the coding of
    // every level (with the preset's stream precision, which reads the measured errors).
    step("pfrep (LOD0)", [&] { (void)buildPfrepExtension(mesh, ratios, PfrepOptions{}, d); });
    step("measure: all levels (as the bake)", [&] {
        std::vector<const Mesh*> levels;
        for (const LodLevel& l : chain->levels) levels.push_back(&l.mesh);
        DistanceOptions distance;
        distance.sample_count = settings.error_samples;
        auto measured = prepareAndMeasureSurfaceDistances(mesh, levels, distance);
        for (size_t i = 0; measured.ok() && i < measured->size(); ++i) {
            if (!(*measured)[i].ok()) continue;
            chain->levels[i].has_distance = true;
            chain->levels[i].distance = *(*measured)[i];
        }
    });
    ValenceStreamOptions valence_options;
    valence_options.position_bits = settings.stream_precision.position_bits;
    valence_options.normal_bits = settings.stream_precision.normal_bits;
    valence_options.adaptive = settings.stream_precision.adaptive;
    valence_options.error_fraction = settings.stream_precision.error_fraction;
    const PackStreamEncoder valence = valenceStreamEncoder(valence_options);
    // As the bake codes a level: prepare, then the commit it returns.
    auto encode = [&](size_t l, PackLevel& level) {
        Result<PackStreamCommit> commit = valence.prepare(*chain, l, level.mesh);
        if (commit.ok() && *commit) (void)(*commit)(level);
    };
    std::vector<PackLevel> packed(chain->levels.size() + 1);
    packed[0].mesh = mesh;
    for (size_t l = 0; l < chain->levels.size(); ++l) packed[l + 1].mesh = chain->levels[l].mesh;
    if (threads > 1) {
        // The bake's last phase on a large asset: every level's coding side by side, largest first.
        std::vector<PackLevel> copies = packed;
        step("valence, all levels side by side", [&] {
            (void)parallelFor(copies.size(), 1, [&](size_t l) { encode(l, copies[l]); });
        });
    }
    for (size_t l = 0; l < packed.size(); ++l) {
        const std::string name = "valence level " + std::to_string(l);
        step(name.c_str(), [&] { encode(l, packed[l]); });
    }
    PackDescription description;
    PackAsset asset;
    asset.name = "bench";
    asset.levels = std::move(packed);
    const LodMetrics metrics = lodMetrics(mesh, *chain, ScreenParams{}, settings.hysteresis);
    asset.screen_coverage = msftScreenCoverage(metrics);
    description.assets.push_back(std::move(asset));
    step("pack writing (writePackGlb)", [&] { (void)writePackGlb(std::move(description)); });
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    std::string mesh_path = std::string(LODBAKE_BENCH_MESHES_DIR) + "/dragon_poisson.ply";
    int runs = 3;
    bool stages_only = false, bar_only = false;
    std::string cli = LODBAKE_BENCH_CLI;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--runs" && i + 1 < argc) {
            runs = std::max(1, std::atoi(argv[++i]));
        } else if (a == "--stages") {
            stages_only = true;
        } else if (a == "--bar-only") {
            bar_only = true;
        } else if (a == "--cli" && i + 1 < argc) {
            cli = argv[++i];
        } else if (!a.empty() && a[0] != '-') {
            mesh_path = a;
        } else {
            std::fprintf(stderr, "usage: bake_bench [--runs N] [--stages] [--bar-only] [--cli PATH] [--check] [MESH]\n");
            return 2;
        }
    }
    const std::string preset = std::string(LODBAKE_BENCH_SOURCE_DIR) + "/configs/desktop.json";
    lodbake::BakeSettings settings;
    const lodbake::Status preset_status = lodbake::applyPresetFile(preset, settings);
    if (!preset_status.ok()) {
        std::fprintf(stderr, "error: %s\n", preset_status.message().c_str());
        return 1;
    }
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(mesh_path, lodbake::ReadOptions{}, diagnostics);
    if (!loaded.ok()) {
        std::fprintf(stderr, "error: %s\n", loaded.status().message().c_str());
        return 1;
    }
    const lodbake::Mesh& mesh = loaded->mesh;
    std::printf("mesh %s: %zu triangles; levels", mesh_path.c_str(), mesh.faceCount());
    for (double r : settings.lod_ratios) std::printf(" %g", r);
    std::printf("\n");

    if (stages_only) {
        stageBreakdown(mesh, settings, 1);
        stageBreakdown(mesh, settings, 2);
        return 0;
    }
    const std::string out = std::string(LODBAKE_BENCH_OUT_DIR) + "/bake_bench.glb";
    const std::vector<std::string> command{cli, "bake", mesh_path, "--preset", preset, "--threads", "2", "-o", out};
    std::vector<double> ours_runs, native_runs, peak_runs;
    std::vector<size_t> triangles;
    for (int r = 0; r < runs; ++r) {
        const double start = now();
        double peak = 0;
        if (!runChild(command, peak)) {
            std::fprintf(stderr, "error: '%s bake %s' failed\n", cli.c_str(), mesh_path.c_str());
            return 1;
        }
        ours_runs.push_back(now() - start);
        peak_runs.push_back(peak);
        native_runs.push_back(nativeSeconds(mesh, settings.lod_ratios, triangles));
    }
    const double ours = lodbake_bench::median(ours_runs), native = lodbake_bench::median(native_runs);
    // Where the time goes, in process (2 threads): repair, then the chain with and without measuring.
    if (!bar_only) {
        lodbake::ScopedThreadLimit limit(2);
        lodbake::Mesh repaired = mesh;
        lodbake::Diagnostics d;
        double t0 = now();
        (void)lodbake::repairMesh(repaired, lodbake::RepairOptions{}, "bench", d);
        const double repair_s = now() - t0;
        lodbake::LodChainOptions chain_options;
        chain_options.ratios = settings.lod_ratios;
        chain_options.record_collapses = false;
        chain_options.measure_error = false;
        t0 = now();
        (void)lodbake::buildLodChain(repaired, chain_options, d);
        const double chain_s = now() - t0;
        chain_options.measure_error = true;
        chain_options.distance.sample_count = settings.error_samples;
        t0 = now();
        (void)lodbake::buildLodChain(repaired, chain_options, d);
        const double measured_s = now() - t0;
        std::vector<lodbake::BakeInput> inputs{{"bench", mesh}};
        t0 = now();
        auto baked = lodbake::bake(std::move(inputs), settings, d);
        const double bake_s = now() - t0;
        std::printf("stages (in process, 2 threads): repair %.3f s; chain %.3f s; chain + error measurement %.3f s; "
                    "bake() total %.3f s (pack %zu bytes)\n",
                    repair_s, chain_s, measured_s, bake_s, baked.ok() ? baked->glb.size() : size_t(0));
    }
    std::printf("native meshopt_simplify levels (triangles):");
    for (size_t t : triangles) std::printf(" %zu", t);
    std::printf("\nlodbake bake (desktop preset, 2 threads, whole CLI run) median %.3f s (best %.3f); native "
                "meshopt_simplify (2 threads) median %.3f s (best %.3f); ratio of medians %.2f; %d runs each\n",
                ours, *std::min_element(ours_runs.begin(), ours_runs.end()), native,
                *std::min_element(native_runs.begin(), native_runs.end()), ours / native, runs);
    std::printf("lodbake bake peak resident size: median %.1f MiB (runs:", lodbake_bench::median(peak_runs));
    for (double p : peak_runs) std::printf(" %.1f", p);
    std::printf(")\n");
    lodbake_bench::Bars bars("bake_bench");
    const std::string mesh_name = mesh_path.substr(mesh_path.find_last_of('/') + 1);
    bars.ratio("bake time / native meshopt_simplify, " + mesh_name + ", 2 threads (s)", ours, native, 3.0,
               lodbake_bench::Limit::AtMost);
    return bars.finish(check);
}
