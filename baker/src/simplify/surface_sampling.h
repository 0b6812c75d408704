#pragma once
// The deterministic random numbers and triangle points of the surface-distance sampling, shared by
// measureSurfaceDistance (mesh_distance.cpp) and the cluster builder's group error
// (cluster/group_distance.cpp), so both draw samples the same way.

#include <cmath>
#include <cstdint>

#include "lodbake/core/math.h"

namespace lodbake::detail {

inline uint64_t splitmix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// Uniform in [0, 1) with 53 random bits.
inline double toUnit(uint64_t bits) {
    return double(bits >> 11) * (1.0 / 9007199254740992.0);
}

// The area-uniform point of triangle abc for two uniforms u1, u2 in [0, 1).
inline Vec3d pointOnTriangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, double u1, double u2) {
    const double r1 = std::sqrt(u1);
    return a * (1.0 - r1) + b * (r1 * (1.0 - u2)) + c * (r1 * u2);
}

} // namespace lodbake::detail
