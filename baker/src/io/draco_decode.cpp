// KHR_draco_mesh_compression: decodes the Draco bitstream with Draco's own decoder and converts the
// requested attributes to float, point by point. Draco is used only here.
#include "io/draco_decode.h"

#include <exception>
#include <memory>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/mesh/mesh.h>

namespace lodbake::gltf_detail {

namespace {

Result<DracoMeshData> decodeImpl(const uint8_t* data, size_t size, const std::vector<int>& attribute_ids,
                                 const std::string& context) {
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(data), size);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
        return invalidInput(context + ": cannot decode Draco data: " + decoded.status().error_msg_string());
    std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
    if (!mesh) return invalidInput(context + ": Draco data holds no mesh");

    DracoMeshData out;
    out.point_count = mesh->num_points();
    out.indices.reserve(size_t(mesh->num_faces()) * 3);
    for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
        const draco::Mesh::Face& face = mesh->face(f);
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = face[k].value();
            if (p >= out.point_count)
                return invalidInput(context + ": Draco face " + std::to_string(f.value()) + " refers to point " +
                                    std::to_string(p) + " of " + std::to_string(out.point_count));
            out.indices.push_back(p);
        }
    }
    for (int id : attribute_ids) {
        const draco::PointAttribute* attribute = mesh->GetAttributeByUniqueId(uint32_t(id));
        if (attribute == nullptr)
            return invalidInput(context + ": attribute id " + std::to_string(id) + " is not in the Draco data");
        const int components = attribute->num_components();
        if (components < 1 || components > 4)
            return invalidInput(context + ": Draco attribute " + std::to_string(id) + " has " +
                                std::to_string(components) + " components, expected 1 to 4");
        DracoAttributeData values;
        values.component_count = components;
        values.values.resize(size_t(out.point_count) * size_t(components));
        for (draco::PointIndex p(0); p < out.point_count; ++p) {
            const draco::AttributeValueIndex v = attribute->mapped_index(p);
            if (v.value() >= attribute->size() ||
                !attribute->ConvertValue<float>(v, int8_t(components), &values.values[size_t(p.value()) * components]))
                return invalidInput(context + ": Draco attribute " + std::to_string(id) + " point " +
                                    std::to_string(p.value()) + ": value cannot be read");
        }
        out.attributes.push_back(std::move(values));
    }
    return out;
}

} // namespace

Result<DracoMeshData> decodeDracoMesh(const uint8_t* data, size_t size, const std::vector<int>& attribute_ids,
                                      const std::string& context) {
    try {
        return decodeImpl(data, size, attribute_ids, context);
    } catch (const std::exception& e) {
        return invalidInput(context + ": Draco decoder failed: " + e.what());
    }
}

} // namespace lodbake::gltf_detail
