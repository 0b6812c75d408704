#include <chrono>

#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

namespace {
Mesh tetrahedronMissingFace() {
    Mesh m = tetrahedron();
    m.indices.resize(9);
    return m;
}
double maxEdgeLength(const Mesh& m, size_t first_face) {
    double mx = 0;
    for (size_t f = first_face; f < m.faceCount(); ++f)
        for (int k = 0; k < 3; ++k)
            mx = std::max(
                mx, double(length(m.positions[m.indices[3 * f + k]] - m.positions[m.indices[3 * f + (k + 1) % 3]])));
    return mx;
}
} // namespace

TEST(HoleFillTest, ClosesThreeEdgeHole) {
    Mesh m = tetrahedronMissingFace();
    const HoleFillReport r = fillHoles(m);
    EXPECT_EQ(r.holes_found, 1u);
    EXPECT_EQ(r.holes_filled, 1u);
    EXPECT_EQ(r.faces_added, 1u);
    EXPECT_EQ(r.vertices_added, 0u);
    EXPECT_TRUE(validate(m).isClosedManifold()); // oriented like its neighbours
}

TEST(HoleFillTest, ClosesHemisphereWithDpAndRefines) {
    Mesh m = hemisphere(6, 40); // equator hole of 40 edges
    const size_t faces = m.faceCount();
    const HoleFillReport r = fillHoles(m);
    EXPECT_EQ(r.filled_lengths, (std::vector<uint32_t>{40}));
    EXPECT_GT(r.vertices_added, 0u); // refined to the boundary density
    EXPECT_TRUE(validate(m).isClosedManifold());
    // Boundary edges are ~0.157 long; refined patch edges stay within a few of them.
    EXPECT_LT(maxEdgeLength(m, faces), 0.6);
}

TEST(HoleFillTest, BareTriangulationAddsNoVertices) {
    Mesh m = hemisphere(6, 40);
    HoleFillOptions o;
    o.refine = o.fair = false;
    const HoleFillReport r = fillHoles(m, o);
    EXPECT_EQ(r.vertices_added, 0u);
    EXPECT_EQ(r.faces_added, 38u); // n - 2
    EXPECT_TRUE(validate(m).isClosedManifold());
}

TEST(HoleFillTest, ThousandEdgeHoleIsFast) {
    Mesh m = hemisphere(4, 1000);
    HoleFillOptions o;
    o.max_hole_edges = 1000;
    const auto t0 = std::chrono::steady_clock::now();
    const HoleFillReport r = fillHoles(m, o);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.filled_lengths, (std::vector<uint32_t>{1000}));
    EXPECT_TRUE(validate(m).isClosedManifold());
    RecordProperty("fill_seconds", std::to_string(seconds));
    EXPECT_LT(seconds, 60.0); // catches an O(n^3) fallback or a flip loop; ~1 s on an idle machine (repair_bench)
}

TEST(HoleFillTest, ThousandEdgeHoleBareEarClipping) {
    Mesh m = hemisphere(4, 1000);
    HoleFillOptions o;
    o.max_hole_edges = 1000;
    o.refine = o.fair = false;
    const HoleFillReport r = fillHoles(m, o);
    EXPECT_EQ(r.faces_added, 998u);
    EXPECT_TRUE(validate(m).isClosedManifold());
}

TEST(HoleFillTest, LeavesLargeHolesOpenAndReportsThem) {
    Mesh m = hemisphere(4, 64);
    HoleFillOptions o;
    o.max_hole_edges = 63;
    const HoleFillReport r = fillHoles(m, o);
    EXPECT_EQ(r.holes_filled, 0u);
    EXPECT_EQ(r.skipped_lengths, (std::vector<uint32_t>{64}));
    EXPECT_EQ(validate(m).boundary_loop_lengths, (std::vector<uint32_t>{64}));
}

