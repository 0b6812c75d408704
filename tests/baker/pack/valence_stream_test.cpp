// LODBAKE_valence_compression in packs: the encoder renumbers a level so the plain accessors and the
// stream hold the same triangles; compact packs drop the plain data the stream supplies; every
// shared scan's pack round-trips through the runtime decoder; every emitted extension object and
// the schema example match the schema.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/bake.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/gltf/gltf_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/pack.h"
#include "lodrt/pack.h"
#include "lodrt/valence.h"
#include "data_uri.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using namespace lodbake;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;

constexpr const char* kExt = "LODBAKE_valence_compression";

std::string src(const std::string& relative) {
    return lodbake_test::sourceDir() + "/" + relative;
}

std::string outDir() {
    const std::string dir = lodbake_test::scratchDir() + "/valence_stream";
    fs::create_directories(dir);
    return dir;
}

// A bumpy (n+1)^2-vertex grid with normals and one UV set: enough triangles for the codec to reorder.
Mesh grid(int n) {
    Mesh m;
    m.uvs.resize(1);
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            const float z = 0.1f * std::sin(float(x) * 0.7f) * std::cos(float(y) * 0.5f);
            m.positions.push_back({float(x) / float(n), float(y) / float(n), z});
            m.normals.push_back({0, 0, 1});
            m.uvs[0].push_back({float(x) / float(n), float(y) / float(n)});
        }
    auto v = [n](int x, int y) { return uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            m.indices.insert(m.indices.end(), {v(x, y), v(x + 1, y), v(x + 1, y + 1)});
            m.indices.insert(m.indices.end(), {v(x, y), v(x + 1, y + 1), v(x, y + 1)});
        }
    return m;
}

struct Decoded {
    lodrt::ValenceInfo info;
    std::vector<uint32_t> indices;
    std::vector<float> positions;
};

// Decodes a stream with the runtime decoder; fails the test on any error.
Decoded decode(const uint8_t* data, size_t size) {
    Decoded d;
    EXPECT_EQ(lodrt::valenceReadInfo(data, size, &d.info), lodrt::Result::Ok);
    d.indices.resize(size_t(d.info.triangle_count) * 3);
    d.positions.resize(size_t(d.info.vertex_count) * 3);
    std::vector<float> normals(d.info.has_normals ? d.positions.size() : 0);
    std::vector<uint64_t> scratch((lodrt::valenceScratchSize(d.info) + 7) / 8);
    lodrt::ValenceOutput out;
    out.indices = d.indices.data();
    out.index_capacity = d.indices.size();
    out.positions = d.positions.data();
    out.position_capacity = d.positions.size();
    out.normals = normals.empty() ? nullptr : normals.data();
    out.normal_capacity = normals.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    EXPECT_EQ(lodrt::valenceDecode(data, size, out), lodrt::Result::Ok);
    return d;
}

double quantizationStep(const lodrt::ValenceInfo& info) {
    return double(info.cube_size) / double((1u << info.position_bits) - 1);
}

