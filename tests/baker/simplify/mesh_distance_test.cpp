#include "lodbake/simplify/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <array>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/parallel.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/io/mesh_io.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

using lodbake::Mesh;
using lodbake::Vec3f;

Mesh icosahedron() {
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    Mesh m;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    for (Vec3f& p : m.positions) p = lodbake::normalize(p);
    m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
                 3, 9,  4, 3, 4, 2, 3, 2, 6, 3, 6, 8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
    return m;
}

// Splits every triangle into four; new vertices are projected onto the unit sphere.
Mesh subdivideOnSphere(const Mesh& in) {
    Mesh out;
    out.positions = in.positions;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoint;
    auto mid = [&](uint32_t a, uint32_t b) {
        auto key = std::make_pair(std::min(a, b), std::max(a, b));
        auto it = midpoint.find(key);
        if (it != midpoint.end()) return it->second;
        out.positions.push_back(lodbake::normalize((out.positions[a] + out.positions[b]) * 0.5f));
        uint32_t id = uint32_t(out.positions.size() - 1);
        midpoint.emplace(key, id);
        return id;
    };
    for (size_t t = 0; t < in.faceCount(); ++t) {
        uint32_t a = in.indices[t * 3], b = in.indices[t * 3 + 1], c = in.indices[t * 3 + 2];
        uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
        out.indices.insert(out.indices.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    return out;
}

Mesh icosphere(int levels) {
    Mesh m = icosahedron();
    for (int i = 0; i < levels; ++i) m = subdivideOnSphere(m);
    return m;
}

// n×n grid of quads in [0,1]² at height z, two triangles each.
Mesh gridPlane(uint32_t n, float z) {
    Mesh m;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i) m.positions.push_back(Vec3f(float(i) / n, float(j) / n, z));
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            uint32_t v = j * (n + 1) + i;
            m.indices.insert(m.indices.end(), {v, v + 1, v + n + 2, v, v + n + 2, v + n + 1});
        }
    return m;
}

// Moves every vertex along a pseudo-random direction by up to `amplitude` (deterministic).
Mesh perturbed(Mesh m, float amplitude, uint64_t seed) {
    uint64_t s = seed;
    auto next = [&s]() {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return float(double(s >> 11) * (1.0 / 9007199254740992.0)) * 2.0f - 1.0f;
    };
    for (Vec3f& p : m.positions) p += Vec3f(next(), next(), next()) * amplitude;
    return m;
}

// Vertex clustering on a grid of `cells` per bounding-box diagonal: a crude but real decimation.
Mesh clustered(const Mesh& m, double cells) {
    lodbake::Aabb box = lodbake::computeBounds(m);
    const double cell = box.diagonal() / cells;
    std::map<std::array<int64_t, 3>, uint32_t> cell_of;
    std::vector<lodbake::Vec3d> sum;
    std::vector<uint32_t> count, remap(m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
        lodbake::Vec3d p = lodbake::toDouble(m.positions[v]);
        std::array<int64_t, 3> key{int64_t(std::floor((p.x - box.min.x) / cell)),
                                   int64_t(std::floor((p.y - box.min.y) / cell)),
                                   int64_t(std::floor((p.z - box.min.z) / cell))};
        auto it = cell_of.emplace(key, uint32_t(sum.size())).first;
        if (it->second == sum.size()) {
            sum.push_back(lodbake::Vec3d());
            count.push_back(0);
        }
        sum[it->second] += p;
        count[it->second]++;
        remap[v] = it->second;
    }
    Mesh out;
    for (size_t c = 0; c < sum.size(); ++c) out.positions.push_back(Vec3f(sum[c] / double(count[c])));
    for (size_t t = 0; t < m.faceCount(); ++t) {
        uint32_t a = remap[m.indices[t * 3]], b = remap[m.indices[t * 3 + 1]], c = remap[m.indices[t * 3 + 2]];
        if (a != b && b != c && c != a) out.indices.insert(out.indices.end(), {a, b, c});
    }
    return out;
}

