// PfrepPackTest: LODBAKE_progressive_fans in a baked pack. The emitted extension object and the
// schema example validate against schemas/LODBAKE_progressive_fans, the object agrees with its blob
// (the README's cross-field rules), and the blob extracts, at each chain level's PFRep level, a
// valid manifold mesh with the announced triangle count.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/bake.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodrt/pfrep.h"
#include "data_uri.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const char* const kExtension = "LODBAKE_progressive_fans";

std::string schemaPath() {
    return lodbake_test::sourceDir() +
           "/schemas/LODBAKE_progressive_fans/schema/mesh.LODBAKE_progressive_fans.schema.json";
}

std::string scratch(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/pfrep_pack";
    fs::create_directories(dir);
    return dir + "/" + name;
}

// Validates one JSON document against the extension schema; returns the validator's output, empty
// when valid.
std::string validate(const json& object, const std::string& name) {
    const std::string path = scratch(name);
    std::ofstream(path) << object.dump(1);
    const lodbake_test::CommandResult r = lodbake_test::runCommand(
        lodbake_test::python() + " " +
        lodbake_test::shellQuote(lodbake_test::sourceDir() + "/tests/support/validate_schema.py") + " " +
        lodbake_test::shellQuote(schemaPath()) + " " + lodbake_test::shellQuote(path));
    return r.exit_code == 0 ? std::string() : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

// Problems of a triangle list: dangling or repeated indices, duplicate triangles, and with
// `check_manifold` edges with more than two faces or inconsistent orientation and vertices whose
// faces form more than one fan. Empty when it is valid (and an oriented manifold, with or without
// boundary).
std::string meshProblems(const std::vector<uint32_t>& tris, uint32_t vertex_count, bool check_manifold) {
    std::set<std::array<uint32_t, 3>> seen;
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    std::map<uint32_t, std::vector<std::pair<uint32_t, uint32_t>>> around; // vertex -> (next, prev) per face
    for (size_t t = 0; t < tris.size() / 3; ++t) {
        const uint32_t a = tris[3 * t], b = tris[3 * t + 1], c = tris[3 * t + 2];
        if (a >= vertex_count || b >= vertex_count || c >= vertex_count) return "dangling index";
        if (a == b || b == c || a == c) return "degenerate triangle " + std::to_string(t);
        std::array<uint32_t, 3> key{a, b, c};
        std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
        if (!seen.insert(key).second) return "duplicate triangle " + std::to_string(t);
        if (!check_manifold) continue;
        for (auto [u, v] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
            if (++directed[{u, v}] > 1) return "edge used twice in one direction (non-manifold or flipped)";
        around[a].push_back({b, c});
        around[b].push_back({c, a});
        around[c].push_back({a, b});
    }
    for (const auto& [v, fans] : around) {
        // Faces around v link when one's next is another's prev; one fan <=> one component.
        std::vector<size_t> parent(fans.size());
        for (size_t i = 0; i < fans.size(); ++i) parent[i] = i;
        auto find = [&](size_t x) {
            while (parent[x] != x) x = parent[x] = parent[parent[x]];
            return x;
        };
        std::map<uint32_t, size_t> by_prev;
        for (size_t i = 0; i < fans.size(); ++i) by_prev[fans[i].second] = i;
        for (size_t i = 0; i < fans.size(); ++i) {
            const auto it = by_prev.find(fans[i].first);
            if (it != by_prev.end()) parent[find(i)] = find(it->second);
        }
        size_t components = 0;
        for (size_t i = 0; i < fans.size(); ++i) components += find(i) == i;
        if (components != 1) return "vertex " + std::to_string(v) + " joins " + std::to_string(components) + " fans";
    }
    return {};
}

// The bytes of buffer view `view` of a GLB (its BIN chunk).
std::vector<uint8_t> viewBytes(const std::vector<uint8_t>& glb, const json& doc, int view) {
    uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const size_t bin = 20 + json_length + 8;
    const json& v = doc["bufferViews"][size_t(view)];
    const size_t offset = bin + v.value("byteOffset", size_t(0));
    const size_t length = v["byteLength"].get<size_t>();
    if (offset + length > glb.size()) return {};
    return std::vector<uint8_t>(glb.begin() + long(offset), glb.begin() + long(offset + length));
}

// Every rule of the README that JSON Schema cannot state, for one mesh's extension object in a pack.
void checkObjectAgainstBlob(const json& object, const std::vector<uint8_t>& blob, size_t chain_levels,
                            bool require_manifold_input) {
    bool input_manifold = false;
    lodrt::PfrepModel m;
    // A format 3 blob (`format`: 3, the bake's default) is checked through the format 2 bytes it
    // decodes to.
    std::vector<uint8_t> decoded;
    if (object.contains("format")) {
        ASSERT_EQ(object["format"].get<uint32_t>(), 3u);
        lodrt::PfrepCompressedInfo info;
        ASSERT_EQ(lodrt::pfrepCompressedInfo(blob.data(), blob.size(), &info), lodrt::Result::Ok);
        decoded.resize(info.decoded_bytes);
        std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
        ASSERT_EQ(lodrt::pfrepDecompress(blob.data(), blob.size(), decoded.data(), decoded.size(), scratch.data(),
                                         info.scratch_bytes, &m),
                  lodrt::Result::Ok);
    } else {
        ASSERT_EQ(lodrt::openPfrep(blob.data(), blob.size(), &m), lodrt::Result::Ok);
    }
    EXPECT_EQ(object["vertexCount"].get<uint32_t>(), m.vertex_count);
    EXPECT_EQ(object["removedCount"].get<uint32_t>(), m.removed_count);
    EXPECT_EQ(object["triangleCount"].get<uint32_t>(), m.level0_triangles);
    const json& levels = object["levels"];
    ASSERT_EQ(levels.size(), chain_levels);
    EXPECT_EQ(levels[0]["removals"].get<uint32_t>(), 0u);
    EXPECT_EQ(levels[0]["triangles"].get<uint32_t>(), m.level0_triangles);
    std::vector<uint32_t> tris(lodrt::pfrepMaxTriangles(m) * 3);
    for (size_t l = 0; l < levels.size(); ++l) {
        SCOPED_TRACE("level " + std::to_string(l));
        const uint32_t k = levels[l]["removals"].get<uint32_t>();
        ASSERT_LE(k, m.removed_count);
        if (l > 0) {
            EXPECT_GE(k, levels[l - 1]["removals"].get<uint32_t>());
            EXPECT_LE(levels[l]["triangles"].get<uint32_t>(), levels[l - 1]["triangles"].get<uint32_t>());
        }
        size_t count = 0;
        ASSERT_EQ(lodrt::pfrepExtractLevel(m, k, tris.data(), tris.size() / 3, &count), lodrt::Result::Ok);
        EXPECT_EQ(count, levels[l]["triangles"].get<size_t>());
        EXPECT_GT(count, 0u);
        // Every level is valid; when level 0 is an oriented manifold, so is every level.
        const std::vector<uint32_t> level(tris.begin(), tris.begin() + long(count * 3));
        if (l == 0) {
            input_manifold = meshProblems(level, m.vertex_count, true).empty();
            if (require_manifold_input) {
                EXPECT_TRUE(input_manifold) << meshProblems(level, m.vertex_count, true);
            }
        }
        EXPECT_EQ(meshProblems(level, m.vertex_count, input_manifold), "");
    }
}

struct BakedPack {
    std::vector<uint8_t> glb;
    json doc;
    std::vector<double> ratios;
    bool pfrep_from_chain = false;
};

BakedPack bakePack(const std::string& path, uint32_t error_samples, bool pfrep_from_chain) {
    BakedPack out;
    lodbake::Diagnostics diagnostics;
    auto loaded = lodbake::readMesh(path, {}, diagnostics);
    EXPECT_TRUE(loaded.ok()) << loaded.status().message();
    if (!loaded.ok()) return out;
    lodbake::BakeSettings settings;
    settings.error_samples = error_samples;
    settings.pfrep_from_chain = pfrep_from_chain;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "scan";
    inputs[0].mesh = std::move(loaded->mesh);
    auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
    EXPECT_TRUE(baked.ok()) << baked.status().message();
    if (!baked.ok()) return out;
    out.glb = std::move(baked->glb);
    out.doc = lodbake_test::glbJson(out.glb);
    out.ratios = settings.lod_ratios;
    out.pfrep_from_chain = pfrep_from_chain;
    return out;
}

// The LOD0 mesh of the pack's only group: it carries the extension, and no other mesh does.
void checkPack(const BakedPack& pack, bool require_manifold_input) {
    ASSERT_FALSE(pack.glb.empty());
    const json& doc = pack.doc;
    const json& root = doc["nodes"][doc["scenes"][0]["nodes"][0].get<size_t>()];
    const json& ids = root["extensions"]["MSFT_lod"]["ids"];
    const size_t mesh = root["mesh"].get<size_t>();
    for (size_t i = 0; i < doc["meshes"].size(); ++i) {
        const bool has = doc["meshes"][i].contains("extensions") && doc["meshes"][i]["extensions"].contains(kExtension);
        EXPECT_EQ(has, i == mesh) << "mesh " << i;
    }
    const json& object = doc["meshes"][mesh]["extensions"][kExtension];
    EXPECT_EQ(validate(object, "emitted.json"), "");
    const json& used = doc["extensionsUsed"];
    EXPECT_NE(std::find(used.begin(), used.end(), kExtension), used.end());
    const json& view = doc["bufferViews"][object["bufferView"].get<size_t>()];
    EXPECT_FALSE(view.contains("byteStride"));
    const std::vector<uint8_t> blob = viewBytes(pack.glb, doc, object["bufferView"].get<int>());
    ASSERT_FALSE(blob.empty());
    checkObjectAgainstBlob(object, blob, ids.size() + 1, require_manifold_input);
    const json& levels = object["levels"];
    ASSERT_EQ(levels.size(), ids.size() + 1);
    for (size_t l = 0; l < levels.size(); ++l) {
        const size_t level_mesh = l == 0 ? mesh : doc["nodes"][ids[l - 1].get<size_t>()]["mesh"].get<size_t>();
        uint64_t triangles = 0;
        for (const json& primitive : doc["meshes"][level_mesh]["primitives"])
            triangles += doc["accessors"][primitive["indices"].get<size_t>()]["count"].get<uint64_t>() / 3;
        if (pack.pfrep_from_chain || l == 0) {
            // From the chain's own pass each PFRep level named has exactly the triangles of its plain
            // chain level (and LOD0 is the full mesh either way).
            EXPECT_EQ(levels[l]["triangles"].get<uint64_t>(), triangles) << "level " << l;
        } else if (levels[l]["removals"].get<uint32_t>() < object["removedCount"].get<uint32_t>()) {
            // From its own half-edge pass a PFRep level does not exceed its chain level's triangle
            // budget unless the sequence ends first.
            const double budget = pack.ratios[l - 1] * object["triangleCount"].get<double>();
            EXPECT_LE(levels[l]["triangles"].get<double>(), budget) << "level " << l;
        }
    }
}

TEST(PfrepPackTest, RockSamplePackCarriesAValidProgressiveFansObject) {
    for (bool from_chain : {false, true}) {
        SCOPED_TRACE(from_chain ? "pfrep_from_chain" : "own half-edge pass");
        const BakedPack pack =
            bakePack(lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock_000.ply", 20000, from_chain);
        checkPack(pack, false); // a raw scan: overlapping sheets survive the repair
    }
}

TEST(PfrepPackTest, RockerArmPackLevelsAreManifold) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (bool from_chain : {false, true}) {
        SCOPED_TRACE(from_chain ? "pfrep_from_chain" : "own half-edge pass");
        const BakedPack pack = bakePack(lodbake_test::sharedMesh("rocker_arm.obj"), 20000, from_chain);
        checkPack(pack, true);
    }
}

TEST(PfrepPackTest, ExtensionObjectRejectsBadRatiosAndEmptyMeshes) {
    lodbake::Diagnostics diagnostics;
    lodbake::Mesh empty;
    EXPECT_FALSE(lodbake::buildPfrepExtension(empty, {1.0}, {}, diagnostics).ok());
    lodbake::Mesh quad;
    quad.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    quad.indices = {0, 1, 2, 0, 2, 3};
    EXPECT_FALSE(lodbake::buildPfrepExtension(quad, {1.0, 0.0}, {}, diagnostics).ok());
    EXPECT_FALSE(lodbake::buildPfrepExtension(quad, {1.5}, {}, diagnostics).ok());
    auto object = lodbake::buildPfrepExtension(quad, {1.0, 0.5}, {}, diagnostics);
    ASSERT_TRUE(object.ok()) << object.status().message();
    json j = json::parse(object->json.text());
    EXPECT_FALSE(j.contains("bufferView")); // the pack writer adds it
    j["bufferView"] = 0;
    EXPECT_EQ(validate(j, "quad.json"), "");
    checkObjectAgainstBlob(j, object->blob, 2, true);
    EXPECT_EQ(j["levels"][1]["triangles"].get<int>(), 1);
}

// examples/minimal.gltf: valid against the schema, and its embedded blob obeys the README's rules.
TEST(PfrepPackTest, SchemaExampleIsValidAndItsBlobOpens) {
    auto text = lodbake::readFileBytes(lodbake_test::sourceDir() + "/schemas/LODBAKE_progressive_fans/examples/minimal.gltf");
    ASSERT_TRUE(text.ok());
    const json doc = json::parse(text->begin(), text->end());
    const json& object = doc["meshes"][0]["extensions"][kExtension];
    EXPECT_EQ(validate(object, "example.json"), "");
    const std::string uri = doc["buffers"][0]["uri"].get<std::string>();
    std::vector<uint8_t> buffer;
    ASSERT_TRUE(lodbake_test::dataUriBytes(uri, buffer)) << uri.substr(0, 64);
    ASSERT_EQ(buffer.size(), doc["buffers"][0]["byteLength"].get<size_t>());
    const json& view = doc["bufferViews"][object["bufferView"].get<size_t>()];
    const size_t offset = view.value("byteOffset", size_t(0));
    ASSERT_LE(offset + view["byteLength"].get<size_t>(), buffer.size());
    const std::vector<uint8_t> blob(buffer.begin() + long(offset),
                                    buffer.begin() + long(offset + view["byteLength"].get<size_t>()));
    checkObjectAgainstBlob(object, blob, 2, true);
}

} // namespace
