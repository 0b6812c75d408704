// Simplification benchmark: our simplifier next to two meshoptimizer anchors measured in the same
// run (these machines are noisy, so only same-run ratios mean anything).
//
//   quality  per mesh and ratio (0.5, 0.1, 0.02, 0.005): triangles, mean and Hausdorff distance
//            (measureSurfaceDistance, relative to the input's diagonal) of our level and of npm
//            meshoptimizer 1.3 simplifyWithUpdate (no error limit, no flags) run by
//            scripts/node-bench/simplify.mjs on the same input at our level's triangle count.
//   speed    our 5-level chain (0.5, 0.25, 0.1, 0.03, 0.01; buildLodChain without error
//            measurement) against native meshopt_simplify (Debian libmeshoptimizer 0.18, options 0,
//            no error limit) for the same 5 levels, each from the original, one thread.
//   memory   peak RSS (VmHWM) of a fresh process of this program that loads the mesh and
//            builds the chain (or runs the 5 meshopt_simplify calls), minus an idle one, per input triangle.
//
//   quality levels are compared at EQUAL OR FEWER triangles: meshoptimizer 1.3 runs first at the
//            ratio's target, then our level is made with meshoptimizer's achieved count as target.
//            Two chains per mesh, both printed for every cell: the defaults (what `lodbake lods`
//            gives; topology kept, late levels refined) and with remove_covered_components (the
//            setting a preset for merged scans uses, `--remove-covered-components`).
//
// Bars (docs/simplify.md), per mesh: mean and Hausdorff distance <= meshoptimizer 1.3's in every
// cell (a cell is met by the defaults or by remove_covered_components, the merged-scan presets'
// setting; judged on the worst cell); chain time <= native meshopt_simplify on the meshes of 500k
// triangles and more (the bar is set on the 1 M-triangle meshes; median of the runs); peak RSS of the
// chain <= 300 B per input triangle (native meshopt's printed beside it).
//
// usage: simplify_bench [--meshes DIR] [--out DIR] [--node-bench DIR] [--samples N] [--skip-node]
//                       [--speed-only] [--runs N] [--check] [MESH...]
// The run ends with one summary table (markdown) of every mesh: quality, speed ratio, memory, then the
// bars; --check exits 1 when one is not met.
// Not a ctest: run it through scripts/bench-simplify.sh.

#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <meshoptimizer.h>

#include "bench_bar.h"
#include "core/parallel.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"

namespace {

using lodbake::Mesh;

const std::vector<double> kQualityRatios{0.5, 0.1, 0.02, 0.005};
const std::vector<double> kChainRatios{0.5, 0.25, 0.1, 0.03, 0.01};
const std::vector<std::string> kDefaultMeshes{"bunny_zipper.ply", "igea.ply",           "lucy100k.ply",
                                              "nefertiti.obj",    "dragon_poisson.ply", "dragon_stand_merged.ply"};

struct Args {
    std::string meshes_dir = LODBAKE_BENCH_MESHES_DIR;
    std::string out_dir = LODBAKE_BENCH_OUT_DIR;
    std::string node_bench_dir = LODBAKE_BENCH_NODE_DIR;
    uint32_t samples = 200000;
    bool run_node = true;
    bool speed_only = false; // skip memory and quality
    int runs = 0;            // timing runs per mesh; 0: 3, or 2 above 400k triangles
    std::vector<std::string> meshes;
};

// One mesh's figures, kept for the summary table printed at the end.
struct QualityRow {
    double ratio = 0;
    size_t ours_tris = 0, anchor_tris = 0;
    double ours_mean = 0, ours_haus = 0, anchor_mean = 0, anchor_haus = 0;
    size_t covered_tris = 0; // with remove_covered_components
    double covered_mean = 0, covered_haus = 0;
};
struct MeshResult {
    std::string name;
    size_t triangles = 0;
    double ours_s = 0, native_s = 0;
    double ours_bytes = 0, native_bytes = 0;
    std::vector<QualityRow> quality;
};

double seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
    return std::chrono::duration<double>(b - a).count();
}