lodbake::DistanceResult measure(const Mesh& a, const Mesh& b, const lodbake::DistanceOptions& options = {}) {
    auto r = lodbake::measureSurfaceDistance(a, b, options);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? r.value() : lodbake::DistanceResult();
}

TEST(MeshDistanceTest, IdenticalMeshesGiveZero) {
    Mesh sphere = icosphere(3);
    lodbake::DistanceResult r = measure(sphere, sphere);
    EXPECT_LT(r.hausdorff, 1e-12);
    EXPECT_LT(r.mean, 1e-13);
    EXPECT_GT(r.diagonal, 3.0);
}

TEST(MeshDistanceTest, OffsetPlaneGivesExactOffset) {
    Mesh a = gridPlane(8, 0.0f);
    Mesh b = gridPlane(3, 0.25f); // different tessellation, same extent
    lodbake::DistanceResult r = measure(a, b);
    EXPECT_DOUBLE_EQ(r.hausdorff, 0.25);
    EXPECT_DOUBLE_EQ(r.mean, 0.25);
    EXPECT_DOUBLE_EQ(r.rms, 0.25);
    EXPECT_DOUBLE_EQ(r.max_ref_to_approx, 0.25);
    EXPECT_DOUBLE_EQ(r.max_approx_to_ref, 0.25);
    EXPECT_DOUBLE_EQ(r.diagonal, std::sqrt(2.0));
    EXPECT_DOUBLE_EQ(r.hausdorffRel(), 0.25 / std::sqrt(2.0));
}

TEST(MeshDistanceTest, SphereVsInscribedIcosahedron) {
    // Every icosahedron vertex lies on the unit sphere; the farthest point is over a face centre, at
    // 1 - inradius. The reference is a fine icosphere, whose own sag (≈1.5e-4 at 5 levels) and the
    // sampling density bound how close we get.
    Mesh sphere = icosphere(5);
    Mesh ico = icosahedron();
    Vec3f centre =
        (ico.positions[ico.indices[0]] + ico.positions[ico.indices[1]] + ico.positions[ico.indices[2]]) / 3.0f;
    const double expected = 1.0 - lodbake::length(lodbake::toDouble(centre));
    ASSERT_NEAR(expected, 0.2053, 1e-3); // sanity of the construction itself
    lodbake::DistanceResult r = measure(sphere, ico);
    EXPECT_NEAR(r.hausdorff, expected, 1e-3);
    EXPECT_LE(r.hausdorff, expected + 1e-6);
    EXPECT_NEAR(r.max_ref_to_approx, expected, 1e-3);
    EXPECT_NEAR(r.max_approx_to_ref, expected, 1e-3);
    EXPECT_GT(r.mean, 0.02);
    EXPECT_LT(r.mean, expected);
}

TEST(MeshDistanceTest, BitIdenticalAcrossThreadCountsAndSeeded) {
    Mesh reference = perturbed(icosphere(5), 0.01f, 7);
    Mesh approx = perturbed(icosphere(2), 0.02f, 9);
    lodbake::DistanceOptions options;
    options.sample_count = 50000;
    lodbake::DistanceResult one, two;
    {
        lodbake::ScopedThreadLimit limit(1);
        one = measure(reference, approx, options);
    }
    {
        lodbake::ScopedThreadLimit limit(2);
        two = measure(reference, approx, options);
    }
    EXPECT_EQ(one.hausdorff, two.hausdorff);
    EXPECT_EQ(one.mean, two.mean);
    EXPECT_EQ(one.rms, two.rms);
    EXPECT_EQ(one.max_ref_to_approx, two.max_ref_to_approx);
    EXPECT_EQ(one.max_approx_to_ref, two.max_approx_to_ref);

    options.seed = 2;
    lodbake::DistanceResult other_seed = measure(reference, approx, options);
    EXPECT_NE(one.mean, other_seed.mean);
    EXPECT_NEAR(one.mean, other_seed.mean, one.mean * 0.02);
}

