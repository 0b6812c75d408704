// PfrepRegionTest: region blocks (docs/format/pfrep.md "Region blocks"). With every block loaded the
// decoded buffer is the format 2 blob byte for byte, so every level and every refinement equals
// format 2's; with a subset, refinement never reads a non-resident record or inserts a non-resident
// vertex, and with the blocks pfrepRegionBlocksNeeded lists it makes the same masks as the whole
// blob, frame by frame. Cut and corrupted blobs give errors, never reads outside the buffers (each
// block is copied into an allocation of exactly its size).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <vector>

#include "../simplify/simplify_test_meshes.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/pfrep/pfrep_region.h"
#include "lodrt/detail/pfrep_region.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "pfrep_extract.h"
#include "cli_runner.h"
#include "lodbake/io/mesh_io.h"
#include "pfrep_region_view.h"
#include "test_paths.h"

namespace {

struct Blobs {
    std::vector<uint8_t> format2, region;
};

Blobs makeBlobs(int subdivisions, uint32_t block_vertices, uint32_t root_vertices) {
    Blobs b;
    lodbake::Diagnostics d;
    lodbake::PfrepOptions options;
    options.target_ratio = 0.01f;
    auto built = lodbake::buildPfrep(lodbake_test::icosphere(subdivisions), options, d);
    EXPECT_TRUE(built.ok());
    if (!built.ok()) return b;
    b.format2 = built->blob;
    lodbake::PfrepRegionOptions ro;
    ro.block_vertices = block_vertices;
    ro.root_vertices = root_vertices;
    auto region = lodbake::writePfrepRegions(b.format2, ro);
    EXPECT_TRUE(region.ok()) << region.status().message();
    if (region.ok()) b.region = *region;
    return b;
}

const Blobs& largerBlobs() {
    static const Blobs b = makeBlobs(5, 64, 256); // 10,242 vertices
    return b;
}
const Blobs& smallBlobs() {
    static const Blobs b = makeBlobs(3, 64, 64); // 642 vertices
    return b;
}

// An opened region blob with its buffers.
struct Opened {
    lodrt::PfrepRegionInfo info;
    std::vector<uint8_t> decoded;
    std::vector<uint64_t> state;
    lodrt::PfrepRegions g;
    lodrt::Result open(const std::vector<uint8_t>& blob, size_t size) {
        lodrt::Result r = lodrt::pfrepRegionInfo(blob.data(), size, &info);
        if (r != lodrt::Result::Ok) return r;
        if (info.decoded_bytes > (64u << 20) || info.state_bytes > (64u << 20)) return lodrt::Result::BadStructure;
        decoded.assign(info.decoded_bytes, 0xcd);
        state.assign((info.state_bytes + 7) / 8, 0);
        std::vector<uint8_t> prefix(blob.begin(), blob.begin() + long(size));
        return lodrt::pfrepRegionOpen(prefix.data(), prefix.size(), decoded.data(), decoded.size(), state.data(),
                                      info.state_bytes, &g);
    }
    lodrt::Result load(const std::vector<uint8_t>& blob, uint32_t k) {
        const lodrt::PfrepRegionBlock& b = g.blocks[k];
        if (uint64_t(b.offset) + b.size > blob.size()) return lodrt::Result::Truncated;
        std::vector<uint8_t> bytes(blob.begin() + b.offset, blob.begin() + b.offset + b.size);
        return lodrt::pfrepRegionLoadBlock(&g, k, bytes.data(), bytes.size());
    }
};

bool bit(const uint8_t* bits, uint32_t v) {
    return (bits[v >> 3] >> (v & 7)) & 1;
}

// Overwrites the record and entry of every non-resident vertex with 0xff: codes of a huge radius and
// error (a criterion read would insert it) and an entry header announcing 65,598 neighbours of 31
// bits (a decode would read far outside the buffer, which ASan reports, or insert garbage ranks).
void poisonNonResident(Opened& o) {
    const lodrt::PfrepModel& m = o.g.model;
    for (uint32_t v = 0; v < m.vertex_count; ++v) {
        if (bit(m.resident, v)) continue;
        std::memset(o.decoded.data() + lodrt::detail::pfrepRecordOffset(m, v), 0xff,
                    lodrt::format::kPfrepVertexRecordSize);
        const uint64_t begin = lodrt::detail::pfrepEntryOffset(m, v);
        const uint64_t end = v + 1 < m.vertex_count && ((v + 1) >> m.block_shift) == (v >> m.block_shift)
                                 ? lodrt::detail::pfrepEntryOffset(m, v + 1)
                                 : lodrt::detail::pfrepStreamEnd(m, v);
        std::memset(o.decoded.data() + begin, 0xff, size_t(end - begin));
    }
}

// A camera flying past the sphere (radius 1 about the origin), close to its +x side, looking at it.
lodrt::PfrepView flightView(int frame, int frames) {
    const float t = float(frame) / float(std::max(frames - 1, 1));
    const float eye[3] = {2.0f, -0.6f + 1.2f * t, 0.3f};
    const float target[3] = {0.95f, -0.3f + 0.6f * t, 0.0f};
    lodrt::PfrepView view = lodbake_test::cameraView(eye, target, 0.5f, 1.5f, 0.01f, 100.0f, 300.0f, 1.0f);
    return view;
}

TEST(PfrepRegionTest, AllBlocksRebuildFormat2AndItsLevelsAndRefinement) {
    const Blobs& b = largerBlobs();
    ASSERT_FALSE(b.region.empty());
    Opened o;
    ASSERT_EQ(o.open(b.region, b.region.size()), lodrt::Result::Ok);
    ASSERT_GT(o.g.block_count, 20u);
    lodrt::PfrepModel whole;
    ASSERT_EQ(lodrt::openPfrep(b.format2.data(), b.format2.size(), &whole), lodrt::Result::Ok);
    // Root first, then the other blocks in a shuffled order.
    std::vector<uint32_t> order;
    for (uint32_t k = 1; k < o.g.block_count; ++k) order.push_back(k);
    std::shuffle(order.begin(), order.end(), std::mt19937(7));
    ASSERT_EQ(o.load(b.region, 0), lodrt::Result::Ok);
    for (uint32_t k : order) ASSERT_EQ(o.load(b.region, k), lodrt::Result::Ok);
    EXPECT_EQ(o.g.loaded_bytes, b.region.size());
    EXPECT_EQ(o.decoded, b.format2);
    const lodrt::PfrepModel& m = o.g.model;
    EXPECT_EQ(m.loaded_from, 0u);
    EXPECT_EQ(m.max_radius, whole.max_radius);
    EXPECT_EQ(m.max_error, whole.max_error);
    for (uint32_t k = 0; k <= m.removed_count; k += std::max(1u, m.removed_count / 37))
        ASSERT_EQ(lodbake_test::pfrepLevel(m, k), lodbake_test::pfrepLevel(whole, k)) << "level " << k;
    ASSERT_EQ(lodbake_test::pfrepLevel(m, m.removed_count), lodbake_test::pfrepLevel(whole, m.removed_count));
    // Selective refinement along a flight, both models stepped alike: same masks, same meshes.
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(m)), mask_b(mask_a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    lodrt::pfrepMaskCoarsest(m, mask_a.data());
    lodrt::pfrepMaskCoarsest(whole, mask_b.data());
    ASSERT_EQ(mask_a, mask_b);
    for (int frame = 0; frame < 12; ++frame) {
        const lodrt::PfrepView view = flightView(frame, 12);
        size_t ca = 0, cb = 0;
        ASSERT_EQ(lodrt::pfrepRefine(m, view, mask_a.data(), scratch.data(), scratch.size(), &ca), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepRefine(whole, view, mask_b.data(), scratch.data(), scratch.size(), &cb),
                  lodrt::Result::Ok);
        ASSERT_EQ(ca, cb);
        ASSERT_EQ(mask_a, mask_b) << "frame " << frame;
        ASSERT_EQ(lodbake_test::pfrepSelective(m, mask_a), lodbake_test::pfrepSelective(whole, mask_b));
    }
}

// With the blocks the flight needs (loaded as it goes, never evicted) the region model makes the
// whole blob's masks; non-resident records and entries are poisoned (poisonNonResident), so any read
// of one would change a decision or read outside the buffer.
TEST(PfrepRegionTest, NeededBlocksGiveTheWholeBlobsMasksWithoutReadingOthers) {
    const Blobs& b = largerBlobs();
    Opened o;
    ASSERT_EQ(o.open(b.region, b.region.size()), lodrt::Result::Ok);
    ASSERT_EQ(o.load(b.region, 0), lodrt::Result::Ok);
    lodrt::PfrepModel whole;
    ASSERT_EQ(lodrt::openPfrep(b.format2.data(), b.format2.size(), &whole), lodrt::Result::Ok);
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(whole)), mask_b(mask_a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(whole));
    lodrt::pfrepMaskCoarsest(whole, mask_b.data());
    std::vector<uint32_t> needed(o.g.block_count);
    const int frames = 16;
    size_t max_present = 0;
    for (int frame = 0; frame < frames; ++frame) {
        const lodrt::PfrepView view = flightView(frame, frames);
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepRegionBlocksNeeded(o.g, view, needed.data(), needed.size(), &count), lodrt::Result::Ok);
        ASSERT_GE(count, 1u);
        ASSERT_EQ(needed[0], 0u);
        for (size_t k = 0; k < count; ++k) ASSERT_EQ(o.load(b.region, needed[k]), lodrt::Result::Ok);
        if (frame == 0) lodrt::pfrepMaskCoarsest(o.g.model, mask_a.data());
        poisonNonResident(o);
        for (int step = 0; step < 3; ++step) {
            size_t ca = 0, cb = 0;
            ASSERT_EQ(lodrt::pfrepRefine(o.g.model, view, mask_a.data(), scratch.data(), scratch.size(), &ca),
                      lodrt::Result::Ok);
            ASSERT_EQ(lodrt::pfrepRefine(whole, view, mask_b.data(), scratch.data(), scratch.size(), &cb),
                      lodrt::Result::Ok);
            ASSERT_EQ(mask_a, mask_b) << "frame " << frame << " step " << step;
        }
        size_t present = 0;
        for (uint32_t v = 0; v < whole.vertex_count; ++v) present += !bit(mask_a.data(), v);
        max_present = std::max(max_present, present);
        ASSERT_EQ(lodbake_test::pfrepSelective(o.g.model, mask_a), lodbake_test::pfrepSelective(whole, mask_b));
    }
    // The flight refines a part of the sphere and leaves blocks out (a small uniform sphere: its
    // accumulated bounding spheres are large; the fly-by benchmark measures a real scan).
    EXPECT_GT(max_present, 2000u);
    EXPECT_LT(o.g.loaded_bytes, b.region.size() * 95 / 100);
}

