#pragma once
// Storage for large working arrays (the simplifier's corner table, quadrics and queue; the valence
// encoder's closed mesh, conquest and position tables): a std::vector whose big allocations are backed
// by transparent huge pages where the OS offers them.
//
// The collapse loop reads these arrays at random (a collapse touches a few dozen points and faces
// anywhere in a mesh of hundreds of MB), so with 4 KB pages most accesses also miss the TLB, and
// filling fresh arrays costs one page fault per 4 KB. On Linux, an allocation of at least
// kHugePageBytes is aligned to 2 MB and marked MADV_HUGEPAGE: the kernel then backs it with 2 MB
// pages when it can (with THP set to "madvise" or "always"), which removes most TLB misses and
// page faults (bake time: docs/benchmarks.md, "Bake time and peak memory against native
// meshoptimizer"). Only whole 2 MB pages
// inside the requested size are advised, so no memory beyond the request becomes resident, and
// such blocks are mapped and unmapped directly, so they never sit in malloc's free lists.
// Elsewhere, for small arrays, and in AddressSanitizer builds it is plain operator new. Contents
// and results do not depend on it.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

// AddressSanitizer cannot check accesses inside memory we map ourselves, so sanitizer builds keep
// every array on operator new.
#if defined(__SANITIZE_ADDRESS__)
#define LODBAKE_ASAN_BUILD 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LODBAKE_ASAN_BUILD 1
#endif
#endif

#if defined(__linux__) && !defined(LODBAKE_ASAN_BUILD)
#include <sys/mman.h>
#include <unistd.h>
#if defined(MADV_HUGEPAGE)
#define LODBAKE_LARGE_ARRAY_MMAP 1
#endif
#endif

namespace lodbake::detail {

template <class T>
struct LargeArrayAllocator {
    using value_type = T;
    static constexpr size_t kHugePageBytes = size_t(2) << 20;
#if defined(LODBAKE_LARGE_ARRAY_MMAP)
    static size_t pageRound(size_t bytes) {
        const size_t page = size_t(sysconf(_SC_PAGESIZE));
        return (bytes + page - 1) / page * page;
    }
#endif

    LargeArrayAllocator() = default;
    template <class U>
    LargeArrayAllocator(const LargeArrayAllocator<U>&) {}

    T* allocate(size_t n) {
        const size_t bytes = n * sizeof(T);
#if defined(LODBAKE_LARGE_ARRAY_MMAP)
        if (bytes >= kHugePageBytes) {
            // Mapped directly (not through malloc, whose arenas would keep the alignment slack and
            // freed blocks around): 2 MB more than asked, then the unaligned head and the tail are
            // unmapped again. Freed blocks go straight back to the OS.
            const size_t length = pageRound(bytes);
            void* raw = mmap(nullptr, length + kHugePageBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                             -1, 0);
            if (raw == MAP_FAILED) throw std::bad_alloc();
            const uintptr_t start = reinterpret_cast<uintptr_t>(raw);
            const uintptr_t aligned = (start + kHugePageBytes - 1) & ~uintptr_t(kHugePageBytes - 1);
            if (aligned > start) munmap(raw, aligned - start);
            const uintptr_t end = start + length + kHugePageBytes;
            if (end > aligned + length) munmap(reinterpret_cast<void*>(aligned + length), end - (aligned + length));
            // Advice only: failure (e.g. THP disabled) leaves ordinary pages. Only whole 2 MB pages
            // inside the request, so nothing past it becomes resident.
            madvise(reinterpret_cast<void*>(aligned), bytes & ~(kHugePageBytes - 1), MADV_HUGEPAGE);
            return reinterpret_cast<T*>(aligned);
        }
#endif
        return static_cast<T*>(::operator new(bytes));
    }

    void deallocate(T* p, size_t n) {
#if defined(LODBAKE_LARGE_ARRAY_MMAP)
        if (n * sizeof(T) >= kHugePageBytes) {
            munmap(p, pageRound(n * sizeof(T)));
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
