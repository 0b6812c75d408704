// The pack's LOD metrics (lodbake/pack/pack.h, LodMetrics) of a measured chain.
#include "lodbake/bake/bake.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lodbake/core/lod_policy.h"

namespace lodbake {

LodMetrics lodMetrics(const Mesh& full, const LodChain& chain, const ScreenParams& screen, double hysteresis) {
    LodMetrics m;
    m.bounding_radius = chain.bounding_radius;
    m.pixel_threshold = screen.pixel_threshold;
    m.viewport_height_px = screen.viewport_height_px;
    m.vertical_fov_rad = screen.vertical_fov_rad;
    LodMetricsLevel lod0;
    lod0.triangles = full.faceCount();
    lod0.vertices = full.vertexCount();
    lod0.screen_coverage = 1.0;
    m.levels.push_back(lod0);
    for (const LodLevel& level : chain.levels) {
        LodMetricsLevel l;
        l.triangles = level.mesh.faceCount();
        l.vertices = level.mesh.vertexCount();
        if (level.has_distance) {
            l.hausdorff_error = level.distance.hausdorff;
            l.mean_error = level.distance.mean;
            l.hausdorff_error_rel = level.distance.hausdorffRel();
            l.mean_error_rel = level.distance.meanRel();
        }
        // Errors are measured independently per level; a coarser level never claims to be better.
        const LodMetricsLevel& prev = m.levels.back();
        l.hausdorff_error = std::max(l.hausdorff_error, prev.hausdorff_error);
        l.mean_error = std::max(l.mean_error, prev.mean_error);
        l.hausdorff_error_rel = std::max(l.hausdorff_error_rel, prev.hausdorff_error_rel);
        l.mean_error_rel = std::max(l.mean_error_rel, prev.mean_error_rel);
        // The switch policy (core/lod_policy.h).
        l.switch_distance = levelSwitchDistance(l.hausdorff_error, prev.switch_distance, screen);
        l.screen_coverage = screenCoverage(chain.bounding_radius, l.switch_distance, screen);
        const HysteresisBand band = hysteresisBand(l.switch_distance, hysteresis);
        l.hysteresis_near = band.near;
        l.hysteresis_far = band.far;
        m.levels.push_back(l);
    }
    return m;
}

double lodErrorFloor(const Mesh& mesh) {
    const Aabb box = computeBounds(mesh);
    if (box.isEmpty()) return 0.0;
    double largest = 0.0;
    for (int k = 0; k < 3; ++k)
        largest = std::max({largest, std::fabs(double(box.min[k])), std::fabs(double(box.max[k]))});
    return std::ldexp(largest, -20);
}

std::vector<DroppedLodLevel> dropIndistinctLevels(LodMetrics& metrics, const Mesh& full, const LodChain& chain,
                                                  const ScreenParams& screen, double min_ratio) {
    std::vector<double> distances;
    for (const LodMetricsLevel& l : metrics.levels) distances.push_back(l.switch_distance);
    const double floor = switchDistance(lodErrorFloor(full), screen);
    const std::vector<bool> keep = distinctLevels(distances, min_ratio, floor);
    std::vector<DroppedLodLevel> dropped;
    std::vector<LodMetricsLevel> kept;
    size_t finer = 0; // the last kept level so far (LOD0 is always kept, and so is the last level)
    for (size_t l = 0; l < keep.size(); ++l) {
        if (keep[l]) {
            kept.push_back(metrics.levels[l]);
            finer = l;
            continue;
        }
        size_t coarser = l + 1;
        while (!keep[coarser]) ++coarser;
        DroppedLodLevel d;
        d.level = l;
        d.ratio = l - 1 < chain.levels.size() ? chain.levels[l - 1].target_ratio : 0.0;
        d.triangles = metrics.levels[l].triangles;
        d.hausdorff_error = metrics.levels[l].hausdorff_error;
        d.switch_distance = metrics.levels[l].switch_distance;
        d.finer_level = finer;
        d.coarser_level = coarser;
        d.coarser_switch_distance = metrics.levels[coarser].switch_distance;
        dropped.push_back(d);
    }
    metrics.levels = std::move(kept);
    return dropped;
}

std::string droppedLevelNote(const DroppedLodLevel& d, double min_ratio) {
    char text[400];
    std::snprintf(text, sizeof text,
                  "lod chain: level %zu (ratio %g, %llu triangles, Hausdorff %.4g) dropped: it would be taken at "
                  "%.4g and level %zu at %.4g, not more than %g times farther (lod_min_switch_ratio); level %zu "
                  "serves until %.4g",
                  d.level, d.ratio, static_cast<unsigned long long>(d.triangles), d.hausdorff_error, d.switch_distance,
                  d.coarser_level, d.coarser_switch_distance, min_ratio, d.finer_level, d.coarser_switch_distance);
    return text;
}

} // namespace lodbake
