#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "lodrt/frustum.h"

using lodrt::ClipDepth;
using lodrt::Containment;
using lodrt::Frustum;

namespace {

// Column-major perspective, fov 90 degrees, aspect 1, near 1, far 100, camera at the origin looking down -z.
void perspective(ClipDepth depth, float m[16]) {
    const float n = 1, f = 100;
    for (int i = 0; i < 16; ++i) m[i] = 0;
    m[0] = 1;
    m[5] = 1;
    m[11] = -1;
    if (depth == ClipDepth::NegativeOneToOne) {
        m[10] = -(f + n) / (f - n);
        m[14] = -2 * f * n / (f - n);
    } else {
        m[10] = f / (n - f);
        m[14] = f * n / (n - f);
    }
}

// The planes worked out by hand for that frustum (left, right, bottom, top, near, far).
const float kExpected[6][4] = {
    {float(M_SQRT1_2), 0, -float(M_SQRT1_2), 0},
    {-float(M_SQRT1_2), 0, -float(M_SQRT1_2), 0},
    {0, float(M_SQRT1_2), -float(M_SQRT1_2), 0},
    {0, -float(M_SQRT1_2), -float(M_SQRT1_2), 0},
    {0, 0, -1, -1},
    {0, 0, 1, 100},
};

Frustum frustumFor(ClipDepth depth) {
    float m[16];
    perspective(depth, m);
    Frustum f;
    EXPECT_TRUE(lodrt::extractFrustum(m, depth, &f));
    return f;
}

} // namespace

TEST(FrustumTest, ExtractsOpenGlPlanes) {
    const Frustum f = frustumFor(ClipDepth::NegativeOneToOne);
    for (int p = 0; p < 6; ++p)
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(f.planes[p][c], kExpected[p][c], 1e-5 * (1 + std::fabs(kExpected[p][c]))) << p << " " << c;
}

TEST(FrustumTest, ExtractsVulkanPlanes) {
    const Frustum f = frustumFor(ClipDepth::ZeroToOne);
    for (int p = 0; p < 6; ++p)
        for (int c = 0; c < 4; ++c)
            EXPECT_NEAR(f.planes[p][c], kExpected[p][c], 1e-5 * (1 + std::fabs(kExpected[p][c]))) << p << " " << c;
}

TEST(FrustumTest, WrongConventionMovesTheNearPlane) {
    // An OpenGL matrix read as 0..1 depth puts the near plane at the wrong distance.
    float m[16];
    perspective(ClipDepth::NegativeOneToOne, m);
    Frustum f;
    ASSERT_TRUE(lodrt::extractFrustum(m, ClipDepth::ZeroToOne, &f));
    EXPECT_GT(std::fabs(f.planes[4][3] - kExpected[4][3]), 0.1f);
}

TEST(FrustumTest, RejectsDegenerateMatrix) {
    float zero[16] = {};
    Frustum f;
    f.planes[0][0] = 42;
    EXPECT_FALSE(lodrt::extractFrustum(zero, ClipDepth::ZeroToOne, &f));
    EXPECT_EQ(f.planes[0][0], 42); // unchanged
    float m[16];
    perspective(ClipDepth::ZeroToOne, m);
    m[0] = NAN;
    EXPECT_FALSE(lodrt::extractFrustum(m, ClipDepth::ZeroToOne, &f));
}

TEST(FrustumTest, ClassifiesSpheres) {
    const Frustum f = frustumFor(ClipDepth::NegativeOneToOne);
    struct Case {
        float c[3], r;
        Containment expected;
    } cases[] = {
        {{0, 0, -50}, 1, Containment::Inside},         {{0, 0, 10}, 1, Containment::Outside},
        {{0, 0, -1}, 0.5f, Containment::Intersecting}, {{0, 0, -100}, 0.5f, Containment::Intersecting},
        {{0, 0, -101}, 0.5f, Containment::Outside},    {{-60, 0, -50}, 5, Containment::Outside},
        {{-50, 0, -50}, 1, Containment::Intersecting}, {{0, 49, -50}, 0.5f, Containment::Inside},
        {{0, 0, -50}, 200, Containment::Intersecting}, {{0, 0, -0.5f}, 0.49f, Containment::Outside},
    };
    for (const Case& c : cases) EXPECT_EQ(lodrt::classifySphere(f, c.c, c.r), c.expected) << c.c[0] << " " << c.c[2];
}

