#pragma once
// The out-of-core partitioner: streams a scan (PLY or OBJ, lodbake/io/mesh_stream.h) into spatial
// partitions on disk, each a file holding its triangles over its own vertices, with every vertex's
// global id (its number in the input) so that the borders between partitions can be found and locked
// later. Memory stays within the limit the caller passes, whatever the input size.
//
// Passes (docs/pipeline.md, "Out-of-core foundations"):
//  1. vertices: positions are spilled to a temporary file in the work folder and a deterministic
//     sample kept (every k-th vertex, k doubling as the sample fills);
//  2. a k-d tree over the sample cuts space into L leaves of about equal vertex counts, L chosen so
//     that a leaf's triangles fit a job (below); the spill is read back once to give every vertex
//     its leaf number (2 bytes, 4 beyond 65,535 leaves);
//  3. triangles: each goes to the leaf that two or three of its vertices share, else to the lowest
//     of their three leaves, and is appended (as global ids) to that leaf's raw file through a
//     buffer of B bytes;
//  4. jobs, one per leaf, in parallel: the raw triangles are read back, their vertices numbered
//     locally in global-id order, positions fetched from the spill, and the partition written to
//     `<work>/<content hash><kPartitionExtension>`.
// The set is the same for any thread count (files in leaf order, named by content). Raw files and
// the spill are always removed; on an error or a cancel every partition file the run created is
// removed too (a file already there under the same name, hence with the same bytes, stays). A write error (a full disk) is an IoError naming the path.
//
// Memory formula (bytes; V vertices, T triangles, J concurrent jobs, W the reader window, C the
// reader's chunk arrays, S the sample cap):
//   fixed     = W + C + 32 S + 1 MiB (spill buffer) + 64 KiB (spill reads)
//   pass 3    = fixed + V * cell_bytes + L * B
//   pass 4    = fixed + J * (kJobBytesPerTriangle * T_leaf + 1 MiB + 64 KiB)
// The target T_leaf is (limit - fixed - J * (1 MiB + 64 KiB)) / (J * P), P = kJobBytesPerTriangle (or
// build_bytes_per_triangle when larger, and then P stands for 64 in pass 4 too), L is
// T / (0.8 T_leaf) rounded up (the margin absorbs the sample's error in leaf sizes) and
// B = min(1 MiB, (limit - fixed - V * cell_bytes) / L), which must be at least 4 KiB: a limit too
// small for the input is a ResourceLimit error that states the minimum.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_stream.h"
#include "lodrt/format.h"

namespace lodbake::ooc {

/// Bytes a partition job holds per triangle of its partition: raw triangles (12) and sorted
/// (id, corner) pairs (24), then the triangles with unique ids and positions (16 per vertex, at most 3
/// vertices per triangle): at most 60, whatever the mesh. The file is written through a buffer.
constexpr uint64_t kJobBytesPerTriangle = 64;

struct PartitionOptions {
    std::string work_dir;                         // created if missing
    uint64_t memory_limit_bytes = uint64_t(1) << 30;
    int threads = 0;                              // concurrent jobs at most; 0: TBB's default
    StreamReadOptions read;
    const std::atomic<bool>* cancel = nullptr;    // set to stop: the run fails and removes its files
    uint64_t sample_cap = uint64_t(1) << 20;      // S above (the sample holds up to 2 S positions)
    // A job numbers its leaf's vertices by rank in a bitmap over the leaf's id range (3/16 byte per
    // id) when the range is at most this many ids per triangle of the leaf, else by sorting (id,
    // corner) pairs; at most 128 (the bound kJobBytesPerTriangle assumes), 0 always sorts.
    uint32_t bitmap_ids_per_triangle = 128;
    // Bytes per triangle of the job that will build each partition under the same limit
    // (ooc::kPartitionBuildBytesPerTriangle for buildPartition); leaves are sized by it in place of
    // kJobBytesPerTriangle when it is larger. 0: sized for writing the partitions only.
    uint64_t build_bytes_per_triangle = 0;
    // The target triangles per leaf (T_leaf) when not 0: leaves are then sized by it alone, so the
    // partitions do not depend on the limit or the thread count, and the limit only decides how many
    // jobs run at once (fewer than `threads` when fewer fit; none fitting is a ResourceLimit error
    // stating the minimum). 0: T_leaf from the limit and the thread count (formula above).
    uint64_t leaf_triangles = 0;
};

struct PartitionFile {
    std::string path;
    uint64_t content_hash = 0;
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    Vec3f bounds_min, bounds_max;
};

struct PartitionSet {
    std::vector<PartitionFile> partitions; // leaf order; empty leaves have no file
    uint64_t vertex_count = 0;
    uint64_t triangle_count = 0;
    uint64_t leaf_count = 0;
    uint64_t target_triangles = 0;    // T_leaf
    uint64_t largest_partition = 0;   // triangles
    uint64_t memory_bound_bytes = 0;  // the larger of the formula's pass 3 and pass 4 values
    uint64_t accounted_peak_bytes = 0; // the largest total of the buffers above held at one time
};

/// Partitions `input` (.ply or .obj) into `options.work_dir`.
Result<PartitionSet> partitionMesh(const std::string& input, const PartitionOptions& options,
                                   Diagnostics& diagnostics);

/// One partition read back: vertices in global-id order and triangles over them.
struct PartitionData {
    std::vector<uint32_t> global_ids; // increasing
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices;    // 3 per triangle, local vertex numbers
    uint64_t content_hash = 0;        // of the file's bytes (what partitionMesh names it by)
};

/// Reads and checks a partition file (magic, sizes, ids increasing, indices in range). File layout,
/// little-endian: kPartitionMagic, u32 vertex count V, u32 triangle count T, 6 floats of bounds
/// (min xyz, max xyz), V u32 global ids, V x 3 float positions, T x 3 u32 local indices. Reads into
/// the arrays directly: memory is 16 V + 12 T bytes.
Result<PartitionData> readPartitionFile(const std::string& path);

/// A partition file's header as read, checked for its magic and for a file size that is exactly what
/// its counts need (layout below).
struct PartitionHeader {
    uint8_t bytes[lodrt::format::kPartitionHeaderBytes] = {}; // as in the file (hashed with the rest)
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    Vec3f bounds_min, bounds_max;
};

/// Reads and checks the header of the partition file open as `fd`; `path` names it in messages.
Result<PartitionHeader> readPartitionHeader(int fd, const std::string& path);

/// Removes the files of a set.
void removePartitionFiles(const PartitionSet& set);

} // namespace lodbake::ooc
