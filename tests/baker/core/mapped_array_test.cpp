#include "lodbake/core/mapped_array.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <utility>

#include "core/large_array.h"

using lodbake::detail::MappedArray;
using lodbake::detail::MappedPages;

namespace {

// Resident bytes of this process (Linux), or -1 where /proc is not there.
long long residentBytes() {
    std::ifstream statm("/proc/self/statm");
    long long pages_total = 0, pages_resident = 0;
    if (!(statm >> pages_total >> pages_resident)) return -1;
    return pages_resident * 4096;
}

template <MappedPages Pages> void expectContentsKeptAcrossGrowth() {
    // Grows by doubling through every size class: operator new below the threshold, a mapping above.
    MappedArray<uint32_t, Pages> a;
    for (uint32_t i = 0; i < (3u << 20); ++i) a.push_back(i * 2654435761u);
    MappedArray<uint32_t, Pages> b = a; // a copy allocates its own block
    for (uint32_t i = 0; i < a.size(); i += 4099) ASSERT_EQ(b[i], i * 2654435761u) << i;
    a.clear();
    a.shrink_to_fit();
    MappedArray<uint32_t, Pages>().swap(b);
    EXPECT_TRUE(b.empty());
}

} // namespace

TEST(MappedArrayTest, KeepsContentsAcrossGrowthCopiesAndFrees) {
    expectContentsKeptAcrossGrowth<MappedPages::Huge>();
    expectContentsKeptAcrossGrowth<MappedPages::Small>();
}

// What the removal log relies on: a reservation far beyond what is written costs only the pages
// written, 4 KB at a time (with transparent huge pages, one byte written in each 2 MB would make the
// whole 128 MiB resident), and freeing the block gives them back.
TEST(MappedArrayTest, SmallPagesMakeOnlyWrittenPagesResident) {
#if !defined(LODBAKE_LARGE_ARRAY_MMAP)
    // Operator new instead (sanitizer builds, no mmap): the sanitizer's allocator keeps freed blocks
    // and writes shadow memory for them, so residency says nothing about the mapped path.
    GTEST_SKIP() << "blocks come from operator new in this build";
#endif
    const long long before = residentBytes();
    if (before < 0) GTEST_SKIP() << "no /proc/self/statm";
    constexpr size_t kStride = size_t(2) << 20, kBytes = size_t(128) << 20;
    lodbake::detail::MappedAllocator<uint8_t, MappedPages::Small> allocator;
    uint8_t* p = allocator.allocate(kBytes);
    for (size_t at = 0; at < kBytes; at += kStride) p[at] = 1;
    size_t sum = 0;
    for (size_t at = 0; at < kBytes; at += kStride) sum += p[at];
    EXPECT_EQ(sum, kBytes / kStride);
    EXPECT_LT(residentBytes() - before, 16ll << 20) << "writing one byte per 2 MB made far more resident";
    allocator.deallocate(p, kBytes);
    EXPECT_LT(residentBytes() - before, 16ll << 20) << "a freed block stayed resident";
}
