#pragma once
// PFRep reader: progressive fans (Cortés Carrillo), docs/format/pfrep.md.
//
// The blob is built by lodbake from a HALF-EDGE-collapse sequence (each step removes one vertex u and
// re-attaches its neighbourhood to a neighbour that stays in place), so vertex ids are removal ranks
// and every triangle ever alive is stored once, as a fan slot at its lowest-ranked corner, tagged
// with the vertex whose removal created it (or none for input triangles).
//
// The reader treats the blob as hostile: openPfrep() validates every field and every entry once
// (offsets, counts, index ranges, the rank rules that make dependency cycles impossible); after it
// returns Ok, extraction and refinement cannot read outside the blob. Nothing here allocates or
// throws: every output goes to caller-owned buffers whose needed size can be queried first.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/result.h"

namespace lodrt {

/// A validated view of a PFRep blob or of a prefix of it (the bytes must outlive it). Plain data;
/// copy freely.
///
/// Prefix streaming (format version 2): the blob stores its blocks of 2^block_shift vertices coarse
/// end first, so a prefix holds the header, the block directory and the blocks of the highest ranks.
/// Vertices [loaded_from, vertex_count) are then loaded and validated; levels k >= loaded_from
/// (k <= removed_count) can be extracted exactly as from the whole blob, and selective refinement
/// keeps every vertex below loaded_from removed. Nothing ever reads beyond `size`.
struct PfrepModel {
    const uint8_t* data = nullptr;
    size_t size = 0; // bytes available (validated); blob_size once complete
    uint32_t vertex_count = 0;
    uint32_t removed_count = 0; // vertices [0, removed_count) can be removed, in this order
    uint32_t block_shift = 0;
    uint32_t level0_triangles = 0; // triangles of the full-detail mesh (the largest any level has)
    float position_min[3] = {0, 0, 0};
    float position_step[3] = {0, 0, 0};
    float error_unit = 0;
    uint32_t blob_size = 0;   // bytes of the whole blob
    uint32_t block_count = 0; // ceil(vertex_count / 2^block_shift)
    uint32_t loaded_blocks = 0; // blocks validated: block_count - loaded_blocks .. block_count - 1
    uint32_t loaded_from = 0;   // lowest loaded vertex (vertex_count when no block is loaded; 0 = complete)
    uint32_t loaded_original_triangles = 0; // input triangles stored in the loaded blocks
    uint32_t max_fan_neighbours = 0;
    /// Largest bounding-sphere radius and removal error of any loaded vertex: with the position box
    /// they bound a whole instance, so pfrepRefine can decide it at once.
    float max_radius = 0;
    float max_error = 0;
    /// Optional criterion table (pfrepAttachCriterionTable; caller-owned, shared by every instance).
    /// pfrepExtendPrefix detaches it (the new vertices are not in it): attach it again.
    const float* criterion_table = nullptr;
    /// Region blocks (pfrepRegionOpen): one bit per vertex, 1 = its record and entry are loaded.
    /// When set, residency replaces the `v >= loaded_from` rule for selective refinement (a
    /// non-resident vertex is never inserted, its record never read); loaded_from is then the
    /// lowest rank of the resident suffix, so level k is extractable iff k >= loaded_from as before.
    const uint8_t* resident = nullptr;
};

/// Validates the whole blob (size must equal its blob_size). Truncated / TrailingBytes / BadMagic /
/// UnsupportedVersion / OutOfBounds / BadStructure on bad input; `model` is only written on Ok.
LODRT_API Result openPfrep(const void* data, size_t size, PfrepModel* model);

/// Opens a prefix data[0, size) of a blob: validates the header, the block directory and every
/// block wholly inside the prefix (a block cut by the end of the prefix is ignored until more bytes
/// arrive). Truncated when the header or the directory is cut; TrailingBytes when size exceeds
/// the header's blob_size; otherwise openPfrep's codes for what the prefix holds.
LODRT_API Result openPfrepPrefix(const void* data, size_t size, PfrepModel* model);

/// More bytes arrived: data[0, size) (size >= model->size; data may have moved, the first
/// model->size bytes must be the ones validated before) is validated from the first block not yet
/// loaded. On error *model is unchanged. When the blob becomes complete, the input-triangle count is
/// checked against the header (BadStructure).
LODRT_API Result pfrepExtendPrefix(PfrepModel* model, const void* data, size_t size);

/// Bytes of prefix needed before level `level` (<= removed_count) can be extracted, i.e. before
/// vertex `level` and every higher rank are loaded. Needs only the header and directory (a model
/// from openPfrepPrefix). Returns blob_size for level 0.
LODRT_API uint64_t pfrepPrefixBytesForLevel(const PfrepModel& model, uint32_t level);

/// Bytes of header and block directory, the smallest prefix openPfrepPrefix accepts. `header` must
/// hold kPfrepHeaderSize bytes; 0 when they are not a PFRep header of a supported version.
LODRT_API uint64_t pfrepDirectoryBytes(const void* header, size_t size);

// ---- Format 3 (compressed; docs/format/pfrep.md "Format 3"). ----
// A format 3 blob is the range-coded form of a format 2 blob. It decodes, in one pass, to exactly
// the format 2 bytes it was made from, which then open as any format 2 blob (same extraction and
// refinement, same speed). The decoder treats every byte as hostile: a bad stream gives an error,
// never a read or write outside the buffers given.

struct PfrepCompressedInfo {
    uint32_t vertex_count = 0;
    uint32_t decoded_bytes = 0; // size of the format 2 blob it decodes to
    size_t scratch_bytes = 0;   // scratch pfrepDecompress needs (8-byte aligned)
};

/// Reads the header of a format 3 blob (its first format::kPfrepHeaderSize bytes are enough):
/// Truncated / BadMagic / UnsupportedVersion / BadStructure.
LODRT_API Result pfrepCompressedInfo(const void* data, size_t size, PfrepCompressedInfo* info);

/// Decodes a format 3 blob data[0, size) into out[0, info.decoded_bytes) and opens the result as
/// openPfrep does (the model points into `out`, which must outlive it). `scratch` (8-byte aligned,
/// info.scratch_bytes) is free again on return. BufferTooSmall when a buffer is short;
/// CorruptStream / Truncated on a bad stream; otherwise openPfrep's codes for the decoded blob.
LODRT_API Result pfrepDecompress(const void* data, size_t size, void* out, size_t out_capacity, void* scratch,
                                 size_t scratch_bytes, PfrepModel* model);

// ---- Format 4 (coded against LOD0; docs/format/pfrep.md "Format 4"). ----
// A format 4 blob holds only the removal sequence and the criterion codes; the decoder is given
// LOD0's points and triangles (numbered as the format says), replays the removals and writes a
// format 2 blob with the same levels, fans' triangles, dependencies and records, which then opens
// as any format 2 blob. Every byte (and LOD0) is treated as hostile.

/// LOD0 as a format 4 decoder needs it: point_count points (3 floats each) and triangle_count
/// triangles (3 point ids each, no repeated point).
struct PfrepLod0 {
    const float* positions = nullptr;
    uint32_t point_count = 0;
    const uint32_t* triangles = nullptr;
    uint32_t triangle_count = 0;
};

struct PfrepFormat4Info {
    uint32_t vertex_count = 0;
    uint32_t point_count = 0;     // LOD0's points the blob refers to
    uint32_t level0_triangles = 0; // LOD0's triangles
    uint32_t decoded_bytes = 0;   // size of the format 2 blob it decodes to
    size_t scratch_bytes = 0;     // scratch pfrepDecodeFormat4 needs (8-byte aligned)
};

/// Reads the header of a format 4 blob (its first format::kPfrepHeaderSize bytes are enough):
/// Truncated / BadMagic / UnsupportedVersion / BadStructure.
LODRT_API Result pfrepFormat4Info(const void* data, size_t size, PfrepFormat4Info* info);

/// Decodes a format 4 blob data[0, size) against `lod0` into out[0, info.decoded_bytes) and opens
/// the result as openPfrep does. BufferTooSmall for short buffers; BadStructure when lod0 does not
/// match the header or is malformed; CorruptStream / Truncated on a bad stream.
LODRT_API Result pfrepDecodeFormat4(const void* data, size_t size, const PfrepLod0& lod0, void* out,
                                    size_t out_capacity, void* scratch, size_t scratch_bytes, PfrepModel* model);

/// A pack's LOD0 numbered for format 4 (docs/format/pfrep.md "In a glTF pack"), from the mesh its
/// LODBAKE_valence_compression stream decodes to (`positions`: 3 floats per vertex; `indices`: 3
/// per triangle): vertices with bit-identical positions are one point; points are numbered in order
/// of first use by the triangles whose three corners are distinct points, in triangle order; those
/// triangles are LOD0's. Writes the points into `points` (3 * vertex_count floats) and the
/// triangles into `triangles` (3 * triangle_count), and sets *lod0 to them. `scratch` holds
/// pfrepNumberLod0ScratchBytes(vertex_count) bytes (8-byte aligned). BadStructure for an index out
/// of range, BufferTooSmall for short buffers.
LODRT_API size_t pfrepNumberLod0ScratchBytes(uint32_t vertex_count);
LODRT_API Result pfrepNumberLod0(const float* positions, uint32_t vertex_count, const uint32_t* indices,
                                 uint32_t triangle_count, float* points, size_t point_capacity, uint32_t* triangles,
                                 size_t triangle_capacity, void* scratch, size_t scratch_bytes, PfrepLod0* lod0);

/// pfrepNumberLod0 with a format 4 blob's split list applied (docs/format/pfrep.md "Split list"):
/// welded vertices that the list splits are points apart, so a LOD0 whose stream's quantization put
/// several of the blob's points on one position is numbered as the blob was coded. `split` /
/// `split_bytes` as pfrepFormat4SplitList finds them (null / 0: no list, the same as
/// pfrepNumberLod0); same buffers and scratch. CorruptStream / Truncated for a list that does not
/// decode.
LODRT_API Result pfrepNumberLod0Split(const void* split, size_t split_bytes, const float* positions,
                                      uint32_t vertex_count, const uint32_t* indices, uint32_t triangle_count,
                                      float* points, size_t point_capacity, uint32_t* triangles,
                                      size_t triangle_capacity, void* scratch, size_t scratch_bytes, PfrepLod0* lod0);

/// The split list of a format 4 blob data[0, size) (format::kPfrep4FlagSplitPoints): *split points
/// to its bytes, *split_bytes is their count (null / 0 when the blob has none). The header's errors,
/// Truncated when the list does not fit in `size`, CorruptStream when its count is below 5.
LODRT_API Result pfrepFormat4SplitList(const void* data, size_t size, const void** split, size_t* split_bytes);

/// A pack's format 4 blob (LODBAKE_progressive_fans with format 4) is decoded against the
/// LODBAKE_valence_compression stream of the same mesh (LOD0, one primitive): the stream is decoded,
/// numbered by pfrepNumberLod0Split (with the blob's split list), and handed to pfrepDecodeFormat4. `blob` needs its header only for
/// the info. BadStructure when the stream is not a valid one or the blob was coded against another
/// LOD0 (its check differs, or its counts); otherwise the two decoders' results.
struct PfrepPackFormat4Info {
    uint32_t decoded_bytes = 0; // the format 2 blob
    size_t scratch_bytes = 0;   // everything else: LOD0 decoded and numbered, and the decoder's scratch
};
LODRT_API Result pfrepPackFormat4Info(const void* blob, size_t blob_size, const void* lod0_stream, size_t lod0_size,
                                      PfrepPackFormat4Info* info);
LODRT_API Result pfrepDecodePackFormat4(const void* blob, size_t blob_size, const void* lod0_stream, size_t lod0_size,
                                        void* out, size_t out_capacity, void* scratch, size_t scratch_bytes,
                                        PfrepModel* model);

/// Dequantized positions of every vertex (3 floats each) into `out` of `capacity` floats
/// (needs 3 * vertex_count). Vertices not loaded yet get 0.
LODRT_API Result pfrepDecodePositions(const PfrepModel& model, float* out, size_t capacity);

/// Bytes of one instance mask: exactly vertex_count bits, rounded up to whole bytes.
inline size_t pfrepMaskBytes(const PfrepModel& model) { return (size_t(model.vertex_count) + 7) / 8; }

/// Upper bound of the triangles any extraction yields (level0_triangles); use it to size buffers.
inline size_t pfrepMaxTriangles(const PfrepModel& model) { return model.level0_triangles; }
/// Upper bound of the uint32 values a fan extraction yields.
inline size_t pfrepMaxFanValues(const PfrepModel& model) { return size_t(model.level0_triangles) * 4; }

/// The mesh after the first `level` removals (0: full detail; removed_count: coarsest) as an
/// indexed triangle list of vertex ids (3 per triangle). `*triangle_count` receives the count.
/// BufferTooSmall when `capacity` (in triangles) is short; InvalidArgument when level > removed_count;
/// NotLoaded when level < loaded_from.
LODRT_API Result pfrepExtractLevel(const PfrepModel& model, uint32_t level, uint32_t* indices, size_t capacity,
                                   size_t* triangle_count);

/// Same mesh as triangle fans: a sequence of records [n, centre, rim_0 .. rim_n] (n >= 1 triangles:
/// (centre, rim_j, rim_j+1) for j < n). `*value_count` receives the uint32 values written.
LODRT_API Result pfrepExtractLevelFans(const PfrepModel& model, uint32_t level, uint32_t* values, size_t capacity,
                                       size_t* value_count);

// ---- Selective refinement: one bit per vertex per instance, 1 = removed. ----

/// Sets the mask to the full-detail mesh (all zero) or to the coarsest one (ranks < removed_count set).
/// For a prefix, both also set every rank below loaded_from (not loaded = removed); every selective
/// function expects those bits set, and never reads the entry of a vertex below loaded_from.
LODRT_API void pfrepMaskFinest(const PfrepModel& model, uint8_t* mask);
LODRT_API void pfrepMaskCoarsest(const PfrepModel& model, uint8_t* mask);

/// Scratch needed by simplify/insert/refine, in uint32 values (vertex_count; shared by instances).
inline size_t pfrepScratchValues(const PfrepModel& model) { return model.vertex_count; }

/// SimplifyVertex(v): removes v and, recursively, every vertex whose removal created a triangle of
/// v's fan. No-op for never-removed ids or already removed v. InvalidArgument for bad arguments.
LODRT_API Result pfrepSimplifyVertex(const PfrepModel& model, uint8_t* mask, uint32_t vertex, uint32_t* scratch,
                                     size_t scratch_capacity);
/// InsertVertex(v): brings v back and, recursively (lowest rank first), every corner of its visible
/// fan triangles.
LODRT_API Result pfrepInsertVertex(const PfrepModel& model, uint8_t* mask, uint32_t vertex, uint32_t* scratch,
                                   size_t scratch_capacity);

/// The instance's current mesh as a triangle list; visits only entries whose bit is 0.
LODRT_API Result pfrepExtractSelective(const PfrepModel& model, const uint8_t* mask, uint32_t* indices,
                                       size_t capacity, size_t* triangle_count);

/// View-dependent criterion (Hoppe 1997): a vertex is wanted when its bounding sphere meets the
/// view frustum, its normal cone is not entirely back-facing, and its removal error projected at
/// its distance exceeds `pixel_tolerance` pixels. All in the instance's model space.
struct PfrepView {
    float eye[3] = {0, 0, 0};
    float planes[6][4] = {}; // inward frustum planes a x + b y + c z + d >= 0
    float pixels_per_unit_at_distance_one = 1000.0f; // viewport_height / (2 tan(fov / 2))
    float pixel_tolerance = 1.0f;
    /// Hysteresis h in (0, 1] of pfrepRefine: a removed vertex is inserted when its projected error
    /// exceeds pixel_tolerance, a present one is simplified only below pixel_tolerance * h. Values
    /// outside (0, 1] mean 1 (no band).
    float hysteresis = 0.5f;
    /// Hysteresis of the frustum and back-face tests, radians in [0, 0.5]: a present vertex counts as
    /// inside the frustum while its sphere is within this angle (seen from the eye) outside a plane,
    /// and as front-facing while its normal cone widened by this angle is. Insertion uses the
    /// exact tests. Values outside [0, 0.5] (and NaN) mean 0.
    float cull_hysteresis = 0.05f;
    /// Work bound of one pfrepRefine call: it stops starting new operations once this many mask bits
    /// have changed (an operation's closure may exceed it by its own size); the rest continues on
    /// the next call from the mask alone. 0 means no bound.
    uint32_t max_changed_bits = 0;
};

/// Per-vertex data of the criterion, dequantized.
struct PfrepVertexBounds {
    float position[3];
    float radius;
    float error;
    float cone_axis[3];
    float cone_angle; // radians; >= pi / 2 means never back-facing
};
LODRT_API Result pfrepVertexBounds(const PfrepModel& model, uint32_t vertex, PfrepVertexBounds* out);
LODRT_API bool pfrepWanted(const PfrepModel& model, const PfrepView& view, uint32_t vertex);

/// Floats of a criterion table: 8 per vertex (bounding-sphere centre and radius, removal error, normal
/// cone axis) plus one cone-angle byte per vertex, rounded up to floats.
inline size_t pfrepCriterionTableFloats(const PfrepModel& model) {
    return size_t(model.vertex_count) * 8 + (size_t(model.vertex_count) + 3) / 4;
}
/// Fills table[0, capacity) with the dequantized refinement criterion of every loaded vertex and
/// attaches it to *model, so pfrepRefine reads each vertex's criterion from 32 contiguous bytes
/// instead of decoding its record (same values, same decisions, faster: pfrep_bench's refinement,
/// docs/benchmarks.md, "PFRep blobs"). Costs
/// 32.25 bytes per vertex per model, not per instance. InvalidArgument / BufferTooSmall.
LODRT_API Result pfrepAttachCriterionTable(PfrepModel* model, float* table, size_t capacity);

/// One adaptation step of an instance towards `view`, in increasing rank: a present removable vertex
/// is simplified when the criterion fails at tolerance pixel_tolerance * hysteresis AND it fails
/// for every other vertex its SimplifyVertex closure would remove (else nothing changes: the
/// closure would drop a vertex the next step inserts again); a removed vertex whose triangles are
/// visible is inserted when the criterion holds at pixel_tolerance. The band between the two
/// thresholds comes from the criterion alone: no state beyond the |V|-bit mask. Under a fixed view
/// repeated steps converge and then do nothing. Visits only the entries of present vertices.
/// `*changes` receives the number of mask bits changed (0: the mask is a fixed point of this view). With view.max_changed_bits > 0 the step stops
/// early; every operation is a whole SimplifyVertex / InsertVertex closure, so the mask is always a
/// valid (crack-free) refinement, and the next step continues towards the view.
LODRT_API Result pfrepRefine(const PfrepModel& model, const PfrepView& view, uint8_t* mask, uint32_t* scratch,
                             size_t scratch_capacity, size_t* changes);

// ---- Region blocks (docs/format/pfrep.md "Region blocks"). ----
// A region blob holds the format 2 table cut into spatially coherent blocks: block 0 (the root)
// holds the coarsest ranks, every other block a set of ranks of one rank band whose positions are
// near each other. A small directory gives each block's byte range and bounds (a box containing the
// bounding spheres of every vertex whose insertion can need one of its vertices, and the largest
// error of those), so a streamer loads only the blocks a view needs (pfrepRegionBlocksNeeded).
// Loading decodes a block into a caller-owned buffer laid out as the format 2 blob, so extraction
// and refinement run on the format 2 code; the model's `resident` bits say which vertices are
// there. Every byte is treated as hostile.

struct PfrepRegionInfo {
    uint32_t vertex_count = 0;
    uint32_t block_count = 0;
    uint32_t decoded_bytes = 0; // the format 2 buffer pfrepRegionOpen lays the blocks into
    uint64_t open_bytes = 0;    // header, directory and skeleton: the prefix pfrepRegionOpen reads
    uint64_t blob_size = 0;     // the whole region blob
    size_t state_bytes = 0;     // state buffer pfrepRegionOpen needs (8-byte aligned)
};

/// Reads a region blob's header (its first format::kPfrepRegionHeaderSize bytes are enough):
/// Truncated / BadMagic / UnsupportedVersion / BadStructure.
LODRT_API Result pfrepRegionInfo(const void* data, size_t size, PfrepRegionInfo* info);

/// One block of the directory.
struct PfrepRegionBlock {
    uint32_t offset = 0; // byte range in the region blob
    uint32_t size = 0;
    uint32_t vertices = 0;
    float lo[3] = {0, 0, 0}; // bounds (docs/format/pfrep.md "Region blocks")
    float hi[3] = {0, 0, 0};
    float max_error = 0;
};

/// A region blob opened: the directory (copied into the state buffer), the decoded format 2 buffer
/// and the residency. Use `model` for every pfrep function; it changes with each load or eviction.
struct PfrepRegions {
    PfrepModel model;
    const PfrepRegionBlock* blocks = nullptr; // block_count entries (in the state buffer)
    uint32_t block_count = 0;
    uint64_t open_bytes = 0;
    uint64_t blob_size = 0;
    uint64_t loaded_bytes = 0; // open_bytes plus the sizes of the loaded blocks
    const uint8_t* block_loaded = nullptr; // one byte per block, 1 = loaded
    // Internal: the buffers (caller-owned).
    uint8_t* decoded = nullptr;
    uint8_t* state = nullptr;
};

/// Opens data[0, size) (size >= info.open_bytes; only the first open_bytes are read): validates the
/// header, the directory and the skeleton, lays the format 2 header, block directory and entry
/// offsets into `decoded` (info.decoded_bytes, zeroed elsewhere) and sets every vertex non-resident.
/// `state` holds info.state_bytes (8-byte aligned). No block is loaded: load block 0 next. Both
/// buffers must outlive *regions. Truncated / BadMagic / UnsupportedVersion / OutOfBounds /
/// BadStructure / BufferTooSmall; *regions is only written on Ok.
LODRT_API Result pfrepRegionOpen(const void* data, size_t size, void* decoded, size_t decoded_capacity, void* state,
                                 size_t state_bytes, PfrepRegions* regions);

/// Loads block `block` from its bytes (exactly blocks[block].size of them, from the blob at
/// blocks[block].offset): validates its ranks, records and entries and lays them into the decoded
/// buffer. Ok (nothing to do) when it is loaded already; InvalidArgument for a bad index; otherwise
/// openPfrep's codes (BadStructure also for a rank another loaded block holds). On error nothing
/// changes. When every block is loaded the decoded buffer is the format 2 blob, byte for byte.
LODRT_API Result pfrepRegionLoadBlock(PfrepRegions* regions, uint32_t block, const void* bytes, size_t size);

/// Before evicting block `block`, every instance mask must have its vertices removed: this simplifies
/// each present vertex of the block (with its SimplifyVertex closure) in `mask`. `scratch` as for
/// pfrepSimplifyVertex.
LODRT_API Result pfrepRegionReleaseMask(const PfrepRegions& regions, uint32_t block, uint8_t* mask, uint32_t* scratch,
                                        size_t scratch_capacity);

/// Evicts a loaded block (not block 0): its vertices become non-resident and their bytes in the
/// decoded buffer zero. Masks must have been released first (pfrepRegionReleaseMask). A criterion
/// table attached to the model is detached (attach it again).
LODRT_API Result pfrepRegionEvictBlock(PfrepRegions* regions, uint32_t block);

/// The blocks `view` needs (block 0 always): every block whose bounds pass the criterion at the keep
/// threshold (pixel_tolerance * hysteresis, frustum widened by cull_hysteresis). With these blocks
/// resident, every vertex pfrepRefine would insert under this view from the whole blob, and every
/// vertex of its insertion closure, is resident (docs/format/pfrep.md "Region blocks"). Writes up to
/// `capacity` block indices in increasing order; `*count` receives how many are needed
/// (BufferTooSmall when more than capacity).
LODRT_API Result pfrepRegionBlocksNeeded(const PfrepRegions& regions, const PfrepView& view, uint32_t* blocks,
                                         size_t capacity, size_t* count);

} // namespace lodrt
