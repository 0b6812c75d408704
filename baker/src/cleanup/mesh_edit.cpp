#include "mesh_edit.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "core/parallel.h"

namespace lodbake {
namespace cleanup_detail {

uint32_t EdgeTable::find(uint32_t a, uint32_t b) const {
    const uint64_t k = edgeKey(a, b);
    auto it = std::lower_bound(keys.begin(), keys.end(), k);
    return it != keys.end() && *it == k ? uint32_t(it - keys.begin()) : kNone;
}

EdgeTable buildEdgeTable(const Mesh& mesh) {
    return buildEdgeTable(mesh.indices, mesh.vertexCount());
}

namespace {
// Ascending sort of a short run (a vertex's bucket holds a handful of half-edges).
void sortRun(uint64_t* first, uint64_t* last) {
    if (last - first > 32) {
        std::sort(first, last);
        return;
    }
    for (uint64_t* i = first + 1; i < last; ++i) {
        const uint64_t x = *i;
        uint64_t* j = i;
        for (; j > first && *(j - 1) > x; --j) *j = *(j - 1);
        *j = x;
    }
}
} // namespace

EdgeTable buildEdgeTable(const std::vector<uint32_t>& indices, size_t vertex_count) {
    EdgeTable t;
    buildEdgeTable(indices, vertex_count, t);
    return t;
}

void buildEdgeTable(const std::vector<uint32_t>& indices, size_t vertex_count, EdgeTable& t) {
    // Counting sort of the half-edges by lower vertex, then a small sort by (upper vertex, corner)
    // inside each bucket: the same order as sorting (key, corner) globally, in linear time for
    // mesh-like input. The corners are scattered straight into `corners`, and `corner_edge` holds each
    // corner's upper vertex until its edge id replaces it, so no array beyond the table's own is
    // allocated (fresh pages are what this costs most).
    t.keys.clear();
    t.begin.clear();
    const size_t corner_count = indices.size();
    const size_t face_count = corner_count / 3;
    const size_t n = vertex_count;
    const uint32_t* ix = indices.data();
    // start[lo + 1] ends up as the first slot of bucket lo (counted at lo + 2, prefix-summed, then
    // advanced by the scatter), so start[0..n] is the bucket table without a second array.
    std::vector<uint32_t> start(n + 2, 0);
    t.corner_edge.resize(corner_count);
    for (size_t f = 0; f < face_count; ++f) {
        const uint32_t a = ix[3 * f], b = ix[3 * f + 1], c = ix[3 * f + 2];
        uint32_t* hi = &t.corner_edge[3 * f];
        if (a == b || b == c || a == c) {
            hi[0] = hi[1] = hi[2] = kNone;
            continue;
        }
        hi[0] = std::max(a, b);
        hi[1] = std::max(b, c);
        hi[2] = std::max(c, a);
        ++start[std::min(a, b) + 2];
        ++start[std::min(b, c) + 2];
        ++start[std::min(c, a) + 2];
    }
    for (size_t v = 2; v < n + 2; ++v) start[v] += start[v - 1];
    const size_t half_count = start[n + 1];
    t.corners.resize(half_count);
    for (size_t f = 0; f < face_count; ++f) {
        if (t.corner_edge[3 * f] == kNone) continue;
        const uint32_t a = ix[3 * f], b = ix[3 * f + 1], c = ix[3 * f + 2];
        t.corners[start[std::min(a, b) + 1]++] = uint32_t(3 * f);
        t.corners[start[std::min(b, c) + 1]++] = uint32_t(3 * f + 1);
        t.corners[start[std::min(c, a) + 1]++] = uint32_t(3 * f + 2);
    }
    // Then per fixed chunk of vertices (never derived from the thread count), in parallel: sort each
    // bucket by (upper vertex, corner) in place and count the chunk's distinct edges; from the
    // chunks' first edge ids, write keys, ranges and corner_edge. A chunk touches only its own
    // buckets and their corners, so the table does not depend on the schedule.
    constexpr size_t kChunk = 8192;
    const size_t chunk_count = (n + kChunk - 1) / kChunk;
    std::vector<uint32_t> chunk_first_edge(chunk_count + 1, 0);
    auto sortChunk = [&](size_t chunk) {
        constexpr size_t kRun = 64;
        uint64_t run[kRun];
        std::vector<uint64_t> long_run;
        uint32_t edges = 0;
        for (size_t lo = chunk * kChunk; lo < std::min(n, (chunk + 1) * kChunk); ++lo) {
            const size_t first = start[lo], count = start[lo + 1] - first;
            uint64_t* r = run;
            if (count > kRun) {
                long_run.resize(count);
                r = long_run.data();
            }
            for (size_t i = 0; i < count; ++i) {
                const uint32_t c = t.corners[first + i];
                r[i] = (uint64_t(t.corner_edge[c]) << 32) | c; // corner_edge still holds the upper vertex
            }
            sortRun(r, r + count);
            for (size_t i = 0; i < count; ++i) {
                edges += i == 0 || (r[i] >> 32) != (r[i - 1] >> 32);
                t.corners[first + i] = uint32_t(r[i]);
            }
        }
        chunk_first_edge[chunk + 1] = edges;
    };
    auto emitChunk = [&](size_t chunk) {
        uint32_t e = chunk_first_edge[chunk];
        for (size_t lo = chunk * kChunk; lo < std::min(n, (chunk + 1) * kChunk); ++lo) {
            uint32_t prev_hi = kNone;
            for (size_t i = start[lo]; i < start[lo + 1]; ++i) {
                const uint32_t c = t.corners[i], hi = t.corner_edge[c];
                if (i == start[lo] || hi != prev_hi) {
                    t.keys[e] = (uint64_t(lo) << 32) | hi;
                    t.begin[e] = uint32_t(i);
                    ++e;
                    prev_hi = hi;
                }
                t.corner_edge[c] = e - 1;
            }
        }
    };
    // Sorting is idempotent, so a failed parallel run (out of memory in a worker) is redone here.
    if (!parallelFor(chunk_count, 1, sortChunk).ok())
        for (size_t chunk = 0; chunk < chunk_count; ++chunk) sortChunk(chunk);
    for (size_t chunk = 0; chunk < chunk_count; ++chunk) chunk_first_edge[chunk + 1] += chunk_first_edge[chunk];
    const size_t edge_count = chunk_first_edge[chunk_count];
    t.keys.resize(edge_count);
    t.begin.resize(edge_count + 1);
    if (!parallelFor(chunk_count, 1, emitChunk).ok()) {
        // The scheduler failed part-way: restore every corner's upper vertex and emit on this thread.
        for (size_t f = 0; f < face_count; ++f) {
            if (t.corner_edge[3 * f] == kNone) continue;
            const uint32_t a = ix[3 * f], b = ix[3 * f + 1], c = ix[3 * f + 2];
            t.corner_edge[3 * f] = std::max(a, b);
            t.corner_edge[3 * f + 1] = std::max(b, c);
            t.corner_edge[3 * f + 2] = std::max(c, a);
        }
        for (size_t chunk = 0; chunk < chunk_count; ++chunk) emitChunk(chunk);
    }
    t.begin[edge_count] = uint32_t(half_count);
}

Vec3d faceNormal(const Mesh& m, size_t f) {
    const Vec3d a = toDouble(m.positions[m.indices[3 * f]]);
    const Vec3d b = toDouble(m.positions[m.indices[3 * f + 1]]);
    const Vec3d c = toDouble(m.positions[m.indices[3 * f + 2]]);
    return cross(b - a, c - a);
}

std::vector<uint32_t> faceSubmeshes(const Mesh& mesh) {
    std::vector<uint32_t> s(mesh.faceCount(), 0);
    for (size_t i = 0; i < mesh.submeshes.size(); ++i) {
        const SubMesh& sm = mesh.submeshes[i];
        for (uint32_t f = sm.first_index / 3; f < (sm.first_index + sm.index_count) / 3 && f < s.size(); ++f)
            s[f] = uint32_t(i);
    }
    return s;
}

size_t removeFaces(Mesh& mesh, const std::vector<uint8_t>& keep) {
    const size_t face_count = mesh.faceCount();
    std::vector<uint32_t> kept_before(face_count + 1, 0); // faces kept among [0, f)
    for (size_t f = 0; f < face_count; ++f) kept_before[f + 1] = kept_before[f] + (keep[f] ? 1 : 0);
    if (kept_before[face_count] == face_count) return 0;
    size_t out = 0;
    for (size_t f = 0; f < face_count; ++f) {
        if (!keep[f]) continue;
        for (int k = 0; k < 3; ++k) mesh.indices[3 * out + k] = mesh.indices[3 * f + k];
        ++out;
    }
    mesh.indices.resize(3 * out);
    for (SubMesh& sm : mesh.submeshes) {
        const size_t first = std::min<size_t>(sm.first_index / 3, face_count);
        const size_t last = std::min<size_t>((sm.first_index + sm.index_count) / 3, face_count);
        sm.first_index = 3 * kept_before[first];
        sm.index_count = 3 * (kept_before[last] - kept_before[first]);
    }
    return face_count - out;
}

void insertFaces(Mesh& mesh, const std::vector<std::array<uint32_t, 3>>& faces, const std::vector<uint32_t>& submesh) {
    if (faces.empty()) return;
    if (mesh.submeshes.empty()) {
        for (const auto& t : faces) mesh.indices.insert(mesh.indices.end(), t.begin(), t.end());
        return;
    }
    // Rebuild the index buffer sub-mesh by sub-mesh, appending each one's new faces at its end.
    std::vector<uint32_t> indices;
    indices.reserve(mesh.indices.size() + 3 * faces.size());
    for (size_t s = 0; s < mesh.submeshes.size(); ++s) {
        SubMesh& sm = mesh.submeshes[s];
        const uint32_t first = uint32_t(indices.size());
        indices.insert(indices.end(), mesh.indices.begin() + sm.first_index,
                       mesh.indices.begin() + sm.first_index + sm.index_count);
        for (size_t i = 0; i < faces.size(); ++i)
            if (submesh[i] == s || (s + 1 == mesh.submeshes.size() && submesh[i] >= mesh.submeshes.size()))
                indices.insert(indices.end(), faces[i].begin(), faces[i].end());
        sm.first_index = first;
        sm.index_count = uint32_t(indices.size()) - first;
    }
    mesh.indices.swap(indices);
}

namespace {
template <class T> void remapStream(std::vector<T>& s, const std::vector<uint32_t>& first_old, uint32_t new_count) {
    if (s.empty()) return;
    std::vector<T> out(new_count);
    for (uint32_t n = 0; n < new_count; ++n) out[n] = s[first_old[n]];
    s.swap(out);
}
template <class T> void pushCopy(std::vector<T>& s, uint32_t v) {
    if (!s.empty()) s.push_back(T(s[v]));
}
} // namespace

void remapVertices(Mesh& mesh, const std::vector<uint32_t>& old_to_new, uint32_t new_count) {
    std::vector<uint32_t> first_old(new_count, kNone);
    for (uint32_t v = 0; v < old_to_new.size(); ++v)
        if (old_to_new[v] != kNone && first_old[old_to_new[v]] == kNone) first_old[old_to_new[v]] = v;
    remapStream(mesh.positions, first_old, new_count);
    remapStream(mesh.normals, first_old, new_count);
    remapStream(mesh.tangents, first_old, new_count);
    remapStream(mesh.colors, first_old, new_count);
    for (auto& uv : mesh.uvs) remapStream(uv, first_old, new_count);
    for (uint32_t& i : mesh.indices) i = old_to_new[i];
}

uint32_t duplicateVertex(Mesh& mesh, uint32_t v) {
    pushCopy(mesh.positions, v);
    pushCopy(mesh.normals, v);
    pushCopy(mesh.tangents, v);
    pushCopy(mesh.colors, v);
    for (auto& uv : mesh.uvs) pushCopy(uv, v);
    return uint32_t(mesh.positions.size() - 1);
}

uint32_t blendedVertex(Mesh& mesh, const std::array<uint32_t, 3>& from) {
    const uint32_t v = duplicateVertex(mesh, from[0]);
    const float third = 1.0f / 3.0f;
    mesh.positions[v] = (mesh.positions[from[0]] + mesh.positions[from[1]] + mesh.positions[from[2]]) * third;
    if (mesh.hasNormals())
        mesh.normals[v] = normalize(mesh.normals[from[0]] + mesh.normals[from[1]] + mesh.normals[from[2]]);
    if (mesh.hasTangents()) {
        Vec3f t;
        for (uint32_t f : from) t += Vec3f(mesh.tangents[f].x, mesh.tangents[f].y, mesh.tangents[f].z);
        t = normalize(t);
        mesh.tangents[v] = Vec4f(t.x, t.y, t.z, mesh.tangents[from[0]].w);
    }
    if (mesh.hasColors()) {
        Vec4f c;
        for (uint32_t f : from)
            for (int k = 0; k < 4; ++k) c[k] += mesh.colors[f][k] * third;
        mesh.colors[v] = c;
    }
    for (auto& uv : mesh.uvs) {
        Vec2f u;
        for (uint32_t f : from) {
            u.x += uv[f].x * third;
            u.y += uv[f].y * third;
        }
        uv[v] = u;
    }
    return v;
}

UnionFind::UnionFind(size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), uint32_t(0));
}

