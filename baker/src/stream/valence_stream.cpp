// LODBAKE_valence_compression: each primitive of a level coded with the valence codec
// (lodbake/codec/valence_encoder.h, docs/format/valence.md) into one buffer view.
//
// The codec chooses its own vertex and triangle order. Rather than carrying a remapping table, the
// level's mesh is renumbered into that order before the plain accessors are written, so a reader
// that decodes a stream gets exactly the triangles (same index triples) the plain indices hold.
// Positions, normals, UV sets, colours and tangents are all in the stream (its "attributes" map names
// them), so a compact pack drops every one of their plain accessors.
// A level with several primitives (materials, scan sets) is laid out primitive by primitive, each
// primitive's vertices a range of its own in its stream's decoded order.
#include "lodbake/stream/stream.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "core/large_array.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodrt/format.h"
#include "lodrt/result.h"
#include "lodrt/valence.h"

namespace lodbake {

namespace {

constexpr uint32_t kMinPositionBits = 8; // the format's range (docs/format/valence.md)
constexpr uint32_t kMinNormalBits = 4;
// From this many triangles on, the coder's working set (about 150 bytes per triangle) is worth
// handing back before the check decodes (ValenceStreamOptions::release_memory).
constexpr size_t kReleaseMemoryTriangles = size_t(1) << 17;

template <typename T> void permute(std::vector<T>& stream, const std::vector<uint32_t>& new_of_old) {
    if (stream.empty()) return;
    std::vector<T> out(stream.size());
    for (size_t v = 0; v < stream.size(); ++v) out[new_of_old[v]] = std::move(stream[v]);
    stream = std::move(out);
}

// out[new] = in[old_of_new[new]] for every stream the mesh has.
template <typename T> std::vector<T> gather(const std::vector<T>& in, const std::vector<uint32_t>& old_of_new) {
    if (in.empty()) return {};
    std::vector<T> out(old_of_new.size());
    for (size_t v = 0; v < old_of_new.size(); ++v) out[v] = in[old_of_new[v]];
    return out;
}

// The check decoder's indices, on core/large_array.h's storage: from 2 MB on, huge pages where the OS
// offers them. In a std::vector they cost a 4 KB page fault per 1,024 indices; the commit copies them
// into the level's own index array, which is already resident and has the same size.
using DecodedIndices = detail::LargeArray<uint32_t>;

// True when decoded triangle t is input triangle old_face_of[t], renumbered, possibly rotated
// cyclically (which keeps its orientation).
bool sameTriangles(const Mesh& mesh, const codec::ValenceEncodeResult& encoded, const DecodedIndices& decoded) {
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

// The sub-meshes that become glTF primitives (the writer skips empty ones); one range when the mesh
// has no sub-meshes.
std::vector<SubMesh> primitiveRanges(const Mesh& mesh) {
    std::vector<SubMesh> out;
    if (mesh.submeshes.empty()) {
        if (!mesh.indices.empty()) out.push_back({"", 0, uint32_t(mesh.indices.size()), MaterialId::invalid()});
        return out;
    }
    for (const SubMesh& s : mesh.submeshes)
        if (s.index_count > 0) out.push_back(s);
    return out;
}

// One coded stream: the bytes, the decoder's indices, and where each input vertex went.
struct CodedStream {
    std::vector<uint8_t> bytes;
    std::vector<uint32_t> new_vertex_of; // input vertex -> decoded vertex
    DecodedIndices indices;              // the decoder's
    bool has_normals = false;
    std::vector<codec::ValenceAttributeReport> attributes; // in stream order
};

// An uninitialised array on core/large_array.h's storage: from 2 MB on it is mapped on its own and
// backed by transparent huge pages where the OS offers them. The check's decoder fills fresh blocks
// of up to about 150 bytes per triangle (its scratch and the positions it has to write); with 4 KB
// pages every first touch is a page fault, which on a large level costs more than the decode
// itself.
template <typename T> class ScratchArray {
public:
    explicit ScratchArray(size_t n) : n_(std::max<size_t>(n, 1)), p_(detail::LargeArrayAllocator<T>().allocate(n_)) {}
    ~ScratchArray() { detail::LargeArrayAllocator<T>().deallocate(p_, n_); }
    ScratchArray(const ScratchArray&) = delete;
    ScratchArray& operator=(const ScratchArray&) = delete;
    T* data() { return p_; }

private:
    size_t n_;
    T* p_;
};

// The check's decode with the runtime decoder: the indices only (the decoder still needs somewhere to
// put the positions; the normals it skips). Fails (internal error) when the stream does not decode or
// does not hold `vertex_count` vertices.
Result<DecodedIndices> decodeIndices(const std::vector<uint8_t>& bytes, size_t vertex_count, const std::string& where) {
    lodrt::ValenceInfo info;
    lodrt::Result r = lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info);
    if (r != lodrt::Result::Ok) return internalError(where + ": header: " + lodrt::resultName(r));
    if (info.vertex_count != vertex_count)
        return internalError(where + ": the stream decodes " + std::to_string(info.vertex_count) + " vertices, expected " +
                             std::to_string(vertex_count));
    DecodedIndices indices(3 * size_t(info.triangle_count));
    // Not value-initialised: the decoder writes every scratch word before it reads it, and the parts
    // sized for the worst case stay untouched and so cost no resident memory.
    ScratchArray<float> positions(3 * size_t(info.vertex_count));
    const size_t scratch_words = (lodrt::valenceScratchSize(info) + 7) / 8;
    ScratchArray<uint64_t> scratch(scratch_words);
    lodrt::ValenceOutput output;
    output.indices = indices.data();
    output.index_capacity = indices.size();
    output.positions = positions.data();
    output.position_capacity = 3 * size_t(info.vertex_count);
    output.normals = nullptr; // skipped: the check compares triangles
    output.scratch = scratch.data();
    output.scratch_size = scratch_words * 8;
    r = lodrt::valenceDecode(bytes.data(), bytes.size(), output);
    if (r != lodrt::Result::Ok) return internalError(where + ": streams: " + lodrt::resultName(r));
    return indices;
}

// Codes `mesh` (positions, normals, one triangle list) and checks the stream by decoding it with the
// runtime decoder: the indices written as plain accessors are the decoder's own, and a codec that
// lost a triangle is caught here rather than in a reader.
codec::ValenceEncodeOptions encodeOptions(const Mesh& mesh, const ValencePrecision& precision) {
    codec::ValenceEncodeOptions encode_options;
    encode_options.position_bits = precision.position_bits;
    encode_options.normal_bits = precision.normal_bits;
    encode_options.encode_normals = mesh.hasNormals();
    encode_options.uv_bits = precision.uv_bits;
    encode_options.color_bits = precision.color_bits;
    encode_options.tangent_bits = precision.tangent_bits;
    return encode_options;
}

Result<CodedStream> codeStream(const Mesh& mesh, const ValencePrecision& precision, const std::string& where,
                               const std::function<void()>& release_memory) {
    Result<codec::ValenceEncodeResult> encoded = codec::encodeValence(mesh, encodeOptions(mesh, precision));
    if (!encoded.ok()) return Status(encoded.status().code(), where + ": " + encoded.status().message());
    // The decoder's scratch is one large block that the allocator maps fresh, while the coder's freed
    // tables may still be resident: without this the check's peak sits on top of the coder's (peak
    // memory: docs/benchmarks.md, "Bake time and peak memory against native meshoptimizer"). Small
    // meshes are not worth the call.
    if (release_memory && mesh.faceCount() >= kReleaseMemoryTriangles) release_memory();
    LODBAKE_ASSIGN_OR_RETURN(DecodedIndices decoded, decodeIndices(encoded->bytes, mesh.vertexCount(), where));
    if (encoded->new_vertex_of.size() != mesh.vertexCount() || !sameTriangles(mesh, *encoded, decoded))
        return internalError(where + ": the decoded triangles differ from the level's");
    CodedStream out;
    out.bytes = std::move(encoded->bytes);
    out.new_vertex_of = std::move(encoded->new_vertex_of);
    out.indices = std::move(decoded);
    out.has_normals = mesh.hasNormals();
    out.attributes = std::move(encoded->attributes);
    return out;
}

PackExtension streamExtension(CodedStream& stream, const ValencePrecision& precision) {
    JsonNode attributes = JsonNode::object();
    if (stream.has_normals) attributes.set("NORMAL", uint64_t(1));
    attributes.set("POSITION", uint64_t(0));
    // The stream's attribute table, in order, takes the ids from 2 on.
    bool uv = false, color = false, tangent = false;
    for (size_t i = 0; i < stream.attributes.size(); ++i) {
        const codec::ValenceAttributeReport& a = stream.attributes[i];
        std::string name = "TANGENT";
        if (a.kind == lodrt::format::kValenceAttributeUv) name = "TEXCOORD_" + std::to_string(a.set);
        if (a.kind == lodrt::format::kValenceAttributeColor) name = "COLOR_" + std::to_string(a.set);
        attributes.set(name, uint64_t(2 + i));
        uv = uv || a.kind == lodrt::format::kValenceAttributeUv;
        color = color || a.kind == lodrt::format::kValenceAttributeColor;
        tangent = tangent || a.kind == lodrt::format::kValenceAttributeTangent;
    }
    PackExtension e;
    e.name = lodrt::format::kExtValenceCompression;
    e.json = JsonNode::object();
    e.json.set("attributes", std::move(attributes));
    if (color) e.json.set("colorBits", uint64_t(precision.color_bits));
    if (stream.has_normals) e.json.set("normalBits", uint64_t(precision.normal_bits));
    e.json.set("positionBits", uint64_t(precision.position_bits));
    if (tangent) e.json.set("tangentBits", uint64_t(precision.tangent_bits));
    if (uv) e.json.set("uvBits", uint64_t(precision.uv_bits));
    e.blobs.push_back(std::move(stream.bytes));
    e.blob_view_members.push_back("bufferView");
    e.is_stream = true;
    return e;
}

// A level with one primitive: coded whole (unreferenced vertices too); the commit renumbers it.
Result<PackStreamCommit> prepareSingle(const ValencePrecision& precision, const std::string& where, const Mesh& mesh,
                                       const std::function<void()>& release_memory) {
    LODBAKE_ASSIGN_OR_RETURN(CodedStream coded, codeStream(mesh, precision, where, release_memory));
    auto prepared = std::make_shared<CodedStream>(std::move(coded));
    const size_t vertex_count = mesh.vertexCount();
    return PackStreamCommit([precision, prepared, vertex_count, where](PackLevel& level) -> Status {
        Mesh& m = level.mesh;
        if (m.vertexCount() != vertex_count) return internalError(where + ": the level changed after it was coded");
        const std::vector<uint32_t>& new_vertex_of = prepared->new_vertex_of;
        permute(m.positions, new_vertex_of);
        permute(m.normals, new_vertex_of);
        permute(m.tangents, new_vertex_of);
        for (std::vector<Vec2f>& uv : m.uvs) permute(uv, new_vertex_of);
        permute(m.colors, new_vertex_of);
        m.indices.assign(prepared->indices.begin(), prepared->indices.end());
        // The single non-empty sub-mesh covers every index (empty ones before it start at 0, after it at the end).
        uint32_t offset = 0;
        for (SubMesh& s : m.submeshes) {
            s.first_index = offset;
            if (s.index_count > 0) s.index_count = uint32_t(m.indices.size());
            offset += s.index_count;
        }
        level.primitive_vertex_ranges.clear();
        level.primitive_extensions.assign(1, {});
        level.primitive_extensions[0].push_back(streamExtension(*prepared, precision));
        return Status::okStatus();
    });
}

// A level with several primitives: each primitive's referenced vertices (in increasing index order)
// coded as a mesh of their own. The commit lays the level out primitive by primitive.
Result<PackStreamCommit> prepareMulti(const ValencePrecision& precision, const std::string& where, const Mesh& mesh,
                                      const std::vector<SubMesh>& ranges, const std::function<void()>& release_memory) {
    struct Primitive {
        std::vector<uint32_t> level_vertex_of; // local (input order) -> level vertex
        CodedStream coded;
    };
    auto prepared = std::make_shared<std::vector<Primitive>>(ranges.size());
    std::vector<uint32_t> local_of(mesh.vertexCount(), UINT32_MAX);
    for (size_t p = 0; p < ranges.size(); ++p) {
        const SubMesh& range = ranges[p];
        if (size_t(range.first_index) + range.index_count > mesh.indices.size() || range.index_count % 3 != 0)
            return internalError(where + ": sub-mesh " + std::to_string(p) + " does not fit the index list");
        Primitive& primitive = (*prepared)[p];
        std::vector<uint32_t> used(mesh.indices.begin() + range.first_index,
                                   mesh.indices.begin() + range.first_index + range.index_count);
        std::sort(used.begin(), used.end());
        used.erase(std::unique(used.begin(), used.end()), used.end());
        if (!used.empty() && used.back() >= mesh.vertexCount())
            return internalError(where + ": sub-mesh " + std::to_string(p) + " uses a vertex the level does not have");
        for (size_t i = 0; i < used.size(); ++i) local_of[used[i]] = uint32_t(i);
        Mesh local;
        local.positions = gather(mesh.positions, used);
        local.normals = gather(mesh.normals, used);
        local.tangents = gather(mesh.tangents, used);
        local.colors = gather(mesh.colors, used);
        for (const std::vector<Vec2f>& uv : mesh.uvs) local.uvs.push_back(gather(uv, used));
        local.indices.reserve(range.index_count);
        for (uint32_t i = range.first_index; i < range.first_index + range.index_count; ++i)
            local.indices.push_back(local_of[mesh.indices[i]]);
        const std::string primitive_where = where + " (primitive " + std::to_string(p) + ")";
        LODBAKE_ASSIGN_OR_RETURN(primitive.coded, codeStream(local, precision, primitive_where, release_memory));
        primitive.level_vertex_of = std::move(used);
    }
    const size_t vertex_count = mesh.vertexCount();
    return PackStreamCommit([precision, prepared, vertex_count, where](PackLevel& level) -> Status {
        Mesh& m = level.mesh;
        if (m.vertexCount() != vertex_count) return internalError(where + ": the level changed after it was coded");
        std::vector<uint32_t> old_of_new; // new level vertex -> old level vertex
        std::vector<uint32_t> indices;
        std::vector<PackLevel::VertexRange> vertex_ranges;
        std::vector<std::pair<uint32_t, uint32_t>> index_ranges;
        for (Primitive& primitive : *prepared) {
            const auto first = uint32_t(old_of_new.size());
            const auto count = uint32_t(primitive.level_vertex_of.size());
            old_of_new.resize(old_of_new.size() + count);
            for (uint32_t local = 0; local < count; ++local)
                old_of_new[first + primitive.coded.new_vertex_of[local]] = primitive.level_vertex_of[local];
            index_ranges.emplace_back(uint32_t(indices.size()), uint32_t(primitive.coded.indices.size()));
            for (uint32_t i : primitive.coded.indices) indices.push_back(first + i);
            vertex_ranges.push_back({first, count});
        }
        m.positions = gather(m.positions, old_of_new);
        m.normals = gather(m.normals, old_of_new);
        m.tangents = gather(m.tangents, old_of_new);
        for (std::vector<Vec2f>& uv : m.uvs) uv = gather(uv, old_of_new);
        m.colors = gather(m.colors, old_of_new);
        m.indices = std::move(indices);
        // Non-empty sub-meshes take their primitive's triangles; empty ones keep an empty range in place.
        size_t p = 0;
        uint32_t offset = 0;
        for (SubMesh& s : m.submeshes) {
            if (s.index_count > 0) {
                s.first_index = index_ranges[p].first;
                s.index_count = index_ranges[p].second;
                ++p;
            } else {
                s.first_index = offset;
            }
            offset = s.first_index + s.index_count;
        }
        level.primitive_vertex_ranges = std::move(vertex_ranges);
        level.primitive_extensions.assign(prepared->size(), {});
        for (size_t q = 0; q < prepared->size(); ++q)
            level.primitive_extensions[q].push_back(streamExtension((*prepared)[q].coded, precision));
        return Status::okStatus();
    });
}

Result<PackStreamCommit> prepareLevel(const ValenceStreamOptions& options, const LodChain& chain, size_t level_index,
                                      const Mesh& mesh) {
    const std::vector<SubMesh> ranges = primitiveRanges(mesh);
    if (ranges.empty()) return PackStreamCommit();
    const std::string where = "level " + std::to_string(level_index) + ": LODBAKE_valence_compression";
    const ValencePrecision precision = valencePrecision(options, chain, level_index, mesh);
    // Several primitives, or one that is not the whole index list (the commit keeps the layout simple).
    if (ranges.size() == 1 && ranges[0].first_index == 0 && ranges[0].index_count == mesh.indices.size())
        return prepareSingle(precision, where, mesh, options.release_memory);
    return prepareMulti(precision, where, mesh, ranges, options.release_memory);
}

// Median edge length of the mesh's triangles (each triangle's three edges; 0 without triangles).
double medianEdgeLength(const Mesh& mesh) {
    std::vector<double> lengths;
    lengths.reserve(mesh.indices.size());
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const Vec3f& a = mesh.positions[mesh.indices[t + size_t(k)]];
            const Vec3f& b = mesh.positions[mesh.indices[t + size_t((k + 1) % 3)]];
            lengths.push_back(length(toDouble(b) - toDouble(a)));
        }
    if (lengths.empty()) return 0.0;
    std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(lengths.size() / 2), lengths.end());
    return lengths[lengths.size() / 2];
}

