// NodeTransformTest: node hierarchies with TRS and matrix transforms in hand-built packs. Every LOD
// node exposes its world transform (composed through its parents); bad transforms and cyclic
// hierarchies are refused; non-uniform scales widen bounding spheres by the largest axis scale, and
// selection and culling of such instances stay conservative.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "glb_builder.h"
#include "lod_pack_builder.h"
#include "lodrt/frustum.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "lodrt/selection.h"

using lodrt::Result;

namespace {

// Two levels (meshes 0 and 1, positions in [-1, 1]^3) of a chain rooted at node 1, under a group
// node 0; level 1's node 2 hangs under node 3. `nodes` replaces the node array when not empty.
std::string packJson(const std::string& root_transform, const std::string& group_transform,
                     const std::string& holder_transform, const std::string& nodes = "") {
    lodrt_test::LodPackSpec spec;
    spec.errors = {0, 0.01};
    std::string json = lodrt_test::lodPackJson(spec);
    const size_t at = json.rfind(R"("nodes":[)");
    std::string n = nodes;
    if (n.empty())
        n = R"("nodes":[{"name":"group","children":[1,3])" + group_transform +
            R"(},{"name":"root","mesh":0,"extensions":{"MSFT_lod":{"ids":[2]}},)"
            R"("extras":{"MSFT_screencoverage":[0.5]})" + root_transform +
            R"(},{"name":"lod1","mesh":1},{"name":"holder","children":[2])" + holder_transform + "}]}";
    return json.substr(0, at) + n;
}

struct Loaded {
    std::vector<uint8_t> bytes;
    lodrt::Pack pack;
    lodrt::ModelSet models;
    Result result = Result::Ok;
    std::string message;
};

void load(const std::string& json, Loaded* out) {
    lodrt_test::LodPackSpec spec;
    spec.errors = {0, 0.01};
    out->bytes = lodrt_test::makeGlb(json, lodrt_test::lodPackBin(spec));
    char message[256] = "";
    out->result = lodrt::loadPack(out->bytes.data(), out->bytes.size(), nullptr, &out->pack, message, sizeof(message));
    if (out->result == Result::Ok)
        out->result = lodrt::buildModels(out->pack, nullptr, &out->models, message, sizeof(message));
    out->message = message;
}

void expectMatrix(const float* got, const std::vector<double>& want) {
    for (int k = 0; k < 16; ++k) EXPECT_NEAR(got[k], want[size_t(k)], 1e-5) << "element " << k;
}

} // namespace

TEST(NodeTransformTest, WorldTransformsComposeThroughParents) {
    Loaded l;
    load(packJson(R"(,"rotation":[0,0,0.70710678,0.70710678],"scale":[1,1,3])",
                  R"(,"translation":[10,0,0],"scale":[2,2,2])",
                  R"(,"matrix":[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,5,0,1])"),
         &l);
    ASSERT_EQ(l.result, Result::Ok) << l.message;
    ASSERT_EQ(l.models.modelCount(), 1u);
    const lodrt::ModelInfo& m = l.models.model(0);
    ASSERT_EQ(m.level_count, 2u);
    // Node 1: T(10,0,0) S(2) * R_z(90 degrees) S(1,1,3): x -> 2y, y -> -2x, z -> 6z.
    expectMatrix(l.models.modelLevel(0, 0).world_transform, {0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 6, 0, 10, 0, 0, 1});
    // Node 2 under node 3 under node 0: T(10,0,0) S(2) T(0,5,0).
    expectMatrix(l.models.modelLevel(0, 1).world_transform, {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 10, 10, 0, 1});
    expectMatrix(m.world_transform, {0, 2, 0, 0, -2, 0, 0, 0, 0, 0, 6, 0, 10, 0, 0, 1});
    EXPECT_FLOAT_EQ(m.max_axis_scale, 6.0f);
    EXPECT_FLOAT_EQ(m.world_sphere_radius, 6.0f * std::sqrt(3.0f));
    EXPECT_NEAR(m.world_sphere_center[0], 10.0f, 1e-5);
    EXPECT_NEAR(m.world_sphere_center[1], 0.0f, 1e-5);
    // The object-space bounds are unchanged.
    EXPECT_FLOAT_EQ(m.sphere_radius, std::sqrt(3.0f));
}

