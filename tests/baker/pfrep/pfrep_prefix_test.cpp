// PfrepPrefixTest: progressive-prefix streaming of a PFRep blob (format version 2). The blocks are
// stored coarse end first, so every prefix that holds the header and the block directory opens; the
// levels it covers extract exactly as from the whole blob, selective refinement stays within what is
// loaded, and the model refines as more bytes arrive (also through PackSource range reads).
// Truncated and corrupted prefixes give errors, never reads beyond the prefix (each prefix is copied
// into an allocation of exactly its size, so ASan sees any overrun).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <random>
#include <string>

#include "../simplify/simplify_test_meshes.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "pfrep_extract.h"
#include "lodrt/streaming.h"
#include "../../runtime/glb_builder.h"

namespace {

std::vector<uint8_t> buildBlob(int subdivisions) {
    lodbake::Diagnostics d;
    lodbake::PfrepOptions options;
    options.target_ratio = 0.02f;
    auto b = lodbake::buildPfrep(lodbake_test::icosphere(subdivisions), options, d);
    EXPECT_TRUE(b.ok());
    return b.ok() ? b->blob : std::vector<uint8_t>();
}

const std::vector<uint8_t>& smallBlob() {
    static const std::vector<uint8_t> blob = buildBlob(3); // 642 vertices, 3 blocks
    return blob;
}
const std::vector<uint8_t>& largerBlob() {
    static const std::vector<uint8_t> blob = buildBlob(4); // 2,562 vertices, 11 blocks
    return blob;
}

TEST(PfrepPrefixTest, EveryPrefixExtractsTheLevelsItCovers) {
    for (const std::vector<uint8_t>* blob_ptr : {&smallBlob(), &largerBlob()}) {
        const std::vector<uint8_t>& blob = *blob_ptr;
        ASSERT_FALSE(blob.empty());
        lodrt::PfrepModel full;
        ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &full), lodrt::Result::Ok);
        ASSERT_GT(full.block_count, 2u);
        const uint64_t directory = lodrt::pfrepDirectoryBytes(blob.data(), blob.size());
        ASSERT_EQ(directory, lodrt::format::kPfrepHeaderSize + 4ull * full.block_count);
        // Reference levels from the whole blob.
        std::vector<std::vector<uint32_t>> reference(full.removed_count + 1);
        for (uint32_t k = 0; k <= full.removed_count; ++k) reference[k] = lodbake_test::pfrepLevel(full, k);
        uint32_t previous_from = full.vertex_count + 1;
        size_t distinct = 0;
        // Every length of the small blob; for the larger one (each open validates what it holds,
        // so all lengths would be quadratic) every length near a block boundary and a stride between.
        const bool every = blob_ptr == &smallBlob();
        std::vector<size_t> ends;
        for (uint32_t b = 0; b < full.block_count; ++b)
            ends.push_back(size_t(lodrt::pfrepPrefixBytesForLevel(full, b << full.block_shift)));
        ends.push_back(size_t(directory));
        auto nearEnd = [&](size_t len) {
            for (size_t e : ends)
                if (len + 3 >= e && len <= e + 3) return true;
            return false;
        };
        for (size_t len = 0; len <= blob.size(); ++len) {
            if (!every && !nearEnd(len) && len % 101 != 0) continue;
            std::vector<uint8_t> prefix(blob.begin(), blob.begin() + std::ptrdiff_t(len));
            lodrt::PfrepModel m;
            const lodrt::Result r = lodrt::openPfrepPrefix(prefix.data(), prefix.size(), &m);
            if (len < directory) {
                ASSERT_EQ(r, lodrt::Result::Truncated) << len;
                continue;
            }
            ASSERT_EQ(r, lodrt::Result::Ok) << len;
            // Exactly the blocks wholly inside the prefix are loaded.
            ASSERT_EQ(m.loaded_from == 0, len == blob.size());
            for (uint32_t k = 0; k <= full.removed_count; k += 1 + full.removed_count / 97)
                ASSERT_EQ(lodrt::pfrepPrefixBytesForLevel(m, k) <= len, k >= m.loaded_from) << len << " " << k;
            // Every level the prefix covers when the coverage changes; a few at every other length.
            const bool all_levels = m.loaded_from != previous_from;
            distinct += all_levels;
            previous_from = m.loaded_from;
            for (uint32_t k = 0; k <= full.removed_count; ++k) {
                const bool sample = k == m.loaded_from || k == full.removed_count || k + 1 == m.loaded_from ||
                                    k == uint32_t((len * 7919u) % (full.removed_count + 1));
                if (!all_levels && !sample) continue;
                lodrt::Result lr;
                const std::vector<uint32_t> got = lodbake_test::pfrepLevel(m, k, &lr);
                if (k < m.loaded_from) {
                    ASSERT_EQ(lr, lodrt::Result::NotLoaded) << len << " " << k;
                } else {
                    ASSERT_EQ(lr, lodrt::Result::Ok) << len << " " << k;
                    ASSERT_EQ(got, reference[k]) << "prefix " << len << " level " << k;
                }
            }
            if (m.loaded_from <= full.removed_count) {
                EXPECT_EQ(lodbake_test::pfrepLevelFans(m, full.removed_count),
                          lodbake_test::pfrepLevelFans(full, full.removed_count));
                EXPECT_EQ(lodbake_test::pfrepLevelFans(m, m.loaded_from),
                          lodbake_test::pfrepLevelFans(full, m.loaded_from));
            }
        }
        EXPECT_GE(distinct, size_t(full.block_count) + 1);
    }
}

