// glTF 2.0 / GLB import: container and reference checks, tinygltf parsing (images kept encoded),
// accessor decoding with full bounds checks, KHR_mesh_quantization, KHR_draco_mesh_compression,
// and scene flattening with node transforms applied, or the scene kept as a graph of meshes read once.
#include "lodbake/io/gltf.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <exception>
#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "io/draco_decode.h"
#include "io/gltf_meshopt.h"
#include "io/gltf_model.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/json_limits.h"
#include "lodrt/format.h"


namespace lodbake {

namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A; // "JSON"
constexpr uint32_t kChunkBin = 0x004E4942;  // "BIN\0"
constexpr const char* kDracoExtension = lodrt::format::kExtKhrDracoMeshCompression;
constexpr uint64_t kMaxViewlessCount = uint64_t(1) << 20; // elements of an accessor without a bufferView
constexpr uint64_t kMaxDracoPointsPerByte = 32; // real meshes need well over 2 bits of Draco data per point

uint32_t readU32(const uint8_t* p) {
    return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}

// Checks the GLB container (header and chunk table) before tinygltf reads it.
Status checkGlbContainer(const uint8_t* data, size_t size, const std::string& name, const uint8_t** json,
                         size_t* json_size) {
    if (size < 12) return invalidInput(name + ": GLB header: expected 12 bytes, the file has " + std::to_string(size));
    if (readU32(data) != kGlbMagic) return invalidInput(name + ": GLB header: bad magic, expected \"glTF\"");
    const uint32_t version = readU32(data + 4);
    if (version != 2) return invalidInput(name + ": GLB header: version " + std::to_string(version) + ", expected 2");
    const uint32_t total = readU32(data + 8);
    if (total != size)
        return invalidInput(name + ": GLB header: length field says " + std::to_string(total) +
                            " bytes but the file has " + std::to_string(size));
    size_t offset = 12;
    int chunk_index = 0;
    while (offset < size) {
        if (size - offset < 8)
            return invalidInput(name + ": GLB chunk " + std::to_string(chunk_index) + ": truncated chunk header");
        const uint32_t length = readU32(data + offset);
        const uint32_t type = readU32(data + offset + 4);
        if (uint64_t(length) > size - offset - 8)
            return invalidInput(name + ": GLB chunk " + std::to_string(chunk_index) + ": length " +
                                std::to_string(length) + " runs past the end of the file (" +
                                std::to_string(size - offset - 8) + " bytes left)");
        if (chunk_index == 0) {
            if (type != kChunkJson) return invalidInput(name + ": GLB chunk 0: expected the JSON chunk first");
            *json = data + offset + 8;
            *json_size = length;
        } else if (chunk_index == 1 && type != kChunkBin) {
            // Unknown chunks after JSON are allowed and ignored; only BIN must come second if present.
        }
        offset += 8 + size_t(length);
        ++chunk_index;
    }
    if (chunk_index == 0) return invalidInput(name + ": GLB: no JSON chunk");
    return Status::okStatus();
}

// What the JSON pre-pass found. tinygltf 2.7 (built without Draco) refuses an `indices` accessor
// without a buffer view, which is how KHR_draco_mesh_compression primitives declare them, so those
// are taken out of the JSON before tinygltf sees it and remembered here.
struct JsonPrepass {
    bool is_changed = false;
    std::string json_text;                                  // the rewritten JSON when is_changed
    std::map<std::pair<size_t, size_t>, int> draco_indices; // (mesh, primitive) -> indices accessor
};

// Checks the references tinygltf follows while loading (buffer views of buffers and images), so that
// a hostile file cannot make it read outside its buffers.
Status checkJsonReferences(const uint8_t* json_bytes, size_t json_size, const std::string& name, JsonPrepass& prepass) {
    nlohmann::json root;
    try {
        root = nlohmann::json::parse(json_bytes, json_bytes + json_size);
    } catch (const std::exception& e) {
        std::string what = e.what();
        for (char& c : what)
            if (c == '\n' || c == '\r') c = ' ';
        return invalidInput(name + ": JSON: syntax error: " + what);
    }
    if (!root.is_object()) return invalidInput(name + ": JSON: expected an object at the top level");
    auto arrayOf = [&](const char* key) -> const nlohmann::json* {
        auto it = root.find(key);
        if (it == root.end()) return nullptr;
        return &*it;
    };
    const nlohmann::json* buffers = arrayOf("buffers");
    const nlohmann::json* views = arrayOf("bufferViews");
    const nlohmann::json* images = arrayOf("images");
    for (const auto* a : {buffers, views, images})
        if (a != nullptr && !a->is_array())
            return invalidInput(name + ": JSON: buffers, bufferViews and images must be arrays");
    const size_t buffer_count = buffers ? buffers->size() : 0;
    const size_t view_count = views ? views->size() : 0;
    for (size_t i = 0; i < view_count; ++i) {
        const nlohmann::json& v = (*views)[i];
        const std::string where = name + ": bufferView " + std::to_string(i);
        if (!v.is_object()) return invalidInput(where + ": expected an object");
        auto b = v.find("buffer");
        if (b == v.end() || !b->is_number_unsigned() || b->get<uint64_t>() >= buffer_count)
            return invalidInput(where + ": buffer: expected an index below " + std::to_string(buffer_count));
        const nlohmann::json& buffer = (*buffers)[b->get<size_t>()];
        uint64_t declared = 0;
        if (buffer.is_object() && buffer.contains("byteLength") && buffer["byteLength"].is_number_unsigned())
            declared = buffer["byteLength"].get<uint64_t>();
        uint64_t offset = 0, length = 0;
        if (v.contains("byteOffset")) {
            if (!v["byteOffset"].is_number_unsigned())
                return invalidInput(where + ": byteOffset: expected a non-negative integer");
            offset = v["byteOffset"].get<uint64_t>();
        }
        if (!v.contains("byteLength") || !v["byteLength"].is_number_unsigned())
            return invalidInput(where + ": byteLength: expected a non-negative integer");
        length = v["byteLength"].get<uint64_t>();
        if (offset > declared || length > declared - offset)
            return invalidInput(where + ": bytes " + std::to_string(offset) + ".." + std::to_string(offset + length) +
                                " run past the end of buffer " + std::to_string(b->get<size_t>()) + " (" +
                                std::to_string(declared) + " bytes)");
    }
    const size_t image_count = images ? images->size() : 0;
    for (size_t i = 0; i < image_count; ++i) {
        const nlohmann::json& im = (*images)[i];
        if (!im.is_object()) return invalidInput(name + ": image " + std::to_string(i) + ": expected an object");
        auto bv = im.find("bufferView");
        if (bv != im.end() && (!bv->is_number_unsigned() || bv->get<uint64_t>() >= view_count))
            return invalidInput(name + ": image " + std::to_string(i) + ": bufferView: expected an index below " +
                                std::to_string(view_count));
    }
    auto meshes = root.find("meshes");
    if (meshes != root.end() && meshes->is_array()) {
        for (size_t m = 0; m < meshes->size(); ++m) {
            nlohmann::json& mesh = (*meshes)[m];
            if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
            nlohmann::json& primitives = mesh["primitives"];
            for (size_t p = 0; p < primitives.size(); ++p) {
                nlohmann::json& primitive = primitives[p];
                if (!primitive.is_object() || !primitive.contains("extensions") ||
                    !primitive["extensions"].is_object() || !primitive["extensions"].contains(kDracoExtension) ||
                    !primitive.contains("indices"))
                    continue;
                if (!primitive["indices"].is_number_unsigned())
                    return invalidInput(name + ": mesh " + std::to_string(m) + " primitive " + std::to_string(p) +
                                        ": indices: expected an accessor index");
                prepass.draco_indices[{m, p}] = primitive["indices"].get<int>();
                primitive.erase("indices");
                prepass.is_changed = true;
            }
        }
    }
    replaceMeshoptFallbacks(root, prepass.is_changed);
    if (prepass.is_changed) prepass.json_text = root.dump();
    return Status::okStatus();
}

// A GLB with its JSON chunk replaced (other chunks copied as they are).
std::vector<uint8_t> replaceGlbJson(const uint8_t* data, size_t size, size_t old_json_size, std::string json) {
    while (json.size() % 4 != 0) json.push_back(' ');
    const size_t rest_offset = 12 + 8 + old_json_size;
    const size_t rest = size > rest_offset ? size - rest_offset : 0;
    std::vector<uint8_t> out;
    auto put32 = [&](uint32_t v) {
        for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
    };
    put32(kGlbMagic);
    put32(2);
    put32(uint32_t(12 + 8 + json.size() + rest));
    put32(uint32_t(json.size()));
    put32(kChunkJson);
    out.insert(out.end(), json.begin(), json.end());
    out.insert(out.end(), data + rest_offset, data + rest_offset + rest);
    return out;
}

// tinygltf callbacks: external files go through the SideFileLoader, images stay encoded.
struct LoaderContext {
    const SideFileLoader* load_side_file = nullptr;
    std::string base_dir; // folder of the glTF file ("" for the current folder)
};

// URIs are percent-encoded ("my%20texture.png"); files are not.
std::string percentDecode(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            out.push_back(char(std::stoi(uri.substr(i + 1, 2), nullptr, 16)));
            i += 2;
        } else {
            out.push_back(uri[i]);
        }
    }
    return out;
}

