#pragma once
// PFRep format 3 (docs/format/pfrep.md, "Format 3"): the coding of one vertex's entry and record,
// written once as a template over the coder so the baker's encoder and lodrt's decoder cannot
// disagree. A coder passes each value through: `v = coder.bit(prob, v)` codes v when encoding and
// returns the decoded value (ignoring its argument) when decoding.
//
// Predictions use only what the decoder already has, vertices being coded in increasing rank:
// the entries of lower ranks (their fans A_d) and their records. A dependency d of vertex i is a
// lower-ranked vertex whose fan mentions i (its removal re-created triangles around i), so the
// dependencies are flags over the list of i's "mentioners"; i's neighbours were mostly neighbours of
// those same vertices, so they are indices into the mentioners' fans ("candidates"); the criterion
// codes grow along dependencies, so they are coded as differences from the dependencies' maximum.
//
// Also here: the canonical writer of a format 2 entry, which the decoder uses to rebuild the
// format 2 blob and the encoder to check that a blob is canonical (exactly reproducible).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"

namespace lodrt {
namespace detail {

constexpr uint32_t kPfrepMaxFan = 63 + 65535;       // longest A_i a format 2 entry can hold
constexpr uint32_t kPfrepMaxDependencies = 7 + 65535; // most dependency groups of one entry
constexpr uint32_t kPfrepSlotTriangle = 0x80000000u;  // PfrepCodecState::fans: the slot holds a triangle

struct PfrepUintModel {
    uint32_t klass[1u << format::kValenceClassTreeBits];
    uint32_t top[33];
    void init() {
        initRangeProbs(klass, sizeof(klass) / 4);
        initRangeProbs(top, sizeof(top) / 4);
    }
};

/// Every adaptive model of a format 3 stream (all start at 1/2).
struct PfrepCodecModels {
    PfrepUintModel block_bytes;
    PfrepUintModel fan_count[4];
    uint32_t is_dependency[8];
    PfrepUintModel extra_dependencies, extra_dependency_distance;
    uint32_t has_original[2];
    uint32_t in_candidates[3];
    PfrepUintModel candidate_step[2];
    PfrepUintModel neighbour_distance;
    uint32_t in_second[2];
    PfrepUintModel second_step;
    uint32_t group_same[3];
    PfrepUintModel group[2];
    PfrepUintModel position[3][10];
    PfrepUintModel radius[3];
    PfrepUintModel error[6];
    uint32_t cone_angle[17][16];
    PfrepUintModel cone_axis[2][2];
    void init() {
        block_bytes.init();
        for (auto& u : fan_count) u.init();
        initRangeProbs(is_dependency, 8);
        extra_dependencies.init();
        extra_dependency_distance.init();
        initRangeProbs(has_original, 2);
        initRangeProbs(in_candidates, 3);
        for (auto& u : candidate_step) u.init();
        neighbour_distance.init();
        initRangeProbs(in_second, 2);
        second_step.init();
        initRangeProbs(group_same, 3);
        for (auto& u : group) u.init();
        for (auto& a : position)
            for (auto& u : a) u.init();
        for (auto& u : radius) u.init();
        for (auto& u : error) u.init();
        initRangeProbs(&cone_angle[0][0], 17 * 16);
        for (auto& a : cone_axis)
            for (auto& u : a) u.init();
    }
};

/// One vertex of the table: its format 2 entry, unpacked, and its 10-byte record.
struct PfrepEntry {
    uint32_t n = 0;            // length of A_i
    uint32_t m = 0;            // dependency groups
    uint32_t has_original = 0; // 1 when some slot holds an input triangle
    uint32_t* neighbours = nullptr;   // A_i (capacity kPfrepMaxFan)
    uint32_t* dependencies = nullptr; // increasing (capacity kPfrepMaxDependencies)
    uint32_t* groups = nullptr;       // per slot: 0 none, 1 input triangle, 2 + k dependency k
    uint8_t record[format::kPfrepVertexRecordSize] = {};
};

/// What encoder and decoder keep while coding vertices in increasing rank (caller memory).
struct PfrepCodecState {
    uint32_t vertex_count = 0, removed_count = 0, block_shift = 0;
    const uint32_t* block_offset = nullptr; // per block: byte offset of its records in `blob`
    const uint8_t* blob = nullptr;          // the format 2 blob: records of ranks < i are read back
    uint32_t* mention_count = nullptr; // per vertex: entries that mentioned it so far
    uint32_t* mentions = nullptr;      // per vertex, kPfrepMentionSlots: the latest of those entries (a ring)
    uint32_t* candidate_stamp = nullptr; // per vertex: i + 1 while it is a candidate of vertex i
    uint32_t* candidate_index = nullptr; // per vertex: its index in `candidates`
    uint32_t* mention_stamp = nullptr;   // per vertex: i + 1 once entry i mentioned it
    uint32_t* fan_stamp = nullptr;       // per vertex: i + 1 once its fan was scanned whole for vertex i
    uint32_t* fan_begin = nullptr;       // per vertex + 1: where its A_i starts in `fans`
    uint32_t* fans = nullptr;            // every A_i, in rank order (total_slots values)
    uint32_t* candidates = nullptr;      // kPfrepCandidateLimit values
    uint32_t* mentioners = nullptr;      // kPfrepMentionSlots values
    uint32_t total_slots = 0, used_slots = 0;
    int64_t axis_weight[3] = {0, 0, 0}; // pfrepAxisWeights of the header's position_step