// Largest extent of the bounding box of every vertex, unreferenced ones too (the codec's
// quantization cube edge; computeBounds would leave strays out).
double cubeSize(const Mesh& mesh) {
    Aabb box;
    for (const Vec3f& p : mesh.positions) box.expand(p);
    if (box.isEmpty()) return 0.0;
    return std::max({double(box.max.x) - box.min.x, double(box.max.y) - box.min.y, double(box.max.z) - box.min.z});
}

double displacementBound(double cube, uint32_t bits) {
    return std::sqrt(3.0) / 2.0 * cube / double((uint32_t(1) << bits) - 1);
}

} // namespace

double octahedralMaxAngle(uint32_t bits) {
    static std::mutex mutex;
    static std::array<double, 17> cache{};
    bits = std::min<uint32_t>(std::max<uint32_t>(bits, 2), 16);
    // Measured up to 10 bits; above, the worst angle scales with the step (the mapping is smooth).
    constexpr uint32_t kMeasuredBits = 10;
    if (bits > kMeasuredBits)
        return octahedralMaxAngle(kMeasuredBits) * double((1u << kMeasuredBits) - 1) / double((1u << bits) - 1);
    const std::lock_guard<std::mutex> lock(mutex);
    if (cache[bits] > 0.0) return cache[bits];
    // Every direction whose octahedral coordinates lie on a grid of a quarter of the coded step: the
    // coded values, the rounding boundaries between them (the worst round-off) and the points between.
    const int steps = 2 * int((1u << bits) - 1); // grid points per unit of u and v
    // acos is decreasing with a slope of at least 1 in magnitude: a cosine more than kMargin above the
    // smallest one met so far has an angle smaller than that one's by far more than acos's rounding, so
    // the acos (most of the time of this loop) is taken only near the smallest cosine.
    constexpr double kMargin = 1e-9;
    double worst = 0.0, smallest = 2.0;
    for (int i = 0; i <= 2 * steps; ++i)
        for (int j = 0; j <= 2 * steps; ++j) {
            const double u = -1.0 + double(i) / steps, v = -1.0 + double(j) / steps;
            double x = u, y = v;
            const double z = 1.0 - std::fabs(u) - std::fabs(v);
            if (z < 0.0) {
                x = (1.0 - std::fabs(v)) * (u < 0.0 ? -1.0 : 1.0);
                y = (1.0 - std::fabs(u)) * (v < 0.0 ? -1.0 : 1.0);
            }
            const double len = std::sqrt(x * x + y * y + z * z);
            const float n[3] = {float(x / len), float(y / len), float(z / len)};
            uint32_t q[2];
            lodrt::octahedralEncode(n, bits, q);
            float d[3];
            lodrt::octahedralDecode(q, bits, d);
            const double dlen = std::sqrt(double(d[0]) * d[0] + double(d[1]) * d[1] + double(d[2]) * d[2]);
            const double dot = (double(n[0]) * d[0] + double(n[1]) * d[1] + double(n[2]) * d[2]) / dlen;
            const double c = std::min(1.0, std::max(-1.0, dot));
            if (c > smallest + kMargin) continue;
            smallest = std::min(smallest, c);
            worst = std::max(worst, std::acos(c));
        }
    cache[bits] = worst;
    return worst;
}

