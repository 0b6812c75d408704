// PFRep builder (Cortés Carrillo, progressive fans): replays a half-edge-collapse sequence, stores
// every triangle once at its lowest-ranked corner as a fan slot with its dependency, decomposes
// each vertex's opposite edges into walks ("crowns") concatenated into one cyclic sequence A_i with
// one validity mask per dependency, and writes the blob of docs/format/pfrep.md.
#include "lodbake/pfrep/pfrep_builder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <unordered_map>

#include "core/byte_order.h"
#include "core/large_array.h"
#include "core/parallel.h"
#include "lodbake/simplify/quadric.h"
#include "lodrt/format.h"

namespace lodbake {
namespace {

constexpr uint32_t kNone = 0xffffffffu;
// Items per task of the parallel loops (fixed, so nothing depends on the thread count).
constexpr size_t kChunk = 4096;

struct Triangle {
    uint32_t p[3];
    uint32_t dependency; // point whose removal created it, kNone for input triangles
};

uint32_t bitWidth(uint32_t v) {
    return v == 0 ? 0 : 32 - uint32_t(__builtin_clz(v));
}

class BitWriter {
public:
    // The low `bits` bits of value, least significant first, through a 64-bit accumulator that is
    // flushed a byte at a time.
    void write(uint64_t value, uint32_t bits) {
        while (bits > 32) {
            put(uint32_t(value), 32);
            value >>= 32;
            bits -= 32;
        }
        put(uint32_t(value), bits);
    }
    void alignByte() {
        if (pending_bits_ > 0) {
            bytes_.push_back(uint8_t(pending_));
            pending_ = 0;
            pending_bits_ = 0;
        }
    }
    size_t byteSize() const { return bytes_.size() + (pending_bits_ > 0 ? 1 : 0); }
    std::vector<uint8_t>& bytes() {
        alignByte();
        return bytes_;
    }

private:
    void put(uint32_t value, uint32_t bits) {
        if (bits == 0) return;
        if (bits < 32) value &= (1u << bits) - 1;
        pending_ |= uint64_t(value) << pending_bits_;
        pending_bits_ += bits;
        while (pending_bits_ >= 8) {
            bytes_.push_back(uint8_t(pending_));
            pending_ >>= 8;
            pending_bits_ -= 8;
        }
    }

    std::vector<uint8_t> bytes_;
    uint64_t pending_ = 0; // bits not yet in bytes_ (fewer than 8 between calls)
    uint32_t pending_bits_ = 0;
};

void writeCount(BitWriter& w, uint32_t count, uint32_t bits) {
    const uint32_t escape = (1u << bits) - 1;
    if (count < escape) {
        w.write(count, bits);
    } else {
        w.write(escape, bits);
        w.write(count - escape, lodrt::format::kPfrepCountEscapeBits);
    }
}

Vec3d toD(const Vec3f& v) {
    return Vec3d(v);
}

double pointTriangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    // Closest point on a triangle (Ericson, Real-Time Collision Detection §5.1.5).
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0 && d2 <= 0) return length(p - a);
    const Vec3d bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0 && d4 <= d3) return length(p - b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return length(p - (a + ab * (d1 / (d1 - d3))));
    const Vec3d cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0 && d5 <= d6) return length(p - c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return length(p - (a + ac * (d2 / (d2 - d6))));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
    const double denom = 1.0 / (va + vb + vc);
    return length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

uint8_t logCode(double value, double unit) {
    if (!(value > 0) || !(unit > 0)) return 0;
    const double c = std::ceil(std::log2(value / unit) * lodrt::format::kPfrepLogCodeSteps) + 1;
    return uint8_t(std::clamp(c, 1.0, 255.0));
}

uint16_t coneCode(const Vec3d& axis, double angle) {
    // Octahedral axis (6 + 6 bits) and angle in 15ths of pi, rounded up; the angle is widened by the
    // axis quantization error so the stored cone still contains every normal.
    Vec3d n = normalize(axis);
    if (length(n) == 0) return uint16_t(15u << 12);
    const double s = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
    double x = n.x / s, y = n.y / s;
    if (n.z < 0) {
        const double ox = x;
        x = (1 - std::fabs(y)) * (ox >= 0 ? 1 : -1);
        y = (1 - std::fabs(ox)) * (y >= 0 ? 1 : -1);
    }
    const uint32_t qx = uint32_t(std::lround((x * 0.5 + 0.5) * 63));
    const uint32_t qy = uint32_t(std::lround((y * 0.5 + 0.5) * 63));
    // Decode as the runtime does to measure the axis error.
    double dx = qx / 63.0 * 2 - 1, dy = qy / 63.0 * 2 - 1, dz = 1 - std::fabs(dx) - std::fabs(dy);
    if (dz < 0) {
        const double ox = dx;
        dx = (1 - std::fabs(dy)) * (ox >= 0 ? 1 : -1);
        dy = (1 - std::fabs(ox)) * (dy >= 0 ? 1 : -1);
    }
    const Vec3d decoded = normalize(Vec3d(dx, dy, dz));
    const double err = std::acos(std::clamp(dot(decoded, n), -1.0, 1.0));
    const double a = angle + err;
    const uint32_t code = a >= M_PI ? 15u : std::min(15u, uint32_t(std::ceil(a / M_PI * 15.0)));
    return uint16_t(qx | (qy << 6) | (code << 12));
}

} // namespace

