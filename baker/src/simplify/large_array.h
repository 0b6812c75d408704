#pragma once
// Storage for the simplifier's large working arrays (corner table, quadrics, queue): a std::vector
// whose big allocations are backed by transparent huge pages where the OS offers them.
//
// The collapse loop reads these arrays at random (a collapse touches a few dozen points and faces
// anywhere in a mesh of hundreds of MB), so with 4 KB pages most accesses also miss the TLB, and
// filling fresh arrays costs one page fault per 4 KB. On Linux, an allocation of at least
// kHugePageBytes is aligned to 2 MB and marked MADV_HUGEPAGE: the kernel then backs it with 2 MB
// pages when it can (with THP set to "madvise" or "always"), which removes most TLB misses and
// page faults (dragon_poisson's chain: docs/simplify.md, "Measured"). Only whole 2 MB pages
// inside the requested size are advised, so no memory beyond the request becomes resident.
// Elsewhere, or for small arrays, it is plain operator new. Contents and results do not depend on
// it.

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace lodbake::detail {

template <class T>
struct LargeArrayAllocator {
    using value_type = T;
    static constexpr size_t kHugePageBytes = size_t(2) << 20;

    LargeArrayAllocator() = default;
    template <class U>
    LargeArrayAllocator(const LargeArrayAllocator<U>&) {}

    T* allocate(size_t n) {
        const size_t bytes = n * sizeof(T);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        if (bytes >= kHugePageBytes) {
            // aligned_alloc wants a multiple of the alignment; the tail past `bytes` is never touched.
            const size_t rounded = (bytes + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
            void* p = std::aligned_alloc(kHugePageBytes, rounded);
            if (!p) throw std::bad_alloc();
            // Advice only: failure (e.g. THP disabled) leaves ordinary pages.
            madvise(p, bytes & ~(kHugePageBytes - 1), MADV_HUGEPAGE);
            return static_cast<T*>(p);
        }
#endif
        return static_cast<T*>(::operator new(bytes));
    }

    void deallocate(T* p, size_t n) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
        if (n * sizeof(T) >= kHugePageBytes) {
            std::free(p);
            return;
        }
#endif
        (void)n;
        ::operator delete(p);
    }

    template <class U>
    bool operator==(const LargeArrayAllocator<U>&) const {
        return true;
    }
    template <class U>
    bool operator!=(const LargeArrayAllocator<U>&) const {
        return false;
    }
};

template <class T>
using LargeArray = std::vector<T, LargeArrayAllocator<T>>;

} // namespace lodbake::detail
