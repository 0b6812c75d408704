// glTF export: round trips through our importer attribute by attribute, index width, byte layout,
// determinism and the fixes that keep the Khronos validator quiet.
#include <cmath>
#include <map>

#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "lodbake/io/gltf.h"
#include "lodbake/version.h"

namespace {

using namespace lodbake;

SideFileLoader noSideFiles() {
    return
        [](const std::string& path) -> Result<std::vector<uint8_t>> { return ioError(path + ": no side files here"); };
}

LoadedMesh importGlb(const std::vector<uint8_t>& bytes) {
    Diagnostics diagnostics;
    Result<LoadedMesh> r =
        readGltfFromMemory(bytes.data(), bytes.size(), "mem.glb", noSideFiles(), ReadOptions{}, diagnostics);
    EXPECT_TRUE(r.ok()) << r.status().message();
    return r.ok() ? std::move(r).value() : LoadedMesh{};
}

std::vector<uint8_t> exportGlb(const Mesh& mesh) {
    Result<GltfFiles> files = writeGltfToMemory(mesh, GltfWriteOptions{});
    EXPECT_TRUE(files.ok()) << files.status().message();
    return files.ok() ? files->main : std::vector<uint8_t>{};
}

void expectSameMesh(const Mesh& a, const Mesh& b) {
    ASSERT_EQ(a.positions.size(), b.positions.size());
    ASSERT_EQ(a.indices, b.indices);
    for (size_t i = 0; i < a.positions.size(); ++i) {
        EXPECT_EQ(a.positions[i].x, b.positions[i].x) << i;
        EXPECT_EQ(a.positions[i].y, b.positions[i].y) << i;
        EXPECT_EQ(a.positions[i].z, b.positions[i].z) << i;
    }
    ASSERT_EQ(a.normals.size(), b.normals.size());
    for (size_t i = 0; i < a.normals.size(); ++i) {
        EXPECT_NEAR(a.normals[i].x, b.normals[i].x, 1e-6) << i;
        EXPECT_NEAR(a.normals[i].y, b.normals[i].y, 1e-6) << i;
        EXPECT_NEAR(a.normals[i].z, b.normals[i].z, 1e-6) << i;
    }
    ASSERT_EQ(a.tangents.size(), b.tangents.size());
    for (size_t i = 0; i < a.tangents.size(); ++i) {
        EXPECT_NEAR(a.tangents[i].x, b.tangents[i].x, 1e-6) << i;
        EXPECT_NEAR(a.tangents[i].y, b.tangents[i].y, 1e-6) << i;
        EXPECT_NEAR(a.tangents[i].z, b.tangents[i].z, 1e-6) << i;
        EXPECT_EQ(a.tangents[i].w, b.tangents[i].w) << i;
    }
    ASSERT_EQ(a.uvs.size(), b.uvs.size());
    for (size_t s = 0; s < a.uvs.size(); ++s)
        for (size_t i = 0; i < a.uvs[s].size(); ++i) {
            EXPECT_EQ(a.uvs[s][i].x, b.uvs[s][i].x) << s << " " << i;
            EXPECT_EQ(a.uvs[s][i].y, b.uvs[s][i].y) << s << " " << i;
        }
    ASSERT_EQ(a.colors.size(), b.colors.size());
    for (size_t i = 0; i < a.colors.size(); ++i) {
        EXPECT_EQ(a.colors[i].x, b.colors[i].x) << i;
        EXPECT_EQ(a.colors[i].y, b.colors[i].y) << i;
        EXPECT_EQ(a.colors[i].z, b.colors[i].z) << i;
        EXPECT_EQ(a.colors[i].w, b.colors[i].w) << i;
    }
}

TEST(GltfExportTest, GlbRoundTripKeepsEveryAttribute) {
    const Mesh source = lodbake_test::richMesh();
    const LoadedMesh loaded = importGlb(exportGlb(source));
    expectSameMesh(source, loaded.mesh);
    EXPECT_EQ(loaded.source.encoding, "glb");
    EXPECT_EQ(loaded.source.file_vertex_count, 8u); // one POSITION accessor shared by both primitives
    EXPECT_EQ(loaded.source.file_face_count, 4u);
}

TEST(GltfExportTest, RoundTripKeepsSubMeshesMaterialsAndTextures) {
    const Mesh source = lodbake_test::richMesh();
    const Mesh mesh = importGlb(exportGlb(source)).mesh;
    ASSERT_EQ(mesh.submeshes.size(), 2u);
    // One primitive per sub-mesh, each over the shared vertex streams: the importer flattens them
    // into two copies of the vertices, so compare the triangles through the positions.
    for (size_t s = 0; s < 2; ++s) {
        const SubMesh& in = source.submeshes[s];
        const SubMesh& out = mesh.submeshes[s];
        EXPECT_EQ(out.index_count, in.index_count);
        EXPECT_EQ(out.material.value, in.material.value);
        for (uint32_t k = 0; k < in.index_count; ++k) {
            const Vec3f& a = source.positions[source.indices[in.first_index + k]];
            const Vec3f& b = mesh.positions[mesh.indices[out.first_index + k]];
            EXPECT_EQ(a.x, b.x);
            EXPECT_EQ(a.y, b.y);
            EXPECT_EQ(a.z, b.z);
        }
    }
    ASSERT_EQ(mesh.materials.size(), 2u);
    const Material& t = mesh.materials[0];
    EXPECT_EQ(t.name, "textured");
    EXPECT_EQ(t.base_color_factor.y, 0.75f);
    EXPECT_EQ(t.metallic_factor, 0.25f);
    EXPECT_EQ(t.roughness_factor, 0.75f);
    EXPECT_EQ(t.base_color_texture.texture, 0);
    EXPECT_EQ(t.normal_texture.texcoord, 1u);
    EXPECT_EQ(t.normal_scale, 0.5f);
    EXPECT_FLOAT_EQ(t.emissive_factor.z, 0.3f);
    EXPECT_TRUE(t.is_double_sided);
    const Material& m = mesh.materials[1];
    EXPECT_EQ(m.alpha_mode, AlphaMode::Mask);
    EXPECT_EQ(m.alpha_cutoff, 0.25f);
    EXPECT_EQ(m.occlusion_texture.texture, 0);
    EXPECT_EQ(m.occlusion_strength, 0.5f);
    ASSERT_EQ(mesh.textures.size(), 1u);
    EXPECT_EQ(mesh.textures[0].mime_type, "image/png");
    EXPECT_EQ(mesh.textures[0].bytes, lodbake_test::tinyPng());
}

TEST(GltfExportTest, GltfWithSideBinRoundTrips) {
    const Mesh source = lodbake_test::richMesh();
    GltfWriteOptions options;
    options.binary = false;
    options.bin_name = "rich mesh.bin";
    Result<GltfFiles> files = writeGltfToMemory(source, options);
    ASSERT_TRUE(files.ok()) << files.status().message();
    ASSERT_FALSE(files->bin.empty());
    EXPECT_EQ(files->bin.size() % 4, 0u);
    const auto json = nlohmann::json::parse(files->main.begin(), files->main.end());
    EXPECT_EQ(json["buffers"][0]["uri"], "rich%20mesh.bin");
    EXPECT_EQ(json["buffers"][0]["byteLength"], files->bin.size());
    std::vector<std::string> requested;
    SideFileLoader loader = [&](const std::string& path) -> Result<std::vector<uint8_t>> {
        requested.push_back(path);
        if (path == "dir/rich mesh.bin") return files->bin;
        return ioError(path + ": not found");
    };
    Diagnostics diagnostics;
    Result<LoadedMesh> r =
        readGltfFromMemory(files->main.data(), files->main.size(), "dir/rich.gltf", loader, ReadOptions{}, diagnostics);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->source.encoding, "gltf");
    expectSameMesh(source, r->mesh);
    ASSERT_EQ(requested.size(), 1u);
    ASSERT_EQ(r->mesh.textures.size(), 1u);
    EXPECT_EQ(r->mesh.textures[0].bytes, lodbake_test::tinyPng());
}

