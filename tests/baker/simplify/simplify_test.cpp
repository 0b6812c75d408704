#include "lodbake/simplify/simplify.h"

#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>

#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include "lodbake/cleanup/topology.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/mesh_distance.h"
#include "mesh_builders.h"
#include "simplify_test_meshes.h"
#include "test_paths.h"

namespace {

using lodbake::Diagnostics;
using lodbake::Mesh;
using lodbake::SimplifyOptions;
using lodbake::SimplifyOutput;
using lodbake::Vec2f;
using lodbake::Vec3f;

SimplifyOutput run(const Mesh& mesh, const SimplifyOptions& options, Diagnostics* diagnostics = nullptr) {
    Diagnostics local;
    auto result = lodbake::simplify(mesh, options, diagnostics ? *diagnostics : local);
    EXPECT_TRUE(result.ok()) << result.status().message();
    return result.ok() ? std::move(result).value() : SimplifyOutput();
}

SimplifyOptions ratio(float r) {
    SimplifyOptions o;
    o.target_ratio = r;
    return o;
}

Vec3f faceNormal(const Mesh& m, size_t f) {
    const Vec3f a = m.positions[m.indices[f * 3]], b = m.positions[m.indices[f * 3 + 1]],
                c = m.positions[m.indices[f * 3 + 2]];
    return lodbake::cross(b - a, c - a);
}

TEST(SimplifyTest, ReachesRatioOnSubdividedSphereKeepingItClosed) {
    const Mesh sphere = lodbake_test::icosphere(4); // 5120 faces
    const SimplifyOutput out = run(sphere, ratio(0.25f));
    EXPECT_TRUE(out.reached_target);
    EXPECT_LE(out.mesh.faceCount(), 1280u);
    EXPECT_GE(out.mesh.faceCount(), 1278u);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_vertex_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2);
    EXPECT_EQ(t.component_count, 1u);
    // No face flipped inside out, and all vertices still close to the sphere.
    for (size_t f = 0; f < out.mesh.faceCount(); ++f) {
        const Vec3f c = out.mesh.positions[out.mesh.indices[f * 3]];
        EXPECT_GT(lodbake::dot(faceNormal(out.mesh, f), c), 0.0f) << "face " << f;
    }
    for (const Vec3f& p : out.mesh.positions) EXPECT_NEAR(lodbake::length(p), 1.0f, 0.02f);
}

TEST(SimplifyTest, ReachesAbsoluteTriangleCount) {
    SimplifyOptions o;
    o.target_triangles = 100;
    const SimplifyOutput out = run(lodbake_test::icosphere(3), o);
    EXPECT_TRUE(out.reached_target);
    EXPECT_LE(out.mesh.faceCount(), 100u);
    EXPECT_GE(out.mesh.faceCount(), 98u);
}

TEST(SimplifyTest, StopsAtErrorLimit) {
    // Checked with the surface distance, not with the simplifier's own estimates. The limit bounds
    // each collapse's quadric RMS distance, so the measured RMS distance stays below it; the largest
    // distance over a fan is a few times its RMS, so Hausdorff gets four times the limit.
    const Mesh sphere = lodbake_test::icosphere(5); // 20480 faces
    SimplifyOptions o;
    o.target_ratio = 0.0f;
    double previous_rms = std::numeric_limits<double>::infinity();
    size_t previous_faces = 0;
    for (double limit : {3e-3, 3e-4}) {
        SCOPED_TRACE(limit);
        o.max_error = limit;
        const SimplifyOutput out = run(sphere, o);
        EXPECT_LT(out.mesh.faceCount(), sphere.faceCount());
        const auto d = lodbake::measureSurfaceDistance(sphere, out.mesh);
        ASSERT_TRUE(d.ok()) << d.status().message();
        EXPECT_LE(d->rms, limit);
        EXPECT_LE(d->hausdorff, 4 * limit);
        // A tighter limit keeps more faces and measures closer.
        EXPECT_GT(out.mesh.faceCount(), previous_faces);
        EXPECT_LT(d->rms, previous_rms);
        previous_faces = out.mesh.faceCount();
        previous_rms = d->rms;
    }
    // Without a limit the same run goes much further and measures far above the loosest limit.
    o.max_error = std::numeric_limits<double>::infinity();
    const SimplifyOutput unlimited = run(sphere, o);
    const auto d = lodbake::measureSurfaceDistance(sphere, unlimited.mesh);
    ASSERT_TRUE(d.ok()) << d.status().message();
    EXPECT_GT(d->rms, 3e-2);
    o.max_error = 0.0;
    const SimplifyOutput none = run(sphere, o);
    EXPECT_EQ(none.mesh.faceCount(), sphere.faceCount()); // every collapse on a sphere has some error
}

