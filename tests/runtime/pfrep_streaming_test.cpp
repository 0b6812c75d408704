// PfrepStreamingTest: the Streamer streams a model's LODBAKE_progressive_fans blob as a growing
// prefix (lodrt/streaming.h). Lives in lodbake_tests because the pack is baked with the baker; the
// code under test is runtime code only.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <string>
#include <thread>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "lodrt/streaming.h"
#include "manual_jobs.h"
#include "test_paths.h"

namespace {

using lodrt::kNoLevel;
using lodrt::ModelDemand;
using lodrt::PackSource;
using lodrt::PfrepStreamState;
using lodrt::Result;
using lodrt::Streamer;
using lodrt_test::ManualJobs;

// A wavy height field of n x n vertices.
lodbake::Mesh heightField(int n, float phase) {
    lodbake::Mesh mesh;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            mesh.positions.push_back({float(x) / float(n - 1), float(y) / float(n - 1),
                                      0.05f * std::sin(0.3f * float(x) + phase) * std::cos(0.25f * float(y))});
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const uint32_t a = uint32_t(y * n + x), b = a + 1, c = a + uint32_t(n), d = c + 1;
            mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
        }
    return mesh;
}

// Two models, each with a multi-block PFRep blob (format 2, streamed as prefixes, or format 3,
// decoded whole); baked once per format for the suite.
std::vector<uint8_t>* bakePack(uint32_t pfrep_format) {
    {
        lodbake::BakeSettings settings;
        settings.pfrep_format = pfrep_format;
        settings.compact = pfrep_format == lodrt::format::kPfrepVersionLod0; // format 4 is for compact packs
        settings.lod_ratios = {0.5, 0.25, 0.1, 0.03};
        settings.error_samples = 2000;
        settings.threads = 2;
        std::vector<lodbake::BakeInput> inputs(2);
        inputs[0].name = "a";
        inputs[0].mesh = heightField(64, 0.0f);
        inputs[1].name = "b";
        inputs[1].mesh = heightField(64, 1.0f);
        lodbake::Diagnostics diagnostics;
        auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
        EXPECT_TRUE(baked.ok()) << baked.status().message();
        return new std::vector<uint8_t>(baked.ok() ? baked->glb : std::vector<uint8_t>());
    }
}

const std::vector<uint8_t>& bakedPack() {
    static const std::vector<uint8_t>* glb = bakePack(lodrt::format::kPfrepVersion);
    return *glb;
}

const std::vector<uint8_t>& bakedPack3() {
    static const std::vector<uint8_t>* glb = bakePack(lodrt::format::kPfrepVersionCompressed);
    return *glb;
}

// A range reader over a file in memory that counts the bytes it serves inside [watch_begin,
// watch_end) and fails every read that reaches past `cut` and starts before watch_end (a blob cut
// short, or a failing disk).
struct File {
    std::vector<uint8_t> bytes;
    uint64_t cut = UINT64_MAX;
    uint64_t watch_begin = 0, watch_end = 0;
    uint64_t watched_bytes = 0;
    static Result read(void* user, uint64_t offset, void* dst, size_t size) {
        File* f = static_cast<File*>(user);
        if (offset > f->bytes.size() || size > f->bytes.size() - offset) return Result::Truncated;
        if (offset + size > f->cut && offset < f->watch_end) return Result::Truncated;
        const uint64_t lo = std::max(offset, f->watch_begin), hi = std::min(offset + size, f->watch_end);
        if (hi > lo) f->watched_bytes += hi - lo;
        std::memcpy(dst, f->bytes.data() + offset, size);
        return Result::Ok;
    }
    lodrt::RangeReader reader() { return lodrt::RangeReader{&File::read, this}; }
};

// What the test knows about one model's blob, read straight from the pack.
struct Blob {
    uint32_t view = 0;
    uint64_t file_offset = 0; // of the view's first byte in the GLB
    std::vector<uint8_t> bytes;
    lodrt::PfrepModel whole;
    std::vector<uint32_t> removals; // per chain level
};

Blob blobOf(const PackSource& source, uint32_t model) {
    Blob b;
    const lodrt::Pack& pack = source.pack();
    const lodrt::LevelInfo& level0 = source.models().modelLevel(model, 0);
    const lodrt::JsonValue ext = pack.mesh(level0.mesh).json.find("extensions").find("LODBAKE_progressive_fans");
    uint64_t view = 0;
    EXPECT_TRUE(ext.find("bufferView").asUint64(&view));
    b.view = uint32_t(view);
    for (uint32_t l = 0; l < source.models().model(model).level_count; ++l) {
        uint64_t k = 0;
        EXPECT_TRUE(ext.find("levels").at(l).find("removals").asUint64(&k));
        b.removals.push_back(uint32_t(k));
    }
    b.bytes.resize(pack.bufferView(b.view).byte_length);
    EXPECT_EQ(source.readBufferView(b.view, 0, b.bytes.data(), b.bytes.size()), Result::Ok);
    EXPECT_EQ(lodrt::openPfrep(b.bytes.data(), b.bytes.size(), &b.whole), Result::Ok);
    uint32_t json_length = 0;
    std::memcpy(&json_length, bakedPack().data() + 12, 4);
    b.file_offset = 20 + uint64_t(json_length) + 8 + pack.bufferView(b.view).byte_offset;
    return b;
}

std::vector<uint32_t> extract(const lodrt::PfrepModel& model, uint32_t level) {
    std::vector<uint32_t> tris(3 * lodrt::pfrepMaxTriangles(model));
    size_t count = 0;
    EXPECT_EQ(lodrt::pfrepExtractLevel(model, level, tris.data(), tris.size() / 3, &count), Result::Ok);
    tris.resize(3 * count);
    return tris;
}

// Every chain level the streamed prefix claims to cover extracts exactly as from the whole blob.
void expectCoveredLevelsMatch(const Streamer& streamer, uint32_t model, const Blob& blob) {
    const lodrt::PfrepModel* m = streamer.pfrepModel(model);
    ASSERT_NE(m, nullptr);
    const uint8_t covered = streamer.pfrepLevel(model);
    if (covered == kNoLevel) return;
    for (uint32_t l = covered; l < blob.removals.size(); ++l) {
        SCOPED_TRACE("chain level " + std::to_string(l));
        ASSERT_GE(blob.removals[l], m->loaded_from);
        EXPECT_EQ(extract(*m, blob.removals[l]), extract(blob.whole, blob.removals[l]));
    }
}

