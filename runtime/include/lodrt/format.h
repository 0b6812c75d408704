#pragma once
// Every on-disk constant and record layout shared by the baker's encoders and the runtime's decoders
// (STYLE.md §2). The specs in docs/format/ are normative; a change here changes them too.

#include <cstdint>

namespace lodrt {
namespace format {

// glTF binary container (glTF 2.0 spec, "GLB File Format Specification").
constexpr uint32_t kGlbMagic = 0x46546C67u;     // "glTF" little-endian
constexpr uint32_t kGlbVersion = 2;
constexpr uint32_t kGlbChunkJson = 0x4E4F534Au; // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942u;  // "BIN\0"
constexpr uint32_t kGlbHeaderSize = 12;
constexpr uint32_t kGlbChunkHeaderSize = 8;

// PFRep progressive fans (docs/format/pfrep.md). Little-endian; all offsets are byte offsets from the
// start of the blob. Vertex ids are removal ranks: vertex i is the i-th vertex removed by the
// half-edge-collapse sequence, ids >= removed_count are never removed.
constexpr uint32_t kPfrepMagic = 0x31524650u; // "PFR1"
constexpr uint32_t kPfrepVersion = 1;
constexpr uint32_t kPfrepHeaderSize = 64;
// Header fields (byte offset: type):
//   0 u32 magic, 4 u32 version, 8 u32 vertex_count, 12 u32 removed_count, 16 u32 block_shift,
//   20 u32 level0_triangles, 24 f32[3] position_min, 36 f32[3] position_step,
//   48 f32 error_unit, 52 u32 vertex_records_offset, 56 u32 offset_table_offset, 60 u32 entries_offset.
constexpr uint32_t kPfrepVertexRecordSize = 10; // u16 q[3], u8 radius, u8 error, u16 cone
constexpr uint32_t kPfrepMaxBlockShift = 8;
constexpr uint32_t kPfrepStreamPadding = 16;    // zero bytes after the entry stream (64-bit bit reads)
constexpr uint32_t kPfrepMaxVertices = 0x40000000u;
// Entry bit fields (LSB first): neighbour count (6 bits, 63 = 63 + next 16 bits), dependency count
// (3 bits, 7 = 7 + next 16 bits), has_original (1), neighbour width (5), dependency width (5, only
// when dependencies > 0).
constexpr uint32_t kPfrepCountBits = 6;
constexpr uint32_t kPfrepDependencyCountBits = 3;
constexpr uint32_t kPfrepCountEscapeBits = 16;
constexpr uint32_t kPfrepWidthBits = 5;
// Log-scale codes: value(code) = 0 for code 0, else error_unit * 2^((code - 1) / 8).
constexpr uint32_t kPfrepLogCodeSteps = 8;
// Compressed mesh (.lbm), docs/format/valence.md. Little-endian header of kValenceHeaderSize bytes,
// then the connectivity, position and normal range-coded streams, back to back.
constexpr uint32_t kValenceMagic = 0x4D42424Cu; // "LBBM" little-endian
constexpr uint16_t kValenceVersion = 1;
constexpr uint32_t kValenceHeaderSize = 48;
constexpr uint16_t kValenceFlagNormals = 1u;
constexpr uint32_t kValenceMinPositionBits = 8;
constexpr uint32_t kValenceMaxPositionBits = 16;
constexpr uint32_t kValenceMinNormalBits = 4;
constexpr uint32_t kValenceMaxNormalBits = 16;
constexpr uint32_t kValenceMaxCount = 1u << 28; // vertex and triangle counts
// Header plausibility: counts above these multiples of their stream's byte length are refused.
constexpr uint32_t kValenceTrianglesPerByte = 128; // of the connectivity stream
constexpr uint32_t kValenceVerticesPerByte = 64;   // of the position stream (and of the normal stream)
// Binary range coder (LZMA style): 11-bit probabilities, adaptation shift 5, 32-bit range.
constexpr uint32_t kRangeProbBits = 11;
constexpr uint32_t kRangeProbInit = 1u << (kRangeProbBits - 1);
constexpr uint32_t kRangeAdaptShift = 5;
constexpr uint32_t kRangeTopValue = 1u << 24;
// Connectivity model: a FIFO of recent edges and a move-to-front cache of recent vertices.
constexpr uint32_t kValenceEdgeFifo = 32;   // edge symbol 0..31 = FIFO slot, 32 = no shared edge
constexpr uint32_t kValenceVertexFifo = 32; // vertex symbol 0 = new, 1..32 = cache slot + 1, 33 = explicit
constexpr uint32_t kValenceSymbolTreeBits = 6; // edge and vertex symbols are 6-bit trees
constexpr uint32_t kValenceVertexSymbolNew = 0;
constexpr uint32_t kValenceVertexSymbolExplicit = kValenceVertexFifo + 1;
// Integer coding: the bit length class k (0..32) of value+1 as a 6-bit tree, then k low bits.
constexpr uint32_t kValenceClassTreeBits = 6;
constexpr uint32_t kValenceResidualContexts = 18; // previous class of the same component, clamped

} // namespace format
} // namespace lodrt
