// Two-sided surface distance in the manner of Metro (Cignoni, Rocchini, Scopigno, "Metro: measuring
// error on simplified surfaces", 1998): area-uniform random samples on each surface plus its
// referenced vertices, each measured exactly against the other surface (closest point on triangle
// through a TriangleBvh). Same definitions as ../shared/eval/meshdist.py.
//
// Speed: the points of a side are measured in Morton (Z-curve) order of their position, so
// consecutive queries are close in space and the previous answer bounds the next query tightly.
// The index (DistanceIndex) is a 4-wide BVH: four child boxes are tested at once in float, with
// boxes widened at build time so that rounding can only make the float test visit more, never less;
// leaf triangles are measured exactly in double. The result is the minimum of the exact distance over
// all triangles whatever the tree, so it equals what any exact search returns.
// measureSurfaceDistances draws the reference side's points once for all levels and measures the
// levels one after the other (each level's chunks in parallel), so one level's BVH and points exist
// at a time. measureReferenceSides measures the reference side alone, ahead of the rest (the bake runs
// it beside the PFRep build), with the reference's points kept as their sources and recomputed per query.
//
// Determinism: sample k of a side is drawn from a counter-based generator (splitmix64 of seed, side
// and k), so it does not depend on which thread draws it. Points are processed in chunks of a fixed
// size; each chunk writes its max / sum / sum of squares into its own slot and the slots are combined
// in chunk order, so the result is bit-identical for any thread count.

#include "lodbake/simplify/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/large_array.h"
#include "core/parallel.h"
#include "simplify/distance_sides.h"
#include "simplify/surface_sampling.h"
#include "lodbake/core/bvh.h"

namespace lodbake {

namespace {

using detail::LargeArray;
// A side's points (Morton order); large, filled once, read in order by the queries.
using PointArray = LargeArray<Vec3d>;

constexpr size_t kChunkSize = detail::kDistanceChunkSize;
using detail::kApproxStream;
using detail::kReferenceStream;

using detail::pointOnTriangle;
using detail::splitmix64;
using detail::toUnit;

constexpr uint32_t kMortonCells = 1u << 21; // per axis: 3 x 21 bits fill a 63-bit code

// Bit i of a 7-bit value moved to bit 3i.
struct SpreadTable {
    uint32_t bits[128];
    constexpr SpreadTable() : bits() {
        for (uint32_t v = 0; v < 128; ++v) {
            uint32_t s = 0;
            for (int i = 0; i < 7; ++i) s |= ((v >> i) & 1u) << (3 * i);
            bits[v] = s;
        }
    }
};
constexpr SpreadTable kSpread;

// Spreads the low 21 bits of x so that bit i lands at bit 3i (7 bits per table look-up).
uint64_t spreadBits(uint64_t x) {
    return uint64_t(kSpread.bits[x & 127]) | (uint64_t(kSpread.bits[(x >> 7) & 127]) << 21) |
           (uint64_t(kSpread.bits[(x >> 14) & 127]) << 42);
}

// Z-order code of a point already scaled to [0, kMortonCells - 1] per axis (clamped).
uint64_t mortonCode(const Vec3d& q) {
    auto cell = [](double v) { return uint64_t(std::min(std::max(v, 0.0), double(kMortonCells - 1))); };
    return spreadBits(cell(q.x)) | (spreadBits(cell(q.y)) << 1) | (spreadBits(cell(q.z)) << 2);
}

double triangleArea(const Mesh& mesh, size_t t) {
    return detail::samplingTriangleArea(mesh.positions[mesh.indices[t * 3]], mesh.positions[mesh.indices[t * 3 + 1]],
                                        mesh.positions[mesh.indices[t * 3 + 2]]);
}

// Checks what this module relies on; the whole-mesh checks belong to cleanup::validate().
Status checkSurface(const Mesh& mesh, const char* role) {
    if (mesh.indices.size() % 3 != 0) {
        return invalidInput(std::string(role) + " mesh: indices: expected a multiple of 3, got " +
                            std::to_string(mesh.indices.size()));
    }
    std::vector<uint8_t> checked(mesh.positions.size(), 0);
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
        uint32_t v = mesh.indices[c];
        if (v >= mesh.positions.size()) {
            return invalidInput(std::string(role) + " mesh: triangle " + std::to_string(c / 3) + ": index " +
                                std::to_string(v) + " out of range (" + std::to_string(mesh.positions.size()) +
                                " vertices)");
        }
        if (!checked[v]) {
            checked[v] = 1;
            if (!isFinite(mesh.positions[v])) {
                return invalidInput(std::string(role) + " mesh: vertex " + std::to_string(v) +
                                    ": expected finite coordinates");
            }
        }
    }
    for (size_t t = 0; t < mesh.faceCount(); ++t) {
        if (triangleArea(mesh, t) > 0.0) return Status::okStatus();
    }
    return invalidInput(std::string(role) + " mesh: expected at least one triangle of non-zero area, found " +
                        (mesh.faceCount() == 0 ? std::string("no triangles") : std::string("only degenerate ones")));
}

constexpr uint32_t kLeafBit = 0x80000000u;
constexpr uint32_t kEmptyChild = 0xffffffffu;
constexpr uint32_t kLeafTriangles = 4;   // a range this small becomes a leaf
constexpr uint32_t kMaxSlots = 1u << 28; // slot field of a leaf reference
constexpr size_t kStackSize = 3 * 96; // at most 3 pushes per node level; every level splits once or more (63 code bits + 28 halvings)
// Relative slack of the pruning test: far above the float test's rounding (about 4e-7 relative) and
// the exact test's (a few ulps of the coordinates, covered by the absolute term).
constexpr double kPruneRelative = 1.0 + 1.0 / (1 << 20);

bool isLeaf(uint32_t ref) { return ref != kEmptyChild && (ref & kLeafBit) != 0; }

// Squared distance from p to triangle (a, b, c), exactly as the measurement has always computed it.
inline double exactDistanceSq(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d d = p - closestPointOnTriangle(p, a, b, c);
    return dot(d, d);
}

struct BuildBox {
    float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF};
    float hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
    void expand(const float* plo, const float* phi) {
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], plo[k]);
            hi[k] = std::max(hi[k], phi[k]);
        }
    }
    void expand(const BuildBox& b) { expand(b.lo, b.hi); }
    double halfArea() const {
        if (lo[0] > hi[0]) return 0.0;
        const double dx = double(hi[0]) - lo[0], dy = double(hi[1]) - lo[1], dz = double(hi[2]) - lo[2];
        return dx * dy + dy * dz + dz * dx;
    }
};

