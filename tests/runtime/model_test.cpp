#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lod_pack_builder.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"

using lodrt::ModelSet;
using lodrt::Pack;
using lodrt::Result;
using lodrt_test::LodPackSpec;

namespace {

struct Built {
    Result result;
    std::string message;
};

Built build(const LodPackSpec& spec, ModelSet* models, Pack* pack) {
    const std::vector<uint8_t> bytes = lodrt_test::lodPackGlb(spec);
    static std::vector<std::vector<uint8_t>> keep; // packs point into their bytes
    keep.push_back(bytes);
    char message[256] = "";
    Result r = lodrt::loadPack(keep.back().data(), keep.back().size(), nullptr, pack, message, sizeof(message));
    if (r != Result::Ok) return {r, message};
    r = lodrt::buildModels(*pack, nullptr, models, message, sizeof(message));
    return {r, message};
}

Built buildBroken(const LodPackSpec& spec) {
    Pack pack;
    ModelSet models;
    Built b = build(spec, &models, &pack);
    if (b.result != Result::Ok) {
        EXPECT_EQ(models.modelCount(), 0u);
    }
    return b;
}

} // namespace

TEST(ModelTest, BuildsChainWithMetricsAndBounds) {
    Pack pack;
    ModelSet models;
    LodPackSpec spec;
    spec.chains = 2;
    ASSERT_EQ(build(spec, &models, &pack).result, Result::Ok);
    ASSERT_EQ(models.modelCount(), 2u);
    const lodrt::ModelInfo& m = models.model(1);
    EXPECT_EQ(m.level_count, 4u);
    EXPECT_EQ(m.root_node, 4u);
    EXPECT_EQ(m.error_source, lodrt::ErrorSource::Measured);
    EXPECT_FLOAT_EQ(m.sphere_radius, std::sqrt(3.0f));
    EXPECT_FLOAT_EQ(m.aabb_min[0], -1.0f);
    const lodrt::LevelInfo& l2 = models.modelLevel(1, 2);
    EXPECT_EQ(l2.node, 6u);
    EXPECT_EQ(l2.triangle_count, 1u);
    EXPECT_FLOAT_EQ(l2.hausdorff_error, 0.004f);
    EXPECT_FLOAT_EQ(l2.switch_distance, 2.0f);
    EXPECT_FLOAT_EQ(l2.band_near, 1.8f);
    EXPECT_EQ(l2.data_offset, 6u * 44u);
    EXPECT_EQ(l2.data_size, 42u); // positions + 6 bytes of indices (the view, not the padding)
}

TEST(ModelTest, PlainMeshNodesAreSingleLevelModels) {
    Pack pack;
    ModelSet models;
    LodPackSpec spec;
    spec.errors = {0};
    spec.chains = 3;
    ASSERT_EQ(build(spec, &models, &pack).result, Result::Ok);
    ASSERT_EQ(models.modelCount(), 3u);
    EXPECT_EQ(models.model(2).level_count, 1u);
}

TEST(ModelTest, RejectsCyclicIds) {
    LodPackSpec spec;
    spec.chains = 2;
    spec.node0_lod_ids = "[4]"; // node 4 is chain 1's root, which lists 5, 6, 7: nested
    spec.node0_metrics = R"({"levels":[]})";
    Built b = buildBroken(spec);
    EXPECT_EQ(b.result, Result::BadGltf);
    EXPECT_NE(b.message.find("has MSFT_lod too"), std::string::npos) << b.message;
}

TEST(ModelTest, RejectsTwoNodeCycle) {
    // Node 0 lists node 1 and node 1 lists node 0.
    LodPackSpec spec;
    std::string json = lodrt_test::lodPackJson(spec);
    const std::string plain = R"({"name":"n1","mesh":1})";
    const size_t at = json.find(plain);
    ASSERT_NE(at, std::string::npos);
    json.replace(at, plain.size(), R"({"name":"n1","mesh":1,"extensions":{"MSFT_lod":{"ids":[0]}}})");
    const std::vector<uint8_t> bytes = lodrt_test::makeGlb(json, lodrt_test::lodPackBin(spec));
    Pack pack;
    ASSERT_EQ(lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack), Result::Ok);
    ModelSet models;
    char message[256];
    EXPECT_EQ(lodrt::buildModels(pack, nullptr, &models, message, sizeof(message)), Result::BadGltf);
    EXPECT_NE(std::string(message).find("cyclic"), std::string::npos) << message;
}

