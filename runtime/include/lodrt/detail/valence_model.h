#pragma once
// Model state the .lbm encoder (baker/src/codec) and decoder (runtime/src/valence_decoder.cpp) must
// update identically, kept in one place so the two cannot drift apart (Draco's *_shared.h split).
// Not part of the runtime's API.
//
// Connectivity is the valence-driven conquest of Touma & Gotsman ("Triangle Mesh Compression",
// Graphics Interface 1998) with the focus choice of Alliez & Desbrun ("Valence-Driven Connectivity
// Encoding for 3D Meshes", Eurographics 2001), run by ONE engine (Conquest) for both sides: the
// encoder plugs in an Io that looks at the real mesh and writes symbols, the decoder one that reads
// them. docs/format/valence.md describes the same steps in words.
//
// Terms. The coded mesh is closed (every boundary loop is capped by a dummy vertex) and manifold.
// The conquered region is bounded by active lists: cyclic lists of nodes, each node a vertex plus
// the wedge of still unconquered triangles around it between its two front edges. node.free counts
// the edges still to be added inside that wedge (0 = its wedge is one triangle). A vertex has one
// node per wedge (a split or merge gives it two). For the front edge k -> next(k) of node K,
// node.corner is the corner opposite that edge in the conquered triangle.
//
//        x            Each step adds the triangle across the focus F's front edge f -> n:
//       / \           (n, f, x), x = a new vertex (add), a vertex of the same list (split) or of
//      /   \          a stacked list (merge). A node whose wedge is one triangle is closed:
//     f --- n         triangle (next, k, prev), and the node leaves its list.

#include <cmath>
#include <cstddef>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "lodrt/format.h"
#include "lodrt/result.h"
#include "lodrt/valence.h"

namespace lodrt {
namespace detail {

constexpr uint32_t kNone = 0xFFFFFFFFu;

/// Sets every adaptive binary probability to its initial value.
inline void initRangeProbs(uint32_t* probs, size_t n) {
    for (size_t i = 0; i < n; ++i) probs[i] = format::kRangeStateInit;
}

/// The 12-bit probability of a 0 bit that model state `s` codes with (format.h, "Binary range coder").
/// The estimates stay in [kRangeStateMin, kRangeStateMax], so p is in [16, 4080] without a clamp and
/// either outcome leaves range >= 2^16: one byte of renormalisation always suffices.
inline uint32_t rangeProb(uint32_t s) {
    return ((s & 0xFFFFu) + (s >> 16)) >> (17 - format::kRangeProbBits);
}

/// Model state after coding a bit given as a mask (all ones for 1, zero for 0). Both outcomes are
/// computed and one selected without a branch: the bits are unpredictable.
inline uint32_t rangeUpdateMasked(uint32_t s, uint32_t mask) {
    const uint32_t fast = s & 0xFFFFu, slow = s >> 16;
    using format::kRangeStateMax;
    using format::kRangeStateMin;
    const uint32_t one = (fast - ((fast - kRangeStateMin) >> format::kRangeFastShift)) |
                         ((slow - ((slow - kRangeStateMin) >> format::kRangeSlowShift)) << 16);
    const uint32_t zero = (fast + ((kRangeStateMax - fast) >> format::kRangeFastShift)) |
                          ((slow + ((kRangeStateMax - slow) >> format::kRangeSlowShift)) << 16);
    return zero ^ ((zero ^ one) & mask);
}

/// Model state after coding bit b.
inline uint32_t rangeUpdate(uint32_t s, uint32_t b) { return rangeUpdateMasked(s, 0u - uint32_t(b != 0)); }

/// Adaptive multi-symbol model (format.h, "Multi-symbol adaptive models"): cum[i] is the coded
/// cumulative frequency of symbols < i out of 2^kRangeCdfBits (cum[0] = 0, cum[N] = 2^kRangeCdfBits);
/// symbol i codes with width cum[i+1] - cum[i] >= kRangeCdfMinFreq (the last one also gets the range
/// coder's rounding slack).
template <uint32_t N, uint32_t LastRate> struct CdfModel {
    static constexpr uint32_t kN = N;
    uint16_t cum[kN + 1];
    uint16_t uses;
    void init() {
        using namespace format;
        constexpr uint32_t spare = (1u << kRangeCdfBits) - kN * kRangeCdfMinFreq;
        for (uint32_t i = 0; i <= kN; ++i) cum[i] = uint16_t(spare * i / kN + kRangeCdfMinFreq * i);
        uses = 0;
    }
    /// After coding symbol s: every cum[i] (0 < i < N) moves a 2^-rate step toward its bound,
    /// the upper one (2^kRangeCdfBits - kRangeCdfMinFreq * (N - i)) for i > s, the lower one
    /// (kRangeCdfMinFreq * i) for i <= s. Order and minimum widths are kept.
    inline void update(uint32_t s) {
        using namespace format;
        const uint32_t rate = uses < kRangeCdfRateStep       ? kRangeCdfRateFirst
                              : uses < 2 * kRangeCdfRateStep ? kRangeCdfRateFirst + 1
                                                             : LastRate;
        uses = uint16_t(uses < 2 * kRangeCdfRateStep ? uses + 1 : uses);
#if defined(__SSE2__)
        // The same arithmetic in 16-bit lanes (every intermediate value is in [0, 2^15)): blocks of
        // 8 entries from cum[1], then one block ending at cum[N - 1] for the rest. All blocks are
        // computed from the old values; the last block is stored first, so entries it shares with
        // the one before are overwritten with the same value.
        const __m128i shift = _mm_cvtsi32_si128(int(rate));
        const __m128i sv = _mm_set1_epi16(int16_t(s));
        __m128i out[kBlocks + 1];
        for (uint32_t b = 0; b <= kBlocks; ++b) {
            if (b == kBlocks && !kTail) break;
            const uint32_t start = b < kBlocks ? 1 + 8 * b : kN - 8;
            const __m128i idx = _mm_add_epi16(_mm_set1_epi16(int16_t(start)), _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7));
            const __m128i lo = _mm_slli_epi16(idx, 3);
            const __m128i hi =
                _mm_add_epi16(lo, _mm_set1_epi16(int16_t((1u << kRangeCdfBits) - kRangeCdfMinFreq * kN)));
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&cum[start]));
            const __m128i up = _mm_add_epi16(c, _mm_sra_epi16(_mm_sub_epi16(hi, c), shift));
            const __m128i down = _mm_sub_epi16(c, _mm_sra_epi16(_mm_sub_epi16(c, lo), shift));
            const __m128i above = _mm_cmpgt_epi16(idx, sv);
            out[b] = _mm_or_si128(_mm_and_si128(above, up), _mm_andnot_si128(above, down));
        }
        if (kTail) _mm_storeu_si128(reinterpret_cast<__m128i*>(&cum[kN - 8]), out[kBlocks]);
        for (uint32_t b = 0; b < kBlocks; ++b) _mm_storeu_si128(reinterpret_cast<__m128i*>(&cum[1 + 8 * b]), out[b]);
#else
        for (uint32_t i = 1; i < kN; ++i) {
            const int32_t c = cum[i];
            const int32_t hi = int32_t((1u << kRangeCdfBits) - kRangeCdfMinFreq * (kN - i));
            const int32_t lo = int32_t(kRangeCdfMinFreq * i);
            const int32_t up = c + ((hi - c) >> rate), down = c - ((c - lo) >> rate);
            cum[i] = uint16_t(i > s ? up : down);
        }
#endif
    }
    /// The number of i in 1..N-1 with cum[i] <= slot: the symbol whose interval holds `slot`.
    inline uint32_t find(uint32_t slot) const {
#if defined(__SSE2__)
        // Every cum[i] (i < N) is at most 2^15 - kRangeCdfMinFreq, so a slot clamped to 2^15 - 2 gives the
        // same count in signed 16-bit lanes.
        const uint32_t clamped = slot < 0x7FFEu ? slot : 0x7FFEu;
        const __m128i limit = _mm_set1_epi16(int16_t(clamped + 1));
        __m128i acc = _mm_setzero_si128();
        for (uint32_t b = 0; b < kBlocks; ++b) {
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&cum[1 + 8 * b]));
            acc = _mm_sub_epi16(acc, _mm_cmplt_epi16(c, limit));
        }
        if (kTail) {
            // Lanes of the last block that an earlier block already counted are masked off.
            const __m128i idx = _mm_add_epi16(_mm_set1_epi16(int16_t(kN - 8)), _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7));
            const __m128i fresh = _mm_cmpgt_epi16(idx, _mm_set1_epi16(int16_t(8 * kBlocks)));
            const __m128i c = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&cum[kN - 8]));
            acc = _mm_sub_epi16(acc, _mm_and_si128(fresh, _mm_cmplt_epi16(c, limit)));
        }
        const __m128i sums = _mm_sad_epu8(acc, _mm_setzero_si128());
        return uint32_t(_mm_cvtsi128_si32(sums)) + uint32_t(_mm_extract_epi16(sums, 4));
