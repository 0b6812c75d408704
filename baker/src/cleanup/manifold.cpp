// Non-manifold repair: pair the faces of over-used edges, cut or remove the rest, then split every
// vertex whose corners form several fans (pmp-library's non-manifold vertex handling works the same
// way: one vertex per fan).
#include <algorithm>
#include <cmath>

#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters ManifoldReport::counters() const {
    return {{"repeated_index_faces_removed", repeated_index_faces_removed},
            {"non_manifold_edges", non_manifold_edges},
            {"faces_cut", faces_cut},
            {"faces_removed", faces_removed},
            {"vertices_split", vertices_split},
            {"vertices_added", vertices_added}};
}

namespace {

// How well two faces on a shared edge continue each other: opposite traversal (consistent
// orientation) is preferred, then the flattest dihedral. Larger is better.
double pairScore(const Mesh& m, uint32_t ca, uint32_t cb) {
    const bool opposite = halfStart(m, ca) != halfStart(m, cb);
    const Vec3d na = normalize(faceNormal(m, ca / 3)), nb = normalize(faceNormal(m, cb / 3));
    const double d = dot(na, nb);   // 1 when flat and consistent
    return opposite ? 2.0 + d : -d; // inconsistent pairs: flat means normals opposite
}

// Greedy pairing of the half-edges of one edge; returns pairs, leaves the rest in `unpaired`.
void pairEdge(const Mesh& m, const uint32_t* corners, uint32_t k, std::vector<CornerPair>& pairs,
              std::vector<uint32_t>& unpaired) {
    std::vector<uint8_t> taken(k, 0);
    for (;;) {
        double best = -1e300;
        uint32_t bi = kNone, bj = kNone;
        for (uint32_t i = 0; i < k; ++i)
            for (uint32_t j = i + 1; j < k; ++j) {
                if (taken[i] || taken[j]) continue;
                const double s = pairScore(m, corners[i], corners[j]);
                if (s > best) { // strict: ties keep the lowest corner pair
                    best = s;
                    bi = i;
                    bj = j;
                }
            }
        if (bi == kNone) break;
        taken[bi] = taken[bj] = 1;
        pairs.push_back({corners[bi], corners[bj]});
    }
    for (uint32_t i = 0; i < k; ++i)
        if (!taken[i]) unpaired.push_back(corners[i]);
}

// The over-used edges of `mesh` (three or more faces; faces with a repeated index have no edges),
// ascending by key, each with its corners ascending: what an edge table of `mesh` lists for them. It
// is only valid when `mesh` came from a mesh whose over-used edges had the keys `overused` (ascending)
// by removing faces and splitting vertices into new ids >= `new_from`, without a repeated-index face:
// removing faces only takes half-edges away, and a split moves corners only to new vertices, so an
// edge between two older vertices keeps a subset of its half-edges. Only the half-edges of the
// edges over-used before and of the edges touching a new vertex are gathered and counted.
struct OverusedEdge {
    uint64_t key;
    std::vector<uint32_t> corners;
};
std::vector<OverusedEdge> overusedEdges(const Mesh& mesh, const std::vector<uint64_t>& overused, size_t new_from) {
    std::vector<std::pair<uint64_t, uint32_t>> candidates; // (key, corner)
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        const uint32_t* t = &mesh.indices[3 * f];
        if (std::max({t[0], t[1], t[2]}) < new_from && overused.empty()) continue;
        if (hasRepeatedIndex(mesh, f)) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k);
            const uint32_t a = halfStart(mesh, c), b = halfEnd(mesh, c);
            const uint64_t key = edgeKey(a, b);
            if (std::max(a, b) >= new_from || std::binary_search(overused.begin(), overused.end(), key))
                candidates.push_back({key, c});
        }
    }
    std::sort(candidates.begin(), candidates.end());
    std::vector<OverusedEdge> out;
    for (size_t i = 0; i < candidates.size();) {
        size_t j = i;
        while (j < candidates.size() && candidates[j].first == candidates[i].first) ++j;
        if (j - i > 2) {
            OverusedEdge e{candidates[i].first, {}};
            for (size_t x = i; x < j; ++x) e.corners.push_back(candidates[x].second);
            out.push_back(std::move(e));
        }
        i = j;
    }
    return out;
}

