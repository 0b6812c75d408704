// Decoder for the .lbm compressed mesh (docs/format/valence.md). Mirrors
// baker/src/codec/valence_encoder.cpp step for step; every model update here has its twin there.

#include <cmath>
#include <cstring>

#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"

namespace lodrt {
namespace {

using namespace format;
using detail::Fifo;
using detail::MoveToFront;
using detail::initRangeProbs;

uint32_t read32(const uint8_t* p) {
    return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}
uint16_t read16(const uint8_t* p) {
    return uint16_t(p[0] | (p[1] << 8));
}
float readFloat(const uint8_t* p) {
    uint32_t u = read32(p);
    float f;
    std::memcpy(&f, &u, 4);
    return f;
}

// LZMA-style binary range decoder. Reading past the end yields zeros and is remembered, so a cut
// stream is reported instead of read out of bounds.
class RangeDecoder {
public:
    bool init(const uint8_t* data, size_t size) {
        p_ = data;
        end_ = data + size;
        if (size < 5 || data[0] != 0) return false;
        for (int i = 0; i < 5; ++i) code_ = (code_ << 8) | next();
        return true;
    }
    uint32_t bit(uint16_t& prob) {
        uint32_t bound = (range_ >> kRangeProbBits) * prob;
        uint32_t result;
        if (code_ < bound) {
            range_ = bound;
            prob = uint16_t(prob + (((1u << kRangeProbBits) - prob) >> kRangeAdaptShift));
            result = 0;
        } else {
            code_ -= bound;
            range_ -= bound;
            prob = uint16_t(prob - (prob >> kRangeAdaptShift));
            result = 1;
        }
        if (range_ < kRangeTopValue) {
            range_ <<= 8;
            code_ = (code_ << 8) | next();
        }
        return result;
    }
    uint32_t direct(uint32_t count) {
        uint32_t v = 0;
        for (uint32_t i = 0; i < count; ++i) {
            range_ >>= 1;
            uint32_t b = 0;
            if (code_ >= range_) {
                code_ -= range_;
                b = 1;
            }
            v = (v << 1) | b;
            if (range_ < kRangeTopValue) {
                range_ <<= 8;
                code_ = (code_ << 8) | next();
            }
        }
        return v;
    }
    uint32_t tree(uint16_t* probs, uint32_t bits) {
        uint32_t m = 1;
        for (uint32_t i = 0; i < bits; ++i) m = (m << 1) | bit(probs[m]);
        return m - (1u << bits);
    }
    // Bit-length class k of value+1 (6-bit tree), its top bit below the leading one modelled, the rest
    // direct. Returns false for a class above 32 bits.
    bool uint(uint16_t* class_probs, uint16_t* top_probs, uint64_t* value, uint32_t* klass) {
        uint32_t k = tree(class_probs, kValenceClassTreeBits);
        if (k > 32) return false;
        *klass = k;
        uint64_t v = 1;
        if (k >= 1) v = (v << 1) | bit(top_probs[k]);
        if (k >= 2) v = (v << (k - 1)) | direct(k - 1);
        *value = v - 1;
        return true;
    }
    bool finishedExactly() const { return overrun_ == 0 && p_ == end_; }

private:
    uint8_t next() {
        if (p_ < end_) return *p_++;
        ++overrun_;
        return 0;
    }
    const uint8_t* p_ = nullptr;
    const uint8_t* end_ = nullptr;
    uint32_t range_ = 0xFFFFFFFFu;
    uint32_t code_ = 0;
    uint32_t overrun_ = 0;
};


constexpr uint32_t kClassProbs = 1u << kValenceClassTreeBits;
constexpr uint32_t kTopProbs = 33;

// Adaptive models of one residual stream with `Components` components.
template <int Components> struct ResidualModel {
    uint16_t klass[Components][kValenceResidualContexts][kClassProbs];
    uint16_t top[Components][kValenceResidualContexts][kTopProbs];
    uint32_t previous[Components];
    void init() {
        initRangeProbs(&klass[0][0][0], sizeof(klass) / 2);
        initRangeProbs(&top[0][0][0], sizeof(top) / 2);
        for (int j = 0; j < Components; ++j) previous[j] = 0;
    }
    // Zigzag-decoded residual of component j; false on a corrupt class.
    bool decode(RangeDecoder& rd, int j, int64_t* residual) {
        // Context: the mean class of this component's last residual and of the residual coded just
        // before (the previous component, or for component 0 the last component of the last vertex).
        uint32_t ctx = (previous[j] + previous[(j + Components - 1) % Components] + 1) >> 1;
        if (ctx >= kValenceResidualContexts) ctx = kValenceResidualContexts - 1;
        uint64_t u;
        uint32_t k;
        if (!rd.uint(klass[j][ctx], top[j][ctx], &u, &k)) return false;
        previous[j] = k;
        *residual = (u & 1) ? -int64_t(u >> 1) - 1 : int64_t(u >> 1);
        return true;
    }
};


struct Decoder {
    const ValenceInfo* info;
    uint16_t* qpos;      // 3 per vertex
    uint16_t* qnorm;     // 2 per vertex, or null
    int64_t* normal_sum; // 3 per vertex when normals: sum of incident face normals (quantized space)
    RangeDecoder conn, pos, nrm;
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

