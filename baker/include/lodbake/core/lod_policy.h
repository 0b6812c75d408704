#pragma once
// The LOD switch policy: when a level of a chain replaces the finer one, in one place. A level whose
// (measured Hausdorff) error is e is acceptable from the distance at which e projects to the pixel
// threshold; around that switch distance a hysteresis band keeps the selection from flickering; the
// screen coverage at the switch distance is what MSFT_screencoverage and the texture sizes read. A level
// that would be drawn over almost no distances before the next one takes over is not worth its bytes:
// distinctLevels says which levels of a chain to keep.
//
// The simplifier (updateSwitchDistances, lod_chain.h) and the bake's level metrics (lodMetrics,
// bake.h) derive every level's numbers here. lodrt computes the same formulas at run time, in
// float, under the same names (runtime/src/selection.cpp: switchDistance, hysteresisFar);
// LodPolicyAgreementTest holds the two to the same numbers. Texture sizing from the coverage is the
// bake's (textureLevels, bake.cpp).

#include <vector>

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

/// Whether a level acceptable from distance `finer` on is worth drawing before the next coarser level,
/// acceptable from `coarser`: selection by distance draws it over [finer, coarser) only, and it counts
/// only when coarser > min_ratio · max(finer, floor) (min_ratio: BakeSettings::lod_min_switch_ratio;
/// floor: the switch distance of an error that is rounding, not geometry, so that two lossless levels
/// measuring different rounding noise are not told apart). With min_ratio >= 1, two levels that
/// switch at the same distance (0 included) are never both distinct; min_ratio 0 makes every level
/// distinct.
bool isDistinctSwitch(double finer, double coarser, double min_ratio, double floor = 0.0);

/// Which levels of a chain to keep, given their switch distances (`switch_distances[0]` is LOD0's, 0;
/// non-decreasing as levelSwitchDistance makes them): LOD0 (the full-detail mesh every viewer shows)
/// and the coarsest level always; walking from the coarsest towards LOD0, a level is kept when the
/// next kept coarser level switches distinctly farther (isDistinctSwitch with `min_ratio`, `floor`).
/// Of two levels that switch together the coarser one stays: it is as acceptable at that distance,
/// with fewer triangles, so every distance still draws the level it drew before or a finer one.
std::vector<bool> distinctLevels(const std::vector<double>& switch_distances, double min_ratio, double floor = 0.0);

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