// splitVerticesByFans over the 2-use edges of `mesh` (no repeated-index face), when only the
// vertices marked in `candidate` can have more than one fan: the same vertices split, the same new
// ids in the same order (one per fan other than a vertex's first, in ascending order of the fan's
// lowest corner), the same corners rewritten. Only the faces touching a candidate are looked at: every
// edge at a candidate lies on them, so their table gives those edges' exact uses, hence every join
// between corners of a candidate.
size_t splitCandidateVerticesByFans(Mesh& mesh, const std::vector<uint8_t>& candidate, size_t& added) {
    added = 0;
    std::vector<uint32_t> local_faces;
    std::vector<uint32_t> local_indices;
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        const uint32_t* t = &mesh.indices[3 * f];
        if (!candidate[t[0]] && !candidate[t[1]] && !candidate[t[2]]) continue;
        local_faces.push_back(uint32_t(f));
        local_indices.insert(local_indices.end(), t, t + 3);
    }
    // Local corner 3i+k is corner 3*local_faces[i]+k: ascending in both numberings, so the lowest
    // corner of a fan (its union-find root) is the same in either.
    const EdgeTable table = buildEdgeTable(local_indices, mesh.vertexCount());
    auto next = [](uint32_t c) { return c % 3 == 2 ? c - 2 : c + 1; };
    UnionFind fans(local_indices.size());
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        if (table.uses(e) != 2) continue;
        const uint64_t key = table.keys[e];
        // An edge between two non-candidates may have faces outside the local set: its count is not
        // exact, and it joins no corner of a candidate anyway.
        if (!candidate[uint32_t(key >> 32)] && !candidate[uint32_t(key)]) continue;
        const uint32_t a = table.corners[table.begin[e]], b = table.corners[table.begin[e] + 1];
        if (local_indices[a] == local_indices[b]) {
            fans.unite(a, b);
            fans.unite(next(a), next(b));
        } else {
            fans.unite(a, next(b));
            fans.unite(next(a), b);
        }
    }
    // Fans other than the first of their vertex, by lowest corner: new ids in that order.
    std::vector<uint32_t> first_root(mesh.vertexCount(), kNone);
    std::vector<uint32_t> root_vertex(local_indices.size(), kNone);
    std::vector<uint8_t> split(mesh.vertexCount(), 0);
    size_t split_count = 0;
    for (uint32_t c = 0; c < local_indices.size(); ++c) {
        const uint32_t v = local_indices[c];
        if (!candidate[v]) continue;
        const uint32_t r = fans.find(c);
        if (first_root[v] == kNone) first_root[v] = r;
        if (r == first_root[v]) continue;
        if (root_vertex[r] == kNone) {
            root_vertex[r] = duplicateVertex(mesh, v);
            ++added;
            if (!split[v]) {
                split[v] = 1;
                ++split_count;
            }
        }
        mesh.indices[3 * local_faces[c / 3] + c % 3] = root_vertex[r];
    }
    return split_count;
}

} // namespace

ManifoldReport makeManifold(Mesh& mesh, const ManifoldOptions& options) {
    Scratch scratch;
    return makeManifold(mesh, options, scratch);
}

