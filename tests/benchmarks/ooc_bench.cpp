// ooc_bench: the foundations of the out-of-core bake, measured on a generated scan. Generates a
// displaced-torus scan of N triangles (lodbake_scansim's surface mode) into a work folder, then in
// the same run: streams it through the streaming reader (both passes), partitions it under a memory
// limit, and reads it whole with readMesh() as the anchor. Prints wall time, triangles per second and
// process CPU time and peak resident memory of each stage (VmHWM, reset between stages through
// /proc/self/clear_refs), and the ratios to readMesh. The in-memory reader runs last so that its memory does not stay resident
// under the other stages' figures.
//
// With --cluster, the partitions (sized for the partition job) are then built one after the other by
// buildPartition (lodbake/ooc/partition_build.h), and the whole scan by buildClusterLod, in the same
// run: triangles per second and peak resident memory of both, and the errors of the two at equal
// triangle counts. A depth-d cut is every cluster made at depth <= d whose parent group is deeper
// (a partition's roots stay in every cut above its top); its triangles and its largest and
// triangle-weighted mean group error are printed per depth, and each partitioned cut's errors are
// divided by the whole build's at the same triangle count (log-log interpolation between depths).
//
// With --cluster the partitions' hierarchies are then merged pairwise level by level (ooc::mergeAll,
// lodbake/ooc/partition_merge.h) and assembled into one hierarchy, compared with the whole build at
// equal triangle counts through threshold cuts: the cut at error threshold t is every cluster whose
// own error is at most t and whose parent's is above it (what the runtime draws where one model unit
// projects to one pixel); the error of a hierarchy at N triangles is the smallest group error whose
// cut has at most N triangles, and that cut's triangle-weighted mean error is printed beside it. N
// runs over the whole build's depth-cut triangle counts. --levels-per-job N sets the levels each
// partition job and each merge below the top builds (default ooc::kLevelsPerJob; 0: as far as the
// locked border allows); --leaf-order-pairs merges adjacent pairs in leaf order instead of the k-d
// tree's siblings; --pairwise merges two files per job (MergeOptions::group_by_memory off) instead
// of as many k-d siblings as one job's bound fits; --seeds K also builds the whole input in memory
// with ClusterLodOptions::seed 2..K, prints each one's ratios to the default build's the same way (how
// far in-memory builds that differ only in METIS's and the sampler's seed are apart), and the merged
// error at each N over the largest and the smallest of the K in-memory builds' errors there.
//
// Bars: the partitioner's peak resident memory stays under the limit it was given (issue: "peak
// resident memory stays under the limit whatever the input size"); with --cluster, so do the
// partition and merge jobs', and the merged hierarchy's error at equal triangle counts is within 10 %
// of the in-memory build's (issue: "levels whose measured errors are within 10 % of the in-memory
// path's at equal triangle counts").
//
// usage: ooc_bench [--triangles N] [--memory-limit MIB] [--dir DIR] [--threads N] [--no-anchor]
//                  [--scan FILE] [--cluster] [--levels-per-job N] [--leaf-order-pairs] [--pairwise] [--seeds K]
//                  [--check]
//   defaults: 10,000,000 triangles, 1024 MiB, DIR = the build's ooc_bench_out folder. --scan reads
//   an existing file (made by lodbake_scansim --surface) instead of generating one, and keeps it.
//
// --driver runs the whole out-of-core bake through ooc::buildOutOfCore on a scan file in a child
// process and reports its peak RSS and throughput (runDriverMode below).
//
// --level-error measures one level's error against the input out of core (ooc::measureLevelError)
// and in memory, each in a child process: time and peak RSS of both (runLevelErrorMode below).
//
// --pack-errors compares the levels of three packs of one scan by their recorded (measured) errors:
// the in-memory `lodbake bake --clusters` pack (a child process of the CLI), the out-of-core pack
// (ooc::writeOutOfCorePack with partitions of --leaf-triangles, default 65,536, under --memory-limit,
// default 4096 MiB, so that every level is kept and measured), and the same writer with one
// partition of 4 Mi triangles holding the whole input (an in-memory cluster hierarchy).
// Each out-of-core level's Hausdorff and mean errors are divided by the in-memory chain's at the
// same triangle count (log-log interpolation between its levels; a count outside its levels is
// marked and not judged) (runPackErrorsMode below).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench_bar.h"
#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/io/mesh_stream.h"
#include "lodbake/ooc/driver.h"
#include "lodbake/ooc/level_error.h"
#include "lodbake/ooc/ooc_pack.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/ooc/tree_pages.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/config/bake_config.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodbake/simplify/simplify.h"
#include "scansim.h"

namespace {

using Clock = std::chrono::steady_clock;

// Peak resident memory since the last resetPeak(), in MiB.
double peakMiB() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
    return NAN;
}

void resetPeak() {
    std::ofstream clear("/proc/self/clear_refs");
    clear << "5";
}

// CPU seconds of the whole process (every thread), user and system: on a shared machine the wall
// time also counts the time the process waited for a core.
double processCpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Stage {
    double seconds = 0, cpu_seconds = 0, peak_mib = 0;
};

template <class F> Stage measure(F&& f) {
    resetPeak();
    const auto t0 = Clock::now();
    const double c0 = processCpuSeconds();
    f();
    Stage s;
    s.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    s.cpu_seconds = processCpuSeconds() - c0;
    s.peak_mib = peakMiB();
    return s;
}

void fail(const lodbake::Status& s) {
    std::fprintf(stderr, "ooc_bench: %s\n", s.message().c_str());
    std::exit(1);
}

void printStage(const char* name, const Stage& s, uint64_t triangles, const Stage* anchor) {
    std::printf("%-28s %8.2f s wall %8.2f s cpu %9.3f Mtri/s (wall) %9.3f Mtri/s (cpu) %9.1f MiB peak", name, s.seconds,
                s.cpu_seconds, double(triangles) / s.seconds / 1e6, double(triangles) / s.cpu_seconds / 1e6, s.peak_mib);
    if (anchor && anchor->seconds > 0)
        std::printf("   vs readMesh: wall x%.3f, cpu x%.3f, peak x%.3f", s.seconds / anchor->seconds,
                    s.cpu_seconds / anchor->cpu_seconds, s.peak_mib / anchor->peak_mib);
    std::printf("\n");
}

// A depth cut's size and errors (see the header).
struct DepthCut {
    uint32_t depth = 0;
    uint64_t triangles = 0;
    double max_error = 0, mean_error = 0;
};

// Depth-d cuts, d = 0 .. deepest, of hierarchies side by side (one per partition, or the whole).
std::vector<DepthCut> depthCuts(const std::vector<const lodbake::ClusterLodHierarchy*>& parts) {
    uint32_t deepest = 0;
    for (const auto* h : parts)
        for (const auto& g : h->groups) deepest = std::max(deepest, g.depth);
    std::vector<DepthCut> cuts(deepest + 1);
    for (uint32_t d = 0; d <= deepest; ++d) {
        DepthCut& c = cuts[d];
        c.depth = d;
        double weighted = 0;
        for (const auto* h : parts)
            for (const auto& cl : h->clusters) {
                const uint32_t own = cl.self_group == lodrt::kClusterNone ? 0 : h->groups[cl.self_group].depth;
                const bool above = cl.parent_group != lodrt::kClusterNone && h->groups[cl.parent_group].depth <= d;
                if (own > d || above) continue;
                const double e = cl.self_group == lodrt::kClusterNone ? 0.0 : double(h->groups[cl.self_group].error);
                c.triangles += cl.triangle_count;
                c.max_error = std::max(c.max_error, e);
                weighted += e * cl.triangle_count;
            }
        c.mean_error = c.triangles ? weighted / double(c.triangles) : 0;
    }
    return cuts;
}

