// glTF 2.0 / GLB export through tinygltf: one mesh, one primitive per sub-mesh, every stream in its
// own tightly packed buffer view, images embedded in the buffer. The output is made to pass the
// Khronos glTF-Validator without errors or warnings (exact min/max, unit normals and tangents,
// aligned views, no dangling texture coordinates).
#include "lodbake/io/gltf.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <exception>
#include <sstream>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "lodbake/version.h"
#include "io/gltf_model.h"

namespace lodbake {

namespace {

template <class T>
int addFloatAccessor(tinygltf::Model& model, BufferBuilder& buffer, const std::vector<T>& values, int components,
                     int type, bool with_bounds) {
    std::vector<float> flat;
    flat.reserve(values.size() * size_t(components));
    for (const T& v : values) {
        const float* f = &v.x;
        for (int c = 0; c < components; ++c) flat.push_back(f[c]);
    }
    tinygltf::Accessor accessor;
    accessor.bufferView = buffer.addView(flat.data(), flat.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    accessor.byteOffset = 0;
    accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    accessor.count = values.size();
    accessor.type = type;
    if (with_bounds) {
        accessor.minValues.assign(size_t(components), 0.0);
        accessor.maxValues.assign(size_t(components), 0.0);
        for (size_t i = 0; i < values.size(); ++i)
            for (int c = 0; c < components; ++c) {
                const double v = flat[i * size_t(components) + size_t(c)];
                if (i == 0 || v < accessor.minValues[size_t(c)]) accessor.minValues[size_t(c)] = v;
                if (i == 0 || v > accessor.maxValues[size_t(c)]) accessor.maxValues[size_t(c)] = v;
            }
    }
    model.accessors.push_back(std::move(accessor));
    return int(model.accessors.size() - 1);
}

std::string sniffMime(const std::vector<uint8_t>& b) {
    if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "image/png";
    if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "image/jpeg";
    return "";
}

bool finite3(const Vec3f& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Unit normals for the validator: non-unit ones are renormalised; zero or non-finite ones are
// replaced by the area-weighted normal of the faces around the vertex (or +Z for isolated vertices).
std::vector<Vec3f> exportNormals(const Mesh& mesh) {
    std::vector<Vec3f> normals = mesh.normals;
    std::vector<bool> bad(normals.size(), false);
    bool any_bad = false;
    for (size_t i = 0; i < normals.size(); ++i) {
        const Vec3f& n = normals[i];
        const double len = std::sqrt(double(n.x) * n.x + double(n.y) * n.y + double(n.z) * n.z);
        if (!finite3(n) || !(len > 1e-12)) {
            bad[i] = true;
            any_bad = true;
        } else {
            normals[i] = Vec3f(float(n.x / len), float(n.y / len), float(n.z / len));
        }
    }
    if (any_bad) {
        std::vector<Vec3d> sum(normals.size(), Vec3d(0.0, 0.0, 0.0));
        for (size_t f = 0; f < mesh.faceCount(); ++f) {
            const uint32_t a = mesh.indices[f * 3], b = mesh.indices[f * 3 + 1], c = mesh.indices[f * 3 + 2];
            const Vec3d n = cross(toDouble(mesh.positions[b]) - toDouble(mesh.positions[a]),
                                  toDouble(mesh.positions[c]) - toDouble(mesh.positions[a]));
            for (uint32_t v : {a, b, c})
                if (bad[v]) sum[v] = sum[v] + n;
        }
        for (size_t i = 0; i < normals.size(); ++i) {
            if (!bad[i]) continue;
            const double len = length(sum[i]);
            normals[i] = len > 0.0 ? Vec3f(float(sum[i].x / len), float(sum[i].y / len), float(sum[i].z / len))
                                   : Vec3f(0.0f, 0.0f, 1.0f);
        }
    }
    // float rounding after division can leave |n| a few ulps off 1; the validator allows 0.0005.
    return normals;
}

std::vector<Vec4f> exportTangents(const Mesh& mesh, const std::vector<Vec3f>& normals) {
    std::vector<Vec4f> tangents = mesh.tangents;
    for (size_t i = 0; i < tangents.size(); ++i) {
        Vec4f& t = tangents[i];
        const double len = std::sqrt(double(t.x) * t.x + double(t.y) * t.y + double(t.z) * t.z);
        const float w = t.w < 0.0f ? -1.0f : 1.0f;
        if (std::isfinite(len) && len > 1e-12) {
            t = Vec4f(float(t.x / len), float(t.y / len), float(t.z / len), w);
        } else {
            // Any unit vector perpendicular to the normal.
            const Vec3f n = normals[i];
            const Vec3d axis = std::fabs(n.x) < 0.9f ? Vec3d(1.0, 0.0, 0.0) : Vec3d(0.0, 1.0, 0.0);
            const Vec3d p = normalize(cross(toDouble(n), axis));
            t = Vec4f(float(p.x), float(p.y), float(p.z), w);
        }
    }
    return tangents;
}

// Refuses positions and texture coordinates a viewer cannot use.
Status checkExportable(const Mesh& mesh) {
    if (mesh.faceCount() == 0) return invalidInput("glTF export: the mesh has no triangles");
    for (size_t i = 0; i < mesh.positions.size(); ++i)
        if (!finite3(mesh.positions[i]))
            return invalidInput("glTF export: vertex " + std::to_string(i) + ": position is not finite");
    for (const auto& set : mesh.uvs)
        for (size_t i = 0; i < set.size(); ++i)
            if (!std::isfinite(set[i].x) || !std::isfinite(set[i].y))
                return invalidInput("glTF export: vertex " + std::to_string(i) + ": texture coordinate is not finite");
    return Status::okStatus();
}

// The vertex streams as written: unit normals and tangents, colours clamped to [0, 1].
struct ExportStreams {
    std::vector<Vec3f> normals;
    std::vector<Vec4f> tangents, colors;
};

ExportStreams exportStreams(const Mesh& mesh) {
    ExportStreams out;
    if (mesh.hasNormals()) {
        out.normals = exportNormals(mesh);
        if (mesh.hasTangents()) out.tangents = exportTangents(mesh, out.normals);
    }
    if (mesh.hasColors()) {
        out.colors = mesh.colors;
        for (Vec4f& c : out.colors)
            for (float* f : {&c.x, &c.y, &c.z, &c.w})
                *f = std::isfinite(*f) ? std::min(std::max(*f, 0.0f), 1.0f) : 0.0f;
    }
    return out;
}

// A primitive holding the attribute accessors of vertices [first, first + count).
tinygltf::Primitive addAttributes(tinygltf::Model& model, BufferBuilder& buffer, const Mesh& mesh,
                                  const ExportStreams& streams, size_t first, size_t count) {
    const bool whole = first == 0 && count == mesh.vertexCount();
    auto add = [&](const auto& values, int components, int type, bool with_bounds) {
        if (whole) return addFloatAccessor(model, buffer, values, components, type, with_bounds);
        const std::vector<typename std::decay_t<decltype(values)>::value_type> part(
            values.begin() + std::ptrdiff_t(first), values.begin() + std::ptrdiff_t(first + count));
        return addFloatAccessor(model, buffer, part, components, type, with_bounds);
    };
    tinygltf::Primitive primitive;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    primitive.attributes["POSITION"] = add(mesh.positions, 3, TINYGLTF_TYPE_VEC3, true);
    if (!streams.normals.empty()) {
        primitive.attributes["NORMAL"] = add(streams.normals, 3, TINYGLTF_TYPE_VEC3, false);
        if (!streams.tangents.empty())
            primitive.attributes["TANGENT"] = add(streams.tangents, 4, TINYGLTF_TYPE_VEC4, false);
    }
    for (size_t s = 0; s < mesh.uvs.size(); ++s)
        primitive.attributes["TEXCOORD_" + std::to_string(s)] = add(mesh.uvs[s], 2, TINYGLTF_TYPE_VEC2, false);
    if (!streams.colors.empty()) primitive.attributes["COLOR_0"] = add(streams.colors, 4, TINYGLTF_TYPE_VEC4, false);
    return primitive;
}

// Per non-empty sub-mesh with vertex ranges (else one for the whole mesh): its primitive's attributes
// in `bases`, and in `sub_first` the first vertex its indices are relative to.
Status addPrimitiveAttributes(tinygltf::Model& model, BufferBuilder& buffer, const Mesh& mesh,
                              const ExportStreams& streams, const std::vector<SubMesh>& submeshes,
                              const std::vector<std::pair<uint32_t, uint32_t>>* vertex_ranges,
                              std::vector<uint32_t>& sub_first, std::vector<tinygltf::Primitive>& bases) {
    sub_first.assign(submeshes.size(), 0);
    if (!vertex_ranges) {
        bases.push_back(addAttributes(model, buffer, mesh, streams, 0, mesh.vertexCount()));
        return Status::okStatus();
    }
    size_t p = 0;
    for (size_t s = 0; s < submeshes.size(); ++s) {
        if (submeshes[s].index_count == 0) continue;
        if (p >= vertex_ranges->size()) return internalError("glTF export: fewer vertex ranges than primitives");
        const auto [first, count] = (*vertex_ranges)[p++];
        if (size_t(first) + count > mesh.vertexCount())
            return internalError("glTF export: a primitive's vertex range exceeds the vertices");
        for (uint32_t i = submeshes[s].first_index; i < submeshes[s].first_index + submeshes[s].index_count; ++i)
            if (i >= mesh.indices.size() || mesh.indices[i] < first || mesh.indices[i] - first >= count)
                return internalError("glTF export: a primitive's index lies outside its vertex range");
        sub_first[s] = first;
        bases.push_back(addAttributes(model, buffer, mesh, streams, first, count));
    }
    if (p != vertex_ranges->size()) return internalError("glTF export: more vertex ranges than primitives");
    return Status::okStatus();
}

// Indices: one view for all sub-meshes (16-bit when the vertex count allows), each index relative to
// its sub-mesh's first vertex when there are vertex ranges. Returns the view.
int addIndexView(BufferBuilder& buffer, const Mesh& mesh, const std::vector<SubMesh>& submeshes,
                 const std::vector<uint32_t>& sub_first, bool with_ranges, bool short_indices) {
    const int index_size = short_indices ? 2 : 4;
    std::vector<uint8_t> index_bytes(mesh.indices.size() * size_t(index_size));
    std::vector<uint32_t> index_base(with_ranges ? mesh.indices.size() : 0, 0); // only with vertex ranges
    for (size_t s = 0; s < submeshes.size() && with_ranges; ++s)
        for (size_t i = submeshes[s].first_index;
             i < size_t(submeshes[s].first_index) + submeshes[s].index_count && i < mesh.indices.size(); ++i)
            index_base[i] = sub_first[s];
    for (size_t i = 0; i < mesh.indices.size(); ++i) {
        const uint32_t index = mesh.indices[i] - (with_ranges ? index_base[i] : 0);
        if (short_indices) {
            const auto v = uint16_t(index);
            std::memcpy(&index_bytes[i * 2], &v, 2);
        } else {
            std::memcpy(&index_bytes[i * 4], &index, 4);
        }
    }
    return buffer.addView(index_bytes.data(), index_bytes.size(), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
}

// Textures with bytes a viewer can decode, and those kept verbatim on request; others are dropped (and
// the slots using them). Returns the model texture of each mesh texture (-1: dropped); with `dedupe`,
// equal bytes share one texture.
std::vector<int> addTextures(tinygltf::Model& model, BufferBuilder& buffer, const Mesh& mesh, ModelDedupe* dedupe) {
    std::vector<int> texture_map(mesh.textures.size(), -1);
    for (size_t t = 0; t < mesh.textures.size(); ++t) {
        const Texture& texture = mesh.textures[t];
        std::string mime = sniffMime(texture.bytes);
        if (mime.empty() && texture.is_verbatim && !texture.bytes.empty())
            mime = texture.mime_type.empty() ? "application/octet-stream" : texture.mime_type;
        if (mime.empty()) continue;
        if (dedupe) {
            const auto found = dedupe->textures.find(texture.bytes);
            if (found != dedupe->textures.end()) {
                texture_map[t] = found->second;
                continue;
            }
        }
        tinygltf::Image image;
        image.name = texture.name;
        image.mimeType = mime;
        image.bufferView = buffer.addView(texture.bytes.data(), texture.bytes.size(), 0);
        model.images.push_back(std::move(image));
        tinygltf::Texture gtex;
        gtex.source = int(model.images.size() - 1);
        model.textures.push_back(std::move(gtex));
        texture_map[t] = int(model.textures.size() - 1);
        if (dedupe) dedupe->textures.emplace(texture.bytes, texture_map[t]);
    }
    return texture_map;
}

// A material as glTF has it, factors clamped to their valid ranges, slots on dropped textures or
// missing UV sets left unset.
tinygltf::Material exportMaterial(const Material& in, const Mesh& mesh, const std::vector<int>& texture_map) {
    auto slot = [&](const TextureSlot& s, int& index, int& texcoord) {
        if (!s.isSet() || size_t(s.texture) >= texture_map.size() || texture_map[size_t(s.texture)] < 0) return;
        if (s.texcoord >= mesh.uvs.size()) return;
        index = texture_map[size_t(s.texture)];
        texcoord = int(s.texcoord);
    };
    tinygltf::Material out;
    out.name = in.name;
    auto& pbr = out.pbrMetallicRoughness;
    pbr.baseColorFactor = {in.base_color_factor.x, in.base_color_factor.y, in.base_color_factor.z,
                           in.base_color_factor.w};
    for (double& f : pbr.baseColorFactor) f = std::isfinite(f) ? std::min(std::max(f, 0.0), 1.0) : 1.0;
    pbr.metallicFactor = std::min(std::max(double(in.metallic_factor), 0.0), 1.0);
    pbr.roughnessFactor = std::min(std::max(double(in.roughness_factor), 0.0), 1.0);
    slot(in.base_color_texture, pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord);
    slot(in.metallic_roughness_texture, pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord);
    slot(in.normal_texture, out.normalTexture.index, out.normalTexture.texCoord);
    out.normalTexture.scale = in.normal_scale;
    slot(in.occlusion_texture, out.occlusionTexture.index, out.occlusionTexture.texCoord);
    out.occlusionTexture.strength = std::min(std::max(double(in.occlusion_strength), 0.0), 1.0);
    slot(in.emissive_texture, out.emissiveTexture.index, out.emissiveTexture.texCoord);
    out.emissiveFactor = {in.emissive_factor.x, in.emissive_factor.y, in.emissive_factor.z};
    for (double& f : out.emissiveFactor) f = std::isfinite(f) ? std::min(std::max(f, 0.0), 1.0) : 0.0;
    switch (in.alpha_mode) {
    case AlphaMode::Opaque:
        out.alphaMode = "OPAQUE";
        break;
    case AlphaMode::Mask:
        out.alphaMode = "MASK";
        out.alphaCutoff = std::max(double(in.alpha_cutoff), 0.0);
        break;
    case AlphaMode::Blend:
        out.alphaMode = "BLEND";
        break;
    }
    out.doubleSided = in.is_double_sided;
    return out;
}

// Adds the mesh's materials; with `dedupe`, one equal to a material added since dedupe->first_material
// is reused. Returns the model material of each mesh material.
std::vector<int> addMaterials(tinygltf::Model& model, const Mesh& mesh, const std::vector<int>& texture_map,
                              const ModelDedupe* dedupe) {
    std::vector<int> material_map;
    for (const Material& in : mesh.materials) {
        tinygltf::Material out = exportMaterial(in, mesh, texture_map);
        int index = -1;
        if (dedupe)
            for (size_t m = dedupe->first_material; m < model.materials.size() && index < 0; ++m)
                if (model.materials[m] == out) index = int(m);
        if (index < 0) {
            model.materials.push_back(std::move(out));
            index = int(model.materials.size() - 1);
        }
        material_map.push_back(index);
    }
    return material_map;
}

} // namespace

Result<int> addMeshToModel(tinygltf::Model& model, BufferBuilder& buffer, const Mesh& mesh, ModelDedupe* dedupe,
                           const std::vector<std::pair<uint32_t, uint32_t>>* vertex_ranges) {
    LODBAKE_RETURN_IF_ERROR(checkExportable(mesh));
    const ExportStreams streams = exportStreams(mesh);
    std::vector<SubMesh> submeshes = mesh.submeshes;
    if (submeshes.empty()) {
        SubMesh all;
        all.index_count = uint32_t(mesh.indices.size());
        submeshes.push_back(all);
    }
    std::vector<uint32_t> sub_first;
    std::vector<tinygltf::Primitive> bases;
    LODBAKE_RETURN_IF_ERROR(
        addPrimitiveAttributes(model, buffer, mesh, streams, submeshes, vertex_ranges, sub_first, bases));
    const bool short_indices = mesh.vertexCount() < 65536;
    const int index_view = addIndexView(buffer, mesh, submeshes, sub_first, vertex_ranges != nullptr, short_indices);
    const std::vector<int> texture_map = addTextures(model, buffer, mesh, dedupe);
    const std::vector<int> material_map = addMaterials(model, mesh, texture_map, dedupe);

    // One primitive per non-empty sub-mesh, each with its own index accessor into the shared view.
    const size_t index_size = short_indices ? 2 : 4;
    tinygltf::Mesh gmesh;
    size_t primitive_index = 0;
    for (const SubMesh& sub : submeshes) {
        if (sub.index_count == 0) continue;
        tinygltf::Accessor accessor;
        accessor.bufferView = index_view;
        accessor.byteOffset = size_t(sub.first_index) * index_size;
        accessor.componentType =
            short_indices ? TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT : TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        accessor.count = sub.index_count;
        accessor.type = TINYGLTF_TYPE_SCALAR;
        model.accessors.push_back(std::move(accessor));
        tinygltf::Primitive primitive = bases[vertex_ranges ? primitive_index++ : 0];
        primitive.indices = int(model.accessors.size() - 1);
        if (sub.material.isValid() && sub.material.value < material_map.size())
            primitive.material = material_map[sub.material.value];
        gmesh.primitives.push_back(std::move(primitive));
    }
    if (gmesh.primitives.empty()) return invalidInput("glTF export: every sub-mesh is empty");
    model.meshes.push_back(std::move(gmesh));
    return int(model.meshes.size() - 1);
}

namespace {

Result<tinygltf::Model> buildModel(const Mesh& mesh, std::vector<uint8_t>& buffer_bytes) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = std::string("lodbake ") + kVersionString;
    BufferBuilder buffer(model);
    LODBAKE_RETURN_IF_ERROR(addMeshToModel(model, buffer, mesh, nullptr, nullptr).status());

    tinygltf::Node node;
    node.mesh = 0;
    model.nodes.push_back(std::move(node));
    tinygltf::Scene scene;
    scene.nodes.push_back(0);
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;

    buffer_bytes = buffer.finish();
    tinygltf::Buffer gbuffer;
    gbuffer.data = buffer_bytes;
    model.buffers.push_back(std::move(gbuffer));
    return model;
}

// URIs are percent-encoded: "my mesh.bin" is written as "my%20mesh.bin".
std::string percentEncode(const std::string& name) {
    static const char* kHex = "0123456789ABCDEF";
    std::string out;
    for (char ch : name) {
        const auto c = static_cast<unsigned char>(ch);
        if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~' || c == '/') {
            out.push_back(ch);
        } else {
            out.push_back('%');
            out.push_back(kHex[c >> 4]);
            out.push_back(kHex[c & 15]);
        }
    }
    return out;
}

Result<GltfFiles> writeImpl(const Mesh& mesh, const GltfWriteOptions& options) {
    std::vector<uint8_t> buffer_bytes;
    LODBAKE_ASSIGN_OR_RETURN(tinygltf::Model model, buildModel(mesh, buffer_bytes));
    tinygltf::TinyGLTF writer;
    std::ostringstream stream;
    GltfFiles files;
    if (options.binary) {
        if (!writer.WriteGltfSceneToStream(&model, stream, false, true))
            return internalError("glTF export: tinygltf failed");
        const std::string s = stream.str();
        files.main.assign(s.begin(), s.end());
        return files;
    }
    if (options.bin_name.empty()) return invalidInput("glTF export: .gltf output needs a side buffer name");
    model.buffers[0].data.clear();
    model.buffers[0].uri = percentEncode(options.bin_name);
    if (!writer.WriteGltfSceneToStream(&model, stream, true, false))
        return internalError("glTF export: tinygltf failed");
    // tinygltf embeds buffers when writing to a stream; point the buffer at the side file instead.
    nlohmann::json json = nlohmann::json::parse(stream.str());
    json["buffers"] =
        nlohmann::json::array({{{"byteLength", buffer_bytes.size()}, {"uri", percentEncode(options.bin_name)}}});
    const std::string text = json.dump(2) + "\n";
    files.main.assign(text.begin(), text.end());
    files.bin = std::move(buffer_bytes);
    return files;
}

} // namespace

Result<GltfFiles> writeGltfToMemory(const Mesh& mesh, const GltfWriteOptions& options) {
    try {
        return writeImpl(mesh, options);
    } catch (const std::exception& e) {
        return internalError(std::string("glTF export failed: ") + e.what());
    }
}

} // namespace lodbake
