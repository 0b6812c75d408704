#include "lodbake/core/memory_gate.h"

#include <algorithm>

namespace lodbake {

namespace {

uint64_t mib(uint64_t bytes) { return (bytes + (uint64_t(1) << 20) - 1) >> 20; }

} // namespace

Status MemoryGate::acquire(uint64_t bytes, const std::string& what) {
    if (bytes > limit_)
        return resourceLimit(what + ": needs " + std::to_string(mib(bytes)) + " MiB, above the memory limit of " +
                             std::to_string(mib(limit_)) + " MiB (--memory-limit)");
    std::unique_lock<std::mutex> lock(mutex_);
    const uint64_t ticket = next_ticket_++;
    changed_.wait(lock, [&] { return ticket == serving_ && (reserved_ == 0 || reserved_ + bytes <= limit_); });
    reserved_ += bytes;
    peak_ = std::max(peak_, reserved_);
    ++serving_;
    changed_.notify_all();
    return Status();
}

void MemoryGate::release(uint64_t bytes) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        reserved_ -= std::min(bytes, reserved_);
    }
    changed_.notify_all();
}

uint64_t MemoryGate::peakReserved() {
    std::lock_guard<std::mutex> lock(mutex_);
    return peak_;
}

} // namespace lodbake