TEST(SimplifyTest, TetrahedronFailsTheLinkConditionAndStaysIntact) {
    Diagnostics diagnostics;
    SimplifyOptions o;
    o.target_triangles = 1;
    const SimplifyOutput out = run(lodbake_test::tetrahedron(), o, &diagnostics);
    EXPECT_EQ(out.mesh.faceCount(), 4u);
    EXPECT_FALSE(out.reached_target);
    EXPECT_FALSE(diagnostics.empty());
}

TEST(SimplifyTest, PyramidCollapsesToATetrahedronAndNoFurther) {
    // Closed square pyramid: 5 vertices, 6 faces (base split in two).
    const Mesh pyramid = lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}},
                                                {0, 2, 1, 0, 3, 2, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4});
    SimplifyOptions o;
    o.target_triangles = 1;
    o.min_triangle_quality = 0.0f;
    o.max_normal_change_deg = 180.0f;
    const SimplifyOutput out = run(pyramid, o);
    EXPECT_EQ(out.mesh.faceCount(), 4u);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(SimplifyTest, NormalRotationBoundBlocksCollapses) {
    const Mesh sphere = lodbake_test::icosphere(2);
    SimplifyOptions o = ratio(0.5f);
    o.max_normal_change_deg = 0.01f; // every collapse on a sphere tilts some face more than this
    const SimplifyOutput out = run(sphere, o);
    EXPECT_EQ(out.mesh.faceCount(), sphere.faceCount());
    EXPECT_FALSE(out.reached_target);
}

TEST(SimplifyTest, FlatGridKeepsItsBorderAndArea) {
    const Mesh g = lodbake_test::flatGrid(12);
    const SimplifyOutput out = run(g, ratio(0.02f));
    EXPECT_LT(out.mesh.faceCount(), 40u);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_loop_count, 1u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    double area = 0;
    for (size_t f = 0; f < out.mesh.faceCount(); ++f) {
        const Vec3f n = faceNormal(out.mesh, f);
        EXPECT_GT(n.z, 0.0f);
        area += 0.5 * lodbake::length(n);
    }
    EXPECT_NEAR(area, 1.0, 1e-5); // border vertices moved only along the border
    std::set<std::pair<float, float>> corners;
    for (const Vec3f& p : out.mesh.positions) {
        EXPECT_NEAR(p.z, 0.0f, 1e-6f);
        if ((p.x == 0.0f || p.x == 1.0f) && (p.y == 0.0f || p.y == 1.0f)) corners.insert({p.x, p.y});
    }
    EXPECT_EQ(corners.size(), 4u);
}