void settle(Streamer& streamer, const ModelDemand* demand, uint64_t budget) {
    for (int i = 0; i < 60; ++i) {
        streamer.update(demand);
        if (budget > 0) {
            const lodrt::StreamStats s = streamer.stats();
            EXPECT_LE(s.resident_bytes + s.in_flight_bytes, budget) << "update " << i;
        }
    }
}

} // namespace

TEST(PfrepStreamingTest, PrefixGrowsWithDemandAndMatchesWholeBlob) {
    File file;
    file.bytes = bakedPack();
    ASSERT_FALSE(file.bytes.empty());
    PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
    ASSERT_EQ(source.models().modelCount(), 2u);
    const Blob blob = blobOf(source, 0);
    const uint32_t levels = source.models().model(0).level_count;
    ASSERT_GE(levels, 4u);
    ASSERT_GT(blob.whole.block_count, 4u); // enough blocks for prefixes to differ
    file.watch_begin = blob.file_offset;
    file.watch_end = blob.file_offset + blob.bytes.size();

    ManualJobs jobs;
    const lodrt::JobSystem system = jobs.system();
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, nullptr), Result::Ok);
    // No demand: only the header, then the directory (pinned, like coarsest levels); never blocks.
    streamer.update(nullptr);
    EXPECT_EQ(streamer.pfrepState(0), PfrepStreamState::Loading);
    EXPECT_EQ(streamer.pfrepModel(0), nullptr);
    EXPECT_EQ(file.watched_bytes, 0u); // submitted, not run
    for (int i = 0; i < 4; ++i) {
        jobs.runAll();
        streamer.update(nullptr);
    }
    ASSERT_EQ(streamer.pfrepState(0), PfrepStreamState::Resident);
    const lodrt::PfrepModel* directory = streamer.pfrepModel(0);
    ASSERT_NE(directory, nullptr);
    EXPECT_EQ(directory->size, lodrt::pfrepDirectoryBytes(blob.bytes.data(), blob.bytes.size()));
    EXPECT_EQ(streamer.pfrepLevel(0), kNoLevel);
    EXPECT_EQ(file.watched_bytes, directory->size + lodrt::format::kPfrepHeaderSize);

    // Demand rises from the coarsest chain level to full detail: the prefix grows to exactly the
    // bytes that level needs, and every covered level extracts as from the whole blob.
    std::vector<ModelDemand> demand(2);
    uint64_t previous = directory->size;
    std::vector<uint64_t> sizes;
    for (uint32_t wanted = levels; wanted-- > 0;) {
        SCOPED_TRACE("wanted level " + std::to_string(wanted));
        demand[0] = {uint8_t(wanted), 5.0f};
        for (int i = 0; i < 12; ++i) {
            streamer.update(demand.data());
            jobs.runAll();
        }
        streamer.update(demand.data());
        ASSERT_EQ(streamer.pfrepState(0), PfrepStreamState::Resident);
        EXPECT_EQ(streamer.pfrepLevel(0), wanted);
        const lodrt::PfrepModel* m = streamer.pfrepModel(0);
        ASSERT_NE(m, nullptr);
        uint64_t needed = lodrt::pfrepPrefixBytesForLevel(blob.whole, blob.removals[wanted]);
        if (needed < previous) needed = previous;
        EXPECT_EQ(m->size, needed);
        EXPECT_GE(m->size, previous);
        EXPECT_EQ(std::memcmp(m->data, blob.bytes.data(), m->size), 0);
        // Nothing beyond the prefix was read, and nothing twice.
        EXPECT_EQ(file.watched_bytes, m->size + lodrt::format::kPfrepHeaderSize);
        expectCoveredLevelsMatch(streamer, 0, blob);
        previous = m->size;
        if (sizes.empty() || sizes.back() != m->size) sizes.push_back(m->size);
        // Model 1 had no demand: directory only.
        EXPECT_EQ(streamer.pfrepLevel(1), kNoLevel);
    }
    EXPECT_LT(lodrt::pfrepPrefixBytesForLevel(blob.whole, blob.removals[levels - 1]), blob.bytes.size());
    EXPECT_EQ(previous, blob.bytes.size());
    EXPECT_GE(sizes.size(), 3u);                        // the prefix really grew in steps, not in one read
    EXPECT_EQ(streamer.pfrepModel(0)->loaded_from, 0u); // complete
    // One buffer per model: model 0's whole blob, model 1's directory.
    EXPECT_EQ(streamer.stats().pfrep_resident_bytes,
              blob.bytes.size() + lodrt::pfrepDirectoryBytes(blobOf(source, 1).bytes.data(), 64));
}

TEST(PfrepStreamingTest, BudgetShrinksLeastUsefulPrefix) {
    const std::vector<uint8_t>& bytes = bakedPack();
    ASSERT_FALSE(bytes.empty());
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    const Blob blob0 = blobOf(source, 0), blob1 = blobOf(source, 1);
    // Pinned bytes first (coarsest levels and directories), measured without a budget.
    uint64_t pinned = 0;
    {
        Streamer probe;
        ASSERT_EQ(probe.init(&source, nullptr, nullptr), Result::Ok);
        for (int i = 0; i < 4; ++i) probe.update(nullptr);
        pinned = probe.stats().resident_bytes;
    }
    // Room for one model's finest level and the growth of one blob (old and new buffers), not two.
    lodrt::StreamerOptions options;
    options.budget_bytes = pinned + std::max(source.levelBytes(0, 0), source.levelBytes(1, 0)) +
                           2 * std::max(blob0.bytes.size(), blob1.bytes.size());
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, &options), Result::Ok); // inline jobs
    std::vector<ModelDemand> demand(2);
    demand[0] = {0, 10.0f};
    settle(streamer, demand.data(), options.budget_bytes);
    EXPECT_EQ(streamer.pfrepLevel(0), 0);
    EXPECT_EQ(streamer.pfrepLevel(1), kNoLevel);
    EXPECT_EQ(streamer.stats().pfrep_shrinks, 0u);
    expectCoveredLevelsMatch(streamer, 0, blob0);

    // The camera turns: model 1 wants full detail, model 0 nothing. Model 0's prefix is shrunk step
    // by step to make room, stays valid, and model 1's grows to the whole blob.
    demand[0] = {kNoLevel, 0.0f};
    demand[1] = {0, 10.0f};
    settle(streamer, demand.data(), options.budget_bytes);
    EXPECT_EQ(streamer.pfrepLevel(1), 0);
    EXPECT_GT(streamer.stats().pfrep_shrinks, 0u);
    EXPECT_NE(streamer.pfrepLevel(0), 0);
    ASSERT_NE(streamer.pfrepModel(0), nullptr); // the directory is never dropped
    EXPECT_LT(streamer.pfrepModel(0)->size, blob0.bytes.size());
    expectCoveredLevelsMatch(streamer, 0, blob0);
    expectCoveredLevelsMatch(streamer, 1, blob1);
    // And back: the shrunk prefix grows again from where it stopped.
    demand[0] = {0, 10.0f};
    demand[1] = {kNoLevel, 0.0f};
    settle(streamer, demand.data(), options.budget_bytes);
    EXPECT_EQ(streamer.pfrepLevel(0), 0);
    expectCoveredLevelsMatch(streamer, 0, blob0);
}

