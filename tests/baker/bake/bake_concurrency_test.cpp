// The bake's concurrent phase (docs/bake.md, "Concurrency"): stream encoders in two steps, the same
// bytes for any thread count, and per-stage CPU accounting in the hooks.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <set>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/bake/stages.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/pack/pack.h"
#include "lodbake/stream/stream.h"
#include "stream_level.h"

namespace {

using namespace lodbake;

// A bumpy (n x n)-cell grid with normals: every level of a chain differs from the last.
Mesh bumpyGrid(int n) {
    Mesh mesh;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            const float z = 0.05f * std::sin(0.7f * float(x)) * std::cos(0.45f * float(y));
            mesh.positions.push_back({float(x) / float(n), float(y) / float(n), z});
            mesh.normals.push_back({0, 0, 1});
        }
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
        }
    return mesh;
}

bool sameLevel(const PackLevel& a, const PackLevel& b) {
    if (a.mesh.indices != b.mesh.indices || a.mesh.positions.size() != b.mesh.positions.size()) return false;
    for (size_t v = 0; v < a.mesh.positions.size(); ++v)
        if (!(a.mesh.positions[v] == b.mesh.positions[v])) return false;
    auto same = [](const PackExtension& x, const PackExtension& y) {
        return x.name == y.name && x.json == y.json && x.blobs == y.blobs && x.is_stream == y.is_stream;
    };
    if (a.mesh_extensions.size() != b.mesh_extensions.size() ||
        a.primitive_extensions.size() != b.primitive_extensions.size())
        return false;
    for (size_t i = 0; i < a.mesh_extensions.size(); ++i)
        if (!same(a.mesh_extensions[i], b.mesh_extensions[i])) return false;
    for (size_t p = 0; p < a.primitive_extensions.size(); ++p) {
        if (a.primitive_extensions[p].size() != b.primitive_extensions[p].size()) return false;
        for (size_t i = 0; i < a.primitive_extensions[p].size(); ++i)
            if (!same(a.primitive_extensions[p][i], b.primitive_extensions[p][i])) return false;
    }
    return true;
}

TEST(StreamEncoderTest, PrepareLeavesTheMeshAlone) {
    const Mesh original = bumpyGrid(8);
    for (const PackStreamEncoder& encoder : builtinStreamEncoders()) {
        Mesh mesh = original;
        ASSERT_TRUE(encoder.prepare(LodChain{}, 0, mesh).ok());
        EXPECT_EQ(mesh.indices, original.indices) << encoder.extension_name;
    }
}

// The valence stream hands the coder's freed working set back (release_memory) before its check
// decodes, on large levels only, and the hook changes no byte.
TEST(StreamEncoderTest, ValenceReleasesMemoryBetweenCodingAndCheckOnLargeLevels) {
    for (int n : {256, 40}) { // 131,072 and 3,200 triangles
        SCOPED_TRACE(n);
        ValenceStreamOptions options;
        int calls = 0;
        options.release_memory = [&] { ++calls; };
        PackLevel hooked, plain;
        hooked.mesh = plain.mesh = bumpyGrid(n);
        ASSERT_TRUE(lodbake_test::encodeStreamLevel(valenceStreamEncoder(options), LodChain{}, 0, hooked).ok());
        EXPECT_EQ(calls, n == 256 ? 1 : 0);
        ASSERT_TRUE(lodbake_test::encodeStreamLevel(valenceStreamEncoder(), LodChain{}, 0, plain).ok());
        EXPECT_TRUE(sameLevel(hooked, plain));
    }
}

// bake() passes BakeHooks::release_memory on to the valence stream: a large asset's LOD0 calls it.
TEST(BakeConcurrencyTest, LargeAssetReleasesMemoryThroughTheHook) {
    BakeSettings settings;
    settings.lod_ratios = {0.1};
    settings.error_samples = 2000;
    settings.progressive_fans = false;
    std::atomic<int> calls{0};
    BakeHooks hooks;
    hooks.release_memory = [&] { ++calls; };
    std::vector<BakeInput> inputs{{"grid", bumpyGrid(256)}};
    Diagnostics diagnostics;
    Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics, hooks);
    ASSERT_TRUE(out.ok()) << out.status().message();
    EXPECT_EQ(calls.load(), 1); // LOD0 only: level 1 has 13,108 triangles
}

TEST(BakeConcurrencyTest, SameBytesForOneAndTwoThreadsAndEveryStageTimed) {
    std::vector<std::vector<uint8_t>> packs;
    for (uint32_t threads : {1u, 2u, 4u}) {
        BakeSettings settings;
        settings.threads = threads;
        settings.lod_ratios = {0.5, 0.2, 0.05};
        settings.error_samples = 5000;
        std::vector<BakeInput> inputs{{"a", bumpyGrid(40)}, {"b", bumpyGrid(24)}};
        std::mutex mutex;
        std::set<BakeStage> seen;
        bool cpu_consistent = true;
        BakeHooks hooks;
        hooks.stage_done = [&](size_t, BakeStage stage, const StageTime& time) {
            std::lock_guard<std::mutex> lock(mutex);
            seen.insert(stage);
            // The process's CPU time includes that of the thread that ran the stage (clock ticks aside).
            cpu_consistent = cpu_consistent && time.wall_seconds >= 0 && time.thread_cpu_seconds >= 0 &&
                             time.thread_cpu_seconds <= time.cpu_seconds + 0.02;
        };
        Diagnostics diagnostics;
        Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics, hooks);
        ASSERT_TRUE(out.ok()) << out.status().message();
        ASSERT_EQ(out->assets.size(), 2u);
        for (const BakeAssetReport& a : out->assets) {
            ASSERT_EQ(a.metrics.levels.size(), 4u);
            for (size_t l = 1; l < 4; ++l) {
                EXPECT_GT(a.metrics.levels[l].hausdorff_error, 0.0);
                EXPECT_GE(a.metrics.levels[l].switch_distance, a.metrics.levels[l - 1].switch_distance);
            }
        }
        for (BakeStage stage : {BakeStage::Repair, BakeStage::LodChain, BakeStage::Measure, BakeStage::Pfrep,
                                BakeStage::Textures, BakeStage::Encode, BakeStage::Pack})
            EXPECT_TRUE(seen.count(stage)) << bakeStageName(stage);
        EXPECT_TRUE(cpu_consistent);
        packs.push_back(std::move(out->glb));
    }
    EXPECT_EQ(packs[0], packs[1]);
    EXPECT_EQ(packs[0], packs[2]);
}

} // namespace
