#pragma once
// PFRep format 3: the range-coded form of a format 2 blob (docs/format/pfrep.md, "Format 3").

#include <cstdint>
#include <vector>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/pfrep/pfrep_builder.h"

namespace lodbake {

/// Codes a format 2 blob (as buildPfrep writes it) as format 3. The blob is validated first
/// (lodrt::openPfrep), and the result is decoded again and compared, so what this returns decodes
/// to exactly `blob`. InvalidInput for a blob that is not valid or not canonical (an entry not
/// written the way the builder writes it: smallest widths, one group per slot).
Result<std::vector<uint8_t>> compressPfrep(const std::vector<uint8_t>& blob);

/// Codes `build` as format 4 (docs/format/pfrep.md "Format 4"): its removal sequence and criterion
/// codes, against LOD0's `points` and `triangles` (3 point ids each) numbered as the sequence numbers
/// them (chainPoints of LOD0). The result is decoded again (lodrt::pfrepDecodeFormat4) and compared
/// with build.blob: same vertices, records, and triangles and dependencies at every entry.
/// InvalidInput when the build does not fit LOD0 or format 4 cannot hold it.
Result<std::vector<uint8_t>> compressPfrepFormat4(const PfrepBuild& build, const std::vector<Vec3f>& points,
                                                  const std::vector<uint32_t>& triangles);

/// The same against a LOD0 numbered apart from the build (a pack's LOD0 as its decoded stream
/// numbers it, lodrt::pfrepNumberLod0): point_of[p] is the id in `points` / `triangles` of the
/// build's point p. The blob then also codes the ranks of the points never removed
/// (format::kPfrep4FlagCodedTail), so it decodes to the build's table as the plain call does.
/// A non-empty `split_list` (codePfrepSplitList, by which `points` / `triangles` were numbered) is
/// stored after the header (format::kPfrep4FlagSplitPoints).
Result<std::vector<uint8_t>> compressPfrepFormat4(const PfrepBuild& build, const std::vector<Vec3f>& points,
                                                  const std::vector<uint32_t>& triangles,
                                                  const std::vector<uint32_t>& point_of,
                                                  const std::vector<uint8_t>& split_list = {});

/// The split list of a pack's format 4 blob (docs/format/pfrep.md "Split list"). `weld` holds, per
/// vertex of LOD0's decoded stream, the lowest vertex with its position bits; vertices of a weld
/// stand for one point of the build iff their `labels` are equal. Returns the coded list (what
/// lodrt::pfrepNumberLod0Split reads) and leaves in `weld` the lowest vertex of each vertex's group.
std::vector<uint8_t> codePfrepSplitList(std::vector<uint32_t>& weld, const std::vector<uint32_t>& labels);

} // namespace lodbake