// Bottom-up boxes over a Morton-sorted triangle order (Lauterbach et al., "Fast BVH construction on
// GPUs", 2009): a range is split where the highest differing bit of its codes flips (in the middle
// when all codes are equal), twice per node for four children. No pass over the triangles per level,
// only a binary search per split, so the build costs about one sort; the tree depends on the input only.
class IndexBuilder {
public:
    IndexBuilder(const LargeArray<uint64_t>& codes, const detail::DistanceArray<Vec3f>& corners,
                 detail::DistanceArray<DistanceIndex::Node>& nodes, double slack)
        : codes_(codes), corners_(corners), nodes_(nodes), slack_(slack) {}

    uint32_t build(uint32_t begin, uint32_t end, BuildBox& box) {
        const uint32_t count = end - begin;
        if (count <= kLeafTriangles) {
            for (size_t c = size_t(begin) * 3; c < size_t(end) * 3; ++c) {
                const float xyz[3] = {corners_[c].x, corners_[c].y, corners_[c].z};
                box.expand(xyz, xyz);
            }
            return kLeafBit | (begin << 3) | (count - 1);
        }
        uint32_t bounds[5] = {begin, end, end, end, end}; // children [bounds[i], bounds[i + 1])
        int n = 1;
        while (n < 4) {
            int widest = -1;
            for (int i = 0; i < n; ++i) {
                const uint32_t c = bounds[i + 1] - bounds[i];
                if (c > kLeafTriangles && (widest < 0 || c > bounds[widest + 1] - bounds[widest])) widest = i;
            }
            if (widest < 0) break;
            const uint32_t mid = splitPoint(bounds[widest], bounds[widest + 1]);
            for (int i = n + 1; i > widest + 1; --i) bounds[i] = bounds[i - 1];
            bounds[widest + 1] = mid;
            ++n;
        }
        const uint32_t index = uint32_t(nodes_.size());
        nodes_.emplace_back();
        uint32_t refs[4] = {kEmptyChild, kEmptyChild, kEmptyChild, kEmptyChild};
        BuildBox boxes[4];
        for (int i = 0; i < n; ++i) {
            refs[i] = build(bounds[i], bounds[i + 1], boxes[i]);
            box.expand(boxes[i]);
        }
        DistanceIndex::Node& node = nodes_[index];
        for (int i = 0; i < 4; ++i) {
            node.child[i] = refs[i];
            for (int k = 0; k < 3; ++k) {
                // Widened outwards by the slack (an empty child keeps an empty box: +inf / -inf).
                node.lo[k][i] = i < n ? float(double(boxes[i].lo[k]) - slack_) : HUGE_VALF;
                node.hi[k][i] = i < n ? float(double(boxes[i].hi[k]) + slack_) : -HUGE_VALF;
            }
        }
        return index;
    }

private:
    uint32_t splitPoint(uint32_t begin, uint32_t end) const {
        const uint64_t first = codes_[begin], last = codes_[end - 1];
        if (first == last) return begin + (end - begin) / 2;
        const int bit = 63 - __builtin_clzll(first ^ last);
        // Codes are sorted and share every bit above `bit`: the first one with it set starts the right part.
        return uint32_t(std::partition_point(codes_.begin() + begin, codes_.begin() + end,
                                             [bit](uint64_t c) { return ((c >> bit) & 1) == 0; }) -
                        codes_.begin());
    }

    const LargeArray<uint64_t>& codes_;
    const detail::DistanceArray<Vec3f>& corners_;
    detail::DistanceArray<DistanceIndex::Node>& nodes_;
    double slack_;
};

using SideStats = OneSidedDistance;

// How one side's points are drawn: area-uniform stratified samples, then the referenced vertices.
// Point i is recomputed from (i, its source: the sample's triangle or the vertex) with the same
// arithmetic wherever it is evaluated, so a stored point and a recomputed one are the same bits.
class SideSampler {
public:
    SideSampler(const Mesh& from, const DistanceOptions& options, uint64_t stream)
        : from_(from), sample_count_(options.sample_count), key_(splitmix64(options.seed ^ stream)) {}

    size_t sampleCount() const { return sample_count_; }
    uint64_t key() const { return key_; }
    // Point `point` (samples first, then vertices) from its source.
    Vec3d at(uint32_t point, uint32_t source) const {
        return point < sample_count_ ? sampleOn(point, source) : toDouble(from_.positions[source]);
    }
    // Sample i's point on triangle `tri`.
    Vec3d sampleOn(size_t i, size_t tri) const {
        const uint64_t base = key_ + uint64_t(i) * 3;
        const double u1 = toUnit(splitmix64(base + 1)), u2 = toUnit(splitmix64(base + 2));
        const Vec3d a = toDouble(from_.positions[from_.indices[tri * 3]]);
        const Vec3d b = toDouble(from_.positions[from_.indices[tri * 3 + 1]]);
        const Vec3d c = toDouble(from_.positions[from_.indices[tri * 3 + 2]]);
        return pointOnTriangle(a, b, c, u1, u2);
    }

private:
    const Mesh& from_;
    size_t sample_count_;
    uint64_t key_;
};

