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

// Whether some edge of `mesh` may have more than two faces, after splitVerticesByFans turned the
// mesh `table` was built from (no repeated-index faces, none removed since) into `mesh`. The split
// moved corners only to new vertices (ids >= vertices_before), so an edge between two older
// vertices keeps a subset of its half-edges: only the edges over-used in `table` and the edges
// touching a new vertex can be over-used now. Those are counted exactly.
bool mayHaveOverusedEdge(const Mesh& mesh, const EdgeTable& table, size_t vertices_before) {
    std::vector<uint64_t> overused;
    for (uint32_t e = 0; e < table.edgeCount(); ++e)
        if (table.uses(e) > 2) overused.push_back(table.keys[e]); // ascending, as the table's keys
    std::vector<uint64_t> candidates;
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        if (hasRepeatedIndex(mesh, f)) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t c = uint32_t(3 * f + k);
            const uint32_t a = halfStart(mesh, c), b = halfEnd(mesh, c);
            const uint64_t key = edgeKey(a, b);
            if (std::max(a, b) >= vertices_before || std::binary_search(overused.begin(), overused.end(), key))
                candidates.push_back(key);
        }
    }
    std::sort(candidates.begin(), candidates.end());
    for (size_t i = 2; i < candidates.size(); ++i)
        if (candidates[i] == candidates[i - 2]) return true;
    return false;
}

} // namespace

ManifoldReport makeManifold(Mesh& mesh, const ManifoldOptions& options) {
    Scratch scratch;
    return makeManifold(mesh, options, scratch);
}

ManifoldReport cleanup_detail::makeManifold(Mesh& mesh, const ManifoldOptions& options, Scratch& scratch) {
    ManifoldReport r;
    if (countRepeatedIndexFaces(mesh)) {
        std::vector<uint8_t> keep(mesh.faceCount(), 1);
        for (size_t f = 0; f < mesh.faceCount(); ++f) keep[f] = !hasRepeatedIndex(mesh, f);
        r.repeated_index_faces_removed = removeFaces(mesh, keep);
    }
    EdgeTable& table = scratch.table;
    buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
    std::vector<CornerPair> joins;
    joins.reserve(table.edgeCount());
    std::vector<uint32_t> unpaired;
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        const uint32_t k = table.uses(e);
        const uint32_t* c = &table.corners[table.begin[e]];
        if (k == 2) {
            joins.push_back({c[0], c[1]});
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
    r.vertices_split = splitVerticesByFans(mesh, joins, added);
    r.vertices_added = added;
    // A cut face still joined to the kept pair around both ends of the edge keeps using it (splitting
    // vertices cannot separate it): those faces are removed. Bounded; each round removes faces.
    // The first round's table is skipped when it would find nothing: see mayHaveOverusedEdge.
    const bool check = options.edge_mode != NonManifoldEdgeMode::Cut ||
                       mayHaveOverusedEdge(mesh, table, vertices_before_split);
    for (int round = 0; round < 8 && check; ++round) {
        buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
        std::vector<uint32_t> extra;
        for (uint32_t e = 0; e < table.edgeCount(); ++e) {
            const uint32_t k = table.uses(e);
            if (k <= 2) continue;
            // Keep only the best-fitting pair on this edge.
            std::vector<CornerPair> pairs;
            pairEdge(mesh, &table.corners[table.begin[e]], std::min<uint32_t>(k, 64), pairs, extra);
            for (size_t i = 1; i < pairs.size(); ++i) extra.insert(extra.end(), {pairs[i].a, pairs[i].b});
            for (uint32_t i = 64; i < k; ++i) extra.push_back(table.corners[table.begin[e] + i]);
        }
        if (extra.empty()) break;
        std::vector<uint8_t> keep(mesh.faceCount(), 1);
        for (uint32_t c : extra) keep[c / 3] = 0;
        const size_t removed = removeFaces(mesh, keep);
        r.faces_removed += removed;
        r.faces_cut -= std::min<uint64_t>(r.faces_cut, removed);
        // Removing faces can pinch a vertex again: split once more across the remaining pairs.
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
