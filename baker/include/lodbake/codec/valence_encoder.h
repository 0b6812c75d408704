#pragma once
// Encoder of the .lbm compressed mesh (docs/format/valence.md); runtime/include/lodrt/valence.h
// decodes it.
//
// What is coded: triangles (lossless as index triples over the decoded vertex order; each triangle
// possibly rotated cyclically, which keeps its orientation; triangles are reordered), positions
// quantized in the bounding cube, optional octahedral normals, every UV set (quantized in its own
// square range, predicted from the positions across the mesh; a UV seam is a cut in the coded
// connectivity, so a prediction never crosses it), the colours (RGB or RGBA, own range per channel,
// parallelogram prediction) and the tangents (octahedral, predicted from the UV gradient, handedness
// from the UV orientation). Sub-meshes are coded as separate streams by the pack. Any triangle soup is accepted: non-manifold and
// inconsistently oriented parts are cut into manifold pieces (vertex copies, recorded in the stream so
// that the decoder merges them back), which costs bits but loses nothing.
//
// Connectivity: Touma-Gotsman valence-driven conquest with the Alliez-Desbrun focus choice and
// adaptive context range coding; positions: multi-parallelogram prediction; normals: predicted from the
// face normals of the decoded geometry. See docs/format/valence.md.

#include <cstdint>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake::codec {

struct ValenceEncodeOptions {
    uint32_t position_bits = 14; // 8..16
    bool encode_normals = true;  // when the mesh has normals
    uint32_t normal_bits = 10;   // octahedral bits per component, 4..16
    bool encode_attributes = true; // UV sets, colours and tangents, when the mesh has them
    uint32_t uv_bits = 12;       // per component, 4..16
    uint32_t color_bits = 8;     // per channel, 4..16
    uint32_t tangent_bits = 10;  // octahedral bits per component, 4..16
    /// A quantization cube shared by several streams (the pages of LODBAKE_cluster_lod, so a vertex
    /// two pages share decodes to one float): when cube_size > 0, positions are quantized in the cube
    /// at cube_min of edge cube_size instead of the mesh's own bounds; a vertex outside it fails.
    float cube_min[3] = {0, 0, 0};
    float cube_size = 0;
};

/// One coded attribute of an encoded stream.
struct ValenceAttributeReport {
    uint32_t kind = 0; // lodrt::format::kValenceAttributeUv / Color / Tangent
    uint32_t set = 0;  // UV set / colour set index
    uint32_t bits = 0;
    size_t bytes = 0;  // its range-coded and raw bit parts
    /// Largest |decoded - input| over its components (tangent: over the xyz of the unit vector).
    double max_error = 0.0;
};

struct ValenceEncodeResult {
    std::vector<uint8_t> bytes;
    /// new_vertex_of[old] = decoded index of input vertex `old` (a permutation of all vertices,
    /// unreferenced ones included).
    std::vector<uint32_t> new_vertex_of;
    /// old_face_of[new] = input face decoded as triangle `new`.
    std::vector<uint32_t> old_face_of;
    size_t connectivity_bytes = 0;
    size_t position_bytes = 0;
    size_t normal_bytes = 0;
    size_t header_bytes = 0; // the header and, with attributes, their table
    std::vector<ValenceAttributeReport> attributes; // in stream order
    size_t cut_vertex_copies = 0; // vertex copies the manifold cut made (merged back by the decoder)
    size_t dummy_vertices = 0;    // one per boundary loop of the cut mesh
    size_t twin_decisions = 0;    // boundary vertices with a twin candidate (0 without twins)
    size_t twin_vertices = 0;     // vertices that take their twin's position instead of coding one
    /// Largest |decoded - input| over all position coordinates (the quantization error).
    double max_position_error = 0.0;
};

/// Fails (InvalidInput) on inconsistent meshes, non-finite positions, or counts above 2^28; fails
/// (InvalidInput) on bit depths out of range. Deterministic: the same mesh and options give the same
/// bytes.
Result<ValenceEncodeResult> encodeValence(const Mesh& mesh, const ValenceEncodeOptions& options = {});

/// Decodes with the runtime decoder into a baker Mesh (positions, normals, UV sets, colours, tangents,
/// one triangle list).
/// `name` prefixes error messages.
Result<Mesh> decodeValence(const std::vector<uint8_t>& bytes, const std::string& name);

} // namespace lodbake::codec
