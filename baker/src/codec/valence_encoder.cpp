// Encoder of the .lbm compressed mesh. Every model step mirrors runtime/src/valence_decoder.cpp;
// docs/format/valence.md is the normative description of both.

#include "lodbake/codec/valence_encoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "codec/range_encoder.h"
#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"

namespace lodbake::codec {
namespace {

using namespace lodrt::format;
using lodrt::detail::Fifo;
using lodrt::detail::MoveToFront;
using lodrt::detail::initRangeProbs;

constexpr uint32_t kUnassigned = 0xFFFFFFFFu;
constexpr uint32_t kNone = 0xFFFFFFFFu;
constexpr uint32_t kClassProbs = 1u << kValenceClassTreeBits;
constexpr uint32_t kTopProbs = 33;


template <int Components> struct ResidualModel {
    uint16_t klass[Components][kValenceResidualContexts][kClassProbs];
    uint16_t top[Components][kValenceResidualContexts][kTopProbs];
    uint32_t previous[Components];
    void init() {
        initRangeProbs(&klass[0][0][0], sizeof(klass) / 2);
        initRangeProbs(&top[0][0][0], sizeof(top) / 2);
        for (int j = 0; j < Components; ++j) previous[j] = 0;
    }
    void encode(RangeEncoder& re, int j, int64_t residual) {
        uint32_t ctx = std::min<uint32_t>((previous[j] + previous[(j + Components - 1) % Components] + 1) >> 1,
                                          kValenceResidualContexts - 1);
        uint64_t u = residual >= 0 ? uint64_t(residual) << 1 : ((uint64_t(-residual - 1)) << 1) | 1u;
        previous[j] = re.uint(klass[j][ctx], top[j][ctx], u);
    }
};


// True when the two triangles have at least two corners in common.
bool sharesEdge(const uint32_t* a, const uint32_t* b) {
    int shared = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) shared += a[i] == b[j];
    return shared >= 2;
}

// Faces in a vertex-cache-friendly order (Forsyth's linear-speed greedy: an LRU cache as large as the
// coder's vertex cache, the best-scoring triangle around cached vertices next), plus a bonus for
// continuing across an edge of the face just emitted: most triangles then name edge FIFO slot 0 or 1
// and most old apices are cached. The bonus (measured: 14.0 -> 11.8 bits/vertex on bunny_zipper,
// 14.4 -> 12.3 on lucy100k) makes the order strip-like without giving up the cache.
std::vector<uint32_t> traversalOrder(const std::vector<uint32_t>& indices, size_t vertex_count) {
    constexpr int kCache = int(kValenceVertexFifo);
    constexpr double kStripBonus = 2.0;
    constexpr size_t kSearch = 4;
    const size_t fn = indices.size() / 3;
    std::vector<uint32_t> first(vertex_count + 1, 0);
    for (uint32_t v : indices) ++first[v + 1];
    for (size_t v = 0; v < vertex_count; ++v) first[v + 1] += first[v];
    std::vector<uint32_t> faces_of(indices.size());
    {
        std::vector<uint32_t> fill(first.begin(), first.end() - 1);
        for (size_t c = 0; c < indices.size(); ++c) faces_of[fill[indices[c]]++] = uint32_t(c / 3);
    }
    std::vector<uint32_t> live(vertex_count); // unemitted faces per vertex
    for (size_t v = 0; v < vertex_count; ++v) live[v] = first[v + 1] - first[v];
    std::vector<int> cache_pos(vertex_count, -1);
    double position_score[kCache];
    for (int p = 0; p < kCache; ++p)
        position_score[p] = p < 3 ? 0.75 : std::pow(1.0 - double(p - 3) / double(kCache - 3), 1.5);
    constexpr uint32_t kValenceTable = 64;
    double valence_score[kValenceTable];
    for (uint32_t n = 1; n < kValenceTable; ++n) valence_score[n] = 2.0 / std::sqrt(double(n));
    auto vertexScore = [&](uint32_t v) {
        if (live[v] == 0) return -1.0;
        const int p = cache_pos[v];
        const double s = p >= 0 ? position_score[p] : 0.0;
        return s + (live[v] < kValenceTable ? valence_score[live[v]] : 2.0 / std::sqrt(double(live[v])));
    };
    std::vector<double> vscore(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) vscore[v] = vertexScore(uint32_t(v));
    std::vector<uint8_t> done(fn, 0);
    std::vector<uint32_t> order;
    order.reserve(fn);
    std::vector<uint32_t> cache, next_cache;
    size_t scan = 0;
    while (order.size() < fn) {
        // Best face around the cached vertices; ties by lower face index.
        uint32_t best = 0xFFFFFFFFu;
        double best_score = -1e300;
        // The most recent vertices first; the rest of the cache only when they have no face left.
        for (size_t ci = 0; ci < cache.size(); ++ci) {
            if (ci == kSearch && best != 0xFFFFFFFFu) break;
            const uint32_t v = cache[ci];
            for (uint32_t k = first[v]; k < first[v + 1]; ++k) {
                uint32_t f = faces_of[k];
                if (done[f]) continue;
                double s = vscore[indices[3 * f]] + vscore[indices[3 * f + 1]] + vscore[indices[3 * f + 2]];
                if (!order.empty() && sharesEdge(&indices[3 * size_t(f)], &indices[3 * size_t(order.back())]))
                    s += kStripBonus;
                if (s > best_score || (s == best_score && f < best)) {
                    best_score = s;
                    best = f;
                }
            }
        }
        if (best == 0xFFFFFFFFu) {
            while (done[scan]) ++scan;
            best = uint32_t(scan);
        }
        done[best] = 1;
        order.push_back(best);
        // LRU update: the face's vertices to the front.
        next_cache.clear();
        const uint32_t* t = &indices[3 * size_t(best)];
        for (int i = 0; i < 3; ++i) {
            --live[t[i]];
            if (std::find(next_cache.begin(), next_cache.end(), t[i]) == next_cache.end()) next_cache.push_back(t[i]);
        }
        for (uint32_t v : cache)
            if (v != t[0] && v != t[1] && v != t[2]) next_cache.push_back(v);
        for (size_t i = kCache; i < next_cache.size(); ++i) {
            cache_pos[next_cache[i]] = -1;
            vscore[next_cache[i]] = vertexScore(next_cache[i]);
        }
        if (next_cache.size() > size_t(kCache)) next_cache.resize(kCache);
        for (size_t i = 0; i < next_cache.size(); ++i) {
            cache_pos[next_cache[i]] = int(i);
            vscore[next_cache[i]] = vertexScore(next_cache[i]);
        }
        std::swap(cache, next_cache);
    }
    return order;
}

struct Encoder {
    const Mesh* mesh;
    const ValenceEncodeOptions* options;
    bool normals = false;
    std::vector<uint32_t> new_of;      // old -> new
    std::vector<uint16_t> qpos_old;    // 3 per old vertex
    std::vector<uint16_t> qnorm_old;   // 2 per old vertex
    std::vector<uint16_t> qpos, qnorm; // by new index
    RangeEncoder conn, pos, nrm;
    uint16_t edge_probs[kValenceEdgeFifo + 1][1u << kValenceSymbolTreeBits];
    uint16_t vertex_probs[2][1u << kValenceSymbolTreeBits];
    uint16_t explicit_class[kClassProbs];
    uint16_t explicit_top[kTopProbs];
    ResidualModel<3> pos_model;
    ResidualModel<2> nrm_model;
    Fifo<kValenceEdgeFifo> edge_a, edge_b, edge_c;
    MoveToFront<kValenceVertexFifo> vertices;
    uint32_t next_new = 0;