TEST(PfrepPrefixTest, ExtendingAGrowingBufferMatchesOpeningIt) {
    const std::vector<uint8_t>& blob = largerBlob();
    ASSERT_FALSE(blob.empty());
    const size_t directory = size_t(lodrt::pfrepDirectoryBytes(blob.data(), blob.size()));
    std::vector<uint8_t> held(blob.begin(), blob.begin() + std::ptrdiff_t(directory));
    lodrt::PfrepModel m;
    ASSERT_EQ(lodrt::openPfrepPrefix(held.data(), held.size(), &m), lodrt::Result::Ok);
    EXPECT_EQ(m.loaded_from, m.vertex_count);
    EXPECT_EQ(m.loaded_blocks, 0u);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> idx(size_t(m.level0_triangles) * 3);
    size_t n = 0;
    EXPECT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &n), lodrt::Result::NotLoaded);
    uint32_t last_from = m.loaded_from;
    while (held.size() < blob.size()) {
        const size_t grow = std::min<size_t>(blob.size() - held.size(), 733);
        // A new vector each time: the bytes move, as when an engine reallocates its buffer.
        std::vector<uint8_t> next(blob.begin(), blob.begin() + std::ptrdiff_t(held.size() + grow));
        ASSERT_EQ(lodrt::pfrepExtendPrefix(&m, next.data(), next.size()), lodrt::Result::Ok);
        held.swap(next);
        lodrt::PfrepModel opened;
        ASSERT_EQ(lodrt::openPfrepPrefix(held.data(), held.size(), &opened), lodrt::Result::Ok);
        EXPECT_EQ(m.loaded_from, opened.loaded_from);
        EXPECT_EQ(m.loaded_blocks, opened.loaded_blocks);
        EXPECT_EQ(m.max_radius, opened.max_radius);
        EXPECT_EQ(m.max_error, opened.max_error);
        EXPECT_LE(m.loaded_from, last_from);
        last_from = m.loaded_from;
    }
    EXPECT_EQ(m.loaded_from, 0u);
    EXPECT_EQ(m.loaded_original_triangles, m.level0_triangles);
    lodrt::PfrepModel full;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &full), lodrt::Result::Ok);
    EXPECT_EQ(lodbake_test::pfrepLevel(m, 0), lodbake_test::pfrepLevel(full, 0));
    // More bytes than the blob has.
    std::vector<uint8_t> longer = blob;
    longer.push_back(0);
    EXPECT_EQ(lodrt::pfrepExtendPrefix(&m, longer.data(), longer.size()), lodrt::Result::TrailingBytes);
    EXPECT_EQ(lodrt::openPfrepPrefix(longer.data(), longer.size(), &m), lodrt::Result::TrailingBytes);
}

