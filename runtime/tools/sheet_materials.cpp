// What --render shades with: attribute streams as floats (float, or normalised integers as
// KHR_mesh_quantization allows), glTF materials and their textures decoded through the image module.
#include "sheet_materials.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace loddump {

namespace {

// The bytes of buffer view `index` when they are in the GLB's binary chunk (all lodrt can see).
const uint8_t* bufferViewBytes(const lodrt::Pack& pack, uint64_t index, uint64_t* size) {
    if (index >= pack.bufferViewCount()) return nullptr;
    const lodrt::BufferViewInfo& view = pack.bufferView(uint32_t(index));
    const lodrt::GlbView& c = pack.container();
    if (!pack.buffer(view.buffer).is_glb_bin || !c.bin || view.byte_offset + view.byte_length > c.bin_size)
        return nullptr;
    *size = view.byte_length;
    return c.bin + view.byte_offset;
}

float componentValue(const uint8_t* p, lodrt::ComponentType type, bool is_normalized) {
    switch (type) {
    case lodrt::ComponentType::Float: {
        float f;
        std::memcpy(&f, p, 4);
        return f;
    }
    case lodrt::ComponentType::UnsignedByte:
        return is_normalized ? float(p[0]) / 255.0f : float(p[0]);
    case lodrt::ComponentType::Byte:
        return is_normalized ? std::max(float(int8_t(p[0])) / 127.0f, -1.0f) : float(int8_t(p[0]));
    case lodrt::ComponentType::UnsignedShort: {
        const uint16_t v = uint16_t(p[0] | p[1] << 8);
        return is_normalized ? float(v) / 65535.0f : float(v);
    }
    case lodrt::ComponentType::Short: {
        const int16_t v = int16_t(uint16_t(p[0] | p[1] << 8));
        return is_normalized ? std::max(float(v) / 32767.0f, -1.0f) : float(v);
    }
    default:
        return 0.0f;
    }
}

// Appends `count` elements of `components` floats from the accessor of attribute `name`, or zeros
// when the primitive has no such attribute or lodrt cannot see its data.
void appendStream(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, const char* name, uint32_t components,
                  size_t count, std::vector<float>* out) {
    const size_t first = out->size();
    out->resize(first + count * components, 0.0f);
    for (uint32_t a = 0; a < prim.attribute_count; ++a) {
        const lodrt::AttributeInfo& attribute = pack.attribute(prim.first_attribute + a);
        if (attribute.name != name) continue;
        const lodrt::AccessorInfo& acc = pack.accessor(attribute.accessor);
        if (acc.buffer_view == lodrt::kNoIndex || acc.is_sparse || acc.count != count ||
            lodrt::componentCount(acc.type) != components)
            return;
        uint64_t size = 0;
        const uint8_t* view = bufferViewBytes(pack, acc.buffer_view, &size);
        const uint32_t component_size = lodrt::componentSize(acc.component_type);
        const uint64_t stride = pack.bufferView(acc.buffer_view).byte_stride ? pack.bufferView(acc.buffer_view).byte_stride
                                                                              : acc.element_size;
        if (!view || component_size == 0 || (count > 0 && acc.byte_offset + (count - 1) * stride + acc.element_size > size))
            return;
        for (size_t i = 0; i < count; ++i)
            for (uint32_t k = 0; k < components; ++k)
                (*out)[first + i * components + k] =
                    componentValue(view + acc.byte_offset + i * stride + k * component_size, acc.component_type,
                                   acc.normalized);
        return;
    }
}

// Texture slot `slot` of a material (its index and texCoord), or null.
const SheetTexture* slotTexture(lodrt::JsonValue slot, SheetTextures& textures, uint32_t* uv_set) {
    uint64_t index = 0, tex_coord = 0;
    if (!slot.find("index").asUint64(&index)) return nullptr;
    if (slot.find("texCoord").isValid() && !slot.find("texCoord").asUint64(&tex_coord)) return nullptr;
    if (tex_coord > 1) return nullptr; // the sheet reads TEXCOORD_0 and TEXCOORD_1
    *uv_set = uint32_t(tex_coord);
    return textures.texture(index);
}

SheetMaterial readMaterial(const lodrt::Pack& pack, uint32_t index, SheetTextures& textures) {
    SheetMaterial m;
    const lodrt::JsonValue json = pack.document().root().find("materials").at(index);
    const lodrt::JsonValue pbr = json.find("pbrMetallicRoughness");
    const lodrt::JsonValue factor = pbr.find("baseColorFactor");
    if (factor.isArray() && factor.size() == 4)
        for (uint32_t k = 0; k < 4; ++k) m.base_colour[k] = float(factor.at(k).number());
    m.base_colour_texture = slotTexture(pbr.find("baseColorTexture"), textures, &m.base_colour_uv);
    m.normal_texture = slotTexture(json.find("normalTexture"), textures, &m.normal_uv);
    if (json.find("normalTexture").find("scale").isNumber())
        m.normal_scale = float(json.find("normalTexture").find("scale").number());
    return m;
}

} // namespace

