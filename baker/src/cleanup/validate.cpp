#include "lodbake/cleanup/validate.h"

#include <algorithm>
#include <cmath>
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

namespace cleanup_detail {

ValidationReport validateWithTable(const Mesh& input, const ValidateOptions& options, EdgeTable* table_out,
                                   const std::function<void()>& beside) {
    ValidationReport r;
    const size_t n = input.vertexCount();
    // The counts weld bit-identical positions, the loops and components equal ones (-0 == +0). The
    // two agree unless some coordinate is -0 or NaN; then each is computed on its own.
    std::vector<uint32_t> welded;
    const std::vector<uint32_t>* indices = &input.indices;
    bool counts_done = false;
    uint64_t distinct = n;
    if (options.weld_by_position) {
        bool bits_differ = false;
        for (const Vec3f& p : input.positions)
            for (float x : {p.x, p.y, p.z}) bits_differ |= std::isnan(x) || (x == 0.0f && std::signbit(x));
        if (bits_differ) {
            TopologyOptions topo;
            topo.weld_by_position = true;
            r.topology = computeTopologyStats(input, topo);
            counts_done = true;
        }
        const std::vector<uint32_t> rep = positionWeldMap(input);
        distinct = 0;
        for (size_t v = 0; v < n; ++v) distinct += rep[v] == v;
        welded.resize(input.indices.size());
        for (size_t c = 0; c < welded.size(); ++c) welded[c] = rep[input.indices[c]];
        indices = &welded;
    }
    EdgeTable local;
    EdgeTable& table = table_out ? *table_out : local;
    buildEdgeTable(*indices, n, table);
    UnionFind comps(n);
    if (counts_done) {
        for (size_t f = 0; f < indices->size() / 3; ++f) {
            comps.unite((*indices)[3 * f], (*indices)[3 * f + 1]);
            comps.unite((*indices)[3 * f], (*indices)[3 * f + 2]);
        }
    }
    // The boundary loops need the table only: walked beside the counts.
    auto loops = [&] {
        r.boundary_loop_lengths.clear();
        r.open_boundary_chains = 0;
        for (const BoundaryLoop& loop : findBoundaryLoops(*indices, table)) {
            r.boundary_loop_lengths.push_back(uint32_t(loop.vertices.size()));
            r.open_boundary_chains += !loop.closed;
        }
        if (beside) beside();
    };
    if (counts_done)
        loops();
    else
        r.topology = topologyFromTable(input, *indices, distinct, table, comps, loops);
    std::sort(r.boundary_loop_lengths.begin(), r.boundary_loop_lengths.end(), std::greater<uint32_t>());

    std::vector<uint32_t> faces_of_root(n, 0);
    for (size_t f = 0; f < indices->size() / 3; ++f) ++faces_of_root[comps.find((*indices)[3 * f])];
    for (uint32_t c : faces_of_root)
        if (c) r.component_face_counts.push_back(c);
    std::sort(r.component_face_counts.begin(), r.component_face_counts.end(), std::greater<uint32_t>());
    return r;
}

} // namespace cleanup_detail

ValidationReport validate(const Mesh& input, const ValidateOptions& options) {
    return validateWithTable(input, options, nullptr);
}

} // namespace lodbake
