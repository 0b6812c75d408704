// PfrepTest: the blob's levels are the simplifier's meshes (triangle for triangle, by position),
// fans equal lists, levels are manifold when the input is, selective refinement is crack-free, and
// raw non-manifold scans go through.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <set>

#include "core/parallel.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodrt/pfrep.h"
#include "test_paths.h"

namespace {

using lodbake::CollapseSequence;
using Tri = std::array<uint32_t, 3>;

Tri canonicalTri(uint32_t a, uint32_t b, uint32_t c) {
    // Rotation that starts at the smallest id keeps the orientation.
    if (b < a && b < c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
}

struct Baked {
    lodbake::LodChain chain;
    std::vector<uint32_t> point_triangles;
    lodbake::PfrepBuild build;
    lodrt::PfrepModel model;
};

// Simplifies with half-edge collapses, keeping snapshots at several ratios, and builds the blob
// from the very same recorded sequence.
std::unique_ptr<Baked> bake(const std::string& name, std::vector<double> ratios) {
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh(name), {}, diagnostics);
    if (!loaded.ok()) return nullptr;
    auto baked = std::make_unique<Baked>();
    lodbake::LodChainOptions options;
    options.ratios = std::move(ratios);
    options.measure_error = false;
    options.simplify.placement = lodbake::CollapsePlacement::KeepEndpoint;
    auto chain = lodbake::buildLodChain(loaded->mesh, options, diagnostics);
    if (!chain.ok()) return nullptr;
    baked->chain = std::move(*chain);
    auto tris = lodbake::pointTriangles(loaded->mesh, baked->chain.sequence);
    if (!tris.ok()) return nullptr;
    baked->point_triangles = std::move(*tris);
    auto build = lodbake::buildPfrepFromSequence(baked->chain.sequence, baked->point_triangles, diagnostics);
    if (!build.ok()) return nullptr;
    baked->build = std::move(*build);
    if (lodrt::openPfrep(baked->build.blob.data(), baked->build.blob.size(), &baked->model) != lodrt::Result::Ok)
        return nullptr;
    return baked;
}

// A level as a set of point triangles.
std::multiset<Tri> extractPoints(const Baked& b, uint32_t level) {
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(b.model) * 3);
    size_t count = 0;
    EXPECT_EQ(lodrt::pfrepExtractLevel(b.model, level, idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
    std::multiset<Tri> out;
    for (size_t t = 0; t < count; ++t)
        out.insert(canonicalTri(b.build.rank_point[idx[t * 3]], b.build.rank_point[idx[t * 3 + 1]],
                                b.build.rank_point[idx[t * 3 + 2]]));
    return out;
}

std::multiset<Tri> meshPoints(const lodbake::Mesh& mesh, const CollapseSequence& seq) {
    auto tris = lodbake::pointTriangles(mesh, seq);
    EXPECT_TRUE(tris.ok());
    std::multiset<Tri> out;
    for (size_t t = 0; tris.ok() && t < tris->size() / 3; ++t)
        out.insert(canonicalTri((*tris)[t * 3], (*tris)[t * 3 + 1], (*tris)[t * 3 + 2]));
    return out;
}

// Closed 2-manifold: every directed edge has exactly one opposite and appears once.
bool closedManifold(const std::vector<uint32_t>& idx, size_t count, std::string& why) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < count; ++t)
        for (int k = 0; k < 3; ++k) ++directed[{idx[t * 3 + k], idx[t * 3 + (k + 1) % 3]}];
    for (const auto& [e, n] : directed) {
        auto it = directed.find({e.second, e.first});
        if (n != 1 || it == directed.end() || it->second != 1) {
            why = "edge " + std::to_string(e.first) + "-" + std::to_string(e.second) + " used " + std::to_string(n) +
                  " times, reverse " + std::to_string(it == directed.end() ? 0 : it->second);
            return false;
        }
    }
    return true;
}

class PfrepTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        if (!lodbake_test::haveSharedMeshes()) return;
        rocker_ = bake("rocker_arm.obj", {0.9, 0.7, 0.5, 0.3, 0.1, 0.03, 0.01}).release();
        scan_ = bake("dragon_scan_stand0_tri.ply", {0.8, 0.5, 0.2, 0.05}).release();
        bunny_ = bake("bunny_zipper.ply", {0.6, 0.25, 0.05}).release();
    }
    static void TearDownTestSuite() {
        delete rocker_;
        delete scan_;
        delete bunny_;
        rocker_ = scan_ = bunny_ = nullptr;
    }
    static Baked* rocker_;
    static Baked* scan_;
    static Baked* bunny_;
};
Baked* PfrepTest::rocker_ = nullptr;
Baked* PfrepTest::scan_ = nullptr;
Baked* PfrepTest::bunny_ = nullptr;

TEST_F(PfrepTest, LevelsEqualTheSimplifierSnapshots) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (Baked* b : {rocker_, scan_, bunny_}) {
        ASSERT_NE(b, nullptr);
        EXPECT_EQ(b->build.removed, b->chain.sequence.records.size());
        for (const auto& level : b->chain.levels) {
            const auto got = extractPoints(*b, uint32_t(level.collapse_count));
            const auto want = meshPoints(level.mesh, b->chain.sequence);
            EXPECT_EQ(got.size(), level.mesh.faceCount());
            EXPECT_TRUE(got == want) << "level after " << level.collapse_count << " collapses";
        }
    }
}

TEST_F(PfrepTest, EveryLevelEqualsAnIndependentReplay) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (Baked* b : {rocker_, scan_}) {
        ASSERT_NE(b, nullptr);
        // Replay the recorded collapses on a plain triangle set and compare at ~60 levels.
        std::vector<Tri> tris;
        std::vector<std::vector<uint32_t>> incident(b->chain.sequence.point_positions.size());
        std::vector<uint8_t> dead;
        std::multiset<Tri> alive;
        auto add = [&](Tri t) {
            for (uint32_t p : t) incident[p].push_back(uint32_t(tris.size()));
            tris.push_back(t);
            dead.push_back(0);
            alive.insert(canonicalTri(t[0], t[1], t[2]));
        };
        for (size_t t = 0; t < b->point_triangles.size() / 3; ++t)
            add({b->point_triangles[t * 3], b->point_triangles[t * 3 + 1], b->point_triangles[t * 3 + 2]});
        const auto& records = b->chain.sequence.records;
        const size_t step = std::max<size_t>(1, records.size() / 60);
        for (size_t k = 0; k <= records.size(); ++k) {
            if (k % step == 0 || k == records.size() || k < 5) {
                ASSERT_TRUE(extractPoints(*b, uint32_t(k)) == alive) << "k = " << k;
            }
            if (k == records.size()) break;
            const uint32_t u = records[k].removed_point, v = records[k].kept_point;
            const std::vector<uint32_t> ring = incident[u];
            for (uint32_t id : ring) {
                if (dead[id]) continue;
                dead[id] = 1;
                Tri t = tris[id];
                alive.erase(alive.find(canonicalTri(t[0], t[1], t[2])));
                if (t[0] == v || t[1] == v || t[2] == v) continue;
                for (auto& p : t)
                    if (p == u) p = v;
                add(t);
            }
        }
    }
}

TEST_F(PfrepTest, LevelsOfAClosedInputAreClosedManifoldsWithoutDuplicates) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    for (uint32_t k = 0; k <= m.removed_count; k += std::max(1u, m.removed_count / 40)) {
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepExtractLevel(m, k, idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
        std::string why;
        EXPECT_TRUE(closedManifold(idx, count, why)) << "k = " << k << ": " << why;
        std::set<Tri> unique;
        for (size_t t = 0; t < count; ++t) {
            for (int c = 0; c < 3; ++c) {
                EXPECT_GE(idx[t * 3 + c], k);
                EXPECT_LT(idx[t * 3 + c], m.vertex_count);
            }
            unique.insert(canonicalTri(idx[t * 3], idx[t * 3 + 1], idx[t * 3 + 2]));
        }
        EXPECT_EQ(unique.size(), count);
    }
}

