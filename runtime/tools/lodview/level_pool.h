#pragma once
// The memory lodrt's streamers get through their Allocator hook: one arena allocated when the
// packs are opened, carved first-fit with a free list that coalesces neighbours. An engine serves
// streamed level buffers from memory it reserved up front; with this, streaming a level during a
// frame costs no heap allocation. A request the arena cannot hold falls back to malloc and is
// counted, so a report can show how many heap allocations the frames still made.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

#include "lodrt/allocator.h"

namespace lodview {

class LevelPool {
public:
    LevelPool() = default;
    ~LevelPool();
    LevelPool(const LevelPool&) = delete;
    LevelPool& operator=(const LevelPool&) = delete;

    /// Reserves the arena. False when it cannot be allocated.
    bool init(size_t bytes);
    /// The hook to hand to lodrt (user = this).
    lodrt::Allocator allocator();

    uint64_t calls() const { return calls_.load(); }          // every allocate call
    uint64_t heapCalls() const { return heap_calls_.load(); } // of those, served by malloc

private:
    struct Free {
        size_t offset, size;
    };
    static constexpr size_t kAlign = 16; // header size too: keeps every block aligned for any scalar
    void* allocate(size_t size);
    void deallocate(void* ptr);
    uint8_t* arena_ = nullptr;
    size_t arena_size_ = 0;
    std::vector<Free> free_; // sorted by offset, never touching each other
    std::mutex mutex_;
    std::atomic<uint64_t> calls_{0}, heap_calls_{0};
};

} // namespace lodview