// A point in Morton order: its code, its index (samples first, then vertices) and its source.
struct PointKey {
    uint64_t code;
    uint32_t point;
    uint32_t source; // the sample's triangle, or the vertex
    bool operator<(const PointKey& o) const { return code < o.code || (code == o.code && point < o.point); }
};

// One side's points as keys sorted in Morton order of their position (ties by point index).
Result<LargeArray<PointKey>> sortedPointKeys(const Mesh& from, const DistanceOptions& options,
                                             const SideSampler& sampler, const char* role) {
    const size_t tri_count = from.faceCount();
    LargeArray<double> cdf(tri_count);
    double total = 0.0;
    size_t last_positive = 0;
    for (size_t t = 0; t < tri_count; ++t) {
        double area = triangleArea(from, t);
        if (area > 0.0) last_positive = t;
        total += area;
        cdf[t] = total;
    }
    if (!(total > 0.0) || !std::isfinite(total)) {
        return invalidInput(std::string(role) + " mesh: expected at least one triangle of non-zero area, found " +
                            (tri_count == 0 ? std::string("no triangles") : std::string("only degenerate ones")));
    }

    std::vector<uint32_t> vertices;
    if (options.include_vertices) {
        std::vector<uint8_t> used(from.positions.size(), 0);
        for (uint32_t v : from.indices) used[v] = 1;
        vertices.reserve(size_t(std::count(used.begin(), used.end(), uint8_t(1))));
        for (size_t v = 0; v < used.size(); ++v) {
            if (used[v]) vertices.push_back(uint32_t(v));
        }
    }

    const size_t sample_count = sampler.sampleCount();
    const size_t point_count = sample_count + vertices.size();
    const uint64_t key = sampler.key();

    // Sample i's triangle. Stratified over the area CDF: sample i falls in the i-th of sample_count
    // equal slices of the total area. Each sample is still area-uniform and the estimate has less variance.
    auto triangleOf = [&](size_t i, size_t& t) -> size_t {
        const double u0 = toUnit(splitmix64(key + uint64_t(i) * 3));
        const double x = (double(i) + u0) / double(sample_count) * total;
        // x grows with i, so the triangle is found by walking forward from the previous sample's
        // (`t`, the first triangle whose CDF exceeds x: what upper_bound returns). Zero-area
        // triangles own an empty interval of the CDF and are never chosen.
        while (t < tri_count && !(cdf[t] > x)) ++t;
        return t < tri_count ? t : last_positive;
    };

    // Every point's Morton code (and its triangle, or its vertex), in chunks; then the codes sorted
    // (ties by point index). The points themselves are computed again from the stored source when they
    // are needed: independent loads in parallel chunks instead of a serial permutation, and no array of
    // points beside the codes until the codes are sorted.
    LargeArray<PointKey> order(point_count);
    const Aabb box = computeBounds(from);
    const Vec3d box_min = toDouble(box.min);
    const Vec3d extent = toDouble(box.max) - box_min;
    const double max_extent = std::max({extent.x, extent.y, extent.z, 1e-300});
    const double scale = double(kMortonCells - 1) / max_extent;
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(point_count, kChunkSize, [&](size_t, size_t begin, size_t end) {
        size_t t = 0;
        if (begin < sample_count) {
            const double x = double(begin) / double(sample_count) * total;
            t = size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
        }
        for (size_t i = begin; i < end; ++i) {
            uint32_t source;
            Vec3d point;
            if (i < sample_count) {
                source = uint32_t(triangleOf(i, t));
                point = sampler.sampleOn(i, source);
            } else {
                source = vertices[i - sample_count];
                point = toDouble(from.positions[source]);
            }
            order[i] = {mortonCode((point - box_min) * scale), uint32_t(i), source};
        }
    }));
    LargeArray<double>().swap(cdf);
    std::sort(order.begin(), order.end());
    return order;
}

// The points measured from one side, stored in Morton order of their position (ties by point index).
Result<PointArray> samplePoints(const Mesh& from, const DistanceOptions& options, uint64_t stream, const char* role) {
    const SideSampler sampler(from, options, stream);
    LODBAKE_ASSIGN_OR_RETURN(LargeArray<PointKey> order, sortedPointKeys(from, options, sampler, role));
    const size_t point_count = order.size();
    PointArray points(point_count);
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(point_count, kChunkSize, [&](size_t, size_t first, size_t end) {
        for (size_t k = first; k < end; ++k) points[k] = sampler.at(order[k].point, order[k].source);
    }));
    return points;
}

// One side's points in the same order as samplePoints gives them, kept as (point, source) pairs, a third of
// the memory (8 bytes a point instead of 24), each point recomputed by the query that needs it.
struct PointSources {
    uint32_t point;
    uint32_t source;
};

Result<LargeArray<PointSources>> samplePointSources(const Mesh& from, const DistanceOptions& options,
                                                    const SideSampler& sampler, const char* role) {
    LODBAKE_ASSIGN_OR_RETURN(LargeArray<PointKey> order, sortedPointKeys(from, options, sampler, role));
    LargeArray<PointSources> sources(order.size());
    for (size_t k = 0; k < order.size(); ++k) sources[k] = {order[k].point, order[k].source};
    return sources;
}

