#include <cstring>
#include <deque>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lod_pack_builder.h"
#include "lodrt/streaming.h"
#include "manual_jobs.h"

using lodrt::kMaxLevels;
using lodrt::kNoLevel;
using lodrt::LevelState;
using lodrt::ModelDemand;
using lodrt::PackSource;
using lodrt::RangeReader;
using lodrt::Result;
using lodrt::Streamer;

namespace {

using lodrt_test::ManualJobs;

struct File {
    std::vector<uint8_t> bytes;
    std::vector<std::pair<uint64_t, size_t>> reads;
    static Result read(void* user, uint64_t offset, void* dst, size_t size) {
        File* f = static_cast<File*>(user);
        f->reads.push_back({offset, size});
        if (offset > f->bytes.size() || size > f->bytes.size() - offset) return Result::Truncated;
        std::memcpy(dst, f->bytes.data() + offset, size);
        return Result::Ok;
    }
    RangeReader reader() { return RangeReader{&File::read, this}; }
};

} // namespace

TEST(StreamingTest, ReaderReadsOnlyHeaderAndJsonUpFront) {
    File file;
    lodrt_test::LodPackSpec spec;
    spec.chains = 2;
    file.bytes = lodrt_test::lodPackGlb(spec);
    PackSource source;
    char message[256] = "";
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr, message, sizeof(message)), Result::Ok)
        << message;
    uint64_t read_bytes = 0;
    for (auto& r : file.reads) read_bytes += r.second;
    const size_t bin_size = lodrt_test::lodPackBin(spec).size();
    EXPECT_EQ(read_bytes, file.bytes.size() - bin_size); // header, JSON chunk, BIN chunk header
    ASSERT_EQ(source.models().modelCount(), 2u);
    PackSource in_memory;
    ASSERT_EQ(in_memory.openBytes(file.bytes.data(), file.bytes.size(), nullptr), Result::Ok);
    for (uint32_t m = 0; m < 2; ++m)
        for (uint32_t l = 0; l < 4; ++l) {
            std::vector<uint8_t> a(source.levelBytes(m, l)), b(in_memory.levelBytes(m, l));
            ASSERT_EQ(source.readLevel(m, l, a.data(), a.size()), Result::Ok);
            ASSERT_EQ(in_memory.readLevel(m, l, b.data(), b.size()), Result::Ok);
            EXPECT_EQ(a, b);
            const uint8_t* indices = source.accessorData(m, l, a.data(), 2 * (m * 4 + l) + 1);
            ASSERT_NE(indices, nullptr);
            EXPECT_EQ(indices[2 * 2], 2); // third index of the triangle
        }
    std::vector<uint8_t> small(3);
    EXPECT_EQ(source.readLevel(0, 0, small.data(), small.size()), Result::BufferTooSmall);
    // Indices widened into caller memory after asking for the bound.
    std::vector<uint8_t> level(source.levelBytes(1, 2));
    ASSERT_EQ(source.readLevel(1, 2, level.data(), level.size()), Result::Ok);
    ASSERT_EQ(source.levelIndexCount(1, 2), 3u);
    std::vector<uint32_t> indices(3);
    size_t written = 0;
    ASSERT_EQ(source.copyLevelIndices(1, 2, level.data(), indices.data(), indices.size(), &written), Result::Ok);
    EXPECT_EQ(written, 3u);
    EXPECT_EQ(indices, (std::vector<uint32_t>{0, 1, 2}));
    EXPECT_EQ(source.copyLevelIndices(1, 2, level.data(), indices.data(), 2, &written), Result::BufferTooSmall);
}

