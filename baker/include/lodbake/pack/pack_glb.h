#pragma once
// The pack writer: a PackDescription (pack.h) as one GLB, through the io module's glTF model
// helpers (src/io/gltf_model.h). The pack module owns it because it is the pack's layout; the io
// module's glTF reader and writer know nothing of packs.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
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
/// The same bytes, written to `path`, and the only writer of extensions with blobs in files
/// (PackExtension::spilled, the streamed cluster pages): the binary chunk except those blobs is
/// assembled in memory, and each file is copied into its place through a bounded buffer. Memory:
/// the pack without its spilled blobs, plus `buffer_bytes` and a 64 KiB copy buffer. Written to a
/// temporary in the folder of `path` renamed into place: on any error or when `cancel` is set
/// (IoError naming `path`) nothing is left. A failed write (a full disk) is an IoError naming
/// `path`. Returns the bytes written.
Result<uint64_t> writePackGlbFile(PackDescription&& description, const std::string& path,
                                  const std::atomic<bool>* cancel = nullptr, size_t buffer_bytes = size_t(1) << 20);

} // namespace lodbake