bool fileExists(const std::string&, void*) {
    return true;
}
std::string expandFilePath(const std::string& path, void*) {
    return path;
}
bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
    auto* context = static_cast<LoaderContext*>(user);
    // tinygltf joins base_dir and the raw URI; decode the URI part and join it our way.
    std::string uri = path;
    if (!context->base_dir.empty() && uri.rfind(context->base_dir + "/", 0) == 0)
        uri = uri.substr(context->base_dir.size() + 1);
    Result<std::vector<uint8_t>> bytes = (*context->load_side_file)(joinPath(context->base_dir, percentDecode(uri)));
    if (!bytes.ok()) {
        if (err) *err += bytes.status().message() + "\n";
        return false;
    }
    *out = std::move(bytes).value();
    return true;
}
bool writeWholeFile(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing is not allowed while reading\n";
    return false;
}
bool keepEncodedImage(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
    // Images in buffer views are copied later with bounds checks; only URI images are kept here.
    if (image->bufferView < 0 && bytes != nullptr && size > 0) image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

std::string firstLine(const std::string& text) {
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string line = text.substr(start, end - start);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
        if (line.size() > 240) line = line.substr(0, 240) + "...";
        if (!line.empty()) return line;
        start = end + 1;
    }
    return "unknown error";
}

// ---- Accessors ----------------------------------------------------------------------------------

int componentSize(int component_type) {
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return 4;
    default:
        return 0;
    }
}

const char* typeName(int components) {
    switch (components) {
    case 1:
        return "SCALAR";
    case 2:
        return "VEC2";
    case 3:
        return "VEC3";
    case 4:
        return "VEC4";
    default:
        return "MAT";
    }
}

double readComponent(const uint8_t* p, int component_type, bool normalized) {
    switch (component_type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const double v = double(int8_t(p[0]));
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? p[0] / 255.0 : double(p[0]);
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        int16_t s;
        std::memcpy(&s, p, 2);
        return normalized ? std::max(s / 32767.0, -1.0) : double(s);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        uint16_t s;
        std::memcpy(&s, p, 2);
        return normalized ? s / 65535.0 : double(s);
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return double(readU32(p));
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float f;
        std::memcpy(&f, p, 4);
        return double(f);
    }
    default:
        return 0.0;
    }
}

struct AccessorData {
    int components = 0;
    int component_type = 0;
    bool normalized = false;
    size_t count = 0;
    std::vector<double> values; // count * components
};

// Bytes [offset, offset + length) of a buffer view, checked against its buffer.
Result<std::pair<const uint8_t*, size_t>> viewBytes(const tinygltf::Model& model, int view_index,
                                                    const std::string& where) {
    if (view_index < 0 || size_t(view_index) >= model.bufferViews.size())
        return invalidInput(where + ": bufferView " + std::to_string(view_index) + " does not exist (" +
                            std::to_string(model.bufferViews.size()) + " buffer views)");
    const tinygltf::BufferView& view = model.bufferViews[size_t(view_index)];
    if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size())
        return invalidInput(where + ": bufferView " + std::to_string(view_index) + ": buffer " +
                            std::to_string(view.buffer) + " does not exist");
    const std::vector<unsigned char>& data = model.buffers[size_t(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
        return invalidInput(where + ": bufferView " + std::to_string(view_index) + ": bytes " +
                            std::to_string(view.byteOffset) + ".." + std::to_string(view.byteOffset + view.byteLength) +
                            " run past the end of buffer " + std::to_string(view.buffer) + " (" +
                            std::to_string(data.size()) + " bytes)");
    return std::make_pair(data.data() + view.byteOffset, size_t(view.byteLength));
}

// Reads `count` elements of `element_size` bytes with `stride` from a buffer view at `offset`.
Status checkRange(size_t view_length, size_t offset, size_t count, size_t stride, size_t element_size,
                  const std::string& where) {
    if (count == 0) return Status::okStatus();
    const uint64_t last = uint64_t(offset) + uint64_t(count - 1) * stride + element_size;
    if (offset > view_length || last > view_length)
        return invalidInput(where + ": " + std::to_string(count) + " elements from byte offset " +
                            std::to_string(offset) + " need " + std::to_string(last) +
                            " bytes but the buffer view has " + std::to_string(view_length));
    return Status::okStatus();
}

Result<AccessorData> readAccessor(const tinygltf::Model& model, int index, const std::string& where_prefix,
                                  const ReadOptions& options) {
    const std::string where = where_prefix;
    if (index < 0 || size_t(index) >= model.accessors.size())
        return invalidInput(where + ": accessor does not exist (" + std::to_string(model.accessors.size()) +
                            " accessors)");
    const tinygltf::Accessor& accessor = model.accessors[size_t(index)];
    AccessorData out;
    out.component_type = accessor.componentType;
    out.components = componentCount(accessor.type);
    out.normalized = accessor.normalized;
    out.count = accessor.count;
    const int csize = componentSize(accessor.componentType);
    if (csize == 0)
        return invalidInput(where + ": componentType " + std::to_string(accessor.componentType) +
                            " is not a valid glTF component type");
    if (out.components == 0) return invalidInput(where + ": type " + std::to_string(accessor.type) + " is not valid");
    if (accessor.normalized && (accessor.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                                accessor.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
        return invalidInput(where + ": normalized is only allowed for byte and short components");
    if (accessor.count == 0) return invalidInput(where + ": count is 0, expected at least 1");
    if (accessor.count > options.max_vertex_count * 3 + 3)
        return resourceLimit(where + ": count " + std::to_string(accessor.count) + " exceeds the reader limit");
    const size_t element_size = size_t(csize) * size_t(out.components);

    if (accessor.bufferView >= 0) {
        LODBAKE_ASSIGN_OR_RETURN(auto view, viewBytes(model, accessor.bufferView, where));
        const tinygltf::BufferView& bv = model.bufferViews[size_t(accessor.bufferView)];
        size_t stride = element_size;
        if (bv.byteStride != 0) {
            if (bv.byteStride < element_size || bv.byteStride > 252)
                return invalidInput(where + ": bufferView " + std::to_string(accessor.bufferView) + ": byteStride " +
                                    std::to_string(bv.byteStride) + " is invalid for " + std::to_string(element_size) +
                                    "-byte elements");
            stride = bv.byteStride;
        }
        LODBAKE_RETURN_IF_ERROR(
            checkRange(view.second, accessor.byteOffset, accessor.count, stride, element_size, where));
        out.values.resize(accessor.count * size_t(out.components));
        for (size_t i = 0; i < accessor.count; ++i) {
            const uint8_t* p = view.first + accessor.byteOffset + i * stride;
            for (int c = 0; c < out.components; ++c)
                out.values[i * size_t(out.components) + size_t(c)] =
                    readComponent(p + size_t(c) * size_t(csize), accessor.componentType, accessor.normalized);
        }
    } else {
        // No bytes back such an accessor (zeros plus sparse values), so its count cannot be checked
        // against the file: allow what a sparse accessor plausibly needs, not the reader's limits.
        const uint64_t allowed =
            std::max<uint64_t>(kMaxViewlessCount, 64 * uint64_t(accessor.sparse.isSparse ? accessor.sparse.count : 0));
        if (accessor.count > allowed)
            return resourceLimit(where + ": count " + std::to_string(accessor.count) +
                                 " without a bufferView exceeds " + std::to_string(allowed) +
                                 " (the reader limit for accessors with no data)");
        out.values.assign(accessor.count * size_t(out.components), 0.0);
    }

    if (accessor.sparse.isSparse) {
        const auto& sparse = accessor.sparse;
        const std::string sw = where + ": sparse";
        if (sparse.count <= 0 || size_t(sparse.count) > accessor.count)
            return invalidInput(sw + ": count " + std::to_string(sparse.count) + " must be 1.." +
                                std::to_string(accessor.count));
        const int isize = componentSize(sparse.indices.componentType);
        if (sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            sparse.indices.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return invalidInput(sw + ": indices componentType " + std::to_string(sparse.indices.componentType) +
                                " is not an unsigned integer type");
        LODBAKE_ASSIGN_OR_RETURN(auto iview, viewBytes(model, sparse.indices.bufferView, sw + " indices"));
        LODBAKE_ASSIGN_OR_RETURN(auto vview, viewBytes(model, sparse.values.bufferView, sw + " values"));
        if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
            return invalidInput(sw + ": byteOffset must not be negative");
        LODBAKE_RETURN_IF_ERROR(checkRange(iview.second, size_t(sparse.indices.byteOffset), size_t(sparse.count),
                                           size_t(isize), size_t(isize), sw + " indices"));
        LODBAKE_RETURN_IF_ERROR(checkRange(vview.second, size_t(sparse.values.byteOffset), size_t(sparse.count),
                                           element_size, element_size, sw + " values"));
        int64_t previous = -1;
        for (size_t k = 0; k < size_t(sparse.count); ++k) {
            const auto target =
                int64_t(readComponent(iview.first + size_t(sparse.indices.byteOffset) + k * size_t(isize),
                                      sparse.indices.componentType, false));
            if (target <= previous || uint64_t(target) >= accessor.count)
                return invalidInput(sw + ": index " + std::to_string(k) + " (" + std::to_string(target) +
                                    ") must be increasing and below " + std::to_string(accessor.count));
            previous = target;
            const uint8_t* p = vview.first + size_t(sparse.values.byteOffset) + k * element_size;
            for (int c = 0; c < out.components; ++c)
                out.values[size_t(target) * size_t(out.components) + size_t(c)] =
                    readComponent(p + size_t(c) * size_t(csize), accessor.componentType, accessor.normalized);
        }
    }
    return out;
}

// ---- Transforms ---------------------------------------------------------------------------------

using Mat4 = std::array<double, 16>; // column-major, like glTF

Mat4 identity() {
    return {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
}

Mat4 multiply(const Mat4& a, const Mat4& b) {
    Mat4 r{};
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) {
            double s = 0.0;
            for (int k = 0; k < 4; ++k) s += a[size_t(k * 4 + row)] * b[size_t(c * 4 + k)];
            r[size_t(c * 4 + row)] = s;
        }
    return r;
}

Result<Mat4> localMatrix(const tinygltf::Node& node, const std::string& where) {
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16) return invalidInput(where + ": matrix: expected 16 numbers");
        Mat4 m;
        for (size_t i = 0; i < 16; ++i) {
            if (!std::isfinite(node.matrix[i])) return invalidInput(where + ": matrix: not finite");
            m[i] = node.matrix[i];
        }
        return m;
    }
    double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
    if (!node.translation.empty()) {
        if (node.translation.size() != 3) return invalidInput(where + ": translation: expected 3 numbers");
        for (size_t i = 0; i < 3; ++i) t[i] = node.translation[i];
    }
    if (!node.rotation.empty()) {
        if (node.rotation.size() != 4) return invalidInput(where + ": rotation: expected 4 numbers");
        for (size_t i = 0; i < 4; ++i) q[i] = node.rotation[i];
        const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(n > 0.0) || !std::isfinite(n)) return invalidInput(where + ": rotation: expected a unit quaternion");
        for (double& v : q) v /= n;
    }
    if (!node.scale.empty()) {
        if (node.scale.size() != 3) return invalidInput(where + ": scale: expected 3 numbers");
        for (size_t i = 0; i < 3; ++i) s[i] = node.scale[i];
    }
    for (double v : {t[0], t[1], t[2], s[0], s[1], s[2]})
        if (!std::isfinite(v)) return invalidInput(where + ": translation/scale: not finite");
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)}; // column-major
    Mat4 m{};
    for (int c = 0; c < 3; ++c)
        for (int row = 0; row < 3; ++row) m[size_t(c * 4 + row)] = r[c * 3 + row] * s[c];
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1.0;
    return m;
}

