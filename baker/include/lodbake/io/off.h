#pragma once
// Object File Format: OFF, COFF (vertex colours), NOFF (vertex normals), and combinations such as
// CNOFF; polygons triangulated; ascii only (binary OFF is refused with a clear message).

#include <cstdint>
#include <string>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Parses an ascii OFF held in memory; `name` prefixes messages. Keywords [ST][C][N]OFF; the counts
/// may share the keyword's line; '#' comments anywhere; one vertex or face per line. Colours: integer
/// components are 0..255, others 0..1 (Geomview), 3 or 4 components, sRGB converted to linear; ST
/// texture coordinates are flipped to the glTF convention. Per-face colours are skipped (one note).
/// SourceInfo: counts from the header, face_kind "triangles" or "polygons", encoding "ascii".
/// Errors, one line "<name>: <header | vertex N | face N>: <expected>": unknown keyword (4OFF, nOFF
/// and binary OFF: Unsupported); counts that are negative, over ReadOptions limits (ResourceLimit) or
/// larger than the remaining bytes could hold (checked before allocating); wrong value counts,
/// non-numeric or non-finite values; face indices out of range; faces with fewer than 3 or more than
/// max_polygon_vertices corners; a file that ends early. Lines after the last face: a warning.
Result<LoadedMesh> readOffFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics);

/// Serialises positions and triangles as OFF, or COFF with sRGB 0..255 "r g b a" when the mesh has
/// colours. Shortest round-trip float text; deterministic. Normals and UVs are not written.
std::string writeOffToMemory(const Mesh& mesh);

} // namespace lodbake