TEST_F(PfrepTest, FansDrawTheSameTrianglesAsTheList) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (Baked* b : {rocker_, scan_}) {
        ASSERT_NE(b, nullptr);
        const lodrt::PfrepModel& m = b->model;
        std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3), fans(lodrt::pfrepMaxFanValues(m));
        for (uint32_t k : {0u, m.removed_count / 3, m.removed_count / 2, m.removed_count}) {
            size_t count = 0, values = 0;
            ASSERT_EQ(lodrt::pfrepExtractLevel(m, k, idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
            ASSERT_EQ(lodrt::pfrepExtractLevelFans(m, k, fans.data(), fans.size(), &values), lodrt::Result::Ok);
            std::multiset<Tri> a, f;
            for (size_t t = 0; t < count; ++t) a.insert(canonicalTri(idx[t * 3], idx[t * 3 + 1], idx[t * 3 + 2]));
            for (size_t p = 0; p < values;) {
                const uint32_t n = fans[p];
                ASSERT_GE(n, 1u);
                ASSERT_LE(p + n + 3, values);
                for (uint32_t j = 0; j < n; ++j) f.insert(canonicalTri(fans[p + 1], fans[p + 2 + j], fans[p + 3 + j]));
                p += n + 3;
            }
            EXPECT_TRUE(a == f) << "k = " << k;
            // Fans save submissions: fewer values than a list's 3 per triangle.
            if (k == 0) {
                EXPECT_LT(values, count * 3); // full detail: fans average well above one triangle
            }
        }
        size_t count = 0;
        EXPECT_EQ(lodrt::pfrepExtractLevel(m, 0, idx.data(), 3, &count), lodrt::Result::BufferTooSmall);
        EXPECT_EQ(lodrt::pfrepExtractLevel(m, m.removed_count + 1, idx.data(), idx.size() / 3, &count),
                  lodrt::Result::InvalidArgument);
    }
}

TEST_F(PfrepTest, SelectiveRefinementIsCrackFree) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    std::mt19937 rng(7);
    // The mask starts at the full mesh: selective extraction equals level 0.
    lodrt::pfrepMaskFinest(m, mask.data());
    size_t count = 0;
    ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
    EXPECT_EQ(count, m.level0_triangles);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
    size_t coarse = 0;
    std::vector<uint32_t> idx2(idx.size());
    ASSERT_EQ(lodrt::pfrepExtractLevel(m, m.removed_count, idx2.data(), idx2.size() / 3, &coarse), lodrt::Result::Ok);
    EXPECT_EQ(count, coarse);
    // Random operations, a region at a time (refine around one vertex, coarsen elsewhere).
    size_t distinct_sizes = 0, last = 0;
    for (int round = 0; round < 60; ++round) {
        for (int op = 0; op < 40; ++op) {
            const uint32_t v = rng() % m.removed_count;
            if (rng() % 2)
                ASSERT_EQ(lodrt::pfrepInsertVertex(m, mask.data(), v, scratch.data(), scratch.size()), lodrt::Result::Ok);
            else
                ASSERT_EQ(lodrt::pfrepSimplifyVertex(m, mask.data(), v, scratch.data(), scratch.size()), lodrt::Result::Ok);
        }
        ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
        std::string why;
        ASSERT_TRUE(closedManifold(idx, count, why)) << "round " << round << ": " << why;
        for (size_t t = 0; t < count * 3; ++t) ASSERT_FALSE((mask[idx[t] >> 3] >> (idx[t] & 7)) & 1);
        distinct_sizes += count != last;
        last = count;
    }
    EXPECT_GT(distinct_sizes, 10u);
}

TEST_F(PfrepTest, ViewDependentRefinementFollowsTheCameraWithoutCracks) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = m.position_min[k];
        hi[k] = m.position_min[k] + 65535.0f * m.position_step[k];
    }
    const float size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    std::vector<size_t> counts;
    for (float dist : {20.0f, 5.0f, 1.5f, 0.8f, 5.0f, 20.0f}) {
        lodrt::PfrepView view;
        view.eye[0] = (lo[0] + hi[0]) * 0.5f;
        view.eye[1] = (lo[1] + hi[1]) * 0.5f;
        view.eye[2] = hi[2] + dist * size;
        // A frustum that keeps everything (planes far away) so only distance and facing matter.
        for (int p = 0; p < 6; ++p) {
            view.planes[p][p / 2] = p % 2 ? -1.0f : 1.0f;
            view.planes[p][3] = 1e6f;
        }
        for (int iter = 0; iter < 20; ++iter) {
            size_t changes = 0;
            ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes),
                      lodrt::Result::Ok);
            if (changes == 0) break;
        }
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
        std::string why;
        EXPECT_TRUE(closedManifold(idx, count, why)) << "distance " << dist << ": " << why;
        counts.push_back(count);
    }
    EXPECT_LT(counts[0], counts[2]); // closer: more triangles
    EXPECT_LT(counts[5], counts[3]); // moving away coarsens again
}

