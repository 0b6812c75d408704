#include "lodbake/cleanup/topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include "core/parallel.h"

#include "mesh_edit.h"

namespace lodbake {

namespace cleanup_detail {

namespace {

// The counts that come from the faces and vertices alone: non-finite, referenced and degenerate
// counts, duplicates among faces with a repeated id, and the components (`components` gets the
// unions). Also `repeated_faces`, for the Euler characteristic.
void faceCounts(const Mesh& mesh, const std::vector<uint32_t>& indices, uint64_t distinct_vertex_count,
                UnionFind& components, TopologyStats& s, uint64_t& repeated_faces) {
    const size_t n = mesh.vertexCount();
    const size_t face_count = indices.size() / 3;
    const uint32_t* ix = indices.data();
    s.face_count = face_count;
    for (const Vec3f& p : mesh.positions) s.non_finite_vertex_count += !isFinite(p);

    std::vector<uint8_t> referenced(n, 0);
    for (uint32_t v : indices) referenced[v] = 1;
    s.vertex_count = distinct_vertex_count;
    s.referenced_vertex_count = uint64_t(std::count(referenced.begin(), referenced.end(), uint8_t(1)));
    s.unreferenced_vertex_count = distinct_vertex_count - s.referenced_vertex_count;

    // Degenerate faces. Duplicates (same vertex set as an earlier face) are counted as the sum over
    // groups of equal sorted triples of (size - 1): a face with three distinct ids a < b < c is
    // grouped at its edge (a, b), so only the faces on one edge are compared (edgeCounts); faces with
    // a repeated id, which have no edges, are grouped by sorting their few triples.
    repeated_faces = 0;
    std::vector<std::array<uint32_t, 3>> repeated_keys;
    for (size_t f = 0; f < face_count; ++f) {
        const uint32_t a = ix[3 * f], b = ix[3 * f + 1], c = ix[3 * f + 2];
        if (a == b || b == c || a == c) {
            ++repeated_faces;
            std::array<uint32_t, 3> k = {a, b, c};
            std::sort(k.begin(), k.end());
            repeated_keys.push_back(k);
            continue;
        }
        const Vec3d pa = toDouble(mesh.positions[a]);
        const Vec3d e = cross(toDouble(mesh.positions[b]) - pa, toDouble(mesh.positions[c]) - pa);
        s.degenerate_face_count += dot(e, e) == 0.0;
    }
    s.degenerate_face_count += repeated_faces;
    std::sort(repeated_keys.begin(), repeated_keys.end());
    for (size_t i = 1; i < repeated_keys.size(); ++i) s.duplicate_face_count += repeated_keys[i] == repeated_keys[i - 1];

    // Components: faces joined through shared vertices.
    for (size_t f = 0; f < face_count; ++f) {
        components.unite(ix[3 * f], ix[3 * f + 1]);
        components.unite(ix[3 * f], ix[3 * f + 2]);
    }
    for (size_t v = 0; v < n; ++v) s.component_count += referenced[v] && components.find(uint32_t(v)) == v;
}

// The counts that come from the edge table: edges, boundary edges and loops, non-manifold edges and
// vertices, inconsistent edges, duplicates among faces with three distinct ids.
void edgeCounts(const Mesh& mesh, const std::vector<uint32_t>& indices, const EdgeTable& table, TopologyStats& s) {
    const size_t n = mesh.vertexCount();
    const size_t face_count = indices.size() / 3;
    const uint32_t* ix = indices.data();
    auto next = [](uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; };

    // Per edge: its uses. One use is a boundary edge (kept directed, as its face runs it); two join the
    // corners at each end into one fan, and tell whether the two faces agree on the direction; three
    // or more make the edge and both its vertices non-manifold.
    UnionFind fans(indices.size());
    std::vector<uint8_t> on_nonmanifold_edge(n, 0);
    std::vector<std::pair<uint32_t, uint32_t>> boundary; // directed as traversed by its face
    std::vector<uint32_t> thirds;                        // third ids of the faces grouped at one edge
    s.edge_count = table.edgeCount();
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        const uint32_t* ec = &table.corners[table.begin[e]];
        const uint32_t uses = table.uses(e);
        if (uses == 1) {
            ++s.boundary_edge_count;
            boundary.push_back({ix[ec[0]], ix[next(ec[0])]});
        } else if (uses == 2) {
            const uint32_t c0 = ec[0], c1 = ec[1];
            if (ix[c0] == ix[c1]) { // same direction
                ++s.inconsistent_edge_count;
                fans.unite(c0, c1);
                fans.unite(next(c0), next(c1));
            } else {
                fans.unite(c0, next(c1));
                fans.unite(next(c0), c1);
            }
        } else {
            ++s.non_manifold_edge_count;
            const uint64_t key = table.keys[e];
            on_nonmanifold_edge[uint32_t(key >> 32)] = on_nonmanifold_edge[uint32_t(key)] = 1;
        }
        if (uses < 2) continue;
        // Duplicates grouped at this edge: faces whose two lowest ids are its ends, by third id.
        const uint32_t hi = uint32_t(table.keys[e]);
        thirds.clear();
        for (uint32_t i = 0; i < uses; ++i) {
            const uint32_t third = ix[next(next(ec[i]))];
            if (third > hi) thirds.push_back(third);
        }
        if (thirds.size() < 2) continue;
        std::sort(thirds.begin(), thirds.end());
        for (size_t i = 1; i < thirds.size(); ++i) s.duplicate_face_count += thirds[i] == thirds[i - 1];
    }