// Distances from the points pointAt(0 .. point_count - 1) to the surface indexed by `to`.
template <class PointAt>
Result<SideStats> measurePointsAt(size_t point_count, const PointAt& pointAt, const DistanceIndex& to) {
    std::vector<SideStats> chunks(chunkCount(point_count, kChunkSize));
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(point_count, kChunkSize, [&](size_t chunk, size_t first, size_t end) {
        SideStats s;
        // Consecutive points (Morton order) are near each other: the previous answer's triangle gives
        // a tight first bound that prunes most of the tree. The minimum found is the same either way.
        DistanceIndex::Cursor cursor;
        for (size_t k = first; k < end; ++k) {
            const double d = std::sqrt(to.closestDistanceSq(pointAt(k), cursor));
            s.max = std::max(s.max, d);
            s.sum += d;
            s.sum_sq += d * d;
            s.count++;
        }
        chunks[chunk] = s;
    }));

    SideStats total_stats;
    for (const SideStats& s : chunks) {
        total_stats.max = std::max(total_stats.max, s.max);
        total_stats.sum += s.sum;
        total_stats.sum_sq += s.sum_sq;
        total_stats.count += s.count;
    }
    return total_stats;
}

// Distances from `points` to the surface indexed by `to`.
Result<SideStats> measurePoints(const PointArray& points, const DistanceIndex& to) {
    return measurePointsAt(
        points.size(), [&](size_t k) -> const Vec3d& { return points[k]; }, to);
}

Status checkOptions(const DistanceOptions& options) {
    if (options.sample_count == 0 && !options.include_vertices) {
        return invalidInput("distance options: expected sample_count > 0 or include_vertices, got neither");
    }
    return Status::okStatus();
}

// What an approximation needs before it is measured: its index and its side's points (each built
// only from the approximation, so it can be prepared while the previous one is measured). No index
// when the reference side was measured beforehand (measureReferenceSides): nothing else queries it.
struct ApproxSide {
    Status status = Status::okStatus();
    DistanceIndex index;
    PointArray points;
};

// An approximation's index, after the surface check every measurement of it makes first.
Result<DistanceIndex> checkedIndex(const Mesh& approx) {
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    return DistanceIndex::build(approx.positions, approx.indices);
}

// Side i's distances when they were measured beforehand (known[i], when there and not null).
const OneSidedDistance* knownSide(const std::vector<const OneSidedDistance*>& known, size_t i) {
    return i < known.size() ? known[i] : nullptr;
}

ApproxSide prepareApprox(const Mesh& approx, const DistanceOptions& options, bool with_index) {
    ApproxSide side;
    if (with_index) {
        Result<DistanceIndex> index = checkedIndex(approx);
        if (!index.ok()) {
            side.status = index.status();
            return side;
        }
        side.index = std::move(index).value();
    } else {
        side.status = checkSurface(approx, "approximation");
        if (!side.status.ok()) return side;
    }
    Result<PointArray> points = samplePoints(approx, options, kApproxStream, "approximation");
    if (!points.ok()) {
        side.status = points.status();
        side.index = DistanceIndex();
        return side;
    }
    side.points = std::move(points).value();
    return side;
}

// One prepared approximation against a reference whose side's points are already drawn, or whose
// side was measured beforehand (`known`, not null).
Result<DistanceResult> measurePrepared(const DistanceReference& reference, const PointArray& reference_points,
                                       const ApproxSide& approx, const OneSidedDistance* known) {
    LODBAKE_RETURN_IF_ERROR(approx.status);
    SideStats ref_to_approx;
    if (known) {
        ref_to_approx = *known;
    } else {
        LODBAKE_ASSIGN_OR_RETURN(ref_to_approx, measurePoints(reference_points, approx.index));
    }
    LODBAKE_ASSIGN_OR_RETURN(SideStats approx_to_ref, measurePoints(approx.points, reference.index()));

    return detail::twoSidedDistance(ref_to_approx, approx_to_ref, reference.diagonal());
}

// Measures approximations[i] for every i, each prepared (prepareApprox) while the one before it is
// measured: two tasks side by side, the next approximation's serial index build and sampling beside the
// current one's parallel queries, so idle threads join the queries. At most two approximations' indexes
// and points exist at once. `first` is approximations[0] already prepared (empty when there are none).
// `known[i]`, when there and not null, is approximation i's reference side, measured beforehand.
std::vector<Result<DistanceResult>> measurePipelined(const DistanceReference& reference,
                                                     const PointArray& reference_points,
                                                     const std::vector<const Mesh*>& approximations,
                                                     const DistanceOptions& options, ApproxSide first,
                                                     const std::vector<const OneSidedDistance*>& known) {
    std::vector<Result<DistanceResult>> results(approximations.size(), Result<DistanceResult>(DistanceResult{}));
    ApproxSide current = std::move(first);
    for (size_t i = 0; i < approximations.size(); ++i) {
        ApproxSide next;
        const bool has_next = i + 1 < approximations.size();
        const Status run = parallelFor(has_next ? 2 : 1, 1, [&](size_t task) {
            if (task == 0)
                results[i] = measurePrepared(reference, reference_points, current, knownSide(known, i));
            else
                next = prepareApprox(*approximations[i + 1], options, knownSide(known, i + 1) == nullptr);
        });
        if (!run.ok()) {
            results[i] = run;
            if (has_next) next.status = run;
        }
        current = std::move(next);
    }
    return results;
}

// closestDistanceSq's steps. They run for every node the search visits, so they are forced inline:
// the search compiles to the same loop as if they were written in place.

// One entry of the search stack: a child reference and the float distance to its box (a lower bound).
struct SearchEntry {
    uint32_t ref;
    float dist;
};