SheetTextures::SheetTextures(const lodrt::Pack& pack, DecodeImage decode)
    : pack_(pack), decode_(std::move(decode)) {}

const SheetTexture* SheetTextures::texture(uint64_t index) {
    const lodrt::JsonValue root = pack_.document().root();
    const lodrt::JsonValue texture = root.find("textures").at(uint32_t(std::min<uint64_t>(index, UINT32_MAX)));
    if (!texture.isObject()) return nullptr;
    if (decoded_.size() <= index) {
        decoded_.resize(size_t(index) + 1);
        is_tried_.resize(size_t(index) + 1, false);
    }
    if (is_tried_[index]) return decoded_[index].get();
    is_tried_[index] = true;
    const std::string where = "/textures/" + std::to_string(index);
    uint64_t source = 0, view = 0, size = 0;
    if (!texture.find("source").asUint64(&source) ||
        !root.find("images").at(uint32_t(std::min<uint64_t>(source, UINT32_MAX))).find("bufferView").asUint64(&view)) {
        problems_.push_back(where + ": no image in a buffer view");
        return nullptr;
    }
    const uint8_t* bytes = bufferViewBytes(pack_, view, &size);
    if (!bytes) {
        problems_.push_back(where + ": the image's bytes are outside the GLB");
        return nullptr;
    }
    auto decoded = std::make_unique<SheetTexture>();
    std::string error;
    if (!decode_(bytes, size_t(size), decoded.get(), &error)) {
        problems_.push_back(where + ": " + error);
        return nullptr;
    }
    decoded_[index] = std::move(decoded);
    return decoded_[index].get();
}

namespace {

// Appends the decoded stream `values` when it holds `count` elements, else the accessor's.
void appendStreamOrAccessor(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, const char* name,
                            uint32_t components, size_t count, const std::vector<float>& values,
                            std::vector<float>* out) {
    if (values.size() == count * components)
        out->insert(out->end(), values.begin(), values.end());
    else
        appendStream(pack, prim, name, components, count, out);
}

} // namespace

void appendShading(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, size_t vertex_count,
                   size_t triangle_count, const StreamShading& decoded, SheetTextures& textures, SheetMesh* out) {
    const uint32_t material_count = pack.materialCount();
    if (material_count == 0) return;
    if (out->materials.empty()) {
        // Every material of the pack, then the glTF default material for primitives without one.
        for (uint32_t m = 0; m < material_count; ++m) out->materials.push_back(readMaterial(pack, m, textures));
        out->materials.emplace_back();
        out->uvs.resize(2);
    }
    // Vertices appended before the first primitive with shading data get zeros (face normals).
    const size_t vertices_before = out->positions.size() / 3 - vertex_count;
    out->normals.resize(vertices_before * 3, 0.0f);
    out->tangents.resize(vertices_before * 4, 0.0f);
    for (std::vector<float>& set : out->uvs) set.resize(vertices_before * 2, 0.0f);
    out->triangle_material.resize(out->indices.size() / 3 - triangle_count, material_count);
    appendStreamOrAccessor(pack, prim, "NORMAL", 3, vertex_count, decoded.normals, &out->normals);
    appendStreamOrAccessor(pack, prim, "TANGENT", 4, vertex_count, decoded.tangents, &out->tangents);
    appendStreamOrAccessor(pack, prim, "TEXCOORD_0", 2, vertex_count, decoded.uvs[0], &out->uvs[0]);
    appendStreamOrAccessor(pack, prim, "TEXCOORD_1", 2, vertex_count, decoded.uvs[1], &out->uvs[1]);
    const uint32_t material = prim.material < material_count ? prim.material : material_count;
    out->triangle_material.resize(out->indices.size() / 3, material);
}

} // namespace loddump
