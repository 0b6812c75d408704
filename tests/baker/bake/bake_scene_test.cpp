// glTF scenes kept as graphs (docs/bake.md "Scenes"): a scene of two meshes, one rotated and
// translated under a parent, the other instanced twice, reads as a graph (meshes once, nodes with
// their names and transforms) and bakes into one LOD group per mesh node with the input's nodes,
// names and transforms, clean for the Khronos validator, loddump and lodrt; --merge-scene gives the
// single merged group of other inputs.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../gltf/gltf_test_util.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/gltf.h"
#include "lodbake/io/mesh_io.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;
using nlohmann::json;

constexpr double kPi = 3.14159265358979323846;

std::string outDir() {
    const std::string dir = lodbake_test::scratchDir() + "/bake_scene";
    fs::create_directories(dir);
    return dir;
}

std::vector<uint8_t> bytesOf(const std::string& path) {
    auto r = lodbake::readFileBytes(path);
    return r.ok() ? *r : std::vector<uint8_t>();
}

// A closed torus grid (major radius big_r, minor small_r), float positions and uint32 indices.
struct Grid {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
};

Grid torus(float big_r, float small_r, uint32_t nu, uint32_t nv) {
    Grid g;
    for (uint32_t u = 0; u < nu; ++u)
        for (uint32_t v = 0; v < nv; ++v) {
            const double a = 2 * kPi * u / nu, b = 2 * kPi * v / nv;
            g.positions.push_back(float((big_r + small_r * std::cos(b)) * std::cos(a)));
            g.positions.push_back(float(small_r * std::sin(b)));
            g.positions.push_back(float((big_r + small_r * std::cos(b)) * std::sin(a)));
        }
    for (uint32_t u = 0; u < nu; ++u)
        for (uint32_t v = 0; v < nv; ++v) {
            const uint32_t a = u * nv + v, b = ((u + 1) % nu) * nv + v;
            const uint32_t c = ((u + 1) % nu) * nv + (v + 1) % nv, d = u * nv + (v + 1) % nv;
            g.indices.insert(g.indices.end(), {a, d, c, a, c, b});
        }
    return g;
}

// Appends a mesh (POSITION + indices accessors, one primitive with `material`) to doc and bin.
void addMesh(json& doc, std::vector<uint8_t>& bin, const std::string& name, const Grid& g, int material) {
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (size_t i = 0; i < g.positions.size(); ++i) {
        lo[i % 3] = std::min(lo[i % 3], g.positions[i]);
        hi[i % 3] = std::max(hi[i % 3], g.positions[i]);
    }
    const size_t p = lodbake_test::appendValues(bin, g.positions);
    const size_t i = lodbake_test::appendValues(bin, g.indices);
    const size_t views = doc["bufferViews"].size(), accessors = doc["accessors"].size();
    doc["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", p}, {"byteLength", g.positions.size() * 4}, {"target", 34962}});
    doc["bufferViews"].push_back(
        {{"buffer", 0}, {"byteOffset", i}, {"byteLength", g.indices.size() * 4}, {"target", 34963}});
    doc["accessors"].push_back({{"bufferView", views},
                                {"componentType", 5126},
                                {"count", g.positions.size() / 3},
                                {"type", "VEC3"},
                                {"min", {lo[0], lo[1], lo[2]}},
                                {"max", {hi[0], hi[1], hi[2]}}});
    doc["accessors"].push_back(
        {{"bufferView", views + 1}, {"componentType", 5125}, {"count", g.indices.size()}, {"type", "SCALAR"}});
    doc["meshes"].push_back(
        {{"name", name},
         {"primitives",
          {{{"attributes", {{"POSITION", accessors}}}, {"indices", accessors + 1}, {"material", material}}}}});
}

