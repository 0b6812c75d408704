#pragma once
// Surface denoising: Laplacian smoothing with umbrella, cotangent or Fujiwara weights, Taubin λ|μ
// (the volume-preserving default), and the p-Laplacian diffusion with a curvature-adaptive fidelity
// term from Guerra 2012 (seed 003). A feature-preserving mode keeps sharp creases: it filters face
// normals only among neighbours within the feature angle and moves vertices to fit them (Sun,
// Rosin, Martin, Langbein 2007), so creases are never averaged across.

#include <cstdint>

#include "lodbake/cleanup/passes.h"
#include "lodbake/core/mesh.h"

namespace lodbake {

enum class DenoiseMethod {
    Laplacian,  // x += λ·L x per iteration (shrinks)
    Taubin,     // λ step then μ step per iteration (Taubin 1995); no shrinkage of low frequencies
    PLaplacian, // x += Δt·(L_p x − λ_i (x − x0)), L_p weights |x_j − x_i|^(p−2) (Guerra 2012)
};

enum class LaplacianWeights {
    Umbrella,  // w_ij = 1
    Cotangent, // w_ij = (cot α + cot β) / 2, clamped at 0
    Fujiwara,  // w_ij = 1 / |x_j − x_i|
};

struct DenoiseOptions {
    DenoiseMethod method = DenoiseMethod::Taubin;
    LaplacianWeights weights = LaplacianWeights::Umbrella; // for Laplacian and Taubin
    uint32_t iterations = 5;         // Laplacian/Taubin: steps; feature mode: normal-filter/vertex-update rounds
    uint32_t outer_iterations = 2;   // PLaplacian: outer iterations of 10 inner diffusion steps
    double lambda = 0.5;             // Laplacian/Taubin step size (0, 1]
    double mu = -0.53;               // Taubin shrink-compensating step (|μ| slightly above λ)
    double p = 1.0;                  // PLaplacian exponent (2 = plain Laplacian; p < 2 favours edges)
    double time_step = 0.1;          // PLaplacian Δt (weights are normalised, so ≤ 1 is stable)
    double fidelity = 0.3;           // PLaplacian λ: pull back toward the input
    bool adaptive_fidelity = true;   // PLaplacian: scale λ per vertex by its curvature relative to the mean
    bool fix_boundary = true;        // boundary vertices do not move
    bool preserve_features = false;  // replaces `method`: normal filtering within the feature angle (Sun et al. 2007)
                                     // for free vertices; crease vertices slide along the crease; corners fixed
    double feature_angle_deg = 30.0; // a crease is an edge whose face normals differ by more than this
    double max_crease_change_deg = 1.0; // preserve_features: a step that changes a crease's dihedral angle by more
                                        // than this is undone around it and those vertices are pinned
};

struct DenoiseReport {
    uint64_t vertices_moved = 0;
    uint64_t feature_edges = 0;       // preserve_features: crease edges detected
    uint64_t fixed_vertices = 0;      // boundary, isolated and feature-corner vertices held in place
    double mean_displacement_rel = 0; // mean |Δx| over moved vertices / bbox diagonal
    double max_displacement_rel = 0;
    double roughness_before_deg = 0; // meanDihedralDeviation before
    double roughness_after_deg = 0;
    PassCounters counters() const;
};

/// Smooths vertex positions in place (connectivity untouched). Deterministic: Jacobi updates in
/// vertex order.
DenoiseReport denoise(Mesh& mesh, const DenoiseOptions& options = {});

/// Roughness figure: mean angle, in degrees, between the normals of the two faces of every interior
/// manifold edge (0 for a plane). Noise raises it; smoothing lowers it.
double meanDihedralDeviation(const Mesh& mesh);

} // namespace lodbake