// The whole build's error at `triangles`, interpolated in log-log between its depth cuts (NAN outside).
double errorAt(const std::vector<DepthCut>& whole, uint64_t triangles, bool mean) {
    for (size_t i = 1; i < whole.size(); ++i) {
        const DepthCut &fine = whole[i - 1], &coarse = whole[i];
        if (triangles > fine.triangles || triangles < coarse.triangles) continue;
        const double ef = mean ? fine.mean_error : fine.max_error, ec = mean ? coarse.mean_error : coarse.max_error;
        if (ef <= 0 || fine.triangles == coarse.triangles) return ec;
        const double f = std::log(double(fine.triangles) / double(triangles)) /
                         std::log(double(fine.triangles) / double(coarse.triangles));
        return std::exp(std::log(ef) + f * (std::log(ec) - std::log(ef)));
    }
    return NAN;
}

void printComparison(const char* label, const std::vector<DepthCut>& part, const std::vector<DepthCut>& whole) {
    std::printf("depth cuts (whole buildClusterLod):\n");
    for (const DepthCut& c : whole)
        std::printf("  depth %2u %10llu triangles  max error %.6g  mean error %.6g\n", c.depth,
                    (unsigned long long)c.triangles, c.max_error, c.mean_error);
    std::printf("depth cuts (%s), error / whole's at equal triangles:\n", label);
    for (const DepthCut& c : part) {
        const double wm = errorAt(whole, c.triangles, false), wa = errorAt(whole, c.triangles, true);
        std::printf("  depth %2u %10llu triangles  max error %.6g (x%.3f)  mean error %.6g (x%.3f)\n", c.depth,
                    (unsigned long long)c.triangles, c.max_error, c.max_error / wm, c.mean_error, c.mean_error / wa);
    }
}

// A threshold cut's size and errors (see the header).
struct ThresholdCut {
    double threshold = 0;
    uint64_t triangles = 0;
    double mean_error = 0;
};

// The error of `h` at `triangles` (the header's definition), by a sweep over the group errors: a
// cluster is in the cut for thresholds in [own error, parent error).
ThresholdCut errorAtTriangles(const lodbake::ClusterLodHierarchy& h, uint64_t triangles) {
    const auto own = [&](const lodrt::ClusterLodCluster& c) {
        return c.self_group == lodrt::kClusterNone ? 0.0 : double(h.groups[c.self_group].error);
    };
    std::vector<std::pair<double, int64_t>> events;
    for (const auto& c : h.clusters) {
        events.push_back({own(c), int64_t(c.triangle_count)});
        if (c.parent_group != lodrt::kClusterNone)
            events.push_back({double(h.groups[c.parent_group].error), -int64_t(c.triangle_count)});
    }
    std::sort(events.begin(), events.end());
    ThresholdCut cut;
    cut.threshold = NAN;
    int64_t count = 0;
    for (size_t i = 0; i < events.size();) {
        size_t j = i;
        while (j < events.size() && events[j].first == events[i].first) count += events[j++].second;
        if (uint64_t(count) <= triangles) {
            cut.threshold = events[i].first;
            break;
        }
        i = j;
    }
    if (std::isnan(cut.threshold)) return cut;
    double weighted = 0;
    for (const auto& c : h.clusters) {
        const double e = own(c);
        const double parent = c.parent_group == lodrt::kClusterNone ? INFINITY : double(h.groups[c.parent_group].error);
        if (e > cut.threshold || parent <= cut.threshold) continue;
        cut.triangles += c.triangle_count;
        weighted += e * c.triangle_count;
    }
    cut.mean_error = cut.triangles ? weighted / double(cut.triangles) : 0;
    return cut;
}

// Prints the merged hierarchy's errors against the whole build's at the whole build's depth-cut
// triangle counts, and returns the largest ratio of the errors (NAN when none was comparable).
double printThresholdComparison(const lodbake::ClusterLodHierarchy& merged, const lodbake::ClusterLodHierarchy& whole) {
    std::printf("threshold cuts at equal triangles (N = whole build's depth-cut triangles): error, mean error\n");
    double worst = NAN;
    for (const DepthCut& d : depthCuts({&whole})) {
        if (d.depth == 0) continue;
        const ThresholdCut w = errorAtTriangles(whole, d.triangles), m = errorAtTriangles(merged, d.triangles);
        const double ratio = m.threshold / w.threshold;
        if (std::isfinite(ratio) && !(ratio <= worst)) worst = ratio;
        std::printf("  N %10llu  whole %.6g (%llu tri, mean %.6g)  merged %.6g (%llu tri, mean %.6g)  ratio x%.3f mean x%.3f\n",
                    (unsigned long long)d.triangles, w.threshold, (unsigned long long)w.triangles, w.mean_error,
                    m.threshold, (unsigned long long)m.triangles, m.mean_error, ratio, m.mean_error / w.mean_error);
    }
    return worst;
}

// In-memory builds of `scan` with seeds 2..seeds, each compared with the default build (seed 1), and
// the merged error at each N over the largest and smallest of the seeds' errors there.
void printSeedSpread(const std::string& scan, uint64_t seeds, const lodbake::ClusterLodHierarchy& merged,
                     const lodbake::ClusterLodHierarchy& whole) {
    lodbake::Diagnostics d;
    lodbake::Result<lodbake::LoadedMesh> m = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
    if (!m.ok()) fail(m.status());
    std::vector<lodbake::ClusterLodHierarchy> builds;
    for (uint64_t seed = 2; seed <= seeds; ++seed) {
        lodbake::ClusterLodOptions o;
        o.seed = seed;
        auto other = lodbake::buildClusterLod(m->mesh, o, d);
        if (!other.ok()) fail(other.status());
        std::printf("in-memory build with seed %llu against the default seed:\n", (unsigned long long)seed);
        const double largest = printThresholdComparison(*other, whole);
        std::printf("in-memory, seed %llu / seed 1: largest ratio %.3f\n", (unsigned long long)seed, largest);
        builds.push_back(std::move(*other));
    }
    std::printf("merged over the in-memory builds' (seeds 1..%llu) largest and smallest error at each N:\n",
                (unsigned long long)seeds);
    double beyond = NAN;
    for (const DepthCut& c : depthCuts({&whole})) {
        if (c.depth == 0) continue;
        double hi = errorAtTriangles(whole, c.triangles).threshold, lo = hi;
        for (const auto& b : builds) {
            const double e = errorAtTriangles(b, c.triangles).threshold;
            if (!std::isfinite(e) || e <= 0) continue;
            hi = std::max(hi, e);
            lo = std::min(lo, e);
        }
        const double e = errorAtTriangles(merged, c.triangles).threshold;
        if (std::isfinite(e / hi) && !(e / hi <= beyond)) beyond = e / hi;
        std::printf("  N %10llu  merged / largest x%.3f  merged / smallest x%.3f  (largest / smallest x%.3f)\n",
                    (unsigned long long)c.triangles, e / hi, e / lo, hi / lo);
    }
    std::printf("merged / largest in-memory error over seeds 1..%llu: largest %.3f\n", (unsigned long long)seeds, beyond);
}

// --pages: partition + build + merge a scan (as --cluster does), then write the merge tree's
// LODBAKE_cluster_lod pages without its geometry (ooc::writeTreeClusterPages: the table from the
// files' records, the pages read back by offset, spilled) against the in-memory path
// (ooc::assembleHierarchy + writeClusterLodPack), each stage's peak resident memory above the
// resident memory at its start (after malloc_trim; VmHWM reset), and the same-bytes check (table
// blob and pages).
//   ooc_bench --pages [--scan FILE | --triangles N] [--memory-limit MIB] [--dir DIR] [--threads N] [--check]
double residentMiB() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind("VmRSS:", 0) == 0) return std::strtod(line.c_str() + 6, nullptr) / 1024.0;
    return NAN;
}