    // A vertex is non-manifold when its corners form more than one fan, or it is on a non-manifold edge.
    std::vector<uint32_t> first_fan(n, kNone);
    std::vector<uint8_t> multi_fan(n, 0);
    for (size_t f = 0; f < face_count; ++f) {
        const uint32_t* t = ix + 3 * f;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k), v = ix[c];
            const uint32_t root = fans.find(c);
            if (first_fan[v] == kNone) first_fan[v] = root;
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
}

} // namespace

TopologyStats topologyFromTable(const Mesh& mesh, const std::vector<uint32_t>& indices,
                                uint64_t distinct_vertex_count, const EdgeTable& table, UnionFind& components,
                                const std::function<void()>& beside) {
    // Two independent halves (and the caller's `beside`), run side by side; each writes only its own
    // report and union-find, so the sums do not depend on the schedule.
    TopologyStats from_faces, from_edges;
    uint64_t repeated_faces = 0;
    auto part = [&](size_t i) {
        if (i == 0) {
            edgeCounts(mesh, indices, table, from_edges);
        } else {
            faceCounts(mesh, indices, distinct_vertex_count, components, from_faces, repeated_faces);
            if (beside) beside();
        }
    };
    if (!parallelFor(2, 1, part).ok()) {
        // A worker ran out of memory: both halves again on this thread, from scratch (the unions
        // already made are repeated, which changes nothing).
        from_faces = TopologyStats();
        from_edges = TopologyStats();
        part(0);
        part(1);
    }
    TopologyStats s = from_faces;
    s.edge_count = from_edges.edge_count;
    s.boundary_edge_count = from_edges.boundary_edge_count;
    s.boundary_loop_count = from_edges.boundary_loop_count;
    s.non_manifold_edge_count = from_edges.non_manifold_edge_count;
    s.non_manifold_vertex_count = from_edges.non_manifold_vertex_count;
    s.inconsistent_edge_count = from_edges.inconsistent_edge_count;
    s.duplicate_face_count += from_edges.duplicate_face_count;
    s.euler_characteristic = int64_t(s.referenced_vertex_count) - int64_t(s.edge_count) +
                             int64_t(s.face_count - repeated_faces);
    return s;
}

} // namespace cleanup_detail

TopologyStats computeTopologyStats(const Mesh& mesh, const TopologyOptions& options) {
    using namespace cleanup_detail;
    const size_t n = mesh.vertexCount();
    uint64_t distinct = n;
    std::vector<uint32_t> welded;
    const std::vector<uint32_t>* indices = &mesh.indices;
    if (options.weld_by_position) {
        const std::vector<uint32_t> remap = bitwiseWeldMap(mesh);
        distinct = 0;
        for (size_t v = 0; v < n; ++v) distinct += remap[v] == v;
        welded.resize(mesh.indices.size());
        for (size_t c = 0; c < welded.size(); ++c) welded[c] = remap[mesh.indices[c]];
        indices = &welded;
    }
    const EdgeTable table = buildEdgeTable(*indices, n);
    UnionFind components(n);
    return topologyFromTable(mesh, *indices, distinct, table, components);
}

} // namespace lodbake