TEST(PfrepStreamingTest, TruncatedReadsFailTheStreamNotTheFrame) {
    File good;
    good.bytes = bakedPack();
    ASSERT_FALSE(good.bytes.empty());
    PackSource probe;
    ASSERT_EQ(probe.openReader(good.reader(), good.bytes.size(), nullptr), Result::Ok);
    const Blob blob = blobOf(probe, 0);
    const uint64_t directory = lodrt::pfrepDirectoryBytes(blob.bytes.data(), blob.bytes.size());
    // The file is cut (reads fail) at points across model 0's blob: the stream keeps the longest
    // prefix it validated before the cut, reports Failed, and never reads or grows again.
    std::vector<uint64_t> cuts;
    for (uint64_t cut = 0; cut < blob.bytes.size(); cut += 97) cuts.push_back(cut);
    cuts.insert(cuts.end(), {directory - 1, directory, blob.bytes.size() - 1, blob.bytes.size()});
    int failed = 0, resident = 0;
    for (const uint64_t cut : cuts) {
        File file = good;
        file.cut = blob.file_offset + cut;
        file.watch_begin = blob.file_offset;
        file.watch_end = blob.file_offset + blob.bytes.size();
        PackSource source;
        ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
        Streamer streamer;
        ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
        std::vector<ModelDemand> demand(2, ModelDemand{0, 1.0f});
        for (int i = 0; i < 20; ++i) streamer.update(demand.data());
        const PfrepStreamState state = streamer.pfrepState(0);
        const lodrt::PfrepModel* m = streamer.pfrepModel(0);
        if (cut < blob.bytes.size()) {
            EXPECT_EQ(state, PfrepStreamState::Failed) << cut;
            ++failed;
        } else {
            EXPECT_EQ(state, PfrepStreamState::Resident);
            ++resident;
        }
        if (cut < directory) {
            EXPECT_EQ(m, nullptr) << cut;
        } else {
            ASSERT_NE(m, nullptr) << cut;
            EXPECT_LE(m->size, cut);
            expectCoveredLevelsMatch(streamer, 0, blob);
        }
        EXPECT_EQ(streamer.pfrepLevel(1), 0); // the other model is not affected
        if (cut < blob.bytes.size()) {
            EXPECT_GT(streamer.stats().failures, 0u);
        }
    }
    EXPECT_GT(failed, 5);
    EXPECT_EQ(resident, 1);
}

TEST(PfrepStreamingTest, CorruptBlobsAndObjectsNeverCrash) {
    const std::vector<uint8_t>& good = bakedPack();
    ASSERT_FALSE(good.empty());
    PackSource probe;
    ASSERT_EQ(probe.openBytes(good.data(), good.size(), nullptr), Result::Ok);
    const Blob blob = blobOf(probe, 0);
    uint32_t seed = 99;
    auto next = [&seed] {
        seed = seed * 1664525u + 1013904223u;
        return seed >> 8;
    };
    int failed = 0;
    for (int iteration = 0; iteration < 300; ++iteration) {
        std::vector<uint8_t> bytes = good;
        // Flip bytes inside model 0's blob, mostly in its header and directory.
        const uint64_t span = iteration % 2 ? blob.bytes.size() : std::min<uint64_t>(blob.bytes.size(), 256);
        for (int e = 0; e < 1 + iteration % 3; ++e)
            bytes[blob.file_offset + next() % span] ^= uint8_t(1 + next() % 255);
        PackSource source;
        ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
        Streamer streamer;
        ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
        std::vector<ModelDemand> demand(2, ModelDemand{0, 1.0f});
        for (int i = 0; i < 20; ++i) streamer.update(demand.data());
        const lodrt::PfrepModel* m = streamer.pfrepModel(0);
        if (streamer.pfrepState(0) == PfrepStreamState::Failed) ++failed;
        if (!m) continue;
        // Whatever was accepted was validated: extracting its loaded levels stays inside the bytes.
        std::vector<uint32_t> tris(3 * lodrt::pfrepMaxTriangles(*m));
        size_t count = 0;
        for (uint32_t k = m->loaded_from; k <= m->removed_count; k += 1 + m->removed_count / 8)
            EXPECT_EQ(lodrt::pfrepExtractLevel(*m, k, tris.data(), tris.size() / 3, &count), Result::Ok);
    }
    EXPECT_GT(failed, 10);

    // A hostile extension object (removals past the blob's removed count) fails the stream only.
    const std::string needle = "\"removals\":";
    std::vector<uint8_t> bytes = good;
    auto at = std::search(bytes.begin(), bytes.end(), needle.begin(), needle.end());
    ASSERT_NE(at, bytes.end());
    // The first entry is level 0 ("removals":0); make it 9 (still valid JSON, same length).
    ASSERT_EQ(*(at + long(needle.size())), '0');
    const std::string level1 = "\"removals\":";
    auto second = std::search(at + 1, bytes.end(), level1.begin(), level1.end());
    ASSERT_NE(second, bytes.end());
    // Give chain level 1 more removals than the blob has by rewriting its digits to 9s.
    std::string digits;
    for (auto p = second + long(level1.size()); p != bytes.end() && *p >= '0' && *p <= '9'; ++p) {
        *p = '9';
        digits += '9';
    }
    ASSERT_GT(std::stoull(digits), uint64_t(blob.whole.removed_count));
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
    std::vector<ModelDemand> demand(2, ModelDemand{0, 1.0f});
    for (int i = 0; i < 20; ++i) streamer.update(demand.data());
    // Whichever model's object was edited fails when its directory arrives; the other streams on.
    const uint32_t bad = streamer.pfrepState(0) == PfrepStreamState::Failed ? 0 : 1;
    EXPECT_EQ(streamer.pfrepState(bad), PfrepStreamState::Failed);
    EXPECT_EQ(streamer.pfrepLevel(bad), kNoLevel);
    EXPECT_EQ(streamer.pfrepState(1 - bad), PfrepStreamState::Resident);
    EXPECT_EQ(streamer.pfrepLevel(1 - bad), 0);
}

