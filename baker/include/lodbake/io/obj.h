#pragma once
// Wavefront OBJ with MTL: groups, materials (usemtl/mtllib), map_Kd textures, negative indices,
// polygons (triangulated), per-vertex colours ("v x y z r g b").

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Parses an OBJ held in memory. `name` is the OBJ's path: it prefixes every message, and side files
/// named by mtllib (relative to the OBJ's folder) and by map_* (relative to the MTL's folder) are
/// requested from `load_side_file` as paths joined to its folder.
///
/// Result: one GPU vertex per distinct (v, vt, vn) triple, numbered by position index and then by
/// first use (a file without vt/vn keeps its vertex order); positions no face uses are kept. vt is
/// flipped to the glTF convention (v' = 1 - v). Vertex colours ("v x y z r g b [a]", 0..1, or 0..255
/// when any component exceeds 1) are sRGB and converted to linear. Polygons are triangulated
/// (quads on the shorter valid diagonal, larger ones by ear clipping). Faces are grouped into one
/// SubMesh per material, in order of first use, each a contiguous range; `submeshes` stays empty when
/// no usemtl is used. MTL → Material: see the mapping table at the top of obj.cpp (Kd, d/Tr, Ke, Ns,
/// Pr, Pm, map_Kd, map_Bump/bump/norm with -bm, map_Ke). SourceInfo: file_vertex_count = `v`
/// statements, file_face_count = `f` statements, face_kind "triangles" or "polygons", encoding "ascii".
///
/// Errors (InvalidInput unless noted), one line "<name>: line N: <statement>: <expected>":
/// no `v` statements; index 0 or out of range (negative indices are relative); non-numeric or
/// non-finite numbers; faces with fewer than 3 corners; a statement keyword that is not plain text;
/// lines over 1 MiB; polygons over ReadOptions::max_polygon_vertices; usemtl naming a material no
/// MTL defines; an MTL or texture that cannot be read (names the MTL line and the file); a malformed
/// MTL ("<name>: <mtl> line N: ..."). More than ReadOptions::max_vertex_count vertices or
/// max_face_count triangles: ResourceLimit.
/// Diagnostics: skipped l/p statements (one note), ignored statements, w coordinates, corners
/// without vt (set to 0,0) or vn (normals dropped), vertices without colour, fan fallbacks.
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
/// Writes v (with sRGB "r g b" when the mesh has colours; alpha is not representable), vt from the
/// first UV set (flipped back), vn, then per sub-mesh "usemtl" and "f v/vt/vn" with one shared index.
/// Numbers use the shortest text that reads back exactly, so output is deterministic and positions
/// round-trip bit-exactly. Textures with bytes become "<base_name>_<texture index>.<png|jpg|...>";
/// textures without bytes are referenced by their uri. Sub-meshes without a material, when others
/// have one, use a stand-in white material "lodbake_default". Tangents and extra UV sets are dropped.
ObjFiles writeObjToMemory(const Mesh& mesh, const std::string& base_name);

} // namespace lodbake
