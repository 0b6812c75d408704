#include "lodbake/cleanup/topology.h"

#include <gtest/gtest.h>

#include "mesh_builders.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(TopologyTest, ClosedTetrahedron) {
    const TopologyStats t = computeTopologyStats(tetrahedron());
    EXPECT_EQ(t.face_count, 4u);
    EXPECT_EQ(t.edge_count, 6u);
    EXPECT_EQ(t.boundary_edge_count, 0u);
    EXPECT_EQ(t.boundary_loop_count, 0u);
    EXPECT_EQ(t.component_count, 1u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_vertex_count, 0u);
    EXPECT_EQ(t.inconsistent_edge_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(TopologyTest, QuadHasOneBoundaryLoop) {
    const TopologyStats t = computeTopologyStats(quad());
    EXPECT_EQ(t.boundary_edge_count, 4u);
    EXPECT_EQ(t.boundary_loop_count, 1u);
    EXPECT_EQ(t.euler_characteristic, 1);
}

TEST(TopologyTest, BowTieVertexIsNonManifold) {
    const TopologyStats t = computeTopologyStats(bowTie());
    EXPECT_EQ(t.non_manifold_vertex_count, 1u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.component_count, 1u);
    EXPECT_EQ(t.boundary_edge_count, 6u);
}

TEST(TopologyTest, FinEdgeIsNonManifold) {
    const TopologyStats t = computeTopologyStats(finEdge());
    EXPECT_EQ(t.non_manifold_edge_count, 1u);
    EXPECT_EQ(t.non_manifold_vertex_count, 2u);
}

TEST(TopologyTest, FlippedFaceGivesInconsistentEdges) {
    Mesh m = quad();
    std::swap(m.indices[4], m.indices[5]); // second triangle now 0,3,2
    const TopologyStats t = computeTopologyStats(m);
    EXPECT_EQ(t.inconsistent_edge_count, 1u);
}

TEST(TopologyTest, CountsDegenerateDuplicateAndUnreferenced) {
    Mesh m = quad();
    m.positions.push_back({5, 5, 5});                  // unreferenced
    m.positions.push_back({0.5f, 0.0f, 0.0f});          // collinear with 0 and 1
    m.indices.insert(m.indices.end(), {2, 0, 1});       // duplicate of face 0, rotated
    m.indices.insert(m.indices.end(), {0, 0, 1});       // repeated index
    m.indices.insert(m.indices.end(), {0, 1, 5});       // zero area
    const TopologyStats t = computeTopologyStats(m);
    EXPECT_EQ(t.duplicate_face_count, 1u);
    EXPECT_EQ(t.degenerate_face_count, 2u);
    EXPECT_EQ(t.unreferenced_vertex_count, 1u);
}

TEST(TopologyTest, WeldByPositionJoinsSeams) {
    // Two triangles of a quad with the diagonal's vertices duplicated, as at a UV seam.
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 1, 2, 3, 4, 5});
    const TopologyStats stored = computeTopologyStats(m);
    EXPECT_EQ(stored.component_count, 2u);
    EXPECT_EQ(stored.boundary_edge_count, 6u);
    TopologyOptions weld;
    weld.weld_by_position = true;
    const TopologyStats welded = computeTopologyStats(m, weld);
    EXPECT_EQ(welded.vertex_count, 4u);
    EXPECT_EQ(welded.component_count, 1u);
    EXPECT_EQ(welded.boundary_edge_count, 4u);
    EXPECT_EQ(welded.boundary_loop_count, 1u);
}

TEST(TopologyTest, NonFiniteVerticesCounted) {
    Mesh m = singleTriangle();
    m.positions[1].y = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(computeTopologyStats(m).non_finite_vertex_count, 1u);
}

TEST(TopologyTest, EmptyMesh) {
    const TopologyStats t = computeTopologyStats(Mesh());
    EXPECT_EQ(t.face_count, 0u);
    EXPECT_EQ(t.component_count, 0u);
}
