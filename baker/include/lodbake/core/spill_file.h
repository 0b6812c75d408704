#pragma once
// Files written or read a buffer at a time, for data larger than memory (the out-of-core jobs, the
// streamed pack writer's spill and GLB, the generated scans): written sequentially to a temporary
// renamed into place. Every error names the path.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake {

/// A temporary file in the folder of `path` (a dot name derived from it, unique per process and
/// file), written sequentially through a buffer of its own and readable back while it exists.
/// commit() renames it to `path`; destroyed without commit() it is removed, so an error or a cancel
/// leaves nothing behind. Registered with the signal cleanup (lodbake/core/temp_files.h) while it
/// exists. Every error names `path`; a failed write (a full disk) is an IoError.
class SpillFile {
public:
    SpillFile() = default;
    SpillFile(const SpillFile&) = delete;
    SpillFile& operator=(const SpillFile&) = delete;
    ~SpillFile();

    /// Creates the temporary for `path`; `buffer_bytes` (at least 4 KiB) are held until finish().
    Status open(const std::string& path, size_t buffer_bytes = size_t(1) << 20);
    Status write(const void* data, size_t size);
    /// Flushes and frees the buffer; the file keeps its temporary name (readable by copyTo).
    Status finish();
    /// finish(), closes and renames the temporary to the path given to open().
    Status commit();
    /// Removes the temporary (also done by the destructor).
    void discard();

    /// Writes bytes [0, size) of this file (finished) into `out` through `buffer`, whose size is the
    /// piece read at a time (it is resized to 64 KiB when empty). Stops with an IoError naming
    /// `out`'s path when `cancel` is set.
    Status copyTo(SpillFile& out, uint64_t size, std::vector<uint8_t>& buffer,
                  const std::atomic<bool>* cancel) const;

    uint64_t bytesWritten() const { return written_; }
    size_t bufferBytes() const { return buffer_.size(); }
    const std::string& path() const { return path_; }
    const std::string& tempPath() const { return temp_; }

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

} // namespace lodbake