int runPagesMode(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    uint64_t triangles = 2000000, limit_mib = 1024;
    int threads = 0;
    std::string dir = LODBAKE_BENCH_OUT_DIR, given_scan;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--triangles" && i + 1 < argc) triangles = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--memory-limit" && i + 1 < argc) limit_mib = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dir" && i + 1 < argc) dir = argv[++i];
        else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
        else if (a == "--scan" && i + 1 < argc) given_scan = argv[++i];
        else {
            std::fprintf(stderr, "usage: ooc_bench --pages [--scan FILE | --triangles N] [--memory-limit MIB] "
                                 "[--dir DIR] [--threads N] [--check]\n");
            return 2;
        }
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    const std::string scan = given_scan.empty() ? dir + "/ooc_bench_pages_scan.ply" : given_scan;
    const std::string work = dir + "/ooc_bench_pages_work", lods = dir + "/ooc_bench_pages_lods";
    if (given_scan.empty()) {
        lodbake::scansim::SurfaceOptions surface;
        surface.triangles = triangles;
        if (auto r = lodbake::scansim::writeSurfacePly(surface, scan); !r.ok()) fail(r.status());
    }
    std::unique_ptr<lodbake::ScopedThreadLimit> limit;
    if (threads > 0) limit = std::make_unique<lodbake::ScopedThreadLimit>(size_t(threads));
    lodbake::ooc::PartitionSet set;
    lodbake::ooc::MergeTree tree;
    const Stage build = measure([&] {
        lodbake::Diagnostics d;
        lodbake::ooc::PartitionOptions po;
        po.work_dir = work;
        po.memory_limit_bytes = limit_mib << 20;
        po.threads = threads;
        po.build_bytes_per_triangle = lodbake::ooc::kPartitionBuildBytesPerTriangle;
        auto r = lodbake::ooc::partitionMesh(scan, po, d);
        if (!r.ok()) fail(r.status());
        set = std::move(*r);
        lodbake::ooc::PartitionBuildOptions bo;
        bo.work_dir = lods;
        bo.memory_limit_bytes = limit_mib << 20;
        if (set.partitions.size() > 1) bo.cluster.max_levels = lodbake::ooc::kLevelsPerJob;
        std::vector<std::string> files;
        for (const lodbake::ooc::PartitionFile& f : set.partitions) {
            auto b = lodbake::ooc::buildPartition(f.path, bo, d);
            if (!b.ok()) fail(b.status());
            files.push_back(b->path);
        }
        lodbake::ooc::MergeOptions mo;
        mo.work_dir = lods;
        mo.memory_limit_bytes = limit_mib << 20;
        auto m = lodbake::ooc::mergeAll(files, mo, d);
        if (!m.ok()) fail(m.status());
        tree = std::move(*m);
    });
    uint64_t t = 0;
    for (const lodbake::ooc::PartitionFile& f : set.partitions) t += f.triangle_count;
    uint64_t file_bytes = 0;
    for (const std::string& f : tree.partitions) file_bytes += std::filesystem::file_size(f, ec);
    for (const lodbake::ooc::MergeFile& m : tree.merges) file_bytes += std::filesystem::file_size(m.path, ec);
    std::printf("scan: %llu triangles (%s); %zu partitions, %zu merges, hierarchy files %.1f MiB\n",
                (unsigned long long)t, scan.c_str(), tree.partitions.size(), tree.merges.size(),
                double(file_bytes) / 1048576.0);
    printStage("partition + build + merge", build, t, nullptr);

    const std::string out = dir + "/ooc_bench_pages.glb";
    lodbake::ooc::TreePagesResult streamed;
    malloc_trim(0); // the build's freed heap back to the system, so the stages start from what is live
    const double streamed_start = residentMiB();
    const Stage pages = measure([&] {
        lodbake::ooc::TreePagesOptions o;
        o.memory_limit_bytes = limit_mib << 20;
        auto r = lodbake::ooc::writeTreeClusterPages(tree, out, o);
        if (!r.ok()) fail(r.status());
        streamed = std::move(*r);
    });
    std::vector<uint8_t> memory_table, memory_pages;
    uint32_t clusters = 0;
    malloc_trim(0);
    const double memory_start = residentMiB();
    const Stage memory = measure([&] {
        auto h = lodbake::ooc::assembleHierarchy(tree, uint64_t(16) << 30);
        if (!h.ok()) fail(h.status());
        auto p = lodbake::writeClusterLodPack(*h, lodbake::ClusterPackOptions());
        if (!p.ok()) fail(p.status());
        clusters = uint32_t(h->clusters.size());
        memory_table = std::move(p->extension.blobs[0]);
        memory_pages = std::move(p->extension.blobs[1]);
    });
    auto spill = lodbake::readFileBytes(streamed.pack.pages->tempPath());
    if (!spill.ok()) fail(spill.status());
    const bool same = streamed.pack.extension.blobs[0] == memory_table && *spill == memory_pages;
    printStage("streamed tree pages", pages, t, nullptr);
    printStage("assemble + in-memory pack", memory, t, nullptr);
    std::printf("streamed: peak RSS %.1f MiB above its start (%.1f MiB); table bound %.1f MiB, accounted %.1f MiB; "
                "writer bound %.1f MiB, accounted %.1f MiB; %.1f MiB of geometry read back\n",
                pages.peak_mib - streamed_start, streamed_start, double(streamed.table_bound_bytes) / 1048576.0,
                double(streamed.table_accounted_bytes) / 1048576.0,
                double(streamed.pack.memory_bound_bytes) / 1048576.0,
                double(streamed.pack.accounted_peak_bytes) / 1048576.0, double(streamed.bytes_read) / 1048576.0);
    std::printf("in memory: peak RSS %.1f MiB above its start (%.1f MiB)\n", memory.peak_mib - memory_start,
                memory_start);
    std::printf("%u clusters; table %zu bytes, pages %zu bytes: %s\n", clusters, memory_table.size(),
                memory_pages.size(), same ? "same bytes" : "DIFFERENT BYTES");
    streamed = lodbake::ooc::TreePagesResult();
    for (const lodbake::ooc::MergeFile& m : tree.merges) std::filesystem::remove(m.path, ec);
    for (const std::string& f : tree.partitions) std::filesystem::remove(f, ec);
    std::filesystem::remove(lods, ec);
    lodbake::ooc::removePartitionFiles(set);
    std::filesystem::remove(work, ec);
    if (given_scan.empty()) std::filesystem::remove(scan, ec);

    lodbake_bench::Bars bars("ooc_bench --pages");
    bars.absolute("streamed tree pages: same table and pages bytes (1 = yes)", same ? 1.0 : 0.0, 1.0,
                  lodbake_bench::Limit::AtLeast);
    bars.absolute("streamed tree pages peak RSS MiB <= memory limit", pages.peak_mib, double(limit_mib),
                  lodbake_bench::Limit::AtMost, memory.peak_mib);
    return bars.finish(check);
}


// --driver: the whole out-of-core bake through ooc::buildOutOfCore (partitioner, partition jobs and
// merge rounds side by side under one memory gate, streamed pages) on a scan file, in a child
// process so that its peak resident memory (getrusage RUSAGE_CHILDREN ru_maxrss) is the run's alone:
// wall time per stage, throughput in input triangles per second, peak RSS against the limit and the
// accounted peak. --repeat N runs it N times and reports the medians.
//   ooc_bench --driver --scan FILE [--memory-limit MIB] [--dir DIR] [--threads N] [--repeat N] [--check]
struct DriverRun {
    double seconds = 0, stage[4] = {0, 0, 0, 0}, peak_mib = 0, accounted_mib = 0;
    uint64_t triangles = 0, partitions = 0, merges = 0, rounds = 0, clusters = 0, output_bytes = 0;
    uint64_t output_hash = 0; // of the table blob and the pages file, to compare runs
};

