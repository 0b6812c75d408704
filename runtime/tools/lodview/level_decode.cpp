#include "level_decode.h"

#include <algorithm>

namespace lodview {

namespace {

uint32_t jsonIndex(const lodrt::JsonValue& value) {
    uint64_t v = 0;
    return value.asUint64(&v) && v < lodrt::kNoIndex ? uint32_t(v) : lodrt::kNoIndex;
}

// The accessor of attribute `name` of primitive p, or kNoIndex.
uint32_t attributeAccessor(const lodrt::Pack& pack, const lodrt::PrimitiveInfo& prim, std::string_view name) {
    for (uint32_t a = 0; a < prim.attribute_count; ++a) {
        const lodrt::AttributeInfo& attribute = pack.attribute(prim.first_attribute + a);
        if (attribute.name == name) return attribute.accessor;
    }
    return lodrt::kNoIndex;
}

constexpr char kTexCoordNames[8][11] = {"TEXCOORD_0", "TEXCOORD_1", "TEXCOORD_2", "TEXCOORD_3",
                                        "TEXCOORD_4", "TEXCOORD_5", "TEXCOORD_6", "TEXCOORD_7"};

std::string failure(const char* what, lodrt::Result r) {
    return std::string(what) + " (" + lodrt::resultName(r) + ")";
}

bool hasData(const lodrt::Pack& pack, uint32_t accessor) {
    return accessor != lodrt::kNoIndex && pack.accessor(accessor).buffer_view != lodrt::kNoIndex;
}

} // namespace

uint32_t baseColourImageView(const lodrt::Pack& pack, uint32_t material, uint32_t* tex_coord) {
    const lodrt::JsonValue root = pack.document().root();
    const lodrt::JsonValue info =
        root.find("materials").at(material).find("pbrMetallicRoughness").find("baseColorTexture");
    const uint32_t texture = jsonIndex(info.find("index"));
    const uint32_t set = info.find("texCoord").isValid() ? jsonIndex(info.find("texCoord")) : 0;
    if (texture == lodrt::kNoIndex || set > 7) return lodrt::kNoIndex;
    const uint32_t image = jsonIndex(root.find("textures").at(texture).find("source"));
    if (image == lodrt::kNoIndex) return lodrt::kNoIndex;
    const uint32_t view = jsonIndex(root.find("images").at(image).find("bufferView"));
    if (view == lodrt::kNoIndex || view >= pack.bufferViewCount()) return lodrt::kNoIndex;
    *tex_coord = set;
    return view;
}

template <class T> void LevelDecoder::ensure(std::vector<T>* v, size_t n) {
    if (v->size() >= n) return;
    v->resize(n);
    ++growths_;
}

void LevelDecoder::reserve(const lodrt::PackSource& source) {
    const lodrt::Pack& pack = source.pack();
    const lodrt::ModelSet& models = source.models();
    size_t vertices = 1, indices = 1, scratch = 1, prims = 1;
    for (uint32_t m = 0; m < models.modelCount(); ++m)
        for (uint32_t l = 0; l < models.model(m).level_count; ++l) {
            const lodrt::MeshInfo& mesh = pack.mesh(models.modelLevel(m, l).mesh);
            size_t v = 0, i = 0;
            for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
                const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
                v += size_t(prim.vertex_count);
                i += size_t(prim.index_count);
                for (uint32_t a = 0; a <= prim.attribute_count; ++a) {
                    const uint32_t acc =
                        a == prim.attribute_count ? prim.indices : pack.attribute(prim.first_attribute + a).accessor;
                    if (acc != lodrt::kNoIndex) scratch = std::max(scratch, size_t(lodrt::accessorScratchBytes(pack, acc)));
                }
            }
            vertices = std::max(vertices, v);
            indices = std::max(indices, i);
            prims = std::max(prims, size_t(mesh.primitive_count));
        }
    // A reservation never counts as growth: only what decode() has to add later does.
    if (positions_.size() < 3 * vertices) positions_.resize(3 * vertices);
    if (uvs_.size() < 2 * vertices) uvs_.resize(2 * vertices);
    if (indices_.size() < indices) indices_.resize(indices);
    if (scratch_.size() < (scratch + 7) / 8) scratch_.resize((scratch + 7) / 8);
    primitives_.reserve(std::max(primitives_.capacity(), prims));
}

