// Pack writer: a PackDescription as one GLB through tinygltf. LOD groups use MSFT_lod on the LOD0
// node (https://github.com/KhronosGroup/glTF/tree/main/extensions/2.0/Vendor/MSFT_lod) with the
// MSFT_screencoverage array in the node's extras, as that extension specifies.
#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <exception>
#include <ostream>
#include <map>
#include <memory>
#include <set>
#include <streambuf>

#include <tiny_gltf.h>

#include "lodbake/pack/pack_glb.h"

#include "io/gltf_model.h"
#include "pack/web_meshopt.h"
#include "lodbake/core/json_writer.h"
#include "lodbake/pack/pack.h"
#include "lodbake/core/spill_file.h"
#include "lodbake/version.h"
#include "lodrt/format.h"

namespace lodbake {

namespace {

// Room the GLB header and JSON chunk get behind the binary chunk's bytes (assembleGlb inserts them in
// front, moving the bytes within the vector; a bigger JSON only costs one more copy of the buffer).
constexpr size_t kGlbHeadRoom = size_t(1) << 20;

// A number as tinygltf would hold it had the JsonWriter's text of it been parsed: integer text (no
// fraction, no exponent) that fits 64 bits becomes an int (narrowed as nlohmann's get<int> does),
// everything else a double, non-finite values null. So the pack's JSON is what a text round trip
// would give, byte for byte.
tinygltf::Value numberValue(double d) {
    const std::string text = JsonWriter::formatNumber(d);
    if (text == "null") return tinygltf::Value();
    if (text.find_first_of(".eE") != std::string::npos) return tinygltf::Value(d);
    errno = 0;
    if (text[0] == '-') {
        const long long i = std::strtoll(text.c_str(), nullptr, 10);
        if (errno != ERANGE) return tinygltf::Value(static_cast<int>(i));
    } else {
        const unsigned long long u = std::strtoull(text.c_str(), nullptr, 10);
        if (errno != ERANGE) return tinygltf::Value(static_cast<int>(u));
    }
    return tinygltf::Value(d);
}

tinygltf::Value toValue(const JsonNode& j) {
    switch (j.kind()) {
    case JsonNode::Kind::Object: {
        tinygltf::Value::Object o;
        for (const auto& member : j.members()) o[member.first] = toValue(member.second);
        return tinygltf::Value(std::move(o));
    }
    case JsonNode::Kind::Array: {
        tinygltf::Value::Array a;
        for (const JsonNode& item : j.items()) a.push_back(toValue(item));
        return tinygltf::Value(std::move(a));
    }
    case JsonNode::Kind::Bool:
        return tinygltf::Value(j.asBool());
    case JsonNode::Kind::Int:
        return tinygltf::Value(static_cast<int>(j.asInt()));
    case JsonNode::Kind::UInt:
        return tinygltf::Value(static_cast<int>(j.asUInt()));
    case JsonNode::Kind::Double:
        return numberValue(j.asDouble());
    case JsonNode::Kind::String:
        return tinygltf::Value(j.asString());
    case JsonNode::Kind::Null:
        break;
    }
    return tinygltf::Value();
}

// Where an extension object with buffer-view members sits, so the members can be renumbered when
// the buffer is compacted.
struct ViewPatch {
    enum class Scope { Mesh, Primitive, Node } scope = Scope::Mesh;
    size_t object = 0;    // mesh or node index
    size_t primitive = 0; // Scope::Primitive only
    std::string extension;
    std::string member;
    std::shared_ptr<const SpillFile> spilled; // the view's bytes are in this file (writePackGlbFile)
};

Status addExtension(const PackExtension& e, BufferBuilder& buffer, tinygltf::ExtensionMap& target,
                    std::set<std::string>& used, std::set<std::string>& streams, const ViewPatch& where,
                    std::vector<ViewPatch>& patches) {
    JsonNode object = e.json;
    if (!object.isObject()) return invalidInput("pack: extension " + e.name + ": expected a JSON object");
    if (e.blobs.size() != e.blob_view_members.size() || (!e.spilled.empty() && e.spilled.size() != e.blobs.size()))
        return internalError("pack: extension " + e.name + ": blob and member counts differ");
    for (size_t b = 0; b < e.blobs.size(); ++b) {
        // A spilled blob gets an empty view here; placeSpilledViews gives it its length and room.
        const std::shared_ptr<const SpillFile> spilled = e.spilled.empty() ? nullptr : e.spilled[b];
        object.set(e.blob_view_members[b],
                   buffer.addView(e.blobs[b].data(), spilled ? 0 : e.blobs[b].size(), 0));
        ViewPatch patch = where;
        patch.extension = e.name;
        patch.member = e.blob_view_members[b];
        patch.spilled = spilled;
        patches.push_back(std::move(patch));
    }
    target[e.name] = toValue(object);
    used.insert(e.name);
    if (e.is_stream) streams.insert(e.name);
    return Status::okStatus();
}

tinygltf::ExtensionMap& patchTarget(tinygltf::Model& model, const ViewPatch& p) {
    switch (p.scope) {
    case ViewPatch::Scope::Mesh:
        return model.meshes[p.object].extensions;
    case ViewPatch::Scope::Primitive:
        return model.meshes[p.object].primitives[p.primitive].extensions;
    case ViewPatch::Scope::Node:
        break;
    }
    return model.nodes[p.object].extensions;
}

// Compact packs, as KHR_draco_mesh_compression does: the accessors a primitive's stream extension
// supplies (its "attributes" map and the indices) keep count, type and min/max but lose their
// buffer view, unless a primitive without such a stream also uses them. Then the buffer is rebuilt
// from the views still referenced, in their original order, and every view index is renumbered.
std::vector<uint8_t> dropStreamedAccessors(tinygltf::Model& model, const std::set<std::string>& streams,
                                           const std::vector<uint8_t>& bytes, const std::vector<ViewPatch>& patches) {
    std::set<int> covered, needed;
    for (const tinygltf::Mesh& mesh : model.meshes)
        for (const tinygltf::Primitive& primitive : mesh.primitives) {
            std::set<std::string> supplied;
            bool has_stream = false;
            for (const auto& ext : primitive.extensions) {
                if (!streams.count(ext.first)) continue;
                has_stream = true;
                const tinygltf::Value& attributes = ext.second.Get("attributes");
                if (attributes.IsObject())
                    for (const std::string& key : attributes.Keys()) supplied.insert(key);
            }
            for (const auto& attribute : primitive.attributes)
                (supplied.count(attribute.first) ? covered : needed).insert(attribute.second);
            if (primitive.indices >= 0) (has_stream ? covered : needed).insert(primitive.indices);
        }
    for (int a : covered)
        if (!needed.count(a)) {
            model.accessors[size_t(a)].bufferView = -1;
            model.accessors[size_t(a)].byteOffset = 0; // only allowed with a buffer view
        }

    std::vector<int> views_used(model.bufferViews.size(), 0);
    for (const tinygltf::Accessor& a : model.accessors)
        if (a.bufferView >= 0) views_used[size_t(a.bufferView)] = 1;
    for (const tinygltf::Image& i : model.images)
        if (i.bufferView >= 0) views_used[size_t(i.bufferView)] = 1;
    for (const ViewPatch& p : patches) {
        const tinygltf::Value& v = patchTarget(model, p)[p.extension].Get(p.member);
        if (v.IsInt()) views_used[size_t(v.Get<int>())] = 1;
    }
    std::vector<int> new_index(model.bufferViews.size(), -1);
    std::vector<tinygltf::BufferView> views;
    std::vector<uint8_t> out;
    out.reserve(bytes.size() + kGlbHeadRoom);
    for (size_t i = 0; i < model.bufferViews.size(); ++i) {
        if (!views_used[i]) continue;
        tinygltf::BufferView view = model.bufferViews[i];
        while (out.size() % 4 != 0) out.push_back(0);
        const auto begin = bytes.begin() + std::ptrdiff_t(view.byteOffset);
        view.byteOffset = out.size();
        out.insert(out.end(), begin, begin + std::ptrdiff_t(view.byteLength));
        new_index[i] = int(views.size());
        views.push_back(std::move(view));
    }
    while (out.size() % 4 != 0) out.push_back(0);
    model.bufferViews = std::move(views);
    for (tinygltf::Accessor& a : model.accessors)
        if (a.bufferView >= 0) a.bufferView = new_index[size_t(a.bufferView)];
    for (tinygltf::Image& i : model.images)
        if (i.bufferView >= 0) i.bufferView = new_index[size_t(i.bufferView)];
    for (const ViewPatch& p : patches) {
        tinygltf::ExtensionMap& target = patchTarget(model, p);
        tinygltf::Value::Object object = target[p.extension].Get<tinygltf::Value::Object>();
        object[p.member] = tinygltf::Value(new_index[size_t(object[p.member].Get<int>())]);
        target[p.extension] = tinygltf::Value(std::move(object));
    }
    return out;
}

// An output stream buffer that appends to a byte vector: the GLB is written once, straight into the
// vector returned, rather than into a stringstream that is then copied twice.
class VectorStreamBuf : public std::streambuf {
public:
    explicit VectorStreamBuf(std::vector<uint8_t>& out) : out_(out) {}

protected:
    std::streamsize xsputn(const char* s, std::streamsize n) override {
        const auto* p = reinterpret_cast<const uint8_t*>(s);
        out_.insert(out_.end(), p, p + n);
        return n;
    }
    int_type overflow(int_type c) override {
        if (!traits_type::eq_int_type(c, traits_type::eof())) out_.push_back(uint8_t(traits_type::to_char_type(c)));
        return traits_type::not_eof(c);
    }

private:
    std::vector<uint8_t>& out_;
};

// Frees what a level no longer needs once it is in the model (its mesh and extension blobs).
void releaseLevel(PackLevel& level) {
    level.mesh = Mesh();
    for (PackExtension& e : level.mesh_extensions) {
        std::vector<std::vector<uint8_t>>().swap(e.blobs);
        e.spilled.clear(); // the writer keeps the files it still needs
    }
    for (auto& list : level.primitive_extensions)
        for (PackExtension& e : list) {
            std::vector<std::vector<uint8_t>>().swap(e.blobs);
            e.spilled.clear();
        }
}

void appendU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

// The GLB tinygltf writes for a model whose only buffer holds `bin_size` bytes, up to where those
// bytes start, given `shell`: what it wrote for the same model with that buffer empty (its JSON then
// says "byteLength":0 and it has no BIN chunk). Same layout as tinygltf's WriteBinaryGltfStream:
// 12-byte header, the JSON chunk padded with spaces to 4 bytes, the BIN chunk (padded with zeros by
// the caller) after its 8-byte chunk header.
// `web`: the --web pack's compressed views (their extension objects and the fallback buffer), or null.
Result<std::vector<uint8_t>> glbHead(const std::vector<uint8_t>& shell, uint64_t bin_size, const WebViews* web) {
    if (shell.size() < 20) return internalError("pack: tinygltf wrote no GLB header");
    uint32_t json_chunk = 0;
    for (int k = 0; k < 4; ++k) json_chunk |= uint32_t(shell[12 + size_t(k)]) << (8 * k);
    if (size_t(json_chunk) + 20 > shell.size()) return internalError("pack: tinygltf wrote a short JSON chunk");
    std::string json(shell.begin() + 20, shell.begin() + 20 + std::ptrdiff_t(json_chunk));
    while (!json.empty() && json.back() == ' ') json.pop_back();
    if (web) LODBAKE_RETURN_IF_ERROR(webPatchJson(json, *web));
    const std::string extra_buffers = web ? webFallbackBufferJson(*web) : std::string();
    const std::string empty = "\"buffers\":[{\"byteLength\":0}]";
    const size_t at = json.find(empty);
    if (at == std::string::npos || json.find(empty, at + 1) != std::string::npos)
        return internalError("pack: the GLB's buffer entry was not found");
    if (bin_size > 0xffffffffull - 64 - json.size()) return resourceLimit("pack: GLB larger than 4 GiB");
    if (bin_size > 0)
        json.replace(at, empty.size(),
                     "\"buffers\":[{\"byteLength\":" + std::to_string(bin_size) + "}" +
                         (extra_buffers.empty() ? "" : "," + extra_buffers) + "]");
    const uint32_t json_pad = uint32_t((4 - json.size() % 4) % 4), bin_pad = uint32_t((4 - bin_size % 4) % 4);
    const uint32_t json_length = uint32_t(json.size()) + json_pad;
    const uint32_t total = 12 + 8 + json_length + (bin_size ? 8 + uint32_t(bin_size) + bin_pad : 0);
    std::vector<uint8_t> head;
    head.reserve(28 + json_length);
    head.insert(head.end(), {'g', 'l', 'T', 'F'});
    appendU32(head, 2);
    appendU32(head, total);
    appendU32(head, json_length);
    appendU32(head, 0x4E4F534Au); // "JSON"
    head.insert(head.end(), json.begin(), json.end());
    head.insert(head.end(), json_pad, uint8_t(' '));
    if (bin_size == 0) return head;
    appendU32(head, uint32_t(bin_size) + bin_pad);
    appendU32(head, 0x004E4942u); // "BIN\0"
    return head;
}

// The whole GLB with `bin` as its binary chunk; `bin` becomes the result (its bytes move once).
Result<std::vector<uint8_t>> assembleGlb(const std::vector<uint8_t>& shell, std::vector<uint8_t> bin,
                                         const WebViews* web) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> head, glbHead(shell, bin.size(), web));
    if (bin.empty()) return head;
    bin.insert(bin.end(), (4 - bin.size() % 4) % 4, uint8_t(0));
    bin.insert(bin.begin(), head.begin(), head.end());
    return bin;
}