TEST(StreamingTest, ReaderRejectsBrokenContainers) {
    File good;
    good.bytes = lodrt_test::lodPackGlb();
    for (size_t n = 0; n < good.bytes.size(); ++n) {
        File f;
        f.bytes.assign(good.bytes.begin(), good.bytes.begin() + n);
        PackSource source;
        EXPECT_NE(source.openReader(f.reader(), f.bytes.size(), nullptr), Result::Ok) << n;
    }
    File f = good;
    f.bytes[0] = 'x';
    PackSource source;
    EXPECT_EQ(source.openReader(f.reader(), f.bytes.size(), nullptr), Result::BadMagic);
    f = good;
    f.bytes[4] = 3;
    EXPECT_EQ(source.openReader(f.reader(), f.bytes.size(), nullptr), Result::UnsupportedVersion);
    f = good;
    f.bytes.push_back(0);
    EXPECT_EQ(source.openReader(f.reader(), f.bytes.size(), nullptr), Result::TrailingBytes);
    // A reader that fails is reported, not ignored.
    RangeReader failing{[](void*, uint64_t, void*, size_t) { return Result::OutOfBounds; }, nullptr};
    EXPECT_EQ(source.openReader(failing, good.bytes.size(), nullptr), Result::OutOfBounds);
}

TEST(StreamingTest, CoarsestLevelsFirstAndNothingBlocks) {
    File file;
    lodrt_test::LodPackSpec spec;
    spec.chains = 3;
    file.bytes = lodrt_test::lodPackGlb(spec);
    PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
    ManualJobs jobs;
    lodrt::JobSystem system = jobs.system();
    lodrt::StreamerOptions options;
    options.max_in_flight = 8;
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, &options), Result::Ok);
    std::vector<ModelDemand> demand(3);
    demand[1] = {0, 10.0f}; // model 1 wants full detail
    streamer.update(demand.data());
    // Submitted, not run: nothing is resident and the frame went on.
    EXPECT_EQ(jobs.queue.size(), 6u); // 3 coarsest levels first, then model 1's levels 0, 1, 2 ... up to 8
    for (uint32_t m = 0; m < 3; ++m) EXPECT_EQ(streamer.state(m, 3), LevelState::Loading);
    EXPECT_EQ(streamer.residentTable()[1 * kMaxLevels + 0], kNoLevel);
    EXPECT_FALSE(streamer.idle());
    jobs.runAll();
    streamer.update(demand.data());
    EXPECT_TRUE(streamer.idle());
    for (uint32_t m = 0; m < 3; ++m) EXPECT_EQ(streamer.state(m, 3), LevelState::Resident);
    EXPECT_EQ(streamer.residentTable()[1 * kMaxLevels + 0], 0);
    EXPECT_EQ(streamer.residentTable()[0 * kMaxLevels + 0], 3); // model 0: only its coarsest level
    size_t size = 0;
    EXPECT_NE(streamer.levelData(1, 0, &size), nullptr);
    EXPECT_EQ(size, source.levelBytes(1, 0));
    const lodrt::StreamStats stats = streamer.stats();
    EXPECT_EQ(stats.resident_levels, 6u);
    EXPECT_EQ(stats.streamed_bytes, stats.resident_bytes);
    EXPECT_EQ(stats.in_flight_bytes, 0u);
}