    // Decodes the attributes of the new vertex x; (a, b, c) is the parallelogram (c opposite), or
    // a == kNone for the previous-vertex predictor.
    static constexpr uint32_t kNone = 0xFFFFFFFFu;
    Result decodeAttributes(uint32_t x, uint32_t a, uint32_t b, uint32_t c) {
        const int64_t qmax = (int64_t(1) << info->position_bits) - 1;
        for (int j = 0; j < 3; ++j) {
            int64_t p = 0;
            if (a != kNone) {
                p = int64_t(qpos[3 * a + j]) + qpos[3 * b + j] - qpos[3 * c + j];
                p = p < 0 ? 0 : (p > qmax ? qmax : p);
            } else if (x > 0) {
                p = qpos[3 * (x - 1) + j];
            }
            int64_t r;
            if (!pos_model.decode(pos, j, &r)) return Result::CorruptStream;
            int64_t q = p + r;
            if (q < 0 || q > qmax) return Result::CorruptStream;
            qpos[3 * x + j] = uint16_t(q);
        }
        return Result::Ok;
    }

    // Normals are decoded after all positions, in vertex order, each predicted by the octahedral code
    // of the sum of its faces' (area-weighted) normals computed exactly on the quantized positions.
    Result decodeNormals(const uint32_t* indices, size_t triangle_count) {
        const size_t vn = info->vertex_count;
        for (size_t i = 0; i < 3 * vn; ++i) normal_sum[i] = 0;
        for (size_t t = 0; t < triangle_count; ++t) {
            const uint32_t* f = &indices[3 * t];
            int64_t e1[3], e2[3];
            for (int j = 0; j < 3; ++j) {
                e1[j] = int64_t(qpos[3 * f[1] + j]) - qpos[3 * f[0] + j];
                e2[j] = int64_t(qpos[3 * f[2] + j]) - qpos[3 * f[0] + j];
            }
            const int64_t n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                  e1[0] * e2[1] - e1[1] * e2[0]};
            for (int c = 0; c < 3; ++c)
                for (int j = 0; j < 3; ++j) normal_sum[3 * f[c] + j] += n[j];
        }
        const uint32_t nb = info->normal_bits;
        const uint32_t mask = (1u << nb) - 1;
        const int64_t half = int64_t(1) << (nb - 1);
        for (size_t x = 0; x < vn; ++x) {
            const int64_t* sum = &normal_sum[3 * x];
            uint32_t p[2];
            if (sum[0] != 0 || sum[1] != 0 || sum[2] != 0) {
                const float fs[3] = {float(sum[0]), float(sum[1]), float(sum[2])};
                octahedralEncode(fs, nb, p);
            } else if (x > 0) {
                p[0] = qnorm[2 * (x - 1)];
                p[1] = qnorm[2 * (x - 1) + 1];
            } else {
                p[0] = p[1] = uint32_t(half);
            }
            for (int j = 0; j < 2; ++j) {
                int64_t r;
                if (!nrm_model.decode(nrm, j, &r)) return Result::CorruptStream;
                if (r < -half || r >= half) return Result::CorruptStream;
                qnorm[2 * x + j] = uint16_t((p[j] + uint32_t(r)) & mask);
            }
        }
        return Result::Ok;
    }

