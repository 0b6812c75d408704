// PFRep per-instance refinement (lodrt/pfrep_instance.h). Lives in lodbake_tests because the blob
// is built with the baker's PFRep builder; the code under test is runtime code only.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lodbake/pfrep/pfrep_builder.h"
#include "lodrt/frustum.h"
#include "lodrt/pfrep_instance.h"
#include "mesh_builders.h"

namespace {

struct Blob {
    std::vector<uint8_t> bytes;
    lodrt::PfrepModel model;
};

// A 40 x 40 wavy height field, simplified down to 2% of its triangles.
const Blob& blob() {
    static Blob* b = [] {
        Blob* out = new Blob();
        const lodbake::Mesh mesh = lodbake_test::wavyField(40, 0.05f, 0.5f, 0.4f);
        lodbake::PfrepOptions options;
        options.target_ratio = 0.02f;
        lodbake::Diagnostics diagnostics;
        auto build = lodbake::buildPfrep(mesh, options, diagnostics);
        EXPECT_TRUE(build.ok());
        out->bytes = build.value().blob;
        EXPECT_EQ(lodrt::openPfrep(out->bytes.data(), out->bytes.size(), &out->model), lodrt::Result::Ok);
        return out;
    }();
    return *b;
}

// Frustum of a camera at `eye` looking down -z with a 90 degree fov (planes built directly).
lodrt::Frustum frustumAt(const float eye[3]) {
    lodrt::Frustum f;
    const float h = float(M_SQRT1_2);
    const float normals[6][3] = {{h, 0, -h}, {-h, 0, -h}, {0, h, -h}, {0, -h, -h}, {0, 0, -1}, {0, 0, 1}};
    const float offsets[6] = {0, 0, 0, 0, -0.01f, 100};
    for (int p = 0; p < 6; ++p) {
        for (int k = 0; k < 3; ++k) f.planes[p][k] = normals[p][k];
        f.planes[p][3] = offsets[p] - (normals[p][0] * eye[0] + normals[p][1] * eye[1] + normals[p][2] * eye[2]);
    }
    return f;
}

size_t settle(const lodrt::PfrepModel& model, const lodrt::PfrepView& view, std::vector<uint8_t>* mask,
              std::vector<uint32_t>* indices) {
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(model));
    size_t triangles = 0, changes = 1;
    for (int step = 0; step < 50 && changes > 0; ++step)
        EXPECT_EQ(lodrt::pfrepUpdateInstance(model, view, mask->data(), scratch.data(), scratch.size(), indices->data(),
                                             indices->size() / 3, &triangles, &changes),
                  lodrt::Result::Ok);
    EXPECT_EQ(changes, 0u); // converged
    return triangles;
}

} // namespace

TEST(PfrepInstanceTest, PlacedInstanceRefinesLikeModelSpaceCamera) {
    const lodrt::PfrepModel& model = blob().model;
    // World camera 3 units in front of an instance moved to (10, 5, -20) and scaled by 4.
    lodrt::InstancePlacement placement;
    placement.translation[0] = 10;
    placement.translation[1] = 5;
    placement.translation[2] = -20;
    placement.scale = 4;
    const float world_eye[3] = {12, 7, -17};
    lodrt::PfrepView world_view;
    ASSERT_EQ(lodrt::pfrepInstanceView(frustumAt(world_eye), world_eye, placement, 1000, 1, 0.5f, &world_view),
              lodrt::Result::Ok);
    // The same camera expressed in model space directly: eye (0.5, 0.5, 0.75).
    const float model_eye[3] = {0.5f, 0.5f, 0.75f};
    lodrt::PfrepView model_view;
    ASSERT_EQ(lodrt::pfrepInstanceView(frustumAt(model_eye), model_eye, lodrt::InstancePlacement(), 1000, 1, 0.5f,
                                       &model_view),
              lodrt::Result::Ok);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(world_view.eye[k], model_eye[k], 1e-5);
    // Side planes pass through the eye in both spaces; near and far keep their world distances
    // (0.01 and 100 world units are 0.0025 and 25 model units), far from the mesh either way.
    for (int p = 0; p < 4; ++p) EXPECT_NEAR(world_view.planes[p][3], model_view.planes[p][3], 1e-4) << p;
    EXPECT_NEAR(world_view.planes[4][3], model_view.planes[4][3] + 0.0075f, 1e-4);

    std::vector<uint8_t> a(lodrt::pfrepMaskBytes(model)), b(a.size());
    lodrt::pfrepMaskCoarsest(model, a.data());
    lodrt::pfrepMaskCoarsest(model, b.data());
    std::vector<uint32_t> ia(3 * lodrt::pfrepMaxTriangles(model)), ib(ia.size());
    const size_t ta = settle(model, world_view, &a, &ia);
    const size_t tb = settle(model, model_view, &b, &ib);
    EXPECT_EQ(ta, tb);
    EXPECT_EQ(a, b); // the |V|-bit mask is the whole per-instance state
}

