// PfrepReaderSafetyTest: the runtime reader treats the blob as hostile. Every truncated prefix and
// thousands of random corruptions give an error code or a blob that can be used without reading
// outside it; crafted bad offsets, dependency cycles and out-of-range indices give their codes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>

#include "../simplify/simplify_test_meshes.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

namespace {

std::vector<uint8_t> smallBlob() {
    lodbake::Diagnostics d;
    lodbake::PfrepOptions options;
    options.target_ratio = 0.05f;
    auto b = lodbake::buildPfrep(lodbake_test::icosphere(3), options, d);
    EXPECT_TRUE(b.ok());
    return b.ok() ? b->blob : std::vector<uint8_t>();
}

// Exercises every reader entry point on an opened model; with ASan/UBSan builds this is where an
// out-of-bounds read would show.
void exercise(const lodrt::PfrepModel& m) {
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3 + 3);
    std::vector<uint32_t> fans(lodrt::pfrepMaxFanValues(m) + 4);
    std::vector<float> pos(size_t(m.vertex_count) * 3);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m) + 1);
    size_t n = 0;
    lodrt::pfrepDecodePositions(m, pos.data(), pos.size());
    for (uint32_t k : {0u, m.removed_count / 2, m.removed_count}) {
        lodrt::pfrepExtractLevel(m, k, idx.data(), idx.size() / 3, &n);
        EXPECT_LE(n, idx.size() / 3);
        lodrt::pfrepExtractLevelFans(m, k, fans.data(), fans.size(), &n);
        EXPECT_LE(n, fans.size());
    }
    lodrt::pfrepMaskFinest(m, mask.data());
    for (uint32_t v = 0; v < m.vertex_count; v += 7)
        lodrt::pfrepSimplifyVertex(m, mask.data(), v, scratch.data(), scratch.size());
    for (uint32_t v = 0; v < m.vertex_count; v += 5)
        lodrt::pfrepInsertVertex(m, mask.data(), v, scratch.data(), scratch.size());
    lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &n);
    lodrt::PfrepView view;
    view.eye[2] = 3;
    for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e3f;
    lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &n);
}

TEST(PfrepReaderSafetyTest, ValidBlobOpens) {
    const auto blob = smallBlob();
    ASSERT_FALSE(blob.empty());
    lodrt::PfrepModel m;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &m), lodrt::Result::Ok);
    EXPECT_EQ(m.level0_triangles, 1280u);
    exercise(m);
}

TEST(PfrepReaderSafetyTest, EveryTruncatedPrefixIsRefused) {
    const auto blob = smallBlob();
    ASSERT_FALSE(blob.empty());
    for (size_t len = 0; len < blob.size(); ++len) {
        // A copy of exactly `len` bytes, so a read past the end lands outside the allocation.
        std::vector<uint8_t> prefix(blob.begin(), blob.begin() + std::ptrdiff_t(len));
        lodrt::PfrepModel m;
        const lodrt::Result r = lodrt::openPfrep(prefix.data(), prefix.size(), &m);
        ASSERT_NE(r, lodrt::Result::Ok) << "prefix of " << len << " bytes";
    }
    EXPECT_EQ(lodrt::openPfrep(nullptr, 10, nullptr), lodrt::Result::InvalidArgument);
}

TEST(PfrepReaderSafetyTest, RandomCorruptionNeverCrashes) {
    const auto blob = smallBlob();
    ASSERT_FALSE(blob.empty());
    std::mt19937 rng(1234);
    size_t opened = 0, refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::vector<uint8_t> bad = blob;
        const int flips = 1 + int(rng() % 8);
        for (int f = 0; f < flips; ++f) {
            // Half of the trials hit the header and block directory, where damage is most structural.
            const size_t span = trial % 2 ? bad.size() : std::min<size_t>(bad.size(), 64 + 64);
            bad[rng() % span] = uint8_t(rng());
        }
        lodrt::PfrepModel m;
        if (lodrt::openPfrep(bad.data(), bad.size(), &m) == lodrt::Result::Ok) {
            ++opened;
            exercise(m);
        } else {
            ++refused;
        }
    }
    EXPECT_GT(refused, 100u);
    EXPECT_GT(opened, 100u); // damage to positions or bounds alone leaves a usable blob
}

uint32_t get32(const std::vector<uint8_t>& b, size_t at) {
    uint32_t v;
    std::memcpy(&v, b.data() + at, 4);
    return v;
}
void set32(std::vector<uint8_t>& b, size_t at, uint32_t v) { std::memcpy(b.data() + at, &v, 4); }

