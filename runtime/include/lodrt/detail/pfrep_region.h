#pragma once
// Internal helpers shared by the PFRep region-block reader (runtime/src/pfrep_region.cpp) and its
// writer (baker/src/pfrep/pfrep_region.cpp): positions inside a format 2 layout and per-entry
// validation. Not a stable API.

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

} // namespace lodrt::detail
