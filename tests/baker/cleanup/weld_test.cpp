#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

namespace {
// A triangle soup: every face has its own three vertices.
Mesh soup(const Mesh& m) {
    Mesh s;
    for (uint32_t i : m.indices) {
        s.indices.push_back(uint32_t(s.positions.size()));
        s.positions.push_back(m.positions[i]);
    }
    return s;
}
} // namespace

TEST(WeldTest, ExactWeldRestoresSoup) {
    Mesh m = soup(uvSphere(8, 12));
    const size_t faces = m.faceCount();
    const WeldReport r = weldVertices(m);
    EXPECT_EQ(r.vertices_before, faces * 3);
    EXPECT_EQ(r.vertices_after, uvSphere(8, 12).vertexCount());
    EXPECT_EQ(r.vertices_merged, r.vertices_before - r.vertices_after);
    EXPECT_TRUE(validate(m).isClosedManifold());
}

TEST(WeldTest, ToleranceMergesJitteredCopiesOnly) {
    Mesh m = soup(uvSphere(8, 12));
    for (size_t v = 0; v < m.vertexCount(); ++v) m.positions[v].x += 1e-7f * hashNoise(uint32_t(v));
    Mesh exact = m;
    EXPECT_LT(weldVertices(exact).vertices_merged, m.vertexCount() - 86);
    WeldOptions o;
    o.tolerance_rel = 1e-5;
    const WeldReport r = weldVertices(m, o);
    EXPECT_EQ(r.vertices_after, 86u); // (8-1)*12 + 2 poles
    EXPECT_TRUE(validate(m).isClosedManifold());
}

TEST(WeldTest, ToleranceDoesNotMergeDistinctNeighbours) {
    Mesh m = uvSphere(8, 12);
    WeldOptions o;
    o.tolerance_rel = 1e-4;
    EXPECT_EQ(weldVertices(m, o).vertices_merged, 0u);
}

TEST(WeldTest, RespectsUvSeamsUnlessAsked) {
    Mesh m = quad();
    // Duplicate vertex 2 with a different UV and use it in the second face.
    m.uvs.push_back({{0, 0}, {1, 0}, {1, 1}, {0, 1}});
    m.positions.push_back(m.positions[2]);
    m.uvs[0].push_back({0.5f, 0.5f});
    m.indices[4] = 4;
    Mesh kept = m;
    const WeldReport r = weldVertices(kept);
    EXPECT_EQ(r.vertices_merged, 0u);
    EXPECT_EQ(r.seam_pairs_kept, 1u);
    WeldOptions o;
    o.respect_attributes = false;
    const WeldReport all = weldVertices(m, o);
    EXPECT_EQ(all.vertices_merged, 1u);
    ASSERT_EQ(m.uvs[0].size(), 4u);        // stream compacted with the positions
    EXPECT_EQ(m.uvs[0][2], (Vec2f{1, 1})); // the representative keeps its own UV
    EXPECT_EQ(m.indices[4], 2u);
}

TEST(WeldTest, RespectsNormalSeams) {
    Mesh m = quad();
    m.normals.assign(4, {0, 0, 1});
    m.positions.push_back(m.positions[0]);
    m.normals.push_back({1, 0, 0});
    m.indices[3] = 4;
    WeldOptions o;
    o.tolerance_rel = 1e-3;
    EXPECT_EQ(weldVertices(m, o).vertices_merged, 0u);
}

TEST(WeldTest, IsDeterministicAndKeepsLowestIndex) {
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 0}}, {0, 1, 2, 4, 2, 3});
    Mesh copy = m;
    weldVertices(m);
    weldVertices(copy);
    EXPECT_EQ(m.indices, copy.indices);
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 1}));
}

TEST(WeldTest, NonFiniteNeverMerges) {
    Mesh m = makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {std::nanf(""), 0, 0}, {std::nanf(""), 0, 0}}, {0, 1, 2});
    EXPECT_EQ(weldVertices(m).vertices_merged, 0u);
    WeldOptions o;
    o.tolerance_rel = 0.1;
    EXPECT_EQ(weldVertices(m, o).vertices_merged, 0u);
}

TEST(WeldTest, EmptyMesh) {
    Mesh m;
    EXPECT_EQ(weldVertices(m).vertices_after, 0u);
}

TEST(WeldTest, ToleranceMatchesQuadraticScan) {
    // Clusters of near-copies on a coarse grid, more than one scan chunk (4096 vertices) so the
    // pre-pass's cursors cross chunk boundaries and x slabs: every vertex must join the lowest
    // earlier representative within the tolerance, exactly as an all-pairs scan finds it.
    // Seeds 4 and 5 add an unreferenced stray far outside the box (the last vertex): its cell does
    // not fit 32 bits, so the cells are kept as 64-bit coordinates.
    for (uint32_t seed : {1u, 2u, 3u, 4u, 5u}) {
        Mesh m;
        const uint32_t n = 9000;
        for (uint32_t v = 0; v < n; ++v) {
            const uint32_t h = v * 2654435761u + seed * 40503u;
            const float x = float(h % 23) / 23.0f, y = float((h / 23) % 19) / 19.0f, z = float((h / 437) % 17) / 17.0f;
            m.positions.push_back({x + 2e-3f * hashNoise(3 * v + seed), y + 2e-3f * hashNoise(3 * v + 1 + seed),
                                   z + 2e-3f * hashNoise(3 * v + 2 + seed)});
            m.indices.push_back(v); // every vertex referenced
        }
        if (seed >= 4) m.positions.push_back({seed == 4 ? 1e12f : -1e12f, 0.5f, 0.5f});
        WeldOptions o;
        o.tolerance_rel = 1.5e-3;
        const double tol = o.tolerance_rel * computeBounds(m).diagonal();
        std::vector<uint32_t> target(n);
        std::vector<uint8_t> is_rep(n, 0);
        for (uint32_t v = 0; v < n; ++v) {
            target[v] = v;
            for (uint32_t u = 0; u < v; ++u) {
                if (!is_rep[u]) continue;
                const Vec3d d = toDouble(m.positions[u]) - toDouble(m.positions[v]);
                if (dot(d, d) <= tol * tol) {
                    target[v] = u;
                    break;
                }
            }
            is_rep[v] = target[v] == v;
        }
        std::vector<uint32_t> new_id(n), expected;
        uint32_t next = 0, merged = 0;
        for (uint32_t v = 0; v < n; ++v)
            if (is_rep[v]) new_id[v] = next++;
        for (uint32_t v = 0; v < n; ++v) {
            merged += !is_rep[v];
            expected.push_back(new_id[target[v]]);
        }
        ASSERT_GT(merged, 100u) << seed; // the case is not trivial
        ASSERT_LT(merged, n / 2) << seed;
        const WeldReport r = weldVertices(m, o);
        EXPECT_EQ(r.vertices_merged, merged) << seed;
        EXPECT_EQ(m.indices, expected) << seed;
    }
}
