// simplify(): one run of the edge-collapse engine (edge_collapse.cpp) towards a single target.
#include "lodbake/simplify/simplify.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "simplify/edge_collapse.h"
#include "simplify/level_refine.h"

namespace lodbake {

namespace {

std::string formatError(double e) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", e);
    return buf;
}

} // namespace

Result<SimplifyOutput> simplify(const Mesh& mesh, const SimplifyOptions& options, Diagnostics& diagnostics) {
    if (!(options.target_ratio >= 0.0f && options.target_ratio <= 1.0f))
        return invalidInput("simplify options: target_ratio " + formatError(options.target_ratio) +
                            ": expected a value in [0, 1]");
    if (!(options.max_error >= 0.0)) return invalidInput("simplify options: max_error: expected a non-negative number");
    detail::EdgeCollapser engine;
    LODBAKE_RETURN_IF_ERROR(engine.init(mesh, options, diagnostics));
    // One target, the serial collapse order: no partitioned rounds (docs/simplify.md). They are for the
    // bake's chain, which runs alone on its stage; they change the Hausdorff error of a single
    // target's result (either way, depending on the target), so this call keeps the serial order's.
    engine.setRoundMinFaces(SIZE_MAX);
    const size_t faces = engine.initialFaceCount();
    size_t target = 0;
    if (options.target_triangles > 0)
        target = options.target_triangles;
    else if (options.target_ratio > 0.0f)
        target = size_t(std::ceil(double(options.target_ratio) * double(faces)));
    const bool has_error_target = std::isfinite(options.max_error);
    const bool reached_faces = engine.run(target, options.max_error, nullptr);
    SimplifyOutput out;
    out.input_triangles = faces;
    out.collapses = engine.collapseCount();
    out.max_collapse_error = engine.maxCollapseError();
    // With only an error target, running out of collapses under the limit is the goal itself.
    out.reached_target = reached_faces || target == 0;
    if (!reached_faces && target > 0) {
        diagnostics.note("simplify: stopped at " + std::to_string(engine.faceCount()) + " triangles (target " +
                         std::to_string(target) + "): " +
                         (has_error_target ? "no valid collapse left within max_error " + formatError(options.max_error)
                                           : std::string("no valid collapse left")));
    }
    if (engine.removalCount() > 0)
        diagnostics.note("simplify: " + std::to_string(engine.removalCount()) + " covered components (" +
                         std::to_string(engine.removedFaceCount()) + " faces) removed (remove_covered_components)");
    out.mesh = engine.extract();
    if (engine.refinesSnapshot()) detail::refineLevelPositions(mesh, out.mesh, options.max_normal_change_deg);
    return out;
}

} // namespace lodbake
