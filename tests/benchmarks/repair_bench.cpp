// repair_bench: times the default repair pipeline (repairMesh) on the shared scans, best of 3 runs
// on fresh copies, and prints it next to an anchor measured in the same run: computeTopologyStats
// on the same input (one sort of all half-edges), as a ratio, so a noisy machine shows in both.
// Also prints what the pipeline left unresolved, a denoise run's roughness before/after, and (with
// --passes) the time of each pass run on its own, in pipeline order, on one copy.
// --bake: instead, the pipeline as `lodbake bake` runs it (RepairOptions report_before and
// report_welded off) at 1 and 2 threads: best-of-3 wall time with the process CPU time of that run.
//
// usage: repair_bench [--passes | --bake] [DIR] [FILE...]   (DIR defaults to the shared meshes folder)

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_bar.h"
#include "bench_timing.h"

#include "core/parallel.h"
#include "lodbake/cleanup/repair.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/io/mesh_io.h"

namespace {

constexpr int kRuns = 3;

template <class F> double bestMs(F&& f) { return lodbake_bench::bestMs(kRuns, f); }

// Runs the default pipeline's passes one by one on a copy of `input` and prints each one's time.
void printPassTimes(const lodbake::Mesh& input) {
    using namespace lodbake;
    Mesh m = input;
    const RepairOptions o;
    std::printf("    passes (ms):");
    auto timed = [&](const char* name, auto&& fn) {
        std::printf(" %s %.0f", name, lodbake_bench::bestMs(1, fn));
    };
    timed("validate", [&] { validate(m); });
    timed("weld", [&] { weldVertices(m, o.weld_options); });
    timed("degenerate", [&] { removeDegenerateFaces(m, o.degenerate_options); });
    timed("unreferenced", [&] { removeUnreferencedVertices(m); });
    timed("manifold", [&] { makeManifold(m, o.manifold_options); });
    timed("orient", [&] { orientFaces(m, o.orient_options); });
    timed("components", [&] { removeSmallComponents(m, o.component_options); });
    timed("unreferenced", [&] { removeUnreferencedVertices(m); });
    timed("holes", [&] { fillHoles(m, o.hole_options); });
    timed("normals", [&] { computeNormals(m, o.normal_options); });
    timed("validate", [&] { validate(m); });
    std::printf("\n");
}

double cpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

// The bake's repair call (bake.cpp) at 1 and 2 threads: best wall of kRuns, and that run's CPU time.
void printBakeTimes(const std::string& name, const lodbake::Mesh& input) {
    using namespace lodbake;
    RepairOptions o;
    o.report_welded = false;
    o.report_before = false;
    for (size_t threads : {size_t(1), size_t(2)}) {
        ScopedThreadLimit limit(threads);
        double best_wall = 1e300, best_cpu = 0.0;
        for (int run = 0; run < kRuns; ++run) {
            Mesh m = input;
            Diagnostics d;
            const auto t0 = std::chrono::steady_clock::now();
            const double c0 = cpuSeconds();
            (void)repairMesh(m, o, name, d);
            const double cpu = cpuSeconds() - c0;
            const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (wall < best_wall) {
                best_wall = wall;
                best_cpu = cpu;
            }
        }
        std::printf("    bake repair, %zu thread%s: wall %.3f s, cpu %.3f s\n", threads, threads > 1 ? "s" : "",
                    best_wall, best_cpu);
    }
}

} // namespace

int main(int argc, char** argv) {
    // --check is accepted so that scripts/bench.sh can pass it to every bench; there is no bar.
    (void)lodbake_bench::takeCheckFlag(argc, argv);
    lodbake_bench::Bars::printNone("repair_bench",
                                   "repair time next to computeTopologyStats; no bar in the docs or issues");
    using namespace lodbake;
    bool pass_times = false, bake_times = false;
    std::vector<std::string> args;
    for (int i = 1; i < argc; ++i) {
        if (std::string(argv[i]) == "--passes")
            pass_times = true;
        else if (std::string(argv[i]) == "--bake")
            bake_times = true;
        else
            args.push_back(argv[i]);
    }
    const std::string dir = !args.empty() ? args[0] : LODBAKE_BENCH_SHARED_MESHES_DIR;
    std::vector<std::string> names;
    for (size_t i = 1; i < args.size(); ++i) names.push_back(args[i]);
    if (names.empty())
        names = {"lucy100k.ply", "bunny_zipper.ply", "bunny_scan_bun000_tri.ply", "dragon_scan_stand0_tri.ply",
                 "dragon_stand_merged.ply"};
    std::printf("%-28s %9s %10s %10s %8s  %s\n", "file", "tris", "repair ms", "anchor ms", "ratio", "result");
    int failures = 0;
    for (const std::string& name : names) {
        const std::string path = dir + "/" + name;
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(path, ReadOptions(), diagnostics);
        if (!loaded.ok()) {
            std::printf("%-28s skipped: %s\n", name.c_str(), loaded.status().message().c_str());
            ++failures;
            continue;
        }
        const Mesh& input = loaded->mesh;
        if (bake_times) {
            std::printf("%-28s %9zu\n", name.c_str(), input.faceCount());
            printBakeTimes(name, input);
            continue;
        }
        RepairReport report;
        Mesh out;
        const double repair_ms = bestMs([&] {
            out = input;
            Diagnostics d;
            Result<RepairReport> r = repairMesh(out, RepairOptions(), name, d);
            if (r.ok()) report = *r;
        });
        const double anchor_ms = bestMs([&] { computeTopologyStats(input); });
        const TopologyStats& t = report.after.topology;
        std::printf("%-28s %9zu %10.1f %10.1f %8.2f  %s, %llu comp., %llu boundary loops, %zu tris\n", name.c_str(),
                    input.faceCount(), repair_ms, anchor_ms, repair_ms / anchor_ms,
                    report.after.isClosedManifold() ? "closed manifold"
                    : report.after.isManifold()     ? "manifold"
                                                    : "NOT manifold",
                    (unsigned long long)t.component_count, (unsigned long long)t.boundary_loop_count, out.faceCount());
        for (const std::string& u : report.unresolved) std::printf("    unresolved: %s\n", u.c_str());
        if (pass_times) printPassTimes(input);
        Mesh smooth = out;
        const DenoiseReport dr = denoise(smooth);
        std::printf("    denoise (taubin): roughness %.3f -> %.3f deg, mean displacement %.2e of diagonal\n",
                    dr.roughness_before_deg, dr.roughness_after_deg, dr.mean_displacement_rel);
    }
    return failures ? 1 : 0;
}
