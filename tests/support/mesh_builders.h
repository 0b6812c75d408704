#pragma once
// Tiny hand-built meshes for unit tests (pmp tests/helpers.h style).

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

} // namespace lodbake_test