TEST(ValenceStreamTest, LevelIsRenumberedIntoTheDecodedOrder) {
    PackLevel level;
    level.mesh = grid(24);
    const Mesh original = level.mesh;
    const PackStreamEncoder encoder = valenceStreamEncoder();
    ASSERT_TRUE(encoder.encode(LodChain{}, 0, level).ok());
    ASSERT_EQ(level.primitive_extensions.size(), 1u);
    ASSERT_EQ(level.primitive_extensions[0].size(), 1u);
    const PackExtension& e = level.primitive_extensions[0][0];
    EXPECT_EQ(e.name, kExt);
    EXPECT_TRUE(e.is_stream);
    ASSERT_EQ(e.blobs.size(), 1u);
    ASSERT_EQ(e.blob_view_members, std::vector<std::string>{"bufferView"});
    const nlohmann::json j = nlohmann::json::parse(e.json);
    EXPECT_EQ(j["attributes"]["POSITION"], 0);
    EXPECT_EQ(j["attributes"]["NORMAL"], 1);
    EXPECT_EQ(j["positionBits"], 14);
    EXPECT_EQ(j["normalBits"], 8);

    const Decoded d = decode(e.blobs[0].data(), e.blobs[0].size());
    EXPECT_EQ(d.indices, level.mesh.indices); // the plain indices are the decoder's own
    ASSERT_EQ(level.mesh.vertexCount(), original.vertexCount());
    const double step = quantizationStep(d.info);
    for (size_t v = 0; v < level.mesh.vertexCount(); ++v)
        for (int k = 0; k < 3; ++k)
            ASSERT_NEAR(d.positions[v * 3 + size_t(k)], (&level.mesh.positions[v].x)[k], step) << v;
    // The same surface: every renumbered triangle's corners (with their UVs) are an original triangle's.
    std::multiset<std::array<float, 9>> before, after;
    auto corners = [](const Mesh& m, std::multiset<std::array<float, 9>>& out) {
        for (size_t t = 0; t < m.faceCount(); ++t) {
            std::array<std::array<float, 3>, 3> c;
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = m.indices[t * 3 + size_t(k)];
                c[size_t(k)] = {m.positions[v].x, m.positions[v].y, m.uvs[0][v].x + 7.0f * m.uvs[0][v].y};
            }
            std::sort(c.begin(), c.end());
            out.insert({c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2]});
        }
    };
    corners(original, before);
    corners(level.mesh, after);
    EXPECT_EQ(before, after);

    // Re-using the encoder gives identical bytes.
    PackLevel again;
    again.mesh = original;
    ASSERT_TRUE(encoder.encode(LodChain{}, 0, again).ok());
    EXPECT_EQ(again.primitive_extensions[0][0].blobs[0], e.blobs[0]);
}

TEST(ValenceStreamTest, MultiPrimitiveLevelsAreLeftPlain) {
    PackLevel level;
    level.mesh = grid(4);
    const size_t half = level.mesh.indices.size() / 2;
    level.mesh.submeshes = {{"a", 0, uint32_t(half), MaterialId::invalid()},
                            {"b", uint32_t(half), uint32_t(half), MaterialId::invalid()}};
    const Mesh original = level.mesh;
    ASSERT_TRUE(valenceStreamEncoder().encode(LodChain{}, 0, level).ok());
    EXPECT_TRUE(level.primitive_extensions.empty());
    EXPECT_EQ(level.mesh.indices, original.indices);
}

PackDescription onePack(bool compact) {
    PackDescription description;
    description.compact = compact;
    PackAsset asset;
    asset.name = "grid";
    asset.levels.resize(2);
    asset.levels[0].mesh = grid(16);
    asset.levels[1].mesh = grid(4);
    asset.screen_coverage = {0.5, 0.0};
    const PackStreamEncoder encoder = valenceStreamEncoder();
    for (size_t l = 0; l < 2; ++l) EXPECT_TRUE(encoder.encode(LodChain{}, l, asset.levels[l]).ok());
    description.assets.push_back(std::move(asset));
    return description;
}

