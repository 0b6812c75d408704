#include "lodbake/core/mapped_array.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <utility>

#include "core/large_array.h"

#if defined(LODBAKE_ASAN_BUILD)
#include <sanitizer/allocator_interface.h>
#include <sanitizer/asan_interface.h>
#endif

using lodbake::detail::MappedArray;
using lodbake::detail::MappedPages;

namespace {

#if defined(LODBAKE_LARGE_ARRAY_MMAP)
// Resident bytes of this process (Linux), or -1 where /proc is not there.
long long residentBytes() {
    std::ifstream statm("/proc/self/statm");
    long long pages_total = 0, pages_resident = 0;
    if (!(statm >> pages_total >> pages_resident)) return -1;
    return pages_resident * 4096;
}
#endif

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

#if defined(LODBAKE_LARGE_ARRAY_MMAP)
// What the removal log relies on: a reservation far beyond what is written costs only the pages
// written, 4 KB at a time (with transparent huge pages, one byte written in each 2 MB would make the
// whole 128 MiB resident), and freeing the block gives them back.
// Only where blocks are mapped (Linux, not AddressSanitizer): elsewhere they come from operator new,
// and the residency of that allocator's blocks says nothing about this code. The sanitizer build
// checks its own path below instead.
TEST(MappedArrayTest, SmallPagesMakeOnlyWrittenPagesResident) {
    const long long before = residentBytes();
    ASSERT_GE(before, 0) << "no /proc/self/statm on a Linux build";
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
#endif

#if defined(LODBAKE_ASAN_BUILD)
// What AddressSanitizer builds do instead of mapping (core/large_array.h): every block, the big ones
// included, comes from the sanitizer's allocator, so a read past a block's end or after its release
// is caught. A block mapped by our code would pass all of these reads unnoticed (its shadow is zero).
TEST(MappedArrayTest, SanitizerBuildsKeepEveryBlockUnderAddressSanitizer) {
    // Below and above each kind's mapping threshold (64 KB Small, 2 MB Huge); the odd sizes end
    // inside an 8-byte shadow granule, so the byte after the block is poisoned in any layout.
    for (const MappedPages pages : {MappedPages::Small, MappedPages::Huge})
        for (const size_t bytes : {size_t(4096 + 5), (size_t(3) << 20) + 5}) {
            SCOPED_TRACE(testing::Message() << "pages " << int(pages) << ", " << bytes << " bytes");
            uint8_t* p = static_cast<uint8_t*>(lodbake::detail::allocateMapped(bytes, pages));
            ASSERT_NE(p, nullptr);
            if (!__sanitizer_get_ownership(p)) { // (asking its size would abort the run)
                ADD_FAILURE() << "the block does not come from the sanitizer's allocator";
                lodbake::detail::freeMapped(p, bytes, pages);
                continue;
            }
            EXPECT_EQ(__sanitizer_get_allocated_size(p), bytes);
            EXPECT_EQ(__asan_region_is_poisoned(p, bytes), nullptr);
            EXPECT_TRUE(__asan_address_is_poisoned(p + bytes)) << "the byte after the block is addressable";
            lodbake::detail::freeMapped(p, bytes, pages);
            EXPECT_TRUE(__asan_address_is_poisoned(p)) << "a freed block is still addressable";
        }
}
#endif