// A view of the rocker arm from `dist` model sizes above its top, shifted by `dx` sizes sideways,
// looking down -z through a 60 degree frustum: the side planes cull part of the mesh.
lodrt::PfrepView rockerView(const lodrt::PfrepModel& m, float dist, float dx) {
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = m.position_min[k];
        hi[k] = m.position_min[k] + 65535.0f * m.position_step[k];
    }
    const float size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    lodrt::PfrepView view;
    view.eye[0] = (lo[0] + hi[0]) * 0.5f + dx * size;
    view.eye[1] = (lo[1] + hi[1]) * 0.5f;
    view.eye[2] = hi[2] + dist * size;
    const float c = std::cos(0.5236f), sn = std::sin(0.5236f);
    const float planes[5][3] = {{0, 0, -1}, {c, 0, -sn}, {-c, 0, -sn}, {0, c, -sn}, {0, -c, -sn}};
    for (int p = 0; p < 5; ++p) {
        for (int k = 0; k < 3; ++k) view.planes[p][k] = planes[p][k];
        view.planes[p][3] = -(planes[p][0] * view.eye[0] + planes[p][1] * view.eye[1] + planes[p][2] * view.eye[2]);
    }
    view.planes[5][3] = 1e30f;
    view.pixels_per_unit_at_distance_one = 1080.0f / (2.0f * std::tan(0.5236f));
    view.pixel_tolerance = 1.0f;
    return view;
}

TEST_F(PfrepTest, StaticCameraConvergesThenDoesNoVertexOperations) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    for (float dist : {0.6f, 2.0f}) {
        for (int start = 0; start < 2; ++start) {
            if (start == 0)
                lodrt::pfrepMaskCoarsest(m, mask.data());
            else
                lodrt::pfrepMaskFinest(m, mask.data());
            const lodrt::PfrepView view = rockerView(m, dist, 0.1f);
            // The first refinement: steps until one does nothing (insertions below the scan position
            // are examined by the next step), which must happen within a few steps.
            size_t changes = 1, first = 0;
            int steps = 0;
            for (; steps < 50 && changes > 0; ++steps) {
                ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes),
                          lodrt::Result::Ok);
                if (steps == 0) first = changes;
            }
            EXPECT_EQ(changes, 0u) << "distance " << dist << " start " << start << ": no fixed point in 50 steps";
            EXPECT_GT(first, 0u);
            const std::vector<uint8_t> settled = mask;
            for (int frame = 0; frame < 5; ++frame) {
                ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes),
                          lodrt::Result::Ok);
                EXPECT_EQ(changes, 0u) << "distance " << dist << " start " << start << " frame " << frame;
            }
            EXPECT_EQ(mask, settled);
        }
    }
}

TEST_F(PfrepTest, SlowlyMovingCameraTogglesNoVertexTwiceWithinFewFrames) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    size_t changes = 1;
    for (int steps = 0; steps < 50 && changes > 0; ++steps)
        ASSERT_EQ(lodrt::pfrepRefine(m, rockerView(m, 0.8f, -0.3f), mask.data(), scratch.data(), scratch.size(), &changes),
                  lodrt::Result::Ok);
    ASSERT_EQ(changes, 0u);
    // Flies sideways and closer, 1% of the model size per frame; one refinement step per frame.
    std::vector<int> last_flip(m.vertex_count, -100);
    size_t flips = 0;
    std::vector<uint8_t> previous = mask;
    for (int frame = 0; frame < 60; ++frame) {
        const lodrt::PfrepView view = rockerView(m, 0.8f - 0.005f * frame, -0.3f + 0.01f * frame);
        ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes), lodrt::Result::Ok);
        for (uint32_t v = 0; v < m.vertex_count; ++v) {
            if (((mask[v >> 3] ^ previous[v >> 3]) >> (v & 7)) & 1) {
                ++flips;
                EXPECT_GT(frame - last_flip[v], 4) << "vertex " << v << " flipped at frames " << last_flip[v] << " and "
                                                   << frame;
                last_flip[v] = frame;
            }
        }
        previous = mask;
        if (frame % 10 == 9) {
            size_t count = 0;
            ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
            std::string why;
            ASSERT_TRUE(closedManifold(idx, count, why)) << "frame " << frame << ": " << why;
        }
    }
    EXPECT_GT(flips, 0u); // the camera moved enough to change the mesh
}