TEST(HoleFillTest, NewFacesJoinTheAdjacentSubMesh) {
    Mesh m = tetrahedronMissingFace();
    m.submeshes = {{"a", 0, 3, MaterialId::invalid()}, {"b", 3, 6, MaterialId::invalid()}};
    fillHoles(m);
    ASSERT_EQ(m.faceCount(), 4u);
    EXPECT_EQ(m.submeshes[0].index_count + m.submeshes[1].index_count, 12u);
    EXPECT_EQ(m.submeshes[1].first_index, m.submeshes[0].index_count);
}

TEST(HoleFillTest, AllBoundaryStripAndSingleTriangle) {
    Mesh s = strip(30); // one loop of 62 edges: gets capped into a closed flat pillow
    const HoleFillReport r = fillHoles(s);
    EXPECT_EQ(r.holes_filled, 1u);
    EXPECT_TRUE(validate(s).isManifold());
    Mesh t = singleTriangle(); // its own boundary: the fill would duplicate the face
    const HoleFillReport rt = fillHoles(t);
    EXPECT_EQ(rt.holes_found, 1u);
    EXPECT_TRUE(validate(t).isManifold());
    EXPECT_EQ(validate(t).topology.duplicate_face_count, 0u);
    Mesh empty;
    EXPECT_EQ(fillHoles(empty).holes_found, 0u);
}

TEST(HoleFillTest, UvSeamsAreNotHoles) {
    // Two UV islands of one closed sphere: the upper half's vertices on the equator are duplicated.
    Mesh m = uvSphere(6, 12);
    m.uvs.push_back(std::vector<Vec2f>(m.vertexCount(), Vec2f(0, 0)));
    const size_t n = m.vertexCount();
    std::vector<uint32_t> copy(n, UINT32_MAX);
    for (size_t f = 0; f < m.faceCount(); ++f) {
        bool upper = true;
        for (int k = 0; k < 3; ++k) upper &= m.positions[m.indices[3 * f + k]].z >= -1e-6f;
        if (!upper) continue;
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = m.indices[3 * f + k];
            if (std::fabs(m.positions[v].z) > 1e-6f) continue;
            if (copy[v] == UINT32_MAX) {
                copy[v] = uint32_t(m.positions.size());
                m.positions.push_back(m.positions[v]);
                m.uvs[0].push_back(Vec2f(1, 1));
            }
            v = copy[v];
        }
    }
    ASSERT_EQ(validate(m).boundary_loop_lengths.size(), 2u);
    const size_t faces = m.faceCount();
    const HoleFillReport r = fillHoles(m);
    EXPECT_EQ(r.seam_loops, 2u);
    EXPECT_EQ(r.holes_found, 0u);
    EXPECT_EQ(m.faceCount(), faces);
    ComponentOptions o;
    o.min_area_fraction = 0.6; // each island is half the area: neither may go, they are one surface
    EXPECT_EQ(removeSmallComponents(m, o).components_removed, 0u);
}

TEST(HoleFillTest, NewVerticesInterpolateAttributes) {
    Mesh m = hemisphere(6, 40);
    m.uvs.push_back({});
    m.colors.clear();
    for (const Vec3f& p : m.positions) {
        m.uvs[0].push_back({p.x * 0.5f + 0.5f, p.y * 0.5f + 0.5f});
        m.colors.push_back({0.25f, 0.5f, 0.75f, 1.0f});
    }
    const size_t before = m.vertexCount();
    const HoleFillReport r = fillHoles(m);
    ASSERT_GT(r.vertices_added, 0u);
    ASSERT_EQ(m.uvs[0].size(), m.vertexCount());
    for (size_t v = before; v < m.vertexCount(); ++v) {
        // Inside the unit disk of the rim's UVs, and the constant colour is kept.
        const Vec2f uv = m.uvs[0][v];
        EXPECT_LT(std::hypot(uv.x - 0.5f, uv.y - 0.5f), 0.5f);
        EXPECT_NEAR(m.colors[v].y, 0.5f, 1e-6f);
    }
}
