#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lod_pack_builder.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/selection.h"

using lodrt::kNoLevel;
using lodrt::LodTable;
using lodrt::ModelSet;
using lodrt::Pack;
using lodrt::Result;
using lodrt::SelectionParams;

namespace {

// Errors 0, 0.001, 0.004, 0.016; with fov 90 degrees and a 1000 px viewport K = 500, so at 1 px the
// levels are acceptable from 0, 0.5, 2 and 8 units.
struct Fixture {
    std::vector<uint8_t> bytes = lodrt_test::lodPackGlb();
    Pack pack;
    ModelSet models;
    Fixture() {
        EXPECT_EQ(lodrt::loadPack(bytes.data(), bytes.size(), nullptr, &pack), Result::Ok);
        EXPECT_EQ(lodrt::buildModels(pack, nullptr, &models), Result::Ok);
    }
};

SelectionParams params(float hysteresis) {
    SelectionParams p;
    p.vertical_fov = float(M_PI / 2);
    p.viewport_height = 1000;
    p.hysteresis = hysteresis;
    return p;
}

} // namespace

TEST(SelectionTest, PicksCoarsestLevelWithinThreshold) {
    Fixture fx;
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, params(-1), nullptr), Result::Ok);
    EXPECT_NEAR(t.acceptDistance(0, 2), 2.0f, 1e-5);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 0.4f, kNoLevel), 0);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.0f, kNoLevel), 1);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 3.0f, kNoLevel), 2);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1e6f, kNoLevel), 3);
    // A coarser current level than allowed is refined at once.
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.0f, 3), 1);
}

TEST(SelectionTest, ScreenSpaceErrorStaysUnderThreshold) {
    Fixture fx;
    for (float h : {-1.0f, 0.1f, 0.5f}) {
        LodTable t;
        ASSERT_EQ(t.prepare(fx.models, params(h), nullptr), Result::Ok);
        uint8_t level = kNoLevel;
        for (int step = 0; step < 4000; ++step) {
            const float d = 0.01f + 12.0f * std::fabs(std::sin(step * 0.003f)); // in and out again
            level = lodrt::selectLevel(t, 0, d, level);
            const float sse = fx.models.modelLevel(0, level).hausdorff_error * 500.0f / d;
            EXPECT_LE(sse, 1.0f + 1e-4f) << d;
        }
    }
}

TEST(SelectionTest, HysteresisHoldsLevelInsideBand) {
    Fixture fx;
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, params(0.1f), nullptr), Result::Ok);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 2.1f, 1), 1); // acceptable for 2 but not past 2 * 1.1
    EXPECT_EQ(lodrt::selectLevel(t, 0, 2.25f, 1), 2);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 2.1f, 2), 2); // back inside the band: stays
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.99f, 2), 1);
}

TEST(SelectionTest, SlowCameraFlipsEachBoundaryOnce) {
    Fixture fx;
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, params(0.1f), nullptr), Result::Ok);
    // Camera creeps outward with a jitter of +-0.5% per frame (a hand-held VR head).
    uint8_t level = kNoLevel;
    int flips = 0;
    for (int step = 0; step < 20000; ++step) {
        const float d = 0.3f + step * 0.0006f + 0.005f * (step % 2 ? 1 : -1) * (0.3f + step * 0.0006f);
        const uint8_t next = lodrt::selectLevel(t, 0, d, level);
        if (level != kNoLevel && next != level) ++flips;
        level = next;
    }
    EXPECT_EQ(flips, 3); // 0 -> 1 -> 2 -> 3, never back
    // Without the band the same jitter flickers at every boundary.
    LodTable none;
    ASSERT_EQ(none.prepare(fx.models, params(-1), nullptr), Result::Ok);
    level = kNoLevel;
    flips = 0;
    for (int step = 0; step < 20000; ++step) {
        const float d = 0.3f + step * 0.0006f + 0.005f * (step % 2 ? 1 : -1) * (0.3f + step * 0.0006f);
        const uint8_t next = lodrt::selectLevel(none, 0, d, level);
        if (level != kNoLevel && next != level) ++flips;
        level = next;
    }
    EXPECT_GT(flips, 3);
}