Result<std::vector<uint32_t>> pointTriangles(const Mesh& mesh, const CollapseSequence& sequence) {
    struct Key {
        uint32_t b[3];
        bool operator==(const Key& o) const { return b[0] == o.b[0] && b[1] == o.b[1] && b[2] == o.b[2]; }
    };
    struct KeyHash {
        size_t operator()(const Key& k) const {
            return size_t(k.b[0]) * 0x9E3779B97F4A7C15ull ^ size_t(k.b[1]) * 0xC2B2AE3D27D4EB4Full ^ k.b[2];
        }
    };
    auto key = [](const Vec3f& p) {
        Key k;
        std::memcpy(&k.b[0], &p.x, 4);
        std::memcpy(&k.b[1], &p.y, 4);
        std::memcpy(&k.b[2], &p.z, 4);
        return k;
    };
    std::unordered_map<Key, uint32_t, KeyHash> point_of;
    point_of.reserve(sequence.point_positions.size() * 2);
    for (uint32_t p = 0; p < sequence.point_positions.size(); ++p)
        point_of.emplace(key(sequence.point_positions[p]), p);
    // One look-up per referenced vertex (not per corner).
    std::vector<uint32_t> point_of_vertex(mesh.positions.size(), kNone);
    std::vector<uint32_t> out;
    out.reserve(mesh.indices.size());
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        uint32_t t[3];
        for (int k = 0; k < 3; ++k) {
            const uint32_t vertex = mesh.indices[f * 3 + k];
            uint32_t& point = point_of_vertex[vertex];
            if (point == kNone) {
                auto it = point_of.find(key(mesh.positions[vertex]));
                if (it == point_of.end())
                    return invalidInput("pfrep: face " + std::to_string(f) + ": position not in the collapse sequence");
                point = it->second;
            }
            t[k] = point;
        }
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        out.insert(out.end(), t, t + 3);
    }
    return out;
}