#else
        uint32_t s = 0;
        for (uint32_t i = 1; i < kN; ++i) s += cum[i] <= slot ? 1u : 0u;
        return s;
#endif
    }

private:
    static_assert(kN >= 9 && kN <= 256, "blocks of 8 entries");
    static constexpr uint32_t kBlocks = (kN - 1) / 8;           // full blocks from cum[1]
    static constexpr bool kTail = (kN - 1) % 8 != 0;            // entries left after them
};

using ResidualLengthModel = CdfModel<format::kValenceResidualSymbols, format::kRangeCdfRateLast>;
using ConnectivitySymbolModel = CdfModel<(1u << format::kValenceSymbolTreeBits), format::kRangeCdfRateLastConnectivity>;

/// What sits across the focus's front edge.
enum class VertexKind : uint32_t { Add = 0, Dummy = 1, Split = 2, Merge = 3 };
struct VertexSymbol {
    VertexKind kind = VertexKind::Add;
    uint32_t valence = 0; // Add / Dummy
    uint32_t offset = 0;  // Split: steps from the focus along next (>= 3); Merge: steps from the list's head
    uint32_t list = 0;    // Merge: 0 = top of the stack
    uint32_t free_a = 0;  // Split / Merge: free edges left in the wedge of x on the focus's side
};

/// Flat arrays of the conquest; sizes in elements, all owned by the caller.
struct ConquestArrays {
    uint32_t* corner_vertex = nullptr; // 3 * max_triangles
    uint32_t* corner_opposite = nullptr;
    uint32_t* vertex_flags = nullptr;  // max_vertices: bit 0 dummy; bits 1.. open node count
    uint32_t* vertex_corner = nullptr; // max_vertices: one corner of the vertex
    uint32_t* vertex_valence = nullptr;
    uint32_t* node_vertex = nullptr; // max_nodes = max_vertices + max_triangles
    uint32_t* node_prev = nullptr;
    uint32_t* node_next = nullptr;
    uint32_t* node_free = nullptr;
    uint32_t* node_corner = nullptr;
    uint32_t* completion = nullptr; // max_vertices: vertices in the order their last node closed
    uint32_t* stack_head = nullptr; // max_triangles
    uint32_t* stack_size = nullptr;
    uint32_t max_vertices = 0;
    uint32_t max_triangles = 0;
};

constexpr uint32_t kFlagDummy = 1u;
constexpr uint32_t kFlagOpenOne = 2u;
/// Nodes within this many steps on each side of a closed focus are candidates for the next focus
/// (a wider window finds a better next focus, so symbols cost fewer bits; beyond 8 steps the gain
/// ends while the search still grows).
constexpr uint32_t kFocusWindow = 8;
constexpr uint32_t kValenceContexts = 33; // 32 focus contexts + 1 for the seed triangle
constexpr uint32_t kSeedContext = 32;

/// Context of the symbol coded at focus F: the valences of the front edge's two vertices (their sum,
/// 8 buckets) and the focus's free edges (1, 2, 3, 4+). It predicts the symbol better than the focus
/// valence alone or the previous valence, so the stream is smaller (docs/benchmarks.md, "Valence codec
/// against Draco").
inline uint32_t valenceContext(uint32_t focus_valence, uint32_t focus_free, uint32_t next_valence) {
    uint32_t sum = focus_valence + next_valence;
    sum = sum < 8 ? 0 : (sum > 15 ? 7 : sum - 8);
    const uint32_t free = focus_free >= 4 ? 3 : (focus_free == 0 ? 0 : focus_free - 1);
    return sum * 4 + free;
}

