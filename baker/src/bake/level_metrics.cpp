// The pack's LOD metrics (lodbake/pack/pack.h, LodMetrics) of a measured chain.
#include "lodbake/bake/bake.h"

#include <algorithm>

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

} // namespace lodbake
