// PfrepRegionStreamingTest: the lodrt::Streamer loads a format 5 LODBAKE_progressive_fans blob (region
// blocks, docs/format/pfrep.md "Region blocks") by view (lodrt/streaming.h, wantPfrepBlocks). Lives
// in lodbake_tests because the pack is baked with the baker; the code under test is runtime code.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "lodrt/streaming.h"
#include "manual_jobs.h"
#include "mesh_builders.h"
#include "pfrep_extract.h"

namespace region_streaming {

// A wavy height field of n x n vertices over [0, 1]^2.
// The wavy field of 180 x 180 vertices baked with a format 5 blob of `block_vertices` per block.
std::vector<uint8_t> bakeWaves(uint32_t block_vertices) {
    lodbake::BakeSettings settings;
    settings.pfrep_format = lodrt::format::kPfrepFormatRegions;
    settings.pfrep_region_block = block_vertices;
    settings.lod_ratios = {0.5, 0.25, 0.1, 0.03};
    settings.error_samples = 2000;
    settings.threads = 2;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "waves";
    inputs[0].mesh = lodbake_test::wavyField(180, 0.04f, 0.37f, 0.29f);
    lodbake::Diagnostics diagnostics;
    auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
    EXPECT_TRUE(baked.ok()) << baked.status().message();
    return baked.ok() ? baked->glb : std::vector<uint8_t>();
}

// One model whose blob is format 5 with a root block and a few dozen others (default block sizes).
const std::vector<uint8_t>& regionPack() {
    static const std::vector<uint8_t>* glb =
        new std::vector<uint8_t>(bakeWaves(lodbake::BakeSettings{}.pfrep_region_block));
    return *glb;
}

// The region blob as stored, its file offset, and the format 2 table every block together makes.
struct RegionBlob {
    uint32_t view = 0;
    uint64_t file_offset = 0;
    std::vector<uint8_t> bytes;
    std::vector<uint8_t> format2;
    lodrt::PfrepModel whole;
    lodrt::PfrepRegionInfo info;
    std::vector<lodrt::PfrepRegionBlock> blocks;
};

RegionBlob regionBlob(const lodrt::PackSource& source, const std::vector<uint8_t>& glb) {
    RegionBlob b;
    const lodrt::Pack& pack = source.pack();
    const lodrt::JsonValue ext = pack.mesh(source.models().modelLevel(0, 0).mesh)
                                     .json.find("extensions")
                                     .find(lodrt::format::kExtProgressiveFans);
    uint64_t view = 0, format = 0;
    EXPECT_TRUE(ext.find("bufferView").asUint64(&view));
    EXPECT_TRUE(ext.find(lodrt::format::kPfrepExtensionFormatMember).asUint64(&format));
    EXPECT_EQ(format, lodrt::format::kPfrepFormatRegions);
    b.view = uint32_t(view);
    b.bytes.resize(pack.bufferView(b.view).byte_length);
    EXPECT_EQ(source.readBufferView(b.view, 0, b.bytes.data(), b.bytes.size()), lodrt::Result::Ok);
    uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    b.file_offset = 20 + uint64_t(json_length) + 8 + pack.bufferView(b.view).byte_offset;
    EXPECT_EQ(lodrt::pfrepRegionInfo(b.bytes.data(), b.bytes.size(), &b.info), lodrt::Result::Ok);
    b.format2.assign(b.info.decoded_bytes, 0);
    std::vector<uint64_t> state((b.info.state_bytes + 7) / 8);
    lodrt::PfrepRegions regions;
    EXPECT_EQ(lodrt::pfrepRegionOpen(b.bytes.data(), b.bytes.size(), b.format2.data(), b.format2.size(), state.data(),
                                     state.size() * 8, &regions),
              lodrt::Result::Ok);
    for (uint32_t k = 0; k < regions.block_count; ++k) {
        b.blocks.push_back(regions.blocks[k]);
        EXPECT_EQ(
            lodrt::pfrepRegionLoadBlock(&regions, k, b.bytes.data() + regions.blocks[k].offset, regions.blocks[k].size),
            lodrt::Result::Ok);
    }
    EXPECT_EQ(lodrt::openPfrep(b.format2.data(), b.format2.size(), &b.whole), lodrt::Result::Ok);
    return b;
}

// A range reader over the pack in memory that counts the bytes it serves inside the blob.
struct CountingFile {
    std::vector<uint8_t> bytes;
    uint64_t watch_begin = 0, watch_end = 0;
    uint64_t watched_bytes = 0;
    static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
        CountingFile* f = static_cast<CountingFile*>(user);
        if (offset > f->bytes.size() || size > f->bytes.size() - offset) return lodrt::Result::Truncated;
        const uint64_t lo = std::max(offset, f->watch_begin), hi = std::min(offset + size, f->watch_end);
        if (hi > lo) f->watched_bytes += hi - lo;
        std::memcpy(dst, f->bytes.data() + offset, size);
        return lodrt::Result::Ok;
    }
    lodrt::RangeReader reader() { return lodrt::RangeReader{&CountingFile::read, this}; }
};

