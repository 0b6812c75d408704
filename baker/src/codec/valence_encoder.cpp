// Encoder of the .lbm compressed mesh (docs/format/valence.md). The input is cut into a closed
// manifold (non-manifold or inconsistently oriented edges become boundaries, vertices with several
// fans are copied, every boundary loop gets a dummy vertex), then conquered by the engine shared with
// the decoder (lodrt/detail/valence_model.h, Touma-Gotsman 1998 / Alliez-Desbrun 2001). This file's
// Io answers the engine's questions from the mesh, writes the symbols, and checks every assumption the
// decoder will make; when one does not hold (a pinched front in a very irregular input), the triangles
// around the offending vertices are cut loose and the encoding restarts.

#include "lodbake/codec/valence_encoder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>

#include "codec/range_encoder.h"
#include "core/byte_order.h"
#include "core/large_array.h"
#include "lodrt/detail/valence_model.h"
#include "lodrt/format.h"
#include "lodrt/valence.h"

namespace lodbake::codec {
namespace {

using namespace lodrt::format;
using lodrt::detail::initRangeProbs;
using lodrt::detail::kNone;
using lodrt::detail::VertexKind;
using lodrt::detail::VertexSymbol;

// The encoder's large arrays (a corner or two per input corner, several per vertex) are filled fresh.
// The largest are backed by transparent huge pages where the OS offers them (core/large_array.h): one
// page fault per 2 MB instead of one per 4 KB, where first-touch faults otherwise take a large share
// of a scan's encode time.
// Smaller ones stay with malloc, which hands a repeated encode memory already resident.
// From 2 MB, the smallest size with a whole huge page: the bake codes each level once, into fresh
// memory, and a fault on a 2 MB page replaces 512 faults on 4 KB pages, so every level's large arrays
// gain, not only LOD0's.
constexpr size_t kMapBytes = size_t(2) << 20;
template <class T> struct CodecAllocator {
    using value_type = T;
    CodecAllocator() = default;
    template <class U> CodecAllocator(const CodecAllocator<U>&) {}
    T* allocate(size_t n) {
        if (n * sizeof(T) >= kMapBytes) return lodbake::detail::LargeArrayAllocator<T>().allocate(n);
        return static_cast<T*>(::operator new(n * sizeof(T)));
    }
    void deallocate(T* p, size_t n) {
        if (n * sizeof(T) >= kMapBytes) return lodbake::detail::LargeArrayAllocator<T>().deallocate(p, n);
        ::operator delete(p);
    }
    template <class U> bool operator==(const CodecAllocator<U>&) const { return true; }
    template <class U> bool operator!=(const CodecAllocator<U>&) const { return false; }
};
template <class T> using CodecArray = std::vector<T, CodecAllocator<T>>;
using U32Array = CodecArray<uint32_t>;
using I32Array = CodecArray<int32_t>;
using U8Array = CodecArray<uint8_t>;

// A U32Array's storage without the initialisation, for arrays whose every element is written before it
// is read: no fill pass, and pages nobody writes (the unused tail of a worst-case size) never become
// resident.
class UninitArray {
public:
    UninitArray() = default;
    explicit UninitArray(size_t n) { allocate(n); }
    ~UninitArray() { reset(); }
    UninitArray(const UninitArray&) = delete;
    UninitArray& operator=(const UninitArray&) = delete;
    void allocate(size_t n) {
        reset();
        if (n == 0) return;
        p_ = CodecAllocator<uint32_t>().allocate(n);
        n_ = n;
    }
    uint32_t* get() const { return p_; }
    uint32_t& operator[](size_t i) const { return p_[i]; }
    void reset() {
        if (p_) CodecAllocator<uint32_t>().deallocate(p_, n_);
        p_ = nullptr;
        n_ = 0;
    }

private:
    size_t n_ = 0;
    uint32_t* p_ = nullptr;
};

constexpr uint32_t kClassProbs = 1u << kValenceClassTreeBits;
constexpr uint32_t kTopProbs = 33;
constexpr int kMaxRestarts = 12;

inline uint32_t nextCorner(uint32_t c) {
    return c % 3 == 2 ? c - 2 : c + 1;
}
inline uint32_t prevCorner(uint32_t c) {
    return c % 3 == 0 ? c + 2 : c - 1;
}

struct UintModel {
    uint32_t klass[kClassProbs];
    uint32_t top[kTopProbs];
    void init() {
        initRangeProbs(klass, kClassProbs);
        initRangeProbs(top, kTopProbs);
    }
};

template <int Components, int Contexts> struct ResidualModel {
    static constexpr uint32_t kTree = 1u << kValenceResidualTreeBits;
    using LengthModel = lodrt::detail::ResidualLengthModel;
    LengthModel length[Components][Contexts];
    uint32_t sign[Components][lodrt::detail::kSignContexts];
    uint32_t second[Components][2 * kTree];
    uint32_t top[Components][kTree];
    void init() {
        for (auto& per_component : length)
            for (LengthModel& m : per_component) m.init();
        initRangeProbs(&sign[0][0], sizeof(sign) / 4);
        initRangeProbs(&second[0][0], sizeof(second) / 4);
        initRangeProbs(&top[0][0], sizeof(top) / 4);
    }
};

// Models of the position stream: the residuals and the per-component snap decisions.
struct PositionModel {
    ResidualModel<3, lodrt::detail::kPositionContexts> residuals;
    uint32_t snap[3][kValenceSnapContexts];
    void init() {
        residuals.init();
        initRangeProbs(&snap[0][0], sizeof(snap) / 4);
    }
};

// One position coordinate as the position pass codes it.
struct PositionValue {
    int j = 0;        // component
    int32_t r = 0;    // residual (value - prediction)
    uint32_t ctx = 0;        // length context
    uint32_t spread_ctx = 0; // length context with spread contexts (kValenceFlagSpreadX)
    uint32_t sign_ctx = 0;
    bool has_candidate = false;
    bool hit = false;      // the value equals the candidate
    int32_t candidate = 0; // snap candidate (has_candidate)
    uint32_t snap_ctx = 0;
};

// A PositionValue packed into 8 bytes (the candidate itself is not kept: coding needs only the hit).
struct CodedValue {
    int32_t r;
    uint32_t meta; // ctx (8 bits), spread_ctx (8), sign_ctx (4), snap_ctx (7), has_candidate (1), hit (1)
    static CodedValue of(const PositionValue& v) {
        return {v.r, v.ctx | (v.spread_ctx << 8) | (v.sign_ctx << 16) | (v.snap_ctx << 20) |
                         (uint32_t(v.has_candidate) << 27) | (uint32_t(v.hit) << 28)};
    }
    PositionValue value(int j) const {
        PositionValue v;
        v.j = j;
        v.r = r;
        v.ctx = meta & 0xFFu;
        v.spread_ctx = (meta >> 8) & 0xFFu;
        v.sign_ctx = (meta >> 16) & 0xFu;
        v.snap_ctx = (meta >> 20) & 0x7Fu;
        v.has_candidate = (meta >> 27) & 1u;
        v.hit = (meta >> 28) & 1u;
        return v;
    }
};
static_assert(lodrt::detail::kPositionContexts <= 256 && lodrt::detail::kSignContexts <= 16 &&
                  kValenceSnapContexts <= 128,
              "CodedValue's fields");

// The sizes one component's position stream would have, coded two ways that differ only in the residual
// length contexts (without and with spread contexts), both with snap decisions or both without: what
// RangeEncoder and BitWriter would write, without writing it. A range coder's output length depends only
// on its range, not on `low`: each renormalisation shift is one byte and finish() adds 5, so only the
// range is kept. The two ways code the same snap, sign and mantissa decisions with the same model
// states (those models see the same values in both), so those models are shared and each decision's
// probability is computed once; each way keeps its own length models and range. The raw bits are the
// same in both ways: only counted.
class WayPairSizer {
public:
    using LengthModel = lodrt::detail::ResidualLengthModel;
    static constexpr uint32_t kTree = 1u << kValenceResidualTreeBits;

    explicit WayPairSizer(bool snap) : snap_(snap) {
        for (auto& per_way : length_)
            for (LengthModel& m : per_way) m.init();
        initRangeProbs(sign_, lodrt::detail::kSignContexts);
        initRangeProbs(second_, 2 * kTree);
        initRangeProbs(top_, kTree);
        initRangeProbs(snap_probs_, kValenceSnapContexts);
    }
    bool alive(int way) const { return alive_[way]; }
    void drop(int way) { alive_[way] = false; }
    /// Codes values[i] for i in [begin, end) with i % 3 == j (the component's values) into the ways alive.
    void code(const CodedValue* values, size_t begin, size_t end, int j) {
        size_t i = begin + size_t((j - int(begin % 3) + 3) % 3);
        if (alive_[0] && alive_[1])
            codeWays<3>(values, i, end);
        else if (alive_[0])
            codeWays<1>(values, i, end);
        else if (alive_[1])
            codeWays<2>(values, i, end);
    }
    /// RangeEncoder::bytesSoFar() plus BitWriter::bytesSoFar() of way `way`.
    size_t bytesSoFar(int way) const { return 1 + shifts_[way] + size_t(raw_bits_ / 8); }
    /// The size of way `way`'s two finished parts.
    size_t finishedBytes(int way) const { return shifts_[way] + 5 + size_t((raw_bits_ + 7) / 8); }

private:
    template <uint32_t Live> void codeWays(const CodedValue* values, size_t i, size_t end) {
        for (; i < end; i += 3) {
            const uint32_t meta = values[i].meta;
            if (snap_ && ((meta >> 27) & 1u)) {
                const uint32_t hit = (meta >> 28) & 1u;
                bit<Live>(snap_probs_[(meta >> 20) & 0x7Fu], hit);
                if (hit) continue;
            }
            const int32_t r = values[i].r;
            const uint32_t mag = uint32_t(r < 0 ? -r : r);
            const uint32_t k = lodrt::detail::bitLength(mag);
            if (Live & 1u) symbol(0, length_[0][meta & 0xFFu], k);
            if (Live & 2u) symbol(1, length_[1][(meta >> 8) & 0xFFu], k);
            if (k == 0) continue;
            bit<Live>(sign_[(meta >> 16) & 0xFu], r < 0 ? 1u : 0u);
            if (k >= 2) bit<Live>(top_[k], (mag >> (k - 2)) & 1u);
            if (k >= 3) bit<Live>(second_[2 * k + ((mag >> (k - 2)) & 1u)], (mag >> (k - 3)) & 1u);
            if (k >= 4) raw_bits_ += k - 3;
        }
    }
    template <uint32_t Live> void bit(uint32_t& prob, uint32_t b) {
        const uint32_t p = lodrt::detail::rangeProb(prob);
        for (int w = 0; w < 2; ++w) {
            if (!((Live >> w) & 1u)) continue;
            const uint32_t bound = (range_[w] >> kRangeProbBits) * p;
            range_[w] = b ? range_[w] - bound : bound;
            normalize(w);
        }
        prob = lodrt::detail::rangeUpdate(prob, b);
    }
    void symbol(int w, LengthModel& m, uint32_t s) {
        const uint32_t r = range_[w] >> kRangeCdfBits;
        const uint32_t low = r * m.cum[s];
        const uint32_t high = s + 1 < LengthModel::kN ? r * m.cum[s + 1] : range_[w];
        range_[w] = high - low;
        m.update(s);
        normalize(w);
    }
    void normalize(int w) {
        while (range_[w] < kRangeTopValue) {
            range_[w] <<= 8;
            ++shifts_[w];
        }
    }

