// repair_bench: times the default repair pipeline (repairMesh) on the shared scans, best of 3 runs
// on fresh copies, and prints it next to an anchor measured in the same run: computeTopologyStats
// on the same input (one sort of all half-edges), as a ratio, so a noisy machine shows in both.
// Also prints what the pipeline left unresolved, and a denoise run's roughness before/after.
//
// usage: repair_bench [DIR] [FILE...]   (DIR defaults to the shared meshes folder)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench_timing.h"

#include "lodbake/cleanup/repair.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/io/mesh_io.h"

namespace {

constexpr int kRuns = 3;

template <class F> double bestMs(F&& f) { return lodbake_bench::bestMs(kRuns, f); }

} // namespace

int main(int argc, char** argv) {
    using namespace lodbake;
    const std::string dir = argc > 1 ? argv[1] : LODBAKE_BENCH_SHARED_MESHES_DIR;
    std::vector<std::string> names;
    for (int i = 2; i < argc; ++i) names.push_back(argv[i]);
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
        Mesh smooth = out;
        const DenoiseReport dr = denoise(smooth);
        std::printf("    denoise (taubin): roughness %.3f -> %.3f deg, mean displacement %.2e of diagonal\n",
                    dr.roughness_before_deg, dr.roughness_after_deg, dr.mean_displacement_rel);
    }
    return failures ? 1 : 0;
}
