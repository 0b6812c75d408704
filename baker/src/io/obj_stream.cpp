// The streaming OBJ reader (lodbake/io/mesh_stream.h): the file is read a window at a time, each
// window cut after a complete logical line, and split into statements by the in-memory reader's
// LineReader and number and corner parsers (io/obj_syntax.h). OBJ indices only reach back, so a
// single pass could resolve faces, but the partitioner needs every position before the first face
// (it derives its grid from them): the reader makes one pass per kind, like the PLY reader.
#include <algorithm>
#include <memory>
#include <vector>

#include "io/obj_syntax.h"
#include "io/ply_stream.h"
#include "io/stream_window.h"

namespace lodbake::detail {

namespace {

using namespace obj;

class ObjStreamReader final : public MeshStreamReader {
public:
    ObjStreamReader(std::unique_ptr<ByteSource> source, std::string name, const StreamReadOptions& options)
        : source_(std::move(source)), name_(std::move(name)), options_(options) {
        info_.format = MeshFormat::Obj;
        info_.encoding = "ascii";
    }

    const StreamInfo& info() const override { return info_; }
    Status forEachVertexChunk(const VertexChunkSink& sink) override;
    Status forEachTriangleChunk(const TriangleChunkSink& sink) override;

private:
    std::unique_ptr<ByteSource> source_;
    std::string name_;
    StreamReadOptions options_;
    StreamInfo info_;

    // Calls statement(key, rest, line_number) for every non-empty logical line of the file.
    template <class F> Status forEachStatement(F&& statement);
    Status fail(uint64_t line, const std::string& what) const {
        return invalidInput(name_ + ": line " + std::to_string(line) + ": " + what);
    }
};

template <class F> Status ObjStreamReader::forEachStatement(F&& statement) {
    // A window must hold the longest logical line the in-memory reader accepts, with room to spare.
    StreamWindow window(*source_, options_.buffer_bytes, std::max(options_.max_record_bytes, 4 * kMaxLineBytes),
                        StreamWindow::Cut::Lines);
    Status started = window.start(0);
    uint64_t lines = 0;
    for (;;) {
        if (!started.ok())
            return started.code() == StatusCode::ResourceLimit
                       ? fail(lines + 1, "longer than " + std::to_string(kMaxLineBytes) + " bytes")
                       : started;
        LineReader reader(window.data(), window.exposed(), lines);
        std::string_view line;
        uint64_t number = 0;
        std::string error;
        while (reader.next(line, number, error)) {
            std::string_view rest = line;
            const std::string_view key = nextToken(rest);
            if (!key.empty()) LODBAKE_RETURN_IF_ERROR(statement(key, rest, number));
        }
        if (!error.empty()) return invalidInput(name_ + ": " + error);
        lines = reader.physicalLines();
        if (window.atEnd()) return Status();
        started = window.advance(window.exposed());
    }
}

Status ObjStreamReader::forEachVertexChunk(const VertexChunkSink& sink) {
    std::vector<Vec3f> chunk;
    chunk.reserve(std::max<size_t>(1, options_.vertex_chunk));
    uint64_t vertices = 0, texcoords = 0, normals = 0, faces = 0, triangles = 0;
    auto statement = [&](std::string_view key, std::string_view rest, uint64_t line) -> Status {
        float t[7];
        size_t n = 0;
        std::string what;
        if (key == "v") {
            what = readObjFloats("v", rest, t, 3, 7, n);
            if (what.empty() && n == 5)
                what = "v: expected 3 (x y z), 4 (x y z w), 6 (x y z r g b) or 7 (x y z r g b a) numbers, got 5";
            if (!what.empty()) return fail(line, what);
            if (vertices == 0xffffffffu)
                return resourceLimit(name_ + ": line " + std::to_string(line) + ": more than 2^32 - 1 vertices");
            chunk.push_back({t[0], t[1], t[2]});
            if (chunk.size() == chunk.capacity()) {
                LODBAKE_RETURN_IF_ERROR(sink(vertices + 1 - chunk.size(), chunk.data(), chunk.size()));
                chunk.clear();
            }
            ++vertices;
        } else if (key == "vt" || key == "vn") {
            what = key == "vt" ? readObjFloats("vt", rest, t, 1, 3, n) : readObjFloats("vn", rest, t, 3, 3, n);
            if (!what.empty()) return fail(line, what);
            ++(key == "vt" ? texcoords : normals);
        } else if (key == "f" || key == "fo") {
            size_t corners = 0;
            while (!nextToken(rest).empty()) ++corners;
            ++faces;
            triangles += corners >= 3 ? corners - 2 : 0;
        } else if (key == "usemtl" || key == "mtllib") {
            if (trim(rest).empty())
                return fail(line, std::string(key) + (key == "usemtl" ? ": expected a material name" : ": expected a file name"));
        } else if (!isPlainKeyword(key)) {
            return fail(line, "expected an OBJ statement, got '" + excerpt(key) + "'");
        }
        return Status();
    };
    LODBAKE_RETURN_IF_ERROR(forEachStatement(statement));
    if (!chunk.empty()) LODBAKE_RETURN_IF_ERROR(sink(vertices - chunk.size(), chunk.data(), chunk.size()));
    if (vertices == 0) return invalidInput(name_ + ": no vertices (no 'v' statements)");
    info_.vertex_count = vertices;
    info_.face_records = faces;
    info_.triangle_estimate = triangles;
    return Status();
}

Status ObjStreamReader::forEachTriangleChunk(const TriangleChunkSink& sink) {
    TriangleChunker chunker(sink, options_.triangle_chunk);
    std::vector<uint32_t> poly;
    uint64_t vertices = 0, texcoords = 0, normals = 0;
    auto statement = [&](std::string_view key, std::string_view rest, uint64_t line) -> Status {
        if (key == "v") ++vertices;
        else if (key == "vt") ++texcoords;
        else if (key == "vn") ++normals;
        if (key != "f" && key != "fo") return Status();
        poly.clear();
        for (std::string_view tok = nextToken(rest); !tok.empty(); tok = nextToken(rest)) {
            if (poly.size() >= options_.max_polygon_vertices)
                return fail(line, "f: polygon has more than " + std::to_string(options_.max_polygon_vertices) +
                                      " vertices (max_polygon_vertices)");
            Corner c;
            const std::string what = parseObjCorner(tok, vertices, texcoords, normals, c);
            if (!what.empty()) return fail(line, what);
            poly.push_back(c.v);
        }
        if (poly.size() < 3) return fail(line, "f: expected at least 3 vertices, got " + std::to_string(poly.size()));
        return chunker.addPolygon(poly);
    };
    LODBAKE_RETURN_IF_ERROR(forEachStatement(statement));
    LODBAKE_RETURN_IF_ERROR(chunker.finish());
    if (vertices == 0) return invalidInput(name_ + ": no vertices (no 'v' statements)");
    info_.vertex_count = vertices;
    info_.triangle_estimate = chunker.triangles();
    return Status();
}

} // namespace

Result<std::unique_ptr<MeshStreamReader>> openObjStream(std::unique_ptr<ByteSource> source, const std::string& name,
                                                        const StreamReadOptions& options, Diagnostics& diagnostics) {
    (void)diagnostics; // nothing in an OBJ's vertices or faces is worth a note that is not an error
    return std::unique_ptr<MeshStreamReader>(std::make_unique<ObjStreamReader>(std::move(source), name, options));
}

} // namespace lodbake::detail
