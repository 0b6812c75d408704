// LOD metrics in the pack: the levels' measured errors and switch distances as the
// LODBAKE_lod_metrics node extension and the MSFT_screencoverage array (MSFT_lod).
#include "lodbake/pack/pack.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "lodrt/format.h"

namespace lodbake {

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
    JsonNode levels = JsonNode::array();
    for (const LodMetricsLevel& l : m.levels) {
        JsonNode level = JsonNode::object();
        level.set("hausdorffError", up(l.hausdorff_error));
        level.set("hausdorffErrorRelative", up(l.hausdorff_error_rel));
        level.set("hysteresisBand", JsonNode::array().push(down(l.hysteresis_near)).push(up(l.hysteresis_far)));
        level.set("meanError", up(l.mean_error));
        level.set("meanErrorRelative", up(l.mean_error_rel));
        level.set("screenCoverage", down(l.screen_coverage));
        level.set("switchDistance", up(l.switch_distance));
        level.set("triangles", l.triangles);
        level.set("vertices", l.vertices);
        levels.push(std::move(level));
    }
    PackExtension e;
    e.name = lodrt::format::kExtLodMetrics;
    e.json = JsonNode::object();
    e.json.set("boundingRadius", up(m.bounding_radius));
    if (m.input_triangles > 0) e.json.set(lodrt::format::kLodMetricsInputTriangles, m.input_triangles);
    e.json.set("levels", std::move(levels));
    e.json.set("pixelThreshold", m.pixel_threshold);
    e.json.set("verticalFov", m.vertical_fov_rad);
    e.json.set("viewportHeight", m.viewport_height_px);
    return e;
}

std::vector<double> msftScreenCoverage(const LodMetrics& m) {
    std::vector<double> out(m.levels.size(), 0.0);
    for (size_t i = 0; i + 1 < m.levels.size(); ++i) out[i] = down(m.levels[i + 1].screen_coverage);
    for (size_t i = 1; i < out.size(); ++i) out[i] = std::min(out[i], out[i - 1]);
    return out;
}

} // namespace lodbake
