#pragma once
// The topological repair passes. Each is a free function over a Mesh with an options struct, and each
// returns a report of exactly what it changed. Every pass keeps all attribute streams (normals,
// tangents, UV sets, colours) and sub-mesh ranges in step with the vertices and faces it edits.
//
// Common precondition: checkMeshConsistency(mesh) is ok. No pass throws, asserts on input data or
// loops without bound; an empty mesh is returned unchanged with an all-zero report.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "lodbake/core/mesh.h"

namespace lodbake {

/// Named counters of one pass, in a fixed order (for --json and logs).
using PassCounters = std::vector<std::pair<std::string, uint64_t>>;

// ---- weld -------------------------------------------------------------------------------------

struct WeldOptions {
    double tolerance_rel = 0.0; // merge distance as a fraction of the bbox diagonal; 0: bit-identical positions only
    bool respect_attributes = true; // never merge across UV / normal seams (below)
    float uv_tolerance = 1e-4f;     // max |Δuv| per component for two vertices to merge
    float normal_angle_deg = 1.0f;  // max angle between normals for two vertices to merge
};

struct WeldReport {
    uint64_t vertices_merged = 0; // vertices that now point at another (earlier) vertex
    uint64_t seam_pairs_kept = 0; // pairs close enough to merge but kept apart by respect_attributes
    uint64_t vertices_before = 0;
    uint64_t vertices_after = 0;
    PassCounters counters() const;
};

/// Merges vertices whose positions lie within tolerance_rel * diagonal of an earlier representative
/// (spatial hash over cells of that size; each vertex joins the lowest-index representative in range,
/// so the result is deterministic and does not chain). Merged vertices are dropped from every stream;
/// faces may become degenerate (run removeDegenerateFaces next). Non-finite vertices never merge.
WeldReport weldVertices(Mesh& mesh, const WeldOptions& options = {});

// ---- degenerate / duplicate faces ----------------------------------------------------------------

struct DegenerateOptions {
    bool remove_zero_area = true;  // faces whose area is exactly zero in double precision
    bool remove_duplicates = true; // faces with the same vertex set as an earlier face (either winding)
};

struct DegenerateReport {
    uint64_t repeated_index_faces = 0;
    uint64_t zero_area_faces = 0;
    uint64_t duplicate_faces = 0;
    uint64_t non_finite_faces = 0; // faces touching a NaN/Inf vertex
    PassCounters counters() const;
};

/// Removes faces with a repeated index, zero area, a non-finite vertex, or the vertex set of an
/// earlier face (the first occurrence is kept).
DegenerateReport removeDegenerateFaces(Mesh& mesh, const DegenerateOptions& options = {});

// ---- unreferenced vertices -------------------------------------------------------------------------

struct UnreferencedReport {
    uint64_t vertices_removed = 0;
    PassCounters counters() const;
};

/// Drops vertices no face references and compacts every stream (relative order kept).
UnreferencedReport removeUnreferencedVertices(Mesh& mesh);

// ---- manifold ----------------------------------------------------------------------------------------

enum class NonManifoldEdgeMode {
    Cut,    // keep the best-fitting pair of faces joined; the others are cut loose (vertices duplicated)
    Remove, // keep the best-fitting pair; delete the other faces
};

struct ManifoldOptions {
    NonManifoldEdgeMode edge_mode = NonManifoldEdgeMode::Cut;
};

struct ManifoldReport {
    uint64_t repeated_index_faces_removed = 0; // precondition clean-up
    uint64_t non_manifold_edges = 0;           // edges with three or more faces, found
    uint64_t faces_cut = 0;                    // edge-face incidences cut loose (Cut mode)
    uint64_t faces_removed = 0;                // Remove mode
    uint64_t vertices_split = 0;               // non-manifold vertices split into one vertex per fan
    uint64_t vertices_added = 0;
    PassCounters counters() const;
};

/// Makes every edge have at most two faces and every vertex a single fan. On an edge with k > 2
/// faces, pairs are chosen greedily by fit (opposite traversal first, then the flattest dihedral,
/// ties by face index); unpaired faces are cut or removed. Then every vertex whose corners form
/// several fans is split, one vertex per fan.
ManifoldReport makeManifold(Mesh& mesh, const ManifoldOptions& options = {});

// ---- orientation ---------------------------------------------------------------------------------------

struct OrientOptions {
    bool outward = true;            // closed components: make the signed volume positive
    bool cut_non_orientable = true; // Möbius-like components: cut the conflicting edges (else leave them inconsistent)
};

struct OrientReport {
    uint64_t faces_flipped = 0;
    uint64_t components = 0;
    uint64_t closed_components_reversed = 0; // flipped as a whole to face outward
    uint64_t non_orientable_components = 0;
    uint64_t edges_cut = 0; // conflicting edges cut in non-orientable components
    uint64_t vertices_added = 0;
    PassCounters counters() const;
};

/// Orients every edge-connected component consistently (breadth-first, flipping faces that disagree
/// with their already-oriented neighbour). An open component keeps the orientation of the larger
/// area; a closed one is made outward. Precondition: manifold (run makeManifold first); on a
/// non-manifold edge the extra faces are treated as unconnected.
OrientReport orientFaces(Mesh& mesh, const OrientOptions& options = {});

// ---- small components ---------------------------------------------------------------------------------

struct ComponentOptions {
    // Speckle is judged at the scanner's sampling scale: under 20 triangles a component spans only
    // a handful of samples and carries no surface shape. The area fraction catches floaters in dense
    // reconstructions (90 faces of a million). Larger values drop real range-scan pieces separated by
    // depth discontinuities (docs/repair.md, "Small components").
    uint32_t min_face_count = 20;      // remove components with fewer faces
    double min_area_fraction = 0.0003; // remove components with less than this fraction of the total area
};

struct ComponentReport {
    uint64_t components_before = 0;
    uint64_t components_removed = 0;
    uint64_t faces_removed = 0;
    uint64_t area_removed_ppm = 0; // removed area in millionths of the total area
    PassCounters counters() const;
};

/// Removes vertex-connected components (vertices with bit-identical positions count as connected, so
/// UV islands of one surface stay together) that are small by face count or by area fraction. The
/// largest component (by area, ties by lowest face) is always kept. Leaves vertices unreferenced.
ComponentReport removeSmallComponents(Mesh& mesh, const ComponentOptions& options = {});

// ---- hole filling --------------------------------------------------------------------------------------

struct HoleFillOptions {
    uint32_t max_hole_edges = 100; // fill boundary loops of at most this many edges; larger ones stay open
    uint32_t max_dp_edges = 200; // up to this size use the O(n^3) Liepa triangulation, above it min-angle ear clipping
    bool refine = true;          // split patch triangles to match the surrounding edge density, relax by flips
    bool fair = true;            // smooth the new interior vertices (umbrella, boundary fixed)
    uint32_t fair_iterations = 30;
};

struct HoleFillReport {
    uint64_t seam_loops = 0;        // boundary loops along attribute seams (a matching rim at the same positions): not holes
    uint64_t holes_found = 0;
    uint64_t holes_filled = 0;
    uint64_t faces_added = 0;
    uint64_t vertices_added = 0;
    std::vector<uint32_t> filled_lengths;  // edges per filled hole, descending
    std::vector<uint32_t> skipped_lengths; // too large (> max_hole_edges), descending
    uint64_t holes_unfillable = 0;         // every triangulation would create a non-manifold edge, or open chain
    PassCounters counters() const;
};

/// Fills closed boundary loops of at most max_hole_edges edges (loops running along an attribute
/// seam, where another rim has the same positions, are not holes and are skipped) (Liepa 2003, "Filling holes in
/// meshes": a triangulation minimising the worst dihedral angle then area, then refinement and
/// fairing). New faces are oriented with the surrounding ones and appended to the sub-mesh of the
/// adjacent face. Precondition: manifold and consistently oriented (makeManifold, orientFaces).
HoleFillReport fillHoles(Mesh& mesh, const HoleFillOptions& options = {});

} // namespace lodbake
