// The switch policy is computed twice: the baker derives each level's switch distance and hysteresis
// band from its measured error (LODBAKE_lod_metrics), and lodrt's screen-space-error selection derives
// its accept and coarsen distances from the same error at run time. These tests hold the two to the
// same numbers for the same screen parameters, so a change to either formula fails here.

#include <gtest/gtest.h>

#include <vector>

#include "lodbake/bake/bake.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/selection.h"
#include "mesh_builders.h"

namespace {

// A bumpy height field: its levels have distinct, growing errors.
lodbake::Mesh bumpyField(int n) {
    return lodbake_test::wavyField(n, 0.06f, 0.45f, 0.35f);
}

struct Screen {
    double pixel_threshold;
    double viewport_height_px;
    double vertical_fov_deg;
    double hysteresis;
};

void expectBakerAndRuntimeAgree(const Screen& screen) {
    lodbake::BakeSettings settings;
    settings.lod_ratios = {0.5, 0.2, 0.05, 0.01};
    settings.error_samples = 4000;
    settings.pixel_threshold = screen.pixel_threshold;
    settings.viewport_height_px = screen.viewport_height_px;
    settings.vertical_fov_deg = screen.vertical_fov_deg;
    settings.hysteresis = screen.hysteresis;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "field";
    inputs[0].mesh = bumpyField(48);
    lodbake::Diagnostics diagnostics;
    auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
    ASSERT_TRUE(baked.ok()) << baked.status().message();

    lodrt::Pack pack;
    char error[256] = {};
    ASSERT_EQ(lodrt::loadPack(baked->glb.data(), baked->glb.size(), nullptr, &pack, error, sizeof error),
              lodrt::Result::Ok)
        << error;
    lodrt::ModelSet models;
    ASSERT_EQ(lodrt::buildModels(pack, nullptr, &models, error, sizeof error), lodrt::Result::Ok) << error;
    ASSERT_EQ(models.modelCount(), 1u);
    ASSERT_EQ(models.model(0).error_source, lodrt::ErrorSource::Measured);

    lodrt::SelectionParams params;
    params.mode = lodrt::SelectionMode::ScreenSpaceError;
    params.pixel_threshold = float(screen.pixel_threshold);
    params.viewport_height = float(screen.viewport_height_px);
    params.vertical_fov = float(screen.vertical_fov_deg * 3.14159265358979323846 / 180.0);
    params.hysteresis = float(screen.hysteresis);
    lodrt::LodTable table;
    ASSERT_EQ(table.prepare(models, params, nullptr), lodrt::Result::Ok);

    const uint32_t level_count = models.model(0).level_count;
    ASSERT_EQ(level_count, 5u);
    float largest_error = 0;
    size_t compared = 0;
    for (uint32_t l = 1; l < level_count; ++l) {
        const lodrt::LevelInfo& level = models.modelLevel(0, l);
        SCOPED_TRACE("level " + std::to_string(l));
        ASSERT_GT(level.hausdorff_error, 0.0f);
        // The baker keeps switch distances non-decreasing (a level never switches in before a finer
        // one); the runtime's per-level formula gives the same number wherever the error itself grows.
        if (level.hausdorff_error < largest_error) continue;
        largest_error = level.hausdorff_error;
        const float tolerance = 1e-5f * level.switch_distance;
        EXPECT_NEAR(table.acceptDistance(0, l), level.switch_distance, tolerance);
        EXPECT_NEAR(table.coarsenDistance(0, l), level.band_far, tolerance);
        // And the selection itself: just inside the switch distance the finer level stays, just
        // beyond the band the runtime switches to this one.
        EXPECT_LT(lodrt::selectLevel(table, 0, level.switch_distance * 0.999f, uint8_t(l - 1)), l);
        EXPECT_GE(lodrt::selectLevel(table, 0, level.band_far * 1.001f, uint8_t(l - 1)), l);
        ++compared;
    }
    EXPECT_GE(compared, 3u);
}

TEST(LodPolicyAgreementTest, DefaultScreenGivesTheBakedSwitchDistances) {
    expectBakerAndRuntimeAgree({1.0, 1080.0, 60.0, 0.1});
}

TEST(LodPolicyAgreementTest, OtherScreenGivesTheBakedSwitchDistances) {
    expectBakerAndRuntimeAgree({2.5, 1440.0, 45.0, 0.25});
}

} // namespace