// Only the blocks of one view resident while the camera moves on: refinement only ever makes
// resident vertices present, inserting a non-resident vertex is refused, and the mesh stays closed.
TEST(PfrepRegionTest, MissingBlocksAreNeverInserted) {
    const Blobs& b = largerBlobs();
    Opened o;
    ASSERT_EQ(o.open(b.region, b.region.size()), lodrt::Result::Ok);
    const lodrt::PfrepModel& m = o.g.model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    size_t changes = 0;
    // Nothing loaded yet: refinement and selective extraction are not possible.
    EXPECT_EQ(lodrt::pfrepRefine(m, flightView(0, 2), mask.data(), scratch.data(), scratch.size(), &changes),
              lodrt::Result::NotLoaded);
    ASSERT_EQ(o.load(b.region, 0), lodrt::Result::Ok);
    // Resident: the blocks the flight's first view needs; the flight then moves on past them.
    lodrt::PfrepView first = flightView(0, 8);
    first.hysteresis = 1.0f;
    first.cull_hysteresis = 0.0f;
    std::vector<uint32_t> needed(o.g.block_count);
    size_t needed_count = 0;
    ASSERT_EQ(lodrt::pfrepRegionBlocksNeeded(o.g, first, needed.data(), needed.size(), &needed_count),
              lodrt::Result::Ok);
    ASSERT_GT(needed_count, 1u);
    ASSERT_LT(needed_count, o.g.block_count);
    for (size_t i = 0; i < needed_count; ++i)
        if (needed[i] != 0) {
            ASSERT_EQ(o.load(b.region, needed[i]), lodrt::Result::Ok);
        }
    poisonNonResident(o);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    for (int frame = 0; frame < 8; ++frame) {
        for (int step = 0; step < 3; ++step)
            ASSERT_EQ(
                lodrt::pfrepRefine(m, flightView(frame, 8), mask.data(), scratch.data(), scratch.size(), &changes),
                lodrt::Result::Ok);
        for (uint32_t v = 0; v < m.vertex_count; ++v) ASSERT_TRUE(bit(mask.data(), v) || bit(m.resident, v)) << v;
    }
    uint32_t refused = 0, inserted = 0;
    for (uint32_t v = 0; v < m.removed_count; v += 7) {
        const std::vector<uint8_t> before = mask;
        const lodrt::Result r = lodrt::pfrepInsertVertex(m, mask.data(), v, scratch.data(), scratch.size());
        if (r == lodrt::Result::NotLoaded) {
            ++refused;
            ASSERT_EQ(mask, before);
        } else {
            ASSERT_EQ(r, lodrt::Result::Ok);
            inserted += before != mask;
        }
        for (uint32_t x = 0; x < m.vertex_count; ++x) ASSERT_TRUE(bit(mask.data(), x) || bit(m.resident, x));
    }
    // Both outcomes occur: closures that reach a missing block are refused, others go through.
    EXPECT_GT(refused, 10u);
    EXPECT_GT(inserted, 0u);
    EXPECT_EQ(lodrt::pfrepVertexBounds(m, 1, nullptr), lodrt::Result::InvalidArgument);
}