// Runs the driver in a forked child, which writes its figures to a pipe.
bool runDriverChild(const std::string& scan, const std::string& dir, uint64_t limit_mib, int threads, DriverRun& run) {
    int fds[2];
    if (pipe(fds) != 0) return false;
    const auto t0 = Clock::now();
    const pid_t pid = fork();
    if (pid < 0) return false;
    if (pid == 0) {
        close(fds[0]);
        std::unique_ptr<lodbake::ScopedThreadLimit> limit;
        if (threads > 0) limit = std::make_unique<lodbake::ScopedThreadLimit>(size_t(threads));
        lodbake::ooc::OutOfCoreOptions o;
        o.work_dir = dir + "/ooc_bench_driver_work";
        o.memory_limit_bytes = limit_mib << 20;
        o.threads = threads;
        lodbake::Diagnostics d;
        const std::string out = dir + "/ooc_bench_driver_pages.bin";
        auto r = lodbake::ooc::buildOutOfCore(scan, out, o, d);
        if (!r.ok()) {
            std::fprintf(stderr, "ooc_bench: %s\n", r.status().message().c_str());
            _exit(1);
        }
        DriverRun c;
        c.stage[0] = r->partition.seconds;
        c.stage[1] = r->build.seconds;
        c.stage[2] = r->merge.seconds;
        c.stage[3] = r->pages.seconds;
        c.accounted_mib = double(r->accounted_peak_bytes) / 1048576.0;
        c.triangles = r->triangle_count;
        c.partitions = r->partition_count;
        c.merges = r->merge_count;
        c.rounds = r->merge_rounds;
        c.clusters = r->cluster_count;
        std::error_code ec;
        c.output_bytes = std::filesystem::file_size(out, ec);
        {
            lodbake::Hasher h;
            h.addBytes(r->table.data(), r->table.size());
            std::ifstream f(out, std::ios::binary);
            std::vector<char> buf(size_t(1) << 20);
            while (f.read(buf.data(), std::streamsize(buf.size())) || f.gcount() > 0)
                h.addBytes(buf.data(), size_t(f.gcount()));
            c.output_hash = h.digest();
        }
        std::filesystem::remove(out, ec);
        const ssize_t w = write(fds[1], &c, sizeof c);
        _exit(w == ssize_t(sizeof c) ? 0 : 1);
    }
    close(fds[1]);
    DriverRun c;
    const ssize_t got = read(fds[0], &c, sizeof c);
    close(fds[0]);
    int status = 0;
    rusage u{};
    if (wait4(pid, &status, 0, &u) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || got != ssize_t(sizeof c))
        return false;
    run = c;
    run.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    run.peak_mib = double(u.ru_maxrss) / 1024.0;
    return true;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? NAN : v[v.size() / 2];
}

int runDriverMode(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    uint64_t limit_mib = 1024;
    int threads = 0, repeat = 1;
    std::string dir = LODBAKE_BENCH_OUT_DIR, scan;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--memory-limit" && i + 1 < argc) limit_mib = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dir" && i + 1 < argc) dir = argv[++i];
        else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
        else if (a == "--repeat" && i + 1 < argc) repeat = std::max(1, std::atoi(argv[++i]));
        else if (a == "--scan" && i + 1 < argc) scan = argv[++i];
        else {
            std::fprintf(stderr, "usage: ooc_bench --driver --scan FILE [--memory-limit MIB] [--dir DIR] [--threads N] "
                                 "[--repeat N] [--check]\n");
            return 2;
        }
    }
    if (scan.empty()) {
        std::fprintf(stderr, "ooc_bench --driver: --scan FILE is required\n");
        return 2;
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    std::vector<DriverRun> runs;
    for (int k = 0; k < repeat; ++k) {
        DriverRun r;
        if (!runDriverChild(scan, dir, limit_mib, threads, r)) {
            std::fprintf(stderr, "ooc_bench --driver: the run failed\n");
            return 1;
        }
        std::printf("run %d: %.1f s wall (partition %.1f, jobs %.1f, merges %.1f, pages %.1f), %.3f Mtri/s, "
                    "peak RSS %.1f MiB, accounted %.1f MiB, hash %s\n",
                    k + 1, r.seconds, r.stage[0], r.stage[1], r.stage[2], r.stage[3], double(r.triangles) / r.seconds / 1e6,
                    r.peak_mib, r.accounted_mib, lodbake::hashToHex(r.output_hash).c_str());
        runs.push_back(r);
    }
    std::vector<double> secs, peaks;
    for (const DriverRun& r : runs) {
        secs.push_back(r.seconds);
        peaks.push_back(r.peak_mib);
    }
    const DriverRun& f = runs.front();
    const double s = median(secs), peak = median(peaks);
    std::printf("%llu triangles, %llu partitions, %llu merges in %llu rounds, %llu clusters, pages %.1f MiB, "
                "table + pages hash %s\n",
                (unsigned long long)f.triangles, (unsigned long long)f.partitions, (unsigned long long)f.merges,
                (unsigned long long)f.rounds, (unsigned long long)f.clusters, double(f.output_bytes) / 1048576.0,
                lodbake::hashToHex(f.output_hash).c_str());
    std::printf("median of %d: %.1f s wall, %.3f Mtri/s, peak RSS %.1f MiB (limit %llu MiB)\n", repeat, s,
                double(f.triangles) / s / 1e6, peak, (unsigned long long)limit_mib);
    lodbake_bench::Bars bars("ooc_bench --driver");
    bars.absolute("out-of-core driver peak RSS MiB <= memory limit", peak, double(limit_mib), lodbake_bench::Limit::AtMost);
    return bars.finish(check);
}

// --level-error: the out-of-core level error (ooc::measureLevelError, lodbake/ooc/level_error.h)
// against the in-memory measurement (measureSurfaceDistance on the input read whole) of the same
// level. A first child process reads the scan, simplifies it to --ratio of its triangles (the level,
// written to DIR/ooc_bench_level.ply) and partitions it (leaves of --leaf-triangles, as the driver
// sizes them); then one child measures out of core from the partition files and one in memory from
// the scan, each reading the level from its file, so that each one's peak RSS (RUSAGE_CHILDREN of
// that child) is its own: wall time of the measurement and the child's peak RSS, the ratios out of
// core / in memory, and both results (they differ by sampling noise only: the in-memory samples are
// stratified over the file's triangle order, the out-of-core ones over the partitions').
//   ooc_bench --level-error --scan FILE [--ratio R] [--leaf-triangles N] [--memory-limit MIB] [--dir DIR]
//             [--threads N] [--samples N] [--check]
struct LevelErrorRun {
    double seconds = 0, peak_mib = 0, accounted_mib = 0, bound_mib = 0;
    double hausdorff = 0, mean = 0, rms = 0, diagonal = 0;
    uint64_t input_triangles = 0, level_triangles = 0, partitions = 0, level_points = 0, level_queries = 0;
};

struct LevelErrorSetup {
    std::string scan, dir, level_path, list_path;
    double ratio = 0.1;
    uint64_t leaf_triangles = lodbake::ooc::kDefaultLeafTriangles, limit_mib = 1024;
    uint32_t samples = 200000;
    int threads = 0;
};

