// Adaptive stream precision (ValenceStreamOptions::adaptive, docs/bake.md "Stream precision"): the
// bits each level gets from its own measured error, the octahedral error table it relies on, and a
// bake whose coarse levels are coded with fewer bits while every claim the rule makes holds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/bake.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/pack.h"
#include "lodbake/stream/stream.h"
#include "lodrt/pack.h"
#include "lodrt/valence.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

constexpr const char* kExt = "LODBAKE_valence_compression";

// An (n+1)^2 grid on the unit square with normals; its bounding cube edge is 1.
Mesh unitGrid(int n) {
    Mesh m;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            m.positions.push_back({float(x) / float(n), float(y) / float(n), 0.0f});
            m.normals.push_back({0, 0, 1});
        }
    auto v = [n](int x, int y) { return uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            m.indices.insert(m.indices.end(), {v(x, y), v(x + 1, y), v(x + 1, y + 1)});
            m.indices.insert(m.indices.end(), {v(x, y), v(x + 1, y + 1), v(x, y + 1)});
        }
    return m;
}

double bound(uint32_t bits) { // largest displacement in a unit cube
    return std::sqrt(3.0) / 2.0 / double((1u << bits) - 1);
}

LodChain chainWithMeanError(double mean) {
    LodChain chain;
    chain.levels.resize(1);
    chain.levels[0].has_distance = true;
    chain.levels[0].distance.mean = mean;
    chain.levels[0].distance.hausdorff = 10 * mean;
    return chain;
}

TEST(StreamPrecisionTest, PositionBitsAreTheFewestWithinTheErrorFraction) {
    ValenceStreamOptions options;
    options.adaptive = true;
    const Mesh mesh = unitGrid(8);
    for (double mean : {1e-5, 1e-4, 3e-4, 1e-3, 5e-3, 0.05}) {
        SCOPED_TRACE(mean);
        const ValencePrecision p = valencePrecision(options, chainWithMeanError(mean), 1, mesh);
        EXPECT_LE(p.position_bits, 14u);
        EXPECT_GE(p.position_bits, 8u);
        EXPECT_DOUBLE_EQ(p.max_displacement, bound(p.position_bits));
        if (p.position_bits < 14) {
            EXPECT_LE(bound(p.position_bits), options.error_fraction * mean);
        }
        if (p.position_bits > 8) {
            EXPECT_GT(bound(p.position_bits - 1), options.error_fraction * mean);
        }
    }
    // 1e-3 of a unit cube at a quarter: 0.866 / (2^b - 1) <= 2.5e-4 first holds at b = 12.
    EXPECT_EQ(valencePrecision(options, chainWithMeanError(1e-3), 1, mesh).position_bits, 12u);
    // A tiny error never asks for more than the options' bits.
    EXPECT_EQ(valencePrecision(options, chainWithMeanError(1e-9), 1, mesh).position_bits, 14u);
}

TEST(StreamPrecisionTest, LodZeroUnmeasuredLevelsAndTheOffSwitchKeepTheOptionsBits) {
    ValenceStreamOptions options;
    options.adaptive = true;
    options.position_bits = 13;
    options.normal_bits = 7;
    const Mesh mesh = unitGrid(8);
    const LodChain chain = chainWithMeanError(0.05);
    ValencePrecision p = valencePrecision(options, chain, 0, mesh);
    EXPECT_EQ(p.position_bits, 13u);
    EXPECT_EQ(p.normal_bits, 7u);
    LodChain unmeasured = chain;
    unmeasured.levels[0].has_distance = false;
    p = valencePrecision(options, unmeasured, 1, mesh);
    EXPECT_EQ(p.position_bits, 13u);
    EXPECT_EQ(p.normal_bits, 7u);
    options.adaptive = false;
    p = valencePrecision(options, chain, 1, mesh);
    EXPECT_EQ(p.position_bits, 13u);
    EXPECT_EQ(p.normal_bits, 7u);
    EXPECT_FALSE(valenceStreamEncoder(options).needs.measured_errors);
    options.adaptive = true;
    EXPECT_TRUE(valenceStreamEncoder(options).needs.measured_errors);
}