uint32_t UnionFind::find(uint32_t x) {
    while (parent_[x] != x) {
        parent_[x] = parent_[parent_[x]];
        x = parent_[x];
    }
    return x;
}

void UnionFind::unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a < b)
        parent_[b] = a;
    else if (b < a)
        parent_[a] = b;
}

size_t splitVerticesByFans(Mesh& mesh, const std::vector<CornerPair>& joins, size_t& added, const EdgeTable* table) {
    added = 0;
    const size_t corner_count = mesh.indices.size();
    UnionFind fans(corner_count);
    // The sets (each rooted at its lowest corner) do not depend on the order of the unions.
    auto join = [&](uint32_t a, uint32_t b) {
        const uint32_t an = a % 3 == 2 ? a - 2 : a + 1;
        const uint32_t bn = b % 3 == 2 ? b - 2 : b + 1;
        if (mesh.indices[a] == mesh.indices[b]) { // same direction (orientation not yet consistent)
            fans.unite(a, b);
            fans.unite(an, bn);
        } else {
            fans.unite(a, bn);
            fans.unite(an, b);
        }
    };
    if (table)
        for (uint32_t e = 0; e < table->edgeCount(); ++e)
            if (table->uses(e) == 2) join(table->corners[table->begin[e]], table->corners[table->begin[e] + 1]);
    for (const CornerPair& p : joins) join(p.a, p.b);
    // Corners are visited in ascending order, so a vertex's first fan is the one with its lowest corner.
    const size_t n = mesh.vertexCount();
    std::vector<uint32_t> first_root(n, kNone);
    // Fan root -> its new vertex, for the fans that are not their vertex's first: few in practice.
    // Only looked up, never iterated, so its order cannot reach the output.
    std::unordered_map<uint32_t, uint32_t> root_vertex;
    std::vector<uint8_t> split(n, 0);
    size_t split_count = 0;
    for (size_t c = 0; c < corner_count; ++c) {
        const uint32_t v = mesh.indices[c];
        const uint32_t r = fans.find(uint32_t(c));
        if (first_root[v] == kNone) first_root[v] = r;
        if (r == first_root[v]) continue;
        auto [it, inserted] = root_vertex.try_emplace(r, 0u);
        if (inserted) {
            it->second = duplicateVertex(mesh, v);
            ++added;
            if (!split[v]) {
                split[v] = 1;
                ++split_count;
            }
        }
        mesh.indices[c] = it->second;
    }
    return split_count;
}