TEST(ValenceStreamTest, CompactPackDropsOnlyThePlainDataTheStreamSupplies) {
    Result<std::vector<uint8_t>> plain = writePackGlb(onePack(false));
    Result<std::vector<uint8_t>> compact = writePackGlb(onePack(true));
    ASSERT_TRUE(plain.ok()) << plain.status().message();
    ASSERT_TRUE(compact.ok()) << compact.status().message();
    EXPECT_LT(compact->size(), plain->size());
    const nlohmann::json p = lodbake_test::glbJson(*plain);
    const nlohmann::json c = lodbake_test::glbJson(*compact);
    EXPECT_FALSE(p.contains("extensionsRequired"));
    EXPECT_EQ(c["extensionsRequired"], nlohmann::json::array({kExt}));
    ASSERT_EQ(c["meshes"].size(), 2u);
    for (const nlohmann::json& mesh : c["meshes"]) {
        const nlohmann::json& prim = mesh["primitives"][0];
        for (const char* dropped : {"POSITION", "NORMAL"}) {
            const nlohmann::json& acc = c["accessors"][prim["attributes"][dropped].get<size_t>()];
            EXPECT_FALSE(acc.contains("bufferView")) << dropped;
            EXPECT_GT(acc["count"].get<int>(), 0);
        }
        EXPECT_FALSE(c["accessors"][prim["indices"].get<size_t>()].contains("bufferView"));
        EXPECT_TRUE(c["accessors"][prim["attributes"]["TEXCOORD_0"].get<size_t>()].contains("bufferView"));
        EXPECT_TRUE(c["accessors"][prim["attributes"]["POSITION"].get<size_t>()].contains("min"));
    }
    // The runtime reads the compact pack, and its streams are the plain pack's, byte for byte.
    lodrt::Pack pc, pp;
    ASSERT_EQ(lodrt::loadPack(compact->data(), compact->size(), nullptr, &pc), lodrt::Result::Ok);
    ASSERT_EQ(lodrt::loadPack(plain->data(), plain->size(), nullptr, &pp), lodrt::Result::Ok);
    for (uint32_t m = 0; m < 2; ++m) {
        auto streamOf = [m](const lodrt::Pack& pack) {
            const lodrt::PrimitiveInfo& prim = pack.primitive(pack.mesh(m).first_primitive);
            uint64_t view = 0;
            EXPECT_TRUE(prim.json.find("extensions").find(kExt).find("bufferView").asUint64(&view));
            const lodrt::BufferViewInfo& v = pack.bufferView(uint32_t(view));
            const uint8_t* b = pack.container().bin + v.byte_offset;
            return std::vector<uint8_t>(b, b + v.byte_length);
        };
        EXPECT_EQ(streamOf(pc), streamOf(pp)) << m;
    }
}

// Triangles of every level of a baked pack, through the runtime: each stream decodes to the plain
// indices (same order; a triangle may start at another corner) and to the plain positions up to the
// quantization step. Returns the number of streams checked; the extension objects go to `objects`.
size_t checkRoundTrip(const std::vector<uint8_t>& glb, const std::string& name, std::vector<nlohmann::json>& objects) {
    lodrt::Pack pack;
    char message[256] = "";
    EXPECT_EQ(lodrt::loadPack(glb.data(), glb.size(), nullptr, &pack, message, sizeof(message)), lodrt::Result::Ok)
        << name << ": " << message;
    const nlohmann::json doc = lodbake_test::glbJson(glb);
    size_t streams = 0;
    const uint8_t* bin = pack.container().bin;
    for (uint32_t p = 0; p < pack.primitiveCount(); ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(p);
        uint64_t view = 0;
        if (!prim.json.find("extensions").find(kExt).find("bufferView").asUint64(&view)) continue;
        ++streams;
        const lodrt::BufferViewInfo& v = pack.bufferView(uint32_t(view));
        const Decoded d = decode(bin + v.byte_offset, size_t(v.byte_length));
        EXPECT_EQ(d.info.triangle_count, prim.triangle_count) << name;
        EXPECT_EQ(d.info.vertex_count, prim.vertex_count) << name;

        const lodrt::AccessorInfo& ia = pack.accessor(prim.indices);
        const lodrt::BufferViewInfo& iv = pack.bufferView(ia.buffer_view);
        const uint8_t* ib = bin + iv.byte_offset + ia.byte_offset;
        const uint32_t isize = lodrt::componentSize(ia.component_type);
        EXPECT_EQ(ia.count, d.indices.size()) << name;
        if (ia.count != d.indices.size()) continue;
        size_t mismatched = 0;
        for (size_t t = 0; t < d.indices.size(); t += 3) {
            uint32_t plain[3] = {0, 0, 0};
            for (int k = 0; k < 3; ++k) std::memcpy(&plain[k], ib + (t + size_t(k)) * isize, isize);
            bool same = false;
            for (int r = 0; r < 3 && !same; ++r)
                same = d.indices[t] == plain[r] && d.indices[t + 1] == plain[(r + 1) % 3] &&
                       d.indices[t + 2] == plain[(r + 2) % 3];
            mismatched += same ? 0 : 1;
        }
        EXPECT_EQ(mismatched, 0u) << name << " primitive " << p;

        uint32_t position = lodrt::kNoIndex;
        for (uint32_t a = 0; a < prim.attribute_count; ++a)
            if (pack.attribute(prim.first_attribute + a).name == "POSITION")
                position = pack.attribute(prim.first_attribute + a).accessor;
        EXPECT_NE(position, lodrt::kNoIndex) << name;
        if (position == lodrt::kNoIndex) continue;
        const lodrt::AccessorInfo& pa = pack.accessor(position);
        const uint8_t* pb = bin + pack.bufferView(pa.buffer_view).byte_offset + pa.byte_offset;
        const double step = quantizationStep(d.info);
        double worst = 0;
        for (size_t i = 0; i < d.positions.size(); ++i) {
            float f = 0;
            std::memcpy(&f, pb + i * 4, 4);
            worst = std::max(worst, std::fabs(double(f) - double(d.positions[i])));
        }
        EXPECT_LE(worst, step) << name << " primitive " << p;

    }
    for (const nlohmann::json& mesh : doc["meshes"])
        for (const nlohmann::json& prim : mesh["primitives"])
            if (prim.contains("extensions") && prim["extensions"].contains(kExt))
                objects.push_back(prim["extensions"][kExt]);
    return streams;
}

