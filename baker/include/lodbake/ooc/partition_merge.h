#pragma once
// The merge step of the out-of-core bake (docs/pipeline.md, "Merge jobs"): two neighbouring
// hierarchy files (partition jobs' .lbplod, or merges' .lbpmrg) in, their roots taken as one level and
// the hierarchy continued over both (continueClusterLod) until one root remains or a level stalls,
// out as a content-hashed file. mergeAll merges the partitions' files over the partitioner's k-d tree,
// round by round (each round one level, over as many k-d siblings per job as its bound fits) until
// one file remains; assembleHierarchy renumbers the partitions' hierarchies and every merge into one
// ClusterLodHierarchy when it fits in memory.
//
// Welding: a root vertex at a position of its file's recorded border is the input vertex of that
// global id (border positions are bit-identical on both sides, the border lock keeps them), so the
// two inputs' roots meet at their shared border by global identity; any other vertex is a point of
// its own input only (welded by position within the input, as its builder welded it). An edge on
// both recorded borders is now used by a triangle on each side: interior, it may simplify. The rest
// of both borders (the cut to partitions not yet merged, the input's own boundary) stays open, hence
// locked by the builder's lock_border, and is the output's recorded border.
//
// Memory formula (bytes; over the two inputs: R roots, V_r and T_r their vertices and triangles,
// B border vertices and E border edges):
//   bound = 2 MiB                                  (the read buffer that hashes an input, the write buffer)
//         + kMergeBytesPerRoot * R                 (root, group and seed records, read and written)
//         + 48 V_r + 15 T_r                        (roots' geometry read, the seed's points, triangles and weld keys)
//         + kClusterBuildBytesPerTriangle * T_r    (continueClusterLod's working set and output)
//         + 64 B + 32 E                            (the borders read, their union-find and the output's border)
// computed from the inputs' headers and root records before any geometry is read; a limit below it
// is a ResourceLimit error naming the first input and the minimum.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/math.h"
#include "lodbake/core/memory_gate.h"
#include "lodbake/core/status.h"
#include "lodbake/ooc/partition_build.h"