TEST(PfrepStreamingTest, WorkerThreadsReachTheSameResult) {
    const std::vector<uint8_t>& bytes = bakedPack();
    ASSERT_FALSE(bytes.empty());
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    const Blob blob = blobOf(source, 1);
    // Each job on its own thread: steps complete while the frame keeps calling update().
    lodrt_test::ThreadJobs threads;
    const lodrt::JobSystem system = threads.system();
    {
        Streamer streamer;
        ASSERT_EQ(streamer.init(&source, &system, nullptr), Result::Ok);
        std::vector<ModelDemand> demand(2);
        demand[1] = {0, 3.0f};
        // Bounded by time, not by a frame count: on a loaded machine the job threads may get
        // little of the CPU while this loop spins.
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
        while (streamer.pfrepLevel(1) != 0 && std::chrono::steady_clock::now() < deadline) {
            streamer.update(demand.data());
            std::this_thread::sleep_for(std::chrono::microseconds(100));
        }
        ASSERT_EQ(streamer.pfrepLevel(1), 0);
        EXPECT_EQ(streamer.pfrepModel(1)->size, blob.bytes.size());
        expectCoveredLevelsMatch(streamer, 1, blob);
        EXPECT_EQ(streamer.pfrepLevel(0), kNoLevel);
    } // the destructor waits for jobs still running
}

// Format 3 in a pack: one read of the whole coded blob, decoded on the job thread into the format 2
// bytes of the same input's format 2 pack, which then serve every chain level at once; the budget
// counts the decoded bytes.
TEST(PfrepStreamingTest, Format3DecodesWholeToTheFormat2Blob) {
    PackSource source2;
    ASSERT_EQ(source2.openBytes(bakedPack().data(), bakedPack().size(), nullptr), Result::Ok);
    File file;
    file.bytes = bakedPack3();
    ASSERT_FALSE(file.bytes.empty());
    EXPECT_LT(file.bytes.size(), bakedPack().size());
    PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
    ManualJobs jobs;
    const lodrt::JobSystem system = jobs.system();
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, nullptr), Result::Ok);
    streamer.update(nullptr);
    EXPECT_EQ(streamer.pfrepState(0), PfrepStreamState::Loading);
    EXPECT_EQ(streamer.pfrepModel(0), nullptr);
    for (int i = 0; i < 4; ++i) {
        jobs.runAll();
        streamer.update(nullptr);
    }
    uint64_t decoded = 0;
    for (uint32_t model = 0; model < 2; ++model) {
        SCOPED_TRACE("model " + std::to_string(model));
        const Blob blob = blobOf(source2, model); // the format 2 pack's blob of the same input
        ASSERT_EQ(streamer.pfrepState(model), PfrepStreamState::Resident);
        EXPECT_EQ(streamer.pfrepLevel(model), 0); // every chain level at once
        const lodrt::PfrepModel* m = streamer.pfrepModel(model);
        ASSERT_NE(m, nullptr);
        ASSERT_EQ(m->size, blob.bytes.size());
        EXPECT_EQ(std::memcmp(m->data, blob.bytes.data(), m->size), 0);
        EXPECT_EQ(m->loaded_from, 0u);
        expectCoveredLevelsMatch(streamer, model, blob);
        decoded += m->size;
        // What an engine sizes its allocator by before streaming: the decoded size read from the
        // header alone, and some scratch; a format 2 pack needs neither.
        uint64_t header_decoded = 0, scratch = 0;
        ASSERT_EQ(source.pfrepDecodeMemory(model, &header_decoded, &scratch), Result::Ok);
        EXPECT_EQ(header_decoded, m->size);
        EXPECT_GT(scratch, 0u);
        ASSERT_EQ(source2.pfrepDecodeMemory(model, &header_decoded, &scratch), Result::Ok);
        EXPECT_EQ(header_decoded, 0u);
        EXPECT_EQ(scratch, 0u);
    }
    EXPECT_EQ(streamer.stats().pfrep_resident_bytes, decoded);
    uint64_t d = 0, s = 0;
    EXPECT_EQ(source.pfrepDecodeMemory(2, &d, &s), Result::InvalidArgument);

    EXPECT_GE(streamer.stats().resident_bytes, decoded);
}

// Under the budget a decoded format 3 blob shrinks like a format 2 prefix (its bytes are format 2),
// and a demand for full detail afterwards decodes the whole blob again, to the same bytes.
TEST(PfrepStreamingTest, Format3ShrinksUnderTheBudgetAndDecodesAgain) {
    PackSource source2;
    ASSERT_EQ(source2.openBytes(bakedPack().data(), bakedPack().size(), nullptr), Result::Ok);
    const std::vector<uint8_t>& bytes = bakedPack3();
    ASSERT_FALSE(bytes.empty());
    PackSource source;
    ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
    // What is pinned (coarsest levels, both decoded blobs) and model 0's full-detail level.
    uint64_t pinned = 0;
    {
        Streamer probe;
        ASSERT_EQ(probe.init(&source, nullptr, nullptr), Result::Ok);
        for (int i = 0; i < 4; ++i) probe.update(nullptr);
        ASSERT_EQ(probe.pfrepLevel(0), 0);
        ASSERT_EQ(probe.pfrepLevel(1), 0);
        pinned = probe.stats().resident_bytes;
    }
    const uint64_t level0 = source.models().modelLevel(0, 0).data_size;
    lodrt::StreamerOptions options;
    options.budget_bytes = pinned + level0 - 1; // model 0's level 0 fits only if something shrinks
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, nullptr, &options), Result::Ok);
    for (int i = 0; i < 4; ++i) streamer.update(nullptr);
    std::vector<ModelDemand> demand(2);
    demand[0] = {0, 1.0f};
    demand[1] = {uint8_t(source.models().model(1).level_count - 1), 1.0f}; // coarsest: its blob is worth nothing
    for (int i = 0; i < 20; ++i) streamer.update(demand.data());
    EXPECT_GT(streamer.stats().pfrep_shrinks, 0u);
    EXPECT_NE(streamer.pfrepLevel(1), 0); // shrunk below full detail
    EXPECT_EQ(streamer.state(0, 0), lodrt::LevelState::Resident);
    const Blob blob1 = blobOf(source2, 1);
    if (const lodrt::PfrepModel* m = streamer.pfrepModel(1)) {
        EXPECT_EQ(std::memcmp(m->data, blob1.bytes.data(), m->size), 0);
        expectCoveredLevelsMatch(streamer, 1, blob1);
    }
    // Full detail of model 1 now matters most: decoded whole again, model 0 makes room.
    demand[1] = {0, 10.0f};
    for (int i = 0; i < 20; ++i) streamer.update(demand.data());
    ASSERT_EQ(streamer.pfrepLevel(1), 0);
    const lodrt::PfrepModel* m = streamer.pfrepModel(1);
    ASSERT_NE(m, nullptr);
    ASSERT_EQ(m->size, blob1.bytes.size());
    EXPECT_EQ(std::memcmp(m->data, blob1.bytes.data(), m->size), 0);
    expectCoveredLevelsMatch(streamer, 1, blob1);
    const lodrt::StreamStats stats = streamer.stats();
    EXPECT_LE(stats.resident_bytes + stats.in_flight_bytes, options.budget_bytes);
}

