#include "lodbake/core/spill_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/temp_files.h"

namespace lodbake {

namespace {

std::string errnoText() { return std::strerror(errno); }

} // namespace

Status writeAll(int fd, const void* data, size_t size, const std::string& path) {
    const uint8_t* p = static_cast<const uint8_t*>(data);
    while (size > 0) {
        const ssize_t n = ::write(fd, p, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            return ioError(path + ": write failed: " + errnoText());
        }
        if (n == 0) return ioError(path + ": write failed: no progress");
        p += n;
        size -= size_t(n);
    }
    return Status();
}

Status appendToFile(const std::string& path, const void* data, size_t size) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (fd < 0) return ioError(path + ": cannot write: " + errnoText());
    Status written = writeAll(fd, data, size, path);
    if (::close(fd) != 0 && written.ok()) written = ioError(path + ": write failed: " + errnoText());
    return written;
}

Status readAt(int fd, uint64_t offset, void* data, size_t size, const std::string& path) {
    uint8_t* p = static_cast<uint8_t*>(data);
    while (size > 0) {
        const ssize_t n = ::pread(fd, p, size, off_t(offset));
        if (n < 0) {
            if (errno == EINTR) continue;
            return ioError(path + ": read failed: " + errnoText());
        }
        if (n == 0) return ioError(path + ": read failed: the file ends early");
        p += n;
        size -= size_t(n);
        offset += uint64_t(n);
    }
    return Status();
}

SpillFile::~SpillFile() { discard(); }

Status SpillFile::open(const std::string& path, size_t buffer_bytes) {
    discard();
    // As AtomicFileWriter: a dot name in the destination folder, unique per process and file.
    static std::atomic<uint64_t> counter{0};
    const size_t slash = path.find_last_of('/');
    const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
    path_ = path;
    temp_ = joinPath(parentDirectory(path),
                     "." + base + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter.fetch_add(1)));
    slot_ = registerTempFile(temp_);
    fd_ = ::open(temp_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0) {
        const std::string err = errnoText();
        unregisterTempFile(slot_);
        slot_ = -1;
        temp_.clear();
        return ioError(path + ": cannot write: " + err);
    }
    buffer_.assign(std::max<size_t>(buffer_bytes, 4096), 0);
    used_ = 0;
    written_ = 0;
    return Status::okStatus();
}

Status SpillFile::flush() {
    if (used_ == 0) return Status::okStatus();
    const Status s = writeAll(fd_, buffer_.data(), used_, path_);
    used_ = 0;
    return s;
}

Status SpillFile::write(const void* data, size_t size) {
    if (fd_ < 0 || buffer_.empty()) return internalError(path_ + ": write to a file that is not open");
    if (size == 0) return Status::okStatus(); // an empty array's data() may be null, which memcpy must not get
    const uint8_t* p = static_cast<const uint8_t*>(data);
    written_ += size;
    if (used_ + size > buffer_.size()) {
        LODBAKE_RETURN_IF_ERROR(flush());
        if (size >= buffer_.size()) return writeAll(fd_, p, size, path_);
    }
    std::memcpy(buffer_.data() + used_, p, size);
    used_ += size;
    return Status::okStatus();
}

Status SpillFile::finish() {
    if (fd_ < 0) return internalError(path_ + ": finish of a file that is not open");
    const Status s = flush();
    std::vector<uint8_t>().swap(buffer_);
    return s;
}

Status SpillFile::commit() {
    Status s = fd_ >= 0 && !buffer_.empty() ? finish() : Status::okStatus();
    if (fd_ < 0) return internalError(path_ + ": commit of a file that is not open");
    if (::close(fd_) != 0 && s.ok()) s = ioError(path_ + ": write failed: " + errnoText());
    fd_ = -1;
    if (s.ok() && std::rename(temp_.c_str(), path_.c_str()) != 0)
        s = ioError(path_ + ": cannot move into place: " + errnoText());
    if (!s.ok()) {
        discard();
        return s;
    }
    unregisterTempFile(slot_);
    slot_ = -1;
    temp_.clear();
    return s;
}

void SpillFile::discard() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (!temp_.empty()) ::unlink(temp_.c_str());
    temp_.clear();
    unregisterTempFile(slot_);
    slot_ = -1;
    std::vector<uint8_t>().swap(buffer_);
    used_ = 0;
}

Status SpillFile::copyTo(SpillFile& out, uint64_t size, std::vector<uint8_t>& buffer,
                            const std::atomic<bool>* cancel) const {
    if (fd_ < 0 || !buffer_.empty()) return internalError(path_ + ": copy from a file that is not finished");
    if (size > written_) return internalError(path_ + ": copy of more bytes than the file holds");
    if (buffer.empty()) buffer.resize(size_t(1) << 16);
    uint64_t offset = 0;
    while (offset < size) {
        if (cancel && cancel->load()) return ioError(out.path() + ": writing cancelled");
        const size_t want = size_t(std::min<uint64_t>(buffer.size(), size - offset));
        const ssize_t n = ::pread(fd_, buffer.data(), want, off_t(offset));
        if (n < 0) {
            if (errno == EINTR) continue;
            return ioError(path_ + ": read failed: " + errnoText());
        }
        if (n == 0) return ioError(path_ + ": read failed: the file ends early");
        LODBAKE_RETURN_IF_ERROR(out.write(buffer.data(), size_t(n)));
        offset += uint64_t(n);
    }
    return Status::okStatus();
}

} // namespace lodbake
