// Batch progress: the fraction and ETA from stage events, the bar text, and the CLI drawing the bar
// only when stderr is a terminal.
#include <gtest/gtest.h>

#include <filesystem>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/progress.h"
#include "test_paths.h"

namespace {

using lodbake::BakeStage;
using lodbake::BatchProgress;
using lodbake::kWholePack;

TEST(BatchProgressTest, FractionFollowsStagesWeightedByJob) {
    BatchProgress p({3.0, 1.0}, {1, 2}, {"big.glb", "small.glb"});
    EXPECT_EQ(p.fraction(), 0.0);
    EXPECT_LT(p.etaSeconds(10.0), 0.0); // nothing known yet
    p.stageDone(0, 0, BakeStage::Load);
    p.stageDone(0, 0, BakeStage::Repair);
    p.stageDone(0, 0, BakeStage::LodChain);
    const double after_chain = p.fraction();
    EXPECT_NEAR(after_chain, 0.75 * (0.01 + 0.09 + 0.36), 1e-12);
    // Two inputs: each input's stage is half the job's share.
    p.stageDone(1, 0, BakeStage::LodChain);
    EXPECT_NEAR(p.fraction(), after_chain + 0.25 * 0.36 / 2, 1e-12);
    // A finished job counts fully, whatever stages were reported.
    p.jobDone(1);
    p.jobDone(1); // idempotent
    EXPECT_EQ(p.jobsDone(), 1u);
    EXPECT_NEAR(p.fraction(), after_chain + 0.25, 1e-12);
    const double f = p.fraction();
    EXPECT_NEAR(p.etaSeconds(20.0), 20.0 * (1 - f) / f, 1e-9);
    p.jobDone(0);
    EXPECT_EQ(p.fraction(), 1.0);
    EXPECT_EQ(p.etaSeconds(20.0), 0.0);
}

// The stages that take the time carry the share: after the chain less than half is done, and the
// measurement and the per-level coding earn theirs run by run, never more than their share.
TEST(BatchProgressTest, StagesRunSeveralTimesEarnTheirShareRunByRun) {
    BatchProgress p({1.0}, {1}, {"dragon.glb"}, {6});
    for (BakeStage s : {BakeStage::Load, BakeStage::Repair, BakeStage::LodChain}) p.stageDone(0, 0, s);
    const double after_chain = p.fraction();
    EXPECT_LT(after_chain, 0.5);
    p.stageDone(0, 0, BakeStage::Pfrep);
    p.stageDone(0, 0, BakeStage::Measure); // the reference sides
    const double after_first_measure = p.fraction();
    p.stageDone(0, 0, BakeStage::Measure); // the rest
    EXPECT_NEAR(p.fraction() - after_first_measure, after_first_measure - after_chain - 0.07, 1e-12);
    p.stageDone(0, 0, BakeStage::Textures);
    const double before_coding = p.fraction();
    EXPECT_LT(before_coding, 0.85);
    for (int level = 0; level < 6; ++level) p.stageDone(0, 0, BakeStage::Encode);
    const double coded = p.fraction();
    EXPECT_NEAR(coded - before_coding, 0.15, 1e-12);
    p.stageDone(0, 0, BakeStage::Encode); // a seventh run earns nothing
    p.stageDone(0, 0, BakeStage::Measure);
    EXPECT_EQ(p.fraction(), coded);
    p.stageDone(0, kWholePack, BakeStage::Pack);
    p.stageDone(0, kWholePack, BakeStage::Write);
    EXPECT_NEAR(p.fraction(), 0.99, 1e-9); // at most 99 % until the job is done

    // A small input measures in one run: the texture levels that follow it complete its share.
    BatchProgress one({1.0}, {1}, {"bunny.glb"}, {6});
    one.stageDone(0, 0, BakeStage::Measure);
    EXPECT_NEAR(one.fraction(), 0.15, 1e-12);
    one.stageDone(0, 0, BakeStage::Textures);
    EXPECT_NEAR(one.fraction(), 0.31, 1e-12);
}

// The bar names the stage that is running (the one with the largest share when several run side by
// side), and the last one finished when nothing runs.
TEST(BatchProgressTest, BarNamesTheRunningStage) {
    BatchProgress p({1.0, 1.0}, {1, 1}, {"dragon.glb", "bunny.glb"}, {6, 6});
    p.stageRunning(0, 0, BakeStage::LodChain, true);
    EXPECT_NE(p.barLine(1.0, 120).find("lod_chain dragon.glb"), std::string::npos) << p.barLine(1.0, 120);
    p.stageRunning(0, 0, BakeStage::LodChain, false);
    p.stageDone(0, 0, BakeStage::LodChain);
    p.stageRunning(0, 0, BakeStage::Pfrep, true);
    p.stageRunning(0, 0, BakeStage::Measure, true);
    p.stageRunning(0, 0, BakeStage::Encode, true);
    EXPECT_EQ(p.shownStage(), BakeStage::Measure);
    p.stageRunning(0, 0, BakeStage::Measure, false);
    EXPECT_EQ(p.shownStage(), BakeStage::Encode);
    p.stageRunning(0, 0, BakeStage::Encode, false); // a run with nothing to code ends without a time
    p.stageRunning(0, 0, BakeStage::Pfrep, false);
    p.stageDone(0, 0, BakeStage::Pfrep);
    EXPECT_EQ(p.shownStage(), BakeStage::Pfrep); // nothing runs: the last stage finished
    p.stageRunning(1, 0, BakeStage::Repair, true); // another pack moves: the bar follows it
    EXPECT_NE(p.barLine(1.0, 120).find("repair bunny.glb"), std::string::npos) << p.barLine(1.0, 120);
    p.jobDone(1); // its runs are over with it
    p.stageRunning(0, 0, BakeStage::Pack, true);
    EXPECT_NE(p.barLine(1.0, 120).find("pack dragon.glb"), std::string::npos) << p.barLine(1.0, 120);
}

TEST(BatchProgressTest, BarShowsPercentJobsStageAndEtaWithinTheWidth) {
    BatchProgress p({1.0, 1.0}, {1, 1}, {"rock.glb", "tree.glb"});
    p.stageDone(1, 0, BakeStage::Load);
    p.stageDone(1, 0, BakeStage::Repair);
    p.jobDone(0);
    const std::string line = p.barLine(30.0, 100);
    EXPECT_LE(line.size(), 100u);
    EXPECT_EQ(line.front(), '[');
    EXPECT_NE(line.find(" 55%"), std::string::npos) << line;
    EXPECT_NE(line.find("1/2"), std::string::npos) << line;
    EXPECT_NE(line.find("repair tree.glb"), std::string::npos) << line;
    EXPECT_NE(line.find("ETA 0:25"), std::string::npos) << line;
    EXPECT_LE(p.barLine(30.0, 40).size(), 40u);
    EXPECT_EQ(BatchProgress::formatDuration(3725), "1:02:05");
    EXPECT_EQ(BatchProgress::formatDuration(59.6), "1:00");
}

TEST(BatchProgressTest, CliDrawsTheBarOnlyOnATerminal) {
    // util-linux `script` gives the bake a pseudo-terminal (Debian's bsdutils, an essential package).
    ASSERT_EQ(lodbake_test::runCommand("command -v script").exit_code, 0)
        << "no `script` command: install util-linux's script (Debian: bsdutils)";
    const std::string d = lodbake_test::scratchDir() + "/progress_tty_" + std::to_string(::getpid());
    std::filesystem::create_directories(d);
    const std::string assets = lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock.conf";
    const std::string bake = lodbake_test::shellQuote(lodbake_test::lodbakeCli()) + " bake " +
                             lodbake_test::shellQuote(assets) + " -o " + lodbake_test::shellQuote(d + "/rock.glb") +
                             " --levels 0.5 --threads 1";
    const auto tty = lodbake_test::runCommand("script -qfec " + lodbake_test::shellQuote(bake) + " /dev/null");
    ASSERT_EQ(tty.exit_code, 0) << tty.output;
    EXPECT_NE(tty.output.find("\r\033[K["), std::string::npos) << tty.output;
    EXPECT_NE(tty.output.find("100%"), std::string::npos) << tty.output;
    EXPECT_NE(tty.output.find("ETA"), std::string::npos) << tty.output;
    // The bar names the stage and the pack (which stage is shown when: BarNamesTheRunningStage); the
    // rock's repair, with the merge of its scans, runs long enough to be drawn.
    EXPECT_NE(tty.output.find("repair rock.glb"), std::string::npos) << tty.output;
    EXPECT_EQ(tty.output.find("lodbake: [1/1]"), std::string::npos) << "plain lines on a terminal";
    const auto quiet =
        lodbake_test::runCommand("script -qfec " + lodbake_test::shellQuote(bake + " --quiet") + " /dev/null");
    ASSERT_EQ(quiet.exit_code, 0) << quiet.output;
    EXPECT_EQ(quiet.output.find('['), std::string::npos) << quiet.output;
}

} // namespace