TEST(PfrepStreamingTest, Format3CorruptBlobsNeverCrash) {
    const std::vector<uint8_t>& good = bakedPack3();
    ASSERT_FALSE(good.empty());
    PackSource probe;
    ASSERT_EQ(probe.openBytes(good.data(), good.size(), nullptr), Result::Ok);
    const lodrt::Pack& pack = probe.pack();
    const lodrt::JsonValue ext =
        pack.mesh(probe.models().modelLevel(0, 0).mesh).json.find("extensions").find("LODBAKE_progressive_fans");
    uint64_t view = 0, format = 0;
    ASSERT_TRUE(ext.find("bufferView").asUint64(&view));
    ASSERT_TRUE(ext.find("format").asUint64(&format));
    EXPECT_EQ(format, 3u);
    uint32_t json_length = 0;
    std::memcpy(&json_length, good.data() + 12, 4);
    const uint64_t offset = 20 + uint64_t(json_length) + 8 + pack.bufferView(uint32_t(view)).byte_offset;
    const uint64_t length = pack.bufferView(uint32_t(view)).byte_length;
    uint32_t seed = 7;
    auto next = [&seed] {
        seed = seed * 1664525u + 1013904223u;
        return seed >> 8;
    };
    int failed = 0;
    for (int iteration = 0; iteration < 100; ++iteration) {
        std::vector<uint8_t> bytes = good;
        const uint64_t span = iteration % 2 ? length : std::min<uint64_t>(length, 96);
        for (int e = 0; e < 1 + iteration % 3; ++e) bytes[offset + next() % span] ^= uint8_t(1 + next() % 255);
        PackSource source;
        ASSERT_EQ(source.openBytes(bytes.data(), bytes.size(), nullptr), Result::Ok);
        Streamer streamer;
        ASSERT_EQ(streamer.init(&source, nullptr, nullptr), Result::Ok);
        std::vector<ModelDemand> demand(2, ModelDemand{0, 1.0f});
        for (int i = 0; i < 10; ++i) streamer.update(demand.data());
        if (streamer.pfrepState(0) == PfrepStreamState::Failed) ++failed;
        const lodrt::PfrepModel* m = streamer.pfrepModel(0);
        if (!m) continue;
        std::vector<uint32_t> tris(3 * lodrt::pfrepMaxTriangles(*m));
        size_t count = 0;
        for (uint32_t k = m->loaded_from; k <= m->removed_count; k += 1 + m->removed_count / 8)
            EXPECT_EQ(lodrt::pfrepExtractLevel(*m, k, tris.data(), tris.size() / 3, &count), Result::Ok);
    }
    EXPECT_GT(failed, 50);
}

// ---- Format 4: coded against LOD0's own valence stream (docs/format/pfrep.md "In a glTF pack") ----