CommandResult validateObjects(const std::vector<std::string>& files) {
    std::string command = lodbake_test::python() + " " + shellQuote(src("tests/support/validate_schema.py")) + " " +
                          shellQuote(src("schemas/LODBAKE_valence_compression/schema/"
                                         "mesh.primitive.LODBAKE_valence_compression.schema.json"));
    for (const std::string& f : files) command += " " + shellQuote(f);
    return runCommand(command);
}

// Every shared scan, baked with a light preset (no repair, one coarse level, few error samples): every
// level carries a stream (every scan is one primitive), and every stream round-trips. The extension objects of all packs
// are checked against the schema.
TEST(ValenceStreamSharedMeshesTest, EveryScanRoundTripsThroughTheRuntimeDecoder) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    BakeSettings settings;
    settings.repair = false;
    settings.lod_ratios = {0.01};
    settings.error_samples = 1000;
    settings.textures.enabled = false;
    settings.threads = 2;
    std::vector<nlohmann::json> objects;
    for (const char* name : {"bunny_zipper.ply", "igea.ply", "igea_tristrips.ply", "lucy100k.ply", "nefertiti.obj",
                             "rocker_arm.obj", "dragon_poisson.ply", "bunny_scan_bun000_tri.ply",
                             "dragon_scan_stand0_tri.ply", "dragon_stand_merged.ply", "fandisk.obj", "spot.obj",
                             "lee_perry_smith/LeePerrySmith.glb", "nefertiti_fraunhofer_textured.glb"}) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(lodbake_test::sharedMesh(name), ReadOptions{}, diagnostics);
        ASSERT_TRUE(loaded.ok()) << name << ": " << loaded.status().message();
        std::vector<BakeInput> inputs(1);
        inputs[0].name = fs::path(name).stem().string();
        inputs[0].mesh = std::move(loaded->mesh);
        Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics);
        ASSERT_TRUE(out.ok()) << name << ": " << out.status().message();
        const size_t streams = checkRoundTrip(out->glb, name, objects);
        EXPECT_EQ(streams, settings.lod_ratios.size() + 1) << name;
    }
    std::vector<std::string> files;
    for (size_t i = 0; i < objects.size(); ++i) {
        files.push_back(outDir() + "/object_" + std::to_string(i) + ".json");
        std::ofstream(files.back()) << objects[i].dump();
    }
    files.push_back(src("schemas/LODBAKE_valence_compression/examples/minimal.gltf"));
    // The example is a whole glTF document: validate its one extension object.
    const nlohmann::json example =
        nlohmann::json::parse(std::ifstream(files.back()))["meshes"][0]["primitives"][0]["extensions"][kExt];
    files.back() = outDir() + "/example_object.json";
    std::ofstream(files.back()) << example.dump();
    const CommandResult v = validateObjects(files);
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

