#pragma once
// Heap allocation counting for the benchmarks that check "0 heap allocations per frame": link
// heap_count.cpp into the benchmark, whose global operator new and delete it replaces.

#include <atomic>
#include <cstdint>

namespace lodbake_bench {

/// Incremented by every operator new (and by any allocator hook a benchmark routes through it).
extern std::atomic<uint64_t> g_heap_allocations;

} // namespace lodbake_bench
