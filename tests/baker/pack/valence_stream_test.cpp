// LODBAKE_valence_compression in packs: the encoder renumbers a level so the plain accessors and the
// stream hold the same triangles; compact packs drop the plain data the stream supplies; every
// shared scan's pack round-trips through the runtime decoder; every emitted extension object and
// the schema example match the schema.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/bake.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/pack.h"
#include "lodbake/stream/stream.h"
#include "lodrt/pack.h"
#include "lodrt/valence.h"
#include "data_uri.h"
#include "mesh_builders.h"
#include "stream_level.h"
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
    ASSERT_TRUE(lodbake_test::encodeStreamLevel(encoder, LodChain{}, 0, level).ok());
    ASSERT_EQ(level.primitive_extensions.size(), 1u);
    ASSERT_EQ(level.primitive_extensions[0].size(), 1u);
    const PackExtension& e = level.primitive_extensions[0][0];
    EXPECT_EQ(e.name, kExt);
    EXPECT_TRUE(e.is_stream);
    ASSERT_EQ(e.blobs.size(), 1u);
    ASSERT_EQ(e.blob_view_members, std::vector<std::string>{"bufferView"});
    const nlohmann::json j = nlohmann::json::parse(e.json.text());
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
    ASSERT_TRUE(lodbake_test::encodeStreamLevel(encoder, LodChain{}, 0, again).ok());
    EXPECT_EQ(again.primitive_extensions[0][0].blobs[0], e.blobs[0]);
}

// A grid split into two primitives (rows [0, n/2) and [n/2, n), sharing the middle row of vertices)
// with an empty sub-mesh between them, two materials, and one vertex no triangle uses.
Mesh twoPrimitiveGrid(int n) {
    Mesh m = grid(n);
    const auto half = uint32_t(m.indices.size() / 2);
    m.materials.resize(2);
    m.materials[0].name = "a";
    m.materials[1].name = "b";
    m.materials[1].base_color_factor = {0.5f, 0.25f, 1.0f, 1.0f};
    m.submeshes = {
        {"a", 0, half, MaterialId(0)}, {"empty", half, 0, MaterialId::invalid()}, {"b", half, half, MaterialId(1)}};
    m.positions.push_back({5, 5, 5});
    m.normals.push_back({0, 0, 1});
    m.uvs[0].push_back({0, 0});
    return m;
}

// Every triangle of sub-mesh s as its three corners (position and UV), corner order normalised.
std::multiset<std::array<float, 15>> subMeshCorners(const Mesh& m, const SubMesh& s) {
    std::multiset<std::array<float, 15>> out;
    for (uint32_t i = s.first_index; i < s.first_index + s.index_count; i += 3) {
        std::array<std::array<float, 5>, 3> c;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t v = m.indices[i + k];
            c[k] = {m.positions[v].x, m.positions[v].y, m.positions[v].z, m.uvs[0][v].x, m.uvs[0][v].y};
        }
        std::sort(c.begin(), c.end());
        std::array<float, 15> flat;
        for (size_t k = 0; k < 15; ++k) flat[k] = c[k / 5][k % 5];
        out.insert(flat);
    }
    return out;
}