// The example's stream must decode with the current format version: a codec change that bumps the
// version has to regenerate it (`lodbake encode tet.obj --bits 14 --no-normals`).
TEST(ValenceStreamSchemaTest, ExampleStreamDecodesToItsTetrahedron) {
    const nlohmann::json doc =
        nlohmann::json::parse(std::ifstream(src("schemas/LODBAKE_valence_compression/examples/minimal.gltf")));
    std::vector<uint8_t> buffer;
    ASSERT_TRUE(lodbake_test::dataUriBytes(doc["buffers"][0]["uri"].get<std::string>(), buffer));
    const nlohmann::json& object = doc["meshes"][0]["primitives"][0]["extensions"][kExt];
    const nlohmann::json& view = doc["bufferViews"][object["bufferView"].get<size_t>()];
    const size_t offset = view.value("byteOffset", size_t(0)), length = view["byteLength"].get<size_t>();
    ASSERT_LE(offset + length, buffer.size());
    lodrt::ValenceInfo info;
    ASSERT_EQ(lodrt::valenceReadInfo(buffer.data() + offset, length, &info), lodrt::Result::Ok);
    EXPECT_EQ(info.vertex_count, doc["accessors"][0]["count"].get<uint32_t>());
    EXPECT_EQ(info.triangle_count * 3, doc["accessors"][1]["count"].get<uint32_t>());
    EXPECT_EQ(info.position_bits, object["positionBits"].get<uint32_t>());
    std::vector<uint32_t> indices(3 * info.triangle_count);
    std::vector<float> positions(3 * info.vertex_count);
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 1);
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size();
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    ASSERT_EQ(lodrt::valenceDecode(buffer.data() + offset, length, out), lodrt::Result::Ok);
    for (size_t i = 0; i < positions.size(); ++i) {
        EXPECT_GE(positions[i], doc["accessors"][0]["min"][i % 3].get<float>() - 1e-4f);
        EXPECT_LE(positions[i], doc["accessors"][0]["max"][i % 3].get<float>() + 1e-4f);
    }
}

TEST(ValenceStreamSchemaTest, SchemaRejectsBrokenObjects) {
    const std::vector<std::pair<std::string, std::string>> bad = {
        {"no_view", R"({"attributes": {"POSITION": 0}, "positionBits": 14})"},
        {"bits", R"({"bufferView": 0, "attributes": {"POSITION": 0}, "positionBits": 20})"},
        {"normal_bits_missing", R"({"bufferView": 0, "attributes": {"POSITION": 0, "NORMAL": 1}, "positionBits": 14})"},
        {"unknown_attribute", R"({"bufferView": 0, "attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "positionBits": 14})"},
    };
    for (const auto& [name, text] : bad) {
        const std::string file = outDir() + "/bad_" + name + ".json";
        std::ofstream(file) << text;
        EXPECT_EQ(validateObjects({file}).exit_code, 1) << name;
    }
    const std::string good = outDir() + "/good.json";
    std::ofstream(good) << R"({"bufferView": 3, "attributes": {"POSITION": 0, "NORMAL": 1}, "positionBits": 14,
                               "normalBits": 8})";
    const CommandResult v = validateObjects({good});
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

} // namespace