struct Instance {
    int mesh = -1;
    Mat4 world = identity();
};

Status collectInstances(const tinygltf::Model& model, const std::string& name, std::vector<Instance>& out) {
    if (model.scenes.empty()) {
        for (size_t m = 0; m < model.meshes.size(); ++m) out.push_back({int(m), identity()});
        return Status::okStatus();
    }
    const int scene_index = model.defaultScene >= 0 ? model.defaultScene : 0;
    if (size_t(scene_index) >= model.scenes.size())
        return invalidInput(name + ": scene: default scene " + std::to_string(scene_index) + " does not exist");
    struct Item {
        int node;
        Mat4 parent;
        size_t depth;
    };
    std::vector<Item> stack;
    const auto& roots = model.scenes[size_t(scene_index)].nodes;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, identity(), 0});
    size_t visits = 0;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const std::string where = name + ": node " + std::to_string(item.node);
        if (item.node < 0 || size_t(item.node) >= model.nodes.size())
            return invalidInput(where + ": does not exist (" + std::to_string(model.nodes.size()) + " nodes)");
        if (item.depth > model.nodes.size() || ++visits > 4 * model.nodes.size() + 16)
            return invalidInput(where + ": the node hierarchy has a cycle or a shared child");
        const tinygltf::Node& node = model.nodes[size_t(item.node)];
        LODBAKE_ASSIGN_OR_RETURN(Mat4 local, localMatrix(node, where));
        const Mat4 world = multiply(item.parent, local);
        if (node.mesh >= 0) {
            if (size_t(node.mesh) >= model.meshes.size())
                return invalidInput(where + ": mesh " + std::to_string(node.mesh) + " does not exist");
            out.push_back({node.mesh, world});
        }
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it)
            stack.push_back({*it, world, item.depth + 1});
    }
    return Status::okStatus();
}

// ---- Primitives ---------------------------------------------------------------------------------

struct PrimitiveData {
    std::vector<Vec3f> positions;
    std::vector<Vec3f> normals;
    std::vector<Vec4f> tangents;
    std::map<uint32_t, std::vector<Vec2f>> uvs;
    std::vector<Vec4f> colors;
    std::vector<uint32_t> indices;
    int material = -1;
    std::string name;
    int shares_vertices_of = -1; // index of an earlier part of the same instance with the same accessors
};

// A primitive attribute: accessor values (or Draco-decoded values) and how to describe it in errors.
struct AttributeSource {
    std::string semantic;
    int accessor = -1;
    AccessorData data;
};