    const uint8_t* record(uint32_t v) const {
        const uint32_t b = v >> block_shift;
        return blob + block_offset[b] + size_t(v - (b << block_shift)) * format::kPfrepVertexRecordSize;
    }
};

inline uint32_t pfrepBitWidth(uint32_t v) {
    uint32_t w = 0;
    while (w < 32 && (v >> w) != 0) ++w;
    return w;
}

inline uint32_t pfrepLoad16(const uint8_t* p) { return uint32_t(p[0]) | (uint32_t(p[1]) << 8); }
inline void pfrepStore16(uint8_t* p, uint32_t v) {
    p[0] = uint8_t(v);
    p[1] = uint8_t(v >> 8);
}
inline uint64_t pfrepZigzag(int64_t v) { return v < 0 ? uint64_t(-v) * 2 - 1 : uint64_t(v) * 2; }
inline int64_t pfrepUnzigzag(uint64_t z) { return (z & 1) ? -int64_t((z + 1) / 2) : int64_t(z / 2); }

/// Codes a signed difference value - prediction of a field whose values lie in [0, limit]; false
/// when the decoded value falls outside.
template <class Coder>
bool pfrepCodeField(Coder& c, PfrepUintModel& model, uint32_t prediction, uint32_t limit, uint32_t* value) {
    const uint64_t z = c.uint(model, Coder::kEncoding ? pfrepZigzag(int64_t(*value) - int64_t(prediction)) : 0);
    const int64_t v = int64_t(prediction) + pfrepUnzigzag(z);
    if (c.failed() || v < 0 || v > int64_t(limit)) return false;
    *value = uint32_t(v);
    return true;
}

/// The latest vertices whose fans mention i (latest first) and, among them, i's dependencies.
template <class Coder>
bool pfrepCodeDependencies(Coder& c, PfrepCodecModels& models, PfrepCodecState& s, uint32_t i, PfrepEntry& e,
                           uint32_t* mentioner_count) {
    uint32_t mc = 0;
    // The latest kPfrepMentionSlots mentioners, latest first: one cache line per vertex.
    const uint32_t seen = s.mention_count[i];
    const uint32_t* ring = s.mentions + size_t(i) * format::kPfrepMentionSlots;
    for (; mc < seen && mc < format::kPfrepMentionSlots; ++mc)
        s.mentioners[mc] = ring[(seen - 1 - mc) % format::kPfrepMentionSlots];
    *mentioner_count = mc;
    auto isDependency = [&](uint32_t d) {
        return std::binary_search(e.dependencies, e.dependencies + e.m, d);
    };
    uint32_t found = 0;
    uint32_t* out = Coder::kEncoding ? nullptr : e.dependencies;
    for (uint32_t k = 0; k < mc; ++k) {
        const uint32_t d = s.mentioners[k];
        const uint32_t ctx = std::min(k, 3u) * 2 + (found > 0 ? 1u : 0u);
        const uint32_t flag = c.bit(models.is_dependency[ctx], Coder::kEncoding ? uint32_t(isDependency(d)) : 0u);
        if (flag) {
            if (out) out[found] = d;
            ++found;
        }
    }
    // Dependencies that are not mentioners (never in a blob the builder writes, but representable).
    uint32_t extra_count = 0;
    if (Coder::kEncoding) extra_count = e.m - found;
    extra_count = uint32_t(c.uint(models.extra_dependencies, extra_count));
    if (c.failed() || uint64_t(found) + extra_count > kPfrepMaxDependencies) return false;
    uint32_t k = 0;
    for (uint32_t x = 0; x < extra_count; ++x) {
        uint32_t d = 0;
        if (Coder::kEncoding) {
            while (std::find(s.mentioners, s.mentioners + mc, e.dependencies[k]) != s.mentioners + mc) ++k;
            d = e.dependencies[k++];
        }
        const uint64_t distance = c.uint(models.extra_dependency_distance, Coder::kEncoding ? i - 1 - d : 0);
        if (c.failed() || distance >= i) return false;
        if (out) out[found + x] = uint32_t(i - 1 - distance);
    }
    if (!Coder::kEncoding) {
        e.m = found + extra_count;
        std::sort(e.dependencies, e.dependencies + e.m);
        for (uint32_t x = 1; x < e.m; ++x)
            if (e.dependencies[x] == e.dependencies[x - 1]) return false;
    }
    return true;
}

/// Candidates for i's neighbours: the fans of its dependencies, then of its other mentioners, each
/// vertex once, only ranks above i, bounded in count and in values scanned.
struct PfrepCandidates {
    PfrepCodecState& s;
    uint32_t i;
    uint32_t count = 0, scanned = 0;
    uint32_t after_i = kNone; // index the candidate following the first i in a fan got (or would get)
    void addFan(uint32_t d) {
        if (count == format::kPfrepCandidateLimit || scanned == format::kPfrepCandidateScanLimit) return;
        const uint32_t begin = s.fan_begin[d], length = s.fan_begin[d + 1] - begin;
        const uint32_t stamp = i + 1;
        // A fan scanned whole before for this vertex adds nothing new (its vertices above i are
        // listed, i's place is known): it only counts towards the scan limit. Neighbours share
        // most of their mentioners, so most fans come again.
        if (s.fan_stamp[d] == stamp) {
            scanned = std::min<uint32_t>(format::kPfrepCandidateScanLimit, scanned + length);
            return;
        }
        // Locals: the stores below go through uint32_t pointers the compiler must otherwise assume
        // alias the counters and the state's arrays.
        const uint32_t* fan = s.fans + begin;
        uint32_t* candidate_stamp = s.candidate_stamp;
        uint32_t* candidate_index = s.candidate_index;
        uint32_t* candidates = s.candidates;
        uint32_t n = count, at = after_i;
        const uint32_t take = std::min<uint32_t>(length, format::kPfrepCandidateScanLimit - scanned);
        uint32_t t = 0;
        for (; t < take && n < format::kPfrepCandidateLimit; ++t) {
            const uint32_t v = fan[t] & ~kPfrepSlotTriangle;
            if (v == i && at == kNone) at = n;
            if (v <= i || candidate_stamp[v] == stamp) continue;
            candidate_stamp[v] = stamp;
            candidate_index[v] = n;
            candidates[n++] = v;
        }
        scanned += t;
        count = n;
        after_i = at;
        if (t == length) s.fan_stamp[d] = stamp;
    }
    // The fans of the latest entries that mention a (its neighbours when they were removed).
    void addMentionersOf(uint32_t a) {
        const uint32_t seen = s.mention_count[a];
        const uint32_t* ring = s.mentions + size_t(a) * format::kPfrepMentionSlots;
        for (uint32_t k = 0; k < seen && k < format::kPfrepMentionSlots; ++k)
            addFan(ring[(seen - 1 - k) % format::kPfrepMentionSlots]);
    }
};

template <class Coder>
bool pfrepCodeFan(Coder& c, PfrepCodecModels& models, PfrepCodecState& s, uint32_t i, PfrepEntry& e,
                  uint32_t mentioner_count) {
    PfrepCandidates cand{s, i};
    for (uint32_t pass = 0; pass < 2; ++pass)
        for (uint32_t k = 0; k < mentioner_count; ++k) {
            const uint32_t d = s.mentioners[k];
            if (std::binary_search(e.dependencies, e.dependencies + e.m, d) == (pass == 0)) cand.addFan(d);
        }
    // The first `primary` candidates come from i's mentioners; the rest ("second ring") from the
    // entries that mention the neighbours coded so far, added as each one is coded.
    const uint32_t primary = cand.count;
    uint32_t ctx_previous = 0;   // 0: first neighbour, 1: the previous was a candidate, 2: it was not
    // The candidate expected next: after a candidate, the one listed after it; at the start and after
    // a vertex that is not a candidate, the one listed after i in the first fan that holds i.
    const uint32_t restart = cand.after_i == kNone || cand.after_i >= primary ? 0 : cand.after_i;
    uint32_t predicted = restart;
    uint32_t second_from = primary; // where the latest second-ring fans start
    // The second ring is only looked at for a neighbour that is not a primary candidate, so the
    // fans of the neighbours coded so far are added then, in coding order (the list, its count and
    // second_from are what adding each right after it was coded gives); most neighbours are
    // primary candidates, and the fans of the last ones are never read.
    uint32_t pending = 0; // e.neighbours[pending, k) have not had their mentioners' fans added
    auto addPending = [&](uint32_t k) {
        for (; pending < k; ++pending) {
            second_from = cand.count < format::kPfrepCandidateLimit ? cand.count : primary;
            cand.addMentionersOf(e.neighbours[pending]);
            if (second_from >= cand.count) second_from = primary;
        }
    };
    for (uint32_t k = 0; k < e.n; ++k) {
        uint32_t a = Coder::kEncoding ? e.neighbours[k] : 0;
        // Primary candidates are listed before any second-ring one: the flag does not depend on
        // whether the pending fans were added.
        uint32_t in = 0;
        if (primary > 0)
            in = c.bit(models.in_candidates[ctx_previous],
                       Coder::kEncoding ? uint32_t(s.candidate_stamp[a] == i + 1 && s.candidate_index[a] < primary) : 0u);
        uint32_t in_second = 0;
        if (!in) addPending(k);
        if (!in && cand.count > primary)
            in_second = c.bit(models.in_second[ctx_previous == 0 ? 0 : 1],
                              Coder::kEncoding ? uint32_t(s.candidate_stamp[a] == i + 1) : 0u);
        if (in) {
            // The step forward from the expected candidate, cyclically.
            const uint32_t from = predicted % primary;
            const uint64_t step = c.uint(models.candidate_step[ctx_previous == 1 ? 1 : 0],
                                         Coder::kEncoding ? (s.candidate_index[a] + primary - from) % primary : 0);
            if (c.failed() || step >= primary) return false;
            const uint32_t index = uint32_t((from + step) % primary);
            a = s.candidates[index];
            predicted = index + 1;
            ctx_previous = 1;
        } else if (in_second) {
            const uint32_t count = cand.count - primary, from = second_from - primary;
            const uint64_t step = c.uint(models.second_step,
                                         Coder::kEncoding ? (s.candidate_index[a] - primary + count - from) % count : 0);
            if (c.failed() || step >= count) return false;
            a = s.candidates[primary + uint32_t((from + step) % count)];
            predicted = restart;
            ctx_previous = 2;
        } else {
            const uint64_t distance = c.uint(models.neighbour_distance, Coder::kEncoding ? a - i - 1 : 0);
            if (c.failed() || uint64_t(i) + 1 + distance >= s.vertex_count) return false;
            a = uint32_t(i + 1 + distance);
            predicted = restart;
            ctx_previous = 2;
        }
        e.neighbours[k] = a;
    }
    return true;
}

// The dependency group slot (a, b) is predicted to be in: the latest dependency d whose fan holds
// both a and b (d's removal with i kept re-creates d's triangle (d, a, b) as (i, a, b)); 0 when none
// does (or the entry is too large to look: more than 16 dependencies or a fan over 64).
inline uint32_t pfrepPredictGroup(const PfrepCodecState& s, const PfrepEntry& e, uint32_t a, uint32_t b) {
    if (e.m > 16) return 0;
    for (uint32_t k = e.m; k-- > 0;) {
        const uint32_t d = e.dependencies[k];
        const uint32_t begin = s.fan_begin[d], end = s.fan_begin[d + 1];
        if (end - begin > 64) continue;
        bool has_a = false, has_b = false;
        for (uint32_t t = begin; t < end; ++t) {
            const uint32_t v = s.fans[t] & ~kPfrepSlotTriangle;
            has_a |= v == a;
            has_b |= v == b;
        }
        if (has_a && has_b) return 2 + k;
    }
    return 0;
}

// Slot groups: per slot, "the expected group" (the predicted dependency, else the previous slot's
// group), else the group among the others.
template <class Coder>
bool pfrepCodeGroups(Coder& c, PfrepCodecModels& models, const PfrepCodecState& s, PfrepEntry& e) {
    const uint32_t groups = 1 + e.has_original + e.m;
    auto toCode = [&](uint32_t g) { return g <= 1 ? g : g - 1 + e.has_original; };
    auto fromCode = [&](uint32_t g) { return g == 0 ? 0u : e.has_original && g == 1 ? 1u : g + 1 - e.has_original; };
    uint32_t previous = 0;
    for (uint32_t k = 0; k < e.n; ++k) {
        uint32_t g = Coder::kEncoding ? toCode(e.groups[k]) : 0;
        if (groups > 1) {
            const uint32_t predicted = pfrepPredictGroup(s, e, e.neighbours[k], e.neighbours[(k + 1) % e.n]);
            const bool has_reference = k > 0 || predicted != 0;
            const uint32_t reference = predicted != 0 ? toCode(predicted) : previous;
            uint32_t same = 0;
            if (has_reference) {
                const uint32_t ctx = predicted != 0 ? 2u : previous == 0 ? 0u : 1u;
                same = c.bit(models.group_same[ctx], Coder::kEncoding ? uint32_t(g == reference) : 0u);
            }
            if (!same) {
                const uint32_t alternatives = has_reference ? groups - 1 : groups;
                const uint32_t coded = has_reference && g > reference ? g - 1 : g;
                const uint64_t v = c.uint(models.group[has_reference ? 1 : 0], Coder::kEncoding ? coded : 0);
                if (c.failed() || v >= alternatives) return false;
                g = has_reference && v >= reference ? uint32_t(v) + 1 : uint32_t(v);
            } else {
                g = reference;
            }
        }
        previous = g;
        e.groups[k] = fromCode(g);
    }
    return true;
}

// The record's criterion codes: radius and error predicted by the dependencies' maximum (they grow
// along dependencies), the cone angle in the context of theirs. Position and cone axis come in the
// second pass.
template <class Coder>
bool pfrepCodeCriterion(Coder& c, PfrepCodecModels& models, const PfrepCodecState& s, uint32_t i, PfrepEntry& e) {
    uint32_t radius = 0, error = 0, angle = 16;
    for (uint32_t k = 0; k < e.m; ++k) {
        const uint8_t* r = s.record(e.dependencies[k]);
        radius = std::max<uint32_t>(radius, r[6]);
        error = std::max<uint32_t>(error, r[7]);
        angle = std::max<uint32_t>(angle == 16 ? 0 : angle, pfrepLoad16(r + 8) >> 12);
    }
    const uint32_t with = std::min(e.m, 2u);
    uint32_t v = e.record[6];
    if (!pfrepCodeField(c, models.radius[with], radius, 255, &v)) return false;
    e.record[6] = uint8_t(v);
    v = e.record[7];
    if (!pfrepCodeField(c, models.error[(i < s.removed_count ? 3 : 0) + with], error, 255, &v)) return false;
    e.record[7] = uint8_t(v);
    const uint32_t cone = pfrepLoad16(e.record + 8);
    const uint32_t coded_angle = c.tree(models.cone_angle[angle], 4, cone >> 12);
    // The axis comes with the position, in the second pass.
    pfrepStore16(e.record + 8, (Coder::kEncoding ? cone & 0xFFF : 0u) | (coded_angle << 12));
    return !c.failed();
}

/// Codes vertex i (entry then record) and appends its fan to the state. False on a corrupt stream
/// (decoding) or a value the format cannot hold.
template <class Coder> bool pfrepCodeVertex(Coder& c, PfrepCodecModels& models, PfrepCodecState& s, uint32_t i, PfrepEntry& e) {
    uint32_t mentioner_count = 0;
    if (!pfrepCodeDependencies(c, models, s, i, e, &mentioner_count)) return false;
    const uint64_t n = c.uint(models.fan_count[std::min(e.m, 3u)], e.n);
    if (c.failed() || n > kPfrepMaxFan || s.used_slots + n > s.total_slots) return false;
    e.n = uint32_t(n);
    e.has_original = c.bit(models.has_original[e.m > 0 ? 1 : 0], e.has_original);
    if (!pfrepCodeFan(c, models, s, i, e, mentioner_count)) return false;
    if (!pfrepCodeGroups(c, models, s, e)) return false;
    if (!pfrepCodeCriterion(c, models, s, i, e)) return false;
    // Register the fan: its values for later candidates (bit 31: the slot holds a triangle), each
    // distinct vertex as mentioned by i.
    s.fan_begin[i] = s.used_slots;
    for (uint32_t k = 0; k < e.n; ++k) {
        const uint32_t a = e.neighbours[k];
        s.fans[s.used_slots++] = a | (e.groups[k] != 0 ? kPfrepSlotTriangle : 0u);
        if (s.mention_stamp[a] == i + 1) continue;
        s.mention_stamp[a] = i + 1;
        s.mentions[size_t(a) * format::kPfrepMentionSlots + s.mention_count[a] % format::kPfrepMentionSlots] = i;
        ++s.mention_count[a];
    }
    s.fan_begin[i + 1] = s.used_slots;
    return true;
}

/// Integer weights of the three axes (position_step relative to the largest, in 1024ths), so the
/// fan normal below is computed in integers and encoder and decoder agree on every platform.
inline void pfrepAxisWeights(const float step[3], int64_t out[3]) {
    const double largest = std::max({double(step[0]), double(step[1]), double(step[2])});
    for (int a = 0; a < 3; ++a) {
        const double w = largest > 0 && step[a] > 0 ? double(step[a]) / largest * 1024.0 : 0.0;
        out[a] = w >= 0 && w <= 1024.0 ? int64_t(w + 0.5) : 0;
    }
}

/// Octahedral code (6 + 6 bits, as the builder's cone axis) of the sum of the normals of the first
/// 64 triangles of vertex i's fan, from the quantized positions; false when the sum is zero.
inline bool pfrepFanAxis(const PfrepCodecState& s, uint32_t i, const uint8_t* record, uint32_t out[2]) {
    const uint32_t begin = s.fan_begin[i], count = s.fan_begin[i + 1] - begin;
    int64_t n[3] = {0, 0, 0};
    int64_t pi[3];
    for (int a = 0; a < 3; ++a) pi[a] = pfrepLoad16(record + 2 * a);
    uint32_t used = 0;
    for (uint32_t j = 0; j < count && used < 64; ++j) {
        const uint32_t t = s.fans[begin + j];
        if (!(t & kPfrepSlotTriangle)) continue;
        ++used;
        const uint8_t* ra = s.record(t & ~kPfrepSlotTriangle);
        const uint8_t* rb = s.record(s.fans[begin + (j + 1) % count] & ~kPfrepSlotTriangle);
        int64_t u[3], v[3];
        for (int a = 0; a < 3; ++a) {
            u[a] = (int64_t(pfrepLoad16(ra + 2 * a)) - pi[a]) * s.axis_weight[a];
            v[a] = (int64_t(pfrepLoad16(rb + 2 * a)) - pi[a]) * s.axis_weight[a];
        }
        // |u|, |v| < 2^27 per component: each product < 2^54, 64 sums < 2^61.
        n[0] += u[1] * v[2] - u[2] * v[1];
        n[1] += u[2] * v[0] - u[0] * v[2];
        n[2] += u[0] * v[1] - u[1] * v[0];
    }
    auto magnitude = [](int64_t x) { return x < 0 ? -x : x; };
    int64_t sum = magnitude(n[0]) + magnitude(n[1]) + magnitude(n[2]);
    if (sum == 0) return false;
    while (sum >= (int64_t(1) << 40)) { // 63 * 2 * sum stays far inside 64 bits
        for (int64_t& x : n) x /= 2;
        sum = magnitude(n[0]) + magnitude(n[1]) + magnitude(n[2]);
    }
    if (sum == 0) return false;
    int64_t x = n[0], y = n[1];
    if (n[2] < 0) { // the lower hemisphere folds over the diagonals
        const int64_t fx = (sum - magnitude(y)) * (x >= 0 ? 1 : -1);
        const int64_t fy = (sum - magnitude(x)) * (y >= 0 ? 1 : -1);
        x = fx;
        y = fy;
    }
    // round(63 · (x / sum + 1) / 2), halves up, as the builder's lround of a non-negative value.
    out[0] = uint32_t(std::min<int64_t>(63, (63 * (x + sum) + sum) / (2 * sum)));
    out[1] = uint32_t(std::min<int64_t>(63, (63 * (y + sum) + sum) / (2 * sum)));
    return true;
}

/// Position and cone axis of vertex i, coded in DECREASING rank after every entry: its fan's vertices rank above
/// it, so their positions are known, and i lies amid them (its neighbourhood when it was removed).
/// `record` holds i's record and receives the position; the prediction is the mean of the fan's
/// values, or the position of i + 1 for an empty fan. Then the cone axis, predicted by the fan's
/// normal (pfrepFanAxis).
template <class Coder>
bool pfrepCodePosition(Coder& c, PfrepCodecModels& models, const PfrepCodecState& s, uint32_t i, uint8_t* record) {
    uint64_t sum[3] = {0, 0, 0};
    uint32_t count = 0;
    uint32_t low[3] = {0xFFFF, 0xFFFF, 0xFFFF}, high[3] = {0, 0, 0};
    for (uint32_t t = s.fan_begin[i]; t < s.fan_begin[i + 1]; ++t) {
        const uint8_t* r = s.record(s.fans[t] & ~kPfrepSlotTriangle);
        for (int a = 0; a < 3; ++a) {
            const uint32_t q = pfrepLoad16(r + 2 * a);
            sum[a] += q;
            low[a] = std::min(low[a], q);
            high[a] = std::max(high[a], q);
        }
        ++count;
    }
    uint32_t pred[3] = {0, 0, 0};
    for (int a = 0; a < 3; ++a)
        pred[a] = count > 0 ? uint32_t((sum[a] + count / 2) / count)
                            : i + 1 < s.vertex_count ? pfrepLoad16(s.record(i + 1) + 2 * a) : 0;
    for (int a = 0; a < 3; ++a) {
        uint32_t q = pfrepLoad16(record + 2 * a);
        // Context: 0 without a fan, else 1 + half the bit length of the fan's extent on this axis
        // (the residual scales with the fan).
        const uint32_t ctx = count > 0 ? 1 + pfrepBitWidth(high[a] - low[a]) / 2 : 0;
        if (!pfrepCodeField(c, models.position[a][ctx], pred[a], 0xFFFF, &q)) return false;
        pfrepStore16(record + 2 * a, q);
    }
    // The cone axis, predicted by the octahedral code of the fan's normal.
    uint32_t predicted_axis[2] = {0, 0};
    const bool has_normal = pfrepFanAxis(s, i, record, predicted_axis);
    const uint32_t cone = pfrepLoad16(record + 8);
    uint32_t axis[2] = {cone & 63, (cone >> 6) & 63};
    for (int a = 0; a < 2; ++a)
        if (!pfrepCodeField(c, models.cone_axis[a][has_normal ? 1 : 0], predicted_axis[a], 63, &axis[a])) return false;
    pfrepStore16(record + 8, axis[0] | (axis[1] << 6) | (cone & 0xF000u));
    return true;
}


/// Bytes of entry i written canonically (docs/format/pfrep.md "Entry i"): counts with escapes,
/// the smallest widths that hold the codes, masks in group order.
inline size_t pfrepEntryBytes(const PfrepEntry& e, uint32_t i) {
    uint32_t max_neighbour = 0, max_dependency = 0;
    for (uint32_t k = 0; k < e.n; ++k) max_neighbour = std::max(max_neighbour, e.neighbours[k] - i - 1);
    for (uint32_t k = 0; k < e.m; ++k) max_dependency = std::max(max_dependency, i - 1 - e.dependencies[k]);
    uint64_t bits = format::kPfrepCountBits + (e.n >= 63 ? format::kPfrepCountEscapeBits : 0) +
                    format::kPfrepDependencyCountBits + (e.m >= 7 ? format::kPfrepCountEscapeBits : 0) + 1 +
                    format::kPfrepWidthBits + (e.m > 0 ? format::kPfrepWidthBits : 0);
    bits += uint64_t(e.n) * pfrepBitWidth(max_neighbour) + uint64_t(e.has_original) * e.n +
            uint64_t(e.m) * (pfrepBitWidth(max_dependency) + e.n);
    return size_t((bits + 7) / 8);
}

/// Writes entry i at out (exactly pfrepEntryBytes(e, i) bytes).
inline void pfrepWriteEntry(const PfrepEntry& e, uint32_t i, uint8_t* out) {
    // Bits gather in a 64-bit accumulator, flushed a byte at a time (at most 32 bits per put).
    uint64_t pending = 0;
    uint32_t pending_bits = 0;
    size_t at = 0;
    auto put = [&](uint64_t value, uint32_t bits) {
        if (bits == 0) return;
        pending |= (value & ((uint64_t(1) << bits) - 1)) << pending_bits;
        pending_bits += bits;
        while (pending_bits >= 8) {
            out[at++] = uint8_t(pending);
            pending >>= 8;
            pending_bits -= 8;
        }
    };
    auto putCount = [&](uint32_t count, uint32_t bits) {
        const uint32_t escape = (1u << bits) - 1;
        if (count < escape) {
            put(count, bits);
        } else {
            put(escape, bits);
            put(count - escape, format::kPfrepCountEscapeBits);
        }
    };
    uint32_t max_neighbour = 0, max_dependency = 0;
    for (uint32_t k = 0; k < e.n; ++k) max_neighbour = std::max(max_neighbour, e.neighbours[k] - i - 1);
    for (uint32_t k = 0; k < e.m; ++k) max_dependency = std::max(max_dependency, i - 1 - e.dependencies[k]);
    const uint32_t wa = pfrepBitWidth(max_neighbour), wd = pfrepBitWidth(max_dependency);
    putCount(e.n, format::kPfrepCountBits);
    putCount(e.m, format::kPfrepDependencyCountBits);
    put(e.has_original, 1);
    put(wa, format::kPfrepWidthBits);
    if (e.m > 0) put(wd, format::kPfrepWidthBits);
    for (uint32_t k = 0; k < e.n; ++k) put(e.neighbours[k] - i - 1, wa);
    auto putMask = [&](uint32_t group) {
        for (uint32_t k = 0; k < e.n; k += 32) {
            const uint32_t take = std::min(32u, e.n - k);
            uint64_t word = 0;
            for (uint32_t b = 0; b < take; ++b) word |= uint64_t(e.groups[k + b] == group) << b;
            put(word, take);
        }
    };
    if (e.has_original) putMask(1);
    for (uint32_t k = 0; k < e.m; ++k) {
        put(i - 1 - e.dependencies[k], wd);
        putMask(2 + k);
    }
    if (pending_bits > 0) out[at++] = uint8_t(pending);

}

} // namespace detail
} // namespace lodrt