TEST(SimplifyTest, CurvedGridBorderVerticesStayOnTheBorder) {
    const Mesh g = lodbake_test::grid(16, [](float x, float y) { return 0.3f * std::sin(3 * x) * std::cos(2 * y); });
    const SimplifyOutput out = run(g, ratio(0.1f));
    EXPECT_TRUE(out.reached_target);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_loop_count, 1u);
    // Every output border vertex lies on the square's border (within the quadric's tolerance).
    std::vector<int> border_uses(out.mesh.vertexCount(), 0);
    std::map<std::pair<uint32_t, uint32_t>, int> edge_uses;
    for (size_t f = 0; f < out.mesh.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = out.mesh.indices[f * 3 + k], b = out.mesh.indices[f * 3 + (k + 1) % 3];
            ++edge_uses[{std::min(a, b), std::max(a, b)}];
        }
    int border_vertices = 0;
    for (const auto& e : edge_uses) {
        if (e.second != 1) continue;
        for (uint32_t v : {e.first.first, e.first.second}) {
            const Vec3f p = out.mesh.positions[v];
            const float d = std::min(std::min(p.x, 1.0f - p.x), std::min(p.y, 1.0f - p.y));
            EXPECT_NEAR(d, 0.0f, 2e-3f) << "vertex " << v;
            ++border_vertices;
        }
    }
    EXPECT_GT(border_vertices, 8);
}

TEST(SimplifyTest, LockBorderKeepsBorderVerticesExactly) {
    const Mesh g = lodbake_test::grid(10, [](float x, float y) { return 0.2f * x * y; });
    SimplifyOptions o = ratio(0.2f);
    o.lock_border = true;
    const SimplifyOutput out = run(g, o);
    std::set<std::tuple<float, float, float>> input;
    for (const Vec3f& p : g.positions) input.insert({p.x, p.y, p.z});
    int border = 0;
    for (const Vec3f& p : out.mesh.positions)
        if (p.x == 0.0f || p.x == 1.0f || p.y == 0.0f || p.y == 1.0f) {
            ++border;
            EXPECT_TRUE(input.count({p.x, p.y, p.z}));
        }
    EXPECT_EQ(border, 40); // all 40 border vertices of a 10×10 grid remain
}

// Two UV charts meeting along x = 0.5: seam vertices are duplicated with different UVs.
Mesh seamGrid(int n) {
    Mesh g = lodbake_test::grid(n, [](float x, float y) { return 0.1f * std::sin(4 * x + 3 * y); });
    g.uvs.resize(1);
    g.uvs[0].resize(g.vertexCount());
    for (size_t v = 0; v < g.vertexCount(); ++v) g.uvs[0][v] = Vec2f(g.positions[v].x, g.positions[v].y);
    // Faces right of the seam use copies of their vertices with UVs shifted by +2.
    std::vector<uint32_t> copy(g.vertexCount(), UINT32_MAX);
    for (size_t f = 0; f < g.faceCount(); ++f) {
        float cx = 0;
        for (int k = 0; k < 3; ++k) cx += g.positions[g.indices[f * 3 + k]].x / 3.0f;
        if (cx < 0.5f) continue;
        for (int k = 0; k < 3; ++k) {
            uint32_t& i = g.indices[f * 3 + k];
            if (copy[i] == UINT32_MAX) {
                copy[i] = uint32_t(g.positions.size());
                g.positions.push_back(g.positions[i]);
                g.uvs[0].push_back(Vec2f(g.uvs[0][i].x + 2.0f, g.uvs[0][i].y));
            }
            i = copy[i];
        }
    }
    return g;
}

