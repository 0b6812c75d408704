// glTF import from hand-built documents: node transform flattening (TRS hierarchy, matrices,
// mirroring), strips/fans/points, sparse accessors, KHR_mesh_quantization, external files through
// the side-file loader, materials and KHR_draco_mesh_compression.
#include <algorithm>
#include <cmath>
#include <map>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "lodbake/io/gltf.h"

namespace {

using namespace lodbake;
using nlohmann::json;

// Builds a glTF document with one buffer (embedded as a data: URI or returned for a GLB).
class DocBuilder {
public:
    DocBuilder() {
        doc_["asset"] = {{"version", "2.0"}};
        doc_["accessors"] = json::array();
        doc_["bufferViews"] = json::array();
        doc_["meshes"] = json::array();
    }

    template <class T> int view(const std::vector<T>& values) {
        const size_t offset = lodbake_test::appendValues(bin_, values);
        doc_["bufferViews"].push_back(
            {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", values.size() * sizeof(T)}});
        return int(doc_["bufferViews"].size() - 1);
    }

    template <class T>
    int accessor(const std::vector<T>& values, int component_type, const char* type, size_t count,
                 bool normalized = false) {
        json a = {{"bufferView", view(values)}, {"componentType", component_type}, {"type", type}, {"count", count}};
        if (normalized) a["normalized"] = true;
        doc_["accessors"].push_back(a);
        return int(doc_["accessors"].size() - 1);
    }

    int floats(const std::vector<float>& values, const char* type, size_t components) {
        return accessor(values, 5126, type, values.size() / components);
    }

    int indices(const std::vector<uint16_t>& values) { return accessor(values, 5123, "SCALAR", values.size()); }

    json& doc() { return doc_; }
    std::vector<uint8_t>& bin() { return bin_; }

    std::string gltfText() {
        json d = doc_;
        d["buffers"] = json::array({{{"byteLength", bin_.size()},
                                     {"uri", "data:application/octet-stream;base64," + lodbake_test::base64(bin_)}}});
        return d.dump();
    }

    std::vector<uint8_t> glb() {
        json d = doc_;
        std::vector<uint8_t> bin = bin_;
        while (bin.size() % 4 != 0) bin.push_back(0);
        d["buffers"] = json::array({{{"byteLength", bin.size()}}});
        return lodbake_test::makeGlb(d, bin);
    }

private:
    json doc_;
    std::vector<uint8_t> bin_;
};

SideFileLoader noSideFiles() {
    return [](const std::string& path) -> Result<std::vector<uint8_t>> { return ioError(path + ": not found"); };
}

Result<LoadedMesh> readText(const std::string& text, Diagnostics& diagnostics,
                            const SideFileLoader& loader = noSideFiles(), const std::string& name = "test.gltf") {
    return readGltfFromMemory(reinterpret_cast<const uint8_t*>(text.data()), text.size(), name, loader, ReadOptions{},
                              diagnostics);
}

// One triangle in the z=0 plane facing +Z, with normals and a tangent along +X.
int addTriangleMesh(DocBuilder& b, const std::string& name) {
    const int pos = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3", 3);
    const int nrm = b.floats({0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3", 3);
    const int tan = b.floats({1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}, "VEC4", 4);
    const int idx = b.indices({0, 1, 2});
    b.doc()["meshes"].push_back(
        {{"name", name},
         {"primitives",
          json::array({{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TANGENT", tan}}}, {"indices", idx}}})}});
    return int(b.doc()["meshes"].size() - 1);
}

Vec3d faceNormal(const Mesh& m, size_t f) {
    const Vec3d a = toDouble(m.positions[m.indices[f * 3]]);
    const Vec3d b = toDouble(m.positions[m.indices[f * 3 + 1]]);
    const Vec3d c = toDouble(m.positions[m.indices[f * 3 + 2]]);
    return cross(b - a, c - a);
}

void expectNear(const Vec3f& a, const Vec3d& b, double tolerance = 1e-5) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(GltfImportTest, NodeHierarchyIsFlattenedWithMirroring) {
    DocBuilder b;
    const int mesh = addTriangleMesh(b, "tri");
    const double s = std::sqrt(0.5);
    b.doc()["nodes"] = json::array({
        // 0: translate (10,0,0), rotate 90 degrees about Z, scale 2; child 1 adds (0,0,5) and holds the mesh.
        {{"translation", {10, 0, 0}}, {"rotation", {0, 0, s, s}}, {"scale", {2, 2, 2}}, {"children", {1}}},
        {{"translation", {0, 0, 5}}, {"mesh", mesh}},
        // 2: mirrored in X by a matrix (column-major), with a translation of (0,0,-3).
        {{"matrix", {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -3, 1}}, {"mesh", mesh}},
        // 3: not in the scene: must be ignored.
        {{"mesh", mesh}, {"translation", {100, 100, 100}}},
    });
    b.doc()["scenes"] = json::array({{{"nodes", {0, 2}}}});
    b.doc()["scene"] = 0;
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.vertexCount(), 6u);
    ASSERT_EQ(m.faceCount(), 2u);
    ASSERT_EQ(m.submeshes.size(), 2u);
    // Instance 1: p -> R(z,90) * 2 * (p + (0,0,5)) + (10,0,0); R maps (x,y) to (-y,x).
    expectNear(m.positions[0], Vec3d(10, 0, 10));
    expectNear(m.positions[1], Vec3d(10, 2, 10));
    expectNear(m.positions[2], Vec3d(8, 0, 10));
    expectNear(m.normals[1], Vec3d(0, 0, 1));
    EXPECT_NEAR(m.tangents[1].y, 1.0, 1e-6); // +X rotated to +Y
    EXPECT_EQ(m.tangents[1].w, 1.0f);
    // Instance 2: mirrored; positions mirrored, winding flipped so the geometric normal still agrees
    // with the (inverse-transpose) normal, tangent handedness flipped.
    expectNear(m.positions[4], Vec3d(-1, 0, -3));
    expectNear(m.normals[4], Vec3d(0, 0, 1));
    expectNear(Vec3f(m.tangents[4].x, m.tangents[4].y, m.tangents[4].z), Vec3d(-1, 0, 0));
    EXPECT_EQ(m.tangents[4].w, -1.0f);
    EXPECT_EQ(m.indices[3], 3u);
    EXPECT_EQ(m.indices[4], 5u);
    EXPECT_EQ(m.indices[5], 4u);
    for (size_t f = 0; f < m.faceCount(); ++f) {
        const Vec3d n = faceNormal(m, f);
        EXPECT_GT(dot(n, toDouble(m.normals[m.indices[f * 3]])), 0.0) << "face " << f;
    }
    EXPECT_EQ(r->source.file_vertex_count, 3u);
    EXPECT_EQ(r->source.file_face_count, 1u);
}

TEST(GltfImportTest, NoScenesMeansEveryMeshAndDefaultSceneIsHonoured) {
    DocBuilder b;
    addTriangleMesh(b, "a");
    addTriangleMesh(b, "b");
    Diagnostics d1;
    Result<LoadedMesh> all = readText(b.gltfText(), d1);
    ASSERT_TRUE(all.ok()) << all.status().message();
    EXPECT_EQ(all->mesh.faceCount(), 2u);

    b.doc()["nodes"] = json::array({{{"mesh", 0}}, {{"mesh", 1}, {"translation", {0, 0, 1}}}});
    b.doc()["scenes"] = json::array({{{"nodes", {0}}}, {{"nodes", {1}}}});
    b.doc()["scene"] = 1;
    Diagnostics d2;
    Result<LoadedMesh> second = readText(b.gltfText(), d2);
    ASSERT_TRUE(second.ok()) << second.status().message();
    ASSERT_EQ(second->mesh.faceCount(), 1u);
    EXPECT_EQ(second->mesh.positions[0].z, 1.0f);
    EXPECT_EQ(second->mesh.submeshes[0].name, "b");
}

TEST(GltfImportTest, StripsAndFansAreTriangulatedPointsSkipped) {
    DocBuilder b;
    const int pos = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 2, 0}, "VEC3", 3);
    b.doc()["meshes"].push_back({{"primitives", json::array({{{"attributes", {{"POSITION", pos}}}, {"mode", 5}},
                                                             {{"attributes", {{"POSITION", pos}}}, {"mode", 6}},
                                                             {{"attributes", {{"POSITION", pos}}}, {"mode", 0}},
                                                             {{"attributes", {{"POSITION", pos}}}, {"mode", 1}}})}});
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.submeshes.size(), 2u);
    EXPECT_EQ(m.faceCount(), 6u); // strip of 5 -> 3, fan of 5 -> 3
    // The strip's triangles of this planar layout all face +Z (parity handled); the fan follows the
    // spec's (i+1, i+2, 0) order.
    for (size_t f = 0; f < 3; ++f) EXPECT_GT(faceNormal(m, f).z, 0.0) << "face " << f;
    EXPECT_EQ(std::vector<uint32_t>(m.indices.begin(), m.indices.begin() + 9),
              (std::vector<uint32_t>{0, 1, 2, 1, 3, 2, 2, 3, 4}));
    EXPECT_EQ(std::vector<uint32_t>(m.indices.begin() + 9, m.indices.end()),
              (std::vector<uint32_t>{1, 2, 0, 2, 3, 0, 3, 4, 0}));
    EXPECT_EQ(m.vertexCount(), 5u); // both primitives use the same accessors, so they share vertices
    size_t skipped = 0;
    for (const auto& item : diagnostics.items())
        if (item.message.find("point/line primitive skipped") != std::string::npos) ++skipped;
    EXPECT_EQ(skipped, 2u);
}

TEST(GltfImportTest, SparseAccessorAndMissingIndices) {
    DocBuilder b;
    const int pos = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 5, 5, 6, 6, 6, 7, 7, 7}, "VEC3", 3);
    const int sparse_idx = b.view(std::vector<uint16_t>{1, 4});
    const int sparse_val = b.view(std::vector<float>{9, 8, 7, 6, 5, 4});
    b.doc()["accessors"][size_t(pos)]["sparse"] = {{"count", 2},
                                                   {"indices", {{"bufferView", sparse_idx}, {"componentType", 5123}}},
                                                   {"values", {{"bufferView", sparse_val}}}};
    b.doc()["meshes"].push_back({{"primitives", json::array({{{"attributes", {{"POSITION", pos}}}}})}});
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    EXPECT_EQ(m.indices, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5}));
    expectNear(m.positions[1], Vec3d(9, 8, 7));
    expectNear(m.positions[4], Vec3d(6, 5, 4));
    expectNear(m.positions[3], Vec3d(5, 5, 5));
}

TEST(GltfImportTest, QuantizedAttributesAreDequantized) {
    DocBuilder b;
    // Unnormalized unsigned short positions scaled by the node; normalized byte normals; normalized
    // unsigned byte UVs and VEC3 colours.
    const int pos = b.accessor(std::vector<uint16_t>{0, 0, 0, 0, 100, 0, 0, 0, 0, 100, 0, 0}, 5123, "VEC3", 3);
    b.doc()["accessors"][size_t(pos)]["min"] = {0, 0, 0};
    b.doc()["accessors"][size_t(pos)]["max"] = {100, 100, 0};
    // Each VEC3 of uint16 takes 6 bytes; the spec pads vertex elements to 4 bytes via byteStride.
    b.doc()["bufferViews"][size_t(b.doc()["accessors"][size_t(pos)]["bufferView"].get<int>())]["byteStride"] = 8;
    const int nrm = b.accessor(std::vector<int8_t>{0, 0, 127, 0, 0, 0, 127, 0, -128, 0, 0, 0}, 5120, "VEC3", 3, true);
    b.doc()["bufferViews"][size_t(b.doc()["accessors"][size_t(nrm)]["bufferView"].get<int>())]["byteStride"] = 4;
    const int uv = b.accessor(std::vector<uint8_t>{0, 255, 0, 0, 255, 0, 0, 0, 51, 51, 0, 0}, 5121, "VEC2", 3, true);
    b.doc()["bufferViews"][size_t(b.doc()["accessors"][size_t(uv)]["bufferView"].get<int>())]["byteStride"] = 4;
    const int col = b.accessor(std::vector<uint8_t>{255, 0, 0, 0, 0, 255, 0, 0, 0, 0, 255, 0}, 5121, "VEC3", 3, true);
    b.doc()["bufferViews"][size_t(b.doc()["accessors"][size_t(col)]["bufferView"].get<int>())]["byteStride"] = 4;
    b.doc()["meshes"].push_back(
        {{"primitives",
          json::array(
              {{{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", uv}, {"COLOR_0", col}}}}})}});
    b.doc()["nodes"] = json::array({{{"mesh", 0}, {"scale", {0.01, 0.01, 0.01}}}});
    b.doc()["scenes"] = json::array({{{"nodes", {0}}}});
    b.doc()["extensionsUsed"] = {"KHR_mesh_quantization"};
    b.doc()["extensionsRequired"] = {"KHR_mesh_quantization"};
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    const Mesh& m = r->mesh;
    expectNear(m.positions[1], Vec3d(1, 0, 0));
    expectNear(m.positions[2], Vec3d(0, 1, 0));
    expectNear(m.normals[0], Vec3d(0, 0, 1));
    expectNear(m.normals[2], Vec3d(-1, 0, 0));
    EXPECT_FLOAT_EQ(m.uvs[0][0].y, 1.0f);
    EXPECT_FLOAT_EQ(m.uvs[0][2].x, 0.2f);
    EXPECT_FLOAT_EQ(m.colors[1].y, 1.0f);
    EXPECT_FLOAT_EQ(m.colors[1].w, 1.0f);

    // Without the extension, integer positions are refused with a message naming the accessor.
    b.doc().erase("extensionsUsed");
    b.doc().erase("extensionsRequired");
    Diagnostics d2;
    Result<LoadedMesh> refused = readText(b.gltfText(), d2);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.status().message().find("accessor 0 (POSITION): integer positions need KHR_mesh_quantization"),
              std::string::npos)
        << refused.status().message();
}

TEST(GltfImportTest, ExternalBufferAndImageGoThroughTheLoader) {
    DocBuilder b;
    addTriangleMesh(b, "tri");
    b.doc()["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = b.floats({0, 0, 1, 0, 0, 1}, "VEC2", 2);
    json d = b.doc();
    d["buffers"] = json::array({{{"byteLength", b.bin().size()}, {"uri", "geo%20data.bin"}}});
    d["images"] = json::array({{{"uri", "tex.png"}}});
    d["textures"] = json::array({{{"source", 0}}});
    d["materials"] =
        json::array({{{"name", "m"},
                      {"alphaMode", "BLEND"},
                      {"emissiveTexture", {{"index", 0}, {"texCoord", 3}}},
                      {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}}}}});
    d["meshes"][0]["primitives"][0]["material"] = 0;
    const std::string text = d.dump();
    std::vector<std::string> requested;
    const std::vector<uint8_t> bin = b.bin();
    SideFileLoader loader = [&](const std::string& path) -> Result<std::vector<uint8_t>> {
        requested.push_back(path);
        if (path.find(".bin") != std::string::npos) return bin;
        if (path == "assets/tex.png") return lodbake_test::tinyPng();
        return ioError(path + ": not found");
    };
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(text, diagnostics, loader, "assets/scene.gltf");
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(requested.size(), 2u);
    EXPECT_EQ(requested[0], "assets/geo data.bin");
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.textures.size(), 1u);
    EXPECT_EQ(m.textures[0].uri, "tex.png");
    EXPECT_EQ(m.textures[0].mime_type, "image/png");
    EXPECT_EQ(m.textures[0].bytes, lodbake_test::tinyPng());
    ASSERT_EQ(m.materials.size(), 1u);
    EXPECT_EQ(m.materials[0].alpha_mode, AlphaMode::Blend);
    EXPECT_EQ(m.materials[0].metallic_factor, 0.0f);
    EXPECT_EQ(m.materials[0].base_color_texture.texture, 0);
    // TEXCOORD_3 does not exist: the slot is dropped with a warning, keeping the mesh consistent.
    EXPECT_FALSE(m.materials[0].emissive_texture.isSet());
    EXPECT_EQ(diagnostics.warningCount(), 1u);
    EXPECT_TRUE(checkMeshConsistency(m, "x").ok());
    EXPECT_EQ(m.submeshes[0].material.value, 0u);
}

TEST(GltfImportTest, ErrorsNameTheElement) {
    DocBuilder b;
    const int pos = b.floats({0, 0, 0, 1, 0, 0, 0, 1, 0}, "VEC3", 3);
    const int idx = b.indices({0, 1, 9});
    b.doc()["meshes"].push_back(
        {{"name", "Rock"}, {"primitives", json::array({{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}})}});
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().message(), "test.gltf: mesh \"Rock\" primitive 0: index 2 is 9, out of range (3 vertices)");

    b.doc()["extensionsRequired"] = {"KHR_unknown_thing"};
    Result<LoadedMesh> ext = readText(b.gltfText(), diagnostics);
    ASSERT_FALSE(ext.ok());
    EXPECT_NE(ext.status().message().find("KHR_unknown_thing"), std::string::npos);
}

// ---- Draco ----------------------------------------------------------------------------------------

struct Grid {
    std::vector<Vec3f> positions;
    std::vector<Vec2f> uvs;
    std::vector<std::array<uint32_t, 3>> triangles;
};

Grid makeGrid(int n) {
    Grid g;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) {
            g.positions.push_back(Vec3f(float(x) * 0.37f, float(y) * 0.21f, std::sin(float(x + y)) * 0.5f));
            g.uvs.push_back(Vec2f(float(x) / float(n), float(y) / float(n)));
        }
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const uint32_t a = uint32_t(y * (n + 1) + x), b = a + 1, c = a + uint32_t(n + 1), d = c + 1;
            g.triangles.push_back({a, b, d});
            g.triangles.push_back({a, d, c});
        }
    return g;
}

TEST(GltfImportTest, DracoCompressedGlbDecodesToTheSourceTriangles) {
    const Grid grid = makeGrid(6);
    draco::TriangleSoupMeshBuilder builder;
    builder.Start(int(grid.triangles.size()));
    const int pos_att = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    const int uv_att = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
    for (size_t f = 0; f < grid.triangles.size(); ++f) {
        const auto& t = grid.triangles[f];
        builder.SetAttributeValuesForFace(pos_att, draco::FaceIndex(uint32_t(f)), &grid.positions[t[0]].x,
                                          &grid.positions[t[1]].x, &grid.positions[t[2]].x);
        builder.SetAttributeValuesForFace(uv_att, draco::FaceIndex(uint32_t(f)), &grid.uvs[t[0]].x, &grid.uvs[t[1]].x,
                                          &grid.uvs[t[2]].x);
    }
    std::unique_ptr<draco::Mesh> dmesh = builder.Finalize();
    ASSERT_NE(dmesh, nullptr);
    draco::Encoder encoder;
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 14);
    encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, 12);
    draco::EncoderBuffer encoded;
    ASSERT_TRUE(encoder.EncodeMeshToBuffer(*dmesh, &encoded).ok());

    std::vector<uint8_t> bin(encoded.data(), encoded.data() + encoded.size());
    json doc;
    doc["asset"] = {{"version", "2.0"}};
    doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    doc["bufferViews"] = json::array({{{"buffer", 0}, {"byteLength", bin.size()}}});
    while (bin.size() % 4 != 0) bin.push_back(0);
    doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
    doc["accessors"] = json::array({
        {{"componentType", 5126}, {"type", "VEC3"}, {"count", dmesh->num_points()}},
        {{"componentType", 5126}, {"type", "VEC2"}, {"count", dmesh->num_points()}},
        {{"componentType", 5125}, {"type", "SCALAR"}, {"count", dmesh->num_faces() * 3}},
    });
    doc["meshes"] = json::array(
        {{{"primitives", json::array({{{"attributes", {{"POSITION", 0}, {"TEXCOORD_0", 1}}},
                                       {"indices", 2},
                                       {"extensions",
                                        {{"KHR_draco_mesh_compression",
                                          {{"bufferView", 0},
                                           {"attributes",
                                            {{"POSITION", dmesh->attribute(pos_att)->unique_id()},
                                             {"TEXCOORD_0", dmesh->attribute(uv_att)->unique_id()}}}}}}}}})}}});
    doc["nodes"] = json::array({{{"mesh", 0}}});
    doc["scenes"] = json::array({{{"nodes", {0}}}});
    const std::vector<uint8_t> glb = lodbake_test::makeGlb(doc, bin);

    Diagnostics diagnostics;
    Result<LoadedMesh> r =
        readGltfFromMemory(glb.data(), glb.size(), "draco.glb", noSideFiles(), ReadOptions{}, diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->source.encoding, "glb+draco");
    const Mesh& m = r->mesh;
    ASSERT_EQ(m.faceCount(), grid.triangles.size());
    ASSERT_EQ(m.uvs.size(), 1u);
    // Draco may reorder faces and rotate corners: match every source triangle to a decoded one with
    // the same corners in the same cyclic order, within the quantisation step.
    const double pos_tolerance = 2.5 / double(1 << 14) * 2.0; // extent 2.22 over 14 bits, doubled
    const double uv_tolerance = 2.0 / double(1 << 12);
    std::vector<bool> used(m.faceCount(), false);
    for (const auto& t : grid.triangles) {
        bool found = false;
        for (size_t f = 0; f < m.faceCount() && !found; ++f) {
            if (used[f]) continue;
            for (int rot = 0; rot < 3 && !found; ++rot) {
                bool same = true;
                for (int k = 0; k < 3 && same; ++k) {
                    const uint32_t v = m.indices[f * 3 + size_t((k + rot) % 3)];
                    const Vec3f& p = m.positions[v];
                    const Vec3f& q = grid.positions[t[size_t(k)]];
                    same = std::fabs(p.x - q.x) < pos_tolerance && std::fabs(p.y - q.y) < pos_tolerance &&
                           std::fabs(p.z - q.z) < pos_tolerance &&
                           std::fabs(m.uvs[0][v].x - grid.uvs[t[size_t(k)]].x) < uv_tolerance &&
                           std::fabs(m.uvs[0][v].y - grid.uvs[t[size_t(k)]].y) < uv_tolerance;
                }
                if (same) found = used[f] = true;
            }
        }
        EXPECT_TRUE(found) << "source triangle " << t[0] << " " << t[1] << " " << t[2] << " not decoded";
    }

    // A damaged Draco stream (truncated, or with flipped bytes) is refused or decoded, never a crash;
    // truncation must always be refused.
    const size_t draco_size = encoded.size();
    for (size_t cut = 0; cut < draco_size; cut += 5) {
        json d = doc;
        d["bufferViews"][0]["byteLength"] = cut == 0 ? 1 : cut;
        const std::vector<uint8_t> truncated = lodbake_test::makeGlb(d, bin);
        Diagnostics dd;
        Result<LoadedMesh> t =
            readGltfFromMemory(truncated.data(), truncated.size(), "cut.glb", noSideFiles(), ReadOptions{}, dd);
        EXPECT_FALSE(t.ok()) << "truncated at " << cut;
        if (!t.ok()) {
            EXPECT_NE(t.status().message().find("KHR_draco_mesh_compression"), std::string::npos)
                << t.status().message();
        }
    }
    for (size_t at = 0; at < draco_size; at += 3) {
        std::vector<uint8_t> flipped = bin;
        flipped[at] ^= 0x5A;
        const std::vector<uint8_t> damaged = lodbake_test::makeGlb(doc, flipped);
        Diagnostics dd;
        Result<LoadedMesh> t =
            readGltfFromMemory(damaged.data(), damaged.size(), "flip.glb", noSideFiles(), ReadOptions{}, dd);
        if (t.ok()) {
            EXPECT_EQ(t->mesh.faceCount(), grid.triangles.size());
        }
    }

    // Accessor counts must agree with the Draco data.
    doc["accessors"][0]["count"] = dmesh->num_points() + 1;
    const std::vector<uint8_t> bad = lodbake_test::makeGlb(doc, bin);
    Result<LoadedMesh> refused =
        readGltfFromMemory(bad.data(), bad.size(), "draco.glb", noSideFiles(), ReadOptions{}, diagnostics);
    ASSERT_FALSE(refused.ok());
    EXPECT_NE(refused.status().message().find("accessor 0 (POSITION)"), std::string::npos)
        << refused.status().message();
}

} // namespace

namespace {

// Damaged files (bytes flipped, lengths cut) are refused with a message or read, never a crash.
TEST(GltfImportTest, RandomlyDamagedFilesNeverCrash) {
    Result<GltfFiles> files = writeGltfToMemory(lodbake_test::richMesh(), GltfWriteOptions{});
    ASSERT_TRUE(files.ok());
    const std::vector<uint8_t>& glb = files->main;
    uint64_t state = 0x9E3779B97F4A7C15ull; // fixed seed: the same cases every run
    auto next = [&]() {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(state >> 33);
    };
    size_t refused = 0;
    for (int round = 0; round < 400; ++round) {
        std::vector<uint8_t> damaged = glb;
        const int flips = 1 + int(next() % 4);
        for (int k = 0; k < flips; ++k) damaged[next() % damaged.size()] = uint8_t(next());
        if (round % 5 == 0) damaged.resize(next() % damaged.size());
        Diagnostics diagnostics;
        Result<LoadedMesh> r = readGltfFromMemory(damaged.data(), damaged.size(), "damaged.glb", noSideFiles(),
                                                  ReadOptions{}, diagnostics);
        if (!r.ok()) {
            ++refused;
            EXPECT_EQ(r.status().message().rfind("damaged.glb: ", 0), 0u) << r.status().message();
            EXPECT_EQ(r.status().message().find('\n'), std::string::npos) << r.status().message();
        }
    }
    EXPECT_GT(refused, 80u); // every truncation at least
}

} // namespace

namespace {

TEST(GltfImportTest, AccessorWithoutDataCannotClaimHugeCounts) {
    DocBuilder b;
    const int idx = b.indices({0, 1, 2});
    b.doc()["accessors"].push_back({{"componentType", 5126}, {"type", "VEC3"}, {"count", 200000000}});
    const int pos = int(b.doc()["accessors"].size() - 1);
    b.doc()["meshes"].push_back(
        {{"primitives", json::array({{{"attributes", {{"POSITION", pos}}}, {"indices", idx}}})}});
    Diagnostics diagnostics;
    Result<LoadedMesh> r = readText(b.gltfText(), diagnostics);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::ResourceLimit);
    EXPECT_NE(r.status().message().find("accessor 1 (POSITION): count 200000000 without a bufferView"),
              std::string::npos)
        << r.status().message();
    // A small one is all zeros, as the spec says.
    b.doc()["accessors"][size_t(pos)]["count"] = 3;
    Result<LoadedMesh> zeros = readText(b.gltfText(), diagnostics);
    ASSERT_TRUE(zeros.ok()) << zeros.status().message();
    EXPECT_EQ(zeros->mesh.positions[2].x, 0.0f);
}

} // namespace