// A view whose bytes are in a file: in the in-memory binary chunk it is empty at `bin_offset`; the
// GLB holds the file's `size` bytes there, padded with zeros to 4.
struct SpilledView {
    uint64_t bin_offset = 0;
    uint64_t size = 0;
    std::shared_ptr<const SpillFile> file;
};

uint64_t align4(uint64_t n) { return (n + 3) / 4 * 4; }

// Gives each spilled view its length and moves every later view by the room it takes, so the views
// are where the same blob in memory would have put them (the binary chunk's views are in offset
// order, each 4-aligned). Returns the spilled views in offset order.
Result<std::vector<SpilledView>> placeSpilledViews(tinygltf::Model& model, const std::vector<ViewPatch>& patches) {
    std::map<int, std::shared_ptr<const SpillFile>> spilled;
    for (const ViewPatch& p : patches) {
        if (!p.spilled) continue;
        const tinygltf::Value& v = patchTarget(model, p)[p.extension].Get(p.member);
        if (!v.IsInt() || v.Get<int>() < 0 || size_t(v.Get<int>()) >= model.bufferViews.size())
            return internalError("pack: extension " + p.extension + ": spilled view not found");
        spilled[v.Get<int>()] = p.spilled;
    }
    std::vector<SpilledView> out;
    uint64_t shift = 0;
    for (size_t i = 0; i < model.bufferViews.size(); ++i) {
        tinygltf::BufferView& view = model.bufferViews[i];
        const auto it = spilled.find(int(i));
        if (it != spilled.end()) out.push_back({uint64_t(view.byteOffset), it->second->bytesWritten(), it->second});
        view.byteOffset = size_t(view.byteOffset + shift);
        if (it == spilled.end()) continue;
        view.byteLength = size_t(out.back().size);
        shift += align4(out.back().size);
    }
    return out;
}