TEST(SelectionTest, BiasFinestLevelAndBands) {
    Fixture fx;
    SelectionParams p = params(-1);
    p.lod_bias = 1; // as if twice as far
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, p, nullptr), Result::Ok);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.1f, kNoLevel), 2);
    p.lod_bias = 0;
    p.finest_level = 2;
    ASSERT_EQ(t.update(fx.models, p), Result::Ok);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 0.1f, kNoLevel), 2);
    p.finest_level = 200; // clamped to the coarsest level
    ASSERT_EQ(t.update(fx.models, p), Result::Ok);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 0.1f, kNoLevel), 3);
    // Distance bands: baked switch distance = error * 500 with a 10% band.
    p = SelectionParams();
    p.mode = lodrt::SelectionMode::DistanceBands;
    ASSERT_EQ(t.update(fx.models, p), Result::Ok);
    EXPECT_EQ(lodrt::selectLevel(t, 0, 2.1f, 1), 1);  // below band_far 2.2
    EXPECT_EQ(lodrt::selectLevel(t, 0, 2.3f, 1), 2);  // beyond it
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.85f, 2), 2); // above band_near 1.8
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.75f, 2), 1);
}

TEST(SelectionTest, CrossFadeRisesBeforeTheSwitch) {
    Fixture fx;
    SelectionParams p = params(0.1f);
    p.cross_fade = 0.2f;
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, p, nullptr), Result::Ok);
    float fade = -1;
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.0f, 1, &fade), 1);
    EXPECT_EQ(fade, 0.0f); // far from the switch at 2.2
    EXPECT_EQ(lodrt::selectLevel(t, 0, 1.98f, 1, &fade), 1);
    EXPECT_NEAR(fade, 0.5f, 1e-3); // halfway through [1.76, 2.2]
    EXPECT_EQ(lodrt::selectLevel(t, 0, 100.0f, 3, &fade), 3);
    EXPECT_EQ(fade, 0.0f); // coarsest level: nothing to fade to
}

TEST(SelectionTest, RejectsBadParams) {
    Fixture fx;
    LodTable t;
    SelectionParams p;
    p.vertical_fov = 4;
    EXPECT_EQ(t.prepare(fx.models, p, nullptr), Result::InvalidArgument);
    p = SelectionParams();
    p.pixel_threshold = -1;
    EXPECT_EQ(t.prepare(fx.models, p, nullptr), Result::InvalidArgument);
    p = SelectionParams();
    p.cross_fade = 1;
    EXPECT_EQ(t.prepare(fx.models, p, nullptr), Result::InvalidArgument);
    p = SelectionParams();
    p.lod_bias = NAN;
    EXPECT_EQ(t.prepare(fx.models, p, nullptr), Result::InvalidArgument);
}

TEST(SelectionTest, BatchMatchesSingleAndUsesResidency) {
    Fixture fx;
    LodTable t;
    ASSERT_EQ(t.prepare(fx.models, params(0.1f), nullptr), Result::Ok);
    const size_t n = 64;
    std::vector<float> x(n), y(n, 0), z(n, 0), r(n, 0.5f), s(n);
    std::vector<uint32_t> model(n, 0);
    std::vector<uint8_t> level(n, kNoLevel), draw(n);
    std::vector<lodrt::Containment> vis(n, lodrt::Containment::Inside);
    for (size_t i = 0; i < n; ++i) x[i] = 0.2f * float(i), s[i] = 1.0f + float(i % 3);
    vis[5] = lodrt::Containment::Outside;
    lodrt::InstanceArrays in{x.data(), y.data(), z.data(), r.data(), s.data(), model.data(), n};
    // Only levels 1 and 3 are resident: level 0 and 1 draw 1, levels 2 and 3 draw 3.
    uint8_t resident[lodrt::kMaxLevels] = {1, 1, 3, 3, kNoLevel, kNoLevel, kNoLevel, kNoLevel};
    lodrt::SelectionOutput out{level.data(), draw.data(), nullptr};
    const float eye[3] = {0, 0, 0};
    EXPECT_EQ(lodrt::selectLevels(t, eye, in, vis.data(), resident, out), n - 1);
    for (size_t i = 0; i < n; ++i) {
        if (i == 5) {
            EXPECT_EQ(level[i], kNoLevel);
            EXPECT_EQ(draw[i], kNoLevel);
            continue;
        }
        const float d = std::fmax(std::fabs(x[i]) - 0.5f, 0.0f) / s[i];
        EXPECT_EQ(level[i], lodrt::selectLevel(t, 0, d, kNoLevel)) << i;
        EXPECT_EQ(draw[i], resident[level[i]]) << i;
    }
    std::vector<lodrt::ModelDemand> demand(1);
    lodrt::accumulateDemand(t, params(0.1f), eye, in, vis.data(), level.data(), demand.data());
    EXPECT_EQ(demand[0].wanted_level, 0);
    EXPECT_GT(demand[0].priority, 0.0f);
}