/// The conquest engine. `Io` supplies what the stream says (decoder) or what the mesh says (encoder):
///   bool moreComponents();                                 start another component?
///   Result seedVertex(VertexSymbol*);                     kind Add or Dummy
///   Result vertexSymbol(uint32_t context, uint32_t focus, VertexSymbol*);
///   Result onTriangle(uint32_t t, uint32_t attach_corner); after triangle t was created across the
///                                                          front edge whose corner was attach_corner
///                                                          (kNone for a seed)
template <class Io> class Conquest {
public:
    ConquestArrays a;
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    uint32_t node_count = 0;
    uint32_t stack_count = 0;
    uint32_t completion_count = 0;

    Result run(Io& io) {
        while (io.moreComponents()) {
            Result r = component(io);
            if (r != Result::Ok) return r;
        }
        return Result::Ok;
    }

    uint32_t next(uint32_t k) const { return a.node_next[k]; }

private:
    uint32_t newVertex(const VertexSymbol& s) {
        uint32_t v = vertex_count++;
        a.vertex_flags[v] = s.kind == VertexKind::Dummy ? kFlagDummy : 0;
        a.vertex_valence[v] = s.valence;
        a.vertex_corner[v] = kNone;
        return v;
    }
    uint32_t newNode(uint32_t v, uint32_t free) {
        uint32_t k = node_count++;
        a.node_vertex[k] = v;
        a.node_free[k] = free;
        a.node_corner[k] = kNone;
        a.vertex_flags[v] += kFlagOpenOne;
        return k;
    }
    uint32_t newTriangle(uint32_t v0, uint32_t v1, uint32_t v2) {
        uint32_t t = triangle_count++;
        uint32_t* cv = &a.corner_vertex[3 * size_t(t)];
        cv[0] = v0;
        cv[1] = v1;
        cv[2] = v2;
        uint32_t* co = &a.corner_opposite[3 * size_t(t)];
        co[0] = co[1] = co[2] = kNone;
        for (int i = 0; i < 3; ++i)
            if (a.vertex_corner[cv[i]] == kNone) a.vertex_corner[cv[i]] = 3 * t + uint32_t(i);
        return t;
    }
    void glue(uint32_t c, uint32_t d) {
        a.corner_opposite[c] = d;
        a.corner_opposite[d] = c;
    }
    bool room(uint32_t vertices, uint32_t triangles, uint32_t nodes) const {
        return vertex_count + uint64_t(vertices) <= a.max_vertices &&
               triangle_count + uint64_t(triangles) <= a.max_triangles &&
               node_count + uint64_t(nodes) <= uint64_t(a.max_vertices) + a.max_triangles;
    }
    bool validNew(const VertexSymbol& s) const {
        return (s.kind == VertexKind::Add || s.kind == VertexKind::Dummy) && s.valence >= 2 && s.valence < (1u << 28);
    }
    // A vertex is complete (all its triangles known) when its last node closes; positions are coded
    // in that order, when most neighbours of a vertex are known (docs/format/valence.md "Positions").
    void closeNode(uint32_t k) {
        const uint32_t v = a.node_vertex[k];
        a.vertex_flags[v] -= kFlagOpenOne;
        if ((a.vertex_flags[v] >> 1) == 0 && completion_count < a.max_vertices) a.completion[completion_count++] = v;
    }

    Result component(Io& io) {
        if (!room(3, 1, 3)) return Result::CorruptStream;
        uint32_t v[3], k[3];
        for (int i = 0; i < 3; ++i) {
            VertexSymbol s;
            Result r = io.seedVertex(&s);
            if (r != Result::Ok) return r;
            if (!validNew(s)) return Result::CorruptStream;
            v[i] = newVertex(s);
            k[i] = newNode(v[i], s.valence - 2);
        }
        uint32_t t = newTriangle(v[0], v[1], v[2]);
        for (int i = 0; i < 3; ++i) {
            a.node_next[k[i]] = k[(i + 1) % 3];
            a.node_prev[k[i]] = k[(i + 2) % 3];
            a.node_corner[k[i]] = 3 * t + uint32_t((i + 2) % 3); // opposite edge v[i] -> v[i+1]
        }
        Result r = io.onTriangle(t, kNone);
        if (r != Result::Ok) return r;
        uint32_t focus = k[0], size = 3;
        for (;;) {
            r = conquerList(io, focus, size);
            if (r != Result::Ok) return r;
            if (stack_count == 0) return Result::Ok;
            --stack_count;
            focus = a.stack_head[stack_count];
            size = a.stack_size[stack_count];
        }
    }

    // Conquers the list containing `focus` until it closes.
    Result conquerList(Io& io, uint32_t focus, uint32_t size) {
        for (;;) {
            const uint32_t f = focus, n = a.node_next[f], p = a.node_prev[f];
            uint32_t k = kNone;
            if (a.node_free[f] == 0)
                k = f;
            else if (a.node_free[n] == 0)
                k = n;
            else if (a.node_free[p] == 0)
                k = p;
            if (k != kNone) {
                const uint32_t kn = a.node_next[k], kp = a.node_prev[k];
                if (!room(0, 1, 0)) return Result::CorruptStream;
                const uint32_t attach = a.node_corner[k];
                const uint32_t t = newTriangle(a.node_vertex[kn], a.node_vertex[k], a.node_vertex[kp]);
                glue(3 * t + 2, attach);
                glue(3 * t + 0, a.node_corner[kp]);
                if (size == 3) {
                    // The last triangle of the region: its third edge is the list edge kn -> kp.
                    if (a.node_free[kn] != 0 || a.node_free[kp] != 0) return Result::CorruptStream;
                    glue(3 * t + 1, a.node_corner[kn]);
                    closeNode(k);
                    closeNode(kn);
                    closeNode(kp);
                    return io.onTriangle(t, attach);
                }
                if (a.node_free[kn] == 0 || a.node_free[kp] == 0) return Result::CorruptStream;
                --a.node_free[kn];
                --a.node_free[kp];
                a.node_corner[kp] = 3 * t + 1;
                a.node_next[kp] = kn;
                a.node_prev[kn] = kp;
                closeNode(k);
                --size;
                if (k == f) focus = pickFocus(kn, kp);
                Result r = io.onTriangle(t, attach);
                if (r != Result::Ok) return r;
                continue;
            }
            VertexSymbol s;
            const uint32_t fv = a.node_vertex[f];
            Result r = io.vertexSymbol(
                valenceContext(a.vertex_valence[fv], a.node_free[f], a.vertex_valence[a.node_vertex[n]]), f, &s);
            if (r != Result::Ok) return r;
            const uint32_t attach = a.node_corner[f];
            uint32_t x, t;
            if (s.kind == VertexKind::Add || s.kind == VertexKind::Dummy) {
                if (!validNew(s) || !room(1, 1, 1)) return Result::CorruptStream;
                x = newVertex(s);
                const uint32_t xk = newNode(x, s.valence - 2);
                t = newTriangle(a.node_vertex[n], fv, x);
                a.node_corner[xk] = 3 * t + 1;
                a.node_next[f] = xk;
                a.node_prev[xk] = f;
                a.node_next[xk] = n;
                a.node_prev[n] = xk;
                ++size;
            } else {
                uint32_t xk = kNone, other_size = 0;
                if (s.kind == VertexKind::Split) {
                    if (s.offset < 3 || s.offset + 2 > size) return Result::CorruptStream;
                    xk = f;
                    for (uint32_t i = 0; i < s.offset; ++i) xk = a.node_next[xk];
                } else if (s.kind == VertexKind::Merge) {
                    if (s.list >= stack_count) return Result::CorruptStream;
                    const uint32_t si = stack_count - 1 - s.list;
                    other_size = a.stack_size[si];
                    if (s.offset >= other_size) return Result::CorruptStream;
                    xk = a.stack_head[si];
                    for (uint32_t i = 0; i < s.offset; ++i) xk = a.node_next[xk];
                    for (uint32_t i = si; i + 1 < stack_count; ++i) {
                        a.stack_head[i] = a.stack_head[i + 1];
                        a.stack_size[i] = a.stack_size[i + 1];
                    }
                    --stack_count;
                } else {
                    return Result::CorruptStream;
                }
                if (a.node_free[xk] < 2 || s.free_a > a.node_free[xk] - 2 || !room(0, 1, 1))
                    return Result::CorruptStream;
                x = a.node_vertex[xk];
                const uint32_t x2 = newNode(x, a.node_free[xk] - 2 - s.free_a);
                a.node_free[xk] = s.free_a;
                t = newTriangle(a.node_vertex[n], fv, x);
                a.node_corner[x2] = 3 * t + 1;
                const uint32_t xp = a.node_prev[xk];
                a.node_next[xp] = x2;
                a.node_prev[x2] = xp;
                a.node_next[x2] = n;
                a.node_prev[n] = x2;
                a.node_next[f] = xk;
                a.node_prev[xk] = f;
                if (s.kind == VertexKind::Split) {
                    // The part after the focus's old neighbour waits on the stack.
                    if (stack_count >= a.max_triangles) return Result::CorruptStream;
                    a.stack_head[stack_count] = n;
                    a.stack_size[stack_count] = s.offset;
                    ++stack_count;
                    size = size - s.offset + 1;
                } else {
                    size = size + other_size + 1;
                }
            }
            glue(3 * t + 2, attach);
            a.node_corner[f] = 3 * t + 0;
            --a.node_free[f];
            --a.node_free[n];
            r = io.onTriangle(t, attach);
            if (r != Result::Ok) return r;
        }
    }

    // Alliez-Desbrun: the next focus is the node with the fewest free edges, searched within
    // kFocusWindow steps of the closed focus (ties: nearer first, then the `next` side).
    uint32_t pickFocus(uint32_t after, uint32_t before) const {
        uint32_t best = after, best_free = a.node_free[after];
        uint32_t fwd = after, bwd = before;
        for (uint32_t i = 0; i < kFocusWindow && best_free > 0; ++i) {
            if (i > 0) {
                fwd = a.node_next[fwd];
                bwd = a.node_prev[bwd];
            }
            if (a.node_free[fwd] < best_free) {
                best = fwd;
                best_free = a.node_free[fwd];
            }
            if (a.node_free[bwd] < best_free) {
                best = bwd;
                best_free = a.node_free[bwd];
            }
        }
        return best;
    }
};

