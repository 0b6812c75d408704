#pragma once
// Encoder of the .lbm compressed mesh (docs/format/valence.md); runtime/include/lodrt/valence.h
// decodes it.
//
// What is coded: triangles (lossless as index triples over the decoded vertex order; each triangle
// possibly rotated cyclically, which keeps its orientation; triangles are reordered), positions
// quantized in the bounding cube, optional octahedral normals. UV sets, colours, tangents and
// sub-meshes are NOT coded (the CLI warns). Any triangle soup is accepted: non-manifold and
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
    size_t header_bytes = 0;
    size_t cut_vertex_copies = 0; // vertex copies the manifold cut made (merged back by the decoder)
    size_t dummy_vertices = 0;    // one per boundary loop of the cut mesh
    /// Largest |decoded - input| over all position coordinates (the quantization error).
    double max_position_error = 0.0;
};

/// Fails (InvalidInput) on inconsistent meshes, non-finite positions, or counts above 2^28; fails
/// (InvalidInput) on bit depths out of range. Deterministic: the same mesh and options give the same
/// bytes.
Result<ValenceEncodeResult> encodeValence(const Mesh& mesh, const ValenceEncodeOptions& options = {});

/// Decodes with the runtime decoder into a baker Mesh (positions, normals, one triangle list).
/// `name` prefixes error messages.
Result<Mesh> decodeValence(const std::vector<uint8_t>& bytes, const std::string& name);

} // namespace lodbake::codec
