#include "lodbake/core/mapped_array.h"

#include <new>

#include "core/large_array.h"

namespace lodbake::detail {

namespace {
// Below this a Small block is not worth a mapping of its own.
constexpr size_t kSmallMappedBytes = size_t(64) << 10;
} // namespace

void* allocateMapped(size_t bytes, MappedPages pages) {
    if (pages == MappedPages::Huge) return LargeArrayAllocator<unsigned char>().allocate(bytes);
#if defined(LODBAKE_LARGE_ARRAY_MMAP)
    if (bytes >= kSmallMappedBytes) {
        void* p = mmap(nullptr, LargeArrayAllocator<unsigned char>::pageRound(bytes), PROT_READ | PROT_WRITE,
                       MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED) throw std::bad_alloc();
        return p;
    }
#endif
    return ::operator new(bytes);
}

void freeMapped(void* p, size_t bytes, MappedPages pages) {
    if (pages == MappedPages::Huge) {
        LargeArrayAllocator<unsigned char>().deallocate(static_cast<unsigned char*>(p), bytes);
        return;
    }
#if defined(LODBAKE_LARGE_ARRAY_MMAP)
    if (bytes >= kSmallMappedBytes) {
        munmap(p, LargeArrayAllocator<unsigned char>::pageRound(bytes));
        return;
    }
#endif
    ::operator delete(p);
}

} // namespace lodbake::detail
