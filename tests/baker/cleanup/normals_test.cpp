#include <cmath>

#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/normals.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(NormalsTest, SphereNormalsPointOutward) {
    Mesh m = uvSphere(12, 24);
    for (NormalWeighting w : {NormalWeighting::Area, NormalWeighting::Angle, NormalWeighting::AreaAngle}) {
        NormalOptions o;
        o.weighting = w;
        const NormalsReport r = computeNormals(m, o);
        EXPECT_EQ(r.vertices_added, 0u);
        ASSERT_EQ(m.normals.size(), m.vertexCount());
        for (size_t v = 0; v < m.vertexCount(); ++v) EXPECT_GT(dot(m.normals[v], normalize(m.positions[v])), 0.98f);
    }
}

TEST(NormalsTest, AngleWeightingIgnoresTessellation) {
    // Corner (0,0,0) of a cube-like corner: one face split into many thin triangles must not dominate.
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0.1f, 0}, {1, 0.2f, 0}},
                      {0, 1, 4, 0, 4, 5, 0, 5, 2, 0, 2, 3, 0, 3, 1});
    NormalOptions o;
    o.weighting = NormalWeighting::Angle;
    computeNormals(m, o);
    const Vec3f n = m.normals[0];
    EXPECT_NEAR(n.x, n.y, 1e-5f);
    EXPECT_NEAR(n.y, n.z, 1e-5f);
    o.weighting = NormalWeighting::Area; // area: the three 90-degree sectors have different areas here
    computeNormals(m, o);
    EXPECT_GT(std::fabs(m.normals[0].z - m.normals[0].x), 1e-3f);
}

TEST(NormalsTest, CreaseAngleSplitsCubeCorners) {
    Mesh m = makeMesh(
        {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
        {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7});
    Mesh smooth = m;
    EXPECT_EQ(computeNormals(smooth).vertices_added, 0u); // default 180: never split
    NormalOptions o;
    o.crease_angle_deg = 60;
    const NormalsReport r = computeNormals(m, o);
    EXPECT_EQ(r.crease_edges, 12u);
    EXPECT_EQ(r.vertices_split, 8u);
    EXPECT_EQ(m.vertexCount(), 24u);
    for (size_t f = 0; f < m.faceCount(); ++f) {
        const Vec3f a = m.positions[m.indices[3 * f]];
        const Vec3f fn = normalize(cross(m.positions[m.indices[3 * f + 1]] - a, m.positions[m.indices[3 * f + 2]] - a));
        for (int k = 0; k < 3; ++k) EXPECT_GT(dot(m.normals[m.indices[3 * f + k]], fn), 0.9999f);
    }
    ValidateOptions weld;
    weld.weld_by_position = true;
    EXPECT_TRUE(validate(m, weld).boundary_loop_lengths.empty()); // split only in attributes
}

TEST(NormalsTest, UvSeamVerticesShareTheNormal) {
    Mesh m = uvSphere(8, 16);
    // Split vertex 20 into a seam copy for one of its faces.
    m.positions.push_back(m.positions[20]);
    for (size_t c = 0; c < m.indices.size(); ++c)
        if (m.indices[c] == 20) {
            m.indices[c] = uint32_t(m.positions.size() - 1);
            break;
        }
    computeNormals(m);
    EXPECT_EQ(m.normals[20], m.normals.back());
}

TEST(NormalsTest, DegenerateInputs) {
    Mesh empty;
    EXPECT_EQ(computeNormals(empty).vertices_added, 0u);
    Mesh deg = makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2});
    computeNormals(deg);
    EXPECT_EQ(deg.normals[0], (Vec3f{0, 0, 1}));
    Mesh isolated;
    isolated.positions = {{1, 2, 3}};
    computeNormals(isolated);
    EXPECT_EQ(isolated.normals.size(), 1u);
}
