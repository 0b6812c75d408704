// Discrete LOD chains from one incremental edge-collapse pass (Gasparello 2007 §1.4 and §4.3.5:
// discrete levels selected by distance), with per-level measured error and switch distances.
#include "lodbake/simplify/lod_chain.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "simplify/edge_collapse.h"
#include "simplify/level_refine.h"

namespace lodbake {

namespace {

std::string ratioText(double ratio) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%g", ratio);
    return buf;
}

// Why the engine stops above a target: every edge left is refused by a validity rule
// (docs/simplify.md, "Validity of a collapse"); the chain has no error budget of its own.
constexpr const char* kStallReason = "no valid collapse left";

} // namespace

Result<LodChain> buildLodChain(const Mesh& mesh, const LodChainOptions& options, Diagnostics& diagnostics) {
    std::vector<double> ratios = options.ratios;
    for (double r : ratios) {
        if (!(r > 0.0 && r <= 1.0)) {
            char buf[64];
            std::snprintf(buf, sizeof buf, "%g", r);
            return invalidInput(std::string("lod chain options: ratio ") + buf + ": expected a value in (0, 1]");
        }
    }
    if (ratios.empty()) return invalidInput("lod chain options: ratios: expected at least one level");
    std::sort(ratios.begin(), ratios.end(), [](double a, double b) { return a > b; });
    ratios.erase(std::unique(ratios.begin(), ratios.end()), ratios.end());

    LodChain chain;
    const Aabb box = computeBounds(mesh);
    chain.bounding_radius = box.isEmpty() ? 0.0 : box.diagonal() * 0.5;
    {
        // The engine's working arrays (several times the input's size) are released at the end of this
        // block, before the error measurement builds its BVHs: peak memory is the larger of the two, not
        // their sum.
        detail::EdgeCollapser engine;
        LODBAKE_RETURN_IF_ERROR(engine.init(mesh, options.simplify, diagnostics));
        CollapseSequence* sequence = options.record_collapses ? &chain.sequence : nullptr;
        const size_t faces = engine.initialFaceCount();
        if (sequence) {
            engine.describe(*sequence);
            // Each collapse removes two faces, or one on a border: reserving for one (pages never
            // written are never resident) saves growing the record by doubling, which copies it.
            const size_t last_target = size_t(std::ceil(ratios.back() * double(faces)));
            const size_t collapses = faces > last_target ? faces - last_target : 0;
            sequence->records.reserve(collapses);
            if (!sequence->point_triangles.empty()) {
                // A half-edge collapse on a scan re-creates about three triangles; room for four per
                // collapse saves growing the list by doubling.
                sequence->created_end.reserve(collapses);
                sequence->created_triangles.reserve(collapses * 4 * 3);
            }
            if (sequence->attribute_stride > 0) {
                sequence->wedge_updates.reserve(collapses);
                sequence->wedge_attributes.reserve(collapses * sequence->attribute_stride);
            }
        }
        const bool record_removals = options.record_removals && !options.simplify.remove_covered_components;
        if (record_removals) {
            // Every collapse removes at least one face.
            chain.removals.reserve(faces);
            engine.setRemovalLog(&chain.removals);
        }
        bool stuck = false;
        for (double ratio : ratios) {
            const size_t target = size_t(std::ceil(ratio * double(faces)));
            const std::string name = "lod chain: level ratio " + ratioText(ratio);
            if (stuck) {
                // Its mesh would be the previous level's again: a chain never holds two equal levels.
                diagnostics.note(name + " omitted (target " + std::to_string(target) + "): the chain stopped at " +
                                 std::to_string(engine.faceCount()) + " triangles");
                continue;
            }
            LodLevel level;
            level.target_ratio = ratio;
            level.reached_target = engine.run(target, HUGE_VAL, sequence);
            if (!chain.levels.empty() && engine.faceCount() == chain.levels.back().mesh.faceCount()) {
                stuck = !level.reached_target;
                diagnostics.note(name + " omitted (target " + std::to_string(target) + "): " +
                                 (stuck ? std::string(kStallReason) + " at " : "the same as the previous level, ") +
                                 std::to_string(engine.faceCount()) + " triangles");
                continue;
            }
            if (!level.reached_target) {
                stuck = true;
                diagnostics.note(name + " stopped at " + std::to_string(engine.faceCount()) + " triangles (target " +
                                 std::to_string(target) + "): " + std::string(kStallReason));
            }
            level.collapse_count = engine.collapseCount();
            level.removal_count = engine.removalCount();
            level.quadric_error = engine.maxCollapseError();
            level.mesh = engine.extract();
            level.is_refined = engine.refinesSnapshot(); // refined below, once the engine is gone
            chain.levels.push_back(std::move(level));
        }
        if (engine.droppedChartCount() > 0)
            diagnostics.note("lod chain: " + std::to_string(engine.droppedChartCount()) + " of " +
                             std::to_string(engine.chartCount()) + " UV charts collapsed away by the last level");
        if (record_removals) {
            // The vertex-removal reading goes on to the end of valid collapses (PFRep wants every level
            // there is); nothing is snapshotted any more.
            if (!stuck) engine.run(0, HUGE_VAL, sequence);
            chain.removals_complete = true;
            engine.setRemovalLog(nullptr);
        }
        if (engine.removalCount() > 0)
            diagnostics.note("lod chain: " + std::to_string(engine.removalCount()) + " covered components (" +
                             std::to_string(engine.removedFaceCount()) +
                             " faces) removed (remove_covered_components)");
    }
    // Late levels: vertex refinement of the snapshots (docs/simplify.md, "Level refinement"), after the
    // engine's arrays are released so that it does not add to the chain's peak memory.
    for (LodLevel& level : chain.levels)
        if (level.is_refined) detail::refineLevelPositions(mesh, level.mesh, options.simplify.max_normal_change_deg);
    if (options.measure_error)
        measureLodChain(mesh, chain, options, diagnostics);
    else
        updateSwitchDistances(chain, options.screen);
    return chain;
}

void measureLodChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options, Diagnostics& diagnostics) {
    measureLodChain(mesh, chain, options, {}, diagnostics);
}

void measureLodChain(const Mesh& mesh, LodChain& chain, const LodChainOptions& options,
                     const std::vector<const OneSidedDistance*>& reference_sides, Diagnostics& diagnostics) {
    // The input's index, its points and the first level's are built side by side; then each level is
    // measured (in parallel inside) while the next one's index and points are built, so at most two
    // levels' indexes and points exist at once (mesh_distance.h).
    std::vector<const Mesh*> meshes;
    for (const LodLevel& level : chain.levels) meshes.push_back(&level.mesh);
    Result<std::vector<Result<DistanceResult>>> measured =
        prepareAndMeasureSurfaceDistances(mesh, meshes, options.distance, reference_sides);
    if (!measured.ok()) diagnostics.warn("lod chain: errors not measured: " + measured.status().message());
    for (size_t i = 0; measured.ok() && i < measured->size(); ++i) {
        LodLevel& level = chain.levels[i];
        const Result<DistanceResult>& d = (*measured)[i];
        if (!d.ok()) {
            diagnostics.warn("lod chain: level ratio " + std::to_string(level.target_ratio) +
                             ": error not measured: " + d.status().message());
            continue;
        }
        level.has_distance = true;
        level.distance = *d;
    }
    updateSwitchDistances(chain, options.screen);
}

void keepLevels(LodChain& chain, const std::vector<bool>& keep) {
    size_t kept = 0;
    for (size_t i = 0; i < chain.levels.size(); ++i) {
        if (i < keep.size() && !keep[i]) continue;
        if (kept != i) chain.levels[kept] = std::move(chain.levels[i]);
        ++kept;
    }
    chain.levels.erase(chain.levels.begin() + long(kept), chain.levels.end());
}

void updateSwitchDistances(LodChain& chain, const ScreenParams& screen) {
    double previous = 0.0;
    for (LodLevel& level : chain.levels) {
        const double e = level.has_distance ? level.distance.hausdorff : level.quadric_error;
        level.switch_distance = levelSwitchDistance(e, previous, screen);
        previous = level.switch_distance;
        level.screen_coverage = screenCoverage(chain.bounding_radius, level.switch_distance, screen);
    }
}

} // namespace lodbake
