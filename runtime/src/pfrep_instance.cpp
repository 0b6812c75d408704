// Per-instance PFRep refinement in model space (see lodrt/pfrep_instance.h).

#include "lodrt/pfrep_instance.h"

#include <cmath>

namespace lodrt {

Result pfrepInstanceView(const Frustum& world, const float eye[3], const InstancePlacement& placement,
                         float pixels_per_unit, float pixel_tolerance, float hysteresis, PfrepView* out) {
    const float s = placement.scale;
    if (!out || !eye || !(s > 0) || !std::isfinite(s)) return Result::InvalidArgument;
    const float* t = placement.translation;
    PfrepView view;
    for (int k = 0; k < 3; ++k) view.eye[k] = (eye[k] - t[k]) / s;
    // n . (s p + t) + d >= 0  <=>  n . p + (n . t + d) / s >= 0: the normal stays unit length.
    for (int p = 0; p < 6; ++p) {
        const float* w = world.planes[p];
        view.planes[p][0] = w[0];
        view.planes[p][1] = w[1];
        view.planes[p][2] = w[2];
        view.planes[p][3] = (w[0] * t[0] + w[1] * t[1] + w[2] * t[2] + w[3]) / s;
    }
    view.pixels_per_unit_at_distance_one = pixels_per_unit;
    view.pixel_tolerance = pixel_tolerance;
    view.hysteresis = hysteresis;
    *out = view;
    return Result::Ok;
}

Result pfrepUpdateInstance(const PfrepModel& model, const PfrepView& view, uint8_t* mask, uint32_t* scratch,
                           size_t scratch_capacity, uint32_t* indices, size_t capacity, size_t* triangle_count,
                           size_t* changes) {
    size_t done = 0;
    Result r = pfrepRefine(model, view, mask, scratch, scratch_capacity, &done);
    if (changes) *changes = done;
    if (r != Result::Ok) return r;
    return pfrepExtractSelective(model, mask, indices, capacity, triangle_count);
}

} // namespace lodrt