    bool snap_;
    bool alive_[2] = {true, true};
    uint32_t range_[2] = {0xFFFFFFFFu, 0xFFFFFFFFu};
    size_t shifts_[2] = {0, 0};
    uint64_t raw_bits_ = 0;
    LengthModel length_[2][lodrt::detail::kPositionContexts];
    uint32_t sign_[lodrt::detail::kSignContexts];
    uint32_t second_[2 * kTree];
    uint32_t top_[kTree];
    uint32_t snap_probs_[kValenceSnapContexts];
};

// The closed manifold the conquest runs on: a corner table whose first 3 * face_count corners are the
// input faces (same order and rotation), then the dummy triangles.
struct ClosedMesh {
    U32Array corner_vertex; // closed vertex per corner
    U32Array opposite;      // every corner paired
    U32Array source;        // closed vertex -> input vertex, kNone for dummies
    U32Array valence;       // corners per closed vertex
    size_t real_triangles = 0;
};

// The half-edge pairing of an earlier build and the faces it exploded, for a build that explodes more.
struct PriorPairing {
    U32Array opposite;
    std::vector<uint8_t> exploded;
};

// Working vertex per corner: the input vertex, or for exploded/degenerate faces a private copy
// numbered from the input vertex count on. Only which corners share a working vertex matters, not the
// numbering.
struct WorkingVertices {
    UninitArray work;        // working vertex per corner
    U8Array own;             // per face: its corners have private copies
    U32Array private_source; // private copy - input vertex count -> its input vertex
};

void assignWorkingVertices(const Mesh& mesh, const std::vector<uint8_t>& exploded, WorkingVertices& wv) {
    const size_t fn = mesh.faceCount(), inputs = mesh.vertexCount();
    UninitArray& work = wv.work;
    U8Array& own = wv.own;
    U32Array& private_source = wv.private_source;
    work.allocate(3 * fn);
    own.assign(fn, 0);
    for (size_t f = 0; f < fn; ++f) {
        const uint32_t* t = &mesh.indices[3 * f];
        own[f] = exploded[f] || t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
        for (int i = 0; i < 3; ++i) {
            if (own[f]) {
                work[3 * f + size_t(i)] = uint32_t(inputs + private_source.size());
                private_source.push_back(t[i]);
            } else {
                work[3 * f + size_t(i)] = t[i];
            }
        }
    }
}

// The pairing of a build stopped by several fans (`prior`) updated for the faces exploded since.
void updatePairing(const Mesh& mesh, const WorkingVertices& wv, PriorPairing& prior, U32Array& opposite) {
    const size_t fn = mesh.faceCount(), inputs = mesh.vertexCount();
    const UninitArray& work = wv.work;
    const U8Array& own = wv.own;
    opposite.swap(prior.opposite);
    // A group (the half-edges of one undirected edge between input vertices) changes only by losing
    // the half-edges of newly exploded faces, whose vertices all get marked here: the groups with
    // both vertices marked are formed again from their remaining half-edges, every other pair stays.
    U8Array marked(inputs, 0);
    bool any = false;
    for (size_t f = 0; f < fn; ++f) {
        if (!own[f] || prior.exploded[f]) continue;
        const uint32_t* t = &mesh.indices[3 * f];
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue; // had private vertices already
        any = true;
        for (int i = 0; i < 3; ++i) {
            marked[t[i]] = 1;
            const uint32_t c = uint32_t(3 * f + size_t(i));
            if (opposite[c] != kNone) opposite[opposite[c]] = kNone;
            opposite[c] = kNone;
        }
    }
    if (any) {
        struct HalfEdge {
            uint32_t lower, upper, corner;
        };
        std::vector<HalfEdge> regroup;
        for (size_t f = 0; f < fn; ++f) {
            if (own[f]) continue;
            const uint32_t* w = &work[3 * f];
            for (int i = 0; i < 3; ++i) {
                const uint32_t u = w[(i + 1) % 3], v = w[(i + 2) % 3];
                if (!marked[u] || !marked[v]) continue;
                const uint32_t c = uint32_t(3 * f + size_t(i));
                regroup.push_back({std::min(u, v), std::max(u, v), c});
                opposite[c] = kNone;
            }
        }
        std::sort(regroup.begin(), regroup.end(), [](const HalfEdge& x, const HalfEdge& y) {
            return x.lower != y.lower   ? x.lower < y.lower
                   : x.upper != y.upper ? x.upper < y.upper
                                        : x.corner < y.corner;
        });
        for (size_t i = 0; i < regroup.size();) {
            size_t j = i;
            while (j < regroup.size() && regroup[j].lower == regroup[i].lower &&
                   regroup[j].upper == regroup[i].upper)
                ++j;
            if (j - i == 2) {
                const uint32_t c = regroup[i].corner, d = regroup[i + 1].corner;
                if (work[nextCorner(c)] == work[prevCorner(d)]) {
                    opposite[c] = d;
                    opposite[d] = c;
                }
            }
            i = j;
        }
    }
}

// Pairs the half-edges of faces without private vertices from scratch. Half-edges are bucketed by
// their smaller vertex (counting sort, 4 bytes per corner instead of a sorted 16-byte key per corner),
// each bucket grouped by the larger vertex. The half-edges of faces with private vertices are alone in
// their group: they are left out.
void pairHalfEdges(const WorkingVertices& wv, size_t fn, size_t inputs, U32Array& opposite) {
    const size_t cn = 3 * fn;
    const UninitArray& work = wv.work;
    const U8Array& own = wv.own;
    opposite.assign(cn, kNone);
    U32Array start(inputs + 1, 0);
    UninitArray bucket(cn);
    for (size_t f = 0; f < fn; ++f) {
        if (own[f]) continue;
        const uint32_t* w = &work[3 * f];
        ++start[std::min(w[1], w[2]) + 1];
        ++start[std::min(w[2], w[0]) + 1];
        ++start[std::min(w[0], w[1]) + 1];
    }
    for (size_t v = 0; v < inputs; ++v) start[v + 1] += start[v];
    {
        U32Array fill(start.begin(), start.end() - 1);
        for (size_t f = 0; f < fn; ++f) {
            if (own[f]) continue;
            const uint32_t* w = &work[3 * f];
            const uint32_t c = uint32_t(3 * f);
            bucket[fill[std::min(w[1], w[2])]++] = c;
            bucket[fill[std::min(w[2], w[0])]++] = c + 1;
            bucket[fill[std::min(w[0], w[1])]++] = c + 2;
        }
    }
    // Each bucket's upper vertices are loaded once (the corners of a bucket are scattered over the
    // mesh, so every load is a cache miss) into a small array sorted along with the corners.
    constexpr size_t kLocal = 64;
    uint32_t local_up[kLocal];
    std::vector<uint32_t> large_up;
    for (size_t v = 0; v < inputs; ++v) {
        uint32_t* b = bucket.get() + start[v];
        const size_t n = start[v + 1] - start[v];
        if (n < 2) continue; // a lone half-edge pairs with nothing
        uint32_t* up = local_up;
        if (n > kLocal) {
            large_up.resize(n);
            up = large_up.data();
        }
        for (size_t i = 0; i < n; ++i) up[i] = std::max(work[nextCorner(b[i])], work[prevCorner(b[i])]);
        // Buckets are small (about a valence): insertion sort by the upper vertex.
        for (size_t i = 1; i < n; ++i) {
            const uint32_t x = b[i], ux = up[i];
            size_t j = i;
            for (; j > 0 && up[j - 1] > ux; --j) {
                b[j] = b[j - 1];
                up[j] = up[j - 1];
            }
            b[j] = x;
            up[j] = ux;
        }
        for (size_t i = 0; i < n;) {
            size_t j = i;
            while (j < n && up[j] == up[i]) ++j;
            if (j - i == 2) {
                const uint32_t c = b[i], d = b[i + 1];
                if (work[nextCorner(c)] == work[prevCorner(d)]) {
                    opposite[c] = d;
                    opposite[d] = c;
                }
            }
            i = j;
        }
    }
}

// Splits the working vertices into fans, one closed vertex each (m.corner_vertex, m.source); returns the
// number of boundary half-edges.
size_t numberFans(const WorkingVertices& wv, size_t cn, size_t inputs, ClosedMesh& m) {
    auto sourceOf = [&](uint32_t w) { return w < inputs ? w : wv.private_source[w - inputs]; };
    // Split vertices into fans: the corners around one working vertex joined across paired edges, i.e.
    // the orbits of s(c) = next(opposite[next(c)]) (the same vertex's corner across the edge prev(c) -> c;
    // its inverse is prev(opposite[prev(c)])), each a chain or a cycle. One closed vertex per fan,
    // numbered in the order of the fans' first corners: in increasing corner order the first corner not
    // yet numbered is the first of its fan, which is then walked both ways.
    // The dummy triangles are appended by capBoundaries: room for them is reserved up front.
    size_t boundary = 0;
    for (uint32_t c = 0; c < cn; ++c) boundary += m.opposite[c] == kNone;
    m.corner_vertex.reserve(cn + 3 * boundary);
    m.corner_vertex.assign(cn, kNone);
    m.source.reserve(inputs + wv.private_source.size() + boundary / 3 + 1);
    for (uint32_t c = 0; c < cn; ++c) {
        if (m.corner_vertex[c] != kNone) continue;
        const uint32_t id = uint32_t(m.source.size());
        m.source.push_back(sourceOf(wv.work[c]));
        m.corner_vertex[c] = id;
        bool cycle = false;
        for (uint32_t x = c;;) {
            const uint32_t o = m.opposite[nextCorner(x)];
            if (o == kNone) break;
            x = nextCorner(o);
            if (x == c) {
                cycle = true;
                break;
            }
            m.corner_vertex[x] = id;
        }
        if (cycle) continue;
        for (uint32_t x = c;;) {
            const uint32_t o = m.opposite[prevCorner(x)];
            if (o == kNone) break;
            x = prevCorner(o);
            m.corner_vertex[x] = id;
        }
    }
    return boundary;
}

// Caps every boundary loop with a dummy vertex and its fan of dummy triangles.
void capBoundaries(size_t cn, size_t boundary, ClosedMesh& m) {
    m.opposite.reserve(cn + 3 * boundary);
    // Boundary loops: each vertex now has at most one outgoing boundary half-edge.
    const size_t vn = m.source.size();
    U32Array out_boundary(vn, kNone);
    for (uint32_t c = 0; c < cn; ++c)
        if (m.opposite[c] == kNone) out_boundary[m.corner_vertex[nextCorner(c)]] = c;
    // A capped boundary corner gets its opposite in the dummy triangle: `opposite` marks what is done.
    for (uint32_t c0 = 0; c0 < cn; ++c0) {
        if (m.opposite[c0] != kNone) continue;
        const uint32_t d = uint32_t(m.source.size());
        m.source.push_back(kNone);
        uint32_t first_tri = kNone, previous_tri = kNone;
        for (uint32_t c = c0;;) {
            const uint32_t u = m.corner_vertex[nextCorner(c)], w = m.corner_vertex[prevCorner(c)];
            const uint32_t t = uint32_t(m.corner_vertex.size() / 3);
            m.corner_vertex.insert(m.corner_vertex.end(), {w, u, d});
            m.opposite.insert(m.opposite.end(), {kNone, kNone, kNone});
            m.opposite[3 * t + 2] = c;
            m.opposite[c] = 3 * t + 2;
            if (previous_tri != kNone) {
                m.opposite[3 * previous_tri + 1] = 3 * t;
                m.opposite[3 * t] = 3 * previous_tri + 1;
            } else {
                first_tri = t;
            }
            previous_tri = t;
            c = out_boundary[w];
            if (c == c0) break;
        }
        m.opposite[3 * previous_tri + 1] = 3 * first_tri;
        m.opposite[3 * first_tri] = 3 * previous_tri + 1;
    }
}

// Builds the closed manifold. `exploded[f]` faces get private copies of their three vertices. With
// `several_fans` set, input vertices whose corners fall into several fans (copies included) are listed
// there, and when there are any the build stops after numbering the fans (the caller cuts them loose and
// builds again). With `prior` (a build stopped so, with a subset of `exploded`), its pairing is updated
// instead of computed again: only edges of newly exploded faces change.
ClosedMesh buildClosed(const Mesh& mesh, const std::vector<uint8_t>& exploded, std::vector<uint32_t>* several_fans,
                       PriorPairing* prior) {
    const size_t fn = mesh.faceCount(), cn = 3 * fn, inputs = mesh.vertexCount();
    ClosedMesh m;
    m.real_triangles = fn;
    WorkingVertices wv;
    assignWorkingVertices(mesh, exploded, wv);
    // Pair half-edges: an undirected edge with exactly one half-edge each way is interior; every
    // other half-edge becomes a boundary. Corner c is opposite the half-edge next(c) -> prev(c).
    if (prior)
        updatePairing(mesh, wv, *prior, m.opposite);
    else
        pairHalfEdges(wv, fn, inputs, m.opposite);
    U8Array().swap(wv.own);
    const size_t boundary = numberFans(wv, cn, inputs, m);
    wv.work.reset();
    U32Array().swap(wv.private_source);
    if (several_fans) {
        std::vector<uint8_t> fans(mesh.vertexCount(), 0);
        for (uint32_t src : m.source) {
            if (fans[src] == 1) several_fans->push_back(src);
            if (fans[src] < 2) ++fans[src];
        }
        if (!several_fans->empty()) return m;
    }
    capBoundaries(cn, boundary, m);
    m.valence.assign(m.source.size(), 0);
    for (uint32_t v : m.corner_vertex) ++m.valence[v];
    return m;
}

// Signals a broken decoder assumption; `culprit` is a closed vertex to cut loose.
struct Failure {
    bool failed = false;
    uint32_t culprit_a = kNone, culprit_b = kNone, culprit_c = kNone;
    std::vector<uint32_t> culprit_sources; // input vertices to cut loose (the pre-cut below)
};

struct EncoderIo {
    const ClosedMesh* m = nullptr;
    lodrt::detail::Conquest<EncoderIo>* engine = nullptr;
    RangeEncoder* re = nullptr;
    Failure* failure = nullptr;
    U32Array engine_id; // closed vertex -> engine vertex
    U32Array real_of;   // engine corner -> closed-mesh corner
    U8Array conquered;  // per closed triangle
    uint32_t next_engine_vertex = 0;
    size_t scan = 0;
    uint32_t seed = kNone;
    uint32_t more;
    lodrt::detail::ConnectivitySymbolModel symbols[lodrt::detail::kValenceContexts];
    UintModel escape, offset, list, free_a, dup;

