// The --web pack form (web_meshopt.h, docs/format/web.md): KHR_mesh_quantization attributes compressed
// with EXT_meshopt_compression through Debian's libmeshoptimizer encoders.
//
// Positions keep float components in object units, on a power-of-two grid stored through the
// EXPONENTIAL filter with one exponent per component: the mesh needs no dequantizing node transform,
// so LODBAKE_lod_metrics, MSFT_lod and every reader's bounds stay in the units the levels were measured
// in, and the codec sees constant exponent bytes and integer mantissas.
#include "pack/web_meshopt.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>

#include <meshoptimizer.h>

#include "io/gltf_model.h"
#include "lodrt/format.h"

namespace lodbake {

namespace {

namespace fmt = lodrt::format;

// Reads accessor `a` as floats (components per element), tightly packed.
Result<std::vector<float>> readFloats(const tinygltf::Model& model, const tinygltf::Accessor& a, size_t components,
                                      const std::vector<uint8_t>& bin) {
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT || a.bufferView < 0 || a.sparse.isSparse)
        return internalError("pack: --web: attribute accessor is not plain float data");
    const tinygltf::BufferView& view = model.bufferViews[size_t(a.bufferView)];
    const size_t element = components * sizeof(float);
    const size_t stride = view.byteStride ? view.byteStride : element;
    const size_t begin = view.byteOffset + a.byteOffset;
    if (a.count > 0 && begin + (a.count - 1) * stride + element > bin.size())
        return internalError("pack: --web: accessor outside the buffer");
    std::vector<float> out(a.count * components);
    for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i * components], &bin[begin + i * stride], element);
    return out;
}

Result<std::vector<uint32_t>> readIndices(const tinygltf::Model& model, const tinygltf::Accessor& a,
                                          const std::vector<uint8_t>& bin) {
    if (a.bufferView < 0 || a.sparse.isSparse) return internalError("pack: --web: index accessor without data");
    const size_t size = a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                        : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT ? 4
                                                                                  : 0;
    if (size == 0) return internalError("pack: --web: index accessor is neither u16 nor u32");
    const tinygltf::BufferView& view = model.bufferViews[size_t(a.bufferView)];
    const size_t begin = view.byteOffset + a.byteOffset;
    if (begin + a.count * size > bin.size()) return internalError("pack: --web: accessor outside the buffer");
    std::vector<uint32_t> out(a.count);
    for (size_t i = 0; i < a.count; ++i) {
        uint32_t v = 0;
        std::memcpy(&v, &bin[begin + i * size], size); // little-endian host, as the GLB
        out[i] = v;
    }
    return out;
}

// An ATTRIBUTES view of `count` elements of `stride` bytes, vertex-coded, with its filter.
WebViews::View attributeView(const void* data, size_t count, size_t stride, const char* filter) {
    WebViews::View v;
    v.bytes.resize(meshopt_encodeVertexBufferBound(count, stride));
    v.bytes.resize(meshopt_encodeVertexBuffer(v.bytes.data(), v.bytes.size(), data, count, stride));
    v.count = count;
    v.stride = uint32_t(stride);
    v.mode = fmt::kMeshoptModeAttributes;
    v.filter = filter;
    v.target = TINYGLTF_TARGET_ARRAY_BUFFER;
    return v;
}

// One 32-bit EXPONENTIAL filter value: exponent in the top byte, 24-bit two's complement mantissa.
uint32_t expValue(int exponent, int32_t mantissa) {
    return (uint32_t(uint8_t(int8_t(exponent))) << 24) | (uint32_t(mantissa) & 0xFFFFFFu);
}

WebViews::View encodePositions(tinygltf::Accessor& a, const std::vector<float>& xyz, double max_step) {
    const int e = webPositionExponent(xyz.data(), a.count, max_step);
    std::vector<uint32_t> words(xyz.size());
    std::vector<double> lo(3, 0.0), hi(3, 0.0);
    for (size_t i = 0; i < xyz.size(); ++i) {
        const auto m = int32_t(std::nearbyint(std::ldexp(double(xyz[i]), -e)));
        words[i] = expValue(e, m);
        const double v = std::ldexp(double(m), e); // exactly what a decoder produces
        const size_t c = i % 3;
        if (i < 3 || v < lo[c]) lo[c] = v;
        if (i < 3 || v > hi[c]) hi[c] = v;
    }
    a.minValues = lo;
    a.maxValues = hi;
    return attributeView(words.data(), a.count, 12, fmt::kMeshoptFilterExponential);
}

// Normals (3 components, w written 0) and tangents (4, w the handedness) as 8-bit octahedral vectors.
WebViews::View encodeOctahedral(tinygltf::Accessor& a, const std::vector<float>& values, size_t components) {
    std::vector<float> xyzw(a.count * 4, 0.0f);
    for (size_t i = 0; i < a.count; ++i)
        for (size_t c = 0; c < components; ++c) xyzw[i * 4 + c] = values[i * components + c];
    std::vector<int8_t> encoded(a.count * 4);
    meshopt_encodeFilterOct(encoded.data(), a.count, 4, int(fmt::kWebNormalBits), xyzw.data());
    a.componentType = TINYGLTF_COMPONENT_TYPE_BYTE;
    a.normalized = true;
    return attributeView(encoded.data(), a.count, 4, fmt::kMeshoptFilterOctahedral);
}

