#pragma once
// The LOD switch policy: when a level of a chain replaces the finer one, in one place. A level whose
// (measured Hausdorff) error is e is acceptable from the distance at which e projects to the pixel
// threshold; around that switch distance a hysteresis band keeps the selection from flickering; the
// screen coverage at the switch distance is what MSFT_screencoverage and the texture sizes read.
//
// The simplifier (updateSwitchDistances, lod_chain.h) and the bake's level metrics (lodMetrics,
// bake.h) derive every level's numbers here. lodrt computes the same formulas at run time, in
// float, under the same names (runtime/src/selection.cpp: switchDistance, hysteresisFar);
// LodPolicyAgreementTest holds the two to the same numbers. Texture sizing from the coverage is the
// bake's (textureLevels, bake.cpp).

namespace lodbake {

/// The screen a chain is baked for.
struct ScreenParams {
    double pixel_threshold = 1.0; // largest tolerated screen-space error, pixels
    double viewport_height_px = 1080.0;
    double vertical_fov_rad = 1.0471975511965976; // 60 degrees
};

/// The distance from which a level of `error` (object units) is acceptable: where the error
/// projects to `pixel_threshold` pixels, d = e · H / (2 · p · tan(fov / 2)) with H the viewport height.
/// 0 for e ≤ 0; +inf when p ≤ 0 or the field of view is invalid.
double switchDistance(double error, const ScreenParams& screen);

/// A level's switch distance down a chain: switchDistance(error), but never before the finer level's
/// (`finer`), so that selection by distance is monotone even where independently measured errors
/// are not.
double levelSwitchDistance(double error, double finer, const ScreenParams& screen);

/// Fraction of the viewport height covered by a sphere of `radius` at `distance` (the projected
/// diameter, 2 r / (2 d tan(fov / 2))), capped at 1 (so 1 when distance ≤ 0).
double screenCoverage(double radius, double distance, const ScreenParams& screen);

/// The hysteresis band around a switch distance d: the finer level comes back below d (1 - h), this
/// level is taken beyond d (1 + h). `hysteresis` h is a fraction of d (BakeSettings::hysteresis).
struct HysteresisBand {
    double near = 0;
    double far = 0;
};
HysteresisBand hysteresisBand(double switch_distance, double hysteresis);

} // namespace lodbake