    void init() {
        more = kRangeStateInit;
        for (auto& model : symbols) model.init();
        escape.init();
        offset.init();
        list.init();
        free_a.init();
        dup.init();
        engine_id.assign(m->source.size(), kNone);
        conquered.assign(m->corner_vertex.size() / 3, 0);
    }
    lodrt::Result fail(uint32_t a, uint32_t b) {
        failure->failed = true;
        failure->culprit_a = a;
        failure->culprit_b = b;
        return lodrt::Result::CorruptStream;
    }
    bool moreComponents() {
        while (scan < m->real_triangles && conquered[scan]) ++scan;
        const bool more_left = scan < m->real_triangles;
        re->bit(more, more_left ? 1u : 0u);
        seed = more_left ? uint32_t(scan) : kNone;
        seed_index = 0;
        return more_left;
    }
    void writeNew(uint32_t ctx, uint32_t v) {
        const uint32_t val = m->valence[v];
        if (m->source[v] == kNone) {
            re->symbol(symbols[ctx], kValenceSymbolDummy);
            re->uint(escape.klass, escape.top, val);
        } else if (val >= 3 && val - 3 + kValenceSymbolFirstValence < (1u << kValenceSymbolTreeBits)) {
            re->symbol(symbols[ctx], val - 3 + kValenceSymbolFirstValence);
        } else {
            re->symbol(symbols[ctx], kValenceSymbolEscape);
            re->uint(escape.klass, escape.top, val);
        }
        engine_id[v] = next_engine_vertex++;
    }
    lodrt::Result seedVertex(VertexSymbol* s) {
        const uint32_t v = m->corner_vertex[3 * size_t(seed) + seed_index++];
        return newSymbol(lodrt::detail::kSeedContext, v, s);
    }
    uint32_t seed_index = 0;
    uint32_t last_vertices[3] = {kNone, kNone, kNone};
    lodrt::Result newSymbol(uint32_t ctx, uint32_t v, VertexSymbol* s) {
        if (engine_id[v] != kNone) return fail(v, kNone);
        s->kind = m->source[v] == kNone ? VertexKind::Dummy : VertexKind::Add;
        s->valence = m->valence[v];
        writeNew(ctx, v);
        return lodrt::Result::Ok;
    }
    lodrt::Result vertexSymbol(uint32_t ctx, uint32_t focus, VertexSymbol* s) {
        const auto& a = engine->a;
        const uint32_t rc = real_of[a.node_corner[focus]];
        const uint32_t ro = m->opposite[rc];
        const uint32_t x = m->corner_vertex[ro];
        if (conquered[ro / 3]) return fail(m->corner_vertex[rc], x);
        if (engine_id[x] == kNone) return newSymbol(ctx, x, s);
        // x is on the front: walk its wedge on the focus side (across edge f-x) to the front edge
        // bounding it, counting the unconquered triangles.
        uint32_t c = ro, m_count = 0;
        for (;;) {
            const uint32_t o = m->opposite[nextCorner(c)];
            const uint32_t nc = nextCorner(o);
            if (conquered[nc / 3]) {
                c = nc;
                break;
            }
            c = nc;
            if (++m_count > m->valence[x]) return fail(x, kNone);
        }
        if (m_count == 0) return fail(x, m->corner_vertex[rc]);
        const uint32_t target = prevCorner(c); // in the conquered triangle, opposite front edge x -> y
        const uint32_t ex = engine_id[x];
        auto isTarget = [&](uint32_t k) { return a.node_vertex[k] == ex && real_of[a.node_corner[k]] == target; };
        s->free_a = m_count - 1;
        uint32_t k = focus, d = 0;
        do {
            if (isTarget(k)) {
                s->kind = VertexKind::Split;
                s->offset = d;
                re->symbol(symbols[ctx], kValenceSymbolSplit);
                if (d < 3) return fail(x, kNone);
                re->uint(offset.klass, offset.top, d - 3);
                re->uint(free_a.klass, free_a.top, s->free_a);
                return lodrt::Result::Ok;
            }
            k = a.node_next[k];
            ++d;
        } while (k != focus);
        for (uint32_t li = 0; li < engine->stack_count; ++li) {
            const uint32_t si = engine->stack_count - 1 - li;
            k = a.stack_head[si];
            for (d = 0; d < a.stack_size[si]; ++d, k = a.node_next[k]) {
                if (!isTarget(k)) continue;
                s->kind = VertexKind::Merge;
                s->list = li;
                s->offset = d;
                re->symbol(symbols[ctx], kValenceSymbolMerge);
                re->uint(list.klass, list.top, li);
                re->uint(offset.klass, offset.top, d);
                re->uint(free_a.klass, free_a.top, s->free_a);
                return lodrt::Result::Ok;
            }
        }
        return fail(x, kNone);
    }
    lodrt::Result onTriangle(uint32_t t, uint32_t attach) {
        const auto& a = engine->a;
        // The engine reports its triangles in creation order (t = 0, 1, ...): real_of grows by 3.
        if (real_of.size() != 3 * size_t(t)) real_of.resize(3 * size_t(t), kNone);
        uint32_t rt;
        if (attach == kNone) {
            rt = seed;
            real_of.insert(real_of.end(), {3 * rt, 3 * rt + 1, 3 * rt + 2});
        } else {
            const uint32_t ro = m->opposite[real_of[attach]];
            rt = ro / 3;
            real_of.insert(real_of.end(), {nextCorner(ro), prevCorner(ro), ro});
        }
        if (conquered[rt]) return fail(m->corner_vertex[3 * rt], m->corner_vertex[3 * rt + 1]);
        conquered[rt] = 1;
        for (uint32_t i = 0; i < 3; ++i) last_vertices[i] = m->corner_vertex[3 * rt + i];
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t ec = 3 * t + i, rc = real_of[ec];
            if (engine_id[m->corner_vertex[rc]] != a.corner_vertex[ec])
                return fail(m->corner_vertex[rc], m->corner_vertex[real_of[3 * t + (i + 1) % 3]]);
            const uint32_t eo = a.corner_opposite[ec];
            const uint32_t ro = m->opposite[rc];
            const bool ok = eo != kNone ? real_of[eo] == ro : !conquered[ro / 3];
            if (!ok) return fail(m->corner_vertex[nextCorner(rc)], m->corner_vertex[prevCorner(rc)]);
        }
        return lodrt::Result::Ok;
    }
};


// One attempt: conquest of the closed mesh built with `exploded`. Fills `io` (and its engine) or
// reports the failure.
struct Attempt {
    ClosedMesh closed;
    lodrt::detail::Conquest<EncoderIo> engine;
    EncoderIo io;
    RangeEncoder conn;
    Failure failure;
    bool precut = false; // cut vertices with several fans loose instead of conquering (first round)
    // After a precut: its pairing and exploded faces, which the next build updates.
    PriorPairing prior;
    bool has_prior = false;
    // The engine writes every element before reading it (the decoder relies on the same).
    UninitArray corner_vertex, corner_opposite, vertex_flags, vertex_corner, vertex_valence, node_vertex,
        node_prev, node_next, node_free, node_corner, completion, stack_head, stack_size;

