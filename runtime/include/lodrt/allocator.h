#pragma once
// Allocation hooks (cgltf_options.memory, meshopt_setAllocator), passed per call or per document:
// lodrt has no global state. A zero-initialised Allocator means std::malloc/std::free.

#include <cstddef>

#include "lodrt/export.h"

namespace lodrt {

struct Allocator {
    /// Returns size bytes aligned for any scalar type, or null on failure (lodrt then returns
    /// Result::OutOfMemory). Never called with size 0. Null means std::malloc.
    void* (*allocate)(void* user, size_t size) = nullptr;
    /// Releases a pointer that allocate returned. Never called with null. Null means std::free.
    void (*deallocate)(void* user, void* ptr) = nullptr;
    /// Passed unchanged to both hooks.
    void* user = nullptr;
};

} // namespace lodrt
