// PFRep format 3 encoder: reads a validated format 2 blob entry by entry and codes every vertex in
// rank order with the coding shared with lodrt's decoder (lodrt/detail/pfrep_codec.h).
#include "lodbake/pfrep/pfrep_compress.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <memory>
#include <string>

#include "codec/range_encoder.h"
#include "lodrt/detail/pfrep_codec.h"
#include "lodrt/detail/pfrep_codec4.h"
#include "lodrt/format.h"
#include "lodrt/pfrep.h"

namespace lodbake {
namespace {

namespace fmt = lodrt::format;
using lodrt::detail::PfrepEntry;

uint32_t load32(const uint8_t* p) {
    return uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) | (uint32_t(p[3]) << 24);
}
void store32(uint8_t* p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = uint8_t(v >> (8 * k));
}

struct EncodeCoder {
    static constexpr bool kEncoding = true;
    codec::RangeEncoder enc;
    uint32_t bit(uint32_t& prob, uint32_t b) {
        enc.bit(prob, b);
        return b;
    }
    uint32_t tree(uint32_t* probs, uint32_t bits, uint32_t v) {
        enc.tree(probs, bits, v);
        return v;
    }
    uint64_t uint(lodrt::detail::PfrepUintModel& model, uint64_t v) {
        enc.uint(model.klass, model.top, v);
        return v;
    }
    uint32_t direct(uint32_t v, uint32_t count) {
        enc.direct(v, count);
        return v;
    }
    bool failed() const { return false; }
};

// Bits of a format 2 entry, least significant first (the blob is validated: reads stay inside).
struct BitCursor {
    const uint8_t* data;
    uint64_t at;
    uint32_t read(uint32_t bits) {
        uint32_t v = 0;
        for (uint32_t b = 0; b < bits; ++b, ++at) v |= uint32_t((data[at >> 3] >> (at & 7)) & 1) << b;
        return v;
    }
    uint32_t count(uint32_t bits) {
        const uint32_t v = read(bits);
        return v == (1u << bits) - 1 ? v + read(fmt::kPfrepCountEscapeBits) : v;
    }
};

// Entry i of the blob, unpacked into e (whose arrays have the detail::kPfrepMax* capacities);
// false when a slot is in two groups.
bool parseEntry(const uint8_t* entry, uint32_t i, PfrepEntry& e) {
    BitCursor r{entry, 0};
    e.n = r.count(fmt::kPfrepCountBits);
    e.m = r.count(fmt::kPfrepDependencyCountBits);
    e.has_original = r.read(1);
    const uint32_t wa = r.read(fmt::kPfrepWidthBits);
    const uint32_t wd = e.m > 0 ? r.read(fmt::kPfrepWidthBits) : 0;
    for (uint32_t k = 0; k < e.n; ++k) e.neighbours[k] = i + 1 + r.read(wa);
    std::fill(e.groups, e.groups + e.n, 0u);
    auto readMask = [&](uint32_t group) {
        for (uint32_t k = 0; k < e.n; ++k) {
            if (!r.read(1)) continue;
            if (e.groups[k] != 0) return false;
            e.groups[k] = group;
        }
        return true;
    };
    if (e.has_original && !readMask(1)) return false;
    for (uint32_t k = 0; k < e.m; ++k) {
        e.dependencies[k] = i - 1 - r.read(wd);
        if (!readMask(2 + k)) return false;
    }
    return true;
}

struct Arrays {
    std::vector<uint32_t> mention_count, mentions, candidate_stamp, candidate_index, mention_stamp, fan_stamp, fan_begin, fans, candidates, mentioners, block_offset, neighbours, dependencies, groups;
};

} // namespace