    bool run(const Mesh& mesh, const std::vector<uint8_t>& exploded) {
        const bool use_prior = has_prior && !precut;
        has_prior = false;
        if (use_prior) prior.opposite.swap(closed.opposite);
        // A restart's previous closed mesh and conquest arrays go before the new mesh is built: its
        // temporaries on top of them made the restart the encoder's peak.
        closed = ClosedMesh();
        for (auto* v : {&corner_vertex, &corner_opposite, &vertex_flags, &vertex_corner, &vertex_valence, &node_vertex,
                        &node_prev, &node_next, &node_free, &node_corner, &completion, &stack_head, &stack_size})
            v->reset();
        // Vertices with several fans (non-manifold vertices and edges) pinch the front where their
        // copies meet, and the conquest fails there, often near its end. Cutting their triangles
        // loose before the first conquest costs a few copies and saves the restart.
        closed = buildClosed(mesh, exploded, precut ? &failure.culprit_sources : nullptr, use_prior ? &prior : nullptr);
        prior = PriorPairing();
        if (!failure.culprit_sources.empty()) {
            failure.failed = true;
            // The pairing is complete (the build stopped after the fans): the next build updates it.
            prior.exploded = exploded;
            has_prior = true;
            return false;
        }
        const size_t vc = closed.source.size(), tc = closed.corner_vertex.size() / 3;
        for (auto* v : {&corner_vertex, &corner_opposite}) v->allocate(3 * tc);
        for (auto* v : {&vertex_flags, &vertex_corner, &vertex_valence, &completion}) v->allocate(vc);
        for (auto* v : {&node_vertex, &node_prev, &node_next, &node_free, &node_corner}) v->allocate(vc + tc);
        for (auto* v : {&stack_head, &stack_size}) v->allocate(tc);
        auto& a = engine.a;
        a.corner_vertex = corner_vertex.get();
        a.corner_opposite = corner_opposite.get();
        a.vertex_flags = vertex_flags.get();
        a.vertex_corner = vertex_corner.get();
        a.vertex_valence = vertex_valence.get();
        a.node_vertex = node_vertex.get();
        a.node_prev = node_prev.get();
        a.node_next = node_next.get();
        a.node_free = node_free.get();
        a.node_corner = node_corner.get();
        a.completion = completion.get();
        a.stack_head = stack_head.get();
        a.stack_size = stack_size.get();
        a.max_vertices = uint32_t(vc);
        a.max_triangles = uint32_t(tc);
        io.m = &closed;
        io.engine = &engine;
        io.re = &conn;
        io.failure = &failure;
        io.init();
        io.real_of.reserve(3 * tc);
        lodrt::Result r = engine.run(io);
        if (r != lodrt::Result::Ok && !failure.failed) {
            // The engine refused a step (e.g. a front pinched onto itself): blame the last triangle.
            failure.failed = true;
            failure.culprit_a = io.last_vertices[0];
            failure.culprit_b = io.last_vertices[1];
            failure.culprit_c = io.last_vertices[2];
        }
        if (!failure.failed &&
            (engine.vertex_count != vc || engine.triangle_count != tc || engine.completion_count != vc))
            failure.failed = true;
        return !failure.failed;
    }

    // Back to a new attempt's state for a restart (run() frees and refills the conquest arrays).
    void reset() {
        engine = lodrt::detail::Conquest<EncoderIo>();
        io = EncoderIo();
        conn = RangeEncoder();
        failure = Failure();
    }

    // After a successful run: frees what only the conquest needed (the closed mesh, the active lists,
    // the encoder's bookkeeping), keeping the engine's corner table, vertex arrays, real_of and the
    // connectivity coder for the steps after it.
    void releaseConquestState() {
        for (auto* v : {&node_vertex, &node_prev, &node_next, &node_free, &node_corner, &completion, &stack_head, &stack_size})
            v->reset();
        for (auto* v : {&closed.corner_vertex, &closed.opposite, &closed.source, &closed.valence, &io.engine_id})
            U32Array().swap(*v);
        U8Array().swap(io.conquered);
    }
};

// `bytes`: the stream, for the version it names.
std::string describe(lodrt::Result r, const std::vector<uint8_t>& bytes) {
    std::string what;
    switch (r) {
    case lodrt::Result::Truncated:
        what = "the file ends before the lengths its header gives";
        break;
    case lodrt::Result::BadMagic:
        what = "not an .lbm file (bad magic)";
        break;
    case lodrt::Result::UnsupportedVersion:
        what = "format version " + std::to_string(bytes.size() >= 6 ? bytes[4] | (bytes[5] << 8) : 0) +
               " is not supported (this decoder reads versions " + std::to_string(kValenceVersionWithoutAttributes) +
               " and " + std::to_string(kValenceVersion) + "; re-encode the mesh)";
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
    return what + " (" + lodrt::resultName(r) + ")";
}

// The options' bit counts, the format's count limits and finite positions.
Status checkEncodable(const Mesh& mesh, const ValenceEncodeOptions& options, bool normals) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, "valence encoder"));
    if (options.position_bits < kValenceMinPositionBits || options.position_bits > kValenceMaxPositionBits)
        return invalidInput("valence encoder: position bits " + std::to_string(options.position_bits) +
                            " outside [8, 16]");
    if (normals && (options.normal_bits < kValenceMinNormalBits || options.normal_bits > kValenceMaxNormalBits))
        return invalidInput("valence encoder: normal bits " + std::to_string(options.normal_bits) + " outside [4, 16]");
    if (options.encode_attributes) {
        const size_t count = mesh.uvs.size() + (mesh.hasColors() ? 1 : 0) + (mesh.hasTangents() ? 1 : 0);
        if (count > kValenceMaxAttributes)
            return invalidInput("valence encoder: " + std::to_string(count) + " attributes exceed the format limit of " +
                                std::to_string(kValenceMaxAttributes));
        const std::pair<const char*, uint32_t> bits[] = {
            {"UV", mesh.uvs.empty() ? kValenceMinAttributeBits : options.uv_bits},
            {"colour", mesh.hasColors() ? options.color_bits : kValenceMinAttributeBits},
            {"tangent", mesh.hasTangents() ? options.tangent_bits : kValenceMinAttributeBits}};
        for (const auto& [name, b] : bits)
            if (b < kValenceMinAttributeBits || b > kValenceMaxAttributeBits)
                return invalidInput(std::string("valence encoder: ") + name + " bits " + std::to_string(b) +
                                    " outside [4, 16]");
    }
    const size_t vn = mesh.vertexCount(), fn = mesh.faceCount();
    // Cutting can copy each corner's vertex and cap each boundary edge: keep the closed counts in range.
    if (vn > kValenceMaxCount / 4 || fn > kValenceMaxCount / 4)
        return invalidInput("valence encoder: " + std::to_string(vn) + " vertices / " + std::to_string(fn) +
                            " triangles exceed the format limit of 2^26");
    for (size_t i = 0; i < vn; ++i) {
        const Vec3f& p = mesh.positions[i];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
            return invalidInput("valence encoder: vertex " + std::to_string(i) + ": position is not finite");
    }
    return Status::okStatus();
}

// The quantization cube over all vertices (unreferenced ones are coded too) and every input vertex's
// quantized position.
struct Quantization {
    float lo[3] = {0, 0, 0};
    float cube = 0;
    uint32_t qmax = 0;
    I32Array qpos; // three per input vertex
};

Status quantizePositions(const Mesh& mesh, const codec::ValenceEncodeOptions& options, Quantization& out,
                         double& max_error) {
    const size_t vn = mesh.vertexCount();
    const uint32_t bits = options.position_bits;
    float* lo = out.lo;
    float hi[3] = {0, 0, 0};
    for (size_t i = 0; i < vn; ++i) {
        const float c[3] = {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z};
        for (int j = 0; j < 3; ++j) {
            if (i == 0 || c[j] < lo[j]) lo[j] = c[j];
            if (i == 0 || c[j] > hi[j]) hi[j] = c[j];
        }
    }
    float cube = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.0f});
    if (options.cube_size > 0) {
        for (int j = 0; j < 3; ++j)
            if (vn > 0 && (lo[j] < options.cube_min[j] || hi[j] > options.cube_min[j] + options.cube_size))
                return invalidInput("valence encoder: a vertex lies outside the given quantization cube");
        for (int j = 0; j < 3; ++j) lo[j] = options.cube_min[j];
        cube = options.cube_size;
    }
    if (!std::isfinite(cube)) return invalidInput("valence encoder: bounding box extent overflows a float");
    const uint32_t qmax = (1u << bits) - 1;
    const float step = cube / float(qmax);
    out.cube = cube;
    out.qmax = qmax;
    out.qpos.resize(3 * vn);
    for (size_t i = 0; i < vn; ++i) {
        const float c[3] = {mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z};
        for (int j = 0; j < 3; ++j) {
            const double t = cube > 0.0f ? double(c[j] - lo[j]) / double(cube) * qmax : 0.0;
            // t >= 0 (c[j] >= lo[j]), so the truncation is floor(t + 0.5), without two library calls.
            const long q = std::clamp<long>(long(t + 0.5), 0, long(qmax));
            out.qpos[3 * i + size_t(j)] = int32_t(q);
            const double decoded = double(lo[j] + float(q) * step);
            max_error = std::max(max_error, std::fabs(decoded - double(c[j])));
        }
    }
    return Status::okStatus();
}

// Conquest, cutting more of the mesh loose while a decoder assumption fails.
Result<std::unique_ptr<Attempt>> conquer(const Mesh& mesh) {
    const size_t vn = mesh.vertexCount(), fn = mesh.faceCount();
    std::vector<uint8_t> exploded(fn, 0);
    auto attempt = std::make_unique<Attempt>();
    for (int round = 0;; ++round) {
        if (round > 0) attempt->reset();
        attempt->precut = round == 0;
        if (attempt->run(mesh, exploded)) break;
        const bool all = std::all_of(exploded.begin(), exploded.end(), [](uint8_t e) { return e != 0; });
        if (all) return internalError("valence encoder: conquest failed on fully cut mesh");
        bool changed = false;
        if (round < kMaxRestarts) {
            const Failure& f = attempt->failure;
            std::vector<uint8_t> culprit(vn, 0);
            for (uint32_t cv : {f.culprit_a, f.culprit_b, f.culprit_c})
                if (cv != kNone && attempt->closed.source[cv] != kNone) culprit[attempt->closed.source[cv]] = 1;
            for (uint32_t src : f.culprit_sources) culprit[src] = 1;
            for (size_t t = 0; t < fn; ++t) {
                if (exploded[t]) continue;
                const uint32_t* tri = &mesh.indices[3 * t];
                if (culprit[tri[0]] || culprit[tri[1]] || culprit[tri[2]]) exploded[t] = changed = true;
            }
        }
        if (!changed) std::fill(exploded.begin(), exploded.end(), uint8_t(1));
    }
    return attempt;
}

// The final vertex order: conquest order without dummies and copies, then unreferenced vertices.
struct FinalOrder {
    U32Array source_of_engine;    // input vertex per engine vertex, kNone for dummies
    U32Array final_of;            // final vertex per engine vertex, kNone for dummies
    std::vector<uint32_t> new_of; // final vertex per input vertex
    std::vector<std::pair<uint32_t, uint32_t>> dups; // (rank among non-dummies, final id of the original)
    uint32_t referenced = 0;      // final vertices some triangle uses (the first ones)
    uint32_t rank = 0;            // engine vertices that are not dummies
};

// Orders the vertices, frees the conquest's working state, and codes the copies (cut vertices) into
// the connectivity stream.
FinalOrder orderVertices(Attempt& attempt, size_t vn) {
    FinalOrder o;
    EncoderIo& io = attempt.io;
    const uint32_t vc = uint32_t(attempt.closed.source.size());
    o.source_of_engine.resize(vc);
    for (uint32_t v = 0; v < vc; ++v) o.source_of_engine[io.engine_id[v]] = attempt.closed.source[v];
    attempt.releaseConquestState();
    o.final_of.assign(vc, kNone);
    o.new_of.assign(vn, kNone);
    uint32_t final_count = 0;
    for (uint32_t ev = 0; ev < vc; ++ev) {
        const uint32_t src = o.source_of_engine[ev];
        if (src == kNone) continue;
        if (o.new_of[src] != kNone) {
            o.dups.push_back({o.rank, o.new_of[src]});
            o.final_of[ev] = o.new_of[src];
        } else {
            o.new_of[src] = o.final_of[ev] = final_count++;
        }
        ++o.rank;
    }
    RangeEncoder& conn = attempt.conn;
    conn.uint(io.dup.klass, io.dup.top, o.dups.size());
    for (size_t i = 0; i < o.dups.size(); ++i) {
        const uint32_t gap = i == 0 ? o.dups[i].first : o.dups[i].first - o.dups[i - 1].first - 1;
        const uint32_t back = (o.dups[i].first - uint32_t(i)) - 1 - o.dups[i].second;
        conn.uint(io.dup.klass, io.dup.top, gap);
        conn.uint(io.dup.klass, io.dup.top, back);
    }
    o.referenced = final_count;
    for (size_t v = 0; v < vn; ++v)
        if (o.new_of[v] == kNone) o.new_of[v] = final_count++;
    return o;
}

