#include "lodbake/simplify/lod_chain.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "core/parallel.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/io/mesh_io.h"
#include "simplify_test_meshes.h"
#include "test_paths.h"

namespace {

using lodbake::Diagnostics;
using lodbake::LodChain;
using lodbake::LodChainOptions;
using lodbake::Mesh;
using lodbake::Vec3f;

LodChain build(const Mesh& mesh, const LodChainOptions& options) {
    Diagnostics d;
    auto r = lodbake::buildLodChain(mesh, options, d);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? std::move(r).value() : LodChain();
}

LodChainOptions quick() {
    LodChainOptions o;
    o.distance.sample_count = 20000;
    return o;
}

TEST(LodChainTest, OnePassReachesEveryLevel) {
    const Mesh sphere = lodbake_test::icosphere(5); // 20480 faces
    const LodChain chain = build(sphere, quick());
    ASSERT_EQ(chain.levels.size(), 5u);
    const double ratios[] = {0.5, 0.25, 0.1, 0.03, 0.01};
    size_t previous_collapses = 0;
    for (size_t i = 0; i < 5; ++i) {
        const lodbake::LodLevel& l = chain.levels[i];
        EXPECT_DOUBLE_EQ(l.target_ratio, ratios[i]);
        EXPECT_TRUE(l.reached_target);
        const double target = std::ceil(ratios[i] * 20480);
        EXPECT_LE(double(l.mesh.faceCount()), target);
        EXPECT_GE(double(l.mesh.faceCount()), target - 2);
        EXPECT_GT(l.collapse_count, previous_collapses);
        previous_collapses = l.collapse_count;
        const lodbake::TopologyStats t = lodbake::computeTopologyStats(l.mesh);
        EXPECT_EQ(t.euler_characteristic, 2);
        EXPECT_EQ(t.boundary_edge_count, 0u);
    }
    EXPECT_EQ(chain.sequence.records.size(), chain.levels.back().collapse_count);
}

TEST(LodChainTest, ErrorIsMonotoneAcrossTheChain) {
    const LodChain chain = build(lodbake_test::icosphere(5), quick());
    for (size_t i = 1; i < chain.levels.size(); ++i) {
        const auto& a = chain.levels[i - 1];
        const auto& b = chain.levels[i];
        ASSERT_TRUE(a.has_distance && b.has_distance);
        EXPECT_GE(b.quadric_error, a.quadric_error);
        EXPECT_GT(b.distance.mean, a.distance.mean);
        EXPECT_GT(b.distance.hausdorff, a.distance.hausdorff);
        EXPECT_GE(b.switch_distance, a.switch_distance);
        EXPECT_LE(b.screen_coverage, a.screen_coverage);
    }
}

TEST(LodChainTest, CollapseSequenceReplaysToEveryLevel) {
    // Sphere vertices are all distinct and referenced, so each is one point; the engine numbers
    // points in its own order (first use by the faces), so they are matched by position.
    const Mesh sphere = lodbake_test::icosphere(4);
    LodChainOptions o = quick();
    o.measure_error = false;
    o.simplify.refine_late_levels = false; // positions exactly as the replay (see LateLevelsAreRefinedCopies)
    const LodChain chain = build(sphere, o);
    const lodbake::CollapseSequence& s = chain.sequence;
    ASSERT_EQ(s.point_positions.size(), sphere.vertexCount());
    std::map<std::array<float, 3>, uint32_t> point_at;
    for (uint32_t p = 0; p < s.point_positions.size(); ++p)
        point_at[{s.point_positions[p].x, s.point_positions[p].y, s.point_positions[p].z}] = p;
    ASSERT_EQ(point_at.size(), sphere.vertexCount());
    std::vector<uint32_t> point_of(sphere.vertexCount());
    for (uint32_t v = 0; v < sphere.vertexCount(); ++v) {
        const auto it = point_at.find({sphere.positions[v].x, sphere.positions[v].y, sphere.positions[v].z});
        ASSERT_NE(it, point_at.end());
        point_of[v] = it->second;
    }
    std::vector<uint32_t> parent(sphere.vertexCount());
    for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    std::vector<Vec3f> pos = s.point_positions;
    auto find = [&](uint32_t v) {
        while (parent[v] != v) v = parent[v];
        return v;
    };
    size_t applied = 0;
    for (const lodbake::LodLevel& level : chain.levels) {
        for (; applied < level.collapse_count; ++applied) {
            const lodbake::CollapseRecord& r = s.records[applied];
            ASSERT_EQ(find(r.removed_point), r.removed_point); // removed only once
            ASSERT_EQ(find(r.kept_point), r.kept_point);
            parent[r.removed_point] = r.kept_point;
            pos[r.kept_point] = r.position;
        }
        std::vector<std::array<float, 9>> replayed, actual;
        for (size_t f = 0; f < sphere.faceCount(); ++f) {
            const uint32_t a = find(point_of[sphere.indices[f * 3]]), b = find(point_of[sphere.indices[f * 3 + 1]]),
                           c = find(point_of[sphere.indices[f * 3 + 2]]);
            if (a == b || b == c || a == c) continue;
            replayed.push_back(
                {pos[a].x, pos[a].y, pos[a].z, pos[b].x, pos[b].y, pos[b].z, pos[c].x, pos[c].y, pos[c].z});
        }
        const Mesh& m = level.mesh;
        for (size_t f = 0; f < m.faceCount(); ++f) {
            const Vec3f a = m.positions[m.indices[f * 3]], b = m.positions[m.indices[f * 3 + 1]],
                        c = m.positions[m.indices[f * 3 + 2]];
            actual.push_back({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
        }
        EXPECT_EQ(replayed, actual) << "level " << level.target_ratio;
    }
}

TEST(LodChainTest, LateLevelsAreRefinedCopies) {
    // refine_late_levels moves the vertices of levels of at most 2.5 % of the input's faces; it works on the
    // snapshot, so faces, the collapse record and every later level are those of the unrefined chain.
    const Mesh sphere = lodbake_test::icosphere(5); // 20480 faces: 0.01 is refined, 0.03 is not
    LodChainOptions o = quick();
    const LodChain refined = build(sphere, o);
    o.simplify.refine_late_levels = false;
    const LodChain plain = build(sphere, o);
    ASSERT_EQ(refined.levels.size(), plain.levels.size());
    EXPECT_EQ(refined.sequence.records.size(), plain.sequence.records.size());
    for (size_t i = 0; i < refined.levels.size(); ++i) {
        const lodbake::LodLevel& r = refined.levels[i];
        const lodbake::LodLevel& p = plain.levels[i];
        EXPECT_EQ(r.mesh.indices, p.mesh.indices) << r.target_ratio;
        EXPECT_EQ(r.collapse_count, p.collapse_count);
        const bool late = double(p.mesh.faceCount()) <= 0.025 * 20480;
        EXPECT_EQ(r.is_refined, late) << r.target_ratio;
        EXPECT_FALSE(p.is_refined);
        if (!late) {
            EXPECT_TRUE(r.mesh.positions == p.mesh.positions) << r.target_ratio;
            continue;
        }
        EXPECT_FALSE(r.mesh.positions == p.mesh.positions) << r.target_ratio;
        // A coarse sphere's faces are chords inside it: the refined vertices move out and the
        // level gets closer to the input.
        ASSERT_TRUE(r.has_distance && p.has_distance);
        EXPECT_LT(r.distance.mean, p.distance.mean) << r.target_ratio;
        EXPECT_LE(r.distance.hausdorff, p.distance.hausdorff) << r.target_ratio;
    }
}

TEST(LodChainTest, ChainIsDeterministicAndMatchesSingleSimplify) {
    const Mesh sphere = lodbake_test::icosphere(4);
    LodChainOptions o = quick();
    o.measure_error = false;
    const LodChain a = build(sphere, o);
    const LodChain b = build(sphere, o);
    ASSERT_EQ(a.levels.size(), b.levels.size());
    for (size_t i = 0; i < a.levels.size(); ++i) {
        EXPECT_EQ(a.levels[i].mesh.indices, b.levels[i].mesh.indices);
        EXPECT_EQ(a.levels[i].mesh.positions, b.levels[i].mesh.positions);
    }
    // A level equals simplify() to the same target: both run the same collapse order.
    Diagnostics d;
    lodbake::SimplifyOptions so;
    so.target_ratio = 0.1f;
    auto single = lodbake::simplify(sphere, so, d);
    ASSERT_TRUE(single.ok());
    EXPECT_EQ(single->mesh.indices, a.levels[2].mesh.indices);
    EXPECT_EQ(single->mesh.positions, a.levels[2].mesh.positions);
}

TEST(LodChainTest, ChainDoesNotDependOnTheThreadCount) {
    // The engine's set-up (twins, kinds, attribute quadrics, initial keys) and the level refinement
    // run in parallel over fixed chunks: 10,242 points and 20,480 faces span several chunks, and the
    // 1 % level is refined (10,242 samples).
    Mesh sphere = lodbake_test::icosphere(5);
    sphere.normals.resize(sphere.positions.size());
    for (size_t v = 0; v < sphere.positions.size(); ++v) sphere.normals[v] = lodbake::normalize(sphere.positions[v]);
    LodChainOptions o = quick();
    o.measure_error = false;
    LodChain chains[2];
    for (int threads = 1; threads <= 2; ++threads) {
        lodbake::ScopedThreadLimit limit{size_t(threads)};
        chains[threads - 1] = build(sphere, o);
    }
    ASSERT_EQ(chains[0].levels.size(), chains[1].levels.size());
    EXPECT_TRUE(chains[0].levels.back().is_refined);
    for (size_t i = 0; i < chains[0].levels.size(); ++i) {
        EXPECT_EQ(chains[0].levels[i].mesh.indices, chains[1].levels[i].mesh.indices);
        EXPECT_TRUE(chains[0].levels[i].mesh.positions == chains[1].levels[i].mesh.positions);
        EXPECT_TRUE(chains[0].levels[i].mesh.normals == chains[1].levels[i].mesh.normals);
    }
}

TEST(LodChainTest, SwitchDistanceFollowsTheProjectionFormula) {
    lodbake::ScreenParams s; // 1 px, 1080 px, 60 degrees
    const double expected = 0.01 * 1080.0 / (2.0 * 1.0 * std::tan(3.14159265358979323846 / 6.0));
    EXPECT_NEAR(lodbake::switchDistance(0.01, s), expected, 1e-12);
    s.pixel_threshold = 2.0;
    EXPECT_NEAR(lodbake::switchDistance(0.01, s), expected / 2.0, 1e-12);
    EXPECT_EQ(lodbake::switchDistance(0.0, s), 0.0);
    // A sphere of radius r at distance d covers r / (d tan(fov/2)) of the viewport height.
    s.pixel_threshold = 1.0;
    EXPECT_NEAR(lodbake::screenCoverage(1.0, 10.0, s), 1.0 / (10.0 * std::tan(3.14159265358979323846 / 6.0)), 1e-12);
    EXPECT_EQ(lodbake::screenCoverage(1.0, 0.0, s), 1.0);
    // At the switch distance the error e projects to exactly p pixels.
    const double d = lodbake::switchDistance(0.003, s);
    const double pixels = 0.003 / (2.0 * d * std::tan(s.vertical_fov_rad / 2.0)) * s.viewport_height_px;
    EXPECT_NEAR(pixels, s.pixel_threshold, 1e-12);
}

TEST(LodChainTest, RejectsBadRatiosAndNotesUnreachableLevels) {
    Diagnostics d;
    LodChainOptions o;
    o.ratios = {0.5, 0.0};
    EXPECT_FALSE(lodbake::buildLodChain(lodbake_test::icosphere(1), o, d).ok());
    o.ratios = {1.5};
    EXPECT_FALSE(lodbake::buildLodChain(lodbake_test::icosphere(1), o, d).ok());
    // An icosahedron cannot go below a tetrahedron: the last level stops there and says so.
    const Mesh tetra = lodbake_test::icosphere(0); // icosahedron: 20 faces, reaches 4 at best
    o.ratios = {0.5, 0.01};
    o.measure_error = false;
    auto chain = lodbake::buildLodChain(tetra, o, d);
    ASSERT_TRUE(chain.ok());
    ASSERT_EQ(chain->levels.size(), 2u);
    EXPECT_TRUE(chain->levels[0].reached_target);
    EXPECT_FALSE(chain->levels[1].reached_target);
    EXPECT_GE(chain->levels[1].mesh.faceCount(), 4u);
    EXPECT_FALSE(d.empty());
}

bool noteContains(const Diagnostics& d, const std::string& text) {
    for (const lodbake::Diagnostic& m : d.items())
        if (m.message.find(text) != std::string::npos) return true;
    return false;
}

TEST(LodChainTest, AStoppedChainNeverRepeatsALevel) {
    // The icosahedron stops above 0.1 of its faces: that level is kept (not reached, with its
    // reason) and the ones after it, which could only repeat it, are left out with a note.
    Diagnostics d;
    LodChainOptions o;
    o.ratios = {0.5, 0.1, 0.05, 0.01};
    o.measure_error = false;
    auto chain = lodbake::buildLodChain(lodbake_test::icosphere(0), o, d);
    ASSERT_TRUE(chain.ok());
    ASSERT_EQ(chain->levels.size(), 2u);
    EXPECT_TRUE(chain->levels[0].reached_target);
    EXPECT_FALSE(chain->levels[1].reached_target);
    EXPECT_LT(chain->levels[1].mesh.faceCount(), chain->levels[0].mesh.faceCount());
    EXPECT_TRUE(noteContains(d, "level ratio 0.1 stopped at")) << d.items().size();
    EXPECT_TRUE(noteContains(d, "no valid collapse left"));
    EXPECT_TRUE(noteContains(d, "level ratio 0.05 omitted"));
    EXPECT_TRUE(noteContains(d, "level ratio 0.01 omitted"));
}

TEST(LodChainTest, RatiosWithTheSameTargetGiveOneLevel) {
    // 20 faces: 0.5 and 0.48 both ask for 10 triangles; the second level would repeat the first.
    Diagnostics d;
    LodChainOptions o;
    o.ratios = {0.5, 0.48, 0.3};
    o.measure_error = false;
    auto chain = lodbake::buildLodChain(lodbake_test::icosphere(0), o, d);
    ASSERT_TRUE(chain.ok());
    ASSERT_EQ(chain->levels.size(), 2u);
    EXPECT_EQ(chain->levels[0].target_ratio, 0.5);
    EXPECT_EQ(chain->levels[1].target_ratio, 0.3);
    EXPECT_TRUE(noteContains(d, "level ratio 0.48 omitted"));
    for (size_t i = 1; i < chain->levels.size(); ++i)
        EXPECT_LT(chain->levels[i].mesh.faceCount(), chain->levels[i - 1].mesh.faceCount());
}

TEST(LodChainTest, Lucy100kChainMeasuresEveryLevel) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("lucy100k.ply"), lodbake::ReadOptions(), diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    LodChainOptions o;
    o.distance.sample_count = 50000;
    const LodChain chain = build(loaded->mesh, o);
    ASSERT_EQ(chain.levels.size(), 5u);
    for (size_t i = 0; i < chain.levels.size(); ++i) {
        const auto& l = chain.levels[i];
        EXPECT_TRUE(l.reached_target);
        ASSERT_TRUE(l.has_distance);
        // The mean error grows level by level; the Hausdorff error need not (a coarser level can
        // place one vertex better), so switch distances are made monotone instead.
        if (i > 0) {
            EXPECT_GT(l.distance.mean, chain.levels[i - 1].distance.mean);
            EXPECT_GE(l.switch_distance, chain.levels[i - 1].switch_distance);
        }
        const lodbake::TopologyStats t = lodbake::computeTopologyStats(l.mesh);
        EXPECT_EQ(t.boundary_edge_count, 0u);
        EXPECT_EQ(t.non_manifold_edge_count, 0u);
        EXPECT_EQ(t.component_count, 1u);
    }
    // Generous bounds around what was measured (mean 1e-3 of the diagonal even at 1 %).
    EXPECT_LT(chain.levels[0].distance.meanRel(), 5e-5);
    EXPECT_LT(chain.levels[4].distance.meanRel(), 3e-3);
}

} // namespace
