#pragma once
// Files written or read a buffer at a time, for data larger than memory (the out-of-core bake and
// the generated scans). Every error names the path.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake::ooc {

/// A file written sequentially through a buffer of its own, to a temporary in the destination's
/// folder that commit() renames into place. Destroyed without commit() (an error, a cancel), it
/// removes the temporary, so a failed run never leaves a partial file. The temporary is registered
/// with the signal cleanup (lodbake/core/temp_files.h) while it exists. A failed write (a full disk)
/// is an IoError naming the final path.
class StreamingFile {
public:
    StreamingFile() = default;
    StreamingFile(const StreamingFile&) = delete;
    StreamingFile& operator=(const StreamingFile&) = delete;
    ~StreamingFile();

    /// Creates the temporary for `path`; `buffer_bytes` of memory are held until commit().
    Status open(const std::string& path, size_t buffer_bytes = size_t(1) << 20);
    Status write(const void* data, size_t size);
    /// Flushes, closes and renames the temporary to the path given to open().
    Status commit();
    /// Removes the temporary (also done by the destructor); the path keeps what it had before.
    void discard();

    uint64_t bytesWritten() const { return written_; }
    const std::string& path() const { return path_; }

private:
    std::string path_, temp_;
    int fd_ = -1;
    int slot_ = -1;
    std::vector<uint8_t> buffer_;
    size_t used_ = 0;
    uint64_t written_ = 0;
    Status flush();
};

/// Writes all of `data` to the open descriptor `fd` (retrying short writes); the error names `path`.
Status writeAll(int fd, const void* data, size_t size, const std::string& path);

/// Appends `data` to the file at `path` (created if missing): open, write, close.
Status appendToFile(const std::string& path, const void* data, size_t size);

/// Reads exactly `size` bytes at `offset` of the open descriptor `fd`; a short file is an error
/// naming `path`.
Status readAt(int fd, uint64_t offset, void* data, size_t size, const std::string& path);

} // namespace lodbake::ooc
