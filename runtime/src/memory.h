#pragma once
// Internal: allocation through the caller's hooks and a growable array of trivially copyable values
// that reports failure instead of throwing (std::vector would abort under -fno-exceptions).

#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <type_traits>

#include "lodrt/allocator.h"

namespace lodrt {
namespace detail {

inline void* allocateBytes(const Allocator& allocator, size_t size) {
    if (size == 0) size = 1;
    return allocator.allocate ? allocator.allocate(allocator.user, size) : std::malloc(size);
}

inline void deallocateBytes(const Allocator& allocator, void* ptr) {
    if (!ptr) return;
    if (allocator.deallocate) {
        allocator.deallocate(allocator.user, ptr);
    } else {
        std::free(ptr);
    }
}

/// Allocates count values of T, or null on overflow or failure.
template <typename T> T* allocateArray(const Allocator& allocator, size_t count) {
    static_assert(std::is_trivially_copyable<T>::value, "lodrt arrays hold plain data");
    if (count > size_t(-1) / sizeof(T)) return nullptr;
    return static_cast<T*>(allocateBytes(allocator, count * sizeof(T)));
}

template <typename T> struct Growable {
    static_assert(std::is_trivially_copyable<T>::value, "lodrt arrays hold plain data");
    T* data = nullptr;
    size_t size = 0;
    size_t capacity = 0;

    bool reserve(const Allocator& allocator, size_t wanted) {
        if (wanted <= capacity) return true;
        size_t new_capacity = capacity < 16 ? 16 : capacity;
        while (new_capacity < wanted) {
            if (new_capacity > size_t(-1) / 2 / sizeof(T)) return false;
            new_capacity *= 2;
        }
        T* fresh = allocateArray<T>(allocator, new_capacity);
        if (!fresh) return false;
        if (size > 0) std::memcpy(fresh, data, size * sizeof(T));
        deallocateBytes(allocator, data);
        data = fresh;
        capacity = new_capacity;
        return true;
    }
    bool push(const Allocator& allocator, const T& value) {
        if (size == capacity && !reserve(allocator, size + 1)) return false;
        data[size++] = value;
        return true;
    }
    bool append(const Allocator& allocator, const T* values, size_t count) {
        if (count == 0) return true;
        if (size + count < size || !reserve(allocator, size + count)) return false;
        std::memcpy(data + size, values, count * sizeof(T));
        size += count;
        return true;
    }
    /// Hands the storage to the caller, who frees it with deallocateBytes.
    T* release() {
        T* out = data;
        data = nullptr;
        size = capacity = 0;
        return out;
    }
    void reset(const Allocator& allocator) {
        deallocateBytes(allocator, data);
        data = nullptr;
        size = capacity = 0;
    }
};

} // namespace detail
} // namespace lodrt