std::vector<BoundaryLoop> findBoundaryLoops(const Mesh& mesh, const EdgeTable& table) {
    return findBoundaryLoops(mesh.indices, table);
}

std::vector<BoundaryLoop> findBoundaryLoops(const std::vector<uint32_t>& indices, const EdgeTable& table) {
    auto halfStart = [&](uint32_t c) { return indices[c]; };
    auto halfEnd = [&](uint32_t c) { return indices[c % 3 == 2 ? c - 2 : c + 1]; };
    // Directed boundary half-edges sorted by start vertex, then corner.
    std::vector<std::pair<uint32_t, uint32_t>> out; // (start vertex, corner)
    for (size_t e = 0; e < table.edgeCount(); ++e)
        if (table.uses(uint32_t(e)) == 1) {
            const uint32_t c = table.corners[table.begin[e]];
            out.push_back({halfStart(c), c});
        }
    std::sort(out.begin(), out.end());
    std::vector<uint8_t> used(out.size(), 0);
    auto nextFrom = [&](uint32_t v) -> size_t {
        auto it = std::lower_bound(out.begin(), out.end(), std::make_pair(v, uint32_t(0)));
        for (; it != out.end() && it->first == v; ++it)
            if (!used[size_t(it - out.begin())]) return size_t(it - out.begin());
        return SIZE_MAX;
    };
    std::vector<BoundaryLoop> loops;
    for (size_t i = 0; i < out.size(); ++i) {
        if (used[i]) continue;
        BoundaryLoop loop;
        const uint32_t start = out[i].first;
        size_t cur = i;
        loop.closed = false;
        while (cur != SIZE_MAX) {
            used[cur] = 1;
            loop.vertices.push_back(out[cur].first);
            loop.corners.push_back(out[cur].second);
            const uint32_t end = halfEnd(out[cur].second);
            if (end == start) {
                loop.closed = true;
                break;
            }
            cur = nextFrom(end);
        }
        loops.push_back(std::move(loop));
    }
    return loops;
}

