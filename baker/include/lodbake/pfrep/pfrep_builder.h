#pragma once
// PFRep builder: Cortés Carrillo's progressive-fans multiresolution representation, written as the
// compact blob the runtime reads (lodrt/pfrep.h; layout in docs/format/pfrep.md).
//
// PFRep's primitive removes ONE vertex and re-triangulates its neighbourhood. We drive it from a
// HALF-EDGE-collapse sequence (SimplifyOptions::placement = CollapsePlacement::KeepEndpoint): the
// removed point u goes, its faces that contain the kept point v die, the others are re-created with
// u replaced by v, tagged with u as their dependency. No point ever moves, so level k of the blob is
// exactly the simplifier's mesh after k collapses (triangle for triangle, by position); full-edge
// sequences (kept point moved) are refused. The bake instead reads its discrete chain's full-edge
// collapses as vertex removals (buildPfrepFromChain): one simplification for both.
//
// Vertex ids in the blob are removal ranks; positions are quantized to 16 bits per axis over the
// bounding box. Only positions are stored (no normals, UVs or colours).

#include <cstdint>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/simplify.h"

namespace lodbake {

struct PfrepOptions {
    float target_ratio = 0.0f; // simplify down to this fraction of the input triangles (0: as far as valid)
    SimplifyOptions simplify;  // validity rules and weights; targets and placement are overridden
};

struct PfrepBuild {
    std::vector<uint8_t> blob;
    std::vector<uint32_t> rank_point;  // point id (CollapseSequence::point_positions) of every blob vertex
    std::vector<uint32_t> rank_kept;   // per removed rank: the point it collapsed into (format 4)
    size_t removed = 0;                // vertices removable in order (the collapses recorded)
    size_t level0_triangles = 0;       // triangles of the full-detail mesh
    size_t stored_triangles = 0;       // every triangle that ever exists in the sequence
    size_t dependency_groups = 0;      // (v_d, B_d) masks stored, originals excluded
    size_t neighbour_slots = 0;        // total length of the fan sequences A_i
    std::vector<uint32_t> level_triangles; // triangles of level k (after k removals), k = 0..removed
};

/// Points of every input triangle as the simplifier sees them (positions welded bit-exactly,
/// triangles with a repeated point dropped): 3 point ids per triangle, in input order.
Result<std::vector<uint32_t>> pointTriangles(const Mesh& mesh, const CollapseSequence& sequence);

/// Builds the blob from a recorded half-edge-collapse sequence over `point_triangles`.
/// InvalidInput when a record moves its kept point or references a point without faces.
Result<PfrepBuild> buildPfrepFromSequence(const CollapseSequence& sequence, const std::vector<uint32_t>& point_triangles,
                                          Diagnostics& diagnostics);

/// Points of `mesh` as the simplifier numbers them (lod_chain.h: bit-identical positions welded,
/// numbered in order of first use by the faces not degenerate by position) and those faces' points.
Status chainPoints(const MeshView& mesh, std::vector<Vec3f>& positions, std::vector<uint32_t>& triangles);

/// Builds the blob from a discrete chain's own simplification pass (LodChain::removals, recorded with
/// LodChainOptions::record_removals) over `mesh`, the chain's input: each full-edge collapse is read
/// as the half-edge collapse that removes one end and keeps the other at its ORIGINAL position, so
/// level k of the blob has exactly the chain's faces after k collapses (positions differ: the chain
/// moved its points). The end that stays is the one with the lower error for the merged point's
/// face-plane quadric, as the half-edge simplifier chooses its direction, or the chain's kept end
/// when the chain did not move it.
Result<PfrepBuild> buildPfrepFromChain(const MeshView& mesh, const CollapsePairLog& removals, Diagnostics& diagnostics);

/// Runs the half-edge simplifier on `mesh` and builds the blob.
Result<PfrepBuild> buildPfrep(const Mesh& mesh, const PfrepOptions& options, Diagnostics& diagnostics);

} // namespace lodbake
