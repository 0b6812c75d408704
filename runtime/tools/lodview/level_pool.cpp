#include "level_pool.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>

namespace lodview {

LevelPool::~LevelPool() {
    std::free(arena_);
}

bool LevelPool::init(size_t bytes) {
    arena_size_ = (bytes + kAlign - 1) / kAlign * kAlign;
    arena_ = static_cast<uint8_t*>(std::malloc(arena_size_));
    if (!arena_) return false;
    // Free blocks never outnumber live allocations plus one: a few per streamed level.
    free_.reserve(65536);
    free_.push_back({0, arena_size_});
    return true;
}

lodrt::Allocator LevelPool::allocator() {
    lodrt::Allocator a;
    a.user = this;
    a.allocate = [](void* user, size_t size) { return static_cast<LevelPool*>(user)->allocate(size); };
    a.deallocate = [](void* user, void* ptr) { static_cast<LevelPool*>(user)->deallocate(ptr); };
    return a;
}

void* LevelPool::allocate(size_t size) {
    calls_.fetch_add(1, std::memory_order_relaxed);
    const size_t need = kAlign + (size + kAlign - 1) / kAlign * kAlign;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        for (size_t i = 0; i < free_.size(); ++i) {
            Free& f = free_[i];
            if (f.size < need) continue;
            uint8_t* block = arena_ + f.offset;
            // A remainder too small to hold a header and a value stays with the block.
            const size_t take = f.size - need < 2 * kAlign ? f.size : need;
            std::memcpy(block, &take, sizeof(take));
            f.offset += take;
            f.size -= take;
            if (f.size == 0) free_.erase(free_.begin() + ptrdiff_t(i));
            return block + kAlign;
        }
    }
    heap_calls_.fetch_add(1, std::memory_order_relaxed);
    return std::malloc(size);
}

void LevelPool::deallocate(void* ptr) {
    uint8_t* p = static_cast<uint8_t*>(ptr);
    if (p < arena_ || p >= arena_ + arena_size_) {
        std::free(ptr);
        return;
    }
    Free block{size_t(p - kAlign - arena_), 0};
    std::memcpy(&block.size, p - kAlign, sizeof(block.size));
    std::lock_guard<std::mutex> lock(mutex_);
    auto at = std::lower_bound(free_.begin(), free_.end(), block,
                               [](const Free& a, const Free& b) { return a.offset < b.offset; });
    at = free_.insert(at, block);
    // Merge with the next block, then with the previous one.
    if (at + 1 != free_.end() && at->offset + at->size == (at + 1)->offset) {
        at->size += (at + 1)->size;
        free_.erase(at + 1);
    }
    if (at != free_.begin() && (at - 1)->offset + (at - 1)->size == at->offset) {
        (at - 1)->size += at->size;
        free_.erase(at);
    }
}

} // namespace lodview