/// Adds the normal of triangle `f` (the cross product of its edges on the quantized positions
/// `qpos`, exact in integers) to the sums of its three vertices: the normal predictor's input
/// (docs/format/valence.md, "Normals"). Summation order does not matter in integers.
inline void addFaceNormal(const int32_t* qpos, const uint32_t f[3], int64_t* sum) {
    const int32_t* p0 = &qpos[3 * size_t(f[0])];
    const int32_t* p1 = &qpos[3 * size_t(f[1])];
    const int32_t* p2 = &qpos[3 * size_t(f[2])];
    const int64_t e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    const int64_t e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    const int64_t n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    for (int c = 0; c < 3; ++c)
        for (int j = 0; j < 3; ++j) sum[3 * size_t(f[c]) + size_t(j)] += n[j];
}

/// Prediction `p` of vertex x's octahedral normal (`bits` per component): the sum of its faces'
/// normals `s3`, encoded; for a vertex without one, the previous vertex's coded normal (`qnorm`, two
/// components per vertex), and the centre of the octahedron for the first.
inline void predictNormal(const int64_t* s3, const uint32_t* qnorm, size_t x, uint32_t bits, uint32_t p[2]) {
    if (s3[0] != 0 || s3[1] != 0 || s3[2] != 0) {
        const float fs[3] = {float(s3[0]), float(s3[1]), float(s3[2])};
        octahedralEncode(fs, bits, p);
    } else if (x > 0) {
        p[0] = qnorm[2 * (x - 1)];
        p[1] = qnorm[2 * (x - 1) + 1];
    } else {
        p[0] = p[1] = uint32_t(1) << (bits - 1);
    }
}

/// Integer division rounded half away from zero.
inline int64_t divRound(int64_t sum, int64_t count) {
    return sum >= 0 ? (sum + count / 2) / count : -((-sum + count / 2) / count);
}

/// Where the position pass finds each coded vertex's prediction, computed from the connectivity
/// alone (docs/format/valence.md "Positions", Order and Prediction) so that the residual pass reads
/// it sequentially instead of walking the corner table between two residual decodes.
/// Capacities (elements): order, count, neighbour: vertex_count; triples: 3 * max_triples.
struct PositionPlan {
    uint32_t* order = nullptr;     // coded vertices in coding order
    uint32_t* count = nullptr;     // per entry of order: its parallelograms (triples)
    uint32_t* neighbour = nullptr; // per entry: the first known neighbour a met in the walk, kNone if none
    uint32_t* triples = nullptr;   // (a, b, w) of every parallelogram a + b - w, entry after entry
    uint8_t* boundary = nullptr;   // optional, per entry: 1 when the vertex has a dummy neighbour
    uint32_t max_triples = 0;
    uint32_t ordered = 0;      // entries of order filled
    uint32_t triple_count = 0; // triples filled
};

