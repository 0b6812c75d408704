#pragma once
// Helpers shared by the glTF suites: a mesh using every attribute the exporter writes, a tiny PNG,
// base64 for hand-built glTF JSON, GLB JSON-chunk access, and running a command.

#include <array>
#include <cstdio>
#include <cstring>
#include <sys/wait.h>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lodbake/core/mesh.h"
#include "cli_runner.h"

namespace lodbake_test {

/// A valid 2x2 RGB PNG (red, green / blue, white).
inline std::vector<uint8_t> tinyPng() {
    return {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44,
            0x52, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0xfd,
            0xd4, 0x9a, 0x73, 0x00, 0x00, 0x00, 0x12, 0x49, 0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8,
            0xcf, 0xc0, 0xc0, 0x00, 0xc2, 0x0c, 0xff, 0x81, 0x00, 0x00, 0x1f, 0xee, 0x05, 0xfb, 0xf1,
            0xab, 0xba, 0x77, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
}

inline std::string base64(const std::vector<uint8_t>& bytes) {
    static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8 | bytes[i + 2];
        for (int k = 3; k >= 0; --k) out.push_back(kAlphabet[(v >> (6 * k)) & 63]);
    }
    if (i + 1 == bytes.size()) {
        const uint32_t v = uint32_t(bytes[i]) << 16;
        out += {kAlphabet[(v >> 18) & 63], kAlphabet[(v >> 12) & 63], '=', '='};
    } else if (i + 2 == bytes.size()) {
        const uint32_t v = uint32_t(bytes[i]) << 16 | uint32_t(bytes[i + 1]) << 8;
        out += {kAlphabet[(v >> 18) & 63], kAlphabet[(v >> 12) & 63], kAlphabet[(v >> 6) & 63], '='};
    }
    return out;
}

/// Appends little-endian values to a byte buffer (4-byte aligned start) and returns the offset.
template <class T> size_t appendValues(std::vector<uint8_t>& buffer, const std::vector<T>& values) {
    while (buffer.size() % 4 != 0) buffer.push_back(0);
    const size_t offset = buffer.size();
    buffer.resize(offset + values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(buffer.data() + offset, values.data(), values.size() * sizeof(T));
    return offset;
}

/// Wraps JSON and a BIN chunk into a GLB.
inline std::vector<uint8_t> makeGlb(const nlohmann::json& json, std::vector<uint8_t> bin) {
    std::string text = json.dump();
    while (text.size() % 4 != 0) text.push_back(' ');
    while (bin.size() % 4 != 0) bin.push_back(0);
    std::vector<uint8_t> out;
    auto put32 = [&](uint32_t v) {
        for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
    };
    put32(0x46546C67);
    put32(2);
    put32(uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
    put32(uint32_t(text.size()));
    put32(0x4E4F534A);
    out.insert(out.end(), text.begin(), text.end());
    if (!bin.empty()) {
        put32(uint32_t(bin.size()));
        put32(0x004E4942);
        out.insert(out.end(), bin.begin(), bin.end());
    }
    return out;
}

/// The JSON chunk of a GLB, parsed.
inline nlohmann::json glbJson(const std::vector<uint8_t>& glb) {
    uint32_t length = 0;
    std::memcpy(&length, glb.data() + 12, 4);
    return nlohmann::json::parse(glb.begin() + 20, glb.begin() + 20 + length);
}

/// The BIN chunk of a GLB (empty without one), as makeGlb takes it.
inline std::vector<uint8_t> glbBin(const std::vector<uint8_t>& glb) {
    uint32_t json_length = 0, bin_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const size_t bin = 20 + size_t(json_length);
    if (bin + 8 > glb.size()) return {};
    std::memcpy(&bin_length, glb.data() + bin, 4);
    return std::vector<uint8_t>(glb.begin() + long(bin + 8), glb.begin() + long(bin + 8 + bin_length));
}

/// Two sub-meshes (two quads) with normals, tangents, two UV sets, colours, two materials and a PNG
/// texture: every stream and material feature the exporter writes.
inline lodbake::Mesh richMesh() {
    using namespace lodbake;
    Mesh m;
    m.positions = {{0, 0, 0},    {1, 0, 0},    {1, 1, 0},     {0, 1, 0},
                   {2, 0, 0.5f}, {3, 0, 0.5f}, {3, 1, 0.25f}, {2, 1, 0.25f}};
    m.normals.assign(8, Vec3f(0, 0, 1));
    m.tangents.assign(8, Vec4f(1, 0, 0, 1));
    m.tangents[5].w = -1.0f;
    m.uvs.resize(2);
    for (size_t i = 0; i < 8; ++i) {
        m.uvs[0].push_back(Vec2f(m.positions[i].x / 3.0f, m.positions[i].y));
        m.uvs[1].push_back(Vec2f(0.25f * float(i), 0.5f));
    }
    for (size_t i = 0; i < 8; ++i) m.colors.push_back(Vec4f(float(i) / 8.0f, 0.5f, 1.0f - float(i) / 8.0f, 1.0f));
    m.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
    SubMesh a;
    a.name = "left";
    a.first_index = 0;
    a.index_count = 6;
    a.material = MaterialId(0);
    SubMesh b = a;
    b.name = "right";
    b.first_index = 6;
    b.material = MaterialId(1);
    m.submeshes = {a, b};
    Material textured;
    textured.name = "textured";
    textured.base_color_factor = Vec4f(0.5f, 0.75f, 1.0f, 1.0f);
    textured.metallic_factor = 0.25f;
    textured.roughness_factor = 0.75f;
    textured.base_color_texture.texture = 0;
    textured.normal_texture.texture = 0;
    textured.normal_texture.texcoord = 1;
    textured.normal_scale = 0.5f;
    textured.emissive_factor = Vec3f(0.1f, 0.2f, 0.3f);
    textured.is_double_sided = true;
    Material masked;
    masked.name = "masked";
    masked.alpha_mode = AlphaMode::Mask;
    masked.alpha_cutoff = 0.25f;
    masked.occlusion_texture.texture = 0;
    masked.occlusion_strength = 0.5f;
    m.materials = {textured, masked};
    Texture tex;
    tex.name = "checker";
    tex.mime_type = "image/png";
    tex.bytes = tinyPng();
    m.textures = {tex};
    return m;
}

struct CommandResult {
    int exit_code = -1;
    std::string output; // stdout and stderr
};

/// Runs a shell command, capturing stdout and stderr together.
inline CommandResult runCommand(const std::string& command) {
    CommandResult r;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (pipe == nullptr) return r;
    std::array<char, 4096> chunk{};
    size_t n = 0;
    while ((n = fread(chunk.data(), 1, chunk.size(), pipe)) > 0) r.output.append(chunk.data(), n);
    const int status = pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

/// A shell prefix that turns LeakSanitizer off for one command (ASan and UBSan stay on). Under the
/// CI's AddressSanitizer build, LeakSanitizer's stop-the-world tracer itself sometimes crashes
/// (signal 11 in the tracer, "LeakSanitizer has encountered a fatal error") at the exit of a long
/// multi-threaded bake that loaded the OpenImageIO module; it reports no leak. Only those bakes use
/// it; outside sanitizer builds the variable is ignored.
inline std::string withoutLeakCheck() {
    return "ASAN_OPTIONS=\"${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0\" ";
}

} // namespace lodbake_test
