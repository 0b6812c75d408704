#pragma once
// The bake pipeline: per input mesh, repair → LOD chain (measured errors, switch distances) →
// texture levels → pack description, then one glTF pack for all inputs (docs/bake.md).

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/bake/stages.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/core/diagnostics.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/image/texture_resize.h"
#include "lodbake/pack/pack.h"
#include "lodbake/simplify/lod_chain.h"

namespace lodbake {

struct BakeInput {
    std::string name; // LOD group name (node name); made unique by appending "_<n>" when repeated
    Mesh mesh;
};

/// A level of the chain as built that the pack leaves out because the next kept coarser level takes
/// over at almost the same distance (BakeSettings::lod_min_switch_ratio, docs/bake.md "Dead levels").
struct DroppedLodLevel {
    size_t level = 0; // its index in the chain as built, LOD0 = 0
    double ratio = 0; // its lod_ratios entry
    uint64_t triangles = 0;
    double hausdorff_error = 0; // as the metrics carry it (the running maximum down the chain)
    double switch_distance = 0; // where it would have been taken
    size_t finer_level = 0;     // the kept level drawn in its place (chain as built)
    size_t coarser_level = 0;   // the next kept coarser level (chain as built), taken at
    double coarser_switch_distance = 0;
};

struct BakeAssetReport {
    std::string name;
    uint64_t input_triangles = 0;
    uint64_t input_vertices = 0;
    std::vector<std::string> repair_unresolved;        // what repair could not fix
    std::vector<std::string> merge;                    // what the range-view merge did (empty: no merge)
    LodMetrics metrics;                                // LOD0 first
    std::vector<std::vector<ImageSize>> texture_sizes; // per level, per texture of that level's mesh
    std::vector<DroppedLodLevel> dropped_levels;       // chain levels the pack leaves out (not in metrics)
};

struct BakeOutput {
    std::vector<uint8_t> glb;
    std::vector<BakeAssetReport> assets;
};

/// Metrics of `chain` with LOD0 = `full` (error 0, switch distance 0) prepended. `hysteresis` is the
/// band half-width as a fraction of each switch distance.
LodMetrics lodMetrics(const Mesh& full, const LodChain& chain, const ScreenParams& screen, double hysteresis);

/// Removes from `metrics` (lodMetrics of `chain`, LOD0 = `full`) every level whose switch distance
/// is not distinct from the next kept coarser level's (distinctLevels, core/lod_policy.h, with
/// `min_ratio` = BakeSettings::lod_min_switch_ratio and the floor lodErrorFloor(full)) and returns
/// them, finest first. The kept levels' numbers are left as they were: their errors stay the running
/// maximum over every finer measured level, dropped ones included, so each kept level is taken at
/// the same distance as in the full chain.
std::vector<DroppedLodLevel> dropIndistinctLevels(LodMetrics& metrics, const Mesh& full, const LodChain& chain,
                                                  const ScreenParams& screen, double min_ratio);

/// The largest measured error that is rounding rather than geometry: 2^-20 of the largest
/// coordinate magnitude of `mesh`'s bounds (eight float32 steps there). Levels the simplifier made
/// without moving the surface (a flat stretch) measure the rounding of their float positions, a few
/// such steps at most, and differ from each other by nothing else.
double lodErrorFloor(const Mesh& mesh);

/// The note the bake gives for a dropped level: which, where it and the level that replaces it
/// would switch, and the setting.
std::string droppedLevelNote(const DroppedLodLevel& level, double min_ratio);

/// Bakes `inputs` (consumed) with `settings` into one GLB. Inputs are processed in parallel (at
/// most settings.threads workers, 0 = all); the bytes do not depend on the thread count. Warnings
/// from every stage go to `diagnostics` in input order. Fails on invalid settings, on inputs that
/// cannot be simplified or measured, on texture errors, and (settings.compact) when no compressed
/// stream extension is available (checkCompact).
Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics);
/// As above, reporting each finished stage to `hooks` (lodbake/bake/stages.h).
Result<BakeOutput> bake(std::vector<BakeInput> inputs, const BakeSettings& settings, Diagnostics& diagnostics,
                        const BakeHooks& hooks);

/// As above for inputs that keep a scene graph (docs/bake.md "Scenes"): `scene`'s nodes name inputs
/// by index (PackNode::asset); each input is baked once however many nodes instance it, and the
/// pack holds the graph with a LOD group on every node that names an input. An empty scene is bake().
Result<BakeOutput> bakeScene(std::vector<BakeInput> inputs, PackScene scene, const BakeSettings& settings,
                             Diagnostics& diagnostics, const BakeHooks& hooks);

/// The report as JSON (stable key order): settings echo, per asset the repair leftovers, every
/// level's metrics and texture sizes, and the pack size.
std::string bakeReportJson(const BakeOutput& output, const BakeSettings& settings);
/// As above for a pack of `pack_bytes` written elsewhere (output.glb empty: an out-of-core pack).
std::string bakeReportJson(const BakeOutput& output, const BakeSettings& settings, uint64_t pack_bytes);

} // namespace lodbake
