// Replacement global operator new/delete that count allocations (heap_count.h).

#include "heap_count.h"

#include <cstdlib>
#include <new>

namespace lodbake_bench {
std::atomic<uint64_t> g_heap_allocations{0};
} // namespace lodbake_bench

// The replacements below pair malloc with free on purpose (both sides are ours).
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif

void* operator new(size_t size) {
    ++lodbake_bench::g_heap_allocations;
    void* p = std::malloc(size ? size : 1);
    if (!p) std::abort();
    return p;
}
void* operator new[](size_t size) {
    return operator new(size);
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, size_t) noexcept {
    std::free(p);
}