TEST(PfrepReaderSafetyTest, CraftedDamageGivesItsCode) {
    const auto blob = smallBlob();
    ASSERT_FALSE(blob.empty());
    lodrt::PfrepModel m;
    auto open = [&](const std::vector<uint8_t>& b) { return lodrt::openPfrep(b.data(), b.size(), &m); };
    {
        auto b = blob;
        b[0] ^= 1;
        EXPECT_EQ(open(b), lodrt::Result::BadMagic);
    }
    {
        auto b = blob;
        set32(b, 4, 1); // version 1 (global tables, coarse end last) is no longer read
        EXPECT_EQ(open(b), lodrt::Result::UnsupportedVersion);
    }
    {
        auto b = blob;
        set32(b, 8, 0xfffffff0u); // absurd vertex count: refused before anything is read
        EXPECT_NE(open(b), lodrt::Result::Ok);
        set32(b, 8, get32(blob, 8) + 1000); // the block count no longer matches
        EXPECT_EQ(open(b), lodrt::Result::BadStructure);
    }
    {
        auto b = blob;
        set32(b, 12, get32(blob, 8) + 1); // more removable vertices than vertices
        EXPECT_EQ(open(b), lodrt::Result::BadStructure);
    }
    {
        auto b = blob;
        set32(b, 60, 1); // reserved field
        EXPECT_EQ(open(b), lodrt::Result::BadStructure);
    }
    {
        auto b = blob;
        set32(b, 52, get32(blob, 52) - 1); // the blob announces one byte less than it has
        EXPECT_EQ(open(b), lodrt::Result::TrailingBytes);
        set32(b, 52, get32(blob, 52) + 1);
        EXPECT_EQ(open(b), lodrt::Result::Truncated);
    }
    const uint32_t vertex_count = get32(blob, 8);
    const uint32_t shift = get32(blob, 16);
    const size_t blocks = get32(blob, 56);
    ASSERT_EQ(blocks, (size_t(vertex_count) + (size_t(1) << shift) - 1) >> shift);
    {
        auto b = blob;
        set32(b, 64 + 4 * (blocks - 1), get32(blob, 64 + 4 * (blocks - 1)) + 4); // first stored block moved
        EXPECT_EQ(open(b), lodrt::Result::OutOfBounds);
        b = blob;
        set32(b, 64, 0x7fffffffu); // block 0 (stored last) past the blob
        EXPECT_EQ(open(b), lodrt::Result::OutOfBounds);
    }
    {
        auto b = blob;
        b[blob.size() - 1] = 1; // padding after block 0's stream
        EXPECT_EQ(open(b), lodrt::Result::BadStructure);
    }
    // Entry 1 (in block 0) rewritten by hand: one neighbour, one dependency on itself (a cycle) or
    // on a higher rank, or a neighbour past the last vertex.
    const size_t block0 = get32(blob, 64);
    const size_t count0 = std::min<size_t>(size_t(1) << shift, vertex_count);
    uint16_t rel;
    std::memcpy(&rel, blob.data() + block0 + count0 * 10 + 2, 2);
    const size_t entry1 = block0 + count0 * 12 + rel;
    auto writeEntry = [&](std::vector<uint8_t>& b, uint32_t neighbour_delta, uint32_t dependency_delta) {
        // 2 neighbours, 1 dependency, no originals, widths 20 / 20, then A, the dependency, its mask.
        std::vector<int> bits;
        auto put = [&](uint64_t v, int n) {
            for (int k = 0; k < n; ++k) bits.push_back(int((v >> k) & 1));
        };
        put(2, 6);
        put(1, 3);
        put(0, 1);
        put(20, 5);
        put(20, 5);
        put(neighbour_delta, 20);
        put(0, 20);
        put(dependency_delta, 20);
        put(1, 2);
        for (size_t k = 0; k < bits.size(); ++k) {
            uint8_t& byte = b[entry1 + k / 8];
            byte = uint8_t(bits[k] ? byte | (1u << (k % 8)) : byte & ~(1u << (k % 8)));
        }
    };
    {
        auto b = blob;
        writeEntry(b, vertex_count + 5, 0); // neighbour out of range
        const lodrt::Result r = open(b);
        EXPECT_TRUE(r == lodrt::Result::OutOfBounds || r == lodrt::Result::BadStructure) << lodrt::resultName(r);
    }
    {
        auto b = blob;
        writeEntry(b, 3, 1); // dependency 1 - 1 - 1 = -1: not below the entry (a cycle)
        const lodrt::Result r = open(b);
        EXPECT_TRUE(r == lodrt::Result::BadStructure || r == lodrt::Result::OutOfBounds) << lodrt::resultName(r);
    }
}

TEST(PfrepReaderSafetyTest, CallerBuffersAreChecked) {
    const auto blob = smallBlob();
    lodrt::PfrepModel m;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &m), lodrt::Result::Ok);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    EXPECT_EQ(lodrt::pfrepSimplifyVertex(m, mask.data(), 0, scratch.data(), scratch.size() - 1),
              lodrt::Result::InvalidArgument);
    EXPECT_EQ(lodrt::pfrepInsertVertex(m, mask.data(), m.vertex_count, scratch.data(), scratch.size()),
              lodrt::Result::InvalidArgument);
    std::vector<float> pos(3);
    EXPECT_EQ(lodrt::pfrepDecodePositions(m, pos.data(), pos.size()), lodrt::Result::BufferTooSmall);
    EXPECT_EQ(mask.size(), (m.vertex_count + 7) / 8);
}

} // namespace