// Selective refinement of a partly loaded model: vertices below loaded_from stay removed, the mesh
// is exactly what the whole blob gives for the same mask, and the refinement resumes when more
// blocks arrive.
TEST(PfrepPrefixTest, SelectiveRefinementStaysInsideTheLoadedPart) {
    const std::vector<uint8_t>& blob = largerBlob();
    lodrt::PfrepModel full;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &full), lodrt::Result::Ok);
    // A prefix covering about half the removals.
    const uint32_t target = full.removed_count / 2;
    const size_t len = size_t(lodrt::pfrepPrefixBytesForLevel(full, target));
    ASSERT_LT(len, blob.size());
    std::vector<uint8_t> prefix(blob.begin(), blob.begin() + std::ptrdiff_t(len));
    lodrt::PfrepModel m;
    ASSERT_EQ(lodrt::openPfrepPrefix(prefix.data(), prefix.size(), &m), lodrt::Result::Ok);
    ASSERT_LE(m.loaded_from, target);
    ASSERT_GT(m.loaded_from, 0u);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    lodrt::pfrepMaskCoarsest(m, mask.data());
    lodrt::PfrepView view; // eye close to the sphere: everything in reach wants refining
    view.eye[2] = 1.5f;
    for (int p = 0; p < 6; ++p) view.planes[p][3] = 1e3f;
    view.pixels_per_unit_at_distance_one = 1e6f;
    size_t changes = 0;
    for (int step = 0; step < 4; ++step)
        ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes),
                  lodrt::Result::Ok);
    for (uint32_t v = 0; v < m.loaded_from; ++v) ASSERT_TRUE((mask[v >> 3] >> (v & 7)) & 1) << v;
    const std::vector<uint32_t> partial = lodbake_test::pfrepSelective(m, mask);
    EXPECT_EQ(partial, lodbake_test::pfrepSelective(full, mask));
    auto present = [&] {
        size_t c = 0;
        for (uint32_t v = 0; v < m.vertex_count; ++v) c += !((mask[v >> 3] >> (v & 7)) & 1);
        return c;
    };
    const size_t present_partial = present();
    EXPECT_GT(present_partial, size_t(m.vertex_count - m.removed_count)) << "refinement inserted vertices";
    EXPECT_EQ(lodrt::pfrepInsertVertex(m, mask.data(), m.loaded_from - 1, scratch.data(), scratch.size()),
              lodrt::Result::NotLoaded);
    lodrt::PfrepVertexBounds bounds;
    EXPECT_EQ(lodrt::pfrepVertexBounds(m, 0, &bounds), lodrt::Result::NotLoaded);
    // The rest arrives; the same mask refines on to full detail.
    ASSERT_EQ(lodrt::pfrepExtendPrefix(&m, blob.data(), blob.size()), lodrt::Result::Ok);
    ASSERT_EQ(m.loaded_from, 0u);
    for (int step = 0; step < 4; ++step)
        ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes),
                  lodrt::Result::Ok);
    EXPECT_GT(present(), present_partial);
    EXPECT_EQ(lodbake_test::pfrepSelective(m, mask), lodbake_test::pfrepSelective(full, mask));
}