    // One vertex reference; `ctx` 0 for the apex of an edge-matched triangle, 1 otherwise.
    Result decodeVertex(uint32_t ctx, uint32_t a, uint32_t b, uint32_t c, uint32_t* out) {
        uint32_t s = conn.tree(vertex_probs[ctx], kValenceSymbolTreeBits);
        if (s == kValenceVertexSymbolNew) {
            if (next_new >= info->vertex_count) return Result::CorruptStream;
            uint32_t x = next_new++;
            Result r = decodeAttributes(x, a, b, c);
            if (r != Result::Ok) return r;
            *out = x;
            return Result::Ok;
        }
        if (s <= kValenceVertexFifo) {
            if (s - 1 >= vertices.count) return Result::CorruptStream;
            *out = vertices.slot[s - 1];
            return Result::Ok;
        }
        if (s != kValenceVertexSymbolExplicit) return Result::CorruptStream;
        uint64_t d;
        uint32_t k;
        if (!conn.uint(explicit_class, explicit_top, &d, &k) || d >= next_new) return Result::CorruptStream;
        *out = next_new - 1 - uint32_t(d);
        return Result::Ok;
    }
};

} // namespace

Result valenceReadInfo(const uint8_t* data, size_t size, ValenceInfo* info) {
    if (!info || (!data && size > 0)) return Result::InvalidArgument;
    *info = ValenceInfo();
    if (size < 4) return Result::Truncated;
    if (read32(data) != kValenceMagic) return Result::BadMagic;
    if (size < kValenceHeaderSize) return Result::Truncated;
    if (read16(data + 4) != kValenceVersion) return Result::UnsupportedVersion;
    const uint16_t flags = read16(data + 6);
    if (flags & ~kValenceFlagNormals) return Result::CorruptStream;
    ValenceInfo v;
    v.vertex_count = read32(data + 8);
    v.triangle_count = read32(data + 12);
    v.position_bits = data[16];
    v.normal_bits = data[17];
    if (read16(data + 18) != 0) return Result::CorruptStream;
    for (int j = 0; j < 3; ++j) v.bounds_min[j] = readFloat(data + 20 + 4 * j);
    v.cube_size = readFloat(data + 32);
    v.connectivity_bytes = read32(data + 36);
    v.position_bytes = read32(data + 40);
    v.normal_bytes = read32(data + 44);
    v.has_normals = (flags & kValenceFlagNormals) != 0;
    if (v.vertex_count > kValenceMaxCount || v.triangle_count > kValenceMaxCount) return Result::CorruptStream;
    if (v.position_bits < kValenceMinPositionBits || v.position_bits > kValenceMaxPositionBits)
        return Result::CorruptStream;
    if (v.has_normals ? (v.normal_bits < kValenceMinNormalBits || v.normal_bits > kValenceMaxNormalBits)
                      : (v.normal_bits != 0 || v.normal_bytes != 0))
        return Result::CorruptStream;
    for (int j = 0; j < 3; ++j)
        if (!std::isfinite(v.bounds_min[j])) return Result::CorruptStream;
    if (!std::isfinite(v.cube_size) || v.cube_size < 0.0f) return Result::CorruptStream;
    // Every coded symbol costs at least ~0.022 bits (probabilities saturate at 31/2048), so a stream
    // of n bytes cannot hold more than a bounded number of triangles or vertices: refuse counts above
    // that before the caller allocates for them.
    if (uint64_t(v.triangle_count) >
        uint64_t(kValenceTrianglesPerByte) * v.connectivity_bytes + kValenceTrianglesPerByte)
        return Result::CorruptStream;
    if (uint64_t(v.vertex_count) > uint64_t(kValenceVerticesPerByte) * v.position_bytes + kValenceVerticesPerByte)
        return Result::CorruptStream;
    if (v.has_normals &&
        uint64_t(v.vertex_count) > uint64_t(kValenceVerticesPerByte) * v.normal_bytes + kValenceVerticesPerByte)
        return Result::CorruptStream;
    const uint64_t total =
        uint64_t(kValenceHeaderSize) + v.connectivity_bytes + v.position_bytes + uint64_t(v.normal_bytes);
    if (size < total) return Result::Truncated;
    if (size > total) return Result::TrailingBytes;
    *info = v;
    return Result::Ok;
}

