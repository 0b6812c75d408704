#pragma once
// Internal helpers shared by the PFRep region-block reader (runtime/src/pfrep_region.cpp), its
// writer (baker/src/pfrep/pfrep_region.cpp) and the Streamer: positions inside a format 2 layout,
// per-entry validation, and block loading in two halves. Not a stable API.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/pfrep.h"

namespace lodrt::detail {

/// Byte offset (from m.data) of vertex v's record; its block's layout must be in place.
LODRT_API uint64_t pfrepRecordOffset(const PfrepModel& m, uint32_t v);
/// Byte offset (from m.data) where entry i starts (its block's entry offsets must be in place).
LODRT_API uint64_t pfrepEntryOffset(const PfrepModel& m, uint32_t i);
/// Byte offset where the entry stream of i's block ends (its padding follows).
LODRT_API uint64_t pfrepStreamEnd(const PfrepModel& m, uint32_t i);
/// Validates entry i laid out at bytes [begin, end) of m.data (the block padding or other bytes of
/// the buffer follow), as openPfrep does, and that it ends in the byte before `end`. Adds its input
/// triangles to *originals and writes its fan length to *neighbours on Ok.
LODRT_API Result pfrepValidateEntryAt(const PfrepModel& m, uint32_t i, uint64_t begin, uint64_t end,
                                      uint64_t* originals, uint32_t* neighbours);
/// A_i of a validated entry: writes min(n, capacity) neighbours, returns n.
LODRT_API size_t pfrepEntryNeighbours(const PfrepModel& m, uint32_t i, uint32_t* out, size_t capacity);
/// Value of a radius / error log code.
LODRT_API float pfrepLogValue(const PfrepModel& m, uint32_t code);

/// What staging a region block found, for its commit.
struct PfrepRegionStaged {
    uint64_t originals = 0;      // its input triangles
    uint32_t max_neighbours = 0; // the model's max_fan_neighbours with the block's fans
    uint32_t max_radius_code = 0, max_error_code = 0;
    uint64_t records_offset = 0; // where its records start in the block's bytes
};

/// Bytes that must be readable after a block's bytes given to pfrepRegionStageBlock: its entries are
/// validated where they lie, and the bit reader loads whole 8-byte words.
constexpr size_t kPfrepRegionStagePadding = 8;

/// First half of pfrepRegionLoadBlock, for a loader thread while another thread refines with the
/// model: checks the block's size and ranks (none resident, none set in `claimed` when given) and
/// validates its records and entries in `bytes` (followed by kPfrepRegionStagePadding readable
/// bytes), writing nothing but the block's rank list in the state buffer and (on Ok) the block's
/// bits in `claimed` (V bits, owned by the loader: the ranks staged and not yet committed). The
/// decoded buffer is not touched. The block must not be loaded.
LODRT_API Result pfrepRegionStageBlock(const PfrepRegions& regions, uint32_t block, const void* bytes, size_t size,
                                       uint8_t* claimed, PfrepRegionStaged* staged);
/// Clears a staged block's bits in `claimed` (after its commit, or instead of it).
LODRT_API void pfrepRegionUnclaim(const PfrepRegions& regions, uint32_t block, uint8_t* claimed);
/// Second half, on the thread that owns the model: lays the staged block's records and entries
/// (the same `bytes`) into the decoded buffer, checks the input triangles of all loaded blocks and
/// makes the block's vertices resident. On BadStructure the block's bytes are zero again.
LODRT_API Result pfrepRegionCommitBlock(PfrepRegions* regions, uint32_t block, const void* bytes,
                                        const PfrepRegionStaged& staged);

} // namespace lodrt::detail