TEST(ValenceStreamTest, MultiPrimitiveLevelGetsOneStreamPerPrimitive) {
    PackLevel level;
    level.mesh = twoPrimitiveGrid(8);
    const Mesh original = level.mesh;
    ASSERT_TRUE(lodbake_test::encodeStreamLevel(valenceStreamEncoder(), LodChain{}, 0, level).ok());
    const Mesh& m = level.mesh;
    // Sub-meshes keep their order, names, materials and triangle counts; the empty one stays empty.
    ASSERT_EQ(m.submeshes.size(), 3u);
    for (size_t s = 0; s < 3; ++s) {
        EXPECT_EQ(m.submeshes[s].name, original.submeshes[s].name);
        EXPECT_EQ(m.submeshes[s].material, original.submeshes[s].material);
        EXPECT_EQ(m.submeshes[s].index_count, original.submeshes[s].index_count);
    }
    // One stream and one vertex range per non-empty sub-mesh; the shared middle row (9 vertices) is
    // copied into both ranges and the unused vertex is gone.
    ASSERT_EQ(level.primitive_extensions.size(), 2u);
    ASSERT_EQ(level.primitive_vertex_ranges.size(), 2u);
    EXPECT_EQ(level.primitive_vertex_ranges[0].first, 0u);
    EXPECT_EQ(level.primitive_vertex_ranges[0].count, 45u);
    EXPECT_EQ(level.primitive_vertex_ranges[1].first, 45u);
    EXPECT_EQ(level.primitive_vertex_ranges[1].count, 45u);
    EXPECT_EQ(m.vertexCount(), 90u);
    EXPECT_EQ(m.uvs[0].size(), 90u);
    EXPECT_EQ(m.normals.size(), 90u);
    const SubMesh* primitives[2] = {&m.submeshes[0], &m.submeshes[2]};
    const SubMesh* before[2] = {&original.submeshes[0], &original.submeshes[2]};
    for (size_t p = 0; p < 2; ++p) {
        SCOPED_TRACE("primitive " + std::to_string(p));
        const PackLevel::VertexRange range = level.primitive_vertex_ranges[p];
        ASSERT_EQ(level.primitive_extensions[p].size(), 1u);
        const PackExtension& e = level.primitive_extensions[p][0];
        EXPECT_EQ(e.name, kExt);
        EXPECT_TRUE(e.is_stream);
        const Decoded d = decode(e.blobs[0].data(), e.blobs[0].size());
        EXPECT_EQ(d.info.vertex_count, range.count);
        ASSERT_EQ(d.indices.size(), primitives[p]->index_count);
        for (size_t i = 0; i < d.indices.size(); ++i)
            ASSERT_EQ(d.indices[i] + range.first, m.indices[primitives[p]->first_index + i]) << i;
        const double step = quantizationStep(d.info);
        for (uint32_t v = 0; v < range.count; ++v)
            for (int k = 0; k < 3; ++k)
                ASSERT_NEAR(d.positions[v * 3 + uint32_t(k)], (&m.positions[range.first + v].x)[k], step) << v;
        EXPECT_EQ(subMeshCorners(m, *primitives[p]), subMeshCorners(original, *before[p]));
    }
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
    for (size_t l = 0; l < 2; ++l)
        EXPECT_TRUE(lodbake_test::encodeStreamLevel(encoder, LodChain{}, l, asset.levels[l]).ok());
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
        // UVs are in the stream too (format version 7): every plain vertex accessor goes.
        for (const char* dropped : {"POSITION", "NORMAL", "TEXCOORD_0"}) {
            const nlohmann::json& acc = c["accessors"][prim["attributes"][dropped].get<size_t>()];
            EXPECT_FALSE(acc.contains("bufferView")) << dropped;
            EXPECT_GT(acc["count"].get<int>(), 0);
        }
        EXPECT_TRUE(prim["extensions"][kExt]["attributes"].contains("TEXCOORD_0"));
        EXPECT_FALSE(c["accessors"][prim["indices"].get<size_t>()].contains("bufferView"));
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

CommandResult validateGltf(const std::vector<std::string>& files) {
    std::string command = shellQuote(LODBAKE_TEST_NODE) + " " + shellQuote(src("scripts/node/validate-gltf.js"));
    for (const std::string& f : files) command += " " + shellQuote(f);
    return runCommand(command);
}

PackDescription twoPrimitivePack(bool compact) {
    PackDescription description;
    description.compact = compact;
    PackAsset asset;
    asset.name = "grids";
    asset.levels.resize(2);
    asset.levels[0].mesh = twoPrimitiveGrid(16);
    asset.levels[1].mesh = twoPrimitiveGrid(6);
    asset.screen_coverage = {0.5, 0.0};
    const PackStreamEncoder encoder = valenceStreamEncoder();
    for (size_t l = 0; l < 2; ++l)
        EXPECT_TRUE(lodbake_test::encodeStreamLevel(encoder, LodChain{}, l, asset.levels[l]).ok());
    description.assets.push_back(std::move(asset));
    return description;
}

// Packs of multi-primitive levels: every primitive's stream round-trips against its own accessors,
// the compact pack keeps only the UVs as plain data, loddump decodes it, and the validator accepts both.
TEST(ValenceStreamTest, MultiPrimitivePacksRoundTripAndValidate) {
    Result<std::vector<uint8_t>> plain = writePackGlb(twoPrimitivePack(false));
    Result<std::vector<uint8_t>> compact = writePackGlb(twoPrimitivePack(true));
    ASSERT_TRUE(plain.ok()) << plain.status().message();
    ASSERT_TRUE(compact.ok()) << compact.status().message();
    std::vector<nlohmann::json> objects;
    EXPECT_EQ(checkRoundTrip(*plain, "plain", objects), 4u);
    const nlohmann::json c = lodbake_test::glbJson(*compact);
    EXPECT_EQ(c["extensionsRequired"], nlohmann::json::array({kExt}));
    std::set<size_t> accessors;
    for (const nlohmann::json& mesh : c["meshes"]) {
        ASSERT_EQ(mesh["primitives"].size(), 2u);
        for (const nlohmann::json& prim : mesh["primitives"]) {
            EXPECT_TRUE(prim["extensions"].contains(kExt));
            for (const char* dropped : {"POSITION", "NORMAL", "TEXCOORD_0"})
                EXPECT_FALSE(c["accessors"][prim["attributes"][dropped].get<size_t>()].contains("bufferView"));
            EXPECT_FALSE(c["accessors"][prim["indices"].get<size_t>()].contains("bufferView"));
            for (auto it = prim["attributes"].begin(); it != prim["attributes"].end(); ++it)
                EXPECT_TRUE(accessors.insert(it.value().get<size_t>()).second) << "accessor shared by two primitives";
        }
    }
    const std::string plain_path = outDir() + "/two_primitives.glb",
                      compact_path = outDir() + "/two_primitives_compact.glb";
    std::ofstream(plain_path, std::ios::binary)
        .write(reinterpret_cast<const char*>(plain->data()), std::streamsize(plain->size()));
    std::ofstream(compact_path, std::ios::binary)
        .write(reinterpret_cast<const char*>(compact->data()), std::streamsize(compact->size()));
    for (const std::string& path : {plain_path, compact_path}) {
        const CommandResult d = runCommand(shellQuote(LODBAKE_TEST_LODDUMP) + " " + shellQuote(path));
        EXPECT_EQ(d.exit_code, 0) << path << ": " << d.output;
    }
    const CommandResult v = validateGltf({plain_path, compact_path});
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

// The rock sample is a scan set: six primitives per level, one per scan. A compact bake codes each
// primitive; the plain bake's streams round-trip; loddump reads both and the validator accepts them.
TEST(ValenceStreamTest, ScanSetLevelsGetAStreamPerScan) {
    std::vector<std::string> paths;
    for (bool compact : {false, true}) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(src("assets/samples/rock_scan/rock.conf"), ReadOptions{}, diagnostics);
        ASSERT_TRUE(loaded.ok()) << loaded.status().message();
        BakeSettings settings;
        settings.lod_ratios = {0.1};
        settings.error_samples = 1000;
        settings.textures.enabled = false;
        settings.stream_precision.adaptive = true;
        settings.compact = compact;
        settings.merge = MergeMode::Off; // keep the six scans as six sheets (one primitive each)
        std::vector<BakeInput> inputs(1);
        inputs[0].name = "rock";
        inputs[0].mesh = std::move(loaded->mesh);
        Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics);
        ASSERT_TRUE(out.ok()) << out.status().message();
        const nlohmann::json doc = lodbake_test::glbJson(out->glb);
        size_t primitives = 0, streams = 0;
        for (const nlohmann::json& mesh : doc["meshes"])
            for (const nlohmann::json& prim : mesh["primitives"]) {
                ++primitives;
                streams += prim.contains("extensions") && prim["extensions"].contains(kExt) ? 1 : 0;
            }
        EXPECT_EQ(primitives, 12u);
        EXPECT_EQ(streams, 12u);
        if (!compact) {
            std::vector<nlohmann::json> objects;
            EXPECT_EQ(checkRoundTrip(out->glb, "rock", objects), 12u);
        }
        paths.push_back(outDir() + (compact ? "/rock_compact.glb" : "/rock_plain.glb"));
        std::ofstream(paths.back(), std::ios::binary)
            .write(reinterpret_cast<const char*>(out->glb.data()), std::streamsize(out->glb.size()));
        const CommandResult d = runCommand(shellQuote(LODBAKE_TEST_LODDUMP) + " " + shellQuote(paths.back()));
        EXPECT_EQ(d.exit_code, 0) << d.output;
        EXPECT_EQ(d.output.find("error"), std::string::npos) << d.output;
    }
    const CommandResult v = validateGltf(paths);
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

// Every shared scan, baked with a light preset (no repair, one coarse level, few error samples): every
// level carries a stream (every scan is one primitive), every stream round-trips, and the pack's
// extension objects match the schema. One test per scan, so that CTest spreads them over the cores.
class ValenceStreamScanTest : public ::testing::TestWithParam<const char*> {};

TEST_P(ValenceStreamScanTest, RoundTripsThroughTheRuntimeDecoder) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string name = GetParam();
    BakeSettings settings;
    settings.repair = false;
    settings.lod_ratios = {0.01};
    settings.error_samples = 1000;
    settings.textures.enabled = false;
    settings.threads = 2;
    Diagnostics diagnostics;
    Result<LoadedMesh> loaded = readMesh(lodbake_test::sharedMesh(name), ReadOptions{}, diagnostics);
    ASSERT_TRUE(loaded.ok()) << name << ": " << loaded.status().message();
    std::vector<BakeInput> inputs(1);
    const std::string stem = fs::path(name).stem().string();
    inputs[0].name = stem;
    inputs[0].mesh = std::move(loaded->mesh);
    Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics);
    ASSERT_TRUE(out.ok()) << name << ": " << out.status().message();
    std::vector<nlohmann::json> objects;
    const size_t streams = checkRoundTrip(out->glb, name, objects);
    EXPECT_EQ(streams, settings.lod_ratios.size() + 1) << name;
    std::vector<std::string> files;
    for (size_t i = 0; i < objects.size(); ++i) {
        files.push_back(outDir() + "/" + stem + "_object_" + std::to_string(i) + ".json");
        std::ofstream(files.back()) << objects[i].dump();
    }
    const CommandResult v = validateObjects(files);
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, ValenceStreamScanTest,
                         ::testing::Values("bunny_zipper.ply", "igea.ply", "igea_tristrips.ply", "lucy100k.ply",
                                           "nefertiti.obj", "rocker_arm.obj", "dragon_poisson.ply",
                                           "bunny_scan_bun000_tri.ply", "dragon_scan_stand0_tri.ply",
                                           "dragon_stand_merged.ply", "fandisk.obj", "spot.obj",
                                           "lee_perry_smith/LeePerrySmith.glb",
                                           "nefertiti_fraunhofer_textured.glb"),
                         [](const ::testing::TestParamInfo<const char*>& param_info) {
                             std::string name = fs::path(param_info.param).stem().string();
                             for (char& c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c)))
                                     c = '_';
                             return name;
                         });