/// Fills `plan`. Order (like Draco's prediction-degree traversal): the next vertex is taken from the
/// highest non-empty of three stacks, where a vertex is pushed on stack d when d of its triangles
/// have both other vertices already ordered (d = 1, 2, 3+); when all are empty, the first unordered
/// vertex in conquest order. Dummy vertices are never ordered. Prediction of v, over the same walk
/// around v with "known" = ordered before v: every corner whose a, b and opposite vertex w are known
/// gives a triple; the first known a is the neighbour. `state` (bytes), `stack0..2` (vertex_count
/// each) are scratch. False when the corner cycles are broken or the triples overflow (a corrupt
/// stream).
inline bool planPositions(const uint32_t* cv, const uint32_t* opp, const uint32_t* vertex_corner,
                          const uint32_t* vertex_flags, const uint32_t* valence, uint32_t vertex_count,
                          uint8_t* state, uint32_t* stack0, uint32_t* stack1, uint32_t* stack2, PositionPlan* plan) {
    // One byte per vertex, so a neighbour costs one load: bit 7 ordered, bit 6 dummy (never ordered,
    // never pushed: it reads as ordered for the triples test below only through bit 7, which it never
    // gets), bits 0..2 the count of its triangles with both other vertices ordered, saturated at 4.
    constexpr uint8_t kOrdered = 0x80, kDummy = 0x40, kDegree = 0x07;
    for (uint32_t v = 0; v < vertex_count; ++v) state[v] = (vertex_flags[v] & kFlagDummy) ? kDummy : 0;
    uint32_t top[3] = {0, 0, 0};
    uint32_t* stack[3] = {stack0, stack1, stack2};
    uint32_t count = 0, scan = 0, triples = 0;
    for (;;) {
        uint32_t v = kNone;
        for (int level = 2; level >= 0 && v == kNone; --level) {
            while (top[level] > 0) {
                const uint32_t u = stack[level][--top[level]];
                if (!(state[u] & kOrdered)) {
                    v = u;
                    break;
                }
            }
        }
        if (v == kNone) {
            while (scan < vertex_count && (state[scan] & (kOrdered | kDummy))) ++scan;
            if (scan == vertex_count) break;
            v = scan;
        }
        state[v] |= kOrdered;
        plan->order[count] = v;
        uint32_t n = 0, neighbour = kNone, boundary = 0;
        // Each triangle (v, a, b) with exactly one of a, b ordered now has both others of the
        // unordered one ordered.
        const uint32_t c0 = vertex_corner[v];
        if (c0 == kNone) return false;
        const uint32_t steps = valence[v];
        uint32_t c = c0, i3 = c0 % 3; // i3: c's place in its triangle, carried along the walk
        for (uint32_t step = 0;; ++step) {
            if (step > steps) return false;
            const uint32_t t3 = c - i3;
            const uint32_t cn = i3 == 2 ? t3 : c + 1, cp = i3 == 0 ? t3 + 2 : c - 1;
            const uint32_t va = cv[cn], vb = cv[cp];
            const uint32_t sa = state[va], sb = state[vb];
            boundary |= (sa | sb) & kDummy;
            const uint32_t oa = sa & kOrdered, ob = sb & kOrdered;
            if (oa != ob) {
                const uint32_t u = oa ? vb : va;
                const uint32_t su = oa ? sb : sa;
                if (!(su & kDummy)) {
                    const uint32_t d = (su & kDegree) + 1;
                    if (d <= 4) state[u] = uint8_t((su & ~uint32_t(kDegree)) | d);
                    if (d <= 3) stack[d - 1][top[d - 1]++] = u;
                }
            } else if (oa && va != v && vb != v) {
                const uint32_t o = opp[c];
                if (o == kNone) return false;
                const uint32_t w = cv[o];
                if ((state[w] & kOrdered) && w != v) {
                    if (triples >= plan->max_triples) return false;
                    uint32_t* t = &plan->triples[3 * size_t(triples++)];
                    t[0] = va;
                    t[1] = vb;
                    t[2] = w;
                    ++n;
                }
            }
            if (neighbour == kNone && oa && va != v) neighbour = va;
            // Swing to the next corner around v: next(opposite(next(c))).
            const uint32_t o = opp[cn];
            if (o == kNone) return false;
            const uint32_t o3 = o % 3;
            c = o3 == 2 ? o - 2 : o + 1;
            i3 = o3 == 2 ? 0 : o3 + 1;
            if (c == c0) break;
        }
        plan->count[count] = n;
        plan->neighbour[count] = neighbour;
        if (plan->boundary) plan->boundary[count] = boundary ? 1 : 0;
        ++count;
    }
    plan->ordered = count;
    plan->triple_count = triples;
    return true;
}

/// Prediction of a vertex from its plan entry (`n` triples at `t`, `neighbour`): the mean of the
/// parallelograms rounded half away from zero, else the neighbour's position, else `fallback`. *scale
/// is the largest coordinate difference between a and b of the first triple (0 without triples).
/// With `Spread`, spread[j] is the largest minus the smallest parallelogram value of component j (0
/// when n < 2); without it, spread is not written.
template <bool Spread>
inline void predictFromPlanOf(const int32_t* qpos, const uint32_t* t, uint32_t n, uint32_t neighbour,
                              const int32_t fallback[3], int32_t out[3], uint32_t* scale, uint32_t spread[3]) {
    uint32_t sc = 0;
    if (n > 0) {
        // Coordinates are below 2^16, so a parallelogram a + b - w lies in (-2^16, 2^17): 32 bits.
        int64_t sum[3] = {0, 0, 0};
        int32_t lo[3], hi[3];
        {
            const int32_t* pa = &qpos[3 * size_t(t[0])];
            const int32_t* pb = &qpos[3 * size_t(t[1])];
            const int32_t* pw = &qpos[3 * size_t(t[2])];
            for (int j = 0; j < 3; ++j) {
                const int32_t p = pa[j] + pb[j] - pw[j];
                sum[j] = p;
                lo[j] = hi[j] = p;
                const uint32_t d = uint32_t(pa[j] > pb[j] ? pa[j] - pb[j] : pb[j] - pa[j]);
                if (d > sc) sc = d;
            }
        }
        for (uint32_t i = 1; i < n; ++i) {
            const uint32_t* e = t + 3 * size_t(i);
            const int32_t* pa = &qpos[3 * size_t(e[0])];
            const int32_t* pb = &qpos[3 * size_t(e[1])];
            const int32_t* pw = &qpos[3 * size_t(e[2])];
            for (int j = 0; j < 3; ++j) {
                const int32_t p = pa[j] + pb[j] - pw[j];
                sum[j] += p;
                if (Spread) {
                    lo[j] = p < lo[j] ? p : lo[j];
                    hi[j] = p > hi[j] ? p : hi[j];
                }
            }
        }
        if (n == 1) {
            for (int j = 0; j < 3; ++j) out[j] = int32_t(sum[j]);
        } else {
            for (int j = 0; j < 3; ++j) {
                // divRound, with a 32-bit division whenever the magnitude fits (always, unless n is huge).
                const uint64_t mag = uint64_t(sum[j] >= 0 ? sum[j] : -sum[j]) + n / 2;
                const uint64_t q = mag <= 0xFFFFFFFFu ? uint64_t(uint32_t(mag) / n) : mag / n;
                out[j] = sum[j] >= 0 ? int32_t(q) : -int32_t(q);
            }
        }
        if (Spread)
            for (int j = 0; j < 3; ++j) spread[j] = uint32_t(hi[j] - lo[j]);
    } else {
        if (neighbour != kNone) {
            for (int j = 0; j < 3; ++j) out[j] = qpos[3 * size_t(neighbour) + size_t(j)];
        } else {
            for (int j = 0; j < 3; ++j) out[j] = fallback[j];
        }
        if (Spread) spread[0] = spread[1] = spread[2] = 0;
    }
    *scale = sc;
}

/// predictFromPlanOf with the spreads.
inline void predictFromPlan(const int32_t* qpos, const uint32_t* t, uint32_t n, uint32_t neighbour,
                            const int32_t fallback[3], int32_t out[3], uint32_t* scale, uint32_t spread[3]) {
    predictFromPlanOf<true>(qpos, t, n, neighbour, fallback, out, scale, spread);
}