// Plain, quantized or meshopt-compressed accessors.
bool LevelDecoder::decodeAccessors(const lodrt::PackSource& source, const lodrt::BinBytes& bin, DecodedPrimitive* out,
                                   uint32_t uv_set, std::string* error) {
    const lodrt::Pack& pack = source.pack();
    const lodrt::PrimitiveInfo& prim = pack.primitive(out->primitive);
    uint8_t* scratch = reinterpret_cast<uint8_t*>(scratch_.data());
    const size_t scratch_size = scratch_.size() * 8;
    const uint32_t position = attributeAccessor(pack, prim, "POSITION");
    if (position == lodrt::kNoIndex || lodrt::componentCount(pack.accessor(position).type) != 3) {
        *error = "a primitive has no VEC3 POSITION accessor";
        return false;
    }
    lodrt::Result r = lodrt::readAccessorFloats(pack, position, bin, positions_.data() + 3 * size_t(out->first_vertex),
                                                3 * size_t(out->vertex_count), scratch, scratch_size);
    if (r != lodrt::Result::Ok) {
        *error = failure("POSITION cannot be read from the level's bytes", r);
        return false;
    }
    if (prim.indices == lodrt::kNoIndex) {
        for (uint32_t i = 0; i < out->index_count; ++i) indices_[out->first_index + i] = i;
    } else {
        r = lodrt::readAccessorIndices(pack, prim.indices, bin, prim.vertex_count, indices_.data() + out->first_index,
                                       out->index_count, scratch, scratch_size);
        if (r != lodrt::Result::Ok) {
            *error = failure("the indices cannot be read from the level's bytes", r);
            return false;
        }
    }
    const uint32_t uv = uv_set < 8 ? attributeAccessor(pack, prim, kTexCoordNames[uv_set]) : lodrt::kNoIndex;
    if (uv != lodrt::kNoIndex && lodrt::componentCount(pack.accessor(uv).type) == 2)
        out->has_uv = lodrt::readAccessorFloats(pack, uv, bin, uvs_.data() + 2 * size_t(out->first_vertex),
                                                2 * size_t(out->vertex_count), scratch, scratch_size) == lodrt::Result::Ok;
    return true;
}

// A LODBAKE_valence_compression stream: triangles, positions and the texture coordinates the
// stream codes (attribute ids 2 + their entry of the stream's attribute table).
bool LevelDecoder::decodeStream(const lodrt::PackSource& source, const lodrt::BinBytes& bin,
                                const lodrt::JsonValue& stream, DecodedPrimitive* out, uint32_t uv_set,
                                std::string* error) {
    const lodrt::Pack& pack = source.pack();
    const lodrt::PrimitiveInfo& prim = pack.primitive(out->primitive);
    const uint32_t view = jsonIndex(stream.find("bufferView"));
    if (view == lodrt::kNoIndex || view >= pack.bufferViewCount()) {
        *error = "LODBAKE_valence_compression: bufferView: expected the index of a buffer view";
        return false;
    }
    const lodrt::BufferViewInfo& info = pack.bufferView(view);
    if (!pack.buffer(info.buffer).is_glb_bin || info.byte_offset < bin.offset ||
        info.byte_offset - bin.offset > bin.size || info.byte_length > bin.size - (info.byte_offset - bin.offset)) {
        *error = "LODBAKE_valence_compression: buffer view " + std::to_string(view) +
                 " is not inside the level's streamed bytes";
        return false;
    }
    const uint8_t* data = bin.data + (info.byte_offset - bin.offset);
    const size_t size = size_t(info.byte_length);
    lodrt::ValenceInfo header;
    lodrt::Result r = lodrt::valenceReadInfo(data, size, &header);
    if (r != lodrt::Result::Ok) {
        *error = failure("LODBAKE_valence_compression: the stream header does not parse", r);
        return false;
    }
    if (header.vertex_count != prim.vertex_count || uint64_t(header.triangle_count) * 3 != prim.index_count) {
        *error = "LODBAKE_valence_compression: the stream decodes to " + std::to_string(header.vertex_count) +
                 " vertices and " + std::to_string(header.triangle_count) + " triangles, the accessors say " +
                 std::to_string(prim.vertex_count) + " and " + std::to_string(prim.index_count / 3);
        return false;
    }
    ensure(&scratch_, (lodrt::valenceScratchSize(header) + 7) / 8);
    lodrt::ValenceOutput output;
    output.indices = indices_.data() + out->first_index;
    output.index_capacity = out->index_count;
    output.positions = positions_.data() + 3 * size_t(out->first_vertex);
    output.position_capacity = 3 * size_t(out->vertex_count);
    output.scratch = scratch_.data();
    output.scratch_size = scratch_.size() * 8;
    // The texture coordinates: from the stream when it codes them, else from their accessor.
    const uint32_t uv_id = uv_set < 8 ? jsonIndex(stream.find("attributes").find(kTexCoordNames[uv_set])) : lodrt::kNoIndex;
    const uint32_t entry = uv_id >= 2 && uv_id != lodrt::kNoIndex ? uv_id - 2 : lodrt::kNoIndex;
    if (entry < header.attribute_count && header.attributes[entry].kind == lodrt::format::kValenceAttributeUv &&
        header.attributes[entry].components == 2) {
        output.attributes[entry] = uvs_.data() + 2 * size_t(out->first_vertex);
        output.attribute_capacity[entry] = 2 * size_t(out->vertex_count);
        out->has_uv = true;
    }
    r = lodrt::valenceDecode(data, size, output);
    if (r != lodrt::Result::Ok) {
        *error = failure("LODBAKE_valence_compression: the stream does not decode", r);
        return false;
    }
    const uint32_t* idx = indices_.data() + out->first_index;
    for (uint32_t i = 0; i < out->index_count; ++i)
        if (idx[i] >= out->vertex_count) {
            *error = "LODBAKE_valence_compression: a decoded index is out of range";
            return false;
        }
    const uint32_t uv = uv_set < 8 ? attributeAccessor(pack, prim, kTexCoordNames[uv_set]) : lodrt::kNoIndex;
    if (!out->has_uv && hasData(pack, uv) && lodrt::componentCount(pack.accessor(uv).type) == 2) {
        uint8_t* scratch = reinterpret_cast<uint8_t*>(scratch_.data());
        out->has_uv = lodrt::readAccessorFloats(pack, uv, bin, uvs_.data() + 2 * size_t(out->first_vertex),
                                                2 * size_t(out->vertex_count), scratch,
                                                scratch_.size() * 8) == lodrt::Result::Ok;
    }
    return true;
}