// Converges `mask` under `view` (steps until one changes nothing); false if 50 steps do not suffice.
bool settle(const lodrt::PfrepModel& m, const lodrt::PfrepView& view, std::vector<uint8_t>& mask,
            std::vector<uint32_t>& scratch) {
    size_t changes = 1;
    for (int steps = 0; steps < 50 && changes > 0; ++steps)
        if (lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes) != lodrt::Result::Ok)
            return false;
    return changes == 0;
}

TEST_F(PfrepTest, CullBandKeepsVerticesThatJustLeftTheFrustumOrTurnedAway) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    ASSERT_TRUE(settle(m, rockerView(m, 0.3f, 0.0f), mask, scratch));
    // A sideways move of 0.1 model sizes: vertices near one side plane leave the frustum, most by a
    // small angle.
    size_t removed_with[2] = {0, 0};
    for (int band = 0; band < 2; ++band) {
        std::vector<uint8_t> moved = mask;
        lodrt::PfrepView view = rockerView(m, 0.3f, 0.1f);
        view.cull_hysteresis = band ? 0.05f : 0.0f;
        size_t changes = 0;
        ASSERT_EQ(lodrt::pfrepRefine(m, view, moved.data(), scratch.data(), scratch.size(), &changes), lodrt::Result::Ok);
        for (uint32_t v = 0; v < m.vertex_count; ++v)
            removed_with[band] += ((moved[v >> 3] & ~mask[v >> 3]) >> (v & 7)) & 1;
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepExtractSelective(m, moved.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
        std::string why;
        EXPECT_TRUE(closedManifold(idx, count, why)) << "band " << band << ": " << why;
    }
    EXPECT_GT(removed_with[0], 0u) << "the move should drop vertices without a band";
    EXPECT_LT(removed_with[1], removed_with[0]);
}

TEST_F(PfrepTest, BoundedStepsStayCrackFreeAndConverge) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
    lodrt::PfrepView view = rockerView(m, 0.3f, 0.1f);
    lodrt::pfrepMaskCoarsest(m, mask.data());
    size_t unbounded_first = 0;
    {
        std::vector<uint8_t> copy = mask;
        ASSERT_EQ(lodrt::pfrepRefine(m, view, copy.data(), scratch.data(), scratch.size(), &unbounded_first),
                  lodrt::Result::Ok);
    }
    ASSERT_GT(unbounded_first, 100u);
    view.max_changed_bits = 16;
    size_t changes = 1, steps = 0, first = 0;
    for (; steps < 400 && changes > 0; ++steps) {
        std::vector<uint8_t> before = mask;
        ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes), lodrt::Result::Ok);
        size_t flipped = 0;
        for (size_t b = 0; b < mask.size(); ++b) flipped += size_t(__builtin_popcount(uint8_t(mask[b] ^ before[b])));
        EXPECT_EQ(flipped, changes); // changes counts mask bits
        if (steps == 0) first = changes;
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepExtractSelective(m, mask.data(), idx.data(), idx.size() / 3, &count), lodrt::Result::Ok);
        std::string why;
        ASSERT_TRUE(closedManifold(idx, count, why)) << "step " << steps << ": " << why;
    }
    EXPECT_GT(first, 0u);
    EXPECT_LT(first, unbounded_first / 2);
    EXPECT_GT(steps, 2u);
    EXPECT_EQ(changes, 0u) << "bounded steps did not converge in 400 steps";
    // The bounded steps end on a mask where an unbounded step has nothing to do either.
    view.max_changed_bits = 0;
    ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes), lodrt::Result::Ok);
    EXPECT_EQ(changes, 0u);
}