/// Bit length of x (0 for 0).
inline uint32_t bitLength(uint32_t x) {
#if defined(__GNUC__) || defined(__clang__)
    return x == 0 ? 0u : 32u - uint32_t(__builtin_clz(x));
#else
    uint32_t k = 0;
    while (x != 0) {
        ++k;
        x >>= 1;
    }
    return k;
#endif
}

/// Context of a position residual from the gate-edge scale (bit length, 0..11).
inline uint32_t scaleContext(uint32_t scale, uint32_t count) {
    uint32_t b = bitLength(scale);
    b = b > 9 ? 9 : b;
    return count >= 2 ? b + 10 : b; // 20 contexts
}
constexpr uint32_t kPositionLengthBuckets = 12;
constexpr uint32_t kPositionBaseContexts = 20 + 2 * kPositionLengthBuckets;
/// Spread contexts (format version 6, per component when its header flag is set, for vertices with
/// two or more parallelograms): the bit length of the component's parallelogram spread (capped at 11)
/// for x, and that times the earlier components' largest residual length (capped at 11) for y and z.
constexpr uint32_t kPositionSpreadBuckets = 12;
constexpr uint32_t kPositionContexts =
    kPositionBaseContexts + kPositionSpreadBuckets + kPositionLengthBuckets * kPositionSpreadBuckets;

/// Context of a position residual. x (earlier_length == kNone): the gate-edge context. y and z: the
/// bit length of the vertex's earlier components' largest residual (capped at 11), and whether two or
/// more parallelograms were averaged. The three errors come from one misprediction of the vertex, so
/// the earlier magnitude predicts the later ones better than the gate edge does.
inline uint32_t positionContext(uint32_t scale_ctx, uint32_t earlier_length) {
    if (earlier_length == kNone) return scale_ctx;
    const uint32_t b = earlier_length < kPositionLengthBuckets ? earlier_length : kPositionLengthBuckets - 1;
    return 20 + (scale_ctx >= 10 ? kPositionLengthBuckets : 0) + b;
}

/// Context of a position residual of a component coded with spread contexts (its header flag set):
/// positionContext for a vertex with fewer than two parallelograms (scale_ctx < 10); else from
/// `spread`, the component's parallelogram spread (predictFromPlan), and for y and z the earlier
/// components' largest residual length. Where the parallelograms agree, the prediction is good.
inline uint32_t spreadContext(uint32_t scale_ctx, uint32_t earlier_length, uint32_t spread) {
    if (scale_ctx < 10) return positionContext(scale_ctx, earlier_length);
    uint32_t s = bitLength(spread);
    s = s < kPositionSpreadBuckets ? s : kPositionSpreadBuckets - 1;
    if (earlier_length == kNone) return kPositionBaseContexts + s;
    const uint32_t b = earlier_length < kPositionLengthBuckets ? earlier_length : kPositionLengthBuckets - 1;
    return kPositionBaseContexts + kPositionSpreadBuckets + b * kPositionSpreadBuckets + s;
}

/// Neighbour-coordinate ("snap") candidates of the three position components (docs/format/valence.md
/// "Positions"): for component j, among the a and b of the vertex's triples, then its neighbour, the
/// coordinate nearest the prediction pred[j] (ties: the smaller value). False without any (then for
/// every component). ctx[j] is the snap context: the bit length of |candidate - pred| (capped at 15)
/// times 5 plus the number of triple entries holding the candidate value (1 without triples, capped
/// at 4). Iso-surface meshes put every vertex on a grid edge, so two of its coordinates are grid
/// planes it shares with neighbours.
/// Only the components in `Mask` (bit j: component j) are computed; the others are left unset.
template <uint32_t Mask>
inline bool snapCandidatesOf(const int32_t* qpos, const uint32_t* t, uint32_t n, uint32_t neighbour,
                             const int32_t pred[3], int32_t candidate[3], uint32_t ctx[3]) {
    if (n == 0 && neighbour == kNone) return false;
    // Key: distance above, value below (values are < 2^16), so the smallest key is the nearest value,
    // ties to the smaller one. Branch-free minimum over the 2n triple entries and the neighbour.
    uint64_t best[3] = {~uint64_t(0), ~uint64_t(0), ~uint64_t(0)};
    auto key = [&](const int32_t* p, int j) {
        const int64_t d = int64_t(p[j]) - pred[j];
        return (uint64_t(d < 0 ? -d : d) << 17) | uint64_t(uint32_t(p[j]));
    };
    const uint32_t* end = t + 3 * size_t(n);
    for (const uint32_t* e = t; e != end; e += 3) {
        const int32_t* pa = &qpos[3 * size_t(e[0])];
        const int32_t* pb = &qpos[3 * size_t(e[1])];
        for (int j = 0; j < 3; ++j) {
            if (!((Mask >> j) & 1u)) continue;
            const uint64_t ka = key(pa, j), kb = key(pb, j);
            const uint64_t k = ka < kb ? ka : kb;
            best[j] = k < best[j] ? k : best[j];
        }
    }
    if (neighbour != kNone) {
        const int32_t* pn = &qpos[3 * size_t(neighbour)];
        for (int j = 0; j < 3; ++j) {
            if (!((Mask >> j) & 1u)) continue;
            const uint64_t k = key(pn, j);
            best[j] = k < best[j] ? k : best[j];
        }
    }
    uint32_t mult[3] = {1, 1, 1};
    if (n > 0) {
        mult[0] = mult[1] = mult[2] = 0;
        for (int j = 0; j < 3; ++j) candidate[j] = int32_t(best[j] & 0x1FFFFu);
        for (const uint32_t* e = t; e != end; e += 3) {
            const int32_t* pa = &qpos[3 * size_t(e[0])];
            const int32_t* pb = &qpos[3 * size_t(e[1])];
            for (int j = 0; j < 3; ++j)
                if ((Mask >> j) & 1u) mult[j] += uint32_t(pa[j] == candidate[j]) + uint32_t(pb[j] == candidate[j]);
        }
    }
    for (int j = 0; j < 3; ++j) {
        if (!((Mask >> j) & 1u)) continue;
        candidate[j] = int32_t(best[j] & 0x1FFFFu);
        const uint64_t d = best[j] >> 17;
        uint32_t b = bitLength(d > 0xFFFFFFFFu ? 0xFFFFFFFFu : uint32_t(d));
        b = b < format::kValenceSnapDistanceBuckets - 1 ? b : format::kValenceSnapDistanceBuckets - 1;
        const uint32_t m = mult[j] < format::kValenceSnapMultiplicity ? mult[j] : format::kValenceSnapMultiplicity - 1;
        ctx[j] = b * format::kValenceSnapMultiplicity + m;
    }
    return true;
}