Status checkAttributeFormat(const AttributeSource& a, const std::string& where, bool quantized) {
    const AccessorData& d = a.data;
    const std::string& s = a.semantic;
    auto expectComponents = [&](int n) -> Status {
        if (d.components != n)
            return invalidInput(where + ": expected " + typeName(n) + ", got " + typeName(d.components));
        return Status::okStatus();
    };
    const bool is_float = d.component_type == TINYGLTF_COMPONENT_TYPE_FLOAT;
    if (d.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return invalidInput(where + ": componentType 5125 (unsigned int) is not allowed for vertex attributes");
    if (s == "POSITION") {
        LODBAKE_RETURN_IF_ERROR(expectComponents(3));
        if (!is_float && !quantized)
            return invalidInput(where + ": integer positions need KHR_mesh_quantization in extensionsUsed");
    } else if (s == "NORMAL") {
        LODBAKE_RETURN_IF_ERROR(expectComponents(3));
        if (!is_float &&
            !(quantized && d.normalized &&
              (d.component_type == TINYGLTF_COMPONENT_TYPE_BYTE || d.component_type == TINYGLTF_COMPONENT_TYPE_SHORT)))
            return invalidInput(where + ": expected float (or normalized byte/short with KHR_mesh_quantization)");
    } else if (s == "TANGENT") {
        LODBAKE_RETURN_IF_ERROR(expectComponents(4));
        if (!is_float &&
            !(quantized && d.normalized &&
              (d.component_type == TINYGLTF_COMPONENT_TYPE_BYTE || d.component_type == TINYGLTF_COMPONENT_TYPE_SHORT)))
            return invalidInput(where + ": expected float (or normalized byte/short with KHR_mesh_quantization)");
    } else if (s.rfind("TEXCOORD_", 0) == 0) {
        LODBAKE_RETURN_IF_ERROR(expectComponents(2));
        const bool core_ok = is_float || (d.normalized && (d.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                                           d.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT));
        if (!core_ok && !quantized)
            return invalidInput(where + ": expected float or normalized unsigned byte/short components");
    } else if (s == "COLOR_0") {
        if (d.components != 3 && d.components != 4)
            return invalidInput(where + ": expected VEC3 or VEC4, got " + typeName(d.components));
        if (!is_float && !(d.normalized && (d.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                                            d.component_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)))
            return invalidInput(where + ": expected float or normalized unsigned byte/short components");
    }
    return Status::okStatus();
}

bool wantedSemantic(const std::string& s) {
    return s == "POSITION" || s == "NORMAL" || s == "TANGENT" || s == "COLOR_0" || s.rfind("TEXCOORD_", 0) == 0;
}

// Decodes the primitive's KHR_draco_mesh_compression data: one float AttributeSource per wanted
// semantic (recorded in `draco_ids`) and the decoded indices, after checking the declared counts.
Status readDracoAttributes(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                           const tinygltf::Value& ext, const std::string& where, const ReadOptions& options,
                           int draco_indices_accessor, std::vector<AttributeSource>& sources,
                           std::map<std::string, int>& draco_ids, std::vector<uint32_t>& draco_indices) {
    const std::string dw = where + ": " + kDracoExtension;
    if (!ext.IsObject() || !ext.Has("bufferView") || !ext.Get("bufferView").IsNumber() || !ext.Has("attributes") ||
        !ext.Get("attributes").IsObject())
        return invalidInput(dw + ": expected an object with bufferView and attributes");
    const int view = ext.Get("bufferView").GetNumberAsInt();
    const tinygltf::Value& attrs = ext.Get("attributes");
    std::vector<int> ids;
    std::vector<std::string> semantics;
    for (const std::string& key : attrs.Keys()) {
        const tinygltf::Value& id = attrs.Get(key);
        if (!id.IsNumber() || id.GetNumberAsInt() < 0) return invalidInput(dw + ": attributes." + key + ": expected an id");
        if (!wantedSemantic(key)) continue;
        if (primitive.attributes.count(key) == 0)
            return invalidInput(dw + ": attributes." + key + ": the primitive has no such attribute accessor");
        ids.push_back(id.GetNumberAsInt());
        semantics.push_back(key);
    }
    LODBAKE_ASSIGN_OR_RETURN(auto bytes, viewBytes(model, view, dw));
    // The declared counts must match what Draco decodes; refusing absurd ones before decoding
    // bounds what a small bitstream can make us allocate (decompression bombs).
    for (const std::string& semantic : semantics) {
        const int a = primitive.attributes.at(semantic);
        if (a < 0 || size_t(a) >= model.accessors.size()) continue; // reported after decoding
        const uint64_t count = model.accessors[size_t(a)].count;
        const uint64_t plausible = kMaxDracoPointsPerByte * uint64_t(bytes.second) + 64;
        if (count > options.max_vertex_count || count > plausible)
            return resourceLimit(dw + ": accessor " + std::to_string(a) + " (" + semantic + "): count " +
                                 std::to_string(count) + ", expected at most " +
                                 std::to_string(std::min<uint64_t>(options.max_vertex_count, plausible)) + " for " +
                                 std::to_string(bytes.second) + " bytes of Draco data");
    }
    LODBAKE_ASSIGN_OR_RETURN(gltf_detail::DracoMeshData decoded,
                             gltf_detail::decodeDracoMesh(bytes.first, bytes.second, ids, dw));
    for (size_t i = 0; i < semantics.size(); ++i) {
        const int accessor_index = primitive.attributes.at(semantics[i]);
        const std::string aw = where + ": accessor " + std::to_string(accessor_index) + " (" + semantics[i] + ")";
        if (accessor_index < 0 || size_t(accessor_index) >= model.accessors.size())
            return invalidInput(aw + ": accessor does not exist");
        const tinygltf::Accessor& accessor = model.accessors[size_t(accessor_index)];
        if (accessor.count != decoded.point_count)
            return invalidInput(aw + ": count " + std::to_string(accessor.count) + " but the Draco data has " +
                                std::to_string(decoded.point_count) + " points");
        AttributeSource src;
        src.semantic = semantics[i];
        src.accessor = accessor_index;
        src.data.components = componentCount(accessor.type);
        if (src.data.components != decoded.attributes[i].component_count)
            return invalidInput(aw + ": type " + typeName(src.data.components) + " but the Draco attribute has " +
                                std::to_string(decoded.attributes[i].component_count) + " components");
        src.data.component_type = TINYGLTF_COMPONENT_TYPE_FLOAT; // Draco dequantises to float
        src.data.count = decoded.point_count;
        src.data.values.assign(decoded.attributes[i].values.begin(), decoded.attributes[i].values.end());
        draco_ids[semantics[i]] = accessor_index;
        sources.push_back(std::move(src));
    }
    if (draco_indices_accessor >= 0) {
        if (size_t(draco_indices_accessor) >= model.accessors.size())
            return invalidInput(where + ": indices accessor " + std::to_string(draco_indices_accessor) +
                                " does not exist");
        const size_t declared = model.accessors[size_t(draco_indices_accessor)].count;
        if (declared != decoded.indices.size())
            return invalidInput(where + ": accessor " + std::to_string(draco_indices_accessor) +
                                " (indices): count " + std::to_string(declared) + " but the Draco data has " +
                                std::to_string(decoded.indices.size()) + " indices");
    }
    draco_indices = std::move(decoded.indices);
    return Status::okStatus();
}

// Checks each attribute's format and count and stores its values in `out`; returns the vertex count.
// POSITION is checked first, so that its problems are the ones reported.
Result<size_t> storeAttributes(std::vector<AttributeSource>& sources, const std::map<std::string, int>& draco_ids,
                               const std::string& where, bool quantized, const ReadOptions& options,
                               PrimitiveData& out) {
    std::stable_partition(sources.begin(), sources.end(),
                          [](const AttributeSource& a) { return a.semantic == "POSITION"; });
    const AttributeSource* position = nullptr;
    for (const auto& s : sources)
        if (s.semantic == "POSITION") position = &s;
    const size_t vertex_count = position->data.count;
    if (vertex_count > options.max_vertex_count)
        return resourceLimit(where + ": " + std::to_string(vertex_count) + " vertices exceed the reader limit");
    for (const auto& s : sources) {
        const std::string aw = where + ": accessor " + std::to_string(s.accessor) + " (" + s.semantic + ")";
        LODBAKE_RETURN_IF_ERROR(checkAttributeFormat(s, aw, quantized || draco_ids.count(s.semantic) > 0));
        if (s.data.count != vertex_count)
            return invalidInput(aw + ": count " + std::to_string(s.data.count) + " differs from POSITION count " +
                                std::to_string(vertex_count));
        const std::vector<double>& v = s.data.values;
        if (s.semantic == "POSITION") {
            out.positions.resize(vertex_count);
            for (size_t i = 0; i < vertex_count; ++i) {
                // static_cast: "p(float(v[i * 3]), ...)" parses as a function declaration (Clang).
                const Vec3f p(static_cast<float>(v[i * 3]), static_cast<float>(v[i * 3 + 1]),
                              static_cast<float>(v[i * 3 + 2]));
                if (!isFinite(p) || !std::isfinite(v[i * 3]) || !std::isfinite(v[i * 3 + 1]) ||
                    !std::isfinite(v[i * 3 + 2]))
                    return invalidInput(aw + ": vertex " + std::to_string(i) + " is not finite (NaN or Inf)");
                out.positions[i] = p;
            }
        } else if (s.semantic == "NORMAL") {
            out.normals.resize(vertex_count);
            for (size_t i = 0; i < vertex_count; ++i)
                out.normals[i] = Vec3f(float(v[i * 3]), float(v[i * 3 + 1]), float(v[i * 3 + 2]));
        } else if (s.semantic == "TANGENT") {
            out.tangents.resize(vertex_count);
            for (size_t i = 0; i < vertex_count; ++i)
                out.tangents[i] =
                    Vec4f(float(v[i * 4]), float(v[i * 4 + 1]), float(v[i * 4 + 2]), v[i * 4 + 3] < 0 ? -1.0f : 1.0f);
        } else if (s.semantic == "COLOR_0") {
            out.colors.resize(vertex_count);
            const size_t n = size_t(s.data.components);
            for (size_t i = 0; i < vertex_count; ++i)
                out.colors[i] = Vec4f(float(v[i * n]), float(v[i * n + 1]), float(v[i * n + 2]),
                                      n == 4 ? float(v[i * n + 3]) : 1.0f);
        } else {
            const std::string digits = s.semantic.substr(9);
            if (digits.empty() || digits.size() > 2 || digits.find_first_not_of("0123456789") != std::string::npos)
                continue;
            const uint32_t set = uint32_t(std::stoul(digits));
            std::vector<Vec2f>& uv = out.uvs[set];
            uv.resize(vertex_count);
            for (size_t i = 0; i < vertex_count; ++i) uv[i] = Vec2f(float(v[i * 2]), float(v[i * 2 + 1]));
        }
    }
    for (const auto& n : out.normals)
        if (!std::isfinite(n.x) || !std::isfinite(n.y) || !std::isfinite(n.z))
            return invalidInput(where + ": NORMAL: a normal is not finite");
    return vertex_count;
}

// The primitive's index list as stored: from its accessor, or 0..vertex_count-1 without one.
Result<std::vector<uint32_t>> readIndexList(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                                            const std::string& where, const ReadOptions& options,
                                            size_t vertex_count) {
    std::vector<uint32_t> raw;
    if (primitive.indices >= 0) {
        const std::string iw = where + ": accessor " + std::to_string(primitive.indices) + " (indices)";
        LODBAKE_ASSIGN_OR_RETURN(AccessorData idx, readAccessor(model, primitive.indices, iw, options));
        if (idx.components != 1) return invalidInput(iw + ": expected SCALAR, got " + typeName(idx.components));
        if (idx.normalized || (idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                               idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                               idx.component_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            return invalidInput(iw + ": componentType " + std::to_string(idx.component_type) +
                                ", expected unsigned byte, short or int");
        raw.resize(idx.count);
        for (size_t i = 0; i < idx.count; ++i) raw[i] = uint32_t(idx.values[i]);
    } else {
        raw.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) raw[i] = uint32_t(i);
    }
    return raw;
}

// Triangles from the index list in the primitive's mode (triangles, strip or fan).
Status assembleTriangles(int mode, std::vector<uint32_t>& raw, const std::string& where,
                         std::vector<uint32_t>& indices) {
    switch (mode) {
    case TINYGLTF_MODE_TRIANGLES:
        if (raw.size() % 3 != 0)
            return invalidInput(where + ": " + std::to_string(raw.size()) + " indices, expected a multiple of 3");
        indices = std::move(raw);
        break;
    case TINYGLTF_MODE_TRIANGLE_STRIP:
        for (size_t i = 0; i + 2 < raw.size(); ++i) {
            const uint32_t a = raw[i], b = raw[i + 1], c = raw[i + 2];
            if (a == b || b == c || a == c) continue; // strip restarts
            if (i % 2 == 0)
                indices.insert(indices.end(), {a, b, c});
            else
                indices.insert(indices.end(), {a, c, b}); // spec order for odd triangles
        }
        break;
    case TINYGLTF_MODE_TRIANGLE_FAN:
        for (size_t i = 1; i + 1 < raw.size(); ++i) indices.insert(indices.end(), {raw[i], raw[i + 1], raw[0]});
        break;
    default:
        return invalidInput(where + ": mode " + std::to_string(mode) + " is not valid");
    }
    return Status::okStatus();
}

Result<PrimitiveData> readPrimitive(const tinygltf::Model& model, const tinygltf::Primitive& primitive,
                                    const std::string& where, bool quantized, const ReadOptions& options,
                                    int draco_indices_accessor, bool* used_draco) {
    PrimitiveData out;
    out.material = primitive.material;
    if (primitive.material >= 0 && size_t(primitive.material) >= model.materials.size())
        return invalidInput(where + ": material " + std::to_string(primitive.material) + " does not exist");
    auto pos_it = primitive.attributes.find("POSITION");
    if (pos_it == primitive.attributes.end()) return invalidInput(where + ": attributes: POSITION is missing");

    std::vector<AttributeSource> sources;
    std::vector<uint32_t> draco_indices;
    bool has_draco_indices = false;
    auto draco_it = primitive.extensions.find(kDracoExtension);
    std::map<std::string, int> draco_ids;
    if (draco_it != primitive.extensions.end()) {
        *used_draco = true;
        LODBAKE_RETURN_IF_ERROR(readDracoAttributes(model, primitive, draco_it->second, where, options,
                                                    draco_indices_accessor, sources, draco_ids, draco_indices));
        has_draco_indices = true;
    }
    for (const auto& attribute : primitive.attributes) {
        if (!wantedSemantic(attribute.first) || draco_ids.count(attribute.first)) continue;
        AttributeSource src;
        src.semantic = attribute.first;
        src.accessor = attribute.second;
        const std::string aw = where + ": accessor " + std::to_string(attribute.second) + " (" + attribute.first + ")";
        LODBAKE_ASSIGN_OR_RETURN(src.data, readAccessor(model, attribute.second, aw, options));
        sources.push_back(std::move(src));
    }
    LODBAKE_ASSIGN_OR_RETURN(const size_t vertex_count,
                             storeAttributes(sources, draco_ids, where, quantized, options, out));

    std::vector<uint32_t> raw;
    if (has_draco_indices) {
        raw = std::move(draco_indices);
    } else {
        LODBAKE_ASSIGN_OR_RETURN(raw, readIndexList(model, primitive, where, options, vertex_count));
    }
    for (size_t i = 0; i < raw.size(); ++i)
        if (raw[i] >= vertex_count)
            return invalidInput(where + ": index " + std::to_string(i) + " is " + std::to_string(raw[i]) +
                                ", out of range (" + std::to_string(vertex_count) + " vertices)");
    LODBAKE_RETURN_IF_ERROR(assembleTriangles(primitive.mode, raw, where, out.indices));
    return out;
}

Vec3f transformPoint(const Mat4& m, const Vec3f& p) {
    const double x = p.x, y = p.y, z = p.z;
    return Vec3f(float(m[0] * x + m[4] * y + m[8] * z + m[12]), float(m[1] * x + m[5] * y + m[9] * z + m[13]),
                 float(m[2] * x + m[6] * y + m[10] * z + m[14]));
}

Vec3f transformVector(const std::array<double, 9>& m, const Vec3f& v) { // column-major 3x3
    const Vec3d r(m[0] * v.x + m[3] * v.y + m[6] * v.z, m[1] * v.x + m[4] * v.y + m[7] * v.z,
                  m[2] * v.x + m[5] * v.y + m[8] * v.z);
    const double len = length(r);
    if (!(len > 0.0) || !std::isfinite(len)) return Vec3f(0.0f, 0.0f, 0.0f);
    return Vec3f(float(r.x / len), float(r.y / len), float(r.z / len));
}

// Applies `world` to a primitive: positions, normals (inverse transpose), tangents; mirrored
// transforms flip the winding and the tangent handedness.
void applyTransform(const Mat4& world, PrimitiveData& p) {
    if (world == identity()) return;
    for (Vec3f& v : p.positions) v = transformPoint(world, v);
    const std::array<double, 9> a = {world[0], world[1], world[2], world[4], world[5],
                                     world[6], world[8], world[9], world[10]};
    const double det =
        a[0] * (a[4] * a[8] - a[7] * a[5]) - a[3] * (a[1] * a[8] - a[7] * a[2]) + a[6] * (a[1] * a[5] - a[4] * a[2]);
    // Inverse transpose is the cofactor matrix divided by det; the scale goes away on renormalisation,
    // but its sign matters.
    const std::array<double, 9> cof = {a[4] * a[8] - a[5] * a[7], a[5] * a[6] - a[3] * a[8], a[3] * a[7] - a[4] * a[6],
                                       a[2] * a[7] - a[1] * a[8], a[0] * a[8] - a[2] * a[6], a[1] * a[6] - a[0] * a[7],
                                       a[1] * a[5] - a[2] * a[4], a[2] * a[3] - a[0] * a[5], a[0] * a[4] - a[1] * a[3]};
    // cof is the cofactor matrix (det * inverse transpose), column-major like `a`; only its sign
    // needs fixing, the scale goes away on renormalisation.
    std::array<double, 9> nm = cof;
    if (det < 0)
        for (double& v : nm) v = -v;
    for (Vec3f& n : p.normals) n = transformVector(nm, n);
    for (Vec4f& t : p.tangents) {
        const Vec3f d = transformVector(a, Vec3f(t.x, t.y, t.z));
        t = Vec4f(d.x, d.y, d.z, det < 0 ? -t.w : t.w);
    }
    if (det < 0)
        for (size_t i = 0; i + 2 < p.indices.size(); i += 3) std::swap(p.indices[i + 1], p.indices[i + 2]);
}

std::string mimeFromBytes(const std::vector<uint8_t>& b) {
    if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "image/png";
    if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "image/jpeg";
    if (b.size() >= 12 && std::memcmp(b.data(), "RIFF", 4) == 0 && std::memcmp(b.data() + 8, "WEBP", 4) == 0)
        return "image/webp";
    return "";
}

Status importMaterials(const tinygltf::Model& model, const std::string& name, const ReadOptions& options, Mesh& mesh,
                       Diagnostics& diagnostics) {
    for (size_t t = 0; t < model.textures.size(); ++t) {
        const tinygltf::Texture& texture = model.textures[t];
        Texture out;
        out.name = texture.name;
        if (texture.source < 0 || size_t(texture.source) >= model.images.size()) {
            diagnostics.warn(name + ": texture " + std::to_string(t) + ": no usable image source, kept without pixels");
            mesh.textures.push_back(std::move(out));
            continue;
        }
        const tinygltf::Image& image = model.images[size_t(texture.source)];
        if (out.name.empty()) out.name = image.name;
        if (image.uri.rfind("data:", 0) != 0) out.uri = image.uri;
        if (image.bufferView >= 0) {
            LODBAKE_ASSIGN_OR_RETURN(
                auto bytes, viewBytes(model, image.bufferView, name + ": image " + std::to_string(texture.source)));
            out.bytes.assign(bytes.first, bytes.first + bytes.second);
        } else {
            out.bytes = image.image;
            // A texture file that is referenced but missing is an error, as for OBJ's map_Kd: baking
            // on without it would silently drop the texture from every level.
            if (out.bytes.empty() && options.load_textures)
                return invalidInput(name + ": image " + std::to_string(texture.source) + ": \"" + image.uri +
                                    "\": cannot read the image file (expected it next to the glTF)");
        }
        out.mime_type = image.mimeType;
        if (out.mime_type.empty()) out.mime_type = mimeFromBytes(out.bytes);
        if (!options.load_textures) out.bytes.clear();
        mesh.textures.push_back(std::move(out));
    }
    auto slot = [&](int index, int texcoord, const std::string& where, TextureSlot& s) -> Status {
        if (index < 0) return Status::okStatus();
        if (size_t(index) >= model.textures.size())
            return invalidInput(where + ": texture " + std::to_string(index) + " does not exist");
        if (texcoord < 0) return invalidInput(where + ": texCoord must not be negative");
        s.texture = index;
        s.texcoord = uint32_t(texcoord);
        return Status::okStatus();
    };
    for (size_t m = 0; m < model.materials.size(); ++m) {
        const tinygltf::Material& in = model.materials[m];
        const std::string where = name + ": material " + std::to_string(m);
        Material out;
        out.name = in.name;
        const auto& pbr = in.pbrMetallicRoughness;
        if (pbr.baseColorFactor.size() == 4)
            out.base_color_factor = Vec4f(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                                          float(pbr.baseColorFactor[2]), float(pbr.baseColorFactor[3]));
        out.metallic_factor = float(pbr.metallicFactor);
        out.roughness_factor = float(pbr.roughnessFactor);
        if (in.emissiveFactor.size() == 3)
            out.emissive_factor =
                Vec3f(float(in.emissiveFactor[0]), float(in.emissiveFactor[1]), float(in.emissiveFactor[2]));
        LODBAKE_RETURN_IF_ERROR(
            slot(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, where, out.base_color_texture));
        LODBAKE_RETURN_IF_ERROR(slot(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord, where,
                                     out.metallic_roughness_texture));
        LODBAKE_RETURN_IF_ERROR(slot(in.normalTexture.index, in.normalTexture.texCoord, where, out.normal_texture));
        out.normal_scale = float(in.normalTexture.scale);
        LODBAKE_RETURN_IF_ERROR(
            slot(in.occlusionTexture.index, in.occlusionTexture.texCoord, where, out.occlusion_texture));
        out.occlusion_strength = float(in.occlusionTexture.strength);
        LODBAKE_RETURN_IF_ERROR(
            slot(in.emissiveTexture.index, in.emissiveTexture.texCoord, where, out.emissive_texture));
        if (in.alphaMode == "MASK")
            out.alpha_mode = AlphaMode::Mask;
        else if (in.alphaMode == "BLEND")
            out.alpha_mode = AlphaMode::Blend;
        else if (!in.alphaMode.empty() && in.alphaMode != "OPAQUE")
            return invalidInput(where + ": alphaMode \"" + in.alphaMode + "\", expected OPAQUE, MASK or BLEND");
        out.alpha_cutoff = float(in.alphaCutoff);
        out.is_double_sided = in.doubleSided;
        mesh.materials.push_back(std::move(out));
    }
    return Status::okStatus();
}

// Checks the container and the JSON (depth, references) and parses the document with tinygltf.
// `prepass` receives what the JSON scan found (the Draco indices accessors among it).
Status parseGltfDocument(const uint8_t* data, size_t size, const std::string& name,
                         const SideFileLoader& load_side_file, const ReadOptions& options, Diagnostics& diagnostics,
                         bool is_glb, JsonPrepass& prepass, tinygltf::Model& model) {
    if (!is_glb && lowerExtension(name) == ".glb") {
        if (size < 12)
            return invalidInput(name + ": GLB header: expected 12 bytes, the file has " + std::to_string(size));
        return invalidInput(name + ": GLB header: bad magic, expected \"glTF\"");
    }
    const uint8_t* json = data;
    size_t json_size = size;
    if (is_glb) LODBAKE_RETURN_IF_ERROR(checkGlbContainer(data, size, name, &json, &json_size));
    if (json_size == 0) return invalidInput(name + ": JSON: the document is empty");
    const JsonDepthScan depth = scanJsonDepth(json, json_size, options.max_json_depth);
    if (depth.is_too_deep)
        return resourceLimit(name + ": JSON: byte " + std::to_string(depth.offset) + ": expected at most " +
                             std::to_string(options.max_json_depth) + " levels of nested arrays and objects");
    LODBAKE_RETURN_IF_ERROR(checkJsonReferences(json, json_size, name, prepass));
    if (size > std::numeric_limits<unsigned int>::max()) return resourceLimit(name + ": file larger than 4 GiB");
    std::vector<uint8_t> rewritten;
    if (prepass.is_changed) {
        if (is_glb)
            rewritten = replaceGlbJson(data, size, json_size, prepass.json_text);
        else
            rewritten.assign(prepass.json_text.begin(), prepass.json_text.end());
        data = rewritten.data();
        size = rewritten.size();
    }

    tinygltf::TinyGLTF loader;
    LoaderContext context{&load_side_file, parentDirectory(name)};
    loader.SetFsCallbacks({&fileExists, &expandFilePath, &readWholeFile, &writeWholeFile, &context});
    loader.SetImageLoader(&keepEncodedImage, nullptr);
    std::string err, warn;
    const std::string base_dir = parentDirectory(name);
    const bool ok =
        is_glb ? loader.LoadBinaryFromMemory(&model, &err, &warn, data, static_cast<unsigned int>(size), base_dir)
               : loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(data),
                                            static_cast<unsigned int>(size), base_dir);
    if (!ok) return invalidInput(name + ": " + firstLine(err));
    if (!warn.empty()) diagnostics.note(name + ": " + firstLine(warn));
    return Status::okStatus();
}

// Reads the triangle primitives of every mesh instance, in world space. Primitives of one mesh that
// use the same attribute accessors share their vertices. Counts the file's vertices and faces into
// `source`, each accessor and (mesh, primitive) once.
Status readInstanceParts(const tinygltf::Model& model, const std::vector<Instance>& instances,
                         const JsonPrepass& prepass, const std::string& name, bool quantized,
                         const ReadOptions& options, Diagnostics& diagnostics, std::vector<PrimitiveData>& parts,
                         SourceInfo& source) {
    bool used_draco = false;
    uint64_t total_vertices = 0, total_faces = 0;
    std::set<int> counted_positions;                     // POSITION accessors counted in file_vertex_count
    std::set<std::pair<int, size_t>> counted_primitives; // (mesh, primitive) counted in file_face_count
    for (const Instance& instance : instances) {
        const tinygltf::Mesh& gmesh = model.meshes[size_t(instance.mesh)];
        std::map<std::map<std::string, int>, size_t> shared;
        for (size_t p = 0; p < gmesh.primitives.size(); ++p) {
            const std::string where = name + ": mesh \"" +
                                      (gmesh.name.empty() ? std::to_string(instance.mesh) : gmesh.name) +
                                      "\" primitive " + std::to_string(p);
            const tinygltf::Primitive& primitive = gmesh.primitives[p];
            if (primitive.mode >= TINYGLTF_MODE_POINTS && primitive.mode <= TINYGLTF_MODE_LINE_STRIP) {
                diagnostics.note(where + ": point/line primitive skipped");
                continue;
            }
            auto draco_indices = prepass.draco_indices.find({size_t(instance.mesh), p});
            const int draco_indices_accessor =
                draco_indices == prepass.draco_indices.end() ? -1 : draco_indices->second;
            LODBAKE_ASSIGN_OR_RETURN(PrimitiveData part, readPrimitive(model, primitive, where, quantized, options,
                                                                       draco_indices_accessor, &used_draco));
            const bool is_draco = primitive.extensions.count(kDracoExtension) > 0;
            if (counted_positions.insert(primitive.attributes.at("POSITION")).second || is_draco)
                total_vertices += part.positions.size();
            if (counted_primitives.insert({instance.mesh, p}).second) total_faces += part.indices.size() / 3;
            if (total_vertices > options.max_vertex_count || total_faces > options.max_face_count)
                return resourceLimit(where + ": the scene exceeds the reader's vertex or face limit");
            if (!is_draco) {
                auto it = shared.find(primitive.attributes);
                if (it != shared.end()) {
                    part.shares_vertices_of = int(it->second);
                    part.positions.clear();
                    part.normals.clear();
                    part.tangents.clear();
                    part.uvs.clear();
                    part.colors.clear();
                } else {
                    shared[primitive.attributes] = parts.size();
                }
            }
            applyTransform(instance.world, part);
            part.name = gmesh.name;
            parts.push_back(std::move(part));
        }
    }
    if (used_draco) source.encoding += "+draco";
    source.file_vertex_count = total_vertices;
    source.file_face_count = total_faces;
    return Status::okStatus();
}

// Merges the parts into one mesh with one submesh per part: a stream present in any part is present
// in all (neutral fill values).
void mergeParts(const std::vector<PrimitiveData>& parts, Mesh& mesh) {
    bool has_normals = false, has_tangents = false, has_colors = false;
    uint32_t uv_sets = 0;
    for (const PrimitiveData& part : parts) {
        has_normals |= !part.normals.empty();
        has_tangents |= !part.tangents.empty();
        has_colors |= !part.colors.empty();
        if (!part.uvs.empty()) uv_sets = std::max(uv_sets, part.uvs.rbegin()->first + 1);
    }
    mesh.uvs.resize(uv_sets);
    std::vector<uint32_t> part_base(parts.size(), 0);
    for (size_t k = 0; k < parts.size(); ++k) {
        const PrimitiveData& part = parts[k];
        const auto base =
            part.shares_vertices_of >= 0 ? part_base[size_t(part.shares_vertices_of)] : uint32_t(mesh.positions.size());
        part_base[k] = base;
        const size_t n = part.positions.size();
        mesh.positions.insert(mesh.positions.end(), part.positions.begin(), part.positions.end());
        if (has_normals) {
            if (part.normals.empty())
                mesh.normals.insert(mesh.normals.end(), n, Vec3f(0.0f, 0.0f, 0.0f));
            else
                mesh.normals.insert(mesh.normals.end(), part.normals.begin(), part.normals.end());
        }
        if (has_tangents) {
            if (part.tangents.empty())
                mesh.tangents.insert(mesh.tangents.end(), n, Vec4f(1.0f, 0.0f, 0.0f, 1.0f));
            else
                mesh.tangents.insert(mesh.tangents.end(), part.tangents.begin(), part.tangents.end());
        }
        if (has_colors) {
            if (part.colors.empty())
                mesh.colors.insert(mesh.colors.end(), n, Vec4f(1.0f, 1.0f, 1.0f, 1.0f));
            else
                mesh.colors.insert(mesh.colors.end(), part.colors.begin(), part.colors.end());
        }
        for (uint32_t s = 0; s < uv_sets; ++s) {
            auto it = part.uvs.find(s);
            if (it == part.uvs.end())
                mesh.uvs[s].insert(mesh.uvs[s].end(), n, Vec2f(0.0f, 0.0f));
            else
                mesh.uvs[s].insert(mesh.uvs[s].end(), it->second.begin(), it->second.end());
        }
        SubMesh sub;
        sub.name = part.name;
        sub.first_index = uint32_t(mesh.indices.size());
        sub.index_count = uint32_t(part.indices.size());
        if (part.material >= 0) sub.material = MaterialId(uint32_t(part.material));
        for (uint32_t i : part.indices) mesh.indices.push_back(base + i);
        mesh.submeshes.push_back(std::move(sub));
    }
}

// Texture slots must sample a UV set the mesh has; the others are dropped with a warning.
void dropUnsampledTextures(const std::string& name, Diagnostics& diagnostics, Mesh& mesh) {
    for (size_t m = 0; m < mesh.materials.size(); ++m) {
        Material& material = mesh.materials[m];
        for (TextureSlot* slot : {&material.base_color_texture, &material.metallic_roughness_texture,
                                  &material.normal_texture, &material.occlusion_texture, &material.emissive_texture}) {
            if (slot->isSet() && slot->texcoord >= mesh.uvs.size()) {
                diagnostics.warn(name + ": material " + std::to_string(m) + ": texture " +
                                 std::to_string(slot->texture) + " samples TEXCOORD_" + std::to_string(slot->texcoord) +
                                 ", which the meshes lack; the texture is dropped from the material");
                *slot = TextureSlot{};
            }
        }
    }
}

// The extensions the document requires must be ones this reader decodes; returns whether its
// accessors may be quantized (KHR_mesh_quantization).
Result<bool> checkRequiredExtensions(const tinygltf::Model& model, const std::string& name) {
    bool quantized = false;
    for (const std::string& e : model.extensionsUsed)
        if (e == lodrt::format::kExtKhrMeshQuantization) quantized = true;
    for (const std::string& e : model.extensionsRequired)
        if (e != lodrt::format::kExtKhrMeshQuantization && e != kDracoExtension &&
            e != lodrt::format::kExtMeshoptCompression)
            return unsupported(name + ": extensionsRequired: extension \"" + e + "\" is not supported");
    return quantized;
}

Result<LoadedMesh> flattenModel(const tinygltf::Model& model, const JsonPrepass& prepass, bool quantized, bool is_glb,
                                const std::string& name, const ReadOptions& options, Diagnostics& diagnostics);

// A document as both readers start from it: parsed, its required extensions checked and its
// EXT_meshopt_compression views decoded.
struct ParsedGltf {
    tinygltf::Model model;
    JsonPrepass prepass;
    bool is_glb = false;
    bool quantized = false;
};

Status parseForImport(const uint8_t* data, size_t size, const std::string& name, const SideFileLoader& load_side_file,
                      const ReadOptions& options, Diagnostics& diagnostics, ParsedGltf& out) {
    out.is_glb = size >= 4 && readU32(data) == kGlbMagic;
    LODBAKE_RETURN_IF_ERROR(parseGltfDocument(data, size, name, load_side_file, options, diagnostics, out.is_glb,
                                              out.prepass, out.model));
    LODBAKE_ASSIGN_OR_RETURN(out.quantized, checkRequiredExtensions(out.model, name));
    return decodeMeshoptViews(out.model, name);
}

Result<LoadedMesh> readGltfImpl(const uint8_t* data, size_t size, const std::string& name,
                                const SideFileLoader& load_side_file, const ReadOptions& options,
                                Diagnostics& diagnostics) {
    ParsedGltf parsed;
    LODBAKE_RETURN_IF_ERROR(parseForImport(data, size, name, load_side_file, options, diagnostics, parsed));
    return flattenModel(parsed.model, parsed.prepass, parsed.quantized, parsed.is_glb, name, options, diagnostics);
}

// Every mesh instance of the parsed document, in world space, as one mesh (readGltfFromMemory).
Result<LoadedMesh> flattenModel(const tinygltf::Model& model, const JsonPrepass& prepass, bool quantized, bool is_glb,
                                const std::string& name, const ReadOptions& options, Diagnostics& diagnostics) {
    LoadedMesh loaded;
    loaded.source.encoding = is_glb ? "glb" : "gltf";
    loaded.source.face_kind = "triangles";
    Mesh& mesh = loaded.mesh;
    LODBAKE_RETURN_IF_ERROR(importMaterials(model, name, options, mesh, diagnostics));

    std::vector<Instance> instances;
    LODBAKE_RETURN_IF_ERROR(collectInstances(model, name, instances));
    std::vector<PrimitiveData> parts;
    LODBAKE_RETURN_IF_ERROR(
        readInstanceParts(model, instances, prepass, name, quantized, options, diagnostics, parts, loaded.source));
    if (parts.empty()) return invalidInput(name + ": meshes: the scene holds no triangle primitives");
    mergeParts(parts, mesh);
    dropUnsampledTextures(name, diagnostics, mesh);
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    return loaded;
}

// ---- Scene graph (readGltfSceneFromMemory) ------------------------------------------------------

bool hasTrianglePrimitive(const tinygltf::Mesh& mesh) {
    for (const tinygltf::Primitive& p : mesh.primitives)
        if (!(p.mode >= TINYGLTF_MODE_POINTS && p.mode <= TINYGLTF_MODE_LINE_STRIP)) return true;
    return false;
}

// The nodes the default scene reaches, with their world transforms. glTF nodes form strict trees,
// so a node reached twice (a shared child, a cycle, a root listed twice) is an error: the graph kept
// would not say which parent places it.
struct SceneWalk {
    std::vector<bool> reached;
    std::vector<Mat4> world;
    size_t mesh_nodes = 0; // reached nodes whose mesh has a triangle primitive
};

Status walkScene(const tinygltf::Model& model, const std::string& name, SceneWalk& walk) {
    walk.reached.assign(model.nodes.size(), false);
    walk.world.assign(model.nodes.size(), identity());
    const int scene_index = model.defaultScene >= 0 ? model.defaultScene : 0;
    std::vector<std::pair<int, Mat4>> stack;
    const auto& roots = model.scenes[size_t(scene_index)].nodes;
    for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, identity()});
    while (!stack.empty()) {
        const auto [index, parent] = stack.back();
        stack.pop_back();
        const std::string where = name + ": node " + std::to_string(index);
        if (index < 0 || size_t(index) >= model.nodes.size())
            return invalidInput(where + ": does not exist (" + std::to_string(model.nodes.size()) + " nodes)");
        if (walk.reached[size_t(index)])
            return invalidInput(where + ": reached twice from the scene (a cycle or a shared child; expected a tree)");
        walk.reached[size_t(index)] = true;
        const tinygltf::Node& node = model.nodes[size_t(index)];
        LODBAKE_ASSIGN_OR_RETURN(Mat4 local, localMatrix(node, where));
        walk.world[size_t(index)] = multiply(parent, local);
        if (node.mesh >= 0) {
            if (size_t(node.mesh) >= model.meshes.size())
                return invalidInput(where + ": mesh " + std::to_string(node.mesh) + " does not exist");
            if (hasTrianglePrimitive(model.meshes[size_t(node.mesh)])) ++walk.mesh_nodes;
        }
        for (auto it = node.children.rbegin(); it != node.children.rend(); ++it)
            stack.push_back({*it, walk.world[size_t(index)]});
    }
    return Status::okStatus();
}

