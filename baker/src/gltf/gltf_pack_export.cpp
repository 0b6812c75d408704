// Pack writer: a PackDescription as one GLB through tinygltf. LOD groups use MSFT_lod on the LOD0
// node (https://github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Vendor/MSFT_lod) with the
// MSFT_screencoverage array in the node's extras, as that extension specifies.
#include <exception>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "gltf/gltf_model.h"
#include "lodbake/gltf/gltf_io.h"
#include "lodbake/pack/pack.h"
#include "lodbake/version.h"

namespace lodbake {

namespace {

tinygltf::Value toValue(const nlohmann::json& j) {
    if (j.is_object()) {
        tinygltf::Value::Object o;
        for (auto it = j.begin(); it != j.end(); ++it) o[it.key()] = toValue(it.value());
        return tinygltf::Value(std::move(o));
    }
    if (j.is_array()) {
        tinygltf::Value::Array a;
        for (const auto& e : j) a.push_back(toValue(e));
        return tinygltf::Value(std::move(a));
    }
    if (j.is_boolean()) return tinygltf::Value(j.get<bool>());
    if (j.is_number_integer() || j.is_number_unsigned()) return tinygltf::Value(j.get<int>());
    if (j.is_number()) return tinygltf::Value(j.get<double>());
    if (j.is_string()) return tinygltf::Value(j.get<std::string>());
    return tinygltf::Value();
}

Status addExtension(const PackExtension& e, BufferBuilder& buffer, tinygltf::ExtensionMap& target,
                    std::set<std::string>& used, std::set<std::string>& streams) {
    nlohmann::json object = nlohmann::json::parse(e.json);
    if (!object.is_object()) return invalidInput("pack: extension " + e.name + ": expected a JSON object");
    if (e.blobs.size() != e.blob_view_members.size())
        return internalError("pack: extension " + e.name + ": blob and member counts differ");
    for (size_t b = 0; b < e.blobs.size(); ++b)
        object[e.blob_view_members[b]] = buffer.addView(e.blobs[b].data(), e.blobs[b].size(), 0);
    target[e.name] = toValue(object);
    used.insert(e.name);
    if (e.is_stream) streams.insert(e.name);
    return Status::okStatus();
}

Result<std::vector<uint8_t>> writeImpl(const PackDescription& description) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = std::string("lodbake ") + kVersionString;
    BufferBuilder buffer(model);
    ModelDedupe dedupe;
    std::set<std::string> used, streams;
    tinygltf::Scene scene;
    for (const PackAsset& asset : description.assets) {
        if (asset.levels.empty()) return invalidInput("pack: asset \"" + asset.name + "\" has no levels");
        dedupe.first_material = model.materials.size(); // share materials within one asset only
        std::vector<int> nodes;
        for (size_t l = 0; l < asset.levels.size(); ++l) {
            const PackLevel& level = asset.levels[l];
            const std::string level_name = asset.name + "_lod" + std::to_string(l);
            Result<int> mesh_index = addMeshToModel(model, buffer, level.mesh, &dedupe);
            if (!mesh_index.ok())
                return Status(mesh_index.status().code(), level_name + ": " + mesh_index.status().message());
            tinygltf::Mesh& gmesh = model.meshes[size_t(*mesh_index)];
            gmesh.name = level_name;
            for (const PackExtension& e : level.mesh_extensions)
                LODBAKE_RETURN_IF_ERROR(addExtension(e, buffer, gmesh.extensions, used, streams));
            if (!level.primitive_extensions.empty() && level.primitive_extensions.size() != gmesh.primitives.size())
                return internalError(level_name + ": primitive extension lists do not match the primitives");
            for (size_t p = 0; p < level.primitive_extensions.size(); ++p)
                for (const PackExtension& e : level.primitive_extensions[p])
                    LODBAKE_RETURN_IF_ERROR(addExtension(e, buffer, gmesh.primitives[p].extensions, used, streams));
            tinygltf::Node node;
            node.name = l == 0 ? asset.name : level_name;
            node.mesh = *mesh_index;
            model.nodes.push_back(std::move(node));
            nodes.push_back(int(model.nodes.size() - 1));
        }
        tinygltf::Node& root = model.nodes[size_t(nodes[0])];
        if (nodes.size() > 1) {
            tinygltf::Value::Array ids;
            for (size_t l = 1; l < nodes.size(); ++l) ids.push_back(tinygltf::Value(nodes[l]));
            tinygltf::Value::Object lod;
            lod["ids"] = tinygltf::Value(std::move(ids));
            root.extensions["MSFT_lod"] = tinygltf::Value(std::move(lod));
            used.insert("MSFT_lod");
            if (asset.screen_coverage.size() == nodes.size()) {
                tinygltf::Value::Array coverage;
                for (double c : asset.screen_coverage) coverage.push_back(tinygltf::Value(c));
                tinygltf::Value::Object extras;
                extras["MSFT_screencoverage"] = tinygltf::Value(std::move(coverage));
                root.extras = tinygltf::Value(std::move(extras));
            }
        }
        for (const PackExtension& e : asset.node_extensions)
            LODBAKE_RETURN_IF_ERROR(addExtension(e, buffer, root.extensions, used, streams));
        scene.nodes.push_back(nodes[0]);
    }
    if (scene.nodes.empty()) return invalidInput("pack: nothing to write");
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;
    model.extensionsUsed.assign(used.begin(), used.end());
    if (description.compact) model.extensionsRequired.assign(streams.begin(), streams.end());

    tinygltf::Buffer gbuffer;
    gbuffer.data = buffer.finish();
    model.buffers.push_back(std::move(gbuffer));
    tinygltf::TinyGLTF writer;
    std::ostringstream stream;
    if (!writer.WriteGltfSceneToStream(&model, stream, false, true)) return internalError("pack: tinygltf failed");
    const std::string s = stream.str();
    return std::vector<uint8_t>(s.begin(), s.end());
}

} // namespace

Result<std::vector<uint8_t>> writePackGlb(const PackDescription& description) {
    try {
        return writeImpl(description);
    } catch (const nlohmann::json::exception& e) {
        return invalidInput(std::string("pack: malformed extension JSON: ") + e.what());
    } catch (const std::exception& e) {
        return internalError(std::string("pack: glTF writing failed: ") + e.what());
    }
}

} // namespace lodbake