namespace {

struct Slot {
    uint32_t a, b, dep; // ranks; dep kNone for input triangles
};

// Entries. Each starts on a byte boundary and depends only on its own fan, so fixed chunks of
// vertices are written in parallel, each into its own stream, and concatenated in order: the
// same bytes as one stream written entry after entry.
struct EntryChunk {
    BitWriter stream;
    Status status = Status::okStatus();
    size_t dependency_groups = 0, neighbour_slots = 0;
};

// buildBlob's working arrays, from step to step.
struct BlobState {
    BlobState(const CollapseSequence& seq, uint32_t points)
        : sequence(seq), point_count(points), rank_of(points, kNone), removal_error(points, 0.0),
          referenced(points, 0) {
        rank_point.reserve(points);
    }
    const CollapseSequence& sequence;
    uint32_t point_count;
    detail::LargeArray<Triangle> tris;        // every stored triangle (buildFans: as ranks)
    detail::LargeArray<uint32_t> rank_of;     // per point
    std::vector<uint32_t> rank_point;         // per rank: the removed points in order, then the survivors
    detail::LargeArray<double> removal_error; // per point
    detail::LargeArray<uint8_t> referenced;   // per point: on an input triangle
    uint32_t removed = 0, vertex_count = 0;
    size_t level0 = 0, stored_triangles = 0;
    detail::LargeArray<uint32_t> fan_first; // per rank, its fan's first slot; then the end
    detail::LargeArray<Slot> slots;
    detail::LargeArray<double> err, radius, cone_angle; // per rank: the view-dependent bounds
    detail::LargeArray<Vec3d> axis;
    detail::LargeArray<uint32_t> entry_offset; // per rank: its entry's offset in `stream`
    BitWriter stream;                          // the entries
};

// Record r, before it is ranked: both points valid and not yet removed, the kept point unmoved.
Status checkRecord(const BlobState& state, size_t r) {
    const CollapseSequence& sequence = state.sequence;
    const uint32_t point_count = state.point_count;
    const detail::LargeArray<uint32_t>& rank_of = state.rank_of;
    const CollapseRecord& rec = sequence.records[r];
    const uint32_t u = rec.removed_point, v = rec.kept_point;
    if (u >= point_count || v >= point_count || u == v || rank_of[u] != kNone || rank_of[v] != kNone)
        return invalidInput("pfrep: collapse " + std::to_string(r) + ": bad points");
    if (rec.position != sequence.point_positions[v])
        return invalidInput("pfrep: collapse " + std::to_string(r) +
                            ": the kept point moves (full-edge collapse); PFRep needs placement KeepEndpoint");
    return Status::okStatus();
}

// The simplifier logs the triangles each record re-creates (CollapseSequence::created_triangles):
// then the list of every triangle is the input's followed by the log, and no replay is needed.
Status listLoggedTriangles(BlobState& state, const std::vector<uint32_t>& point_triangles,
                           CollapseSequence* releasable, std::vector<uint32_t>* releasable_triangles) {
    const CollapseSequence& sequence = state.sequence;
    const uint32_t point_count = state.point_count;
    const size_t input_count = point_triangles.size() / 3;
    detail::LargeArray<Triangle>& tris = state.tris;
    detail::LargeArray<uint32_t>& rank_of = state.rank_of;
    std::vector<uint32_t>& rank_point = state.rank_point;
    detail::LargeArray<double>& removal_error = state.removal_error;
    detail::LargeArray<uint8_t>& referenced = state.referenced;
    const size_t created_count = sequence.created_end.back();
    if (sequence.created_triangles.size() != created_count * 3)
        return invalidInput("pfrep: the re-created triangle log does not match its ranges");
    for (uint32_t p : point_triangles) referenced[p] = 1;
    tris.reserve(input_count + created_count);
    for (size_t t = 0; t < input_count; ++t)
        tris.push_back({{point_triangles[t * 3], point_triangles[t * 3 + 1], point_triangles[t * 3 + 2]}, kNone});
    size_t first = 0;
    for (size_t r = 0; r < sequence.records.size(); ++r) {
        LODBAKE_RETURN_IF_ERROR(checkRecord(state, r));
        const uint32_t u = sequence.records[r].removed_point;
        const size_t last = sequence.created_end[r];
        if (last < first || last > created_count)
            return invalidInput("pfrep: collapse " + std::to_string(r) + ": bad re-created triangle range");
        rank_of[u] = uint32_t(rank_point.size());
        rank_point.push_back(u);
        for (size_t t = first; t < last; ++t) {
            const uint32_t* c = &sequence.created_triangles[t * 3];
            if (c[0] >= point_count || c[1] >= point_count || c[2] >= point_count)
                return invalidInput("pfrep: collapse " + std::to_string(r) +
                                    ": re-created triangle point out of range");
            tris.push_back({{c[0], c[1], c[2]}, u});
        }
        first = last;
    }
    // Each removed point's error: its distance to the nearest triangle its removal creates (0
    // when it creates none). Independent per record: fixed chunks in parallel.
    LODBAKE_RETURN_IF_ERROR(parallelFor(sequence.records.size(), kChunk, [&](size_t r) {
        const uint32_t u = sequence.records[r].removed_point;
        const size_t lo = r == 0 ? 0 : sequence.created_end[r - 1], hi = sequence.created_end[r];
        double err = HUGE_VAL;
        const Vec3d pu = toD(sequence.point_positions[u]);
        for (size_t t = lo; t < hi; ++t) {
            const uint32_t* c = &sequence.created_triangles[t * 3];
            err = std::min(err, pointTriangleDistance(pu, toD(sequence.point_positions[c[0]]),
                                                      toD(sequence.point_positions[c[1]]),
                                                      toD(sequence.point_positions[c[2]])));
        }
        removal_error[u] = hi > lo ? err : 0.0;
    }));
    if (releasable) {
        std::vector<uint32_t>().swap(releasable->created_triangles);
        std::vector<uint32_t>().swap(*releasable_triangles);
    }
    return Status::okStatus();
}

// Replays the sequence to list the triangles each record re-creates.
Status replayCollapses(BlobState& state, const std::vector<uint32_t>& point_triangles) {
    const CollapseSequence& sequence = state.sequence;
    const uint32_t point_count = state.point_count;
    const size_t input_count = point_triangles.size() / 3;
    detail::LargeArray<Triangle>& tris = state.tris;
    detail::LargeArray<uint32_t>& rank_of = state.rank_of;
    std::vector<uint32_t>& rank_point = state.rank_point;
    detail::LargeArray<double>& removal_error = state.removal_error;
    detail::LargeArray<uint8_t>& referenced = state.referenced;
    tris.reserve(point_triangles.size() / 3 * 3);
    // Alive incident triangles of every point, in insertion order, as ranges of one pool: laid out
    // point after point for the input, a range moves to the pool's end when it outgrows its capacity.
    // A triangle leaves its corners' ranges when it dies, so a removed point's range is its ring.
    struct Range {
        uint32_t offset = 0, size = 0, capacity = 0;
    };
    detail::LargeArray<Range> incident(point_count);
    for (uint32_t p : point_triangles) ++incident[p].capacity;
    size_t pool_size = 0;
    for (uint32_t p = 0; p < point_count; ++p) {
        referenced[p] = incident[p].capacity > 0;
        incident[p].offset = uint32_t(pool_size);
        incident[p].capacity += 4; // room for the triangles a neighbour's removal brings
        pool_size += incident[p].capacity;
    }
    if (pool_size > 0xffffffffu / 2) return resourceLimit("pfrep: too many triangles");
    detail::LargeArray<uint32_t> pool(pool_size);
    pool.reserve(pool_size + pool_size / 2);
    auto link = [&](uint32_t p, uint32_t t) {
        Range& r = incident[p];
        if (r.size == r.capacity) {
            const uint32_t offset = uint32_t(pool.size());
            pool.resize(pool.size() + size_t(r.capacity) * 2);
            std::copy(pool.begin() + r.offset, pool.begin() + r.offset + r.size, pool.begin() + offset);
            r.offset = offset;
            r.capacity *= 2;
        }
        pool[r.offset + r.size++] = t;
    };
    auto unlink = [&](uint32_t p, uint32_t t) {
        Range& r = incident[p];
        uint32_t* first = pool.data() + r.offset;
        r.size = uint32_t(std::remove(first, first + r.size, t) - first);
    };
    for (size_t t = 0; t < input_count; ++t) {
        Triangle tri{{point_triangles[t * 3], point_triangles[t * 3 + 1], point_triangles[t * 3 + 2]}, kNone};
        for (uint32_t p : tri.p) link(p, uint32_t(tris.size()));
        tris.push_back(tri);
    }

    // Replay: ranks in removal order, then the survivors that have faces, by point id. The
    // triangles record r re-creates are tris[created_end[r - 1], created_end[r]).
    std::vector<uint32_t> ring;
    detail::LargeArray<uint32_t> created_end(sequence.records.size());
    for (size_t r = 0; r < sequence.records.size(); ++r) {
        const CollapseRecord& rec = sequence.records[r];
        const uint32_t u = rec.removed_point, v = rec.kept_point;
        LODBAKE_RETURN_IF_ERROR(checkRecord(state, r));
        rank_of[u] = uint32_t(rank_point.size());
        rank_point.push_back(u);
        ring.assign(pool.begin() + incident[u].offset, pool.begin() + incident[u].offset + incident[u].size);
        if (ring.empty())
            return invalidInput("pfrep: collapse " + std::to_string(r) + ": removed point has no faces");
        incident[u].size = 0;
        for (uint32_t t : ring) {
            for (uint32_t p : tris[t].p)
                if (p != u) unlink(p, t);
            const Triangle& old = tris[t];
            if (old.p[0] == v || old.p[1] == v || old.p[2] == v) continue;
            Triangle fresh = old;
            for (uint32_t& p : fresh.p)
                if (p == u) p = v;
            fresh.dependency = u;
            const uint32_t id = uint32_t(tris.size());
            tris.push_back(fresh);
            for (uint32_t p : fresh.p) link(p, id);
        }
        created_end[r] = uint32_t(tris.size());
    }
    detail::LargeArray<uint32_t>().swap(pool);
    detail::LargeArray<Range>().swap(incident);
    // Each removed point's error (its distance to the nearest triangle its removal creates, 0 when
    // it creates none), after the replay: independent per record, fixed chunks in parallel.
    LODBAKE_RETURN_IF_ERROR(parallelFor(sequence.records.size(), kChunk, [&](size_t r) {
        const uint32_t u = sequence.records[r].removed_point;
        const size_t lo = r == 0 ? input_count : created_end[r - 1], hi = created_end[r];
        double err = HUGE_VAL;
        const Vec3d pu = toD(sequence.point_positions[u]);
        for (size_t t = lo; t < hi; ++t)
            err = std::min(err, pointTriangleDistance(pu, toD(sequence.point_positions[tris[t].p[0]]),
                                                      toD(sequence.point_positions[tris[t].p[1]]),
                                                      toD(sequence.point_positions[tris[t].p[2]])));
        removal_error[u] = hi > lo ? err : 0.0;
    }));
    return Status::okStatus();
}

// Every triangle goes to the fan of its lowest-ranked corner, rotated to start there. The rank
// look-ups (random accesses) are done in parallel, in place: each triangle becomes its corners'
// ranks rotated to start at the lowest, and its dependency's rank.
Status buildFans(BlobState& state) {
    const uint32_t vertex_count = state.vertex_count;
    detail::LargeArray<Triangle>& tris = state.tris;
    const detail::LargeArray<uint32_t>& rank_of = state.rank_of;
    size_t& level0 = state.level0;
    detail::LargeArray<uint32_t>& fan_first = state.fan_first;
    detail::LargeArray<Slot>& slots = state.slots;
    for (const Triangle& t : tris) level0 += t.dependency == kNone;
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(tris.size(), kChunk, [&](size_t, size_t first, size_t last) {
        for (size_t i = first; i < last; ++i) {
            Triangle& t = tris[i];
            const uint32_t r[3] = {rank_of[t.p[0]], rank_of[t.p[1]], rank_of[t.p[2]]};
            int m = 0;
            if (r[1] < r[m]) m = 1;
            if (r[2] < r[m]) m = 2;
            t = {{r[m], r[(m + 1) % 3], r[(m + 2) % 3]}, t.dependency == kNone ? kNone : rank_of[t.dependency]};
        }
    }));
    fan_first.assign(vertex_count + 1, 0);
    for (const Triangle& t : tris) ++fan_first[t.p[0] + 1];
    for (uint32_t i = 0; i < vertex_count; ++i) fan_first[i + 1] += fan_first[i];
    slots.resize(tris.size());
    {
        detail::LargeArray<uint32_t> fill(fan_first.begin(), fan_first.end() - 1);
        for (const Triangle& t : tris) slots[fill[t.p[0]]++] = {t.p[1], t.p[2], t.dependency};
    }
    state.stored_triangles = tris.size();
    detail::LargeArray<Triangle>().swap(tris); // the slots hold everything from here on
    return Status::okStatus();
}