ManifoldReport cleanup_detail::makeManifold(Mesh& mesh, const ManifoldOptions& options, Scratch& scratch,
                                            bool whole_mesh_recheck) {
    ManifoldReport r;
    if (countRepeatedIndexFaces(mesh)) {
        std::vector<uint8_t> keep(mesh.faceCount(), 1);
        for (size_t f = 0; f < mesh.faceCount(); ++f) keep[f] = !hasRepeatedIndex(mesh, f);
        r.repeated_index_faces_removed = removeFaces(mesh, keep);
    }
    EdgeTable& table = scratch.table;
    buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
    // In the cut mode no face is removed before the split, so the split reads the 2-use edges from
    // the table itself and `joins` holds only the pairs chosen on over-used edges (an array of
    // every edge's pair costs fresh pages); the remove mode lists every join.
    const bool joins_from_table = options.edge_mode == NonManifoldEdgeMode::Cut;
    std::vector<CornerPair> joins;
    std::vector<uint32_t> unpaired;
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        const uint32_t k = table.uses(e);
        const uint32_t* c = &table.corners[table.begin[e]];
        if (k == 2) {
            if (!joins_from_table) joins.push_back({c[0], c[1]});
        } else if (k > 2) {
            ++r.non_manifold_edges;
            const size_t before = unpaired.size();
            if (k > 64) { // pathological fans: pair in corner order instead of the quadratic search
                for (uint32_t i = 0; i + 1 < k; i += 2) joins.push_back({c[i], c[i + 1]});
                if (k % 2) unpaired.push_back(c[k - 1]);
            } else {
                pairEdge(mesh, c, k, joins, unpaired);
            }
            r.faces_cut += unpaired.size() - before;
        }
    }
    if (options.edge_mode == NonManifoldEdgeMode::Remove && !unpaired.empty()) {
        std::vector<uint8_t> keep(mesh.faceCount(), 1);
        for (uint32_t c : unpaired) keep[c / 3] = 0;
        r.faces_removed = removeFaces(mesh, keep);
        r.faces_cut = 0;
        // Removing faces shifts corners: pair again on the smaller mesh (no edge has > 2 faces now
        // except where a removed face's partner was itself over-used; repeat until stable).
        for (int round = 0; round < 8; ++round) {
            buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
            joins.clear();
            unpaired.clear();
            for (uint32_t e = 0; e < table.edgeCount(); ++e) {
                const uint32_t k = table.uses(e);
                const uint32_t* c = &table.corners[table.begin[e]];
                if (k == 2)
                    joins.push_back({c[0], c[1]});
                else if (k > 2)
                    pairEdge(mesh, c, std::min<uint32_t>(k, 64), joins, unpaired);
            }
            if (unpaired.empty()) break;
            std::vector<uint8_t> keep2(mesh.faceCount(), 1);
            for (uint32_t c : unpaired) keep2[c / 3] = 0;
            r.faces_removed += removeFaces(mesh, keep2);
        }
    }
    const size_t vertices_before_split = mesh.vertexCount();
    size_t added = 0;
    r.vertices_split = splitVerticesByFans(mesh, joins, added, joins_from_table ? &table : nullptr);
    r.vertices_added = added;
    // A cut face still joined to the kept pair around both ends of the edge keeps using it (splitting
    // vertices cannot separate it): those faces are removed, and the vertices of removed faces split
    // again across the remaining pairs (removing faces can pinch a vertex again). Bounded; each
    // round removes faces.
    auto removeExtra = [&](const std::vector<uint32_t>& extra) {
        std::vector<uint8_t> keep(mesh.faceCount(), 1);
        for (uint32_t c : extra) keep[c / 3] = 0;
        const size_t removed = removeFaces(mesh, keep);
        r.faces_removed += removed;
        r.faces_cut -= std::min<uint64_t>(r.faces_cut, removed);
    };
    // Pairs the over-used edge with corners c[0..k) again, keeping only the best-fitting pair.
    auto extraOf = [&](const uint32_t* c, uint32_t k, std::vector<uint32_t>& extra) {
        std::vector<CornerPair> pairs;
        pairEdge(mesh, c, std::min<uint32_t>(k, 64), pairs, extra);
        for (size_t i = 1; i < pairs.size(); ++i) extra.insert(extra.end(), {pairs[i].a, pairs[i].b});
        for (uint32_t i = 64; i < k; ++i) extra.push_back(c[i]);
    };
    if (options.edge_mode == NonManifoldEdgeMode::Cut && !whole_mesh_recheck) {
        // No whole-mesh table: the edges that can be over-used are found from the previous ones and
        // the new vertices (overusedEdges), and only the vertices of removed faces can gain a fan,
        // since every other vertex keeps its corners and its edges' uses, and each was one fan
        // across joins that are all still 2-use edges.
        std::vector<uint64_t> overused;
        for (uint32_t e = 0; e < table.edgeCount(); ++e)
            if (table.uses(e) > 2) overused.push_back(table.keys[e]); // ascending, as the table's keys
        size_t new_from = vertices_before_split;
        for (int round = 0; round < 8; ++round) {
            const std::vector<OverusedEdge> edges = overusedEdges(mesh, overused, new_from);
            std::vector<uint32_t> extra;
            for (const OverusedEdge& e : edges) extraOf(e.corners.data(), uint32_t(e.corners.size()), extra);
            if (extra.empty()) break;
            std::vector<uint8_t> candidate(mesh.vertexCount(), 0);
            for (uint32_t c : extra)
                for (uint32_t k = 0; k < 3; ++k) candidate[mesh.indices[c / 3 * 3 + k]] = 1;
            removeExtra(extra);
            overused.clear();
            for (const OverusedEdge& e : edges) overused.push_back(e.key);
            new_from = mesh.vertexCount();
            size_t more = 0;
            r.vertices_split += splitCandidateVerticesByFans(mesh, candidate, more);
            r.vertices_added += more;
        }
        return r;
    }
    for (int round = 0; round < 8; ++round) {
        buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
        std::vector<uint32_t> extra;
        for (uint32_t e = 0; e < table.edgeCount(); ++e)
            if (table.uses(e) > 2) extraOf(&table.corners[table.begin[e]], table.uses(e), extra);
        if (extra.empty()) break;
        removeExtra(extra);
        buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
        joins.clear();
        for (uint32_t e = 0; e < table.edgeCount(); ++e)
            if (table.uses(e) == 2) joins.push_back({table.corners[table.begin[e]], table.corners[table.begin[e] + 1]});
        size_t more = 0;
        r.vertices_split += splitVerticesByFans(mesh, joins, more);
        r.vertices_added += more;
    }
    return r;
}

} // namespace lodbake