TEST(PfrepPrefixTest, CorruptPrefixesAreRefused) {
    const std::vector<uint8_t>& blob = largerBlob();
    lodrt::PfrepModel full;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &full), lodrt::Result::Ok);
    const size_t directory = size_t(lodrt::pfrepDirectoryBytes(blob.data(), blob.size()));
    // The first stored block (the coarse end) and the prefix that holds exactly it.
    const size_t first_block = directory;
    const size_t first_end = size_t(lodrt::pfrepPrefixBytesForLevel(full, full.vertex_count - 1));
    ASSERT_GT(first_end, first_block);
    {
        std::vector<uint8_t> p(blob.begin(), blob.begin() + std::ptrdiff_t(first_end));
        p[first_end - 1] = 7; // padding of the block
        lodrt::PfrepModel m;
        EXPECT_EQ(lodrt::openPfrepPrefix(p.data(), p.size(), &m), lodrt::Result::BadStructure);
        // One byte short: the damaged block is not loaded yet, so the prefix still opens.
        EXPECT_EQ(lodrt::openPfrepPrefix(p.data(), p.size() - 1, &m), lodrt::Result::Ok);
        EXPECT_EQ(m.loaded_blocks, 0u);
        // ... and extending it into the damage fails, leaving the model as it was.
        const lodrt::PfrepModel before = m;
        EXPECT_EQ(lodrt::pfrepExtendPrefix(&m, p.data(), p.size()), lodrt::Result::BadStructure);
        EXPECT_EQ(m.loaded_blocks, before.loaded_blocks);
        EXPECT_EQ(m.size, before.size);
    }
    {
        std::vector<uint8_t> p(blob.begin(), blob.begin() + std::ptrdiff_t(directory));
        p[4] = 1; // version
        lodrt::PfrepModel m;
        EXPECT_EQ(lodrt::openPfrepPrefix(p.data(), p.size(), &m), lodrt::Result::UnsupportedVersion);
        EXPECT_EQ(lodrt::pfrepDirectoryBytes(p.data(), p.size()), 0u);
        p = std::vector<uint8_t>(blob.begin(), blob.begin() + std::ptrdiff_t(directory));
        p[directory - 1] ^= 0x40; // directory entry of block 0
        EXPECT_EQ(lodrt::openPfrepPrefix(p.data(), p.size(), &m), lodrt::Result::OutOfBounds);
    }
    // Random damage inside a half-loaded prefix: an error, or a model every entry point can use.
    const size_t half = size_t(lodrt::pfrepPrefixBytesForLevel(full, full.removed_count / 2));
    std::mt19937 rng(77);
    size_t refused = 0, opened = 0;
    for (int trial = 0; trial < 1500; ++trial) {
        std::vector<uint8_t> p(blob.begin(), blob.begin() + std::ptrdiff_t(half - size_t(trial % 3)));
        for (int f = 0; f < 1 + trial % 4; ++f) p[rng() % p.size()] = uint8_t(rng());
        lodrt::PfrepModel m;
        if (lodrt::openPfrepPrefix(p.data(), p.size(), &m) != lodrt::Result::Ok) {
            ++refused;
            continue;
        }
        ++opened;
        std::vector<uint32_t> idx(size_t(m.level0_triangles) * 3 + 3);
        size_t n = 0;
        for (uint32_t k : {m.loaded_from, m.removed_count}) {
            if (k > m.removed_count) continue;
            lodrt::pfrepExtractLevel(m, k, idx.data(), idx.size() / 3, &n);
            EXPECT_LE(n, idx.size() / 3);
        }
        std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
        std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
        lodrt::pfrepMaskFinest(m, mask.data());
        for (uint32_t v = 0; v < m.vertex_count; v += 11)
            lodrt::pfrepSimplifyVertex(m, mask.data(), v, scratch.data(), scratch.size());
        for (uint32_t v = 0; v < m.vertex_count; v += 5)
            lodrt::pfrepInsertVertex(m, mask.data(), v, scratch.data(), scratch.size());
        lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &n);
        lodrt::PfrepView view;
        view.eye[2] = 3;
        for (int q = 0; q < 6; ++q) view.planes[q][3] = 1e3f;
        lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &n);
    }
    EXPECT_GT(refused, 100u);
    EXPECT_GT(opened, 100u);
}

// A pack whose BIN chunk holds the blob in a buffer view, opened through a range reader: the engine
// reads the header, the directory, then more and more of the view, refining as it goes.
struct MemoryFile {
    const std::vector<uint8_t>* bytes;
    size_t reads = 0;
    uint64_t bytes_read = 0;
};

lodrt::Result readMemory(void* user, uint64_t offset, void* dst, size_t size) {
    MemoryFile* f = static_cast<MemoryFile*>(user);
    if (offset > f->bytes->size() || size > f->bytes->size() - offset) return lodrt::Result::OutOfBounds;
    std::memcpy(dst, f->bytes->data() + offset, size);
    ++f->reads;
    f->bytes_read += size;
    return lodrt::Result::Ok;
}