TEST(FrustumTest, ClassifiesBoxes) {
    const Frustum f = frustumFor(ClipDepth::ZeroToOne);
    struct Case {
        float lo[3], hi[3];
        Containment expected;
    } cases[] = {
        {{-1, -1, -51}, {1, 1, -49}, Containment::Inside},
        {{-1, -1, 1}, {1, 1, 3}, Containment::Outside},
        {{-1, -1, -2}, {1, 1, 0}, Containment::Intersecting},
        {{60, -1, -51}, {61, 1, -49}, Containment::Outside},
        {{49, -1, -51}, {51, 1, -49}, Containment::Intersecting},
        {{-1000, -1000, -1000}, {1000, 1000, 1000}, Containment::Intersecting},
        {{-1, -1, -102}, {1, 1, -101}, Containment::Outside},
    };
    for (const Case& c : cases) EXPECT_EQ(lodrt::classifyBox(f, c.lo, c.hi), c.expected) << c.lo[0] << " " << c.lo[2];
}

TEST(FrustumTest, BatchMatchesSingleTests) {
    const Frustum f = frustumFor(ClipDepth::ZeroToOne);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> pos(-120, 120), rad(0, 10);
    const size_t n = 1003;
    std::vector<float> x(n), y(n), z(n), r(n), lx(n), ly(n), lz(n), hx(n), hy(n), hz(n);
    for (size_t i = 0; i < n; ++i) {
        x[i] = pos(rng), y[i] = pos(rng), z[i] = pos(rng), r[i] = rad(rng);
        lx[i] = x[i] - r[i], ly[i] = y[i] - r[i], lz[i] = z[i] - r[i];
        hx[i] = x[i] + r[i], hy[i] = y[i] + r[i], hz[i] = z[i] + r[i];
    }
    std::vector<Containment> spheres(n), boxes(n);
    const size_t vs = lodrt::classifySpheres(f, x.data(), y.data(), z.data(), r.data(), n, spheres.data());
    const size_t vb =
        lodrt::classifyBoxes(f, lx.data(), ly.data(), lz.data(), hx.data(), hy.data(), hz.data(), n, boxes.data());
    size_t expect_s = 0, expect_b = 0, inside = 0, outside = 0;
    for (size_t i = 0; i < n; ++i) {
        const float c[3] = {x[i], y[i], z[i]}, lo[3] = {lx[i], ly[i], lz[i]}, hi[3] = {hx[i], hy[i], hz[i]};
        EXPECT_EQ(spheres[i], lodrt::classifySphere(f, c, r[i])) << i;
        EXPECT_EQ(boxes[i], lodrt::classifyBox(f, lo, hi)) << i;
        expect_s += spheres[i] != Containment::Outside;
        expect_b += boxes[i] != Containment::Outside;
        inside += spheres[i] == Containment::Inside;
        outside += spheres[i] == Containment::Outside;
    }
    EXPECT_EQ(vs, expect_s);
    EXPECT_EQ(vb, expect_b);
    EXPECT_GT(inside, 10u); // the random scene exercises every outcome
    EXPECT_GT(outside, 10u);
}

TEST(FrustumTest, BvhCullMatchesFlatCull) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> pos(-300, 300), rad(0.1f, 3);
    const size_t n = 5000;
    std::vector<float> x(n), y(n), z(n), r(n);
    for (size_t i = 0; i < n; ++i) x[i] = pos(rng), y[i] = pos(rng) * 0.1f, z[i] = pos(rng), r[i] = rad(rng);
    lodrt::InstanceBvh bvh;
    ASSERT_EQ(bvh.build(x.data(), y.data(), z.data(), r.data(), n, nullptr), lodrt::Result::Ok);
    EXPECT_GT(bvh.nodeCount(), 2u * (n / lodrt::InstanceBvh::kLeafSize) - 2);
    for (ClipDepth depth : {ClipDepth::NegativeOneToOne, ClipDepth::ZeroToOne}) {
        const Frustum f = frustumFor(depth);
        std::vector<Containment> flat(n), tree(n);
        const size_t a = lodrt::classifySpheres(f, x.data(), y.data(), z.data(), r.data(), n, flat.data());
        const size_t b = bvh.cull(f, tree.data());
        EXPECT_EQ(a, b);
        for (size_t i = 0; i < n; ++i) {
            // A group accepted whole is Inside for each member; a member's own test agrees then.
            EXPECT_EQ(flat[i] == Containment::Outside, tree[i] == Containment::Outside) << i;
            if (tree[i] == Containment::Inside) {
                EXPECT_EQ(flat[i], Containment::Inside) << i;
            }
        }
    }
    float bad = NAN;
    lodrt::InstanceBvh broken;
    EXPECT_EQ(broken.build(&bad, &bad, &bad, &bad, 1, nullptr), lodrt::Result::InvalidArgument);
}
