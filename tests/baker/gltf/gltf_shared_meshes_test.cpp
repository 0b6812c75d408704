// The real textured scans in ../shared/meshes: counts as documented in its README, materials and
// embedded images, and a GLB round trip through our exporter. Each file is loaded once per suite.
#include <map>
#include <memory>

#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "lodbake/io/gltf.h"
#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

class GltfSharedMeshesTest : public testing::Test {
protected:
    static void SetUpTestSuite() {
        if (!lodbake_test::haveSharedMeshes()) return;
        for (const char* name : {"lee_perry_smith/LeePerrySmith.glb", "nefertiti_fraunhofer_textured.glb"}) {
            Diagnostics diagnostics;
            Result<LoadedMesh> r = readMesh(lodbake_test::sharedMesh(name), ReadOptions{}, diagnostics);
            if (r.ok())
                loaded_[name] = std::make_shared<LoadedMesh>(std::move(r).value());
            else
                errors_[name] = r.status().message();
        }
    }
    static void TearDownTestSuite() {
        loaded_.clear();
        errors_.clear();
    }

    static const LoadedMesh* get(const std::string& name) {
        auto it = loaded_.find(name);
        if (it == loaded_.end()) {
            ADD_FAILURE() << name << ": " << errors_[name];
            return nullptr;
        }
        return it->second.get();
    }

    static std::map<std::string, std::shared_ptr<LoadedMesh>> loaded_;
    static std::map<std::string, std::string> errors_;
};

std::map<std::string, std::shared_ptr<LoadedMesh>> GltfSharedMeshesTest::loaded_;
std::map<std::string, std::string> GltfSharedMeshesTest::errors_;

void expectRoundTrip(const Mesh& mesh) {
    Result<GltfFiles> files = writeGltfToMemory(mesh, GltfWriteOptions{});
    ASSERT_TRUE(files.ok()) << files.status().message();
    Diagnostics diagnostics;
    Result<LoadedMesh> back = readGltfFromMemory(
        files->main.data(), files->main.size(), "roundtrip.glb",
        [](const std::string& p) -> Result<std::vector<uint8_t>> { return ioError(p); }, ReadOptions{}, diagnostics);
    ASSERT_TRUE(back.ok()) << back.status().message();
    const Mesh& m = back->mesh;
    EXPECT_EQ(m.indices, mesh.indices);
    ASSERT_EQ(m.positions.size(), mesh.positions.size());
    size_t position_mismatches = 0;
    for (size_t i = 0; i < m.positions.size(); ++i)
        if (!(m.positions[i] == mesh.positions[i])) ++position_mismatches;
    EXPECT_EQ(position_mismatches, 0u);
    ASSERT_EQ(m.uvs.size(), mesh.uvs.size());
    for (size_t s = 0; s < m.uvs.size(); ++s) {
        size_t uv_mismatches = 0;
        for (size_t i = 0; i < m.uvs[s].size(); ++i)
            if (!(m.uvs[s][i] == mesh.uvs[s][i])) ++uv_mismatches;
        EXPECT_EQ(uv_mismatches, 0u);
    }
    ASSERT_EQ(m.normals.size(), mesh.normals.size());
    // Exported normals are unit length; compare directions (source normals need not be unit).
    size_t normal_mismatches = 0;
    for (size_t i = 0; i < m.normals.size(); ++i) {
        const Vec3d a(m.normals[i]), b(mesh.normals[i]);
        EXPECT_NEAR(length(a), 1.0, 1e-5) << i;
        if (length(b) > 1e-6 && dot(a, b) / length(b) < 0.99999) ++normal_mismatches;
    }
    EXPECT_EQ(normal_mismatches, 0u);
    ASSERT_EQ(m.textures.size(), mesh.textures.size());
    for (size_t t = 0; t < m.textures.size(); ++t) EXPECT_EQ(m.textures[t].bytes, mesh.textures[t].bytes);
    ASSERT_EQ(m.materials.size(), mesh.materials.size());
}

TEST_F(GltfSharedMeshesTest, LeePerrySmithCountsAndRoundTrip) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const LoadedMesh* lee = get("lee_perry_smith/LeePerrySmith.glb");
    ASSERT_NE(lee, nullptr);
    EXPECT_EQ(lee->mesh.vertexCount(), 9279u);
    EXPECT_EQ(lee->mesh.faceCount(), 17684u);
    EXPECT_EQ(lee->source.file_vertex_count, 9279u);
    EXPECT_EQ(lee->source.file_face_count, 17684u);
    EXPECT_EQ(lee->source.encoding, "glb");
    EXPECT_EQ(lee->mesh.uvs.size(), 1u);
    EXPECT_TRUE(lee->mesh.hasNormals());
    // The README: the material references no textures.
    EXPECT_TRUE(lee->mesh.textures.empty());
    expectRoundTrip(lee->mesh);
}

TEST_F(GltfSharedMeshesTest, NefertitiCountsTexturesAndRoundTrip) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const LoadedMesh* nef = get("nefertiti_fraunhofer_textured.glb");
    ASSERT_NE(nef, nullptr);
    EXPECT_EQ(nef->mesh.vertexCount(), 11378u);
    EXPECT_EQ(nef->mesh.faceCount(), 19482u);
    EXPECT_EQ(nef->source.file_vertex_count, 11378u);
    EXPECT_EQ(nef->source.file_face_count, 19482u);
    EXPECT_TRUE(nef->mesh.hasTangents());
    ASSERT_EQ(nef->mesh.materials.size(), 1u);
    const Material& material = nef->mesh.materials[0];
    ASSERT_TRUE(material.base_color_texture.isSet());
    ASSERT_TRUE(material.normal_texture.isSet());
    ASSERT_EQ(nef->mesh.textures.size(), 2u);
    for (const Texture& t : nef->mesh.textures) {
        EXPECT_EQ(t.mime_type, "image/jpeg");
        ASSERT_GT(t.bytes.size(), 3u);
        EXPECT_EQ(t.bytes[0], 0xFF); // still JPEG-encoded: the importer never decodes images
        EXPECT_EQ(t.bytes[1], 0xD8);
    }
    expectRoundTrip(nef->mesh);
}

} // namespace