TEST(MeshDistanceTest, PreparedReferenceGivesTheSameResult) {
    Mesh reference = perturbed(icosphere(4), 0.01f, 11);
    Mesh approx = perturbed(icosphere(2), 0.01f, 12);
    lodbake::DistanceOptions options;
    options.sample_count = 20000;
    auto prepared = lodbake::DistanceReference::prepare(reference);
    ASSERT_TRUE(prepared.ok());
    lodbake::DistanceResult direct = measure(reference, approx, options);
    auto again = lodbake::measureSurfaceDistance(prepared.value(), approx, options);
    ASSERT_TRUE(again.ok());
    EXPECT_EQ(direct.hausdorff, again->hausdorff);
    EXPECT_EQ(direct.mean, again->mean);
    EXPECT_EQ(direct.rms, again->rms);
    EXPECT_EQ(direct.diagonal, again->diagonal);
    EXPECT_FALSE(lodbake::DistanceReference::prepare(lodbake_test::makeMesh({{0, 0, 0}}, {})).ok());
}

// A batch result equals the one-level result bit for bit (or fails with the same message).
void expectSameBits(const lodbake::Result<lodbake::DistanceResult>& got,
                    const lodbake::Result<lodbake::DistanceResult>& want, const std::string& label) {
    ASSERT_EQ(got.ok(), want.ok()) << label;
    if (!want.ok()) {
        EXPECT_EQ(got.status().message(), want.status().message()) << label;
        return;
    }
    EXPECT_EQ(got->hausdorff, want->hausdorff) << label;
    EXPECT_EQ(got->mean, want->mean) << label;
    EXPECT_EQ(got->rms, want->rms) << label;
    EXPECT_EQ(got->max_ref_to_approx, want->max_ref_to_approx) << label;
    EXPECT_EQ(got->max_approx_to_ref, want->max_approx_to_ref) << label;
    EXPECT_EQ(got->diagonal, want->diagonal) << label;
}

// Four levels of an icosphere reference for the batch tests (seeds from `seed`): three perturbed
// spheres and a degenerate one (third), which fails to measure.
std::vector<Mesh> batchLevels(uint64_t seed) {
    return {perturbed(icosphere(3), 0.01f, seed + 1), perturbed(icosphere(2), 0.02f, seed + 2),
            lodbake_test::makeMesh({{0, 0, 0}}, {}), perturbed(icosphere(1), 0.02f, seed + 3)};
}

struct LevelBatch {
    Mesh reference;
    std::vector<Mesh> levels;
    std::vector<const Mesh*> pointers;
    lodbake::DistanceOptions options;
    explicit LevelBatch(uint64_t seed) : reference(perturbed(icosphere(4), 0.01f, seed)), levels(batchLevels(seed)) {
        for (const Mesh& m : levels) pointers.push_back(&m);
        options.sample_count = 20000;
    }
};

TEST(MeshDistanceTest, BatchOfLevelsEqualsOneByOneForAnyThreadCount) {
    const LevelBatch in(21);
    auto prepared = lodbake::DistanceReference::prepare(in.reference);
    ASSERT_TRUE(prepared.ok());
    for (int threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit(threads);
        const auto batch = lodbake::measureSurfaceDistances(prepared.value(), in.pointers, in.options);
        ASSERT_EQ(batch.size(), in.levels.size());
        for (size_t i = 0; i < in.levels.size(); ++i) {
            expectSameBits(batch[i], lodbake::measureSurfaceDistance(prepared.value(), in.levels[i], in.options),
                           std::to_string(i));
        }
    }
}