// The schema's example is a whole glTF document: its one extension object matches the schema.
TEST(ValenceStreamSchemaTest, ExampleObjectMatchesTheSchema) {
    const nlohmann::json example = nlohmann::json::parse(std::ifstream(src(
        "schemas/LODBAKE_valence_compression/examples/minimal.gltf")))["meshes"][0]["primitives"][0]["extensions"][kExt];
    const std::string file = outDir() + "/example_object.json";
    std::ofstream(file) << example.dump();
    const CommandResult v = validateObjects({file});
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
        {"unknown_attribute",
         R"({"bufferView": 0, "attributes": {"POSITION": 0, "JOINTS_0": 2}, "positionBits": 14})"},
        {"uv_bits_missing",
         R"({"bufferView": 0, "attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "positionBits": 14})"},
        {"tangent_bits_without_tangents",
         R"({"bufferView": 0, "attributes": {"POSITION": 0}, "positionBits": 14, "tangentBits": 10})"},
        {"color_bits_missing",
         R"({"bufferView": 0, "attributes": {"POSITION": 0, "COLOR_0": 2}, "positionBits": 14})"},
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
    const std::string textured = outDir() + "/good_textured.json";
    std::ofstream(textured) << R"({"bufferView": 3, "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2,
                                   "COLOR_0": 3, "TANGENT": 4}, "positionBits": 14, "normalBits": 8,
                                   "uvBits": 12, "colorBits": 8, "tangentBits": 10})";
    const CommandResult vt = validateObjects({textured});
    EXPECT_EQ(vt.exit_code, 0) << vt.output;
}