TEST(StreamPrecisionTest, NormalBitsFollowTheLeanOfTheLevel) {
    ValenceStreamOptions options;
    options.adaptive = true;
    const Mesh mesh = unitGrid(8); // median edge 1/8
    for (double mean : {1e-4, 1e-3, 1e-2, 3e-2, 0.1}) {
        SCOPED_TRACE(mean);
        const ValencePrecision p = valencePrecision(options, chainWithMeanError(mean), 1, mesh);
        const double allowed = options.error_fraction * std::atan(mean / 0.125);
        EXPECT_LE(p.normal_bits, 8u);
        EXPECT_GE(p.normal_bits, 4u);
        EXPECT_DOUBLE_EQ(p.max_normal_angle, octahedralMaxAngle(p.normal_bits));
        if (p.normal_bits < 8) {
            EXPECT_LE(octahedralMaxAngle(p.normal_bits), allowed);
        }
        if (p.normal_bits > 4) {
            EXPECT_GT(octahedralMaxAngle(p.normal_bits - 1), allowed);
        }
    }
    EXPECT_LT(valencePrecision(options, chainWithMeanError(0.05), 1, mesh).normal_bits, 8u);
}

// The table the normal rule uses must not underestimate: random directions never round by more.
TEST(StreamPrecisionTest, OctahedralMaxAngleBoundsRandomDirections) {
    std::mt19937 rng(7);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    double previous = 10.0;
    for (uint32_t bits : {4u, 5u, 6u, 8u, 10u, 12u}) {
        const double table = octahedralMaxAngle(bits);
        EXPECT_LT(table, previous) << bits;
        previous = table;
        double worst = 0.0;
        for (int i = 0; i < 20000; ++i) {
            float n[3] = {gauss(rng), gauss(rng), gauss(rng)};
            const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(len > 1e-6f)) continue;
            for (float& c : n) c /= len;
            uint32_t q[2];
            lodrt::octahedralEncode(n, bits, q);
            float d[3];
            lodrt::octahedralDecode(q, bits, d);
            const double dlen = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
            const double dot = (double(n[0]) * d[0] + double(n[1]) * d[1] + double(n[2]) * d[2]) / dlen;
            worst = std::max(worst, std::acos(std::min(1.0, dot)));
        }
        EXPECT_LE(worst, table * 1.001) << bits;
        EXPECT_GT(worst, table * 0.5) << bits; // and is not a loose bound either
    }
    // 8 bits per component: a little under one degree.
    EXPECT_GT(octahedralMaxAngle(8), 0.5 * 3.14159265 / 180.0);
    EXPECT_LT(octahedralMaxAngle(8), 1.0 * 3.14159265 / 180.0);
}