// A closed triangle (its engine corners' vertices) is output unless it has a dummy vertex.
bool isOutputTriangle(const lodrt::detail::ConquestArrays& a, const uint32_t* cv) {
    return !((a.vertex_flags[cv[0]] | a.vertex_flags[cv[1]] | a.vertex_flags[cv[2]]) & lodrt::detail::kFlagDummy);
}

// The position pass's plan (order and prediction triples, from the connectivity alone) and the
// coordinates it visits, predicted exactly as the decoder will.
class PositionWalk {
public:
    PositionWalk(const lodrt::detail::ConquestArrays& a, const FinalOrder& order, const Quantization& quantized,
                 size_t vn, uint32_t vc, uint32_t tc)
        : order_(order), quantized_(quantized), qpos_(3 * size_t(vc), 0), qpos_final_(3 * vn), plan_order_(vc),
          count_(vc), neighbour_(vc), triples_(9 * size_t(tc)), boundary_(vc, 0) {
        plan_.order = plan_order_.data();
        plan_.boundary = boundary_.data();
        plan_.count = count_.data();
        plan_.neighbour = neighbour_.data();
        plan_.triples = triples_.get();
        plan_.max_triples = 3 * tc;
        {
            U8Array ordered(vc);
            U32Array stack0(vc), stack1(vc), stack2(vc);
            planned_ = lodrt::detail::planPositions(a.corner_vertex, a.corner_opposite, a.vertex_corner,
                                                    a.vertex_flags, a.vertex_valence, vc, ordered.data(),
                                                    stack0.data(), stack1.data(), stack2.data(), &plan_);
        }
        twin_.assign(plan_.ordered, kNone);
        isolated_.resize(vn - order.referenced);
        final_done_.assign(vn, 0);
        for (size_t v = 0; v < vn; ++v)
            if (order.new_of[v] >= order.referenced) isolated_[order.new_of[v] - order.referenced] = uint32_t(v);
    }

    bool planned() const { return planned_; }
    uint32_t planEntries() const { return plan_.ordered; }
    // Quantized positions in final order, complete after a walk of the whole plan.
    const I32Array& finalPositions() const { return qpos_final_; }
    // The prediction triples are only read by walks.
    void releasePlan() { triples_.reset(); }
    // Quantized positions per engine vertex, complete after a walk of the whole plan.
    const int32_t* closedPositions() const { return qpos_.data(); }
    // Calls f(engine vertex, its triples, their count, its neighbour) for every plan entry in order.
    template <class F> void forEachPlanned(F&& f) const {
        const uint32_t* triple = plan_.triples;
        for (uint32_t i = 0; i < plan_.ordered; ++i) {
            f(plan_order_[i], triple, count_[i], neighbour_[i]);
            triple += 3 * size_t(count_[i]);
        }
    }

    // Visits every coded coordinate in stream order with everything its coding needs. The contexts do
    // not depend on how a coordinate is coded (a snapped one counts with the length and sign of
    // candidate - prediction), so each component's values can be coded into a stream of its own.
    // `mask`: the components whose snap candidates are needed (bit j); `limit`: plan entries to visit
    // (all of them, then the vertices no triangle uses, unless fewer).
    template <class Code> void walk(uint32_t mask, uint32_t limit, Code&& code) {
        std::fill(final_done_.begin(), final_done_.end(), uint8_t(0));
        const uint32_t qmax = quantized_.qmax;
        int32_t last[3] = {int32_t(qmax + 1) / 2, int32_t(qmax + 1) / 2, int32_t(qmax + 1) / 2};
        uint32_t prev_sign[3] = {0, 0, 0};
        const uint32_t* triple = plan_.triples;
        const uint32_t entries = std::min(limit, plan_.ordered);
        for (uint32_t i = 0; i < entries; ++i) {
            const uint32_t ev = plan_order_[i], n = count_[i];
            const uint32_t* t = triple;
            triple += 3 * size_t(n);
            const uint32_t fid = order_.final_of[ev];
            if (fid == kNone) continue;
            const uint32_t src = order_.source_of_engine[ev];
            int32_t* q = &qpos_[3 * size_t(ev)];
            for (int j = 0; j < 3; ++j) q[j] = quantized_.qpos[3 * size_t(src) + size_t(j)];
            if (!final_done_[fid]) {
                if (twin_[i] == kNone) { // a twin takes its partner's position: nothing coded here
                    int32_t pred[3];
                    uint32_t scale = 0, spread[3];
                    lodrt::detail::predictFromPlan(qpos_.data(), t, n, neighbour_[i], last, pred, &scale, spread);
                    vertex(mask, prev_sign, q, pred, lodrt::detail::scaleContext(scale, n), spread, t, n,
                           neighbour_[i], code);
                }
                for (int j = 0; j < 3; ++j) qpos_final_[3 * size_t(fid) + size_t(j)] = q[j];
                final_done_[fid] = 1;
            }
            for (int j = 0; j < 3; ++j) last[j] = q[j];
        }
        if (entries < plan_.ordered) return;
        for (uint32_t v : isolated_) {
            const int32_t* q = &quantized_.qpos[3 * size_t(v)];
            const int32_t pred[3] = {last[0], last[1], last[2]};
            const uint32_t spread[3] = {0, 0, 0};
            vertex(mask, prev_sign, q, pred, lodrt::detail::scaleContext(0, 0), spread, nullptr, 0, kNone, code);
            for (int j = 0; j < 3; ++j) {
                last[j] = q[j];
                qpos_final_[3 * size_t(order_.new_of[v]) + size_t(j)] = q[j];
            }
        }
    }

    // Position twins (docs/format/valence.md "Twins"): with cells of 2^shift units, every boundary
    // vertex's candidate and whether it is the vertex's twin, in stream order (the decisions the twin
    // part codes); the hits are skipped by later walks and paired in twin_of (final vertices).
    struct TwinDecision {
        uint32_t ctx;
        bool hit;
    };
    std::vector<TwinDecision> decideTwins(uint32_t shift, std::vector<uint32_t>& twin_of) {
        std::fill(final_done_.begin(), final_done_.end(), uint8_t(0));
        std::fill(twin_.begin(), twin_.end(), kNone);
        const uint32_t vc = uint32_t(qpos_.size() / 3);
        size_t slots = kValenceTwinMinSlots;
        while (slots < 2 * size_t(vc)) slots *= 2;
        U32Array head(slots, kNone), next(vc, kNone);
        lodrt::detail::TwinGrid grid;
        grid.head = head.data();
        grid.next = next.data();
        grid.mask = uint32_t(slots - 1);
        grid.shift = shift;
        grid.qmax = int32_t(quantized_.qmax);
        std::vector<TwinDecision> out;
        forEachEntry([&](uint32_t i, uint32_t ev, uint32_t fid, const int32_t* pred, const uint32_t* t, uint32_t n) {
            if (pred && boundary_[i]) {
                uint32_t ctx = 0;
                const uint32_t c = lodrt::detail::twinCandidate(grid, qpos_.data(), pred, t, n, neighbour_[i], &ctx);
                if (c != kNone) {
                    const bool hit = std::equal(&qpos_[3 * size_t(c)], &qpos_[3 * size_t(c)] + 3, &qpos_[3 * size_t(ev)]);
                    out.push_back({ctx, hit});
                    if (hit) {
                        twin_[i] = c;
                        const uint32_t other = order_.final_of[c];
                        if (twin_of[fid] == kNone) twin_of[fid] = other;
                        if (twin_of[other] == kNone) twin_of[other] = fid;
                    }
                }
            }
            if (boundary_[i]) lodrt::detail::twinInsert(grid, qpos_.data(), ev);
        });
        return out;
    }
    // Bit length of the median prediction error (largest coordinate) of the boundary vertices: the
    // twin grid's cell shift, so that a typical twin lies within the cells searched.
    uint32_t twinShift() {
        std::fill(final_done_.begin(), final_done_.end(), uint8_t(0));
        std::vector<uint32_t> errors;
        forEachEntry([&](uint32_t i, uint32_t ev, uint32_t, const int32_t* pred, const uint32_t*, uint32_t) {
            if (!pred || !boundary_[i]) return;
            uint32_t m = 0;
            for (int j = 0; j < 3; ++j) m = std::max(m, uint32_t(std::abs(qpos_[3 * size_t(ev) + size_t(j)] - pred[j])));
            errors.push_back(m);
        });
        if (errors.empty()) return 0;
        std::nth_element(errors.begin(), errors.begin() + std::ptrdiff_t(errors.size() / 2), errors.end());
        return std::min(lodrt::detail::bitLength(errors[errors.size() / 2]), kValenceMaxTwinShift);
    }
    bool anyTwin() const {
        return std::any_of(twin_.begin(), twin_.end(), [](uint32_t t) { return t != kNone; });
    }
    void clearTwins() { std::fill(twin_.begin(), twin_.end(), kNone); }

private:
    // Plan entries in order with their engine vertex, final vertex and prediction (null for a copy of
    // a vertex already coded); qpos_ holds every position up to the entry's own, final_done_ is kept.
    template <class F> void forEachEntry(F&& f) {
        const uint32_t qmax = quantized_.qmax;
        int32_t last[3] = {int32_t(qmax + 1) / 2, int32_t(qmax + 1) / 2, int32_t(qmax + 1) / 2};
        const uint32_t* triple = plan_.triples;
        for (uint32_t i = 0; i < plan_.ordered; ++i) {
            const uint32_t ev = plan_order_[i], n = count_[i];
            const uint32_t* t = triple;
            triple += 3 * size_t(n);
            const uint32_t fid = order_.final_of[ev];
            if (fid == kNone) continue;
            int32_t* q = &qpos_[3 * size_t(ev)];
            for (int j = 0; j < 3; ++j) q[j] = quantized_.qpos[3 * size_t(order_.source_of_engine[ev]) + size_t(j)];
            if (!final_done_[fid]) {
                int32_t pred[3];
                uint32_t scale = 0, spread[3];
                lodrt::detail::predictFromPlan(qpos_.data(), t, n, neighbour_[i], last, pred, &scale, spread);
                f(i, ev, fid, pred, t, n);
                final_done_[fid] = 1;
            } else {
                f(i, ev, fid, static_cast<const int32_t*>(nullptr), t, n);
            }
            for (int j = 0; j < 3; ++j) last[j] = q[j];
        }
    }

    // One vertex: `q` its coordinates, `t`/`n`/`nb` its plan entry (n = 0, nb = kNone: none).
    template <class Code>
    void vertex(uint32_t mask, uint32_t* prev_sign, const int32_t* q, const int32_t* pred, uint32_t ctx,
                const uint32_t* spread, const uint32_t* t, uint32_t n, uint32_t nb, Code& code) {
        uint32_t earlier = kNone, x_sign = 0;
        int32_t candidate[3] = {0, 0, 0};
        uint32_t snap_ctx[3] = {0, 0, 0};
        const bool has_candidate =
            lodrt::detail::snapCandidates(qpos_.data(), t, n, nb, pred, mask, candidate, snap_ctx);
        for (int j = 0; j < 3; ++j) {
            const int32_t r = q[j] - pred[j];
            PositionValue value;
            value.j = j;
            value.r = r;
            value.ctx = lodrt::detail::positionContext(ctx, earlier);
            value.spread_ctx = lodrt::detail::spreadContext(ctx, earlier, spread[j]);
            value.sign_ctx = prev_sign[j] * 3 + x_sign;
            value.has_candidate = has_candidate && ((mask >> j) & 1u);
            value.candidate = candidate[j];
            value.snap_ctx = snap_ctx[j];
            value.hit = value.has_candidate && value.candidate == q[j];
            code(value);
            prev_sign[j] = lodrt::detail::signClass(r);
            if (j == 0) x_sign = prev_sign[0];
            const uint32_t k = lodrt::detail::bitLength(uint32_t(r < 0 ? -r : r));
            earlier = earlier == kNone ? k : std::max(earlier, k);
        }
    }

