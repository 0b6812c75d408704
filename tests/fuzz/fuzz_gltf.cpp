// libFuzzer target for the glTF 2.0 / GLB importer (lodbake/io/gltf.h) with Draco, straight
// from memory, read flattened and as a scene graph. Inputs starting with "glTF" take the GLB path,
// others the JSON path. Every external buffer or image URI is served the input itself, which covers
// self-referencing buffers. Run with scripts/fuzz.sh gltf SECONDS.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "lodbake/io/gltf.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::vector<uint8_t> input(data, data + size);
    const bool is_glb = size >= 4 && data[0] == 'g' && data[1] == 'l' && data[2] == 'T' && data[3] == 'F';
    int side_requests = 0;
    const lodbake::SideFileLoader loader = [&](const std::string& path) -> lodbake::Result<std::vector<uint8_t>> {
        if (++side_requests > 64) return lodbake::ioError(path + ": too many side files requested by one input");
        return input;
    };
    lodbake::Diagnostics diagnostics;
    const lodbake::ReadOptions options = lodbake_fuzz::smallLimits();
    lodbake_fuzz::checkLoaded(lodbake::readGltfFromMemory(input.data(), input.size(),
                                                          is_glb ? "fuzz/model.glb" : "fuzz/model.gltf", loader,
                                                          options, diagnostics));
    // The scene-graph reading of the same bytes: every mesh consistent, every index in range.
    side_requests = 0;
    lodbake::Result<lodbake::LoadedScene> scene = lodbake::readGltfSceneFromMemory(
        input.data(), input.size(), is_glb ? "fuzz/model.glb" : "fuzz/model.gltf", loader, options, diagnostics);
    if (!scene.ok() || !scene->isGraph()) {
        lodbake_fuzz::checkLoaded(scene.ok() ? lodbake::Result<lodbake::LoadedMesh>(std::move(scene->flat))
                                             : lodbake::Result<lodbake::LoadedMesh>(scene.status()));
        return 0;
    }
    for (const lodbake::Mesh& mesh : scene->meshes)
        if (!lodbake::checkMeshConsistency(mesh, "fuzz").ok()) __builtin_trap();
    for (const lodbake::SceneNode& node : scene->nodes) {
        if (node.mesh >= int32_t(scene->meshes.size())) __builtin_trap();
        for (uint32_t c : node.children)
            if (c >= scene->nodes.size()) __builtin_trap();
    }
    for (uint32_t r : scene->roots)
        if (r >= scene->nodes.size()) __builtin_trap();
    return 0;
}