// Triangles per level: the slot at entry c with dependency d lives in levels (d, c] (from 0 for
// input triangles), capped at the last level.
std::vector<uint32_t> countLevelTriangles(const BlobState& state) {
    const uint32_t removed = state.removed, vertex_count = state.vertex_count;
    const detail::LargeArray<uint32_t>& fan_first = state.fan_first;
    const detail::LargeArray<Slot>& slots = state.slots;
    detail::LargeArray<int64_t> level_delta(size_t(removed) + 2, 0);
    for (uint32_t c = 0; c < vertex_count; ++c)
        for (uint32_t s = fan_first[c]; s < fan_first[c + 1]; ++s) {
            const uint32_t from = slots[s].dep == kNone ? 0 : slots[s].dep + 1;
            const uint32_t to = std::min(c, removed);
            if (from > to) continue;
            ++level_delta[from];
            --level_delta[size_t(to) + 1];
        }
    std::vector<uint32_t> level_triangles(size_t(removed) + 1);
    int64_t running = 0;
    for (uint32_t k = 0; k <= removed; ++k) level_triangles[k] = uint32_t(running += level_delta[k]);
    return level_triangles;
}

// Per-vertex bounds for the view-dependent criterion, accumulated over dependencies (whose
// ranks are lower, so already final): error and sphere grow monotonically up the hierarchy.
// Each vertex's own fan is measured in parallel (fixed chunks); then one pass in rank order adds
// what the dependencies bring. Every value is a maximum, so splitting the two changes no bit.
Status computeVertexBounds(BlobState& state) {
    const CollapseSequence& sequence = state.sequence;
    const std::vector<uint32_t>& rank_point = state.rank_point;
    const uint32_t removed = state.removed, vertex_count = state.vertex_count;
    const detail::LargeArray<uint32_t>& fan_first = state.fan_first;
    const detail::LargeArray<Slot>& slots = state.slots;
    const detail::LargeArray<double>& removal_error = state.removal_error;
    state.err.assign(vertex_count, 0.0);
    state.radius.assign(vertex_count, 0.0);
    state.cone_angle.assign(vertex_count, 0.0);
    state.axis.resize(vertex_count);
    detail::LargeArray<double>& err = state.err;
    detail::LargeArray<double>& radius = state.radius;
    detail::LargeArray<double>& cone_angle = state.cone_angle;
    detail::LargeArray<Vec3d>& axis = state.axis;
    auto pos = [&](uint32_t rank) { return toD(sequence.point_positions[rank_point[rank]]); };
    LODBAKE_RETURN_IF_ERROR(parallelFor(vertex_count, kChunk, [&](size_t vi) {
        const uint32_t i = uint32_t(vi);
        const Vec3d pi = pos(i);
        double rad = 0;
        Vec3d sum;
        for (uint32_t s = fan_first[i]; s < fan_first[i + 1]; ++s) {
            const Vec3d pa = pos(slots[s].a), pb = pos(slots[s].b);
            rad = std::max({rad, length(pa - pi), length(pb - pi)});
            sum += cross(pa - pi, pb - pi);
        }
        Vec3d ax = normalize(sum);
        double angle = 0;
        if (length(ax) == 0) angle = M_PI;
        // The widest face normal: acos decreases, so one acos of the smallest cosine.
        double min_cos = HUGE_VAL;
        for (uint32_t s = fan_first[i]; s < fan_first[i + 1]; ++s) {
            const Vec3d pa = pos(slots[s].a), pb = pos(slots[s].b);
            min_cos = std::min(min_cos, std::clamp(dot(ax, normalize(cross(pa - pi, pb - pi))), -1.0, 1.0));
        }
        if (min_cos != HUGE_VAL) angle = std::max(angle, std::acos(min_cos));
        err[i] = i < removed ? removal_error[rank_point[i]] : 0.0;
        radius[i] = rad;
        axis[i] = ax;
        cone_angle[i] = angle;
    }));
    for (uint32_t i = 0; i < vertex_count; ++i) {
        double e = err[i], rad = radius[i], angle = cone_angle[i];
        const uint32_t s_end = fan_first[i + 1];
        if (fan_first[i] < s_end) {
            const Vec3d pi = pos(i);
            const Vec3d& ax = axis[i];
            // The triangles one removal re-creates are stored one after the other, so a dependency
            // often repeats in consecutive slots: each maximum is taken once per run (std::max is
            // idempotent, so this changes no bit).
            uint32_t previous = kNone;
            for (uint32_t s = fan_first[i]; s < s_end; ++s) {
                const uint32_t d = slots[s].dep;
                if (d == kNone || d == previous) continue;
                previous = d;
                e = std::max(e, err[d]);
                rad = std::max(rad, length(pos(d) - pi) + radius[d]);
                angle = std::max(angle, std::acos(std::clamp(dot(ax, axis[d]), -1.0, 1.0)) + cone_angle[d]);
            }
        }
        err[i] = e;
        radius[i] = rad;
        cone_angle[i] = std::min(angle, M_PI);
    }
    return Status::okStatus();
}