// Close over one corner of the field, looking at it: 1 px at a 1000 px viewport, a frustum that
// sees x, y <= 0.25 (two side planes; the others all-zero, which accept everything).
lodrt::PfrepView cornerView() {
    lodrt::PfrepView view;
    view.eye[0] = -0.02f;
    view.eye[1] = -0.02f;
    view.eye[2] = 0.08f;
    const float planes[2][4] = {{-1, 0, 0, 0.25f}, {0, -1, 0, 0.25f}};
    std::memcpy(view.planes, planes, sizeof(planes));
    view.pixels_per_unit_at_distance_one = 1000.0f;
    view.pixel_tolerance = 1.0f;
    return view;
}

// Refines `mask` from the coarsest mesh until the view is a fixed point.
void refineToFixedPoint(const lodrt::PfrepModel& model, const lodrt::PfrepView& view, std::vector<uint8_t>& mask) {
    mask.assign(lodrt::pfrepMaskBytes(model), 0);
    lodrt::pfrepMaskCoarsest(model, mask.data());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(model));
    for (int step = 0; step < 1000; ++step) {
        size_t changes = 0;
        ASSERT_EQ(lodrt::pfrepRefine(model, view, mask.data(), scratch.data(), scratch.size(), &changes),
                  lodrt::Result::Ok);
        if (changes == 0) return;
    }
    FAIL() << "no fixed point";
}

// The blocks the streamer loads for a view: those listed at its insert threshold.
std::vector<uint32_t> neededBlocks(const lodrt::PfrepRegions& regions, const lodrt::PfrepView& view) {
    lodrt::PfrepView insert = view;
    insert.hysteresis = 1.0f;
    insert.cull_hysteresis = 0.0f;
    std::vector<uint32_t> blocks(regions.block_count);
    size_t count = 0;
    EXPECT_EQ(lodrt::pfrepRegionBlocksNeeded(regions, insert, blocks.data(), blocks.size(), &count), lodrt::Result::Ok);
    blocks.resize(count);
    return blocks;
}

std::vector<uint32_t> loadedBlocks(const lodrt::PfrepRegions& regions) {
    std::vector<uint32_t> loaded;
    for (uint32_t k = 0; k < regions.block_count; ++k)
        if (regions.block_loaded[k]) loaded.push_back(k);
    return loaded;
}