// prepareAndMeasureSurfaceDistances builds the reference's index, its points and the first level's
// setup side by side: the same bits as prepare + one call per level, a failing level (degenerate)
// reported in its slot, and a bad reference or empty options failing the whole call.
TEST(MeshDistanceTest, PrepareAndMeasureEqualsOneByOneForAnyThreadCount) {
    Mesh reference = perturbed(icosphere(4), 0.01f, 31);
    std::vector<Mesh> levels = {perturbed(icosphere(3), 0.01f, 32), lodbake_test::makeMesh({{0, 0, 0}}, {}),
                                perturbed(icosphere(2), 0.02f, 33)};
    std::vector<const Mesh*> pointers;
    for (const Mesh& m : levels) pointers.push_back(&m);
    lodbake::DistanceOptions options;
    options.sample_count = 20000;
    auto prepared = lodbake::DistanceReference::prepare(reference);
    ASSERT_TRUE(prepared.ok());
    for (int threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit(threads);
        const auto batch = lodbake::prepareAndMeasureSurfaceDistances(reference, pointers, options);
        ASSERT_TRUE(batch.ok()) << batch.status().message();
        ASSERT_EQ(batch->size(), levels.size());
        for (size_t i = 0; i < levels.size(); ++i) {
            expectSameBits((*batch)[i], lodbake::measureSurfaceDistance(prepared.value(), levels[i], options),
                           std::to_string(i));
        }
        EXPECT_FALSE((*batch)[1].ok());
        EXPECT_TRUE(lodbake::prepareAndMeasureSurfaceDistances(reference, {}, options)->empty());
    }
    EXPECT_FALSE(lodbake::prepareAndMeasureSurfaceDistances(levels[1], pointers, options).ok());
    lodbake::DistanceOptions none;
    none.sample_count = 0;
    none.include_vertices = false;
    EXPECT_FALSE(lodbake::prepareAndMeasureSurfaceDistances(reference, pointers, none).ok());
}

// measureReferenceSides measures the reference side of every level on its own (the bake runs it beside
// the PFRep build); prepareAndMeasureSurfaceDistances then takes the sides it is given instead of
// measuring them: the same bits as measuring both sides there, for any subset given and thread count.
TEST(MeshDistanceTest, ReferenceSidesMeasuredBeforehandGiveTheSameBits) {
    const LevelBatch in(41);
    auto prepared = lodbake::DistanceReference::prepare(in.reference);
    ASSERT_TRUE(prepared.ok());
    for (int threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit(threads);
        const auto sides = lodbake::measureReferenceSides(in.reference, in.pointers, in.options);
        ASSERT_TRUE(sides.ok()) << sides.status().message();
        ASSERT_EQ(sides->size(), in.levels.size());
        EXPECT_FALSE((*sides)[2].ok()); // degenerate level
        // Every side, none, and the sides of in.levels 1 and on (the bake's use).
        for (size_t first : {size_t(0), size_t(1), in.levels.size()}) {
            std::vector<const lodbake::OneSidedDistance*> known(in.levels.size(), nullptr);
            for (size_t i = first; i < in.levels.size(); ++i)
                if ((*sides)[i].ok()) known[i] = &*(*sides)[i];
            const auto batch = lodbake::prepareAndMeasureSurfaceDistances(in.reference, in.pointers, in.options, known);
            ASSERT_TRUE(batch.ok()) << batch.status().message();
            ASSERT_EQ(batch->size(), in.levels.size());
            for (size_t i = 0; i < in.levels.size(); ++i) {
                const auto single = lodbake::measureSurfaceDistance(prepared.value(), in.levels[i], in.options);
                expectSameBits((*batch)[i], single, std::to_string(first) + " " + std::to_string(i));
                if (single.ok()) {
                    EXPECT_EQ((*sides)[i]->max, single->max_ref_to_approx) << i;
                }
            }
        }
    }
    // A given side is taken as it is, not measured again.
    lodbake::OneSidedDistance forged;
    forged.max = 123.0;
    forged.sum = 1.0;
    forged.sum_sq = 1.0;
    forged.count = 1;
    const auto taken =
        lodbake::prepareAndMeasureSurfaceDistances(in.reference, in.pointers, in.options, {nullptr, &forged, nullptr, nullptr});
    ASSERT_TRUE(taken.ok());
    EXPECT_EQ((*taken)[1]->max_ref_to_approx, 123.0);
    EXPECT_EQ((*taken)[1]->hausdorff, 123.0);
    EXPECT_FALSE(lodbake::measureReferenceSides(in.levels[2], in.pointers, in.options).ok());
    lodbake::DistanceOptions none;
    none.sample_count = 0;
    none.include_vertices = false;
    EXPECT_FALSE(lodbake::measureReferenceSides(in.reference, in.pointers, none).ok());
    EXPECT_TRUE(lodbake::measureReferenceSides(in.reference, {}, in.options)->empty());
}

