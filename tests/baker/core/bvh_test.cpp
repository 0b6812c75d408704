#include "lodbake/core/bvh.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "core/parallel.h"

namespace {

using lodbake::Vec3d;
using lodbake::Vec3f;

// Small deterministic generator for test data (not the library's).
struct TestRng {
    uint64_t state;
    double next() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * (1.0 / 9007199254740992.0);
    }
};

double distSq(const Vec3d& a, const Vec3d& b) {
    return lodbake::dot(a - b, a - b);
}

TEST(TriangleBvhTest, ClosestPointRegions) {
    Vec3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    // Interior: straight down.
    Vec3d q = lodbake::closestPointOnTriangle(Vec3d(0.25, 0.25, 2), a, b, c);
    EXPECT_DOUBLE_EQ(q.x, 0.25);
    EXPECT_DOUBLE_EQ(q.y, 0.25);
    EXPECT_DOUBLE_EQ(q.z, 0.0);
    // Vertex regions.
    EXPECT_EQ(lodbake::closestPointOnTriangle(Vec3d(-1, -1, 0.5), a, b, c), a);
    EXPECT_EQ(lodbake::closestPointOnTriangle(Vec3d(3, -0.5, 0), a, b, c), b);
    EXPECT_EQ(lodbake::closestPointOnTriangle(Vec3d(-0.1, 4, 0), a, b, c), c);
    // Edge regions.
    q = lodbake::closestPointOnTriangle(Vec3d(0.5, -2, 1), a, b, c);
    EXPECT_DOUBLE_EQ(q.x, 0.5);
    EXPECT_DOUBLE_EQ(q.y, 0.0);
    q = lodbake::closestPointOnTriangle(Vec3d(1, 1, 0), a, b, c);
    EXPECT_DOUBLE_EQ(q.x, 0.5);
    EXPECT_DOUBLE_EQ(q.y, 0.5);
    q = lodbake::closestPointOnTriangle(Vec3d(-3, 0.5, 0), a, b, c);
    EXPECT_DOUBLE_EQ(q.x, 0.0);
    EXPECT_DOUBLE_EQ(q.y, 0.5);
}

TEST(TriangleBvhTest, ClosestPointOnDegenerateTriangles) {
    // Collinear: behaves like the segment from (0,0,0) to (2,0,0).
    Vec3d q = lodbake::closestPointOnTriangle(Vec3d(1.5, 1, 0), Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(2, 0, 0));
    EXPECT_DOUBLE_EQ(q.x, 1.5);
    EXPECT_DOUBLE_EQ(q.y, 0.0);
    // All corners coincide.
    q = lodbake::closestPointOnTriangle(Vec3d(5, 5, 5), Vec3d(1, 2, 3), Vec3d(1, 2, 3), Vec3d(1, 2, 3));
    EXPECT_EQ(q, Vec3d(1, 2, 3));
}

TEST(TriangleBvhTest, MatchesBruteForceOnRandomSoup) {
    TestRng rng{42};
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices;
    // Small random triangles in a unit cube, plus a few duplicated and degenerate ones.
    for (uint32_t t = 0; t < 3000; ++t) {
        Vec3f base(float(rng.next()), float(rng.next()), float(rng.next()));
        for (int k = 0; k < 3; ++k) {
            Vec3f offset(float(rng.next() - 0.5) * 0.1f, float(rng.next() - 0.5) * 0.1f,
                         float(rng.next() - 0.5) * 0.1f);
            positions.push_back(base + (t % 97 == 0 ? Vec3f() : offset));
            indices.push_back(uint32_t(positions.size() - 1));
        }
    }
    for (int k = 0; k < 30; ++k) indices.insert(indices.end(), {0, 1, 2});
    auto built = lodbake::TriangleBvh::build(positions, indices);
    ASSERT_TRUE(built.ok());
    const lodbake::TriangleBvh& bvh = built.value();
    ASSERT_EQ(bvh.triangleCount(), indices.size() / 3);
    EXPECT_LE(bvh.depth(), lodbake::TriangleBvh::kMaxDepth);

    for (int i = 0; i < 500; ++i) {
        Vec3d p(rng.next() * 1.6 - 0.3, rng.next() * 1.6 - 0.3, rng.next() * 1.6 - 0.3);
        double best = INFINITY;
        for (size_t t = 0; t < indices.size() / 3; ++t) {
            Vec3d q = lodbake::closestPointOnTriangle(p, lodbake::toDouble(positions[indices[t * 3]]),
                                                      lodbake::toDouble(positions[indices[t * 3 + 1]]),
                                                      lodbake::toDouble(positions[indices[t * 3 + 2]]));
            best = std::min(best, distSq(p, q));
        }
        lodbake::ClosestHit hit = bvh.closest(p);
        ASSERT_TRUE(hit.isFound());
        EXPECT_EQ(hit.distance_sq, best) << "query " << i;
        EXPECT_EQ(distSq(p, hit.point), hit.distance_sq);
    }
}

TEST(TriangleBvhTest, SameTreeForAnyThreadCount) {
    // Large enough that the top is split on one thread and the subtrees in parallel.
    TestRng rng{7};
    std::vector<Vec3f> positions;
    std::vector<uint32_t> indices;
    for (uint32_t t = 0; t < 60000; ++t) {
        Vec3f base(float(rng.next()), float(rng.next()), float(rng.next() * 0.1));
        for (int k = 0; k < 3; ++k) {
            positions.push_back(base + Vec3f(float(rng.next()) * 0.01f, float(rng.next()) * 0.01f, 0.0f));
            indices.push_back(uint32_t(positions.size() - 1));
        }
    }
    std::vector<lodbake::TriangleBvh> trees;
    for (size_t threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit(threads);
        trees.push_back(lodbake::TriangleBvh::build(positions, indices).value());
    }
    EXPECT_EQ(trees[0].nodeCount(), trees[1].nodeCount());
    EXPECT_EQ(trees[0].depth(), trees[1].depth());
    for (int i = 0; i < 200; ++i) {
        Vec3d p(rng.next(), rng.next(), rng.next() * 0.2 - 0.05);
        lodbake::ClosestHit a = trees[0].closest(p), b = trees[1].closest(p);
        EXPECT_EQ(a.face, b.face);
        EXPECT_EQ(a.distance_sq, b.distance_sq);
    }
}

TEST(TriangleBvhTest, RespectsMaxDistanceAndEmptyTree) {
    std::vector<Vec3f> positions{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    std::vector<uint32_t> indices{0, 1, 2};
    lodbake::TriangleBvh bvh = lodbake::TriangleBvh::build(positions, indices).value();
    EXPECT_TRUE(bvh.closest(Vec3d(0.2, 0.2, 1.0)).isFound());
    EXPECT_FALSE(bvh.closest(Vec3d(0.2, 0.2, 1.0), 0.5).isFound()); // 1.0² is not < 0.5
    lodbake::TriangleBvh empty = lodbake::TriangleBvh::build(positions, {}).value();
    EXPECT_TRUE(empty.isEmpty());
    EXPECT_FALSE(empty.closest(Vec3d(0, 0, 0)).isFound());
}

} // namespace
