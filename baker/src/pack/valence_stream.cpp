// LODBAKE_valence_compression: each level's primitive coded with the valence codec
// (lodbake/codec/valence_encoder.h, docs/format/valence.md) into one buffer view.
//
// The codec chooses its own vertex and triangle order. Rather than carrying a remapping table, the
// level's mesh is renumbered into that order before the plain accessors are written, so a reader
// that decodes the stream gets exactly the triangles (same index triples) the plain indices hold,
// and attributes the codec does not code (UVs, colours, tangents) stay valid as plain accessors.
#include "lodbake/pack/pack.h"

#include <memory>
#include <string>
#include <utility>

#include "lodbake/codec/valence_encoder.h"
#include "lodbake/core/json_writer.h"

namespace lodbake {

namespace {

template <typename T> void permute(std::vector<T>& stream, const std::vector<uint32_t>& new_of_old) {
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

// The codec's work for one level (read-only): the stream, checked by decoding it, and the
// renumbering that its commit applies to the level.
Result<PackStreamCommit> prepareLevel(const ValenceStreamOptions& options, size_t level_index, const Mesh& mesh) {
    if (primitiveCount(mesh) != 1) return PackStreamCommit();
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
    struct Prepared {
        std::vector<uint32_t> new_vertex_of;
        std::vector<uint32_t> indices; // the decoder's
        std::vector<uint8_t> bytes;
    };
    auto prepared = std::make_shared<Prepared>();
    prepared->new_vertex_of = std::move(encoded->new_vertex_of);
    prepared->indices = std::move(decoded->indices);
    prepared->bytes = std::move(encoded->bytes);
    const size_t vertex_count = mesh.vertexCount();
    return PackStreamCommit([options, prepared, vertex_count, where](PackLevel& level) -> Status {
        Mesh& m = level.mesh;
        if (m.vertexCount() != vertex_count) return internalError(where + ": the level changed after it was coded");
        const std::vector<uint32_t>& new_vertex_of = prepared->new_vertex_of;
        permute(m.positions, new_vertex_of);
        permute(m.normals, new_vertex_of);
        permute(m.tangents, new_vertex_of);
        for (std::vector<Vec2f>& uv : m.uvs) permute(uv, new_vertex_of);
        permute(m.colors, new_vertex_of);
        m.indices = std::move(prepared->indices);
        // The single non-empty sub-mesh covers every index (empty ones before it start at 0, after it at the end).
        uint32_t offset = 0;
        for (SubMesh& s : m.submeshes) {
            s.first_index = offset;
            if (s.index_count > 0) s.index_count = uint32_t(m.indices.size());
            offset += s.index_count;
        }

        const bool has_normals = m.hasNormals();
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
        e.blobs.push_back(std::move(prepared->bytes));
        e.blob_view_members.push_back("bufferView");
        e.is_stream = true;
        level.primitive_extensions.assign(1, {});
        level.primitive_extensions[0].push_back(std::move(e));
        return Status::okStatus();
    });
}

} // namespace

PackStreamEncoder valenceStreamEncoder(const ValenceStreamOptions& options) {
    return makeStreamEncoder("LODBAKE_valence_compression",
                             [options](const LodChain&, size_t level_index, const Mesh& mesh) {
                                 return prepareLevel(options, level_index, mesh);
                             });
}

} // namespace lodbake