// Brute force: the exact distance the index computes, over every triangle.
double bruteForceDistanceSq(const Mesh& m, const lodbake::Vec3d& p) {
    double best = HUGE_VAL;
    for (size_t t = 0; t < m.faceCount(); ++t) {
        const lodbake::Vec3d a = lodbake::toDouble(m.positions[m.indices[t * 3]]);
        const lodbake::Vec3d b = lodbake::toDouble(m.positions[m.indices[t * 3 + 1]]);
        const lodbake::Vec3d c = lodbake::toDouble(m.positions[m.indices[t * 3 + 2]]);
        const lodbake::Vec3d q = lodbake::closestPointOnTriangle(p, a, b, c);
        best = std::min(best, lodbake::dot(p - q, p - q));
    }
    return best;
}

// The index returns exactly the brute-force minimum (same bits), with or without a hint, for points on,
// near and far from the surface, coordinates beyond the float test's range, and degenerate triangles.
TEST(MeshDistanceTest, IndexEqualsBruteForceExactly) {
    for (float scale : {1.0f, 1e-3f, 3e4f}) {
        Mesh m = perturbed(icosphere(3), 0.05f, 31);
        // Degenerate triangles: a sliver with coincident corners and a collinear one.
        m.positions.push_back(Vec3f(0.2f, 0.1f, 1.5f));
        m.positions.push_back(Vec3f(0.4f, 0.3f, 1.7f));
        const uint32_t base = uint32_t(m.positions.size() - 2);
        m.positions.push_back(Vec3f(0.6f, 0.5f, 1.9f));
        m.indices.insert(m.indices.end(), {base, base, base + 1, base, base + 1, base + 2});
        for (Vec3f& p : m.positions) p = p * scale;
        auto index = lodbake::DistanceIndex::build(m.positions, m.indices);
        ASSERT_TRUE(index.ok());
        EXPECT_EQ(index->triangleCount(), m.faceCount());
        uint64_t state = 77;
        auto next = [&state]() {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return double(state >> 11) * (1.0 / 9007199254740992.0) * 2.0 - 1.0;
        };
        uint32_t hint = lodbake::DistanceIndex::kNoHint;
        for (int i = 0; i < 3000; ++i) {
            // Mostly near the unit sphere, some far away (beyond twice the mesh's largest coordinate).
            const double radius = i % 10 == 0 ? 5.0 + 50.0 * (next() + 1.0) : 1.0 + 0.1 * next();
            lodbake::Vec3d dir(next(), next(), next());
            if (lodbake::length(dir) == 0) continue;
            const lodbake::Vec3d p = lodbake::normalize(dir) * (radius * scale);
            const double want = bruteForceDistanceSq(m, p);
            uint32_t cold = lodbake::DistanceIndex::kNoHint;
            EXPECT_EQ(index->closestDistanceSq(p, cold), want) << "scale " << scale << " point " << i;
            EXPECT_EQ(index->closestDistanceSq(p, hint), want) << "scale " << scale << " point " << i;
            ASSERT_NE(hint, lodbake::DistanceIndex::kNoHint);
            ASSERT_LT(hint, index->triangleCount());
        }
    }
    auto empty = lodbake::DistanceIndex::build({}, {});
    ASSERT_TRUE(empty.ok());
    uint32_t hint = lodbake::DistanceIndex::kNoHint;
    EXPECT_EQ(empty->closestDistanceSq(lodbake::Vec3d(0, 0, 0), hint), HUGE_VAL);
}

