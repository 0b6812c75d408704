#pragma once
// Files a pack is written through when its bytes should not all be in memory at once
// (docs/pipeline.md, "Streamed pack writer"): the spill that holds a large blob (the cluster pages)
// until the GLB is assembled, and the GLB itself, written sequentially and renamed into place.

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
class PackTempFile {
public:
    PackTempFile() = default;
    PackTempFile(const PackTempFile&) = delete;
    PackTempFile& operator=(const PackTempFile&) = delete;
    ~PackTempFile();

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
    Status copyTo(PackTempFile& out, uint64_t size, std::vector<uint8_t>& buffer,
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

} // namespace lodbake
