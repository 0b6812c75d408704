// Runs the Khronos glTF-Validator (scripts/node/validate-gltf.js) on our exports: a tiny mesh with
// every attribute and a texture, the shared scans converted by the CLI, as GLB and as .gltf + .bin.
// Any validator error or warning fails. A missing node or validator is a failure, not a skip.
#include <cstring>
#include <filesystem>

#include <gtest/gtest.h>

#include "gltf_test_util.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/gltf.h"
#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using namespace lodbake;

std::string nodeExecutable() {
    return LODBAKE_TEST_NODE;
}
std::string validatorScript() {
    return lodbake_test::sourceDir() + "/scripts/node/validate-gltf.js";
}

// Fails the current test unless node and the validator package are installed.
void requireValidator() {
    const std::string node = nodeExecutable();
    ASSERT_TRUE(!node.empty() && node.find("NOTFOUND") == std::string::npos && fs::exists(node))
        << "node was not found at configure time: run scripts/install-deps.sh, then re-run cmake";
    ASSERT_TRUE(fs::exists(lodbake_test::sourceDir() + "/scripts/node/node_modules/gltf-validator"))
        << "gltf-validator is not installed in scripts/node/node_modules: run scripts/install-deps.sh";
}

lodbake_test::CommandResult validate(const std::vector<std::string>& files) {
    std::string command =
        lodbake_test::shellQuote(nodeExecutable()) + " " + lodbake_test::shellQuote(validatorScript());
    for (const std::string& f : files) command += " " + lodbake_test::shellQuote(f);
    return lodbake_test::runCommand(command);
}

std::string outDir() {
    const std::string dir = lodbake_test::scratchDir() + "/gltf_validator";
    fs::create_directories(dir);
    return dir;
}

TEST(GltfValidatorTest, TinyMeshWithEveryAttributePasses) {
    requireValidator();
    const Mesh mesh = lodbake_test::richMesh();
    std::vector<std::string> files;
    for (const char* name : {"rich.glb", "rich.gltf"}) {
        const std::string path = outDir() + "/" + name;
        Diagnostics diagnostics;
        const Status s = writeMesh(mesh, path, WriteOptions{}, diagnostics);
        ASSERT_TRUE(s.ok()) << s.message();
        files.push_back(path);
    }
    // A mesh with a zero normal and more than 65535 vertices (unsigned int indices).
    Mesh big;
    for (int y = 0; y < 260; ++y)
        for (int x = 0; x < 260; ++x) big.positions.push_back(Vec3f(float(x), float(y), 0.0f));
    big.normals.assign(big.positions.size(), Vec3f(0.0f, 0.0f, 1.0f));
    big.normals[7] = Vec3f(0.0f, 0.0f, 0.0f);
    for (uint32_t y = 0; y + 1 < 260; ++y)
        for (uint32_t x = 0; x + 1 < 260; ++x) {
            const uint32_t a = y * 260 + x;
            big.indices.insert(big.indices.end(), {a, a + 1, a + 261, a, a + 261, a + 260});
        }
    const std::string big_path = outDir() + "/big.glb";
    Diagnostics diagnostics;
    ASSERT_TRUE(writeMesh(big, big_path, WriteOptions{}, diagnostics).ok());
    files.push_back(big_path);
    // Awkward input: degenerate triangles, an unreferenced vertex, an empty sub-mesh, colours out of
    // [0,1], non-unit normals, a zero tangent and a texture that is not an image.
    Mesh awkward = lodbake_test::richMesh();
    awkward.positions.push_back(Vec3f(9.0f, 9.0f, 9.0f));
    awkward.normals.push_back(Vec3f(0.0f, 2.0f, 0.0f));
    awkward.tangents.push_back(Vec4f(0.0f, 0.0f, 0.0f, 1.0f));
    for (auto& set : awkward.uvs) set.push_back(Vec2f(0.0f, 0.0f));
    awkward.colors.push_back(Vec4f(2.0f, -1.0f, 0.5f, 1.0f));
    awkward.indices.insert(awkward.indices.end(), {0, 0, 1, 2, 2, 2});
    awkward.submeshes[1].index_count += 6;
    SubMesh empty;
    empty.first_index = uint32_t(awkward.indices.size());
    awkward.submeshes.push_back(empty);
    Texture junk;
    junk.bytes = {1, 2, 3};
    awkward.textures.push_back(junk);
    awkward.materials[1].emissive_texture.texture = 1;
    const std::string awkward_path = outDir() + "/awkward.glb";
    const Status awkward_status = writeMesh(awkward, awkward_path, WriteOptions{}, diagnostics);
    ASSERT_TRUE(awkward_status.ok()) << awkward_status.message();
    files.push_back(awkward_path);
    const lodbake_test::CommandResult r = validate(files);
    EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(GltfValidatorTest, ValidatorCatchesABrokenFile) {
    requireValidator();
    // Control: the validator must flag a file whose POSITION bounds are wrong, or the test above
    // would pass for the wrong reason.
    Result<GltfFiles> files = writeGltfToMemory(lodbake_test::richMesh(), GltfWriteOptions{});
    ASSERT_TRUE(files.ok());
    nlohmann::json json = lodbake_test::glbJson(files->main);
    const int position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
    json["accessors"][size_t(position)]["max"][0] = 42.0;
    uint32_t json_length = 0;
    std::memcpy(&json_length, files->main.data() + 12, 4);
    std::vector<uint8_t> bin(files->main.begin() + 20 + json_length + 8, files->main.end());
    const std::vector<uint8_t> broken = lodbake_test::makeGlb(json, bin);
    const std::string path = outDir() + "/broken.glb";
    ASSERT_TRUE(writeFileAtomic(path, broken.data(), broken.size()).ok());
    const lodbake_test::CommandResult r = validate({path});
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("ACCESSOR_MAX_MISMATCH"), std::string::npos) << r.output;
}

TEST(GltfValidatorTest, ConvertedSharedMeshesPass) {
    requireValidator();
    LODBAKE_REQUIRE_SHARED_MESHES();
    std::vector<std::string> files;
    const std::vector<std::pair<std::string, std::string>> inputs = {
        {"lee_perry_smith/LeePerrySmith.glb", "lee"},
        {"nefertiti_fraunhofer_textured.glb", "nefertiti"},
        {"spot.obj", "spot"},
        {"bunny_zipper.ply", "bunny"},
    };
    for (const auto& input : inputs) {
        for (const char* ext : {".glb", ".gltf"}) {
            const std::string out = outDir() + "/" + input.second + ext;
            const lodbake_test::CommandResult r =
                lodbake_test::runCommand(lodbake_test::shellQuote(lodbake_test::lodbakeCli()) + " convert " +
                                         lodbake_test::shellQuote(lodbake_test::sharedMesh(input.first)) + " -o " +
                                         lodbake_test::shellQuote(out));
            ASSERT_EQ(r.exit_code, 0) << input.first << ": " << r.output;
            files.push_back(out);
        }
    }
    ASSERT_EQ(files.size(), 2 * inputs.size());
    const lodbake_test::CommandResult r = validate(files);
    EXPECT_EQ(r.exit_code, 0) << r.output;
}

} // namespace