// An upper bound of the binary chunk's size: every attribute stream as floats, indices as 32 bits,
// every texture and extension blob, and the alignment of each buffer view. The buffer is reserved
// with it, so the pack's bytes are copied into it once (growing by doubling copied each byte about
// twice more and mapped fresh pages for each copy); the part never written is never touched.
size_t binaryBound(const PackDescription& description) {
    size_t bytes = 0;
    auto blobs = [&](const std::vector<PackExtension>& list) {
        for (const PackExtension& e : list)
            for (const std::vector<uint8_t>& b : e.blobs) bytes += b.size() + 4;
    };
    for (const PackAsset& asset : description.assets) {
        blobs(asset.node_extensions);
        for (const PackLevel& level : asset.levels) {
            const Mesh& m = level.mesh;
            const size_t per_vertex = sizeof(Vec3f) * 2 + sizeof(Vec4f) * 2 + sizeof(Vec2f) * m.uvs.size();
            const size_t primitives = std::max<size_t>(1, m.submeshes.size());
            bytes += m.vertexCount() * per_vertex + m.indices.size() * sizeof(uint32_t) + 64 * primitives;
            for (const Texture& t : m.textures) bytes += t.bytes.size() + 4;
            blobs(level.mesh_extensions);
            for (const auto& list : level.primitive_extensions) blobs(list);
        }
    }
    return bytes;
}