namespace {

std::array<uint32_t, 3> positionBits(const Vec3f& p) {
    std::array<uint32_t, 3> k;
    std::memcpy(k.data(), &p, sizeof(k));
    return k;
}

} // namespace

std::vector<uint32_t> positionWeldMap(const Mesh& mesh) {
    const uint32_t n = uint32_t(mesh.vertexCount());
    bool has_nan = false;
    for (const Vec3f& p : mesh.positions) has_nan |= std::isnan(p.x) || std::isnan(p.y) || std::isnan(p.z);
    if (!has_nan) {
        // Float equality is bit equality once -0 is read as +0 (and nothing is NaN).
        return lowestEqualKey(n, [&](uint32_t v) {
            std::array<uint32_t, 3> k = positionBits(mesh.positions[v]);
            for (uint32_t& w : k)
                if (w == 0x80000000u) w = 0;
            return k;
        });
    }
    // With NaNs, keep the sorted scan this map was first defined by (a NaN never equals its neighbour).
    std::vector<uint32_t> order(n), rep(n);
    std::iota(order.begin(), order.end(), 0u);
    auto less = [&](uint32_t a, uint32_t b) {
        const Vec3f& p = mesh.positions[a];
        const Vec3f& q = mesh.positions[b];
        if (p.x != q.x) return p.x < q.x;
        if (p.y != q.y) return p.y < q.y;
        if (p.z != q.z) return p.z < q.z;
        return a < b;
    };
    std::sort(order.begin(), order.end(), less);
    for (uint32_t i = 0; i < n; ++i)
        rep[order[i]] = (i > 0 && mesh.positions[order[i]] == mesh.positions[order[i - 1]]) ? rep[order[i - 1]] : order[i];
    return rep;
}