TEST(GltfExportTest, BytesAreDeterministicAndAligned) {
    const Mesh source = lodbake_test::richMesh();
    const std::vector<uint8_t> a = exportGlb(source);
    const std::vector<uint8_t> b = exportGlb(source);
    EXPECT_EQ(a, b);
    ASSERT_GT(a.size(), 20u);
    EXPECT_EQ(a.size() % 4, 0u);
    const nlohmann::json json = lodbake_test::glbJson(a);
    EXPECT_EQ(json["asset"]["generator"], std::string("lodbake ") + kVersionString);
    EXPECT_EQ(json["asset"]["version"], "2.0");
    EXPECT_EQ(json["scene"], 0);
    ASSERT_EQ(json["nodes"].size(), 1u);
    ASSERT_EQ(json["meshes"].size(), 1u);
    EXPECT_EQ(json["meshes"][0]["primitives"].size(), 2u);
    for (const auto& view : json["bufferViews"]) EXPECT_EQ(view.value("byteOffset", 0u) % 4, 0u);
    for (const auto& accessor : json["accessors"]) EXPECT_FALSE(accessor.contains("byteStride"));
    EXPECT_EQ(json["images"][0]["mimeType"], "image/png");
}

TEST(GltfExportTest, PositionBoundsAreExact) {
    Mesh mesh = lodbake_test::richMesh();
    mesh.positions[3] = Vec3f(-0.1f, 1.3f, -7.77f);
    const nlohmann::json json = lodbake_test::glbJson(exportGlb(mesh));
    const int position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
    const auto& accessor = json["accessors"][size_t(position)];
    EXPECT_EQ(float(accessor["min"][0].get<double>()), -0.1f);
    EXPECT_EQ(float(accessor["max"][1].get<double>()), 1.3f);
    EXPECT_EQ(float(accessor["min"][2].get<double>()), -7.77f);
    EXPECT_EQ(float(accessor["max"][0].get<double>()), 3.0f);
}

