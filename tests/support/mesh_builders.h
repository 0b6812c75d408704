#pragma once
// Tiny hand-built meshes for unit tests (pmp tests/helpers.h style).

#include <cmath>
#include <cstdint>
#include <initializer_list>

#include "lodbake/core/mesh.h"

namespace lodbake_test {

inline lodbake::Mesh makeMesh(std::initializer_list<lodbake::Vec3f> positions,
                              std::initializer_list<uint32_t> indices) {
    lodbake::Mesh m;
    m.positions.assign(positions.begin(), positions.end());
    m.indices.assign(indices.begin(), indices.end());
    return m;
}

/// Closed tetrahedron, outward-facing.
inline lodbake::Mesh tetrahedron() {
    return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3});
}

/// One triangle.
inline lodbake::Mesh singleTriangle() { return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {0, 1, 2}); }

/// Two triangles sharing only vertex 0 (a bow-tie: a non-manifold vertex).
inline lodbake::Mesh bowTie() {
    return makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}}, {0, 1, 2, 0, 3, 4});
}

/// Three triangles sharing edge (0,1): a non-manifold edge.
inline lodbake::Mesh finEdge() {
    return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}}, {0, 1, 2, 1, 0, 3, 0, 1, 4});
}

/// A quad split into two triangles (open: 4 boundary edges in one loop).
inline lodbake::Mesh quad() { return makeMesh({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {0, 1, 2, 0, 2, 3}); }

/// A bumpy closed sphere: a latitude-longitude grid of `rings` x `segments` with the poles welded.
inline lodbake::Mesh bumpySphere(int rings, int segments) {
    using lodbake::Vec3f;
    lodbake::Mesh m;
    const float pi = 3.14159265f;
    m.positions.push_back(Vec3f(0, 0, 1));
    for (int r = 1; r < rings; ++r)
        for (int s = 0; s < segments; ++s) {
            const float th = pi * float(r) / float(rings), ph = 2 * pi * float(s) / float(segments);
            const float bump = 1.0f + 0.05f * std::sin(5 * ph) * std::sin(4 * th);
            m.positions.push_back(
                Vec3f(bump * std::sin(th) * std::cos(ph), bump * std::sin(th) * std::sin(ph), bump * std::cos(th)));
        }
    m.positions.push_back(Vec3f(0, 0, -1));
    const uint32_t south = uint32_t(m.positions.size() - 1);
    auto at = [&](int r, int s) { return uint32_t(1 + (r - 1) * segments + (s % segments)); };
    for (int s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {0, at(1, s), at(1, s + 1)});
    for (int r = 1; r + 1 < rings; ++r)
        for (int s = 0; s < segments; ++s)
            m.indices.insert(m.indices.end(), {at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s), at(r + 1, s + 1),
                                               at(r, s + 1)});
    for (int s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {south, at(rings - 1, s + 1), at(rings - 1, s)});
    return m;
}

/// A wavy height field of n x n vertices over the unit square (2 (n - 1)^2 triangles):
/// z = amplitude sin(kx x) cos(ky y) at grid column x, row y.
inline lodbake::Mesh wavyField(int n, float amplitude, float kx, float ky) {
    lodbake::Mesh mesh;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
            mesh.positions.push_back({float(x) / float(n - 1), float(y) / float(n - 1),
                                      amplitude * std::sin(kx * float(x)) * std::cos(ky * float(y))});
    for (int y = 0; y + 1 < n; ++y)
        for (int x = 0; x + 1 < n; ++x) {
            const uint32_t a = uint32_t(y * n + x), b = a + 1, c = a + uint32_t(n), d = c + 1;
            mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
        }
    return mesh;
}

} // namespace lodbake_test