// A cursor carried along a walk (small steps near the surface, occasional jumps, points far out) gives
// exactly the brute-force minimum at every step, like a cold query: starting below the root never
// skips the nearest triangle.
TEST(MeshDistanceTest, CursorWalkEqualsBruteForceExactly) {
    for (float scale : {1.0f, 2.5e-3f}) {
        Mesh m = perturbed(icosphere(4), 0.03f, 7);
        for (Vec3f& p : m.positions) p = p * scale;
        auto index = lodbake::DistanceIndex::build(m.positions, m.indices);
        ASSERT_TRUE(index.ok());
        uint64_t state = 5;
        auto next = [&state]() {
            state = state * 6364136223846793005ull + 1442695040888963407ull;
            return double(state >> 11) * (1.0 / 9007199254740992.0) * 2.0 - 1.0;
        };
        lodbake::DistanceIndex::Cursor cursor;
        lodbake::Vec3d dir(1, 0, 0);
        uint32_t deep = 0;
        for (int i = 0; i < 4000; ++i) {
            if (i % 500 == 499)
                dir = lodbake::Vec3d(next(), next(), next()); // a jump
            else
                dir = dir + lodbake::Vec3d(next(), next(), next()) * 0.02; // a step of about one triangle
            if (lodbake::length(dir) == 0) continue;
            const double radius = i % 97 == 0 ? 3.0 : 1.0 + 0.04 * next();
            const lodbake::Vec3d p = lodbake::normalize(dir) * (radius * scale);
            const double want = bruteForceDistanceSq(m, p);
            ASSERT_EQ(index->closestDistanceSq(p, cursor), want) << "scale " << scale << " point " << i;
            ASSERT_LE(cursor.depth, lodbake::DistanceIndex::kCursorDepth);
            if (cursor.depth > 3) ++deep;
        }
        EXPECT_GT(deep, 1000u) << "the walk should keep a path below the root";
    }
}

TEST(MeshDistanceTest, RejectsDegenerateInput) {
    Mesh good = lodbake_test::tetrahedron();
    Mesh no_triangles = good;
    no_triangles.indices.clear();
    Mesh flat = lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2, 0, 0, 1});
    Mesh out_of_range = lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 3});
    Mesh not_finite = lodbake_test::singleTriangle();
    not_finite.positions[1].y = NAN;

    auto expectError = [](const Mesh& a, const Mesh& b, const std::string& fragment) {
        auto r = lodbake::measureSurfaceDistance(a, b);
        ASSERT_FALSE(r.ok());
        EXPECT_EQ(r.status().code(), lodbake::StatusCode::InvalidInput);
        EXPECT_NE(r.status().message().find(fragment), std::string::npos) << r.status().message();
    };
    expectError(no_triangles, good,
                "reference mesh: expected at least one triangle of non-zero area, found no triangles");
    expectError(good, flat,
                "approximation mesh: expected at least one triangle of non-zero area, found only degenerate");
    expectError(good, out_of_range, "approximation mesh: triangle 0: index 3 out of range (3 vertices)");
    expectError(not_finite, good, "reference mesh: vertex 1: expected finite coordinates");

    lodbake::DistanceOptions nothing;
    nothing.sample_count = 0;
    nothing.include_vertices = false;
    auto r = lodbake::measureSurfaceDistance(good, good, nothing);
    EXPECT_FALSE(r.ok());
    // Vertices alone are a valid (coarse) measurement.
    nothing.include_vertices = true;
    EXPECT_TRUE(lodbake::measureSurfaceDistance(good, good, nothing).ok());
}

// --- Agreement with ../shared/eval/meshdist.py (Open3D RaycastingScene) -------------------------

void writeBinaryPly(const Mesh& m, const std::string& path) {
    std::ofstream f(path, std::ios::binary);
    f << "ply\nformat binary_little_endian 1.0\nelement vertex " << m.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.faceCount()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3f& p : m.positions) f.write(reinterpret_cast<const char*>(&p.x), 12); // x86: little-endian
    for (size_t t = 0; t < m.faceCount(); ++t) {
        uint8_t n = 3;
        f.write(reinterpret_cast<const char*>(&n), 1);
        f.write(reinterpret_cast<const char*>(&m.indices[t * 3]), 12);
    }
    ASSERT_TRUE(f.good()) << path;
}