// Squared float distances from (px, py, pz) to the four child boxes of `node`. `dist` is 16-byte aligned.
__attribute__((always_inline)) inline void childBoxDistancesSq(const DistanceIndex::Node& node, float px, float py,
                                                               float pz, float* dist) {
#if defined(__SSE2__)
    const __m128 vx = _mm_set1_ps(px), vy = _mm_set1_ps(py), vz = _mm_set1_ps(pz);
    const __m128 zero = _mm_setzero_ps();
    const __m128 dx =
        _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_loadu_ps(node.lo[0]), vx), _mm_sub_ps(vx, _mm_loadu_ps(node.hi[0]))), zero);
    const __m128 dy =
        _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_loadu_ps(node.lo[1]), vy), _mm_sub_ps(vy, _mm_loadu_ps(node.hi[1]))), zero);
    const __m128 dz =
        _mm_max_ps(_mm_max_ps(_mm_sub_ps(_mm_loadu_ps(node.lo[2]), vz), _mm_sub_ps(vz, _mm_loadu_ps(node.hi[2]))), zero);
    _mm_store_ps(dist, _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
#else
    for (int i = 0; i < 4; ++i) {
        const float dx = std::max(std::max(node.lo[0][i] - px, px - node.hi[0][i]), 0.0f);
        const float dy = std::max(std::max(node.lo[1][i] - py, py - node.hi[1][i]), 0.0f);
        const float dz = std::max(std::max(node.lo[2][i] - pz, pz - node.hi[2][i]), 0.0f);
        dist[i] = dx * dx + dy * dy + dz * dz;
    }
#endif
}

// Bit i set for each child i whose distance is within `limit_f`. `dist` is 16-byte aligned.
__attribute__((always_inline)) inline unsigned childrenWithin(const float* dist, float limit_f) {
#if defined(__SSE2__)
    return unsigned(_mm_movemask_ps(_mm_cmple_ps(_mm_load_ps(dist), _mm_set1_ps(limit_f))));
#else
    unsigned mask = 0;
    for (int i = 0; i < 4; ++i) mask |= unsigned(dist[i] <= limit_f) << i;
    return mask;
#endif
}

// Where to start (see Cursor): the deepest node of the last query's path whose clearance, less the
// distance from the last point, still exceeds the limit. Every triangle outside it is then farther
// than the limit from p (triangle inequality), so the search would skip it anyway. The entries kept
// are lower bounds for p as well once that distance is taken off; entry 0 is the root (nothing
// outside it). Only with the float box test, whose distances the clearances come from. Returns the
// number of path entries the search starts below (the start node is cursor.node[depth - 1]).
inline uint32_t resumeDepth(DistanceIndex::Cursor& cursor, const Vec3d& p, double limit, float mag, uint32_t root,
                            bool use_float) {
    uint32_t depth = 1;
    if (use_float && cursor.depth > 0) {
        const Vec3d step = p - cursor.point;
        // Margins far above the rounding of these few double operations.
        const double moved = std::sqrt(dot(step, step)) * (1.0 + 0x1p-40) + double(mag) * 0x1p-50;
        depth = cursor.depth;
        for (; depth > 1; --depth) {
            const double c = cursor.clearance[depth - 1] - moved;
            if (c > 0.0 && c * c * (1.0 - 0x1p-40) > limit) break;
        }
        for (uint32_t i = 1; i < depth; ++i) cursor.clearance[i] -= moved;
    } else {
        cursor.node[0] = root;
        cursor.clearance[0] = std::numeric_limits<double>::infinity();
    }
    cursor.depth = use_float ? depth : 0;
    cursor.point = p;
    return depth;
}

// The search descends alone into child `only` (reference `ref`) of a node on the cursor's path: the
// child joins the path with its clearance. Returns false (the path ends) when the cursor is full.
__attribute__((always_inline)) inline bool extendCursorPath(DistanceIndex::Cursor& cursor, uint32_t ref,
                                                            const float* dist, int only, float mag) {
    if (cursor.depth >= DistanceIndex::kCursorDepth) return false;
    // The other children's boxes are beyond the limit; their float distance bounds the distance from
    // p to their triangles: up to a relative 2^-20 for the float arithmetic and |p - float(p)| < M 2^-22
    // (|p| <= 2M).
    float nearest_other = HUGE_VALF;
    for (int i = 0; i < 4; ++i)
        if (i != only) nearest_other = std::min(nearest_other, dist[i]);
    const double bound = std::sqrt(double(nearest_other) * (1.0 - 0x1p-19)) - double(mag) * 0x1p-22;
    cursor.node[cursor.depth] = ref;
    cursor.clearance[cursor.depth] = std::min(cursor.clearance[cursor.depth - 1], bound);
    ++cursor.depth;
    return true;
}

// Of the children in `mask` (two or more), the nearest is returned to be visited next and the others
// are pushed farthest first.
__attribute__((always_inline)) inline uint32_t pushAllButNearest(const DistanceIndex::Node& node, unsigned mask,
                                                                 const float* dist, SearchEntry* stack, size_t& top) {
    SearchEntry keep[4];
    int n = 0;
    for (; mask != 0; mask &= mask - 1) {
        const int i = __builtin_ctz(mask);
        const SearchEntry x{node.child[i], dist[i]};
        int j = n++;
        while (j > 0 && keep[j - 1].dist < x.dist) {
            keep[j] = keep[j - 1];
            --j;
        }
        keep[j] = x;
    }
    for (int i = 0; i + 1 < n; ++i) stack[top++] = keep[i];
    return keep[n - 1].ref;
}

} // namespace

