#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "lodbake/cleanup/passes.h"
#include "lodbake/cleanup/validate.h"

using namespace lodbake;
using namespace lodbake_test;

namespace {
Mesh sphereWithSpeckle() {
    Mesh m = uvSphere(10, 16); // 288 faces
    for (int i = 0; i < 3; ++i) {
        Mesh t = singleTriangle();
        for (auto& p : t.positions) p = p * 0.01f + Vec3f(3.0f + i, 0, 0);
        appendMesh(m, t);
    }
    Mesh big = strip(40); // 80 faces, area 40: larger than the sphere (~12.5)
    for (auto& p : big.positions) p.z += 10;
    appendMesh(m, big);
    return m;
}
} // namespace

TEST(ComponentsTest, RemovesByFaceCount) {
    Mesh m = sphereWithSpeckle();
    ComponentOptions o;
    o.min_face_count = 50;
    o.min_area_fraction = 0;
    const ComponentReport r = removeSmallComponents(m, o);
    EXPECT_EQ(r.components_before, 5u);
    EXPECT_EQ(r.components_removed, 3u);
    EXPECT_EQ(r.faces_removed, 3u);
    EXPECT_EQ(m.faceCount(), 288u + 80u);
}

TEST(ComponentsTest, RemovesByAreaFraction) {
    Mesh m = sphereWithSpeckle();
    ComponentOptions o;
    o.min_face_count = 0;
    o.min_area_fraction = 0.5; // the sphere is ~24% of the area, the strip ~76%
    const ComponentReport r = removeSmallComponents(m, o);
    EXPECT_EQ(r.components_removed, 4u);
    EXPECT_EQ(m.faceCount(), 80u);
}

TEST(ComponentsTest, AlwaysKeepsLargest) {
    Mesh m = singleTriangle();
    ComponentOptions o;
    o.min_face_count = 1000;
    EXPECT_EQ(removeSmallComponents(m, o).components_removed, 0u);
    EXPECT_EQ(m.faceCount(), 1u);
}

TEST(ComponentsTest, EmptyMesh) {
    Mesh m;
    EXPECT_EQ(removeSmallComponents(m).components_before, 0u);
}
