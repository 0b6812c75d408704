#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(DegenerateTest, RemovesEachKindAndCountsIt) {
    Mesh m = quad();
    m.positions.push_back({0.5f, 0, 0});          // 4: on edge 0-1
    m.positions.push_back({std::nanf(""), 0, 0}); // 5
    m.indices.insert(m.indices.end(), {0, 0, 1}); // repeated index
    m.indices.insert(m.indices.end(), {0, 1, 4}); // zero area
    m.indices.insert(m.indices.end(), {2, 1, 0}); // duplicate of face 0 with the other winding
    m.indices.insert(m.indices.end(), {1, 2, 0}); // duplicate of face 0, rotated
    m.indices.insert(m.indices.end(), {0, 2, 5}); // non-finite vertex
    const DegenerateReport r = removeDegenerateFaces(m);
    EXPECT_EQ(r.repeated_index_faces, 1u);
    EXPECT_EQ(r.zero_area_faces, 1u);
    EXPECT_EQ(r.duplicate_faces, 2u);
    EXPECT_EQ(r.non_finite_faces, 1u);
    EXPECT_EQ(m.indices, quad().indices); // the first occurrences stay, in order
}

TEST(DegenerateTest, KeepsSubMeshRangesInStep) {
    Mesh m = quad();
    m.indices.insert(m.indices.end(), {0, 0, 1, 0, 1, 2});
    m.submeshes = {{"a", 0, 6, MaterialId::invalid()}, {"b", 6, 6, MaterialId::invalid()}};
    removeDegenerateFaces(m);
    ASSERT_EQ(m.faceCount(), 2u);
    EXPECT_EQ(m.submeshes[0].first_index, 0u);
    EXPECT_EQ(m.submeshes[0].index_count, 6u);
    EXPECT_EQ(m.submeshes[1].first_index, 6u);
    EXPECT_EQ(m.submeshes[1].index_count, 0u);
}

TEST(DegenerateTest, AllFacesDegenerateLeavesNoFaces) {
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2, 0, 0, 0, 1, 1, 2});
    const DegenerateReport r = removeDegenerateFaces(m);
    EXPECT_EQ(m.faceCount(), 0u);
    EXPECT_EQ(r.zero_area_faces + r.repeated_index_faces, 3u);
}

TEST(DegenerateTest, OptionsDisableZeroAreaAndDuplicates) {
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2, 2, 1, 0});
    DegenerateOptions o;
    o.remove_zero_area = false;
    o.remove_duplicates = false;
    removeDegenerateFaces(m, o);
    EXPECT_EQ(m.faceCount(), 2u);
}

TEST(DegenerateTest, UnreferencedVerticesCompactEveryStream) {
    Mesh m = makeMesh({{9, 9, 9}, {0, 0, 0}, {8, 8, 8}, {1, 0, 0}, {0, 1, 0}}, {1, 3, 4});
    m.colors = {{0, 0, 0, 1}, {1, 0, 0, 1}, {0, 0, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}};
    const UnreferencedReport r = removeUnreferencedVertices(m);
    EXPECT_EQ(r.vertices_removed, 2u);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2}));
    ASSERT_EQ(m.colors.size(), 3u);
    EXPECT_EQ(m.colors[1], (Vec4f{0, 1, 0, 1}));
    EXPECT_EQ(m.positions[2], (Vec3f{0, 1, 0}));
}

TEST(DegenerateTest, IsolatedVerticesOnly) {
    Mesh m;
    m.positions = {{0, 0, 0}, {1, 2, 3}};
    EXPECT_EQ(removeDegenerateFaces(m).repeated_index_faces, 0u);
    EXPECT_EQ(removeUnreferencedVertices(m).vertices_removed, 2u);
    EXPECT_EQ(m.vertexCount(), 0u);
}