lodbake::Result<Mesh> load(const std::string& path) {
    lodbake::Diagnostics diagnostics;
    LODBAKE_ASSIGN_OR_RETURN(lodbake::LoadedMesh loaded, lodbake::readMesh(path, lodbake::ReadOptions(), diagnostics));
    Mesh mesh = std::move(loaded.mesh);
    // Positions only: the anchors see positions only, so attribute quadrics must not tilt the comparison.
    mesh.normals.clear();
    mesh.uvs.clear();
    mesh.colors.clear();
    mesh.tangents.clear();
    return mesh;
}

lodbake::Result<lodbake::LodChain> ourChain(const Mesh& mesh, const std::vector<double>& ratios,
                                           bool remove_covered_components = false) {
    lodbake::LodChainOptions options;
    options.ratios = ratios;
    options.simplify.remove_covered_components = remove_covered_components;
    options.measure_error = false;
    lodbake::Diagnostics diagnostics;
    return lodbake::buildLodChain(mesh, options, diagnostics);
}

// The five native meshopt_simplify levels, each from the original. Returns triangles per level.
std::vector<size_t> nativeChain(const Mesh& mesh) {
    std::vector<size_t> triangles;
    std::vector<unsigned int> destination(mesh.indices.size());
    for (double ratio : kChainRatios) {
        size_t target = size_t(double(mesh.faceCount()) * ratio) * 3;
        size_t count =
            meshopt_simplify(destination.data(), mesh.indices.data(), mesh.indices.size(), &mesh.positions[0].x,
                             mesh.positions.size(), sizeof(lodbake::Vec3f), target, FLT_MAX, 0, nullptr);
        triangles.push_back(count / 3);
    }
    return triangles;
}

std::string shellQuote(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

// Peak resident set of this process so far (VmHWM), in bytes; 0 if unknown. VmHWM belongs to the
// address space, so a freshly exec'd process starts from zero (ru_maxrss would include the forking
// parent's pages).
uint64_t peakRssOfSelf() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) == 0) return uint64_t(std::strtoull(line.c_str() + 6, nullptr, 10)) * 1024;
    }
    return 0;
}

// The work whose peak memory is measured, run by a child process (`--rss-child none|ours|native MESH`);
// prints "peak_rss <bytes>".
bool rssChildWork(const std::string& which, const std::string& path) {
    if (which != "none") { // "none" is the baseline: an idle process of this program
        auto mesh = load(path);
        if (!mesh.ok()) return false;
        if (which == "ours") {
            if (!ourChain(mesh.value(), kChainRatios).ok()) return false;
        } else {
            nativeChain(mesh.value());
        }
    }
    std::printf("peak_rss %llu\n", static_cast<unsigned long long>(peakRssOfSelf()));
    return true;
}

// Runs this program again as `--rss-child which path` and returns the child's peak RSS in bytes
// (0 if it failed). A fresh process, not a bare fork: TBB's worker pool does not survive fork.
uint64_t peakRssOfChild(const std::string& which, const std::string& path) {
    std::fflush(stdout);
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
    if (n <= 0) return 0;
    self[n] = 0;
    std::string cmd = shellQuote(self) + " --rss-child " + which + " " + shellQuote(path);
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return 0;
    uint64_t rss = 0;
    char line[256];
    while (std::fgets(line, sizeof(line), pipe)) {
        if (std::strncmp(line, "peak_rss ", 9) == 0) rss = std::strtoull(line + 9, nullptr, 10);
    }
    return pclose(pipe) == 0 ? rss : 0;
}

struct AnchorLevel {
    size_t target = 0;
    size_t triangles = 0;
    double seconds = 0;
    std::string path;
};

double jsonNumber(const std::string& line, const std::string& key) {
    size_t at = line.find("\"" + key + "\":");
    return at == std::string::npos ? -1.0 : std::strtod(line.c_str() + at + key.size() + 3, nullptr);
}

std::string jsonString(const std::string& line, const std::string& key) {
    size_t at = line.find("\"" + key + "\":\"");
    if (at == std::string::npos) return {};
    at += key.size() + 4;
    return line.substr(at, line.find('"', at) - at);
}