    void init() {
        initRangeProbs(&edge_probs[0][0], sizeof(edge_probs) / 2);
        initRangeProbs(&vertex_probs[0][0], sizeof(vertex_probs) / 2);
        initRangeProbs(explicit_class, kClassProbs);
        initRangeProbs(explicit_top, kTopProbs);
        pos_model.init();
        nrm_model.init();
    }

    void encodeAttributes(uint32_t old, uint32_t x, uint32_t a, uint32_t b, uint32_t c) {
        const int64_t qmax = (int64_t(1) << options->position_bits) - 1;
        for (int j = 0; j < 3; ++j) {
            int64_t p = 0;
            if (a != kNone) {
                p = int64_t(qpos[3 * a + j]) + qpos[3 * b + j] - qpos[3 * c + j];
                p = std::clamp<int64_t>(p, 0, qmax);
            } else if (x > 0) {
                p = qpos[3 * (x - 1) + j];
            }
            qpos[3 * x + j] = qpos_old[3 * old + j];
            pos_model.encode(pos, j, int64_t(qpos[3 * x + j]) - p);
        }
    }

    // Normals after all positions, in new vertex order, each predicted from the exact sum of its
    // faces' normals on the quantized positions (the decoder's decodeNormals).
    void encodeNormals(const std::vector<uint32_t>& triangles) {
        const size_t vn = new_of.size();
        std::vector<int64_t> sum(3 * vn, 0);
        for (size_t t = 0; t + 2 < triangles.size(); t += 3) {
            const uint32_t* f = &triangles[t];
            int64_t e1[3], e2[3];
            for (int j = 0; j < 3; ++j) {
                e1[j] = int64_t(qpos[3 * f[1] + j]) - qpos[3 * f[0] + j];
                e2[j] = int64_t(qpos[3 * f[2] + j]) - qpos[3 * f[0] + j];
            }
            const int64_t n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                  e1[0] * e2[1] - e1[1] * e2[0]};
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < 3; ++j) sum[3 * f[c] + j] += n[j];
        }
        const uint32_t nb = options->normal_bits;
        const uint32_t mask = (1u << nb) - 1;
        const int64_t half = int64_t(1) << (nb - 1);
        for (size_t x = 0; x < vn; ++x) {
            const int64_t* s3 = &sum[3 * x];
            uint32_t p[2];
            if (s3[0] != 0 || s3[1] != 0 || s3[2] != 0) {
                const float fs[3] = {float(s3[0]), float(s3[1]), float(s3[2])};
                lodrt::octahedralEncode(fs, nb, p);
            } else if (x > 0) {
                p[0] = qnorm[2 * (x - 1)];
                p[1] = qnorm[2 * (x - 1) + 1];
            } else {
                p[0] = p[1] = uint32_t(half);
            }
            for (int j = 0; j < 2; ++j) {
                int64_t r = int64_t((qnorm[2 * x + j] - p[j]) & mask);
                if (r >= half) r -= int64_t(mask) + 1;
                nrm_model.encode(nrm, j, r);
            }
        }
    }

    // Codes input vertex `old`; returns its new index.
    uint32_t encodeVertex(uint32_t ctx, uint32_t old, uint32_t a, uint32_t b, uint32_t c) {
        uint32_t id = new_of[old];
        if (id == kUnassigned) {
            conn.tree(vertex_probs[ctx], kValenceSymbolTreeBits, kValenceVertexSymbolNew);
            id = next_new++;
            new_of[old] = id;
            encodeAttributes(old, id, a, b, c);
            return id;
        }
        int slot = vertices.find(id);
        if (slot >= 0) {
            conn.tree(vertex_probs[ctx], kValenceSymbolTreeBits, uint32_t(slot) + 1);
            return id;
        }
        conn.tree(vertex_probs[ctx], kValenceSymbolTreeBits, kValenceVertexSymbolExplicit);
        conn.uint(explicit_class, explicit_top, uint64_t(next_new - 1 - id));
        return id;
    }
};