namespace {

const std::vector<uint8_t>& bakedPack4() {
    static const std::vector<uint8_t>* glb = bakePack(lodrt::format::kPfrepVersionLod0);
    return *glb;
}

// The bytes of buffer view `view` of a pack in memory.
std::vector<uint8_t> viewBytes(const PackSource& source, uint32_t view) {
    std::vector<uint8_t> bytes(source.pack().bufferView(view).byte_length);
    EXPECT_EQ(source.readBufferView(view, 0, bytes.data(), bytes.size()), Result::Ok);
    return bytes;
}

// Model m's PFRep blob and its LOD0's (one primitive's) valence stream.
struct Format4Blob {
    std::vector<uint8_t> blob, lod0;
};

Format4Blob format4Blob(const PackSource& source, uint32_t m) {
    Format4Blob out;
    const lodrt::Pack& pack = source.pack();
    const lodrt::MeshInfo& mesh = pack.mesh(source.models().modelLevel(m, 0).mesh);
    const lodrt::JsonValue ext = mesh.json.find("extensions").find("LODBAKE_progressive_fans");
    uint64_t view = 0, format = 0;
    EXPECT_TRUE(ext.find("bufferView").asUint64(&view));
    EXPECT_TRUE(ext.find("format").asUint64(&format));
    EXPECT_EQ(format, 4u);
    out.blob = viewBytes(source, uint32_t(view));
    EXPECT_EQ(mesh.primitive_count, 1u);
    const lodrt::JsonValue stream =
        pack.primitive(mesh.first_primitive).json.find("extensions").find("LODBAKE_valence_compression");
    EXPECT_TRUE(stream.find("bufferView").asUint64(&view));
    out.lod0 = viewBytes(source, uint32_t(view));
    return out;
}

// Decodes `b.blob` against `lod0` into `out`; the result code.
Result decodePack4(const std::vector<uint8_t>& blob, const std::vector<uint8_t>& lod0, std::vector<uint8_t>& out,
                   lodrt::PfrepModel* model) {
    lodrt::PfrepPackFormat4Info info;
    const Result r = lodrt::pfrepPackFormat4Info(blob.data(), blob.size(), lod0.data(), lod0.size(), &info);
    if (r != Result::Ok) return r;
    out.assign(info.decoded_bytes, 0);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    return lodrt::pfrepDecodePackFormat4(blob.data(), blob.size(), lod0.data(), lod0.size(), out.data(), out.size(),
                                         scratch.data(), scratch.size() * 8, model);
}

// A format 4 blob that must carry a split list (its size goes to *split_bytes), decoded against its
// LOD0 into `decoded`.
void decodeWithSplitList(const Format4Blob& b, std::vector<uint8_t>& decoded, lodrt::PfrepModel* got,
                         size_t* split_bytes) {
    const void* split = nullptr;
    ASSERT_EQ(lodrt::pfrepFormat4SplitList(b.blob.data(), b.blob.size(), &split, split_bytes), Result::Ok);
    EXPECT_GE(*split_bytes, 5u);
    ASSERT_EQ(decodePack4(b.blob, b.lod0, decoded, got), Result::Ok);
}

std::vector<std::array<uint32_t, 3>> sortedLevel(const lodrt::PfrepModel& model, uint32_t level) {
    const std::vector<uint32_t> tris = extract(model, level);
    std::vector<std::array<uint32_t, 3>> out(tris.size() / 3);
    for (size_t t = 0; t < out.size(); ++t) out[t] = {tris[t * 3], tris[t * 3 + 1], tris[t * 3 + 2]};
    std::sort(out.begin(), out.end());
    return out;
}

// `got` (decoded from format 4) against `want` (the format 2 blob of the same input): every level
// as a triangle set, every position, and view-dependent refinement from a moving camera mask for
// mask (the criterion data: radius, error, cone).
void expectSameTables(const lodrt::PfrepModel& got, const lodrt::PfrepModel& want) {
    ASSERT_EQ(got.vertex_count, want.vertex_count);
    ASSERT_EQ(got.removed_count, want.removed_count);
    ASSERT_EQ(got.level0_triangles, want.level0_triangles);
    for (uint32_t k = 0; k <= want.removed_count; ++k) ASSERT_EQ(sortedLevel(got, k), sortedLevel(want, k)) << k;
    std::vector<float> pa(size_t(want.vertex_count) * 3), pb(pa.size());
    ASSERT_EQ(lodrt::pfrepDecodePositions(want, pa.data(), pa.size()), Result::Ok);
    ASSERT_EQ(lodrt::pfrepDecodePositions(got, pb.data(), pb.size()), Result::Ok);
    EXPECT_EQ(pa, pb);
    std::vector<uint8_t> ma(lodrt::pfrepMaskBytes(want)), mb(ma.size());
    lodrt::pfrepMaskCoarsest(want, ma.data());
    lodrt::pfrepMaskCoarsest(got, mb.data());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(want));
    for (int frame = 0; frame < 12; ++frame) {
        lodrt::PfrepView view;
        view.eye[0] = 0.5f + 0.1f * float(frame);
        view.eye[1] = -0.3f;
        view.eye[2] = 0.4f;
        for (auto& plane : view.planes) plane[3] = 1e6f; // no culling
        view.pixels_per_unit_at_distance_one = 800.0f;
        size_t ca = 0, cb = 0;
        ASSERT_EQ(lodrt::pfrepRefine(want, view, ma.data(), scratch.data(), scratch.size(), &ca), Result::Ok);
        ASSERT_EQ(lodrt::pfrepRefine(got, view, mb.data(), scratch.data(), scratch.size(), &cb), Result::Ok);
        ASSERT_EQ(ma, mb) << "frame " << frame;
        EXPECT_EQ(ca, cb);
    }
}

} // namespace

// The pack's format 4 blob decodes, against LOD0's stream, to format 2's tables; a LOD0 of the
// same size but another geometry (the other model's) is refused by the blob's LOD0 check.
TEST(PfrepStreamingTest, Format4DecodesAgainstLod0ToTheFormat2Tables) {
    PackSource source2, source4;
    ASSERT_EQ(source2.openBytes(bakedPack().data(), bakedPack().size(), nullptr), Result::Ok);
    ASSERT_FALSE(bakedPack4().empty());
    ASSERT_EQ(source4.openBytes(bakedPack4().data(), bakedPack4().size(), nullptr), Result::Ok);
    Format4Blob b[2] = {format4Blob(source4, 0), format4Blob(source4, 1)};
    for (uint32_t m = 0; m < 2; ++m) {
        SCOPED_TRACE("model " + std::to_string(m));
        const Blob want = blobOf(source2, m);
        EXPECT_LT(b[m].blob.size() * 4, want.bytes.size());
        std::vector<uint8_t> decoded;
        lodrt::PfrepModel got;
        ASSERT_EQ(decodePack4(b[m].blob, b[m].lod0, decoded, &got), Result::Ok);
        expectSameTables(got, want.whole);
        // The other model's LOD0: same point and triangle counts, other positions.
        std::vector<uint8_t> other;
        EXPECT_EQ(decodePack4(b[m].blob, b[1 - m].lod0, other, &got), Result::BadStructure);
    }
}

// Hostile bytes in a pack context: every cut of the blob, and bytes changed in the blob or in LOD0's
// stream, give an error or (for a change the stream cannot see) a valid model; never a crash.
TEST(PfrepStreamingTest, Format4TruncatedOrCorruptIsRefused) {
    PackSource source4;
    ASSERT_EQ(source4.openBytes(bakedPack4().data(), bakedPack4().size(), nullptr), Result::Ok);
    const Format4Blob b = format4Blob(source4, 0);
    std::vector<uint8_t> out;
    lodrt::PfrepModel model;
    for (size_t cut = 0; cut < b.blob.size(); cut += 1 + cut / 64) {
        const std::vector<uint8_t> part(b.blob.begin(), b.blob.begin() + std::ptrdiff_t(cut));
        EXPECT_NE(decodePack4(part, b.lod0, out, &model), Result::Ok) << cut;
    }
    for (size_t cut = 0; cut < b.lod0.size(); cut += 1 + cut / 16) {
        const std::vector<uint8_t> part(b.lod0.begin(), b.lod0.begin() + std::ptrdiff_t(cut));
        EXPECT_NE(decodePack4(b.blob, part, out, &model), Result::Ok) << cut;
    }
    uint32_t seed = 11;
    auto next = [&seed] {
        seed = seed * 1664525u + 1013904223u;
        return seed >> 8;
    };
    int refused = 0;
    for (int i = 0; i < 200; ++i) {
        Format4Blob c = b;
        std::vector<uint8_t>& target = i % 2 ? c.blob : c.lod0;
        target[next() % target.size()] ^= uint8_t(1 + next() % 255);
        if (decodePack4(c.blob, c.lod0, out, &model) != Result::Ok) {
            ++refused;
            continue;
        }
        std::vector<uint32_t> tris(3 * lodrt::pfrepMaxTriangles(model));
        size_t count = 0;
        for (uint32_t k = 0; k <= model.removed_count; k += 1 + model.removed_count / 8)
            EXPECT_EQ(lodrt::pfrepExtractLevel(model, k, tris.data(), tris.size() / 3, &count), Result::Ok);
    }
    EXPECT_GT(refused, 150);
}

