#pragma once
// Every on-disk constant and record layout shared by the baker's encoders and the runtime's decoders
// (STYLE.md §2). The specs in docs/format/ are normative; a change here changes them too.

#include <cstdint>

namespace lodrt {
namespace format {

// glTF binary container (glTF 2.0 spec, "GLB File Format Specification").
constexpr uint32_t kGlbMagic = 0x46546C67u;     // "glTF" little-endian
constexpr uint32_t kGlbVersion = 2;
constexpr uint32_t kGlbChunkJson = 0x4E4F534Au; // "JSON"
constexpr uint32_t kGlbChunkBin = 0x004E4942u;  // "BIN\0"
constexpr uint32_t kGlbHeaderSize = 12;
constexpr uint32_t kGlbChunkHeaderSize = 8;

} // namespace format
} // namespace lodrt
