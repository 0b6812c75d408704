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

struct BakeAssetReport {
    std::string name;
    uint64_t input_triangles = 0;
    uint64_t input_vertices = 0;
    std::vector<std::string> repair_unresolved;        // what repair could not fix
    std::vector<std::string> merge;                    // what the range-view merge did (empty: no merge)
    LodMetrics metrics;                                // LOD0 first
    std::vector<std::vector<ImageSize>> texture_sizes; // per level, per texture of that level's mesh
};

struct BakeOutput {
    std::vector<uint8_t> glb;
    std::vector<BakeAssetReport> assets;
};

/// Metrics of `chain` with LOD0 = `full` (error 0, switch distance 0) prepended. `hysteresis` is the
/// band half-width as a fraction of each switch distance.
LodMetrics lodMetrics(const Mesh& full, const LodChain& chain, const ScreenParams& screen, double hysteresis);

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
