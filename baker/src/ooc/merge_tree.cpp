// The merge driver and the assembly of a merge tree (lodbake/ooc/partition_merge.h).
#include <algorithm>
#include <filesystem>
#include <map>
#include <system_error>

#include <unistd.h>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lodbake/core/file_io.h"
#include "lodbake/ooc/partition_merge.h"
#include "ooc/merge_rounds.h"

namespace lodbake::ooc {

namespace {

constexpr uint32_t kNone = lodrt::kClusterNone;

// Removes the merge files a failed run wrote (not one that was there before it under the same name,
// which holds the same bytes).
void removeWritten(const std::vector<std::string>& written) {
    for (const std::string& p : written) ::unlink(p.c_str());
}

// One file of the tree in memory, with its clusters' global numbers.
struct Piece {
    ClusterLodHierarchy h;
    std::vector<MergeSeed> seeds;      // merges only
    const Piece* input[2] = {nullptr, nullptr};
    std::vector<uint32_t> global;      // per local cluster
    uint32_t group_base = 0;
};

uint32_t remapGroup(uint32_t g, uint32_t base) {
    return g == kNone ? kNone : g + base;
}

// Appends the local clusters [from, to) of `p` to `out` in order (their global numbers are the next
// ones), with their geometry and their groups renumbered.
void appendClusters(const Piece& p, uint32_t from, uint32_t to, ClusterLodHierarchy& out) {
    for (uint32_t c = from; c < to; ++c) {
        lodrt::ClusterLodCluster rec = p.h.clusters[c];
        rec.self_group = remapGroup(rec.self_group, p.group_base);
        rec.parent_group = remapGroup(rec.parent_group, p.group_base);
        const uint32_t first_vertex = uint32_t(out.positions.size()), first_triangle = uint32_t(out.indices.size() / 3);
        out.positions.insert(out.positions.end(), p.h.positions.begin() + rec.first_vertex,
                             p.h.positions.begin() + rec.first_vertex + rec.vertex_count);
        out.indices.insert(out.indices.end(), p.h.indices.begin() + size_t(rec.first_triangle) * 3,
                           p.h.indices.begin() + (size_t(rec.first_triangle) + rec.triangle_count) * 3);
        rec.first_vertex = first_vertex;
        rec.first_triangle = first_triangle;
        out.clusters.push_back(rec);
    }
}

void appendGroups(const Piece& p, ClusterLodHierarchy& out) {
    for (lodrt::ClusterLodGroup g : p.h.groups) {
        const uint32_t first = uint32_t(out.group_children.size());
        for (uint32_t i = 0; i < g.child_count; ++i)
            out.group_children.push_back(p.global[p.h.group_children[g.first_child + i]]);
        g.first_child = first;
        out.level_count = std::max(out.level_count, g.depth);
        out.groups.push_back(g);
    }
}

} // namespace

int buildTree(uint32_t begin, uint32_t end, MergePairing pairing, std::vector<TreeNode>& nodes) {
    const int at = int(nodes.size());
    nodes.push_back(TreeNode());
    nodes[size_t(at)].begin = begin;
    nodes[size_t(at)].end = end;
    if (end - begin == 1) return at;
    uint32_t mid = begin + (end - begin) / 2;
    if (pairing == MergePairing::LeafOrder) {
        // Adjacent pairs in leaf order, an odd last one carried up, level by level: the tree whose
        // left side is the largest power of two below the count.
        uint32_t p = 1;
        while (2 * p < end - begin) p *= 2;
        mid = begin + p;
    }
    const int l = buildTree(begin, mid, pairing, nodes);
    const int r = buildTree(mid, end, pairing, nodes);
    nodes[size_t(at)].left = l;
    nodes[size_t(at)].right = r;
    nodes[size_t(at)].height = 1 + std::max(nodes[size_t(l)].height, nodes[size_t(r)].height);
    return at;
}

namespace {

// One tree node's merge job: its two children's files in, `levels` levels built (0: none, the
// inputs' roots carried as the output's roots with their shared cut no longer on the border).
Status runMerge(std::vector<TreeNode>& nodes, TreeNode& n, uint32_t levels, const MergeOptions& options,
                const std::vector<std::string>& before, std::vector<std::string>& written, MergeTree& tree,
                Diagnostics& diagnostics) {
    if (options.cancel && options.cancel->load()) return ioError(nodes[size_t(n.left)].file + ": merge cancelled");
    MergeOptions job = options;
    job.cluster.max_levels = levels;
    // The job's bound (kMergeFixedBytes plus its two inputs', as mergePartitionLods computes it) is
    // reserved for as long as it runs.
    const uint64_t bound = kMergeFixedBytes + nodes[size_t(n.left)].size.boundBytes() + nodes[size_t(n.right)].size.boundBytes();
    if (options.gate) LODBAKE_RETURN_IF_ERROR(options.gate->acquire(bound, nodes[size_t(n.left)].file));
    auto made = mergePartitionLods(nodes[size_t(n.left)].file, nodes[size_t(n.right)].file, job, diagnostics);
    if (options.gate) options.gate->release(bound);
    if (!made.ok()) return made.status();
    MergeFile m = std::move(*made);
    if (!std::binary_search(before.begin(), before.end(), m.path)) written.push_back(m.path);
    tree.largest_memory_bound = std::max(tree.largest_memory_bound, m.memory_bound_bytes);
    tree.largest_accounted_peak = std::max(tree.largest_accounted_peak, m.accounted_peak_bytes);
    n.file = m.path;
    n.size.roots = m.root_count;
    n.size.root_vertices = m.root_vertices;
    n.size.root_triangles = m.root_triangles;
    n.size.border_vertices = m.border_vertex_count;
    n.size.border_edges = m.border_edge_count;
    tree.merges.push_back(std::move(m));
    return Status::okStatus();
}

// Runs the merges under picked node `at` (subtreeMerges), one after the other.
Status runSubtree(std::vector<TreeNode>& nodes, int at, uint32_t levels, const MergeOptions& options,
                  const std::vector<std::string>& before, std::vector<std::string>& written, MergeTree& tree,
                  Diagnostics& diagnostics) {
    for (const MergeStep& step : subtreeMerges(nodes, at, levels))
        LODBAKE_RETURN_IF_ERROR(
            runMerge(nodes, nodes[size_t(step.node)], step.levels, options, before, written, tree, diagnostics));
    return Status::okStatus();
}

void collectMerges(const std::vector<TreeNode>& nodes, int at, uint32_t levels, std::vector<MergeStep>& out) {
    const TreeNode& n = nodes[size_t(at)];
    if (!n.file.empty()) return;
    collectMerges(nodes, n.left, 0, out);
    collectMerges(nodes, n.right, 0, out);
    out.push_back({at, levels});
}

} // namespace

std::vector<MergeStep> subtreeMerges(const std::vector<TreeNode>& nodes, int at, uint32_t levels) {
    std::vector<MergeStep> out;
    collectMerges(nodes, at, levels, out);
    return out;
}

uint32_t roundLevels(int node, const MergeOptions& options) {
    if (node == 0 || options.levels_per_job == 0) return options.cluster.max_levels;
    return std::min(options.cluster.max_levels, options.levels_per_job);
}

// The nodes a round merges (preorder, hence leaf order): each highest node with no file whose files
// below fit in one job's bound (with grouping by memory), else each node whose two children have
// files. The rest wait for their subtree.
std::vector<int> roundNodes(const std::vector<TreeNode>& nodes, const MergeOptions& options) {
    std::vector<uint64_t> sum(nodes.size(), 0);
    std::vector<uint8_t> ready(nodes.size(), 0);
    for (size_t i = nodes.size(); i-- > 0;) {
        const TreeNode& n = nodes[i];
        if (!n.file.empty() || n.left < 0) continue;
        for (int c : {n.left, n.right}) {
            const TreeNode& k = nodes[size_t(c)];
            sum[i] += k.file.empty() ? sum[size_t(c)] : k.size.boundBytes();
        }
        ready[i] = !nodes[size_t(n.left)].file.empty() && !nodes[size_t(n.right)].file.empty();
    }
    std::vector<int> picked;
    std::vector<uint8_t> covered(nodes.size(), 0); // an ancestor is picked
    for (size_t i = 0; i < nodes.size(); ++i) {
        const TreeNode& n = nodes[i];
        if (n.left < 0) continue;
        const bool fits = options.group_by_memory &&
                          kMergeFixedBytes + sum[i] <= (options.group_bytes > 0 ? options.group_bytes : options.memory_limit_bytes);
        const bool pick = !covered[i] && n.file.empty() && (fits || ready[i]);
        if (pick) picked.push_back(int(i));
        covered[size_t(n.left)] = covered[size_t(n.right)] = covered[i] || pick;
    }
    return picked;
}


Result<MergeTree> mergeAll(const std::vector<std::string>& partition_lods, const MergeOptions& options,
                           Diagnostics& diagnostics) {
    if (partition_lods.empty()) return invalidInput("merge: expected at least one partition hierarchy");
    MergeTree tree;
    tree.partitions = partition_lods;
    std::vector<std::string> written, before;
    std::error_code ec;
    if (std::filesystem::is_directory(options.work_dir, ec))
        for (const auto& e : std::filesystem::directory_iterator(options.work_dir, ec))
            before.push_back(joinPath(options.work_dir, e.path().filename().string()));
    std::sort(before.begin(), before.end());
    std::vector<TreeNode> nodes;
    buildTree(0, uint32_t(partition_lods.size()), options.pairing, nodes);
    for (TreeNode& n : nodes)
        if (n.left < 0) {
            n.file = partition_lods[n.begin];
            if (options.group_by_memory || options.gate) {
                LODBAKE_ASSIGN_OR_RETURN(n.size, mergeInputSize(n.file));
            }
        }
    while (nodes[0].file.empty()) {
        const std::vector<int> round = roundNodes(nodes, options);
        // Each picked node's subtree is disjoint from the others': with a gate they run side by side,
        // each into its own slot, appended in leaf order so the tree lists the same merges either way.
        std::vector<MergeTree> part(round.size());
        std::vector<std::vector<std::string>> part_written(round.size());
        std::vector<Status> status(round.size());
        std::vector<Diagnostics> notes(round.size());
        auto run = [&](size_t k) {
            status[k] = runSubtree(nodes, round[k], roundLevels(round[k], options), options, before, part_written[k],
                                   part[k], notes[k]);
        };
        if (options.gate && round.size() > 1) {
            tbb::parallel_for(size_t(0), round.size(), size_t(1), [&](size_t k) {
                // Isolated: a thread waiting inside one job's loops must not pick up another subtree,
                // whose wait at the gate could then hold up the job below it on the same stack.
                tbb::this_task_arena::isolate([&] { run(k); });
            });
        } else {
            for (size_t k = 0; k < round.size(); ++k) run(k);
        }
        Status failed;
        for (size_t k = 0; k < round.size(); ++k) {
            written.insert(written.end(), part_written[k].begin(), part_written[k].end());
            for (MergeFile& m : part[k].merges) tree.merges.push_back(std::move(m));
            tree.largest_memory_bound = std::max(tree.largest_memory_bound, part[k].largest_memory_bound);
            tree.largest_accounted_peak = std::max(tree.largest_accounted_peak, part[k].largest_accounted_peak);
            for (const Diagnostic& d : notes[k].items())
                d.severity == Severity::Warning ? diagnostics.warn(d.message) : diagnostics.note(d.message);
            if (failed.ok() && !status[k].ok()) failed = status[k];
        }
        if (!failed.ok()) {
            removeWritten(written);
            return failed;
        }
        ++tree.merge_levels;
    }
    tree.top = nodes[0].file;
    return tree;
}

Result<ClusterLodHierarchy> assembleHierarchy(const MergeTree& tree, uint64_t memory_limit_bytes) {
    uint64_t file_bytes = 0;
    std::error_code ec;
    for (const std::string& p : tree.partitions) file_bytes += std::filesystem::file_size(p, ec);
    for (const MergeFile& m : tree.merges) file_bytes += std::filesystem::file_size(m.path, ec);
    // The files read back and the assembled copy.
    if (2 * file_bytes > memory_limit_bytes)
        return resourceLimit((tree.top.empty() ? std::string("merge") : tree.top) + ": memory limit of " +
                             std::to_string(memory_limit_bytes >> 20) + " MiB is too small to assemble the hierarchy (needs " +
                             std::to_string((2 * file_bytes >> 20) + 1) + " MiB)");
    std::vector<Piece> pieces(tree.partitions.size() + tree.merges.size());
    std::map<std::string, const Piece*> by_path;
    for (size_t i = 0; i < tree.partitions.size(); ++i) {
        LODBAKE_ASSIGN_OR_RETURN(PartitionLod p, readPartitionLodFile(tree.partitions[i]));
        pieces[i].h = std::move(p.hierarchy);
        by_path[tree.partitions[i]] = &pieces[i];
    }
    for (size_t i = 0; i < tree.merges.size(); ++i) {
        Piece& piece = pieces[tree.partitions.size() + i];
        LODBAKE_ASSIGN_OR_RETURN(MergedLod m, readMergeFile(tree.merges[i].path));
        piece.h = std::move(m.hierarchy);
        piece.seeds = std::move(m.seeds);
        for (int k = 0; k < 2; ++k) {
            const auto it = by_path.find(tree.merges[i].input_path[k]);
            if (it == by_path.end())
                return invalidInput(tree.merges[i].path + ": input " + tree.merges[i].input_path[k] +
                                    ": expected a file merged before it");
            piece.input[k] = it->second;
        }
        if (piece.seeds.size() != piece.h.lod0_cluster_count)
            return invalidInput(tree.merges[i].path + ": seeds: expected one per level-0 cluster");
        by_path[tree.merges[i].path] = &piece;
    }
    // Global numbers: every partition's LOD0 clusters (leaf order), then their other clusters, then
    // each merge's own clusters; a merge's seeds are its inputs' roots.
    ClusterLodHierarchy out;
    uint32_t next = 0, groups = 0;
    for (size_t i = 0; i < tree.partitions.size(); ++i) {
        Piece& p = pieces[i];
        p.global.resize(p.h.clusters.size());
        for (uint32_t c = 0; c < p.h.lod0_cluster_count; ++c) p.global[c] = next++;
    }
    out.lod0_cluster_count = next;
    for (size_t i = 0; i < pieces.size(); ++i) {
        Piece& p = pieces[i];
        p.group_base = groups;
        groups += uint32_t(p.h.groups.size());
        if (i < tree.partitions.size()) {
            for (uint32_t c = p.h.lod0_cluster_count; c < p.h.clusters.size(); ++c) p.global[c] = next++;
            continue;
        }
        p.global.resize(p.h.clusters.size());
        for (uint32_t c = 0; c < p.h.lod0_cluster_count; ++c) {
            const MergeSeed& s = p.seeds[c];
            const Piece& in = *p.input[s.input];
            if (s.root >= in.h.roots.size()) return invalidInput("merge: seed " + std::to_string(c) + ": root out of range");
            p.global[c] = in.global[in.h.roots[s.root]];
        }
        for (uint32_t c = p.h.lod0_cluster_count; c < p.h.clusters.size(); ++c) p.global[c] = next++;
    }
    out.clusters.reserve(next);
    for (size_t i = 0; i < tree.partitions.size(); ++i) appendClusters(pieces[i], 0, pieces[i].h.lod0_cluster_count, out);
    for (size_t i = 0; i < pieces.size(); ++i)
        appendClusters(pieces[i], pieces[i].h.lod0_cluster_count, uint32_t(pieces[i].h.clusters.size()), out);
    for (const Piece& p : pieces) appendGroups(p, out);
    // A merge's seeds are its inputs' roots: they now have the merge's groups as parents.
    for (size_t i = tree.partitions.size(); i < pieces.size(); ++i) {
        const Piece& p = pieces[i];
        for (uint32_t c = 0; c < p.h.lod0_cluster_count; ++c)
            out.clusters[p.global[c]].parent_group = remapGroup(p.h.clusters[c].parent_group, p.group_base);
    }
    const Piece& top = *by_path.at(tree.top);
    for (uint32_t r : top.h.roots) out.roots.push_back(top.global[r]);
    out.reached_single_group = out.roots.size() == 1;
    if (lodrt::validateClusterLod(out.view()) != lodrt::Result::Ok)
        return invalidInput(tree.top + ": assembled hierarchy: expected a valid cluster hierarchy");
    return out;
}

} // namespace lodbake::ooc
