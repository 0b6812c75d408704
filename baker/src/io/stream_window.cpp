#include "io/stream_window.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace lodbake::detail {

ByteSource::~ByteSource() {
    if (fd_ >= 0) ::close(fd_);
}

Status ByteSource::openFile(const std::string& path) {
    path_ = path;
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    struct stat st;
    if (::fstat(fd_, &st) != 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    if (!S_ISREG(st.st_mode)) return ioError(path + ": cannot open: not a regular file");
    size_ = uint64_t(st.st_size);
    return Status();
}

void ByteSource::openMemory(const uint8_t* data, size_t size) {
    memory_ = data;
    size_ = size;
}

Status ByteSource::read(uint64_t offset, uint8_t* out, size_t n) const {
    if (offset > size_ || n > size_ - offset) return internalError(path_ + ": read beyond the end of the file");
    if (memory_) {
        if (n > 0) std::memcpy(out, memory_ + offset, n);
        return Status();
    }
    while (n > 0) {
        const ssize_t got = ::pread(fd_, out, n, off_t(offset));
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) return ioError(path_ + ": read failed: " + std::strerror(errno));
        if (got == 0) return ioError(path_ + ": read failed: the file shrank while it was read");
        out += got;
        n -= size_t(got);
        offset += uint64_t(got);
    }
    return Status();
}

Status StreamWindow::start(uint64_t offset) {
    if (buffer_.size() != initial_) std::vector<uint8_t>(initial_).swap(buffer_);
    base_ = offset;
    valid_ = 0;
    exposed_ = 0;
    return advance(0);
}

size_t StreamWindow::boundary() const {
    if (cut_ == Cut::Bytes || base_ + valid_ == source_.size()) return valid_;
    const uint8_t* b = buffer_.data();
    if (cut_ == Cut::Tokens) {
        for (size_t i = valid_; i > 0; --i) {
            const char c = char(b[i - 1]);
            if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') return i;
        }
        return 0;
    }
    // Lines: after the last line break that ends a logical line (its line does not end in '\').
    size_t i = valid_;
    while (i > 0) {
        const uint8_t* nl = static_cast<const uint8_t*>(::memrchr(b, '\n', i));
        if (!nl) return 0;
        size_t j = size_t(nl - b);
        size_t k = j;
        while (k > 0 && (b[k - 1] == '\r' || b[k - 1] == ' ' || b[k - 1] == '\t' || b[k - 1] == '\f' || b[k - 1] == '\v'))
            --k;
        if (k == 0 || b[k - 1] != '\\') return j + 1;
        i = j;
    }
    return 0;
}

Status StreamWindow::advance(size_t keep) {
    keep = std::min(keep, valid_);
    if (keep > 0) std::memmove(buffer_.data(), buffer_.data() + keep, valid_ - keep);
    base_ += keep;
    valid_ -= keep;
    const size_t before = exposed_ > keep ? exposed_ - keep : 0;
    for (;;) {
        if (valid_ == buffer_.size()) {
            if (buffer_.size() >= max_) return resourceLimit("record longer than " + std::to_string(max_) + " bytes");
            buffer_.resize(std::min(max_, buffer_.size() * 2));
        }
        const uint64_t left = source_.size() - (base_ + valid_);
        const size_t n = size_t(std::min<uint64_t>(left, buffer_.size() - valid_));
        LODBAKE_RETURN_IF_ERROR(source_.read(base_ + valid_, buffer_.data() + valid_, n));
        valid_ += n;
        exposed_ = boundary();
        if (exposed_ > before || base_ + valid_ == source_.size()) return Status();
    }
}

} // namespace lodbake::detail