// The asset's level meshes with their mesh and primitive extensions, in level order; returns their
// mesh indices. `owned`, when set, is the asset itself: each level is released once in the model.
// `web`: the --web pack's compressed views (levels in web order, each mesh's position step), or null.
Result<std::vector<int>> addAssetMeshes(tinygltf::Model& model, BufferBuilder& buffer, ModelDedupe& dedupe,
                                        const PackAsset& asset, PackAsset* owned, std::set<std::string>& used,
                                        std::set<std::string>& streams, std::vector<ViewPatch>& patches,
                                        WebViews* web) {
    if (asset.levels.empty()) return invalidInput("pack: asset \"" + asset.name + "\" has no levels");
    dedupe.first_material = model.materials.size(); // share materials within one asset only
    std::vector<int> meshes;
    for (size_t l = 0; l < asset.levels.size(); ++l) {
        const PackLevel& level = asset.levels[l];
        const std::string level_name = asset.name + "_lod" + std::to_string(l);
        std::vector<std::pair<uint32_t, uint32_t>> ranges;
        for (const PackLevel::VertexRange& r : level.primitive_vertex_ranges) ranges.emplace_back(r.first, r.count);
        const Mesh web_mesh = web ? webLevelOrder(level.mesh) : Mesh();
        Result<int> mesh_index =
            addMeshToModel(model, buffer, web ? web_mesh : level.mesh, &dedupe, ranges.empty() ? nullptr : &ranges);
        if (!mesh_index.ok())
            return Status(mesh_index.status().code(), level_name + ": " + mesh_index.status().message());
        tinygltf::Mesh& gmesh = model.meshes[size_t(*mesh_index)];
        gmesh.name = level_name;
        if (web) {
            web->mesh_position_step.resize(model.meshes.size());
            web->mesh_position_step[size_t(*mesh_index)] = level.web_position_step;
        }
        ViewPatch where;
        where.object = size_t(*mesh_index);
        for (const PackExtension& e : level.mesh_extensions)
            LODBAKE_RETURN_IF_ERROR(addExtension(e, buffer, gmesh.extensions, used, streams, where, patches));
        if (!level.primitive_extensions.empty() && level.primitive_extensions.size() != gmesh.primitives.size())
            return internalError(level_name + ": primitive extension lists do not match the primitives");
        where.scope = ViewPatch::Scope::Primitive;
        for (size_t p = 0; p < level.primitive_extensions.size(); ++p) {
            where.primitive = p;
            for (const PackExtension& e : level.primitive_extensions[p])
                LODBAKE_RETURN_IF_ERROR(
                    addExtension(e, buffer, gmesh.primitives[p].extensions, used, streams, where, patches));
        }
        if (owned) releaseLevel(owned->levels[l]);
        meshes.push_back(*mesh_index);
    }
    return meshes;
}