void put32(std::vector<uint8_t>& out, size_t at, uint32_t v) {
    for (int i = 0; i < 4; ++i) out[at + i] = uint8_t(v >> (8 * i));
}
void putFloat(std::vector<uint8_t>& out, size_t at, float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    put32(out, at, u);
}

std::string describe(lodrt::Result r) {
    const char* what = "";
    switch (r) {
    case lodrt::Result::Truncated:
        what = "the file ends before the lengths its header gives";
        break;
    case lodrt::Result::BadMagic:
        what = "not an .lbm file (bad magic)";
        break;
    case lodrt::Result::UnsupportedVersion:
        what = "format version other than 1";
        break;
    case lodrt::Result::TrailingBytes:
        what = "bytes after the streams the header announces";
        break;
    case lodrt::Result::CorruptStream:
        what = "corrupt (a value out of range)";
        break;
    default:
        what = "cannot decode";
        break;
    }
    return std::string(what) + " (" + lodrt::resultName(r) + ")";
}

} // namespace

Result<ValenceEncodeResult> encodeValence(const Mesh& mesh, const ValenceEncodeOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, "valence encoder"));
    if (options.position_bits < kValenceMinPositionBits || options.position_bits > kValenceMaxPositionBits)
        return invalidInput("valence encoder: position bits " + std::to_string(options.position_bits) +
                            " outside [8, 16]");
    const bool normals = options.encode_normals && mesh.hasNormals();
    if (normals && (options.normal_bits < kValenceMinNormalBits || options.normal_bits > kValenceMaxNormalBits))
        return invalidInput("valence encoder: normal bits " + std::to_string(options.normal_bits) + " outside [4, 16]");
    const size_t vn = mesh.vertexCount(), fn = mesh.faceCount();
    if (vn > kValenceMaxCount || fn > kValenceMaxCount)
        return invalidInput("valence encoder: " + std::to_string(vn) + " vertices / " + std::to_string(fn) +
                            " triangles exceed the format limit of 2^28");
    for (size_t i = 0; i < vn; ++i) {
        const Vec3f& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return invalidInput("valence encoder: vertex " + std::to_string(i) + ": position is not finite");
    }

    // Quantization cube: all vertices (unreferenced ones are coded too).
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < vn; ++i) {
        const float c[3] = {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z};
        for (int j = 0; j < 3; ++j) {
            if (i == 0 || c[j] < lo[j]) lo[j] = c[j];
            if (i == 0 || c[j] > hi[j]) hi[j] = c[j];
        }
    }
    float cube = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.0f});
    if (!std::isfinite(cube)) return invalidInput("valence encoder: bounding box extent overflows a float");
    const uint32_t qmax = (1u << options.position_bits) - 1;
    const float step = cube / float(qmax);

    Encoder e;
    e.mesh = &mesh;
    e.options = &options;
    e.normals = normals;
    e.init();
    e.new_of.assign(vn, kUnassigned);
    e.qpos_old.resize(3 * vn);
    e.qpos.resize(3 * vn);
    ValenceEncodeResult result;
    for (size_t i = 0; i < vn; ++i) {
        const float c[3] = {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z};
        for (int j = 0; j < 3; ++j) {
            double t = cube > 0.0f ? double(c[j] - lo[j]) / double(cube) * qmax : 0.0;
            long q = std::lround(std::floor(t + 0.5));
            q = std::clamp<long>(q, 0, long(qmax));
            e.qpos_old[3 * i + j] = uint16_t(q);
            double decoded = double(lo[j] + float(q) * step);
            result.max_position_error = std::max(result.max_position_error, std::fabs(decoded - double(c[j])));
        }
    }
    if (normals) {
        e.qnorm_old.resize(2 * vn);
        e.qnorm.resize(2 * vn);
        for (size_t i = 0; i < vn; ++i) {
            const float n[3] = {mesh.normals[i].x, mesh.normals[i].y, mesh.normals[i].z};
            uint32_t q[2];
            lodrt::octahedralEncode(n, options.normal_bits, q);
            e.qnorm_old[2 * i] = uint16_t(q[0]);
            e.qnorm_old[2 * i + 1] = uint16_t(q[1]);
        }
    }

    result.old_face_of = traversalOrder(mesh.indices, vn);
    uint32_t previous_edge = kValenceEdgeFifo;
    std::vector<uint32_t> triangles; // as decoded, new vertex indices
    triangles.reserve(mesh.indices.size());
    for (uint32_t f : result.old_face_of) {
        const uint32_t o[3] = {mesh.indices[3 * size_t(f)], mesh.indices[3 * size_t(f) + 1],
                               mesh.indices[3 * size_t(f) + 2]};
        // The first FIFO edge a->b that this face contains as a directed edge.
        uint32_t es = kValenceEdgeFifo, rot = 0;
        for (uint32_t i = 0; i < e.edge_a.count && es == kValenceEdgeFifo; ++i) {
            for (uint32_t r = 0; r < 3; ++r) {
                if (e.new_of[o[r]] == e.edge_a.at(i) && e.new_of[o[(r + 1) % 3]] == e.edge_b.at(i)) {
                    es = i;
                    rot = r;
                    break;
                }
            }
        }
        e.conn.tree(e.edge_probs[previous_edge], kValenceSymbolTreeBits, es);
        previous_edge = es;
        uint32_t v[3];
        if (es < kValenceEdgeFifo) {
            v[0] = e.edge_a.at(es);
            v[1] = e.edge_b.at(es);
            v[2] = e.encodeVertex(0, o[(rot + 2) % 3], v[0], v[1], e.edge_c.at(es));
        } else {
            for (int i = 0; i < 3; ++i) v[i] = e.encodeVertex(1, o[i], kNone, kNone, kNone);
        }
        for (int i = es < kValenceEdgeFifo ? 1 : 0; i < 3; ++i) {
            e.edge_a.push(v[(i + 1) % 3]);
            e.edge_b.push(v[i]);
            e.edge_c.push(v[(i + 2) % 3]);
        }
        for (int i = 0; i < 3; ++i) e.vertices.touch(v[i]);
        triangles.insert(triangles.end(), {v[0], v[1], v[2]});
    }
    for (size_t i = 0; i < vn; ++i) {
        if (e.new_of[i] != kUnassigned) continue;
        uint32_t x = e.next_new++;
        e.new_of[i] = x;
        e.encodeAttributes(uint32_t(i), x, kNone, kNone, kNone);
    }
    if (normals) {
        for (size_t i = 0; i < vn; ++i) {
            e.qnorm[2 * size_t(e.new_of[i])] = e.qnorm_old[2 * i];
            e.qnorm[2 * size_t(e.new_of[i]) + 1] = e.qnorm_old[2 * i + 1];
        }
        e.encodeNormals(triangles);
    }

    std::vector<uint8_t> conn = e.conn.finish(), pos = e.pos.finish(), nrm;
    if (normals) nrm = e.nrm.finish();
    std::vector<uint8_t>& out = result.bytes;
    out.assign(kValenceHeaderSize, 0);
    put32(out, 0, kValenceMagic);
    out[4] = uint8_t(kValenceVersion);
    out[5] = uint8_t(kValenceVersion >> 8);
    out[6] = normals ? uint8_t(kValenceFlagNormals) : 0;
    put32(out, 8, uint32_t(vn));
    put32(out, 12, uint32_t(fn));
    out[16] = uint8_t(options.position_bits);
    out[17] = normals ? uint8_t(options.normal_bits) : 0;
    for (int j = 0; j < 3; ++j) putFloat(out, 20 + 4 * j, lo[j]);
    putFloat(out, 32, cube);
    put32(out, 36, uint32_t(conn.size()));
    put32(out, 40, uint32_t(pos.size()));
    put32(out, 44, uint32_t(nrm.size()));
    out.insert(out.end(), conn.begin(), conn.end());
    out.insert(out.end(), pos.begin(), pos.end());
    out.insert(out.end(), nrm.begin(), nrm.end());
    result.header_bytes = kValenceHeaderSize;
    result.connectivity_bytes = conn.size();
    result.position_bytes = pos.size();
    result.normal_bytes = nrm.size();
    result.new_vertex_of = std::move(e.new_of);
    return result;
}