// The Streamer decodes a format 4 blob only once the model's level 0 is resident (it never loads
// level 0 for it), then holds the same tables as format 2; a pack whose blob read fails fails the
// stream, not the frame.
TEST(PfrepStreamingTest, Format4WaitsForLevel0ThenMatchesFormat2) {
    PackSource source2;
    ASSERT_EQ(source2.openBytes(bakedPack().data(), bakedPack().size(), nullptr), Result::Ok);
    File file;
    file.bytes = bakedPack4();
    ASSERT_FALSE(file.bytes.empty());
    PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
    ManualJobs jobs;
    const lodrt::JobSystem system = jobs.system();
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, nullptr), Result::Ok);
    for (int i = 0; i < 6; ++i) {
        streamer.update(nullptr); // nothing wanted: the coarsest levels and the blobs' headers only
        jobs.runAll();
    }
    for (uint32_t m = 0; m < 2; ++m) {
        EXPECT_NE(streamer.state(m, 0), lodrt::LevelState::Resident);
        EXPECT_EQ(streamer.pfrepState(m), PfrepStreamState::Absent);
        EXPECT_EQ(streamer.pfrepModel(m), nullptr);
    }
    std::vector<ModelDemand> demand(2, ModelDemand{0, 1.0f});
    for (int i = 0; i < 8; ++i) {
        streamer.update(demand.data());
        jobs.runAll();
    }
    streamer.update(demand.data());
    for (uint32_t m = 0; m < 2; ++m) {
        SCOPED_TRACE("model " + std::to_string(m));
        ASSERT_EQ(streamer.state(m, 0), lodrt::LevelState::Resident);
        ASSERT_EQ(streamer.pfrepState(m), PfrepStreamState::Resident);
        EXPECT_EQ(streamer.pfrepLevel(m), 0);
        const lodrt::PfrepModel* got = streamer.pfrepModel(m);
        ASSERT_NE(got, nullptr);
        const Blob want = blobOf(source2, m);
        expectSameTables(*got, want.whole);
        // What an engine sizes its allocator by: the decoded size and the scratch (LOD0's stream read).
        uint64_t decoded = 0, scratch = 0;
        ASSERT_EQ(source.pfrepDecodeMemory(m, &decoded, &scratch), Result::Ok);
        EXPECT_EQ(decoded, got->size);
        EXPECT_GT(scratch, decoded);
    }
    // Model 0's blob zeroed after its header: its stream fails, the levels and model 1 still stream.
    const Format4Blob b = format4Blob(source, 0);
    std::vector<uint8_t> broken = file.bytes;
    const auto at = std::search(broken.begin(), broken.end(), b.blob.begin(), b.blob.end());
    ASSERT_NE(at, broken.end());
    for (size_t i = 80; i < b.blob.size(); ++i) at[std::ptrdiff_t(i)] = 0; // the stream after its header
    PackSource broken_source;
    ASSERT_EQ(broken_source.openBytes(broken.data(), broken.size(), nullptr), Result::Ok);
    Streamer s2;
    ASSERT_EQ(s2.init(&broken_source, nullptr, nullptr), Result::Ok);
    for (int i = 0; i < 8; ++i) s2.update(demand.data());
    EXPECT_EQ(s2.pfrepState(0), PfrepStreamState::Failed);
    EXPECT_EQ(s2.state(0, 0), lodrt::LevelState::Resident);
    EXPECT_EQ(s2.pfrepState(1), PfrepStreamState::Resident);
}

// ---- Format 4 over a LOD0 whose stream welds points (the blob's split list) ----

namespace {

// A height field with a crack: column n / 2 is there twice, the right sheet's copy 2e-5 to the side
// (closer than the 14-bit stream's position step, so most of its points weld to the left sheet's
// in LOD0's stream, as a merged scan's overlapping borders do).
lodbake::Mesh crackedHeightField(int n) {
    lodbake::Mesh mesh = heightField(n, 0.5f);
    const int c = n / 2;
    const uint32_t first_copy = uint32_t(mesh.positions.size());
    for (int y = 0; y < n; ++y) {
        lodbake::Vec3f p = mesh.positions[size_t(y * n + c)];
        p.x += 2e-5f;
        mesh.positions.push_back(p);
    }
    // The right sheet's triangles (those with a corner right of the crack) take the copies.
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        bool right = false;
        for (int k = 0; k < 3; ++k) right = right || int(mesh.indices[t + size_t(k)] % uint32_t(n)) > c;
        if (!right) continue;
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = mesh.indices[t + size_t(k)];
            if (int(v % uint32_t(n)) == c) v = first_copy + v / uint32_t(n);
        }
    }
    return mesh;
}

std::vector<uint8_t> bakeCracked(uint32_t pfrep_format) {
    lodbake::BakeSettings settings;
    settings.pfrep_format = pfrep_format;
    settings.compact = pfrep_format == lodrt::format::kPfrepVersionLod0;
    settings.lod_ratios = {0.5, 0.1};
    settings.error_samples = 500;
    settings.threads = 2;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "cracked";
    inputs[0].mesh = crackedHeightField(40);
    lodbake::Diagnostics diagnostics;
    auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
    EXPECT_TRUE(baked.ok()) << baked.status().message();
    return baked.ok() ? baked->glb : std::vector<uint8_t>();
}

} // namespace