// Gives `mesh` copies of the materials its sub-meshes use and of the textures those sample (in file
// order, renumbered), so each mesh of a scene carries only what it draws.
void keepUsedMaterials(const Mesh& all, Mesh& mesh) {
    std::vector<int> material_map(all.materials.size(), -1);
    for (const SubMesh& sub : mesh.submeshes)
        if (sub.material.isValid() && sub.material.value < all.materials.size()) material_map[sub.material.value] = 0;
    std::vector<int> texture_map(all.textures.size(), -1);
    for (size_t m = 0; m < all.materials.size(); ++m) {
        if (material_map[m] < 0) continue;
        material_map[m] = int(mesh.materials.size());
        mesh.materials.push_back(all.materials[m]);
    }
    for (Material& material : mesh.materials)
        for (TextureSlot* slot : {&material.base_color_texture, &material.metallic_roughness_texture,
                                  &material.normal_texture, &material.occlusion_texture, &material.emissive_texture})
            if (slot->isSet() && size_t(slot->texture) < all.textures.size()) texture_map[size_t(slot->texture)] = 0;
    for (size_t t = 0; t < all.textures.size(); ++t) {
        if (texture_map[t] < 0) continue;
        texture_map[t] = int(mesh.textures.size());
        mesh.textures.push_back(all.textures[t]);
    }
    for (Material& material : mesh.materials)
        for (TextureSlot* slot : {&material.base_color_texture, &material.metallic_roughness_texture,
                                  &material.normal_texture, &material.occlusion_texture, &material.emissive_texture})
            if (slot->isSet() && size_t(slot->texture) < texture_map.size())
                slot->texture = texture_map[size_t(slot->texture)];
    for (SubMesh& sub : mesh.submeshes)
        if (sub.material.isValid() && sub.material.value < material_map.size())
            sub.material = MaterialId(uint32_t(material_map[sub.material.value]));
}

