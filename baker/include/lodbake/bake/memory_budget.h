#pragma once
// The bake's memory budget (docs/bake.md, "Memory"): how much resident memory an in-memory bake of
// an input is allowed for, read from the input without loading it where the format allows, and a
// gate that lets a batch's jobs run side by side only while their allowances fit under one limit.
//
// The allowance of one pack is
//   kBakeBaseBytes + kBakeBytesPerTriangle * T + kBakeBytesPerTexel * X
// with T the input triangles and X the texels of its source images. The per-triangle figure covers
// every stage at once at its peak (the loaded and repaired mesh, the chain, its measurement, the
// coded streams, PFRep and the cluster hierarchy); it is an allowance with margin over measured peaks
// (docs/benchmarks.md, "Bake memory"), not a proven bound. The limit never changes a pack's bytes:
// a bake that fits runs exactly as without a limit, one that does not is refused before it loads.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/diagnostics.h"
#include "lodbake/core/memory_gate.h" // MemoryGate, which the batch runner uses
#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"
#include "lodbake/io/mesh_io.h"

namespace lodbake {

constexpr uint64_t kBakeBaseBytes = uint64_t(96) << 20; // libraries, worker stacks, allocator slack
constexpr uint64_t kBakeBytesPerTriangle = 640;
constexpr uint64_t kBakeBytesPerTexel = 32; // the decoded source (4 B), its resized levels and their buffers

/// What a pack's allowance is computed from.
struct BakeFootprint {
    uint64_t triangles = 0;
    uint64_t texels = 0;
    bool known = false; // false: the format cannot be sized without loading it
};

/// The allowance above, in bytes.
uint64_t bakeMemoryAllowance(const BakeFootprint& footprint);

/// Half of the machine's physical memory: the limit when none is set (a build machine bakes beside
/// other work), or 4 GiB when the system does not say.
uint64_t defaultBakeMemoryLimit();

/// The triangles of an input without loading it: a PLY's header (faces, each counted as one
/// triangle; polygons give more once split, so a polygon PLY reads low) or one streaming pass over an
/// OBJ's statements (exact). Other formats (OFF, glTF, .conf sets) are only sized once loaded:
/// `known` is false. Texels are not read here (images are probed once loaded). Reading errors are
/// those of the streaming readers (lodbake/io/mesh_stream.h).
Result<BakeFootprint> peekInputFootprint(const std::string& path, const ReadOptions& read, Diagnostics& diagnostics);

/// The footprint of loaded meshes: their triangles and the texels of every distinct texture (a
/// texture whose header cannot be read counts as none; the bake reports it).
BakeFootprint loadedFootprint(const std::vector<const Mesh*>& meshes);

/// The refusal of a pack whose allowance exceeds the limit: "<what>: the in-memory bake of T
/// triangles and X texels is allowed N MiB, above the memory limit of L MiB (--memory-limit)".
Status bakeOverLimit(const std::string& what, const BakeFootprint& footprint, uint64_t limit);

} // namespace lodbake
