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

Result pfrepInstanceViewTransform(const Frustum& world, const float eye[3], const float m[16], float pixels_per_unit,
                                  float pixel_tolerance, float hysteresis, PfrepView* out) {
    if (!out || !eye || !m) return Result::InvalidArgument;
    for (int k = 0; k < 16; ++k)
        if (!std::isfinite(m[k])) return Result::InvalidArgument;
    if (m[3] != 0 || m[7] != 0 || m[11] != 0 || m[15] != 1) return Result::InvalidArgument;
    // Inverse of the upper 3x3 (column-major: a(r, c) = m[c * 4 + r]) by cofactors, in double.
    auto a = [m](int r, int c) { return double(m[c * 4 + r]); };
    double inv[3][3];
    inv[0][0] = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
    inv[0][1] = a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2);
    inv[0][2] = a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1);
    inv[1][0] = a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2);
    inv[1][1] = a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0);
    inv[1][2] = a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2);
    inv[2][0] = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
    inv[2][1] = a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1);
    inv[2][2] = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
    const double det = a(0, 0) * inv[0][0] + a(0, 1) * inv[1][0] + a(0, 2) * inv[2][0];
    if (!(std::fabs(det) > 1e-30) || !std::isfinite(det)) return Result::InvalidArgument;
    // Axis scales: the largest and smallest stretch of the 3x3 are bounded by its column norms and by
    // 1 / (row norms of the inverse); both are exact for rotation times axis-aligned scale.
    double s_max = 0, s_min = HUGE_VAL;
    for (int c = 0; c < 3; ++c) {
        const double len = std::sqrt(a(0, c) * a(0, c) + a(1, c) * a(1, c) + a(2, c) * a(2, c));
        s_max = std::fmax(s_max, len);
    }
    for (int r = 0; r < 3; ++r) {
        const double len = std::sqrt(inv[r][0] * inv[r][0] + inv[r][1] * inv[r][1] + inv[r][2] * inv[r][2]) / std::fabs(det);
        s_min = std::fmin(s_min, len > 0 ? 1.0 / len : HUGE_VAL);
    }
    if (!(s_min > 0) || !std::isfinite(s_max)) return Result::InvalidArgument;
    PfrepView view;
    const double d[3] = {double(eye[0]) - m[12], double(eye[1]) - m[13], double(eye[2]) - m[14]};
    for (int r = 0; r < 3; ++r) view.eye[r] = float((inv[r][0] * d[0] + inv[r][1] * d[1] + inv[r][2] * d[2]) / det);
    // n . (A y + t) + w >= 0  <=>  (A^T n) . y + (n . t + w) >= 0, then renormalised.
    for (int p = 0; p < 6; ++p) {
        const float* w = world.planes[p];
        double n[3];
        for (int c = 0; c < 3; ++c) n[c] = w[0] * a(0, c) + w[1] * a(1, c) + w[2] * a(2, c);
        const double off = double(w[0]) * m[12] + double(w[1]) * m[13] + double(w[2]) * m[14] + w[3];
        const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(len > 0)) return Result::InvalidArgument;
        for (int c = 0; c < 3; ++c) view.planes[p][c] = float(n[c] / len);
        view.planes[p][3] = float(off / len);
    }
    view.pixels_per_unit_at_distance_one = float(double(pixels_per_unit) * s_max / s_min);
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