TEST(SimplifyTest, SeamsAreOnlyCollapsedAlongThemselves) {
    const Mesh g = seamGrid(16);
    const SimplifyOutput out = run(g, ratio(0.15f));
    EXPECT_TRUE(out.reached_target);
    const Mesh& m = out.mesh;
    ASSERT_EQ(m.uvs.size(), 1u);
    std::map<std::tuple<float, float, float>, std::set<int>> charts_at;
    for (size_t f = 0; f < m.faceCount(); ++f) {
        int chart = -1;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[f * 3 + k];
            const int c = m.uvs[0][v].x >= 1.5f ? 1 : 0;
            if (chart < 0) chart = c;
            EXPECT_EQ(c, chart) << "face " << f << " straddles the seam";
            const Vec3f p = m.positions[v];
            charts_at[{p.x, p.y, p.z}].insert(c);
            // UVs stay the interpolated parametrisation (u = x within each chart, v = y).
            EXPECT_NEAR(m.uvs[0][v].x - 2.0f * float(c), p.x, 0.02f);
            EXPECT_NEAR(m.uvs[0][v].y, p.y, 0.02f);
        }
    }
    // Both sides of the seam agree: every position used by both charts lies on x = 0.5.
    int seam_points = 0;
    for (const auto& e : charts_at) {
        if (e.second.size() == 2) {
            ++seam_points;
            EXPECT_NEAR(std::get<0>(e.first), 0.5f, 1e-3f);
        }
    }
    EXPECT_GE(seam_points, 2);
    // Welded by position the surface is still one open sheet with one border.
    lodbake::TopologyOptions weld;
    weld.weld_by_position = true;
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(m, weld);
    EXPECT_EQ(t.boundary_loop_count, 1u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
}

TEST(SimplifyTest, ColoursAreInterpolatedNotSnapped) {
    Mesh sphere = lodbake_test::icosphere(4);
    for (const Vec3f& p : sphere.positions) sphere.colors.push_back({0.5f + 0.5f * p.x, 0.5f, 0.5f - 0.25f * p.z, 1});
    const SimplifyOutput out = run(sphere, ratio(0.1f));
    ASSERT_TRUE(out.mesh.hasColors());
    double worst = 0;
    for (size_t v = 0; v < out.mesh.vertexCount(); ++v) {
        const Vec3f p = out.mesh.positions[v];
        worst = std::max(worst, double(std::fabs(out.mesh.colors[v].x - (0.5f + 0.5f * p.x))));
        worst = std::max(worst, double(std::fabs(out.mesh.colors[v].z - (0.5f - 0.25f * p.z))));
    }
    EXPECT_LT(worst, 0.01);
}

TEST(SimplifyTest, NormalsStayUnitAndClose) {
    Mesh sphere = lodbake_test::icosphere(4);
    sphere.normals = sphere.positions;
    const SimplifyOutput out = run(sphere, ratio(0.1f));
    ASSERT_TRUE(out.mesh.hasNormals());
    for (size_t v = 0; v < out.mesh.vertexCount(); ++v) {
        EXPECT_NEAR(lodbake::length(out.mesh.normals[v]), 1.0f, 1e-5f);
        EXPECT_GT(lodbake::dot(out.mesh.normals[v], lodbake::normalize(out.mesh.positions[v])), 0.99f);
    }
}

TEST(SimplifyTest, SubmeshBordersArePreserved) {
    Mesh g = lodbake_test::grid(16, [](float x, float y) { return 0.1f * x * y; });
    // Left half of the faces (by centroid) in sub-mesh 0, right half in 1: reorder faces.
    std::vector<uint32_t> left, right;
    for (size_t f = 0; f < g.faceCount(); ++f) {
        float cx = 0;
        for (int k = 0; k < 3; ++k) cx += g.positions[g.indices[f * 3 + k]].x / 3.0f;
        auto& dst = cx < 0.5f ? left : right;
        dst.insert(dst.end(), g.indices.begin() + f * 3, g.indices.begin() + f * 3 + 3);
    }
    g.indices = left;
    g.indices.insert(g.indices.end(), right.begin(), right.end());
    g.materials.resize(2);
    g.submeshes = {{"left", 0, uint32_t(left.size()), lodbake::MaterialId(0)},
                   {"right", uint32_t(left.size()), uint32_t(right.size()), lodbake::MaterialId(1)}};
    const SimplifyOutput out = run(g, ratio(0.1f));
    ASSERT_EQ(out.mesh.submeshes.size(), 2u);
    ASSERT_TRUE(lodbake::checkMeshConsistency(out.mesh, "out").ok());
    for (int s = 0; s < 2; ++s) {
        const lodbake::SubMesh& sm = out.mesh.submeshes[s];
        EXPECT_GT(sm.index_count, 0u);
        for (uint32_t i = sm.first_index; i < sm.first_index + sm.index_count; ++i) {
            const float x = out.mesh.positions[out.mesh.indices[i]].x;
            if (s == 0) {
                EXPECT_LE(x, 0.5f + 1e-4f);
            } else {
                EXPECT_GE(x, 0.5f - 1e-4f);
            }
        }
    }
}