// MSFT_lod on nodes[0] (the other nodes, coarser in order) and its MSFT_screencoverage extras.
void setLodGroup(tinygltf::Model& model, const std::vector<int>& nodes, const std::vector<double>& screen_coverage,
                 std::set<std::string>& used) {
    if (nodes.size() < 2) return;
    tinygltf::Node& root = model.nodes[size_t(nodes[0])];
    tinygltf::Value::Array ids;
    for (size_t l = 1; l < nodes.size(); ++l) ids.push_back(tinygltf::Value(nodes[l]));
    tinygltf::Value::Object lod;
    lod["ids"] = tinygltf::Value(std::move(ids));
    root.extensions[lodrt::format::kExtMsftLod] = tinygltf::Value(std::move(lod));
    used.insert(lodrt::format::kExtMsftLod);
    if (screen_coverage.size() == nodes.size()) {
        tinygltf::Value::Array coverage;
        for (double c : screen_coverage) coverage.push_back(tinygltf::Value(c));
        tinygltf::Value::Object extras;
        extras[lodrt::format::kMsftScreenCoverage] = tinygltf::Value(std::move(coverage));
        root.extras = tinygltf::Value(std::move(extras));
    }
}

// ---- Scene graphs (PackScene) -------------------------------------------------------------------

// Indices in range, one parent per node, roots without a parent, transforms of the right sizes.
Status checkScene(const PackDescription& description) {
    const PackScene& scene = description.scene;
    std::vector<int> parents(scene.nodes.size(), 0);
    for (size_t n = 0; n < scene.nodes.size(); ++n) {
        const PackNode& node = scene.nodes[n];
        const std::string where = "pack: scene node " + std::to_string(n);
        if (node.asset >= 0 && size_t(node.asset) >= description.assets.size())
            return internalError(where + ": asset " + std::to_string(node.asset) + " does not exist");
        if (!node.matrix.empty() && node.matrix.size() != 16) return internalError(where + ": matrix needs 16 numbers");
        if ((!node.translation.empty() && node.translation.size() != 3) ||
            (!node.rotation.empty() && node.rotation.size() != 4) || (!node.scale.empty() && node.scale.size() != 3))
            return internalError(where + ": translation, rotation or scale of the wrong size");
        for (uint32_t c : node.children) {
            if (c >= scene.nodes.size() || ++parents[c] > 1)
                return internalError(where + ": child " + std::to_string(c) + " missing or with two parents");
        }
    }
    for (uint32_t r : scene.roots)
        if (r >= scene.nodes.size() || parents[r] != 0)
            return internalError("pack: scene root " + std::to_string(r) + " missing or a child");
    if (scene.roots.empty()) return internalError("pack: scene without roots");
    return Status::okStatus();
}

