#pragma once
// Test helpers: build GLB containers and tiny glTF packs byte by byte, independent of the baker.

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace lodrt_test {

inline void putU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

inline void setU32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) out[at + i] = uint8_t(v >> (8 * i));
}

constexpr uint32_t kChunkJson = 0x4E4F534Au;
constexpr uint32_t kChunkBin = 0x004E4942u;

struct Chunk {
    uint32_t type;
    std::vector<uint8_t> payload; // written as is (callers pad when they want a valid file)
};

/// A GLB with the given chunks; the header length is the real total unless length_override is set.
inline std::vector<uint8_t> makeGlbChunks(const std::vector<Chunk>& chunks, uint32_t version = 2) {
    std::vector<uint8_t> out = {'g', 'l', 'T', 'F'};
    putU32(out, version);
    putU32(out, 0);
    for (const Chunk& chunk : chunks) {
        putU32(out, uint32_t(chunk.payload.size()));
        putU32(out, chunk.type);
        out.insert(out.end(), chunk.payload.begin(), chunk.payload.end());
    }
    setU32(out, 8, uint32_t(out.size()));
    return out;
}

/// A valid GLB: JSON padded with spaces, BIN (omitted when empty) padded with zeros.
inline std::vector<uint8_t> makeGlb(const std::string& json, const std::vector<uint8_t>& bin = {}) {
    std::vector<Chunk> chunks;
    Chunk json_chunk{kChunkJson, std::vector<uint8_t>(json.begin(), json.end())};
    while (json_chunk.payload.size() % 4) json_chunk.payload.push_back(' ');
    chunks.push_back(json_chunk);
    if (!bin.empty()) {
        Chunk bin_chunk{kChunkBin, bin};
        while (bin_chunk.payload.size() % 4) bin_chunk.payload.push_back(0);
        chunks.push_back(bin_chunk);
    }
    return makeGlbChunks(chunks);
}

template <typename T> void appendValues(std::vector<uint8_t>& out, const std::vector<T>& values) {
    const size_t at = out.size();
    out.resize(at + values.size() * sizeof(T));
    std::memcpy(out.data() + at, values.data(), values.size() * sizeof(T)); // tests run on little-endian hosts
}

/// BIN of the quad pack: 4 positions (48 B), 4 normals (48 B), 6 u16 indices (12 B).
inline std::vector<uint8_t> quadBin() {
    std::vector<uint8_t> bin;
    appendValues<float>(bin, {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0});
    appendValues<float>(bin, {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1});
    appendValues<uint16_t>(bin, {0, 1, 2, 0, 2, 3});
    return bin;
}

/// glTF JSON of the quad pack; `extra` is spliced into the root object (e.g. ",\"x\":1").
inline std::string quadJson(const std::string& extra = "") {
    return R"({"asset":{"version":"2.0","generator":"lodrt tests"},)"
           R"("buffers":[{"byteLength":108}],)"
           R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96,"byteStride":12,"target":34962},)"
           R"({"buffer":0,"byteOffset":96,"byteLength":12,"target":34963}],)"
           R"("accessors":[{"bufferView":0,"byteOffset":0,"componentType":5126,"count":4,"type":"VEC3",)"
           R"("min":[0,0,0],"max":[1,1,0]},)"
           R"({"bufferView":0,"byteOffset":48,"componentType":5126,"count":4,"type":"VEC3"},)"
           R"({"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],)"
           R"("materials":[{"name":"stone"}],)"
           R"("meshes":[{"name":"Quad","primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":2,)"
           R"("material":0,"extensions":{"LODBAKE_test":{"level":3}}}]}],)"
           R"("nodes":[{"name":"root","children":[1]},{"name":"quad","mesh":0}],)"
           R"("scenes":[{"nodes":[0]}],"scene":0)" +
           extra + "}";
}

inline std::vector<uint8_t> quadGlb() {
    return makeGlb(quadJson(), quadBin());
}

} // namespace lodrt_test