ValencePrecision valencePrecision(const ValenceStreamOptions& options, const LodChain& chain, size_t level_index,
                                  const Mesh& mesh) {
    ValencePrecision p;
    p.position_bits = options.position_bits;
    p.normal_bits = options.normal_bits;
    p.uv_bits = options.uv_bits;
    p.color_bits = options.color_bits;
    p.tangent_bits = options.tangent_bits;
    const double cube = cubeSize(mesh);
    p.max_displacement = displacementBound(cube, p.position_bits);
    p.max_normal_angle = mesh.hasNormals() ? octahedralMaxAngle(p.normal_bits) : 0.0;
    if (!options.adaptive || level_index == 0 || level_index > chain.levels.size()) return p;
    const LodLevel& level = chain.levels[level_index - 1];
    if (!level.has_distance || !(level.distance.mean > 0.0) || !(cube > 0.0)) return p;
    // Positions: the fewest bits whose largest displacement is at most error_fraction of the level's
    // own measured mean distance to LOD0.
    const double allowed = options.error_fraction * level.distance.mean;
    for (uint32_t bits = kMinPositionBits; bits < options.position_bits; ++bits)
        if (displacementBound(cube, bits) <= allowed) {
            p.position_bits = bits;
            break;
        }
    p.max_displacement = displacementBound(cube, p.position_bits);
    if (!mesh.hasNormals()) return p;
    // Normals: the level's surface lies a mean distance e from LOD0's, over edges of median length L,
    // so its faces already lean by about atan(e / L) against LOD0's; the fewest bits whose largest
    // rounding angle is at most error_fraction of that lean.
    const double edge = medianEdgeLength(mesh);
    if (!(edge > 0.0)) return p;
    const double allowed_angle = options.error_fraction * std::atan(level.distance.mean / edge);
    for (uint32_t bits = kMinNormalBits; bits < options.normal_bits; ++bits)
        if (octahedralMaxAngle(bits) <= allowed_angle) {
            p.normal_bits = bits;
            break;
        }
    p.max_normal_angle = octahedralMaxAngle(p.normal_bits);
    return p;
}