// No view: the header, the opening and the root block arrive (pinned) and nothing else. A view close
// to one corner: exactly the blocks it needs are read, once each, in requests of at most
// pfrep_blocks_per_request blocks; refinement on the streamed model then gives the same mask and mesh
// as on the whole table, from a fraction of the blob's bytes.
TEST(PfrepRegionStreamingTest, LoadsTheBlocksAViewNeedsAndRefinesAsTheWholeTable) {
    CountingFile file;
    file.bytes = regionPack();
    ASSERT_FALSE(file.bytes.empty());
    lodrt::PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), lodrt::Result::Ok);
    const RegionBlob blob = regionBlob(source, file.bytes);
    ASSERT_GE(blob.blocks.size(), 12u);
    file.watch_begin = blob.file_offset;
    file.watch_end = blob.file_offset + blob.bytes.size();

    lodrt_test::ManualJobs jobs;
    const lodrt::JobSystem system = jobs.system();
    lodrt::StreamerOptions options;
    options.pfrep_blocks_per_request = 3;
    lodrt::Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, &options), lodrt::Result::Ok);
    streamer.update(nullptr);
    EXPECT_EQ(streamer.pfrepState(0), lodrt::PfrepStreamState::Loading);
    for (int i = 0; i < 6; ++i) {
        jobs.runAll();
        streamer.update(nullptr);
    }
    ASSERT_EQ(streamer.pfrepState(0), lodrt::PfrepStreamState::Resident);
    const lodrt::PfrepRegions* regions = streamer.pfrepRegions(0);
    ASSERT_NE(regions, nullptr);
    ASSERT_NE(streamer.pfrepModel(0), nullptr);
    EXPECT_EQ(streamer.pfrepModel(0), &regions->model);
    EXPECT_EQ(loadedBlocks(*regions), std::vector<uint32_t>{0});
    EXPECT_EQ(file.watched_bytes, lodrt::format::kPfrepRegionHeaderSize + blob.info.open_bytes + blob.blocks[0].size);
    EXPECT_EQ(streamer.stats().pfrep_blocks_loaded, 1u);
    // The coarse levels the root holds extract as from the whole table.
    const uint8_t covered = streamer.pfrepLevel(0);
    ASSERT_NE(covered, lodrt::kNoLevel);
    EXPECT_GT(covered, 0u);

    const lodrt::PfrepView view = cornerView();
    const std::vector<uint32_t> needed = neededBlocks(*regions, view);
    ASSERT_GT(needed.size(), 4u);
    ASSERT_LT(needed.size(), blob.blocks.size());
    uint32_t requests = streamer.stats().requests;
    for (int frame = 0; frame < 40; ++frame) {
        streamer.wantPfrepBlocks(0, view, 2.0f);
        streamer.update(nullptr);
        jobs.runAll();
    }
    streamer.update(nullptr);
    EXPECT_EQ(loadedBlocks(*regions), needed);
    uint64_t block_bytes = 0;
    for (uint32_t k : needed) block_bytes += blob.blocks[k].size;
    EXPECT_EQ(file.watched_bytes, lodrt::format::kPfrepRegionHeaderSize + blob.info.open_bytes + block_bytes);
    EXPECT_LT(file.watched_bytes, blob.bytes.size() * 3 / 4);
    requests = streamer.stats().requests - requests;
    EXPECT_EQ(requests, (needed.size() - 1 + 2) / 3); // three blocks per request, root excluded
    EXPECT_EQ(streamer.stats().pfrep_blocks_loaded, needed.size());
    EXPECT_EQ(streamer.stats().failures, 0u);

    std::vector<uint8_t> streamed_mask, whole_mask;
    refineToFixedPoint(*streamer.pfrepModel(0), view, streamed_mask);
    refineToFixedPoint(blob.whole, view, whole_mask);
    EXPECT_EQ(streamed_mask, whole_mask);
    EXPECT_EQ(lodbake_test::pfrepSelective(*streamer.pfrepModel(0), streamed_mask),
              lodbake_test::pfrepSelective(blob.whole, whole_mask));
    // The view refined below what the root block alone holds.
    uint32_t present_below_root = 0;
    for (uint32_t v = 0; v < blob.whole.vertex_count; ++v)
        if (!((whole_mask[v >> 3] >> (v & 7)) & 1) && v < streamer.pfrepRegions(0)->model.vertex_count - 4096)
            ++present_below_root;
    EXPECT_GT(present_below_root, 100u);
    // No view any more: nothing else is read.
    const uint64_t before = file.watched_bytes;
    for (int frame = 0; frame < 4; ++frame) {
        streamer.update(nullptr);
        jobs.runAll();
    }
    EXPECT_EQ(file.watched_bytes, before);
}

