#pragma once
// Decoding of KHR_draco_mesh_compression payloads (internal to the gltf module).

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake::gltf_detail {

/// One decoded attribute: `component_count` floats per point, in point order.
struct DracoAttributeData {
    int component_count = 0;
    std::vector<float> values;
};

struct DracoMeshData {
    uint32_t point_count = 0;
    std::vector<uint32_t> indices;              // 3 per face, into the points
    std::vector<DracoAttributeData> attributes; // in the order of the requested ids
};

/// Decodes a Draco mesh and extracts the attributes with the given unique ids. `context` prefixes
/// error messages ("<file>: mesh \"m\" primitive 0: KHR_draco_mesh_compression").
Result<DracoMeshData> decodeDracoMesh(const uint8_t* data, size_t size, const std::vector<int>& attribute_ids,
                                      const std::string& context);

} // namespace lodbake::gltf_detail