// Runs scripts/node-bench/simplify.mjs once for all targets of one mesh.
std::vector<AnchorLevel> runNodeAnchor(const Args& args, const std::string& input_ply, const std::string& prefix,
                                       const std::vector<size_t>& targets) {
    std::string cmd = "node " + shellQuote(args.node_bench_dir + "/simplify.mjs") + " " + shellQuote(input_ply) + " " +
                      shellQuote(prefix);
    for (size_t t : targets) cmd += " " + std::to_string(t);
    std::vector<AnchorLevel> levels;
    FILE* pipe = popen(cmd.c_str(), "r");
    if (!pipe) return levels;
    char buffer[4096];
    while (std::fgets(buffer, sizeof(buffer), pipe)) {
        std::string line(buffer);
        AnchorLevel level;
        level.target = size_t(jsonNumber(line, "target"));
        level.triangles = size_t(jsonNumber(line, "triangles"));
        level.seconds = jsonNumber(line, "seconds");
        level.path = jsonString(line, "path");
        if (!level.path.empty()) levels.push_back(level);
    }
    if (pclose(pipe) != 0) std::printf("  meshoptimizer 1.3 anchor failed: %s\n", cmd.c_str());
    return levels;
}

std::string ratioText(double ours, double anchor) {
    if (!(anchor > 0)) return "   n/a";
    char b[32];
    std::snprintf(b, sizeof(b), "%6.2f", ours / anchor);
    return b;
}

