// The phase cut of the bake's post-chain tasks (baker/src/bake/phases.h; docs/bake.md,
// "Concurrency"): every task once, in the fixed start order; small assets in one phase, the big
// tasks of a large asset each alone.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bake/phases.h"

namespace {

using lodbake::bake_detail::concurrentPhases;
using lodbake::bake_detail::EncoderCost;
using lodbake::bake_detail::PhaseEstimates;
using lodbake::bake_detail::PhaseTask;

// "p0" LOD0-only encoder 0, "e1" other encoder 1 on LOD0, "L3" level 3, "M" measurement, "R1" the
// reference sides of levels 1 and on; phases separated by '|'.
std::string describe(const std::vector<std::vector<PhaseTask>>& phases) {
    std::string s;
    for (size_t p = 0; p < phases.size(); ++p) {
        if (p) s += " | ";
        for (size_t t = 0; t < phases[p].size(); ++t) {
            const PhaseTask& task = phases[p][t];
            if (t) s += " ";
            switch (task.kind) {
            case PhaseTask::Kind::Measure:
                s += "M";
                break;
            case PhaseTask::Kind::MeasureReference:
                s += "R" + std::to_string(task.index);
                break;
            case PhaseTask::Kind::Lod0Encoder:
                s += (task.index == 0 ? "p" : "e") + std::to_string(task.index);
                break;
            case PhaseTask::Kind::Level:
                s += "L" + std::to_string(task.index);
                break;
            }
        }
    }
    return s;
}

std::vector<size_t> desktopLevels(size_t lod0) {
    std::vector<size_t> t{lod0};
    for (double r : {0.5, 0.25, 0.1, 0.03, 0.01}) t.push_back(size_t(r * double(lod0)));
    return t;
}

// PFRep (LOD0 only), then valence (builtinStreamEncoders order, their StreamCost).
const std::vector<EncoderCost> kBuiltin{{true, 190}, {false, 110}};

TEST(BakePhasesTest, SmallAssetRunsEveryTaskAtOnce) {
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(70000))), "p0 M e1 L1 L2 L3 L4 L5");
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(300000))), "p0 M e1 L1 L2 L3 L4 L5");
}

TEST(BakePhasesTest, LargeAssetRunsItsBigTasksAlone) {
    // dragon_poisson: PFRep beside the reference sides of every level, the measurement alone, then
    // the coding of every level side by side.
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(1067852))), "p0 R1 | M | e1 L1 L2 L3 L4 L5");
    // A mid-size asset: the PFRep build beside the measurement and LOD0's coding, then the other levels.
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(500000))), "p0 M e1 | L1 L2 L3 L4 L5");
}

TEST(BakePhasesTest, ReferenceSidesOnlyBesideAnEarlierTaskAndBeforeTheMeasurement) {
    // Without a PFRep encoder it would run first in its phase, where it gains nothing.
    EXPECT_EQ(describe(concurrentPhases(std::vector<EncoderCost>{{false, 110}}, desktopLevels(1067852))), "M | p0 L1 L2 L3 L4 L5");
    // In the measurement's phase the measurement measures both sides itself.
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(300000))), "p0 M e1 L1 L2 L3 L4 L5");
    // Only LOD0: nothing to measure.
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, {1067852})), "p0 | M | e1");
    // Where the PFRep build and the reference sides together exceed the budget, the PFRep build runs
    // alone and the measurement measures both sides.
    // With one thread (measure_reference_ahead off) nothing would idle beside the PFRep build.
    PhaseEstimates one_thread;
    one_thread.measure_reference_ahead = false;
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(1067852), one_thread)), "p0 | M | e1 L1 L2 L3 L4 L5");
    PhaseEstimates smaller;
    smaller.budget_bytes = 224.0 * 1024 * 1024;
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(1067852), smaller)), "p0 | M | e1 L1 L2 L3 L4 L5");
}

TEST(BakePhasesTest, OrderAndTasksDoNotDependOnTheCut) {
    // Every task once, in the start order; the reference sides only where they are worth it.
    // (5,000,000 triangles: the PFRep build alone is above the budget, so nothing joins it.)
    for (size_t lod0 : {0ul, 1000ul, 250000ul, 600000ul, 1067852ul, 5000000ul}) {
        std::string all;
        for (const auto& phase : concurrentPhases(kBuiltin, desktopLevels(lod0)))
            for (const PhaseTask& task : phase) all += describe({{task}}) + " ";
        EXPECT_EQ(all, lod0 == 1067852ul ? "p0 R1 M e1 L1 L2 L3 L4 L5 " : "p0 M e1 L1 L2 L3 L4 L5 ") << lod0;
    }
    PhaseEstimates tiny;
    tiny.budget_bytes = 1;
    EXPECT_EQ(describe(concurrentPhases(kBuiltin, desktopLevels(1000), tiny)), "p0 | M | e1 | L1 | L2 | L3 | L4 | L5");
}

TEST(BakePhasesTest, NoStreamEncoders) {
    EXPECT_EQ(describe(concurrentPhases({}, {5000000, 100})), "M | L1");
    EXPECT_EQ(describe(concurrentPhases({}, {100})), "M");
}

} // namespace
