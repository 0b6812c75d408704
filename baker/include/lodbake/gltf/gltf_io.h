#pragma once
// glTF 2.0 / GLB import and export (via tinygltf; Draco for KHR_draco_mesh_compression). tinygltf
// and Draco types never appear in this header (STYLE.md §2).

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"
#include "lodbake/io/obj.h"

namespace lodbake {

/// Imports every triangle primitive of every mesh instanced by the default scene (or every mesh
/// when there is no scene), applying node transforms, as one flattened mesh with one sub-mesh per
/// primitive. Accepts KHR_draco_mesh_compression and KHR_mesh_quantization. `load_side_file` opens
/// external buffers and images relative to `name`.
Result<LoadedMesh> readGltfFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                      const SideFileLoader& load_side_file, const ReadOptions& options,
                                      Diagnostics& diagnostics);

struct GltfWriteOptions {
    bool binary = true;          // GLB (true) or .gltf JSON with a side .bin
    std::string bin_name;        // .gltf only: name of the side buffer file
};

/// Files that make up a glTF export: the main file and, for .gltf, the side buffer.
struct GltfFiles {
    std::vector<uint8_t> main;
    std::vector<uint8_t> bin; // empty for GLB
};

/// Serialises a mesh as glTF 2.0 that passes the Khronos validator with no errors or warnings.
Result<GltfFiles> writeGltfToMemory(const Mesh& mesh, const GltfWriteOptions& options);

} // namespace lodbake