Result<DistanceIndex> DistanceIndex::build(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices) {
    DistanceIndex index;
    const size_t tri_count = indices.size() / 3;
    if (tri_count == 0) return index;
    if (tri_count >= kMaxSlots) {
        return resourceLimit("distance index: " + std::to_string(tri_count) + " triangles, expected fewer than 2^28");
    }
    // Box centres and their bounds, the largest coordinate magnitude.
    LargeArray<Vec3f> centres(tri_count);
    BuildBox centre_box;
    float magnitude = 0.0f;
    for (size_t t = 0; t < tri_count; ++t) {
        BuildBox box;
        for (int k = 0; k < 3; ++k) {
            const Vec3f& v = positions[indices[t * 3 + k]];
            const float xyz[3] = {v.x, v.y, v.z};
            box.expand(xyz, xyz);
        }
        float c[3];
        for (int k = 0; k < 3; ++k) {
            c[k] = (box.lo[k] + box.hi[k]) * 0.5f;
            magnitude = std::max({magnitude, std::fabs(box.lo[k]), std::fabs(box.hi[k])});
        }
        centres[t] = Vec3f(c[0], c[1], c[2]);
        centre_box.expand(c, c);
    }
    // Triangles in Morton order of their box centre, ties by triangle index.
    LargeArray<std::pair<uint64_t, uint32_t>> order(tri_count);
    {
        const Vec3d lo(centre_box.lo[0], centre_box.lo[1], centre_box.lo[2]);
        const double extent = std::max({double(centre_box.hi[0]) - lo.x, double(centre_box.hi[1]) - lo.y,
                                        double(centre_box.hi[2]) - lo.z, 1e-300});
        const double scale = double(kMortonCells - 1) / extent;
        for (size_t t = 0; t < tri_count; ++t) order[t] = {mortonCode((toDouble(centres[t]) - lo) * scale), uint32_t(t)};
    }
    LargeArray<Vec3f>().swap(centres);
    std::sort(order.begin(), order.end());
    LargeArray<uint64_t> codes(tri_count);
    index.face_of_slot_.resize(tri_count);
    index.corners_.reserve(tri_count * 3 + 1);
    for (size_t s = 0; s < tri_count; ++s) {
        const uint32_t t = order[s].second;
        codes[s] = order[s].first;
        index.face_of_slot_[s] = t;
        for (int k = 0; k < 3; ++k) index.corners_.push_back(positions[indices[size_t(t) * 3 + k]]);
    }
    LargeArray<std::pair<uint64_t, uint32_t>>().swap(order);
    index.corners_.push_back(Vec3f(0.0f, 0.0f, 0.0f)); // padding: the query loads 4 floats per corner
    // The float box test is exact enough only for queries whose coordinates are at most twice the
    // mesh's largest (the rounding of the query point to float is then below a quarter of the slack);
    // others, and meshes of extreme scale, take the double test. The slack is M * 2^-21.
    const bool float_ok = magnitude > 1e-12f && magnitude < 1e12f;
    const double slack = double(magnitude) * std::ldexp(1.0, -21);
    index.magnitude_ = float_ok ? magnitude : 0.0f;
    index.slack_ = slack;
    index.nodes_.reserve(tri_count / (2 * kLeafTriangles) + 2);
    IndexBuilder builder(codes, index.corners_, index.nodes_, slack);
    BuildBox root_box;
    index.root_ = builder.build(0, uint32_t(tri_count), root_box);
    return index;
}

double DistanceIndex::scalarBoxDistanceSq(const Node& node, int child, const Vec3d& p) const {
    double d = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double lo = node.lo[k][child], hi = node.hi[k][child], v = p[k];
        const double e = v < lo ? lo - v : (v > hi ? v - hi : 0.0);
        d += e * e;
    }
    return d;
}

double DistanceIndex::triangleBoxDistanceSq(uint32_t slot, const Vec3d& p) const {
    const Vec3f* c = &corners_[size_t(slot) * 3];
    double d = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double lo = double(std::min(std::min(c[0][k], c[1][k]), c[2][k])) - slack_;
        const double hi = double(std::max(std::max(c[0][k], c[1][k]), c[2][k])) + slack_;
        const double v = p[k];
        const double e = v < lo ? lo - v : (v > hi ? v - hi : 0.0);
        d += e * e;
    }
    return d;
}

double DistanceIndex::closestDistanceSq(const Vec3d& p, uint32_t& hint) const {
    Cursor cursor;
    cursor.hint = hint;
    const double d = closestDistanceSq(p, cursor);
    hint = cursor.hint;
    return d;
}