// A general transform: uniform scale + translation as a matrix gives the placement's view; a rotation
// about z moves the eye with it; a non-uniform scale raises pixels per unit by max / min axis scale.
TEST(PfrepInstanceTest, TransformViewMatchesPlacementAndHandlesNonUniformScale) {
    const float world_eye[3] = {12, 7, -17};
    lodrt::InstancePlacement placement;
    placement.translation[0] = 10;
    placement.translation[1] = 5;
    placement.translation[2] = -20;
    placement.scale = 4;
    lodrt::PfrepView by_placement, by_matrix;
    ASSERT_EQ(lodrt::pfrepInstanceView(frustumAt(world_eye), world_eye, placement, 1000, 1, 0.5f, &by_placement),
              lodrt::Result::Ok);
    const float uniform[16] = {4, 0, 0, 0, 0, 4, 0, 0, 0, 0, 4, 0, 10, 5, -20, 1};
    ASSERT_EQ(lodrt::pfrepInstanceViewTransform(frustumAt(world_eye), world_eye, uniform, 1000, 1, 0.5f, &by_matrix),
              lodrt::Result::Ok);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(by_matrix.eye[k], by_placement.eye[k], 1e-5);
    for (int p = 0; p < 6; ++p)
        for (int k = 0; k < 4; ++k) EXPECT_NEAR(by_matrix.planes[p][k], by_placement.planes[p][k], 1e-4) << p << " " << k;
    EXPECT_FLOAT_EQ(by_matrix.pixels_per_unit_at_distance_one, 1000.0f);
    // Rotation by 90 degrees about z, scaled (1, 2, 8): world (x, y, z) = (-2 y_m, x_m, 8 z_m).
    const float rotated[16] = {0, 1, 0, 0, -2, 0, 0, 0, 0, 0, 8, 0, 0, 0, 0, 1};
    const float eye[3] = {-4, 3, 16};
    lodrt::PfrepView v;
    ASSERT_EQ(lodrt::pfrepInstanceViewTransform(frustumAt(eye), eye, rotated, 1000, 1, 0.5f, &v), lodrt::Result::Ok);
    EXPECT_NEAR(v.eye[0], 3.0f, 1e-5);
    EXPECT_NEAR(v.eye[1], 2.0f, 1e-5);
    EXPECT_NEAR(v.eye[2], 2.0f, 1e-5);
    EXPECT_NEAR(v.pixels_per_unit_at_distance_one, 8000.0f, 1e-2);
    for (int p = 0; p < 6; ++p) {
        const float len = std::sqrt(v.planes[p][0] * v.planes[p][0] + v.planes[p][1] * v.planes[p][1] +
                                    v.planes[p][2] * v.planes[p][2]);
        EXPECT_NEAR(len, 1.0f, 1e-5);
        // Side planes pass through the eye in model space too.
        if (p < 4) {
            EXPECT_NEAR(v.planes[p][0] * v.eye[0] + v.planes[p][1] * v.eye[1] + v.planes[p][2] * v.eye[2] + v.planes[p][3],
                        0.0f, 1e-4);
        }
    }
    const float singular[16] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    EXPECT_EQ(lodrt::pfrepInstanceViewTransform(frustumAt(eye), eye, singular, 1000, 1, 0.5f, &v),
              lodrt::Result::InvalidArgument);
    const float projective[16] = {1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    EXPECT_EQ(lodrt::pfrepInstanceViewTransform(frustumAt(eye), eye, projective, 1000, 1, 0.5f, &v),
              lodrt::Result::InvalidArgument);
}

TEST(PfrepInstanceTest, FarInstanceKeepsFewerTriangles) {
    const lodrt::PfrepModel& model = blob().model;
    std::vector<uint32_t> indices(3 * lodrt::pfrepMaxTriangles(model));
    size_t tris[2];
    const float distances[2] = {0.5f, 40.0f};
    for (int i = 0; i < 2; ++i) {
        const float eye[3] = {0.5f, 0.5f, distances[i]};
        lodrt::PfrepView view;
        ASSERT_EQ(lodrt::pfrepInstanceView(frustumAt(eye), eye, lodrt::InstancePlacement(), 1000, 0.5f, 0.5f, &view),
                  lodrt::Result::Ok);
        std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(model));
        lodrt::pfrepMaskCoarsest(model, mask.data());
        tris[i] = settle(model, view, &mask, &indices);
        for (size_t k = 0; k < 3 * tris[i]; ++k) ASSERT_LT(indices[k], model.vertex_count);
    }
    EXPECT_GT(tris[0], 2 * tris[1]) << tris[0] << " vs " << tris[1];
    EXPECT_LE(tris[0], lodrt::pfrepMaxTriangles(model));
}

TEST(PfrepInstanceTest, RejectsBadPlacementAndSmallBuffers) {
    const lodrt::PfrepModel& model = blob().model;
    const float eye[3] = {0.5f, 0.5f, 0.5f};
    lodrt::PfrepView view;
    lodrt::InstancePlacement placement;
    placement.scale = 0;
    EXPECT_EQ(lodrt::pfrepInstanceView(frustumAt(eye), eye, placement, 1000, 1, 0.5f, &view),
              lodrt::Result::InvalidArgument);
    placement.scale = 1;
    ASSERT_EQ(lodrt::pfrepInstanceView(frustumAt(eye), eye, placement, 1000, 1, 0.5f, &view), lodrt::Result::Ok);
    std::vector<uint8_t> mask(lodrt::pfrepMaskBytes(model));
    lodrt::pfrepMaskFinest(model, mask.data());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(model)), indices(3);
    size_t triangles = 0;
    EXPECT_EQ(lodrt::pfrepUpdateInstance(model, view, mask.data(), scratch.data(), scratch.size(), indices.data(), 1,
                                         &triangles, nullptr),
              lodrt::Result::BufferTooSmall);
}
