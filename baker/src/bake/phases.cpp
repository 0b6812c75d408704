// The phase cut of the bake's post-chain tasks (phases.h).
#include "bake/phases.h"

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

std::vector<std::vector<PhaseTask>> concurrentPhases(const std::vector<EncoderCost>& encoders,
                                                     const std::vector<size_t>& level_triangles,
                                                     const PhaseEstimates& estimates) {
    const double lod0 = level_triangles.empty() ? 0.0 : double(level_triangles[0]);
    std::vector<PhaseTask> tasks;
    double level_bytes_per_triangle = 0; // every encoder that codes every level, on one level
    for (const EncoderCost& encoder : encoders)
        if (!encoder.lod0_only) level_bytes_per_triangle += encoder.bytes_per_triangle;
    for (size_t e = 0; e < encoders.size(); ++e)
        if (encoders[e].lod0_only)
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, encoders[e].bytes_per_triangle * lod0});
    const size_t reference_at = tasks.size();
    // Every level (1 and on): one index at a time, the first the largest.
    constexpr size_t kFirstReferenceLevel = 1;
    if (estimates.measure_reference_ahead && level_triangles.size() > kFirstReferenceLevel)
        tasks.push_back(
            {PhaseTask::Kind::MeasureReference, kFirstReferenceLevel,
             estimates.reference_points_bytes_per_triangle * lod0 +
                 estimates.reference_index_bytes_per_triangle * double(level_triangles[kFirstReferenceLevel])});
    tasks.push_back({PhaseTask::Kind::Measure, 0, estimates.measure_bytes_per_triangle * lod0});
    for (size_t e = 0; e < encoders.size(); ++e)
        if (!encoders[e].lod0_only)
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, encoders[e].bytes_per_triangle * lod0});
    for (size_t l = 1; l < level_triangles.size(); ++l)
        tasks.push_back({PhaseTask::Kind::Level, l, level_bytes_per_triangle * double(level_triangles[l])});
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
        }
    }
    return phases;
}

} // namespace bake_detail
} // namespace lodbake
