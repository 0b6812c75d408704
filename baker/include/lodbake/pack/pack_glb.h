#pragma once
// The pack writer: a PackDescription (pack.h) as one GLB, through the io module's glTF model
// helpers (src/io/gltf_model.h). The pack module owns it because it is the pack's layout; the io
// module's glTF reader and writer know nothing of packs.

#include <cstdint>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake {

struct PackDescription;

/// Serialises a pack description (pack/pack.h) as one GLB: per asset, one glTF mesh per level, a
/// LOD0 node in the scene with MSFT_lod (the other levels' nodes, highest detail first),
/// extras.MSFT_screencoverage and the asset's node extensions; mesh and primitive extensions with
/// their blobs stored as buffer views. Extensions are listed in extensionsUsed; stream extensions also
/// in extensionsRequired when the description is compact. Deterministic bytes; passes the Khronos
/// validator. Errors: a level without triangles or non-finite data, malformed extension JSON.
Result<std::vector<uint8_t>> writePackGlb(const PackDescription& description);
/// The same bytes; frees each level's mesh and blobs once the pack holds them (lower peak memory).
Result<std::vector<uint8_t>> writePackGlb(PackDescription&& description);

} // namespace lodbake