std::vector<uint32_t> bitwiseWeldMap(const Mesh& mesh) {
    return lowestEqualKey(uint32_t(mesh.vertexCount()), [&](uint32_t v) { return positionBits(mesh.positions[v]); });
}

namespace {
bool attributesDiffer(const Mesh& m, uint32_t a, uint32_t b) {
    if (m.hasNormals() && m.normals[a] != m.normals[b]) return true;
    if (m.hasTangents() && m.tangents[a] != m.tangents[b]) return true;
    if (m.hasColors() && m.colors[a] != m.colors[b]) return true;
    for (const auto& uv : m.uvs)
        if (uv[a] != uv[b]) return true;
    return false;
}
} // namespace

std::vector<uint8_t> seamCorners(const Mesh& mesh, const EdgeTable& table, const std::vector<uint32_t>& weld) {
    std::vector<uint8_t> seam(mesh.indices.size(), 0);
    if (!mesh.hasNormals() && !mesh.hasTangents() && !mesh.hasColors() && mesh.uvs.empty()) return seam;
    std::vector<std::pair<uint64_t, uint32_t>> rims; // (welded key, corner)
    for (uint32_t e = 0; e < table.edgeCount(); ++e)
        if (table.uses(e) == 1) {
            const uint32_t c = table.corners[table.begin[e]];
            rims.push_back({edgeKey(weld[halfStart(mesh, c)], weld[halfEnd(mesh, c)]), c});
        }
    std::sort(rims.begin(), rims.end());
    for (size_t i = 0; i < rims.size();) {
        size_t j = i;
        while (j < rims.size() && rims[j].first == rims[i].first) ++j;
        for (size_t x = i; x < j; ++x)
            for (size_t y = i; y < j; ++y) {
                if (x == y) continue;
                const uint32_t c = rims[x].second, o = rims[y].second;
                const uint32_t va = halfStart(mesh, c), vb = halfEnd(mesh, c);
                uint32_t oa = halfStart(mesh, o), ob = halfEnd(mesh, o);
                if (weld[oa] != weld[va]) std::swap(oa, ob);
                if (attributesDiffer(mesh, va, oa) || attributesDiffer(mesh, vb, ob)) seam[c] = seam[o] = 1;
            }
        i = j;
    }
    return seam;
}

