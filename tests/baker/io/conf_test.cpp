#include "lodbake/io/conf.h"

#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "mesh_builders.h"
#include "test_paths.h"

using namespace lodbake;

namespace {

void writeText(const std::string& path, const std::string& text) {
    ASSERT_TRUE(writeFileAtomic(path, text.data(), text.size()).ok()) << path;
}

const char* kTrianglePly = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                           "1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n";

} // namespace

TEST(ConfTest, TransformIsConjugateQuaternionThenTranslation) {
    // q = 90 degrees about +z: R(q) maps x to y, so R(q)^T maps x to -y.
    Mesh m = lodbake_test::makeMesh({{1, 0, 0}}, {});
    m.normals.push_back({1, 0, 0});
    const double s = std::sqrt(0.5);
    const double q[4] = {0, 0, s, s};
    applyConfTransform(m, Vec3d(10, 20, 30), q);
    EXPECT_NEAR(m.positions[0].x, 10.0f, 1e-5f);
    EXPECT_NEAR(m.positions[0].y, 19.0f, 1e-5f);
    EXPECT_NEAR(m.positions[0].z, 30.0f, 1e-5f);
    EXPECT_NEAR(m.normals[0].y, -1.0f, 1e-6f);
}

TEST(ConfTest, ConcatenatesScansWithoutWelding) {
    const std::string dir = lodbake_test::scratchDir() + "/conf_two";
    std::filesystem::create_directories(dir);
    writeText(dir + "/a.ply", kTrianglePly);
    writeText(dir + "/set.conf", "camera 0 0 0 0 0 0 1\nbmesh a.ply 0 0 0 0 0 0 1\nbmesh a.ply 5 0 0 0 0 0 2\n");
    Diagnostics d;
    auto r = readMesh(dir + "/set.conf", ReadOptions(), d);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->mesh.vertexCount(), 6u);
    EXPECT_EQ(r->mesh.faceCount(), 2u);
    EXPECT_EQ(r->mesh.indices[3], 3u);
    EXPECT_FLOAT_EQ(r->mesh.positions[3].x, 6.0f); // unnormalised identity quaternion, then +5 in x
    ASSERT_EQ(r->mesh.submeshes.size(), 2u);
    EXPECT_EQ(r->mesh.submeshes[1].name, "a.ply");
    EXPECT_EQ(r->source.format, MeshFormat::Conf);
    ASSERT_EQ(r->source.files_read.size(), 3u);
    EXPECT_EQ(r->source.files_read[0], dir + "/set.conf");
}

TEST(ConfTest, StanfordDragonSetMatchesTheMergedScan) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    // dragon_stand_merged.ply was made from these 15 scans and this .conf (shared README): same
    // triangles, and the same world-space extent.
    Diagnostics d;
    auto set = readMesh(lodbake_test::sharedMesh("range_scans/dragon_stand/dragonStandRight.conf"), ReadOptions(), d);
    ASSERT_TRUE(set.ok()) << set.status().message();
    auto merged = readMesh(lodbake_test::sharedMesh("dragon_stand_merged.ply"), ReadOptions(), d);
    ASSERT_TRUE(merged.ok()) << merged.status().message();
    EXPECT_EQ(set->mesh.vertexCount(), 469193u);
    EXPECT_EQ(set->mesh.faceCount(), merged->mesh.faceCount());
    EXPECT_EQ(set->source.files_read.size(), 16u);
    const Aabb a = computeBounds(set->mesh), b = computeBounds(merged->mesh);
    for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(a.min[k], b.min[k], 1e-6f) << k;
        EXPECT_NEAR(a.max[k], b.max[k], 1e-6f) << k;
    }
}

TEST(ConfTest, MissingScanNamesLineAndFile) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    // bun.conf lists all ten bunny scans, but only bun000 is in the shared folder.
    Diagnostics d;
    auto r = readMesh(lodbake_test::sharedMesh("bun.conf"), ReadOptions(), d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("bun.conf: line"), std::string::npos) << r.status().message();
    EXPECT_NE(r.status().message().find(".ply"), std::string::npos) << r.status().message();
}