// Values in [0, 1] as unsigned 16-bit normalized integers (UVs, colours), padded to a 4-byte stride.
WebViews::View encodeUnorm16(tinygltf::Accessor& a, const std::vector<float>& values, size_t components) {
    const size_t stride = (components * 2 + 3) / 4 * 4;
    std::vector<uint16_t> out(a.count * stride / 2, 0);
    for (size_t i = 0; i < a.count; ++i)
        for (size_t c = 0; c < components; ++c)
            out[i * stride / 2 + c] = uint16_t(std::nearbyint(double(values[i * components + c]) * 65535.0));
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    a.normalized = true;
    return attributeView(out.data(), a.count, stride, fmt::kMeshoptFilterNone);
}

WebViews::View encodePlainFloats(const tinygltf::Accessor& a, const std::vector<float>& values, size_t components) {
    return attributeView(values.data(), a.count, components * 4, fmt::kMeshoptFilterNone);
}

bool inUnitRange(const std::vector<float>& values) {
    for (float f : values)
        if (!(f >= 0.0f && f <= 1.0f)) return false;
    return true;
}

Result<WebViews::View> encodeAttribute(const tinygltf::Model& model, const std::string& name, tinygltf::Accessor& a,
                                       const std::vector<uint8_t>& bin, double max_step) {
    const size_t components = size_t(componentCount(a.type));
    if (components == 0) return internalError("pack: --web: attribute " + name + " is not a vector");
    LODBAKE_ASSIGN_OR_RETURN(std::vector<float> values, readFloats(model, a, components, bin));
    if (name == "POSITION" && components == 3) return encodePositions(a, values, max_step);
    if ((name == "NORMAL" && components == 3) || (name == "TANGENT" && components == 4))
        return encodeOctahedral(a, values, components);
    const bool unorm = name.rfind("TEXCOORD_", 0) == 0 || name.rfind("COLOR_", 0) == 0;
    if (unorm && inUnitRange(values)) return encodeUnorm16(a, values, components);
    return encodePlainFloats(a, values, components);
}

WebViews::View encodeTriangles(const tinygltf::Accessor& a, const std::vector<uint32_t>& indices) {
    static std::once_flag version_once;
    // Index codec version 1 (decodable by every EXT_meshopt_compression reader); set once, as the
    // library keeps it in a global.
    std::call_once(version_once, [] { meshopt_encodeIndexVersion(1); });
    uint32_t vertices = 0;
    for (uint32_t i : indices) vertices = std::max(vertices, i + 1);
    WebViews::View v;
    v.bytes.resize(meshopt_encodeIndexBufferBound(indices.size(), vertices));
    v.bytes.resize(meshopt_encodeIndexBuffer(v.bytes.data(), v.bytes.size(), indices.data(), indices.size()));
    v.count = a.count;
    v.stride = a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2 : 4;
    v.mode = fmt::kMeshoptModeTriangles;
    v.filter = nullptr;
    v.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
    return v;
}

} // namespace

Mesh webLevelOrder(const Mesh& mesh) {
    Mesh out = mesh;
    const size_t n = mesh.vertexCount();
    if (mesh.submeshes.empty()) {
        meshopt_optimizeVertexCacheStrip(out.indices.data(), mesh.indices.data(), mesh.indices.size(), n);
    } else {
        for (const SubMesh& s : mesh.submeshes)
            if (s.index_count > 0)
                meshopt_optimizeVertexCacheStrip(out.indices.data() + s.first_index,
                                                 mesh.indices.data() + s.first_index, s.index_count, n);
    }
    std::vector<unsigned int> remap(n);
    const size_t used = meshopt_optimizeVertexFetchRemap(remap.data(), out.indices.data(), out.indices.size(), n);
    for (uint32_t& i : out.indices) i = remap[i];
    auto apply = [&](auto& stream) {
        if (stream.size() != n) return;
        auto source = stream;
        stream.resize(used);
        for (size_t v = 0; v < n; ++v)
            if (remap[v] != ~0u) stream[remap[v]] = source[v];
    };
    apply(out.positions);
    apply(out.normals);
    apply(out.tangents);
    apply(out.colors);
    for (auto& set : out.uvs) apply(set);
    return out;
}

int webPositionExponent(const float* xyz, size_t count, double max_step) {
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0}, largest = 0;
    for (size_t i = 0; i < count; ++i)
        for (size_t c = 0; c < 3; ++c) {
            const double v = xyz[i * 3 + c];
            if (i == 0 || v < lo[c]) lo[c] = v;
            if (i == 0 || v > hi[c]) hi[c] = v;
            largest = std::max(largest, std::fabs(v));
        }
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    int e = -100;
    if (extent > 0) e = int(std::floor(std::log2(extent / double((1u << fmt::kWebPositionBits) - 1))));
    if (max_step > 0 && std::isfinite(max_step)) e = std::max(e, int(std::floor(std::log2(max_step))));
    // |mantissa| < 2^23 for every coordinate (the 24-bit two's complement field).
    while (e < 100 && std::ldexp(largest, -e) >= double(1 << 23) - 1) ++e;
    return std::min(std::max(e, -100), 100);
}