size_t valenceScratchSize(const ValenceInfo& info) {
    // int64 face-normal sums (normals only), then uint16 quantized positions and normals.
    size_t bytes = info.has_normals ? size_t(info.vertex_count) * 3 * sizeof(int64_t) : 0;
    bytes += size_t(info.vertex_count) * (3 + (info.has_normals ? 2 : 0)) * sizeof(uint16_t);
    return (bytes + 7) & ~size_t(7);
}

void octahedralEncode(const float n[3], uint32_t bits, uint32_t out[2]) {
    float x = n[0], y = n[1], z = n[2];
    float l1 = std::fabs(x) + std::fabs(y) + std::fabs(z);
    if (!(l1 > 0.0f) || !std::isfinite(l1)) {
        x = 0.0f;
        y = 0.0f;
        z = 1.0f;
        l1 = 1.0f;
    }
    float u = x / l1, v = y / l1;
    if (z < 0.0f) {
        float uu = (1.0f - std::fabs(v)) * (u >= 0.0f ? 1.0f : -1.0f);
        float vv = (1.0f - std::fabs(u)) * (v >= 0.0f ? 1.0f : -1.0f);
        u = uu;
        v = vv;
    }
    const float scale = float((1u << bits) - 1);
    float fu = std::floor((u * 0.5f + 0.5f) * scale + 0.5f);
    float fv = std::floor((v * 0.5f + 0.5f) * scale + 0.5f);
    fu = fu < 0.0f ? 0.0f : (fu > scale ? scale : fu);
    fv = fv < 0.0f ? 0.0f : (fv > scale ? scale : fv);
    out[0] = uint32_t(fu);
    out[1] = uint32_t(fv);
}

void octahedralDecode(const uint32_t in[2], uint32_t bits, float n[3]) {
    const float scale = float((1u << bits) - 1);
    float u = float(in[0]) / scale * 2.0f - 1.0f;
    float v = float(in[1]) / scale * 2.0f - 1.0f;
    float z = 1.0f - std::fabs(u) - std::fabs(v);
    if (z < 0.0f) {
        float uu = (1.0f - std::fabs(v)) * (u >= 0.0f ? 1.0f : -1.0f);
        float vv = (1.0f - std::fabs(u)) * (v >= 0.0f ? 1.0f : -1.0f);
        u = uu;
        v = vv;
    }
    float len = std::sqrt(u * u + v * v + z * z);
    n[0] = u / len;
    n[1] = v / len;
    n[2] = z / len;
}

