// LOD metrics for the pack: the chain's measured errors and switch distances as the
// LODBAKE_lod_metrics node extension and the MSFT_screencoverage array (MSFT_lod).
#include "lodbake/pack/pack.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "lodbake/core/json_writer.h"

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
        l.switch_distance = std::max(switchDistance(l.hausdorff_error, screen), prev.switch_distance);
        l.screen_coverage = screenCoverage(chain.bounding_radius, l.switch_distance, screen);
        l.hysteresis_near = l.switch_distance * (1.0 - hysteresis);
        l.hysteresis_far = l.switch_distance * (1.0 + hysteresis);
        m.levels.push_back(l);
    }
    return m;
}

namespace {

// `x` to 7 significant digits (float precision, far finer than the sampling noise of a measured
// error), rounded up or down so that a written bound never claims more than was measured: errors,
// distances and far band edges round up, coverages and near band edges down. Monotone, so the
// orderings the metrics keep (errors non-decreasing, near <= distance <= far) survive. Cuts each
// number from up to 17 digits to 7 in the pack's JSON.
double roundDigits(double x, bool up) {
    if (x == 0.0 || !std::isfinite(x)) return x;
    char text[40];
    std::snprintf(text, sizeof(text), "%.6e", x);
    double v = std::strtod(text, nullptr);
    if (up ? v >= x : v <= x) return v;
    const char* e = std::strchr(text, 'e');
    const double unit = std::pow(10.0, double(std::atoi(e + 1)) - 6.0); // one unit in the 7th digit
    std::snprintf(text, sizeof(text), "%.6e", up ? v + unit : v - unit);
    v = std::strtod(text, nullptr);
    return (up ? v >= x : v <= x) ? v : x; // x itself when the decimal cannot bound it (never in practice)
}

double up(double x) {
    return roundDigits(x, true);
}
double down(double x) {
    return roundDigits(x, false);
}

} // namespace

PackExtension lodMetricsExtension(const LodMetrics& m) {
    JsonWriter j(0);
    j.beginObject();
    j.field("boundingRadius", up(m.bounding_radius));
    j.key("levels").beginArray();
    for (const LodMetricsLevel& l : m.levels) {
        j.beginObject();
        j.field("hausdorffError", up(l.hausdorff_error));
        j.field("hausdorffErrorRelative", up(l.hausdorff_error_rel));
        j.key("hysteresisBand").beginArray().value(down(l.hysteresis_near)).value(up(l.hysteresis_far)).endArray();
        j.field("meanError", up(l.mean_error));
        j.field("meanErrorRelative", up(l.mean_error_rel));
        j.field("screenCoverage", down(l.screen_coverage));
        j.field("switchDistance", up(l.switch_distance));
        j.field("triangles", l.triangles);
        j.field("vertices", l.vertices);
        j.endObject();
    }
    j.endArray();
    j.field("pixelThreshold", m.pixel_threshold);
    j.field("verticalFov", m.vertical_fov_rad);
    j.field("viewportHeight", m.viewport_height_px);
    j.endObject();
    PackExtension e;
    e.name = "LODBAKE_lod_metrics";
    e.json = j.str();
    return e;
}

std::vector<double> msftScreenCoverage(const LodMetrics& m) {
    std::vector<double> out(m.levels.size(), 0.0);
    for (size_t i = 0; i + 1 < m.levels.size(); ++i) out[i] = down(m.levels[i + 1].screen_coverage);
    for (size_t i = 1; i < out.size(); ++i) out[i] = std::min(out[i], out[i - 1]);
    return out;
}

} // namespace lodbake
