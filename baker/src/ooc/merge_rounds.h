#pragma once
// The merge tree's rounds (lodbake/ooc/partition_merge.h, mergeAll), shared by mergeAll, the job
// list (lodbake/ooc/jobs.h) and the driver, so that every way of running the merges builds the same
// tree: the nodes, which nodes a round merges and the order of the merges under a picked node.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/ooc/partition_merge.h"

namespace lodbake::ooc {

// A node of the merge tree over files [begin, end): a leaf per file, and above them the k-d tree
// partitionMesh cut (the left side takes half the leaves, rounded down), so that each merge joins two
// siblings, which share the cut between them; with adjacent pairs in leaf order instead, a pair may
// straddle a cut higher up and share nothing.
struct TreeNode {
    uint32_t begin = 0, end = 0;
    int left = -1, right = -1;
    uint32_t height = 0;
    std::string file;
    MergeInputSize size; // of `file`, once it is there
};

/// Appends the subtree over [begin, end) to `nodes` in preorder; returns its root's index.
int buildTree(uint32_t begin, uint32_t end, MergePairing pairing, std::vector<TreeNode>& nodes);

/// The nodes the next round merges (preorder, hence leaf order): each highest node with no file whose
/// files below fit in one job's bound (with grouping by memory), else each node whose two children
/// have files.
std::vector<int> roundNodes(const std::vector<TreeNode>& nodes, const MergeOptions& options);

/// One merge of a round: tree node `node` from its two children's files, building `levels` levels.
struct MergeStep {
    int node = 0;
    uint32_t levels = 0;
};

/// The merges under picked node `at` in the order they run: every node below without a file,
/// children first and left before right, building no level; `at` itself last, building `levels`.
std::vector<MergeStep> subtreeMerges(const std::vector<TreeNode>& nodes, int at, uint32_t levels);

/// The levels a picked node's merge builds: the top merge (node 0) options.cluster.max_levels, any
/// other at most options.levels_per_job (when not 0).
uint32_t roundLevels(int node, const MergeOptions& options);

} // namespace lodbake::ooc