TEST(StreamingTest, BudgetEvictsLeastUsefulLevelsFirst) {
    lodrt_test::LodPackSpec spec;
    spec.chains = 2;
    const std::vector<uint8_t> bytes = lodrt_test::lodPackGlb(spec);
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    const uint64_t level_bytes = source.levelBytes(0, 0); // 42: every level is one triangle
    lodrt::StreamerOptions options;
    options.budget_bytes = level_bytes * 5; // two coarsest levels + three more
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, &options), Result::Ok); // inline jobs
    std::vector<ModelDemand> demand(2);
    demand[0] = {0, 10.0f}; // model 0 close
    demand[1] = {2, 1.0f};  // model 1 far
    streamer.update(demand.data());
    // Usefulness: model 0 level 0: 10, level 1: 5, level 2: 3.3; model 1 level 2: 1.
    EXPECT_EQ(streamer.state(0, 0), LevelState::Resident);
    EXPECT_EQ(streamer.state(0, 1), LevelState::Resident);
    EXPECT_EQ(streamer.state(0, 2), LevelState::Resident);
    EXPECT_EQ(streamer.state(1, 2), LevelState::Absent);
    EXPECT_LE(streamer.stats().resident_bytes, options.budget_bytes);
    // The camera turns to model 1: model 0's fine levels go, least useful (finest unwanted) first.
    demand[0] = {2, 1.0f};
    demand[1] = {0, 10.0f};
    streamer.update(demand.data());
    EXPECT_EQ(streamer.state(1, 0), LevelState::Resident);
    EXPECT_EQ(streamer.state(0, 0), LevelState::Absent);
    EXPECT_EQ(streamer.state(0, 1), LevelState::Absent);
    EXPECT_EQ(streamer.state(0, 3), LevelState::Resident); // coarsest: never evicted
    EXPECT_EQ(streamer.state(1, 3), LevelState::Resident);
    EXPECT_LE(streamer.stats().resident_bytes, options.budget_bytes);
    EXPECT_GE(streamer.stats().evictions, 2u);
}

TEST(StreamingTest, BadIndicesFailOnlyTheirLevel) {
    lodrt_test::LodPackSpec spec;
    spec.bad_index_level = 1;
    const std::vector<uint8_t> bytes = lodrt_test::lodPackGlb(spec);
    // A full load scans the indices and refuses the pack; the source defers the check to the level.
    lodrt::Pack pack;
    EXPECT_EQ(lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack), Result::OutOfBounds);
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
    ModelDemand demand{0, 1.0f};
    streamer.update(&demand);
    streamer.update(&demand);
    EXPECT_EQ(streamer.state(0, 1), LevelState::Failed);
    EXPECT_EQ(streamer.state(0, 0), LevelState::Resident);
    EXPECT_EQ(streamer.stats().failures, 1u);
    EXPECT_EQ(streamer.residentTable()[1], 2); // level 1 falls back to level 2
}

TEST(StreamingTest, MutatedPacksNeverCrash) {
    lodrt_test::LodPackSpec spec;
    spec.chains = 2;
    const std::vector<uint8_t> good = lodrt_test::lodPackGlb(spec);
    std::mt19937 rng(1234);
    int opened = 0;
    for (int iteration = 0; iteration < 3000; ++iteration) {
        File file;
        file.bytes = good;
        const int edits = 1 + int(rng() % 4);
        for (int e = 0; e < edits; ++e) {
            const size_t at = rng() % file.bytes.size();
            const uint32_t kind = rng() % 3;
            if (kind == 0) file.bytes[at] = uint8_t(rng());
            if (kind == 1) file.bytes[at] = uint8_t("0123456789[]{},-\"e."[rng() % 19]);
            if (kind == 2) file.bytes[at] ^= uint8_t(1u << (rng() % 8));
        }
        for (int mode = 0; mode < 2; ++mode) {
            PackSource source;
            const Result r = mode == 0 ? source.openBytes(file.bytes.data(), file.bytes.size(), nullptr)
                                       : source.openReader(file.reader(), file.bytes.size(), nullptr);
            if (r != Result::Ok) continue;
            ++opened;
            Streamer streamer;
            ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
            std::vector<ModelDemand> demand(source.models().modelCount(), ModelDemand{0, 1.0f});
            streamer.update(demand.data());
            streamer.update(demand.data());
            for (uint32_t m = 0; m < source.models().modelCount(); ++m) {
                const lodrt::ModelInfo& model = source.models().model(m);
                EXPECT_GE(model.level_count, 1u);
                EXPECT_LE(model.level_count, kMaxLevels);
                for (uint32_t l = 0; l < model.level_count; ++l) {
                    size_t size = 0;
                    if (streamer.levelData(m, l, &size)) {
                        EXPECT_EQ(size, source.levelBytes(m, l));
                    }
                }
            }
        }
    }
    EXPECT_GT(opened, 100); // the mutations leave many packs valid enough to stream
}
