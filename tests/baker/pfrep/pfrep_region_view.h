#pragma once
// A perspective camera as a PfrepView (inward, normalized frustum planes), for the region-block
// tests and benchmark.
#include <cmath>

#include "lodrt/pfrep.h"

namespace lodbake_test {

inline lodrt::PfrepView cameraView(const float eye[3], const float target[3], float fov_y, float aspect, float near,
                                   float far, float viewport_height, float pixel_tolerance) {
    float f[3] = {target[0] - eye[0], target[1] - eye[1], target[2] - eye[2]};
    auto normalize = [](float v[3]) {
        const float l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        for (int k = 0; k < 3; ++k) v[k] = l > 0 ? v[k] / l : 0.0f;
    };
    normalize(f);
    float up[3] = {0, 1, 0};
    if (std::fabs(f[1]) > 0.99f) {
        up[1] = 0;
        up[2] = 1;
    }
    float r[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]};
    normalize(r);
    const float u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]};
    const float ty = std::tan(fov_y * 0.5f), tx = ty * aspect;
    lodrt::PfrepView view;
    for (int k = 0; k < 3; ++k) view.eye[k] = eye[k];
    float n[6][3];
    for (int k = 0; k < 3; ++k) {
        n[0][k] = f[k];
        n[1][k] = -f[k];
        n[2][k] = r[k] + tx * f[k];
        n[3][k] = -r[k] + tx * f[k];
        n[4][k] = u[k] + ty * f[k];
        n[5][k] = -u[k] + ty * f[k];
    }
    for (int p = 0; p < 6; ++p) {
        normalize(n[p]);
        for (int k = 0; k < 3; ++k) view.planes[p][k] = n[p][k];
        view.planes[p][3] = -(n[p][0] * eye[0] + n[p][1] * eye[1] + n[p][2] * eye[2]);
    }
    view.planes[0][3] -= near;
    view.planes[1][3] += far;
    view.pixels_per_unit_at_distance_one = viewport_height / (2.0f * ty);
    view.pixel_tolerance = pixel_tolerance;
    return view;
}

} // namespace lodbake_test
