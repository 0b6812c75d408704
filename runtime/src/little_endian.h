#pragma once
// Little-endian loads from untrusted bytes (any alignment), shared by the runtime's binary readers.

#include <cstdint>
#include <cstring>

namespace lodrt::detail {

inline uint16_t loadU16(const uint8_t* p) {
    return uint16_t(p[0] | (p[1] << 8));
}

inline uint32_t loadU32(const uint8_t* p) {
    return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}

inline float loadF32(const uint8_t* p) {
    const uint32_t bits = loadU32(p);
    float f;
    std::memcpy(&f, &bits, sizeof(f));
    return f;
}

} // namespace lodrt::detail