TEST(NodeTransformTest, NodesWithoutTransformsAreIdentity) {
    Loaded l;
    load(packJson("", "", ""), &l);
    ASSERT_EQ(l.result, Result::Ok) << l.message;
    expectMatrix(l.models.modelLevel(0, 1).world_transform, {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
    EXPECT_FLOAT_EQ(l.models.model(0).max_axis_scale, 1.0f);
    EXPECT_FLOAT_EQ(l.models.model(0).world_sphere_radius, l.models.model(0).sphere_radius);
}

TEST(NodeTransformTest, BadTransformsAreRefused) {
    struct Case {
        std::string root, message;
    };
    const std::vector<Case> cases = {
        {R"(,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1],"scale":[1,1,1])", "/nodes/1: expected either matrix"},
        {R"(,"matrix":[1,0,0,0,0,1,0,0,0,0,1,0,0,0,0])", "/nodes/1/matrix: expected 16 finite numbers"},
        {R"(,"matrix":[1,0,0,1,0,1,0,0,0,0,1,0,0,0,0,1])", "/nodes/1/matrix: expected an affine matrix"},
        {R"(,"rotation":[0,0,0,2])", "/nodes/1/rotation: expected a unit quaternion"},
        {R"(,"rotation":[0,0,1])", "/nodes/1/rotation: expected 4 finite numbers"},
        {R"(,"translation":[0,"x",0])", "/nodes/1/translation: expected 3 finite numbers"},
        {R"(,"scale":[1e39,1,1])", "/nodes/1/scale: expected 3 finite numbers"},
        {R"(,"scale":[1e30,1,1],"translation":[0,0,0])", ""}, // fine alone ...
    };
    for (const Case& c : cases) {
        Loaded l;
        load(packJson(c.root, "", ""), &l);
        if (c.message.empty()) {
            EXPECT_EQ(l.result, Result::Ok) << c.root << ": " << l.message;
            continue;
        }
        EXPECT_EQ(l.result, Result::BadGltf) << c.root;
        EXPECT_NE(l.message.find(c.message), std::string::npos) << l.message;
        EXPECT_EQ(l.models.modelCount(), 0u);
    }
    // ... but composed with a parent's huge scale it overflows a float.
    Loaded l;
    load(packJson(R"(,"scale":[1e30,1,1])", R"(,"scale":[1e30,1,1])", ""), &l);
    EXPECT_EQ(l.result, Result::BadGltf);
    EXPECT_NE(l.message.find("world transform overflows"), std::string::npos) << l.message;
}

TEST(NodeTransformTest, CyclicHierarchiesAreRefused) {
    Loaded l;
    load(packJson("", "", "",
                  R"("nodes":[{"name":"a","children":[1]},{"name":"root","mesh":0,"children":[3],)"
                  R"("extensions":{"MSFT_lod":{"ids":[2]}}},{"name":"lod1","mesh":1},{"name":"b","children":[0]}]})"),
         &l);
    EXPECT_EQ(l.result, Result::BadGltf);
    EXPECT_NE(l.message.find("cycle"), std::string::npos) << l.message;
}

TEST(NodeTransformTest, NonUniformScaleWidensSpheresByTheLargestAxis) {
    // Stretched 10x along z: the unit sphere becomes radius 10 (a lower bound would miss the ends).
    const float m[16] = {1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 10, 0, 5, 0, 0, 1};
    EXPECT_FLOAT_EQ(lodrt::maxAxisScale(m), 10.0f);
    const float c[3] = {0, 0, 1};
    float wc[3], wr = 0;
    lodrt::transformSphere(m, c, 1.0f, wc, &wr);
    EXPECT_FLOAT_EQ(wr, 10.0f);
    EXPECT_FLOAT_EQ(wc[0], 5.0f);
    EXPECT_FLOAT_EQ(wc[2], 10.0f);
    // Culling: a frustum whose near plane is z >= 15 sees the stretched model's tip (z up to 20).
    lodrt::Frustum f;
    for (int p = 0; p < 6; ++p) f.planes[p][3] = 100;
    f.planes[4][2] = 1;
    f.planes[4][3] = -15;
    EXPECT_EQ(lodrt::classifySphere(f, wc, wr), lodrt::Containment::Intersecting);
    EXPECT_EQ(lodrt::classifySphere(f, wc, 1.0f), lodrt::Containment::Outside); // the unscaled radius would cull it
    // Composition helper: (A * B) applied equals A applied to B applied.
    const float a[16] = {0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1};
    float ab[16];
    lodrt::multiplyTransforms(a, m, ab);
    float via[3], r1 = 0, tmp[3], direct[3], r2 = 0;
    lodrt::transformSphere(m, c, 1.0f, tmp, &r1);
    lodrt::transformSphere(a, tmp, r1, via, &r1);
    lodrt::transformSphere(ab, c, 1.0f, direct, &r2);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(via[k], direct[k], 1e-5);
    EXPECT_FLOAT_EQ(r1, r2);
}

TEST(NodeTransformTest, SelectionUsesTheLargestAxisScale) {
    Loaded l;
    load(packJson(R"(,"scale":[1,1,4])", "", ""), &l);
    ASSERT_EQ(l.result, Result::Ok) << l.message;
    const lodrt::ModelInfo& info = l.models.model(0);
    lodrt::LodTable table;
    lodrt::SelectionParams params;
    ASSERT_EQ(table.prepare(l.models, params, nullptr), Result::Ok);
    // An instance of the model at the pack's placement, moved along x: its error grows 4x along
    // z, so the coarse level is accepted only 4x farther away than for the unscaled model.
    const float accept = table.acceptDistance(0, 1);
    ASSERT_GT(accept, 0.0f);
    ASSERT_TRUE(std::isfinite(accept));
    const float eye[3] = {0, 0, 0};
    for (float model_units : {accept * 0.5f, accept * 2.0f, accept * 3.9f, accept * 4.5f}) {
        float cx = 0, r = 0, c[3];
        lodrt::transformSphere(info.world_transform, info.sphere_center, info.sphere_radius, c, &r);
        cx = r + model_units + 1e-3f; // distance to the sphere surface: model_units
        const float cy = 0, cz = 0, scale = info.max_axis_scale;
        const uint32_t model = 0;
        lodrt::InstanceArrays in;
        in.center_x = &cx;
        in.center_y = &cy;
        in.center_z = &cz;
        in.radius = &r;
        in.scale = &scale;
        in.model = &model;
        in.count = 1;
        uint8_t level = lodrt::kNoLevel;
        lodrt::SelectionOutput out;
        out.level = &level;
        lodrt::selectLevels(table, eye, in, nullptr, nullptr, out);
        // World distance d, model-unit distance d / 4: level 1 only once d / 4 passes accept.
        EXPECT_EQ(level, model_units / 4.0f > accept ? 1 : 0) << model_units / accept;
    }
}
