// Decoder for the .lbm compressed mesh (docs/format/valence.md). The connectivity is rebuilt by the
// conquest engine shared with the encoder (lodrt/detail/valence_model.h); this file supplies the
// stream reading side of it, then decodes positions (multi-parallelogram prediction over the decoded
// corner table: the order and parallelograms planned from the connectivity first, then the residuals
// in one sequential pass, seam copies taking their twin's position) and normals, then the attribute
// table's UV sets and colours (over the same plan) and tangents. Everything lives in caller memory;
// every value read is checked.

#include <cmath>
#include <cstring>

#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"
#include "little_endian.h"
#include "range_decoder.h"

namespace lodrt {
namespace {

using namespace format;
using detail::kNone;
using detail::VertexKind;
using detail::VertexSymbol;

using detail::loadF32;
using detail::loadU16;
using detail::loadU32;

using detail::RangeDecoder;

// Raw bit part (docs/format/valence.md "Raw bits"): bits packed least significant first, read through a
// 64-bit window. Reading past the end yields zeros and is remembered; finishedExactly() checks that
// the part is consumed to its last byte and that the unused high bits of that byte are zero.
class BitReader {
public:
    void init(const uint8_t* data, size_t size) {
        p_ = data;
        end_ = data + size;
        size_ = size;
    }
    // count <= 24.
    inline uint32_t read(uint32_t count) {
        if (avail_ < count) refill();
        const uint32_t v = uint32_t(window_) & ((1u << count) - 1u);
        window_ >>= count;
        avail_ -= count;
        return v;
    }
    bool overrun() const { return fetched_ > size_ + 8; }
    bool finishedExactly() const {
        const uint64_t used_bits = uint64_t(fetched_) * 8 - avail_;
        return (used_bits + 7) / 8 == size_ && window_ == 0;
    }

private:
    void refill() {
        if (end_ - p_ >= 8) {
            uint64_t w;
            std::memcpy(&w, p_, 8);
            w = toLittle(w);
            window_ |= w << avail_;
            const uint32_t bytes = (63 - avail_) >> 3;
            p_ += bytes;
            fetched_ += bytes;
            avail_ += bytes * 8;
            if (avail_ < 64) window_ &= (uint64_t(1) << avail_) - 1;
            return;
        }
        while (avail_ <= 56) {
            const uint64_t byte = p_ < end_ ? *p_++ : 0;
            window_ |= byte << avail_;
            avail_ += 8;
            ++fetched_;
        }
    }
    static uint64_t toLittle(uint64_t w) {
        const uint16_t probe = 1;
        uint8_t first;
        std::memcpy(&first, &probe, 1);
        if (first == 1) return w;
        uint64_t r = 0;
        for (int i = 0; i < 8; ++i) r |= ((w >> (8 * i)) & 0xFFu) << (8 * (7 - i));
        return r;
    }
    const uint8_t* p_ = nullptr;
    const uint8_t* end_ = nullptr;
    size_t size_ = 0;
    size_t fetched_ = 0; // bytes moved into the window, zeros past the end included
    uint64_t window_ = 0;
    uint32_t avail_ = 0;
};

constexpr uint32_t kClassProbs = 1u << kValenceClassTreeBits;
constexpr uint32_t kTopProbs = 33;

struct UintModel {
    uint32_t klass[kClassProbs];
    uint32_t top[kTopProbs];
    void init() {
        detail::initRangeProbs(klass, kClassProbs);
        detail::initRangeProbs(top, kTopProbs);
    }
};

// Residual models of one attribute: per component and context, the bit length of |r| as a tree,
// then the sign (in a sign context), the top two mantissa bits modelled, the rest direct.
template <int Components, int Contexts> struct ResidualModel {
    static constexpr uint32_t kTree = 1u << kValenceResidualTreeBits;
    using LengthModel = detail::ResidualLengthModel;
    LengthModel length[Components][Contexts];
    uint32_t sign[Components][detail::kSignContexts];
    uint32_t second[Components][2 * kTree];
    uint32_t top[Components][kTree];
    void init() {
        for (auto& per_component : length)
            for (LengthModel& m : per_component) m.init();
        detail::initRangeProbs(&sign[0][0], sizeof(sign) / 4);
        detail::initRangeProbs(&second[0][0], sizeof(second) / 4);
        detail::initRangeProbs(&top[0][0], sizeof(top) / 4);
    }
    // Residual of component j in context ctx; *length_out = bit length of |r|. False when corrupt.
    inline bool decode(RangeDecoder& rd, BitReader& raw, int j, uint32_t ctx, int32_t* r, uint32_t* length_out,
                       uint32_t sign_ctx = 0) {
        const uint32_t k = rd.symbol(length[j][ctx]); // 0..17
        *length_out = k;
        if (k == 0) {
            *r = 0;
            return true;
        }
        const uint32_t negative = rd.bit(sign[j][sign_ctx]);
        uint32_t m = 1;
        if (k >= 2) m = (m << 1) | rd.bit(top[j][k]);
        if (k >= 3) m = (m << 1) | rd.bit(second[j][2 * k + (m & 1u)]);
        if (k >= 4) m = (m << (k - 3)) | raw.read(k - 3);
        // Branch-free negation (the sign is unpredictable): (m ^ -negative) + negative.
        *r = int32_t((m ^ (0u - negative)) + negative);
        return true;
    }
};

// The stream side of the conquest engine.
struct ConnectivityReader {
    RangeDecoder rd;
    uint32_t more;
    detail::ConnectivitySymbolModel symbols[detail::kValenceContexts];
    UintModel escape, offset, list, free_a, dup;

