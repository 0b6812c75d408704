// PFRep format 3 decoder (docs/format/pfrep.md, "Format 3"): a range-coded pass in rank order (entries
// and criterion codes) and one in decreasing rank (positions) rebuild the format 2 blob it was made from, byte for byte, in caller memory; openPfrep then
// validates that blob as it validates any other, so extraction and refinement run on the same bytes
// and give the same results as on the format 2 blob.
#include <cstdint>
#include <cstring>

#include "lodrt/detail/pfrep_codec.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"
#include "little_endian.h"
#include "range_decoder.h"

namespace lodrt {
namespace {

using detail::kNone;

using detail::loadU32;
void store32(uint8_t* p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = uint8_t(v >> (8 * k));
}

struct DecodeCoder {
    static constexpr bool kEncoding = false;
    detail::RangeDecoder rd;
    bool bad = false;
    uint32_t bit(uint32_t& prob, uint32_t) { return rd.bit(prob); }
    uint32_t tree(uint32_t* probs, uint32_t bits, uint32_t) { return rd.tree(probs, bits); }
    uint64_t uint(detail::PfrepUintModel& model, uint64_t) {
        uint64_t v = 0;
        if (!rd.uint(model.klass, model.top, &v)) bad = true;
        return bad ? 0 : v;
    }
    bool failed() const { return bad || rd.overrun(); }
};

struct Header {
    uint32_t vertex_count, removed_count, block_shift, expanded_size, total_slots, block_count;
};

Result readHeader(const uint8_t* p, size_t size, Header& h) {
    if (size < format::kPfrepHeaderSize) return Result::Truncated;
    if (loadU32(p) != format::kPfrepMagic) return Result::BadMagic;
    if (loadU32(p + 4) != format::kPfrepVersionCompressed) return Result::UnsupportedVersion;
    h.vertex_count = loadU32(p + 8);
    h.removed_count = loadU32(p + 12);
    h.block_shift = loadU32(p + 16);
    h.expanded_size = loadU32(p + 52);
    h.total_slots = loadU32(p + 56);
    if (h.vertex_count > format::kPfrepMaxVertices || h.removed_count > h.vertex_count ||
        h.block_shift > format::kPfrepMaxBlockShift || loadU32(p + 60) != 0)
        return Result::BadStructure;
    h.block_count = uint32_t((uint64_t(h.vertex_count) + (uint64_t(1) << h.block_shift) - 1) >> h.block_shift);
    if (h.expanded_size < format::kPfrepHeaderSize + uint64_t(h.block_count) * 4) return Result::BadStructure;
    return Result::Ok;
}

// Scratch layout, in uint32 values (the codec models first, then the state's arrays).
struct Layout {
    uint64_t models, mention_count, mentions, candidate_stamp, candidate_index, mention_stamp, fan_stamp, fan_begin, fans, candidates, mentioners, neighbours, dependencies, groups, block_offset, cursor, total;
};

Layout layout(const Header& h) {
    Layout l;
    // 64-bit arithmetic: the sizes must not wrap where size_t is 32 bits (checked by fitsSizeT).
    uint64_t at = 0;
    auto take = [&](uint64_t values) {
        const uint64_t start = at;
        at += (values + 1) & ~uint64_t(1); // 8-byte steps
        return start;
    };
    const uint64_t v = h.vertex_count, t = h.total_slots;
    l.models = take((sizeof(detail::PfrepCodecModels) + 3) / 4);
    l.mention_count = take(v);
    l.mentions = take(v * format::kPfrepMentionSlots);
    l.candidate_stamp = take(v);
    l.candidate_index = take(v);
    l.mention_stamp = take(v);
    l.fan_stamp = take(v);
    l.fan_begin = take(v + 1);
    l.fans = take(t);
    l.candidates = take(format::kPfrepCandidateLimit);
    l.mentioners = take(format::kPfrepMentionSlots);
    l.neighbours = take(detail::kPfrepMaxFan);
    l.dependencies = take(detail::kPfrepMaxDependencies);
    l.groups = take(detail::kPfrepMaxFan);
    l.block_offset = take(h.block_count);
    l.cursor = take(h.block_count);
    l.total = at;
    return l;
}

uint32_t blockVertices(const Header& h, uint32_t b) {
    const uint32_t first = b << h.block_shift;
    return uint32_t(std::min<uint64_t>(uint64_t(first) + (uint64_t(1) << h.block_shift), h.vertex_count) - first);
}

// The block sizes (coded first), the format 2 header and directory; cursor[b] is where block b's
// entry stream starts.
Result decodeDirectory(DecodeCoder& c, detail::PfrepCodecModels& models, const uint8_t* in, const Header& h,
                       uint8_t* out, uint32_t* block_offset, uint32_t* cursor) {
    const uint32_t record_bytes = format::kPfrepVertexRecordSize + 2;
    uint64_t at = format::kPfrepHeaderSize + uint64_t(h.block_count) * 4;
    for (uint32_t b = 0; b < h.block_count; ++b) {
        cursor[b] = uint32_t(c.uint(models.block_bytes, 0)); // entry bytes of block b, for now
        if (c.failed()) return Result::CorruptStream;
    }
    for (uint32_t b = h.block_count; b-- > 0;) {
        block_offset[b] = uint32_t(at);
        const uint64_t stream = at + uint64_t(blockVertices(h, b)) * record_bytes;
        at = stream + cursor[b] + format::kPfrepStreamPadding;
        if (at > h.expanded_size) return Result::CorruptStream;
        cursor[b] = uint32_t(stream);
    }
    if (at != h.expanded_size) return Result::CorruptStream;
    std::memcpy(out, in, format::kPfrepHeaderSize);
    store32(out + 4, format::kPfrepVersion);
    store32(out + 52, h.expanded_size);
    store32(out + 56, h.block_count);
    for (uint32_t b = 0; b < h.block_count; ++b) store32(out + format::kPfrepHeaderSize + size_t(b) * 4, block_offset[b]);
    return Result::Ok;
}

// Every vertex in rank order: its entry and record decoded, then written where format 2 has them.
Result decodeVertices(DecodeCoder& c, detail::PfrepCodecModels& models, detail::PfrepCodecState& s,
                      detail::PfrepEntry& e, const Header& h, uint8_t* out, uint32_t* cursor) {
    for (uint32_t i = 0; i < h.vertex_count; ++i) {
        if (!detail::pfrepCodeVertex(c, models, s, i, e)) return Result::CorruptStream;
        const uint32_t b = i >> h.block_shift, first = b << h.block_shift, count = blockVertices(h, b);
        uint8_t* records = out + s.block_offset[b];
        std::memset(e.record, 0, 6); // the position comes in the second pass
        std::memcpy(records + size_t(i - first) * format::kPfrepVertexRecordSize, e.record,
                    format::kPfrepVertexRecordSize);
        const uint64_t stream = s.block_offset[b] + uint64_t(count) * (format::kPfrepVertexRecordSize + 2);
        const uint64_t stream_end = (b == 0 ? uint64_t(h.expanded_size) : uint64_t(s.block_offset[b - 1])) -
                                    format::kPfrepStreamPadding;
        const size_t bytes = detail::pfrepEntryBytes(e, i);
        const uint64_t rel = cursor[b] - stream;
        if (cursor[b] + uint64_t(bytes) > stream_end || rel > 0xFFFFu) return Result::CorruptStream;
        detail::pfrepStore16(records + size_t(count) * format::kPfrepVertexRecordSize + size_t(i - first) * 2,
                             uint32_t(rel));
        detail::pfrepWriteEntry(e, i, out + cursor[b]);
        cursor[b] += uint32_t(bytes);
    }
    for (uint32_t b = 0; b < h.block_count; ++b) {
        const uint64_t stream_end = (b == 0 ? uint64_t(h.expanded_size) : uint64_t(s.block_offset[b - 1])) -
                                    format::kPfrepStreamPadding;
        if (cursor[b] != stream_end) return Result::CorruptStream;
    }
    if (s.used_slots != s.total_slots) return Result::CorruptStream;
    for (uint32_t i = h.vertex_count; i-- > 0;)
        if (!detail::pfrepCodePosition(c, models, s, i, out + (s.record(i) - out))) return Result::CorruptStream;
    return Result::Ok;
}

} // namespace

Result pfrepCompressedInfo(const void* data, size_t size, PfrepCompressedInfo* info) {
    if (!data || !info) return Result::InvalidArgument;
    Header h;
    const Result r = readHeader(static_cast<const uint8_t*>(data), size, h);
    if (r != Result::Ok) return r;
    info->vertex_count = h.vertex_count;
    info->decoded_bytes = h.expanded_size;
    const Layout l = layout(h);
    if (l.total > SIZE_MAX / 4) return Result::BadStructure; // more than this platform can address
    info->scratch_bytes = size_t(l.total * 4);
    return Result::Ok;
}

Result pfrepDecompress(const void* data, size_t size, void* out, size_t out_capacity, void* scratch,
                       size_t scratch_bytes, PfrepModel* model) {
    if (!data || !out || !scratch || !model) return Result::InvalidArgument;
    const uint8_t* in = static_cast<const uint8_t*>(data);
    Header h;
    Result r = readHeader(in, size, h);
    if (r != Result::Ok) return r;
    const Layout l = layout(h);
    if (l.total > SIZE_MAX / 4) return Result::BadStructure;
    if (out_capacity < h.expanded_size || scratch_bytes < l.total * 4) return Result::BufferTooSmall;
    if ((reinterpret_cast<uintptr_t>(scratch) & 7) != 0) return Result::InvalidArgument;
    if (size < format::kPfrepHeaderSize + 5) return Result::Truncated; // the range coder's first bytes
    uint32_t* w = static_cast<uint32_t*>(scratch);
    uint8_t* o = static_cast<uint8_t*>(out);
    std::memset(o, 0, h.expanded_size);
    DecodeCoder c;
    if (!c.rd.init(in + format::kPfrepHeaderSize, size - format::kPfrepHeaderSize)) return Result::CorruptStream;
    detail::PfrepCodecModels& models = *reinterpret_cast<detail::PfrepCodecModels*>(w + l.models);
    models.init();
    r = decodeDirectory(c, models, in, h, o, w + l.block_offset, w + l.cursor);
    if (r != Result::Ok) return r;
    detail::PfrepCodecState s;
    s.vertex_count = h.vertex_count;
    s.removed_count = h.removed_count;
    s.block_shift = h.block_shift;
    s.block_offset = w + l.block_offset;
    s.blob = o;
    s.mention_count = w + l.mention_count;
    s.mentions = w + l.mentions;
    s.candidate_stamp = w + l.candidate_stamp;
    s.candidate_index = w + l.candidate_index;
    s.mention_stamp = w + l.mention_stamp;
    s.fan_stamp = w + l.fan_stamp;
    s.fan_begin = w + l.fan_begin;
    s.fans = w + l.fans;
    s.candidates = w + l.candidates;
    s.mentioners = w + l.mentioners;
    s.total_slots = h.total_slots;
    float step[3];
    for (int a = 0; a < 3; ++a) {
        const uint32_t bits = loadU32(in + 36 + 4 * a);
        std::memcpy(&step[a], &bits, 4);
    }
    detail::pfrepAxisWeights(step, s.axis_weight);
    std::fill(s.mention_count, s.mention_count + h.vertex_count, 0u);
    std::fill(s.candidate_stamp, s.candidate_stamp + h.vertex_count, 0u);
    std::fill(s.mention_stamp, s.mention_stamp + h.vertex_count, 0u);
    std::fill(s.fan_stamp, s.fan_stamp + h.vertex_count, 0u);
    s.fan_begin[0] = 0;
    detail::PfrepEntry e;
    e.neighbours = w + l.neighbours;
    e.dependencies = w + l.dependencies;
    e.groups = w + l.groups;
    r = decodeVertices(c, models, s, e, h, o, w + l.cursor);
    if (r != Result::Ok) return r;
    if (c.rd.overrun()) return Result::Truncated;
    if (!c.rd.finishedExactly()) return Result::CorruptStream;
    return openPfrep(o, h.expanded_size, model);
}

} // namespace lodrt
