#pragma once
// Topology statistics of a triangle mesh: the numbers `lodbake info` prints and the repair passes
// start from. A report, not a fix.

#include <cstdint>

#include "lodbake/core/mesh.h"

namespace lodbake {

struct TopologyOptions {
    bool weld_by_position = false; // treat vertices with bit-identical positions as one (splits at UV seams vanish)
};

struct TopologyStats {
    uint64_t vertex_count = 0;              // after welding when weld_by_position
    uint64_t face_count = 0;
    uint64_t referenced_vertex_count = 0;
    uint64_t unreferenced_vertex_count = 0;
    uint64_t edge_count = 0;                // distinct undirected edges of non-degenerate faces
    uint64_t boundary_edge_count = 0;       // edges used by exactly one face
    uint64_t boundary_loop_count = 0;       // closed chains of boundary edges (a pinched loop counts once per chain walked)
    uint64_t non_manifold_edge_count = 0;   // edges used by three or more faces
    uint64_t non_manifold_vertex_count = 0; // vertices whose faces form more than one fan (or sit on a non-manifold edge)
    uint64_t inconsistent_edge_count = 0;   // manifold edges whose two faces traverse it in the same direction
    uint64_t component_count = 0;           // face-connected components (through shared vertices)
    uint64_t degenerate_face_count = 0;     // repeated index or zero area
    uint64_t duplicate_face_count = 0;      // faces with the same vertex set as an earlier face
    uint64_t non_finite_vertex_count = 0;   // NaN or Inf coordinate
    int64_t euler_characteristic = 0;       // V - E + F over referenced vertices
};

TopologyStats computeTopologyStats(const Mesh& mesh, const TopologyOptions& options = {});

} // namespace lodbake