// Runs `body` in a forked child that writes a LevelErrorRun to a pipe; the child's peak RSS is added.
template <class Body> bool runLevelErrorChild(Body&& body, LevelErrorRun& run) {
    int fds[2];
    if (pipe(fds) != 0) return false;
    const pid_t pid = fork();
    if (pid < 0) return false;
    if (pid == 0) {
        close(fds[0]);
        LevelErrorRun c;
        if (!body(c)) _exit(1);
        const ssize_t w = write(fds[1], &c, sizeof c);
        _exit(w == ssize_t(sizeof c) ? 0 : 1);
    }
    close(fds[1]);
    LevelErrorRun c;
    const ssize_t got = read(fds[0], &c, sizeof c);
    close(fds[0]);
    int status = 0;
    rusage u{};
    if (wait4(pid, &status, 0, &u) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0 || got != ssize_t(sizeof c))
        return false;
    run = c;
    run.peak_mib = double(u.ru_maxrss) / 1024.0;
    return true;
}

bool readLevelErrorMesh(const std::string& path, lodbake::Mesh& mesh) {
    lodbake::Diagnostics d;
    auto r = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    if (!r.ok()) {
        std::fprintf(stderr, "ooc_bench: %s\n", r.status().message().c_str());
        return false;
    }
    mesh = std::move(r->mesh);
    return true;
}

// The level (simplified from the scan, written as a PLY) and the partitions (their paths, one a line).
bool prepareLevelError(const LevelErrorSetup& st, LevelErrorRun& c) {
    std::unique_ptr<lodbake::ScopedThreadLimit> limit;
    if (st.threads > 0) limit = std::make_unique<lodbake::ScopedThreadLimit>(size_t(st.threads));
    lodbake::Mesh input;
    if (!readLevelErrorMesh(st.scan, input)) return false;
    lodbake::SimplifyOptions so;
    so.target_ratio = float(st.ratio);
    lodbake::Diagnostics d;
    auto level = lodbake::simplify(input, so, d);
    if (!level.ok() || !lodbake::writeMesh(level->mesh, st.level_path, lodbake::WriteOptions(), d).ok()) return false;
    c.input_triangles = input.faceCount();
    c.level_triangles = level->mesh.faceCount();
    lodbake::ooc::PartitionOptions po;
    po.work_dir = st.dir + "/ooc_bench_level_error_work";
    po.memory_limit_bytes = st.limit_mib << 20;
    po.threads = st.threads;
    po.build_bytes_per_triangle = lodbake::ooc::kPartitionBuildBytesPerTriangle;
    po.leaf_triangles = st.leaf_triangles;
    auto set = lodbake::ooc::partitionMesh(st.scan, po, d);
    if (!set.ok()) {
        std::fprintf(stderr, "ooc_bench: %s\n", set.status().message().c_str());
        return false;
    }
    std::ofstream list(st.list_path);
    for (const auto& f : set->partitions) list << f.path << "\n";
    c.partitions = set->partitions.size();
    return bool(list);
}

void fillLevelErrorRun(const lodbake::DistanceResult& r, LevelErrorRun& c) {
    c.hausdorff = r.hausdorffRel();
    c.mean = r.meanRel();
    c.rms = r.rmsRel();
    c.diagonal = r.diagonal;
}

bool oocLevelError(const LevelErrorSetup& st, LevelErrorRun& c) {
    std::unique_ptr<lodbake::ScopedThreadLimit> limit;
    if (st.threads > 0) limit = std::make_unique<lodbake::ScopedThreadLimit>(size_t(st.threads));
    lodbake::Mesh level;
    if (!readLevelErrorMesh(st.level_path, level)) return false;
    std::vector<std::string> files;
    std::ifstream list(st.list_path);
    for (std::string line; std::getline(list, line);) files.push_back(line);
    lodbake::ooc::LevelErrorOptions o;
    o.distance.sample_count = st.samples;
    o.memory_limit_bytes = st.limit_mib << 20;
    o.threads = st.threads;
    const auto t0 = Clock::now();
    auto r = lodbake::ooc::measureLevelError(files, level, o);
    c.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (!r.ok()) {
        std::fprintf(stderr, "ooc_bench: %s\n", r.status().message().c_str());
        return false;
    }
    fillLevelErrorRun(r->distance, c);
    c.accounted_mib = double(r->accounted_peak_bytes) / 1048576.0;
    c.bound_mib = double(r->memory_bound_bytes) / 1048576.0;
    c.input_triangles = r->input_triangles;
    c.level_triangles = level.faceCount();
    c.partitions = r->partition_count;
    c.level_points = r->level_points;
    c.level_queries = r->level_queries;
    return true;
}

bool inMemoryLevelError(const LevelErrorSetup& st, LevelErrorRun& c) {
    std::unique_ptr<lodbake::ScopedThreadLimit> limit;
    if (st.threads > 0) limit = std::make_unique<lodbake::ScopedThreadLimit>(size_t(st.threads));
    lodbake::Mesh input, level;
    if (!readLevelErrorMesh(st.scan, input) || !readLevelErrorMesh(st.level_path, level)) return false;
    lodbake::DistanceOptions o;
    o.sample_count = st.samples;
    const auto t0 = Clock::now();
    auto r = lodbake::measureSurfaceDistance(input, level, o);
    c.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (!r.ok()) return false;
    fillLevelErrorRun(*r, c);
    c.input_triangles = input.faceCount();
    c.level_triangles = level.faceCount();
    return true;
}

int runLevelErrorMode(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    LevelErrorSetup st;
    st.dir = LODBAKE_BENCH_OUT_DIR;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--scan" && i + 1 < argc) st.scan = argv[++i];
        else if (a == "--ratio" && i + 1 < argc) st.ratio = std::strtod(argv[++i], nullptr);
        else if (a == "--leaf-triangles" && i + 1 < argc) st.leaf_triangles = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--memory-limit" && i + 1 < argc) st.limit_mib = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dir" && i + 1 < argc) st.dir = argv[++i];
        else if (a == "--threads" && i + 1 < argc) st.threads = std::atoi(argv[++i]);
        else if (a == "--samples" && i + 1 < argc) st.samples = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else {
            std::fprintf(stderr, "usage: ooc_bench --level-error --scan FILE [--ratio R] [--leaf-triangles N] "
                                 "[--memory-limit MIB] [--dir DIR] [--threads N] [--samples N]\n");
            return 2;
        }
    }
    if (st.scan.empty()) {
        std::fprintf(stderr, "ooc_bench --level-error: --scan FILE is required\n");
        return 2;
    }
    std::error_code ec;
    std::filesystem::create_directories(st.dir, ec);
    st.level_path = st.dir + "/ooc_bench_level.ply";
    st.list_path = st.dir + "/ooc_bench_level_error_parts.txt";
    std::filesystem::remove_all(st.dir + "/ooc_bench_level_error_work", ec);
    LevelErrorRun prep, ooc, mem;
    if (!runLevelErrorChild([&](LevelErrorRun& c) { return prepareLevelError(st, c); }, prep) ||
        !runLevelErrorChild([&](LevelErrorRun& c) { return oocLevelError(st, c); }, ooc) ||
        !runLevelErrorChild([&](LevelErrorRun& c) { return inMemoryLevelError(st, c); }, mem)) {
        std::fprintf(stderr, "ooc_bench --level-error: a run failed\n");
        return 1;
    }
    std::filesystem::remove_all(st.dir + "/ooc_bench_level_error_work", ec);
    std::printf("%llu input triangles in %llu partitions, level of %llu triangles (%s), %u samples per side\n",
                (unsigned long long)ooc.input_triangles, (unsigned long long)ooc.partitions,
                (unsigned long long)ooc.level_triangles, st.level_path.c_str(), st.samples);
    std::printf("out of core: %8.2f s, peak RSS %8.1f MiB (accounted %.1f, bound %.1f), %llu level points, "
                "%llu partition queries\n",
                ooc.seconds, ooc.peak_mib, ooc.accounted_mib, ooc.bound_mib, (unsigned long long)ooc.level_points,
                (unsigned long long)ooc.level_queries);
    std::printf("in memory:   %8.2f s, peak RSS %8.1f MiB\n", mem.seconds, mem.peak_mib);
    std::printf("ratio out of core / in memory: time x%.3f, peak RSS x%.3f\n", ooc.seconds / mem.seconds,
                ooc.peak_mib / mem.peak_mib);
    for (const LevelErrorRun* r : {&ooc, &mem})
        std::printf("%-12s hausdorff %.4e  mean %.4e  rms %.4e (of the diagonal %.6g)\n",
                    r == &ooc ? "out of core" : "in memory", r->hausdorff, r->mean, r->rms, r->diagonal);
    lodbake_bench::Bars bars("ooc_bench --level-error");
    bars.absolute("out-of-core level error peak RSS MiB <= memory limit", ooc.peak_mib, double(st.limit_mib),
                  lodbake_bench::Limit::AtMost);
    return bars.finish(check);
}