std::vector<uint8_t> glbWithBlob(const std::vector<uint8_t>& blob) {
    std::vector<uint8_t> bin(8, 0xAB); // something before the view
    for (uint8_t b : blob) bin.push_back(b);
    while (bin.size() % 4) bin.push_back(0);
    const std::string json = R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":)" + std::to_string(bin.size()) +
                             R"(}],"bufferViews":[{"buffer":0,"byteOffset":8,"byteLength":)" +
                             std::to_string(blob.size()) + R"(}]})";
    return lodrt_test::makeGlb(json, bin);
}

TEST(PfrepPrefixTest, StreamsThroughPackSourceRangeReads) {
    const std::vector<uint8_t>& blob = largerBlob();
    const std::vector<uint8_t> glb = glbWithBlob(blob);
    MemoryFile file{&glb};
    lodrt::PackSource source;
    lodrt::RangeReader reader{&readMemory, &file};
    ASSERT_EQ(source.openReader(reader, glb.size(), nullptr), lodrt::Result::Ok);
    const uint64_t view_bytes = source.pack().bufferView(0).byte_length;
    ASSERT_EQ(view_bytes, blob.size());
    std::vector<uint8_t> held(lodrt::format::kPfrepHeaderSize);
    ASSERT_EQ(source.readBufferView(0, 0, held.data(), held.size()), lodrt::Result::Ok);
    const size_t directory = size_t(lodrt::pfrepDirectoryBytes(held.data(), held.size()));
    ASSERT_GT(directory, held.size());
    held.resize(directory);
    ASSERT_EQ(source.readBufferView(0, lodrt::format::kPfrepHeaderSize, held.data() + lodrt::format::kPfrepHeaderSize,
                                    directory - lodrt::format::kPfrepHeaderSize),
              lodrt::Result::Ok);
    lodrt::PfrepModel m;
    ASSERT_EQ(lodrt::openPfrepPrefix(held.data(), held.size(), &m), lodrt::Result::Ok);
    lodrt::PfrepModel full;
    ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &full), lodrt::Result::Ok);
    // First drawable: exactly the bytes of the coarsest level.
    const uint32_t coarsest = m.removed_count;
    const size_t first = size_t(lodrt::pfrepPrefixBytesForLevel(m, coarsest));
    held.resize(first);
    ASSERT_EQ(source.readBufferView(0, directory, held.data() + directory, first - directory), lodrt::Result::Ok);
    ASSERT_EQ(lodrt::pfrepExtendPrefix(&m, held.data(), held.size()), lodrt::Result::Ok);
    EXPECT_EQ(lodbake_test::pfrepLevel(m, coarsest), lodbake_test::pfrepLevel(full, coarsest));
    EXPECT_LT(first, blob.size() / 2) << "the coarse end is a small part of the blob";
    // Then level by level towards full detail.
    for (uint32_t want : {coarsest * 3 / 4, coarsest / 2, coarsest / 4, 0u}) {
        const size_t need = size_t(lodrt::pfrepPrefixBytesForLevel(m, want));
        const size_t had = held.size();
        if (need > had) {
            held.resize(need);
            ASSERT_EQ(source.readBufferView(0, had, held.data() + had, need - had), lodrt::Result::Ok);
            ASSERT_EQ(lodrt::pfrepExtendPrefix(&m, held.data(), held.size()), lodrt::Result::Ok);
        }
        ASSERT_LE(m.loaded_from, want);
        EXPECT_EQ(lodbake_test::pfrepLevel(m, want), lodbake_test::pfrepLevel(full, want)) << want;
    }
    EXPECT_EQ(held.size(), blob.size());
    EXPECT_EQ(source.readBufferView(0, view_bytes, held.data(), 1), lodrt::Result::OutOfBounds);
    EXPECT_EQ(source.readBufferView(1, 0, held.data(), 1), lodrt::Result::InvalidArgument);
}

} // namespace