// The opening, the root block and the block reads in flight count towards the budget; a view whose
// blocks do not fit waits, and the budget holds at every update.
TEST(PfrepRegionStreamingTest, BudgetCountsTheOpeningAndTheReads) {
    const std::vector<uint8_t>& bytes = regionPack();
    ASSERT_FALSE(bytes.empty());
    lodrt::PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), lodrt::Result::Ok);
    const RegionBlob blob = regionBlob(source, bytes);
    lodrt::StreamerOptions options; // 16 blocks per request, more than the budget leaves room for
    // Room for the levels the pack pins, the stream's allocation and a little more.
    lodrt::Streamer probe;
    ASSERT_EQ(probe.init(&source, nullptr, nullptr), lodrt::Result::Ok);
    probe.update(nullptr);
    probe.update(nullptr);
    probe.update(nullptr);
    ASSERT_EQ(probe.pfrepState(0), lodrt::PfrepStreamState::Resident);
    const uint64_t pinned = probe.stats().resident_bytes;
    // pfrepDecodeMemory reports that allocation and the opening's read, from the header alone.
    uint64_t kept = 0, scratch = 0;
    ASSERT_EQ(source.pfrepDecodeMemory(0, &kept, &scratch), lodrt::Result::Ok);
    EXPECT_EQ(probe.stats().pfrep_resident_bytes, kept);
    EXPECT_GE(kept, blob.info.decoded_bytes + blob.info.state_bytes);
    EXPECT_EQ(scratch, blob.info.open_bytes);
    const uint64_t largest_pair =
        2 * std::max_element(blob.blocks.begin() + 1, blob.blocks.end(), [](const auto& a, const auto& b) {
                return a.size < b.size;
            })->size;
    options.budget_bytes = pinned + largest_pair;
    lodrt::Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, &options), lodrt::Result::Ok);
    const lodrt::PfrepView view = cornerView();
    for (int frame = 0; frame < 60; ++frame) {
        streamer.wantPfrepBlocks(0, view, 1.0f);
        streamer.update(nullptr);
        const lodrt::StreamStats s = streamer.stats();
        EXPECT_LE(s.resident_bytes + s.in_flight_bytes, options.budget_bytes) << "frame " << frame;
    }
    const lodrt::PfrepRegions* regions = streamer.pfrepRegions(0);
    ASSERT_NE(regions, nullptr);
    EXPECT_EQ(loadedBlocks(*regions), neededBlocks(*regions, view));
    EXPECT_EQ(streamer.stats().resident_bytes, pinned); // blocks fill the opened buffer; reads are transient
}

// Every byte of the blob is hostile: a changed byte in a block fails that block alone (the others and
// the refinement go on), and changes in the header, directory or skeleton fail the stream; nothing
// crashes (sanitizer job), and a failed block is never read again.
TEST(PfrepRegionStreamingTest, CorruptBlocksFailAloneAndNeverCrash) {
    const std::vector<uint8_t>& clean = regionPack();
    ASSERT_FALSE(clean.empty());
    lodrt::PackSource clean_source;
    ASSERT_EQ(clean_source.openBytes(clean.data(), clean.size(), nullptr), lodrt::Result::Ok);
    const RegionBlob blob = regionBlob(clean_source, clean);
    const lodrt::PfrepView view = cornerView();
    // Offsets inside the blob to damage: the header and opening every 97 bytes, the root block, and
    // bytes of several needed blocks (their rank lists, records and entries).
    std::vector<uint64_t> offsets;
    for (uint64_t at = 0; at < blob.info.open_bytes; at += 97) offsets.push_back(at);
    for (uint32_t at = 0; at < blob.blocks[0].size; at += blob.blocks[0].size / 5 + 1)
        offsets.push_back(blob.blocks[0].offset + at);
    for (uint32_t k = 1; k < blob.blocks.size(); k += 5)
        for (uint32_t at = 0; at < blob.blocks[k].size; at += blob.blocks[k].size / 7 + 1)
            offsets.push_back(blob.blocks[k].offset + at);
    uint32_t failed_streams = 0, failed_blocks = 0;
    for (uint64_t at : offsets) {
        SCOPED_TRACE("offset " + std::to_string(at));
        std::vector<uint8_t> bytes = clean;
        bytes[blob.file_offset + at] ^= 0x5a;
        lodrt::PackSource source;
        ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), lodrt::Result::Ok);
        lodrt::Streamer streamer;
        ASSERT_EQ(streamer.init(&source, nullptr, nullptr), lodrt::Result::Ok);
        std::vector<uint8_t> mask;
        std::vector<uint32_t> scratch;
        for (int frame = 0; frame < 12; ++frame) {
            streamer.wantPfrepBlocks(0, view, 1.0f);
            streamer.update(nullptr);
            const lodrt::PfrepModel* model = streamer.pfrepModel(0);
            if (!model) continue;
            if (mask.empty()) {
                mask.assign(lodrt::pfrepMaskBytes(*model), 0);
                lodrt::pfrepMaskCoarsest(*model, mask.data());
                scratch.resize(lodrt::pfrepScratchValues(*model));
            }
            size_t changes = 0;
            EXPECT_EQ(lodrt::pfrepRefine(*model, view, mask.data(), scratch.data(), scratch.size(), &changes),
                      lodrt::Result::Ok);
        }
        const lodrt::StreamStats s = streamer.stats();
        if (streamer.pfrepState(0) == lodrt::PfrepStreamState::Failed) {
            ++failed_streams;
            // Nothing of a failed stream stays held (a bad root block frees the opening's allocation).
            EXPECT_EQ(s.pfrep_resident_bytes, 0u);
            EXPECT_EQ(streamer.pfrepRegions(0), nullptr);
            continue;
        }
        EXPECT_EQ(streamer.pfrepState(0), lodrt::PfrepStreamState::Resident);
        if (s.failures > 0) {
            ++failed_blocks;
            EXPECT_EQ(s.failures, 1u);
            // Every other needed block loaded.
            const lodrt::PfrepRegions* regions = streamer.pfrepRegions(0);
            ASSERT_NE(regions, nullptr);
            EXPECT_EQ(loadedBlocks(*regions).size() + 1, neededBlocks(*regions, view).size());
        }
    }
    EXPECT_GT(failed_streams, 0u);
    EXPECT_GT(failed_blocks, 0u);
}