// ---- --pack-errors ------------------------------------------------------------------------------

struct PackLevelError {
    uint64_t triangles = 0;
    double hausdorff = 0, mean = 0;
};

// The chain of a pack as lodrt reads its LODBAKE_lod_metrics.
bool packChain(const std::string& path, std::vector<PackLevelError>& chain) {
    auto glb = lodbake::readFileBytes(path);
    if (!glb.ok()) return false;
    lodrt::Pack pack;
    lodrt::ModelSet models;
    char message[256] = "";
    if (lodrt::loadPack(glb->data(), glb->size(), nullptr, &pack, message, sizeof message) != lodrt::Result::Ok ||
        lodrt::buildModels(pack, nullptr, &models, message, sizeof message) != lodrt::Result::Ok ||
        models.modelCount() != 1) {
        std::fprintf(stderr, "%s: %s\n", path.c_str(), message);
        return false;
    }
    for (uint32_t l = 0; l < models.model(0).level_count; ++l) {
        const lodrt::LevelInfo& level = models.modelLevel(0, l);
        chain.push_back({level.triangle_count, level.hausdorff_error, level.mean_error});
    }
    return true;
}

// A chain's error at `triangles`: log-log interpolation between its measured levels (level 0, the
// input, has error 0 and is left out); its end level's within 2 % beyond either end; NaN further out.
double chainErrorAt(const std::vector<PackLevelError>& chain, uint64_t triangles, bool mean) {
    if (chain.size() < 2) return NAN;
    const PackLevelError &finest = chain[1], &coarsest = chain.back();
    if (triangles > finest.triangles && double(triangles) <= 1.02 * double(finest.triangles))
        return mean ? finest.mean : finest.hausdorff;
    if (triangles < coarsest.triangles && 1.02 * double(triangles) >= double(coarsest.triangles))
        return mean ? coarsest.mean : coarsest.hausdorff;
    for (size_t i = 1; i + 1 < chain.size(); ++i) {
        const PackLevelError &a = chain[i], &b = chain[i + 1]; // a finer than b
        if (triangles > a.triangles || triangles < b.triangles) continue;
        const double ea = mean ? a.mean : a.hausdorff, eb = mean ? b.mean : b.hausdorff;
        if (a.triangles == b.triangles || ea <= 0 || eb <= 0) return ea;
        const double t = (std::log(double(a.triangles)) - std::log(double(triangles))) /
                         (std::log(double(a.triangles)) - std::log(double(b.triangles)));
        return std::exp(std::log(ea) + t * (std::log(eb) - std::log(ea)));
    }
    return NAN;
}

bool oocPackChain(const std::string& scan, const std::string& out, uint64_t leaf, uint64_t limit_mib, int threads,
                  std::vector<PackLevelError>& chain, std::vector<lodbake::ooc::LevelErrorSource>& sources,
                  double& seconds) {
    const lodbake::BakeSettings settings;
    lodbake::ooc::OocPackOptions o;
    o.driver.work_dir = out + ".work";
    o.driver.memory_limit_bytes = limit_mib << 20;
    o.driver.threads = threads;
    o.driver.leaf_triangles = leaf;
    o.driver.merge_group_bytes = lodbake::ooc::kPartitionBuildBytesPerTriangle * leaf;
    o.lod_ratios = settings.lod_ratios;
    o.distance.sample_count = settings.error_samples;
    o.name = "mesh";
    lodbake::Diagnostics d;
    const auto t0 = std::chrono::steady_clock::now();
    auto r = lodbake::ooc::writeOutOfCorePack(scan, out, o, d);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const lodbake::Diagnostic& item : d.items()) std::printf("  note: %s\n", item.message.c_str());
    if (!r.ok()) {
        std::fprintf(stderr, "%s\n", r.status().message().c_str());
        return false;
    }
    size_t simplified = 0;
    for (const lodbake::ooc::OocPackLevel& l : r->levels) simplified += l.simplified;
    std::printf("  %s: %llu partitions, %llu merges, %llu of %zu candidate levels kept, %llu measured, %zu "
                "simplified from the finest kept level (the others cuts)\n",
                out.c_str(), (unsigned long long)r->driver.partition_count, (unsigned long long)r->driver.merge_count,
                (unsigned long long)r->metrics.levels.size(), r->levels.size(), (unsigned long long)r->measured_levels,
                simplified);
    for (const lodbake::ooc::OocPackLevel& l : r->levels)
        if (l.kept) sources.push_back(l.error_source);
    return packChain(out, chain);
}

const char* sourceName(lodbake::ooc::LevelErrorSource s) {
    switch (s) {
    case lodbake::ooc::LevelErrorSource::Input: return "input";
    case lodbake::ooc::LevelErrorSource::Measured: return "measured";
    case lodbake::ooc::LevelErrorSource::Bound: return "bound";
    case lodbake::ooc::LevelErrorSource::Caller: return "caller";
    }
    return "?";
}

// Prints one out-of-core chain against the in-memory one; judges each measured level's ratios.
void printPackComparison(const char* label, const std::vector<PackLevelError>& ooc,
                         const std::vector<lodbake::ooc::LevelErrorSource>& sources,
                         const std::vector<PackLevelError>& mem, lodbake_bench::Bars* bars) {
    std::printf("%s at equal triangle counts:\n", label);
    std::printf("  level  triangles  source    hausdorff   in-memory   ratio    mean        in-memory   ratio\n");
    for (size_t l = 0; l < ooc.size(); ++l) {
        const PackLevelError& e = ooc[l];
        const double mh = chainErrorAt(mem, e.triangles, false), mm = chainErrorAt(mem, e.triangles, true);
        std::printf("  %5zu %10llu  %-8s  %.4e  %.4e  %6.3f   %.4e  %.4e  %6.3f%s\n", l,
                    (unsigned long long)e.triangles, l < sources.size() ? sourceName(sources[l]) : "?", e.hausdorff,
                    mh, e.hausdorff / mh, e.mean, mm, e.mean / mm, std::isnan(mh) ? "  (outside the chain)" : "");
        if (bars && !std::isnan(mh) && l < sources.size() && sources[l] == lodbake::ooc::LevelErrorSource::Measured) {
            const std::string name = "out of core level " + std::to_string(l);
            bars->ratio(name + " hausdorff / in-memory <= 1.10", e.hausdorff, mh, 1.10, lodbake_bench::Limit::AtMost);
            bars->ratio(name + " mean / in-memory <= 1.10", e.mean, mm, 1.10, lodbake_bench::Limit::AtMost);
        }
    }
}

