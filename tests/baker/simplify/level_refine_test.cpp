// detail::refineLevelPositions: the late levels' vertex refinement moves interior vertices towards
// the input, but never turns a face further than the collapses' normal bound.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "lodbake/core/mesh.h"
#include "simplify/level_refine.h"

namespace {

using lodbake::Mesh;
using lodbake::Vec3d;
using lodbake::Vec3f;

// A four-face tent: corners on the square's open border (fixed), apex in the middle.
Mesh tent(float apex_z) {
    Mesh m;
    m.positions = {Vec3f(0, 0, apex_z), Vec3f(1, -1, 0), Vec3f(1, 1, 0), Vec3f(-1, 1, 0), Vec3f(-1, -1, 0)};
    m.indices = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 1};
    return m;
}

// A flat 5 x 5 grid of input points at height z under the tent: they pull the apex straight down.
Mesh floorAt(float z) {
    Mesh m;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 5; ++i) m.positions.push_back(Vec3f(-0.8f + 0.4f * float(i), -0.8f + 0.4f * float(j), z));
    for (uint32_t j = 0; j < 4; ++j)
        for (uint32_t i = 0; i < 4; ++i) {
            const uint32_t a = j * 5 + i;
            m.indices.insert(m.indices.end(), {a, a + 1, a + 6, a, a + 6, a + 5});
        }
    return m;
}

double largestTurnDeg(const Mesh& before, const Mesh& after) {
    double worst = 0.0;
    for (size_t f = 0; f < before.faceCount(); ++f) {
        auto normal = [&](const Mesh& m) {
            const Vec3d a(m.positions[m.indices[f * 3]]), b(m.positions[m.indices[f * 3 + 1]]),
                c(m.positions[m.indices[f * 3 + 2]]);
            return cross(b - a, c - a);
        };
        const Vec3d n0 = normal(before), n1 = normal(after);
        const double c = dot(n0, n1) / std::sqrt(dot(n0, n0) * dot(n1, n1));
        worst = std::max(worst, std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / 3.14159265358979323846);
    }
    return worst;
}

TEST(LevelRefineTest, MovesTowardsTheInputWithinTheBound) {
    // A nearby input: the apex moves down towards it, the faces turn a little.
    const Mesh near_input = floorAt(-0.2f);
    Mesh level = tent(0.1f);
    const Mesh before = level;
    lodbake::detail::refineLevelPositions(near_input, level, 75.0f);
    EXPECT_LT(level.positions[0][2], 0.1f);
    for (int v = 1; v < 5; ++v) EXPECT_EQ(level.positions[v], before.positions[v]); // border corners stay
    EXPECT_LE(largestTurnDeg(before, level), 75.0);
}

TEST(LevelRefineTest, NoFaceTurnsBeyondTheBound) {
    // An input far below: unbounded steps pull the apex about 3.3 units down and turn a face by about
    // 86 degrees (measured with the bound switched off); with it the faces stay within 75.
    const Mesh far_input = floorAt(-6.0f);
    Mesh level = tent(0.1f);
    const Mesh before = level;
    lodbake::detail::refineLevelPositions(far_input, level, 75.0f);
    EXPECT_LE(largestTurnDeg(before, level), 75.0);
    // With a bound of 90 degrees (no flip allowed) the same faces may turn further, never over.
    Mesh loose = tent(0.1f);
    lodbake::detail::refineLevelPositions(far_input, loose, 89.0f);
    EXPECT_LE(largestTurnDeg(before, loose), 89.0);
}

TEST(LevelRefineTest, TexturedFacesKeepTheirAreaWithinAFactor) {
    // A steep tent over a floor: a step pulls the apex about halfway down, which turns the faces by
    // about 18 degrees but shrinks them to 0.79 of their area. Without UVs the apex moves; with UVs
    // (whose texture that squeeze would stretch) it stays.
    const Mesh floor = floorAt(0.0f);
    Mesh plain = tent(1.0f);
    lodbake::detail::refineLevelPositions(floor, plain, 75.0f);
    EXPECT_LT(plain.positions[0][2], 0.9f);
    Mesh textured = tent(1.0f);
    textured.uvs.push_back({{0.5f, 0.5f}, {1, 0}, {1, 1}, {0, 1}, {0, 0}});
    const Mesh before = textured;
    lodbake::detail::refineLevelPositions(floor, textured, 75.0f);
    for (size_t f = 0; f < before.faceCount(); ++f) {
        auto area2 = [&](const Mesh& m) {
            const Vec3d a(m.positions[m.indices[f * 3]]), b(m.positions[m.indices[f * 3 + 1]]),
                c(m.positions[m.indices[f * 3 + 2]]);
            const Vec3d n = cross(b - a, c - a);
            return dot(n, n);
        };
        const double ratio = std::sqrt(area2(textured) / area2(before));
        EXPECT_GE(ratio, 0.8 - 1e-9) << "face " << f;
        EXPECT_LE(ratio, 1.25 + 1e-9) << "face " << f;
    }
}

} // namespace