MeshResult benchMesh(const Args& args, const std::string& name) {
    MeshResult result;
    result.name = name.substr(0, name.find('.'));
    const std::string path = args.meshes_dir + "/" + name;
    std::printf("\n== %s\n", name.c_str());
    std::fflush(stdout);

    // Memory first, while the parent holds no mesh.
    uint64_t baseline_rss = 0, ours_rss = 0, native_rss = 0;
    if (!args.speed_only) {
        baseline_rss = peakRssOfChild("none", path);
        ours_rss = peakRssOfChild("ours", path);
        native_rss = peakRssOfChild("native", path);
    }

    auto loaded = load(path);
    if (!loaded.ok()) {
        std::printf("  skipped: %s\n", loaded.status().message().c_str());
        return result;
    }
    const Mesh& mesh = loaded.value();
    const double tris = double(mesh.faceCount());
    result.triangles = mesh.faceCount();
    std::printf("  %zu vertices, %zu triangles\n", mesh.vertexCount(), mesh.faceCount());

    // Speed: the median of a few alternating runs, our chain on one thread (and once on all threads).
    const int runs = args.runs > 0 ? args.runs : (mesh.faceCount() > 400000 ? 2 : 3);
    double ours_nt = 1e30;
    std::vector<double> ours_runs, native_runs;
    std::vector<size_t> ours_chain_tris, native_chain_tris;
    for (int r = 0; r < runs; ++r) {
        {
            lodbake::ScopedThreadLimit limit(1);
            auto t0 = std::chrono::steady_clock::now();
            auto chain = ourChain(mesh, kChainRatios);
            auto t1 = std::chrono::steady_clock::now();
            if (!chain.ok()) {
                std::printf("  our chain failed: %s\n", chain.status().message().c_str());
                return result;
            }
            ours_runs.push_back(seconds(t0, t1));
            ours_chain_tris.clear();
            for (const auto& level : chain->levels) ours_chain_tris.push_back(level.mesh.faceCount());
        }
        if (r == 0) {
            auto t0 = std::chrono::steady_clock::now();
            auto chain = ourChain(mesh, kChainRatios);
            auto t1 = std::chrono::steady_clock::now();
            ours_nt = std::min(ours_nt, seconds(t0, t1));
        }
        auto t0 = std::chrono::steady_clock::now();
        native_chain_tris = nativeChain(mesh);
        auto t1 = std::chrono::steady_clock::now();
        native_runs.push_back(seconds(t0, t1));
    }
    const double ours_1t = lodbake_bench::median(ours_runs), native_t = lodbake_bench::median(native_runs);
    result.ours_s = ours_1t;
    result.native_s = native_t;
    std::printf("  5-level chain (0.5 0.25 0.1 0.03 0.01), median of %d: ours %.3f s (1 thread), %.3f s (all threads); "
                "native meshopt_simplify %.3f s; ours/native %.2f (1 thread)\n",
                runs, ours_1t, ours_nt, native_t, ours_1t / native_t);
    std::printf("  chain triangles ours:");
    for (size_t t : ours_chain_tris) std::printf(" %zu", t);
    std::printf("; native:");
    for (size_t t : native_chain_tris) std::printf(" %zu", t);
    std::printf("\n");
    if (args.speed_only) return result;
    auto net = [&](uint64_t rss) { return rss > baseline_rss ? double(rss - baseline_rss) / tris : 0.0; };
    result.ours_bytes = net(ours_rss);
    result.native_bytes = net(native_rss);
    std::printf("  peak RSS per input triangle (child process: load + chain, minus an idle one's %.1f MB): "
                "ours %.0f B, native meshopt %.0f B\n",
                double(baseline_rss) / 1e6, result.ours_bytes, result.native_bytes);

    // Quality: meshoptimizer 1.3 first, at each ratio's target; then ours at its achieved count.
    std::vector<size_t> targets;
    for (double ratio : kQualityRatios) targets.push_back(std::max<size_t>(1, size_t(std::ceil(ratio * tris))));
    std::vector<AnchorLevel> anchor;
    if (args.run_node) {
        std::string input_ply = args.out_dir + "/" + result.name + "_input.ply";
        lodbake::Diagnostics diagnostics;
        lodbake::Status written = lodbake::writeMesh(mesh, input_ply, lodbake::WriteOptions(), diagnostics);
        if (written.ok()) {
            anchor = runNodeAnchor(args, input_ply, args.out_dir + "/" + result.name + "_meshopt13", targets);
        } else {
            std::printf("  cannot write %s: %s\n", input_ply.c_str(), written.message().c_str());
        }
    }
    // Our targets: the anchor's achieved count where it has one (never more than the ratio's target).
    // The chain's level target is ceil(ratio × input faces), so aim half a triangle below the count.
    std::vector<double> our_ratios;
    for (size_t i = 0; i < targets.size(); ++i) {
        size_t count = targets[i];
        if (i < anchor.size() && anchor[i].triangles > 0) count = std::min(count, anchor[i].triangles);
        our_ratios.push_back((double(count) - 0.5) / tris);
    }
    // Two chains: the defaults (topology kept) and with remove_covered_components (components that
    // lie within the accepted error of the rest of the surface may go); both at the same targets.
    auto chain = ourChain(mesh, our_ratios);
    auto covered_chain = ourChain(mesh, our_ratios, true);
    if (!chain.ok() || !covered_chain.ok()) {
        std::printf("  our chain failed: %s\n",
                    (chain.ok() ? covered_chain.status() : chain.status()).message().c_str());
        return result;
    }
    auto prepare_start = std::chrono::steady_clock::now();
    auto reference = lodbake::DistanceReference::prepare(mesh);
    const double prepare_s = seconds(prepare_start, std::chrono::steady_clock::now());
    if (!reference.ok()) {
        std::printf("  cannot measure: %s\n", reference.status().message().c_str());
        return result;
    }
    lodbake::DistanceOptions distance;
    distance.sample_count = args.samples;

    std::printf("  %-6s | %9s %10s %10s | %9s %10s %10s | %9s %10s %10s | %6s %6s | %6s %6s\n", "ratio", "ours tri",
                "ours mean", "ours haus", "cov tri", "cov mean", "cov haus", "mo13 tri", "mo13 mean", "mo13 haus",
                "mean", "haus", "cmean", "chaus");
    double measure_s = 0;
    for (size_t i = 0; i < chain->levels.size() && i < kQualityRatios.size(); ++i) {
        const lodbake::LodLevel& level = chain->levels[i];
        const lodbake::LodLevel& covered_level = covered_chain->levels[i];
        auto measure_start = std::chrono::steady_clock::now();
        auto ours = lodbake::measureSurfaceDistance(reference.value(), level.mesh, distance);
        auto covered = lodbake::measureSurfaceDistance(reference.value(), covered_level.mesh, distance);
        measure_s += seconds(measure_start, std::chrono::steady_clock::now());
        QualityRow row;
        row.ratio = kQualityRatios[i];
        row.ours_tris = level.mesh.faceCount();
        row.covered_tris = covered_level.mesh.faceCount();
        if (i < anchor.size()) {
            auto anchor_mesh = load(anchor[i].path);
            if (anchor_mesh.ok()) {
                auto d = lodbake::measureSurfaceDistance(reference.value(), anchor_mesh.value(), distance);
                if (d.ok()) {
                    row.anchor_tris = anchor_mesh->faceCount();
                    row.anchor_mean = d->meanRel();
                    row.anchor_haus = d->hausdorffRel();
                }
            }
        }
        if (ours.ok()) {
            row.ours_mean = ours->meanRel();
            row.ours_haus = ours->hausdorffRel();
        }
        if (covered.ok()) {
            row.covered_mean = covered->meanRel();
            row.covered_haus = covered->hausdorffRel();
        }
        result.quality.push_back(row);
        std::printf("  %-6g | %9zu %10.3e %10.3e | %9zu %10.3e %10.3e | %9zu %10.3e %10.3e | %s %s | %s %s | %zu "
                    "components removed%s\n",
                    row.ratio, row.ours_tris, row.ours_mean, row.ours_haus, row.covered_tris, row.covered_mean,
                    row.covered_haus, row.anchor_tris, row.anchor_mean, row.anchor_haus,
                    ratioText(row.ours_mean, row.anchor_mean).c_str(), ratioText(row.ours_haus, row.anchor_haus).c_str(),
                    ratioText(row.covered_mean, row.anchor_mean).c_str(),
                    ratioText(row.covered_haus, row.anchor_haus).c_str(), covered_level.removal_count,
                    level.reached_target && covered_level.reached_target ? "" : "  (ours missed the target)");
    }
    std::printf("  distance metric (ours, all threads): reference BVH %.3f s, %zu levels measured in %.3f s\n",
                prepare_s, chain->levels.size(), measure_s);
    std::fflush(stdout);
    return result;
}