int runPackErrorsMode(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    std::string scan, dir = LODBAKE_BENCH_OUT_DIR;
    uint64_t leaf = 65536, limit_mib = 4096;
    int threads = 0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--scan" && i + 1 < argc) scan = argv[++i];
        else if (a == "--leaf-triangles" && i + 1 < argc) leaf = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--memory-limit" && i + 1 < argc) limit_mib = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dir" && i + 1 < argc) dir = argv[++i];
        else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
        else {
            std::fprintf(stderr, "usage: ooc_bench --pack-errors --scan FILE [--leaf-triangles N] [--memory-limit MIB] "
                                 "[--dir DIR] [--threads N] [--check]\n");
            return 2;
        }
    }
    if (scan.empty()) {
        std::fprintf(stderr, "ooc_bench --pack-errors: --scan FILE is required\n");
        return 2;
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    const std::string mem_glb = dir + "/pack_errors_in_memory.glb";
    std::string command = std::string("'") + LODBAKE_BENCH_CLI + "' bake '" + scan + "' --clusters --quiet -o '" +
                          mem_glb + "'";
    if (threads > 0) command += " --threads " + std::to_string(threads);
    const auto t0 = std::chrono::steady_clock::now();
    if (std::system(command.c_str()) != 0) {
        std::fprintf(stderr, "ooc_bench --pack-errors: %s failed\n", command.c_str());
        return 1;
    }
    const double mem_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<PackLevelError> mem, ooc, whole;
    std::vector<lodbake::ooc::LevelErrorSource> ooc_sources, whole_sources;
    double ooc_seconds = 0, whole_seconds = 0;
    if (!packChain(mem_glb, mem)) return 1;
    std::printf("scan %s; in-memory pack %.1f s\n", scan.c_str(), mem_seconds);
    if (!oocPackChain(scan, dir + "/pack_errors_ooc.glb", leaf, limit_mib, threads, ooc, ooc_sources, ooc_seconds))
        return 1;
    if (!oocPackChain(scan, dir + "/pack_errors_whole.glb", uint64_t(1) << 22, limit_mib, threads, whole,
                      whole_sources, whole_seconds))
        return 1;
    std::printf("out-of-core pack (partitions of %llu triangles) %.1f s; one partition %.1f s\n",
                (unsigned long long)leaf, ooc_seconds, whole_seconds);
    std::printf("in-memory --clusters pack chain:\n");
    for (size_t l = 0; l < mem.size(); ++l)
        std::printf("  %5zu %10llu  hausdorff %.4e  mean %.4e\n", l, (unsigned long long)mem[l].triangles,
                    mem[l].hausdorff, mem[l].mean);
    lodbake_bench::Bars bars("ooc_bench --pack-errors");
    printPackComparison("out of core vs the in-memory --clusters pack", ooc, ooc_sources, mem, &bars);
    printPackComparison("one partition (an in-memory hierarchy's cuts) vs the in-memory --clusters pack", whole,
                        whole_sources, mem, nullptr);
    // What the partitions and merges change, the cuts being the same kind on both sides.
    printPackComparison("out of core vs one partition (its in-memory column is the one-partition pack's)", ooc,
                        ooc_sources, whole, nullptr);
    return bars.finish(check);
}
} // namespace

