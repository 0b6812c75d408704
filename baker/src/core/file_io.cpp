#include "lodbake/core/file_io.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <sys/stat.h>
#include <unistd.h>

#include "lodbake/core/temp_files.h"

namespace lodbake {

namespace fs = std::filesystem;

namespace {

std::string errnoText() { return std::strerror(errno); }

template <class Bytes> Result<Bytes> readWholeFile(const std::string& path, uint64_t max_size_bytes) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return ioError(path + ": cannot open: " + errnoText());
    if (S_ISDIR(st.st_mode)) return ioError(path + ": is a directory, expected a file");
    FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) return ioError(path + ": cannot open: " + errnoText());
    Bytes bytes;
    if (S_ISREG(st.st_mode)) {
        if (uint64_t(st.st_size) > max_size_bytes) {
            std::fclose(f);
            return resourceLimit(path + ": file is " + std::to_string(st.st_size) + " bytes, over the limit of " +
                                 std::to_string(max_size_bytes));
        }
        bytes.resize(size_t(st.st_size));
        size_t got = bytes.empty() ? 0 : std::fread(bytes.data(), 1, bytes.size(), f);
        if (got != bytes.size()) {
            std::fclose(f);
            return ioError(path + ": read " + std::to_string(got) + " of " + std::to_string(bytes.size()) + " bytes");
        }
    } else {
        // A pipe or device: read in chunks up to the limit.
        uint8_t chunk[65536];
        size_t got;
        while ((got = std::fread(chunk, 1, sizeof(chunk), f)) > 0) {
            bytes.insert(bytes.end(), chunk, chunk + got);
            if (bytes.size() > max_size_bytes) {
                std::fclose(f);
                return resourceLimit(path + ": input is over the limit of " + std::to_string(max_size_bytes) + " bytes");
            }
        }
    }
    std::fclose(f);
    return bytes;
}

} // namespace

Result<std::vector<uint8_t>> readFileBytes(const std::string& path, uint64_t max_size_bytes) {
    return readWholeFile<std::vector<uint8_t>>(path, max_size_bytes);
}

Result<FileBytes> readLargeFile(const std::string& path, uint64_t max_size_bytes) {
    return readWholeFile<FileBytes>(path, max_size_bytes);
}

AtomicFileWriter::~AtomicFileWriter() { discard(); }

void AtomicFileWriter::discard() {
    for (const Staged& s : staged_) {
        std::remove(s.temp_path.c_str());
        unregisterTempFile(s.registry_slot);
    }
    staged_.clear();
}

namespace {

// The temporary sits in the destination folder so the final rename never crosses file systems.
// Its name starts with '.' and ends in the process id and a per-process counter so concurrent
// bakes, and concurrent writers of one process, do not collide.
std::string stagingPath(const std::string& path) {
    static std::atomic<uint64_t> counter{0};
    const std::string dir = parentDirectory(path);
    const std::string base = fs::path(path).filename().string();
    return joinPath(dir, "." + base + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter.fetch_add(1)));
}

} // namespace

Status AtomicFileWriter::addFile(const std::string& path,
                                 const std::function<Status(const std::string& temp_path)>& write) {
    const std::string temp = stagingPath(path);
    const int slot = registerTempFile(temp);
    const Status s = write(temp);
    if (!s.ok()) {
        std::remove(temp.c_str());
        unregisterTempFile(slot);
        return s;
    }
    staged_.push_back({temp, path, slot});
    return Status();
}

Status AtomicFileWriter::add(const std::string& path, const void* data, size_t size) {
    // Registered before it is created so that a signal (installTempFileSignalCleanup) removes it.
    const std::string temp = stagingPath(path);
    const int slot = registerTempFile(temp);
    FILE* f = std::fopen(temp.c_str(), "wb");
    if (!f) {
        unregisterTempFile(slot);
        return ioError(path + ": cannot write: " + errnoText());
    }
    const bool wrote = size == 0 || std::fwrite(data, 1, size, f) == size;
    const bool closed = std::fclose(f) == 0;
    if (!wrote || !closed) {
        const std::string err = errnoText();
        std::remove(temp.c_str());
        unregisterTempFile(slot);
        return ioError(path + ": write failed: " + err);
    }
    staged_.push_back({temp, path, slot});
    return Status();
}

Status AtomicFileWriter::commit() {
    for (size_t i = 0; i < staged_.size(); ++i) {
        if (std::rename(staged_[i].temp_path.c_str(), staged_[i].final_path.c_str()) != 0) {
            const std::string err = errnoText();
            // Files renamed so far stay (they are complete); the rest are removed by discard().
            staged_.erase(staged_.begin(), staged_.begin() + long(i));
            const std::string failed = staged_.front().final_path;
            discard();
            return ioError(failed + ": cannot move into place: " + err);
        }
        unregisterTempFile(staged_[i].registry_slot);
    }
    staged_.clear();
    return Status();
}

Status writeFileAtomic(const std::string& path, const void* data, size_t size) {
    AtomicFileWriter w;
    LODBAKE_RETURN_IF_ERROR(w.add(path, data, size));
    return w.commit();
}

std::string parentDirectory(const std::string& path) { return fs::path(path).parent_path().string(); }

std::string joinPath(const std::string& dir, const std::string& name) {
    if (dir.empty()) return name;
    return (fs::path(dir) / name).string();
}

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

bool isSameFile(const std::string& a, const std::string& b) {
    std::error_code ec;
    const bool same = fs::equivalent(a, b, ec);
    return !ec && same;
}

} // namespace lodbake
