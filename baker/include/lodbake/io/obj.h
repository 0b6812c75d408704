#pragma once
// Wavefront OBJ with MTL: groups, materials (usemtl/mtllib), map_Kd textures, negative indices,
// polygons (triangulated), per-vertex colours ("v x y z r g b").

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// How an OBJ reader opens its side files (MTL, textures): given a path relative to the OBJ's folder
/// resolved against it, returns the bytes or an error. readMesh() passes a loader that reads files.
using SideFileLoader = std::function<Result<std::vector<uint8_t>>(const std::string& path)>;

Result<LoadedMesh> readObjFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const SideFileLoader& load_side_file, const ReadOptions& options,
                                     Diagnostics& diagnostics);

/// Files that make up an OBJ export: the .obj text, the .mtl text (empty if no materials) and
/// textures to write beside them (relative name → bytes).
struct ObjFiles {
    std::string obj_text;
    std::string mtl_text;
    std::string mtl_name; // file name referenced by mtllib
    std::vector<std::pair<std::string, std::vector<uint8_t>>> textures;
};

/// `base_name` is the output file name without extension (used for mtllib and texture names).
ObjFiles writeObjToMemory(const Mesh& mesh, const std::string& base_name);

} // namespace lodbake