    const FinalOrder& order_;
    const Quantization& quantized_;
    I32Array qpos_, qpos_final_;
    U32Array plan_order_, count_, neighbour_;
    // Sized for the worst case and filled only as far as the plan goes: left uninitialised, so the
    // untouched tail costs no resident memory.
    UninitArray triples_;
    lodrt::detail::PositionPlan plan_;
    bool planned_ = false;
    std::vector<uint32_t> isolated_;
    U8Array final_done_;
    U8Array boundary_;           // per plan entry: a dummy neighbour (plan_.boundary)
    std::vector<uint32_t> twin_; // per plan entry: the twin whose position it takes, kNone
};

// Which components to snap and which to code with spread contexts: every component sized all four
// ways (two without a sizeable share of snap hits) as streams of its own (exact sizes, since a
// component's values and contexts do not depend on the other components' choices; WayPairSizer),
// ways far behind after the first eighth dropped; the smallest of the rest wins (ties: fewer flags).
// Returns the position flags. The estimate's walk keeps every value it visits (8 bytes each) in
// `walked`, so that the stream is coded from them instead of walking the plan again (the walk is half
// of a position pass).
uint16_t choosePositionFlags(PositionWalk& walk, size_t vn, CodecArray<CodedValue>& walked) {
    uint16_t flags_pos = 0;
    // Without a sizeable share of hits the snap flag cannot pay: no snap estimate. The share is
    // counted on the first eighth of the plan (at least 4096 vertices).
    size_t candidates = 0, hits = 0;
    walk.walk(7u, std::max(walk.planEntries() / 8, 4096u), [&](const PositionValue& v) {
        candidates += v.has_candidate;
        hits += v.hit;
    });
    const bool try_snap = hits * 16 >= candidates && hits > 0;
    const int ways = try_snap ? 4 : 2; // way w: snap (w & 2), spread contexts (w & 1)
    walked.reserve(3 * vn);
    walk.walk(try_snap ? 7u : 0u, kNone, [&](const PositionValue& v) { walked.push_back(CodedValue::of(v)); });
    // One sizer per component and snap choice (sizer[j][w >> 1] sizes ways w and w | 1); 6 x 17 KB:
    // not on the stack of a pool thread.
    std::vector<std::unique_ptr<WayPairSizer>> sizers;
    for (int j = 0; j < 3; ++j)
        for (int pair = 0; pair < ways / 2; ++pair) sizers.push_back(std::make_unique<WayPairSizer>(pair == 1));
    auto sizer = [&](int j, int w) -> WayPairSizer& { return *sizers[size_t(j * (ways / 2) + (w >> 1))]; };
    // Values [begin, end) (component order x, y, z per vertex) into every way still alive.
    auto estimate = [&](size_t begin, size_t end) {
        for (int j = 0; j < 3; ++j)
            for (int pair = 0; pair < ways / 2; ++pair) sizer(j, 2 * pair).code(walked.data(), begin, end, j);
    };
    // The first eighth in every way; a way already 2 % (and 256 bytes) larger than the best there
    // is dropped, the others run to the end and the smallest is exact.
    const size_t prefix = 3 * (walked.size() / 24);
    estimate(0, prefix);
    for (int j = 0; j < 3; ++j) {
        size_t so_far[4] = {0, 0, 0, 0}, best = ~size_t(0);
        for (int w = 0; w < ways; ++w) {
            so_far[w] = sizer(j, w).bytesSoFar(w & 1);
            best = std::min(best, so_far[w]);
        }
        for (int w = 0; w < ways; ++w)
            if (so_far[w] > best + std::max<size_t>(256, best / 50)) sizer(j, w).drop(w & 1);
    }
    estimate(prefix, walked.size());
    for (int j = 0; j < 3; ++j) {
        int best = -1;
        size_t best_size = 0;
        for (int w = 0; w < ways; ++w) {
            if (!sizer(j, w).alive(w & 1)) continue;
            const size_t size = sizer(j, w).finishedBytes(w & 1);
            if (best < 0 || size < best_size) {
                best = w;
                best_size = size;
            }
        }
        if (best & 2) flags_pos = uint16_t(flags_pos | (kValenceFlagSnapX << j));
        if (best & 1) flags_pos = uint16_t(flags_pos | (kValenceFlagSpreadX << j));
    }
    return flags_pos;
}

// Codes the walked values with the chosen flags. Values come in component order x, y, z per vertex; a
// component that is not snapped codes without its candidate, exactly as a walk with its mask would
// give it.
void codePositions(const CodecArray<CodedValue>& walked, uint16_t flags_pos, RangeEncoder& pos, BitWriter& pos_raw) {
    PositionModel model;
    model.init();
    const uint32_t snap_mask = uint32_t(flags_pos / kValenceFlagSnapX) & 7u;
    const uint32_t spread_mask = uint32_t(flags_pos / kValenceFlagSpreadX) & 7u;
    for (size_t i = 0; i < walked.size(); ++i) {
        const PositionValue v = walked[i].value(int(i % 3));
        if (v.has_candidate && ((snap_mask >> v.j) & 1u)) {
            pos.bit(model.snap[v.j][v.snap_ctx], v.hit ? 1u : 0u);
            if (v.hit) continue;
        }
        pos.residual(model.residuals, pos_raw, v.j, ((spread_mask >> v.j) & 1u) ? v.spread_ctx : v.ctx, v.r,
                     v.sign_ctx);
    }
}

// Position twins: decided once on the grid whose cells fit the boundary vertices' median prediction
// error, and coded only when at least an eighth of the decisions are hits (each decision costs a
// bit at worst, a hit saves a whole position). Leaves twin_of empty and shift 0 without twins.
void codeTwins(PositionWalk& walk, size_t vn, std::vector<uint32_t>& twin_of, uint32_t& shift,
               std::vector<uint8_t>& bytes, ValenceEncodeResult& result) {
    // Cells from one step finer than the median error to three steps coarser (a seam copy's
    // prediction is worse than a typical boundary vertex's): the most hits wins (ties: the fewest
    // decisions, then the finer cell).
    const uint32_t median = walk.twinShift();
    size_t best_hits = 0, best_decisions = 0;
    shift = median;
    bool first = true;
    for (uint32_t step = 0; step <= 4; ++step) {
        const uint32_t s = std::min(median + step - std::min(median, 1u), kValenceMaxTwinShift);
        std::vector<uint32_t> scratch(vn, kNone);
        const auto d = walk.decideTwins(s, scratch);
        const size_t h = size_t(std::count_if(d.begin(), d.end(), [](const auto& x) { return x.hit; }));
        if (first || h > best_hits || (h == best_hits && d.size() < best_decisions)) {
            best_hits = h;
            best_decisions = d.size();
            shift = s;
            first = false;
        }
    }
    twin_of.assign(vn, kNone);
    const auto decisions = walk.decideTwins(shift, twin_of);
    const size_t hits = size_t(std::count_if(decisions.begin(), decisions.end(), [](const auto& d) { return d.hit; }));
    if (hits == 0 || hits * 8 < decisions.size()) {
        walk.clearTwins();
        twin_of.clear();
        shift = 0;
        return;
    }
    result.twin_decisions = decisions.size();
    result.twin_vertices = hits;
    RangeEncoder rc;
    uint32_t models[lodrt::detail::kTwinContexts];
    initRangeProbs(models, lodrt::detail::kTwinContexts);
    for (const auto& d : decisions) rc.bit(models[d.ctx], d.hit ? 1u : 0u);
    bytes = rc.finish();
}

// Normals after all positions, in final order, each predicted from the exact sum of its faces' normals
// on the quantized positions (the decoder's step 3).
void codeNormals(const Mesh& mesh, uint32_t nb, const FinalOrder& order, const lodrt::detail::ConquestArrays& a,
                 uint32_t tc, const I32Array& qpos_final, const uint32_t* twin_of, RangeEncoder& nrm,
                 BitWriter& nrm_raw) {
    const size_t vn = mesh.vertexCount();
    U32Array qnorm(2 * vn);
    for (size_t i = 0; i < vn; ++i) {
        const float n[3] = {mesh.normals[i].x, mesh.normals[i].y, mesh.normals[i].z};
        uint32_t q[2];
        lodrt::octahedralEncode(n, nb, q);
        qnorm[2 * size_t(order.new_of[i])] = q[0];
        qnorm[2 * size_t(order.new_of[i]) + 1] = q[1];
    }
    // Over the output triangles as the engine's corner table holds them.
    CodecArray<int64_t> sum(3 * vn, 0);
    for (uint32_t t = 0; t < tc; ++t) {
        const uint32_t* cv = &a.corner_vertex[3 * size_t(t)];
        if (!isOutputTriangle(a, cv)) continue;
        const uint32_t f[3] = {order.final_of[cv[0]], order.final_of[cv[1]], order.final_of[cv[2]]};
        lodrt::detail::addFaceNormal(qpos_final.data(), f, sum.data());
    }
    ResidualModel<2, kValenceNormalContexts> nrm_model;
    nrm_model.init();
    const uint32_t mask = (1u << nb) - 1;
    const int32_t half = int32_t(1) << (nb - 1);
    uint32_t nrm_length[2] = {0, 0};
    for (size_t x = 0; x < vn; ++x) {
        uint32_t p[2];
        lodrt::detail::predictNormalTwin(&sum[3 * x], qnorm.data(), x, twin_of ? twin_of[x] : kNone, nb, p);
        for (int j = 0; j < 2; ++j) {
            int32_t r = int32_t((qnorm[2 * x + size_t(j)] - p[j]) & mask);
            if (r >= half) r -= int32_t(mask) + 1;
            const uint32_t ctx = std::min(nrm_length[j], kValenceNormalContexts - 1);
            nrm_length[j] = nrm.residual(nrm_model, nrm_raw, j, ctx, r);
        }
    }
}

// ---- Attributes (format version 7): UV sets, colours, tangents (docs/format/valence.md "Attributes").

using AttributeModel = ResidualModel<4, kValenceAttributeContexts>;

// One attribute as the header's table records it, with its coded parts.
struct CodedAttribute {
    uint8_t kind = 0, components = 0, bits = 0, predictor = 0;
    uint16_t set = 0;
    float min[4] = {0, 0, 0, 0}, size[4] = {0, 0, 0, 0};
    std::vector<uint8_t> range, raw;
    double max_error = 0.0;
};

