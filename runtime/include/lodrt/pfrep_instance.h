#pragma once
// PFRep selective refinement per instance (document 004): the only per-instance state is the
// |V|-bit mask of lodrt/pfrep.h. An instance is its model placed with a translation and a uniform
// scale; these helpers bring the world-space camera into the instance's model space and run one
// refinement step plus an extraction into caller-owned index memory.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/frustum.h"
#include "lodrt/pfrep.h"
#include "lodrt/result.h"

namespace lodrt {

/// Placement of an instance: world = model * scale + translation (scale > 0).
struct InstancePlacement {
    float translation[3] = {0, 0, 0};
    float scale = 1;
};

/// Model-space view of an instance: eye and frustum planes transformed, pixels_per_unit kept (a
/// uniform scale changes errors and distances alike). pixels_per_unit_at_distance_one is
/// viewport_height / (2 tan(fov / 2)) (pixelsPerUnitAtDistanceOne of lodrt/selection.h).
/// Returns InvalidArgument when scale is not a positive finite number.
LODRT_API Result pfrepInstanceView(const Frustum& world_frustum, const float world_eye[3],
                                   const InstancePlacement& placement, float pixels_per_unit_at_distance_one,
                                   float pixel_tolerance, float hysteresis, PfrepView* out);

/// Model-space view of an instance placed by an affine model -> world transform (column-major 4x4,
/// e.g. multiplyTransforms(instance, ModelInfo::world_transform)), which may rotate and scale
/// non-uniformly: the eye is brought back by the inverse, each frustum plane is pulled back and
/// renormalised (exact for model-space spheres), and pixels_per_unit is multiplied by
/// maxAxisScale / minAxisScale, so an error stretched by the largest axis and seen along the most
/// shrunk one is never under-estimated (conservative up to each vertex's own bounding radius).
/// Returns InvalidArgument for a singular, non-affine or non-finite transform.
LODRT_API Result pfrepInstanceViewTransform(const Frustum& world_frustum, const float world_eye[3],
                                            const float model_to_world[16], float pixels_per_unit_at_distance_one,
                                            float pixel_tolerance, float hysteresis, PfrepView* out);

/// One adaptation step of the instance's mask towards `view` (pfrepRefine), then its current mesh as
/// a triangle list into indices[0, 3 * capacity) (pfrepExtractSelective; capacity in triangles,
/// pfrepMaxTriangles(model) always suffices). scratch: pfrepScratchValues(model) values, shareable
/// between instances on one thread. `*changes` (may be null) receives the vertex operations done.
/// Returns pfrepRefine's and pfrepExtractSelective's results.
LODRT_API Result pfrepUpdateInstance(const PfrepModel& model, const PfrepView& view, uint8_t* mask, uint32_t* scratch,
                                     size_t scratch_capacity, uint32_t* indices, size_t capacity,
                                     size_t* triangle_count, size_t* changes);

} // namespace lodrt