Result<Mesh> decodeValence(const std::vector<uint8_t>& bytes, const std::string& name) {
    lodrt::ValenceInfo info;
    lodrt::Result r = lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info);
    if (r != lodrt::Result::Ok) return invalidInput(name + ": header: " + describe(r));
    Mesh mesh;
    std::vector<float> positions(3 * size_t(info.vertex_count)), normals;
    if (info.has_normals) normals.resize(3 * size_t(info.vertex_count));
    mesh.indices.resize(3 * size_t(info.triangle_count));
    std::vector<uint64_t> scratch((lodrt::valenceScratchSize(info) + 7) / 8);
    lodrt::ValenceOutput output;
    output.indices = mesh.indices.data();
    output.index_capacity = mesh.indices.size();
    output.positions = positions.data();
    output.position_capacity = positions.size();
    output.normals = info.has_normals ? normals.data() : nullptr;
    output.normal_capacity = normals.size();
    output.scratch = scratch.data();
    output.scratch_size = scratch.size() * 8;
    r = lodrt::valenceDecode(bytes.data(), bytes.size(), output);
    if (r != lodrt::Result::Ok) return invalidInput(name + ": streams: " + describe(r));
    mesh.positions.resize(info.vertex_count);
    for (size_t i = 0; i < info.vertex_count; ++i)
        mesh.positions[i] = Vec3f{positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
    if (info.has_normals) {
        mesh.normals.resize(info.vertex_count);
        for (size_t i = 0; i < info.vertex_count; ++i)
            mesh.normals[i] = Vec3f{normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
    }
    return mesh;
}

} // namespace lodbake::codec