int main(int argc, char** argv) {
    if (argc > 1 && std::string(argv[1]) == "--pages") return runPagesMode(argc - 1, argv + 1);
    if (argc > 1 && std::string(argv[1]) == "--level-error") return runLevelErrorMode(argc - 1, argv + 1);
    if (argc > 1 && std::string(argv[1]) == "--driver") return runDriverMode(argc - 1, argv + 1);
    if (argc > 1 && std::string(argv[1]) == "--pack-errors") return runPackErrorsMode(argc - 1, argv + 1);
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    uint64_t triangles = 10000000, limit_mib = 1024;
    int threads = 0;
    uint32_t levels_per_job = lodbake::ooc::kLevelsPerJob;
    bool anchor = true, cluster = false, leaf_order = false, pairwise = false;
    uint64_t seeds = 1;
    std::string dir = LODBAKE_BENCH_OUT_DIR, given_scan;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--triangles" && i + 1 < argc) triangles = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--memory-limit" && i + 1 < argc) limit_mib = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--dir" && i + 1 < argc) dir = argv[++i];
        else if (a == "--threads" && i + 1 < argc) threads = std::atoi(argv[++i]);
        else if (a == "--no-anchor") anchor = false;
        else if (a == "--cluster") cluster = true;
        else if (a == "--leaf-order-pairs") leaf_order = true;
        else if (a == "--pairwise") pairwise = true;
        else if (a == "--seeds" && i + 1 < argc) seeds = std::strtoull(argv[++i], nullptr, 10);
        else if (a == "--levels-per-job" && i + 1 < argc) levels_per_job = uint32_t(std::strtoul(argv[++i], nullptr, 10));
        else if (a == "--scan" && i + 1 < argc) given_scan = argv[++i];
        else {
            std::fprintf(stderr, "usage: ooc_bench [--triangles N] [--memory-limit MIB] [--dir DIR] [--threads N] "
                                 "[--no-anchor] [--scan FILE] [--cluster] [--levels-per-job N] [--leaf-order-pairs] [--pairwise] [--seeds K] [--check]\n");
            return 2;
        }
    }
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    const std::string scan = given_scan.empty() ? dir + "/ooc_bench_scan.ply" : given_scan;
    const std::string work = dir + "/ooc_bench_work";

    lodbake::scansim::SurfaceOptions surface;
    surface.triangles = triangles;
    lodbake::scansim::SurfaceStats stats;
    if (given_scan.empty()) {
        const Stage gen = measure([&] {
            lodbake::Result<lodbake::scansim::SurfaceStats> r = lodbake::scansim::writeSurfacePly(surface, scan);
            if (!r.ok()) fail(r.status());
            stats = *r;
        });
        printStage("generate (scansim surface)", gen, stats.triangles, nullptr);
    } else {
        lodbake::Diagnostics d;
        auto reader = lodbake::openMeshStream(scan, lodbake::StreamReadOptions(), d);
        if (!reader.ok()) fail(reader.status());
        stats.vertices = (*reader)->info().vertex_count;
        stats.triangles = (*reader)->info().triangle_estimate;
        stats.bytes = std::filesystem::file_size(scan, ec);
    }
    const uint64_t t = stats.triangles;
    std::printf("scan: %llu triangles, %llu vertices, %.1f MB (%s)\n", (unsigned long long)t,
                (unsigned long long)stats.vertices, double(stats.bytes) / 1e6, scan.c_str());

    double checksum = 0;
    const Stage stream = measure([&] {
        lodbake::Diagnostics d;
        auto reader = lodbake::openMeshStream(scan, lodbake::StreamReadOptions(), d);
        if (!reader.ok()) fail(reader.status());
        lodbake::Status s = (*reader)->forEachVertexChunk([&](uint64_t, const lodbake::Vec3f* p, size_t n) {
            for (size_t i = 0; i < n; ++i) checksum += double(p[i].x);
            return lodbake::Status();
        });
        if (s.ok())
            s = (*reader)->forEachTriangleChunk([&](uint64_t, const uint32_t* c, size_t n) {
                checksum += double(c[3 * n - 1]);
                return lodbake::Status();
            });
        if (!s.ok()) fail(s);
    });

    lodbake::ooc::PartitionSet set;
    const Stage part = measure([&] {
        lodbake::Diagnostics d;
        lodbake::ooc::PartitionOptions o;
        o.work_dir = work;
        o.memory_limit_bytes = limit_mib << 20;
        o.threads = threads;
        if (cluster) o.build_bytes_per_triangle = lodbake::ooc::kPartitionBuildBytesPerTriangle;
        lodbake::Result<lodbake::ooc::PartitionSet> r = lodbake::ooc::partitionMesh(scan, o, d);
        if (!r.ok()) fail(r.status());
        set = std::move(r).value();
    });

    // The partition jobs, one after the other, each under the same limit; their outputs are read back
    // afterwards (outside the measured stage) for the error comparison.
    std::vector<std::string> lod_files;
    uint64_t job_bound = 0, job_accounted = 0;
    const std::string lods = dir + "/ooc_bench_lods";
    const Stage jobs = measure([&] {
        if (!cluster) return;
        lodbake::ooc::PartitionBuildOptions o;
        o.work_dir = lods;
        o.memory_limit_bytes = limit_mib << 20;
        if (levels_per_job > 0) o.cluster.max_levels = levels_per_job;
        for (const lodbake::ooc::PartitionFile& f : set.partitions) {
            lodbake::Diagnostics d;
            auto r = lodbake::ooc::buildPartition(f.path, o, d);
            if (!r.ok()) fail(r.status());
            lod_files.push_back(r->path);
            job_bound = std::max(job_bound, r->memory_bound_bytes);
            job_accounted = std::max(job_accounted, r->accounted_peak_bytes);
        }
    });
    lodbake::ooc::MergeTree tree;
    const Stage merges = measure([&] {
        if (!cluster) return;
        lodbake::ooc::MergeOptions o;
        o.work_dir = lods;
        o.memory_limit_bytes = limit_mib << 20;
        o.levels_per_job = levels_per_job;
        if (leaf_order) o.pairing = lodbake::ooc::MergePairing::LeafOrder;
        o.group_by_memory = !pairwise;
        lodbake::Diagnostics d;
        auto r = lodbake::ooc::mergeAll(lod_files, o, d);
        if (!r.ok()) fail(r.status());
        tree = std::move(*r);
    });
    lodbake::ClusterLodHierarchy whole;
    const Stage whole_build = measure([&] {
        if (!cluster) return;
        lodbake::Diagnostics d;
        lodbake::Result<lodbake::LoadedMesh> m = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
        if (!m.ok()) fail(m.status());
        auto h = lodbake::buildClusterLod(m->mesh, lodbake::ClusterLodOptions(), d);
        if (!h.ok()) fail(h.status());
        whole = std::move(*h);
    });

    Stage read;
    if (anchor) {
        read = measure([&] {
            lodbake::Diagnostics d;
            lodbake::Result<lodbake::LoadedMesh> m = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
            if (!m.ok()) fail(m.status());
            checksum += double(m->mesh.faceCount());
        });
    }
    const Stage* a = anchor ? &read : nullptr;
    double worst_ratio = NAN;
    printStage("stream reader (2 passes)", stream, t, a);
    printStage("partition", part, t, a);
    if (anchor) printStage("readMesh (anchor)", read, t, nullptr);
    std::printf("partitions: %zu files (%llu leaves), target %llu triangles, largest %llu; memory bound %.1f MiB, "
                "accounted peak %.1f MiB, limit %llu MiB (checksum %g)\n",
                set.partitions.size(), (unsigned long long)set.leaf_count, (unsigned long long)set.target_triangles,
                (unsigned long long)set.largest_partition, double(set.memory_bound_bytes) / 1048576.0,
                double(set.accounted_peak_bytes) / 1048576.0, (unsigned long long)limit_mib, checksum);

    if (cluster) {
        printStage("partition jobs (sequential)", jobs, t, a);
        printStage("readMesh + buildClusterLod", whole_build, t, a);
        std::printf("partition jobs: largest memory bound %.1f MiB, accounted peak %.1f MiB\n",
                    double(job_bound) / 1048576.0, double(job_accounted) / 1048576.0);
        std::vector<lodbake::ooc::PartitionLod> parts;
        std::vector<const lodbake::ClusterLodHierarchy*> views;
        uint64_t roots = 0;
        for (const std::string& f : lod_files) {
            auto p = lodbake::ooc::readPartitionLodFile(f);
            if (!p.ok()) fail(p.status());
            parts.push_back(std::move(*p));
        }
        for (const auto& p : parts) {
            views.push_back(&p.hierarchy);
            roots += p.hierarchy.roots.size();
        }
        std::printf("partitioned: %zu hierarchies, %llu roots; whole: %zu roots, %u levels\n", parts.size(),
                    (unsigned long long)roots, whole.roots.size(), whole.level_count);
        printComparison("partition jobs side by side", depthCuts(views), depthCuts({&whole}));
        printStage("merge jobs (sequential)", merges, t, a);
        uint64_t top_roots = 0, top_triangles = 0;
        if (!tree.merges.empty()) {
            top_roots = tree.merges.back().root_count;
            top_triangles = tree.merges.back().root_triangles;
        }
        std::printf("merges: %zu jobs over %u levels; largest memory bound %.1f MiB, accounted peak %.1f MiB; top: %llu "
                    "roots, %llu triangles\n",
                    tree.merges.size(), tree.merge_levels, double(tree.largest_memory_bound) / 1048576.0,
                    double(tree.largest_accounted_peak) / 1048576.0, (unsigned long long)top_roots,
                    (unsigned long long)top_triangles);
        for (const lodbake::ooc::MergeFile& m : tree.merges)
            std::printf("  merge: %u + seeds (%u triangles), %u shared edges -> %u groups, %u levels, %u roots (%u "
                        "triangles), bound %.2f MiB\n",
                        m.seed_count, m.seed_triangles, m.shared_edges, m.group_count, m.level_count, m.root_count,
                        m.root_triangles, double(m.memory_bound_bytes) / 1048576.0);
        parts.clear();
        auto assembled = lodbake::ooc::assembleHierarchy(tree, uint64_t(8) << 30);
        if (!assembled.ok()) fail(assembled.status());
        std::printf("assembled: %zu clusters, %zu groups, %zu roots, deepest group %u\n", assembled->clusters.size(),
                    assembled->groups.size(), assembled->roots.size(), assembled->level_count);
        printComparison("merged and assembled", depthCuts({&*assembled}), depthCuts({&whole}));
        worst_ratio = printThresholdComparison(*assembled, whole);
        if (seeds > 1) printSeedSpread(scan, seeds, *assembled, whole);
        for (const lodbake::ooc::MergeFile& m : tree.merges) std::filesystem::remove(m.path, ec);
        for (const std::string& f : lod_files) std::filesystem::remove(f, ec);
        std::filesystem::remove(lods, ec);
    }

    lodbake_bench::Bars bars("ooc_bench");
    bars.absolute("partition peak RSS MiB <= memory limit", part.peak_mib, double(limit_mib),
                  lodbake_bench::Limit::AtMost, anchor ? read.peak_mib : NAN);
    if (cluster)
        bars.absolute("partition jobs peak RSS MiB <= memory limit", jobs.peak_mib, double(limit_mib),
                      lodbake_bench::Limit::AtMost, whole_build.peak_mib);
    if (cluster) {
        bars.absolute("merge jobs peak RSS MiB <= memory limit", merges.peak_mib, double(limit_mib),
                      lodbake_bench::Limit::AtMost, whole_build.peak_mib);
        bars.absolute("merged / in-memory error at equal triangles <= 1.10 (largest)", worst_ratio, 1.10,
                      lodbake_bench::Limit::AtMost);
    }
    lodbake::ooc::removePartitionFiles(set);
    std::filesystem::remove(work, ec);
    if (given_scan.empty()) std::filesystem::remove(scan, ec);
    return bars.finish(check);
}
