// `lodbake repair` end to end: exit codes, --json report, output written atomically.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/cleanup/validate.h"
#include "lodbake/io/mesh_io.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace {

using lodbake_test::CliRun;

CliRun repairCli(std::vector<std::string> args) {
    args.insert(args.begin(), "repair");
    return lodbake_test::runLodbake(args);
}

} // namespace

TEST(RepairCliTest, UsageErrors) {
    EXPECT_EQ(repairCli({}).exit_code, 2);
    EXPECT_EQ(repairCli({"a.ply"}).exit_code, 2); // no -o
    EXPECT_EQ(repairCli({"a.ply", "-o", "b.xyz"}).exit_code, 2);
    EXPECT_EQ(repairCli({"a.ply", "-o", "b.ply", "--denoise", "magic"}).exit_code, 2);
    EXPECT_EQ(repairCli({"a.ply", "-o", "b.ply", "--max-hole-edges", "lots"}).exit_code, 2);
    const CliRun help = repairCli({"--help"});
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("usage: lodbake repair"), std::string::npos);
}

TEST(RepairCliTest, MissingInputIsAnErrorAndWritesNothing) {
    const std::string out = lodbake_test::scratchDir() + "/repair_missing_out.ply";
    std::filesystem::remove(out);
    const CliRun r = repairCli({lodbake_test::scratchDir() + "/no_such_file.ply", "-o", out});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(RepairCliTest, BunnyZipperJsonReport) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string out = lodbake_test::scratchDir() + "/bunny_zipper_repaired.ply";
    const CliRun r = repairCli({lodbake_test::sharedMesh("bunny_zipper.ply"), "-o", out, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("\"pass\": \"holes\""), std::string::npos);
    EXPECT_NE(r.out.find("\"holes_filled\": 5"), std::string::npos);
    EXPECT_NE(r.out.find("\"closed_manifold\": true"), std::string::npos);
    EXPECT_NE(r.out.find("\"boundary_loop_lengths\": [\n      80,"), std::string::npos) << r.out.substr(0, 2000);
    lodbake::Diagnostics d;
    lodbake::Result<lodbake::LoadedMesh> loaded = lodbake::readMesh(out, lodbake::ReadOptions(), d);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    EXPECT_TRUE(lodbake::validate(loaded->mesh).isClosedManifold());
}