/// snapCandidatesOf for a run-time component mask (1..7; 0 computes nothing and returns false).
inline bool snapCandidates(const int32_t* qpos, const uint32_t* t, uint32_t n, uint32_t neighbour,
                           const int32_t pred[3], uint32_t mask, int32_t candidate[3], uint32_t ctx[3]) {
    switch (mask & 7u) {
    case 1:
        return snapCandidatesOf<1>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 2:
        return snapCandidatesOf<2>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 3:
        return snapCandidatesOf<3>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 4:
        return snapCandidatesOf<4>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 5:
        return snapCandidatesOf<5>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 6:
        return snapCandidatesOf<6>(qpos, t, n, neighbour, pred, candidate, ctx);
    case 7:
        return snapCandidatesOf<7>(qpos, t, n, neighbour, pred, candidate, ctx);
    default:
        return false;
    }
}

/// Sign contexts of a residual: the sign class (0 zero, 1 positive, 2 negative) of the same component's
/// residual at the previously coded vertex, times 3, plus the class of this vertex's x residual (0 for
/// x itself). Parallelogram errors follow the local curvature, so neighbouring signs agree.
constexpr uint32_t kSignContexts = 9;
inline uint32_t signClass(int32_t r) {
    return r > 0 ? 1u : (r < 0 ? 2u : 0u);
}


/// Prediction of a UV or colour value (format version 7, docs/format/valence.md "Attributes") of vertex
/// v from its plan entry (`n` triples at `t`, `neighbour`): `qa` holds the attribute's quantized
/// values, 4 per closed vertex (components beyond `components` unused); `qpos`, 3 per closed vertex,
/// the quantized positions (all decoded before any attribute). With kValencePredictParallelogram
/// the mean of the parallelograms a + b - w rounded half away from zero; with kValencePredictUvGeometric
/// (two components) each triple instead places v in UV space where its position lies relative to the
/// edge ab: at the same fraction along a->b and the same distance from it relative to the edge's
/// length, on the side away from w, and the mean of those is rounded half up. A triple whose edge
/// has no length in space or whose w lies on the edge's line in UV space gives its parallelogram.
/// Without triples: the neighbour's value, else `last`. Clamped to [0, qmax].
/// The geometric prediction uses double arithmetic in one fixed order of correctly rounded operations
/// (+, -, *, /, sqrt), so the encoder and the decoder compute the same bits.
inline void predictAttribute(const int32_t* qa, uint32_t components, const int32_t* qpos, uint32_t v,
                             const uint32_t* t, uint32_t n, uint32_t neighbour, const int32_t* last,
                             uint32_t predictor, int32_t qmax, int32_t* out) {
    if (n == 0) {
        const int32_t* src = neighbour != kNone ? &qa[4 * size_t(neighbour)] : last;
        for (uint32_t j = 0; j < components; ++j) out[j] = src[j];
        return;
    }
    if (predictor == format::kValencePredictUvGeometric && components == 2) {
        const int32_t* pv = &qpos[3 * size_t(v)];
        double acc[2] = {0.0, 0.0};
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t* e = t + 3 * size_t(i);
            const int32_t* pa = &qpos[3 * size_t(e[0])];
            const int32_t* pb = &qpos[3 * size_t(e[1])];
            const int32_t* ua = &qa[4 * size_t(e[0])];
            const int32_t* ub = &qa[4 * size_t(e[1])];
            const int32_t* uw = &qa[4 * size_t(e[2])];
            const double ex = double(pb[0] - pa[0]), ey = double(pb[1] - pa[1]), ez = double(pb[2] - pa[2]);
            const double fx = double(pv[0] - pa[0]), fy = double(pv[1] - pa[1]), fz = double(pv[2] - pa[2]);
            const double gx = double(ub[0] - ua[0]), gy = double(ub[1] - ua[1]);
            const double wx = double(uw[0] - ua[0]), wy = double(uw[1] - ua[1]);
            const double l2 = ex * ex + ey * ey + ez * ez;
            const double side = gx * wy - gy * wx; // w's side of a->b in UV space (perp(g) . (w - a))
            if (l2 > 0.0 && side != 0.0) {
                const double d = ex * fx + ey * fy + ez * fz;
                const double s = d / l2;
                const double dd = d * s;
                const double h2 = fx * fx + fy * fy + fz * fz - dd;
                const double h = h2 > 0.0 ? std::sqrt(h2 / l2) : 0.0;
                const double away = side > 0.0 ? -h : h;
                acc[0] += double(ua[0]) + s * gx - away * gy;
                acc[1] += double(ua[1]) + s * gy + away * gx;
            } else {
                acc[0] += double(ua[0] + ub[0] - uw[0]);
                acc[1] += double(ua[1] + ub[1] - uw[1]);
            }
        }
        for (uint32_t j = 0; j < 2; ++j) {
            const double m = std::floor(acc[j] / double(n) + 0.5);
            out[j] = m < 0.0 ? 0 : (m > double(qmax) ? qmax : int32_t(m));
        }
        return;
    }
    // Neighbour mean: the average of the 2n values at a and b (noisy colours: a parallelogram adds
    // the noise of three vertices, a mean of many averages it out).
    const bool mean = predictor == format::kValencePredictNeighbourMean ||
                      predictor == format::kValencePredictNeighbourMeanDecorrelated;
    for (uint32_t j = 0; j < components; ++j) {
        int64_t sum = 0;
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t* e = t + 3 * size_t(i);
            sum += int64_t(qa[4 * size_t(e[0]) + j]) + qa[4 * size_t(e[1]) + j] - (mean ? 0 : qa[4 * size_t(e[2]) + j]);
        }
        const int64_t m = divRound(sum, int64_t(mean ? 2 * n : n));
        out[j] = m < 0 ? 0 : (m > qmax ? qmax : int32_t(m));
    }
}

/// Whether a colour predictor codes channels 1.. relative to channel 0's residual.
inline bool decorrelatedChannels(uint32_t predictor) {
    return predictor == format::kValencePredictColorDecorrelated ||
           predictor == format::kValencePredictNeighbourMeanDecorrelated;
}

/// Length context of component j of a UV or colour value: `count` the vertex's parallelogram count,
/// `length` the previous vertex's residual length of component 0 (j = 0) or the largest residual
/// length of this vertex's earlier components (j > 0).
inline uint32_t attributeContext(uint32_t j, uint32_t count, uint32_t length) {
    const uint32_t cls = count < 2 ? count : 2;
    const uint32_t l = length < format::kValenceAttributeLengths ? length : format::kValenceAttributeLengths - 1;
    return (j == 0 ? 0 : 3 * format::kValenceAttributeLengths) + cls * format::kValenceAttributeLengths + l;
}