double DistanceIndex::closestDistanceSq(const Vec3d& p, Cursor& cursor) const {
    double best = std::numeric_limits<double>::infinity();
    if (root_ == kEmptyChild) return best;
    uint32_t& hint = cursor.hint;
    auto measureSlot = [&](uint32_t s) __attribute__((always_inline)) {
        const Vec3f* c = &corners_[size_t(s) * 3];
        return exactDistanceSq(p, toDouble(c[0]), toDouble(c[1]), toDouble(c[2]));
    };
    const uint32_t start = hint;
    if (hint != kNoHint) best = measureSlot(hint);
    // A box is skipped only when its (widened, rounded) distance exceeds the best exact distance by the
    // relative slack plus an absolute term far below float resolution: no triangle whose exact
    // distance could be the minimum is ever skipped.
    const double absolute = double(magnitude_) * std::ldexp(1.0, -24);
    const double tiny = absolute * absolute;
    const float mag = magnitude_;
    const bool use_float = std::fabs(p.x) <= 2.0 * mag && std::fabs(p.y) <= 2.0 * mag && std::fabs(p.z) <= 2.0 * mag;
    const float px = float(p.x), py = float(p.y), pz = float(p.z);
    // The float limit is at most FLT_MAX, so an empty child (infinite distance) never passes.
    double limit = 0.0;
    float limit_f = 0.0f;
    auto setLimit = [&]() {
        limit = best * kPruneRelative + tiny;
        limit_f = std::min(float(limit), std::numeric_limits<float>::max());
    };
    setLimit();
#if defined(__SSE2__)
    const __m128 vp = _mm_setr_ps(px, py, pz, 0.0f);
    const __m128 slack4 = _mm_set1_ps(float(slack_)); // exact: the magnitude (a float) times 2^-21
    const __m128 zero = _mm_setzero_ps();
#endif
    // Whether slot s's own box, widened like the node boxes, is beyond the limit: the same test as a
    // node's, so such a triangle cannot be nearer either.
    auto triangleBeyond = [&](uint32_t s) {
#if defined(__SSE2__)
        if (use_float) {
            // Loads 4 floats per corner (the last one reads the padding after the final slot).
            const float* c = &corners_[size_t(s) * 3].x;
            const __m128 c0 = _mm_loadu_ps(c), c1 = _mm_loadu_ps(c + 3), c2 = _mm_loadu_ps(c + 6);
            const __m128 lo = _mm_sub_ps(_mm_min_ps(_mm_min_ps(c0, c1), c2), slack4);
            const __m128 hi = _mm_add_ps(_mm_max_ps(_mm_max_ps(c0, c1), c2), slack4);
            __m128 e = _mm_max_ps(_mm_max_ps(_mm_sub_ps(lo, vp), _mm_sub_ps(vp, hi)), zero);
            e = _mm_mul_ps(e, e);
            const __m128 sum = _mm_add_ss(_mm_add_ss(e, _mm_shuffle_ps(e, e, 1)), _mm_movehl_ps(e, e));
            return _mm_cvtss_f32(sum) > limit_f;
        }
#endif
        return triangleBoxDistanceSq(s, p) > limit;
    };

    SearchEntry stack[kStackSize];
    size_t top = 0;
    uint32_t ref = cursor.node[resumeDepth(cursor, p, limit, mag, root_, use_float) - 1];
    // Whether the search is still on a single path from its start (no branch, no pop yet): each node
    // then joins the cursor's path.
    bool on_path = use_float;
    for (;;) {
        if (isLeaf(ref)) {
            const uint32_t first = (ref & ~kLeafBit) >> 3, count = (ref & 7u) + 1;
            for (uint32_t s = first; s < first + count; ++s) {
                // The hint's distance is already in `best`.
                if (s == start || triangleBeyond(s)) continue;
                const double d = measureSlot(s);
                if (d < best) {
                    best = d;
                    hint = s;
                    setLimit();
                }
            }
        } else {
            const Node& node = nodes_[ref];
            alignas(16) float dist[4];
            if (use_float) {
                childBoxDistancesSq(node, px, py, pz, dist);
            } else {
                // Rounded down to float so the float comparison below stays conservative.
                for (int i = 0; i < 4; ++i) {
                    const double d = scalarBoxDistanceSq(node, i, p);
                    float f = float(d);
                    if (double(f) > d) f = std::nextafter(f, 0.0f);
                    dist[i] = double(f) > limit ? HUGE_VALF : f;
                }
            }
            const unsigned mask = childrenWithin(dist, limit_f);
            if (mask != 0) {
                if ((mask & (mask - 1)) == 0) { // one child: descend without the stack
                    const int only = __builtin_ctz(mask);
                    ref = node.child[only];
                    if (on_path) on_path = extendCursorPath(cursor, ref, dist, only, mag);
                    continue;
                }
                on_path = false;
                ref = pushAllButNearest(node, mask, dist, stack, top);
                continue;
            }
        }
        // Next entry still within the limit.
        on_path = false;
        for (;;) {
            if (top == 0) return best;
            const SearchEntry e = stack[--top];
            if (e.dist <= limit_f) {
                ref = e.ref;
                break;
            }
        }
    }
}

Result<DistanceReference> DistanceReference::prepare(const Mesh& reference) {
    LODBAKE_RETURN_IF_ERROR(checkSurface(reference, "reference"));
    return prepareChecked(reference);
}

Result<DistanceReference> DistanceReference::prepareChecked(const Mesh& reference) {
    DistanceReference prepared;
    prepared.mesh_ = &reference;
    prepared.diagonal_ = computeBounds(reference).diagonal();
    LODBAKE_ASSIGN_OR_RETURN(prepared.index_, DistanceIndex::build(reference.positions, reference.indices));
    return prepared;
}

Result<DistanceResult> measureSurfaceDistance(const DistanceReference& reference, const Mesh& approx,
                                              const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    LODBAKE_ASSIGN_OR_RETURN(PointArray reference_points,
                             samplePoints(reference.mesh(), options, kReferenceStream, "reference"));
    return measurePrepared(reference, reference_points, prepareApprox(approx, options, true), nullptr);
}

std::vector<Result<DistanceResult>> measureSurfaceDistances(const DistanceReference& reference,
                                                            const std::vector<const Mesh*>& approximations,
                                                            const DistanceOptions& options) {
    std::vector<Result<DistanceResult>> results(approximations.size(), Result<DistanceResult>(DistanceResult{}));
    const Status status = checkOptions(options);
    if (!status.ok()) {
        for (auto& r : results) r = status;
        return results;
    }
    // The reference's points are drawn while the first approximation is prepared.
    Result<PointArray> reference_points = Result<PointArray>(PointArray());
    ApproxSide first;
    const Status run = parallelFor(approximations.empty() ? 1 : 2, 1, [&](size_t task) {
        if (task == 0)
            reference_points = samplePoints(reference.mesh(), options, kReferenceStream, "reference");
        else
            first = prepareApprox(*approximations[0], options, true);
    });
    if (!run.ok()) reference_points = run;
    if (!reference_points.ok()) {
        for (auto& r : results) r = reference_points.status();
        return results;
    }
    return measurePipelined(reference, *reference_points, approximations, options, std::move(first), {});
}

