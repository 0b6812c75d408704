#pragma once
// File access for the baker: whole-file reads with size limits, and atomic writes so that a failed
// or interrupted run never leaves a partial output file behind.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "lodbake/core/mapped_array.h"
#include "lodbake/core/status.h"

namespace lodbake {

/// Reads a whole file. Errors name the path. Refuses files larger than `max_size_bytes`.
Result<std::vector<uint8_t>> readFileBytes(const std::string& path, uint64_t max_size_bytes = (uint64_t(1) << 34));

/// The bytes of a large file read once and dropped once parsed (the mesh a run loads), on a mapping
/// of their own (core/mapped_array.h). They are the largest short-lived array of a run: freeing them
/// returns the memory at once, and leaves malloc's heap as it was. (glibc adapts its mmap and trim
/// thresholds to the largest mapped block it frees, up to 32 MiB: after that every array below that
/// size would come from its arenas, and up to twice that size of free memory could stay resident in
/// each.)
using FileBytes = detail::MappedArray<uint8_t, detail::MappedPages::Small>;
/// readFileBytes into FileBytes.
Result<FileBytes> readLargeFile(const std::string& path, uint64_t max_size_bytes = (uint64_t(1) << 34));

/// Writes one or more files so that either all appear complete or none does: every file is written
/// to a temporary name in its destination folder first, and renamed only after all writes succeeded.
/// Destructing an uncommitted writer removes its temporaries.
class AtomicFileWriter {
public:
    AtomicFileWriter() = default;
    AtomicFileWriter(const AtomicFileWriter&) = delete;
    AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
    ~AtomicFileWriter();

    /// Stages `data` for `path`. Fails (naming the path) if the temporary cannot be written.
    Status add(const std::string& path, const void* data, size_t size);
    Status add(const std::string& path, const std::vector<uint8_t>& data) { return add(path, data.data(), data.size()); }
    Status add(const std::string& path, const std::string& text) { return add(path, text.data(), text.size()); }

    /// Stages a file that `write` creates at the temporary path it is given (in the folder of `path`,
    /// registered with the signal cleanup), for writers that write their own file (a pack larger than
    /// memory). Fails with write's error, the temporary removed.
    Status addFile(const std::string& path, const std::function<Status(const std::string& temp_path)>& write);

    /// Renames every staged file into place.
    Status commit();

private:
    struct Staged {
        std::string temp_path;
        std::string final_path;
        int registry_slot = -1; // registerTempFile (lodbake/core/temp_files.h)
    };
    std::vector<Staged> staged_;
    void discard();
};

/// Convenience: one file, atomically.
Status writeFileAtomic(const std::string& path, const void* data, size_t size);

/// The directory part of a path ("" for a bare file name), and the path joined to a relative name.
std::string parentDirectory(const std::string& path);
std::string joinPath(const std::string& dir, const std::string& name);
/// Lower-case extension including the dot (".ply"), or "" if none.
std::string lowerExtension(const std::string& path);

/// True if both paths name the same existing file (used to refuse overwriting the input).
bool isSameFile(const std::string& a, const std::string& b);

} // namespace lodbake
