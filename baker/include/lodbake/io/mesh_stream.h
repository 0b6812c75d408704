#pragma once
// Streaming mesh readers: PLY (ascii, binary little and big endian) and OBJ read a window of the file
// at a time and hand out vertex positions and triangles in bounded chunks, so a scan larger than
// memory can be read. Memory is the window (StreamReadOptions::buffer_bytes, grown only for a single
// record or line longer than it, up to max_record_bytes) plus one chunk of each kind; never the file.
//
// A face may name any vertex of the file (PLY faces index the vertex element, which may be anywhere),
// so the reader does not resolve positions for faces: it makes two passes, one per kind. The caller
// that needs positions per triangle keeps what it needs from the vertex pass (the out-of-core
// partitioner keeps one small cell number per vertex and spills positions to a file,
// lodbake/ooc/partition.h). Reading the file twice is cheaper than any random access to it.
//
// What the streaming readers deliver, and how it differs from readMesh():
// - Positions only (x y z as floats), in file order; vertex ids are their order in the file.
// - Triangles as three vertex ids. Triangles stay as they are; a polygon of n > 3 corners becomes
//   the fan (0, i, i + 1), since choosing a diagonal needs positions (readMesh splits quads on the
//   shorter valid diagonal and ear-clips larger polygons); faces with fewer than 3 corners are
//   dropped (counted in StreamInfo::short_faces). For a triangle mesh in PLY, or in OBJ without vt
//   or vn corners (readMesh makes one vertex per distinct v/vt/vn triple), readMesh() and the stream
//   give the same positions and the same triangles in the same order.
// - PLY: `element face` with a `vertex_indices` (or `vertex_index`) list; other elements are skipped.
//   Triangle strips and range grids need positions to triangulate and are refused (Unsupported).
// - OBJ: `v` statements are the vertices and `f`/`fo` corners their (resolved) position indices;
//   texture coordinates, normals, materials and groups are checked for syntax but not delivered.
//
// Errors are those of the in-memory readers, one line "<name>: <element>: <what was expected>",
// plus "<name>: <element> N: record longer than ... bytes" for a record that does not fit
// max_record_bytes. A sink returning an error stops the pass with that error (a cancel).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake {

struct StreamReadOptions {
    size_t buffer_bytes = size_t(4) << 20;      // the file window
    size_t max_record_bytes = size_t(16) << 20; // the window grows up to this for one long record or line
    size_t vertex_chunk = 65536;                // positions per VertexChunkSink call (at most)
    size_t triangle_chunk = 65536;              // triangles per TriangleChunkSink call (at most)
    uint32_t max_polygon_vertices = 1024;       // larger polygons are refused (ResourceLimit)
};

/// `count` positions with ids first .. first + count - 1.
using VertexChunkSink = std::function<Status(uint64_t first, const Vec3f* positions, size_t count)>;
/// `count` triangles (3 vertex ids each) numbered first .. first + count - 1 in stream order.
using TriangleChunkSink = std::function<Status(uint64_t first, const uint32_t* corners, size_t count)>;

struct StreamInfo {
    MeshFormat format = MeshFormat::Unknown;
    std::string encoding;            // "ascii", "binary_little_endian", "binary_big_endian"
    uint64_t vertex_count = 0;       // PLY: from the header; OBJ: known after the vertex pass
    uint64_t face_records = 0;       // faces as stored; PLY: from the header; OBJ: after the vertex pass
    uint64_t triangle_estimate = 0;  // triangles the faces make (exact once a pass over faces has run)
    uint64_t short_faces = 0;        // faces with fewer than 3 corners, dropped (after the triangle pass)
};

class MeshStreamReader {
public:
    virtual ~MeshStreamReader() = default;
    virtual const StreamInfo& info() const = 0;
    /// One pass over the vertex positions, in order. Also checks every vertex record.
    virtual Status forEachVertexChunk(const VertexChunkSink& sink) = 0;
    /// One pass over the triangles, in order. Also checks every face record (indices in range).
    virtual Status forEachTriangleChunk(const TriangleChunkSink& sink) = 0;
};

/// Opens `path` (.ply or .obj, by extension) for streaming; reads and checks the PLY header at once.
Result<std::unique_ptr<MeshStreamReader>> openMeshStream(const std::string& path, const StreamReadOptions& options,
                                                         Diagnostics& diagnostics);

/// The same over bytes in memory (tests and the fuzz target: the window logic is the same, a small
/// buffer_bytes exercises it). `data` must outlive the reader; `name` is used in messages.
Result<std::unique_ptr<MeshStreamReader>> openMeshStreamFromMemory(const uint8_t* data, size_t size,
                                                                   const std::string& name, MeshFormat format,
                                                                   const StreamReadOptions& options,
                                                                   Diagnostics& diagnostics);

} // namespace lodbake