// Eviction: release the block from the mask, evict it; the mask stays valid and refinement goes on;
// loading it again gives the format 2 bytes back.
TEST(PfrepRegionTest, EvictAndReload) {
    const Blobs& b = largerBlobs();
    Opened o;
    ASSERT_EQ(o.open(b.region, b.region.size()), lodrt::Result::Ok);
    for (uint32_t k = 0; k < o.g.block_count; ++k) ASSERT_EQ(o.load(b.region, k), lodrt::Result::Ok);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(o.g.model));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(o.g.model));
    lodrt::pfrepMaskFinest(o.g.model, mask.data());
    const size_t full = lodbake_test::pfrepSelective(o.g.model, mask).size();
    EXPECT_EQ(lodrt::pfrepRegionEvictBlock(&o.g, 0), lodrt::Result::InvalidArgument);
    for (uint32_t k = 1; k < o.g.block_count; k += 2) {
        ASSERT_EQ(lodrt::pfrepRegionReleaseMask(o.g, k, mask.data(), scratch.data(), scratch.size()),
                  lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepRegionEvictBlock(&o.g, k), lodrt::Result::Ok);
    }
    EXPECT_GT(o.g.model.loaded_from, 0u);
    for (uint32_t v = 0; v < o.g.model.vertex_count; ++v)
        ASSERT_TRUE(bit(mask.data(), v) || bit(o.g.model.resident, v));
    const size_t reduced = lodbake_test::pfrepSelective(o.g.model, mask).size();
    EXPECT_LT(reduced, full);
    size_t changes = 0;
    ASSERT_EQ(lodrt::pfrepRefine(o.g.model, flightView(3, 8), mask.data(), scratch.data(), scratch.size(), &changes),
              lodrt::Result::Ok);
    for (uint32_t k = 1; k < o.g.block_count; k += 2) ASSERT_EQ(o.load(b.region, k), lodrt::Result::Ok);
    EXPECT_EQ(o.decoded, b.format2);
    EXPECT_EQ(o.g.model.loaded_from, 0u);
    EXPECT_EQ(o.g.loaded_bytes, b.region.size());
}