TEST(SimplifyTest, NonManifoldInputIsLeftUntouched) {
    // A fin: a third triangle on one edge of a sphere.
    Mesh sphere = lodbake_test::icosphere(3);
    const uint32_t a = sphere.indices[0], b = sphere.indices[1];
    const Vec3f apex = (sphere.positions[a] + sphere.positions[b]) * 0.5f * 1.5f;
    sphere.positions.push_back(apex);
    sphere.indices.insert(sphere.indices.end(), {a, b, uint32_t(sphere.positions.size() - 1)});
    const lodbake::TopologyStats before = lodbake::computeTopologyStats(sphere);
    ASSERT_EQ(before.non_manifold_edge_count, 1u);
    Diagnostics diagnostics;
    const SimplifyOutput out = run(sphere, ratio(0.2f), &diagnostics);
    EXPECT_FALSE(diagnostics.empty());
    const lodbake::TopologyStats after = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(after.non_manifold_edge_count, 1u);
    EXPECT_LE(after.non_manifold_vertex_count, before.non_manifold_vertex_count);
    std::set<std::tuple<float, float, float>> kept;
    for (const Vec3f& p : out.mesh.positions) kept.insert({p.x, p.y, p.z});
    for (uint32_t v : {a, b, uint32_t(sphere.positions.size() - 1)}) {
        const Vec3f p = sphere.positions[v];
        EXPECT_TRUE(kept.count({p.x, p.y, p.z})) << "vertex " << v << " moved";
    }
    // The bow-tie and the bare fin cannot be simplified at all.
    EXPECT_EQ(run(lodbake_test::bowTie(), ratio(0.5f)).mesh.faceCount(), 2u);
    EXPECT_EQ(run(lodbake_test::finEdge(), ratio(0.3f)).mesh.faceCount(), 3u);
}

TEST(SimplifyTest, OutputIsDeterministic) {
    Mesh sphere = lodbake_test::icosphere(4);
    for (const Vec3f& p : sphere.positions) sphere.colors.push_back({p.x * 0.5f + 0.5f, 0.2f, 0.3f, 1});
    const SimplifyOutput a = run(sphere, ratio(0.2f));
    const SimplifyOutput b = run(sphere, ratio(0.2f));
    ASSERT_EQ(a.mesh.indices, b.mesh.indices);
    ASSERT_EQ(a.mesh.positions.size(), b.mesh.positions.size());
    EXPECT_EQ(0,
              std::memcmp(a.mesh.positions.data(), b.mesh.positions.data(), a.mesh.positions.size() * sizeof(Vec3f)));
    EXPECT_EQ(0,
              std::memcmp(a.mesh.colors.data(), b.mesh.colors.data(), a.mesh.colors.size() * sizeof(lodbake::Vec4f)));
}

TEST(SimplifyTest, DuplicateVerticesAndDegenerateFacesAreHandled) {
    // The same quad twice over: vertices 4..7 repeat 0..3 exactly and a zero-area face is added.
    Mesh q =
        lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                               {0, 1, 2, 4, 6, 7, 0, 4, 1});
    Diagnostics diagnostics;
    const SimplifyOutput out = run(q, ratio(1.0f), &diagnostics);
    EXPECT_EQ(out.mesh.faceCount(), 2u);
    EXPECT_EQ(out.mesh.vertexCount(), 4u); // welded
    EXPECT_FALSE(diagnostics.empty());
}