// Writes every entry into state.stream, its offset into state.entry_offset.
Status writeEntries(BlobState& state, PfrepBuild& build) {
    namespace fmt = lodrt::format;
    const uint32_t vertex_count = state.vertex_count;
    const detail::LargeArray<uint32_t>& fan_first = state.fan_first;
    const detail::LargeArray<Slot>& slots = state.slots;
    std::vector<EntryChunk> chunks(chunkCount(vertex_count, kChunk));
    state.entry_offset.resize(vertex_count);
    detail::LargeArray<uint32_t>& entry_offset = state.entry_offset;
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(vertex_count, kChunk, [&](size_t chunk, size_t lo, size_t hi) {
        EntryChunk& out = chunks[chunk];
        std::vector<uint8_t> used, bits;
        std::vector<uint32_t> seq, slot_of_edge, deps;
        for (uint32_t i = uint32_t(lo); i < uint32_t(hi); ++i) {
            out.stream.alignByte();
            entry_offset[i] = uint32_t(out.stream.byteSize()); // within the chunk; made absolute below
            const uint32_t first = fan_first[i], count = fan_first[i + 1] - first;
            // Walks over the directed opposite edges a -> b; a walk starts where more edges leave
            // than arrive when there is such a vertex.
            used.assign(count, 0);
            seq.clear();
            slot_of_edge.assign(count, 0);
            uint32_t remaining = count;
            while (remaining > 0) {
                uint32_t start = kNone;
                // (quadratic: only for fans of ordinary size)
                for (uint32_t e = 0; e < count && start == kNone && count <= 256; ++e) {
                    if (used[e]) continue;
                    int balance = 0;
                    for (uint32_t f = 0; f < count; ++f) {
                        if (used[f]) continue;
                        balance += slots[first + f].a == slots[first + e].a;
                        balance -= slots[first + f].b == slots[first + e].a;
                    }
                    if (balance > 0) start = e;
                }
                if (start == kNone)
                    for (uint32_t e = 0; e < count; ++e)
                        if (!used[e]) {
                            start = e;
                            break;
                        }
                seq.push_back(slots[first + start].a);
                uint32_t e = start;
                while (e != kNone) {
                    used[e] = 1;
                    --remaining;
                    slot_of_edge[e] = uint32_t(seq.size() - 1);
                    seq.push_back(slots[first + e].b);
                    const uint32_t end = slots[first + e].b;
                    e = kNone;
                    for (uint32_t f = 0; f < count; ++f)
                        if (!used[f] && slots[first + f].a == end) {
                            e = f;
                            break;
                        }
                }
            }
            if (seq.size() > 1 && seq.back() == seq.front()) seq.pop_back();
            const uint32_t n = uint32_t(seq.size());
            if (n > 63 + 65535) {
                out.status = resourceLimit("pfrep: vertex with more than 65598 fan neighbours");
                return;
            }
            deps.clear();
            bool has_original = false;
            for (uint32_t e = 0; e < count; ++e) {
                if (slots[first + e].dep == kNone)
                    has_original = true;
                else
                    deps.push_back(slots[first + e].dep);
            }
            std::sort(deps.begin(), deps.end());
            deps.erase(std::unique(deps.begin(), deps.end()), deps.end());
            uint32_t max_neighbour = 0, max_dep = 0;
            for (uint32_t a : seq) max_neighbour = std::max(max_neighbour, a - i - 1);
            for (uint32_t d : deps) max_dep = std::max(max_dep, i - 1 - d);
            writeCount(out.stream, n, fmt::kPfrepCountBits);
            writeCount(out.stream, uint32_t(deps.size()), fmt::kPfrepDependencyCountBits);
            out.stream.write(has_original ? 1 : 0, 1);
            const uint32_t wa = bitWidth(max_neighbour), wd = bitWidth(max_dep);
            out.stream.write(wa, fmt::kPfrepWidthBits);
            if (!deps.empty()) out.stream.write(wd, fmt::kPfrepWidthBits);
            for (uint32_t a : seq) out.stream.write(a - i - 1, wa);
            bits.assign(n, 0);
            auto writeMask = [&](uint32_t dep) {
                std::fill(bits.begin(), bits.end(), 0);
                for (uint32_t e = 0; e < count; ++e)
                    if (slots[first + e].dep == dep) bits[slot_of_edge[e]] = 1;
                for (uint32_t j = 0; j < n; j += 32) { // 32 mask bits per write
                    const uint32_t take = std::min(32u, n - j);
                    uint64_t word = 0;
                    for (uint32_t k = 0; k < take; ++k) word |= uint64_t(bits[j + k]) << k;
                    out.stream.write(word, take);
                }
            };
            if (has_original) writeMask(kNone);
            for (uint32_t d : deps) {
                out.stream.write(i - 1 - d, wd);
                writeMask(d);
            }
            out.dependency_groups += deps.size();
            out.neighbour_slots += n;
        }
        out.stream.alignByte();
    }));
    BitWriter& stream = state.stream;
    std::vector<uint8_t>& stream_bytes = stream.bytes();
    {
        size_t total_bytes = 0;
        for (EntryChunk& chunk : chunks) {
            LODBAKE_RETURN_IF_ERROR(chunk.status);
            total_bytes += chunk.stream.byteSize();
        }
        if (total_bytes > 0xffffffffu) return resourceLimit("pfrep: blob larger than 4 GiB");
        stream_bytes.reserve(total_bytes);
        for (size_t c = 0; c < chunks.size(); ++c) {
            const uint32_t base = uint32_t(stream_bytes.size());
            const uint32_t chunk_end = uint32_t(std::min<size_t>((c + 1) * kChunk, vertex_count));
            for (uint32_t i = uint32_t(c * kChunk); i < chunk_end; ++i) entry_offset[i] += base;
            std::vector<uint8_t>& bytes = chunks[c].stream.bytes();
            stream_bytes.insert(stream_bytes.end(), bytes.begin(), bytes.end());
            std::vector<uint8_t>().swap(bytes);
            build.dependency_groups += chunks[c].dependency_groups;
            build.neighbour_slots += chunks[c].neighbour_slots;
        }
        std::vector<EntryChunk>().swap(chunks);
    }
    return Status::okStatus();
}

