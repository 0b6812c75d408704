#include "lodbake/core/hash.h"

#include <cstring>

#include "lodbake/core/mesh.h"

namespace lodbake {

namespace {

uint64_t mix64(uint64_t x) {
    // splitmix64 finaliser: good avalanche, cheap.
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x;
}

} // namespace

void Hasher::mixWord(uint64_t w) { state_ = mix64(state_ ^ mix64(w + 0x9e3779b97f4a7c15ull)) * 0x2545f4914f6cdd1dull; }

void Hasher::addBytes(const void* data, size_t size) {
    const uint8_t* p = static_cast<const uint8_t*>(data);
    length_ += size;
    // Fill the pending word byte by byte (little-endian order), then whole words.
    while (size > 0 && pending_bytes_ != 0) {
        pending_ |= uint64_t(*p++) << (8 * pending_bytes_);
        --size;
        if (++pending_bytes_ == 8) {
            mixWord(pending_);
            pending_ = 0;
            pending_bytes_ = 0;
        }
    }
    while (size >= 8) {
        uint64_t w = 0;
        for (int i = 0; i < 8; ++i) w |= uint64_t(p[i]) << (8 * i);
        mixWord(w);
        p += 8;
        size -= 8;
    }
    while (size > 0) {
        pending_ |= uint64_t(*p++) << (8 * pending_bytes_);
        ++pending_bytes_;
        --size;
    }
}

void Hasher::addU32(uint32_t v) {
    uint8_t b[4] = {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)};
    addBytes(b, 4);
}

void Hasher::addU64(uint64_t v) {
    addU32(uint32_t(v));
    addU32(uint32_t(v >> 32));
}

void Hasher::addFloat(float v) {
    uint32_t bits;
    std::memcpy(&bits, &v, 4);
    addU32(bits);
}

void Hasher::addString(const std::string& s) {
    addU64(s.size());
    addBytes(s.data(), s.size());
}

uint64_t Hasher::digest() const {
    uint64_t s = state_;
    s = mix64(s ^ mix64(pending_ ^ (uint64_t(pending_bytes_) << 56)));
    return mix64(s ^ length_);
}

namespace {

template <class V> void addVecs(Hasher& h, const std::vector<V>& v, int components) {
    h.addU64(v.size());
    for (const V& x : v)
        for (int c = 0; c < components; ++c) h.addFloat(x[c]);
}

void addSlot(Hasher& h, const TextureSlot& s) {
    h.addU32(uint32_t(s.texture));
    h.addU32(s.texcoord);
}

} // namespace

uint64_t hashMesh(const Mesh& mesh) {
    Hasher h;
    addVecs(h, mesh.positions, 3);
    addVecs(h, mesh.normals, 3);
    addVecs(h, mesh.tangents, 4);
    h.addU64(mesh.uvs.size());
    for (const auto& uv : mesh.uvs) addVecs(h, uv, 2);
    addVecs(h, mesh.colors, 4);
    h.addU64(mesh.indices.size());
    for (uint32_t i : mesh.indices) h.addU32(i);
    h.addU64(mesh.submeshes.size());
    for (const SubMesh& s : mesh.submeshes) {
        h.addString(s.name);
        h.addU32(s.first_index);
        h.addU32(s.index_count);
        h.addU32(s.material.value);
    }
    h.addU64(mesh.materials.size());
    for (const Material& m : mesh.materials) {
        h.addString(m.name);
        for (int c = 0; c < 4; ++c) h.addFloat(m.base_color_factor[c]);
        h.addFloat(m.metallic_factor);
        h.addFloat(m.roughness_factor);
        for (int c = 0; c < 3; ++c) h.addFloat(m.emissive_factor[c]);
        addSlot(h, m.base_color_texture);
        addSlot(h, m.metallic_roughness_texture);
        addSlot(h, m.normal_texture);
        h.addFloat(m.normal_scale);
        addSlot(h, m.occlusion_texture);
        h.addFloat(m.occlusion_strength);
        addSlot(h, m.emissive_texture);
        h.addU32(uint32_t(m.alpha_mode));
        h.addFloat(m.alpha_cutoff);
        h.addU32(m.is_double_sided);
    }
    h.addU64(mesh.textures.size());
    for (const Texture& t : mesh.textures) {
        h.addString(t.name);
        h.addString(t.uri);
        h.addString(t.mime_type);
        h.addU64(t.bytes.size());
        h.addBytes(t.bytes.data(), t.bytes.size());
    }
    return h.digest();
}

std::string hashToHex(uint64_t h) {
    static const char* kDigits = "0123456789abcdef";
    std::string s(16, '0');
    for (int i = 15; i >= 0; --i, h >>= 4) s[size_t(i)] = kDigits[h & 15];
    return s;
}

} // namespace lodbake
