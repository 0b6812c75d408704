#pragma once
// glTF container reader: splits a .glb into its JSON and BIN chunks, or passes a plain .gltf through.
// Every byte is hostile; nothing is copied and nothing is allocated.

#include <cstddef>
#include <cstdint>

#include "lodrt/export.h"
#include "lodrt/result.h"

namespace lodrt {

/// Spans into the caller's bytes; valid as long as those bytes are.
struct GlbView {
    const uint8_t* json = nullptr; // JSON text (GLB JSON chunk, or the whole input for .gltf)
    size_t json_size = 0;          // bytes, including any trailing space padding of the chunk
    const uint8_t* bin = nullptr;  // BIN chunk payload, or null when there is none
    size_t bin_size = 0;           // bytes, including up to 3 bytes of zero padding
    bool is_binary = false;        // true for a GLB container, false for plain JSON text
};

/// Parses a glTF container held in data[0, size).
/// GLB (magic "glTF"): the header length must equal size (Truncated if larger, TrailingBytes if
/// smaller); version must be 2 (UnsupportedVersion); the first chunk must be JSON and non-empty, an
/// optional second chunk may be BIN; every chunk length must be a multiple of 4 and fit in the file;
/// JSON or BIN chunks elsewhere are BadChunk; chunks of other types are skipped, as the spec asks.
/// Plain .gltf: input whose first byte, after an optional UTF-8 byte order mark and JSON whitespace,
/// is '{' is returned whole as json with is_binary false. Anything else is BadMagic (Truncated if it
/// is a strict prefix of the GLB magic).
/// The JSON text itself is not parsed here; see parseJson.
/// Returns Ok and fills *out, or an error and leaves *out zeroed. InvalidArgument if out is null
/// or data is null with size > 0.
LODRT_API Result parseGlb(const uint8_t* data, size_t size, GlbView* out);

} // namespace lodrt
