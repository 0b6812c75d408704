#include "lodbake/cleanup/topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>
#include <vector>

namespace lodbake {

namespace {

class UnionFind {
public:
    explicit UnionFind(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), uint32_t(0)); }
    uint32_t find(uint32_t x) {
        while (parent_[x] != x) {
            parent_[x] = parent_[parent_[x]];
            x = parent_[x];
        }
        return x;
    }
    void unite(uint32_t a, uint32_t b) {
        a = find(a);
        b = find(b);
        // Smaller root wins so the structure does not depend on call order beyond the edge order.
        if (a < b) parent_[b] = a;
        else if (b < a) parent_[a] = b;
    }

private:
    std::vector<uint32_t> parent_;
};

// Maps every vertex to the lowest-numbered vertex with a bit-identical position.
std::vector<uint32_t> weldMap(const Mesh& mesh) {
    const size_t n = mesh.vertexCount();
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    auto key = [&](uint32_t v) {
        std::array<uint32_t, 3> k;
        std::memcpy(k.data(), &mesh.positions[v], sizeof(k));
        return k;
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
        const auto ka = key(a), kb = key(b);
        return ka != kb ? ka < kb : a < b;
    });
    std::vector<uint32_t> map(n);
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && key(order[j]) == key(order[i])) map[order[j++]] = order[i];
        i = j;
    }
    return map;
}

// Sorts `items` by `less`, whose first criterion must be lo(item) < lo(other) with lo in [0, n): a
// counting sort on lo, then a small sort inside each bucket. Mesh-like input has a handful of items
// per bucket, so this is linear in practice and gives exactly std::sort's order.
template <class T, class Lo, class Less> void bucketSort(std::vector<T>& items, size_t n, Lo lo, Less less) {
    std::vector<uint32_t> begin(n + 1, 0);
    for (const T& t : items) ++begin[lo(t) + 1];
    for (size_t v = 0; v < n; ++v) begin[v + 1] += begin[v];
    std::vector<T> sorted(items.size());
    {
        std::vector<uint32_t> fill(begin.begin(), begin.end() - 1);
        for (const T& t : items) sorted[fill[lo(t)]++] = t;
    }
    for (size_t v = 0; v < n; ++v)
        if (begin[v + 1] - begin[v] > 1) std::sort(sorted.begin() + begin[v], sorted.begin() + begin[v + 1], less);
    items.swap(sorted);
}

struct HalfEdge {
    uint32_t lo, hi; // undirected key
    uint32_t face;
    uint8_t corner;  // corner of `face` the half-edge starts at
    bool forward;    // traversed lo -> hi
};

} // namespace

