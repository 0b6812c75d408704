#pragma once
// Content hashing for determinism checks and caches. The hash is defined over little-endian values
// in a fixed order, so it is the same on every machine and does not see struct padding.

#include <cstddef>
#include <cstdint>
#include <string>

namespace lodbake {

struct Mesh;

/// Incremental 64-bit hasher (a multiply-xorshift mix over 8-byte words; not cryptographic).
class Hasher {
public:
    void addBytes(const void* data, size_t size);
    void addU32(uint32_t v);
    void addU64(uint64_t v);
    void addFloat(float v); // hashes the bit pattern, with -0 and +0 kept distinct
    void addString(const std::string& s);
    uint64_t digest() const;

private:
    uint64_t state_ = 0x9e3779b97f4a7c15ull;
    uint64_t length_ = 0;
    uint64_t pending_ = 0;
    unsigned pending_bytes_ = 0;
    void mixWord(uint64_t w);
};

/// Hash of everything that defines the mesh: streams, indices, sub-meshes, materials, texture bytes.
uint64_t hashMesh(const Mesh& mesh);

/// Hex string of a 64-bit hash, 16 lowercase digits.
std::string hashToHex(uint64_t h);

} // namespace lodbake
