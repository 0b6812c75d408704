#pragma once
// Meshes built in code for the simplifier suites: subdivided spheres, grids, seams.

#include <cmath>
#include <map>
#include <utility>

#include "lodbake/core/mesh.h"

namespace lodbake_test {

/// Icosahedron subdivided `levels` times and projected on the unit sphere (20·4^levels faces),
/// outward-facing, no duplicated vertices.
inline lodbake::Mesh icosphere(int levels) {
    using lodbake::Vec3f;
    lodbake::Mesh m;
    const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
    m.positions = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                   {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
    m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
                 3, 9,  4, 3, 4, 2, 3, 2, 6, 3, 6, 8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
    for (auto& p : m.positions) p = lodbake::normalize(p);
    for (int l = 0; l < levels; ++l) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
        auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            const uint32_t id = uint32_t(m.positions.size());
            m.positions.push_back(lodbake::normalize((m.positions[a] + m.positions[b]) * 0.5f));
            mid.emplace(key, id);
            return id;
        };
        std::vector<uint32_t> next;
        for (size_t f = 0; f < m.indices.size(); f += 3) {
            const uint32_t a = m.indices[f], b = m.indices[f + 1], c = m.indices[f + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        m.indices = std::move(next);
    }
    return m;
}

/// An n×n-quad grid over [0,1]² at z = height(x, y), counter-clockwise seen from +z.
template <class Height> lodbake::Mesh grid(int n, Height height) {
    lodbake::Mesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = float(i) / float(n), y = float(j) / float(n);
            m.positions.push_back({x, y, height(x, y)});
        }
    auto id = [n](int i, int j) { return uint32_t(j * (n + 1) + i); };
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            // Alternate the diagonal so the grid has no preferred direction.
            if ((i + j) % 2 == 0)
                m.indices.insert(m.indices.end(),
                                 {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
            else
                m.indices.insert(m.indices.end(),
                                 {id(i, j), id(i + 1, j), id(i, j + 1), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
        }
    return m;
}

/// icosphere(levels) with a smooth radial bump: regular connectivity, but collapse costs that differ
/// from place to place.
inline lodbake::Mesh bumpyIcosphere(int levels) {
    lodbake::Mesh m = icosphere(levels);
    for (lodbake::Vec3f& p : m.positions) {
        const float r = 1.0f + 0.05f * std::sin(7.0f * p.x) * std::sin(5.0f * p.y + 1.0f) * std::sin(3.0f * p.z + 2.0f);
        p = p * r;
    }
    return m;
}

inline lodbake::Mesh flatGrid(int n) {
    return grid(n, [](float, float) { return 0.0f; });
}

} // namespace lodbake_test