// The blob: header, block directory and blocks (docs/format/pfrep.md), into build.blob.
Status writeBlob(BlobState& state, PfrepBuild& build) {
    namespace fmt = lodrt::format;
    const CollapseSequence& sequence = state.sequence;
    const std::vector<uint32_t>& rank_point = state.rank_point;
    const uint32_t removed = state.removed, vertex_count = state.vertex_count;
    const size_t level0 = state.level0;
    const detail::LargeArray<double>& err = state.err;
    const detail::LargeArray<double>& radius = state.radius;
    const detail::LargeArray<double>& cone_angle = state.cone_angle;
    const detail::LargeArray<Vec3d>& axis = state.axis;
    const detail::LargeArray<uint32_t>& entry_offset = state.entry_offset;
    const std::vector<uint8_t>& stream_bytes = state.stream.bytes();
    const size_t entries_size = stream_bytes.size();

    // Blocks: the largest that keeps every in-block offset within 16 bits.
    uint32_t shift = fmt::kPfrepMaxBlockShift;
    for (;; --shift) {
        bool fits = true;
        for (uint32_t i = 0; i < vertex_count && fits; ++i)
            fits = entry_offset[i] - entry_offset[(i >> shift) << shift] <= 0xffffu;
        if (fits || shift == 0) break;
    }
    const size_t blocks = (size_t(vertex_count) + (size_t(1) << shift) - 1) >> shift;
    auto blockFirst = [&](size_t b) { return uint32_t(b << shift); };
    auto blockLast = [&](size_t b) { return uint32_t(std::min<size_t>((b + 1) << shift, vertex_count)); };
    auto entryEnd = [&](uint32_t i) { return i + 1 < vertex_count ? size_t(entry_offset[i + 1]) : entries_size; };
    // Blocks are stored coarse end first (decreasing b), so a prefix of the blob holds the highest
    // ranks: a usable coarse mesh that refines as more bytes arrive.
    const size_t directory_offset = fmt::kPfrepHeaderSize;
    std::vector<size_t> block_offset(blocks);
    size_t total = directory_offset + blocks * 4;
    for (size_t b = blocks; b-- > 0;) {
        block_offset[b] = total;
        const size_t count = blockLast(b) - blockFirst(b);
        total += count * (fmt::kPfrepVertexRecordSize + 2) +
                 (entryEnd(blockLast(b) - 1) - entry_offset[blockFirst(b)]) + fmt::kPfrepStreamPadding;
    }
    if (total > 0xffffffffu) return resourceLimit("pfrep: blob larger than 4 GiB");
    std::vector<uint8_t>& blob = build.blob;
    blob.assign(total, 0);

    Vec3f lo(HUGE_VALF, HUGE_VALF, HUGE_VALF), hi(-HUGE_VALF, -HUGE_VALF, -HUGE_VALF);
    for (uint32_t p : rank_point)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], sequence.point_positions[p][k]);
            hi[k] = std::max(hi[k], sequence.point_positions[p][k]);
        }
    if (vertex_count == 0) lo = hi = Vec3f();
    float step[3];
    for (int k = 0; k < 3; ++k) step[k] = hi[k] > lo[k] ? (hi[k] - lo[k]) / 65535.0f : 0.0f;
    const double diag = length(toD(hi) - toD(lo));
    const float error_unit = diag > 0 ? float(diag * std::ldexp(1.0, -24)) : 1e-30f;

    put32(blob, 0, fmt::kPfrepMagic);
    put32(blob, 4, fmt::kPfrepVersion);
    put32(blob, 8, vertex_count);
    put32(blob, 12, removed);
    put32(blob, 16, shift);
    put32(blob, 20, uint32_t(level0));
    for (int k = 0; k < 3; ++k) {
        putF32(blob, 24 + 4 * k, lo[k]);
        putF32(blob, 36 + 4 * k, step[k]);
    }
    putF32(blob, 48, error_unit);
    put32(blob, 52, uint32_t(total));
    put32(blob, 56, uint32_t(blocks));
    put32(blob, 60, 0);
    // Blocks own disjoint byte ranges: written in parallel, 16 per task.
    LODBAKE_RETURN_IF_ERROR(parallelFor(blocks, 16, [&](size_t b) {
        put32(blob, directory_offset + b * 4, uint32_t(block_offset[b]));
        const uint32_t first = blockFirst(b), last = blockLast(b), count = last - first;
        uint8_t* records = blob.data() + block_offset[b];
        for (uint32_t i = first; i < last; ++i) {
            uint8_t* r = records + size_t(i - first) * fmt::kPfrepVertexRecordSize;
            const Vec3f& p = sequence.point_positions[rank_point[i]];
            for (int k = 0; k < 3; ++k) {
                const uint16_t q =
                    step[k] > 0 ? uint16_t(std::clamp(std::lround((p[k] - lo[k]) / step[k]), 0L, 65535L)) : 0;
                std::memcpy(r + 2 * k, &q, 2);
            }
            r[6] = logCode(radius[i], error_unit);
            r[7] = logCode(err[i], error_unit);
            const uint16_t cone = coneCode(axis[i], cone_angle[i]);
            std::memcpy(r + 8, &cone, 2);
            const uint16_t rel = uint16_t(entry_offset[i] - entry_offset[first]);
            std::memcpy(records + size_t(count) * fmt::kPfrepVertexRecordSize + size_t(i - first) * 2, &rel, 2);
        }
        std::memcpy(records + size_t(count) * (fmt::kPfrepVertexRecordSize + 2),
                    stream_bytes.data() + entry_offset[first], entryEnd(last - 1) - entry_offset[first]);
    }));
    return Status::okStatus();
}

