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

// Damaged scan sets: every truncation of a good .conf and every byte garbled into a control
// character, a digit, a letter or a line break either reads (the prefix or edit is still a valid
// set) or fails with one line naming the .conf; a transform that would push a finite scan outside
// the float range is refused instead of producing infinite positions.
TEST(ConfTest, TruncatedAndGarbledConfsFailOnOneLineNamingTheConf) {
    const std::string dir = lodbake_test::scratchDir() + "/conf_damaged";
    std::filesystem::create_directories(dir);
    writeText(dir + "/a.ply", kTrianglePly);
    const std::string conf = dir + "/set.conf";
    const std::string good = "camera 0 0 0 0 0 0 1\nmesh calib.ply 0 0 0 0 0 0 1\n"
                             "bmesh a.ply 0.5 0 -1 0 0 0.7071068 0.7071068\nbmesh a.ply 1e-3 2 3 0.1 0.2 0.3 0.9\n";
    auto read = [&](const std::string& text, const std::string& what) {
        writeText(conf, text);
        Diagnostics d;
        auto r = readConf(conf, ReadOptions(), d);
        if (r.ok()) {
            EXPECT_TRUE(checkMeshConsistency(r->mesh, what).ok()) << what;
            for (const Vec3f& p : r->mesh.positions)
                EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << what;
            return true;
        }
        const std::string& m = r.status().message();
        EXPECT_EQ(m.rfind(conf + ": ", 0), 0u) << what << ": " << m;
        EXPECT_EQ(m.find('\n'), std::string::npos) << what << ": " << m;
        return false;
    };
    ASSERT_TRUE(read(good, "good"));
    size_t refused = 0;
    for (size_t n = 0; n < good.size(); ++n) refused += !read(good.substr(0, n), "cut to " + std::to_string(n));
    EXPECT_GT(refused, good.size() / 2) << "most cuts lose the bmesh lines or cut a field";
    for (size_t i = 0; i < good.size(); i += 3)
        for (char c : {'\0', '\n', '9', 'x', '#', '\t'}) {
            std::string garbled = good;
            garbled[i] = c;
            read(garbled, "byte " + std::to_string(i) + " set to " + std::to_string(int(c)));
        }
    EXPECT_FALSE(read("bmesh a.ply 1e300 0 0 0 0 0 1\n", "translation beyond float"));
    writeText(conf, "bmesh a.ply 1e300 0 0 0 0 0 1\n");
    Diagnostics d;
    auto far = readConf(conf, ReadOptions(), d);
    ASSERT_FALSE(far.ok());
    EXPECT_NE(far.status().message().find("line 1: the transform moves scan 'a.ply' outside the float range"),
              std::string::npos)
        << far.status().message();
    EXPECT_FALSE(read("bmesh a.ply 0 0 0 0 0 0 1e-300\n", "zero quaternion"));
    EXPECT_FALSE(read("bmesh a.ply 0 0 0 0 0 0 1 extra\n", "ten fields"));
    EXPECT_FALSE(read("bmesh a.ply 0 0 0 0 0 0 nan\n", "nan field"));
    EXPECT_FALSE(read(std::string("bmesh a.ply 0 0 0 0 0 0 1\0\n", 27), "a NUL byte"));
}
