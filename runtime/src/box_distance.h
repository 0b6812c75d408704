#pragma once
// Eye-to-box distances shared by the PFRep culling tests (a whole instance in pfrep.cpp, a region
// block in pfrep_region.cpp).

#include <algorithm>
#include <cmath>

namespace lodrt::detail {

/// Squared distances from `eye` to the nearest and to the farthest point of the box [lo, hi].
struct EyeBoxDistance {
    float near2 = 0.0f;
    float far2 = 0.0f;
};

inline EyeBoxDistance eyeBoxDistance(const float eye[3], const float lo[3], const float hi[3]) {
    EyeBoxDistance d;
    for (int k = 0; k < 3; ++k) {
        const float e = eye[k];
        const float in = e < lo[k] ? lo[k] - e : (e > hi[k] ? e - hi[k] : 0.0f);
        const float out = std::max(std::fabs(e - lo[k]), std::fabs(e - hi[k]));
        d.near2 += in * in;
        d.far2 += out * out;
    }
    return d;
}

} // namespace lodrt::detail
