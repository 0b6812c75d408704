#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lodbake/pack/pack.h"

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
    const nlohmann::json j = nlohmann::json::parse(e.json);
    ASSERT_EQ(j["levels"].size(), 4u);
    EXPECT_EQ(j["levels"][3]["hausdorffError"].get<double>(), 0.05);
    EXPECT_EQ(j["levels"][0]["hysteresisBand"].size(), 2u);
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