TEST(PfrepRawScanTest, NonManifoldMergedScansWithoutRepair) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    auto b = bake("dragon_stand_merged.ply", {0.5, 0.1});
    ASSERT_NE(b, nullptr);
    for (const auto& level : b->chain.levels) {
        const auto got = extractPoints(*b, uint32_t(level.collapse_count));
        EXPECT_TRUE(got == meshPoints(level.mesh, b->chain.sequence)) << "after " << level.collapse_count;
    }
    EXPECT_LE(double(b->build.blob.size()) / double(b->model.vertex_count), 40.0);
}

TEST(PfrepBuilderTest, RefusesFullEdgeSequences) {
    lodbake::CollapseSequence seq;
    seq.point_positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    seq.records.push_back({0, 1, lodbake::Vec3f(0.5f, 0, 0), 0, 0});
    lodbake::Diagnostics d;
    auto r = lodbake::buildPfrepFromSequence(seq, {0, 1, 2, 1, 3, 2}, d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("KeepEndpoint"), std::string::npos);
}

// The simplifier logs the point triangles and the triangles each half-edge collapse re-creates; the
// builder then needs no replay. Both ways must give the same bytes, at any thread count.
TEST(PfrepBuilderTest, LoggedSequenceBuildsTheReplayedBlob) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("rocker_arm.obj"), {}, d);
    ASSERT_TRUE(loaded.ok());
    lodbake::Mesh geometry;
    geometry.positions = loaded->mesh.positions;
    geometry.indices = loaded->mesh.indices;
    lodbake::LodChainOptions options;
    options.ratios = {1e-9};
    options.measure_error = false;
    options.record_collapses = true;
    options.simplify.placement = lodbake::CollapsePlacement::KeepEndpoint;
    auto chain = lodbake::buildLodChain(geometry, options, d);
    ASSERT_TRUE(chain.ok());
    const CollapseSequence& logged = chain->sequence;
    ASSERT_EQ(logged.created_end.size(), logged.records.size());
    ASSERT_GT(logged.records.size(), 1000u);
    auto tris = lodbake::pointTriangles(geometry, logged);
    ASSERT_TRUE(tris.ok());
    EXPECT_EQ(logged.point_triangles, *tris);
    CollapseSequence replayed = logged;
    replayed.created_triangles.clear();
    replayed.created_end.clear();
    std::vector<uint8_t> blobs[3];
    for (int variant = 0; variant < 3; ++variant) {
        lodbake::ScopedThreadLimit limit(variant == 2 ? 2 : 1);
        auto build = lodbake::buildPfrepFromSequence(variant == 0 ? replayed : logged, *tris, d);
        ASSERT_TRUE(build.ok()) << build.status().message();
        blobs[variant] = std::move(build->blob);
    }
    EXPECT_TRUE(blobs[0] == blobs[1]);
    EXPECT_TRUE(blobs[0] == blobs[2]);
    // And through buildPfrep (the bake's path).
    lodbake::PfrepOptions pfrep_options;
    auto direct = lodbake::buildPfrep(geometry, pfrep_options, d);
    ASSERT_TRUE(direct.ok());
    EXPECT_TRUE(direct->blob == blobs[0]);
    // A log that does not match its ranges is refused.
    CollapseSequence broken = logged;
    broken.created_triangles.pop_back();
    EXPECT_FALSE(lodbake::buildPfrepFromSequence(broken, *tris, d).ok());
}

} // namespace

