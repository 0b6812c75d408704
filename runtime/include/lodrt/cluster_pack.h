#pragma once
// Reader of the LODBAKE_cluster_lod extension (docs/format/cluster_lod.md): a cluster LOD hierarchy
// stored on LOD0's mesh as a table (clusters, groups, roots, pages) and pages of geometry, each page a
// positions-only valence stream (lodrt/valence.h) that decodes on its own and is fetched by byte range.
// Every page quantizes on one grid shared by all pages, so a vertex on the border of two pages decodes
// to the same float in both and the drawn cut keeps its crack-free property.
//
// meshoptimizer style, nothing allocated: clusterPackReadInfo reads the table's header and says how much
// memory the open table needs; clusterPackOpen validates every record (indices, ranges, counts against
// the format's limits, page byte ranges inside the pages view, the hierarchy as validateClusterLod
// checks it) into caller memory; clusterPageDecode decodes one page into caller buffers. Every byte is
// treated as hostile: errors are Result codes plus a one-line message, never a read out of bounds.

#include <cstddef>
#include <cstdint>

#include "lodrt/cluster_lod.h"
#include "lodrt/export.h"
#include "lodrt/pack.h"
#include "lodrt/result.h"

namespace lodrt {

/// Where a mesh's extension keeps its bytes: the two buffer views, their byte ranges in the GLB BIN
/// chunk (so the table and each page can be range-read, e.g. with PackSource::readBufferView), and
/// their bytes when the BIN chunk is in memory.
struct ClusterPackSource {
    uint32_t table_view = 0;
    uint32_t pages_view = 0;
    uint64_t table_offset = 0; // of the table view in the BIN chunk
    size_t table_size = 0;
    uint64_t pages_offset = 0; // of the pages view in the BIN chunk
    uint64_t pages_size = 0;
    const uint8_t* table = nullptr; // the bytes when the BIN chunk is in memory (loadPack), else null
    const uint8_t* pages = nullptr;
};

/// Finds `format::kExtClusterLod` on mesh `mesh` of `pack` and checks its object (the two buffer
/// views exist and lie in the GLB BIN chunk, tightly packed). Returns Ok (with null byte pointers
/// for a pack loaded with loadPackJson), NotLoaded when the mesh has no such extension, BadGltf /
/// OutOfBounds with a one-line message otherwise.
LODRT_API Result clusterPackFind(const Pack& pack, uint32_t mesh, ClusterPackSource* out, char* error_message = nullptr,
                                 size_t error_message_size = 0);

/// The table's header.
struct ClusterPackInfo {
    uint32_t cluster_count = 0;
    uint32_t group_count = 0;
    uint32_t group_child_count = 0;
    uint32_t root_count = 0;
    uint32_t page_count = 0;
    uint32_t position_bits = 0;
    float grid_min[3] = {0, 0, 0};
    float grid_size = 0;
    float quantization_error = 0;
    size_t memory_bytes = 0; // what clusterPackOpen needs (aligned to 8)
};

/// Reads and checks the header (magic, version, counts within kClusterMaxCount, the table's exact
/// size, a valid grid). Truncated / TrailingBytes / BadMagic / UnsupportedVersion / BadStructure.
LODRT_API Result clusterPackReadInfo(const uint8_t* table, size_t table_size, ClusterPackInfo* info,
                                     char* error_message = nullptr, size_t error_message_size = 0);

/// One page: its bytes in the pages view and what it decodes to.
struct ClusterPage {
    uint64_t byte_offset = 0; // in the pages view
    uint32_t stream_bytes = 0; // the valence stream
    uint32_t run_count = 0;    // 2-byte runs after the stream
    uint32_t byte_length = 0;  // stream_bytes + 2 * run_count
    uint32_t first_cluster = 0; // into ClusterLodPack::page_clusters
    uint32_t cluster_count = 0;
    uint32_t triangle_count = 0; // sum of its clusters' triangles
};

/// A cluster's place in its page: its triangles are [first_triangle, first_triangle + triangle_count)
/// of the page's decoded, cluster-sorted triangles.
struct ClusterPlace {
    uint32_t page = 0;
    uint32_t first_triangle = 0;
    uint32_t triangle_count = 0;
    uint32_t vertex_count = 0;
};

/// The open table, in the caller's memory. `view` is the hierarchy for selectClusterCut (its clusters
/// carry their normal cones; their triangle ranges number the pages' triangles pack-wide, page after
/// page; their vertex ranges are their page's vertices, vertex_count the cluster's distinct ones).
struct ClusterLodPack {
    ClusterLodView view;
    const ClusterPlace* places = nullptr; // one per cluster
    const ClusterPage* pages = nullptr;
    uint32_t page_count = 0;
    const uint32_t* page_clusters = nullptr; // each page's clusters in table order, one range per page
    ClusterPackInfo info;
};

/// Validates the whole table against `pages_size` (the pages view's length) and fills `out`, pointing
/// into `memory` (info.memory_bytes bytes, aligned to 8; it must outlive `out`). Page streams are not
/// decoded here (clusterPageDecode does, one at a time). Returns Ok or the first problem: OutOfBounds
/// (an index or byte range outside what exists), BadStructure (a count above the format's limits, a
/// non-finite value, a cluster that its parent group does not list, pages whose clusters do not tile
/// them), with a one-line message naming the record.
LODRT_API Result clusterPackOpen(const uint8_t* table, size_t table_size, uint64_t pages_size, void* memory,
                                 size_t memory_size, ClusterLodPack* out, char* error_message = nullptr,
                                 size_t error_message_size = 0);

/// Sizes of one page's decode, read from its stream header (which is checked against the table:
/// the shared grid, a positions-only stream, the triangle count the clusters add up to).
struct ClusterPageInfo {
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    size_t scratch_bytes = 0; // for clusterPageDecode, aligned to 8
};

/// `page` points at the page's byte_length bytes (pages view + byte_offset).
LODRT_API Result clusterPageReadInfo(const ClusterLodPack& pack, uint32_t page_index, const uint8_t* page,
                                     size_t page_size, ClusterPageInfo* info, char* error_message = nullptr,
                                     size_t error_message_size = 0);

/// Decodes page `page_index` into caller buffers: positions (3 floats per vertex) and indices (3 per
/// triangle, page-local vertex indices) with each cluster's triangles at its ClusterPlace range.
/// Nothing is allocated: `scratch` holds info.scratch_bytes (aligned to 8). CorruptStream and the
/// valence decoder's codes for a bad stream, BadStructure for runs that disagree with the table,
/// BufferTooSmall for short outputs.
LODRT_API Result clusterPageDecode(const ClusterLodPack& pack, uint32_t page_index, const uint8_t* page,
                                   size_t page_size, float* positions, size_t position_capacity, uint32_t* indices,
                                   size_t index_capacity, void* scratch, size_t scratch_size,
                                   char* error_message = nullptr, size_t error_message_size = 0);

/// Group residency for selectClusterCutResident from page residency (page_resident[p] nonzero when
/// page p is decoded and uploaded): a group is resident when the pages of all its input clusters
/// are, then closed upward (clusterResidencyClosure). Call when pages arrive or leave.
LODRT_API void clusterGroupResidency(const ClusterLodPack& pack, const uint8_t* page_resident,
                                     uint8_t* group_resident);

} // namespace lodrt
