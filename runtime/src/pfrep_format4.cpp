// PFRep format 4 decoder (docs/format/pfrep.md, "Format 4"): the removal sequence is decoded and
// replayed on LOD0's points and triangles, the table laid out and the records decoded
// (lodrt/detail/pfrep_codec4.h, shared with the baker's encoder), all in caller memory; openPfrep
// then validates the rebuilt format 2 blob as it validates any other.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "lodrt/detail/pfrep_codec4.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "lodrt/valence.h"
#include "little_endian.h"
#include "range_decoder.h"

namespace lodrt {
namespace {

using detail::loadF32;
using detail::loadU32;

struct DecodeCoder {
    static constexpr bool kEncoding = false;
    detail::RangeDecoder rd;
    bool bad = false;
    uint32_t bit(uint32_t& prob, uint32_t) { return rd.bit(prob); }
    uint32_t tree(uint32_t* probs, uint32_t bits, uint32_t) { return rd.tree(probs, bits); }
    uint32_t direct(uint32_t, uint32_t count) { return rd.direct(count); }
    uint64_t uint(detail::PfrepUintModel& model, uint64_t) {
        uint64_t v = 0;
        if (!rd.uint(model.klass, model.top, &v)) bad = true;
        return bad ? 0 : v;
    }
    bool failed() const { return bad || rd.overrun(); }
};

Result readHeader(const uint8_t* p, size_t size, detail::Pfrep4Header& h) {
    if (size < format::kPfrepHeaderSize) return Result::Truncated;
    if (loadU32(p) != format::kPfrepMagic) return Result::BadMagic;
    if (loadU32(p + 4) != format::kPfrepVersionLod0) return Result::UnsupportedVersion;
    h.vertex_count = loadU32(p + 8);
    h.removed_count = loadU32(p + 12);
    h.point_count = loadU32(p + 16);
    h.level0_triangles = loadU32(p + 20);
    for (int a = 0; a < 3; ++a) {
        h.position_min[a] = loadF32(p + 24 + 4 * a);
        h.position_step[a] = loadF32(p + 36 + 4 * a);
        if (!std::isfinite(h.position_min[a]) || !std::isfinite(h.position_step[a]) || h.position_step[a] < 0)
            return Result::BadStructure;
    }
    h.error_unit = loadF32(p + 48);
    h.decoded_size = loadU32(p + 52);
    h.stored_triangles = loadU32(p + 56);
    h.flags = loadU32(p + 60);
    if (!std::isfinite(h.error_unit) || h.error_unit < 0 || (h.flags & ~format::kPfrep4Flags) != 0)
        return Result::BadStructure;
    // A split list numbers a pack's LOD0, whose blob codes its tail and checks that LOD0.
    if ((h.flags & format::kPfrep4FlagSplitPoints) != 0 && (h.flags & format::kPfrep4Flags) != format::kPfrep4Flags)
        return Result::BadStructure;
    if (h.vertex_count > format::kPfrepMaxVertices || h.removed_count > h.vertex_count ||
        h.point_count > format::kPfrepMaxVertices || h.vertex_count > h.point_count ||
        h.stored_triangles < h.level0_triangles ||
        uint64_t(h.stored_triangles) > uint64_t(h.level0_triangles) * format::kPfrepMaxStoredPerLevel0)
        return Result::BadStructure;
    // Every vertex has a record and an entry offset; every block its padding.
    const uint64_t blocks = (uint64_t(h.vertex_count) + (uint64_t(1) << format::kPfrepMaxBlockShift) - 1) >>
                            format::kPfrepMaxBlockShift;
    if (h.decoded_size < format::kPfrepHeaderSize + uint64_t(h.vertex_count) * (format::kPfrepVertexRecordSize + 2) +
                             blocks * (4 + format::kPfrepStreamPadding))
        return Result::BadStructure;
    return Result::Ok;
}

// Where the main stream starts, past the split list (kPfrep4FlagSplitPoints: its u32 byte count,
// then its own range-coded stream, at least 5 bytes); *split / *split_bytes locate the list (null /
// 0 without the flag).
Result splitList(const uint8_t* p, size_t size, const detail::Pfrep4Header& h, const uint8_t** split,
                 size_t* split_bytes, size_t* stream_at) {
    *split = nullptr;
    *split_bytes = 0;
    *stream_at = format::kPfrepHeaderSize;
    if ((h.flags & format::kPfrep4FlagSplitPoints) == 0) return Result::Ok;
    if (size < format::kPfrepHeaderSize + 4) return Result::Truncated;
    const uint32_t bytes = loadU32(p + format::kPfrepHeaderSize);
    if (bytes < 5) return Result::CorruptStream;
    if (bytes > size - format::kPfrepHeaderSize - 4) return Result::Truncated;
    *split = p + format::kPfrepHeaderSize + 4;
    *split_bytes = bytes;
    *stream_at = format::kPfrepHeaderSize + 4 + size_t(bytes);
    return Result::Ok;
}

// Slots of the welding hash table: a power of two at least twice the vertex count.
uint64_t weldSlots(uint32_t vertex_count) {
    uint64_t n = 2;
    while (n < uint64_t(vertex_count) * 2) n <<= 1;
    return n;
}

uint32_t positionHash(const uint32_t bits[3]) {
    uint32_t h = bits[0] * 0x9E3779B1u;
    h ^= bits[1] * 0x85EBCA77u + (h << 6) + (h >> 2);
    h ^= bits[2] * 0xC2B2AE3Du + (h << 6) + (h >> 2);
    return h ^ (h >> 15);
}

} // namespace

size_t pfrepNumberLod0ScratchBytes(uint32_t vertex_count) {
    return size_t((weldSlots(vertex_count) + vertex_count) * sizeof(uint32_t) + 7) & ~size_t(7);
}

namespace {

// pfrepNumberLod0, with the split list split[0, split_bytes) applied to the welds when split is not
// null.
Result numberLod0(const uint8_t* split, size_t split_bytes, const float* positions, uint32_t vertex_count,
                  const uint32_t* indices, uint32_t triangle_count, float* points, size_t point_capacity,
                  uint32_t* triangles, size_t triangle_capacity, void* scratch, size_t scratch_bytes,
                  PfrepLod0* lod0) {
    if ((vertex_count > 0 && (!positions || !points)) || (triangle_count > 0 && (!indices || !triangles)) || !scratch ||
        !lod0 || (split_bytes > 0 && !split))
        return Result::InvalidArgument;
    if (point_capacity < size_t(vertex_count) * 3 || triangle_capacity < size_t(triangle_count) * 3 ||
        scratch_bytes < pfrepNumberLod0ScratchBytes(vertex_count))
        return Result::BufferTooSmall;
    const uint64_t slots = weldSlots(vertex_count);
    uint32_t* table = static_cast<uint32_t*>(scratch);
    uint32_t* point_of = table + slots; // per vertex: its welded point (kNone until used)
    std::memset(table, 0xFF, size_t(slots) * sizeof(uint32_t));
    // Weld: each vertex to the first vertex with its position bits (open addressing), kept in
    // point_of as "weld representative" for now.
    for (uint32_t v = 0; v < vertex_count; ++v) {
        uint32_t bits[3];
        std::memcpy(bits, positions + size_t(v) * 3, 12);
        uint64_t at = positionHash(bits) & (slots - 1);
        while (table[at] != detail::kNone && std::memcmp(positions + size_t(table[at]) * 3, bits, 12) != 0)
            at = (at + 1) & (slots - 1);
        if (table[at] == detail::kNone) table[at] = v;
        point_of[v] = table[at];
    }
    if (split) { // the table is free: two vertex_count arrays for the welds' lists (slots >= 2 * vertex_count)
        detail::Pfrep4SplitModels models;
        models.init();
        DecodeCoder c;
        if (!c.rd.init(split, split_bytes)) return Result::CorruptStream;
        if (!detail::pfrep4CodeSplits(c, models, vertex_count, point_of, nullptr, table, table + vertex_count))
            return c.rd.overrun() ? Result::Truncated : Result::CorruptStream;
        if (c.rd.overrun()) return Result::Truncated;
        if (!c.rd.finishedExactly()) return Result::CorruptStream;
    }
    // The table is free again: it now maps a representative to its point id.
    std::memset(table, 0xFF, size_t(vertex_count) * sizeof(uint32_t)); // slots >= vertex_count
    uint32_t point_count = 0, kept = 0;
    for (uint32_t t = 0; t < triangle_count; ++t) {
        const uint32_t* c = indices + size_t(t) * 3;
        if (c[0] >= vertex_count || c[1] >= vertex_count || c[2] >= vertex_count) return Result::BadStructure;
        const uint32_t w[3] = {point_of[c[0]], point_of[c[1]], point_of[c[2]]};
        if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;
        for (uint32_t k = 0; k < 3; ++k) {
            if (table[w[k]] == detail::kNone) {
                std::memcpy(points + size_t(point_count) * 3, positions + size_t(w[k]) * 3, 12);
                table[w[k]] = point_count++;
            }
            triangles[size_t(kept) * 3 + k] = table[w[k]];
        }
        ++kept;
    }
    lod0->positions = points;
    lod0->point_count = point_count;
    lod0->triangles = triangles;
    lod0->triangle_count = kept;
    return Result::Ok;
}

} // namespace

Result pfrepNumberLod0(const float* positions, uint32_t vertex_count, const uint32_t* indices, uint32_t triangle_count,
                       float* points, size_t point_capacity, uint32_t* triangles, size_t triangle_capacity,
                       void* scratch, size_t scratch_bytes, PfrepLod0* lod0) {
    return numberLod0(nullptr, 0, positions, vertex_count, indices, triangle_count, points, point_capacity, triangles,
                      triangle_capacity, scratch, scratch_bytes, lod0);
}

Result pfrepNumberLod0Split(const void* split, size_t split_bytes, const float* positions, uint32_t vertex_count,
                            const uint32_t* indices, uint32_t triangle_count, float* points, size_t point_capacity,
                            uint32_t* triangles, size_t triangle_capacity, void* scratch, size_t scratch_bytes,
                            PfrepLod0* lod0) {
    if (split && split_bytes == 0) return Result::InvalidArgument;
    return numberLod0(static_cast<const uint8_t*>(split), split_bytes, positions, vertex_count, indices,
                      triangle_count, points, point_capacity, triangles, triangle_capacity, scratch, scratch_bytes,
                      lod0);
}

Result pfrepFormat4SplitList(const void* blob, size_t size, const void** split, size_t* split_bytes) {
    if (!blob || !split || !split_bytes) return Result::InvalidArgument;
    const uint8_t* p = static_cast<const uint8_t*>(blob);
    detail::Pfrep4Header h;
    Result r = readHeader(p, size, h);
    if (r != Result::Ok) return r;
    const uint8_t* at = nullptr;
    size_t stream_at = 0;
    r = splitList(p, size, h, &at, split_bytes, &stream_at);
    *split = at;
    return r;
}

Result pfrepFormat4Info(const void* data, size_t size, PfrepFormat4Info* info) {
    if (!data || !info) return Result::InvalidArgument;
    detail::Pfrep4Header h;
    const Result r = readHeader(static_cast<const uint8_t*>(data), size, h);
    if (r != Result::Ok) return r;
    const uint64_t values = detail::pfrep4ScratchValues(h);
    if (values > SIZE_MAX / 4) return Result::BadStructure; // more than this platform can address
    info->vertex_count = h.vertex_count;
    info->point_count = h.point_count;
    info->level0_triangles = h.level0_triangles;
    info->decoded_bytes = h.decoded_size;
    info->scratch_bytes = size_t(values * 4);
    return Result::Ok;
}

Result pfrepDecodeFormat4(const void* data, size_t size, const PfrepLod0& lod0, void* out, size_t out_capacity,
                          void* scratch, size_t scratch_bytes, PfrepModel* model) {
    if (!data || !out || !scratch || !model) return Result::InvalidArgument;
    const uint8_t* in = static_cast<const uint8_t*>(data);
    detail::Pfrep4State s;
    Result r = readHeader(in, size, s.h);
    if (r != Result::Ok) return r;
    const uint64_t values = detail::pfrep4ScratchValues(s.h);
    if (values > SIZE_MAX / 4) return Result::BadStructure;
    if (out_capacity < s.h.decoded_size || scratch_bytes < values * 4) return Result::BufferTooSmall;
    if ((reinterpret_cast<uintptr_t>(scratch) & 7) != 0) return Result::InvalidArgument;
    if (lod0.point_count != s.h.point_count || lod0.triangle_count != s.h.level0_triangles ||
        (lod0.point_count > 0 && !lod0.positions) || (lod0.triangle_count > 0 && !lod0.triangles))
        return Result::BadStructure;
    const uint8_t* split = nullptr;
    size_t split_bytes = 0, stream_at = 0;
    r = splitList(in, size, s.h, &split, &split_bytes, &stream_at);
    if (r != Result::Ok) return r;
    if (size < stream_at + 5) return Result::Truncated; // the range coder's first bytes
    s.lod0.positions = lod0.positions;
    s.lod0.triangles = lod0.triangles;
    s.lod0.point_count = lod0.point_count;
    s.lod0.triangle_count = lod0.triangle_count;
    detail::Pfrep4Models* models = detail::pfrep4Carve(s, static_cast<uint32_t*>(scratch));
    models->init();
    uint8_t* o = static_cast<uint8_t*>(out);
    std::memset(o, 0, s.h.decoded_size);
    DecodeCoder c;
    if (!c.rd.init(in + stream_at, size - stream_at)) return Result::CorruptStream;
    if (!detail::pfrep4LoadLod0(s)) return Result::BadStructure;
    if (!detail::pfrep4CodeLod0Check(c, s)) return c.rd.overrun() ? Result::Truncated : Result::BadStructure;
    if (!detail::pfrep4CodeRemovals(c, *models, s, nullptr, nullptr) || !detail::pfrep4CodeTail(c, s, nullptr) ||
        !detail::pfrep4BuildSlots(s) || !detail::pfrep4Layout(s) || s.layout_size != s.h.decoded_size ||
        !detail::pfrep4CodeRecords(c, *models, s, nullptr, o))
        return c.rd.overrun() ? Result::Truncated : Result::CorruptStream;
    detail::pfrep4WriteBlob(s, o);
    if (c.rd.overrun()) return Result::Truncated;
    if (!c.rd.finishedExactly()) return Result::CorruptStream;
    return openPfrep(o, s.h.decoded_size, model);
}

namespace {

size_t align8(uint64_t n) {
    return size_t((n + 7) & ~uint64_t(7));
}

// Scratch of a pack's format 4 decode, in order: LOD0's positions and indices as its stream decodes
// them, the numbered points and triangles, then one block the valence decoder, the numbering and
// the format 4 decoder use in turn (the largest of the three).
struct PackScratch {
    uint64_t positions = 0, indices = 0, points = 0, triangles = 0, shared = 0, total = 0;
};

Result packScratch(const void* blob, size_t blob_size, const void* lod0_stream, size_t lod0_size, ValenceInfo* v,
                   PfrepFormat4Info* f, PackScratch* p) {
    if (!blob || !lod0_stream) return Result::InvalidArgument;
    Result r = pfrepFormat4Info(blob, blob_size, f);
    if (r != Result::Ok) return r;
    if (valenceReadInfo(static_cast<const uint8_t*>(lod0_stream), lod0_size, v) != Result::Ok)
        return Result::BadStructure;
    // The blob's LOD0 is the stream's, welded: it cannot have more points or triangles.
    if (f->point_count > v->vertex_count || f->level0_triangles > v->triangle_count) return Result::BadStructure;
    const uint64_t vc = v->vertex_count, tc = v->triangle_count;
    p->positions = align8(vc * 12);
    p->indices = align8(tc * 12);
    p->points = align8(vc * 12);
    p->triangles = align8(tc * 12);
    uint64_t shared = valenceScratchSize(*v);
    const uint64_t number = pfrepNumberLod0ScratchBytes(v->vertex_count);
    shared = shared > number ? shared : number;
    shared = shared > f->scratch_bytes ? shared : f->scratch_bytes;
    p->shared = align8(shared);
    p->total = p->positions + p->indices + p->points + p->triangles + p->shared;
    if (p->total > SIZE_MAX) return Result::BadStructure;
    return Result::Ok;
}

} // namespace

Result pfrepPackFormat4Info(const void* blob, size_t blob_size, const void* lod0_stream, size_t lod0_size,
                            PfrepPackFormat4Info* info) {
    if (!info) return Result::InvalidArgument;
    ValenceInfo v;
    PfrepFormat4Info f;
    PackScratch p;
    const Result r = packScratch(blob, blob_size, lod0_stream, lod0_size, &v, &f, &p);
    if (r != Result::Ok) return r;
    info->decoded_bytes = f.decoded_bytes;
    info->scratch_bytes = size_t(p.total);
    return Result::Ok;
}

Result pfrepDecodePackFormat4(const void* blob, size_t blob_size, const void* lod0_stream, size_t lod0_size, void* out,
                              size_t out_capacity, void* scratch, size_t scratch_bytes, PfrepModel* model) {
    if (!out || !scratch || !model || (reinterpret_cast<uintptr_t>(scratch) & 7) != 0) return Result::InvalidArgument;
    ValenceInfo v;
    PfrepFormat4Info f;
    PackScratch p;
    Result r = packScratch(blob, blob_size, lod0_stream, lod0_size, &v, &f, &p);
    if (r != Result::Ok) return r;
    if (scratch_bytes < p.total || out_capacity < f.decoded_bytes) return Result::BufferTooSmall;
    uint8_t* at = static_cast<uint8_t*>(scratch);
    float* positions = reinterpret_cast<float*>(at);
    uint32_t* indices = reinterpret_cast<uint32_t*>(at + p.positions);
    float* points = reinterpret_cast<float*>(at + p.positions + p.indices);
    uint32_t* triangles = reinterpret_cast<uint32_t*>(at + p.positions + p.indices + p.points);
    uint8_t* shared = at + p.positions + p.indices + p.points + p.triangles;
    ValenceOutput o;
    o.indices = indices;
    o.index_capacity = size_t(v.triangle_count) * 3;
    o.positions = positions;
    o.position_capacity = size_t(v.vertex_count) * 3;
    o.scratch = shared;
    o.scratch_size = size_t(p.shared);
    if (valenceDecode(static_cast<const uint8_t*>(lod0_stream), lod0_size, o) != Result::Ok)
        return Result::BadStructure;
    const void* split = nullptr;
    size_t split_bytes = 0;
    r = pfrepFormat4SplitList(blob, blob_size, &split, &split_bytes);
    if (r != Result::Ok) return r;
    PfrepLod0 lod0;
    r = numberLod0(static_cast<const uint8_t*>(split), split_bytes, positions, v.vertex_count, indices,
                   v.triangle_count, points, size_t(v.vertex_count) * 3, triangles, size_t(v.triangle_count) * 3,
                   shared, size_t(p.shared), &lod0);
    if (r == Result::CorruptStream || r == Result::Truncated) return r; // the split list
    if (r != Result::Ok) return Result::BadStructure;
    return pfrepDecodeFormat4(blob, blob_size, lod0, out, out_capacity, shared, size_t(p.shared), model);
}

} // namespace lodrt
