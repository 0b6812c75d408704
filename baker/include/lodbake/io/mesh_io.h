#pragma once
// Reading and writing meshes in every supported file format, chosen by file extension (readers also
// check the magic bytes). Per-format entry points are in ply.h, obj.h, off.h, conf.h and gltf.h; they
// share the plain types declared here.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

enum class MeshFormat { Unknown, Ply, Obj, Off, Gltf, Glb, Conf };

/// Format from the extension (.ply .obj .off .gltf .glb, and .conf for Stanford range-scan sets;
/// case-insensitive); Unknown otherwise. .conf is input only.
MeshFormat formatFromPath(const std::string& path);
const char* formatName(MeshFormat format);

/// Limits and choices for readers. Counts above a limit are refused before anything is allocated.
struct ReadOptions {
    uint64_t max_vertex_count = uint64_t(1) << 28; // refuse files claiming more vertices
    uint64_t max_face_count = uint64_t(1) << 28;   // refuse files claiming more faces (after triangulation)
    uint32_t max_polygon_vertices = 1024;          // refuse polygons (PLY lists, OBJ/OFF faces) larger than this
    uint32_t max_json_depth = 64;                  // glTF: refuse JSON nested deeper than this (arrays and objects)
    double range_grid_max_edge_factor = 4.0;       // range grids: drop triangles with an edge longer than this × median grid spacing
    bool load_textures = true;                     // read referenced texture files into Texture::bytes
};

/// What the file said, before any conversion (for `lodbake info` and for build-system depfiles).
struct SourceInfo {
    MeshFormat format = MeshFormat::Unknown;
    std::string encoding;           // e.g. "binary_little_endian", "ascii", "glb", "draco"
    uint64_t file_vertex_count = 0; // vertices (positions) as stored in the file
    uint64_t file_face_count = 0;   // faces as stored (polygons, strips or grid cells are counted as the file has them)
    std::string face_kind;          // "triangles", "polygons", "tristrips", "range_grid", ...
    std::vector<std::string> files_read; // every file opened, input first (MTL, textures, .bin buffers)
};

struct LoadedMesh {
    Mesh mesh;
    SourceInfo source;
};

/// How a reader opens its side files (OBJ: MTL and textures; glTF: buffers and images): given a path
/// relative to the main file's folder resolved against it, returns the bytes or an error. readMesh()
/// passes a loader that reads files.
using SideFileLoader = std::function<Result<std::vector<uint8_t>>(const std::string& path)>;

/// Loads a file as one flattened mesh (glTF: all triangle primitives, node transforms applied).
/// Errors are one line naming the file, the element and what was expected.
Result<LoadedMesh> readMesh(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics);

/// One node of a scene kept as a graph (glTF): its name, its local transform exactly as the file
/// wrote it (a matrix, or any of translation / rotation / scale), its world transform, its children
/// and the mesh it instances. Two nodes with the same `mesh` instance one mesh.
struct SceneNode {
    std::string name;
    std::vector<double> matrix;      // 16 numbers, column-major, or empty
    std::vector<double> translation; // 3 numbers or empty
    std::vector<double> rotation;    // unit quaternion x, y, z, w, or empty
    std::vector<double> scale;       // 3 numbers or empty
    std::array<double, 16> world{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; // parents' transforms composed
    std::vector<uint32_t> children;  // indices into LoadedScene::nodes
    int32_t mesh = -1;               // index into LoadedScene::meshes, -1 for none
};

/// A file read either as a scene graph or as one flattened mesh. glTF scenes whose default scene
/// instances two or more mesh nodes are kept as a graph: every distinct glTF mesh with triangles in
/// its own (local) space, holding only the materials and textures it uses, and the nodes reachable
/// from the default scene in file order. Everything else (one mesh node, no scene, PLY/OBJ/OFF/.conf)
/// is `flat`, exactly what readMesh() returns.
struct LoadedScene {
    std::vector<Mesh> meshes;
    std::vector<std::string> mesh_names; // the glTF mesh names (may be empty)
    std::vector<SceneNode> nodes;        // empty: not a graph, see `flat`
    std::vector<uint32_t> roots;         // the default scene's nodes
    SourceInfo source;                   // graph only (else flat.source)
    LoadedMesh flat;
    bool isGraph() const { return !nodes.empty(); }
};

/// Reads `path` as a scene (see LoadedScene); formats without a scene graph give `flat`.
Result<LoadedScene> readMeshScene(const std::string& path, const ReadOptions& options, Diagnostics& diagnostics);

struct WriteOptions {
    bool ply_binary = true; // PLY: binary_little_endian (true) or ascii
};

/// Writes `mesh` in the format its extension names, atomically (no partial file on failure). Side
/// files (.mtl, .bin, textures) are written next to it in the same atomic step.
Status writeMesh(const Mesh& mesh, const std::string& path, const WriteOptions& options, Diagnostics& diagnostics);

} // namespace lodbake