// An instance out of reach (behind the camera, or so far that its largest error is below a pixel)
// is decided as a whole; the result must be what the vertex-by-vertex pass gives: the present
// removable vertices simplified in increasing rank, within the budget, nothing inserted.
TEST_F(PfrepTest, InstanceOutOfReachIsCoarsenedLikeTheVertexPass) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& m = rocker_->model;
    std::vector<uint8_t> start(lodrt::pfrepMaskBytes(m));
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(m));
    lodrt::pfrepMaskCoarsest(m, start.data());
    size_t changes = 1;
    for (int step = 0; step < 50 && changes > 0; ++step)
        ASSERT_EQ(lodrt::pfrepRefine(m, rockerView(m, 0.3f, 0.1f), start.data(), scratch.data(), scratch.size(), &changes),
                  lodrt::Result::Ok);
    size_t present = 0;
    for (uint32_t v = 0; v < m.removed_count; ++v) present += ((start[v >> 3] >> (v & 7)) & 1) == 0;
    ASSERT_GT(present, 200u);
    for (float dist : {-5.0f, 1e6f}) {
        const lodrt::PfrepView base = rockerView(m, dist, 0.1f);
        for (uint32_t v = 0; v < m.vertex_count; ++v) ASSERT_FALSE(lodrt::pfrepWanted(m, base, v)) << dist << " " << v;
        for (uint32_t budget : {0u, 37u, 1000u}) {
            lodrt::PfrepView view = base;
            view.max_changed_bits = budget;
            std::vector<uint8_t> expected = start;
            size_t expected_changes = 0;
            for (uint32_t v = 0; v < m.removed_count && (budget == 0 || expected_changes < budget); ++v)
                if (((expected[v >> 3] >> (v & 7)) & 1) == 0) {
                    expected[v >> 3] = uint8_t(expected[v >> 3] | (1u << (v & 7)));
                    ++expected_changes;
                }
            std::vector<uint8_t> mask = start;
            ASSERT_EQ(lodrt::pfrepRefine(m, view, mask.data(), scratch.data(), scratch.size(), &changes), lodrt::Result::Ok);
            EXPECT_EQ(changes, expected_changes) << dist << " " << budget;
            EXPECT_TRUE(mask == expected) << dist << " " << budget;
        }
    }
}

// The per-model criterion table holds the record's values exactly: a camera path refines every mask
// bit the same with and without it, and pfrepVertexBounds agrees with the table.
TEST_F(PfrepTest, CriterionTableDecidesExactlyLikeTheRecords) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_NE(rocker_, nullptr);
    const lodrt::PfrepModel& plain = rocker_->model;
    lodrt::PfrepModel tabled = plain;
    std::vector<float> table(lodrt::pfrepCriterionTableFloats(plain));
    EXPECT_EQ(lodrt::pfrepAttachCriterionTable(&tabled, table.data(), table.size() - 1), lodrt::Result::BufferTooSmall);
    ASSERT_EQ(lodrt::pfrepAttachCriterionTable(&tabled, table.data(), table.size()), lodrt::Result::Ok);
    ASSERT_EQ(tabled.criterion_table, table.data());
    for (uint32_t v = 0; v < plain.vertex_count; v += 97) {
        lodrt::PfrepVertexBounds b;
        ASSERT_EQ(lodrt::pfrepVertexBounds(plain, v, &b), lodrt::Result::Ok);
        EXPECT_EQ(b.position[0], table[size_t(v) * 8]);
        EXPECT_EQ(b.radius, table[size_t(v) * 8 + 3]);
        EXPECT_EQ(b.error, table[size_t(v) * 8 + 4]);
        EXPECT_EQ(b.cone_axis[2], table[size_t(v) * 8 + 7]);
    }
    std::vector<uint8_t> a(lodrt::pfrepMaskBytes(plain)), b(a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(plain));
    lodrt::pfrepMaskCoarsest(plain, a.data());
    lodrt::pfrepMaskCoarsest(plain, b.data());
    size_t total = 0;
    for (int frame = 0; frame < 60; ++frame) {
        const float dist = 3.0f - 0.045f * float(frame), dx = 0.02f * float(frame % 17) - 0.15f;
        lodrt::PfrepView view = rockerView(plain, dist, dx);
        view.max_changed_bits = frame % 5 == 0 ? 64 : 0;
        size_t ca = 0, cb = 0;
        ASSERT_EQ(lodrt::pfrepRefine(plain, view, a.data(), scratch.data(), scratch.size(), &ca), lodrt::Result::Ok);
        ASSERT_EQ(lodrt::pfrepRefine(tabled, view, b.data(), scratch.data(), scratch.size(), &cb), lodrt::Result::Ok);
        ASSERT_EQ(ca, cb) << "frame " << frame;
        ASSERT_EQ(a, b) << "frame " << frame;
        total += ca;
    }
    EXPECT_GT(total, 100u); // the path did refine
}
