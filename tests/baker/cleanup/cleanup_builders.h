#pragma once
// Hand-built meshes for the cleanup suites (pmp tests/helpers.h style), beyond mesh_builders.h.

#include <cmath>
#include <cstdint>

#include "lodbake/core/mesh.h"
#include "mesh_builders.h"

namespace lodbake_test {

/// A closed UV sphere (radius 1, outward) with `rings` latitude bands and `segments` longitudes.
inline lodbake::Mesh uvSphere(uint32_t rings, uint32_t segments) {
    lodbake::Mesh m;
    m.positions.push_back({0, 0, -1});
    for (uint32_t r = 1; r < rings; ++r) {
        const double th = M_PI * double(r) / rings - M_PI / 2;
        for (uint32_t s = 0; s < segments; ++s) {
            const double ph = 2 * M_PI * double(s) / segments;
            m.positions.push_back(
                {float(std::cos(th) * std::cos(ph)), float(std::cos(th) * std::sin(ph)), float(std::sin(th))});
        }
    }
    m.positions.push_back({0, 0, 1});
    const uint32_t top = uint32_t(m.positions.size() - 1);
    auto ring = [&](uint32_t r, uint32_t s) { return 1 + (r - 1) * segments + s % segments; };
    for (uint32_t s = 0; s < segments; ++s) m.indices.insert(m.indices.end(), {0, ring(1, s + 1), ring(1, s)});
    for (uint32_t r = 1; r + 1 < rings; ++r)
        for (uint32_t s = 0; s < segments; ++s) {
            m.indices.insert(m.indices.end(), {ring(r, s), ring(r, s + 1), ring(r + 1, s + 1)});
            m.indices.insert(m.indices.end(), {ring(r, s), ring(r + 1, s + 1), ring(r + 1, s)});
        }
    for (uint32_t s = 0; s < segments; ++s)
        m.indices.insert(m.indices.end(), {ring(rings - 1, s), ring(rings - 1, s + 1), top});
    return m;
}

/// The lower hemisphere of a UV sphere: open along the equator with a hole of `segments` edges.
inline lodbake::Mesh hemisphere(uint32_t rings_half, uint32_t segments) {
    lodbake::Mesh m = uvSphere(2 * rings_half, segments);
    std::vector<uint32_t> kept;
    for (size_t f = 0; f < m.faceCount(); ++f) {
        bool below = true;
        for (int k = 0; k < 3; ++k) below &= m.positions[m.indices[3 * f + k]].z <= 1e-6f;
        if (below) kept.insert(kept.end(), m.indices.begin() + 3 * f, m.indices.begin() + 3 * f + 3);
    }
    m.indices = kept;
    // Drop the upper half's vertices (keep order).
    std::vector<uint32_t> remap(m.vertexCount(), UINT32_MAX);
    std::vector<lodbake::Vec3f> pos;
    for (uint32_t& i : m.indices) {
        if (remap[i] == UINT32_MAX) {
            remap[i] = uint32_t(pos.size());
            pos.push_back(m.positions[i]);
        }
        i = remap[i];
    }
    m.positions = pos;
    return m;
}

/// A flat strip of `n` quads along x (2n triangles, every vertex on the boundary).
inline lodbake::Mesh strip(uint32_t n) {
    lodbake::Mesh m;
    for (uint32_t i = 0; i <= n; ++i) {
        m.positions.push_back({float(i), 0, 0});
        m.positions.push_back({float(i), 1, 0});
    }
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t a = 2 * i, b = 2 * i + 1, c = 2 * i + 2, d = 2 * i + 3;
        m.indices.insert(m.indices.end(), {a, c, d, a, d, b});
    }
    return m;
}

/// A Möbius strip of `n` quads (n >= 5): a band whose last rung is joined to the first with a half twist.
inline lodbake::Mesh moebius(uint32_t n) {
    lodbake::Mesh m;
    for (uint32_t i = 0; i < n; ++i) {
        const double t = 2 * M_PI * double(i) / n;
        for (int side = -1; side <= 1; side += 2) {
            const double w = 0.3 * side;
            const double rr = 1 + w * std::cos(t / 2);
            m.positions.push_back({float(rr * std::cos(t)), float(rr * std::sin(t)), float(w * std::sin(t / 2))});
        }
    }
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t a = 2 * i, b = 2 * i + 1;
        uint32_t c = 2 * ((i + 1) % n), d = c + 1;
        if (i + 1 == n) std::swap(c, d); // the half twist swaps the two sides
        m.indices.insert(m.indices.end(), {a, c, d, a, d, b});
    }
    return m;
}

/// Two closed tetrahedra sharing only one vertex: a fan pair around a non-manifold vertex.
inline lodbake::Mesh twoConesAtVertex() {
    return makeMesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},
                    {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3, 0, 5, 4, 0, 4, 6, 0, 6, 5, 4, 5, 6});
}

/// Deterministic pseudo-random value in [-1, 1] (hash of an integer; no global RNG state).
inline float hashNoise(uint32_t i) {
    uint32_t x = i * 2654435761u + 0x9E3779B9u;
    x ^= x >> 15;
    x *= 0x85EBCA6Bu;
    x ^= x >> 13;
    return float(x & 0xFFFFFF) / float(0x7FFFFF) - 1.0f;
}

} // namespace lodbake_test