// Root (translated) -> Ring (mesh 0, rotated 45 degrees about y and translated) and PostA (mesh 1);
// PostB (mesh 1 again, a matrix) is a second root; Orphan is in no scene and is dropped.
json sceneJson(std::vector<uint8_t>& bin) {
    json doc = {{"asset", {{"version", "2.0"}}},
                {"bufferViews", json::array()},
                {"accessors", json::array()},
                {"meshes", json::array()}};
    addMesh(doc, bin, "RingMesh", torus(1.0f, 0.3f, 48, 24), 0);
    addMesh(doc, bin, "PostMesh", torus(0.6f, 0.4f, 40, 20), 1);
    doc["materials"] = {{{"name", "Red"}, {"pbrMetallicRoughness", {{"baseColorFactor", {1.0, 0.0, 0.0, 1.0}}}}},
                        {{"name", "Blue"}, {"pbrMetallicRoughness", {{"baseColorFactor", {0.0, 0.0, 1.0, 1.0}}}}}};
    const double s = std::sin(kPi / 8), c = std::cos(kPi / 8);
    doc["nodes"] = {{{"name", "Root"}, {"translation", {0.0, 1.0, 0.0}}, {"children", {1, 2}}},
                    {{"name", "Ring"}, {"mesh", 0}, {"rotation", {0.0, s, 0.0, c}}, {"translation", {1.5, 0.0, -0.5}}},
                    {{"name", "PostA"}, {"mesh", 1}, {"translation", {-2.0, 0.0, 0.0}}},
                    {{"name", "Orphan"}, {"mesh", 0}},
                    {{"name", "PostB"}, {"mesh", 1}, {"matrix", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 3, 0, 0, 1}}}};
    doc["scenes"] = {{{"nodes", {0, 4}}}};
    doc["scene"] = 0;
    doc["buffers"] = {{{"byteLength", 0}}};
    return doc;
}

std::string writeSceneGlb() {
    std::vector<uint8_t> bin;
    json doc = sceneJson(bin);
    while (bin.size() % 4) bin.push_back(0);
    doc["buffers"][0]["byteLength"] = bin.size();
    const std::string path = outDir() + "/two_assets.glb";
    const std::vector<uint8_t> glb = lodbake_test::makeGlb(doc, bin);
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(glb.data()), std::streamsize(glb.size()));
    return path;
}

CommandResult bake(const std::string& args) {
    return runCommand(shellQuote(lodbake_test::lodbakeCli()) + " bake " + args);
}

TEST(GltfSceneImportTest, KeepsNodesNamesTransformsAndReadsEachMeshOnce) {
    const std::string path = writeSceneGlb();
    lodbake::Diagnostics diagnostics;
    lodbake::Result<lodbake::LoadedScene> scene = lodbake::readMeshScene(path, lodbake::ReadOptions{}, diagnostics);
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    ASSERT_TRUE(scene->isGraph());
    ASSERT_EQ(scene->meshes.size(), 2u);
    EXPECT_EQ(scene->mesh_names, (std::vector<std::string>{"RingMesh", "PostMesh"}));
    EXPECT_EQ(scene->meshes[0].faceCount(), 48u * 24u * 2u);
    // Each mesh keeps only its own material, in its own (untransformed) space.
    ASSERT_EQ(scene->meshes[1].materials.size(), 1u);
    EXPECT_EQ(scene->meshes[1].materials[0].name, "Blue");
    EXPECT_NEAR(scene->meshes[0].positions[0].x, 1.3f, 1e-6f);
    ASSERT_EQ(scene->nodes.size(), 4u); // Orphan is in no scene
    const std::vector<std::string> names{"Root", "Ring", "PostA", "PostB"};
    const std::vector<int> meshes{-1, 0, 1, 1};
    for (size_t n = 0; n < 4; ++n) {
        EXPECT_EQ(scene->nodes[n].name, names[n]);
        EXPECT_EQ(scene->nodes[n].mesh, meshes[n]) << names[n];
    }
    EXPECT_EQ(scene->nodes[0].children, (std::vector<uint32_t>{1, 2}));
    EXPECT_EQ(scene->roots, (std::vector<uint32_t>{0, 3}));
    EXPECT_EQ(scene->nodes[1].translation, (std::vector<double>{1.5, 0.0, -0.5}));
    EXPECT_EQ(scene->nodes[3].matrix.size(), 16u);
    // Ring's world transform: the parent's translation composed with its own.
    EXPECT_NEAR(scene->nodes[1].world[13], 1.0, 1e-12);
    EXPECT_NEAR(scene->nodes[1].world[12], 1.5, 1e-12);
    EXPECT_NEAR(scene->nodes[1].world[0], std::cos(kPi / 4), 1e-12);
    EXPECT_EQ(scene->source.file_face_count, 48u * 24u * 2u + 40u * 20u * 2u);

    // One mesh node (even instancing nothing) stays the flattened mesh readMesh returns.
    std::vector<uint8_t> bin;
    json single = sceneJson(bin);
    single["scenes"] = {{{"nodes", {1}}}};
    while (bin.size() % 4) bin.push_back(0);
    single["buffers"][0]["byteLength"] = bin.size();
    const std::vector<uint8_t> glb = lodbake_test::makeGlb(single, bin);
    lodbake::Result<lodbake::LoadedScene> flat = lodbake::readGltfSceneFromMemory(
        glb.data(), glb.size(), "single.glb",
        [](const std::string&) -> lodbake::Result<std::vector<uint8_t>> {
            return lodbake::invalidInput("no side files");
        },
        lodbake::ReadOptions{}, diagnostics);
    ASSERT_TRUE(flat.ok()) << flat.status().message();
    EXPECT_FALSE(flat->isGraph());
    EXPECT_EQ(flat->flat.mesh.faceCount(), 48u * 24u * 2u);
    EXPECT_NEAR(flat->flat.mesh.positions[0].y, 0.0f, 1e-6f);
}

