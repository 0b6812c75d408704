// Consistent orientation: breadth-first propagation over manifold edges, cutting conflicting edges
// in non-orientable components, then outward orientation of closed components by signed volume.
#include <algorithm>
#include <vector>

#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters OrientReport::counters() const {
    return {{"components", components},
            {"faces_flipped", faces_flipped},
            {"closed_components_reversed", closed_components_reversed},
            {"non_orientable_components", non_orientable_components},
            {"edges_cut", edges_cut},
            {"vertices_added", vertices_added}};
}

OrientReport orientFaces(Mesh& mesh, const OrientOptions& options) {
    Scratch scratch;
    return orientFaces(mesh, options, scratch);
}

OrientReport cleanup_detail::orientFaces(Mesh& mesh, const OrientOptions& options, Scratch& scratch) {
    OrientReport r;
    const size_t face_count = mesh.faceCount();
    if (face_count == 0) return r;
    EdgeTable& table = scratch.table;
    buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
    std::vector<uint8_t> flip(face_count, 0), visited(face_count, 0), cut(table.edgeCount(), 0);
    std::vector<uint32_t> component(face_count, kNone);
    std::vector<uint8_t> component_open;
    std::vector<uint8_t> component_conflict;
    std::vector<uint32_t> queue; // breadth-first: faces are taken from `head` on, in the order queued
    queue.reserve(face_count);
    for (uint32_t seed = 0; seed < face_count; ++seed) {
        if (visited[seed] || hasRepeatedIndex(mesh, seed)) continue;
        const uint32_t comp = uint32_t(component_open.size());
        component_open.push_back(0);
        component_conflict.push_back(0);
        visited[seed] = 1;
        component[seed] = comp;
        queue.clear();
        queue.push_back(seed);
        for (size_t head = 0; head < queue.size(); ++head) {
            const uint32_t f = queue[head];
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t c = 3 * f + k;
                const uint32_t e = table.corner_edge[c];
                if (e == kNone) continue;
                if (table.uses(e) != 2) {
                    component_open[comp] |= table.uses(e) == 1;
                    continue;
                }
                const uint32_t* ec = &table.corners[table.begin[e]];
                const uint32_t o = ec[0] == c ? ec[1] : ec[0];
                const uint32_t g = o / 3;
                // Same start vertex means both faces run the edge the same way: one must flip.
                const uint8_t want = flip[f] ^ uint8_t(halfStart(mesh, c) == halfStart(mesh, o));
                if (!visited[g]) {
                    visited[g] = 1;
                    component[g] = comp;
                    flip[g] = want;
                    queue.push_back(g);
                } else if (flip[g] != want && !cut[e]) {
                    cut[e] = 1;
                    component_conflict[comp] = 1;
                }
            }
        }
    }
    r.components = component_open.size();
    for (uint8_t c : component_conflict) r.non_orientable_components += c;
    if (!options.cut_non_orientable) std::fill(cut.begin(), cut.end(), uint8_t(0));
    for (uint8_t c : cut) r.edges_cut += c;

    // Per component: signed volume (closed) or flipped vs kept area (open), after the BFS flips.
    const size_t comp_count = component_open.size();
    std::vector<double> volume(comp_count, 0.0), area_flipped(comp_count, 0.0), area_kept(comp_count, 0.0);
    for (uint32_t f = 0; f < face_count; ++f) {
        const uint32_t comp = component[f];
        if (comp == kNone) continue;
        const Vec3d a = toDouble(mesh.positions[mesh.indices[3 * f]]);
        const Vec3d b = toDouble(mesh.positions[mesh.indices[3 * f + 1]]);
        const Vec3d c = toDouble(mesh.positions[mesh.indices[3 * f + 2]]);
        const double v = dot(a, cross(b, c)) / 6.0;
        volume[comp] += flip[f] ? -v : v;
        const double area = length(cross(b - a, c - a));
        (flip[f] ? area_flipped : area_kept)[comp] += area;
    }
    std::vector<uint8_t> reverse(comp_count, 0);
    for (size_t comp = 0; comp < comp_count; ++comp) {
        const bool closed = !component_open[comp] && !component_conflict[comp];
        if (closed && options.outward) {
            reverse[comp] = volume[comp] < 0.0;
            r.closed_components_reversed += reverse[comp];
        } else {
            reverse[comp] = area_flipped[comp] > area_kept[comp];
        }
    }
    for (uint32_t f = 0; f < face_count; ++f) {
        if (component[f] == kNone) continue;
        if (flip[f] ^ reverse[component[f]]) {
            std::swap(mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]);
            ++r.faces_flipped;
        }
    }
    if (r.edges_cut) {
        // Corners moved within their faces by the flips; rebuild and join across every uncut edge.
        const EdgeTable t2 = buildEdgeTable(mesh);
        std::vector<CornerPair> joins;
        for (uint32_t e = 0; e < t2.edgeCount(); ++e) {
            if (t2.uses(e) != 2) continue;
            const uint32_t* ec = &t2.corners[t2.begin[e]];
            const uint32_t old_e = table.find(halfStart(mesh, ec[0]), halfEnd(mesh, ec[0]));
            if (old_e != kNone && cut[old_e]) continue;
            joins.push_back({ec[0], ec[1]});
        }
        size_t added = 0;
        splitVerticesByFans(mesh, joins, added);
        r.vertices_added = added;
    }
    return r;
}

} // namespace lodbake
