#pragma once
// PFRep region blocks (docs/format/pfrep.md "Region blocks"): the format 2 table cut into spatially
// coherent blocks that a streamer loads independently, with a directory of byte ranges and bounds.

#include <cstdint>
#include <vector>

#include "lodbake/core/lod_policy.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct PfrepRegionOptions {
    uint32_t block_vertices = 1024; // target vertices per block (blocks of a band are near-equal)
    uint32_t root_vertices = 4096;  // block 0: at least this many of the coarsest ranks, and every
                                    // vertex never removed
    // The views the blocks are cut for: a vertex of error e is refined within switchDistance(e) of
    // the eye, so blocks group vertices near in position and in that reach (docs/format/pfrep.md,
    // "Blocks and bounds"). An invalid screen (no finite reach) cuts by position alone.
    ScreenParams screen;
};

struct PfrepRegionStats {
    uint32_t blocks = 0;
    uint32_t bands = 0;
    uint64_t open_bytes = 0; // header + directory + skeleton
    uint64_t root_bytes = 0; // block 0
};

/// Writes the region blob of a format 2 blob (as buildPfrep returns it). The result decodes, once
/// every block is loaded, to exactly `format2` (checked before returning). InvalidInput when
/// `format2` is not a valid format 2 blob.
Result<std::vector<uint8_t>> writePfrepRegions(const std::vector<uint8_t>& format2, const PfrepRegionOptions& options,
                                               PfrepRegionStats* stats = nullptr);

} // namespace lodbake