Result<std::vector<uint8_t>> compressPfrep(const std::vector<uint8_t>& blob) {
    lodrt::PfrepModel model;
    const lodrt::Result opened = lodrt::openPfrep(blob.data(), blob.size(), &model);
    if (opened != lodrt::Result::Ok)
        return invalidInput(std::string("pfrep: format 2 blob: ") + lodrt::resultName(opened));
    const uint32_t vertex_count = model.vertex_count, shift = model.block_shift, blocks = model.block_count;
    Arrays a;
    a.block_offset.resize(blocks);
    for (uint32_t b = 0; b < blocks; ++b) a.block_offset[b] = load32(blob.data() + fmt::kPfrepHeaderSize + size_t(b) * 4);
    auto blockCount = [&](uint32_t b) {
        return uint32_t(std::min<uint64_t>(uint64_t(b + 1) << shift, vertex_count) - (uint64_t(b) << shift));
    };
    auto blockEnd = [&](uint32_t b) { return b == 0 ? uint32_t(blob.size()) : a.block_offset[b - 1]; };
    auto streamStart = [&](uint32_t b) {
        return a.block_offset[b] + blockCount(b) * (fmt::kPfrepVertexRecordSize + 2);
    };
    // Total slots (the sum of every n), from the entries' counts.
    uint64_t total_slots = 0;
    for (uint32_t i = 0; i < vertex_count; ++i) {
        const uint32_t b = i >> shift, first = b << shift;
        const uint8_t* rel = blob.data() + a.block_offset[b] + size_t(blockCount(b)) * fmt::kPfrepVertexRecordSize;
        BitCursor r{blob.data() + streamStart(b) + lodrt::detail::pfrepLoad16(rel + 2 * (i - first)), 0};
        total_slots += r.count(fmt::kPfrepCountBits);
    }
    if (total_slots > 0xFFFFFFFFu) return resourceLimit("pfrep: too many fan slots for format 3");
    a.mention_count.assign(vertex_count, 0);
    a.mentions.assign(size_t(vertex_count) * fmt::kPfrepMentionSlots, 0);
    a.candidate_stamp.assign(vertex_count, 0);
    a.candidate_index.assign(vertex_count, 0);
    a.mention_stamp.assign(vertex_count, 0);
    a.fan_stamp.assign(vertex_count, 0);
    a.fan_begin.assign(size_t(vertex_count) + 1, 0);
    a.fans.resize(total_slots);
    a.candidates.resize(fmt::kPfrepCandidateLimit);
    a.mentioners.resize(fmt::kPfrepMentionSlots);
    a.neighbours.resize(lodrt::detail::kPfrepMaxFan);
    a.dependencies.resize(lodrt::detail::kPfrepMaxDependencies);
    a.groups.resize(lodrt::detail::kPfrepMaxFan);
    lodrt::detail::PfrepCodecState s;
    s.vertex_count = vertex_count;
    s.removed_count = model.removed_count;
    s.block_shift = shift;
    s.block_offset = a.block_offset.data();
    s.blob = blob.data();
    s.mention_count = a.mention_count.data();
    s.mentions = a.mentions.data();
    s.candidate_stamp = a.candidate_stamp.data();
    s.candidate_index = a.candidate_index.data();
    s.mention_stamp = a.mention_stamp.data();
    s.fan_stamp = a.fan_stamp.data();
    s.fan_begin = a.fan_begin.data();
    s.fans = a.fans.data();
    s.candidates = a.candidates.data();
    s.mentioners = a.mentioners.data();
    s.total_slots = uint32_t(total_slots);
    lodrt::detail::pfrepAxisWeights(model.position_step, s.axis_weight);
    auto models = std::make_unique<lodrt::detail::PfrepCodecModels>();
    models->init();
    EncodeCoder c;
    for (uint32_t b = 0; b < blocks; ++b) c.uint(models->block_bytes, blockEnd(b) - fmt::kPfrepStreamPadding - streamStart(b));
    PfrepEntry e;
    e.neighbours = a.neighbours.data();
    e.dependencies = a.dependencies.data();
    e.groups = a.groups.data();
    std::vector<uint8_t> rewritten;
    for (uint32_t i = 0; i < vertex_count; ++i) {
        const uint32_t b = i >> shift, first = b << shift, count = blockCount(b);
        const uint8_t* records = blob.data() + a.block_offset[b];
        const uint8_t* rel = records + size_t(count) * fmt::kPfrepVertexRecordSize;
        const uint32_t start = streamStart(b) + lodrt::detail::pfrepLoad16(rel + 2 * (i - first));
        const uint32_t end = i + 1 < first + count ? streamStart(b) + lodrt::detail::pfrepLoad16(rel + 2 * (i + 1 - first))
                                                   : blockEnd(b) - fmt::kPfrepStreamPadding;
        if (!parseEntry(blob.data() + start, i, e))
            return invalidInput("pfrep: entry " + std::to_string(i) + ": a slot in two groups (not format 3 codable)");
        const size_t bytes = lodrt::detail::pfrepEntryBytes(e, i);
        rewritten.assign(bytes, 0);
        lodrt::detail::pfrepWriteEntry(e, i, rewritten.data());
        if (bytes != end - start || std::memcmp(rewritten.data(), blob.data() + start, bytes) != 0)
            return invalidInput("pfrep: entry " + std::to_string(i) + ": not written canonically (not format 3 codable)");
        std::memcpy(e.record, records + size_t(i - first) * fmt::kPfrepVertexRecordSize, fmt::kPfrepVertexRecordSize);
        if (!lodrt::detail::pfrepCodeVertex(c, *models, s, i, e))
            return invalidInput("pfrep: entry " + std::to_string(i) + ": not format 3 codable");
    }
    for (uint32_t i = vertex_count; i-- > 0;) {
        uint8_t record[fmt::kPfrepVertexRecordSize];
        std::memcpy(record, s.record(i), sizeof(record));
        if (!lodrt::detail::pfrepCodePosition(c, *models, s, i, record))
            return invalidInput("pfrep: vertex " + std::to_string(i) + ": position or cone not format 3 codable");
    }
    std::vector<uint8_t> out(blob.begin(), blob.begin() + fmt::kPfrepHeaderSize);
    store32(out.data() + 4, fmt::kPfrepVersionCompressed);
    store32(out.data() + 52, uint32_t(blob.size()));
    store32(out.data() + 56, uint32_t(total_slots));
    const std::vector<uint8_t> coded = c.enc.finish();
    out.insert(out.end(), coded.begin(), coded.end());
    // Decode it again: what leaves here rebuilds `blob` exactly.
    lodrt::PfrepCompressedInfo info;
    if (lodrt::pfrepCompressedInfo(out.data(), out.size(), &info) != lodrt::Result::Ok)
        return internalError("pfrep: format 3 header does not read back");
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> scratch((info.scratch_bytes + 7) / 8);
    lodrt::PfrepModel check;
    const lodrt::Result r =
        lodrt::pfrepDecompress(out.data(), out.size(), decoded.data(), decoded.size(), scratch.data(), scratch.size() * 8, &check);
    if (r != lodrt::Result::Ok || decoded != blob)
        return internalError(std::string("pfrep: format 3 does not decode to its blob: ") + lodrt::resultName(r));
    return out;
}