    void init() {
        more = kRangeStateInit;
        for (auto& m : symbols) m.init();
        escape.init();
        offset.init();
        list.init();
        free_a.init();
        dup.init();
    }
    bool moreComponents() { return !rd.overrun() && rd.bit(more) != 0; }
    bool readU32(UintModel& m, uint32_t* out) {
        uint64_t v;
        if (!rd.uint(m.klass, m.top, &v) || v > 0xFFFFFFFFu) return false;
        *out = uint32_t(v);
        return true;
    }
    Result symbol(uint32_t ctx, VertexSymbol* s) {
        if (rd.overrun()) return Result::CorruptStream;
        const uint32_t sym = rd.symbol(symbols[ctx]);
        bool ok = true;
        if (sym >= kValenceSymbolFirstValence) {
            s->kind = VertexKind::Add;
            s->valence = sym - kValenceSymbolFirstValence + 3;
        } else if (sym == kValenceSymbolEscape || sym == kValenceSymbolDummy) {
            s->kind = sym == kValenceSymbolDummy ? VertexKind::Dummy : VertexKind::Add;
            ok = readU32(escape, &s->valence);
        } else if (sym == kValenceSymbolSplit) {
            s->kind = VertexKind::Split;
            ok = readU32(offset, &s->offset) && readU32(free_a, &s->free_a);
            s->offset += 3;
        } else {
            s->kind = VertexKind::Merge;
            ok = readU32(list, &s->list) && readU32(offset, &s->offset) && readU32(free_a, &s->free_a);
        }
        return ok ? Result::Ok : Result::CorruptStream;
    }
    Result seedVertex(VertexSymbol* s) {
        Result r = symbol(detail::kSeedContext, s);
        if (r == Result::Ok && s->kind != VertexKind::Add && s->kind != VertexKind::Dummy) return Result::CorruptStream;
        return r;
    }
    Result vertexSymbol(uint32_t ctx, uint32_t, VertexSymbol* s) { return symbol(ctx, s); }
    Result onTriangle(uint32_t, uint32_t) { return Result::Ok; }
};

// One attribute record (format.h, kValenceFlagAttributes), checked against the ones before it.
bool readAttributeRecord(const uint8_t* p, uint32_t index, const ValenceInfo& v, ValenceAttribute* a) {
    a->kind = p[0];
    a->components = p[1];
    a->bits = p[2];
    a->predictor = p[3];
    a->set = loadU16(p + 4);
    if (loadU16(p + 6) != 0) return false;
    for (int j = 0; j < 4; ++j) {
        a->min[j] = loadF32(p + 8 + 4 * j);
        a->size[j] = loadF32(p + 24 + 4 * j);
        if (!std::isfinite(a->min[j]) || !std::isfinite(a->size[j]) || a->size[j] < 0.0f) return false;
    }
    a->bytes = loadU32(p + 40);
    a->raw_bytes = loadU32(p + 44);
    if (a->bits < kValenceMinAttributeBits || a->bits > kValenceMaxAttributeBits) return false;
    if (v.vertex_count > uint64_t(kValenceAttributesPerByte) * (uint64_t(a->bytes) + 1)) return false;
    uint32_t quantized = 0; // components with a range
    if (a->kind == kValenceAttributeUv) {
        if (a->components != 2 || a->predictor > kValencePredictUvGeometric) return false;
        quantized = 2;
    } else if (a->kind == kValenceAttributeColor) {
        if ((a->components != 3 && a->components != 4) || a->predictor == kValencePredictUvGeometric ||
            a->predictor > kValencePredictNeighbourMeanDecorrelated)
            return false;
        quantized = a->components;
    } else if (a->kind == kValenceAttributeTangent) {
        if (a->components != 4 || a->set != 0) return false;
        if (a->predictor != kValenceNoReference &&
            (a->predictor >= index || v.attributes[a->predictor].kind != kValenceAttributeUv))
            return false;
    } else {
        return false;
    }
    for (uint32_t j = quantized; j < 4; ++j)
        if (a->min[j] != 0.0f || a->size[j] != 0.0f) return false;
    return true;
}

// The attribute table after the header (version 7); adds its own and its attributes' bytes to *total.
Result readAttributeTable(const uint8_t* data, size_t size, ValenceInfo* v, uint64_t* total) {
    if (size < uint64_t(kValenceHeaderSize) + kValenceAttributeTablePrefix) return Result::Truncated;
    const uint8_t* prefix = data + kValenceHeaderSize;
    const uint32_t count = loadU32(prefix);
    if (count == 0 || count > kValenceMaxAttributes) return Result::CorruptStream;
    v->twin_bytes = loadU32(prefix + 4);
    v->twin_shift = prefix[8];
    if (v->twin_shift > kValenceMaxTwinShift || prefix[9] != 0 || prefix[10] != 0 || prefix[11] != 0 ||
        (v->twin_bytes == 0 && v->twin_shift != 0))
        return Result::CorruptStream;
    const uint64_t table = kValenceAttributeTablePrefix + uint64_t(count) * kValenceAttributeRecordSize;
    if (size < kValenceHeaderSize + table) return Result::Truncated;
    *total += table + v->twin_bytes;
    for (uint32_t i = 0; i < count; ++i) {
        ValenceAttribute& a = v->attributes[i];
        if (!readAttributeRecord(prefix + kValenceAttributeTablePrefix + size_t(i) * kValenceAttributeRecordSize, i,
                                 *v, &a))
            return Result::CorruptStream;
        *total += uint64_t(a.bytes) + a.raw_bytes;
    }
    v->attribute_count = count;
    return Result::Ok;
}

} // namespace

Result valenceReadInfo(const uint8_t* data, size_t size, ValenceInfo* info) {
    if (!info || (!data && size > 0)) return Result::InvalidArgument;
    *info = ValenceInfo();
    if (size < 4) return Result::Truncated;
    if (loadU32(data) != kValenceMagic) return Result::BadMagic;
    if (size < 6) return Result::Truncated;
    const uint16_t version = loadU16(data + 4);
    if (version != kValenceVersion && version != kValenceVersionWithoutAttributes) return Result::UnsupportedVersion;
    if (size < kValenceHeaderSize) return Result::Truncated;
    const uint16_t flags = loadU16(data + 6);
    if (flags & ~kValenceKnownFlags) return Result::CorruptStream;
    // Version 7 is the attribute table's: it must be there, and only there.
    if (((flags & kValenceFlagAttributes) != 0) != (version == kValenceVersion)) return Result::CorruptStream;
    ValenceInfo v;
    v.version = version;
    v.vertex_count = loadU32(data + 8);
    v.triangle_count = loadU32(data + 12);
    v.closed_vertex_count = loadU32(data + 16);
    v.closed_triangle_count = loadU32(data + 20);
    v.position_bits = data[24];
    v.normal_bits = data[25];
    if (loadU16(data + 26) != 0) return Result::CorruptStream;
    for (int j = 0; j < 3; ++j) v.bounds_min[j] = loadF32(data + 28 + 4 * j);
    v.cube_size = loadF32(data + 40);
    v.connectivity_bytes = loadU32(data + 44);
    v.position_bytes = loadU32(data + 48);
    v.normal_bytes = loadU32(data + 52);
    v.position_raw_bytes = loadU32(data + 56);
    v.normal_raw_bytes = loadU32(data + 60);
    v.has_normals = (flags & kValenceFlagNormals) != 0;
    if (v.vertex_count > kValenceMaxCount || v.triangle_count > kValenceMaxCount ||
        v.closed_vertex_count > kValenceMaxCount || v.closed_triangle_count > kValenceMaxCount)
        return Result::CorruptStream;
    if (v.triangle_count > v.closed_triangle_count) return Result::CorruptStream;
    if (v.position_bits < kValenceMinPositionBits || v.position_bits > kValenceMaxPositionBits)
        return Result::CorruptStream;
    if (v.has_normals ? (v.normal_bits < kValenceMinNormalBits || v.normal_bits > kValenceMaxNormalBits)
                      : (v.normal_bits != 0 || v.normal_bytes != 0 || v.normal_raw_bytes != 0))
        return Result::CorruptStream;
    for (int j = 0; j < 3; ++j)
        if (!std::isfinite(v.bounds_min[j])) return Result::CorruptStream;
    if (!std::isfinite(v.cube_size) || v.cube_size < 0.0f) return Result::CorruptStream;
    // Every coded symbol costs more than 1/256 of a byte (probabilities saturate), so a stream of n
    // bytes cannot describe more than a bounded number of elements: refuse larger counts before the
    // caller allocates for them.
    const uint64_t conn = v.connectivity_bytes;
    if (v.closed_triangle_count > uint64_t(kValenceTrianglesPerByte) * (conn + 1) ||
        v.closed_vertex_count > uint64_t(kValenceVerticesPerByte) * (conn + 1) ||
        v.vertex_count > uint64_t(kValencePositionsPerByte) * (uint64_t(v.position_bytes) + 1) ||
        (v.has_normals && v.vertex_count > uint64_t(kValenceNormalsPerByte) * (uint64_t(v.normal_bytes) + 1)))
        return Result::CorruptStream;
    uint64_t total = uint64_t(kValenceHeaderSize) + v.connectivity_bytes + v.position_bytes +
                     uint64_t(v.position_raw_bytes) + v.normal_bytes + uint64_t(v.normal_raw_bytes);
    if (flags & kValenceFlagAttributes) {
        const Result r = readAttributeTable(data, size, &v, &total);
        if (r != Result::Ok) return r;
    }
    if (size < total) return Result::Truncated;
    if (size > total) return Result::TrailingBytes;
    *info = v;
    return Result::Ok;
}

namespace {

// Scratch layout, in order (each block 8-aligned): see valenceScratchSize.
struct ScratchLayout {
    size_t corner_vertex, corner_opposite, vertex_flags, vertex_corner, vertex_valence, node_vertex, node_prev,
        node_next, node_free, node_corner, completion, stack_head, stack_size, final_of, final_done, qpos, qpos_final,
        decoded, plan_neighbour, plan_triples, normal_sum, qnorm, attr_closed, attr_final[kValenceMaxAttributes],
        tangent_sum, plan_boundary, twin_head, twin_next, twin_of, total;
    size_t twin_slots;
};

// Hash slots of the twin grid: a power of two at least twice the closed vertices (and 16).
size_t twinSlots(size_t closed_vertices) {
    size_t n = kValenceTwinMinSlots;
    while (n < 2 * closed_vertices) n *= 2;
    return n;
}

ScratchLayout layout(const ValenceInfo& info) {
    ScratchLayout l;
    const size_t vc = info.closed_vertex_count, tc = info.closed_triangle_count, vn = info.vertex_count;
    const size_t nodes = vc + tc;
    size_t at = 0;
    auto take = [&](size_t bytes) {
        size_t here = at;
        at += (bytes + 7) & ~size_t(7);
        return here;
    };
    l.corner_vertex = take(3 * tc * 4);
    l.corner_opposite = take(3 * tc * 4);
    l.vertex_flags = take(vc * 4);
    l.vertex_corner = take(vc * 4);
    l.vertex_valence = take(vc * 4);
    l.node_vertex = take(nodes * 4);
    l.node_prev = take(nodes * 4);
    l.node_next = take(nodes * 4);
    l.node_free = take(nodes * 4);
    l.node_corner = take(nodes * 4);
    l.completion = take(vc * 4);
    l.stack_head = take(tc * 4);
    l.stack_size = take(tc * 4);
    l.final_of = take(vc * 4);
    l.final_done = take(vn);
    l.qpos = take(3 * vc * 4);
    l.qpos_final = take(3 * vn * 4);
    l.decoded = take(vc);
    l.plan_neighbour = take(vc * 4);
    l.plan_triples = take(9 * tc * 4);
    l.normal_sum = take(info.has_normals ? 3 * vn * 8 : 0);
    l.qnorm = take(info.has_normals ? 2 * vn * 4 : 0);
    // Attributes: one closed-vertex array reused by each UV or colour set in turn (4 per vertex), each
    // attribute's quantized values in final order (a tangent keeps its octahedral pair), and the
    // tangents' face sums.
    bool tangents = false;
    l.attr_closed = take(info.attribute_count > 0 ? 4 * vc * 4 : 0);
    for (uint32_t i = 0; i < kValenceMaxAttributes; ++i) {
        const ValenceAttribute& a = info.attributes[i];
        const bool used = i < info.attribute_count;
        tangents = tangents || (used && a.kind == kValenceAttributeTangent);
        l.attr_final[i] = take(used ? (a.kind == kValenceAttributeTangent ? 2 : a.components) * vn * 4 : 0);
    }
    l.tangent_sum = take(tangents ? 4 * vn * 8 : 0);
    const bool twins = info.twin_bytes > 0;
    l.twin_slots = twins ? twinSlots(vc) : 0;
    l.plan_boundary = take(twins ? vc : 0);
    l.twin_head = take(l.twin_slots * 4);
    l.twin_next = take(twins ? vc * 4 : 0);
    l.twin_of = take(twins ? vn * 4 : 0);
    l.total = at;
    return l;
}

} // namespace

size_t valenceScratchSize(const ValenceInfo& info) {
    return layout(info).total;
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

namespace {

// The prediction out of line, one function per spread setting: inlined into valenceDecode it slows the
// whole decode of an unflagged stream, at the same instruction count (decode speed: codec_bench,
// docs/benchmarks.md, "Valence codec against Draco").
#if defined(__GNUC__) || defined(__clang__)
#define LODRT_VALENCE_NOINLINE __attribute__((noinline))
#else
#define LODRT_VALENCE_NOINLINE
#endif
template <bool Spread>
LODRT_VALENCE_NOINLINE void predictVertex(const int32_t* qpos, const uint32_t* t, uint32_t n, uint32_t neighbour,
                                          const int32_t fallback[3], int32_t out[3], uint32_t* scale,
                                          uint32_t spread[3]) {
    detail::predictFromPlanOf<Spread>(qpos, t, n, neighbour, fallback, out, scale, spread);
}

// The scratch memory as the layout places it.
struct Scratch {
    uint8_t* base;
    uint32_t* u32(size_t offset) const { return reinterpret_cast<uint32_t*>(base + offset); }
};

// 1a. The conquest over the connectivity stream, on the layout's arrays.
Result runConquest(const uint8_t* stream, const ValenceInfo& info, const ScratchLayout& l, Scratch s,
                   detail::Conquest<ConnectivityReader>& conquest, ConnectivityReader& reader) {
    const uint32_t vc = info.closed_vertex_count, tc = info.closed_triangle_count;
    detail::ConquestArrays& a = conquest.a;
    a.corner_vertex = s.u32(l.corner_vertex);
    a.corner_opposite = s.u32(l.corner_opposite);
    a.vertex_flags = s.u32(l.vertex_flags);
    a.vertex_corner = s.u32(l.vertex_corner);
    a.vertex_valence = s.u32(l.vertex_valence);
    a.node_vertex = s.u32(l.node_vertex);
    a.node_prev = s.u32(l.node_prev);
    a.node_next = s.u32(l.node_next);
    a.node_free = s.u32(l.node_free);
    a.node_corner = s.u32(l.node_corner);
    a.completion = s.u32(l.completion);
    a.stack_head = s.u32(l.stack_head);
    a.stack_size = s.u32(l.stack_size);
    a.max_vertices = vc;
    a.max_triangles = tc;
    reader.init();
    if (!reader.rd.init(stream, info.connectivity_bytes)) return Result::CorruptStream;
    const Result r = conquest.run(reader);
    if (r != Result::Ok) return r;
    if (conquest.vertex_count != vc || conquest.triangle_count != tc || conquest.completion_count != vc)
        return Result::CorruptStream;
    return Result::Ok;
}

// 1b. The duplicate list (the rest of the connectivity stream): the final vertex of every closed
// vertex (kNone for dummies); `final_count`: the vertices some triangle uses.
Result readFinalOrder(const ValenceInfo& info, const detail::ConquestArrays& a, ConnectivityReader& reader,
                      uint32_t* final_of, uint32_t* final_count) {
    const uint32_t vc = info.closed_vertex_count;
    const size_t vn = info.vertex_count;
    uint32_t dup_count = 0;
    if (!reader.readU32(reader.dup, &dup_count) || dup_count > vc) return Result::CorruptStream;
    uint32_t dups_read = 0, dup_rank = kNone, dup_original = 0;
    uint64_t previous_rank = 0;
    auto nextDup = [&]() {
        if (dups_read == dup_count) {
            dup_rank = kNone;
            return true;
        }
        uint32_t gap, back;
        if (!reader.readU32(reader.dup, &gap) || !reader.readU32(reader.dup, &back)) return false;
        const uint64_t rank = (dups_read == 0 ? 0 : previous_rank + 1) + gap;
        const uint64_t finals_before = rank - dups_read;
        if (rank >= vc || back >= finals_before) return false;
        previous_rank = rank;
        dup_rank = uint32_t(rank);
        dup_original = uint32_t(finals_before - 1 - back);
        ++dups_read;
        return true;
    };
    if (!nextDup()) return Result::CorruptStream;
    uint32_t count = 0, rank = 0;
    for (uint32_t v = 0; v < vc; ++v) {
        if (a.vertex_flags[v] & detail::kFlagDummy) {
            final_of[v] = kNone;
            continue;
        }
        if (rank++ == dup_rank) {
            final_of[v] = dup_original;
            if (!nextDup()) return Result::CorruptStream;
            continue;
        }
        if (count >= vn) return Result::CorruptStream;
        final_of[v] = count++;
    }
    if (dup_rank != kNone || !reader.rd.finishedExactly()) return Result::CorruptStream;
    *final_count = count;
    return Result::Ok;
}

// 1c. The output triangles: the closed ones without a dummy vertex, in final vertex ids.
Result writeTriangles(const ValenceInfo& info, const detail::ConquestArrays& a, const uint32_t* final_of,
                      uint32_t* indices) {
    const size_t tn = info.triangle_count;
    size_t out_t = 0;
    for (uint32_t t = 0; t < info.closed_triangle_count; ++t) {
        const uint32_t* cv = &a.corner_vertex[3 * size_t(t)];
        if ((a.vertex_flags[cv[0]] | a.vertex_flags[cv[1]] | a.vertex_flags[cv[2]]) & detail::kFlagDummy) continue;
        if (out_t >= tn) return Result::CorruptStream;
        for (int i = 0; i < 3; ++i) indices[3 * out_t + size_t(i)] = final_of[cv[i]];
        ++out_t;
    }
    return out_t == tn ? Result::Ok : Result::CorruptStream;
}

// The position streams and their models.
struct PositionReader {
    RangeDecoder pos;
    BitReader pos_raw;
    ResidualModel<3, detail::kPositionContexts> model;
    uint32_t snap_models[3][kValenceSnapContexts];
    uint32_t snap_flags = 0, spread_flags = 0;
    int32_t qmax = 0;
    const int32_t* qpos = nullptr; // engine-order positions decoded so far (snap candidates)
    uint32_t prev_sign[3] = {0, 0, 0};

    // One vertex: x, then y and z in the context of the earlier residual lengths and signs, each
    // residual added to `pred`; a snapped component first reads whether it is its candidate. `t`, `n`,
    // `nb`: the plan entry (none: 0, kNone). False on a corrupt stream or a coordinate outside [0, qmax].
    bool vertex(uint32_t ctx, const uint32_t* spread, const int32_t* pred, int32_t* out, const uint32_t* t,
                uint32_t n, uint32_t nb) {
        uint32_t earlier = kNone, x_sign = 0;
        int32_t candidate[3] = {0, 0, 0};
        uint32_t snap_ctx[3] = {0, 0, 0};
        const uint32_t snap =
            snap_flags != 0 && detail::snapCandidates(qpos, t, n, nb, pred, snap_flags, candidate, snap_ctx)
                ? snap_flags
                : 0u;
        for (int j = 0; j < 3; ++j) {
            int32_t res;
            uint32_t length;
            if ((snap >> j) & 1u && pos.bit(snap_models[j][snap_ctx[j]])) {
                res = candidate[j] - pred[j];
                length = detail::bitLength(uint32_t(res < 0 ? -res : res));
            } else if (!model.decode(pos, pos_raw, j,
                                     (spread_flags >> j) & 1u ? detail::spreadContext(ctx, earlier, spread[j])
                                                              : detail::positionContext(ctx, earlier),
                                     &res, &length, prev_sign[j] * 3 + x_sign)) {
                return false;
            }
            prev_sign[j] = detail::signClass(res);
            if (j == 0) x_sign = prev_sign[0];
            earlier = earlier == kNone || length > earlier ? length : earlier;
            const int32_t value = pred[j] + res;
            if (value < 0 || value > qmax) return false;
            out[j] = value;
        }
        return true;
    }
};

// 2. Positions, in the order the plan gives, then the vertices no triangle uses. The plan (order and
// prediction triples) comes from the connectivity alone, then one sequential pass of residuals. The
// node arrays are free again: they hold the order's degree counts and stacks. Fills qpos_final and
// the output positions.
// Position twins (docs/format/valence.md "Twins"): the boundary vertices coded so far in a grid, and
// the twin decisions' own range-coded part. Inactive (no grid) in a stream without twins.
struct TwinReader {
    RangeDecoder rd;
    detail::TwinGrid grid;
    uint32_t models[detail::kTwinContexts];
    uint32_t* twin_of = nullptr; // per final vertex: its twin partner, kNone
    const uint8_t* boundary = nullptr;
    bool active = false;

    bool init(const uint8_t* part, const ValenceInfo& info, const ScratchLayout& l, Scratch s) {
        active = info.twin_bytes > 0;
        if (!active) return true;
        if (!rd.init(part, info.twin_bytes)) return false;
        detail::initRangeProbs(models, detail::kTwinContexts);
        grid.head = s.u32(l.twin_head);
        grid.next = s.u32(l.twin_next);
        grid.mask = uint32_t(l.twin_slots - 1);
        grid.shift = info.twin_shift;
        grid.qmax = int32_t((1u << info.position_bits) - 1);
        for (size_t i = 0; i < l.twin_slots; ++i) grid.head[i] = kNone;
        twin_of = s.u32(l.twin_of);
        for (size_t i = 0; i < info.vertex_count; ++i) twin_of[i] = kNone;
        boundary = s.base + l.plan_boundary;
        return true;
    }
    // The twin of plan entry i predicted at `pred`, kNone when it has none or the stream says no.
    uint32_t twin(uint32_t i, const int32_t* qpos, const int32_t pred[3], const uint32_t* t, uint32_t n,
                  uint32_t neighbour) {
        if (!active || !boundary[i]) return kNone;
        uint32_t ctx = 0;
        const uint32_t candidate = detail::twinCandidate(grid, qpos, pred, t, n, neighbour, &ctx);
        if (candidate == kNone || !rd.bit(models[ctx])) return kNone;
        return candidate;
    }
    void pair(uint32_t a, uint32_t b) {
        if (twin_of[a] == kNone) twin_of[a] = b;
        if (twin_of[b] == kNone) twin_of[b] = a;
    }
};

Result decodePositions(const uint8_t* data, const uint8_t* stream, const ValenceInfo& info, const ScratchLayout& l,
                       Scratch s, const detail::ConquestArrays& a, uint32_t final_count, const ValenceOutput& output,
                       detail::PositionPlan& plan) {
    const size_t vn = info.vertex_count;
    const uint32_t* final_of = s.u32(l.final_of);
    PositionReader reader;
    if (!reader.pos.init(stream, info.position_bytes)) return Result::CorruptStream;
    reader.pos_raw.init(stream + info.position_bytes, info.position_raw_bytes);
    reader.model.init();
    int32_t* qpos = reinterpret_cast<int32_t*>(s.base + l.qpos);
    int32_t* qpos_final = reinterpret_cast<int32_t*>(s.base + l.qpos_final);
    reader.qpos = qpos;
    reader.qmax = int32_t((1u << info.position_bits) - 1);
    const int32_t qmax = reader.qmax;
    int32_t last[3] = {(qmax + 1) / 2, (qmax + 1) / 2, (qmax + 1) / 2};
    detail::initRangeProbs(&reader.snap_models[0][0], sizeof(reader.snap_models) / 4);
    reader.snap_flags = uint32_t(loadU16(data + 6) / kValenceFlagSnapX) & 7u; // header checked above
    reader.spread_flags = uint32_t(loadU16(data + 6) / kValenceFlagSpreadX) & 7u;
    uint8_t* final_done = s.base + l.final_done;
    // An empty mesh has no scratch (null base): memset's pointer must not be null even for 0 bytes.
    if (vn > 0) std::memset(final_done, 0, vn);
    plan.order = a.completion;
    plan.count = a.node_corner;
    plan.neighbour = s.u32(l.plan_neighbour);
    plan.triples = s.u32(l.plan_triples);
    plan.max_triples = 3 * info.closed_triangle_count;
    TwinReader twins;
    if (!twins.init(stream + info.position_bytes + size_t(info.position_raw_bytes), info, l, s))
        return Result::CorruptStream;
    plan.boundary = twins.active ? s.base + l.plan_boundary : nullptr;
    if (!detail::planPositions(a.corner_vertex, a.corner_opposite, a.vertex_corner, a.vertex_flags, a.vertex_valence,
                               info.closed_vertex_count, s.base + l.decoded, a.node_vertex, a.node_prev, a.node_next,
                               &plan))
        return Result::CorruptStream;
    const uint32_t* triple = plan.triples;
    for (uint32_t i = 0; i < plan.ordered; ++i) {
        const uint32_t v = plan.order[i], n = plan.count[i];
        const uint32_t fid = final_of[v];
        int32_t* q = &qpos[3 * size_t(v)];
        int32_t* qf = &qpos_final[3 * size_t(fid)];
        if (final_done[fid]) {
            q[0] = qf[0];
            q[1] = qf[1];
            q[2] = qf[2];
        } else {
            int32_t pred[3];
            uint32_t scale, spread[3] = {0, 0, 0};
            if (reader.spread_flags != 0)
                predictVertex<true>(qpos, triple, n, plan.neighbour[i], last, pred, &scale, spread);
            else
                predictVertex<false>(qpos, triple, n, plan.neighbour[i], last, pred, &scale, spread);
            const uint32_t twin = twins.twin(i, qpos, pred, triple, n, plan.neighbour[i]);
            if (twin != kNone) {
                for (int j = 0; j < 3; ++j) q[j] = qpos[3 * size_t(twin) + size_t(j)];
                twins.pair(fid, final_of[twin]);
            } else if (!reader.vertex(detail::scaleContext(scale, n), spread, pred, q, triple, n, plan.neighbour[i])) {
                return Result::CorruptStream;
            }
            qf[0] = q[0];
            qf[1] = q[1];
            qf[2] = q[2];
            final_done[fid] = 1;
        }
        if (twins.active && twins.boundary[i]) detail::twinInsert(twins.grid, qpos, v);
        triple += 3 * size_t(n);
        last[0] = q[0];
        last[1] = q[1];
        last[2] = q[2];
        if (reader.pos.overrun() || reader.pos_raw.overrun() || (twins.active && twins.rd.overrun()))
            return Result::CorruptStream;
    }
    if (twins.active && !twins.rd.finishedExactly()) return Result::CorruptStream;
    for (size_t fid = final_count; fid < vn; ++fid) {
        int32_t* qf = &qpos_final[3 * fid];
        const uint32_t no_spread[3] = {0, 0, 0};
        if (!reader.vertex(detail::scaleContext(0, 0), no_spread, last, qf, nullptr, 0, kNone))
            return Result::CorruptStream;
        last[0] = qf[0];
        last[1] = qf[1];
        last[2] = qf[2];
    }
    if (!reader.pos.finishedExactly() || !reader.pos_raw.finishedExactly()) return Result::CorruptStream;
    const float step = qmax > 0 ? info.cube_size / float(qmax) : 0.0f;
    for (size_t i = 0; i < 3 * vn; ++i) output.positions[i] = info.bounds_min[i % 3] + float(qpos_final[i]) * step;
    return Result::Ok;
}

// 3. Normals, in final order, predicted by the exact sum of the face normals on the quantized
// positions.
Result decodeNormals(const uint8_t* stream, const ValenceInfo& info, const ScratchLayout& l, Scratch s,
                     const ValenceOutput& output) {
    const size_t vn = info.vertex_count, tn = info.triangle_count;
    RangeDecoder nrm;
    if (!nrm.init(stream, info.normal_bytes)) return Result::CorruptStream;
    BitReader nrm_raw;
    nrm_raw.init(stream + info.normal_bytes, info.normal_raw_bytes);
    const int32_t* qpos_final = reinterpret_cast<const int32_t*>(s.base + l.qpos_final);
    int64_t* sum = reinterpret_cast<int64_t*>(s.base + l.normal_sum);
    uint32_t* qnorm = s.u32(l.qnorm);
    const uint32_t* twin_of = info.twin_bytes > 0 ? s.u32(l.twin_of) : nullptr;
    for (size_t i = 0; i < 3 * vn; ++i) sum[i] = 0;
    for (size_t t = 0; t < tn; ++t) detail::addFaceNormal(qpos_final, &output.indices[3 * t], sum);
    ResidualModel<2, kValenceNormalContexts> nrm_model;
    nrm_model.init();
    const uint32_t nb = info.normal_bits;
    const uint32_t mask = (1u << nb) - 1;
    const int32_t half = int32_t(1) << (nb - 1);
    uint32_t nrm_length[2] = {0, 0};
    for (size_t x = 0; x < vn; ++x) {
        uint32_t p[2];
        detail::predictNormalTwin(&sum[3 * x], qnorm, x, twin_of ? twin_of[x] : kNone, nb, p);
        for (int j = 0; j < 2; ++j) {
            int32_t res;
            uint32_t length;
            const uint32_t ctx = nrm_length[j] < kValenceNormalContexts ? nrm_length[j] : kValenceNormalContexts - 1;
            if (!nrm_model.decode(nrm, nrm_raw, j, ctx, &res, &length)) return Result::CorruptStream;
            if (res < -half || res >= half) return Result::CorruptStream;
            nrm_length[j] = length;
            qnorm[2 * x + size_t(j)] = (p[j] + uint32_t(res)) & mask;
        }
        if (nrm.overrun() || nrm_raw.overrun()) return Result::CorruptStream;
    }
    if (!nrm.finishedExactly() || !nrm_raw.finishedExactly()) return Result::CorruptStream;
    if (output.normals) {
        for (size_t i = 0; i < vn; ++i) octahedralDecode(&qnorm[2 * i], info.normal_bits, &output.normals[3 * i]);
    }
    return Result::Ok;
}

// Residual models of one UV or colour set (docs/format/valence.md "Attributes").
using AttributeModel = ResidualModel<4, kValenceAttributeContexts>;

// Reads one vertex's UV or colour value given its prediction; false on a corrupt stream.
inline bool readAttributeValue(RangeDecoder& rd, BitReader& raw, AttributeModel& model, uint32_t components,
                               uint32_t bits, bool decorrelated, uint32_t n, const int32_t* pred,
                               uint32_t* prev_length, uint32_t* prev_sign, int32_t* out) {
    const uint32_t mask = (1u << bits) - 1;
    const int32_t half = int32_t(1) << (bits - 1);
    uint32_t earlier = 0, first_sign = 0, first = 0;
    for (uint32_t j = 0; j < components; ++j) {
        int32_t res;
        uint32_t length;
        const uint32_t ctx = detail::attributeContext(j, n, j == 0 ? *prev_length : earlier);
        if (!model.decode(rd, raw, int(j), ctx, &res, &length, prev_sign[j] * 3 + first_sign)) return false;
        if (res < -half || res >= half) return false;
        prev_sign[j] = detail::signClass(res);
        if (j == 0) {
            first_sign = prev_sign[0];
            *prev_length = length;
        }
        earlier = length > earlier ? length : earlier;
        // Decorrelated channels 1..: the coded value is the residual minus channel 0's (mod 2^bits).
        const uint32_t r = uint32_t(res) + (decorrelated && j > 0 ? first : 0u);
        if (j == 0) first = uint32_t(res);
        out[j] = int32_t((uint32_t(pred[j]) + r) & mask);
    }
    return true;
}

// A UV or colour set: predicted over the position plan (same order, same triples), copies taking their
// final vertex's value, then the vertices no triangle uses from the previous value.
LODRT_VALENCE_NOINLINE Result decodeAttribute(const uint8_t* stream, const ValenceInfo& info, uint32_t index,
                                              const ScratchLayout& l, Scratch s, const detail::PositionPlan& plan,
                                              uint32_t final_count, const ValenceOutput& output) {
    const ValenceAttribute& at = info.attributes[index];
    const size_t vn = info.vertex_count;
    const uint32_t c = at.components;
    const bool decorrelated = detail::decorrelatedChannels(at.predictor);
    RangeDecoder rd;
    if (!rd.init(stream, at.bytes)) return Result::CorruptStream;
    BitReader raw;
    raw.init(stream + at.bytes, at.raw_bytes);
    AttributeModel model;
    model.init();
    const uint32_t* final_of = s.u32(l.final_of);
    const int32_t* qpos = reinterpret_cast<const int32_t*>(s.base + l.qpos);
    int32_t* qa = reinterpret_cast<int32_t*>(s.base + l.attr_closed);
    int32_t* qf = reinterpret_cast<int32_t*>(s.base + l.attr_final[index]);
    uint8_t* final_done = s.base + l.final_done;
    if (vn > 0) std::memset(final_done, 0, vn);
    const int32_t qmax = int32_t((1u << at.bits) - 1);
    int32_t last[4] = {(qmax + 1) / 2, (qmax + 1) / 2, (qmax + 1) / 2, (qmax + 1) / 2};
    uint32_t prev_length = 0, prev_sign[4] = {0, 0, 0, 0};
    const uint32_t* triple = plan.triples;
    for (uint32_t i = 0; i < plan.ordered; ++i) {
        const uint32_t v = plan.order[i], n = plan.count[i];
        const uint32_t fid = final_of[v];
        int32_t* q = &qa[4 * size_t(v)];
        int32_t* f = &qf[c * size_t(fid)];
        if (final_done[fid]) {
            for (uint32_t j = 0; j < c; ++j) q[j] = f[j];
        } else {
            int32_t pred[4];
            detail::predictAttribute(qa, c, qpos, v, triple, n, plan.neighbour[i], last, at.predictor, qmax, pred);
            if (!readAttributeValue(rd, raw, model, c, at.bits, decorrelated, n, pred, &prev_length, prev_sign, q))
                return Result::CorruptStream;
            for (uint32_t j = 0; j < c; ++j) f[j] = q[j];
            final_done[fid] = 1;
        }
        triple += 3 * size_t(n);
        for (uint32_t j = 0; j < c; ++j) last[j] = q[j];
        if (rd.overrun() || raw.overrun()) return Result::CorruptStream;
    }
    for (size_t fid = final_count; fid < vn; ++fid) {
        int32_t* f = &qf[c * fid];
        if (!readAttributeValue(rd, raw, model, c, at.bits, decorrelated, 0, last, &prev_length, prev_sign, f))
            return Result::CorruptStream;
        for (uint32_t j = 0; j < c; ++j) last[j] = f[j];
        if (rd.overrun() || raw.overrun()) return Result::CorruptStream;
    }
    if (!rd.finishedExactly() || !raw.finishedExactly()) return Result::CorruptStream;
    float* out = output.attributes[index];
    if (out) {
        float step[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        for (uint32_t j = 0; j < c; ++j) step[j] = qmax > 0 ? at.size[j] / float(qmax) : 0.0f;
        for (size_t x = 0; x < vn; ++x)
            for (uint32_t j = 0; j < c; ++j) out[c * x + j] = at.min[j] + float(qf[c * x + j]) * step[j];
    }
    return Result::Ok;
}

// Tangents, in final order after the UV and colour sets before them: the octahedral pair predicted from
// the UV tangent direction summed over the vertex's triangles (on its UV attribute), the handedness in
// the context of their summed UV orientation.
LODRT_VALENCE_NOINLINE Result decodeTangent(const uint8_t* stream, const ValenceInfo& info, uint32_t index,
                                            const ScratchLayout& l, Scratch s, const ValenceOutput& output) {
    const ValenceAttribute& at = info.attributes[index];
    const size_t vn = info.vertex_count, tn = info.triangle_count;
    RangeDecoder rd;
    if (!rd.init(stream, at.bytes)) return Result::CorruptStream;
    BitReader raw;
    raw.init(stream + at.bytes, at.raw_bytes);
    const int32_t* qpos_final = reinterpret_cast<const int32_t*>(s.base + l.qpos_final);
    int64_t* sum = reinterpret_cast<int64_t*>(s.base + l.tangent_sum);
    uint32_t* qt = s.u32(l.attr_final[index]);
    for (size_t i = 0; i < 4 * vn; ++i) sum[i] = 0;
    if (at.predictor != kValenceNoReference) {
        const int32_t* quv = reinterpret_cast<const int32_t*>(s.base + l.attr_final[at.predictor]);
        for (size_t t = 0; t < tn; ++t) detail::addFaceTangent(qpos_final, quv, &output.indices[3 * t], sum);
    }
    ResidualModel<2, kValenceNormalContexts> model;
    model.init();
    uint32_t sign_models[kValenceTangentSignContexts];
    detail::initRangeProbs(sign_models, kValenceTangentSignContexts);
    const uint32_t nb = at.bits, mask = (1u << nb) - 1;
    const int32_t half = int32_t(1) << (nb - 1);
    uint32_t length[2] = {0, 0};
    float* out = output.attributes[index];
    for (size_t x = 0; x < vn; ++x) {
        uint32_t p[2];
        detail::predictNormal(&sum[4 * x], qt, x, nb, p);
        for (int j = 0; j < 2; ++j) {
            int32_t res;
            uint32_t k;
            const uint32_t ctx = length[j] < kValenceNormalContexts ? length[j] : kValenceNormalContexts - 1;
            if (!model.decode(rd, raw, j, ctx, &res, &k)) return Result::CorruptStream;
            if (res < -half || res >= half) return Result::CorruptStream;
            length[j] = k;
            qt[2 * x + size_t(j)] = (p[j] + uint32_t(res)) & mask;
        }
        const uint32_t negative = rd.bit(sign_models[detail::tangentSignContext(sum[4 * x + 3])]);
        if (out) {
            octahedralDecode(&qt[2 * x], nb, &out[4 * x]);
            out[4 * x + 3] = negative ? -1.0f : 1.0f;
        }
        if (rd.overrun() || raw.overrun()) return Result::CorruptStream;
    }
    if (!rd.finishedExactly() || !raw.finishedExactly()) return Result::CorruptStream;
    return Result::Ok;
}

// Every attribute of the table, in table order, from `stream` (just after the normal parts).
Result decodeAttributes(const uint8_t* stream, const ValenceInfo& info, const ScratchLayout& l, Scratch s,
                        const detail::PositionPlan& plan, uint32_t final_count, const ValenceOutput& output) {
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        const ValenceAttribute& at = info.attributes[i];
        const Result r = at.kind == kValenceAttributeTangent
                             ? decodeTangent(stream, info, i, l, s, output)
                             : decodeAttribute(stream, info, i, l, s, plan, final_count, output);
        if (r != Result::Ok) return r;
        stream += at.bytes + size_t(at.raw_bytes);
    }
    return Result::Ok;
}

} // namespace

Result valenceDecode(const uint8_t* data, size_t size, const ValenceOutput& output) {
    ValenceInfo info;
    Result r = valenceReadInfo(data, size, &info);
    if (r != Result::Ok) return r;
    const size_t vn = info.vertex_count, tn = info.triangle_count;
    if ((tn > 0 && !output.indices) || (vn > 0 && !output.positions)) return Result::InvalidArgument;
    if (reinterpret_cast<uintptr_t>(output.scratch) % 8 != 0) return Result::InvalidArgument;
    const ScratchLayout l = layout(info);
    if (l.total > 0 && !output.scratch) return Result::InvalidArgument;
    if (output.index_capacity < 3 * tn || output.position_capacity < 3 * vn || output.scratch_size < l.total ||
        (output.normals && info.has_normals && output.normal_capacity < 3 * vn))
        return Result::BufferTooSmall;
    for (uint32_t i = 0; i < info.attribute_count; ++i)
        if (output.attributes[i] && output.attribute_capacity[i] < size_t(info.attributes[i].components) * vn)
            return Result::BufferTooSmall;
    const Scratch s{static_cast<uint8_t*>(output.scratch)};

    // 1. Connectivity: the conquest, then the duplicate list.
    const uint8_t* stream = data + kValenceHeaderSize;
    if (info.attribute_count > 0)
        stream += kValenceAttributeTablePrefix + size_t(info.attribute_count) * kValenceAttributeRecordSize;
    detail::Conquest<ConnectivityReader> conquest;
    ConnectivityReader reader;
    r = runConquest(stream, info, l, s, conquest, reader);
    if (r != Result::Ok) return r;
    uint32_t final_count = 0;
    r = readFinalOrder(info, conquest.a, reader, s.u32(l.final_of), &final_count);
    if (r != Result::Ok) return r;
    r = writeTriangles(info, conquest.a, s.u32(l.final_of), output.indices);
    if (r != Result::Ok) return r;
    stream += info.connectivity_bytes;
    detail::PositionPlan plan;
    r = decodePositions(data, stream, info, l, s, conquest.a, final_count, output, plan);
    if (r != Result::Ok) return r;
    stream += info.position_bytes + size_t(info.position_raw_bytes) + info.twin_bytes;
    if (info.has_normals) {
        r = decodeNormals(stream, info, l, s, output);
        if (r != Result::Ok) return r;
    }
    stream += info.normal_bytes + size_t(info.normal_raw_bytes);
    return decodeAttributes(stream, info, l, s, plan, final_count, output);
}

} // namespace lodrt