TEST(ModelTest, RejectsSelfReference) {
    LodPackSpec spec;
    spec.node0_lod_ids = "[1,0,2]";
    Built b = buildBroken(spec);
    EXPECT_EQ(b.result, Result::BadGltf);
    EXPECT_NE(b.message.find("cyclic"), std::string::npos) << b.message;
}

TEST(ModelTest, RejectsBadIds) {
    for (const char* ids : {"[1,1,2]", "[1,2,99]", "[1,2,-1]", "[1,2,1.5]", "{}", "[1,2,\"3\"]"}) {
        LodPackSpec spec;
        spec.node0_lod_ids = ids;
        EXPECT_EQ(buildBroken(spec).result, Result::BadGltf) << ids;
    }
}

TEST(ModelTest, RejectsMoreLevelsThanSupported) {
    LodPackSpec spec;
    spec.errors = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    Built b = buildBroken(spec);
    EXPECT_EQ(b.result, Result::BadGltf);
    EXPECT_NE(b.message.find("at most 8 levels"), std::string::npos) << b.message;
}

TEST(ModelTest, RejectsMetricsBreakingTheRules) {
    const char* bad[] = {
        R"({"levels":[]})", // count
        R"({"levels":[{"hausdorffError":0,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":0.1,"meanError":0,"switchDistance":1,"hysteresisBand":[0.9,1.1]},)"
        R"({"hausdorffError":0.05,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":0.2,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // decreasing
        R"({"levels":[{"hausdorffError":0,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":0.1,"meanError":0,"switchDistance":1,"hysteresisBand":[1.1,1.2]},)"
        R"({"hausdorffError":0.2,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":0.3,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // band
        R"({"levels":[{"hausdorffError":0.1,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":0.1,"meanError":0,"switchDistance":1,"hysteresisBand":[0.9,1.1]},)"
        R"({"hausdorffError":0.2,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":0.3,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // level 0 error
        R"({"levels":[{"hausdorffError":0,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":-0.1,"meanError":0,"switchDistance":1,"hysteresisBand":[0.9,1.1]},)"
        R"({"hausdorffError":0.2,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":0.3,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // negative
        R"({"levels":[{"hausdorffError":0,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":1e300,"meanError":0,"switchDistance":1,"hysteresisBand":[0.9,1.1]},)"
        R"({"hausdorffError":1e301,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":1e302,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // not a float
        R"({"levels":[{"hausdorffError":0,"meanError":0,"switchDistance":0,"hysteresisBand":[0,0]},)"
        R"({"hausdorffError":0.1,"meanError":0,"switchDistance":1},)"
        R"({"hausdorffError":0.2,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
        R"({"hausdorffError":0.3,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})", // no band
    };
    for (const char* metrics : bad) {
        LodPackSpec spec;
        spec.node0_metrics = metrics;
        Built b = buildBroken(spec);
        EXPECT_EQ(b.result, Result::BadGltf) << metrics;
        EXPECT_EQ(b.message.rfind("/nodes/0/extensions/LODBAKE_lod_metrics", 0), 0u) << b.message;
    }
}

TEST(ModelTest, RejectsPositionWithoutFiniteBounds) {
    for (const char* bounds : {R"("max":[1,1,1])", R"("min":[1,1,1],"max":[-1,1,1])", R"("min":[0,0],"max":[1,1])"}) {
        LodPackSpec spec;
        spec.position_min_max = bounds;
        Pack pack;
        ModelSet models;
        Built b = build(spec, &models, &pack);
        EXPECT_EQ(b.result, Result::BadGltf) << bounds << " " << b.message;
    }
}