/// Adds output triangle f's UV tangent direction to its three vertices (`sum`, 4 per vertex: xyz and
/// the UV orientation): with edges e1 = p1 - p0, e2 = p2 - p0 over the quantized positions `qpos`
/// (3 per vertex) and (du_i, dv_i) over the quantized UVs `quv` (2 per vertex), the direction of
/// increasing u is (e1 dv2 - e2 dv1) / det with det = du1 dv2 - du2 dv1; the sum takes it times
/// sign(det) (area weighted) and adds det itself as the orientation.
inline void addFaceTangent(const int32_t* qpos, const int32_t* quv, const uint32_t f[3], int64_t* sum) {
    const int32_t* p0 = &qpos[3 * size_t(f[0])];
    const int32_t* p1 = &qpos[3 * size_t(f[1])];
    const int32_t* p2 = &qpos[3 * size_t(f[2])];
    const int32_t* t0 = &quv[2 * size_t(f[0])];
    const int32_t* t1 = &quv[2 * size_t(f[1])];
    const int32_t* t2 = &quv[2 * size_t(f[2])];
    const int64_t du1 = t1[0] - t0[0], dv1 = t1[1] - t0[1], du2 = t2[0] - t0[0], dv2 = t2[1] - t0[1];
    const int64_t det = du1 * dv2 - du2 * dv1;
    const int64_t sg = det > 0 ? 1 : (det < 0 ? -1 : 0);
    int64_t d[3];
    for (int j = 0; j < 3; ++j) d[j] = sg * ((int64_t(p1[j]) - p0[j]) * dv2 - (int64_t(p2[j]) - p0[j]) * dv1);
    for (int c = 0; c < 3; ++c) {
        int64_t* s4 = &sum[4 * size_t(f[c])];
        s4[0] += d[0];
        s4[1] += d[1];
        s4[2] += d[2];
        s4[3] += det;
    }
}

/// Handedness context of a tangent from its vertex's summed UV orientation: 0 positive, 1 negative,
/// 2 none.
inline uint32_t tangentSignContext(int64_t orientation) {
    return orientation > 0 ? 0u : (orientation < 0 ? 1u : 2u);
}


/// Position twins (format version 7, docs/format/valence.md "Twins"): a vertex on a boundary of the
/// coded connectivity (a UV seam's side) usually has the position of a vertex on the seam's other
/// side. A grid of cells 2^shift quantized units wide holds the boundary vertices coded so far
/// (`head`: one chain per hash slot, `mask + 1` slots; `next`: per closed vertex); the candidate of a
/// vertex is the one nearest its prediction among the chains of the 27 cells around it.
constexpr uint32_t kTwinChainLimit = format::kValenceTwinChainLimit;
constexpr uint32_t kTwinContexts = format::kValenceTwinContexts;
struct TwinGrid {
    uint32_t* head = nullptr;
    uint32_t* next = nullptr;
    uint32_t mask = 0;
    uint32_t shift = 0;
    int32_t qmax = 0;
};
inline uint32_t twinSlot(const TwinGrid& g, const int32_t c[3]) {
    return (uint32_t(c[0]) * format::kValenceTwinHash[0] ^ uint32_t(c[1]) * format::kValenceTwinHash[1] ^
            uint32_t(c[2]) * format::kValenceTwinHash[2]) &
           g.mask;
}
inline void twinCell(const TwinGrid& g, const int32_t* p, int32_t c[3]) {
    for (int j = 0; j < 3; ++j) {
        const int32_t x = p[j] < 0 ? 0 : (p[j] > g.qmax ? g.qmax : p[j]);
        c[j] = x >> g.shift;
    }
}
inline void twinInsert(TwinGrid& g, const int32_t* qpos, uint32_t v) {
    int32_t c[3];
    twinCell(g, &qpos[3 * size_t(v)], c);
    const uint32_t slot = twinSlot(g, c);
    g.next[v] = g.head[slot];
    g.head[slot] = v;
}
/// Whether u is one of the vertex's known neighbours: the a or b of one of its `n` triples `t`, or
/// `neighbour` (its twin, on the seam's other side, never is).
inline bool knownNeighbour(uint32_t u, const uint32_t* t, uint32_t n, uint32_t neighbour) {
    if (u == neighbour) return true;
    for (uint32_t i = 0; i < n; ++i)
        if (t[3 * size_t(i)] == u || t[3 * size_t(i) + 1] == u) return true;
    return false;
}

/// The candidate nearest `pred` (squared distance; the first met wins ties; cells in z, y, x order
/// from -1 to +1, each chain newest first, at most kTwinChainLimit vertices of it, the vertex's known
/// neighbours skipped), kNone without one; *ctx its context.
inline uint32_t twinCandidate(const TwinGrid& g, const int32_t* qpos, const int32_t pred[3], const uint32_t* t,
                              uint32_t n, uint32_t neighbour, uint32_t* ctx) {
    int32_t c[3];
    twinCell(g, pred, c);
    uint32_t best = kNone;
    uint64_t best_d = ~uint64_t(0);
    for (int32_t dz = -1; dz <= 1; ++dz)
        for (int32_t dy = -1; dy <= 1; ++dy)
            for (int32_t dx = -1; dx <= 1; ++dx) {
                const int32_t cell[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
                uint32_t v = g.head[twinSlot(g, cell)];
                for (uint32_t k = 0; v != kNone && k < kTwinChainLimit; ++k, v = g.next[v]) {
                    const int32_t* p = &qpos[3 * size_t(v)];
                    uint64_t d = 0;
                    for (int j = 0; j < 3; ++j) {
                        const int64_t e = int64_t(p[j]) - pred[j];
                        d += uint64_t(e * e);
                    }
                    if (d < best_d && !knownNeighbour(v, t, n, neighbour)) {
                        best_d = d;
                        best = v;
                    }
                }
            }
    if (best != kNone) {
        uint32_t m = 0;
        for (int j = 0; j < 3; ++j) {
            const int64_t e = int64_t(qpos[3 * size_t(best) + size_t(j)]) - pred[j];
            const uint64_t a = uint64_t(e < 0 ? -e : e);
            m = a > m ? uint32_t(a > 0xFFFFFFFFu ? 0xFFFFFFFFu : a) : m;
        }
        const uint32_t b = bitLength(m);
        *ctx = b < kTwinContexts ? b : kTwinContexts - 1;
    }
    return best;
}

/// Normal prediction with twins: a vertex whose twin partner comes earlier in final order takes the
/// partner's coded normal (a UV seam rarely splits the normal); else predictNormal.
inline void predictNormalTwin(const int64_t* s3, const uint32_t* qnorm, size_t x, uint32_t partner, uint32_t bits,
                              uint32_t p[2]) {
    if (partner != kNone && partner < x) {
        p[0] = qnorm[2 * size_t(partner)];
        p[1] = qnorm[2 * size_t(partner) + 1];
    } else {
        predictNormal(s3, qnorm, x, bits, p);
    }
}

} // namespace detail
} // namespace lodrt