bool isIdentity(const std::array<double, 16>& m) {
    for (size_t i = 0; i < 16; ++i)
        if (m[i] != (i % 5 == 0 ? 1.0 : 0.0)) return false;
    return true;
}

// The input's local transform, as written.
void setLocalTransform(const PackNode& from, tinygltf::Node& node) {
    if (!from.matrix.empty()) {
        node.matrix = from.matrix;
        return;
    }
    node.translation = from.translation;
    node.rotation = from.rotation;
    node.scale = from.scale;
}

// The lower levels of the group on scene node `n` (model node `n`): nodes outside the scene (as
// MSFT_lod has them) placed where LOD0 is: a root's own transform, a child's world matrix (an
// engine puts a lower level in LOD0's place with the level node's own transform).
void addLowerLevelNodes(tinygltf::Model& model, const PackScene& scene, size_t n, bool is_root,
                        const std::string& base_name, const std::vector<int>& meshes, std::vector<int>& nodes) {
    const PackNode& from = scene.nodes[n];
    nodes.push_back(int(n));
    for (size_t l = 1; l < meshes.size(); ++l) {
        tinygltf::Node node;
        node.name = base_name + "_lod" + std::to_string(l);
        node.mesh = meshes[l];
        if (is_root)
            setLocalTransform(from, node);
        else if (!isIdentity(from.world))
            node.matrix.assign(from.world.begin(), from.world.end());
        model.nodes.push_back(std::move(node));
        nodes.push_back(int(model.nodes.size() - 1));
    }
}

// The scene graph: every PackScene node as model node of the same index (name, transform, children),
// each asset's level meshes written once, and on every node that names an asset a LOD group over
// nodes of its own that share those meshes. The asset's node extensions are written with the first
// such node; later instances copy them (their buffer views are shared).
Status addSceneGraph(tinygltf::Model& model, BufferBuilder& buffer, ModelDedupe& dedupe,
                     const PackDescription& description, PackDescription* owned, std::set<std::string>& used,
                     std::set<std::string>& streams, std::vector<ViewPatch>& patches, WebViews* web,
                     tinygltf::Scene& out) {
    LODBAKE_RETURN_IF_ERROR(checkScene(description));
    const PackScene& scene = description.scene;
    std::vector<std::vector<int>> asset_meshes;
    for (size_t a = 0; a < description.assets.size(); ++a) {
        LODBAKE_ASSIGN_OR_RETURN(std::vector<int> meshes,
                                 addAssetMeshes(model, buffer, dedupe, description.assets[a],
                                                owned ? &owned->assets[a] : nullptr, used, streams, patches, web));
        asset_meshes.push_back(std::move(meshes));
    }
    std::vector<bool> is_child(scene.nodes.size(), false);
    for (const PackNode& from : scene.nodes) {
        tinygltf::Node node;
        node.name = from.name_from_asset && from.asset >= 0 ? description.assets[size_t(from.asset)].name : from.name;
        setLocalTransform(from, node);
        for (uint32_t c : from.children) {
            node.children.push_back(int(c));
            is_child[c] = true;
        }
        if (from.asset >= 0) node.mesh = asset_meshes[size_t(from.asset)][0];
        model.nodes.push_back(std::move(node));
    }
    std::vector<int> first_instance(description.assets.size(), -1);
    for (size_t n = 0; n < scene.nodes.size(); ++n) {
        const int a = scene.nodes[n].asset;
        if (a < 0) continue;
        const PackAsset& asset = description.assets[size_t(a)];
        const std::string base = model.nodes[n].name.empty() ? asset.name : model.nodes[n].name;
        std::vector<int> nodes;
        addLowerLevelNodes(model, scene, n, !is_child[n], base, asset_meshes[size_t(a)], nodes);
        setLodGroup(model, nodes, asset.screen_coverage, used);
        ViewPatch where;
        where.scope = ViewPatch::Scope::Node;
        where.object = n;
        const int first = first_instance[size_t(a)];
        if (first < 0) {
            first_instance[size_t(a)] = int(n);
            for (const PackExtension& e : asset.node_extensions)
                LODBAKE_RETURN_IF_ERROR(
                    addExtension(e, buffer, model.nodes[n].extensions, used, streams, where, patches));
            continue;
        }
        for (const PackExtension& e : asset.node_extensions)
            model.nodes[n].extensions[e.name] = model.nodes[size_t(first)].extensions[e.name];
        const size_t patch_count = patches.size();
        for (size_t p = 0; p < patch_count; ++p)
            if (patches[p].scope == ViewPatch::Scope::Node && patches[p].object == size_t(first)) {
                ViewPatch copy = patches[p];
                copy.object = n;
                patches.push_back(std::move(copy));
            }
    }
    for (uint32_t r : scene.roots) out.nodes.push_back(int(r));
    return Status::okStatus();
}

