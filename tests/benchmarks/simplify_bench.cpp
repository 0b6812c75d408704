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
// usage: simplify_bench [--meshes DIR] [--out DIR] [--node-bench DIR] [--samples N] [--skip-node] [MESH...]
// Not a ctest: run it through scripts/bench-simplify.sh.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cfloat>
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
    std::vector<std::string> meshes;
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

lodbake::Result<lodbake::LodChain> ourChain(const Mesh& mesh, const std::vector<double>& ratios) {
    lodbake::LodChainOptions options;
    options.ratios = ratios;
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

void benchMesh(const Args& args, const std::string& name) {
    const std::string path = args.meshes_dir + "/" + name;
    std::printf("\n== %s\n", name.c_str());
    std::fflush(stdout);

    // Memory first, while the parent holds no mesh.
    const uint64_t baseline_rss = peakRssOfChild("none", path);
    const uint64_t ours_rss = peakRssOfChild("ours", path);
    const uint64_t native_rss = peakRssOfChild("native", path);

    auto loaded = load(path);
    if (!loaded.ok()) {
        std::printf("  skipped: %s\n", loaded.status().message().c_str());
        return;
    }
    const Mesh& mesh = loaded.value();
    const double tris = double(mesh.faceCount());
    std::printf("  %zu vertices, %zu triangles\n", mesh.vertexCount(), mesh.faceCount());

    // Speed: best of a few runs (fewer for big meshes), our chain on one thread and on all threads.
    const int runs = mesh.faceCount() > 400000 ? 1 : 3;
    double ours_1t = 1e30, ours_nt = 1e30, native_t = 1e30;
    std::vector<size_t> ours_chain_tris, native_chain_tris;
    for (int r = 0; r < runs; ++r) {
        {
            lodbake::ScopedThreadLimit limit(1);
            auto t0 = std::chrono::steady_clock::now();
            auto chain = ourChain(mesh, kChainRatios);
            auto t1 = std::chrono::steady_clock::now();
            if (!chain.ok()) {
                std::printf("  our chain failed: %s\n", chain.status().message().c_str());
                return;
            }
            ours_1t = std::min(ours_1t, seconds(t0, t1));
            ours_chain_tris.clear();
            for (const auto& level : chain->levels) ours_chain_tris.push_back(level.mesh.faceCount());
        }
        {
            auto t0 = std::chrono::steady_clock::now();
            auto chain = ourChain(mesh, kChainRatios);
            auto t1 = std::chrono::steady_clock::now();
            ours_nt = std::min(ours_nt, seconds(t0, t1));
        }
        auto t0 = std::chrono::steady_clock::now();
        native_chain_tris = nativeChain(mesh);
        auto t1 = std::chrono::steady_clock::now();
        native_t = std::min(native_t, seconds(t0, t1));
    }
    std::printf("  5-level chain (0.5 0.25 0.1 0.03 0.01): ours %.3f s (1 thread), %.3f s (all threads); "
                "native meshopt_simplify 0.18 %.3f s; ours/native %.2f (1 thread)\n",
                ours_1t, ours_nt, native_t, ours_1t / native_t);
    std::printf("  chain triangles ours:");
    for (size_t t : ours_chain_tris) std::printf(" %zu", t);
    std::printf("; native:");
    for (size_t t : native_chain_tris) std::printf(" %zu", t);
    auto net = [&](uint64_t rss) { return rss > baseline_rss ? double(rss - baseline_rss) / tris : 0.0; };
    std::printf("\n  peak RSS per input triangle (child process: load + chain, minus an idle one's %.1f MB): "
                "ours %.0f B, native meshopt %.0f B\n",
                double(baseline_rss) / 1e6, net(ours_rss), net(native_rss));

    // Quality.
    auto chain = ourChain(mesh, kQualityRatios);
    if (!chain.ok()) {
        std::printf("  our chain failed: %s\n", chain.status().message().c_str());
        return;
    }
    auto prepare_start = std::chrono::steady_clock::now();
    auto reference = lodbake::DistanceReference::prepare(mesh);
    const double prepare_s = seconds(prepare_start, std::chrono::steady_clock::now());
    if (!reference.ok()) {
        std::printf("  cannot measure: %s\n", reference.status().message().c_str());
        return;
    }
    lodbake::DistanceOptions distance;
    distance.sample_count = args.samples;

    std::vector<size_t> targets;
    for (const auto& level : chain->levels) targets.push_back(std::max<size_t>(1, level.mesh.faceCount()));
    std::vector<AnchorLevel> anchor;
    if (args.run_node) {
        std::string base = name.substr(0, name.find('.'));
        std::string input_ply = args.out_dir + "/" + base + "_input.ply";
        lodbake::Diagnostics diagnostics;
        lodbake::Status written = lodbake::writeMesh(mesh, input_ply, lodbake::WriteOptions(), diagnostics);
        if (written.ok()) {
            anchor = runNodeAnchor(args, input_ply, args.out_dir + "/" + base + "_meshopt13", targets);
        } else {
            std::printf("  cannot write %s: %s\n", input_ply.c_str(), written.message().c_str());
        }
    }

    std::printf("  %-6s | %9s %10s %10s | %9s %10s %10s | %6s %6s %6s\n", "ratio", "ours tri", "ours mean", "ours haus",
                "mo13 tri", "mo13 mean", "mo13 haus", "tri", "mean", "haus");
    double measure_s = 0;
    for (size_t i = 0; i < chain->levels.size(); ++i) {
        const lodbake::LodLevel& level = chain->levels[i];
        auto measure_start = std::chrono::steady_clock::now();
        auto ours = lodbake::measureSurfaceDistance(reference.value(), level.mesh, distance);
        measure_s += seconds(measure_start, std::chrono::steady_clock::now());
        double anchor_tris = 0, anchor_mean = 0, anchor_haus = 0;
        if (i < anchor.size()) {
            auto anchor_mesh = load(anchor[i].path);
            if (anchor_mesh.ok()) {
                auto d = lodbake::measureSurfaceDistance(reference.value(), anchor_mesh.value(), distance);
                if (d.ok()) {
                    anchor_tris = double(anchor_mesh->faceCount());
                    anchor_mean = d->meanRel();
                    anchor_haus = d->hausdorffRel();
                }
            }
        }
        double ours_mean = ours.ok() ? ours->meanRel() : 0, ours_haus = ours.ok() ? ours->hausdorffRel() : 0;
        std::printf("  %-6g | %9zu %10.3e %10.3e | %9.0f %10.3e %10.3e | %s %s %s%s\n", level.target_ratio,
                    level.mesh.faceCount(), ours_mean, ours_haus, anchor_tris, anchor_mean, anchor_haus,
                    ratioText(double(level.mesh.faceCount()), anchor_tris).c_str(),
                    ratioText(ours_mean, anchor_mean).c_str(), ratioText(ours_haus, anchor_haus).c_str(),
                    level.reached_target ? "" : "  (ours missed the target; anchor given our count)");
    }
    std::printf("  distance metric (ours, all threads): reference BVH %.3f s, %zu levels measured in %.3f s\n",
                prepare_s, chain->levels.size(), measure_s);
    std::fflush(stdout);
}

} // namespace

int main(int argc, char** argv) {
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
    for (const std::string& name : args.meshes) benchMesh(args, name);
    return 0;
}