TEST(ModelTest, FallsBackToScreenCoverage) {
    LodPackSpec spec;
    spec.node0_metrics = "none";
    spec.node0_extras = R"({"MSFT_screencoverage":[0.5,0.25,0.1,0]})";
    Pack pack;
    ModelSet models;
    Built b = build(spec, &models, &pack);
    ASSERT_EQ(b.result, Result::Ok) << b.message;
    EXPECT_EQ(models.model(0).error_source, lodrt::ErrorSource::ScreenCoverage);
    // coverage 0.5 at the 60 degree reference: d = r / (0.5 tan 30)
    EXPECT_NEAR(models.modelLevel(0, 1).switch_distance, std::sqrt(3.0) / (0.5 * std::tan(M_PI / 6)), 1e-4);
    EXPECT_LT(models.modelLevel(0, 1).hausdorff_error, models.modelLevel(0, 2).hausdorff_error);
    spec.node0_extras = R"({"MSFT_screencoverage":[0.5,0.6,0.1,0]})";
    EXPECT_EQ(buildBroken(spec).result, Result::BadGltf);
    spec.node0_extras = "{}";
    ASSERT_EQ(build(spec, &models, &pack).result, Result::Ok);
    EXPECT_EQ(models.model(0).error_source, lodrt::ErrorSource::Unknown);
    EXPECT_TRUE(std::isinf(models.modelLevel(0, 3).hausdorff_error));
}

TEST(ModelTest, EveryTruncatedPackFailsCleanly) {
    const std::vector<uint8_t> bytes = lodrt_test::lodPackGlb();
    for (size_t n = 0; n < bytes.size(); n += 7) {
        std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + n);
        Pack pack;
        Result r = lodrt::loadPack(prefix.data(), prefix.size(), nullptr, &pack);
        if (r == Result::Ok) {
            ModelSet models;
            lodrt::buildModels(pack, nullptr, &models);
        }
        EXPECT_NE(r, Result::Ok) << n;
    }
}

// LODBAKE_lod_metrics inputTriangles (an out-of-core chain that starts below its input): level 0 may
// then carry errors, not a switch distance; the count must be an integer at least level 0's.
TEST(ModelTest, InputTrianglesLetLevelZeroCarryAnError) {
    auto metrics = [](const char* input, double level0_error, double level0_switch) {
        char text[1024];
        std::snprintf(text, sizeof(text),
                      R"({%s"levels":[{"triangles":1,"hausdorffError":%g,"meanError":0,"switchDistance":%g,)"
                      R"("hysteresisBand":[0,%g]},)"
                      R"({"triangles":1,"hausdorffError":0.1,"meanError":0,"switchDistance":1,"hysteresisBand":[0.9,1.1]},)"
                      R"({"triangles":1,"hausdorffError":0.2,"meanError":0,"switchDistance":2,"hysteresisBand":[1.9,2.1]},)"
                      R"({"triangles":1,"hausdorffError":0.3,"meanError":0,"switchDistance":3,"hysteresisBand":[2.9,3.1]}]})",
                      input, level0_error, level0_switch, level0_switch);
        return std::string(text);
    };
    {
        Pack pack;
        ModelSet models;
        LodPackSpec spec;
        spec.node0_metrics = metrics(R"("inputTriangles":10,)", 0.05, 0);
        const Built b = build(spec, &models, &pack);
        ASSERT_EQ(b.result, Result::Ok) << b.message;
        EXPECT_EQ(models.model(0).input_triangle_count, 10u);
        EXPECT_FLOAT_EQ(models.modelLevel(0, 0).hausdorff_error, 0.05f);
    }
    const std::string refused[] = {
        metrics("", 0.05, 0),                           // an error on level 0 without inputTriangles
        metrics(R"("inputTriangles":10,)", 0.05, 0.5),  // a switch distance on level 0
        metrics(R"("inputTriangles":0,)", 0, 0),        // fewer than level 0's triangles
        metrics(R"("inputTriangles":"10",)", 0.05, 0),  // not an integer
    };
    for (const std::string& m : refused) {
        LodPackSpec spec;
        spec.node0_metrics = m;
        const Built b = buildBroken(spec);
        EXPECT_EQ(b.result, Result::BadGltf) << m;
        EXPECT_EQ(b.message.rfind("/nodes/0/extensions/LODBAKE_lod_metrics", 0), 0u) << b.message;
    }
}