Status encodeWebAccessors(tinygltf::Model& model, const std::vector<uint8_t>& bin, WebViews& out) {
    std::map<int, size_t> done; // accessor -> view
    auto record = [&](int accessor, WebViews::View view) {
        view.accessors.push_back(accessor);
        done[accessor] = out.views.size();
        out.views.push_back(std::move(view));
    };
    for (size_t m = 0; m < model.meshes.size(); ++m)
        for (tinygltf::Primitive& primitive : model.meshes[m].primitives) {
            const double max_step = m < out.mesh_position_step.size() ? out.mesh_position_step[m] : 0.0;
            for (const auto& [name, index] : primitive.attributes) {
                if (index < 0 || done.count(index)) continue;
                tinygltf::Accessor& a = model.accessors[size_t(index)];
                LODBAKE_ASSIGN_OR_RETURN(WebViews::View view, encodeAttribute(model, name, a, bin, max_step));
                if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) out.quantized = true;
                record(index, std::move(view));
            }
            if (primitive.indices < 0 || done.count(primitive.indices)) continue;
            tinygltf::Accessor& a = model.accessors[size_t(primitive.indices)];
            if (primitive.mode != TINYGLTF_MODE_TRIANGLES || a.count % 3 != 0)
                return internalError("pack: --web: a primitive is not a triangle list");
            LODBAKE_ASSIGN_OR_RETURN(std::vector<uint32_t> indices, readIndices(model, a, bin));
            record(primitive.indices, encodeTriangles(a, indices));
        }
    for (const auto& [accessor, view] : done) {
        model.accessors[size_t(accessor)].bufferView = -1;
        model.accessors[size_t(accessor)].byteOffset = 0;
    }
    return Status::okStatus();
}

void appendWebViews(tinygltf::Model& model, std::vector<uint8_t>& bin, WebViews& views) {
    uint64_t fallback = 0;
    views.extension_json.clear();
    for (const WebViews::View& v : views.views) {
        while (bin.size() % 4 != 0) bin.push_back(0);
        // Sorted keys, as the rest of the pack's JSON.
        std::string ext = "{\"buffer\":0,\"byteLength\":" + std::to_string(v.bytes.size()) +
                          ",\"byteOffset\":" + std::to_string(bin.size()) +
                          ",\"byteStride\":" + std::to_string(v.stride) + ",\"count\":" + std::to_string(v.count);
        if (v.filter && std::strcmp(v.filter, fmt::kMeshoptFilterNone) != 0)
            ext += ",\"filter\":\"" + std::string(v.filter) + "\"";
        ext += ",\"mode\":\"" + std::string(v.mode) + "\"}";
        views.extension_json.push_back(std::move(ext));
        bin.insert(bin.end(), v.bytes.begin(), v.bytes.end());

        tinygltf::BufferView view;
        view.buffer = 1;
        view.byteOffset = fallback;
        view.byteLength = v.count * v.stride;
        if (v.target == TINYGLTF_TARGET_ARRAY_BUFFER) view.byteStride = v.stride;
        view.target = v.target;
        // tinygltf does not write bufferView extensions: a marker name holds the place of the
        // extension object, which webPatchJson puts into the JSON text.
        view.name = "\x01meshopt" + std::to_string(views.extension_json.size() - 1);
        fallback += (view.byteLength + 3) / 4 * 4;
        model.bufferViews.push_back(std::move(view));
        for (int a : v.accessors) model.accessors[size_t(a)].bufferView = int(model.bufferViews.size() - 1);
    }
    while (bin.size() % 4 != 0) bin.push_back(0);
    views.fallback_bytes = fallback;
}

Status webPatchJson(std::string& json, const WebViews& views) {
    for (size_t i = 0; i < views.extension_json.size(); ++i) {
        const std::string marker = "\"name\":\"\\u0001meshopt" + std::to_string(i) + "\"";
        const size_t at = json.find(marker);
        if (at == std::string::npos || json.find(marker, at + 1) != std::string::npos)
            return internalError("pack: --web: the place of compressed view " + std::to_string(i) + " was not found");
        json.replace(at, marker.size(),
                     "\"extensions\":{\"" + std::string(fmt::kExtMeshoptCompression) + "\":" + views.extension_json[i] +
                         "}");
    }
    return Status::okStatus();
}

std::string webFallbackBufferJson(const WebViews& views) {
    return "{\"byteLength\":" + std::to_string(views.fallback_bytes) + ",\"extensions\":{\"" +
           std::string(fmt::kExtMeshoptCompression) + "\":{\"" + fmt::kMeshoptFallback + "\":true}}}";
}

} // namespace lodbake
