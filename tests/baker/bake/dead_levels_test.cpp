// Dead levels (docs/bake.md, "Dead levels"): a level whose next coarser level is taken at almost the
// same distance is never (or hardly ever) drawn, so the bake drops it. The policy on switch
// distances, the metrics it edits, the chain it prunes, and whole bakes of a mesh whose first levels
// are lossless (a finely tessellated box beside a bumpy sphere: the box simplifies for free first)
// against controls: the same mesh with the rule off, and a mesh whose levels all differ.

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/core/lod_policy.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/selection.h"
#include "mesh_builders.h"

namespace {

using namespace lodbake;

// A closed box [-1, 1]^3 whose faces are n x n grids (shared edges welded), beside the bumpy sphere
// moved to x = 4. The box loses no accuracy down to a few triangles, so the chain's first levels
// measure only the rounding of their positions.
Mesh boxBesideSphere(int n) {
    Mesh m = lodbake_test::bumpySphere(24, 48);
    for (Vec3f& p : m.positions) p.x += 4.0f;
    const uint32_t base = uint32_t(m.positions.size());
    const int side = n + 1;
    // Grid points of the box's surface, indexed on the (n+1)^3 lattice; only surface points are used.
    std::vector<uint32_t> id(size_t(side) * side * side, UINT32_MAX);
    auto point = [&](int i, int j, int k) {
        uint32_t& v = id[(size_t(i) * side + j) * side + k];
        if (v == UINT32_MAX) {
            v = uint32_t(m.positions.size());
            m.positions.push_back(Vec3f(-1.0f + 2.0f * float(i) / float(n), -1.0f + 2.0f * float(j) / float(n),
                                        -1.0f + 2.0f * float(k) / float(n)));
        }
        return v;
    };
    // Each face: the lattice points with one coordinate fixed at 0 or n, wound outwards.
    for (int axis = 0; axis < 3; ++axis)
        for (int end = 0; end < 2; ++end)
            for (int a = 0; a < n; ++a)
                for (int b = 0; b < n; ++b) {
                    auto at = [&](int u, int v) {
                        int c[3];
                        c[axis] = end * n;
                        c[(axis + 1) % 3] = u;
                        c[(axis + 2) % 3] = v;
                        return point(c[0], c[1], c[2]);
                    };
                    const uint32_t p00 = at(a, b), p10 = at(a + 1, b), p11 = at(a + 1, b + 1), p01 = at(a, b + 1);
                    if (end == 1)
                        m.indices.insert(m.indices.end(), {p00, p10, p11, p00, p11, p01});
                    else
                        m.indices.insert(m.indices.end(), {p00, p11, p10, p00, p01, p11});
                }
    EXPECT_GT(m.positions.size(), base);
    return m;
}

BakeSettings testSettings(double min_ratio) {
    BakeSettings s;
    s.error_samples = 20000;
    s.lod_min_switch_ratio = min_ratio;
    return s;
}

Result<BakeOutput> bakeOne(const Mesh& mesh, const BakeSettings& settings, Diagnostics& diagnostics) {
    std::vector<BakeInput> inputs(1);
    inputs[0].name = "asset";
    inputs[0].mesh = mesh;
    return bake(std::move(inputs), settings, diagnostics);
}

std::vector<double> switchDistances(const LodMetrics& m) {
    std::vector<double> d;
    for (const LodMetricsLevel& l : m.levels) d.push_back(l.switch_distance);
    return d;
}

// Every level of the pack's group is what lodrt's selection picks somewhere: coming from LOD0, at
// some distance between its switch distance and the next level's.
void expectEveryLevelSelectable(const std::vector<uint8_t>& glb) {
    lodrt::Pack pack;
    char error[256] = {};
    ASSERT_EQ(lodrt::loadPack(glb.data(), glb.size(), nullptr, &pack, error, sizeof error), lodrt::Result::Ok) << error;
    lodrt::ModelSet models;
    ASSERT_EQ(lodrt::buildModels(pack, nullptr, &models, error, sizeof error), lodrt::Result::Ok) << error;
    lodrt::SelectionParams params;
    params.hysteresis = -1; // no band: the level is the coarsest whose switch distance was passed
    lodrt::LodTable table;
    ASSERT_EQ(table.prepare(models, params, nullptr), lodrt::Result::Ok);
    const uint32_t n = models.model(0).level_count;
    for (uint32_t l = 1; l < n; ++l) {
        const float from = table.acceptDistance(0, l);
        const float to = l + 1 < n ? table.acceptDistance(0, l + 1) : from * 2 + 1;
        ASSERT_LT(from, to) << "level " << l;
        EXPECT_EQ(lodrt::selectLevel(table, 0, 0.5f * (from + to), lodrt::kNoLevel), l) << "level " << l;
    }
}

TEST(DeadLevelsTest, PolicyKeepsTheCoarserOfTwoLevelsThatSwitchTogether) {
    EXPECT_FALSE(isDistinctSwitch(1.0, 1.0, 1.05));
    EXPECT_FALSE(isDistinctSwitch(1.0, 1.05, 1.05)); // more than k times farther, strictly
    EXPECT_TRUE(isDistinctSwitch(1.0, 1.06, 1.05));
    EXPECT_FALSE(isDistinctSwitch(0.0, 0.0, 1.05)); // two lossless levels
    EXPECT_TRUE(isDistinctSwitch(0.0, 1e-9, 1.05));
    EXPECT_FALSE(isDistinctSwitch(1e-9, 2e-9, 1.05, 1e-6)); // both within the rounding floor
    EXPECT_TRUE(isDistinctSwitch(1.0, 1.0, 0.0));           // 0: every level counts

    using V = std::vector<bool>;
    EXPECT_EQ(distinctLevels({0, 1, 1.0002, 3}, 1.05), (V{true, false, true, true}));
    EXPECT_EQ(distinctLevels({0, 1, 1.0002, 3}, 0.0), (V{true, true, true, true}));
    EXPECT_EQ(distinctLevels({0, 0, 0, 2}, 1.05), (V{true, false, true, true}));
    // From the coarsest level down: 1.06 is too close to 1.09, 1.03 is not, 1 is too close to 1.03.
    EXPECT_EQ(distinctLevels({0, 1, 1.03, 1.06, 1.09}, 1.05), (V{true, false, true, false, true}));
    EXPECT_EQ(distinctLevels({0, 1e-9, 3e-9, 5}, 1.05, 1e-6), (V{true, false, true, true}));
    // LOD0 and the last level always stay.
    EXPECT_EQ(distinctLevels({0, 0}, 1.05), (V{true, true}));
    EXPECT_EQ(distinctLevels({0, 1, 1}, 1.05), (V{true, false, true}));
}

TEST(DeadLevelsTest, DroppedMetricsLevelsLeaveTheKeptOnesAsTheyWere) {
    LodChain chain;
    LodMetrics m;
    const double errors[] = {0, 0.01, 0.0250, 0.02501, 0.08};
    for (size_t l = 0; l < 5; ++l) {
        LodMetricsLevel level;
        level.triangles = 1000 >> l;
        level.hausdorff_error = errors[l];
        level.switch_distance = errors[l] * 100;
        m.levels.push_back(level);
        if (l > 0) {
            chain.levels.emplace_back();
            chain.levels.back().target_ratio = 1.0 / double(1 << l);
        }
    }
    const LodMetrics before = m;
    const std::vector<DroppedLodLevel> dropped = dropIndistinctLevels(m, Mesh(), chain, ScreenParams(), 1.05);
    ASSERT_EQ(dropped.size(), 1u);
    EXPECT_EQ(dropped[0].level, 2u);
    EXPECT_EQ(dropped[0].ratio, 0.25);
    EXPECT_EQ(dropped[0].triangles, 250u);
    EXPECT_EQ(dropped[0].finer_level, 1u);
    EXPECT_EQ(dropped[0].coarser_level, 3u);
    EXPECT_EQ(dropped[0].switch_distance, before.levels[2].switch_distance);
    EXPECT_EQ(dropped[0].coarser_switch_distance, before.levels[3].switch_distance);
    ASSERT_EQ(m.levels.size(), 4u);
    for (size_t k = 0; k < 4; ++k) {
        const size_t l = k < 2 ? k : k + 1;
        EXPECT_EQ(m.levels[k].triangles, before.levels[l].triangles);
        EXPECT_EQ(m.levels[k].switch_distance, before.levels[l].switch_distance);
    }
    const std::string note = droppedLevelNote(dropped[0], 1.05);
    EXPECT_NE(note.find("level 2 (ratio 0.25, 250 triangles"), std::string::npos) << note;
    EXPECT_NE(note.find("level 1 serves until"), std::string::npos) << note;
    // 0 keeps every level.
    LodMetrics all = before;
    EXPECT_TRUE(dropIndistinctLevels(all, Mesh(), chain, ScreenParams(), 0.0).empty());
    EXPECT_EQ(all.levels.size(), 5u);
}

TEST(DeadLevelsTest, KeepLevelsLeavesTheKeptLevelsAndTheRecordAlone) {
    LodChainOptions options;
    options.measure_error = false;
    Diagnostics diagnostics;
    Result<LodChain> chain = buildLodChain(lodbake_test::bumpySphere(16, 32), options, diagnostics);
    ASSERT_TRUE(chain.ok()) << chain.status().message();
    ASSERT_EQ(chain->levels.size(), 5u);
    const LodChain before = *chain;
    keepLevels(*chain, {true, false, true, false, true});
    ASSERT_EQ(chain->levels.size(), 3u);
    for (size_t k = 0; k < 3; ++k) {
        EXPECT_EQ(chain->levels[k].target_ratio, before.levels[2 * k].target_ratio);
        EXPECT_EQ(chain->levels[k].collapse_count, before.levels[2 * k].collapse_count);
        EXPECT_EQ(chain->levels[k].mesh.indices, before.levels[2 * k].mesh.indices);
    }
    EXPECT_EQ(chain->sequence.records.size(), before.sequence.records.size());
}

TEST(DeadLevelsTest, LosslessLevelIsDroppedAndTheRestAreBakedAsWithoutTheRule) {
    const Mesh mesh = boxBesideSphere(24);
    Diagnostics with_rule_diag, without_diag;
    const Result<BakeOutput> with_rule = bakeOne(mesh, testSettings(1.05), with_rule_diag);
    const Result<BakeOutput> without = bakeOne(mesh, testSettings(0.0), without_diag);
    ASSERT_TRUE(with_rule.ok()) << with_rule.status().message();
    ASSERT_TRUE(without.ok()) << without.status().message();

    // Control: without the rule every ratio is a level, and levels 1 and 2 measure no more than the
    // rounding of their positions (far below the floor), so they would be taken at the same distance.
    const LodMetrics& all = without->assets[0].metrics;
    ASSERT_EQ(all.levels.size(), 6u);
    const double floor = lodErrorFloor(mesh);
    EXPECT_LT(all.levels[1].hausdorff_error, floor);
    EXPECT_LT(all.levels[2].hausdorff_error, floor);
    EXPECT_GT(all.levels[3].hausdorff_error, 1000 * floor);
    EXPECT_TRUE(without->assets[0].dropped_levels.empty());

    // The rule drops level 1 (ratio 0.5) only; the kept levels keep their numbers.
    const BakeAssetReport& report = with_rule->assets[0];
    ASSERT_EQ(report.dropped_levels.size(), 1u);
    EXPECT_EQ(report.dropped_levels[0].level, 1u);
    EXPECT_EQ(report.dropped_levels[0].ratio, 0.5);
    EXPECT_EQ(report.dropped_levels[0].finer_level, 0u);
    EXPECT_EQ(report.dropped_levels[0].coarser_level, 2u);
    ASSERT_EQ(report.metrics.levels.size(), 5u);
    for (size_t k = 0; k < 5; ++k) {
        const size_t l = k == 0 ? 0 : k + 1;
        EXPECT_EQ(report.metrics.levels[k].triangles, all.levels[l].triangles) << k;
        EXPECT_EQ(report.metrics.levels[k].switch_distance, all.levels[l].switch_distance) << k;
    }
    bool noted = false;
    for (const Diagnostic& d : with_rule_diag.items())
        noted |= d.message.find("asset: lod chain: level 1 (ratio 0.5, ") != std::string::npos &&
                 d.message.find("dropped") != std::string::npos;
    EXPECT_TRUE(noted);
    EXPECT_NE(bakeReportJson(*with_rule, testSettings(1.05)).find("\"droppedLevels\""), std::string::npos);
    EXPECT_EQ(bakeReportJson(*without, testSettings(0.0)).find("\"droppedLevels\""), std::string::npos);
    EXPECT_LT(with_rule->glb.size(), without->glb.size());

    // What is left obeys the rule, and lodrt's selection picks every level somewhere.
    const std::vector<double> d = switchDistances(report.metrics);
    for (size_t l = 1; l + 1 < d.size(); ++l) EXPECT_GT(d[l + 1], 1.05 * d[l]) << l;
    expectEveryLevelSelectable(with_rule->glb);

    // The same bytes with one thread and with two.
    BakeSettings one = testSettings(1.05), two = testSettings(1.05);
    one.threads = 1;
    two.threads = 2;
    Diagnostics d1, d2;
    const Result<BakeOutput> a = bakeOne(mesh, one, d1), b = bakeOne(mesh, two, d2);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(a->glb, with_rule->glb);
    EXPECT_EQ(b->glb, with_rule->glb);
}

TEST(DeadLevelsTest, DistinctLevelsAreBakedByteForByteAsWithoutTheRule) {
    // Control: a bumpy sphere's levels all differ, so the rule changes nothing.
    const Mesh mesh = lodbake_test::bumpySphere(40, 80);
    Diagnostics d1, d2;
    const Result<BakeOutput> with_rule = bakeOne(mesh, testSettings(1.05), d1);
    const Result<BakeOutput> without = bakeOne(mesh, testSettings(0.0), d2);
    ASSERT_TRUE(with_rule.ok() && without.ok());
    EXPECT_TRUE(with_rule->assets[0].dropped_levels.empty());
    EXPECT_EQ(with_rule->assets[0].metrics.levels.size(), 6u);
    EXPECT_EQ(with_rule->glb, without->glb);
    expectEveryLevelSelectable(with_rule->glb);
}

TEST(DeadLevelsTest, SettingIsZeroOrAFactorAboveOne) {
    for (const char* ok : {"0", "1.001", "1.05", "4", "100"}) {
        BakeSettings s;
        EXPECT_TRUE(
            applyPresetJson(std::string(R"({"version": 1, "lod_min_switch_ratio": )") + ok + "}", "p.json", s).ok())
            << ok;
        EXPECT_EQ(s.lod_min_switch_ratio, std::stod(ok));
    }
    for (const char* bad : {"1", "0.5", "-1", "101", "\"1.1\""}) {
        BakeSettings s;
        const Status status =
            applyPresetJson(std::string(R"({"version": 1, "lod_min_switch_ratio": )") + bad + "}", "p.json", s);
        ASSERT_FALSE(status.ok()) << bad;
        EXPECT_EQ(status.message().rfind("p.json: /lod_min_switch_ratio: expected ", 0), 0u) << status.message();
    }
    BakeSettings s;
    s.lod_min_switch_ratio = 1.0;
    EXPECT_FALSE(validateSettings(s, "settings").ok());
    EXPECT_EQ(BakeSettings().lod_min_switch_ratio, 1.05);
}

} // namespace