int indexComponentType(const Mesh& mesh) {
    const nlohmann::json json = lodbake_test::glbJson(exportGlb(mesh));
    const int indices = json["meshes"][0]["primitives"][0]["indices"];
    return json["accessors"][size_t(indices)]["componentType"];
}

TEST(GltfExportTest, IndexWidthFollowsVertexCount) {
    Mesh small;
    small.positions.resize(65535);
    for (size_t i = 0; i < small.positions.size(); ++i)
        small.positions[i] = Vec3f(float(i % 256), float(i / 256), 0.0f);
    small.indices = {0, 1, 65534};
    EXPECT_EQ(indexComponentType(small), 5123);
    Mesh large = small;
    large.positions.push_back(Vec3f(0.0f, 0.0f, 1.0f));
    large.indices = {0, 1, 65535};
    EXPECT_EQ(indexComponentType(large), 5125);
    const Mesh back = importGlb(exportGlb(large)).mesh;
    EXPECT_EQ(back.indices, large.indices);
}

TEST(GltfExportTest, ZeroAndNonUnitNormalsAreFixed) {
    Mesh mesh = lodbake_test::richMesh();
    mesh.normals[0] = Vec3f(0.0f, 0.0f, 0.0f);
    mesh.normals[1] = Vec3f(0.0f, 0.0f, 3.0f);
    mesh.tangents[2] = Vec4f(0.0f, 0.0f, 0.0f, -1.0f);
    const Mesh back = importGlb(exportGlb(mesh)).mesh;
    for (const Vec3f& n : back.normals) EXPECT_NEAR(length(Vec3d(n)), 1.0, 1e-6);
    // The zero normal is replaced by the normal of the faces around it: +Z for this flat quad.
    EXPECT_NEAR(back.normals[0].z, 1.0f, 1e-6);
    EXPECT_NEAR(back.normals[1].z, 1.0f, 1e-6);
    const Vec4f& t = back.tangents[2];
    EXPECT_NEAR(std::sqrt(t.x * t.x + t.y * t.y + t.z * t.z), 1.0, 1e-6);
    EXPECT_NEAR(t.x * back.normals[2].x + t.y * back.normals[2].y + t.z * back.normals[2].z, 0.0, 1e-6);
    EXPECT_EQ(t.w, -1.0f);
}

TEST(GltfExportTest, RefusesMeshesItCannotWrite) {
    Mesh empty;
    empty.positions = {{0, 0, 0}};
    EXPECT_FALSE(writeGltfToMemory(empty, GltfWriteOptions{}).ok());
    Mesh nan = lodbake_test::richMesh();
    nan.positions[2].y = std::nanf("");
    const Result<GltfFiles> r = writeGltfToMemory(nan, GltfWriteOptions{});
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("vertex 2"), std::string::npos) << r.status().message();
}

TEST(GltfExportTest, TexturesWithoutUsableBytesAreDropped) {
    Mesh mesh = lodbake_test::richMesh();
    mesh.textures[0].bytes = {1, 2, 3, 4};
    const nlohmann::json json = lodbake_test::glbJson(exportGlb(mesh));
    EXPECT_FALSE(json.contains("images"));
    EXPECT_FALSE(json.contains("textures"));
    EXPECT_FALSE(json["materials"][0]["pbrMetallicRoughness"].contains("baseColorTexture"));
}

} // namespace
