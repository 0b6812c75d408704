#pragma once
// Quadric-error-metric edge-collapse simplification (Garland–Heckbert 1997, area-weighted, with
// boundary constraint planes and attribute quadrics).
//
// Preconditions: `mesh` passes checkMeshConsistency and has finite positions (otherwise
// InvalidInput naming the first bad vertex). Vertices with bit-identical positions are treated as
// one surface point: if their attributes also match they are merged, otherwise they form an
// attribute seam, which is only ever collapsed along itself so both sides stay consistent.
//
// Guarantees on the output: no new non-manifold edge or vertex, no change of genus or of the
// number of boundary loops (Dey et al. link condition), boundary, seam and sub-mesh border
// vertices move only along their border, no face normal rotates by more than
// `max_normal_change_deg` in one collapse, and non-manifold spots of the input are left untouched.
// Sub-meshes keep their order, materials and textures are copied unchanged. Unreferenced input
// vertices are dropped. Output is deterministic: identical input and options give identical bytes.

#include <cstdint>
#include <limits>
#include <string>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

/// Relative importance of attribute error against geometric error. An attribute difference of 1
/// (normal components, UV units, colour channels in [0,1]) weighs as much as a geometric error of
/// `weight` × bounding-box diagonal. Normals weigh nothing by default: the bake derives them from the
/// geometry (repair), so their error repeats the geometric one, and near creases, where smooth
/// normals swing, it outweighs it and leads the simplifier away from the surface
/// (docs/benchmarks.md, "Textured assets against gltfpack"). They are still optimised at every
/// collapse, and normal seams are still seams.
struct AttributeWeights {
    float normal = 0.0f;
    float uv = 0.5f;
    float color = 0.25f;
};

/// Where the surviving point of a collapse goes.
enum class CollapsePlacement : uint8_t {
    Optimal,      // full-edge collapse: the kept point moves to the quadric optimum (or onto its border)
    KeepEndpoint, // half-edge collapse: the kept point stays in place (one vertex removed, the
                  // rest untouched: the primitive PFRep is built from, docs/format/pfrep.md)
};

/// What the simplifier may do. The ratio, triangle and error targets combine: simplification stops
/// at the first one reached.
struct SimplifyOptions {
    float target_ratio = 0.5f;     // fraction of input triangles to keep (0: no ratio target)
    uint32_t target_triangles = 0; // absolute triangle count to reach; overrides target_ratio when > 0
    double max_error =
        std::numeric_limits<double>::infinity(); // object units; a collapse whose
                                                 // estimated error (quadric RMS distance) exceeds it is not done
    float border_weight = 10.0f;                 // weight of boundary/seam constraint planes (× edge length²)
    float max_normal_change_deg = 75.0f;         // largest rotation of any face normal in one collapse
    float min_triangle_quality = 0.05f;          // reject collapses creating triangles below this quality
                                        // (4√3·area / Σ edge², 1 = equilateral) unless no worse than before
    float cost_area_exponent = 0.5f;  // queue order: Q(p) / area^k over the merged quadric's face area.
                                      // 0 = Garland–Heckbert's raw area-weighted cost (lowest mean error,
                                      // but small thin features go early), 1 = mean squared distance
                                      // (lowest Hausdorff); 0.5 balances both (docs/simplify.md)
    float tip_distance_weight = 1.0f; // when a collapse is first popped, the squared point distances of
                                      // its endpoints to the new fan and of the new position to the old
                                      // fans, beyond the quadric estimate, are added to its key
                                      // (× sqrt(area)) and it competes again: keeps sharp tips and
                                      // off-surface placements from looking cheap (0: off)
    bool lock_border = false;         // keep open-boundary vertices exactly in place
    bool refine_late_levels = true;   // a result of at most 2.5 % of the input's faces gets its interior vertices
                                      // moved towards the input points nearest to their faces (a copy:
                                      // later levels of a chain are unaffected; Optimal placement only)
    bool remove_covered_components = false; // topology change, off by default: a whole connected component
                                             // whose points all lie within the error already accepted
                                             // (kCoveredComponentFactor × the largest collapse error so far)
                                             // of the REST of the surface is removed, its faces freed for
                                             // the rest (overlapping scans, docs/simplify.md). Only with
                                             // Optimal placement (PFRep records are vertex removals)
    CollapsePlacement placement = CollapsePlacement::Optimal;
    AttributeWeights attribute_weights;
};

struct SimplifyOutput {
    Mesh mesh;
    size_t input_triangles = 0;    // after dropping faces degenerate by position
    size_t collapses = 0;          // edge collapses performed
    double max_collapse_error = 0; // largest estimated error (object units) of a collapse performed
    bool reached_target = false;   // false: stopped at the best valid mesh (see Diagnostics)
};

/// Simplifies `mesh`. When the target cannot be reached (every remaining collapse is invalid or
/// above max_error) the best valid mesh is returned with reached_target = false and a note in
/// `diagnostics`. Fails only on invalid input.
Result<SimplifyOutput> simplify(const Mesh& mesh, const SimplifyOptions& options, Diagnostics& diagnostics);

} // namespace lodbake