// Quantized UV or colour values, 4 per input vertex, in the attribute's own range: per component for
// colours, one square range for a UV set (so that the geometric prediction's right angles stay right
// angles in quantized units).
Status quantizeAttribute(const Mesh& mesh, CodedAttribute& at, I32Array& q) {
    const size_t vn = mesh.vertexCount();
    const uint32_t c = at.components;
    auto value = [&](size_t i, uint32_t j) -> float {
        if (at.kind == kValenceAttributeUv) return j == 0 ? mesh.uvs[at.set][i].x : mesh.uvs[at.set][i].y;
        const Vec4f& col = mesh.colors[i];
        return j == 0 ? col.x : (j == 1 ? col.y : (j == 2 ? col.z : col.w));
    };
    float lo[4] = {0, 0, 0, 0}, hi[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < vn; ++i)
        for (uint32_t j = 0; j < c; ++j) {
            const float x = value(i, j);
            if (!std::isfinite(x))
                return invalidInput("valence encoder: vertex " + std::to_string(i) +
                                    (at.kind == kValenceAttributeUv ? ": UV set " + std::to_string(at.set) : ": colour") +
                                    " is not finite");
            lo[j] = i == 0 || x < lo[j] ? x : lo[j];
            hi[j] = i == 0 || x > hi[j] ? x : hi[j];
        }
    float size[4] = {0, 0, 0, 0};
    for (uint32_t j = 0; j < c; ++j) size[j] = hi[j] - lo[j];
    if (at.kind == kValenceAttributeUv) size[0] = size[1] = std::max(size[0], size[1]);
    const uint32_t qmax = (1u << at.bits) - 1;
    for (uint32_t j = 0; j < c; ++j) {
        if (!std::isfinite(size[j])) return invalidInput("valence encoder: attribute range overflows a float");
        at.min[j] = lo[j];
        at.size[j] = size[j];
    }
    q.assign(4 * vn, 0);
    for (size_t i = 0; i < vn; ++i)
        for (uint32_t j = 0; j < c; ++j) {
            const float x = value(i, j);
            const double t = size[j] > 0.0f ? double(x - lo[j]) / double(size[j]) * qmax : 0.0;
            const long v = std::clamp<long>(long(t + 0.5), 0, long(qmax));
            q[4 * i + j] = int32_t(v);
            const double decoded = double(lo[j] + float(v) * (qmax > 0 ? size[j] / float(qmax) : 0.0f));
            at.max_error = std::max(at.max_error, std::fabs(decoded - double(x)));
        }
    return Status::okStatus();
}

// Codes one vertex's UV or colour residuals (wrapped to [-2^(bits-1), 2^(bits-1))); the decoder's
// readAttributeValue.
void codeAttributeValue(RangeEncoder& rc, BitWriter& raw, AttributeModel& model, const CodedAttribute& at,
                        uint32_t n, const int32_t* value, const int32_t* pred, uint32_t& prev_length,
                        uint32_t* prev_sign) {
    const uint32_t mask = (1u << at.bits) - 1;
    const int32_t half = int32_t(1) << (at.bits - 1);
    const bool decorrelated = lodrt::detail::decorrelatedChannels(at.predictor);
    uint32_t earlier = 0, first_sign = 0, first = 0;
    for (uint32_t j = 0; j < at.components; ++j) {
        const uint32_t full = uint32_t(value[j] - pred[j]);
        if (j == 0) first = full;
        int32_t r = int32_t((full - (decorrelated && j > 0 ? first : 0u)) & mask);
        if (r >= half) r -= int32_t(mask) + 1;
        const uint32_t ctx = lodrt::detail::attributeContext(j, n, j == 0 ? prev_length : earlier);
        const uint32_t k = rc.residual(model, raw, int(j), ctx, r, prev_sign[j] * 3 + first_sign);
        prev_sign[j] = lodrt::detail::signClass(r);
        if (j == 0) {
            first_sign = prev_sign[0];
            prev_length = k;
        }
        earlier = std::max(earlier, k);
    }
}

// A UV or colour set over the position plan (the decoder's decodeAttribute), from its quantized input
// values `q`; `final_values` receives them in final order (components per vertex).
void codeAttribute(const PositionWalk& walk, const FinalOrder& order, const I32Array& q, size_t vn, uint32_t vc,
                   CodedAttribute& at, I32Array& final_values) {
    const uint32_t c = at.components;
    const int32_t qmax = int32_t((1u << at.bits) - 1);
    RangeEncoder rc;
    BitWriter raw;
    auto model = std::make_unique<AttributeModel>();
    model->init();
    I32Array qa(4 * size_t(vc), 0);
    final_values.assign(size_t(c) * vn, 0);
    U8Array done(vn, 0);
    int32_t last[4] = {(qmax + 1) / 2, (qmax + 1) / 2, (qmax + 1) / 2, (qmax + 1) / 2};
    uint32_t prev_length = 0, prev_sign[4] = {0, 0, 0, 0};
    const int32_t* qpos = walk.closedPositions();
    walk.forEachPlanned([&](uint32_t ev, const uint32_t* t, uint32_t n, uint32_t neighbour) {
        const uint32_t fid = order.final_of[ev];
        if (fid == kNone) return;
        const int32_t* value = &q[4 * size_t(order.source_of_engine[ev])];
        for (uint32_t j = 0; j < c; ++j) qa[4 * size_t(ev) + j] = value[j];
        if (!done[fid]) {
            int32_t pred[4];
            lodrt::detail::predictAttribute(qa.data(), c, qpos, ev, t, n, neighbour, last, at.predictor, qmax, pred);
            codeAttributeValue(rc, raw, *model, at, n, value, pred, prev_length, prev_sign);
            for (uint32_t j = 0; j < c; ++j) final_values[size_t(c) * fid + j] = value[j];
            done[fid] = 1;
        }
        for (uint32_t j = 0; j < c; ++j) last[j] = value[j];
    });
    for (size_t v = 0; v < vn; ++v) {
        const uint32_t fid = order.new_of[v];
        if (fid < order.referenced) continue;
        for (uint32_t j = 0; j < c; ++j) final_values[size_t(c) * fid + j] = q[4 * v + j];
    }
    for (size_t fid = order.referenced; fid < vn; ++fid) {
        const int32_t* value = &final_values[size_t(c) * fid];
        codeAttributeValue(rc, raw, *model, at, 0, value, last, prev_length, prev_sign);
        for (uint32_t j = 0; j < c; ++j) last[j] = value[j];
    }
    at.range = rc.finish();
    at.raw = raw.finish();
}

// Tangents in final order (the decoder's decodeTangent); `uv` the final-order quantized values of the
// UV attribute named by at.predictor (null for none).
void codeTangents(const Mesh& mesh, const FinalOrder& order, const lodrt::detail::ConquestArrays& a, uint32_t tc,
                  const I32Array& qpos_final, const int32_t* uv, CodedAttribute& at) {
    const size_t vn = mesh.vertexCount();
    const uint32_t nb = at.bits, mask = (1u << nb) - 1;
    U32Array qt(2 * vn);
    std::vector<uint8_t> negative(vn);
    for (size_t i = 0; i < vn; ++i) {
        const Vec4f& t = mesh.tangents[i];
        const float n[3] = {t.x, t.y, t.z};
        const size_t f = order.new_of[i];
        lodrt::octahedralEncode(n, nb, &qt[2 * f]);
        negative[f] = t.w < 0.0f ? 1 : 0;
        float d[3];
        lodrt::octahedralDecode(&qt[2 * f], nb, d);
        const double len = std::sqrt(double(t.x) * t.x + double(t.y) * t.y + double(t.z) * t.z);
        if (len > 0.0 && std::isfinite(len))
            for (int j = 0; j < 3; ++j) at.max_error = std::max(at.max_error, std::fabs(double(d[j]) - n[j] / len));
    }
    CodecArray<int64_t> sum(4 * vn, 0);
    if (uv)
        for (uint32_t t = 0; t < tc; ++t) {
            const uint32_t* cv = &a.corner_vertex[3 * size_t(t)];
            if (!isOutputTriangle(a, cv)) continue;
            const uint32_t f[3] = {order.final_of[cv[0]], order.final_of[cv[1]], order.final_of[cv[2]]};
            lodrt::detail::addFaceTangent(qpos_final.data(), uv, f, sum.data());
        }
    RangeEncoder rc;
    BitWriter raw;
    ResidualModel<2, kValenceNormalContexts> model;
    model.init();
    uint32_t sign_models[kValenceTangentSignContexts];
    initRangeProbs(sign_models, kValenceTangentSignContexts);
    const int32_t half = int32_t(1) << (nb - 1);
    uint32_t length[2] = {0, 0};
    for (size_t x = 0; x < vn; ++x) {
        uint32_t p[2];
        lodrt::detail::predictNormal(&sum[4 * x], qt.data(), x, nb, p);
        for (int j = 0; j < 2; ++j) {
            int32_t r = int32_t((qt[2 * x + size_t(j)] - p[j]) & mask);
            if (r >= half) r -= int32_t(mask) + 1;
            length[j] = rc.residual(model, raw, j, std::min(length[j], kValenceNormalContexts - 1), r);
        }
        rc.bit(sign_models[lodrt::detail::tangentSignContext(sum[4 * x + 3])], negative[x]);
    }
    at.range = rc.finish();
    at.raw = raw.finish();
}

// Every attribute the options and the mesh have, coded: UV sets (each with the smaller of its two
// predictors), then the colours, then the tangents (predicted on UV set 0 when there is one).
Result<std::vector<CodedAttribute>> codeAttributes(const Mesh& mesh, const ValenceEncodeOptions& options,
                                                   const PositionWalk& walk, const FinalOrder& order,
                                                   const lodrt::detail::ConquestArrays& a, uint32_t vc, uint32_t tc) {
    std::vector<CodedAttribute> out;
    const size_t vn = mesh.vertexCount();
    I32Array q, uv0_final;
    for (size_t s = 0; s < mesh.uvs.size(); ++s) {
        CodedAttribute base;
        base.kind = kValenceAttributeUv;
        base.components = 2;
        base.bits = uint8_t(options.uv_bits);
        base.set = uint16_t(s);
        LODBAKE_RETURN_IF_ERROR(quantizeAttribute(mesh, base, q));
        CodedAttribute best;
        I32Array best_final;
        bool have = false;
        for (uint8_t predictor : {kValencePredictUvGeometric, kValencePredictParallelogram}) {
            CodedAttribute at = base;
            at.predictor = predictor;
            I32Array final_values;
            codeAttribute(walk, order, q, vn, vc, at, final_values);
            if (!have || at.range.size() + at.raw.size() < best.range.size() + best.raw.size()) {
                best = std::move(at);
                best_final = std::move(final_values);
                have = true;
            }
        }
        if (s == 0) uv0_final = std::move(best_final);
        out.push_back(std::move(best));
    }
    if (mesh.hasColors()) {
        // Parallelogram or neighbour mean, channels coded on their own or relative to channel 0's
        // residual (a scan's colour errors are mostly in brightness, shared by the channels):
        // whichever of the four is smallest.
        CodedAttribute base;
        base.kind = kValenceAttributeColor;
        const bool opaque = std::all_of(mesh.colors.begin(), mesh.colors.end(), [](const Vec4f& c) { return c.w == 1.0f; });
        base.components = opaque ? 3 : 4;
        base.bits = uint8_t(options.color_bits);
        LODBAKE_RETURN_IF_ERROR(quantizeAttribute(mesh, base, q));
        CodedAttribute best;
        for (uint8_t predictor : {kValencePredictParallelogram, kValencePredictColorDecorrelated,
                                  kValencePredictNeighbourMean, kValencePredictNeighbourMeanDecorrelated}) {
            CodedAttribute at = base;
            at.predictor = predictor;
            I32Array final_values;
            codeAttribute(walk, order, q, vn, vc, at, final_values);
            if (predictor == kValencePredictParallelogram ||
                at.range.size() + at.raw.size() < best.range.size() + best.raw.size())
                best = std::move(at);
        }
        out.push_back(std::move(best));
    }
    if (mesh.hasTangents()) {
        CodedAttribute at;
        at.kind = kValenceAttributeTangent;
        at.components = 4;
        at.bits = uint8_t(options.tangent_bits);
        at.predictor = mesh.uvs.empty() ? kValenceNoReference : 0;
        codeTangents(mesh, order, a, tc, walk.finalPositions(), mesh.uvs.empty() ? nullptr : uv0_final.data(), at);
        out.push_back(std::move(at));
    }
    return out;
}