namespace {

// A validated format 2 blob's entries and records by rank.
struct BlobView {
    const std::vector<uint8_t>& blob;
    const lodrt::PfrepModel& model;
    uint32_t blockOffset(uint32_t b) const { return load32(blob.data() + fmt::kPfrepHeaderSize + size_t(b) * 4); }
    uint32_t blockCount(uint32_t b) const {
        return uint32_t(std::min<uint64_t>(uint64_t(b + 1) << model.block_shift, model.vertex_count) -
                        (uint64_t(b) << model.block_shift));
    }
    const uint8_t* record(uint32_t i) const {
        const uint32_t b = i >> model.block_shift;
        return blob.data() + blockOffset(b) + size_t(i - (b << model.block_shift)) * fmt::kPfrepVertexRecordSize;
    }
    const uint8_t* entry(uint32_t i) const {
        const uint32_t b = i >> model.block_shift, count = blockCount(b);
        const uint8_t* rel = blob.data() + blockOffset(b) + size_t(count) * fmt::kPfrepVertexRecordSize;
        return rel + size_t(count) * 2 + lodrt::detail::pfrepLoad16(rel + 2 * (i - (b << model.block_shift)));
    }
};

// Entry i's triangles as (a, b, dependency) triples, sorted: what levels and refinement read of it.
bool entryTriangles(const BlobView& view, uint32_t i, PfrepEntry& e, std::vector<std::array<uint32_t, 3>>& out) {
    if (!parseEntry(view.entry(i), i, e)) return false;
    out.clear();
    for (uint32_t k = 0; k < e.n; ++k)
        if (e.groups[k] != 0)
            out.push_back({e.neighbours[k], e.neighbours[(k + 1) % e.n],
                           e.groups[k] == 1 ? lodrt::detail::kNone : e.dependencies[e.groups[k] - 2]});
    std::sort(out.begin(), out.end());
    return true;
}

// The decoded format 4 blob against the builder's: same counts, records, and entry triangles.
Status compareTables(const std::vector<uint8_t>& built, const lodrt::PfrepModel& built_model,
                     const std::vector<uint8_t>& decoded, const lodrt::PfrepModel& decoded_model) {
    if (built_model.vertex_count != decoded_model.vertex_count ||
        built_model.removed_count != decoded_model.removed_count ||
        built_model.level0_triangles != decoded_model.level0_triangles)
        return internalError("pfrep: format 4 decodes to other counts");
    const BlobView a{built, built_model}, b{decoded, decoded_model};
    std::vector<uint32_t> na(lodrt::detail::kPfrepMaxFan), da(lodrt::detail::kPfrepMaxDependencies),
        ga(lodrt::detail::kPfrepMaxFan), nb(na.size()), db(da.size()), gb(ga.size());
    PfrepEntry ea, eb;
    ea.neighbours = na.data();
    ea.dependencies = da.data();
    ea.groups = ga.data();
    eb.neighbours = nb.data();
    eb.dependencies = db.data();
    eb.groups = gb.data();
    std::vector<std::array<uint32_t, 3>> ta, tb;
    for (uint32_t i = 0; i < built_model.vertex_count; ++i) {
        if (std::memcmp(a.record(i), b.record(i), fmt::kPfrepVertexRecordSize) != 0)
            return internalError("pfrep: format 4 decodes vertex " + std::to_string(i) + " to another record");
        if (!entryTriangles(a, i, ea, ta) || !entryTriangles(b, i, eb, tb) || ta != tb)
            return internalError("pfrep: format 4 decodes entry " + std::to_string(i) + " to other triangles");
    }
    return Status::okStatus();
}

// The build's ranks in LOD0's numbering: point_of maps the build's points (null: the same numbering).
Result<std::vector<uint32_t>> renumberRanks(const std::vector<uint32_t>& ranks, const std::vector<uint32_t>* point_of,
                                            size_t point_count) {
    if (!point_of) return ranks;
    std::vector<uint32_t> out(ranks.size());
    for (size_t i = 0; i < ranks.size(); ++i) {
        if (ranks[i] >= point_of->size() || (*point_of)[ranks[i]] >= point_count)
            return invalidInput("pfrep: format 4: a point of the build has no point in LOD0");
        out[i] = (*point_of)[ranks[i]];
    }
    return out;
}

Result<std::vector<uint8_t>> codeFormat4(const PfrepBuild& build, const std::vector<Vec3f>& points,
                                         const std::vector<uint32_t>& triangles, const std::vector<uint32_t>* point_of,
                                         const std::vector<uint8_t>& split_list) {
    namespace d = lodrt::detail;
    lodrt::PfrepModel model;
    const lodrt::Result opened = lodrt::openPfrep(build.blob.data(), build.blob.size(), &model);
    if (opened != lodrt::Result::Ok)
        return invalidInput(std::string("pfrep: format 2 blob: ") + lodrt::resultName(opened));
    if (triangles.size() % 3 != 0 || points.size() >= fmt::kPfrepMaxVertices || triangles.size() / 3 > 0xFFFFFFFFu ||
        build.rank_point.size() != model.vertex_count || build.rank_kept.size() != model.removed_count ||
        build.stored_triangles > 0xFFFFFFFFu || (!split_list.empty() && (!point_of || split_list.size() < 5)) ||
        split_list.size() > 0xFFFFFFFFu)
        return invalidInput("pfrep: format 4: the build does not match its blob or LOD0");
    d::Pfrep4State s;
    s.h.vertex_count = model.vertex_count;
    s.h.removed_count = model.removed_count;
    s.h.point_count = uint32_t(points.size());
    s.h.level0_triangles = uint32_t(triangles.size() / 3);
    s.h.stored_triangles = uint32_t(build.stored_triangles);
    for (int a = 0; a < 3; ++a) {
        s.h.position_min[a] = model.position_min[a];
        s.h.position_step[a] = model.position_step[a];
    }
    s.h.error_unit = model.error_unit;
    // A pack's blob (LOD0 numbered on its decoded stream) also checks that LOD0 (docs/format/pfrep.md).
    s.h.flags = point_of ? lodrt::format::kPfrep4FlagCodedTail | lodrt::format::kPfrep4FlagLod0Check : 0;
    if (!split_list.empty()) s.h.flags |= lodrt::format::kPfrep4FlagSplitPoints;
    s.lod0.positions = points.empty() ? nullptr : &points[0].x;
    s.lod0.triangles = triangles.data();
    s.lod0.point_count = s.h.point_count;
    s.lod0.triangle_count = s.h.level0_triangles;
    std::vector<uint64_t> scratch((d::pfrep4ScratchValues(s.h) + 1) / 2);
    d::Pfrep4Models* models = d::pfrep4Carve(s, reinterpret_cast<uint32_t*>(scratch.data()));
    models->init();
    const BlobView view{build.blob, model};
    std::vector<uint8_t> records(size_t(model.vertex_count) * fmt::kPfrepVertexRecordSize);
    for (uint32_t i = 0; i < model.vertex_count; ++i)
        std::memcpy(&records[size_t(i) * fmt::kPfrepVertexRecordSize], view.record(i), fmt::kPfrepVertexRecordSize);
    LODBAKE_ASSIGN_OR_RETURN(const std::vector<uint32_t> rank_point,
                             renumberRanks(build.rank_point, point_of, points.size()));
    LODBAKE_ASSIGN_OR_RETURN(const std::vector<uint32_t> rank_kept,
                             renumberRanks(build.rank_kept, point_of, points.size()));
    EncodeCoder c;
    if (!d::pfrep4LoadLod0(s) || !d::pfrep4CodeLod0Check(c, s) ||
        !d::pfrep4CodeRemovals(c, *models, s, rank_point.data(), rank_kept.data()) ||
        !d::pfrep4CodeTail(c, s, rank_point.data()))
        return invalidInput("pfrep: format 4: the removal sequence does not replay on LOD0");
    if (!d::pfrep4BuildSlots(s) || !d::pfrep4Layout(s))
        return invalidInput("pfrep: format 4: the replayed table does not fit format 2");
    s.h.decoded_size = uint32_t(s.layout_size);
    std::vector<uint8_t> rebuilt(s.h.decoded_size, 0);
    if (!d::pfrep4CodeRecords(c, *models, s, records.data(), rebuilt.data()))
        return invalidInput("pfrep: format 4: a record is not codable");
    std::vector<uint8_t> out(fmt::kPfrepHeaderSize, 0);
    store32(out.data(), fmt::kPfrepMagic);
    store32(out.data() + 4, fmt::kPfrepVersionLod0);
    store32(out.data() + 8, s.h.vertex_count);
    store32(out.data() + 12, s.h.removed_count);
    store32(out.data() + 16, s.h.point_count);
    store32(out.data() + 20, s.h.level0_triangles);
    std::memcpy(out.data() + 24, build.blob.data() + 24, 28); // position_min, position_step, error_unit
    store32(out.data() + 52, s.h.decoded_size);
    store32(out.data() + 56, s.h.stored_triangles);
    store32(out.data() + 60, s.h.flags);
    if (!split_list.empty()) {
        uint8_t count[4];
        store32(count, uint32_t(split_list.size()));
        out.insert(out.end(), count, count + 4);
        out.insert(out.end(), split_list.begin(), split_list.end());
    }
    const std::vector<uint8_t> coded = c.enc.finish();
    out.insert(out.end(), coded.begin(), coded.end());
    // Decode it again and compare with the builder's table.
    lodrt::PfrepFormat4Info info;
    if (lodrt::pfrepFormat4Info(out.data(), out.size(), &info) != lodrt::Result::Ok)
        return internalError("pfrep: format 4 header does not read back");
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> decode_scratch((info.scratch_bytes + 7) / 8);
    lodrt::PfrepLod0 lod0;
    lod0.positions = s.lod0.positions;
    lod0.point_count = s.h.point_count;
    lod0.triangles = triangles.data();
    lod0.triangle_count = s.h.level0_triangles;
    lodrt::PfrepModel check;
    const lodrt::Result r = lodrt::pfrepDecodeFormat4(out.data(), out.size(), lod0, decoded.data(), decoded.size(),
                                                      decode_scratch.data(), info.scratch_bytes, &check);
    if (r != lodrt::Result::Ok)
        return internalError(std::string("pfrep: format 4 does not decode: ") + lodrt::resultName(r));
    LODBAKE_RETURN_IF_ERROR(compareTables(build.blob, model, decoded, check));
    return out;
}

} // namespace

Result<std::vector<uint8_t>> compressPfrepFormat4(const PfrepBuild& build, const std::vector<Vec3f>& points,
                                                  const std::vector<uint32_t>& triangles) {
    return codeFormat4(build, points, triangles, nullptr, {});
}

Result<std::vector<uint8_t>> compressPfrepFormat4(const PfrepBuild& build, const std::vector<Vec3f>& points,
                                                  const std::vector<uint32_t>& triangles,
                                                  const std::vector<uint32_t>& point_of,
                                                  const std::vector<uint8_t>& split_list) {
    return codeFormat4(build, points, triangles, &point_of, split_list);
}

std::vector<uint8_t> codePfrepSplitList(std::vector<uint32_t>& weld, const std::vector<uint32_t>& labels) {
    const uint32_t n = uint32_t(weld.size());
    std::vector<uint32_t> next(n), groups(n);
    lodrt::detail::Pfrep4SplitModels models;
    models.init();
    EncodeCoder c;
    lodrt::detail::pfrep4CodeSplits(c, models, n, weld.data(), labels.data(), next.data(), groups.data());
    return c.enc.finish();
}

} // namespace lodbake
