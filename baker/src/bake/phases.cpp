// The phase cut of the bake's post-chain tasks (phases.h).
#include "bake/phases.h"

namespace lodbake {
namespace bake_detail {

std::vector<std::vector<PhaseTask>> concurrentPhases(const std::vector<bool>& encoder_is_pfrep,
                                                     const std::vector<size_t>& level_triangles,
                                                     const PhaseEstimates& estimates) {
    const double lod0 = level_triangles.empty() ? 0.0 : double(level_triangles[0]);
    std::vector<PhaseTask> tasks;
    for (size_t e = 0; e < encoder_is_pfrep.size(); ++e)
        if (encoder_is_pfrep[e])
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, estimates.pfrep_bytes_per_triangle * lod0});
    tasks.push_back({PhaseTask::Kind::Measure, 0, estimates.measure_bytes_per_triangle * lod0});
    for (size_t e = 0; e < encoder_is_pfrep.size(); ++e)
        if (!encoder_is_pfrep[e])
            tasks.push_back({PhaseTask::Kind::Lod0Encoder, e, estimates.encode_bytes_per_triangle * lod0});
    for (size_t l = 1; l < level_triangles.size(); ++l)
        tasks.push_back({PhaseTask::Kind::Level, l, estimates.encode_bytes_per_triangle * double(level_triangles[l])});
    std::vector<std::vector<PhaseTask>> phases;
    double sum = 0;
    for (const PhaseTask& task : tasks) {
        if (phases.empty() || sum + task.bytes > estimates.budget_bytes) {
            phases.emplace_back();
            sum = 0;
        }
        phases.back().push_back(task);
        sum += task.bytes;
    }
    return phases;
}

} // namespace bake_detail
} // namespace lodbake