// The attribute table (format.h, kValenceFlagAttributes) for `attributes`.
std::vector<uint8_t> attributeTable(const std::vector<CodedAttribute>& attributes, size_t twin_bytes,
                                    uint32_t twin_shift) {
    std::vector<uint8_t> t(kValenceAttributeTablePrefix + attributes.size() * kValenceAttributeRecordSize, 0);
    put32(t, 0, uint32_t(attributes.size()));
    put32(t, 4, uint32_t(twin_bytes));
    t[8] = uint8_t(twin_shift);
    for (size_t i = 0; i < attributes.size(); ++i) {
        const CodedAttribute& at = attributes[i];
        const size_t o = kValenceAttributeTablePrefix + i * kValenceAttributeRecordSize;
        t[o] = at.kind;
        t[o + 1] = at.components;
        t[o + 2] = at.bits;
        t[o + 3] = at.predictor;
        t[o + 4] = uint8_t(at.set);
        t[o + 5] = uint8_t(at.set >> 8);
        for (size_t j = 0; j < 4; ++j) {
            putF32(t, o + 8 + 4 * j, at.min[j]);
            putF32(t, o + 24 + 4 * j, at.size[j]);
        }
        put32(t, o + 40, uint32_t(at.range.size()));
        put32(t, o + 44, uint32_t(at.raw.size()));
    }
    return t;
}

// The decoded attributes into the mesh's UV sets, colours (alpha 1 for RGB) and tangents.
void copyAttributes(const lodrt::ValenceInfo& info, const std::vector<std::vector<float>>& decoded, Mesh& mesh) {
    const size_t vn = info.vertex_count;
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        const lodrt::ValenceAttribute& at = info.attributes[i];
        const std::vector<float>& d = decoded[i];
        if (at.kind == kValenceAttributeUv) {
            if (mesh.uvs.size() <= at.set) mesh.uvs.resize(size_t(at.set) + 1, std::vector<Vec2f>(vn, Vec2f{0, 0}));
            for (size_t v = 0; v < vn; ++v) mesh.uvs[at.set][v] = Vec2f{d[2 * v], d[2 * v + 1]};
        } else if (at.kind == kValenceAttributeColor) {
            mesh.colors.resize(vn);
            const size_t c = at.components;
            for (size_t v = 0; v < vn; ++v)
                mesh.colors[v] = Vec4f{d[c * v], d[c * v + 1], d[c * v + 2], c == 4 ? d[c * v + 3] : 1.0f};
        } else {
            mesh.tangents.resize(vn);
            for (size_t v = 0; v < vn; ++v) mesh.tangents[v] = Vec4f{d[4 * v], d[4 * v + 1], d[4 * v + 2], d[4 * v + 3]};
        }
    }
}

} // namespace

Result<ValenceEncodeResult> encodeValence(const Mesh& mesh, const ValenceEncodeOptions& options) {
    const bool normals = options.encode_normals && mesh.hasNormals();
    LODBAKE_RETURN_IF_ERROR(checkEncodable(mesh, options, normals));
    const size_t vn = mesh.vertexCount(), fn = mesh.faceCount();
    ValenceEncodeResult result;
    Quantization quantized;
    LODBAKE_RETURN_IF_ERROR(quantizePositions(mesh, options, quantized, result.max_position_error));
    LODBAKE_ASSIGN_OR_RETURN(std::unique_ptr<Attempt> attempt, conquer(mesh));
    const auto& a = attempt->engine.a;
    const uint32_t vc = uint32_t(attempt->closed.source.size()),
                   tc = uint32_t(attempt->closed.corner_vertex.size() / 3);
    FinalOrder order = orderVertices(*attempt, vn);

    // Output triangles: the closed ones without a dummy vertex.
    EncoderIo& io = attempt->io;
    result.old_face_of.reserve(fn);
    for (uint32_t t = 0; t < tc; ++t)
        if (isOutputTriangle(a, &a.corner_vertex[3 * size_t(t)]))
            result.old_face_of.push_back(io.real_of[3 * size_t(t)] / 3);
    U32Array().swap(io.real_of);
    if (result.old_face_of.size() != fn) return internalError("valence encoder: triangle count mismatch");

    PositionWalk walk(a, order, quantized, vn, vc, tc);
    if (!walk.planned()) return internalError("valence encoder: broken corner cycle");
    // Twins only in a stream with attributes (version 7): without them the bytes stay version 6's.
    const bool has_attributes =
        options.encode_attributes && (!mesh.uvs.empty() || mesh.hasColors() || mesh.hasTangents());
    std::vector<uint32_t> twin_of;
    uint32_t twin_shift = 0;
    std::vector<uint8_t> twin_bytes;
    if (has_attributes) codeTwins(walk, vn, twin_of, twin_shift, twin_bytes, result);
    uint16_t flags_pos = 0;
    RangeEncoder pos;
    BitWriter pos_raw;
    {
        CodecArray<CodedValue> walked;
        flags_pos = choosePositionFlags(walk, vn, walked);
        codePositions(walked, flags_pos, pos, pos_raw);
    }
    std::vector<CodedAttribute> attributes;
    if (options.encode_attributes) {
        LODBAKE_ASSIGN_OR_RETURN(attributes, codeAttributes(mesh, options, walk, order, a, vc, tc));
    }
    walk.releasePlan();
    RangeEncoder nrm;
    BitWriter nrm_raw;
    if (normals)
        codeNormals(mesh, options.normal_bits, order, a, tc, walk.finalPositions(), twin_of.empty() ? nullptr : twin_of.data(),
                    nrm, nrm_raw);

    std::vector<uint8_t> conn_bytes = attempt->conn.finish(), pos_bytes = pos.finish(),
                         pos_raw_bytes = pos_raw.finish(), nrm_bytes, nrm_raw_bytes;
    if (normals) {
        nrm_bytes = nrm.finish();
        nrm_raw_bytes = nrm_raw.finish();
    }
    std::vector<uint8_t>& out = result.bytes;
    out.assign(kValenceHeaderSize, 0);
    put32(out, 0, kValenceMagic);
    // Without attributes the stream is a version 6 one, byte for byte (format.h).
    const uint16_t version = attributes.empty() ? kValenceVersionWithoutAttributes : kValenceVersion;
    out[4] = uint8_t(version);
    out[5] = uint8_t(version >> 8);
    const uint16_t flags =
        uint16_t((normals ? kValenceFlagNormals : 0) | flags_pos | (attributes.empty() ? 0 : kValenceFlagAttributes));
    out[6] = uint8_t(flags);
    out[7] = uint8_t(flags >> 8);
    put32(out, 8, uint32_t(vn));
    put32(out, 12, uint32_t(fn));
    put32(out, 16, vc);
    put32(out, 20, tc);
    out[24] = uint8_t(options.position_bits);
    out[25] = normals ? uint8_t(options.normal_bits) : 0;
    for (int j = 0; j < 3; ++j) putF32(out, 28 + 4 * size_t(j), quantized.lo[j]);
    putF32(out, 40, quantized.cube);
    put32(out, 44, uint32_t(conn_bytes.size()));
    put32(out, 48, uint32_t(pos_bytes.size()));
    put32(out, 52, uint32_t(nrm_bytes.size()));
    put32(out, 56, uint32_t(pos_raw_bytes.size()));
    put32(out, 60, uint32_t(nrm_raw_bytes.size()));
    if (!attributes.empty()) {
        const std::vector<uint8_t> table = attributeTable(attributes, twin_bytes.size(), twin_shift);
        out.insert(out.end(), table.begin(), table.end());
    }
    result.header_bytes = out.size();
    for (const std::vector<uint8_t>* part :
         {&conn_bytes, &pos_bytes, &pos_raw_bytes, &twin_bytes, &nrm_bytes, &nrm_raw_bytes})
        out.insert(out.end(), part->begin(), part->end());
    for (const CodedAttribute& at : attributes) {
        out.insert(out.end(), at.range.begin(), at.range.end());
        out.insert(out.end(), at.raw.begin(), at.raw.end());
        ValenceAttributeReport report;
        report.kind = at.kind;
        report.set = at.set;
        report.bits = at.bits;
        report.bytes = at.range.size() + at.raw.size();
        report.max_error = at.max_error;
        result.attributes.push_back(report);
    }
    result.connectivity_bytes = conn_bytes.size();
    result.position_bytes = pos_bytes.size() + pos_raw_bytes.size() + twin_bytes.size();
    result.normal_bytes = nrm_bytes.size() + nrm_raw_bytes.size();
    result.cut_vertex_copies = order.dups.size();
    result.dummy_vertices = vc - order.rank;
    result.new_vertex_of = std::move(order.new_of);
    return result;
}

Result<Mesh> decodeValence(const std::vector<uint8_t>& bytes, const std::string& name) {
    lodrt::ValenceInfo info;
    lodrt::Result r = lodrt::valenceReadInfo(bytes.data(), bytes.size(), &info);
    if (r != lodrt::Result::Ok) return invalidInput(name + ": header: " + describe(r, bytes));
    Mesh mesh;
    std::vector<float> positions(3 * size_t(info.vertex_count)), normals;
    if (info.has_normals) normals.resize(3 * size_t(info.vertex_count));
    mesh.indices.resize(3 * size_t(info.triangle_count));
    // Not value-initialised: the decoder writes every scratch word before it reads it, and the parts
    // sized for the worst case (the prediction triples) stay untouched and so cost no resident memory.
    const size_t scratch_words = (lodrt::valenceScratchSize(info) + 7) / 8;
    std::unique_ptr<uint64_t[]> scratch(new uint64_t[scratch_words]);
    lodrt::ValenceOutput output;
    output.indices = mesh.indices.data();
    output.index_capacity = mesh.indices.size();
    output.positions = positions.data();
    output.position_capacity = positions.size();
    output.normals = info.has_normals ? normals.data() : nullptr;
    output.normal_capacity = normals.size();
    output.scratch = scratch.get();
    output.scratch_size = scratch_words * 8;
    std::vector<std::vector<float>> attributes(info.attribute_count);
    for (uint32_t i = 0; i < info.attribute_count; ++i) {
        attributes[i].resize(size_t(info.attributes[i].components) * info.vertex_count);
        output.attributes[i] = attributes[i].data();
        output.attribute_capacity[i] = attributes[i].size();
    }
    r = lodrt::valenceDecode(bytes.data(), bytes.size(), output);
    scratch.reset(); // before the copies below: they need no scratch
    if (r != lodrt::Result::Ok) return invalidInput(name + ": streams: " + describe(r, bytes));
    mesh.positions.resize(info.vertex_count);
    for (size_t i = 0; i < info.vertex_count; ++i)
        mesh.positions[i] = Vec3f{positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
    std::vector<float>().swap(positions);
    if (info.has_normals) {
        mesh.normals.resize(info.vertex_count);
        for (size_t i = 0; i < info.vertex_count; ++i)
            mesh.normals[i] = Vec3f{normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]};
    }
    copyAttributes(info, attributes, mesh);
    return mesh;
}

} // namespace lodbake::codec