// Reads glTF mesh `m` once, in its own space, with the materials it uses.
Result<Mesh> readLocalMesh(const tinygltf::Model& model, int m, const Mesh& all, const JsonPrepass& prepass,
                           const std::string& name, bool quantized, const ReadOptions& options,
                           Diagnostics& diagnostics, SourceInfo& counts) {
    std::vector<PrimitiveData> parts;
    SourceInfo source;
    LODBAKE_RETURN_IF_ERROR(readInstanceParts(model, {Instance{m, identity()}}, prepass, name, quantized, options,
                                              diagnostics, parts, source));
    if (source.encoding == "+draco" && counts.encoding.find("+draco") == std::string::npos) counts.encoding += "+draco";
    counts.file_vertex_count += source.file_vertex_count;
    counts.file_face_count += source.file_face_count;
    if (counts.file_vertex_count > options.max_vertex_count || counts.file_face_count > options.max_face_count)
        return resourceLimit(name + ": mesh " + std::to_string(m) +
                             ": the scene exceeds the reader's vertex or face limit");
    Mesh mesh;
    mergeParts(parts, mesh);
    keepUsedMaterials(all, mesh);
    const std::string& mesh_name = model.meshes[size_t(m)].name;
    dropUnsampledTextures(name + ": mesh \"" + (mesh_name.empty() ? std::to_string(m) : mesh_name) + "\"",
                          diagnostics, mesh);
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    return mesh;
}