TEST(PfrepRegionTest, WriterRefusesABadBlob) {
    std::vector<uint8_t> bad = smallBlobs().format2;
    ASSERT_FALSE(bad.empty());
    bad[4] = 9; // version
    EXPECT_FALSE(lodbake::writePfrepRegions(bad, lodbake::PfrepRegionOptions()).ok());
}

// Every cut of the opening part, every cut of each block, and changed bytes everywhere: an error or
// a model that extracts and refines inside its buffers.
TEST(PfrepRegionTest, TruncatedAndCorruptedBlobsFailCleanly) {
    const Blobs& b = smallBlobs();
    ASSERT_FALSE(b.region.empty());
    Opened good;
    ASSERT_EQ(good.open(b.region, b.region.size()), lodrt::Result::Ok);
    for (size_t cut = 0; cut < good.info.open_bytes; ++cut) {
        Opened o;
        ASSERT_NE(o.open(b.region, cut), lodrt::Result::Ok) << cut;
    }
    for (uint32_t k = 0; k < good.g.block_count; ++k) {
        const lodrt::PfrepRegionBlock& blk = good.g.blocks[k];
        for (uint32_t cut = 0; cut < blk.size; cut += 1 + cut / 16) {
            std::vector<uint8_t> bytes(b.region.begin() + blk.offset, b.region.begin() + blk.offset + cut);
            ASSERT_EQ(lodrt::pfrepRegionLoadBlock(&good.g, k, bytes.data(), bytes.size()), lodrt::Result::Truncated);
        }
    }
    std::mt19937 rng(11);
    size_t accepted = 0, refused = 0;
    for (size_t at = 0; at < b.region.size(); at += 1 + at / 512) {
        std::vector<uint8_t> blob = b.region;
        blob[at] = uint8_t(blob[at] ^ (1u << (rng() % 8)));
        Opened o;
        lodrt::Result r = o.open(blob, blob.size());
        for (uint32_t k = 0; k < o.g.block_count && r == lodrt::Result::Ok; ++k) r = o.load(blob, k);
        if (r != lodrt::Result::Ok) {
            ++refused;
            continue;
        }
        ++accepted;
        const lodrt::PfrepModel& m = o.g.model;
        std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
        std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
        std::vector<uint32_t> idx(size_t(m.level0_triangles) * 3 + 3);
        size_t n = 0;
        lodrt::pfrepMaskCoarsest(m, mask.data());
        (void)lodrt::pfrepRefine(m, flightView(1, 3), mask.data(), scratch.data(), scratch.size(), &n);
        (void)lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &n);
        (void)lodrt::pfrepExtractLevel(m, 0, idx.data(), idx.size() / 3, &n);
    }
    EXPECT_GT(refused, 0u);
    EXPECT_GT(accepted + refused, 1000u);
}

