#pragma once
// Internal to the io module: EXT_meshopt_compression input for the glTF reader (docs/format/web.md).
// Before tinygltf parses the document, a fallback buffer (no uri, only compressed views use it) gets a
// one-byte data URI in its place, since tinygltf would otherwise copy the BIN chunk into it or fail;
// after parsing, every compressed view is decoded (lodrt/meshopt.h) into a buffer of its own, so the
// rest of the reader sees plain (possibly KHR_mesh_quantization) accessors.

#include <string>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "lodbake/core/status.h"

namespace lodbake {

/// Replaces each fallback buffer of `root` as described above; sets `changed` when it did.
void replaceMeshoptFallbacks(nlohmann::json& root, bool& changed);

/// Decodes every bufferView carrying EXT_meshopt_compression into a new buffer and points the view at
/// it (offset 0, the extension removed). Errors name the view: "<name>: bufferView N: ...".
Status decodeMeshoptViews(tinygltf::Model& model, const std::string& name);

} // namespace lodbake
