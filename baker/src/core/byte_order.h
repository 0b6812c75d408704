#pragma once
// Little-endian fields of the binary blobs the baker writes (PFRep, valence): one byte at a time, so
// the bytes are the same on every host. Their layouts are in lodrt/format.h.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace lodbake {

/// Writes `v` little-endian at bytes [at, at + 4) of `out` (which must hold them).
inline void put32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) out[at + size_t(i)] = uint8_t(v >> (8 * i));
}

/// Writes the IEEE-754 bits of `f` little-endian at bytes [at, at + 4) of `out`.
inline void putF32(std::vector<uint8_t>& out, size_t at, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put32(out, at, u);
}

} // namespace lodbake