TEST(GltfSceneImportTest, ANodeReachedTwiceIsAnError) {
    std::vector<uint8_t> bin;
    json doc = sceneJson(bin);
    doc["nodes"][4]["children"] = {2}; // PostA under Root and under PostB
    while (bin.size() % 4) bin.push_back(0);
    doc["buffers"][0]["byteLength"] = bin.size();
    const std::vector<uint8_t> glb = lodbake_test::makeGlb(doc, bin);
    lodbake::Diagnostics diagnostics;
    lodbake::Result<lodbake::LoadedScene> scene = lodbake::readGltfSceneFromMemory(
        glb.data(), glb.size(), "shared.glb",
        [](const std::string&) -> lodbake::Result<std::vector<uint8_t>> {
            return lodbake::invalidInput("no side files");
        },
        lodbake::ReadOptions{}, diagnostics);
    ASSERT_FALSE(scene.ok());
    EXPECT_EQ(scene.status().message(),
              "shared.glb: node 2: reached twice from the scene (a cycle or a shared child; expected a tree)");
}

// Expects the pack node `n` to have the input node's name and transform members.
void expectSameNode(const json& in, const json& out) {
    EXPECT_EQ(out.value("name", ""), in.value("name", ""));
    for (const char* key : {"translation", "rotation", "scale", "matrix", "children"}) {
        ASSERT_EQ(out.contains(key), in.contains(key)) << in.value("name", "") << " " << key;
        if (in.contains(key)) {
            EXPECT_EQ(out[key], in[key]) << in.value("name", "") << " " << key;
        }
    }
}