// The reached nodes in file order, each mesh read once (meshes without triangles are left out and
// their nodes kept without a mesh).
Result<LoadedScene> buildScene(const tinygltf::Model& model, const SceneWalk& walk, const JsonPrepass& prepass,
                               bool quantized, bool is_glb, const std::string& name, const ReadOptions& options,
                               Diagnostics& diagnostics) {
    LoadedScene scene;
    scene.source.encoding = is_glb ? "glb" : "gltf";
    scene.source.face_kind = "triangles";
    Mesh all;
    LODBAKE_RETURN_IF_ERROR(importMaterials(model, name, options, all, diagnostics));
    std::vector<int> node_map(model.nodes.size(), -1), mesh_map(model.meshes.size(), -1);
    for (size_t n = 0; n < model.nodes.size(); ++n) {
        if (!walk.reached[n]) continue;
        node_map[n] = int(scene.nodes.size());
        const tinygltf::Node& node = model.nodes[n];
        SceneNode out;
        out.name = node.name;
        out.matrix = node.matrix;
        out.translation = node.translation;
        out.rotation = node.rotation;
        out.scale = node.scale;
        out.world = walk.world[n];
        const int m = node.mesh;
        if (m >= 0 && !hasTrianglePrimitive(model.meshes[size_t(m)])) {
            diagnostics.note(name + ": node " + std::to_string(n) + ": mesh " + std::to_string(m) +
                             " has no triangle primitive; the node is kept without it");
        } else if (m >= 0) {
            if (mesh_map[size_t(m)] < 0) {
                LODBAKE_ASSIGN_OR_RETURN(Mesh mesh, readLocalMesh(model, m, all, prepass, name, quantized, options,
                                                                  diagnostics, scene.source));
                mesh_map[size_t(m)] = int(scene.meshes.size());
                scene.meshes.push_back(std::move(mesh));
                scene.mesh_names.push_back(model.meshes[size_t(m)].name);
            }
            out.mesh = mesh_map[size_t(m)];
        }
        scene.nodes.push_back(std::move(out));
    }
    for (size_t n = 0; n < model.nodes.size(); ++n) {
        if (!walk.reached[n]) continue;
        for (int child : model.nodes[n].children)
            scene.nodes[size_t(node_map[n])].children.push_back(uint32_t(node_map[size_t(child)]));
    }
    const int scene_index = model.defaultScene >= 0 ? model.defaultScene : 0;
    for (int root : model.scenes[size_t(scene_index)].nodes) scene.roots.push_back(uint32_t(node_map[size_t(root)]));
    return scene;
}

