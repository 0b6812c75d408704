#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

namespace {
double signedVolume(const Mesh& m) {
    double v = 0;
    for (size_t f = 0; f < m.faceCount(); ++f) {
        const Vec3d a = toDouble(m.positions[m.indices[3 * f]]), b = toDouble(m.positions[m.indices[3 * f + 1]]),
                    c = toDouble(m.positions[m.indices[3 * f + 2]]);
        v += dot(a, cross(b, c)) / 6;
    }
    return v;
}
} // namespace

TEST(OrientTest, FlipsSingleInconsistentFace) {
    Mesh m = uvSphere(6, 8);
    std::swap(m.indices[4], m.indices[5]);
    const OrientReport r = orientFaces(m);
    EXPECT_EQ(r.faces_flipped, 1u);
    EXPECT_EQ(r.closed_components_reversed, 0u);
    EXPECT_TRUE(validate(m).isClosedManifold());
    EXPECT_GT(signedVolume(m), 0);
}

TEST(OrientTest, TurnsInsideOutComponentOutward) {
    Mesh m = tetrahedron();
    Mesh flipped = uvSphere(6, 8);
    for (size_t f = 0; f < flipped.faceCount(); ++f) std::swap(flipped.indices[3 * f + 1], flipped.indices[3 * f + 2]);
    for (auto& p : flipped.positions) p.x += 5;
    appendMesh(m, flipped);
    const OrientReport r = orientFaces(m);
    EXPECT_EQ(r.components, 2u);
    EXPECT_EQ(r.closed_components_reversed, 1u);
    EXPECT_EQ(r.faces_flipped, flipped.faceCount());
    EXPECT_EQ(validate(m).topology.inconsistent_edge_count, 0u);
    EXPECT_GT(signedVolume(m), 0);
}

TEST(OrientTest, OpenComponentKeepsMajorityOrientation) {
    Mesh m = strip(6);
    std::swap(m.indices[1], m.indices[2]); // flip face 0 only
    const OrientReport r = orientFaces(m);
    EXPECT_EQ(r.faces_flipped, 1u);
    EXPECT_EQ(m.indices, strip(6).indices);
}

TEST(OrientTest, CutsMoebiusStrip) {
    Mesh m = moebius(12);
    const ValidationReport before = validate(m);
    EXPECT_GT(before.topology.inconsistent_edge_count, 0u);
    const OrientReport r = orientFaces(m);
    EXPECT_EQ(r.non_orientable_components, 1u);
    EXPECT_GE(r.edges_cut, 1u);
    EXPECT_EQ(r.vertices_added, 2u * r.edges_cut);
    const ValidationReport after = validate(m);
    EXPECT_TRUE(after.isManifold());
    EXPECT_EQ(after.topology.inconsistent_edge_count, 0u);
}

TEST(OrientTest, MoebiusLeftInconsistentWhenCuttingDisabled) {
    Mesh m = moebius(12);
    OrientOptions o;
    o.cut_non_orientable = false;
    const OrientReport r = orientFaces(m, o);
    EXPECT_EQ(r.non_orientable_components, 1u);
    EXPECT_EQ(r.edges_cut, 0u);
    EXPECT_GT(validate(m).topology.inconsistent_edge_count, 0u);
}

TEST(OrientTest, DegenerateInputs) {
    Mesh empty;
    EXPECT_EQ(orientFaces(empty).components, 0u);
    Mesh tri = singleTriangle();
    EXPECT_EQ(orientFaces(tri).faces_flipped, 0u);
    Mesh deg = makeMesh({{0, 0, 0}, {1, 0, 0}}, {0, 0, 1});
    EXPECT_EQ(orientFaces(deg).components, 0u);
}