// buildPfrepFromSequence; when `releasable` is not null (buildPfrep's own sequence and triangles),
// the triangle lists are released as soon as the blob's own list of triangles holds them.
Result<PfrepBuild> buildBlob(const CollapseSequence& sequence, const std::vector<uint32_t>& point_triangles,
                             Diagnostics& diagnostics, CollapseSequence* releasable,
                             std::vector<uint32_t>* releasable_triangles) {
    namespace fmt = lodrt::format;
    const uint32_t point_count = uint32_t(sequence.point_positions.size());
    if (point_triangles.size() % 3 != 0) return invalidInput("pfrep: point triangle list is not a multiple of 3");
    // The working arrays (sized by the mesh) are on core/large_array.h storage: from 2 MB on, huge
    // pages where the OS offers them, so filling them fresh takes one page fault per 2 MB instead of
    // one per 4 KB. A standalone blob build gains most; inside a bake those arrays mostly reuse heap
    // pages the chain freed.
    for (size_t c = 0; c < point_triangles.size(); ++c)
        if (point_triangles[c] >= point_count)
            return invalidInput("pfrep: triangle " + std::to_string(c / 3) + ": point out of range");
    BlobState state(sequence, point_count);
    const bool logged = !sequence.records.empty() && sequence.created_end.size() == sequence.records.size();
    if (logged)
        LODBAKE_RETURN_IF_ERROR(listLoggedTriangles(state, point_triangles, releasable, releasable_triangles));
    else
        LODBAKE_RETURN_IF_ERROR(replayCollapses(state, point_triangles));
    std::vector<uint32_t>& rank_point = state.rank_point;
    detail::LargeArray<uint32_t>& rank_of = state.rank_of;
    const detail::LargeArray<uint8_t>& referenced = state.referenced;
    const uint32_t removed = uint32_t(rank_point.size());
    for (uint32_t p = 0; p < point_count; ++p) {
        if (rank_of[p] != kNone || !referenced[p]) continue;
        rank_of[p] = uint32_t(rank_point.size());
        rank_point.push_back(p);
    }
    const uint32_t vertex_count = uint32_t(rank_point.size());
    if (vertex_count >= fmt::kPfrepMaxVertices) return resourceLimit("pfrep: too many vertices");
    state.removed = removed;
    state.vertex_count = vertex_count;

    LODBAKE_RETURN_IF_ERROR(buildFans(state));
    std::vector<uint32_t> level_triangles = countLevelTriangles(state);
    LODBAKE_RETURN_IF_ERROR(computeVertexBounds(state));
    PfrepBuild build;
    LODBAKE_RETURN_IF_ERROR(writeEntries(state, build));
    LODBAKE_RETURN_IF_ERROR(writeBlob(state, build));

    build.rank_kept.resize(removed);
    for (uint32_t r = 0; r < removed; ++r) build.rank_kept[r] = sequence.records[r].kept_point;
    build.rank_point = std::move(rank_point);
    build.removed = removed;
    build.level0_triangles = state.level0;
    build.stored_triangles = state.stored_triangles;
    build.level_triangles = std::move(level_triangles);
    if (removed == 0) diagnostics.note("pfrep: no vertex could be removed; the blob holds the input only");
    return build;
}

} // namespace

Result<PfrepBuild> buildPfrepFromSequence(const CollapseSequence& sequence,
                                          const std::vector<uint32_t>& point_triangles, Diagnostics& diagnostics) {
    return buildBlob(sequence, point_triangles, diagnostics, nullptr, nullptr);
}

