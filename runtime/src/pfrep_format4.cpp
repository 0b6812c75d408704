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
    if (!std::isfinite(h.error_unit) || h.error_unit < 0 || loadU32(p + 60) != 0) return Result::BadStructure;
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

} // namespace

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
    if (size < format::kPfrepHeaderSize + 5) return Result::Truncated; // the range coder's first bytes
    s.lod0.positions = lod0.positions;
    s.lod0.triangles = lod0.triangles;
    s.lod0.point_count = lod0.point_count;
    s.lod0.triangle_count = lod0.triangle_count;
    detail::Pfrep4Models* models = detail::pfrep4Carve(s, static_cast<uint32_t*>(scratch));
    models->init();
    uint8_t* o = static_cast<uint8_t*>(out);
    std::memset(o, 0, s.h.decoded_size);
    DecodeCoder c;
    if (!c.rd.init(in + format::kPfrepHeaderSize, size - format::kPfrepHeaderSize)) return Result::CorruptStream;
    if (!detail::pfrep4LoadLod0(s)) return Result::BadStructure;
    if (!detail::pfrep4CodeRemovals(c, *models, s, nullptr, nullptr) || !detail::pfrep4BuildSlots(s) ||
        !detail::pfrep4Layout(s) || s.layout_size != s.h.decoded_size ||
        !detail::pfrep4CodeRecords(c, *models, s, nullptr, o))
        return c.rd.overrun() ? Result::Truncated : Result::CorruptStream;
    detail::pfrep4WriteBlob(s, o);
    if (c.rd.overrun()) return Result::Truncated;
    if (!c.rd.finishedExactly()) return Result::CorruptStream;
    return openPfrep(o, s.h.decoded_size, model);
}

} // namespace lodrt