Result<std::vector<Result<OneSidedDistance>>> measureReferenceSides(const Mesh& reference,
                                                                   const std::vector<const Mesh*>& approximations,
                                                                   const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    LODBAKE_RETURN_IF_ERROR(checkSurface(reference, "reference"));
    // The points as their sources (8 bytes each instead of 24) and one approximation's index at a time:
    // this side is meant to run where memory is short (beside another big task); recomputing a point
    // costs little next to its query, and the index builds little next to the queries.
    const SideSampler sampler(reference, options, kReferenceStream);
    LODBAKE_ASSIGN_OR_RETURN(LargeArray<PointSources> points,
                             samplePointSources(reference, options, sampler, "reference"));
    auto pointAt = [&](size_t k) { return sampler.at(points[k].point, points[k].source); };
    std::vector<Result<OneSidedDistance>> results(approximations.size(), OneSidedDistance{});
    for (size_t i = 0; i < approximations.size(); ++i) {
        Result<DistanceIndex> index = checkedIndex(*approximations[i]);
        if (!index.ok()) {
            results[i] = index.status();
            continue;
        }
        results[i] = measurePointsAt(points.size(), pointAt, *index);
    }
    return results;
}

Result<std::vector<Result<DistanceResult>>> prepareAndMeasureSurfaceDistances(
    const Mesh& reference, const std::vector<const Mesh*>& approximations, const DistanceOptions& options) {
    return prepareAndMeasureSurfaceDistances(reference, approximations, options, {});
}

Result<std::vector<Result<DistanceResult>>> prepareAndMeasureSurfaceDistances(
    const Mesh& reference, const std::vector<const Mesh*>& approximations, const DistanceOptions& options,
    const std::vector<const OneSidedDistance*>& reference_sides) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    LODBAKE_RETURN_IF_ERROR(checkSurface(reference, "reference"));
    // The reference's points are needed only for the sides not measured beforehand.
    bool need_points = false;
    for (size_t i = 0; i < approximations.size(); ++i) need_points |= knownSide(reference_sides, i) == nullptr;
    // Three independent setup tasks side by side: the reference's index (serial), its points and the
    // first approximation's index and points.
    Result<DistanceReference> prepared = internalError("distance reference: not prepared");
    Result<PointArray> reference_points = Result<PointArray>(PointArray());
    ApproxSide first;
    LODBAKE_RETURN_IF_ERROR(parallelFor(approximations.empty() ? 2 : 3, 1, [&](size_t task) {
        if (task == 0)
            prepared = DistanceReference::prepareChecked(reference);
        else if (task == 1 && need_points)
            reference_points = samplePoints(reference, options, kReferenceStream, "reference");
        else if (task == 2)
            first = prepareApprox(*approximations[0], options, knownSide(reference_sides, 0) == nullptr);
    }));
    LODBAKE_RETURN_IF_ERROR(prepared.status());
    LODBAKE_RETURN_IF_ERROR(reference_points.status());
    return measurePipelined(*prepared, *reference_points, approximations, options, std::move(first),
                            reference_sides);
}

Result<DistanceResult> measureSurfaceDistance(const Mesh& reference, const Mesh& approx,
                                              const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    // Check the approximation before the (costly) reference BVH is built.
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    LODBAKE_ASSIGN_OR_RETURN(DistanceReference prepared, DistanceReference::prepare(reference));
    return measureSurfaceDistance(prepared, approx, options);
}

namespace detail {

Status checkDistanceOptions(const DistanceOptions& options) { return checkOptions(options); }

Status checkDistanceSurface(const Mesh& mesh, const char* role) { return checkSurface(mesh, role); }

Result<LargeArray<Vec3d>> approximationSidePoints(const Mesh& approx, const DistanceOptions& options) {
    return samplePoints(approx, options, kApproxStream, "approximation");
}

OneSidedDistance combineSideDistances(const double* distances, size_t count) {
    // measurePointsAt's arithmetic: per chunk in point order, then the chunks in order.
    OneSidedDistance total;
    for (size_t first = 0; first < count; first += kChunkSize) {
        const size_t end = std::min(count, first + kChunkSize);
        SideStats s;
        for (size_t k = first; k < end; ++k) {
            const double d = distances[k];
            s.max = std::max(s.max, d);
            s.sum += d;
            s.sum_sq += d * d;
            s.count++;
        }
        total.max = std::max(total.max, s.max);
        total.sum += s.sum;
        total.sum_sq += s.sum_sq;
        total.count += s.count;
    }
    return total;
}

DistanceResult twoSidedDistance(const OneSidedDistance& ref_to_approx, const OneSidedDistance& approx_to_ref,
                                double diagonal) {
    DistanceResult r;
    r.max_ref_to_approx = ref_to_approx.max;
    r.max_approx_to_ref = approx_to_ref.max;
    r.hausdorff = std::max(r.max_ref_to_approx, r.max_approx_to_ref);
    const double n12 = double(ref_to_approx.count), n21 = double(approx_to_ref.count);
    r.mean = (ref_to_approx.sum / n12 + approx_to_ref.sum / n21) / 2.0;
    r.rms = std::sqrt((ref_to_approx.sum_sq / n12 + approx_to_ref.sum_sq / n21) / 2.0);
    r.diagonal = diagonal;
    return r;
}

} // namespace detail

} // namespace lodbake
