#pragma once
// What the out-of-core level error (ooc/level_error.cpp) shares with measureSurfaceDistance
// (mesh_distance.cpp): the sampling streams, the surface check, the approximation side's points in
// the order they are measured, and how a side's distances are combined, so that a measurement split
// across partitions draws the same points and combines them the same way.

#include <cstddef>
#include <cstdint>

#include "core/large_array.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/simplify/mesh_distance.h"

namespace lodbake::detail {

constexpr size_t kDistanceChunkSize = 2048; // points per task; fixed so the reduction order never changes
constexpr uint64_t kReferenceStream = 0x5265664d65736821ull; // decorrelates the two sides' samples
constexpr uint64_t kApproxStream = 0x417070726f782121ull;

/// Area of triangle abc as the sampling's area CDF computes it.
inline double samplingTriangleArea(const Vec3f& a, const Vec3f& b, const Vec3f& c) {
    const Vec3d da = toDouble(a), db = toDouble(b), dc = toDouble(c);
    return 0.5 * length(cross(db - da, dc - da));
}

/// The checks measureSurfaceDistance makes of its options and of each mesh (`role` names it).
Status checkDistanceOptions(const DistanceOptions& options);
Status checkDistanceSurface(const Mesh& mesh, const char* role);

/// The approximation side's points, in the order measureSurfaceDistance measures them (Morton order).
Result<LargeArray<Vec3d>> approximationSidePoints(const Mesh& approx, const DistanceOptions& options);

/// One side's statistics from its points' distances given in measurement order, combined exactly as
/// the measurement combines them (chunks of kDistanceChunkSize, then the chunks in order).
OneSidedDistance combineSideDistances(const double* distances, size_t count);

/// The two-sided result from its two sides, as measureSurfaceDistance computes it.
DistanceResult twoSidedDistance(const OneSidedDistance& ref_to_approx, const OneSidedDistance& approx_to_ref,
                                double diagonal);

} // namespace lodbake::detail