void printSummary(const std::vector<MeshResult>& results, bool speed_only) {
    std::printf("\n## Summary (ratios ours / anchor; quality anchor meshoptimizer 1.3 simplifyWithUpdate, speed "
                "anchor native meshopt_simplify)\n\n");
    if (!speed_only) {
        std::printf("Columns \"cov\": with remove_covered_components (the scanned presets' setting); the others "
                    "with the defaults (topology kept).\n\n");
        std::printf("| mesh | ratio | triangles ours / cov / mo 1.3 | our mean | cov mean | mo 1.3 mean | our Hausdorff | "
                    "cov Hausdorff | mo 1.3 Hausdorff | mean ratio | Hausdorff ratio | cov mean ratio | cov Hausdorff "
                    "ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for (const MeshResult& m : results)
            for (const QualityRow& q : m.quality)
                std::printf("| %s | %g | %zu / %zu / %zu | %.3e | %.3e | %.3e | %.3e | %.3e | %.3e | %s | %s | %s | %s |\n",
                            m.name.c_str(), q.ratio, q.ours_tris, q.covered_tris, q.anchor_tris, q.ours_mean,
                            q.covered_mean, q.anchor_mean, q.ours_haus, q.covered_haus, q.anchor_haus,
                            ratioText(q.ours_mean, q.anchor_mean).c_str(), ratioText(q.ours_haus, q.anchor_haus).c_str(),
                            ratioText(q.covered_mean, q.anchor_mean).c_str(),
                            ratioText(q.covered_haus, q.anchor_haus).c_str());
        std::printf("\n");
    }
    // Peak memory is measured in child processes only for full runs; --speed-only leaves it out.
    std::printf("| mesh | triangles | chain ours s | native s | time ratio |%s\n|---|---|---|---|---|%s\n",
                speed_only ? "" : " ours B/tri | native B/tri |", speed_only ? "" : "---|---|");
    for (const MeshResult& m : results) {
        std::printf("| %s | %zu | %.3f | %.3f | %s |", m.name.c_str(), m.triangles, m.ours_s, m.native_s,
                    ratioText(m.ours_s, m.native_s).c_str());
        if (!speed_only) std::printf(" %.0f | %.0f |", m.ours_bytes, m.native_bytes);
        std::printf("\n");
    }
}

// The bars of every mesh measured (see the header).
void judge(const std::vector<MeshResult>& results, bool speed_only, lodbake_bench::Bars& bars) {
    using lodbake_bench::Limit;
    for (const MeshResult& m : results) {
        if (m.triangles == 0) {
            bars.unmeasured(m.name + ": not loaded", 1.0, Limit::AtMost, true);
            continue;
        }
        // Per cell the better setting; over cells the worst ratio.
        struct Worst {
            double ours = 0, anchor = 0, ratio = -1;
            double cell = 0;
            bool measured = true;
        } mean, haus;
        for (const QualityRow& q : m.quality) {
            auto take = [&](Worst& w, double ours, double covered, double anchor) {
                // A distance of 0 is a failed measurement (a simplified level is never exact).
                if (!(anchor > 0) || !(ours > 0) || !(covered > 0)) {
                    w.measured = false;
                    return;
                }
                const double best = std::min(ours, covered);
                if (best / anchor > w.ratio) w = Worst{best, anchor, best / anchor, q.ratio, w.measured};
            };
            take(mean, q.ours_mean, q.covered_mean, q.anchor_mean);
            take(haus, q.ours_haus, q.covered_haus, q.anchor_haus);
        }
        if (!speed_only) {
            for (const auto& [what, w] : {std::make_pair("mean", &mean), std::make_pair("Hausdorff", &haus)}) {
                char name[160];
                std::snprintf(name, sizeof(name), "%s: %s distance / meshoptimizer 1.3 (worst cell: ratio %g)",
                              m.name.c_str(), what, w->cell);
                if (!w->measured || w->ratio < 0)
                    bars.unmeasured(m.name + ": " + what + " distance / meshoptimizer 1.3 (anchor missing)", 1.0,
                                    Limit::AtMost, true);
                else
                    bars.ratio(name, w->ours, w->anchor, 1.0, Limit::AtMost);
            }
            // 0: the child process that measures the peak failed.
            if (m.ours_bytes > 0)
                bars.absolute(m.name + ": chain peak RSS per input triangle (B; anchor: native meshopt)", m.ours_bytes,
                              300, Limit::AtMost, m.native_bytes);
            else
                bars.unmeasured(m.name + ": chain peak RSS per input triangle (the measuring process failed)", 300,
                                Limit::AtMost, false);
        }
        if (m.triangles >= 500000)
            bars.ratio(m.name + ": 5-level chain time / native meshopt_simplify, 1 thread (s)", m.ours_s, m.native_s,
                       1.0, Limit::AtMost);
    }
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    if (argc == 4 && std::string(argv[1]) == "--rss-child") return rssChildWork(argv[2], argv[3]) ? 0 : 1;
    Args args;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "error: %s needs a value\n", a.c_str());
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--meshes")
            args.meshes_dir = value();
        else if (a == "--out")
            args.out_dir = value();
        else if (a == "--node-bench")
            args.node_bench_dir = value();
        else if (a == "--samples")
            args.samples = uint32_t(std::strtoul(value().c_str(), nullptr, 10));
        else if (a == "--skip-node")
            args.run_node = false;
        else if (a == "--speed-only")
            args.speed_only = true;
        else if (a == "--runs")
            args.runs = int(std::strtol(value().c_str(), nullptr, 10));
        else if (!a.empty() && a[0] == '-') {
            std::fprintf(stderr, "error: unknown option %s\n", a.c_str());
            return 2;
        } else
            args.meshes.push_back(a);
    }
    if (args.meshes.empty()) args.meshes = kDefaultMeshes;
    if (std::system(("mkdir -p " + shellQuote(args.out_dir)).c_str()) != 0) {
        std::fprintf(stderr, "error: cannot create %s\n", args.out_dir.c_str());
        return 1;
    }
    std::printf("simplify_bench: distances relative to the input's bounding-box diagonal, %u samples per side "
                "plus vertices; ratio columns are ours / meshoptimizer 1.3 (lower is better for mean and haus)\n",
                args.samples);
    std::vector<MeshResult> results;
    for (const std::string& name : args.meshes) results.push_back(benchMesh(args, name));
    const bool any = std::any_of(results.begin(), results.end(), [](const MeshResult& r) { return r.triangles > 0; });
    if (!any) {
        std::fprintf(stderr, "error: no mesh could be loaded from %s: nothing was measured\n", args.meshes_dir.c_str());
        return 1;
    }
    printSummary(results, args.speed_only);
    lodbake_bench::Bars bars("simplify_bench");
    judge(results, args.speed_only, bars);
    return bars.finish(check);
}
