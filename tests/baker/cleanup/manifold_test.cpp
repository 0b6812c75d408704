#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(ManifoldTest, SplitsBowTieVertex) {
    Mesh m = bowTie();
    const ManifoldReport r = makeManifold(m);
    EXPECT_EQ(r.vertices_split, 1u);
    EXPECT_EQ(r.vertices_added, 1u);
    EXPECT_EQ(m.vertexCount(), 6u);
    EXPECT_EQ(m.positions[5], m.positions[0]); // the copy sits where the original was
    const ValidationReport v = validate(m);
    EXPECT_TRUE(v.isManifold());
    EXPECT_EQ(v.component_face_counts.size(), 2u);
}

TEST(ManifoldTest, SplitsFanAroundNonManifoldVertex) {
    Mesh m = twoConesAtVertex();
    m.normals.assign(m.vertexCount(), {0, 0, 1});
    const ManifoldReport r = makeManifold(m);
    EXPECT_EQ(r.vertices_split, 1u);
    EXPECT_EQ(m.normals.size(), m.vertexCount()); // streams stay in step
    const ValidationReport v = validate(m);
    EXPECT_TRUE(v.isManifold());
    EXPECT_EQ(v.topology.boundary_edge_count, 0u);
    EXPECT_EQ(v.component_face_counts, (std::vector<uint32_t>{4, 4}));
}

TEST(ManifoldTest, CutsFinEdgeKeepingBestPair) {
    Mesh m = finEdge(); // faces 0 (z=0, +y side), 1 (z=0, -y side), 2 (x=0 plane, vertical)
    const ManifoldReport r = makeManifold(m);
    EXPECT_EQ(r.non_manifold_edges, 1u);
    EXPECT_EQ(r.faces_cut, 1u);
    EXPECT_EQ(m.faceCount(), 3u);
    const ValidationReport v = validate(m);
    EXPECT_TRUE(v.isManifold());
    // The two coplanar, consistently oriented faces stay joined; the vertical fin is cut loose.
    EXPECT_EQ(std::vector<uint32_t>(m.indices.begin() + 6, m.indices.end()), (std::vector<uint32_t>{5, 6, 4}));
    EXPECT_EQ(v.component_face_counts, (std::vector<uint32_t>{2, 1}));
}

TEST(ManifoldTest, RemoveModeDeletesExtraFaces) {
    Mesh m = finEdge();
    ManifoldOptions o;
    o.edge_mode = NonManifoldEdgeMode::Remove;
    const ManifoldReport r = makeManifold(m, o);
    EXPECT_EQ(r.faces_removed, 1u);
    EXPECT_EQ(m.faceCount(), 2u);
    EXPECT_TRUE(validate(m).isManifold());
}

TEST(ManifoldTest, FourFacesOnOneEdgePairUp) {
    // Two sheets crossing along edge (0,1): each sheet is a consistent pair.
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0.5f, 1, 0}, {0.5f, -1, 0}, {0.5f, 0, 1}, {0.5f, 0, -1}},
                      {0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 0, 5});
    const ManifoldReport r = makeManifold(m);
    EXPECT_EQ(r.faces_cut, 0u);
    const ValidationReport v = validate(m);
    EXPECT_TRUE(v.isManifold());
    EXPECT_EQ(v.component_face_counts.size(), 2u);
}

TEST(ManifoldTest, ManifoldInputUnchanged) {
    Mesh m = uvSphere(6, 8);
    const Mesh before = m;
    const ManifoldReport r = makeManifold(m);
    EXPECT_EQ(r.vertices_added + r.faces_cut + r.non_manifold_edges, 0u);
    EXPECT_EQ(m.indices, before.indices);
}

TEST(ManifoldTest, DegenerateInputsDoNotCrash) {
    Mesh all_degenerate = makeMesh({{0, 0, 0}, {1, 0, 0}}, {0, 0, 1, 1, 1, 0});
    EXPECT_EQ(makeManifold(all_degenerate).repeated_index_faces_removed, 2u);
    EXPECT_EQ(all_degenerate.faceCount(), 0u);
    Mesh empty;
    makeManifold(empty);
    Mesh tri = singleTriangle();
    makeManifold(tri);
    EXPECT_EQ(tri.faceCount(), 1u);
}