TopologyStats computeTopologyStats(const Mesh& mesh, const TopologyOptions& options) {
    TopologyStats s;
    const size_t n = mesh.vertexCount();
    const size_t face_count = mesh.faceCount();
    std::vector<uint32_t> remap;
    if (options.weld_by_position) remap = weldMap(mesh);
    auto vid = [&](size_t corner) { return remap.empty() ? mesh.indices[corner] : remap[mesh.indices[corner]]; };

    s.face_count = face_count;
    for (const Vec3f& p : mesh.positions) s.non_finite_vertex_count += !isFinite(p);

    std::vector<uint8_t> referenced(n, 0);
    for (size_t c = 0; c < mesh.indices.size(); ++c) referenced[vid(c)] = 1;
    uint64_t distinct = 0;
    for (size_t v = 0; v < n; ++v) distinct += remap.empty() || remap[v] == v;
    s.vertex_count = distinct;
    s.referenced_vertex_count = uint64_t(std::count(referenced.begin(), referenced.end(), uint8_t(1)));
    s.unreferenced_vertex_count = distinct - s.referenced_vertex_count;

    // Degenerate and duplicate faces.
    std::vector<uint8_t> repeated(face_count, 0);
    std::vector<std::array<uint32_t, 4>> keys;
    keys.reserve(face_count);
    for (size_t f = 0; f < face_count; ++f) {
        const uint32_t a = vid(3 * f), b = vid(3 * f + 1), c = vid(3 * f + 2);
        repeated[f] = a == b || b == c || a == c;
        bool zero_area = false;
        if (!repeated[f]) {
            const Vec3d pa = toDouble(mesh.positions[a]);
            const Vec3d e = cross(toDouble(mesh.positions[b]) - pa, toDouble(mesh.positions[c]) - pa);
            zero_area = dot(e, e) == 0.0;
        }
        s.degenerate_face_count += repeated[f] || zero_area;
        std::array<uint32_t, 4> k = {a, b, c, uint32_t(f)};
        std::sort(k.begin(), k.begin() + 3);
        keys.push_back(k);
    }
    bucketSort(keys, n, [](const std::array<uint32_t, 4>& k) { return k[0]; },
               [](const std::array<uint32_t, 4>& x, const std::array<uint32_t, 4>& y) { return x < y; });
    for (size_t i = 1; i < keys.size(); ++i)
        s.duplicate_face_count += keys[i][0] == keys[i - 1][0] && keys[i][1] == keys[i - 1][1] &&
                                  keys[i][2] == keys[i - 1][2];

    // Edges of faces with three distinct vertices.
    std::vector<HalfEdge> half;
    half.reserve(face_count * 3);
    for (size_t f = 0; f < face_count; ++f) {
        if (repeated[f]) continue;
        for (uint8_t k = 0; k < 3; ++k) {
            const uint32_t a = vid(3 * f + k), b = vid(3 * f + (k + 1) % 3);
            half.push_back({std::min(a, b), std::max(a, b), uint32_t(f), k, a < b});
        }
    }
    bucketSort(half, n, [](const HalfEdge& h) { return h.lo; }, [](const HalfEdge& x, const HalfEdge& y) {
        if (x.lo != y.lo) return x.lo < y.lo;
        if (x.hi != y.hi) return x.hi < y.hi;
        return x.face != y.face ? x.face < y.face : x.corner < y.corner;
    });

    UnionFind fans(face_count * 3); // corners around a vertex joined across manifold edges
    std::vector<uint8_t> on_nonmanifold_edge(n, 0);
    std::vector<std::pair<uint32_t, uint32_t>> boundary; // directed as traversed by its face
    for (size_t i = 0; i < half.size();) {
        size_t j = i;
        while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
        const size_t uses = j - i;
        ++s.edge_count;
        if (uses == 1) {
            ++s.boundary_edge_count;
            const HalfEdge& h = half[i];
            boundary.push_back(h.forward ? std::make_pair(h.lo, h.hi) : std::make_pair(h.hi, h.lo));
        } else if (uses == 2) {
            const HalfEdge& h0 = half[i];
            const HalfEdge& h1 = half[i + 1];
            if (h0.forward == h1.forward) ++s.inconsistent_edge_count;
            // Join the corners at each end of the edge in the two faces.
            for (uint32_t v : {h0.lo, h0.hi}) {
                uint32_t c0 = 0, c1 = 0;
                for (uint32_t k = 0; k < 3; ++k) {
                    if (vid(3 * size_t(h0.face) + k) == v) c0 = 3 * h0.face + k;
                    if (vid(3 * size_t(h1.face) + k) == v) c1 = 3 * h1.face + k;
                }
                fans.unite(c0, c1);
            }
        } else {
            ++s.non_manifold_edge_count;
            on_nonmanifold_edge[half[i].lo] = on_nonmanifold_edge[half[i].hi] = 1;
        }
        i = j;
    }

    // A vertex is non-manifold when its corners form more than one fan, or it is on a non-manifold edge.
    std::vector<uint32_t> first_fan(n, UINT32_MAX);
    std::vector<uint8_t> multi_fan(n, 0);
    for (size_t f = 0; f < face_count; ++f) {
        if (repeated[f]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k), v = vid(c);
            const uint32_t root = fans.find(c);
            if (first_fan[v] == UINT32_MAX) first_fan[v] = root;
            else if (first_fan[v] != root) multi_fan[v] = 1;
        }
    }
    for (size_t v = 0; v < n; ++v) s.non_manifold_vertex_count += multi_fan[v] || on_nonmanifold_edge[v];

    // Boundary loops: walk directed boundary edges; each walk that returns to its start, or cannot
    // continue (orientation flips along the boundary), is one loop.
    std::sort(boundary.begin(), boundary.end());
    std::vector<uint8_t> used(boundary.size(), 0);
    auto next_from = [&](uint32_t v) -> size_t {
        auto it = std::lower_bound(boundary.begin(), boundary.end(), std::make_pair(v, uint32_t(0)));
        for (; it != boundary.end() && it->first == v; ++it)
            if (!used[size_t(it - boundary.begin())]) return size_t(it - boundary.begin());
        return SIZE_MAX;
    };
    for (size_t e = 0; e < boundary.size(); ++e) {
        if (used[e]) continue;
        ++s.boundary_loop_count;
        const uint32_t start = boundary[e].first;
        size_t cur = e;
        while (cur != SIZE_MAX) {
            used[cur] = 1;
            if (boundary[cur].second == start) break;
            cur = next_from(boundary[cur].second);
        }
    }

    // Components: faces joined through shared vertices.
    UnionFind comps(n);
    for (size_t f = 0; f < face_count; ++f) {
        comps.unite(vid(3 * f), vid(3 * f + 1));
        comps.unite(vid(3 * f), vid(3 * f + 2));
    }
    for (size_t v = 0; v < n; ++v) s.component_count += referenced[v] && comps.find(uint32_t(v)) == v;

    s.euler_characteristic =
        int64_t(s.referenced_vertex_count) - int64_t(s.edge_count) + int64_t(face_count - std::count(repeated.begin(), repeated.end(), uint8_t(1)));
    return s;
}

} // namespace lodbake