Result valenceDecode(const uint8_t* data, size_t size, const ValenceOutput& output) {
    ValenceInfo info;
    Result r = valenceReadInfo(data, size, &info);
    if (r != Result::Ok) return r;
    const size_t vn = size_t(info.vertex_count), tn = size_t(info.triangle_count);
    if ((tn > 0 && !output.indices) || (vn > 0 && !output.positions) || (vn > 0 && !output.scratch))
        return Result::InvalidArgument;
    if (reinterpret_cast<uintptr_t>(output.scratch) % 8 != 0) return Result::InvalidArgument;
    if (output.index_capacity < 3 * tn || output.position_capacity < 3 * vn ||
        output.scratch_size < valenceScratchSize(info) ||
        (output.normals && info.has_normals && output.normal_capacity < 3 * vn))
        return Result::BufferTooSmall;

    // The decoder state is ~14 KB of models: kept in a static-free local object.
    Decoder d;
    d.info = &info;
    d.normal_sum = info.has_normals ? static_cast<int64_t*>(output.scratch) : nullptr;
    d.qpos = reinterpret_cast<uint16_t*>(static_cast<uint8_t*>(output.scratch) +
                                         (info.has_normals ? vn * 3 * sizeof(int64_t) : 0));
    d.qnorm = info.has_normals ? d.qpos + 3 * vn : nullptr;
    d.init();
    const uint8_t* stream = data + kValenceHeaderSize;
    if (!d.conn.init(stream, info.connectivity_bytes)) return Result::CorruptStream;
    stream += info.connectivity_bytes;
    if (!d.pos.init(stream, info.position_bytes)) return Result::CorruptStream;
    stream += info.position_bytes;
    if (info.has_normals && !d.nrm.init(stream, info.normal_bytes)) return Result::CorruptStream;

    constexpr uint32_t kNone = Decoder::kNone;
    uint32_t previous_edge = kValenceEdgeFifo;
    for (size_t t = 0; t < tn; ++t) {
        uint32_t es = d.conn.tree(d.edge_probs[previous_edge], kValenceSymbolTreeBits);
        if (es > kValenceEdgeFifo || (es < kValenceEdgeFifo && es >= d.edge_a.count)) return Result::CorruptStream;
        previous_edge = es;
        uint32_t v[3];
        if (es < kValenceEdgeFifo) {
            v[0] = d.edge_a.at(es);
            v[1] = d.edge_b.at(es);
            r = d.decodeVertex(0, v[0], v[1], d.edge_c.at(es), &v[2]);
            if (r != Result::Ok) return r;
        } else {
            for (int i = 0; i < 3; ++i) {
                r = d.decodeVertex(1, kNone, kNone, kNone, &v[i]);
                if (r != Result::Ok) return r;
            }
        }
        output.indices[3 * t + 0] = v[0];
        output.indices[3 * t + 1] = v[1];
        output.indices[3 * t + 2] = v[2];
        // Each edge is offered reversed (as a neighbour with the same orientation sees it), with
        // the opposite corner for the parallelogram; not the edge just matched (now interior).
        for (int i = es < kValenceEdgeFifo ? 1 : 0; i < 3; ++i) {
            d.edge_a.push(v[(i + 1) % 3]);
            d.edge_b.push(v[i]);
            d.edge_c.push(v[(i + 2) % 3]);
        }
        for (int i = 0; i < 3; ++i) d.vertices.touch(v[i]);
    }
    // Vertices no triangle references, in order.
    while (d.next_new < info.vertex_count) {
        uint32_t x = d.next_new++;
        r = d.decodeAttributes(x, kNone, kNone, kNone);
        if (r != Result::Ok) return r;
    }
    if (info.has_normals) {
        r = d.decodeNormals(output.indices, tn);
        if (r != Result::Ok) return r;
    }
    if (!d.conn.finishedExactly() || !d.pos.finishedExactly() || (info.has_normals && !d.nrm.finishedExactly()))
        return Result::CorruptStream;

    const uint32_t qmax = (1u << info.position_bits) - 1;
    const float step = info.cube_size / float(qmax);
    for (size_t i = 0; i < vn; ++i)
        for (int j = 0; j < 3; ++j) output.positions[3 * i + j] = info.bounds_min[j] + float(d.qpos[3 * i + j]) * step;
    if (output.normals && info.has_normals) {
        for (size_t i = 0; i < vn; ++i) {
            uint32_t q[2] = {d.qnorm[2 * i], d.qnorm[2 * i + 1]};
            octahedralDecode(q, info.normal_bits, &output.normals[3 * i]);
        }
    }
    return Result::Ok;
}

} // namespace lodrt
