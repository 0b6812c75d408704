// The LOD switch policy (lodbake/core/lod_policy.h); lodrt's selection (runtime/src/selection.cpp)
// computes the same formulas in float.
#include "lodbake/core/lod_policy.h"

#include <algorithm>
#include <cmath>

namespace lodbake {

double switchDistance(double error, const ScreenParams& screen) {
    if (!(error > 0.0)) return 0.0;
    const double t = std::tan(screen.vertical_fov_rad * 0.5);
    if (!(screen.pixel_threshold > 0.0) || !(t > 0.0) || !std::isfinite(t)) return HUGE_VAL;
    return error * screen.viewport_height_px / (2.0 * screen.pixel_threshold * t);
}

double levelSwitchDistance(double error, double finer, const ScreenParams& screen) {
    return std::max(finer, switchDistance(error, screen));
}

bool isDistinctSwitch(double finer, double coarser, double min_ratio, double floor) {
    return !(min_ratio > 0.0) || coarser > min_ratio * std::max(finer, floor);
}

std::vector<bool> distinctLevels(const std::vector<double>& switch_distances, double min_ratio, double floor) {
    const size_t n = switch_distances.size();
    std::vector<bool> keep(n, true);
    if (n < 3) return keep;
    double next = switch_distances[n - 1]; // the next kept coarser level's
    for (size_t i = n - 2; i >= 1; --i) {
        keep[i] = isDistinctSwitch(switch_distances[i], next, min_ratio, floor);
        if (keep[i]) next = switch_distances[i];
    }
    return keep;
}

double screenCoverage(double radius, double distance, const ScreenParams& screen) {
    const double t = std::tan(screen.vertical_fov_rad * 0.5);
    if (!(distance > 0.0) || !(t > 0.0)) return 1.0;
    return std::min(1.0, radius / (distance * t));
}

HysteresisBand hysteresisBand(double switch_distance, double hysteresis) {
    return {switch_distance * (1.0 - hysteresis), switch_distance * (1.0 + hysteresis)};
}

} // namespace lodbake