// The GLB in parts: tinygltf's output for the model with an empty buffer, the binary chunk, the
// --web views and the views whose bytes are in files (empty in `bin`).
struct GlbParts {
    std::vector<uint8_t> shell, bin;
    WebViews web;
    bool has_web = false;
    std::vector<SpilledView> spilled;
};

// `owned`, when set, is `description` itself: each level's data is released as soon as the model
// holds a copy, so the pack's bytes never exist twice beside all the meshes.
Result<GlbParts> buildGlb(const PackDescription& description, PackDescription* owned) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = std::string("lodbake ") + kVersionString;
    BufferBuilder buffer(model);
    buffer.reserve(binaryBound(description) + kGlbHeadRoom);
    ModelDedupe dedupe;
    std::set<std::string> used, streams;
    std::vector<ViewPatch> patches;
    WebViews web;
    tinygltf::Scene scene;
    if (!description.scene.empty()) {
        LODBAKE_RETURN_IF_ERROR(
            addSceneGraph(model, buffer, dedupe, description, owned, used, streams, patches,
                          description.web ? &web : nullptr, scene));
    }
    for (size_t a = 0; a < description.assets.size() && description.scene.empty(); ++a) {
        const PackAsset& asset = description.assets[a];
        LODBAKE_ASSIGN_OR_RETURN(std::vector<int> meshes,
                                 addAssetMeshes(model, buffer, dedupe, asset, owned ? &owned->assets[a] : nullptr,
                                                used, streams, patches, description.web ? &web : nullptr));
        std::vector<int> nodes;
        for (size_t l = 0; l < meshes.size(); ++l) {
            tinygltf::Node node;
            node.name = l == 0 ? asset.name : asset.name + "_lod" + std::to_string(l);
            node.mesh = meshes[l];
            model.nodes.push_back(std::move(node));
            nodes.push_back(int(model.nodes.size() - 1));
        }
        setLodGroup(model, nodes, asset.screen_coverage, used);
        tinygltf::Node& root = model.nodes[size_t(nodes[0])];
        ViewPatch where;
        where.scope = ViewPatch::Scope::Node;
        where.object = size_t(nodes[0]);
        for (const PackExtension& e : asset.node_extensions)
            LODBAKE_RETURN_IF_ERROR(addExtension(e, buffer, root.extensions, used, streams, where, patches));
        scene.nodes.push_back(nodes[0]);
    }
    if (scene.nodes.empty()) return invalidInput("pack: nothing to write");
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;
    std::vector<uint8_t> bin = buffer.finish();
    std::set<std::string> required = description.compact ? streams : std::set<std::string>();
    if (description.web) {
        LODBAKE_RETURN_IF_ERROR(encodeWebAccessors(model, bin, web));
        required.insert(lodrt::format::kExtMeshoptCompression); // its fallback buffer has no bytes
        if (web.quantized) required.insert(lodrt::format::kExtKhrMeshQuantization);
        used.insert(required.begin(), required.end());
    }
    model.extensionsUsed.assign(used.begin(), used.end());
    model.extensionsRequired.assign(required.begin(), required.end());
    if (description.compact || description.web)
        bin = dropStreamedAccessors(model, description.compact ? streams : std::set<std::string>(), bin, patches);
    if (description.web) appendWebViews(model, bin, web);
    GlbParts parts;
    LODBAKE_ASSIGN_OR_RETURN(parts.spilled, placeSpilledViews(model, patches));
    if (description.web && !parts.spilled.empty())
        return unsupported("pack: --web packs hold no extension blobs in files");
    // tinygltf copies a buffer's data before writing it (and the GLB holds it a third time), so the
    // model is written with an empty buffer and the GLB is assembled here around the binary chunk,
    // byte for byte as tinygltf lays it out: the pack's bytes exist at most twice, briefly.
    model.buffers.push_back(tinygltf::Buffer());
    tinygltf::TinyGLTF writer;
    {
        VectorStreamBuf sink(parts.shell);
        std::ostream stream(&sink);
        if (!writer.WriteGltfSceneToStream(&model, stream, false, true) || !stream)
            return internalError("pack: tinygltf failed");
    }
    parts.bin = std::move(bin);
    parts.web = std::move(web);
    parts.has_web = description.web;
    return parts;
}

