#pragma once
// PFRep format 4 (docs/format/pfrep.md, "Format 4"): the table coded against LOD0, which the decoder
// already has (its points and triangles). Only the removal sequence is coded: per removal, the point
// removed (its index among the points not removed yet) and the point it collapses into (an index
// among its current neighbours); the decoder replays the half-edge collapses to rebuild every stored
// triangle and its dependency, lays out the entries, and reads the records' criterion codes as
// differences from predictions (positions: LOD0's points quantized as the builder quantizes them).
// A pack's blob may also carry a split list (pfrep4CodeSplits), which says how to number LOD0 from
// its decoded stream when the stream's quantization put several of the blob's points on one position.
// Written once as templates over the coder (pfrep_codec.h's convention), so the baker's encoder and
// lodrt's decoder run the same replay and the same layout.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "lodrt/detail/pfrep_codec.h"
#include "lodrt/format.h"

namespace lodrt {
namespace detail {

constexpr uint32_t kPfrep4Unreferenced = 0xFFFFFFFEu; // rank_of of a point on no LOD0 triangle

/// LOD0 as the decoder has it: points (3 floats each) and triangles (3 point ids each, no repeated
/// point), numbered as docs/format/pfrep.md "Format 4" says.
struct Pfrep4Lod0 {
    const float* positions = nullptr;
    const uint32_t* triangles = nullptr;
    uint32_t point_count = 0;
    uint32_t triangle_count = 0;
};

struct Pfrep4Header {
    uint32_t vertex_count = 0, removed_count = 0, point_count = 0, level0_triangles = 0;
    uint32_t stored_triangles = 0, decoded_size = 0;
    uint32_t flags = 0; // format::kPfrep4Flag* (the word at offset 60)
    float position_min[3] = {0, 0, 0}, position_step[3] = {0, 0, 0};
    float error_unit = 0;
};

struct Pfrep4Models {
    PfrepUintModel kept[2];     // index of the kept point among the removed point's neighbours
    PfrepUintModel position[3]; // per axis: quantized position minus LOD0's point quantized
    PfrepCodecModels criterion; // format 3's radius, error, cone_angle and cone_axis models
    void init() {
        for (auto& u : kept) u.init();
        for (auto& u : position) u.init();
        criterion.init();
    }
};

/// Working arrays (caller memory; sizes in pfrep4ScratchValues's comments). T = stored triangles,
/// P = points, V = vertices.
struct Pfrep4State {
    Pfrep4Header h;
    Pfrep4Lod0 lod0;
    uint32_t* tri = nullptr;     // 3T: corners (point ids)
    uint32_t* tri_dep = nullptr; // T: point whose removal created it (kNone: LOD0)
    uint32_t* next = nullptr;    // 3T: incidence lists, node t * 3 + corner, newest first
    uint32_t* head = nullptr;    // P
    uint32_t* fenwick = nullptr; // P + 1: points not removed yet (1-based Fenwick tree)
    uint32_t* stamp = nullptr;   // P
    uint32_t* ring = nullptr;    // T
    uint32_t* neighbours = nullptr; // 2T: distinct neighbours of the removed point
    uint32_t* dead = nullptr;    // T
    uint32_t* rank_of = nullptr; // P
    uint32_t* rank_point = nullptr; // V
    uint32_t* slot_first = nullptr; // V + 1
    uint32_t* slots = nullptr;   // 3T: (a, b, dependency rank) per stored triangle, by lowest corner
    uint32_t* fan_begin = nullptr; // V + 1
    uint32_t* fans = nullptr;    // 2T: A_i values, bit 31 set for a slot holding a triangle
    uint32_t* groups = nullptr;  // 2T: per slot, pfrep_codec.h's group numbering
    uint32_t* dep_begin = nullptr; // V + 1
    uint32_t* deps = nullptr;    // T
    uint32_t* entry_offset = nullptr; // V + 1: entry byte offsets in one stream
    uint32_t* block_offset = nullptr; // V (blocks)
    uint32_t* work = nullptr;    // 8 * kPfrepMaxFan + 2: one entry's crown building
    uint32_t created = 0;        // triangles listed so far
    uint32_t block_shift = 0, block_count = 0;
    uint64_t layout_size = 0; // bytes of the format 2 blob (pfrep4Layout)
};

/// uint32 values of scratch a state needs (each array rounded to an even count).
inline uint64_t pfrep4ScratchValues(const Pfrep4Header& h) {
    const uint64_t t = h.stored_triangles, p = h.point_count, v = h.vertex_count;
    auto even = [](uint64_t x) { return (x + 1) & ~uint64_t(1); };
    return even((sizeof(Pfrep4Models) + 3) / 4) + even(3 * t) * 3 + even(t) * 4 + even(2 * t) * 3 + even(p) * 3 +
           even(p + 1) + even(v) * 2 + even(v + 1) * 4 + even(8 * uint64_t(kPfrepMaxFan) + 2);
}

/// Points out every array of `s` into `w` (pfrep4ScratchValues values); returns the models.
inline Pfrep4Models* pfrep4Carve(Pfrep4State& s, uint32_t* w) {
    const uint64_t t = s.h.stored_triangles, p = s.h.point_count, v = s.h.vertex_count;
    uint64_t at = 0;
    auto take = [&](uint64_t values) {
        uint32_t* start = w + at;
        at += (values + 1) & ~uint64_t(1);
        return start;
    };
    Pfrep4Models* models = reinterpret_cast<Pfrep4Models*>(take((sizeof(Pfrep4Models) + 3) / 4));
    s.tri = take(3 * t);
    s.next = take(3 * t);
    s.slots = take(3 * t);
    s.tri_dep = take(t);
    s.ring = take(t);
    s.dead = take(t);
    s.deps = take(t);
    s.neighbours = take(2 * t);
    s.fans = take(2 * t);
    s.groups = take(2 * t);
    s.head = take(p);
    s.stamp = take(p);
    s.rank_of = take(p);
    s.fenwick = take(p + 1);
    s.rank_point = take(v);
    s.block_offset = take(v);
    s.slot_first = take(v + 1);
    s.fan_begin = take(v + 1);
    s.dep_begin = take(v + 1);
    s.entry_offset = take(v + 1);
    s.work = take(8 * uint64_t(kPfrepMaxFan) + 2);
    return models;
}

// ---- Split list (format::kPfrep4FlagSplitPoints) ----

/// Models of the split list; all start at 1/2.
struct Pfrep4SplitModels {
    uint32_t split[3];       // context: min(vertices of the weld, 4) - 2
    PfrepUintModel group[2]; // context: min(groups so far, 2) - 1
    void init() {
        initRangeProbs(split, 3);
        for (auto& u : group) u.init();
    }
};

/// The split list of a pack's LOD0 (docs/format/pfrep.md "Split list"). `weld[v]` is, per vertex of
/// the decoded stream, the lowest vertex with v's position bits (so weld[v] <= v). For every weld of
/// two or more vertices, by increasing lowest vertex, one bit says whether it splits; the vertices
/// of a weld that splits, by increasing id after its lowest, each name their group: a new one, or
/// one of those so far (counted back from the newest); it must end with two groups or more. On
/// return weld[v] is the lowest vertex of v's group. Encoding: vertices are in one group iff their
/// `label`s are equal. `next` and `groups` hold vertex_count values each. False on a corrupt stream.
template <class Coder>
bool pfrep4CodeSplits(Coder& c, Pfrep4SplitModels& m, uint32_t vertex_count, uint32_t* weld, const uint32_t* label,
                      uint32_t* next, uint32_t* groups) {
    // Each weld as a list by increasing id from its lowest vertex (`groups` holds the heads meanwhile).
    std::fill(groups, groups + vertex_count, kNone);
    for (uint32_t v = vertex_count; v-- > 0;) {
        const uint32_t w = weld[v];
        next[v] = groups[w];
        if (w != v) groups[w] = v;
    }
    for (uint32_t w = 0; w < vertex_count; ++w) {
        if (weld[w] != w || next[w] == kNone) continue;
        uint32_t size = 1;
        bool splits = false;
        for (uint32_t v = next[w]; v != kNone; v = next[v]) {
            ++size;
            if (Coder::kEncoding) splits = splits || label[v] != label[w];
        }
        const uint32_t ctx = (size < 4 ? size : 4) - 2;
        if (!c.bit(m.split[ctx], splits ? 1u : 0u)) continue;
        uint32_t count = 1; // groups so far, by their lowest vertex
        groups[0] = w;
        for (uint32_t v = next[w]; v != kNone; v = next[v]) {
            uint32_t back = 0; // 0: a new group; g > 0: the g-th newest
            if (Coder::kEncoding)
                for (uint32_t g = 0; g < count && back == 0; ++g)
                    if (label[groups[g]] == label[v]) back = count - g;
            // The last vertex of a weld whose vertices so far are one group starts the second.
            if (next[v] != kNone || count > 1) {
                back = uint32_t(c.uint(m.group[count > 1 ? 1 : 0], back));
                if (c.failed() || back > count) return false;
            }
            if (back == 0) groups[count++] = v;
            weld[v] = back == 0 ? v : groups[count - back];
        }
        if (count < 2) return false;
    }
    return !c.failed();
}

// ---- Removal sequence ----

/// Codes x in [0, count) with the truncated binary code (direct bits; count > 0).
template <class Coder> uint32_t pfrep4CodeIndex(Coder& c, uint32_t count, uint32_t x) {
    if (count <= 1) return 0;
    const uint32_t k = pfrepBitWidth(count) - 1; // 2^k <= count < 2^(k+1)
    const uint32_t u = uint32_t((uint64_t(2) << k) - count); // values below u take k bits
    if (Coder::kEncoding) {
        if (x < u) {
            c.direct(x, k);
        } else {
            const uint32_t y = x + u;
            c.direct(y >> 1, k);
            c.direct(y & 1, 1);
        }
        return x;
    }
    uint32_t v = c.direct(0, k);
    if (v < u) return v;
    return ((v << 1) | c.direct(0, 1)) - u;
}

inline void pfrep4FenwickAdd(Pfrep4State& s, uint32_t p, int32_t d) {
    for (uint32_t i = p + 1; i <= s.h.point_count; i += i & (0u - i)) s.fenwick[i] = uint32_t(int32_t(s.fenwick[i]) + d);
}
inline uint32_t pfrep4FenwickBelow(const Pfrep4State& s, uint32_t p) { // remaining points with id < p
    uint32_t sum = 0;
    for (uint32_t i = p; i > 0; i -= i & (0u - i)) sum += s.fenwick[i];
    return sum;
}
inline uint32_t pfrep4FenwickSelect(const Pfrep4State& s, uint32_t index) { // the index-th remaining point
    uint32_t at = 0;
    for (uint32_t step = uint32_t(1) << (pfrepBitWidth(s.h.point_count) - 1); step > 0; step >>= 1)
        if (at + step <= s.h.point_count && s.fenwick[at + step] <= index) {
            at += step;
            index -= s.fenwick[at];
        }
    return at;
}

/// Rank i to the next point of the `remaining` points not ranked yet: its index among them by
/// increasing id (truncated binary, pfrep4CodeIndex), the point (`u` when encoding) taken out of the
/// Fenwick tree. Returns the point, or kNone on a corrupt stream (or, encoding, a point that is not
/// among them).
template <class Coder> uint32_t pfrep4CodeNextPoint(Coder& c, Pfrep4State& s, uint32_t remaining, uint32_t i, uint32_t u) {
    if (Coder::kEncoding && (u >= s.h.point_count || s.rank_of[u] != kNone)) return kNone;
    const uint32_t index = pfrep4CodeIndex(c, remaining, Coder::kEncoding ? pfrep4FenwickBelow(s, u) : 0);
    if (c.failed() || index >= remaining) return kNone;
    if (!Coder::kEncoding) u = pfrep4FenwickSelect(s, index);
    pfrep4FenwickAdd(s, u, -1);
    s.rank_of[u] = i;
    s.rank_point[i] = u;
    return u;
}

/// LOD0's triangles as the first stored triangles, linked into their corners' incidence lists; the
/// Fenwick tree holds the points on a triangle. False when LOD0 is not what the header says.
inline bool pfrep4LoadLod0(Pfrep4State& s) {
    const Pfrep4Lod0& l = s.lod0;
    if (l.point_count != s.h.point_count || l.triangle_count != s.h.level0_triangles) return false;
    std::fill(s.head, s.head + l.point_count, kNone);
    for (uint32_t t = 0; t < l.triangle_count; ++t) {
        const uint32_t* c = l.triangles + size_t(t) * 3;
        if (c[0] >= l.point_count || c[1] >= l.point_count || c[2] >= l.point_count || c[0] == c[1] ||
            c[1] == c[2] || c[0] == c[2])
            return false;
        for (uint32_t k = 0; k < 3; ++k) {
            s.tri[size_t(t) * 3 + k] = c[k];
            s.next[size_t(t) * 3 + k] = s.head[c[k]];
            s.head[c[k]] = t * 3 + k;
        }
        s.tri_dep[t] = kNone;
        s.dead[t] = 0;
    }
    s.created = l.triangle_count;
    std::fill(s.fenwick, s.fenwick + size_t(l.point_count) + 1, 0u);
    uint32_t referenced = 0;
    for (uint32_t p = 0; p < l.point_count; ++p) {
        s.stamp[p] = 0;
        s.rank_of[p] = s.head[p] == kNone ? kPfrep4Unreferenced : kNone;
        s.fenwick[p + 1] = s.head[p] == kNone ? 0u : 1u;
        referenced += s.fenwick[p + 1];
    }
    for (uint32_t i = 1; i <= l.point_count; ++i) { // leaves to the tree, in place
        const uint64_t up = uint64_t(i) + (i & (0u - i));
        if (up <= l.point_count) s.fenwick[up] += s.fenwick[i];
    }
    return referenced == s.h.vertex_count;
}

/// Removal i: u collapses into v. u's live triangles die; those without v come back with v for u.
inline bool pfrep4Collapse(Pfrep4State& s, uint32_t u, uint32_t v, uint32_t ring_size) {
    for (uint32_t r = 0; r < ring_size; ++r) {
        const uint32_t t = s.ring[r];
        s.dead[t] = 1;
        const uint32_t* c = s.tri + size_t(t) * 3;
        if (c[0] == v || c[1] == v || c[2] == v) continue;
        if (s.created >= s.h.stored_triangles) return false;
        const uint32_t fresh = s.created++;
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t p = s.tri[size_t(t) * 3 + k] == u ? v : s.tri[size_t(t) * 3 + k];
            s.tri[size_t(fresh) * 3 + k] = p;
            s.next[size_t(fresh) * 3 + k] = s.head[p];
            s.head[p] = fresh * 3 + k;
        }
        s.tri_dep[fresh] = u;
        s.dead[fresh] = 0;
    }
    s.head[u] = kNone;
    return true;
}

/// The removal sequence: for i < removed_count, the point removed (removed[i] when encoding) and the
/// point it collapses into (kept[i]), replayed on LOD0. False on a corrupt stream or a sequence the
/// format cannot hold (encoding: a kept point that is not a neighbour).
template <class Coder>
bool pfrep4CodeRemovals(Coder& c, Pfrep4Models& models, Pfrep4State& s, const uint32_t* removed, const uint32_t* kept) {
    uint32_t remaining = s.h.vertex_count;
    for (uint32_t i = 0; i < s.h.removed_count; ++i, --remaining) {
        const uint32_t u = pfrep4CodeNextPoint(c, s, remaining, i, Coder::kEncoding ? removed[i] : 0);
        if (u == kNone) return false;
        // u's live triangles (its ring) and their other corners, in list order.
        uint32_t ring_size = 0, count = 0;
        for (uint32_t node = s.head[u]; node != kNone; node = s.next[node]) {
            const uint32_t t = node / 3;
            if (s.dead[t]) continue;
            s.ring[ring_size++] = t;
            for (uint32_t k = 1; k < 3; ++k) {
                const uint32_t p = s.tri[size_t(t) * 3 + (node % 3 + k) % 3];
                if (s.stamp[p] == i + 1) continue;
                s.stamp[p] = i + 1;
                s.neighbours[count++] = p;
            }
        }
        if (ring_size == 0) return false;
        uint32_t choice = 0;
        if (Coder::kEncoding) {
            while (choice < count && s.neighbours[choice] != kept[i]) ++choice;
            if (choice == count) return false;
        }
        choice = uint32_t(c.uint(models.kept[count > 6 ? 1 : 0], choice));
        if (c.failed() || choice >= count) return false;
        if (!pfrep4Collapse(s, u, s.neighbours[choice], ring_size)) return false;
    }
    return true;
}

// ---- Table ----

/// The check of LOD0 that kPfrep4FlagLod0Check codes: FNV-1a over the 32-bit words point_count,
/// triangle_count, every point's three float bit patterns and every triangle's three ids, in order.
inline uint32_t pfrep4Lod0Check(const Pfrep4Lod0& l) {
    uint32_t h = 2166136261u;
    auto word = [&h](uint32_t w) {
        for (int b = 0; b < 4; ++b) h = (h ^ ((w >> (8 * b)) & 0xFFu)) * 16777619u;
    };
    word(l.point_count);
    word(l.triangle_count);
    for (size_t i = 0; i < size_t(l.point_count) * 3; ++i) {
        uint32_t bits;
        std::memcpy(&bits, l.positions + i, 4);
        word(bits);
    }
    for (size_t i = 0; i < size_t(l.triangle_count) * 3; ++i) word(l.triangles[i]);
    return h;
}

/// With kPfrep4FlagLod0Check, codes pfrep4Lod0Check(s.lod0) as two 16-bit direct values; false when
/// decoding finds another value (the blob was coded against another LOD0).
template <class Coder> bool pfrep4CodeLod0Check(Coder& c, const Pfrep4State& s) {
    if ((s.h.flags & format::kPfrep4FlagLod0Check) == 0) return true;
    const uint32_t check = pfrep4Lod0Check(s.lod0);
    const uint32_t low = c.direct(check & 0xFFFFu, 16), high = c.direct(check >> 16, 16);
    return Coder::kEncoding || (low | (high << 16)) == check;
}

/// With format::kPfrep4FlagCodedTail: the ranks removed_count ... vertex_count - 1 of the points
/// never removed, each the index of its point among those not ranked yet (by increasing id), coded
/// as the removals' indices are (`tail` holds the points by rank when encoding). A LOD0 numbered
/// apart from the build (a pack's decoded stream) keeps the build's ranks this way. Without the flag
/// nothing is coded and pfrep4BuildSlots ranks them by point id.
template <class Coder> bool pfrep4CodeTail(Coder& c, Pfrep4State& s, const uint32_t* tail) {
    if ((s.h.flags & format::kPfrep4FlagCodedTail) == 0) return true;
    uint32_t remaining = s.h.vertex_count - s.h.removed_count;
    for (uint32_t i = s.h.removed_count; i < s.h.vertex_count; ++i, --remaining) {
        if (pfrep4CodeNextPoint(c, s, remaining, i, Coder::kEncoding ? tail[i] : 0) == kNone) return false;
    }
    return true;
}

/// Ranks of the points never removed (by point id, unless pfrep4CodeTail ranked them), then every
/// stored triangle as a slot of its lowest-ranked corner, in the order the triangles were listed.
/// False when the counts disagree.
inline bool pfrep4BuildSlots(Pfrep4State& s) {
    uint32_t rank = (s.h.flags & format::kPfrep4FlagCodedTail) != 0 ? s.h.vertex_count : s.h.removed_count;
    for (uint32_t p = 0; p < s.h.point_count; ++p)
        if (s.rank_of[p] == kNone) {
            if (rank >= s.h.vertex_count) return false;
            s.rank_of[p] = rank;
            s.rank_point[rank++] = p;
        }
    if (rank != s.h.vertex_count || s.created != s.h.stored_triangles) return false;
    const uint32_t v = s.h.vertex_count;
    std::fill(s.slot_first, s.slot_first + size_t(v) + 1, 0u);
    for (uint32_t t = 0; t < s.created; ++t) {
        const uint32_t* c = s.tri + size_t(t) * 3;
        const uint32_t r0 = s.rank_of[c[0]], r1 = s.rank_of[c[1]], r2 = s.rank_of[c[2]];
        const uint32_t low = std::min(r0, std::min(r1, r2));
        ++s.slot_first[low + 1];
        // Keep the rotation in place of the corners: ranks from the lowest, orientation kept.
        const uint32_t m = low == r0 ? 0 : low == r1 ? 1 : 2;
        const uint32_t r[3] = {r0, r1, r2};
        s.next[size_t(t) * 3] = r[m];
        s.next[size_t(t) * 3 + 1] = r[(m + 1) % 3];
        s.next[size_t(t) * 3 + 2] = r[(m + 2) % 3];
    }
    for (uint32_t i = 0; i < v; ++i) s.slot_first[i + 1] += s.slot_first[i];
    uint32_t* fill = s.entry_offset; // cursors (entry_offset is not used yet)
    std::copy(s.slot_first, s.slot_first + v, fill);
    for (uint32_t t = 0; t < s.created; ++t) {
        const uint32_t* r = s.next + size_t(t) * 3;
        uint32_t* slot = s.slots + size_t(fill[r[0]]++) * 3;
        slot[0] = r[1];
        slot[1] = r[2];
        slot[2] = s.tri_dep[t] == kNone ? kNone : s.rank_of[s.tri_dep[t]];
    }
    return true;
}


/// Entry i's fan sequence A_i from its slots: walks over the directed edges a -> b opposite i, each
/// starting, while there is one, at the first unused slot whose a is no slot's b, else at the first
/// unused slot; a walk continues with the first unused slot (in slot order) leaving its end. Appends
/// A_i and its slot groups to fans / groups, i's dependencies (increasing) to deps. False when the
/// entry is too large for format 2.
inline bool pfrep4BuildEntry(Pfrep4State& s, uint32_t i, uint32_t* fan_used, uint32_t* deps_used) {
    const uint32_t first = s.slot_first[i], count = s.slot_first[i + 1] - first;
    const uint32_t* sl = s.slots + size_t(first) * 3;
    s.fan_begin[i] = *fan_used;
    s.dep_begin[i] = *deps_used;
    if (count > kPfrepMaxFan) return false;
    uint32_t* order = s.work;              // slots sorted by (a, slot)
    uint32_t* cursor = order + count;      // per group start: first slot of the group maybe unused
    uint32_t* used = cursor + count;
    uint32_t* targeted = used + count;     // per group start: some slot ends at the group's a
    uint32_t* edge_at = targeted + count;  // per slot: its position in A_i
    uint32_t* seq = edge_at + count;       // A_i, up to 2 * count + 1 values
    for (uint32_t k = 0; k < count; ++k) {
        order[k] = k;
        cursor[k] = k;
        used[k] = 0;
        targeted[k] = 0;
    }
    std::sort(order, order + count, [sl](uint32_t x, uint32_t y) {
        return sl[x * 3] != sl[y * 3] ? sl[x * 3] < sl[y * 3] : x < y;
    });
    auto groupOf = [&](uint32_t a) { // first sorted position with this a, or count
        const uint32_t* at = std::lower_bound(order, order + count, a, [sl](uint32_t x, uint32_t value) {
            return sl[x * 3] < value;
        });
        return (at != order + count && sl[*at * 3] == a) ? uint32_t(at - order) : count;
    };
    for (uint32_t k = 0; k < count; ++k) {
        const uint32_t g = groupOf(sl[k * 3 + 1]);
        if (g < count) targeted[g] = 1;
    }
    auto nextFrom = [&](uint32_t a) { // first unused slot leaving a, or kNone
        const uint32_t g = groupOf(a);
        if (g == count) return kNone;
        uint32_t p = cursor[g];
        while (p < count && sl[order[p] * 3] == a && used[order[p]]) ++p;
        cursor[g] = p;
        return p < count && sl[order[p] * 3] == a ? order[p] : kNone;
    };
    uint32_t n = 0, open_scan = 0, any_scan = 0, remaining = count;
    while (remaining > 0) {
        uint32_t start = kNone;
        for (; open_scan < count && start == kNone; ++open_scan)
            if (!used[open_scan] && !targeted[groupOf(sl[open_scan * 3])]) start = open_scan;
        if (start == kNone) {
            while (used[any_scan]) ++any_scan;
            start = any_scan;
        } else {
            --open_scan; // look at it again next time (it is used now, so it is skipped)
        }
        seq[n++] = sl[start * 3];
        for (uint32_t e = start; e != kNone; e = nextFrom(sl[e * 3 + 1])) {
            used[e] = 1;
            --remaining;
            edge_at[e] = n - 1;
            seq[n++] = sl[e * 3 + 1];
        }
    }
    if (n > 1 && seq[n - 1] == seq[0]) --n;
    if (n > kPfrepMaxFan) return false;
    uint32_t* deps = s.deps + *deps_used;
    uint32_t m = 0;
    for (uint32_t k = 0; k < count; ++k)
        if (sl[k * 3 + 2] != kNone) deps[m++] = sl[k * 3 + 2];
    std::sort(deps, deps + m);
    m = uint32_t(std::unique(deps, deps + m) - deps);
    if (m > kPfrepMaxDependencies) return false;
    uint32_t* fans = s.fans + *fan_used;
    uint32_t* groups = s.groups + *fan_used;
    for (uint32_t j = 0; j < n; ++j) {
        fans[j] = seq[j];
        groups[j] = 0;
    }
    for (uint32_t k = 0; k < count; ++k) {
        const uint32_t d = sl[k * 3 + 2];
        groups[edge_at[k]] = d == kNone ? 1u : 2u + uint32_t(std::lower_bound(deps, deps + m, d) - deps);
    }
    *fan_used += n;
    *deps_used += m;
    s.fan_begin[i + 1] = *fan_used;
    s.dep_begin[i + 1] = *deps_used;
    return true;
}

/// The entry of vertex i as pfrep_codec.h's PfrepEntry (neighbours without the triangle bit, in
/// `neighbours`).
inline void pfrep4Entry(const Pfrep4State& s, uint32_t i, PfrepEntry& e, uint32_t* neighbours) {
    const uint32_t begin = s.fan_begin[i];
    e.n = s.fan_begin[i + 1] - begin;
    e.m = s.dep_begin[i + 1] - s.dep_begin[i];
    e.dependencies = s.deps + s.dep_begin[i];
    e.groups = s.groups + begin;
    e.neighbours = neighbours;
    e.has_original = 0;
    for (uint32_t j = 0; j < e.n; ++j) {
        neighbours[j] = s.fans[begin + j] & ~kPfrepSlotTriangle;
        e.has_original |= e.groups[j] == 1 ? 1u : 0u;
    }
}

/// Every entry built, the format 2 layout chosen as the builder chooses it (the largest block
/// shift whose in-block entry offsets fit 16 bits); its size into s.layout_size. False when an
/// entry is too large or the blob would pass 4 GiB.
inline bool pfrep4Layout(Pfrep4State& s) {
    const uint32_t v = s.h.vertex_count;
    uint32_t fan_used = 0, deps_used = 0;
    uint64_t offset = 0;
    uint32_t* neighbours = s.work + 6 * uint64_t(kPfrepMaxFan);
    for (uint32_t i = 0; i < v; ++i) {
        if (!pfrep4BuildEntry(s, i, &fan_used, &deps_used)) return false;
        PfrepEntry e;
        pfrep4Entry(s, i, e, neighbours);
        s.entry_offset[i] = uint32_t(offset);
        offset += pfrepEntryBytes(e, i);
        if (offset > 0xFFFFFFFFu) return false;
        for (uint32_t j = s.fan_begin[i]; j < s.fan_begin[i + 1]; ++j)
            if (s.groups[j] != 0) s.fans[j] |= kPfrepSlotTriangle;
    }
    s.entry_offset[v] = uint32_t(offset);
    uint32_t shift = format::kPfrepMaxBlockShift;
    for (;; --shift) {
        bool fits = true;
        for (uint32_t i = 0; i < v && fits; ++i) fits = s.entry_offset[i] - s.entry_offset[(i >> shift) << shift] <= 0xFFFFu;
        if (fits || shift == 0) break;
    }
    s.block_shift = shift;
    s.block_count = uint32_t((uint64_t(v) + (uint64_t(1) << shift) - 1) >> shift);
    uint64_t total = format::kPfrepHeaderSize + uint64_t(s.block_count) * 4;
    for (uint32_t b = s.block_count; b-- > 0;) {
        const uint32_t lo = b << shift, hi = uint32_t(std::min<uint64_t>(uint64_t(lo) + (uint64_t(1) << shift), v));
        s.block_offset[b] = uint32_t(std::min<uint64_t>(total, 0xFFFFFFFFu));
        total += uint64_t(hi - lo) * (format::kPfrepVertexRecordSize + 2) + (s.entry_offset[hi] - s.entry_offset[lo]) +
                 format::kPfrepStreamPadding;
    }
    s.layout_size = total;
    return total <= 0xFFFFFFFFu;
}

/// A PfrepCodecState that reads the records from `out` (format 3's criterion coding reads them).
inline PfrepCodecState pfrep4CodecView(const Pfrep4State& s, const uint8_t* out) {
    PfrepCodecState cs;
    cs.vertex_count = s.h.vertex_count;
    cs.removed_count = s.h.removed_count;
    cs.block_shift = s.block_shift;
    cs.block_offset = s.block_offset;
    cs.blob = out;
    cs.fan_begin = s.fan_begin;
    cs.fans = s.fans;
    pfrepAxisWeights(s.h.position_step, cs.axis_weight);
    return cs;
}

/// LOD0's point p quantized as the builder quantizes positions (float arithmetic, lround).
inline uint32_t pfrep4Quantize(const Pfrep4Header& h, const float* position, int axis) {
    if (!(h.position_step[axis] > 0)) return 0;
    const float f = (position[axis] - h.position_min[axis]) / h.position_step[axis];
    if (!(f >= 0.0f)) return 0;
    if (!(f <= 65535.0f)) return 65535;
    return uint32_t(std::lround(f));
}

/// The records, written into `out` at their format 2 places: positions (all of them) as differences
/// from LOD0's points, then in rank order radius, error and cone as format 3 codes them (from the
/// dependencies' codes and the fan's normal). `records` (encoding only) holds the records by rank.
template <class Coder>
bool pfrep4CodeRecords(Coder& c, Pfrep4Models& models, Pfrep4State& s, const uint8_t* records, uint8_t* out) {
    const PfrepCodecState cs = pfrep4CodecView(s, out);
    const uint32_t v = s.h.vertex_count;
    for (uint32_t i = 0; i < v; ++i) {
        uint8_t* r = const_cast<uint8_t*>(cs.record(i));
        const float* p = s.lod0.positions + size_t(s.rank_point[i]) * 3;
        for (int a = 0; a < 3; ++a) {
            uint32_t q = Coder::kEncoding ? pfrepLoad16(records + size_t(i) * format::kPfrepVertexRecordSize + 2 * a) : 0;
            if (!pfrepCodeField(c, models.position[a], pfrep4Quantize(s.h, p, a), 0xFFFF, &q)) return false;
            pfrepStore16(r + 2 * a, q);
        }
    }
    PfrepEntry e;
    for (uint32_t i = 0; i < v; ++i) {
        uint8_t* r = const_cast<uint8_t*>(cs.record(i));
        e.m = s.dep_begin[i + 1] - s.dep_begin[i];
        e.dependencies = s.deps + s.dep_begin[i];
        if (Coder::kEncoding) std::memcpy(e.record, records + size_t(i) * format::kPfrepVertexRecordSize, format::kPfrepVertexRecordSize);
        if (!pfrepCodeCriterion(c, models.criterion, cs, i, e)) return false;
        uint32_t axis[2] = {0, 0};
        const bool has_normal = pfrepFanAxis(cs, i, r, axis);
        const uint32_t cone = pfrepLoad16(e.record + 8);
        uint32_t coded[2] = {cone & 63, (cone >> 6) & 63};
        for (int a = 0; a < 2; ++a)
            if (!pfrepCodeField(c, models.criterion.cone_axis[a][has_normal ? 1 : 0], axis[a], 63, &coded[a])) return false;
        r[6] = e.record[6];
        r[7] = e.record[7];
        pfrepStore16(r + 8, coded[0] | (coded[1] << 6) | (cone & 0xF000u));
    }
    return true;
}

inline void pfrep4Store32(uint8_t* p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = uint8_t(v >> (8 * k));
}

/// The format 2 header, directory, entry offsets and entries into `out` (decoded_size bytes,
/// records already written).
inline void pfrep4WriteBlob(const Pfrep4State& s, uint8_t* out) {
    const Pfrep4Header& h = s.h;
    pfrep4Store32(out, format::kPfrepMagic);
    pfrep4Store32(out + 4, format::kPfrepVersion);
    pfrep4Store32(out + 8, h.vertex_count);
    pfrep4Store32(out + 12, h.removed_count);
    pfrep4Store32(out + 16, s.block_shift);
    pfrep4Store32(out + 20, h.level0_triangles);
    for (int a = 0; a < 3; ++a) {
        std::memcpy(out + 24 + 4 * a, &h.position_min[a], 4);
        std::memcpy(out + 36 + 4 * a, &h.position_step[a], 4);
    }
    std::memcpy(out + 48, &h.error_unit, 4);
    pfrep4Store32(out + 52, h.decoded_size);
    pfrep4Store32(out + 56, s.block_count);
    pfrep4Store32(out + 60, 0);
    uint32_t* neighbours = s.work + 6 * uint64_t(kPfrepMaxFan);
    for (uint32_t b = 0; b < s.block_count; ++b) {
        pfrep4Store32(out + format::kPfrepHeaderSize + size_t(b) * 4, s.block_offset[b]);
        const uint32_t lo = b << s.block_shift;
        const uint32_t hi = uint32_t(std::min<uint64_t>(uint64_t(lo) + (uint64_t(1) << s.block_shift), h.vertex_count));
        uint8_t* rel = out + s.block_offset[b] + size_t(hi - lo) * format::kPfrepVertexRecordSize;
        uint8_t* stream = rel + size_t(hi - lo) * 2;
        for (uint32_t i = lo; i < hi; ++i) {
            pfrepStore16(rel + size_t(i - lo) * 2, s.entry_offset[i] - s.entry_offset[lo]);
            PfrepEntry e;
            pfrep4Entry(s, i, e, neighbours);
            pfrepWriteEntry(e, i, stream + (s.entry_offset[i] - s.entry_offset[lo]));
        }
        std::memset(stream + (s.entry_offset[hi] - s.entry_offset[lo]), 0, format::kPfrepStreamPadding);
    }
}

} // namespace detail
} // namespace lodrt