double jsonNumber(const std::string& json, const std::string& key) {
    size_t at = json.find("\"" + key + "\":");
    if (at == std::string::npos) return NAN;
    return std::strtod(json.c_str() + at + key.size() + 3, nullptr);
}

struct PythonResult {
    double hausdorff = NAN, mean = NAN, rms = NAN;
};

// Debian's interpreter, where scripts/install-deps.sh installs python3-open3d.
std::string pythonWithOpen3d() { return lodbake_test::python(); }

PythonResult runMeshdistPy(const std::string& ref_path, const std::string& approx_path) {
    const std::string python = pythonWithOpen3d();
    EXPECT_FALSE(python.empty()) << "no python3 with numpy and open3d (Debian python3-open3d) found";
    const std::string out = ref_path + ".meshdist.json";
    std::remove(out.c_str()); // a failed run must not leave the previous run's numbers to read
    const std::string cmd = python + " '" + lodbake_test::sharedEvalDir() + "/meshdist.py' '" + ref_path +
                            "' '" + approx_path + "' --json > '" + out + "'";
    int rc = std::system(cmd.c_str());
    EXPECT_EQ(rc, 0) << cmd;
    std::ifstream f(out);
    std::stringstream ss;
    ss << f.rdbuf();
    PythonResult r;
    r.hausdorff = jsonNumber(ss.str(), "hausdorff");
    r.mean = jsonNumber(ss.str(), "mean");
    r.rms = jsonNumber(ss.str(), "rms");
    return r;
}

void expectAgreesWithPython(const Mesh& reference, const Mesh& approx, const std::string& name) {
    const std::string dir = lodbake_test::scratchDir();
    const std::string ref_path = dir + "/meshdist_" + name + "_ref.ply";
    const std::string approx_path = dir + "/meshdist_" + name + "_approx.ply";
    writeBinaryPly(reference, ref_path);
    writeBinaryPly(approx, approx_path);
    PythonResult py = runMeshdistPy(ref_path, approx_path);
    lodbake::DistanceResult ours = measure(reference, approx);
    ASSERT_GT(py.hausdorff, 0.0) << name;
    ASSERT_GT(py.mean, 0.0) << name;
    ASSERT_GT(py.rms, 0.0) << name;
    EXPECT_NEAR(ours.hausdorffRel(), py.hausdorff, 0.1 * py.hausdorff) << name;
    EXPECT_NEAR(ours.meanRel(), py.mean, 0.1 * py.mean) << name;
    EXPECT_NEAR(ours.rmsRel(), py.rms, 0.1 * py.rms) << name;
    std::printf("[ meshdist ] %s: hausdorff ours %.4e python %.4e, mean ours %.4e python %.4e, rms ours %.4e "
                "python %.4e\n",
                name.c_str(), ours.hausdorffRel(), py.hausdorff, ours.meanRel(), py.mean, ours.rmsRel(), py.rms);
}

TEST(MeshDistanceTest, AgreesWithOpen3dScriptOnSyntheticMeshes) {
    LODBAKE_REQUIRE_SHARED_EVAL(); // only the script: the meshes are built here
    Mesh sphere = icosphere(5);
    expectAgreesWithPython(sphere, icosahedron(), "sphere_ico");
    expectAgreesWithPython(sphere, perturbed(icosphere(3), 0.01f, 3), "sphere_noisy");
}

TEST(MeshDistanceTest, AgreesWithOpen3dScriptOnBunny) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    LODBAKE_REQUIRE_SHARED_EVAL();
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), lodbake::ReadOptions(), diagnostics);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    const Mesh& bunny = loaded->mesh;
    ASSERT_EQ(bunny.faceCount(), 69451u);
    const float noise = float(lodbake::computeBounds(bunny).diagonal() * 0.002);
    expectAgreesWithPython(bunny, perturbed(bunny, noise, 5), "bunny_noisy");
    Mesh decimated = clustered(bunny, 60.0);
    ASSERT_LT(decimated.faceCount(), bunny.faceCount() / 4);
    expectAgreesWithPython(bunny, decimated, "bunny_clustered");
}

} // namespace
