// The `simplify` and `lods` subcommands, run as a user would (the library is tested elsewhere).
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/diagnostics.h"
#include "lodbake/io/mesh_io.h"
#include "simplify_test_meshes.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace {

using lodbake_test::CliRun;

CliRun lodbake(const std::vector<std::string>& args) { return lodbake_test::runLodbake(args); }

// A sphere written once as a PLY input for every test.
const std::string& sphereFile() {
    static const std::string path = [] {
        const std::string p = lodbake_test::scratchDir() + "/simplify_cli_sphere.ply";
        lodbake::Diagnostics d;
        EXPECT_TRUE(lodbake::writeMesh(lodbake_test::icosphere(4), p, lodbake::WriteOptions(), d).ok());
        return p;
    }();
    return path;
}

size_t triangles(const std::string& path) {
    lodbake::Diagnostics d;
    auto m = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    EXPECT_TRUE(m.ok()) << m.status().message();
    return m.ok() ? m->mesh.faceCount() : 0;
}

TEST(SimplifyCliTest, SimplifyWritesTheTargetTriangleCount) {
    const std::string out = lodbake_test::scratchDir() + "/simplify_cli_half.ply";
    std::filesystem::remove(out);
    const CliRun r = lodbake({"simplify", sphereFile(), "-o", out, "--triangles", "1000", "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_LE(triangles(out), 1000u);
    EXPECT_GE(triangles(out), 998u);
    EXPECT_NE(r.out.find("\"hausdorff_rel\""), std::string::npos);
    const CliRun ratio = lodbake({"simplify", sphereFile(), "-o", out, "--ratio", "0.25"});
    ASSERT_EQ(ratio.exit_code, 0) << ratio.err;
    EXPECT_LE(triangles(out), 1280u);
}

TEST(SimplifyCliTest, LodsWritesEveryLevelAndTheJsonReport) {
    const std::string prefix = lodbake_test::scratchDir() + "/simplify_cli_chain";
    const CliRun r = lodbake({"lods", sphereFile(), "-o", prefix, "--levels", "0.5,0.1,0.02"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const size_t expected[] = {2560, 512, 103};
    for (int i = 0; i < 3; ++i) {
        const std::string file = prefix + "_lod" + std::to_string(i) + ".ply";
        ASSERT_TRUE(std::filesystem::exists(file)) << file;
        EXPECT_LE(triangles(file), expected[i]);
        EXPECT_GE(triangles(file) + 2, expected[i]);
    }
    const std::string json = lodbake_test::readTextFile(prefix + ".json");
    for (const char* key : {"\"levels\"", "\"triangles\"", "\"vertices\"", "\"hausdorff\"", "\"mean_rel\"",
                            "\"switch_distance\"", "\"screen_coverage\""})
        EXPECT_NE(json.find(key), std::string::npos) << key;
}

// A flat-then-wavy grid with a flat patch lying 0.0001 above its flat half (covered).
bool hasPatchVertex(const std::string& path) {
    lodbake::Diagnostics d;
    auto m = lodbake::readMesh(path, lodbake::ReadOptions(), d);
    EXPECT_TRUE(m.ok());
    if (!m.ok()) return false;
    for (const lodbake::Vec3f& p : m->mesh.positions)
        if (p.z > 5e-5f && p.z < 2e-4f && p.x < 0.35f && p.y < 0.35f) return true;
    return false;
}

TEST(SimplifyCliTest, RemoveCoveredComponentsFlag) {
    lodbake::Mesh mesh = lodbake_test::grid(64, [](float x, float y) {
        return x < 0.5f ? 0.0f : 0.05f * std::sin(20.0f * (x - 0.5f)) * std::cos(12.0f * y);
    });
    const lodbake::Mesh patch = lodbake_test::grid(10, [](float, float) { return 0.0f; });
    const uint32_t base = uint32_t(mesh.positions.size());
    for (const lodbake::Vec3f& p : patch.positions) mesh.positions.push_back(p * 0.2f + lodbake::Vec3f(0.1f, 0.1f, 1e-4f));
    for (uint32_t i : patch.indices) mesh.indices.push_back(base + i);
    const std::string in = lodbake_test::scratchDir() + "/simplify_cli_covered.ply";
    lodbake::Diagnostics d;
    ASSERT_TRUE(lodbake::writeMesh(mesh, in, lodbake::WriteOptions(), d).ok());
    ASSERT_TRUE(hasPatchVertex(in));
    const std::string prefix = lodbake_test::scratchDir() + "/simplify_cli_covered";
    ASSERT_EQ(lodbake({"lods", in, "-o", prefix + "_kept", "--levels", "0.05"}).exit_code, 0);
    EXPECT_TRUE(hasPatchVertex(prefix + "_kept_lod0.ply"));
    const CliRun r = lodbake({"lods", in, "-o", prefix + "_cov", "--levels", "0.05", "--remove-covered-components"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_FALSE(hasPatchVertex(prefix + "_cov_lod0.ply"));
    const std::string out = prefix + "_simplified.ply";
    ASSERT_EQ(lodbake({"simplify", in, "-o", out, "--ratio", "0.05", "--remove-covered-components"}).exit_code, 0);
    EXPECT_FALSE(hasPatchVertex(out));
    EXPECT_EQ(lodbake({"simplify", in, "-o", out, "--method", "multilevel", "--ratio", "0.5",
                       "--remove-covered-components"})
                  .exit_code,
              2);
}

TEST(SimplifyCliTest, UsageErrorsExitTwo) {
    const std::string out = lodbake_test::scratchDir() + "/simplify_cli_unused.ply";
    EXPECT_EQ(lodbake({"simplify", sphereFile(), "-o", out}).exit_code, 2); // no target
    EXPECT_EQ(lodbake({"simplify", sphereFile(), "-o", out, "--ratio", "0.5", "--error", "1"}).exit_code, 2);
    EXPECT_EQ(lodbake({"simplify", sphereFile(), "-o", out, "--ratio", "1.5"}).exit_code, 2);
    EXPECT_EQ(lodbake({"simplify", sphereFile(), "-o", out, "--triangles", "abc"}).exit_code, 2);
    EXPECT_EQ(lodbake({"lods", sphereFile(), "-o", out, "--levels", "0.5,x"}).exit_code, 2);
    EXPECT_EQ(lodbake({"lods", sphereFile(), "-o", out, "--levels", "0"}).exit_code, 2);
    EXPECT_EQ(lodbake({"lods", sphereFile()}).exit_code, 2);
    const CliRun missing = lodbake({"simplify", "/nonexistent/in.ply", "-o", out, "--ratio", "0.5"});
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_EQ(missing.err.rfind("error: ", 0), 0u);
    EXPECT_FALSE(std::filesystem::exists(out));
}

} // namespace
