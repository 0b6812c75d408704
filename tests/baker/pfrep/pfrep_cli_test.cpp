// PfrepCliTest: `lodbake pfrep` builds a blob and `--extract K` writes level K; bad blobs and
// arguments fail with one error line.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../simplify/simplify_test_meshes.h"
#include "lodbake/io/mesh_io.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace {

using lodbake_test::CliRun;

CliRun lodbake(const std::vector<std::string>& args) { return lodbake_test::runLodbake(args); }

TEST(PfrepCliTest, BuildThenExtractLevels) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string in = dir + "/pfrep_cli_sphere.ply";
    lodbake::Diagnostics d;
    ASSERT_TRUE(lodbake::writeMesh(lodbake_test::icosphere(3), in, {}, d).ok());
    const std::string blob = dir + "/pfrep_cli_sphere.lbp";
    CliRun r = lodbake({"pfrep", in, "-o", blob, "--ratio", "0.1"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("bytes/vertex"), std::string::npos);
    for (const char* k : {"0", "100", "500"}) {
        const std::string out = dir + "/pfrep_cli_sphere_" + k + ".ply";
        r = lodbake({"pfrep", "--extract", k, blob, "-o", out});
        ASSERT_EQ(r.exit_code, 0) << r.err;
        auto loaded = lodbake::readMesh(out, {}, d);
        ASSERT_TRUE(loaded.ok());
        // Closed sphere, one vertex removed per level: two triangles fewer each.
        EXPECT_EQ(loaded->mesh.faceCount(), 1280u - 2u * std::stoul(k));
    }
    r = lodbake({"pfrep", "--extract", "100000", blob, "-o", dir + "/pfrep_cli_x.ply"});
    EXPECT_EQ(r.exit_code, 1);
    // A damaged blob: one error line naming the file.
    const std::string bad = dir + "/pfrep_cli_bad.lbp";
    {
        std::string bytes = lodbake_test::readTextFile(blob);
        bytes.resize(bytes.size() / 2);
        std::ofstream(bad, std::ios::binary) << bytes;
    }
    r = lodbake({"pfrep", "--extract", "0", bad, "-o", dir + "/pfrep_cli_bad.ply"});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find(bad), std::string::npos);
    EXPECT_FALSE(std::filesystem::exists(dir + "/pfrep_cli_bad.ply"));
    EXPECT_EQ(lodbake({"pfrep", in}).exit_code, 2);
    EXPECT_EQ(lodbake({"pfrep", in, "-o", blob, "--ratio", "2"}).exit_code, 2);
}

} // namespace
