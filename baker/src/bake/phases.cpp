// The phase cut of the bake's post-chain tasks (phases.h).
#include "bake/phases.h"

#include <algorithm>
#include <cmath>

namespace lodbake {
namespace bake_detail {

namespace {

std::vector<std::vector<PhaseTask>> cut(const std::vector<PhaseTask>& tasks, double budget_bytes) {
    std::vector<std::vector<PhaseTask>> phases;
    double sum = 0;
    for (const PhaseTask& task : tasks) {
        if (phases.empty() || sum + task.bytes > budget_bytes) {
            phases.emplace_back();
            sum = 0;
        }
        phases.back().push_back(task);
        sum += task.bytes;
    }
    return phases;
}

} // namespace

std::vector<std::vector<PhaseTask>> concurrentPhases(const std::vector<bool>& encoder_is_pfrep,
                                                     const std::vector<size_t>& level_triangles,
                                                     const PhaseEstimates& estimates) {
    const double lod0 = level_triangles.empty() ? 0.0 : double(level_triangles[0]);
    double level_points = 0;
    for (size_t l = 1; l < level_triangles.size(); ++l) level_points += estimates.sample_points + 0.5 * double(level_triangles[l]);
    const uint32_t slabs = uint32_t(std::min(64.0, std::max(1.0, std::ceil(lod0 / estimates.slab_triangles))));
    std::vector<PhaseTask> tasks;
    for (size_t e = 0; e < encoder_is_pfrep.size(); ++e)
        if (encoder_is_pfrep[e])
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, 0, estimates.pfrep_bytes_per_triangle * lod0});
    const size_t reference_at = tasks.size();
    // Every level (1 and on): one index at a time, the first the largest.
    constexpr size_t kFirstReferenceLevel = 1;
    if (estimates.measure_reference_ahead && level_triangles.size() > kFirstReferenceLevel) {
        // The reference sides, then the levels' sides: the larger of the two working sets.
        const double reference_sides =
            estimates.reference_points_bytes_per_triangle * lod0 +
            estimates.reference_index_bytes_per_triangle * double(level_triangles[kFirstReferenceLevel]);
        const double level_sides = estimates.level_point_bytes * level_points +
                                   estimates.slab_index_bytes_per_triangle * lod0 / double(slabs);
        tasks.push_back({PhaseTask::Kind::MeasureReference, kFirstReferenceLevel, slabs,
                         std::max(reference_sides, level_sides)});
    }
    const size_t measure_at = tasks.size();
    tasks.push_back({PhaseTask::Kind::Measure, 0, 0, estimates.measure_bytes_per_triangle * lod0});
    for (size_t e = 0; e < encoder_is_pfrep.size(); ++e)
        if (!encoder_is_pfrep[e])
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, 0, estimates.encode_bytes_per_triangle * lod0});
    for (size_t l = 1; l < level_triangles.size(); ++l)
        tasks.push_back({PhaseTask::Kind::Level, l, 0, estimates.encode_bytes_per_triangle * double(level_triangles[l])});
    std::vector<std::vector<PhaseTask>> phases = cut(tasks, estimates.budget_bytes);
    if (reference_at < tasks.size() && tasks[reference_at].kind == PhaseTask::Kind::MeasureReference) {
        // Kept only beside an earlier task of its phase and before the measurement's phase.
        bool beside_earlier = false, before_measure = true;
        for (const std::vector<PhaseTask>& phase : phases)
            for (size_t t = 0; t < phase.size(); ++t)
                if (phase[t].kind == PhaseTask::Kind::MeasureReference) {
                    beside_earlier = t > 0;
                    for (const PhaseTask& other : phase) before_measure &= other.kind != PhaseTask::Kind::Measure;
                }
        if (!beside_earlier || !before_measure) {
            tasks.erase(tasks.begin() + std::ptrdiff_t(reference_at));
            phases = cut(tasks, estimates.budget_bytes);
        } else {
            // Kept: the measurement only combines what it measured, so it starts the phase after it, with
            // the coding.
            phases.clear();
            const std::vector<PhaseTask> first(tasks.begin(), tasks.begin() + std::ptrdiff_t(measure_at));
            std::vector<PhaseTask> rest(tasks.begin() + std::ptrdiff_t(measure_at), tasks.end());
            rest.front().bytes = estimates.measured_ahead_bytes;
            for (const std::vector<PhaseTask>& phase : cut(first, estimates.budget_bytes)) phases.push_back(phase);
            for (const std::vector<PhaseTask>& phase : cut(rest, estimates.budget_bytes)) phases.push_back(phase);
        }
    }
    return phases;
}

} // namespace bake_detail
} // namespace lodbake
