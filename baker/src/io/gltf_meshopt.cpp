// EXT_meshopt_compression input for the glTF reader (gltf_meshopt.h), decoded with lodrt's decoders.
#include "io/gltf_meshopt.h"

#include <set>
#include <vector>

#include "lodrt/format.h"
#include "lodrt/meshopt.h"
#include "lodrt/result.h"

namespace lodbake {

namespace {

namespace fmt = lodrt::format;

// The decoders never expand a byte into more than this many (a vertex stream's all-zero group costs two
// header bits for 16 bytes); larger claims are refused before anything is allocated.
constexpr uint64_t kMaxExpansion = 64;

bool hasMeshopt(const nlohmann::json& view) {
    return view.is_object() && view.contains("extensions") && view["extensions"].is_object() &&
           view["extensions"].contains(fmt::kExtMeshoptCompression);
}

bool readCount(const tinygltf::Value& object, const char* key, bool required, uint64_t* out) {
    const tinygltf::Value& v = object.Get(key);
    if (!v.IsNumber()) return !required;
    const double d = v.GetNumberAsDouble();
    if (!(d >= 0.0 && d <= 9007199254740992.0) || d != double(uint64_t(d))) return false;
    *out = uint64_t(d);
    return true;
}

Status decodeView(tinygltf::Model& model, size_t index, const std::string& where) {
    tinygltf::BufferView& view = model.bufferViews[index];
    const tinygltf::Value& ext = view.extensions[fmt::kExtMeshoptCompression];
    if (!ext.IsObject()) return invalidInput(where + ": expected an object");
    uint64_t buffer = 0, offset = 0, length = 0, stride = 0, count = 0;
    if (!readCount(ext, "buffer", true, &buffer) || buffer >= model.buffers.size())
        return invalidInput(where + ": buffer: expected a buffer index");
    if (!readCount(ext, "byteOffset", false, &offset) || !readCount(ext, "byteLength", true, &length) ||
        !readCount(ext, "byteStride", true, &stride) || !readCount(ext, "count", true, &count))
        return invalidInput(where + ": byteOffset, byteLength, byteStride, count: expected non-negative integers");
    const std::vector<unsigned char>& source = model.buffers[size_t(buffer)].data;
    if (offset > source.size() || length > source.size() - offset)
        return invalidInput(where + ": the compressed bytes run past the end of buffer " + std::to_string(buffer));
    lodrt::MeshoptViewInfo info;
    info.buffer = uint32_t(buffer);
    info.byte_offset = offset;
    info.byte_length = length;
    info.stride = uint32_t(stride);
    info.count = count;
    const std::string mode = ext.Get("mode").IsString() ? ext.Get("mode").Get<std::string>() : "";
    const std::string filter = ext.Get("filter").IsString() ? ext.Get("filter").Get<std::string>() : "NONE";
    if (mode == fmt::kMeshoptModeAttributes)
        info.mode = lodrt::MeshoptMode::Attributes;
    else if (mode == fmt::kMeshoptModeTriangles)
        info.mode = lodrt::MeshoptMode::Triangles;
    else if (mode == fmt::kMeshoptModeIndices)
        info.mode = lodrt::MeshoptMode::Indices;
    else
        return invalidInput(where + ": mode: expected ATTRIBUTES, TRIANGLES or INDICES");
    if (filter == fmt::kMeshoptFilterNone)
        info.filter = lodrt::MeshoptFilter::None;
    else if (filter == fmt::kMeshoptFilterOctahedral)
        info.filter = lodrt::MeshoptFilter::Octahedral;
    else if (filter == fmt::kMeshoptFilterQuaternion)
        info.filter = lodrt::MeshoptFilter::Quaternion;
    else if (filter == fmt::kMeshoptFilterExponential)
        info.filter = lodrt::MeshoptFilter::Exponential;
    else
        return invalidInput(where + ": filter: expected NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
    if (stride == 0 || stride > fmt::kMeshoptMaxVertexStride || count > (uint64_t(1) << 40) ||
        count * stride != view.byteLength)
        return invalidInput(where + ": count * byteStride must equal the bufferView's byteLength");
    if (count * stride > kMaxExpansion * length + 4096)
        return invalidInput(where + ": " + std::to_string(length) + " compressed bytes cannot hold " +
                            std::to_string(count * stride) + " bytes");
    std::vector<unsigned char> decoded(size_t(count * stride));
    const lodrt::Result r =
        lodrt::meshoptDecodeView(info, source.data() + offset, size_t(length), decoded.data(), decoded.size());
    if (r != lodrt::Result::Ok)
        return invalidInput(where + ": the compressed stream does not decode (" + lodrt::resultName(r) + ")");
    tinygltf::Buffer out;
    out.data = std::move(decoded);
    model.buffers.push_back(std::move(out));
    view.buffer = int(model.buffers.size() - 1);
    view.byteOffset = 0;
    view.extensions.erase(fmt::kExtMeshoptCompression);
    return Status::okStatus();
}

} // namespace

void replaceMeshoptFallbacks(nlohmann::json& root, bool& changed) {
    auto buffers = root.find("buffers");
    auto views = root.find("bufferViews");
    if (buffers == root.end() || views == root.end() || !buffers->is_array() || !views->is_array()) return;
    std::set<size_t> compressed_only, plain; // plain: used by an uncompressed view or holding compressed bytes
    for (const nlohmann::json& v : *views) {
        if (!v.is_object() || !v.contains("buffer") || !v["buffer"].is_number_unsigned()) continue;
        (hasMeshopt(v) ? compressed_only : plain).insert(v["buffer"].get<size_t>());
        if (!hasMeshopt(v)) continue;
        const nlohmann::json& ext = v["extensions"][fmt::kExtMeshoptCompression];
        if (ext.is_object() && ext.contains("buffer") && ext["buffer"].is_number_unsigned())
            plain.insert(ext["buffer"].get<size_t>());
    }
    for (size_t b : compressed_only) {
        if (plain.count(b) || b >= buffers->size()) continue;
        nlohmann::json& buffer = (*buffers)[b];
        if (!buffer.is_object() || buffer.contains("uri")) continue;
        buffer["uri"] = "data:application/octet-stream;base64,AA==";
        buffer["byteLength"] = 1;
        changed = true;
    }
}

Status decodeMeshoptViews(tinygltf::Model& model, const std::string& name) {
    for (size_t i = 0; i < model.bufferViews.size(); ++i)
        if (model.bufferViews[i].extensions.count(fmt::kExtMeshoptCompression))
            LODBAKE_RETURN_IF_ERROR(
                decodeView(model, i, name + ": bufferView " + std::to_string(i) + ": " + fmt::kExtMeshoptCompression));
    return Status::okStatus();
}

} // namespace lodbake
