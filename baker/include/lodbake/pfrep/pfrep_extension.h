#pragma once
// The LODBAKE_progressive_fans mesh extension (schemas/LODBAKE_progressive_fans): the PFRep blob of a
// pack's full-detail level, stored in a buffer view, plus the PFRep removal count that matches each
// level of the discrete chain. The pack module wraps it into a PackExtension (stream_encoders.cpp);
// this module does not depend on the pack.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/json_value.h"
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/pfrep/pfrep_builder.h"

namespace lodbake {

/// The JSON member that receives the blob's buffer-view index.
inline constexpr const char* kPfrepExtensionViewMember = "bufferView";

struct PfrepExtensionLevel {
    uint32_t removals = 0;  // PFRep level (vertices removed) that stands for this chain level
    uint64_t triangles = 0; // triangles of that PFRep level
};

struct PfrepExtensionObject {
    std::vector<uint8_t> blob;
    uint32_t vertex_count = 0;
    uint32_t removed_count = 0;
    uint64_t triangle_count = 0;             // triangles of PFRep level 0
    std::vector<PfrepExtensionLevel> levels; // one per chain level, highest detail first
    JsonNode json; // the extension object without its bufferView member (the pack writer adds it)
    /// The build's sequence beside the blob (PfrepBuild's members), for coding it as format 4.
    std::vector<uint32_t> rank_point, rank_kept;
    size_t stored_triangles = 0;
};

/// Builds the PFRep of `lod0` (half-edge sequence, `options`) and, for each ratio of
/// `level_ratios` (fractions of lod0's triangles, highest detail first; the first is usually 1),
/// the smallest removal count whose level has at most ratio · triangle_count triangles (the coarsest
/// level when none has). InvalidInput when a ratio is not in (0, 1] or the mesh has no triangle.
/// The blob stores positions only, so both builds read LOD0's geometry alone, as a view of the
/// caller's mesh (which other stages may read meanwhile).
Result<PfrepExtensionObject> buildPfrepExtension(const MeshView& lod0, const std::vector<double>& level_ratios,
                                                 const PfrepOptions& options, Diagnostics& diagnostics);

/// The same from a discrete chain of `lod0` (its input): when the chain recorded its collapses as
/// vertex removals (LodChainOptions::record_removals, LodChain::removals_complete) the blob is built
/// from them (buildPfrepFromChain: no simplification of its own) and chain level i is the blob level
/// at its collapse count, with exactly its triangles; otherwise buildPfrepExtension(lod0, ratios of
/// 1 and the chain's levels, options). `options` only applies to that fallback.
Result<PfrepExtensionObject> buildPfrepExtension(const MeshView& lod0, const LodChain& chain, const PfrepOptions& options,
                                                 Diagnostics& diagnostics);

} // namespace lodbake
