#include "lodbake/core/mesh.h"

#include <gtest/gtest.h>

#include "mesh_builders.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(MeshTest, BoundsIgnoreUnreferencedVertices) {
    Mesh m = singleTriangle();
    m.positions.push_back({100, 100, 100});
    const Aabb box = computeBounds(m);
    EXPECT_EQ(box.max.x, 1.0f);
    EXPECT_EQ(box.max.z, 0.0f);
    EXPECT_NEAR(box.diagonal(), std::sqrt(2.0), 1e-12);
}

TEST(MeshTest, EmptyBoundsHaveZeroDiagonal) {
    EXPECT_TRUE(computeBounds(Mesh()).isEmpty());
    EXPECT_EQ(computeBounds(Mesh()).diagonal(), 0.0);
}

TEST(MeshTest, ConsistencyCatchesOutOfRangeIndex) {
    Mesh m = singleTriangle();
    EXPECT_TRUE(checkMeshConsistency(m, "t").ok());
    m.indices[2] = 3;
    const Status s = checkMeshConsistency(m, "t");
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("out of range"), std::string::npos);
}

TEST(MeshTest, ConsistencyCatchesStreamSizeMismatch) {
    Mesh m = singleTriangle();
    m.normals.resize(2);
    EXPECT_FALSE(checkMeshConsistency(m, "t").ok());
}

TEST(MeshTest, ConsistencyCatchesBadSubMeshes) {
    Mesh m = quad();
    m.submeshes.push_back({"a", 0, 3, {}});
    EXPECT_FALSE(checkMeshConsistency(m, "t").ok()); // covers only the first triangle
    m.submeshes.push_back({"b", 3, 3, MaterialId(0)});
    EXPECT_FALSE(checkMeshConsistency(m, "t").ok()); // material 0 does not exist
    m.materials.push_back(Material());
    EXPECT_TRUE(checkMeshConsistency(m, "t").ok());
}

TEST(MeshTest, AppendOffsetsIndicesMaterialsAndFillsStreams) {
    Mesh a = singleTriangle();
    Mesh b = singleTriangle();
    b.normals.assign(3, Vec3f(0, 0, 1));
    b.materials.push_back(Material());
    b.textures.push_back(Texture());
    b.materials[0].base_color_texture.texture = 0;
    b.uvs.push_back(std::vector<Vec2f>(3, Vec2f(0.5f, 0.5f)));
    b.submeshes.push_back({"b", 0, 3, MaterialId(0)});
    Mesh c = a;
    c.materials.push_back(Material());
    c.textures.push_back(Texture());
    c.materials[0].base_color_texture.texture = 0;
    c.submeshes.push_back({"a", 0, 3, MaterialId(0)});
    c.uvs.push_back(std::vector<Vec2f>(3, Vec2f(0.0f, 0.0f)));
    appendMesh(c, b);
    ASSERT_TRUE(checkMeshConsistency(c, "c").ok()) << checkMeshConsistency(c, "c").message();
    EXPECT_EQ(c.vertexCount(), 6u);
    EXPECT_EQ(c.indices[3], 3u);
    EXPECT_EQ(c.normals.size(), 6u);
    EXPECT_EQ(c.normals[0], Vec3f(0, 0, 0));
    EXPECT_EQ(c.normals[3], Vec3f(0, 0, 1));
    ASSERT_EQ(c.submeshes.size(), 2u);
    EXPECT_EQ(c.submeshes[1].material, MaterialId(1));
    EXPECT_EQ(c.materials[1].base_color_texture.texture, 1);
    EXPECT_EQ(c.uvs[0][4], Vec2f(0.5f, 0.5f));

    Mesh d = a;
    appendMesh(d, a); // no sub-meshes on either side: the first range becomes explicit
    ASSERT_EQ(d.submeshes.size(), 2u);
    EXPECT_TRUE(checkMeshConsistency(d, "d").ok());
}

TEST(MeshTest, CountsRepeatedIndexFacesAndUnreferencedVertices) {
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {9, 9, 9}}, {0, 1, 2, 0, 0, 1});
    EXPECT_EQ(countRepeatedIndexFaces(m), 1u);
    EXPECT_EQ(countUnreferencedVertices(m), 1u);
}

TEST(IndexTypesTest, CornerArithmetic) {
    EXPECT_EQ(faceOf(CornerId(7)), FaceId(2));
    EXPECT_EQ(nextCorner(CornerId(5)), CornerId(3));
    EXPECT_EQ(prevCorner(CornerId(3)), CornerId(5));
    EXPECT_EQ(cornerOf(FaceId(2), 1), CornerId(7));
    EXPECT_FALSE(VertexId::invalid().isValid());
}