// A bake with adaptive precision: LOD0 keeps 14 bits, coarser levels use fewer, every level's
// largest quantization displacement stays within the error fraction of its reported mean error, the
// decoded positions lie that close to the plain ones, and the compact pack is smaller than without.
TEST(StreamPrecisionTest, BakeCodesCoarseLevelsWithFewerBitsWithinTheirError) {
    auto bakeRock = [](bool adaptive, bool compact) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded =
            readMesh(lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock_000.ply", ReadOptions{}, diagnostics);
        EXPECT_TRUE(loaded.ok());
        BakeSettings settings;
        settings.lod_ratios = {0.5, 0.1, 0.03};
        settings.error_samples = 20000;
        settings.textures.enabled = false;
        settings.stream_precision.adaptive = adaptive;
        settings.compact = compact;
        std::vector<BakeInput> inputs(1);
        inputs[0].name = "rock";
        inputs[0].mesh = std::move(loaded->mesh);
        Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics);
        EXPECT_TRUE(out.ok()) << out.status().message();
        return std::move(out).value();
    };
    const BakeOutput plain = bakeRock(true, false);
    const BakeOutput compact = bakeRock(true, true);
    const BakeOutput fixed = bakeRock(false, true);
    EXPECT_LT(compact.glb.size(), fixed.glb.size());

    lodrt::Pack pack;
    ASSERT_EQ(lodrt::loadPack(plain.glb.data(), plain.glb.size(), nullptr, &pack), lodrt::Result::Ok);
    const LodMetrics& metrics = plain.assets[0].metrics;
    ASSERT_EQ(pack.meshCount(), 4u);
    uint32_t coarsest_bits = 14;
    for (uint32_t m = 0; m < pack.meshCount(); ++m) {
        SCOPED_TRACE("level " + std::to_string(m));
        const lodrt::PrimitiveInfo& prim = pack.primitive(pack.mesh(m).first_primitive);
        uint64_t view = 0, bits = 0;
        const lodrt::JsonValue object = prim.json.find("extensions").find(kExt);
        ASSERT_TRUE(object.find("bufferView").asUint64(&view));
        ASSERT_TRUE(object.find("positionBits").asUint64(&bits));
        const lodrt::BufferViewInfo& v = pack.bufferView(uint32_t(view));
        const uint8_t* stream = pack.container().bin + v.byte_offset;
        lodrt::ValenceInfo info;
        ASSERT_EQ(lodrt::valenceReadInfo(stream, size_t(v.byte_length), &info), lodrt::Result::Ok);
        EXPECT_EQ(info.position_bits, bits);
        if (m == 0) {
            EXPECT_EQ(bits, 14u);
        }
        coarsest_bits = uint32_t(bits);
        const double q = std::sqrt(3.0) / 2.0 * double(info.cube_size) / double((1u << bits) - 1);
        if (m > 0 && bits < 14) {
            EXPECT_LE(q, 0.25 * metrics.levels[m].mean_error);
        }
        // Decoded positions against the plain (unquantized) ones: within q.
        std::vector<uint32_t> indices(size_t(info.triangle_count) * 3);
        std::vector<float> positions(size_t(info.vertex_count) * 3), normals(positions.size());
        std::vector<uint64_t> scratch((lodrt::valenceScratchSize(info) + 7) / 8);
        lodrt::ValenceOutput out;
        out.indices = indices.data();
        out.index_capacity = indices.size();
        out.positions = positions.data();
        out.position_capacity = positions.size();
        out.normals = info.has_normals ? normals.data() : nullptr;
        out.normal_capacity = normals.size();
        out.scratch = scratch.data();
        out.scratch_size = scratch.size() * 8;
        ASSERT_EQ(lodrt::valenceDecode(stream, size_t(v.byte_length), out), lodrt::Result::Ok);
        uint32_t position = lodrt::kNoIndex;
        for (uint32_t a = 0; a < prim.attribute_count; ++a)
            if (pack.attribute(prim.first_attribute + a).name == "POSITION")
                position = pack.attribute(prim.first_attribute + a).accessor;
        ASSERT_NE(position, lodrt::kNoIndex);
        const lodrt::AccessorInfo& pa = pack.accessor(position);
        const uint8_t* pb = pack.container().bin + pack.bufferView(pa.buffer_view).byte_offset + pa.byte_offset;
        double worst = 0;
        for (size_t i = 0; i < info.vertex_count; ++i) {
            double d2 = 0;
            for (size_t k = 0; k < 3; ++k) {
                float f = 0;
                std::memcpy(&f, pb + (i * 3 + k) * 4, 4);
                d2 += (double(f) - positions[i * 3 + k]) * (double(f) - positions[i * 3 + k]);
            }
            worst = std::max(worst, std::sqrt(d2));
        }
        EXPECT_LE(worst, q * 1.0001 + 1e-7);
    }
    EXPECT_LT(coarsest_bits, 14u);
}

} // namespace