TEST(SimplifyTest, RejectsNonFiniteInputAndBadOptions) {
    Mesh m = lodbake_test::quad();
    m.positions[2].y = std::numeric_limits<float>::quiet_NaN();
    Diagnostics d;
    auto r = lodbake::simplify(m, SimplifyOptions(), d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("vertex 2"), std::string::npos);
    SimplifyOptions bad;
    bad.target_ratio = 1.5f;
    EXPECT_FALSE(lodbake::simplify(lodbake_test::quad(), bad, d).ok());
}

TEST(SimplifyTest, BunnyScanKeepsHolesAndBeatsReferenceError) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), lodbake::ReadOptions(), diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const Mesh& bunny = loaded->mesh;
    // The reference: meshoptimizer (the system library, meshopt_simplify without an error limit or
    // options) at 10 % of the faces; ours gets at most as many faces as it kept.
    std::vector<uint32_t> reference_indices(bunny.indices.size());
    const size_t reference_index_count = meshopt_simplify(
        reference_indices.data(), bunny.indices.data(), bunny.indices.size(), &bunny.positions[0].x,
        bunny.positions.size(), sizeof(Vec3f), bunny.faceCount() / 10 * 3, FLT_MAX, 0, nullptr);
    Mesh reference;
    reference.positions = bunny.positions;
    reference.indices.assign(reference_indices.begin(), reference_indices.begin() + reference_index_count);
    ASSERT_GT(reference.faceCount(), bunny.faceCount() / 12);
    SimplifyOptions o;
    o.target_triangles = uint32_t(reference.faceCount());
    const SimplifyOutput out = run(bunny, o);
    EXPECT_TRUE(out.reached_target);
    EXPECT_LE(out.mesh.faceCount(), reference.faceCount());
    const lodbake::TopologyStats before = lodbake::computeTopologyStats(bunny);
    const lodbake::TopologyStats after = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(after.boundary_loop_count, before.boundary_loop_count);
    EXPECT_EQ(after.component_count, before.component_count);
    EXPECT_EQ(after.non_manifold_edge_count, 0u);
    const auto ours = lodbake::measureSurfaceDistance(bunny, out.mesh);
    ASSERT_TRUE(ours.ok()) << ours.status().message();
    const auto theirs = lodbake::measureSurfaceDistance(bunny, reference);
    ASSERT_TRUE(theirs.ok()) << theirs.status().message();
    std::printf("[ bunny 10%% ] ours %zu tris: mean %.3e rms %.3e hausdorff %.3e; meshopt_simplify %zu tris: mean "
                "%.3e rms %.3e hausdorff %.3e\n",
                out.mesh.faceCount(), ours->meanRel(), ours->rmsRel(), ours->hausdorffRel(), reference.faceCount(),
                theirs->meanRel(), theirs->rmsRel(), theirs->hausdorffRel());
    EXPECT_LT(ours->meanRel(), theirs->meanRel());
    EXPECT_LT(ours->rmsRel(), theirs->rmsRel());
    EXPECT_LT(ours->hausdorffRel(), theirs->hausdorffRel());
}

TEST(SimplifyTest, BorderPointsMoveOnlyAlongTheBorderEvenWithoutConstraintPlanes) {
    // With no constraint planes a flat grid costs nothing anywhere: only the feature rule keeps
    // border points on the (simplified) outline instead of pulling them inside.
    SimplifyOptions o = ratio(0.05f);
    o.border_weight = 0.0f;
    const SimplifyOutput out = run(lodbake_test::flatGrid(12), o);
    EXPECT_LT(out.mesh.faceCount(), 40u);
    std::map<std::pair<uint32_t, uint32_t>, int> edge_uses;
    for (size_t f = 0; f < out.mesh.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = out.mesh.indices[f * 3 + k], b = out.mesh.indices[f * 3 + (k + 1) % 3];
            ++edge_uses[{std::min(a, b), std::max(a, b)}];
        }
    int border_points = 0;
    float worst = 0.0f;
    for (const auto& e : edge_uses) {
        if (e.second != 1) continue;
        for (uint32_t v : {e.first.first, e.first.second}) {
            const Vec3f p = out.mesh.positions[v];
            worst = std::max(worst, std::min(std::min(p.x, 1.0f - p.x), std::min(p.y, 1.0f - p.y)));
            ++border_points;
        }
    }
    EXPECT_GT(border_points, 0);
    // Cutting a square's corner moves border points onto the cut (measured 0.013 here); a border
    // point pulled inside by an interior collapse lands a cell (1/12) or more away from it.
    EXPECT_LT(worst, 0.03f);
}

