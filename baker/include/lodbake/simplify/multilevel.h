#pragma once
// Multilevel simplification for scanner meshes (Guerra 2012, seed document 003, chapter 3): an
// outer loop that alternates a p-Laplacian smoothing step with a length/curvature-ordered edge
// decimation, so each outer iteration produces the next coarser level.
//
// Preconditions: `mesh` passes checkMeshConsistency and has finite positions (otherwise
// InvalidInput naming the first bad vertex). The method is geometry-only, as in the document: the
// output carries positions and triangles (one range, no material); other attribute streams are
// dropped. Open-boundary vertices and vertices on non-manifold edges never move and are never
// removed. No collapse creates a non-manifold edge, a valence-2 vertex or a flipped triangle.
// Output is deterministic: identical input and options give identical bytes.

#include <cstdint>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct MultilevelOptions {
    double percentage = 50.0;            // percentage of the input's edges to remove, in [0, 100)
    uint32_t iterations = 4;             // outer iterations (OUT_ITS): each smooths, then decimates 1/iterations
    uint32_t smoothing_iterations = 3;   // explicit p-Laplacian steps per outer iteration (the document's sm)
    double ple = 0.5;                    // p-Laplacian exponent p: 2 = plain Laplacian, p < 1 gathers
                                         // vertices toward high curvature
    double time_step = 0.1;              // Δt of each explicit step (weights are normalised: < 1 is stable)
    double lambda = 10.0;                // fidelity λ pulling each smoothing step back toward the level's input
    bool is_adaptive = true;             // scale λ per vertex by its initial curvature (features held harder)
    bool is_sorted = true;               // collapse the shortest, flattest edges first; false: one pass over
                                         // the edges, collapsing every edge shorter than the histogram threshold
    bool has_smoothing = true;           // run the smoothing step of each outer iteration
    bool has_decimation = true;          // run the decimation step of each outer iteration
};

struct MultilevelOutput {
    Mesh mesh;
    size_t input_triangles = 0;
    size_t collapses = 0;           // edge collapses performed over all levels
    size_t collapses_requested = 0; // percentage/100 × edges / 3 (each collapse removes three edges)
    size_t collapses_refused = 0;   // candidates refused by the validity checks
    double length_threshold = 0;    // TOLL: edges shorter than this are decimation candidates (object units)
    bool reached_target = false;    // false: fewer collapses than requested (see Diagnostics)
};

/// Simplifies `mesh` by the multilevel method. The number of collapses is fixed up front from the
/// percentage (edgetocollapse = percentage/100 × |E0| / 3), split evenly over the outer iterations.
/// When valid candidates run out the best mesh is returned with reached_target = false and a note in
/// `diagnostics`. Fails (InvalidInput) only on invalid input or options.
Result<MultilevelOutput> simplifyMultilevel(const Mesh& mesh, const MultilevelOptions& options,
                                            Diagnostics& diagnostics);

} // namespace lodbake
