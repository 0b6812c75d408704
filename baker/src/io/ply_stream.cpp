// The streaming PLY reader (lodbake/io/mesh_stream.h). The header is parsed, and every body value
// read, by the code the in-memory reader uses (io/ply_format.h); what differs is that the body is
// walked through a window of the file, record by record: a record that runs out of window is read
// again from its start once the window has moved on, so no record is ever half-consumed.
#include <limits>
#include <memory>
#include <vector>

#include "io/ply_format.h"
#include "io/ply_stream.h"
#include "io/stream_window.h"

namespace lodbake::detail {

namespace {

using namespace ply_detail;

constexpr uint64_t kUnknownOffset = std::numeric_limits<uint64_t>::max();
constexpr size_t kHeaderWindow = size_t(1) << 20;

class PlyStreamReader final : public MeshStreamReader {
public:
    PlyStreamReader(std::unique_ptr<ByteSource> source, std::string name, const StreamReadOptions& options,
                    Diagnostics& diagnostics)
        : source_(std::move(source)), name_(std::move(name)), options_(options), diagnostics_(diagnostics) {}

    Status open();
    const StreamInfo& info() const override { return info_; }
    Status forEachVertexChunk(const VertexChunkSink& sink) override;
    Status forEachTriangleChunk(const TriangleChunkSink& sink) override;

private:
    std::unique_ptr<ByteSource> source_;
    std::string name_;
    StreamReadOptions options_;
    Diagnostics& diagnostics_;
    Header header_;
    size_t vertex_element_ = 0;
    std::vector<int> index_prop_;           // per element: the face list property, -1 for none
    std::vector<uint64_t> element_offset_;  // per element: file offset of its first record, when known
    StreamInfo info_;