// Jobs on their own threads while the frame refines an instance on the streamed model every frame:
// the same blocks arrive and the settled mask is the whole table's.
TEST(PfrepRegionStreamingTest, WorkerThreadsStageWhileTheFrameRefines) {
    const std::vector<uint8_t>& bytes = regionPack();
    ASSERT_FALSE(bytes.empty());
    lodrt::PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), lodrt::Result::Ok);
    const RegionBlob blob = regionBlob(source, bytes);
    const lodrt::PfrepView view = cornerView();
    lodrt_test::ThreadJobs threads;
    const lodrt::JobSystem system = threads.system();
    std::vector<uint8_t> mask;
    {
        lodrt::Streamer streamer;
        lodrt::StreamerOptions options;
        options.pfrep_blocks_per_request = 1;
        ASSERT_EQ(streamer.init(&source, &system, &options), lodrt::Result::Ok);
        std::vector<uint32_t> scratch;
        std::vector<uint32_t> needed;
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
        while (std::chrono::steady_clock::now() < deadline) {
            streamer.wantPfrepBlocks(0, view, 1.0f);
            streamer.update(nullptr);
            const lodrt::PfrepModel* model = streamer.pfrepModel(0);
            if (model) {
                if (mask.empty()) {
                    mask.assign(lodrt::pfrepMaskBytes(*model), 0);
                    lodrt::pfrepMaskCoarsest(*model, mask.data());
                    scratch.resize(lodrt::pfrepScratchValues(*model));
                    needed = neededBlocks(*streamer.pfrepRegions(0), view);
                }
                size_t changes = 0;
                ASSERT_EQ(lodrt::pfrepRefine(*model, view, mask.data(), scratch.data(), scratch.size(), &changes),
                          lodrt::Result::Ok);
                if (changes == 0 && streamer.idle() && loadedBlocks(*streamer.pfrepRegions(0)) == needed) break;
            }
            std::this_thread::sleep_for(std::chrono::microseconds(100));
        }
        ASSERT_FALSE(mask.empty());
        EXPECT_EQ(loadedBlocks(*streamer.pfrepRegions(0)), needed);
        // Refined while blocks arrived: the mask may have taken another path, but it is a valid
        // refinement of the same table; from the coarsest mesh it settles as on the whole table.
        std::vector<uint8_t> settled, whole;
        refineToFixedPoint(*streamer.pfrepModel(0), view, settled);
        refineToFixedPoint(blob.whole, view, whole);
        EXPECT_EQ(settled, whole);
    }
}

