#pragma once
// The window over a file that the streaming readers (ply_stream.cpp, obj_stream.cpp) parse: a buffer
// holding a stretch of the file, of which only a prefix is "exposed" to the parser, cut where no
// token (PLY ascii) or logical line (OBJ) straddles the end, so that running out of exposed bytes
// always means "read more", never a truncated number that happens to parse.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"
#include "lodbake/io/mesh_stream.h"

namespace lodbake::detail {

/// Bytes of a file (read with pread) or of a buffer in memory.
class ByteSource {
public:
    ByteSource() = default;
    ByteSource(const ByteSource&) = delete;
    ByteSource& operator=(const ByteSource&) = delete;
    ~ByteSource();

    Status openFile(const std::string& path);
    void openMemory(const uint8_t* data, size_t size);
    uint64_t size() const { return size_; }
    /// Reads exactly `n` bytes at `offset`.
    Status read(uint64_t offset, uint8_t* out, size_t n) const;

private:
    std::string path_;
    int fd_ = -1;
    const uint8_t* memory_ = nullptr;
    uint64_t size_ = 0;
};

class StreamWindow {
public:
    enum class Cut { Bytes, Tokens, Lines };

    StreamWindow(const ByteSource& source, size_t buffer_bytes, size_t max_bytes, Cut cut)
        : source_(source), initial_(buffer_bytes < 64 ? 64 : buffer_bytes), max_(max_bytes), cut_(cut) {}

    /// Starts the window at file offset `offset`.
    Status start(uint64_t offset);
    /// Drops the bytes before `keep` and reads more, until more bytes are exposed than were left or
    /// the file ends. ResourceLimit when one record needs more than max_bytes (the message is the
    /// caller's to complete: it knows the element).
    Status advance(size_t keep);

    const uint8_t* data() const { return buffer_.data(); }
    size_t exposed() const { return exposed_; }
    /// True once the exposed bytes reach the end of the file.
    bool atEnd() const { return base_ + exposed_ == source_.size(); }
    uint64_t fileOffset(size_t pos) const { return base_ + pos; }
    size_t capacity() const { return buffer_.size(); }

private:
    const ByteSource& source_;
    size_t initial_, max_;
    Cut cut_;
    std::vector<uint8_t> buffer_;
    uint64_t base_ = 0; // file offset of buffer_[0]
    size_t valid_ = 0;
    size_t exposed_ = 0;
    size_t boundary() const;
};

/// The streaming readers' triangles, handed to the sink in chunks of a fixed number of triangles:
/// polygons are fanned from their first corner; finish() hands over the last, shorter chunk.
class TriangleChunker {
public:
    TriangleChunker(const TriangleChunkSink& sink, size_t chunk_triangles)
        : sink_(sink), chunk_triangles_(chunk_triangles < 1 ? 1 : chunk_triangles) {
        chunk_.reserve(chunk_triangles_ * 3);
    }
    Status addPolygon(const std::vector<uint32_t>& corners) {
        for (size_t k = 1; k + 1 < corners.size(); ++k) {
            chunk_.insert(chunk_.end(), {corners[0], corners[k], corners[k + 1]});
            ++triangles_;
            if (chunk_.size() == chunk_triangles_ * 3) LODBAKE_RETURN_IF_ERROR(flush());
        }
        return Status();
    }
    Status finish() { return chunk_.empty() ? Status() : flush(); }
    uint64_t triangles() const { return triangles_; }

private:
    Status flush() {
        const size_t count = chunk_.size() / 3;
        LODBAKE_RETURN_IF_ERROR(sink_(first_, chunk_.data(), count));
        first_ += count;
        chunk_.clear();
        return Status();
    }
    const TriangleChunkSink& sink_;
    size_t chunk_triangles_;
    std::vector<uint32_t> chunk_;
    uint64_t first_ = 0, triangles_ = 0;
};

} // namespace lodbake::detail
