#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodbake/pack/pack_glb.h"
#include "lodbake/pack/pack.h"
#include "mesh_builders.h"

namespace {

using namespace lodbake;

LodMetrics sample() {
    LodMetrics m;
    m.bounding_radius = 1.0;
    for (double e : {0.0, 0.01, 0.004, 0.05}) { // level 2 measured below level 1
        LodMetricsLevel l;
        l.hausdorff_error = e;
        m.levels.push_back(l);
    }
    m.levels[1].screen_coverage = 0.8;
    m.levels[2].screen_coverage = 0.9; // inconsistent on purpose
    m.levels[3].screen_coverage = 0.2;
    return m;
}

TEST(LodMetricsTest, ScreenCoverageIsShiftedAndNonIncreasing) {
    const std::vector<double> c = msftScreenCoverage(sample());
    ASSERT_EQ(c.size(), 4u);
    EXPECT_EQ(c[0], 0.8);
    EXPECT_EQ(c[1], 0.8); // clamped: never above the finer level's
    EXPECT_EQ(c[2], 0.2);
    EXPECT_EQ(c[3], 0.0);
}

TEST(LodMetricsTest, ExtensionJsonHasEveryLevel) {
    const PackExtension e = lodMetricsExtension(sample());
    EXPECT_EQ(e.name, "LODBAKE_lod_metrics");
    EXPECT_FALSE(e.is_stream);
    const nlohmann::json j = nlohmann::json::parse(e.json.text());
    ASSERT_EQ(j["levels"].size(), 4u);
    EXPECT_EQ(j["levels"][3]["hausdorffError"].get<double>(), 0.05);
    EXPECT_EQ(j["levels"][0]["hysteresisBand"].size(), 2u);
}

// Pack JSON keeps 7 significant digits, rounded so that no written error or distance is below the
// measured one and no coverage above it; orderings survive.
TEST(LodMetricsTest, WrittenNumbersAreShortAndNeverClaimMore) {
    LodMetrics m;
    m.bounding_radius = 0.5825002115210216;
    const double errors[] = {0.0, 0.0025755927661294583, 0.0025755927661294584, 0.04051941208522528};
    for (double e : errors) {
        LodMetricsLevel l;
        l.hausdorff_error = e;
        l.mean_error = e / 7.0;
        l.hausdorff_error_rel = e / 1.1650004230420432;
        l.mean_error_rel = l.mean_error / 1.1650004230420432;
        l.switch_distance = e * 935.3074360871938;
        l.hysteresis_near = l.switch_distance * 0.9;
        l.hysteresis_far = l.switch_distance * 1.1;
        l.screen_coverage = e > 0.0 ? 0.0010787 / e : 1.0;
        m.levels.push_back(l);
    }
    const nlohmann::json j = nlohmann::json::parse(lodMetricsExtension(m).json.text());
    auto digits = [](double v) {
        const std::string text = nlohmann::json(v).dump();
        size_t n = 0;
        bool leading = true;
        for (char c : text) {
            if (c == 'e' || c == 'E') break;
            if (c < '0' || c > '9') continue;
            if (leading && c == '0') continue;
            leading = false;
            ++n;
        }
        return n;
    };
    EXPECT_GE(j["boundingRadius"].get<double>(), m.bounding_radius);
    EXPECT_LE(digits(j["boundingRadius"].get<double>()), 7u);
    for (size_t i = 0; i < m.levels.size(); ++i) {
        SCOPED_TRACE(i);
        const nlohmann::json& l = j["levels"][i];
        const LodMetricsLevel& in = m.levels[i];
        EXPECT_GE(l["hausdorffError"].get<double>(), in.hausdorff_error);
        EXPECT_GE(l["meanError"].get<double>(), in.mean_error);
        EXPECT_GE(l["hausdorffErrorRelative"].get<double>(), in.hausdorff_error_rel);
        EXPECT_GE(l["meanErrorRelative"].get<double>(), in.mean_error_rel);
        EXPECT_GE(l["switchDistance"].get<double>(), in.switch_distance);
        EXPECT_LE(l["screenCoverage"].get<double>(), in.screen_coverage);
        EXPECT_LE(l["hysteresisBand"][0].get<double>(), l["switchDistance"].get<double>());
        EXPECT_GE(l["hysteresisBand"][1].get<double>(), l["switchDistance"].get<double>());
        EXPECT_NEAR(l["hausdorffError"].get<double>(), in.hausdorff_error, 1e-6 * in.hausdorff_error);
        for (const char* key : {"hausdorffError", "meanError", "switchDistance", "screenCoverage"})
            EXPECT_LE(digits(l[key].get<double>()), 7u) << key << " " << l[key];
        if (i > 0) {
            EXPECT_GE(l["hausdorffError"].get<double>(), j["levels"][i - 1]["hausdorffError"].get<double>());
        }
    }
    EXPECT_EQ(j["levels"][0]["hausdorffError"].get<double>(), 0.0);
}

TEST(LodMetricsTest, CompactWithoutStreamsNamesTheMissingExtensions) {
    PackDescription d;
    EXPECT_TRUE(checkCompact(d).ok());
    d.compact = true;
    const Status s = checkCompact(d);
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find("LODBAKE_valence_compression"), std::string::npos);
    PackAsset asset;
    asset.levels.resize(1);
    PackExtension stream;
    stream.name = "LODBAKE_valence_compression";
    stream.is_stream = true;
    asset.levels[0].primitive_extensions = {{stream}};
    d.assets.push_back(asset);
    EXPECT_TRUE(checkCompact(d).ok());
}

} // namespace

namespace {

using namespace lodbake;

std::string glbJsonText(const std::vector<uint8_t>& glb) {
    uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    return std::string(glb.begin() + 20, glb.begin() + 20 + length);
}

// Extension objects are structured data written without a text round trip, yet every number is
// written as the JsonWriter's text of it would read back: integral values as integers, the rest as
// doubles; a non-finite one is a null, which the glTF writer leaves out; members sorted by key.
TEST(PackWriterTest, ExtensionNumbersAreWrittenAsTheirJsonText) {
    PackDescription description;
    PackAsset asset;
    asset.name = "a";
    asset.levels.resize(1);
    asset.levels[0].mesh = lodbake_test::singleTriangle();
    PackExtension e;
    e.name = "EXT_test";
    e.json = JsonNode::object();
    e.json.set("z", 3.0).set("y", 0.1).set("x", 2.5).set("w", int64_t(-5)).set("v", uint64_t(7));
    e.json.set("u", 1e20).set("t", std::numeric_limits<double>::quiet_NaN()).set("s", "text").set("r", true);
    e.json.set("q", JsonNode::array().push(-0.0).push(JsonNode::object().set("p", 4.0)));
    asset.node_extensions.push_back(e);
    description.assets.push_back(std::move(asset));
    Result<std::vector<uint8_t>> glb = writePackGlb(description);
    ASSERT_TRUE(glb.ok()) << glb.status().message();
    const std::string text = glbJsonText(*glb);
    EXPECT_NE(text.find("\"EXT_test\":{\"q\":[0,{\"p\":4}],\"r\":true,\"s\":\"text\",\"u\":1e+20,"
                        "\"v\":7,\"w\":-5,\"x\":2.5,\"y\":0.1,\"z\":3}"),
              std::string::npos)
        << text;
}

} // namespace
