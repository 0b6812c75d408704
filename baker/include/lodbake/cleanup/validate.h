#pragma once
// validate(): a report of everything wrong with a mesh's topology and geometry, before any repair
// runs (STYLE.md §6). It never changes the mesh.

#include <cstdint>
#include <vector>

#include "lodbake/cleanup/topology.h"
#include "lodbake/core/mesh.h"

namespace lodbake {

struct ValidateOptions {
    bool weld_by_position = false; // judge topology with bit-identical positions merged (ignores UV/normal seams)
};

struct ValidationReport {
    TopologyStats topology;                      // counts (see topology.h)
    std::vector<uint32_t> boundary_loop_lengths; // edges per boundary walk, descending
    uint64_t open_boundary_chains = 0;           // walks that could not return to their start (non-manifold or
                                                 // inconsistently oriented boundary)
    std::vector<uint32_t> component_face_counts; // faces per component, descending

    /// No boundary, one component, every edge and vertex manifold, consistent orientation, no
    /// degenerate or duplicate faces, nothing unreferenced or non-finite.
    bool isClosedManifold() const;
    /// Every edge and vertex manifold and consistently oriented (boundaries allowed).
    bool isManifold() const;
};

/// Reports boundary loops (with their lengths), components, non-manifold edges and vertices,
/// inconsistent orientation, degenerate and duplicate faces, unreferenced and non-finite vertices.
/// Precondition: checkMeshConsistency(mesh) is ok (indices in range).
ValidationReport validate(const Mesh& mesh, const ValidateOptions& options = {});

} // namespace lodbake