// One test so the scene is baked once per process.
TEST(BakeSceneTest, TwoMeshSceneBakesIntoOneGroupPerMeshNodeWithTheInputsNodes) {
    const std::string in = writeSceneGlb();
    const std::string pack1 = outDir() + "/scene_t1.glb", pack2 = outDir() + "/scene_t2.glb";
    const std::string merged = outDir() + "/scene_merged.glb", report = outDir() + "/scene_report.json";
    const std::string common = shellQuote(in) + " --levels 0.5,0.25 --quiet";
    const CommandResult run1 =
        bake(common + " --threads 1 -o " + shellQuote(pack1) + " --report " + shellQuote(report));
    ASSERT_EQ(run1.exit_code, 0) << run1.output;
    const CommandResult run2 = bake(common + " --threads 2 -o " + shellQuote(pack2));
    ASSERT_EQ(run2.exit_code, 0) << run2.output;
    const std::vector<uint8_t> glb = bytesOf(pack1);
    ASSERT_FALSE(glb.empty());
    EXPECT_TRUE(glb == bytesOf(pack2)) << "thread count changed the pack";

    std::vector<uint8_t> in_bin;
    const json input = sceneJson(in_bin);
    const json doc = lodbake_test::glbJson(glb);
    {
        SCOPED_TRACE("SameNodesNamesTransformsAndHierarchy");
        EXPECT_EQ(doc["scenes"][0]["nodes"], (json{0, 3}));
        expectSameNode(input["nodes"][0], doc["nodes"][0]);
        expectSameNode(input["nodes"][1], doc["nodes"][1]);
        expectSameNode(input["nodes"][2], doc["nodes"][2]);
        expectSameNode(input["nodes"][4], doc["nodes"][3]);
        EXPECT_FALSE(doc["nodes"][0].contains("mesh"));
        EXPECT_FALSE(doc["nodes"][0].contains("extensions") && doc["nodes"][0]["extensions"].contains("MSFT_lod"));
    }
    {
        SCOPED_TRACE("EachMeshNodeIsAGroupOverSharedMeshes");
        std::vector<std::vector<int>> level_meshes;
        for (int n : {1, 2, 3}) {
            const json& node = doc["nodes"][size_t(n)];
            const json& ids = node["extensions"]["MSFT_lod"]["ids"];
            ASSERT_EQ(ids.size(), 2u) << n;
            EXPECT_EQ(node["extensions"]["LODBAKE_lod_metrics"]["levels"].size(), 3u);
            EXPECT_EQ(node["extras"]["MSFT_screencoverage"].size(), 3u);
            std::vector<int> meshes{node["mesh"].get<int>()};
            for (const json& id : ids) {
                const json& lower = doc["nodes"][id.get<size_t>()];
                meshes.push_back(lower["mesh"].get<int>());
                EXPECT_EQ(lower["name"], node["name"].get<std::string>() + "_lod" + std::to_string(meshes.size() - 1));
                for (const json& root : doc["scenes"][0]["nodes"]) {
                    EXPECT_NE(root, id); // outside the scene
                }
            }
            level_meshes.push_back(meshes);
        }
        EXPECT_EQ(level_meshes[1], level_meshes[2]); // PostA and PostB instance PostMesh's levels
        EXPECT_NE(level_meshes[0][0], level_meshes[1][0]);
        EXPECT_EQ(doc["meshes"].size(), 6u); // two meshes of three levels, each written once
        EXPECT_EQ(doc["meshes"][size_t(level_meshes[0][0])]["name"], "RingMesh_lod0");
        const int material = doc["meshes"][size_t(level_meshes[1][2])]["primitives"][0]["material"].get<int>();
        EXPECT_EQ(doc["materials"][size_t(material)]["name"], "Blue");
        // Levels of a child are placed by LOD0's world matrix, those of a root by its own transform.
        const json& ring_lower = doc["nodes"][doc["nodes"][1]["extensions"]["MSFT_lod"]["ids"][0].get<size_t>()];
        ASSERT_EQ(ring_lower["matrix"].size(), 16u);
        EXPECT_NEAR(ring_lower["matrix"][13].get<double>(), 1.0, 1e-12);
        const json& post_lower = doc["nodes"][doc["nodes"][3]["extensions"]["MSFT_lod"]["ids"][1].get<size_t>()];
        EXPECT_EQ(post_lower["matrix"], input["nodes"][4]["matrix"]);
        std::ifstream report_stream(report);
        const json r = json::parse(report_stream);
        ASSERT_EQ(r["assets"].size(), 2u); // each mesh baked once
        EXPECT_EQ(r["assets"][0]["name"], "RingMesh");
        EXPECT_EQ(r["assets"][1]["levels"][0]["triangles"], 40 * 20 * 2);
    }
    {
        SCOPED_TRACE("ValidatorClean");
        std::string command = shellQuote(LODBAKE_TEST_NODE) + " " +
                              shellQuote(lodbake_test::sourceDir() + "/scripts/node/validate-gltf.js") + " " +
                              shellQuote(pack1);
        const CommandResult v = runCommand(command);
        EXPECT_EQ(v.exit_code, 0) << v.output;
        EXPECT_NE(v.output.find("errors 0 warnings 0"), std::string::npos) << v.output;
    }
    {
        SCOPED_TRACE("LoddumpChecksEveryGroup");
        const CommandResult d = runCommand(shellQuote(LODBAKE_TEST_LODDUMP) + " " + shellQuote(pack1));
        EXPECT_EQ(d.exit_code, 0) << d.output;
        EXPECT_EQ(d.output.find("  error "), std::string::npos) << d.output;
        EXPECT_NE(d.output.find("lod group \"PostB\" (node 3): 3 levels"), std::string::npos) << d.output;
        const CommandResult j = runCommand(shellQuote(LODBAKE_TEST_LODDUMP) + " --json " + shellQuote(pack1));
        ASSERT_EQ(j.exit_code, 0) << j.output;
        const json dump = json::parse(j.output.substr(j.output.find('{')));
        ASSERT_EQ(dump["lodGroups"].size(), 3u);
        EXPECT_EQ(dump["lodGroups"][0]["name"], "Ring");
        EXPECT_EQ(dump["lodGroups"][2]["name"], "PostB");
    }
    {
        SCOPED_TRACE("LodrtLoadsOneModelPerGroupPlacedLikeTheInput");
        lodrt::Pack pack;
        char message[256] = "";
        ASSERT_EQ(lodrt::loadPack(glb.data(), glb.size(), nullptr, &pack, message, sizeof message), lodrt::Result::Ok)
            << message;
        lodrt::ModelSet models;
        ASSERT_EQ(lodrt::buildModels(pack, nullptr, &models, message, sizeof message), lodrt::Result::Ok) << message;
        ASSERT_EQ(models.modelCount(), 3u);
        const char* names[] = {"Ring", "PostA", "PostB"};
        for (uint32_t m = 0; m < 3; ++m) {
            const lodrt::ModelInfo& model = models.model(m);
            EXPECT_EQ(std::string(model.name), names[m]);
            ASSERT_EQ(model.level_count, 3u);
            EXPECT_EQ(model.error_source, lodrt::ErrorSource::Measured);
            for (uint32_t l = 1; l < 3; ++l)
                for (int k = 0; k < 16; ++k)
                    EXPECT_NEAR(models.modelLevel(m, l).world_transform[k], model.world_transform[k], 1e-6)
                        << names[m] << " level " << l;
        }
        const float* ring = models.model(0).world_transform;
        EXPECT_NEAR(ring[0], std::cos(kPi / 4), 1e-6);
        EXPECT_NEAR(ring[2], -std::sin(kPi / 4), 1e-6);
        EXPECT_NEAR(ring[12], 1.5, 1e-6);
        EXPECT_NEAR(ring[13], 1.0, 1e-6);
        EXPECT_NEAR(ring[14], -0.5, 1e-6);
        EXPECT_NEAR(models.model(1).world_transform[12], -2.0, 1e-6);
        EXPECT_NEAR(models.model(1).world_transform[13], 1.0, 1e-6);
        EXPECT_NEAR(models.model(2).world_transform[0], 2.0, 1e-6);
        EXPECT_NEAR(models.model(2).world_transform[12], 3.0, 1e-6);
    }
    {
        SCOPED_TRACE("OtherInputsBesideASceneAreOneRootNodeEach");
        lodbake::Mesh ring;
        const Grid g = torus(1.0f, 0.25f, 32, 16);
        for (size_t i = 0; i < g.positions.size(); i += 3)
            ring.positions.push_back(lodbake::Vec3f(g.positions[i], g.positions[i + 1], g.positions[i + 2]));
        ring.indices = g.indices;
        const std::string ply = outDir() + "/extra_ring.ply", mixed = outDir() + "/scene_mixed.glb";
        lodbake::Diagnostics diagnostics;
        ASSERT_TRUE(lodbake::writeMesh(ring, ply, lodbake::WriteOptions{}, diagnostics).ok());
        const CommandResult m = bake(common + " " + shellQuote(ply) + " -o " + shellQuote(mixed));
        ASSERT_EQ(m.exit_code, 0) << m.output;
        const json both = lodbake_test::glbJson(bytesOf(mixed));
        EXPECT_EQ(both["scenes"][0]["nodes"], (json{0, 3, 4}));
        EXPECT_EQ(both["nodes"][4]["name"], "extra_ring");
        EXPECT_EQ(both["nodes"][4]["extensions"]["MSFT_lod"]["ids"].size(), 2u);
        EXPECT_FALSE(both["nodes"][4].contains("matrix"));
        expectSameNode(input["nodes"][1], both["nodes"][1]);
    }
    {
        SCOPED_TRACE("MergeSceneGivesOneGroup");
        const CommandResult m = bake(common + " --merge-scene -o " + shellQuote(merged));
        ASSERT_EQ(m.exit_code, 0) << m.output;
        const json one = lodbake_test::glbJson(bytesOf(merged));
        ASSERT_EQ(one["scenes"][0]["nodes"].size(), 1u);
        const json& root = one["nodes"][one["scenes"][0]["nodes"][0].get<size_t>()];
        EXPECT_EQ(root["name"], "two_assets");
        EXPECT_EQ(root["extensions"]["MSFT_lod"]["ids"].size(), 2u);
        EXPECT_FALSE(root.contains("translation"));
        EXPECT_EQ(one["meshes"].size(), 3u);
    }
}

} // namespace
