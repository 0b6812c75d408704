// The in-process out-of-core driver (lodbake/ooc/driver.h).
#include "lodbake/ooc/driver.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <system_error>

#include <unistd.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/memory_gate.h"
#include "lodbake/ooc/jobs.h"
#include "lodbake/ooc/partition_build.h"
#include "ooc/merge_rounds.h"

namespace lodbake::ooc {

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// The files of the work folder before the run: a job's output already there under the same name
// holds the same bytes (names are content hashes) and is not the run's to remove.
struct RunFiles {
    std::string work_dir;
    bool made_dir = false;
    std::vector<std::string> before; // sorted
    std::vector<std::string> made;   // every job output the run saw, maybe pre-existing

    void snapshot(const std::string& dir) {
        work_dir = dir;
        std::error_code ec;
        made_dir = !std::filesystem::is_directory(dir, ec);
        if (!made_dir)
            for (const auto& e : std::filesystem::directory_iterator(dir, ec))
                before.push_back(joinPath(dir, e.path().filename().string()));
        std::sort(before.begin(), before.end());
    }
    // Removes what the run created (and the work folder when the run created it and it is empty).
    void removeCreated() {
        for (const std::string& p : made)
            if (!std::binary_search(before.begin(), before.end(), p)) ::unlink(p.c_str());
        made.clear();
        std::error_code ec;
        if (made_dir) std::filesystem::remove(work_dir, ec); // only when empty
    }
};

// A partition job's bound from the partition's header counts (partition_build.h's formula).
uint64_t buildBound(const PartitionFile& f) {
    return 16 * uint64_t(f.vertex_count) + (12 + kClusterBuildBytesPerTriangle) * uint64_t(f.triangle_count) +
           (uint64_t(1) << 20);
}

Status cancelled(const std::string& input) { return ioError(input + ": out-of-core bake cancelled"); }

bool isCancelled(const OutOfCoreOptions& o) { return o.cancel && o.cancel->load(); }

// The partition jobs (runPartitionJob) side by side, each reserving its bound at the gate; outputs in
// leaf order.
Result<std::vector<PartitionJobOutput>> buildPartitions(const std::string& input, const PartitionSet& set,
                                                        const OutOfCoreOptions& o, MemoryGate& gate, RunFiles& files,
                                                        Diagnostics& diagnostics) {
    const ClusterLodOptions cluster = partitionJobCluster(o.cluster, set.partitions.size());
    const size_t n = set.partitions.size();
    std::vector<PartitionJobOutput> out(n);
    std::vector<Status> status(n);
    std::vector<Diagnostics> notes(n);
    const int threads = o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(std::max(1, threads));
    arena.execute([&] {
        tbb::parallel_for(size_t(0), n, size_t(1), [&](size_t i) {
            // Isolated: a thread waiting inside one job's loops must not start another job, whose
            // wait at the gate could then hold up the job below it on the same stack.
            tbb::this_task_arena::isolate([&] {
                const PartitionFile& f = set.partitions[i];
                if (isCancelled(o)) {
                    status[i] = cancelled(input);
                    return;
                }
                const uint64_t bound = buildBound(f);
                status[i] = gate.acquire(bound, f.path);
                if (!status[i].ok()) return;
                auto r = runPartitionJob(f.path, o.work_dir, cluster, o.memory_limit_bytes, notes[i]);
                gate.release(bound);
                if (!r.ok()) {
                    status[i] = r.status();
                    return;
                }
                out[i] = std::move(*r);
            });
        });
    });
    for (size_t i = 0; i < n; ++i) {
        if (!out[i].file.path.empty()) files.made.push_back(out[i].file.path);
        for (const Diagnostic& d : notes[i].items())
            d.severity == Severity::Warning ? diagnostics.warn(d.message) : diagnostics.note(d.message);
    }
    for (const Status& s : status)
        if (!s.ok()) return s;
    return out;
}

// The merges under one picked node of a round (subtreeMerges), one after the other, each reserving
// its bound (kMergeFixedBytes plus its two inputs', as mergePartitionLods computes it) at the gate.
Status runSubtree(std::vector<TreeNode>& nodes, int picked, const MergeOptions& mo, const OutOfCoreOptions& o,
                  MemoryGate& gate, std::vector<MergeFile>& made, Diagnostics& diagnostics) {
    for (const MergeStep& step : subtreeMerges(nodes, picked, roundLevels(picked, mo))) {
        TreeNode& n = nodes[size_t(step.node)];
        const TreeNode& left = nodes[size_t(n.left)];
        const TreeNode& right = nodes[size_t(n.right)];
        if (isCancelled(o)) return ioError(left.file + ": merge cancelled");
        const uint64_t bound = kMergeFixedBytes + left.size.boundBytes() + right.size.boundBytes();
        LODBAKE_RETURN_IF_ERROR(gate.acquire(bound, left.file));
        ClusterLodOptions cluster = o.cluster;
        cluster.max_levels = step.levels;
        auto m = runMergeJob(left.file, right.file, o.work_dir, cluster, o.memory_limit_bytes, diagnostics);
        gate.release(bound);
        if (!m.ok()) return m.status();
        n.file = m->path;
        n.size = {m->root_count, m->root_vertices, m->root_triangles, m->border_vertex_count, m->border_edge_count};
        made.push_back(std::move(*m));
    }
    return Status::okStatus();
}

// The merge rounds over the partitions' k-d tree (roundNodes, as mergeAll and the job list choose
// them): the picked nodes of a round head disjoint subtrees, which run side by side under the gate;
// their merges are listed in the order the job list plans them whatever ran first.
Status mergeRounds(const std::vector<PartitionJobOutput>& lods, const OutOfCoreOptions& o, MemoryGate& gate,
                   RunFiles& files, MergeTree& tree, Diagnostics& diagnostics) {
    const MergeOptions mo = planMergeOptions(o.cluster, o.merge_group_bytes, o.memory_limit_bytes);
    std::vector<TreeNode> nodes;
    buildTree(0, uint32_t(lods.size()), mo.pairing, nodes);
    for (TreeNode& n : nodes)
        if (n.left < 0) {
            n.file = lods[n.begin].file.path;
            n.size = lods[n.begin].size;
            tree.partitions.push_back(n.file);
        }
    const int threads = o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(std::max(1, threads));
    while (nodes[0].file.empty()) {
        const std::vector<int> round = roundNodes(nodes, mo);
        std::vector<std::vector<MergeFile>> made(round.size());
        std::vector<Status> status(round.size());
        std::vector<Diagnostics> notes(round.size());
        arena.execute([&] {
            tbb::parallel_for(size_t(0), round.size(), size_t(1), [&](size_t k) {
                // Isolated: a thread waiting inside one job's loops must not pick up another subtree,
                // whose wait at the gate could then hold up the job below it on the same stack.
                tbb::this_task_arena::isolate(
                    [&] { status[k] = runSubtree(nodes, round[k], mo, o, gate, made[k], notes[k]); });
            });
        });
        Status failed;
        for (size_t k = 0; k < round.size(); ++k) {
            for (MergeFile& m : made[k]) {
                files.made.push_back(m.path);
                tree.largest_memory_bound = std::max(tree.largest_memory_bound, m.memory_bound_bytes);
                tree.largest_accounted_peak = std::max(tree.largest_accounted_peak, m.accounted_peak_bytes);
                tree.merges.push_back(std::move(m));
            }
            for (const Diagnostic& d : notes[k].items())
                d.severity == Severity::Warning ? diagnostics.warn(d.message) : diagnostics.note(d.message);
            if (failed.ok() && !status[k].ok()) failed = status[k];
        }
        LODBAKE_RETURN_IF_ERROR(failed);
        ++tree.merge_levels;
    }
    tree.top = nodes[0].file;
    return Status::okStatus();
}

// The pages of the tree (runPagesJob) into `output_path`: the writer's spill renamed into place.
Status writePages(const MergeTree& tree, const std::string& output_path, const OutOfCoreOptions& o,
                  OutOfCoreResult& result) {
    TreePagesOptions po;
    po.memory_limit_bytes = o.memory_limit_bytes;
    po.stream = o.pages;
    po.stream.cancel = o.cancel;
    LODBAKE_ASSIGN_OR_RETURN(TreePagesResult pages, runPagesJob(tree, output_path, po));
    result.pages_peak_bytes = pages.table_accounted_bytes + pages.pack.accounted_peak_bytes;
    result.cluster_count = pages.cluster_count;
    result.stats = pages.pack.stats;
    result.table = std::move(pages.pack.extension.blobs[0]);
    if (isCancelled(o)) return ioError(output_path + ": out-of-core bake cancelled");
    if (::rename(pages.pack.pages->tempPath().c_str(), output_path.c_str()) != 0)
        return ioError(output_path + ": cannot write the pages");
    return Status::okStatus();
}

Status runStages(const std::string& input, const std::string& output_path, const OutOfCoreOptions& o,
                 RunFiles& files, OutOfCoreResult& result, Diagnostics& diagnostics) {
    auto t0 = Clock::now();
    LODBAKE_ASSIGN_OR_RETURN(PartitionSet set, partitionMesh(input, outOfCorePartitionOptions(o), diagnostics));
    for (const PartitionFile& f : set.partitions) files.made.push_back(f.path);
    result.partition = {since(t0), set.partitions.size()};
    result.triangle_count = set.triangle_count;
    result.vertex_count = set.vertex_count;
    result.partition_count = set.partitions.size();
    result.partition_peak_bytes = set.accounted_peak_bytes;
    if (set.partitions.empty()) return invalidInput(input + ": no triangles");

    MemoryGate gate(o.memory_limit_bytes);
    t0 = Clock::now();
    LODBAKE_ASSIGN_OR_RETURN(std::vector<PartitionJobOutput> lods,
                             buildPartitions(input, set, o, gate, files, diagnostics));
    result.build = {since(t0), lods.size()};

    t0 = Clock::now();
    MergeTree tree;
    LODBAKE_RETURN_IF_ERROR(mergeRounds(lods, o, gate, files, tree, diagnostics));
    result.merge = {since(t0), tree.merges.size()};
    result.merge_count = tree.merges.size();
    result.merge_rounds = tree.merge_levels;
    result.jobs_peak_bytes = gate.peakReserved();

    t0 = Clock::now();
    LODBAKE_RETURN_IF_ERROR(writePages(tree, output_path, o, result));
    result.pages = {since(t0), result.cluster_count};
    result.output = output_path;
    result.tree = std::move(tree);
    result.accounted_peak_bytes =
        std::max({result.partition_peak_bytes, result.jobs_peak_bytes, result.pages_peak_bytes});
    return Status::okStatus();
}

} // namespace

Result<OutOfCoreResult> buildOutOfCore(const std::string& input, const std::string& output_path,
                                       const OutOfCoreOptions& options, Diagnostics& diagnostics) {
    if (options.work_dir.empty()) return invalidInput(input + ": out-of-core bake: no work folder given");
    RunFiles files;
    files.snapshot(options.work_dir);
    OutOfCoreResult result;
    // The output is renamed into place as the last step, so a failed run never made it.
    const Status s = runStages(input, output_path, options, files, result, diagnostics);
    if (!s.ok()) {
        files.removeCreated();
        return s;
    }
    if (!options.keep_intermediate) files.removeCreated();
    return result;
}

} // namespace lodbake::ooc
