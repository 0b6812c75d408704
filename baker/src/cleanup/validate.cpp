#include "lodbake/cleanup/validate.h"

#include <algorithm>
#include <functional>

#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

bool ValidationReport::isManifold() const {
    return topology.non_manifold_edge_count == 0 && topology.non_manifold_vertex_count == 0 &&
           topology.inconsistent_edge_count == 0 && open_boundary_chains == 0;
}

bool ValidationReport::isClosedManifold() const {
    const TopologyStats& t = topology;
    return isManifold() && t.face_count > 0 && t.boundary_edge_count == 0 && t.component_count == 1 &&
           t.degenerate_face_count == 0 && t.duplicate_face_count == 0 && t.unreferenced_vertex_count == 0 &&
           t.non_finite_vertex_count == 0;
}

ValidationReport validate(const Mesh& input, const ValidateOptions& options) {
    ValidationReport r;
    TopologyOptions topo;
    topo.weld_by_position = options.weld_by_position;
    r.topology = computeTopologyStats(input, topo);

    // Loops and components are computed on a copy with the same welding as the counts.
    Mesh welded;
    const Mesh* m = &input;
    if (options.weld_by_position) {
        welded.positions = input.positions;
        welded.indices = input.indices;
        std::vector<uint32_t> order(input.vertexCount());
        for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
        auto less = [&](uint32_t a, uint32_t b) {
            const Vec3f& p = input.positions[a];
            const Vec3f& q = input.positions[b];
            if (p.x != q.x) return p.x < q.x;
            if (p.y != q.y) return p.y < q.y;
            if (p.z != q.z) return p.z < q.z;
            return a < b;
        };
        std::sort(order.begin(), order.end(), less);
        std::vector<uint32_t> rep(order.size());
        for (size_t i = 0; i < order.size(); ++i)
            rep[order[i]] =
                (i > 0 && input.positions[order[i]] == input.positions[order[i - 1]]) ? rep[order[i - 1]] : order[i];
        for (uint32_t& i : welded.indices) i = rep[i];
        m = &welded;
    }
    const EdgeTable table = buildEdgeTable(*m);
    for (const BoundaryLoop& loop : findBoundaryLoops(*m, table)) {
        r.boundary_loop_lengths.push_back(uint32_t(loop.vertices.size()));
        r.open_boundary_chains += !loop.closed;
    }
    std::sort(r.boundary_loop_lengths.begin(), r.boundary_loop_lengths.end(), std::greater<uint32_t>());

    UnionFind comps(m->vertexCount());
    for (size_t f = 0; f < m->faceCount(); ++f) {
        comps.unite(m->indices[3 * f], m->indices[3 * f + 1]);
        comps.unite(m->indices[3 * f], m->indices[3 * f + 2]);
    }
    std::vector<uint32_t> faces_of_root(m->vertexCount(), 0);
    for (size_t f = 0; f < m->faceCount(); ++f) ++faces_of_root[comps.find(m->indices[3 * f])];
    for (uint32_t c : faces_of_root)
        if (c) r.component_face_counts.push_back(c);
    std::sort(r.component_face_counts.begin(), r.component_face_counts.end(), std::greater<uint32_t>());
    return r;
}

} // namespace lodbake
