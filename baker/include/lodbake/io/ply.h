#pragma once
// PLY (Stanford polygon file format): ascii, binary little and big endian, every scalar type; vertex
// normals, colours and texture coordinates kept, other properties skipped; polygons and triangle
// strips triangulated; Stanford range grids triangulated the way the scanner intends.
//
// Conventions of the reader (the writer inverts them):
// - Header: `comment` and `obj_info` lines are accepted anywhere; stray `bye` lines (found in some
//   Stanford dragon range scans) are ignored with a note; CRLF line ends are accepted.
// - Vertex properties used: x y z (required, any scalar type), nx ny nz (normalised), colours
//   red/green/blue[/alpha] (also diffuse_red..., r/g/b/a), texture coordinates s/t, u/v, texture_u/
//   texture_v or texture_s/texture_t. Anything else, and every element other than vertex, face,
//   tristrips and range_grid, is skipped.
// - Colours: colour channels are sRGB-encoded in the file (uchar 0..255, other integer types over
//   their full range, float/double as 0..1) and stored linear in Mesh::colors; alpha is linear.
//   uchar values round-trip exactly through writePlyToMemory.
// - Texture coordinates: PLY's v points up (OpenGL convention); Mesh::uvs[0] uses glTF's, where
//   (0,0) is the image's top-left, so the reader stores v' = 1 - v and the writer writes 1 - v'.
// - Faces (`element face`, list `vertex_indices` or `vertex_index`): triangles as they are; quads
//   split on the diagonal that stays inside; larger polygons ear-clipped in their best-fit plane
//   (fan if the outline self-intersects); faces with fewer than 3 vertices dropped with a warning.
// - `element tristrips`: a -1 restarts the strip; odd triangles are flipped to keep the winding
//   of the strip; triangles with a repeated vertex (strip turns) are dropped.
// - `element range_grid` with `obj_info num_cols` / `num_rows`: a row-major grid of cells holding 0
//   or 1 vertex index. A grid square with 4 samples gives 2 triangles split on its shorter diagonal,
//   one with 3 samples gives 1 triangle. The grid spacing is the larger of the median distances
//   between neighbouring samples along rows and along columns; triangles with an edge longer than
//   ReadOptions::range_grid_max_edge_factor × spacing (bridges across depth jumps) are dropped.
//   Triangles face the scanner. This reproduces the derived files in the shared scan set (the
//   same triangles with the same winding).
//
// SourceInfo: encoding "ascii" / "binary_little_endian" / "binary_big_endian"; file_vertex_count
// is the vertex element's count; file_face_count counts faces, strips or grid cells as the file has
// them; face_kind is "polygons", "tristrips", "range_grid" or "none" (a point cloud).
//
// Errors (InvalidInput unless said otherwise) are one line "<name>: <element>: <what>", e.g.
// "scan.ply: face 12: vertex index 99 out of range (80 vertices)". Counts are checked against the
// bytes present and against ReadOptions limits (ResourceLimit) before anything is allocated.
// Rejected: wrong magic, missing end_header or format, unknown types or keywords, negative counts,
// missing x/y/z, zero vertices ("no vertices"), truncated bodies, non-numeric or out-of-range ascii
// values, non-integer indices, indices out of range, NaN/Inf coordinates (naming the vertex),
// polygons larger than ReadOptions::max_polygon_vertices.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/io/mesh_io.h"

namespace lodbake {

/// Parses a PLY held in memory. `name` is used in messages (normally the path). Notes and warnings
/// (ignored `bye` lines, trailing bytes, dropped short faces, incomplete attribute sets) go to
/// `diagnostics`.
Result<LoadedMesh> readPlyFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                     const ReadOptions& options, Diagnostics& diagnostics);

/// Serialises a mesh as PLY: binary_little_endian when `binary`, else ascii (floats in their
/// shortest exact text). Writes float x,y,z; float nx,ny,nz if normals; float s,t from uvs[0] (v
/// flipped back to PLY's v-up) if present; uchar red,green,blue,alpha (linear → sRGB bytes) if
/// colours; faces as `list uchar int vertex_indices`. Sub-meshes and materials are not written.
/// The output depends only on the mesh (no timestamps), so equal meshes give equal bytes.
/// Precondition: the mesh passes checkMeshConsistency().
std::vector<uint8_t> writePlyToMemory(const Mesh& mesh, bool binary);

} // namespace lodbake
