#pragma once
// Every on-disk constant and record layout shared by the baker's encoders and the runtime's decoders
// (STYLE.md §2). The specs in docs/format/ are normative; a change here changes them too.

#include <cstdint>

namespace lodrt {
namespace format {

// glTF binary container (glTF 2.0 spec, "GLB File Format Specification").
constexpr uint32_t kGlbMagic = 0x46546C67u; // "glTF" little-endian
constexpr uint32_t kGlbVersion = 2;
constexpr uint32_t kGlbChunkJson = 0x4E4F534Au; // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942u;  // "BIN\0"
constexpr uint32_t kGlbHeaderSize = 12;
constexpr uint32_t kGlbChunkHeaderSize = 8;

// glTF extension names. The LODBAKE_ ones are specified in schemas/<name>/; MSFT_lod is
// https://github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Vendor/MSFT_lod, whose screen
// coverage array sits in the LOD0 node's extras under kMsftScreenCoverage.
constexpr const char kExtLodMetrics[] = "LODBAKE_lod_metrics";
// LODBAKE_lod_metrics member: the input's triangle count when the MSFT_lod chain starts below the
// input (an out-of-core bake's chain is cut from its cluster hierarchy); levels[0] may then carry
// errors > 0. Absent: levels[0] is the input.
constexpr const char kLodMetricsInputTriangles[] = "inputTriangles";
constexpr const char kExtValenceCompression[] = "LODBAKE_valence_compression";
constexpr const char kExtProgressiveFans[] = "LODBAKE_progressive_fans";
constexpr const char kExtMsftLod[] = "MSFT_lod";
constexpr const char kMsftScreenCoverage[] = "MSFT_screencoverage";
constexpr const char kExtKhrDracoMeshCompression[] = "KHR_draco_mesh_compression";
constexpr const char kExtKhrMeshQuantization[] = "KHR_mesh_quantization";
// The stream extensions lodrt decodes (lodrt/valence.h, lodrt/pfrep.h): a pack may require them.
constexpr const char* const kDecodedStreamExtensions[] = {kExtValenceCompression, kExtProgressiveFans};

// EXT_meshopt_compression (KhronosGroup/glTF extensions/2.0/Vendor/EXT_meshopt_compression): the
// bufferView extension object, its modes and filters, the codec headers and the members of a fallback
// buffer (one with no uri and no data, referenced only by compressed views). docs/format/web.md.
constexpr const char kExtMeshoptCompression[] = "EXT_meshopt_compression";
constexpr const char kMeshoptModeAttributes[] = "ATTRIBUTES";
constexpr const char kMeshoptModeTriangles[] = "TRIANGLES";
constexpr const char kMeshoptModeIndices[] = "INDICES";
constexpr const char kMeshoptFilterNone[] = "NONE";
constexpr const char kMeshoptFilterOctahedral[] = "OCTAHEDRAL";
constexpr const char kMeshoptFilterQuaternion[] = "QUATERNION";
constexpr const char kMeshoptFilterExponential[] = "EXPONENTIAL";
constexpr const char kMeshoptFallback[] = "fallback";
constexpr uint8_t kMeshoptVertexHeader = 0xA0;   // high nibble; low nibble: vertex codec version (0 or 1)
constexpr uint8_t kMeshoptIndexHeader = 0xE0;    // triangle codec; low nibble: version (0 or 1)
constexpr uint8_t kMeshoptSequenceHeader = 0xD0; // index sequence codec; low nibble: version 1
constexpr uint32_t kMeshoptMaxVertexStride = 256;
constexpr uint32_t kMeshoptVertexBlockMax = 8192;  // bytes of one decoded vertex block (all vertices x stride)
constexpr uint32_t kMeshoptVertexGroup = 16;       // vertices per byte group
constexpr uint32_t kMeshoptVertexTail = 32;        // minimal tail (the first vertex; padding) of a vertex stream
// The --web writer: positions on a power-of-two grid at least this fine over the level's largest
// extent (EXPONENTIAL filter), normals and tangents 8-bit octahedral, UVs in [0,1] as unorm16.
constexpr uint32_t kWebPositionBits = 14;
constexpr uint32_t kWebNormalBits = 8;

// PFRep progressive fans (docs/format/pfrep.md). Little-endian; all offsets are byte offsets from the
// start of the blob. Vertex ids are removal ranks: vertex i is the i-th vertex removed by the
// half-edge-collapse sequence, ids >= removed_count are never removed.
constexpr uint32_t kPfrepMagic = 0x31524650u; // "PFR1"
constexpr uint32_t kPfrepVersion = 2;         // 2: blocks stored coarse end first (prefix streaming)
constexpr uint32_t kPfrepHeaderSize = 64;
// Header fields (byte offset: type):
//   0 u32 magic, 4 u32 version, 8 u32 vertex_count, 12 u32 removed_count, 16 u32 block_shift,
//   20 u32 level0_triangles, 24 f32[3] position_min, 36 f32[3] position_step,
//   48 f32 error_unit, 52 u32 blob_size, 56 u32 block_count, 60 u32 zero.
// Then the block directory (block_count u32: byte offset of block b), then the blocks in DECREASING
// b (the coarse end first). Block b (vertices [b << block_shift, ...)): its vertex records, its u16
// entry offsets (relative to its entry stream), its entry stream, kPfrepStreamPadding zero bytes.
constexpr uint32_t kPfrepVertexRecordSize = 10; // u16 q[3], u8 radius, u8 error, u16 cone
constexpr uint32_t kPfrepMaxBlockShift = 8;
constexpr uint32_t kPfrepStreamPadding = 16; // zero bytes after each block's entry stream (64-bit bit reads)
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
// PFRep format 3 (docs/format/pfrep.md "Format 3"): the same header fields as version 2 except
// bytes 52 (the format 2 blob_size it decodes to) and 56 (total_slots: the sum of every entry's n),
// then one range-coded stream (lodrt/detail/pfrep_codec.h) to the end of the blob.
constexpr uint32_t kPfrepVersionCompressed = 3;
// LODBAKE_progressive_fans member naming the blob's format (absent: kPfrepVersion).
constexpr const char kPfrepExtensionFormatMember[] = "format";
// A streamer refuses a format 3 blob in a pack that claims to decode to more than this many times
// its own size (the coder gains about 3x; the bound keeps a lying header from pinning gigabytes).
constexpr uint32_t kPfrepMaxExpansion = 64;
constexpr uint32_t kPfrepMentionSlots = 8;         // latest mentioners of a vertex kept
constexpr uint32_t kPfrepCandidateLimit = 256;     // neighbour candidates of a vertex
constexpr uint32_t kPfrepCandidateScanLimit = 4096; // fan values scanned for them
// PFRep format 4 (docs/format/pfrep.md "Format 4"): the table coded against LOD0's points and
// triangles, which the decoder is given. Header as version 2 except bytes 16 (point_count: LOD0's
// points), 52 (the format 2 blob_size it decodes to) and 56 (stored_triangles), then one
// range-coded stream (lodrt/detail/pfrep_codec4.h) to the end of the blob.
constexpr uint32_t kPfrepVersionLod0 = 4;
// Format 4 header word at offset 60 (flags; other bits must be 0). kPfrep4FlagCodedTail: the ranks
// of the points never removed are coded (a pack's blob, whose LOD0 is numbered on its decoded
// stream) instead of following point ids.
constexpr uint32_t kPfrep4FlagCodedTail = 1;
// kPfrep4FlagLod0Check: the stream starts with a 32-bit check of the LOD0 it was coded against
// (pfrep4Lod0Check), and a decoder given another LOD0 refuses the blob (BadStructure).
constexpr uint32_t kPfrep4FlagLod0Check = 2;
// kPfrep4FlagSplitPoints: a split list follows the header (u32 byte count, then its range-coded
// stream): which points of a pack's LOD0, welded by its stream's quantization, stand for several of
// the blob's points (pfrepNumberLod0Split). Only a pack's blob (with both flags above) sets it.
constexpr uint32_t kPfrep4FlagSplitPoints = 4;
constexpr uint32_t kPfrep4Flags = kPfrep4FlagCodedTail | kPfrep4FlagLod0Check | kPfrep4FlagSplitPoints;
// Format 4 headers claiming more stored triangles than this many times LOD0's are refused (a
// half-edge sequence stores about 2.6 times as many).
constexpr uint32_t kPfrepMaxStoredPerLevel0 = 16;
// PFRep region blocks (docs/format/pfrep.md "Region blocks"): a container of the format 2 table cut
// into spatially coherent blocks. Header of kPfrepRegionHeaderSize bytes, then block_count directory
// records of kPfrepRegionDirectoryRecordSize bytes (u32 offset, u32 size, u32 vertices, f32 lo[3],
// f32 hi[3], f32 max_error), then the skeleton (the format 2 header and one LEB128 entry length per
// vertex), then the blocks back to back (block 0, the root, first).
constexpr uint32_t kPfrepRegionMagic = 0x47524650u; // "PFRG"
constexpr uint32_t kPfrepRegionVersion = 1;
constexpr uint32_t kPfrepRegionHeaderSize = 64;
constexpr uint32_t kPfrepRegionDirectoryRecordSize = 40;
constexpr uint32_t kPfrepRegionMaxBlocks = 1u << 20;
// LODBAKE_progressive_fans `format` value of a region blob in a pack (docs/format/pfrep.md "In a
// glTF pack"): the Streamer loads the blocks the views reported by Streamer::wantPfrepBlocks need.
constexpr uint32_t kPfrepFormatRegions = 5;
// The values the extension's `format` member may take (docs/format/pfrep.md "In a glTF pack").
constexpr bool isPfrepPackFormat(uint64_t f) {
    return f == kPfrepVersion || f == kPfrepVersionCompressed || f == kPfrepVersionLod0 || f == kPfrepFormatRegions;
}
// Compressed mesh (.lbm), docs/format/valence.md. Little-endian header of kValenceHeaderSize bytes,
// then the connectivity, position and normal streams, back to back; the position and normal streams
// each have a range-coded part followed by a raw bit part (the low mantissa bits of the residuals).
constexpr uint32_t kValenceMagic = 0x4D42424Cu; // "LBBM" little-endian
constexpr uint16_t kValenceVersion = 7; // 5: neighbour-coordinate (snap) flags; 6: spread contexts flags;
                                        // 7: attribute table (UV sets, colours, tangents)
// A stream without extra attributes is written as version 6 (the same bytes a version 6 encoder
// writes); decoders accept both. Version 7 requires the attribute table (kValenceFlagAttributes).
constexpr uint16_t kValenceVersionWithoutAttributes = 6;
constexpr uint32_t kValenceHeaderSize = 64;
// Header fields (byte offset: type): 0 u32 magic, 4 u16 version, 6 u16 flags, 8 u32 vertex_count,
// 12 u32 triangle_count, 16 u32 closed_vertex_count, 20 u32 closed_triangle_count, 24 u8 position_bits,
// 25 u8 normal_bits, 26 u16 zero, 28 f32[3] bounds_min, 40 f32 cube_size, 44 u32 connectivity_bytes,
// 48 u32 position_bytes, 52 u32 normal_bytes (range-coded parts), 56 u32 position_raw_bytes,
// 60 u32 normal_raw_bytes (raw bit parts, bits packed least significant first).
constexpr uint16_t kValenceFlagNormals = 1u;
// Flags bits 1..3: position component j (x, y, z) is coded with the neighbour-coordinate flag ("snap"):
// before its residual, one binary decision says whether the coordinate equals the known neighbour
// coordinate nearest the prediction (docs/format/valence.md "Positions"). The encoder sets a bit when
// it makes that component smaller (iso-surface meshes: vertices on grid edges share grid planes).
constexpr uint16_t kValenceFlagSnapX = 2u; // component j: kValenceFlagSnapX << j
// Flags bits 4..6: position component j is coded with spread contexts: a vertex predicted from two or
// more parallelograms reads its residual length in a context of how far those parallelograms disagree
// on the component (docs/format/valence.md "Positions"). Set where it makes the component smaller.
constexpr uint16_t kValenceFlagSpreadX = 16u; // component j: kValenceFlagSpreadX << j
// Flag bit 7 (version 7 only, and required there): an attribute table follows the header: u32 count
// A (1..kValenceMaxAttributes), u32 twin part bytes (0: no twins), u8 twin cell shift (0..16), three
// zero bytes (kValenceAttributeTablePrefix in all), then A records of kValenceAttributeRecordSize bytes:
//   0 u8 kind (kValenceAttribute*), 1 u8 components, 2 u8 bits, 3 u8 predictor (UV) or the index of
//   the UV attribute a tangent is predicted from (kValenceNoReference: none), 4 u16 set (TEXCOORD_n /
//   COLOR_n), 6 u16 zero, 8 f32[4] min, 24 f32[4] size (unused components 0), 40 u32 range-coded
//   bytes, 44 u32 raw bit bytes. Each attribute's two parts follow the normal parts in table order.
constexpr uint16_t kValenceFlagAttributes = 128u;
constexpr uint16_t kValenceKnownFlags = 255u;
constexpr uint32_t kValenceMaxAttributes = 16;
constexpr uint32_t kValenceAttributeRecordSize = 48;
constexpr uint32_t kValenceAttributeTablePrefix = 12;
// Position twins (docs/format/valence.md "Twins"): a range-coded part between the position raw bits
// and the normals, one decision per boundary vertex that has a candidate.
constexpr uint32_t kValenceMaxTwinShift = 16;
constexpr uint32_t kValenceTwinChainLimit = 16; // grid vertices looked at per cell (bounds a hostile stream's time)
constexpr uint32_t kValenceTwinContexts = 18;   // bit length of the candidate's distance from the prediction
constexpr uint32_t kValenceTwinHash[3] = {73856093u, 19349663u, 83492791u}; // cell -> slot multipliers
constexpr uint32_t kValenceTwinMinSlots = 16; // slots: a power of two, at least this and twice Vc
constexpr uint8_t kValenceAttributeUv = 1;      // 2 components, quantized in their own range
constexpr uint8_t kValenceAttributeColor = 2;   // 3 (RGB) or 4 (RGBA) components
constexpr uint8_t kValenceAttributeTangent = 3; // octahedral xyz (2 components) + handedness sign
constexpr uint8_t kValencePredictParallelogram = 0; // UV and colour: mean of the parallelograms
constexpr uint8_t kValencePredictUvGeometric = 1;   // UV: from the positions (docs/format/valence.md)
constexpr uint8_t kValencePredictColorDecorrelated = 2; // colour: parallelogram, channels 1.. coded
                                                        // relative to channel 0's residual
constexpr uint8_t kValencePredictNeighbourMean = 3;     // colour: mean of the triples' a and b
constexpr uint8_t kValencePredictNeighbourMeanDecorrelated = 4; // colour: that, channels as in 2
constexpr uint8_t kValenceNoReference = 255;
constexpr uint32_t kValenceMinAttributeBits = 4;
constexpr uint32_t kValenceMaxAttributeBits = 16;
// Residual length contexts of a UV or colour component: 3 classes of the vertex's parallelogram count
// (0, 1, 2 or more) times 17 lengths (of the previous vertex's residual for component 0, of this
// vertex's earlier components' largest residual for the others), per component.
constexpr uint32_t kValenceAttributeLengths = 17;
constexpr uint32_t kValenceAttributeContexts = 2 * 3 * kValenceAttributeLengths;
constexpr uint32_t kValenceTangentSignContexts = 3; // predicted handedness: +, -, none
constexpr uint32_t kValenceAttributesPerByte = 1024; // vertices per attribute range-coded byte (2 values each at least)
constexpr uint32_t kValenceSnapDistanceBuckets = 16; // bit length of |candidate - prediction|, capped
constexpr uint32_t kValenceSnapMultiplicity = 5;     // 0..4 triple entries holding the candidate value
constexpr uint32_t kValenceSnapContexts = kValenceSnapDistanceBuckets * kValenceSnapMultiplicity;
constexpr uint32_t kValenceMinPositionBits = 8;
constexpr uint32_t kValenceMaxPositionBits = 16;
constexpr uint32_t kValenceMinNormalBits = 4;
constexpr uint32_t kValenceMaxNormalBits = 16;
constexpr uint32_t kValenceMaxCount = 1u << 28; // vertex and triangle counts
// Header plausibility: counts above these multiples of their stream's byte length are refused before
// anything is allocated. A binary decision costs at least -log2(4080/4096) > 0.0056 bits, a value of
// an 18-symbol model at least -log2(32632/32768) > 0.0059 and of a 32-symbol model at least
// -log2(32520/32768) > 0.0109. Every closed vertex costs a 32-symbol value (< 734 per byte) and a
// closed triangle follows a value or closes a node (< 2 per value); every coded position costs three
// 18-symbol values or snap decisions (< 473 per byte), every normal two (< 678 per byte).
constexpr uint32_t kValenceTrianglesPerByte = 2048; // closed triangles per connectivity byte
constexpr uint32_t kValenceVerticesPerByte = 1024;  // closed vertices per connectivity byte
constexpr uint32_t kValencePositionsPerByte = 512;  // vertices per position range-coded byte
constexpr uint32_t kValenceNormalsPerByte = 1024;   // vertices per normal range-coded byte
// Binary range coder (LZMA style, 32-bit range). Each adaptive model holds two estimates of P(bit = 0)
// in 16-bit fixed point, a fast one (low half of a u32, shift 4) and a slow one (high half, shift 6),
// each kept in [256, 65280]; a bit is coded with their sum >> 5, a 12-bit probability in [16, 4080].
constexpr uint32_t kRangeProbBits = 12;
constexpr uint32_t kRangeStateMin = 256;
constexpr uint32_t kRangeStateMax = 65280;
constexpr uint32_t kRangeFastShift = 4;
constexpr uint32_t kRangeSlowShift = 6;
constexpr uint32_t kRangeStateInit = 0x80008000u; // both estimates 1/2
constexpr uint32_t kRangeTopValue = 1u << 24;
// Connectivity symbols: a 5-bit tree per context. 0 = valence escape (then the valence as an integer),
// 1 = split, 2 = merge, 3 = dummy vertex (then its valence as an integer), 4..31 = valence symbol - 1.
constexpr uint32_t kValenceSymbolTreeBits = 5;
constexpr uint32_t kValenceSymbolEscape = 0;
constexpr uint32_t kValenceSymbolSplit = 1;
constexpr uint32_t kValenceSymbolMerge = 2;
constexpr uint32_t kValenceSymbolDummy = 3;
constexpr uint32_t kValenceSymbolFirstValence = 4; // codes valence 3
// Integer coding: the bit length class k (0..32) of value+1 as a 6-bit tree, then k low bits (the top
// one modelled per class, the rest direct).
constexpr uint32_t kValenceClassTreeBits = 6;
// Residual coding: the bit length k of |r| (0..17) as one adaptive multi-symbol value per context
// (kValenceResidualSymbols), then the sign, the two mantissa bits below the leading one modelled per
// length, the rest raw bits.
constexpr uint32_t kValenceResidualTreeBits = 5; // size of the per-length mantissa model tables
// Multi-symbol adaptive models (docs/format/valence.md "Range coder", `symbol`): a cumulative table of
// N entries with total 2^kRangeCdfBits, every symbol at least kRangeCdfMinFreq wide,
// adapted after each use at a rate (shift) that slows down with the model's use count.
constexpr uint32_t kRangeCdfBits = 15;
constexpr uint32_t kValenceResidualSymbols = 18;
constexpr uint32_t kRangeCdfMinFreq = 8;
constexpr uint32_t kRangeCdfRateFirst = 3;            // shift for the first kRangeCdfRateStep uses
constexpr uint32_t kRangeCdfRateLast = 6;             // residual lengths: shift from 2 * kRangeCdfRateStep uses on
constexpr uint32_t kRangeCdfRateLastConnectivity = 7; // connectivity symbols: the same
constexpr uint32_t kRangeCdfRateStep = 16;
constexpr uint32_t kValenceNormalContexts = 17; // bit length of the same component's previous residual

// LODBAKE_cluster_lod (docs/format/cluster_lod.md): a cluster LOD hierarchy on LOD0's mesh. The
// extension object names two buffer views: kClusterTableMember (the table below) and
// kClusterPagesMember (the pages, back to back). Little-endian throughout.
constexpr const char kExtClusterLod[] = "LODBAKE_cluster_lod";
constexpr const char kClusterTableMember[] = "table";
constexpr const char kClusterPagesMember[] = "pages";
constexpr uint32_t kClusterMagic = 0x4C43424Cu; // "LBCL" little-endian
constexpr uint32_t kClusterVersion = 1;
// Table header (byte offset: type): 0 u32 magic, 4 u32 version, 8 u32 cluster_count, 12 u32 group_count,
// 16 u32 group_child_count, 20 u32 root_count, 24 u32 page_count, 28 u32 position_bits (the grid's
// bits, kValenceMinPositionBits..kValenceMaxPositionBits), 32 f32[3] grid_min, 44 f32 grid_size (the
// quantization cube every page's valence header repeats), 48 f32 quantization_error (largest distance
// quantization moves a vertex; included in every group error), 52 u32[3] zero. Then the records:
// clusters, groups, group children (u32 cluster indices), roots (u32 cluster indices), pages.
constexpr uint32_t kClusterHeaderSize = 64;
// Cluster record: 0 f32[3] center, 12 f32 radius (geometry sphere of the decoded triangles), 16 f32[3]
// cone_axis, 28 f32 cone_cutoff (cosine of the normal cone's half angle; <= 0: no cone), 32 u32
// self_group, 36 u32 parent_group (kClusterNoGroup: none), 40 u32 page, 44 u16 first_triangle (in the
// page's cluster-sorted triangles), 46 u8 triangle_count, 47 u8 vertex_count (distinct vertices).
constexpr uint32_t kClusterRecordSize = 48;
// Group record: 0 f32[3] lod_center, 12 f32 lod_radius, 16 f32 error, 20 f32[3] bounds_center, 32 f32
// bounds_radius, 36 u32 first_child, 40 u32 child_count, 44 u32 depth.
constexpr uint32_t kClusterGroupRecordSize = 48;
// Page record: 0 u32 byte_offset (in the pages view), 4 u32 stream_bytes (a valence stream, docs/format/
// valence.md, positions only), 8 u32 run_count (kClusterRunSize-byte runs after the stream), 12 u32
// cluster_count. A run is u8 local cluster (the page's clusters in table order), u8 triangles: the
// decoded triangles in stream order, run after run.
constexpr uint32_t kClusterPageRecordSize = 16;
constexpr uint32_t kClusterRunSize = 2;
constexpr uint32_t kClusterNoGroup = 0xffffffffu;
constexpr uint32_t kClusterMaxTriangles = 128;      // per cluster
constexpr uint32_t kClusterMaxVertices = 255;       // per cluster
constexpr uint32_t kClusterPageMaxClusters = 256;   // per page (a run's u8 cluster)
constexpr uint32_t kClusterPageMaxTriangles = 65535; // per page (a cluster's u16 first_triangle)
constexpr uint32_t kClusterMaxCount = 1u << 26;     // clusters, groups, children, roots, pages

// Out-of-core partition files (baker/include/lodbake/ooc/partition.h): the 8-byte magic that
// starts each, and the extension of their content-hash names.
constexpr char kPartitionMagic[8] = {'L', 'B', 'P', 'A', 'R', 'T', '0', '1'};
constexpr const char kPartitionExtension[] = ".lbpart";
// A partition's cluster hierarchy, written by the partition job (baker/include/lodbake/ooc/
// partition_build.h; layout in docs/pipeline.md, "Partition jobs").
constexpr char kPartitionLodMagic[8] = {'L', 'B', 'P', 'L', 'O', 'D', '0', '1'};
constexpr const char kPartitionLodExtension[] = ".lbplod";
// Two neighbouring hierarchies (partitions' or merges') continued as one, written by the merge job
// (baker/include/lodbake/ooc/partition_merge.h; layout in docs/pipeline.md, "Merge jobs").
constexpr char kPartitionMergeMagic[8] = {'L', 'B', 'P', 'M', 'R', 'G', '0', '1'};
constexpr const char kPartitionMergeExtension[] = ".lbpmrg";
// Fixed sizes in those files (layouts in docs/pipeline.md): a partition file's header (magic, vertex
// and triangle counts, bounds), a hierarchy file's (magic, source hash, 11 counts), a merge file's
// (magic, 2 input hashes, 2 input kinds, 11 counts), and a merge file's record of one LOD0 seed.
constexpr uint32_t kPartitionHeaderBytes = 8 + 8 + 24;
constexpr uint32_t kPartitionLodHeaderBytes = 8 + 8 + 4 * 11;
constexpr uint32_t kPartitionMergeHeaderBytes = 8 + 16 + 8 + 4 * 11;
constexpr uint32_t kMergeSeedRecordBytes = 44;
// The out-of-core job list (baker/include/lodbake/ooc/jobs.h; protocol in docs/pipeline.md, "Job
// list"): the plan in the work folder, each finished job's record (job-<id>.json), and the files the
// pages job writes (the LODBAKE_cluster_lod pages blob and table blob, named by content hash).
constexpr const char kOocPlanFile[] = "plan.json";
constexpr const char kOocJobRecordPrefix[] = "job-";
constexpr const char kOocJobRecordSuffix[] = ".json";
constexpr const char kOocPagesExtension[] = ".lbpages";
constexpr const char kOocTableExtension[] = ".lbtable";

} // namespace format
} // namespace lodrt