// A compact pack draws what the plain pack draws: for the textured shared assets, every primitive's
// stream decodes (with every attribute) to the level's plain data, which a plain pack writes: the
// same indices, positions within the position step, UVs within half the UV step, tangents within
// the octahedral step with the same handedness.
TEST(ValenceStreamSharedMeshesTest, TexturedStreamsCarryThePlainGeometryAndAttributes) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    for (const char* name : {"spot.obj", "nefertiti_fraunhofer_textured.glb"}) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(lodbake_test::sharedMesh(name), ReadOptions{}, diagnostics);
        ASSERT_TRUE(loaded.ok()) << loaded.status().message();
        PackLevel level;
        level.mesh = loaded->mesh;
        ASSERT_FALSE(level.mesh.uvs.empty()) << name;
        ASSERT_TRUE(lodbake_test::encodeStreamLevel(valenceStreamEncoder(), LodChain{}, 0, level).ok()) << name;
        const Mesh& m = level.mesh;
        for (size_t p = 0; p < level.primitive_extensions.size(); ++p) {
            const PackExtension& e = level.primitive_extensions[p][0];
            const std::vector<uint8_t>& blob = e.blobs[0];
            lodrt::ValenceInfo info;
            ASSERT_EQ(lodrt::valenceReadInfo(blob.data(), blob.size(), &info), lodrt::Result::Ok);
            const uint32_t first = level.primitive_vertex_ranges.empty() ? 0 : level.primitive_vertex_ranges[p].first;
            std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
            std::vector<float> positions(3 * size_t(info.vertex_count));
            std::vector<std::vector<float>> attributes(info.attribute_count);
            std::vector<uint64_t> scratch((lodrt::valenceScratchSize(info) + 7) / 8);
            lodrt::ValenceOutput out;
            out.indices = indices.data();
            out.index_capacity = indices.size();
            out.positions = positions.data();
            out.position_capacity = positions.size();
            for (uint32_t i = 0; i < info.attribute_count; ++i) {
                attributes[i].resize(size_t(info.attributes[i].components) * info.vertex_count);
                out.attributes[i] = attributes[i].data();
                out.attribute_capacity[i] = attributes[i].size();
            }
            out.scratch = scratch.data();
            out.scratch_size = scratch.size() * 8;
            ASSERT_EQ(lodrt::valenceDecode(blob.data(), blob.size(), out), lodrt::Result::Ok) << name;
            const SubMesh range = m.submeshes.empty() ? SubMesh{"", 0, uint32_t(m.indices.size()), MaterialId::invalid()}
                                                      : m.submeshes[p];
            for (size_t i = 0; i < indices.size(); ++i) ASSERT_EQ(indices[i] + first, m.indices[range.first_index + i]);
            const double step = quantizationStep(info);
            for (size_t v = 0; v < info.vertex_count; ++v)
                for (int k = 0; k < 3; ++k)
                    ASSERT_NEAR(positions[3 * v + size_t(k)], (&m.positions[first + v].x)[k], step) << name << " " << v;
            bool saw_uv = false;
            for (uint32_t i = 0; i < info.attribute_count; ++i) {
                const lodrt::ValenceAttribute& a = info.attributes[i];
                const std::vector<float>& d = attributes[i];
                if (a.kind == lodrt::format::kValenceAttributeUv) {
                    saw_uv = true;
                    const double half = 0.5 * double(a.size[0]) / double((1u << a.bits) - 1) + 1e-6;
                    for (size_t v = 0; v < info.vertex_count; ++v) {
                        ASSERT_NEAR(d[2 * v], m.uvs[a.set][first + v].x, half) << name << " uv " << v;
                        ASSERT_NEAR(d[2 * v + 1], m.uvs[a.set][first + v].y, half) << name << " uv " << v;
                    }
                } else if (a.kind == lodrt::format::kValenceAttributeTangent) {
                    const double tol = 4.0 / double((1u << a.bits) - 1);
                    for (size_t v = 0; v < info.vertex_count; ++v) {
                        const Vec4f& t = m.tangents[first + v];
                        const double len = std::sqrt(double(t.x) * t.x + double(t.y) * t.y + double(t.z) * t.z);
                        if (!(len > 0.0)) continue;
                        ASSERT_NEAR(d[4 * v], t.x / len, tol) << name << " tangent " << v;
                        ASSERT_NEAR(d[4 * v + 1], t.y / len, tol) << name << " tangent " << v;
                        ASSERT_NEAR(d[4 * v + 2], t.z / len, tol) << name << " tangent " << v;
                        ASSERT_EQ(d[4 * v + 3] < 0.0f, t.w < 0.0f) << name << " handedness " << v;
                    }
                }
            }
            EXPECT_TRUE(saw_uv) << name;
        }
    }
}

} // namespace
