#pragma once
// Internal to the pack module: the --web form of a pack (docs/format/web.md). Every level's vertex and
// index data is quantized (KHR_mesh_quantization) and compressed with EXT_meshopt_compression, its
// buffer views decoding into a fallback buffer that has no bytes, as web clients (Babylon.js,
// three.js) read it. The pack writer calls these around its buffer compaction.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include "lodbake/core/mesh.h"
#include "lodbake/core/status.h"

namespace lodbake {

/// The level with its triangles in vertex-cache order (per sub-mesh) and its vertices in first-use
/// order (unused vertices dropped), the order meshopt's codecs compress best.
Mesh webLevelOrder(const Mesh& mesh);

/// The power-of-two grid step --web stores positions on: the largest power of two not above the largest
/// extent / (2^kWebPositionBits - 1), or not above `max_step` when that is coarser, and coarsened
/// further only when a coordinate would not fit the 24-bit mantissa of the EXPONENTIAL filter.
/// Returns its exponent (step = 2^exponent).
int webPositionExponent(const float* xyz, size_t count, double max_step = 0);

/// Compressed views waiting for their place in the binary chunk.
struct WebViews {
    struct View {
        std::vector<uint8_t> bytes; // the meshopt stream
        uint64_t count = 0;
        uint32_t stride = 0;
        const char* mode = nullptr;
        const char* filter = nullptr;
        int target = 0;
        std::vector<int> accessors; // the accessors that read it
    };
    std::vector<View> views;
    std::vector<double> mesh_position_step;  // per glTF mesh, its level's web_position_step (input)
    uint64_t fallback_bytes = 0;             // byteLength of the fallback buffer
    std::vector<std::string> extension_json; // per view, its EXT_meshopt_compression object (appendWebViews)
    bool quantized = false;                  // some attribute is no longer float (KHR_mesh_quantization is used)
};

/// Encodes every accessor a mesh primitive reads (attributes and indices): quantized, compressed, the
/// accessor's component type, normalization and bounds updated and its buffer view detached (-1) until
/// appendWebViews gives it the compressed one. `bin` is the buffer the model's views point into.
Status encodeWebAccessors(tinygltf::Model& model, const std::vector<uint8_t>& bin, WebViews& out);

/// Appends the compressed streams to `bin` (4-byte aligned) and adds their buffer views: each decodes
/// into buffer 1, the fallback buffer, and carries the EXT_meshopt_compression object.
void appendWebViews(tinygltf::Model& model, std::vector<uint8_t>& bin, WebViews& views);

/// Puts each compressed view's EXT_meshopt_compression object into the JSON text tinygltf wrote (in
/// place of the marker name appendWebViews gave the view).
Status webPatchJson(std::string& json, const WebViews& views);

/// The fallback buffer's JSON text, as the GLB writer places it after buffer 0.
std::string webFallbackBufferJson(const WebViews& views);

} // namespace lodbake