// The stream welds the crack's points; the format 4 blob tells them apart with its split list and
// still decodes, against that stream, to format 2's tables. Cut or changed anywhere (header, list,
// stream), the blob is refused or gives a valid model.
TEST(PfrepStreamingTest, Format4SplitsPointsLod0sStreamWelds) {
    const std::vector<uint8_t> glb2 = bakeCracked(lodrt::format::kPfrepVersion);
    const std::vector<uint8_t> glb4 = bakeCracked(lodrt::format::kPfrepVersionLod0);
    PackSource source2, source4;
    ASSERT_EQ(source2.openBytes(glb2.data(), glb2.size(), nullptr), Result::Ok);
    ASSERT_EQ(source4.openBytes(glb4.data(), glb4.size(), nullptr), Result::Ok);
    const Format4Blob b = format4Blob(source4, 0);
    ASSERT_GE(b.blob.size(), size_t(lodrt::format::kPfrepHeaderSize + 4));
    uint32_t flags = 0;
    std::memcpy(&flags, b.blob.data() + 60, 4);
    EXPECT_EQ(flags, lodrt::format::kPfrep4Flags); // with a split list
    std::vector<uint8_t> decoded;
    lodrt::PfrepModel got;
    size_t split_bytes = 0;
    ASSERT_NO_FATAL_FAILURE(decodeWithSplitList(b, decoded, &got, &split_bytes));
    expectSameTables(got, blobOf(source2, 0).whole);
    std::vector<uint8_t> out;
    lodrt::PfrepModel model;
    for (size_t cut = 0; cut < b.blob.size(); cut += 1 + cut / 64) {
        const std::vector<uint8_t> part(b.blob.begin(), b.blob.begin() + std::ptrdiff_t(cut));
        EXPECT_NE(decodePack4(part, b.lod0, out, &model), Result::Ok) << cut;
    }
    int refused = 0, tried = 0;
    const size_t end = lodrt::format::kPfrepHeaderSize + 4 + split_bytes + 8;
    for (size_t at = lodrt::format::kPfrepHeaderSize; at < end && at < b.blob.size(); ++at)
        for (uint8_t flip : {uint8_t(0x01), uint8_t(0x10), uint8_t(0x80)}) {
            std::vector<uint8_t> bad = b.blob;
            bad[at] ^= flip;
            ++tried;
            if (decodePack4(bad, b.lod0, out, &model) != Result::Ok) {
                ++refused;
                continue;
            }
            std::vector<uint32_t> tris(3 * lodrt::pfrepMaxTriangles(model));
            size_t count = 0;
            EXPECT_EQ(lodrt::pfrepExtractLevel(model, 0, tris.data(), tris.size() / 3, &count), Result::Ok);
        }
    EXPECT_GT(refused * 4, tried * 3);
}

// dragon_poisson's compact pack: its 14-bit LOD0 stream puts thousands of LOD0's points on another
// point's position; the format 4 blob's split list tells them apart, and decoded against the stream
// (as the Streamer decodes it) the blob gives the tables of the format 2 blob baked from the same
// LOD0: sampled levels as triangle sets, every position, refinement masks. Heavy (two bakes of a
// 1M-triangle scan; tests/CMakeLists.txt).
TEST(PfrepStreamingTest, Format4OnDragonPoissonMatchesFormat2) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("dragon_poisson.ply"), {}, diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    std::vector<uint8_t> glb[2];
    for (int f = 0; f < 2; ++f) {
        lodbake::BakeSettings settings;
        settings.pfrep_format = f ? lodrt::format::kPfrepVersionLod0 : lodrt::format::kPfrepVersion;
        settings.compact = f == 1;
        settings.lod_ratios = {0.1};
        settings.error_samples = 500;
        settings.threads = 2;
        std::vector<lodbake::BakeInput> inputs(1);
        inputs[0].name = "dragon";
        inputs[0].mesh = loaded->mesh;
        auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
        ASSERT_TRUE(baked.ok()) << baked.status().message();
        glb[f] = std::move(baked->glb);
    }
    PackSource source2, source4;
    ASSERT_EQ(source2.openBytes(glb[0].data(), glb[0].size(), nullptr), Result::Ok);
    ASSERT_EQ(source4.openBytes(glb[1].data(), glb[1].size(), nullptr), Result::Ok);
    const Format4Blob b = format4Blob(source4, 0);
    std::vector<uint8_t> decoded;
    lodrt::PfrepModel got;
    size_t split_bytes = 0;
    ASSERT_NO_FATAL_FAILURE(decodeWithSplitList(b, decoded, &got, &split_bytes));
    const Blob want = blobOf(source2, 0);
    ASSERT_EQ(got.vertex_count, want.whole.vertex_count);
    ASSERT_EQ(got.removed_count, want.whole.removed_count);
    EXPECT_LT(b.blob.size() * 6, want.bytes.size());
    const uint32_t step = std::max(1u, want.whole.removed_count / 24);
    for (uint32_t k = 0; k <= want.whole.removed_count; k += step)
        ASSERT_EQ(sortedLevel(got, k), sortedLevel(want.whole, k)) << k;
    ASSERT_EQ(sortedLevel(got, want.whole.removed_count), sortedLevel(want.whole, want.whole.removed_count));
    std::vector<float> pa(size_t(got.vertex_count) * 3), pb(pa.size());
    ASSERT_EQ(lodrt::pfrepDecodePositions(want.whole, pa.data(), pa.size()), Result::Ok);
    ASSERT_EQ(lodrt::pfrepDecodePositions(got, pb.data(), pb.size()), Result::Ok);
    EXPECT_EQ(pa, pb);
    std::vector<uint8_t> ma(lodrt::pfrepMaskBytes(want.whole)), mb(ma.size());
    lodrt::pfrepMaskCoarsest(want.whole, ma.data());
    lodrt::pfrepMaskCoarsest(got, mb.data());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(want.whole));
    for (int frame = 0; frame < 4; ++frame) {
        lodrt::PfrepView view;
        view.eye[0] = 0.1f * float(frame);
        view.eye[2] = 0.3f;
        for (auto& plane : view.planes) plane[3] = 1e6f;
        view.pixels_per_unit_at_distance_one = 2000.0f;
        size_t ca = 0, cb = 0;
        ASSERT_EQ(lodrt::pfrepRefine(want.whole, view, ma.data(), scratch.data(), scratch.size(), &ca), Result::Ok);
        ASSERT_EQ(lodrt::pfrepRefine(got, view, mb.data(), scratch.data(), scratch.size(), &cb), Result::Ok);
        ASSERT_EQ(ma, mb) << "frame " << frame;
        EXPECT_EQ(ca, cb);
    }
}
