#pragma once
// Object File Format: OFF, COFF (vertex colours), NOFF (vertex normals), and combinations such as
// CNOFF; polygons triangulated; ascii only (binary OFF is refused with a clear message).

#include <cstdint>
#include <string>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

Result<LoadedMesh> readOffFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics);

std::string writeOffToMemory(const Mesh& mesh);

} // namespace lodbake