Result<std::vector<uint8_t>> writeImpl(const PackDescription& description, PackDescription* owned) {
    LODBAKE_ASSIGN_OR_RETURN(GlbParts parts, buildGlb(description, owned));
    if (!parts.spilled.empty()) return internalError("pack: an extension blob is in a file: use writePackGlbFile");
    return assembleGlb(parts.shell, std::move(parts.bin), parts.has_web ? &parts.web : nullptr);
}

// The GLB to `path` through a temporary: the head, then the binary chunk with each spilled view's
// file copied in its place through `buffer_bytes`.
Result<uint64_t> writeFileImpl(PackDescription& description, const std::string& path,
                               const std::atomic<bool>* cancel, size_t buffer_bytes) {
    LODBAKE_ASSIGN_OR_RETURN(GlbParts parts, buildGlb(description, &description));
    uint64_t bin_size = parts.bin.size();
    for (const SpilledView& v : parts.spilled) bin_size += align4(v.size);
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> head, glbHead(parts.shell, bin_size, parts.has_web ? &parts.web : nullptr));
    std::vector<uint8_t>().swap(parts.shell);
    SpillFile out;
    LODBAKE_RETURN_IF_ERROR(out.open(path, buffer_bytes));
    LODBAKE_RETURN_IF_ERROR(out.write(head.data(), head.size()));
    std::vector<uint8_t>().swap(head);
    static const uint8_t zeros[4] = {0, 0, 0, 0};
    std::vector<uint8_t> copy_buffer;
    uint64_t at = 0;
    auto writeBin = [&](uint64_t end) { // bin[at, end), never offsetting an empty array's null data()
        return end > at ? out.write(parts.bin.data() + at, size_t(end - at)) : Status::okStatus();
    };
    for (const SpilledView& v : parts.spilled) {
        LODBAKE_RETURN_IF_ERROR(writeBin(v.bin_offset));
        LODBAKE_RETURN_IF_ERROR(v.file->copyTo(out, v.size, copy_buffer, cancel));
        LODBAKE_RETURN_IF_ERROR(out.write(zeros, size_t(align4(v.size) - v.size)));
        at = v.bin_offset;
    }
    LODBAKE_RETURN_IF_ERROR(writeBin(parts.bin.size()));
    LODBAKE_RETURN_IF_ERROR(out.write(zeros, size_t(align4(bin_size) - bin_size)));
    if (cancel && cancel->load()) return ioError(path + ": writing cancelled");
    const uint64_t written = out.bytesWritten();
    LODBAKE_RETURN_IF_ERROR(out.commit());
    return written;
}

} // namespace

Result<std::vector<uint8_t>> writePackGlb(const PackDescription& description) {
    try {
        return writeImpl(description, nullptr);
    } catch (const std::exception& e) {
        return internalError(std::string("pack: glTF writing failed: ") + e.what());
    }
}

Result<std::vector<uint8_t>> writePackGlb(PackDescription&& description) {
    try {
        return writeImpl(description, &description);
    } catch (const std::exception& e) {
        return internalError(std::string("pack: glTF writing failed: ") + e.what());
    }
}

Result<uint64_t> writePackGlbFile(PackDescription&& description, const std::string& path,
                                  const std::atomic<bool>* cancel, size_t buffer_bytes) {
    try {
        return writeFileImpl(description, path, cancel, buffer_bytes);
    } catch (const std::exception& e) {
        return internalError(std::string("pack: glTF writing failed: ") + e.what());
    }
}

} // namespace lodbake