PackStreamEncoder valenceStreamEncoder(const ValenceStreamOptions& options) {
    StreamNeeds needs;
    needs.measured_errors = options.adaptive; // adaptive precision follows each level's measured error
    StreamCost cost;
    cost.bytes_per_triangle = 110; // the coder's tables, then its check's decoder
    return makeStreamEncoder(lodrt::format::kExtValenceCompression, needs, cost,
                             [options](const LodChain& chain, size_t level_index, const Mesh& mesh) {
                                 return prepareLevel(options, chain, level_index, mesh);
                             });
}

std::optional<PackStreamEncoder> valenceStream(const StreamSettings& settings) {
    return valenceStreamEncoder(settings.valence);
}

Result<std::optional<DecodedLevelStream>> decodedLevelStream(const ValenceStreamOptions& options, const LodChain& chain,
                                                             size_t level_index, const Mesh& mesh) {
    const std::vector<SubMesh> ranges = primitiveRanges(mesh);
    if (ranges.size() != 1 || ranges[0].first_index != 0 || ranges[0].index_count != mesh.indices.size())
        return std::optional<DecodedLevelStream>();
    const ValencePrecision precision = valencePrecision(options, chain, level_index, mesh);
    LODBAKE_ASSIGN_OR_RETURN(codec::ValenceEncodeResult encoded,
                             codec::encodeValence(mesh, encodeOptions(mesh, precision)));
    DecodedLevelStream out;
    LODBAKE_ASSIGN_OR_RETURN(out.mesh, codec::decodeValence(encoded.bytes, "level " + std::to_string(level_index)));
    out.new_vertex_of = std::move(encoded.new_vertex_of);
    return std::optional<DecodedLevelStream>(std::move(out));
}

} // namespace lodbake
