// LODBAKE_valence_compression: each level's primitive coded with the valence codec
// (lodbake/codec/valence_encoder.h, docs/format/valence.md) into one buffer view.
//
// The codec chooses its own vertex and triangle order. Rather than carrying a remapping table, the
// level's mesh is renumbered into that order before the plain accessors are written, so a reader
// that decodes the stream gets exactly the triangles (same index triples) the plain indices hold,
// and attributes the codec does not code (UVs, colours, tangents) stay valid as plain accessors.
#include "lodbake/pack/pack.h"

#include <string>
#include <utility>

#include "lodbake/codec/valence_encoder.h"
#include "lodbake/core/json_writer.h"

namespace lodbake {

namespace {

template <typename T>
void permute(std::vector<T>& stream, const std::vector<uint32_t>& new_of_old) {
    if (stream.empty()) return;
    std::vector<T> out(stream.size());
    for (size_t v = 0; v < stream.size(); ++v) out[new_of_old[v]] = std::move(stream[v]);
    stream = std::move(out);
}

// True when decoded triangle t is input triangle old_face_of[t], renumbered, possibly rotated
// cyclically (which keeps its orientation).
bool sameTriangles(const Mesh& mesh, const codec::ValenceEncodeResult& encoded, const std::vector<uint32_t>& decoded) {
    if (decoded.size() != mesh.indices.size() || encoded.old_face_of.size() != mesh.faceCount()) return false;
    for (size_t t = 0; t < encoded.old_face_of.size(); ++t) {
        const size_t old = encoded.old_face_of[t];
        if (old >= mesh.faceCount()) return false;
        uint32_t want[3];
        for (int k = 0; k < 3; ++k) want[k] = encoded.new_vertex_of[mesh.indices[old * 3 + size_t(k)]];
        bool found = false;
        for (int r = 0; r < 3 && !found; ++r)
            found = decoded[t * 3] == want[r] && decoded[t * 3 + 1] == want[(r + 1) % 3] &&
                    decoded[t * 3 + 2] == want[(r + 2) % 3];
        if (!found) return false;
    }
    return true;
}

size_t primitiveCount(const Mesh& mesh) {
    if (mesh.submeshes.empty()) return mesh.indices.empty() ? 0 : 1;
    size_t n = 0;
    for (const SubMesh& s : mesh.submeshes) n += s.index_count > 0 ? 1 : 0;
    return n;
}

Status encodeLevel(const ValenceStreamOptions& options, size_t level_index, PackLevel& level) {
    Mesh& mesh = level.mesh;
    if (primitiveCount(mesh) != 1) return Status::okStatus();
    const std::string where = "level " + std::to_string(level_index) + ": LODBAKE_valence_compression";
    codec::ValenceEncodeOptions encode_options;
    encode_options.position_bits = options.position_bits;
    encode_options.normal_bits = options.normal_bits;
    encode_options.encode_normals = mesh.hasNormals();
    Result<codec::ValenceEncodeResult> encoded = codec::encodeValence(mesh, encode_options);
    if (!encoded.ok()) return Status(encoded.status().code(), where + ": " + encoded.status().message());
    // Decode with the runtime decoder: the indices written as plain accessors are the decoder's own,
    // and a codec that lost a triangle is caught here rather than in a reader.
    Result<Mesh> decoded = codec::decodeValence(encoded->bytes, where);
    if (!decoded.ok()) return internalError(decoded.status().message());
    if (decoded->vertexCount() != mesh.vertexCount() || encoded->new_vertex_of.size() != mesh.vertexCount() ||
        !sameTriangles(mesh, *encoded, decoded->indices))
        return internalError(where + ": the decoded triangles differ from the level's");

    permute(mesh.positions, encoded->new_vertex_of);
    permute(mesh.normals, encoded->new_vertex_of);
    permute(mesh.tangents, encoded->new_vertex_of);
    for (std::vector<Vec2f>& uv : mesh.uvs) permute(uv, encoded->new_vertex_of);
    permute(mesh.colors, encoded->new_vertex_of);
    mesh.indices = std::move(decoded->indices);
    // The single non-empty sub-mesh covers every index (empty ones before it start at 0, after it at the end).
    uint32_t offset = 0;
    for (SubMesh& s : mesh.submeshes) {
        s.first_index = offset;
        if (s.index_count > 0) s.index_count = uint32_t(mesh.indices.size());
        offset += s.index_count;
    }

    const bool has_normals = mesh.hasNormals();
    JsonWriter j(0);
    j.beginObject();
    j.key("attributes").beginObject();
    if (has_normals) j.field("NORMAL", uint64_t(1));
    j.field("POSITION", uint64_t(0));
    j.endObject();
    if (has_normals) j.field("normalBits", uint64_t(options.normal_bits));
    j.field("positionBits", uint64_t(options.position_bits));
    j.endObject();
    PackExtension e;
    e.name = "LODBAKE_valence_compression";
    e.json = j.str();
    e.blobs.push_back(std::move(encoded->bytes));
    e.blob_view_members.push_back("bufferView");
    e.is_stream = true;
    level.primitive_extensions.assign(1, {});
    level.primitive_extensions[0].push_back(std::move(e));
    return Status::okStatus();
}

} // namespace

PackStreamEncoder valenceStreamEncoder(const ValenceStreamOptions& options) {
    PackStreamEncoder encoder;
    encoder.extension_name = "LODBAKE_valence_compression";
    encoder.encode = [options](const LodChain&, size_t level_index, PackLevel& level) {
        return encodeLevel(options, level_index, level);
    };
    return encoder;
}

} // namespace lodbake