Result<LoadedScene> readGltfSceneImpl(const uint8_t* data, size_t size, const std::string& name,
                                      const SideFileLoader& load_side_file, const ReadOptions& options,
                                      Diagnostics& diagnostics) {
    ParsedGltf parsed;
    LODBAKE_RETURN_IF_ERROR(parseForImport(data, size, name, load_side_file, options, diagnostics, parsed));
    const tinygltf::Model& model = parsed.model;
    SceneWalk walk;
    if (!model.scenes.empty()) {
        const int scene_index = model.defaultScene >= 0 ? model.defaultScene : 0;
        if (size_t(scene_index) >= model.scenes.size())
            return invalidInput(name + ": scene: default scene " + std::to_string(scene_index) + " does not exist");
        LODBAKE_RETURN_IF_ERROR(walkScene(model, name, walk));
    }
    if (walk.mesh_nodes < 2) {
        LoadedScene flat;
        LODBAKE_ASSIGN_OR_RETURN(flat.flat, flattenModel(model, parsed.prepass, parsed.quantized, parsed.is_glb, name,
                                                         options, diagnostics));
        return flat;
    }
    return buildScene(model, walk, parsed.prepass, parsed.quantized, parsed.is_glb, name, options, diagnostics);
}

} // namespace

Result<LoadedMesh> readGltfFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                      const SideFileLoader& load_side_file, const ReadOptions& options,
                                      Diagnostics& diagnostics) {
    try {
        return readGltfImpl(data, size, name, load_side_file, options, diagnostics);
    } catch (const std::exception& e) {
        return invalidInput(name + ": glTF parser failed: " + std::string(e.what()));
    }
}

Result<LoadedScene> readGltfSceneFromMemory(const uint8_t* data, size_t size, const std::string& name,
                                            const SideFileLoader& load_side_file, const ReadOptions& options,
                                            Diagnostics& diagnostics) {
    try {
        return readGltfSceneImpl(data, size, name, load_side_file, options, diagnostics);
    } catch (const std::exception& e) {
        return invalidInput(name + ": glTF parser failed: " + std::string(e.what()));
    }
}

} // namespace lodbake