// The pfrep fuzz target's region seed: a small region blob (icosphere, blocks of 16 vertices) with its
// last 3 bytes cut, so `lodbake pfrep --extract` refuses it (Truncated) while the fuzzer loads every
// block but the last. Written to the build folder; the committed copy must open the same way.
TEST(PfrepRegionTest, FuzzSeed) {
    const Blobs fresh = makeBlobs(2, 16, 16);
    ASSERT_FALSE(fresh.region.empty());
    std::vector<uint8_t> cut(fresh.region.begin(), fresh.region.end() - 3);
    std::ofstream(std::string(LODBAKE_TEST_BINARY_DIR) + "/region_icosphere_cut.lbp", std::ios::binary)
        .write(reinterpret_cast<const char*>(cut.data()), std::streamsize(cut.size()));
    std::ifstream in(lodbake_test::sourceDir() + "/tests/malformed/lbp/region_icosphere_cut.lbp", std::ios::binary);
    ASSERT_TRUE(in.good()) << "the fuzz corpus has no region seed";
    const std::vector<uint8_t> seed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    Opened o;
    ASSERT_EQ(o.open(seed, seed.size()), lodrt::Result::Ok);
    ASSERT_GT(o.g.block_count, 4u);
    for (uint32_t k = 0; k + 1 < o.g.block_count; ++k) ASSERT_EQ(o.load(seed, k), lodrt::Result::Ok);
    EXPECT_EQ(o.load(seed, o.g.block_count - 1), lodrt::Result::Truncated);
}

// lodbake pfrep --regions writes a region blob that --extract reads with the format 2 blob's levels.
TEST(PfrepRegionTest, CliWritesAndExtracts) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string in = dir + "/pfrep_region_cli.ply";
    lodbake::Diagnostics d;
    ASSERT_TRUE(lodbake::writeMesh(lodbake_test::icosphere(3), in, {}, d).ok());
    const std::string regions = dir + "/pfrep_region_cli.lbp", format2 = dir + "/pfrep_region_cli2.lbp";
    lodbake_test::CliRun r = lodbake_test::runLodbake({"pfrep", in, "-o", regions, "--ratio", "0.1", "--regions"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("region blocks"), std::string::npos) << r.out;
    r = lodbake_test::runLodbake({"pfrep", in, "-o", format2, "--ratio", "0.1", "--format", "2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    for (const char* k : {"0", "300"}) {
        const std::string a = dir + "/pfrep_region_cli_a.ply", b = dir + "/pfrep_region_cli_b.ply";
        ASSERT_EQ(lodbake_test::runLodbake({"pfrep", "--extract", k, regions, "-o", a}).exit_code, 0);
        ASSERT_EQ(lodbake_test::runLodbake({"pfrep", "--extract", k, format2, "-o", b}).exit_code, 0);
        EXPECT_EQ(lodbake_test::readTextFile(a), lodbake_test::readTextFile(b)) << "level " << k;
    }
    // A cut region blob: one error line, no output.
    const std::string bad = dir + "/pfrep_region_cli_bad.lbp";
    {
        std::string bytes = lodbake_test::readTextFile(regions);
        bytes.resize(bytes.size() - 5);
        std::ofstream(bad, std::ios::binary) << bytes;
    }
    r = lodbake_test::runLodbake({"pfrep", "--extract", "0", bad, "-o", dir + "/pfrep_region_cli_bad.ply"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("Truncated"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir + "/pfrep_region_cli_bad.ply"));
    EXPECT_EQ(lodbake_test::runLodbake({"pfrep", in, "-o", regions, "--regions", "--format", "3"}).exit_code, 2);
    EXPECT_EQ(
        lodbake_test::runLodbake({"pfrep", "--extract", "0", regions, "--regions", "-o", dir + "/x.ply"}).exit_code, 2);
}

} // namespace
