#pragma once
// Storage for the large arrays that public types hold (a DistanceIndex's tree, an LOD chain's removal
// log): big blocks are mapped on their own, so they go back to the OS when freed and never sit in
// malloc's arenas (where a freed block stays resident below the next one, and where glibc's huge-page
// heap, if the user asks for it, makes every touched 2 MB resident). Out of line
// (src/core/mapped_array.cpp), so this header needs nothing from src/. Contents and results do not
// depend on it.

#include <cstddef>
#include <vector>

namespace lodbake::detail {

enum class MappedPages {
    // From 2 MB on, aligned to 2 MB and backed by transparent huge pages where the OS offers them
    // (arrays read at random, core/large_array.h: fewer TLB misses and page faults).
    Huge,
    // From 64 KB on, the system's ordinary pages: only the pages written become resident (a stream
    // written once front to back, reserved for its worst case).
    Small,
};

/// Blocks below the kind's threshold (and every block in AddressSanitizer builds, or off Linux) come
/// from operator new. Throws std::bad_alloc when the memory cannot be had.
void* allocateMapped(size_t bytes, MappedPages pages);
/// `bytes` and `pages` as given to allocateMapped.
void freeMapped(void* p, size_t bytes, MappedPages pages);

template <class T, MappedPages Pages> struct MappedAllocator {
    using value_type = T;
    template <class U> struct rebind { using other = MappedAllocator<U, Pages>; };
    MappedAllocator() = default;
    template <class U> MappedAllocator(const MappedAllocator<U, Pages>&) {}
    T* allocate(size_t n) { return static_cast<T*>(allocateMapped(n * sizeof(T), Pages)); }
    void deallocate(T* p, size_t n) { freeMapped(p, n * sizeof(T), Pages); }
    template <class U> bool operator==(const MappedAllocator<U, Pages>&) const { return true; }
    template <class U> bool operator!=(const MappedAllocator<U, Pages>&) const { return false; }
};

template <class T, MappedPages Pages> using MappedArray = std::vector<T, MappedAllocator<T, Pages>>;

} // namespace lodbake::detail
