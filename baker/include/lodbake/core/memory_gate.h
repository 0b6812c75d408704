#pragma once
// A gate that lets jobs run side by side only while the sum of their stated memory bounds fits
// under one limit: the bake's batch runner (lodbake/bake/memory_budget.h) and the out-of-core
// driver (lodbake/ooc/driver.h) both run their jobs through it.

#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>

#include "lodbake/core/status.h"

namespace lodbake {

/// Lets jobs run side by side while the sum of their reservations stays under `limit` bytes. A
/// reservation larger than the limit is refused at once; one that fits waits until the running ones
/// leave room, in arrival order (a big job is not starved by small ones); a reservation always fits
/// when nothing else is reserved. Waiting holds no reservation, so jobs cannot wait on each other.
class MemoryGate {
public:
    explicit MemoryGate(uint64_t limit) : limit_(limit) {}
    uint64_t limit() const { return limit_; }
    /// Blocks until `bytes` are reserved; ResourceLimit naming `what` when bytes > limit.
    Status acquire(uint64_t bytes, const std::string& what);
    void release(uint64_t bytes);
    /// The largest total reserved at one time so far.
    uint64_t peakReserved();

private:
    std::mutex mutex_;
    std::condition_variable changed_;
    uint64_t limit_ = 0;
    uint64_t reserved_ = 0;
    uint64_t peak_ = 0;
    uint64_t next_ticket_ = 0;
    uint64_t serving_ = 0;
};

} // namespace lodbake
