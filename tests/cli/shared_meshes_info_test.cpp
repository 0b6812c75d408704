// `lodbake info --json` on every shared scan agrees with ../shared/meshes/README.md: counts as
// stored, and the topology figures the README gives (as stored; welded by position for the glTF
// rows, as the README computes them).

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "test_paths.h"

namespace {

struct ReadmeRow {
    const char* file;
    uint64_t file_vertices;   // as stored in the file
    uint64_t triangles;       // after loading (strips and range grids triangulated)
    bool welded;              // compare the welded-by-position topology (glTF rows, spot's UV split)
    int64_t boundary_edges;   // -1: the README gives no figure
    int64_t components;
    int64_t non_manifold_edges;
    int64_t unreferenced;
};

// Figures from ../shared/meshes/README.md. The raw range grid's triangle count is that of the
// derived bunny_scan_bun000_tri.ply, which the README says was triangulated from it.
const ReadmeRow kRows[] = {
    {"bunny_zipper.ply", 35947, 69451, false, 223, 1, 0, 1113},
    {"igea.ply", 134345, 268686, false, 0, 1, 0, 0},
    {"igea_tristrips.ply", 134345, 268686, false, 0, 1, 0, 0},
    {"lucy100k.ply", 50002, 100000, false, 0, 1, 0, 0},
    {"nefertiti.obj", 49971, 99938, false, 0, 1, 0, 0},
    {"rocker_arm.obj", 10044, 20088, false, 0, 1, 0, 0},
    {"dragon_poisson.ply", 535884, 1067852, false, 3996, 8, 1, 0},
    {"bunny_scan_bun000.ply", 40256, 78505, false, 1871, 10, 0, -1},
    {"bunny_scan_bun000_tri.ply", 40173, 78505, false, 1871, 10, 0, 0},
    {"dragon_scan_stand0_tri.ply", 41802, 79436, false, 4152, 22, 0, 0},
    {"dragon_stand_merged.ply", 468773, 886456, false, 51008, 362, 0, 0},
    {"fandisk.obj", 6475, 12946, false, 0, 1, 0, 0},
    {"spot.obj", 2930, 5856, true, 0, 1, 0, -1},
    {"lee_perry_smith/LeePerrySmith.glb", 9279, 17684, true, 0, 1, 0, -1},
    {"nefertiti_fraunhofer_textured.glb", 11378, 19482, true, 516, 1, 3, -1},
};

std::string readText(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

class SharedMeshesInfoTest : public testing::TestWithParam<ReadmeRow> {};

TEST_P(SharedMeshesInfoTest, AgreesWithReadme) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const ReadmeRow& row = GetParam();
    const std::string out =
        lodbake_test::scratchDir() + "/info_" + std::to_string(::getpid()) + "_" + std::to_string(std::rand()) + ".json";
    const std::string cmd = "'" + lodbake_test::lodbakeCli() + "' info --json '" + lodbake_test::sharedMesh(row.file) +
                            "' >'" + out + "' 2>/dev/null";
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd;
    const nlohmann::json info = nlohmann::json::parse(readText(out));
    EXPECT_EQ(info["file_counts"]["vertices"].get<uint64_t>(), row.file_vertices);
    EXPECT_EQ(info["triangles"].get<uint64_t>(), row.triangles);
    const nlohmann::json& topo = info[row.welded ? "topology_welded_by_position" : "topology"];
    if (row.boundary_edges >= 0) {
        EXPECT_EQ(topo["boundary_edges"].get<int64_t>(), row.boundary_edges);
    }
    if (row.components >= 0) {
        EXPECT_EQ(topo["components"].get<int64_t>(), row.components);
    }
    if (row.non_manifold_edges >= 0) {
        EXPECT_EQ(topo["non_manifold_edges"].get<int64_t>(), row.non_manifold_edges);
    }
    if (row.unreferenced >= 0) {
        EXPECT_EQ(info["topology"]["unreferenced_vertices"].get<int64_t>(), row.unreferenced);
    }
    EXPECT_EQ(topo["degenerate_faces"].get<int64_t>(), 0) << "the README: no mesh has degenerate triangles";
}

std::string rowName(const testing::TestParamInfo<ReadmeRow>& info) {
    std::string n = info.param.file;
    for (char& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return n;
}

void PrintTo(const ReadmeRow& row, std::ostream* os) { *os << row.file; }

INSTANTIATE_TEST_SUITE_P(Readme, SharedMeshesInfoTest, testing::ValuesIn(kRows), rowName);

} // namespace
