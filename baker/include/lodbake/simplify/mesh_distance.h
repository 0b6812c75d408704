#pragma once
// Two-sided surface distance between a reference mesh and an approximation, the error every LOD
// level carries. Metro-style: area-uniform (stratified) samples on each surface plus its vertices, exact
// point-to-triangle distance to the other surface through a BVH. Agrees with
// ../shared/eval/meshdist.py (same definitions) within sampling noise.

#include <cstdint>
#include <vector>

#include "lodbake/core/bvh.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct DistanceOptions {
    uint32_t sample_count = 200000; // area-uniform samples per side (vertices are added on top)
    uint64_t seed = 1;              // sampling is deterministic for a seed, whatever the thread count
    bool include_vertices = true;   // also measure from every referenced vertex, so spikes are not missed
};

/// Distances in object units and relative to the reference's bounding-box diagonal.
struct DistanceResult {
    double hausdorff = 0.0; // max of both one-sided maxima
    double mean = 0.0;      // (mean(ref→approx) + mean(approx→ref)) / 2
    double rms = 0.0;       // sqrt((ms(ref→approx) + ms(approx→ref)) / 2)
    double max_ref_to_approx = 0.0;
    double max_approx_to_ref = 0.0;
    double diagonal = 0.0; // reference bounding-box diagonal (referenced vertices)
    double hausdorffRel() const { return diagonal > 0 ? hausdorff / diagonal : 0.0; }
    double meanRel() const { return diagonal > 0 ? mean / diagonal : 0.0; }
    double rmsRel() const { return diagonal > 0 ? rms / diagonal : 0.0; }
};

/// Measures the two-sided distance. Fails (InvalidInput) if either mesh has no triangle of
/// non-zero area, has an index out of range or a referenced vertex with a NaN/Inf coordinate, or if
/// options ask for no points at all (sample_count 0 and include_vertices false).
/// The result is bit-identical for any thread count.
Result<DistanceResult> measureSurfaceDistance(const Mesh& reference, const Mesh& approx,
                                              const DistanceOptions& options = {});

/// A reference surface checked and indexed once, for measuring several approximations against it
/// (every level of an LOD chain) without rebuilding its BVH each time. Keeps a pointer to the mesh:
/// `reference` must outlive this object and stay unchanged.
class DistanceReference {
public:
    /// Fails as measureSurfaceDistance does for a bad reference.
    static Result<DistanceReference> prepare(const Mesh& reference);

    const Mesh& mesh() const { return *mesh_; }
    const TriangleBvh& bvh() const { return bvh_; }

private:
    const Mesh* mesh_ = nullptr;
    TriangleBvh bvh_;
};

/// Same as measureSurfaceDistance(reference.mesh(), approx, options), with the same result.
Result<DistanceResult> measureSurfaceDistance(const DistanceReference& reference, const Mesh& approx,
                                              const DistanceOptions& options = {});

/// Measures every approximation against one reference: results[i] is exactly (bit for bit) what
/// measureSurfaceDistance(reference, *approximations[i], options) returns, including its error. The
/// reference side's points are drawn once, and the approximations are measured one after the other,
/// each in parallel inside (the result does not depend on the thread count). Pointers must not be null.
std::vector<Result<DistanceResult>> measureSurfaceDistances(const DistanceReference& reference,
                                                            const std::vector<const Mesh*>& approximations,
                                                            const DistanceOptions& options = {});

} // namespace lodbake