// pfrep_region_block sizes the blocks the bake writes: a quarter of the default gives about four
// times the blocks, none above it (the root block aside).
TEST(PfrepRegionStreamingTest, RegionBlockSettingSizesTheBlocks) {
    const std::vector<uint8_t> small = bakeWaves(256);
    ASSERT_FALSE(small.empty());
    lodrt::PackSource small_source, default_source;
    ASSERT_EQ(small_source.openBytes(small.data(), small.size(), nullptr), lodrt::Result::Ok);
    ASSERT_EQ(default_source.openBytes(regionPack().data(), regionPack().size(), nullptr), lodrt::Result::Ok);
    const RegionBlob a = regionBlob(small_source, small), b = regionBlob(default_source, regionPack());
    EXPECT_GE(a.blocks.size(), 3 * b.blocks.size());
    uint32_t largest_small = 0, largest_default = 0;
    for (size_t k = 1; k < a.blocks.size(); ++k) largest_small = std::max(largest_small, a.blocks[k].vertices);
    for (size_t k = 1; k < b.blocks.size(); ++k) largest_default = std::max(largest_default, b.blocks[k].vertices);
    EXPECT_LE(largest_small, 256u);
    EXPECT_GT(largest_default, 256u);
    // The same table either way.
    EXPECT_EQ(a.format2, b.format2);
}

// A source that serves another opening than the header it served first (a file replaced between
// the reads, or a hostile server): here the opening of the same table cut into four times fewer
// blocks, consistent in itself. The allocation and the per-block arrays were sized from the first
// header, so the stream fails and frees its allocation; nothing is read or written beyond it
// (sanitizer job).
TEST(PfrepRegionStreamingTest, AnOpeningWithAnotherHeaderFailsTheStream) {
    CountingFile file;
    file.bytes = bakeWaves(256);
    ASSERT_FALSE(file.bytes.empty());
    lodrt::PackSource first_source, other_source;
    ASSERT_EQ(first_source.openBytes(file.bytes.data(), file.bytes.size(), nullptr), lodrt::Result::Ok);
    ASSERT_EQ(other_source.openBytes(regionPack().data(), regionPack().size(), nullptr), lodrt::Result::Ok);
    const RegionBlob first = regionBlob(first_source, file.bytes), other = regionBlob(other_source, regionPack());
    ASSERT_GT(first.blocks.size(), other.blocks.size());
    ASSERT_LE(other.info.open_bytes, first.info.open_bytes);
    struct Swapping {
        CountingFile* file;
        uint64_t blob_offset;
        const std::vector<uint8_t>* other_blob;
        static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
            Swapping* s = static_cast<Swapping*>(user);
            const lodrt::Result r = CountingFile::read(s->file, offset, dst, size);
            if (r == lodrt::Result::Ok && offset == s->blob_offset && size > lodrt::format::kPfrepRegionHeaderSize)
                std::memcpy(dst, s->other_blob->data(), std::min(size, s->other_blob->size()));
            return r;
        }
    } swapping{&file, first.file_offset, &other.bytes};
    lodrt::PackSource source;
    ASSERT_EQ(source.openReader(lodrt::RangeReader{&Swapping::read, &swapping}, file.bytes.size(), nullptr),
              lodrt::Result::Ok);
    lodrt::Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, nullptr), lodrt::Result::Ok);
    for (int frame = 0; frame < 8; ++frame) {
        streamer.wantPfrepBlocks(0, cornerView(), 1.0f);
        streamer.update(nullptr);
    }
    EXPECT_EQ(streamer.pfrepState(0), lodrt::PfrepStreamState::Failed);
    EXPECT_EQ(streamer.pfrepModel(0), nullptr);
    EXPECT_EQ(streamer.pfrepRegions(0), nullptr);
    EXPECT_EQ(streamer.stats().pfrep_resident_bytes, 0u);
    EXPECT_EQ(streamer.stats().in_flight_bytes, 0u);
}

} // namespace region_streaming