VertexAdjacency buildVertexAdjacency(const Mesh& mesh) {
    const size_t n = mesh.vertexCount();
    VertexAdjacency adj;
    adj.begin.assign(n + 1, 0);
    for (size_t f = 0; f < mesh.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) adj.begin[mesh.indices[3 * f + k] + 1] += 2;
    for (size_t v = 0; v < n; ++v) adj.begin[v + 1] += adj.begin[v];
    std::vector<uint32_t> fill(adj.begin.begin(), adj.begin.end() - 1);
    adj.neighbours.resize(adj.begin[n]);
    for (size_t f = 0; f < mesh.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = mesh.indices[3 * f + k];
            adj.neighbours[fill[v]++] = mesh.indices[3 * f + (k + 1) % 3];
            adj.neighbours[fill[v]++] = mesh.indices[3 * f + (k + 2) % 3];
        }
    // Sort and deduplicate each range, then compact.
    uint32_t out = 0;
    for (size_t v = 0; v < n; ++v) {
        auto b = adj.neighbours.begin() + adj.begin[v], e = adj.neighbours.begin() + adj.begin[v + 1];
        std::sort(b, e);
        const auto last = std::unique(b, e);
        const uint32_t start = out;
        for (auto it = b; it != last; ++it)
            if (*it != v) adj.neighbours[out++] = *it;
        adj.begin[v] = start;
    }
    adj.begin[n] = out;
    adj.neighbours.resize(out);
    return adj;
}

std::vector<uint8_t> boundaryVertices(const Mesh& mesh, const EdgeTable& table) {
    std::vector<uint8_t> b(mesh.vertexCount(), 0);
    for (size_t e = 0; e < table.edgeCount(); ++e)
        if (table.uses(uint32_t(e)) == 1) {
            const uint32_t c = table.corners[table.begin[e]];
            b[halfStart(mesh, c)] = b[halfEnd(mesh, c)] = 1;
        }
    return b;
}

} // namespace cleanup_detail
} // namespace lodbake
