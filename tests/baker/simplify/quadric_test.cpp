#include "lodbake/simplify/quadric.h"

#include <cstdint>
#include <iterator>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "simplify/collapse_queue.h"
#include "core/large_array.h"

namespace {

using lodbake::AttributeQuadric;
using lodbake::Quadric;
using lodbake::Vec3d;

TEST(QuadricTest, PlaneQuadricMeasuresWeightedSquaredDistance) {
    // Plane z = 1, i.e. n = (0,0,1), d = -1, weight 3.
    const Quadric q = Quadric::fromPlane(Vec3d(0, 0, 1), -1.0, 3.0);
    EXPECT_DOUBLE_EQ(q.evaluate(Vec3d(5, -2, 1)), 0.0);
    EXPECT_DOUBLE_EQ(q.evaluate(Vec3d(0, 0, 3)), 3.0 * 4.0);
    EXPECT_DOUBLE_EQ(q.weight, 3.0);
}

TEST(QuadricTest, TriangleQuadricIsAreaWeightedNotNormalised) {
    const Quadric small = Quadric::fromTriangle(Vec3d(0, 0, 0), Vec3d(1, 0, 0), Vec3d(0, 1, 0));
    const Quadric big = Quadric::fromTriangle(Vec3d(0, 0, 0), Vec3d(2, 0, 0), Vec3d(0, 2, 0));
    EXPECT_DOUBLE_EQ(small.weight, 0.5);
    EXPECT_DOUBLE_EQ(big.weight, 2.0);
    EXPECT_DOUBLE_EQ(small.evaluate(Vec3d(7, 7, 2)), 0.5 * 4.0);
    EXPECT_DOUBLE_EQ(big.evaluate(Vec3d(7, 7, 2)), 2.0 * 4.0);
    const Quadric degenerate = Quadric::fromTriangle(Vec3d(0, 0, 0), Vec3d(1, 1, 1), Vec3d(2, 2, 2));
    EXPECT_DOUBLE_EQ(degenerate.weight, 0.0);
    EXPECT_DOUBLE_EQ(degenerate.evaluate(Vec3d(1, 2, 3)), 0.0);
}

TEST(QuadricTest, SumOfQuadricsIsSumOfErrors) {
    Quadric a = Quadric::fromPlane(Vec3d(1, 0, 0), -1.0, 1.0);
    const Quadric b = Quadric::fromPlane(Vec3d(0, 1, 0), 2.0, 2.0);
    const Vec3d p(0.5, 0.25, -3);
    const double expected = a.evaluate(p) + b.evaluate(p);
    a += b;
    EXPECT_NEAR(a.evaluate(p), expected, 1e-12);
    EXPECT_DOUBLE_EQ(a.weight, 3.0);
}

TEST(QuadricTest, OptimalPlacementIsTheCornerOfThreePlanes) {
    Quadric q = Quadric::fromPlane(Vec3d(1, 0, 0), -1.0, 1.0);
    q += Quadric::fromPlane(Vec3d(0, 1, 0), -2.0, 1.0);
    q += Quadric::fromPlane(Vec3d(0, 0, 1), -3.0, 1.0);
    Vec3d p;
    ASSERT_TRUE(lodbake::solveQuadric(q, p));
    EXPECT_NEAR(p.x, 1.0, 1e-12);
    EXPECT_NEAR(p.y, 2.0, 1e-12);
    EXPECT_NEAR(p.z, 3.0, 1e-12);
    EXPECT_NEAR(q.evaluate(p), 0.0, 1e-12);
}

TEST(QuadricTest, IllConditionedSystemsAreRefused) {
    Vec3d p(9, 9, 9);
    const Quadric plane = Quadric::fromPlane(Vec3d(0, 0, 1), 0.0, 1.0);
    EXPECT_FALSE(lodbake::solveQuadric(plane, p));
    Quadric two = plane;
    two += Quadric::fromPlane(Vec3d(1, 0, 0), 0.0, 1.0);
    EXPECT_FALSE(lodbake::solveQuadric(two, p));
    // Three planes, two of them almost parallel: refused at the default conditioning.
    Quadric nearly = two;
    nearly += Quadric::fromPlane(lodbake::normalize(Vec3d(1, 1e-6, 0)), 0.0, 1.0);
    EXPECT_FALSE(lodbake::solveQuadric(nearly, p));
    EXPECT_EQ(p.x, 9.0); // untouched on failure
    EXPECT_FALSE(lodbake::solveQuadric(Quadric(), p));
}

TEST(QuadricTest, SegmentMinimumLiesOnThePlaneAndIsClamped) {
    const Quadric q = Quadric::fromPlane(Vec3d(0, 0, 1), 0.0, 1.0);
    const Vec3d m = lodbake::minimizeOnSegment(q, Vec3d(0, 0, -1), Vec3d(0, 0, 3));
    EXPECT_NEAR(m.z, 0.0, 1e-12);
    const Vec3d clamped = lodbake::minimizeOnSegment(q, Vec3d(0, 0, 1), Vec3d(0, 0, 3));
    EXPECT_NEAR(clamped.z, 1.0, 1e-12);
}

TEST(QuadricTest, AttributeQuadricReproducesALinearField) {
    // s = 2x + 3y + 1 sampled on two triangles of the plane z = 0.
    auto s = [](const Vec3d& p) { return 2 * p.x + 3 * p.y + 1; };
    const Vec3d a(0, 0, 0), b(1, 0, 0), c(1, 1, 0), d(0, 1, 0);
    AttributeQuadric aq;
    aq.addTriangle(a, b, c, s(a), s(b), s(c), 1.0);
    aq.addTriangle(a, c, d, s(a), s(c), s(d), 1.0);
    EXPECT_NEAR(aq.area, 1.0, 1e-12);
    const Vec3d p(0.3, 0.6, 0);
    EXPECT_NEAR(aq.optimalValue(p), s(p), 1e-12);
    Quadric q;
    aq.addTo(q);
    EXPECT_NEAR(q.evaluate(p), 0.0, 1e-12); // a consistent field costs nothing anywhere
}

TEST(QuadricTest, AttributeQuadricsOfDisagreeingFieldsAverageAndCost) {
    const Vec3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    AttributeQuadric zero, one;
    zero.addTriangle(a, b, c, 0, 0, 0, 1.0);
    one.addTriangle(a, b, c, 1, 1, 1, 1.0);
    AttributeQuadric both = zero;
    both += one;
    EXPECT_NEAR(both.optimalValue(Vec3d(0.2, 0.2, 0)), 0.5, 1e-12);
    Quadric q;
    both.addTo(q);
    // Σ a (s* − s_f)² = 0.5·0.25 + 0.5·0.25.
    EXPECT_NEAR(q.evaluate(Vec3d(0.2, 0.2, 0)), 0.25, 1e-12);
}

TEST(QuadricTest, AttributeBlockMatchesOneAttributeQuadricPerChannel) {
    // Three channels with different weights over random faces, split over two blocks that are
    // then combined: the packed block must give the error and optimal values of the per-channel
    // quadrics it replaces.
    constexpr size_t kChannels = 3;
    const float weight[kChannels] = {0.5f, 2.0f, 7.0f};
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coord(-1.0, 1.0);
    std::vector<double> block_a(lodbake::attributeBlockSize(kChannels), 0.0);
    std::vector<double> block_b(block_a.size(), 0.0);
    AttributeQuadric reference[kChannels];
    for (int f = 0; f < 20; ++f) {
        const Vec3d p0(coord(rng), coord(rng), coord(rng)), p1(coord(rng), coord(rng), coord(rng)),
            p2(coord(rng), coord(rng), coord(rng));
        float s[3][kChannels];
        for (auto& corner : s)
            for (float& value : corner) value = float(coord(rng));
        lodbake::addTriangleToAttributeBlock(f % 2 ? block_a.data() : block_b.data(), kChannels, p0, p1, p2, s[0],
                                             s[1], s[2], weight);
        for (size_t k = 0; k < kChannels; ++k) reference[k].addTriangle(p0, p1, p2, s[0][k], s[1][k], s[2][k], weight[k]);
    }
    Quadric expected, packed;
    for (const AttributeQuadric& aq : reference) aq.addTo(expected);
    lodbake::addAttributeBlockTo(block_a.data(), block_b.data(), kChannels, weight, packed);
    const Vec3d p(0.2, -0.3, 0.4);
    EXPECT_GT(expected.evaluate(p), 0.0);
    EXPECT_NEAR(packed.evaluate(p), expected.evaluate(p), 1e-9 * expected.evaluate(p));
    std::vector<double> sum = block_a;
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += block_b[i];
    for (size_t k = 0; k < kChannels; ++k) {
        const double value = reference[k].optimalValue(p);
        EXPECT_NEAR(lodbake::attributeBlockOptimalValue(block_a.data(), block_b.data(), k, p), value, 1e-12);
        // Adding first gives the same bits as the pair form (collapse() and its checks agree).
        EXPECT_EQ(lodbake::attributeBlockOptimalValue(sum.data(), nullptr, k, p),
                  lodbake::attributeBlockOptimalValue(block_a.data(), block_b.data(), k, p));
    }
}

TEST(CollapseQueueTest, PopsByCostThenById) {
    lodbake::detail::CollapseQueue q(10);
    q.set(5, 1.0f);
    q.set(3, 1.0f);
    q.set(7, 0.5f);
    q.set(1, 2.0f);
    EXPECT_EQ(q.pop(), 7u);
    EXPECT_EQ(q.pop(), 3u); // tie with 5: smaller id first
    EXPECT_EQ(q.pop(), 5u);
    EXPECT_EQ(q.pop(), 1u);
    EXPECT_TRUE(q.empty());
}

TEST(CollapseQueueTest, UpdateAndRemoveMatchAReferenceOrdering) {
    constexpr uint32_t kIds = 500;
    lodbake::detail::CollapseQueue q(kIds);
    std::set<std::pair<float, uint32_t>> reference;
    std::vector<float> cost(kIds, -1.0f);
    std::mt19937 rng(12345);
    for (int step = 0; step < 20000; ++step) {
        const uint32_t id = rng() % kIds;
        const int op = int(rng() % 4);
        if (op < 2) {
            const float c = float(rng() % 100); // many ties
            if (cost[id] >= 0) reference.erase({cost[id], id});
            cost[id] = c;
            reference.insert({c, id});
            q.set(id, c);
        } else if (op == 2) {
            if (cost[id] >= 0) reference.erase({cost[id], id});
            cost[id] = -1.0f;
            q.remove(id);
        } else if (!reference.empty()) {
            const auto top = *reference.begin();
            ASSERT_EQ(q.topId(), top.second);
            ASSERT_EQ(q.pop(), top.second);
            reference.erase(reference.begin());
            cost[top.second] = -1.0f;
        }
        ASSERT_EQ(q.size(), reference.size());
        if (reference.size() >= 2) {
            ASSERT_EQ(q.secondId(), std::next(reference.begin())->second); // the runner-up
        } else {
            ASSERT_EQ(q.secondId(), lodbake::detail::CollapseQueue::kAbsent);
        }
        if (step % 997 == 0) {
            ASSERT_TRUE(q.isConsistent());
        }
    }
    ASSERT_TRUE(q.isConsistent());
}

// A queue large enough for its arrays to take the huge-page path of LargeArray (2 MB-aligned
// mappings): bulk-built with heapify, it pops in (cost, id) order and its storage is aligned.
TEST(CollapseQueueTest, LargeHeapifiedQueuePopsInOrder) {
    constexpr uint32_t kIds = 400000; // slots: 3.2 MB
    lodbake::detail::CollapseQueue q(kIds);
    q.reserve(kIds);
    std::mt19937 rng(7);
    std::vector<float> cost(kIds);
    for (uint32_t id = 0; id < kIds; ++id) {
        cost[id] = float(rng() % 5000);
        q.pushUnordered(id, cost[id]);
    }
    q.heapify();
    ASSERT_TRUE(q.isConsistent());
    std::pair<float, uint32_t> previous{-1.0f, 0};
    for (uint32_t i = 0; i < kIds; ++i) {
        const uint32_t id = q.pop();
        const std::pair<float, uint32_t> current{cost[id], id};
        ASSERT_LT(previous, current);
        previous = current;
    }
    EXPECT_TRUE(q.empty());

    lodbake::detail::LargeArray<uint32_t> big(size_t(3) << 20, 7u); // 12 MB
#if defined(LODBAKE_LARGE_ARRAY_MMAP) // Linux, not an AddressSanitizer build
    EXPECT_EQ(reinterpret_cast<uintptr_t>(big.data()) % (size_t(2) << 20), 0u);
#endif
    big.push_back(9u); // grows into a new mapping
    EXPECT_EQ(big[0], 7u);
    EXPECT_EQ(big.back(), 9u);
    EXPECT_EQ(big.size(), (size_t(3) << 20) + 1);
}

} // namespace