bool LevelDecoder::decode(const lodrt::PackSource& source, uint32_t model, uint32_t level, const uint8_t* bytes,
                          size_t size, std::string* error) {
    const lodrt::Pack& pack = source.pack();
    const lodrt::LevelInfo& info = source.models().modelLevel(model, level);
    const lodrt::MeshInfo& mesh = pack.mesh(info.mesh);
    const lodrt::BinBytes bin{bytes, info.data_offset, size};
    primitives_.clear();
    vertex_count_ = index_count_ = 0;
    for (uint32_t p = 0; p < mesh.primitive_count; ++p) {
        const lodrt::PrimitiveInfo& prim = pack.primitive(mesh.first_primitive + p);
        if (prim.mode != 4) continue;
        DecodedPrimitive out;
        out.primitive = mesh.first_primitive + p;
        out.first_vertex = vertex_count_;
        out.vertex_count = uint32_t(prim.vertex_count);
        out.first_index = index_count_;
        out.index_count = uint32_t(prim.index_count);
        vertex_count_ += out.vertex_count;
        index_count_ += out.index_count;
        ensure(&positions_, 3 * size_t(vertex_count_));
        ensure(&uvs_, 2 * size_t(vertex_count_));
        ensure(&indices_, size_t(index_count_));
        uint32_t uv_set = lodrt::kNoIndex;
        if (prim.material != lodrt::kNoIndex) out.image_view = baseColourImageView(pack, prim.material, &uv_set);
        // A stream is decoded only when it replaces the accessors' data (--compact): beside plain
        // data it says the same thing at a coarser quantization.
        const lodrt::JsonValue stream = prim.json.find("extensions").find(lodrt::format::kExtValenceCompression);
        const uint32_t position = attributeAccessor(pack, prim, "POSITION");
        out.from_stream = stream.isObject() && (!hasData(pack, position) ||
                                                (prim.indices != lodrt::kNoIndex && !hasData(pack, prim.indices)));
        const bool ok = out.from_stream ? decodeStream(source, bin, stream, &out, uv_set, error)
                                        : decodeAccessors(source, bin, &out, uv_set, error);
        if (!ok) {
            *error = "primitive " + std::to_string(p) + ": " + *error;
            return false;
        }
        primitives_.push_back(out);
    }
    return true;
}

} // namespace lodview
