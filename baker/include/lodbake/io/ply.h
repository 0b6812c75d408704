#pragma once
// PLY (Stanford polygon file format): ascii, binary little and big endian, every scalar type; vertex
// normals, colours and texture coordinates kept, other properties skipped; polygons and triangle
// strips triangulated; Stanford range grids triangulated the way the scanner intends.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Parses a PLY held in memory. `name` is used in messages (normally the path).
Result<LoadedMesh> readPlyFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics);

/// Serialises a mesh as PLY (positions, normals, first UV set as s/t, colours as uchar RGBA).
std::vector<uint8_t> writePlyToMemory(const Mesh& mesh, bool binary);

} // namespace lodbake