Status chainPoints(const MeshView& mesh, std::vector<Vec3f>& positions, std::vector<uint32_t>& triangles) {
    // Weld by bit-identical position (each vertex to the first vertex at its position, by sorting), then
    // number the points in order of first use by the faces that are not degenerate by position: the
    // simplifier's own numbering (lod_chain.h).
    const size_t vertex_count = mesh.positions.size();
    if (vertex_count >= kNone) return resourceLimit("pfrep: too many vertices");
    for (uint32_t i : mesh.indices)
        if (i >= vertex_count) return invalidInput("pfrep: index out of range");
    std::vector<uint32_t> weld(vertex_count, kNone);
    {
        struct Key {
            uint32_t bits[3];
            uint32_t vertex;
        };
        std::vector<Key> keys(vertex_count);
        for (uint32_t v = 0; v < vertex_count; ++v) {
            std::memcpy(keys[v].bits, &mesh.positions[v].x, 12);
            keys[v].vertex = v;
        }
        std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
            if (a.bits[0] != b.bits[0]) return a.bits[0] < b.bits[0];
            if (a.bits[1] != b.bits[1]) return a.bits[1] < b.bits[1];
            if (a.bits[2] != b.bits[2]) return a.bits[2] < b.bits[2];
            return a.vertex < b.vertex;
        });
        for (size_t i = 0; i < vertex_count;) {
            size_t j = i + 1;
            while (j < vertex_count && std::memcmp(keys[j].bits, keys[i].bits, 12) == 0) ++j;
            for (size_t k = i; k < j; ++k) weld[keys[k].vertex] = keys[i].vertex;
            i = j;
        }
    }
    std::vector<uint32_t> point_of(vertex_count, kNone); // per welded (first) vertex
    positions.clear();
    triangles.clear();
    triangles.reserve(mesh.indices.size());
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        const uint32_t w0 = weld[mesh.indices[f * 3]], w1 = weld[mesh.indices[f * 3 + 1]],
                       w2 = weld[mesh.indices[f * 3 + 2]];
        if (w0 == w1 || w1 == w2 || w0 == w2) continue;
        for (uint32_t w : {w0, w1, w2}) {
            if (point_of[w] == kNone) {
                point_of[w] = uint32_t(positions.size());
                positions.push_back(mesh.positions[w]);
            }
            triangles.push_back(point_of[w]);
        }
    }
    return Status::okStatus();
}

Result<PfrepBuild> buildPfrepFromChain(const MeshView& mesh, const CollapsePairLog& removals, Diagnostics& diagnostics) {
    CollapseSequence sequence;
    std::vector<uint32_t> triangles;
    LODBAKE_RETURN_IF_ERROR(chainPoints(mesh, sequence.point_positions, triangles));
    const uint32_t point_count = uint32_t(sequence.point_positions.size());
    // The engine names the merged point by its kept id; the blob keeps one of the two original points
    // for it: rep[engine point] is that point.
    std::vector<uint32_t> rep(point_count);
    for (uint32_t p = 0; p < point_count; ++p) rep[p] = p;
    // The end whose original position has the lower error for the merged point's quadric (face
    // planes, area-weighted, summed over the points merged into it) stays, as the half-edge
    // simplifier chooses its direction.
    std::vector<Quadric> quadric(point_count);
    for (size_t t = 0; t < triangles.size(); t += 3) {
        const Quadric q = Quadric::fromTriangle(toD(sequence.point_positions[triangles[t]]),
                                                toD(sequence.point_positions[triangles[t + 1]]),
                                                toD(sequence.point_positions[triangles[t + 2]]));
        for (int k = 0; k < 3; ++k) quadric[triangles[t + k]] += q;
    }
    sequence.records.reserve(removals.size());
    CollapsePairLog::Reader reader(removals);
    uint32_t u = 0, v = 0;
    bool kept_stays = false;
    for (size_t r = 0; r < removals.size(); ++r) {
        if (!reader.next(u, v, kept_stays) || u >= point_count || v >= point_count || u == v)
            return invalidInput("pfrep: collapse " + std::to_string(r) + ": bad points in the chain's log");
        uint32_t removed = rep[u], kept = rep[v];
        // When the chain did not move its kept point (a corner, or a border or seam point whose edge
        // leaves its line: the quadric has no constraint planes here), that end stays.
        Quadric q = quadric[removed];
        q += quadric[kept];
        if (!kept_stays &&
            q.evaluate(toD(sequence.point_positions[removed])) < q.evaluate(toD(sequence.point_positions[kept])))
            std::swap(removed, kept);
        quadric[kept] = q;
        rep[v] = kept;
        CollapseRecord record;
        record.removed_point = removed;
        record.kept_point = kept;
        record.position = sequence.point_positions[kept];
        sequence.records.push_back(record);
    }
    std::vector<uint32_t>().swap(rep);
    std::vector<Quadric>().swap(quadric);
    return buildBlob(sequence, triangles, diagnostics, nullptr, nullptr);
}

Result<PfrepBuild> buildPfrep(const Mesh& mesh, const PfrepOptions& options, Diagnostics& diagnostics) {
    if (!(options.target_ratio >= 0.0f && options.target_ratio <= 1.0f))
        return invalidInput("pfrep options: ratio: expected a value in [0, 1]");
    LodChainOptions chain_options;
    chain_options.simplify = options.simplify;
    chain_options.simplify.placement = CollapsePlacement::KeepEndpoint;
    // A ratio of 0 is not accepted by the chain: one triangle's worth asks for "as far as valid".
    chain_options.ratios = {std::max(double(options.target_ratio), 1e-9)};
    chain_options.measure_error = false;
    chain_options.record_collapses = true;
    LODBAKE_ASSIGN_OR_RETURN(LodChain chain, buildLodChain(mesh, chain_options, diagnostics));
    // The simplifier lists the point triangles it started from (no look-up of every vertex by position).
    std::vector<uint32_t> triangles = std::move(chain.sequence.point_triangles);
    if (triangles.empty()) {
        LODBAKE_ASSIGN_OR_RETURN(triangles, pointTriangles(mesh, chain.sequence));
    }
    return buildBlob(chain.sequence, triangles, diagnostics, &chain.sequence, &triangles);
}

} // namespace lodbake
