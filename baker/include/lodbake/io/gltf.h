#pragma once
// glTF 2.0 / GLB import and export (via tinygltf; Draco for KHR_draco_mesh_compression). tinygltf
// and Draco types never appear in this header (STYLE.md §2).

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Imports every triangle primitive of every mesh instanced by the default scene (or every mesh
/// when there is no scene), applying node transforms, as one flattened mesh with one sub-mesh per
/// primitive. Accepts KHR_draco_mesh_compression and KHR_mesh_quantization. `load_side_file` opens
/// external buffers and images relative to `name` (URIs percent-decoded; data: URIs decoded).
///
/// - Strips and fans are triangulated; points and lines are skipped with a note.
/// - Normals use the inverse transpose of the node matrix; mirrored nodes flip the winding and the
///   tangent handedness. Primitives of one mesh that share their attribute accessors share vertices.
/// - Images are kept encoded (Texture::bytes + mime_type), one Texture per glTF texture.
/// - Streams missing from some primitives are filled (normals zero, tangents +X, colours white,
///   UVs zero); texture slots whose UV set is missing are dropped with a warning.
/// - Every accessor, buffer view and index is bounds-checked; errors are one line naming the element,
///   e.g. `x.glb: mesh "Rock" primitive 0: accessor 3 (POSITION): vertex 12 is not finite (NaN or Inf)`.
/// - SourceInfo: encoding "glb"/"gltf" (+ "+draco"); file_vertex_count sums the distinct POSITION
///   accessors read, file_face_count the triangles of each distinct primitive.
Result<LoadedMesh> readGltfFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                      const SideFileLoader& load_side_file, const ReadOptions& options,
                                      Diagnostics& diagnostics);

/// Reads a glTF document as a scene graph (LoadedScene, mesh_io.h) when its default scene instances
/// two or more mesh nodes with triangles; otherwise returns `flat` = readGltfFromMemory(). Meshes are
/// read once each, untransformed; nodes keep their names, their transforms as written, their children
/// and their mesh (-1 when the mesh has no triangle primitive). Same checks and messages as
/// readGltfFromMemory.
Result<LoadedScene> readGltfSceneFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                            const SideFileLoader& load_side_file, const ReadOptions& options,
                                            Diagnostics& diagnostics);

struct GltfWriteOptions {
    bool binary = true;   // GLB (true) or .gltf JSON with a side .bin
    std::string bin_name; // .gltf only: name of the side buffer file (written percent-encoded)
};

/// Files that make up a glTF export: the main file and, for .gltf, the side buffer.
struct GltfFiles {
    std::vector<uint8_t> main;
    std::vector<uint8_t> bin; // empty for GLB
};

/// Serialises a mesh as glTF 2.0 that passes the Khronos validator with no errors or warnings: one
/// node, one mesh, one primitive per non-empty sub-mesh over shared vertex streams, indices 16-bit
/// below 65536 vertices, images (PNG/JPEG only; others dropped) embedded in the buffer. Normals and
/// tangents are renormalised (zero ones rebuilt from the faces), colours clamped to [0,1]; the bytes
/// are deterministic. Refuses meshes without triangles or with non-finite positions/UVs.
Result<GltfFiles> writeGltfToMemory(const Mesh& mesh, const GltfWriteOptions& options);

} // namespace lodbake

