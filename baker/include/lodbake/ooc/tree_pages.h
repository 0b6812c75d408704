#pragma once
// The pages of an out-of-core hierarchy written without holding its geometry (docs/pipeline.md,
// "Pages of a merge tree"): assembleClusterTable reads only the records of a merge tree's files
// (partition jobs' .lbplod, merge jobs' .lbpmrg) and numbers them exactly as assembleHierarchy does,
// keeping per cluster where its geometry lies; TreePageSource reads one page's clusters' geometry
// from the files by offset through a small window; writeTreeClusterPages runs the streamed pack
// writer (lodbake/pack/cluster_pack_stream.h) over both. The pages and the table are the bytes
// writeClusterLodPack writes for assembleHierarchy(tree).
//
// Memory formula of the table (bytes; over the tree: C clusters, G groups, H group children, R_top
// the top file's roots, F files; per file f: R_f roots, C_f clusters, S_f level-0 clusters of a merge):
//   bound = 72 C                                   (the records, 60, and each one's locator, 12)
//         + 48 G + 4 H + 4 R_top                   (group records, children, roots)
//         + sum over files of (kTreeTableBytesPerFile + 2 (its path + 1) + 4 R_f)
//                                                  (the file list, each file's roots' global numbers)
//         + max over files of (4 C_f + max(44 S_f, 61,440))
//                                                  (one file's global numbers, then its seed records
//                                                   or the cluster records read 1,024 at a time)
// computed from the files' headers before any record is read; a limit below it is a ResourceLimit
// error naming the top file and the minimum. The page source holds its window (64 KiB by default)
// and at most 64 file descriptors.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/pack/cluster_pack_stream.h"

namespace lodbake::ooc {

/// Bytes per file in the table's bound besides its path (held twice) and roots: the file entry
/// (offsets, counts, size, modification time), its header as read and the per-file arrays' headers.
constexpr uint64_t kTreeTableBytesPerFile = 320;

/// Where a cluster's geometry lies: file `file` of the table, positions from its local vertex
/// `first_vertex`, triangles from its local triangle `first_triangle`.
struct ClusterLocator {
    uint32_t file = 0;
    uint32_t first_vertex = 0;
    uint32_t first_triangle = 0;
};

/// A file of the tree as the table read it. The page source refuses one whose size or modification
/// time has changed since.
struct TreeFile {
    std::string path;
    uint64_t positions_offset = 0; // byte offset of its positions array
    uint64_t indices_offset = 0;   // byte offset of its triangles (3 u8 each)
    uint32_t vertex_count = 0, triangle_count = 0;
    uint64_t size = 0;
    int64_t mtime_ns = 0;
};

/// The records of a merge tree's hierarchy without its geometry: clusters, groups, children and
/// roots numbered as assembleHierarchy numbers them (a cluster's first_vertex and first_triangle are
/// its offsets in the concatenation of every cluster's geometry in cluster order, as there).
struct TreeClusterTable {
    std::vector<lodrt::ClusterLodCluster> clusters;
    std::vector<lodrt::ClusterLodGroup> groups;
    std::vector<uint32_t> group_children;
    std::vector<uint32_t> roots;
    uint32_t lod0_cluster_count = 0;
    uint32_t level_count = 0; // deepest group
    bool reached_single_group = false;
    uint32_t vertex_count = 0, triangle_count = 0; // of the concatenation
    std::vector<TreeFile> files;                   // the partitions in leaf order, then the merges as run
    std::vector<ClusterLocator> locators;          // per cluster
    uint64_t memory_bound_bytes = 0;               // the formula above
    uint64_t accounted_peak_bytes = 0;             // the arrays held at most

    /// A view for the pack writer; valid while this object lives and is unchanged.
    lodrt::ClusterLodView view() const;
};

/// The bound above for `tree` (reads the files' headers only).
Result<uint64_t> clusterTableBound(const MergeTree& tree);

/// Reads the records of every file of `tree` (by offset; no geometry) into one table. Errors name
/// the file: a missing, truncated or inconsistent one is InvalidInput (IoError when it cannot be
/// read); a limit below the bound is ResourceLimit.
Result<TreeClusterTable> assembleClusterTable(const MergeTree& tree, uint64_t memory_limit_bytes);

/// The geometry of a table's clusters read from its files: each file opened on first use and kept
/// open (at most `max_open_files` at once, at least 1: beyond, every descriptor is closed and files
/// are reopened as needed), checked at every opening against the size and modification time the
/// table saw; reads go through one window of `window_bytes`, refilled by pread where a read falls
/// outside it. A short read or a changed file is an InvalidInput error naming the file.
class TreePageSource : public ClusterPageSource {
public:
    explicit TreePageSource(const TreeClusterTable& table, size_t window_bytes = size_t(64) << 10,
                            size_t max_open_files = 64);
    ~TreePageSource() override;
    TreePageSource(const TreePageSource&) = delete;
    TreePageSource& operator=(const TreePageSource&) = delete;

    Status readPage(uint32_t page, const uint32_t* clusters, size_t count, ClusterPageGeometry& out) override;

    /// Every cluster vertex in cluster order, streamed from the files: the same bounds as
    /// clusterPackBounds(assembleHierarchy(tree)).
    Result<ClusterPackBounds> bounds();

    /// Geometry bytes handed out so far (the window may read somewhat more from the files).
    uint64_t bytesRead() const { return bytes_read_; }

private:
    const TreeClusterTable& table_;
    std::vector<int> fds_;
    size_t max_open_ = 64, open_count_ = 0;
    std::vector<uint8_t> window_;
    uint32_t window_file_ = ~0u;
    uint64_t window_offset_ = 0;
    size_t window_size_ = 0;
    uint64_t bytes_read_ = 0;
    Status openFile(uint32_t file);
    Status read(uint32_t file, uint64_t offset, void* data, size_t size);
    Status readCluster(uint32_t cluster, ClusterPageGeometry& out);
};

struct TreePagesOptions {
    uint64_t memory_limit_bytes = uint64_t(1) << 30; // for the table (assembleClusterTable)
    ClusterPackStreamOptions stream;
    size_t window_bytes = size_t(64) << 10;
};

struct TreePagesResult {
    ClusterPackStreamResult pack; // the extension, its spilled pages and the writer's memory figures
    uint64_t table_bound_bytes = 0;
    uint64_t table_accounted_bytes = 0;
    uint64_t bytes_read = 0; // geometry handed out by the source: the bounds pass and the pages
    uint32_t cluster_count = 0;
};

/// Writes `tree`'s hierarchy as LODBAKE_cluster_lod (table in memory, pages spilled beside
/// `output_path`, as writeClusterLodPackStreamed does) without holding its geometry. Errors as
/// assembleClusterTable's, TreePageSource's and the writer's; on any error no spill is left.
Result<TreePagesResult> writeTreeClusterPages(const MergeTree& tree, const std::string& output_path,
                                              const TreePagesOptions& options);

} // namespace lodbake::ooc