    // Reads `el`'s records one by one; `record(ri, at_end, need_more)` parses one from the cursor and
    // sets need_more when the window ended inside it (not at the end of the file).
    template <class F> Status readRecords(size_t ei, StreamWindow& window, BodyCursor& cursor, F&& record);
    Status moveToElement(size_t ei, StreamWindow& window, BodyCursor& cursor);
    Status skipProperty(const Element& el, const Property& p, uint64_t ri, bool at_end, BodyCursor& cursor,
                        bool& need_more);
    Status skipRecord(const Element& el, uint64_t ri, bool at_end, BodyCursor& cursor, bool& need_more);
    Status readIndexList(const Element& el, const Property& p, uint64_t ri, bool at_end, BodyCursor& cursor,
                         std::vector<uint32_t>& poly, bool& need_more);
    std::string recordName(const Element& el, uint64_t ri, const Property& p) const {
        return name_ + ": " + el.name + " " + std::to_string(ri) + " property '" + p.name + "': ";
    }
};

Status PlyStreamReader::open() {
    std::vector<uint8_t> head(size_t(std::min<uint64_t>(source_->size(), kHeaderWindow)));
    LODBAKE_RETURN_IF_ERROR(source_->read(0, head.data(), head.size()));
    LODBAKE_ASSIGN_OR_RETURN(header_, parseHeader(head.data(), head.size(), name_, diagnostics_));
    ReadOptions limits;
    limits.max_vertex_count = std::numeric_limits<uint32_t>::max(); // vertex ids are 32-bit
    LODBAKE_ASSIGN_OR_RETURN(vertex_element_, findVertexElement(header_, name_, limits));
    if (source_->size() > std::numeric_limits<size_t>::max()) return resourceLimit(name_ + ": file too large");
    LODBAKE_RETURN_IF_ERROR(checkBodyHoldsCounts(header_, size_t(source_->size()), name_));
    info_.format = MeshFormat::Ply;
    info_.encoding = encodingName(header_.encoding);
    info_.vertex_count = header_.elements[vertex_element_].count;
    index_prop_.assign(header_.elements.size(), -1);
    element_offset_.assign(header_.elements.size() + 1, kUnknownOffset);
    element_offset_[0] = header_.body_offset;
    for (size_t ei = 0; ei < header_.elements.size(); ++ei) {
        const Element& el = header_.elements[ei];
        int prop = el.findProperty("vertex_indices");
        if (prop < 0) prop = el.findProperty("vertex_index");
        const bool has_list = prop >= 0 && el.properties[size_t(prop)].is_list;
        if ((el.name == "tristrips" || el.name == "range_grid") && has_list && el.count > 0)
            return unsupported(name_ + ": element " + el.name +
                               ": the streaming reader reads faces only (strips and range grids need positions "
                               "to triangulate; read the file whole)");
        if (el.name != "face") continue;
        if (!has_list) {
            diagnostics_.warn(name_ + ": element face: no 'vertex_indices' list; element skipped");
            continue;
        }
        if (!isIntegerType(el.properties[size_t(prop)].value_type))
            return invalidInput(name_ + ": header: element face property '" + el.properties[size_t(prop)].name +
                                "': vertex indices must be integers");
        index_prop_[ei] = prop;
        info_.face_records += el.count;
    }
    info_.triangle_estimate = info_.face_records;
    // Elements of fixed-size binary records can be stepped over without reading them.
    for (size_t ei = 0; ei < header_.elements.size() && header_.encoding != Encoding::Ascii; ++ei) {
        const Element& el = header_.elements[ei];
        for (const Property& p : el.properties)
            if (p.is_list) return Status();
        element_offset_[ei + 1] = element_offset_[ei] + el.count * minRecordBytes(el, header_.encoding);
    }
    return Status();
}

template <class F>
Status PlyStreamReader::readRecords(size_t ei, StreamWindow& window, BodyCursor& cursor, F&& record) {
    const Element& el = header_.elements[ei];
    for (uint64_t ri = 0; ri < el.count; ++ri) {
        for (;;) {
            const size_t start = cursor.position();
            bool need_more = false;
            LODBAKE_RETURN_IF_ERROR(record(ri, window.atEnd(), need_more));
            if (!need_more) break;
            const Status moved = window.advance(start);
            if (!moved.ok())
                return moved.code() == StatusCode::ResourceLimit
                           ? resourceLimit(name_ + ": " + el.name + " " + std::to_string(ri) + ": " + moved.message())
                           : moved;
            cursor.reset(window.data(), window.exposed(), 0);
        }
    }
    element_offset_[ei + 1] = window.fileOffset(cursor.position());
    return Status();
}

Status PlyStreamReader::skipProperty(const Element& el, const Property& p, uint64_t ri, bool at_end,
                                     BodyCursor& cursor, bool& need_more) {
    double count = 1;
    ReadError e = ReadError::None;
    ScalarType t = p.value_type;
    if (p.is_list) {
        e = cursor.read(p.count_type, count);
        if (e != ReadError::None) t = p.count_type;
        if (e == ReadError::None && count < 0)
            return invalidInput(recordName(el, ri, p) + "negative list count " + std::to_string(int64_t(count)));
    }
    if (e == ReadError::None) e = cursor.skip(p.value_type, uint64_t(count));
    if (e == ReadError::End && !at_end) {
        need_more = true;
        return Status();
    }
    if (e != ReadError::None) return invalidInput(recordName(el, ri, p) + describeError(e, cursor, t));
    return Status();
}

Status PlyStreamReader::skipRecord(const Element& el, uint64_t ri, bool at_end, BodyCursor& cursor, bool& need_more) {
    for (const Property& p : el.properties) {
        LODBAKE_RETURN_IF_ERROR(skipProperty(el, p, ri, at_end, cursor, need_more));
        if (need_more) return Status();
    }
    return Status();
}

// The vertex index list of face `ri`, with the in-memory reader's checks: polygon size limit, a
// count the rest of the file can hold, every index in range.
Status PlyStreamReader::readIndexList(const Element& el, const Property& p, uint64_t ri, bool at_end,
                                      BodyCursor& cursor, std::vector<uint32_t>& poly, bool& need_more) {
    auto more = [&](ReadError e) {
        need_more = e == ReadError::End && !at_end;
        return need_more;
    };
    double count_d = 0;
    ReadError e = cursor.read(p.count_type, count_d);
    if (more(e)) return Status();
    if (e != ReadError::None) return invalidInput(recordName(el, ri, p) + describeError(e, cursor, p.count_type));
    if (count_d < 0) return invalidInput(recordName(el, ri, p) + "negative list count " + std::to_string(int64_t(count_d)));
    const uint64_t count = uint64_t(count_d);
    if (count > options_.max_polygon_vertices)
        return resourceLimit(recordName(el, ri, p) + "polygon has " + std::to_string(count) +
                             " vertices, more than the limit of " + std::to_string(options_.max_polygon_vertices));
    for (uint64_t k = 0; k < count; ++k) {
        double v = 0;
        e = cursor.read(p.value_type, v);
        if (more(e)) return Status();
        if (e != ReadError::None) return invalidInput(recordName(el, ri, p) + describeError(e, cursor, p.value_type));
        if (v < 0 || v >= double(info_.vertex_count))
            return invalidInput(name_ + ": " + el.name + " " + std::to_string(ri) + ": vertex index " +
                                std::to_string(int64_t(v)) + " out of range (" + std::to_string(info_.vertex_count) +
                                " vertices)");
        poly.push_back(uint32_t(v));
    }
    return Status();
}

Status PlyStreamReader::moveToElement(size_t ei, StreamWindow& window, BodyCursor& cursor) {
    size_t known = ei;
    while (element_offset_[known] == kUnknownOffset) --known; // element 0's offset is always known
    LODBAKE_RETURN_IF_ERROR(window.start(element_offset_[known]));
    cursor.reset(window.data(), window.exposed(), 0);
    for (size_t k = known; k < ei; ++k) {
        const Element& el = header_.elements[k];
        LODBAKE_RETURN_IF_ERROR(readRecords(k, window, cursor, [&](uint64_t ri, bool at_end, bool& need_more) {
            return skipRecord(el, ri, at_end, cursor, need_more);
        }));
    }
    return Status();
}

Status PlyStreamReader::forEachVertexChunk(const VertexChunkSink& sink) {
    StreamWindow window(*source_, options_.buffer_bytes, options_.max_record_bytes,
                        header_.encoding == Encoding::Ascii ? StreamWindow::Cut::Tokens : StreamWindow::Cut::Bytes);
    BodyCursor cursor(nullptr, 0, 0, header_.encoding);
    LODBAKE_RETURN_IF_ERROR(moveToElement(vertex_element_, window, cursor));
    const Element& el = header_.elements[vertex_element_];
    int slot[3];
    for (int k = 0; k < 3; ++k) slot[k] = el.findProperty(k == 0 ? "x" : k == 1 ? "y" : "z");
    std::vector<Vec3f> chunk;
    chunk.reserve(std::max<size_t>(1, options_.vertex_chunk));
    uint64_t first = 0;
    auto record = [&](uint64_t vi, bool at_end, bool& need_more) -> Status {
        double xyz[3] = {0, 0, 0};
        for (size_t pi = 0; pi < el.properties.size(); ++pi) {
            const Property& p = el.properties[pi];
            ReadError e = ReadError::None;
            ScalarType t = p.value_type;
            if (p.is_list) {
                double count = 0;
                t = p.count_type;
                e = cursor.read(p.count_type, count);
                if (e == ReadError::None && count < 0)
                    return invalidInput(name_ + ": vertex " + std::to_string(vi) + " property '" + p.name +
                                        "': negative list count");
                if (e == ReadError::None) {
                    t = p.value_type;
                    e = cursor.skip(p.value_type, uint64_t(count));
                }
            } else if (int(pi) == slot[0] || int(pi) == slot[1] || int(pi) == slot[2]) {
                e = cursor.read(p.value_type, xyz[int(pi) == slot[0] ? 0 : int(pi) == slot[1] ? 1 : 2]);
            } else {
                e = cursor.skip(p.value_type, 1);
            }
            if (e == ReadError::End && !at_end) {
                need_more = true;
                return Status();
            }
            if (e != ReadError::None)
                return invalidInput(name_ + ": vertex " + std::to_string(vi) + " property '" + p.name +
                                    "': " + describeError(e, cursor, t));
        }
        const Vec3f pos{float(xyz[0]), float(xyz[1]), float(xyz[2])};
        if (!isFinite(pos))
            return invalidInput(name_ + ": vertex " + std::to_string(vi) + ": coordinate is not finite (" +
                                std::to_string(pos.x) + ", " + std::to_string(pos.y) + ", " + std::to_string(pos.z) +
                                ")");
        chunk.push_back(pos);
        if (chunk.size() == chunk.capacity()) {
            LODBAKE_RETURN_IF_ERROR(sink(first, chunk.data(), chunk.size()));
            first += chunk.size();
            chunk.clear();
        }
        return Status();
    };
    LODBAKE_RETURN_IF_ERROR(readRecords(vertex_element_, window, cursor, record));
    if (!chunk.empty()) LODBAKE_RETURN_IF_ERROR(sink(first, chunk.data(), chunk.size()));
    return Status();
}

Status PlyStreamReader::forEachTriangleChunk(const TriangleChunkSink& sink) {
    StreamWindow window(*source_, options_.buffer_bytes, options_.max_record_bytes,
                        header_.encoding == Encoding::Ascii ? StreamWindow::Cut::Tokens : StreamWindow::Cut::Bytes);
    BodyCursor cursor(nullptr, 0, 0, header_.encoding);
    TriangleChunker chunker(sink, options_.triangle_chunk);
    std::vector<uint32_t> poly;
    uint64_t short_faces = 0;
    for (size_t ei = 0; ei < header_.elements.size(); ++ei) {
        if (index_prop_[ei] < 0) continue;
        LODBAKE_RETURN_IF_ERROR(moveToElement(ei, window, cursor));
        const Element& el = header_.elements[ei];
        auto record = [&](uint64_t ri, bool at_end, bool& need_more) -> Status {
            poly.clear();
            for (size_t pi = 0; pi < el.properties.size(); ++pi) {
                const Property& p = el.properties[pi];
                if (int(pi) != index_prop_[ei]) {
                    LODBAKE_RETURN_IF_ERROR(skipProperty(el, p, ri, at_end, cursor, need_more));
                    if (need_more) return Status();
                    continue;
                }
                LODBAKE_RETURN_IF_ERROR(readIndexList(el, p, ri, at_end, cursor, poly, need_more));
                if (need_more) return Status();
            }
            if (poly.size() < 3) {
                ++short_faces;
                return Status();
            }
            return chunker.addPolygon(poly);
        };
        LODBAKE_RETURN_IF_ERROR(readRecords(ei, window, cursor, record));
    }
    LODBAKE_RETURN_IF_ERROR(chunker.finish());
    info_.triangle_estimate = chunker.triangles();
    info_.short_faces = short_faces;
    if (short_faces > 0)
        diagnostics_.warn(name_ + ": face: " + std::to_string(short_faces) + " faces with fewer than 3 vertices dropped");
    return Status();
}

} // namespace

Result<std::unique_ptr<MeshStreamReader>> openPlyStream(std::unique_ptr<ByteSource> source, const std::string& name,
                                                        const StreamReadOptions& options, Diagnostics& diagnostics) {
    auto reader = std::make_unique<PlyStreamReader>(std::move(source), name, options, diagnostics);
    LODBAKE_RETURN_IF_ERROR(reader->open());
    return std::unique_ptr<MeshStreamReader>(std::move(reader));
}

} // namespace lodbake::detail