TEST(SimplifyTest, LinkConditionKeepsClosedSurfacesManifoldDownToATetrahedron) {
    // With the geometric checks relaxed only the topological ones stand between the collapses
    // and a non-manifold result.
    for (int levels : {0, 1, 2}) {
        SimplifyOptions o;
        o.target_triangles = 1;
        o.min_triangle_quality = 0.0f;
        o.max_normal_change_deg = 180.0f;
        const SimplifyOutput out = run(lodbake_test::icosphere(levels), o);
        const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
        EXPECT_EQ(out.mesh.faceCount(), 4u) << "levels " << levels;
        EXPECT_EQ(t.boundary_edge_count, 0u);
        EXPECT_EQ(t.non_manifold_edge_count, 0u);
        EXPECT_EQ(t.non_manifold_vertex_count, 0u);
        EXPECT_EQ(t.duplicate_face_count, 0u);
        EXPECT_EQ(t.euler_characteristic, 2);
    }
    // A torus (genus 1) keeps its genus: Euler characteristic stays 0.
    Mesh torus;
    const int n = 12, m = 8;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            const float a = 6.2831853f * float(i) / n, b = 6.2831853f * float(j) / m;
            torus.positions.push_back({(2 + std::cos(b)) * std::cos(a), (2 + std::cos(b)) * std::sin(a), std::sin(b)});
        }
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < m; ++j) {
            const uint32_t p00 = uint32_t(i * m + j), p10 = uint32_t(((i + 1) % n) * m + j),
                           p01 = uint32_t(i * m + (j + 1) % m), p11 = uint32_t(((i + 1) % n) * m + (j + 1) % m);
            torus.indices.insert(torus.indices.end(), {p00, p10, p11, p00, p11, p01});
        }
    SimplifyOptions o;
    o.target_triangles = 1;
    o.min_triangle_quality = 0.0f;
    o.max_normal_change_deg = 180.0f;
    const SimplifyOutput out = run(torus, o);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_LT(out.mesh.faceCount(), torus.faceCount() / 4);
    EXPECT_EQ(t.euler_characteristic, 0);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_vertex_count, 0u);
    EXPECT_EQ(t.duplicate_face_count, 0u);
}

TEST(SimplifyTest, RawRangeScanKeepsItsTopology) {
    // A raw scan: 10 components, 35 holes, 14 bow-tie vertices on its borders.
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    auto loaded =
        lodbake::readMesh(lodbake_test::sharedMesh("bunny_scan_bun000_tri.ply"), lodbake::ReadOptions(), diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const SimplifyOutput out = run(loaded->mesh, ratio(0.05f));
    EXPECT_TRUE(out.reached_target);
    const lodbake::TopologyStats before = lodbake::computeTopologyStats(loaded->mesh);
    const lodbake::TopologyStats after = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(after.component_count, before.component_count);
    EXPECT_EQ(after.euler_characteristic, before.euler_characteristic);
    EXPECT_EQ(after.non_manifold_edge_count, before.non_manifold_edge_count);
    EXPECT_EQ(after.non_manifold_vertex_count, before.non_manifold_vertex_count);
    EXPECT_EQ(after.inconsistent_edge_count, 0u);
    EXPECT_EQ(after.duplicate_face_count, 0u);
}

} // namespace
