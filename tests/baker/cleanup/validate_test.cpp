#include "lodbake/cleanup/validate.h"

#include <gtest/gtest.h>

#include "cleanup_builders.h"

using namespace lodbake;
using namespace lodbake_test;

TEST(ValidateTest, ClosedTetrahedronIsClosedManifold) {
    const ValidationReport r = validate(tetrahedron());
    EXPECT_TRUE(r.isClosedManifold());
    EXPECT_TRUE(r.boundary_loop_lengths.empty());
    ASSERT_EQ(r.component_face_counts.size(), 1u);
    EXPECT_EQ(r.component_face_counts[0], 4u);
}

TEST(ValidateTest, ReportsBoundaryLoopLengthsDescending) {
    Mesh m = strip(5); // one loop of 12 edges
    Mesh t = singleTriangle();
    for (auto& p : t.positions) p.z += 5;
    appendMesh(m, t);
    const ValidationReport r = validate(m);
    ASSERT_EQ(r.boundary_loop_lengths.size(), 2u);
    EXPECT_EQ(r.boundary_loop_lengths[0], 12u);
    EXPECT_EQ(r.boundary_loop_lengths[1], 3u);
    EXPECT_EQ(r.component_face_counts, (std::vector<uint32_t>{10, 1}));
    EXPECT_TRUE(r.isManifold());
    EXPECT_FALSE(r.isClosedManifold());
}

TEST(ValidateTest, FlagsNonManifoldAndInconsistent) {
    EXPECT_FALSE(validate(finEdge()).isManifold());
    EXPECT_FALSE(validate(bowTie()).isManifold());
    Mesh m = tetrahedron();
    std::swap(m.indices[1], m.indices[2]);
    const ValidationReport r = validate(m);
    EXPECT_EQ(r.topology.inconsistent_edge_count, 3u);
    EXPECT_FALSE(r.isManifold());
}

TEST(ValidateTest, CountsNonFiniteAndUnreferenced) {
    Mesh m = tetrahedron();
    m.positions.push_back({std::nanf(""), 0, 0});
    const ValidationReport r = validate(m);
    EXPECT_EQ(r.topology.non_finite_vertex_count, 1u);
    EXPECT_EQ(r.topology.unreferenced_vertex_count, 1u);
    EXPECT_FALSE(r.isClosedManifold());
}

TEST(ValidateTest, WeldByPositionClosesSeams) {
    Mesh m = tetrahedron();
    // Split vertex 0 of the last face that uses it into a copy at the same position (a UV seam).
    m.positions.push_back(m.positions[0]);
    m.indices[6] = 4;
    EXPECT_FALSE(validate(m).isClosedManifold());
    ValidateOptions o;
    o.weld_by_position = true;
    EXPECT_TRUE(validate(m, o).boundary_loop_lengths.empty());
}

TEST(ValidateTest, EmptyAndVertexOnlyMeshes) {
    const ValidationReport e = validate(Mesh());
    EXPECT_EQ(e.topology.face_count, 0u);
    EXPECT_FALSE(e.isClosedManifold());
    Mesh v;
    v.positions = {{0, 0, 0}, {1, 1, 1}};
    EXPECT_EQ(validate(v).topology.unreferenced_vertex_count, 2u);
}