namespace lodbake::ooc {

/// Bytes per root in the merge job's bound: its cluster record (60) and its self group's (48) read,
/// its seed cluster (48) and its seed record in the output (44).
constexpr uint64_t kMergeBytesPerRoot = 60 + 48 + 48 + 44;

/// The kind of a hierarchy file.
enum class LodFileKind : uint32_t { Partition = 0, Merge = 1 };

/// Levels a job below the top of the merge tree builds (mergeAll; the partition jobs should build as
/// many, through PartitionBuildOptions::cluster.max_levels). A job's outer border is locked, so
/// every level it builds simplifies its inside further while the strip along its border stays as
/// fine as its input: built as far as the lock allows, a partition ends up far coarser inside than
/// the in-memory build at the same triangle count. One level per job keeps the tree level by level
/// (a merge at tree level m builds about depth m + 1), so a strip waits at most until the merge
/// that unlocks it; the top merge then builds on as far as it can.
constexpr uint32_t kLevelsPerJob = 1;

/// How mergeAll pairs the partitions' files, given in leaf order.
enum class MergePairing {
    KdSiblings, // the partitioner's k-d tree (the left side takes half the leaves, rounded down): each
                // merge joins two siblings, which share the cut between them
    LeafOrder,  // adjacent pairs in leaf order, an odd last one carried up, level by level: a pair can
                // straddle a cut higher up the tree and share nothing
};

struct MergeOptions {
    std::string work_dir; // where the output goes; created if missing
    uint64_t memory_limit_bytes = uint64_t(1) << 30;
    ClusterLodOptions cluster; // for mergeAll: the top merge's (its max_levels included)
    uint32_t levels_per_job = kLevelsPerJob; // mergeAll, every merge but the top; 0: as many as it can
    MergePairing pairing = MergePairing::KdSiblings; // mergeAll
    bool group_by_memory = true; // mergeAll: a job joins as many k-d siblings as fit (see mergeAll)
    // mergeAll with group_by_memory: the bound a job's grouped files must fit, when not 0 (else
    // memory_limit_bytes). A fixed value keeps the tree, hence every file, independent of the limit.
    uint64_t group_bytes = 0;
    // mergeAll: when set, the merges of a round (disjoint subtrees) run concurrently, each subtree's
    // jobs one after the other, each reserving its bound here first; else one after the other.
    MemoryGate* gate = nullptr;
    const std::atomic<bool>* cancel = nullptr; // mergeAll: checked before every job; set, the run fails
};

/// What a merge job wrote.
struct MergeFile {
    std::string path; // <work_dir>/<content hash, hex><kPartitionMergeExtension>
    uint64_t content_hash = 0;
    std::string input_path[2];
    uint64_t input_hash[2] = {0, 0};
    LodFileKind input_kind[2] = {LodFileKind::Partition, LodFileKind::Partition};
    uint32_t seed_count = 0;     // the inputs' roots: the merge's level-0 clusters
    uint32_t seed_triangles = 0; // T_r
    uint32_t shared_edges = 0;   // border edges the two inputs shared (now interior)
    uint32_t cluster_count = 0, group_count = 0, root_count = 0, level_count = 0;
    uint32_t root_vertices = 0, root_triangles = 0; // of the new roots
    uint32_t border_vertex_count = 0, border_edge_count = 0;
    bool reached_single_group = false;
    uint64_t memory_bound_bytes = 0;
    uint64_t accounted_peak_bytes = 0; // the arrays held, with the builder at its per-triangle bound
};

/// Merges the hierarchies at `a_path` and `b_path` (either kind). Deterministic for any thread count.
/// Errors name the file: a truncated or corrupted input (its bytes must hash to its name when the
/// name is a content hash) is InvalidInput; no output is left behind on any error.
Result<MergeFile> mergePartitionLods(const std::string& a_path, const std::string& b_path, const MergeOptions& options,
                                     Diagnostics& diagnostics);

/// One seed of a merge: which input root its level-0 cluster is, and the values it carried.
struct MergeSeed {
    uint32_t input = 0; // 0: a, 1: b
    uint32_t root = 0;  // index into that input's roots
    uint32_t depth = 0;
    float error = 0;
    float lod_center[3] = {};
    float lod_radius = 0;
    float bounds_center[3] = {};
    float bounds_radius = 0;
};

/// A merge file read back. hierarchy's clusters [0, lod0_cluster_count) are copies of the inputs'
/// roots (seeds[i] says which); the groups and clusters above are the merge's own.
struct MergedLod {
    uint64_t input_hash[2] = {0, 0};
    LodFileKind input_kind[2] = {LodFileKind::Partition, LodFileKind::Partition};
    ClusterLodHierarchy hierarchy;
    std::vector<MergeSeed> seeds;
    std::vector<uint32_t> border_ids;
    std::vector<Vec3f> border_positions;
    std::vector<uint32_t> border_edges;
};

/// Reads and checks a file written by mergePartitionLods (layout in docs/pipeline.md, "Merge jobs").
Result<MergedLod> readMergeFile(const std::string& path);

/// The merge job's fixed allowance: the buffer that hashes an input and the output's write buffer.
constexpr uint64_t kMergeFixedBytes = uint64_t(2) << 20;

/// What one input adds to a merge job's bound: its roots, their geometry and its border.
struct MergeInputSize {
    uint64_t roots = 0, root_vertices = 0, root_triangles = 0, border_vertices = 0, border_edges = 0;
    /// kMergeBytesPerRoot R + 48 V_r + (15 + kClusterBuildBytesPerTriangle) T_r + 64 B + 32 E. A merge's
    /// bound is kMergeFixedBytes plus its two inputs'; a merge that builds no level keeps its inputs'
    /// roots and at most their borders, so its output adds at most the sum of its inputs'.
    uint64_t boundBytes() const;
};

/// Reads a hierarchy file's header and root records (hashing it, as a merge does) and returns what it
/// adds to a merge job's bound. Errors as mergePartitionLods's for that input.
Result<MergeInputSize> mergeInputSize(const std::string& path);

/// The merge tree of a set of partition hierarchies.
struct MergeTree {
    std::vector<std::string> partitions; // the .lbplod files, leaf order
    std::vector<MergeFile> merges;       // in the order run: round by round, jobs in leaf order
    std::string top;                     // the file that holds the root(s): the last merge, or the
                                         // only partition
    uint32_t merge_levels = 0;           // rounds
    uint64_t largest_memory_bound = 0;   // over the merge jobs
    uint64_t largest_accounted_peak = 0;
};

/// Merges the partitions' hierarchy files (in leaf order) over a binary tree (options.pairing), in
/// rounds. With group_by_memory, a round takes each highest node not yet merged whose files below
/// (the previous rounds' outputs) fit one merge job's bound together (kMergeFixedBytes plus their
/// MergeInputSize::boundBytes) and runs the merges under it, children first: those below it build no
/// level (their output carries their inputs' roots, the shared cut no longer on the border), the one
/// at the node builds the round's level. A node whose two children are done is merged even when its
/// subtree fits no further. Without group_by_memory every round merges the nodes whose two children
/// are done (tree height h in round h), a file whose sibling is a larger subtree waiting. Every job
/// but the top builds at most options.levels_per_job levels; the top builds on as far as it can. The
/// jobs run one after the other, each under options.memory_limit_bytes. On an error every merge file
/// the run wrote is removed.
Result<MergeTree> mergeAll(const std::vector<std::string>& partition_lods, const MergeOptions& options,
                           Diagnostics& diagnostics);

/// The whole hierarchy of a merge tree in memory: every partition's hierarchy and every merge's
/// groups and new clusters, renumbered into one ClusterLodHierarchy (LOD0 clusters first, in leaf
/// order; a merge's seeds are the inputs' root clusters themselves, which become its groups' inputs).
/// Fails (ResourceLimit) when the files' total size exceeds `memory_limit_bytes`: the hierarchy in
/// memory is about as large as its files.
Result<ClusterLodHierarchy> assembleHierarchy(const MergeTree& tree, uint64_t memory_limit_bytes);

} // namespace lodbake::ooc
