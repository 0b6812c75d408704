// The cluster LOD builder (lodbake/cluster/cluster_lod.h) and the runtime cut over what it builds
// (lodrt/cluster_lod.h): limits, monotonic errors, determinism, and the crack-free bar (for random
// views, the cut has no boundary edge that LOD0 lacks).

#include "lodbake/cluster/cluster_lod.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <array>
#include <unordered_map>
#include <random>
#include <string>

#include "core/parallel.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/cluster_lod.h"
#include "cluster_checks.h"
#include "test_paths.h"

namespace {

using lodbake::ClusterLodHierarchy;
using lodbake::Mesh;
using lodbake::Vec3f;

Mesh gridMesh(int n) {
    Mesh m;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x)
            m.positions.push_back(Vec3f(float(x) / n, float(y) / n, 0.05f * std::sin(float(x * 7 + y * 3) / n)));
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, d, a, d, c});
        }
    return m;
}

ClusterLodHierarchy build(const Mesh& mesh) {
    lodbake::Diagnostics d;
    auto h = lodbake::buildClusterLod(mesh, lodbake::ClusterLodOptions(), d);
    EXPECT_TRUE(h.ok()) << h.status().message();
    return h.ok() ? std::move(h.value()) : ClusterLodHierarchy();
}

using namespace lodbake_test;

TEST(ClusterLodTest, GridHierarchyIsWithinLimitsAndMonotonic) {
    const Mesh mesh = gridMesh(90);
    const ClusterLodHierarchy h = build(mesh);
    ASSERT_FALSE(h.clusters.empty());
    EXPECT_GT(h.level_count, 3u);
    // Every LOD0 triangle is in exactly one LOD0 cluster.
    size_t lod0_triangles = 0;
    for (uint32_t c = 0; c < h.lod0_cluster_count; ++c) lod0_triangles += h.clusters[c].triangle_count;
    EXPECT_EQ(lod0_triangles, mesh.faceCount());
    expectLimitsAndMonotonic(h);
}

TEST(ClusterLodTest, GridCutsAreCrackFree) {
    const Mesh mesh = gridMesh(90);
    expectCrackFree(mesh, build(mesh), 300, 7);
}

TEST(ClusterLodTest, FrustumCutIsTheFullCutLessOutsideClusters) {
    const Mesh mesh = gridMesh(90);
    const ClusterLodHierarchy h = build(mesh);
    CutRunner runner(h);
    const float eye[3] = {0.1f, 0.2f, 0.3f};
    const auto full = runner.cut(eye, nullptr, 1.0f);
    std::vector<uint32_t> full_cut(runner.out.begin(), runner.out.begin() + full.written);
    // A frustum looking along +x from the eye: roughly half of the grid is outside.
    lodrt::Frustum f;
    const float planes[6][4] = {{1, 0, 0, -0.1f}, {-1, 0, 0, 10}, {0, 1, 0, 10},
                                {0, -1, 0, 0.6f}, {0, 0, 1, 10},  {0, 0, -1, 10}};
    std::memcpy(f.planes, planes, sizeof planes);
    const auto culled = runner.cut(eye, &f, 1.0f);
    std::vector<uint32_t> expected;
    for (uint32_t c : full_cut)
        if (lodrt::classifySphere(f, h.clusters[c].center, h.clusters[c].radius) != lodrt::Containment::Outside)
            expected.push_back(c);
    std::vector<uint32_t> got(runner.out.begin(), runner.out.begin() + culled.written);
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected);
    EXPECT_LT(got.size(), full_cut.size());
    EXPECT_LE(culled.groups_visited, full.groups_visited);
}

TEST(ClusterLodTest, ValidateRejectsBrokenHierarchies) {
    const Mesh mesh = gridMesh(40);
    ClusterLodHierarchy h = build(mesh);
    ASSERT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::Ok);
    ClusterLodHierarchy bad = h;
    bad.clusters[0].parent_group = uint32_t(bad.groups.size());
    EXPECT_EQ(lodrt::validateClusterLod(bad.view()), lodrt::Result::OutOfBounds);
    bad = h;
    bad.clusters[0].first_vertex = uint32_t(bad.positions.size());
    EXPECT_EQ(lodrt::validateClusterLod(bad.view()), lodrt::Result::OutOfBounds);
    bad = h;
    bad.groups[0].error = NAN;
    EXPECT_EQ(lodrt::validateClusterLod(bad.view()), lodrt::Result::BadStructure);
    bad = h;
    bad.group_children[0] = bad.group_children.back(); // a child of the last group
    EXPECT_EQ(lodrt::validateClusterLod(bad.view()), lodrt::Result::BadStructure);
    bad = h;
    bad.roots.push_back(0);
    EXPECT_EQ(lodrt::validateClusterLod(bad.view()), lodrt::Result::BadStructure);
}

TEST(ClusterLodTest, RejectsBadInput) {
    Mesh mesh = gridMesh(4);
    mesh.indices[5] = 1000;
    lodbake::Diagnostics d;
    auto h = lodbake::buildClusterLod(mesh, lodbake::ClusterLodOptions(), d);
    ASSERT_FALSE(h.ok());
    EXPECT_NE(h.status().message().find("out of range"), std::string::npos);
    mesh = gridMesh(4);
    mesh.positions[3].x = NAN;
    EXPECT_FALSE(lodbake::buildClusterLod(mesh, lodbake::ClusterLodOptions(), d).ok());
    lodbake::ClusterLodOptions o;
    o.max_triangles = 300;
    EXPECT_FALSE(lodbake::buildClusterLod(gridMesh(4), o, d).ok());
}

Mesh loadShared(const std::string& name) {
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), lodbake::ReadOptions(), d);
    EXPECT_TRUE(loaded.ok()) << name;
    return loaded.ok() ? std::move(loaded->mesh) : Mesh();
}

class ClusterLodSharedTest : public ::testing::TestWithParam<const char*> {};

TEST_P(ClusterLodSharedTest, ThousandRandomViewsAreCrackFree) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh mesh = loadShared(GetParam());
    ASSERT_GT(mesh.faceCount(), 0u);
    const ClusterLodHierarchy h = build(mesh);
    expectLimitsAndMonotonic(h);
    expectCrackFree(mesh, h, 1000, 11);
}

INSTANTIATE_TEST_SUITE_P(Scans, ClusterLodSharedTest, ::testing::Values("igea.ply", "dragon_poisson.ply", "dragon_stand_merged.ply"),
                         [](const auto& param_info) {
                             std::string n = param_info.param;
                             return n.substr(0, n.find('.'));
                         });

TEST(ClusterLodTest, SameBytesAtOneAndTwoThreads) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh mesh = loadShared("igea.ply");
    ClusterLodHierarchy one, two;
    {
        lodbake::ScopedThreadLimit limit(1);
        one = build(mesh);
    }
    {
        lodbake::ScopedThreadLimit limit(2);
        two = build(mesh);
    }
    ASSERT_EQ(one.clusters.size(), two.clusters.size());
    ASSERT_EQ(one.groups.size(), two.groups.size());
    EXPECT_EQ(0, std::memcmp(one.clusters.data(), two.clusters.data(), one.clusters.size() * sizeof one.clusters[0]));
    EXPECT_EQ(0, std::memcmp(one.groups.data(), two.groups.data(), one.groups.size() * sizeof one.groups[0]));
    EXPECT_EQ(one.group_children, two.group_children);
    EXPECT_EQ(one.roots, two.roots);
    EXPECT_EQ(one.positions, two.positions);
    EXPECT_EQ(one.indices, two.indices);
}

} // namespace
