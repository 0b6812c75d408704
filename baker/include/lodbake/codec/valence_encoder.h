#pragma once
// Encoder of the .lbm compressed mesh (docs/format/valence.md); runtime/include/lodrt/valence.h
// decodes it.
//
// What is coded: triangles (lossless as index triples over the decoded vertex order, each triangle
// possibly rotated cyclically, which keeps its orientation; triangles may be reordered), positions
// quantized in the bounding cube, optional octahedral normals. UV sets, colours, tangents and
// sub-meshes are NOT coded (the CLI warns). Any triangle soup is accepted: non-manifold and
// inconsistently oriented input costs more bits but needs no cutting and no duplicated vertices.
//
// Status: connectivity is coded with an edge-FIFO coder over a vertex-cache-optimized triangle order
// (each triangle names a recently seen edge and its apex: a new vertex, a cached one or an explicit
// back-reference), not yet with Touma-Gotsman valence conquest; see docs/format/valence.md
// "Limitations".

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
