#pragma once
// Decoder for lodbake's compressed mesh format (.lbm, docs/format/valence.md), meshoptimizer
// decodeVertexBuffer style: read the header with valenceReadInfo, allocate the outputs and the
// scratch it asks for, then call valenceDecode. No allocation, no exceptions; every byte of the
// input is treated as hostile (errors are Result codes, never reads or writes out of bounds).

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/format.h"
#include "lodrt/result.h"

namespace lodrt {

/// One entry of the attribute table (format version 7): a UV set, a colour set or the tangents.
struct ValenceAttribute {
    uint32_t kind = 0;       // format::kValenceAttributeUv / Color / Tangent
    uint32_t components = 0; // floats per vertex in the output: UV 2, colour 3 or 4, tangent 4 (xyz, w = +-1)
    uint32_t bits = 0;       // quantization bits per component (tangent: octahedral bits)
    uint32_t predictor = 0;  // UV: format::kValencePredict*; tangent: index of its UV attribute or kValenceNoReference
    uint32_t set = 0;        // TEXCOORD_n / COLOR_n
    float min[4] = {0.0f, 0.0f, 0.0f, 0.0f};  // quantization range per component (UV, colour)
    float size[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    uint32_t bytes = 0;      // range-coded part
    uint32_t raw_bytes = 0;  // raw bit part
};

struct ValenceInfo {
    uint32_t vertex_count = 0;   // decoded vertices
    uint32_t triangle_count = 0; // decoded triangles
    uint32_t closed_vertex_count = 0;   // coded vertices: decoded ones, their cut copies and dummy vertices
    uint32_t closed_triangle_count = 0; // coded triangles: decoded ones and the dummy triangles closing holes
    uint32_t position_bits = 0; // quantization bits per coordinate
    uint32_t normal_bits = 0;   // octahedral bits per component; 0 when the stream has no normals
    bool has_normals = false;
    float bounds_min[3] = {0.0f, 0.0f, 0.0f}; // corner of the quantization cube
    float cube_size = 0.0f;                   // edge length of the quantization cube
    uint32_t connectivity_bytes = 0;
    uint32_t position_bytes = 0;
    uint32_t normal_bytes = 0;
    uint32_t position_raw_bytes = 0; // raw bit part after the position range-coded part
    uint32_t normal_raw_bytes = 0;
    uint32_t version = 0;
    uint32_t attribute_count = 0; // entries of `attributes` in use (0 for a version 6 stream)
    uint32_t twin_bytes = 0;      // position twin part (0: the stream codes no twins)
    uint32_t twin_shift = 0;      // twin grid cell: 2^twin_shift quantized units
    ValenceAttribute attributes[format::kValenceMaxAttributes];
};

/// Parses and validates the header (magic, version, bit depths, counts, that the stream lengths add
/// up to exactly `size`). Does not decode the streams.
LODRT_API Result valenceReadInfo(const uint8_t* data, size_t size, ValenceInfo* info);

/// Bytes of scratch valenceDecode needs (the conquest's corner table, active lists, the position plan
/// and quantized attributes; about 57 bytes per closed vertex plus 88 per closed triangle, plus 13 per
/// vertex and 32 more with normals; with an attribute table 16 more per closed vertex, 4 per vertex
/// and coded attribute component, 32 per vertex with tangents; with twins 13 to 21 more per closed
/// vertex and 4 per vertex), a multiple of 8.
LODRT_API size_t valenceScratchSize(const ValenceInfo& info);

/// Caller-owned buffers. Capacities are in elements of the pointed-to type.
struct ValenceOutput {
    uint32_t* indices = nullptr; // 3 * triangle_count
    size_t index_capacity = 0;
    float* positions = nullptr; // 3 * vertex_count, xyz
    size_t position_capacity = 0;
    float* normals = nullptr; // 3 * vertex_count when has_normals; may be null to skip them
    size_t normal_capacity = 0;
    /// attributes[i]: info.attributes[i].components * vertex_count floats, or null to skip writing it
    /// (it is still decoded and checked).
    float* attributes[format::kValenceMaxAttributes] = {};
    size_t attribute_capacity[format::kValenceMaxAttributes] = {};
    void* scratch = nullptr; // valenceScratchSize bytes, aligned to 8
    size_t scratch_size = 0;
};

/// Decodes the whole stream. On any error the outputs hold unspecified (but in-bounds) values.
LODRT_API Result valenceDecode(const uint8_t* data, size_t size, const ValenceOutput& output);

/// Octahedral mapping shared by the encoder and the decoder: unit vector <-> two integers in
/// [0, 2^bits - 1].
LODRT_API void octahedralEncode(const float n[3], uint32_t bits, uint32_t out[2]);
LODRT_API void octahedralDecode(const uint32_t in[2], uint32_t bits, float n[3]);

} // namespace lodrt
