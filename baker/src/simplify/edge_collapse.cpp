// Incremental edge collapse with quadric error metrics.
//   M. Garland, P. Heckbert, "Surface Simplification Using Quadric Error Metrics", SIGGRAPH 1997.
//   M. Garland, P. Heckbert, "Simplifying Surfaces with Color and Texture using Quadric Error
//     Metrics", IEEE Visualization 1998; H. Hoppe, "New Quadric Metric for Simplifying Meshes with
//     Appearance Attributes", IEEE Visualization 1999 (attribute quadrics, see quadric.h).
//   T. Dey, H. Edelsbrunner, S. Guha, D. Nekhayev, "Topology Preserving Edge Contraction", 1999
//     (link condition).
//   Constraint planes for borders and the heap with stored positions follow L. Gasparello's thesis
//   (Pisa 2007), ch. 2 and 4.3.3.
//
// Connectivity is a corner table: half-edge h = corner h of the index buffer, from he_[h].point
// to he_[nextHe(h)].point, he_[h].twin the opposite half-edge or kNone. Edges that are not
// 2-manifold with consistent orientation get no twin and lock their endpoints, so non-manifold
// spots of the input are never touched.
//
// Collapse (u removed, v kept, v moved to p), f0 = face of the edge, f1 = face of its twin:
//
//           w0                       w0
//          /  \                      |
//     t2  / f0 \  t1           t2 == t1 (glued)
//        /      \                    |
//       u ------ v        ==>        v (at p)
//        \      /                    |
//         \ f1 /                     |
//          \  /                      |
//           w1                       w1
#include "simplify/edge_collapse.h"


#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <new>
#include <string>
#include <utility>

#include "core/parallel.h"
#include "lodbake/core/math.h"

namespace lodbake::detail {

namespace {

// Below this quality (4√3·area / Σ edge²) a face's normal is too unstable to bound its rotation.
constexpr double kReliableQuality = 0.05;
// A popped collapse whose point-distance penalty grows its key by more than this many times its
// quadric part is re-queued.
constexpr double kRecheckFactor = 4.0;
// Below this fraction of the input's faces the simplifier is in its late stage (see run()): few
// collapses are left and each decides much of the Hausdorff error of the coarse levels.
constexpr double kLateFraction = 0.05;
// fartherFromNewFan skips a triangle whose plane is further than the nearest triangle so far (no
// region test needed); the margin keeps rounding from deciding, since the plane distance and the
// region test's distance differ in the last bits.
constexpr double kPlaneMargin = 1.0 + 1e-9;
// remove_covered_components (docs/simplify.md, "Covered components"): components are checked each
// time the face count has fallen to kComponentCheckStep of the count at the previous check, with a
// tolerance of kCoveredComponentFactor × the largest collapse error (quadric RMS estimate) so far.
// Open border edges lying on another component get kCoveredBorderFactor × the border weight. Both
// factors are tuned on merged range scans, whose overlapping sheets are what the option removes.
constexpr double kComponentCheckStep = 0.8;
constexpr double kCoveredComponentFactor = 1.0;
constexpr double kCoveredBorderFactor = 0.5;

// Hint that *p is about to be read (a random access into a large array).
inline void prefetch(const void* p) {
#if defined(__GNUC__)
    __builtin_prefetch(p);
#else
    (void)p;
#endif
}

// The named steps of init, runRound and collapse are inlined into them: the compiler then sees
// each as one function and keeps its inlining decisions for the hot collapse loop around them
// (left to itself it trades inlines there for the step functions, which slows the loop).
#if defined(__GNUC__)
#define LODBAKE_STEP inline __attribute__((always_inline))
#else
#define LODBAKE_STEP inline
#endif

// Items per task of init's parallel loops: fixed, so no result depends on the thread count.
constexpr uint32_t kInitChunk = 4096;

// Calls fn(chunk, first, last) for consecutive ranges of kInitChunk items of [0, count), in parallel.
template <class Fn> Status forChunks(uint32_t count, Fn&& fn) {
    return parallelForChunks(count, kInitChunk, [&](size_t chunk, size_t first, size_t last) {
        fn(chunk, uint32_t(first), uint32_t(last));
    });
}

uint32_t floatBits(float f) {
    uint32_t b;
    std::memcpy(&b, &f, sizeof b);
    return b;
}

Vec3d toD(const Vec3f& v) {
    return Vec3d(v);
}

double length2(const Vec3d& v) {
    return dot(v, v);
}

// Squared distance from p to the triangle (a, b, c) (Ericson, Real-Time Collision Detection
// §5.1.5, the region tests of closestPointOnTriangle in core/bvh.cpp, inlined for the hot loop).
// ab = b − a, ac = c − a; a triangle with no area is measured through its edges.
double segmentDistance2(const Vec3d& p, const Vec3d& a, const Vec3d& b);
inline double triangleDistance2(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& ab,
                                const Vec3d& ac, bool degenerate) {
    if (degenerate)
        return std::min(std::min(segmentDistance2(p, a, b), segmentDistance2(p, b, c)), segmentDistance2(p, c, a));
    const Vec3d ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return length2(ap);
    const Vec3d bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return length2(bp);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return length2(ap - ab * (d1 / (d1 - d3)));
    const Vec3d cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return length2(cp);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return length2(ap - ac * (d2 / (d2 - d6)));
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return length2(bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    const double denom = 1.0 / (va + vb + vc);
    return length2(ap - ab * (vb * denom) - ac * (vc * denom));
}

// Squared distance from p to the segment [a, b].
double segmentDistance2(const Vec3d& p, const Vec3d& a, const Vec3d& b) {
    const Vec3d ab = b - a;
    const Vec3d ap = p - a;
    const double len2 = length2(ab);
    double t = len2 > 0.0 ? dot(ap, ab) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return length2(ap - ab * t);
}

} // namespace

bool EdgeCollapser::canRemove(uint32_t point, bool feature_edge) const {
    const uint8_t k = kind_[point];
    if (k == kFree) return true;
    if (k == kLine) return feature_edge;
    return false;
}

bool EdgeCollapser::gatherFan(uint32_t point, std::vector<uint32_t>& fan) const {
    fan.clear();
    const uint32_t h0 = point_he_[point];
    if (h0 == kNone) return true;
    const size_t guard = he_.size();
    uint32_t h = h0;
    for (;;) {
        fan.push_back(h);
        // The neighbour's position is read by every user of the fan (flip checks, distances); its
        // miss overlaps the walk to the next face. So are the face's corner wedges when there are
        // attributes (seam checks, the neighbours' attribute blocks in collapse()).
        prefetch(&position_[he_[nextHe(h)].point]);
        if (!corner_wedge_.empty()) prefetch(&corner_wedge_[h]);
        const uint32_t n = he_[prevHe(h)].twin;
        if (n == h0) return true;
        if (n == kNone || fan.size() > guard) break;
        h = n;
    }
    // Open fan: walk the other way from h0.
    h = h0;
    for (;;) {
        const uint32_t t = he_[h].twin;
        if (t == kNone) break;
        h = nextHe(t);
        if (h == h0 || fan.size() > guard) break;
        fan.push_back(h);
        prefetch(&position_[he_[nextHe(h)].point]);
        if (!corner_wedge_.empty()) prefetch(&corner_wedge_[h]);
    }
    return false;
}

EdgeCollapser::Kind EdgeCollapser::classify(Worker& w, uint32_t point) {
    if (kind_[point] == kLocked || kind_[point] == kDead) return Kind(kind_[point]);
    if (point_he_[point] == kNone) return kDead;
    const bool closed = gatherFan(point, w.fan_tmp);
    return classifyFan(w.fan_tmp, closed);
}

EdgeCollapser::Kind EdgeCollapser::classifyFan(const std::vector<uint32_t>& fan, bool closed) const {
    if (!closed && options_.lock_border) return kCorner;
    int features = 0;
    for (uint32_t h : fan) {
        if (isFeature(h)) ++features;
        const uint32_t in = prevHe(h);
        if (he_[in].twin == kNone) ++features; // a boundary edge coming in is nobody's outgoing edge
    }
    if (features == 0) return kFree;
    if (features == 2) return kLine;
    return kCorner;
}

void EdgeCollapser::collectPairs(uint32_t edge, uint32_t removed, WedgePair* pairs, int& pair_count) const {
    const uint32_t a_corner = edge, b_corner = nextHe(edge);
    const bool remove_a = he_[edge].point == removed;
    pairs[0] =
        remove_a ? WedgePair{wedgeAt(a_corner), wedgeAt(b_corner)} : WedgePair{wedgeAt(b_corner), wedgeAt(a_corner)};
    pair_count = 1;
    const uint32_t t = he_[edge].twin;
    if (t == kNone) return;
    // The twin runs b -> a: corner t is b, corner next(t) is a.
    const WedgePair p =
        remove_a ? WedgePair{wedgeAt(nextHe(t)), wedgeAt(t)} : WedgePair{wedgeAt(t), wedgeAt(nextHe(t))};
    if (p.removed != pairs[0].removed || p.kept != pairs[0].kept) pairs[pair_count++] = p;
}

Quadric EdgeCollapser::combinedQuadric(const Quadric& geometric, uint32_t edge, uint32_t removed) const {
    Quadric q = geometric;
    if (channel_count_ == 0) return q;
    WedgePair pairs[2];
    int count = 0;
    collectPairs(edge, removed, pairs, count);
    for (int i = 0; i < count; ++i)
        addAttributeBlockTo(wedgeBlock(pairs[i].removed), wedgeBlock(pairs[i].kept), channel_count_,
                            channel_weight_.data(), q);
    return q;
}

bool EdgeCollapser::evaluate(uint32_t edge, Candidate& c) const {
    const uint32_t a = he_[edge].point;
    if (a == kNone) return false;
    const uint32_t b = he_[nextHe(edge)].point;
    if (kind_[a] >= kLocked || kind_[b] >= kLocked) return false;
    const bool feature = isFeature(edge);
    const bool ra = canRemove(a, feature);
    const bool rb = canRemove(b, feature);
    if (!ra && !rb) return false;
    c.edge = edge;
    c.removed = ra ? a : b;
    c.kept = ra ? b : a;
    // The points' quadrics summed (the geometric error), then with the attribute quadrics.
    Quadric geometric = quadric_[a];
    geometric += quadric_[b];
    Quadric q = combinedQuadric(geometric, edge, c.removed);
    Vec3d pk = toD(position_[c.kept]);
    Vec3d pr = toD(position_[c.removed]);
    if (options_.placement == CollapsePlacement::KeepEndpoint) {
        // Half-edge collapse: the kept point stays where it is. When either end may go, the
        // direction with the lower cost is taken (ties: remove the first end, a).
        if (ra && rb) {
            // Without attributes both directions have the same quadric (the points' sum).
            Quadric q_other = channel_count_ == 0 ? q : combinedQuadric(geometric, edge, b);
            if (q_other.evaluate(pr) < q.evaluate(pk)) {
                std::swap(c.removed, c.kept);
                std::swap(pk, pr);
                q = q_other;
            }
        }
        c.position = pk;
    } else if (kind_[c.kept] == kCorner || (kind_[c.kept] == kLine && !feature)) {
        // Corners never move; a border/seam point only moves along its own feature line.
        c.position = pk;
    } else if (kind_[c.kept] == kLine) {
        // Both on the same feature line: stay on the segment between them, which lies on it.
        c.position = minimizeOnSegment(q, pr, pk);
    } else {
        // The free optimum is only trusted near the edge: in flat or cylindrical regions a barely
        // conditioned system can place the vertex far away at almost no quadric cost. When it is
        // trusted it is the global minimum, so the segment search is only the fallback.
        Vec3d opt;
        if (solveQuadric(q, opt) && length2(opt - (pr + pk) * 0.5) <= 4.0 * length2(pk - pr))
            c.position = opt;
        else
            c.position = minimizeOnSegment(q, pr, pk);
    }
    // Positions are stored in float: evaluate what will actually be stored.
    c.position = roundToFloat(c.position);
    c.cost = q.evaluate(c.position);
    // Attribute quadrics add no weight, so q.weight is the geometric one; without attributes the
    // geometric error is the cost itself.
    const double weight = q.weight;
    double geometric_cost = c.cost;
    if (channel_count_ > 0) geometric_cost = geometric.evaluate(c.position);
    c.error = weight > 0 ? std::sqrt(geometric_cost / weight) : 0.0;
    // Queue key: area-weighted cost divided by area^exponent (see SimplifyOptions).
    if (weight > 0) {
        const double e = options_.cost_area_exponent;
        if (e == 0.5f)
            c.cost /= std::sqrt(weight);
        else if (e == 1.0f)
            c.cost /= weight;
        else if (e != 0.0f)
            c.cost /= std::pow(weight, e);
    }
    if (has_penalty_) c.cost += double(queue_.payload(edge)); // see run()
    return true;
}

Vec3d EdgeCollapser::fanNormal(const std::vector<uint32_t>& fan) const {
    Vec3d sum;
    for (uint32_t h : fan) {
        const Vec3d p0 = toD(position_[he_[h].point]);
        sum += cross(toD(position_[he_[nextHe(h)].point]) - p0, toD(position_[he_[prevHe(h)].point]) - p0);
    }
    return sum;
}

bool EdgeCollapser::normalTurnsTooFar(double d, double len2_a, double len2_b) const {
    // dot < cos·|a|·|b| without square roots (the sign of cos decides which side squares safely).
    const double c = cos_max_normal_change_;
    const double bound2 = c * c * len2_a * len2_b;
    if (c >= 0.0) return d < 0.0 || d * d < bound2;
    return d < 0.0 && d * d > bound2;
}

bool EdgeCollapser::checkFaces(const Worker& w, const std::vector<uint32_t>& fan, uint32_t moved, const Vec3d& p,
                               uint32_t f0, uint32_t f1, RegionNormal& region, double& min_old2,
                               double& min_new2) const {
    // Qualities are compared squared: q² = 12·|n|² / (Σ edge²)², |n| = twice the area.
    const Vec3d pm = toD(position_[moved]);
    for (uint32_t h : fan) {
        const uint32_t f = h / 3;
        const Vec3d px = toD(position_[he_[nextHe(h)].point]);
        const Vec3d py = toD(position_[he_[prevHe(h)].point]);
        const Vec3d xy = px - py;
        const double xy2 = length2(xy);
        const Vec3d n_old = cross(px - pm, py - pm);
        const double len2_old = length2(n_old);
        const double s_old = length2(px - pm) + length2(py - pm) + xy2;
        const double q2_old = 12.0 * len2_old / (s_old * s_old);
        min_old2 = std::min(min_old2, q2_old);
        if (f == f0 || f == f1) continue;
        const Vec3d n_new = cross(px - p, py - p);
        const double len2_new = length2(n_new);
        if (!(len2_new > 0.0)) return false;
        const double s_new = length2(px - p) + length2(py - p) + xy2;
        min_new2 = std::min(min_new2, 12.0 * len2_new / (s_new * s_new));
        if (q2_old >= kReliableQuality * kReliableQuality) {
            if (normalTurnsTooFar(dot(n_old, n_new), len2_old, len2_new)) return false;
        } else {
            // A sliver's normal is noise: judge the new face against the surrounding surface.
            if (!region.ready) {
                region.normal = fanNormal(w.fan_u) + fanNormal(w.fan_v);
                region.ready = true;
            }
            if (normalTurnsTooFar(dot(region.normal, n_new), length2(region.normal), len2_new)) return false;
        }
    }
    return true;
}

bool EdgeCollapser::checkUvFaces(const std::vector<uint32_t>& fan, const Vec3d& p, uint32_t f0, uint32_t f1,
                                 const WedgePair* pairs, int pair_count) const {
    for (uint32_t set = 0; set < uv_set_count_; ++set) {
        const uint32_t ch = uv_channel_ + 2 * set;
        auto value = [&](uint32_t w, uint32_t k) { return double(wedge_value_[size_t(w) * channel_count_ + ch + k]); };
        for (uint32_t h : fan) {
            const uint32_t f = h / 3;
            if (f == f0 || f == f1) continue;
            const uint32_t w = corner_wedge_[h], wx = corner_wedge_[nextHe(h)], wy = corner_wedge_[prevHe(h)];
            const double xu = value(wx, 0), xv = value(wx, 1), yu = value(wy, 0), yv = value(wy, 1);
            double nu = value(w, 0), nv = value(w, 1);
            for (int i = 0; i < pair_count; ++i) {
                if (pairs[i].removed != w && pairs[i].kept != w) continue;
                // The same bits collapse() will store (kept += removed, then the optimal value).
                const double* kept = wedgeBlock(pairs[i].kept);
                const double* removed = wedgeBlock(pairs[i].removed);
                nu = roundToFloat(attributeBlockOptimalValue(kept, removed, ch, p));
                nv = roundToFloat(attributeBlockOptimalValue(kept, removed, ch + 1, p));
                break;
            }
            const double old_area = (xu - value(w, 0)) * (yv - value(w, 1)) - (yu - value(w, 0)) * (xv - value(w, 1));
            const double new_area = (xu - nu) * (yv - nv) - (yu - nu) * (xv - nv);
            if (old_area == 0.0) continue; // already degenerate in UV: nothing to preserve
            if ((old_area > 0) != (new_area > 0) || new_area == 0.0) return false;
        }
    }
    return true;
}

bool EdgeCollapser::isValid(Worker& w, const Candidate& c, int& pair_count, WedgePair* pairs) {
    const uint32_t u = c.removed, v = c.kept, h = c.edge;
    const uint32_t t = he_[h].twin;
    const uint32_t f0 = h / 3;
    const uint32_t f1 = t == kNone ? kNone : t / 3;
    // v's first face loads while u's fan is walked.
    if (point_he_[v] != kNone) prefetch(&he_[point_he_[v]]);
    const bool u_closed = gatherFan(u, w.fan_u);
    const bool v_closed = gatherFan(v, w.fan_v);
    w.fan_u_closed = u_closed;
    w.fan_v_closed = v_closed;
    // An interior edge joining two boundary points would pinch the surface (the hole's virtual
    // vertex is a common neighbour outside the edge's link).
    if (t != kNone && !u_closed && !v_closed) return false;
    const uint32_t w0 = he_[prevHe(h)].point;
    const uint32_t w1 = t == kNone ? kNone : he_[prevHe(t)].point;
    if (w0 == w1) return false;
    // A face whose two other edges are both open would be left dangling or isolated.
    if (he_[nextHe(h)].twin == kNone && he_[prevHe(h)].twin == kNone) return false;
    if (t != kNone && he_[nextHe(t)].twin == kNone && he_[prevHe(t)].twin == kNone) return false;

    // Link condition, vertices: common neighbours of u and v must be exactly w0 (and w1). The
    // neighbours are the far ends of the fans' outgoing edges, plus the other corners when a fan
    // is open (in a closed fan each face's third corner is the next face's far end). A fan has a
    // handful of points, so a linear search beats marking them in a per-point array (a random
    // write per neighbour).
    std::vector<uint32_t>& link_u = w.link_u;
    link_u.clear();
    for (uint32_t he : w.fan_u) {
        link_u.push_back(he_[nextHe(he)].point);
        if (!u_closed) link_u.push_back(he_[prevHe(he)].point);
    }
    auto common = [&](uint32_t x) {
        return x != w0 && x != w1 && x != u && std::find(link_u.begin(), link_u.end(), x) != link_u.end();
    };
    for (uint32_t he : w.fan_v) {
        if (common(he_[nextHe(he)].point)) return false;
        if (!v_closed && common(he_[prevHe(he)].point)) return false;
    }
    // Link condition, edges: the edge w0-w1 is in both links iff faces (u,w0,w1) and (v,w0,w1)
    // exist; they are the faces across the other two edges of f0 (the tetrahedron case).
    if (t != kNone) {
        const uint32_t t1 = he_[nextHe(h)].twin, t2 = he_[prevHe(h)].twin;
        if (t1 != kNone && t2 != kNone && he_[prevHe(t1)].point == w1 && he_[prevHe(t2)].point == w1)
            return false;
    }

    pair_count = 0;
    if (!corner_wedge_.empty()) {
        collectPairs(h, u, pairs, pair_count);
        if (pair_count == 2 && pairs[0].removed == pairs[1].removed) return false; // one wedge, two targets
        // Every wedge of u must have a partner on v, or one side of a seam would be torn.
        for (uint32_t he : w.fan_u) {
            const uint32_t wedge = corner_wedge_[he];
            bool found = false;
            for (int i = 0; i < pair_count; ++i) found = found || pairs[i].removed == wedge;
            if (!found) return false;
        }
    }
    if (uv_channel_ != kNone) {
        // No face flips or degenerates in texture space. A chart may lose its last face: an atlas of
        // hundreds of charts could not reach a coarse level otherwise, and the collapse that drops
        // it pays for it in the queue like any other (its wedge's attribute quadric enters the cost).
        if (!checkUvFaces(w.fan_u, c.position, f0, f1, pairs, pair_count) ||
            !checkUvFaces(w.fan_v, c.position, f0, f1, pairs, pair_count))
            return false;
    }
    RegionNormal region;
    double min_old2 = 1.0, min_new2 = 1.0;
    if (!checkFaces(w, w.fan_u, u, c.position, f0, f1, region, min_old2, min_new2) ||
        !checkFaces(w, w.fan_v, v, c.position, f0, f1, region, min_old2, min_new2))
        return false;
    // Needles: the worst triangle of the neighbourhood may not get worse (removing a sliver is fine).
    const double min_quality = double(options_.min_triangle_quality);
    if (min_new2 < min_quality * min_quality && min_new2 < min_old2) return false;
    return true;
}

LODBAKE_STEP void EdgeCollapser::prefetchNeighbourhood(const Worker& w, const CollapseSequence* sequence) const {
    // Every neighbour's edge to v is re-evaluated at the end (updateEdgesInFan), which reads the
    // neighbour's quadric: a random access each. Requesting them all now lets those misses overlap
    // with each other and with the work below instead of waiting one by one.
    // The same goes for the queue slots of those edges (their twins are known since the fan walks;
    // only the two glued edges change their canonical half-edge below).
    for (const std::vector<uint32_t>* fan : {&w.fan_u, &w.fan_v})
        for (uint32_t he : *fan) {
            prefetchPoint(he_[nextHe(he)].point);
            queue_.prefetch(canonical(he));
        }
    // Those evaluations also read the attribute blocks of the neighbours' wedges (the one at the
    // neighbour's corner of each fan face; its twin's corner is most often the same wedge).
    if (block_size_ > 0)
        for (const std::vector<uint32_t>* fan : {&w.fan_u, &w.fan_v})
            for (uint32_t he : *fan) prefetchWedgeBlock(corner_wedge_[nextHe(he)]);
    // A half-edge sequence reads the triangle ids of u's faces (below).
    if (sequence && !face_triangle_.empty())
        for (uint32_t he : w.fan_u) prefetch(&face_triangle_[he / 3]);
}

LODBAKE_STEP void EdgeCollapser::mergeWedges(const Candidate& c, const WedgePair* pairs, int pair_count,
                                       CollapseSequence* sequence) {
    const bool has_normals = source_->hasNormals();
    const uint32_t color_first = source_->hasColors() ? channel_count_ - 4 : channel_count_;
    for (int i = 0; i < pair_count; ++i) {
        const size_t kept_base = size_t(pairs[i].kept) * channel_count_;
        double* kept_block = &wedge_block_[size_t(pairs[i].kept) * block_size_];
        const double* removed_block = wedgeBlock(pairs[i].removed);
        for (size_t k = 0; k < block_size_; ++k) kept_block[k] += removed_block[k];
        for (uint32_t ch = 0; ch < channel_count_; ++ch) {
            double value = attributeBlockOptimalValue(kept_block, nullptr, ch, c.position);
            if (ch >= color_first) value = std::clamp(value, 0.0, 1.0);
            wedge_value_[kept_base + ch] = float(value);
        }
        if (has_normals) {
            Vec3f n(wedge_value_[kept_base], wedge_value_[kept_base + 1], wedge_value_[kept_base + 2]);
            const float len = length(n);
            if (len > 0.0f) n = n / len;
            wedge_value_[kept_base] = n.x;
            wedge_value_[kept_base + 1] = n.y;
            wedge_value_[kept_base + 2] = n.z;
        }
        if (sequence) {
            sequence->wedge_updates.push_back({pairs[i].removed, pairs[i].kept});
            sequence->wedge_attributes.insert(sequence->wedge_attributes.end(), wedge_value_.begin() + kept_base,
                                              wedge_value_.begin() + kept_base + channel_count_);
        }
    }
}

LODBAKE_STEP void EdgeCollapser::removeCollapsedFaces(Worker& w, uint32_t h, uint32_t t) {
    // Remove f0 (and f1): glue the twins of their two other edges together.
    for (int side = 0; side < 2; ++side) {
        const uint32_t hf = side == 0 ? h : t;
        if (hf == kNone) continue;
        const uint32_t e1 = nextHe(hf), e2 = prevHe(hf);
        const uint32_t t1 = he_[e1].twin, t2 = he_[e2].twin;
        const uint32_t opposite = he_[e2].point;
        if (t1 != kNone) he_[t1].twin = t2;
        if (t2 != kNone) he_[t2].twin = t1;
        point_he_[opposite] = t1 != kNone ? t1 : (t2 != kNone ? nextHe(t2) : kNone);
        const uint32_t f = hf / 3;
        if (uv_channel_ != kNone && --chart_alive_[face_chart_[f]] == 0) ++dropped_charts_;
        for (uint32_t k = 0; k < 3; ++k) {
            he_[f * 3 + k].twin = kNone;
            he_[f * 3 + k].point = kNone;
        }
        if (w.heap)
            ++w.faces_removed;
        else
            --alive_faces_;
    }
}

void EdgeCollapser::collapse(Worker& w, const Candidate& c, const WedgePair* pairs, int pair_count,
                             CollapseSequence* sequence) {
    const uint32_t u = c.removed, v = c.kept, h = c.edge;
    const uint32_t t = he_[h].twin;
    const uint32_t f0 = h / 3;
    const uint32_t f1 = t == kNone ? kNone : t / 3;
    const uint32_t w0 = he_[prevHe(h)].point;
    const uint32_t w1 = t == kNone ? kNone : he_[prevHe(t)].point;

    prefetchNeighbourhood(w, sequence);
    for (uint32_t k = 0; k < 3; ++k) {
        queueRemove(w, canonical(f0 * 3 + k));
        if (f1 != kNone) queueRemove(w, canonical(f1 * 3 + k));
    }

    quadric_[v] += quadric_[u];
    const Vec3f p(float(c.position.x), float(c.position.y), float(c.position.z));
    CollapseRecord record;
    if (sequence) {
        record.removed_point = u;
        record.kept_point = v;
        record.position = p;
        record.first_wedge_update = uint32_t(sequence->wedge_updates.size());
        record.wedge_update_count = uint32_t(pair_count);
    }
    mergeWedges(c, pairs, pair_count, sequence);
    if (sequence) sequence->records.push_back(record);
    if (removal_log_) {
        CollapsePairLog& log = w.heap ? w.removals : *removal_log_; // a part: its own, appended at the merge
        log.add(u, v, p.x == position_[v].x && p.y == position_[v].y && p.z == position_[v].z);
    }
    if (has_penalty_) {
        // v now stands for the input points of both; it keeps the one further from its new fan.
        if (fartherFromNewFan(w, toD(far_[u]), toD(far_[v]), c)) far_[v] = far_[u];
    }
    position_[v] = p;

    // Half-edge sequence: the faces of u other than f0/f1 are re-created with v, oldest first.
    const bool log_triangles = sequence && !face_triangle_.empty();
    if (log_triangles) {
        w.created_tmp.clear();
        for (uint32_t he : w.fan_u) {
            const uint32_t f = he / 3;
            if (f != f0 && f != f1) w.created_tmp.push_back({face_triangle_[f], f});
        }
        std::sort(w.created_tmp.begin(), w.created_tmp.end());
    }
    for (uint32_t he : w.fan_u) {
        he_[he].point = v;
        if (!corner_wedge_.empty()) {
            const uint32_t wedge = corner_wedge_[he];
            for (int i = 0; i < pair_count; ++i)
                if (pairs[i].removed == wedge) corner_wedge_[he] = pairs[i].kept;
        }
    }

    removeCollapsedFaces(w, h, t);

    if (log_triangles) {
        for (const auto& [id, f] : w.created_tmp) {
            (void)id;
            for (uint32_t k = 0; k < 3; ++k) sequence->created_triangles.push_back(he_[f * 3 + k].point);
            face_triangle_[f] = triangle_count_++;
        }
        sequence->created_end.push_back(uint32_t(sequence->created_triangles.size() / 3));
    }

    point_he_[v] = kNone;
    for (const std::vector<uint32_t>* fan : {&w.fan_v, &w.fan_u}) {
        for (uint32_t he : *fan) {
            if (he_[he].point == v) {
                point_he_[v] = he;
                break;
            }
        }
        if (point_he_[v] != kNone) break;
    }
    point_he_[u] = kNone;
    kind_[u] = kDead;
    if (w.heap) {
        ++w.collapses;
        w.max_error = std::max(w.max_error, c.error);
    } else {
        ++collapses_;
        max_error_done_ = std::max(max_error_done_, c.error);
    }

    const uint8_t old_w0 = kind_[w0];
    const uint8_t old_w1 = w1 == kNone ? 0 : kind_[w1];
    // A free opposite point stays free: its fan stays closed, loses f0/f1 and gets one glued edge
    // whose sides carry the same wedges and sub-mesh (no feature edge touched it), so only
    // points on features need their fans walked again.
    if (old_w0 != kFree) kind_[w0] = classify(w, w0);
    if (w1 != kNone && old_w1 != kFree) kind_[w1] = classify(w, w1);
    // v's new fan is what is left of both old fans (no walk needed); it is open iff either was.
    w.fan_tmp.clear();
    for (const std::vector<uint32_t>* fan : {&w.fan_v, &w.fan_u})
        for (uint32_t he : *fan)
            if (he_[he].point == v) w.fan_tmp.push_back(he);
    if (kind_[v] != kLocked && kind_[v] != kDead)
        kind_[v] = point_he_[v] == kNone ? kDead : classifyFan(w.fan_tmp, w.fan_u_closed && w.fan_v_closed);
    updateEdgesInFan(w);
    if (kind_[w0] != old_w0) updateEdgesAround(w, w0);
    if (w1 != kNone && kind_[w1] != old_w1) updateEdgesAround(w, w1);
}

double EdgeCollapser::endpointDistance2(const Worker& w, const Candidate& c, double stop2) const {
    // w.fan_u / w.fan_v hold the fans gathered by isValid. Each distance only matters above stop2
    // (at least the quadric estimate), so its search stops as soon as it falls to that.
    const uint32_t f0 = c.edge / 3;
    const uint32_t t = he_[c.edge].twin;
    const uint32_t f1 = t == kNone ? kNone : t / 3;
    const Vec3d pu = toD(position_[c.removed]), pv = toD(position_[c.kept]);
    const Vec3d& p = c.position;
    // Late stage: also the input points the two ends stand for (far_), whose distances add up over
    // many collapses, and the new faces' centroids.
    const Vec3d fu = toD(far_[c.removed]), fv = toD(far_[c.kept]);
    const double inf = std::numeric_limits<double>::infinity();
    double du = inf, dv = inf, dp = inf;
    double dfu = late_ ? inf : 0.0, dfv = dfu;
    for (const std::vector<uint32_t>* fan : {&w.fan_u, &w.fan_v}) {
        for (uint32_t h : *fan) {
            if (dp <= stop2 && du <= stop2 && dv <= stop2 && dfu <= stop2 && dfv <= stop2) break;
            const uint32_t f = h / 3;
            const Vec3d ox = toD(position_[he_[nextHe(h)].point]);
            const Vec3d oy = toD(position_[he_[prevHe(h)].point]);
            if (dp > stop2) {
                const Vec3d o = toD(position_[he_[h].point]);
                const Vec3d ab = ox - o, ac = oy - o;
                dp = std::min(dp, triangleDistance2(p, o, ox, oy, ab, ac, !(length2(cross(ab, ac)) > 0.0)));
            }
            if (f == f0 || f == f1 || (du <= stop2 && dv <= stop2 && dfu <= stop2 && dfv <= stop2)) continue;
            const Vec3d ab = ox - p, ac = oy - p;
            const bool degenerate = !(length2(cross(ab, ac)) > 0.0);
            if (du > stop2) du = std::min(du, triangleDistance2(pu, p, ox, oy, ab, ac, degenerate));
            if (dv > stop2) dv = std::min(dv, triangleDistance2(pv, p, ox, oy, ab, ac, degenerate));
            if (dfu > stop2) dfu = std::min(dfu, triangleDistance2(fu, p, ox, oy, ab, ac, degenerate));
            if (dfv > stop2) dfv = std::min(dfv, triangleDistance2(fv, p, ox, oy, ab, ac, degenerate));
        }
    }
    double dc = 0; // a new face that bridges a concave region leaves the surface between its corners
    if (late_) {
        for (const std::vector<uint32_t>* fan : {&w.fan_u, &w.fan_v}) {
            for (uint32_t h : *fan) {
                const uint32_t f = h / 3;
                if (f == f0 || f == f1) continue;
                const Vec3d o = toD(position_[he_[h].point]);
                const Vec3d ox = toD(position_[he_[nextHe(h)].point]);
                const Vec3d oy = toD(position_[he_[prevHe(h)].point]);
                const Vec3d centroid = (p + ox + oy) * (1.0 / 3.0);
                // Its own old face first (usually the nearest), then both old fans.
                double d = triangleDistance2(centroid, o, ox, oy, ox - o, oy - o, !(length2(cross(ox - o, oy - o)) > 0.0));
                for (const std::vector<uint32_t>* old_fan : {&w.fan_u, &w.fan_v}) {
                    for (uint32_t g : *old_fan) {
                        if (d <= std::max(stop2, dc)) break;
                        const Vec3d go = toD(position_[he_[g].point]);
                        const Vec3d gx = toD(position_[he_[nextHe(g)].point]);
                        const Vec3d gy = toD(position_[he_[prevHe(g)].point]);
                        d = std::min(d, triangleDistance2(centroid, go, gx, gy, gx - go, gy - go,
                                                          !(length2(cross(gx - go, gy - go)) > 0.0)));
                    }
                }
                dc = std::max(dc, d);
            }
        }
    }
    double result = 0;
    for (double d : {du, dv, dp, dfu, dfv, dc})
        if (std::isfinite(d)) result = std::max(result, d);
    return result;
}

bool EdgeCollapser::fartherFromNewFan(const Worker& w, const Vec3d& a, const Vec3d& b, const Candidate& c) const {
    // Both distances in one walk of the new fan, skipping faces by their planes (kPlaneMargin).
    const uint32_t f0 = c.edge / 3;
    const uint32_t t = he_[c.edge].twin;
    const uint32_t f1 = t == kNone ? kNone : t / 3;
    const Vec3d& p = c.position;
    const Vec3d pa = a - p, pb = b - p;
    double da = std::numeric_limits<double>::infinity(), db = da;
    for (const std::vector<uint32_t>* fan : {&w.fan_u, &w.fan_v}) {
        for (uint32_t h : *fan) {
            const uint32_t f = h / 3;
            if (f == f0 || f == f1) continue;
            const Vec3d ox = toD(position_[he_[nextHe(h)].point]);
            const Vec3d oy = toD(position_[he_[prevHe(h)].point]);
            const Vec3d ab = ox - p, ac = oy - p;
            const Vec3d n = cross(ab, ac);
            const double n2 = length2(n);
            const bool degenerate = !(n2 > 0.0);
            const double ha = dot(pa, n), hb = dot(pb, n);
            if (degenerate || !(ha * ha > da * kPlaneMargin * n2))
                da = std::min(da, triangleDistance2(a, p, ox, oy, ab, ac, degenerate));
            if (degenerate || !(hb * hb > db * kPlaneMargin * n2))
                db = std::min(db, triangleDistance2(b, p, ox, oy, ab, ac, degenerate));
        }
    }
    if (!std::isfinite(db)) return false; // no face left around v
    return da > db;
}

double EdgeCollapser::distanceBound2(const Candidate& c) const {
    // isValid refused a face whose two other edges are both open, so each of p–w0 (and p–w1) is an
    // edge of at least one face of the new fan.
    const Vec3d pu = toD(position_[c.removed]), pv = toD(position_[c.kept]);
    const uint32_t t = he_[c.edge].twin;
    const Vec3d pw0 = toD(position_[he_[prevHe(c.edge)].point]);
    double du = segmentDistance2(pu, c.position, pw0);
    double dv = segmentDistance2(pv, c.position, pw0);
    if (t != kNone) {
        const Vec3d pw1 = toD(position_[he_[prevHe(t)].point]);
        du = std::min(du, segmentDistance2(pu, c.position, pw1));
        dv = std::min(dv, segmentDistance2(pv, c.position, pw1));
    }
    double dp = segmentDistance2(c.position, pu, pv);
    if (late_) {
        // The input points of both ends: as du and dv. A new face's centroid is within a third of
        // the moved corner's displacement of its old face.
        for (uint32_t point : {c.removed, c.kept}) {
            const Vec3d f = toD(far_[point]);
            double d = segmentDistance2(f, c.position, pw0);
            if (t != kNone) d = std::min(d, segmentDistance2(f, c.position, toD(position_[he_[prevHe(t)].point])));
            dp = std::max(dp, d);
        }
        dp = std::max(dp, std::max(length2(c.position - pu), length2(c.position - pv)) * (1.0 / 9.0));
    }
    return std::max(std::max(du, dv), dp);
}

void EdgeCollapser::updateEdgesAround(Worker& w, uint32_t point) {
    gatherFan(point, w.fan_tmp);
    updateEdgesInFan(w);
}

void EdgeCollapser::updateEdgesInFan(Worker& w) {
    // Eager update: every edge around the kept point gets its fresh key now. (Marking them stale
    // and re-keying on pop saves a few instructions but lets keys that dropped wait, so collapses
    // leave the cost order and the Hausdorff error grows.)
    Candidate c;
    auto update = [&](uint32_t he) {
        const uint32_t e = canonical(he);
        if (w.heap) {
            // A part re-keys only its own edges; the others wait for the merge (runRound).
            if (!inPart(w.part, e)) {
                w.deferred.push_back(e);
                return;
            }
            if (evaluate(e, c))
                w.heap->set(e, float(c.cost));
            else
                w.heap->remove(e);
            return;
        }
        if (evaluate(e, c))
            queue_.set(e, float(c.cost));
        else
            queue_.remove(e);
    };
    // The queue slots are far apart: request them all before the first lookup waits for one, then
    // the heap entries they point to (after a collapse the slots were requested at its start).
    for (uint32_t he : w.fan_tmp) queue_.prefetch(canonical(he));
    if (w.heap)
        for (uint32_t he : w.fan_tmp) w.heap->prefetchEntry(canonical(he));
    else
        for (uint32_t he : w.fan_tmp) queue_.prefetchEntry(canonical(he));
    for (uint32_t he : w.fan_tmp) {
        update(he);
        const uint32_t in = prevHe(he);
        if (he_[in].twin == kNone) update(in);
    }
}

void EdgeCollapser::requeueAll() {
    Candidate c;
    for (uint32_t h = 0; h < uint32_t(he_.size()); ++h) {
        if (he_[h].point == kNone || canonical(h) != h) continue;
        if (evaluate(h, c))
            queue_.set(h, float(c.cost));
        else
            queue_.remove(h);
    }
}

bool EdgeCollapser::run(size_t target_faces, double max_error, CollapseSequence* sequence) {
    // A round removes at most half of the faces alive: its seam band (points next to the other part)
    // keeps its density meanwhile, and the serial loop must catch up on it afterwards (one round
    // straight to a distant target leaves it too much, and the Hausdorff error rises above the serial
    // order's).
    // A run that goes further takes more rounds, each cut across the last one's seam (not after a
    // round to the run's own target: the serial loop's share is what catches up on the seam band).
    for (;;) {
        const size_t round_target = std::max(target_faces, alive_faces_ / 2);
        if (!roundApplies(round_target, sequence)) break;
        const size_t alive = alive_faces_;
        runRound(round_target, max_error);
        if (alive_faces_ == alive || round_target == target_faces) break; // (no cut, no room, nothing to collapse)
    }
    size_t collapses_at_requeue = collapses_;
    bool requeued = false;
    while (alive_faces_ > target_faces) {
        if (remove_components_ && alive_faces_ <= next_component_check_ && max_error_done_ > 0.0) {
            next_component_check_ = size_t(double(alive_faces_) * kComponentCheckStep);
            removeCoveredComponents(kCoveredComponentFactor * max_error_done_, sequence);
            continue;
        }
        late_ = alive_faces_ <= late_faces_;
        if (queue_.empty()) {
            // Rejected edges leave the queue until a collapse next to them re-evaluates them; an
            // empty queue may still hide collapses made valid by changes further away.
            if (requeued && collapses_ == collapses_at_requeue) break;
            requeueAll();
            requeued = true;
            collapses_at_requeue = collapses_;
            if (queue_.empty()) break;
        }
        step(serial_, max_error, sequence);
    }
    return alive_faces_ <= target_faces;
}

void EdgeCollapser::step(Worker& w, double max_error, CollapseSequence* sequence) {
    Candidate c;
    WedgePair pairs[2];
    PartHeap* heap = w.heap;
    const uint32_t e = heap ? heap->topId() : queue_.topId();
    auto drop = [&] {
        if (heap)
            heap->remove(e);
        else
            queue_.remove(e);
    };
    // The next edge to pop is most often the current runner-up. Its half-edge is requested
    // now and its points' data once that has arrived (below), so that the next evaluate does
    // not wait for a chain of misses.
    const uint32_t next = heap ? heap->secondId() : queue_.secondId();
    if (next != CollapseQueue::kAbsent) {
        prefetch(&he_[next]);
        if (block_size_ > 0) prefetch(&corner_wedge_[next]);
    }
    if (!evaluate(e, c) || c.error > max_error) {
        drop();
        return;
    }
    int pair_count = 0;
    if (!isValid(w, c, pair_count, pairs)) {
        // Dropped until a neighbouring collapse changes it and re-queues it.
        drop();
        return;
    }
    if (next != CollapseQueue::kAbsent && he_[next].point != kNone) {
        prefetchPoint(he_[next].point);
        prefetchPoint(he_[nextHe(next)].point);
        // Its fans are walked first thing (isValid): their starting half-edges and the twin face.
        prefetch(&point_he_[he_[next].point]);
        prefetch(&point_he_[he_[nextHe(next)].point]);
        if (he_[next].twin != kNone) prefetch(&he_[he_[next].twin]);
        if (block_size_ > 0) {
            prefetchWedgeBlock(corner_wedge_[next]);
            prefetchWedgeBlock(corner_wedge_[nextHe(next)]);
        }
    }
    if (has_penalty_) {
        // Quadrics measure distance to planes: a sharp tip whose faces are nearly parallel to
        // the motion, or a placement off the surface, looks cheap. The true point distances
        // (endpoints to the new fan, new position to the old fans) are priced when the edge is
        // popped and kept as its penalty (added by evaluate until the next pop); when the key
        // grows by more than kRecheckFactor × its quadric part the edge competes again.
        const double base = c.cost - double(queue_.payload(e));
        const double floor2 = c.error * c.error;
        // The price of a distance is × sqrt(area) of the merged quadric, as the key; in the late
        // stage × sqrt of the mean area of an edge's two points instead, so a thin feature is
        // not cheaper to flatten than a broad one with the same distance (Hausdorff error). (A part
        // of a partitioned round never runs in the late stage: alive_faces_ is not its count.)
        const double area = late_ ? 4.0 * total_weight_ / double(alive_faces_)
                                  : quadric_[c.removed].weight + quadric_[c.kept].weight;
        const double scale = double(options_.tip_distance_weight) * std::sqrt(area);
        const double limit = c.cost + kRecheckFactor * std::max(base, 0.0);
        // Cheap upper bounds of the three distances: the new fan contains the segments from the
        // new position to w0 (and w1), the old fans contain the edge itself. When even they
        // cannot send the edge back, collapse without measuring.
        auto requeues = [&](double d2) { return base + scale * std::max(0.0, d2 - floor2) > limit; };
        const double bound = distanceBound2(c);
        if (!requeues(bound)) {
            collapse(w, c, pairs, pair_count, sequence);
            return;
        }
        // Only whether the distance re-queues the edge matters unless it does (the edge then
        // collapses and its penalty is never read again), and that is monotone in the distance:
        // the searches may stop at the largest squared distance that does not re-queue. Above
        // it they run to the exact minimum, so a re-queued edge gets the exact penalty.
        double stop2 = floor2 + (limit - base) / scale;
        for (int i = 0; i < 64 && stop2 > floor2 && requeues(stop2); ++i) stop2 = std::nextafter(stop2, 0.0);
        if (!(std::isfinite(stop2) && stop2 >= floor2 && !requeues(stop2))) stop2 = floor2;
        const double extra = scale * std::max(0.0, endpointDistance2(w, c, stop2) - floor2);
        if (base + extra > limit) {
            queue_.setPayload(e, float(extra)); // the slots are shared with the part heaps
            if (heap) {
                heap->set(e, float(base + extra));
                if (heap->topId() != e) return;
            } else {
                queue_.set(e, float(base + extra));
                if (queue_.topId() != e) return; // still the cheapest: collapse it now
            }
        }
    }
    collapse(w, c, pairs, pair_count, sequence);
}

void EdgeCollapser::queueRemove(Worker& w, uint32_t edge) {
    if (!w.heap)
        queue_.remove(edge);
    else if (inPart(w.part, edge))
        w.heap->remove(edge);
    else
        w.deferred.push_back(edge);
}

bool EdgeCollapser::roundApplies(size_t target_faces, const CollapseSequence* sequence) const {
    // Not below late_faces_ (the late stage prices distances by the whole mesh's mean area), nor with
    // what the parts would share: UV chart counts, component removal, a sequence. (A removal log is
    // kept per part and appended in part order at the merge.)
    return alive_faces_ >= round_min_faces_ && target_faces >= late_faces_ && alive_faces_ > target_faces &&
           alive_faces_ - target_faces >= alive_faces_ / kRoundMinRemovedDivisor && !sequence &&
           uv_channel_ == kNone && !remove_components_;
}

namespace {

// The set-up loops below run over fixed chunks in parallel; each chunk's result is a count, a
// minimum, a maximum or bits OR-ed into shared words, so nothing depends on the thread count or
// on which chunk finishes first.
constexpr size_t kSetupChunk = 65536;
// A failed parallel loop (only bad_alloc gets there) throws as the serial loops' allocations would.
template <class Fn> void inChunks(size_t count, Fn&& fn) {
    if (!parallelForChunks(count, kSetupChunk, fn).ok()) throw std::bad_alloc();
}

} // namespace

// A partitioned round's cut (findRoundCut): a face belongs to part 1 when its first corner's
// bin along `axis` is above `bin`.
struct EdgeCollapser::RoundCut {
    static constexpr uint32_t kBins = 4096;
    int axis = -1;
    double axis_lo = 0, bin_scale = 0;
    uint32_t bin = 0;
    uint32_t binOf(const Vec3f& position) const {
        return std::min(kBins - 1, uint32_t((double(position[axis]) - axis_lo) * bin_scale));
    }
};

LODBAKE_STEP bool EdgeCollapser::findRoundCut(RoundCut& cut) const {
    const uint32_t point_count = uint32_t(position_.size());
    // The cut: a plane across the longest extent of the alive points' box other than the previous
    // round's axis (so that the last round's seam lies inside a part now), at the median of their
    // coordinate (a histogram's bin edge: deterministic and without a copy of the coordinates).
    struct Box {
        float lo[3] = {HUGE_VALF, HUGE_VALF, HUGE_VALF}, hi[3] = {-HUGE_VALF, -HUGE_VALF, -HUGE_VALF};
        uint32_t alive = 0;
    };
    std::vector<Box> boxes(chunkCount(point_count, kSetupChunk));
    inChunks(point_count, [&](size_t chunk, size_t first, size_t last) {
        Box& b = boxes[chunk];
        for (size_t p = first; p < last; ++p) {
            if (point_he_[p] == kNone) continue;
            ++b.alive;
            for (int k = 0; k < 3; ++k) {
                b.lo[k] = std::min(b.lo[k], position_[p][k]);
                b.hi[k] = std::max(b.hi[k], position_[p][k]);
            }
        }
    });
    Box box;
    for (const Box& b : boxes) {
        box.alive += b.alive;
        for (int k = 0; k < 3; ++k) {
            box.lo[k] = std::min(box.lo[k], b.lo[k]);
            box.hi[k] = std::max(box.hi[k], b.hi[k]);
        }
    }
    const float* lo = box.lo;
    const float* hi = box.hi;
    const uint32_t alive_points = box.alive;
    int axis = -1;
    for (int k = 0; k < 3; ++k)
        if (k != round_axis_ && (axis < 0 || hi[k] - lo[k] > hi[axis] - lo[axis])) axis = k;
    if (!(hi[axis] > lo[axis])) return false;
    constexpr uint32_t kBins = RoundCut::kBins;
    cut.axis = axis;
    cut.bin_scale = double(kBins) / (double(hi[axis]) - double(lo[axis]));
    cut.axis_lo = lo[axis];
    auto binOf = [&](uint32_t p) { return cut.binOf(position_[p]); };
    std::vector<std::vector<uint32_t>> chunk_histograms(boxes.size());
    inChunks(point_count, [&](size_t chunk, size_t first, size_t last) {
        std::vector<uint32_t>& h = chunk_histograms[chunk];
        h.assign(kBins, 0);
        for (size_t p = first; p < last; ++p)
            if (point_he_[p] != kNone) ++h[binOf(uint32_t(p))];
    });
    std::vector<uint32_t> histogram(kBins, 0);
    for (const std::vector<uint32_t>& h : chunk_histograms)
        for (uint32_t b = 0; b < kBins; ++b) histogram[b] += h[b];
    uint32_t cut_bin = 0;
    for (uint32_t sum = 0; cut_bin < kBins - 1; ++cut_bin) {
        sum += histogram[cut_bin];
        if (2 * size_t(sum) >= alive_points) break;
    }
    cut.bin = cut_bin;
    return true;
}

LODBAKE_STEP void EdgeCollapser::markRoundParts(const RoundCut& cut) {
    const uint32_t point_count = uint32_t(position_.size());
    const uint32_t he_count = uint32_t(he_.size());
    // A face belongs to the side of its first corner. A point is in part p when every face around it
    // and around each of its neighbours belongs to p; an edge is in p when both ends are. A collapse of
    // such an edge reads and writes only faces of p, points whose faces are all of p (it, its
    // neighbours) and the edges around those, and reads the neighbours' neighbours: the parts never
    // touch the same data (docs/simplify.md, "Partitioned rounds"). Collapses inside p keep this
    // (the kept point's new neighbours were the removed one's), so the sets hold for the round.
    const size_t words = (size_t(point_count) + 63) / 64;
    std::vector<uint64_t> has[2] = {std::vector<uint64_t>(words, 0), std::vector<uint64_t>(words, 0)};
    // Faces of different chunks share words: the bits are OR-ed in atomically.
    auto setBit = [](std::vector<uint64_t>& bits, uint32_t p) {
        __atomic_fetch_or(&bits[p >> 6], uint64_t(1) << (p & 63), __ATOMIC_RELAXED);
    };
    auto bit = [](const std::vector<uint64_t>& bits, uint32_t p) { return (bits[p >> 6] >> (p & 63)) & 1; };
    auto faceSide = [&](uint32_t f) { return cut.binOf(position_[he_[f * 3].point]) > cut.bin ? 1u : 0u; };
    const uint32_t face_count = he_count / 3;
    inChunks(face_count, [&](size_t, size_t first, size_t last) {
        for (uint32_t f = uint32_t(first); f < uint32_t(last); ++f) {
            if (he_[f * 3].point == kNone) continue;
            const uint32_t side = faceSide(f);
            for (uint32_t k = 0; k < 3; ++k) setBit(has[side], he_[f * 3 + k].point);
        }
    });
    for (uint32_t part = 0; part < kRoundParts; ++part) {
        part_points_[part].resize(words);
        for (size_t i = 0; i < words; ++i) part_points_[part][i] = has[part][i] & ~has[1 - part][i];
    }
    std::vector<uint64_t>& outside = has[0]; // points next to a point not in their faces' part
    std::fill(outside.begin(), outside.end(), 0);
    inChunks(face_count, [&](size_t, size_t first, size_t last) {
        for (uint32_t f = uint32_t(first); f < uint32_t(last); ++f) {
            if (he_[f * 3].point == kNone) continue;
            const std::vector<uint64_t>& pure = part_points_[faceSide(f)];
            const uint32_t a = he_[f * 3].point, b = he_[f * 3 + 1].point, c = he_[f * 3 + 2].point;
            if (!bit(pure, a) || !bit(pure, b) || !bit(pure, c)) {
                setBit(outside, a);
                setBit(outside, b);
                setBit(outside, c);
            }
        }
    });
    for (uint32_t part = 0; part < kRoundParts; ++part)
        for (size_t i = 0; i < words; ++i) part_points_[part][i] &= ~outside[i];
    std::vector<uint64_t>().swap(has[0]);
    std::vector<uint64_t>().swap(has[1]);
}

LODBAKE_STEP bool EdgeCollapser::splitQueue(PartHeap* heaps) {
    const uint32_t he_count = uint32_t(he_.size());
    // Each half-edge's part (kRoundParts: none), read in half-edge order here instead of at random
    // by the split's passes over the queue. A part's heap holds at most its edges alive now (its
    // collapses only remove or merge them).
    LargeArray<uint8_t> part_of_edge(he_count);
    std::vector<std::array<uint32_t, kRoundParts>> chunk_capacity(chunkCount(he_count, kSetupChunk));
    inChunks(he_count, [&](size_t chunk, size_t first, size_t last) {
        std::array<uint32_t, kRoundParts> count{};
        for (uint32_t h = uint32_t(first); h < uint32_t(last); ++h) {
            uint32_t part = 0;
            while (part < kRoundParts && !inPart(part, h)) ++part;
            part_of_edge[h] = uint8_t(part);
            if (part < kRoundParts && canonical(h) == h) ++count[part];
        }
        chunk_capacity[chunk] = count;
    });
    uint32_t capacity[kRoundParts] = {0, 0};
    for (const std::array<uint32_t, kRoundParts>& count : chunk_capacity)
        for (uint32_t part = 0; part < kRoundParts; ++part) capacity[part] += count[part];
    auto part_of = [&](uint32_t id) { return uint32_t(part_of_edge[id]); };
    auto for_parts = [](uint32_t count, const auto& fn) {
        if (!parallelFor(count, 1, [&](size_t part) { fn(uint32_t(part)); }).ok()) throw std::bad_alloc();
    };
    const bool split = queue_.split(part_of, capacity, heaps, kRoundParts, for_parts);
    LargeArray<uint8_t>().swap(part_of_edge);
    return split;
}

LODBAKE_STEP void EdgeCollapser::collapseRoundParts(PartHeap* heaps, size_t goal, double max_error) {
    for (uint32_t part = 0; part < kRoundParts; ++part) {
        Worker& w = parts_[part];
        w.heap = &heaps[part];
        w.part = part;
        w.faces_removed = 0;
        w.collapses = 0;
        w.max_error = 0;
        // A part removes at most `goal` faces, so it logs at most `goal` collapses: reserved
        // once (mapped, resident as written) instead of grown by doubling in a worker's heap.
        if (removal_log_) w.removals.reserve(goal);
    }
    late_ = false;
    // The parts run in phases up to a common key limit, so that neither collapses much further
    // up the cost order than the other (with a fixed share of the faces each, the part with the
    // costlier surface goes further than the serial order would, which raises the Hausdorff
    // error). A phase's limit is the key below which the two heaps together hold as
    // many entries as faces are left to remove, from a histogram of the keys' float bits (6
    // mantissa bits: steps of 1.6 %); a collapse removes two faces but re-keys its neighbours
    // above the limit, so a phase removes about two thirds of what is left. Each part may remove
    // at most its part (by entries under the limit) of the faces left, so the round never passes
    // the goal. Phases end once less than 1/32 of the goal is left. A limit at as many entries as
    // faces are left keeps the phases few (a lower limit needs more of them, and each ends in a wait
    // for the slower part). The seam's edges and the rest go on in run()'s serial loop.
    constexpr uint32_t kCostBins = 1u << 14;
    auto costBin = [](float cost) {
        uint32_t bits;
        std::memcpy(&bits, &cost, sizeof bits);
        return cost > 0.0f ? std::min(kCostBins - 1, bits >> 17) : 0u; // +inf: the last bin
    };
    std::vector<uint32_t> key_histogram[kRoundParts];
    for (std::vector<uint32_t>& h : key_histogram) h.assign(kCostBins, 0);
    size_t removed = 0;
    Status status = Status::okStatus();
    for (uint32_t phase = 0; phase < kRoundMaxPhases && removed + goal / 32 < goal && status.ok(); ++phase) {
        const size_t left = goal - removed;
        for (uint32_t part = 0; part < kRoundParts; ++part) {
            std::fill(key_histogram[part].begin(), key_histogram[part].end(), 0u);
            heaps[part].forEachCost([&](float cost) { ++key_histogram[part][costBin(cost)]; });
        }
        uint32_t limit = 0;
        size_t under[kRoundParts] = {}, under_total = 0;
        for (; limit < kCostBins; ++limit) {
            for (uint32_t part = 0; part < kRoundParts; ++part) {
                under[part] += key_histogram[part][limit];
                under_total += key_histogram[part][limit];
            }
            if (under_total >= left) break;
        }
        if (under_total == 0) break;
        size_t cap[kRoundParts];
        for (uint32_t part = 0; part < kRoundParts; ++part)
            cap[part] = parts_[part].faces_removed + size_t(double(left) * double(under[part]) / double(under_total));
        status = parallelFor(kRoundParts, 1, [&](size_t part) {
            Worker& w = parts_[part];
            while (w.faces_removed < cap[part] && !w.heap->empty() && costBin(w.heap->topCost()) <= limit)
                step(w, max_error, nullptr);
        });
        size_t now = 0;
        for (const Worker& w : parts_) now += w.faces_removed;
        if (now == removed) break;
        removed = now;
    }
    queue_.merge(heaps, kRoundParts);
    if (!status.ok()) throw std::bad_alloc(); // as a serial push_back would (only bad_alloc gets here)
    // Counters in part order; the edges the parts left to the merge get their keys now.
    Candidate c;
    for (Worker& w : parts_) {
        alive_faces_ -= w.faces_removed;
        collapses_ += w.collapses;
        max_error_done_ = std::max(max_error_done_, w.max_error);
        for (uint32_t e : w.deferred) {
            if (he_[e].point != kNone && canonical(e) == e && evaluate(e, c))
                queue_.set(e, float(c.cost));
            else
                queue_.remove(e);
        }
        std::vector<uint32_t>().swap(w.deferred);
        if (removal_log_) removal_log_->append(w.removals);
        w.removals.clear();
        w.heap = nullptr;
    }
}

void EdgeCollapser::runRound(size_t target_faces, double max_error) {
    RoundCut cut;
    if (!findRoundCut(cut)) return;
    markRoundParts(cut);
    PartHeap heaps[kRoundParts];
    const size_t goal = size_t(double(alive_faces_ - target_faces) * kRoundShare);
    if (splitQueue(heaps)) {
        collapseRoundParts(heaps, goal, max_error);
        round_axis_ = cut.axis;
        ++rounds_;
    }
    for (std::vector<uint64_t>& bits : part_points_) std::vector<uint64_t>().swap(bits);
}

namespace {

// Attribute channel ch of input vertex v: normal xyz, each UV set, colour rgba.
float channelValue(const Mesh& mesh, uint32_t v, uint32_t ch) {
    if (mesh.hasNormals()) {
        if (ch < 3) return mesh.normals[v][int(ch)];
        ch -= 3;
    }
    if (ch < 2 * mesh.uvs.size()) return mesh.uvs[ch / 2][v][int(ch % 2)];
    ch -= uint32_t(2 * mesh.uvs.size());
    return mesh.colors[v][int(ch)];
}

Status checkSimplifyInput(const Mesh& mesh, const SimplifyOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, "simplify input"));
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
        if (!isFinite(mesh.positions[v]))
            return invalidInput("simplify input: vertex " + std::to_string(v) + ": expected finite coordinates");
    if (!(options.min_triangle_quality >= 0.0f) || !(options.max_normal_change_deg > 0.0f) ||
        !(options.border_weight >= 0.0f) ||
        !(options.cost_area_exponent >= 0.0f && options.cost_area_exponent <= 1.0f) ||
        !(options.tip_distance_weight >= 0.0f))
        return invalidInput("simplify options: expected min_triangle_quality >= 0, max_normal_change_deg > 0, "
                            "border_weight >= 0, cost_area_exponent in [0, 1], tip_distance_weight >= 0");
    return Status::okStatus();
}

} // namespace

// init's map of the input: each vertex's point and wedge (kNone when unreferenced).
struct EdgeCollapser::InputMap {
    const Mesh& mesh;
    bool has_wedges;
    LargeArray<uint32_t> vertex_point, vertex_wedge;
};

LODBAKE_STEP void EdgeCollapser::weldPoints(InputMap& map) {
    const Mesh& mesh = map.mesh;
    const bool has_wedges = map.has_wedges;
    const uint32_t vertex_count = uint32_t(mesh.vertexCount());
    LargeArray<uint8_t> referenced(vertex_count, 0);
    for (uint32_t i : mesh.indices) referenced[i] = 1;
    LargeArray<uint32_t> order;
    order.reserve(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v)
        if (referenced[v]) order.push_back(v);

    // Weld by bit-identical position (points), and by position + attributes (wedges), with open
    // addressing hash tables filled in vertex order: every point and wedge is numbered by its
    // first (smallest) input vertex, independent of the table layout.
    auto attrEqual = [&](uint32_t a, uint32_t b) {
        for (uint32_t ch = 0; ch < channel_count_; ++ch)
            if (floatBits(channelValue(mesh, a, ch)) != floatBits(channelValue(mesh, b, ch))) return false;
        if (mesh.hasTangents())
            for (int k = 0; k < 4; ++k)
                if (floatBits(mesh.tangents[a][k]) != floatBits(mesh.tangents[b][k])) return false;
        return true;
    };
    auto attrHash = [&](uint32_t v, uint64_t h) {
        for (uint32_t ch = 0; ch < channel_count_; ++ch)
            h = (h ^ floatBits(channelValue(mesh, v, ch))) * 0x100000001b3ull;
        if (mesh.hasTangents())
            for (int k = 0; k < 4; ++k) h = (h ^ floatBits(mesh.tangents[v][k])) * 0x100000001b3ull;
        return h;
    };
    auto posHash = [&](uint32_t v) {
        uint64_t h = 0xcbf29ce484222325ull;
        for (int k = 0; k < 3; ++k) h = (h ^ floatBits(mesh.positions[v][k])) * 0x100000001b3ull;
        return h;
    };
    auto finish = [](uint64_t h) { return h ^ (h >> 29) ^ (h >> 47); };
    size_t table_size = 16;
    while (table_size < size_t(order.size()) * 2) table_size *= 2;
    const size_t mask = table_size - 1;
    map.vertex_point.assign(vertex_count, kNone);
    map.vertex_wedge.assign(vertex_count, kNone);
    LargeArray<uint32_t>& vertex_point = map.vertex_point;
    LargeArray<uint32_t>& vertex_wedge = map.vertex_wedge;
    position_.clear();
    wedge_vertex_.clear();
    wedge_point_.clear();
    {
        LargeArray<uint32_t> point_table(table_size, kNone); // first vertex of each point
        LargeArray<uint32_t> wedge_table(has_wedges ? table_size : 0, kNone);
        position_.reserve(order.size());
        wedge_vertex_.reserve(order.size());
        wedge_point_.reserve(order.size());
        // Each vertex's table slots are random accesses: they are hashed kWeldAhead vertices ahead
        // and prefetched, so the misses overlap (a ring of the hashes, so each is computed once).
        constexpr size_t kWeldAhead = 16;
        uint64_t point_hash[kWeldAhead], wedge_hash[kWeldAhead];
        auto hashAhead = [&](size_t n) {
            const uint32_t v = order[n];
            const uint64_t ph = posHash(v);
            point_hash[n % kWeldAhead] = ph;
            prefetch(&point_table[size_t(finish(ph)) & mask]);
            if (has_wedges) {
                const uint64_t wh = finish(attrHash(v, ph));
                wedge_hash[n % kWeldAhead] = wh;
                prefetch(&wedge_table[size_t(wh) & mask]);
            }
        };
        for (size_t n = 0; n < std::min(kWeldAhead, order.size()); ++n) hashAhead(n);
        for (size_t n = 0; n < order.size(); ++n) {
            const uint32_t v = order[n];
            const uint64_t ph = point_hash[n % kWeldAhead];
            const uint64_t wh = has_wedges ? wedge_hash[n % kWeldAhead] : 0;
            if (n + kWeldAhead < order.size()) hashAhead(n + kWeldAhead);
            size_t i = size_t(finish(ph)) & mask;
            for (;;) {
                const uint32_t r = point_table[i];
                if (r == kNone) {
                    point_table[i] = v;
                    vertex_point[v] = uint32_t(position_.size());
                    position_.push_back(mesh.positions[v]);
                    break;
                }
                bool same = true;
                for (int k = 0; k < 3; ++k)
                    same = same && floatBits(mesh.positions[r][k]) == floatBits(mesh.positions[v][k]);
                if (same) {
                    vertex_point[v] = vertex_point[r];
                    break;
                }
                i = (i + 1) & mask;
            }
            if (!has_wedges) { // one wedge per point, numbered alike
                if (vertex_point[v] == wedge_vertex_.size()) {
                    wedge_vertex_.push_back(v);
                    wedge_point_.push_back(vertex_point[v]);
                }
                vertex_wedge[v] = vertex_point[v];
                continue;
            }
            size_t j = size_t(wh) & mask;
            for (;;) {
                const uint32_t r = wedge_table[j];
                if (r == kNone) {
                    wedge_table[j] = v;
                    vertex_wedge[v] = uint32_t(wedge_vertex_.size());
                    wedge_vertex_.push_back(v);
                    wedge_point_.push_back(vertex_point[v]);
                    break;
                }
                if (vertex_point[r] == vertex_point[v] && attrEqual(r, v)) {
                    vertex_wedge[v] = vertex_wedge[r];
                    break;
                }
                j = (j + 1) & mask;
            }
        }
    }
    LargeArray<uint32_t>().swap(order);
}

LODBAKE_STEP void EdgeCollapser::renumberPointsByFirstUse(InputMap& map) {
    const Mesh& mesh = map.mesh;
    const bool has_wedges = map.has_wedges;
    LargeArray<uint32_t>& vertex_point = map.vertex_point;
    LargeArray<uint32_t>& vertex_wedge = map.vertex_wedge;
    // Points renumbered in order of first use by the faces: a collapse touches a few dozen points
    // and faces that are neighbours on the surface, and scans often list their vertices far from
    // the order of their faces. Face order is kept, so points and faces then advance together.
    // (A Morton curve of the positions does worse on merged range scans: their overlapping sheets
    // interleave points of different sheets.) Only storage moves: no decision depends on point ids, so the
    // simplified meshes are the same bits (wedges keep their numbering by first vertex; without
    // attributes a wedge is its point and moves with it).
    const uint32_t n = uint32_t(position_.size());
    LargeArray<uint32_t> first_use(n, kNone);
    uint32_t next = 0;
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        const uint32_t p0 = vertex_point[mesh.indices[f * 3]], p1 = vertex_point[mesh.indices[f * 3 + 1]],
                       p2 = vertex_point[mesh.indices[f * 3 + 2]];
        if (p0 == p1 || p1 == p2 || p0 == p2) continue; // dropped below
        for (uint32_t p : {p0, p1, p2})
            if (first_use[p] == kNone) first_use[p] = next++;
    }
    for (uint32_t p = 0; p < n; ++p) // points only on dropped faces, after the others
        if (first_use[p] == kNone) first_use[p] = next++;
    const LargeArray<uint32_t>& new_id = first_use;
    LargeArray<Vec3f> moved(n);
    for (uint32_t p = 0; p < n; ++p) moved[new_id[p]] = position_[p];
    position_.swap(moved);
    LargeArray<Vec3f>().swap(moved);
    for (uint32_t& p : vertex_point)
        if (p != kNone) p = new_id[p];
    if (has_wedges) {
        for (uint32_t& p : wedge_point_) p = new_id[p];
    } else {
        LargeArray<uint32_t> wedge_vertex(n);
        for (uint32_t w = 0; w < n; ++w) wedge_vertex[new_id[w]] = wedge_vertex_[w];
        wedge_vertex_.swap(wedge_vertex);
        for (uint32_t w = 0; w < n; ++w) wedge_point_[w] = w;
        vertex_wedge = vertex_point;
    }
}

LODBAKE_STEP uint32_t EdgeCollapser::buildFaces(const InputMap& map, Diagnostics& diagnostics) {
    const Mesh& mesh = map.mesh;
    const bool has_wedges = map.has_wedges;
    const LargeArray<uint32_t>& vertex_point = map.vertex_point;
    const LargeArray<uint32_t>& vertex_wedge = map.vertex_wedge;
    // Faces, in input order, without those degenerate by position.
    const size_t input_faces = mesh.faceCount();
    std::vector<SubMesh> groups = mesh.submeshes;
    const bool multi_group = groups.size() > 1;
    he_.clear();
    he_.reserve(input_faces * 3);
    corner_wedge_.clear();
    if (has_wedges) corner_wedge_.reserve(input_faces * 3);
    face_group_.clear();
    uint32_t kept_faces = 0;
    group_first_face_.assign(groups.size() + 1, 0);
    size_t dropped = 0;
    size_t group = 0;
    for (size_t f = 0; f < input_faces; ++f) {
        while (group < groups.size() && f * 3 >= size_t(groups[group].first_index) + groups[group].index_count) {
            ++group;
            if (group < groups.size()) group_first_face_[group] = kept_faces;
        }
        const uint32_t i0 = mesh.indices[f * 3], i1 = mesh.indices[f * 3 + 1], i2 = mesh.indices[f * 3 + 2];
        const uint32_t p0 = vertex_point[i0], p1 = vertex_point[i1], p2 = vertex_point[i2];
        if (p0 == p1 || p1 == p2 || p0 == p2) {
            ++dropped;
            continue;
        }
        he_.insert(he_.end(), {HalfEdge{p0, kNone}, HalfEdge{p1, kNone}, HalfEdge{p2, kNone}});
        if (has_wedges)
            corner_wedge_.insert(corner_wedge_.end(), {vertex_wedge[i0], vertex_wedge[i1], vertex_wedge[i2]});
        if (multi_group) face_group_.push_back(uint32_t(std::min(group, groups.size() - 1)));
        ++kept_faces;
    }
    for (size_t g = group + 1; g < groups.size(); ++g) group_first_face_[g] = kept_faces;
    group_first_face_[groups.size()] = kept_faces;
    if (dropped > 0)
        diagnostics.note("simplify input: " + std::to_string(dropped) +
                         " faces with repeated positions dropped (zero area)");
    return kept_faces;
}

LODBAKE_STEP Status EdgeCollapser::linkTwins(const LargeArray<uint32_t>& start) {
    const uint32_t point_count = uint32_t(position_.size());
    const uint32_t he_count = uint32_t(he_.size());
    // Each point's outgoing half-edges in half-edge order, with their end points: the twin
    // search below then reads two short runs of this array instead of one corner of he_ per
    // candidate (a random access each).
    struct Outgoing {
        uint32_t he;
        uint32_t to;
    };
    LargeArray<Outgoing> list(he_count);
    {
        LargeArray<uint32_t> fill(start.begin(), start.end() - 1);
        for (uint32_t h = 0; h < he_count; ++h) list[fill[he_[h].point]++] = {h, he_[nextHe(h)].point};
    }
    // Each half-edge finds its own twin (the pairing is symmetric: a->b once and b->a once), in
    // parallel over fixed chunks; the points to lock are collected per chunk.
    std::vector<std::vector<uint32_t>> lock_points(chunkCount(he_count, kInitChunk));
    LODBAKE_RETURN_IF_ERROR(forChunks(he_count, [&](size_t chunk, uint32_t first, uint32_t last) {
        for (uint32_t h = first; h < last; ++h) {
            const uint32_t a = he_[h].point, b = he_[nextHe(h)].point;
            uint32_t same = 0, reverse = 0, match = kNone;
            for (uint32_t i = start[a]; i < start[a + 1]; ++i) same += list[i].to == b;
            for (uint32_t i = start[b]; i < start[b + 1]; ++i)
                if (list[i].to == a) {
                    ++reverse;
                    match = list[i].he;
                }
            if (same == 1 && reverse == 1) {
                he_[h].twin = match;
            } else if (same + reverse > 1) {
                lock_points[chunk].push_back(a);
                lock_points[chunk].push_back(b);
            }
        }
    }));
    for (const std::vector<uint32_t>& points : lock_points)
        for (uint32_t point : points) kind_[point] = kLocked;
    std::vector<std::vector<uint32_t>>().swap(lock_points);
    point_he_.assign(point_count, kNone);
    for (uint32_t p = 0; p < point_count; ++p)
        if (start[p] < start[p + 1]) point_he_[p] = list[start[p]].he;
    LargeArray<Outgoing>().swap(list);
    return Status::okStatus();
}

LODBAKE_STEP Status EdgeCollapser::classifyPoints(const LargeArray<uint32_t>& start, Diagnostics& diagnostics) {
    const uint32_t point_count = uint32_t(position_.size());
    // A point whose faces form more than one fan (a bow-tie) is non-manifold: lock it. Any
    // other point gets its kind from the same fan (classifyFan reads only the corner table, the
    // wedges, the groups and the options, all final here).
    std::vector<size_t> locked_in_chunk(chunkCount(point_count, kInitChunk), 0);
    LODBAKE_RETURN_IF_ERROR(forChunks(point_count, [&](size_t chunk, uint32_t first, uint32_t last) {
        std::vector<uint32_t> fan;
        for (uint32_t p = first; p < last; ++p) {
            if (point_he_[p] == kNone) {
                kind_[p] = kDead;
                continue;
            }
            if (kind_[p] != kLocked) {
                const bool closed = gatherFan(p, fan);
                kind_[p] = fan.size() != start[p + 1] - start[p] ? kLocked : classifyFan(fan, closed);
            }
            if (kind_[p] == kLocked) ++locked_in_chunk[chunk];
        }
    }));
    size_t locked = 0;
    for (size_t n : locked_in_chunk) locked += n;
    if (locked > 0)
        diagnostics.note("simplify input: " + std::to_string(locked) +
                         " points on non-manifold or inconsistently oriented edges/fans are kept unchanged");
    return Status::okStatus();
}

LODBAKE_STEP Status EdgeCollapser::accumulateQuadrics(const std::vector<uint8_t>& covered_border) {
    const uint32_t face_count = uint32_t(he_.size() / 3);
    constexpr uint32_t kBatch = 2 * kInitChunk;
    struct FaceQuadrics {
        Quadric face;
        Quadric constraint[3];
        uint8_t has_constraint[3];
    };
    // Sized by the mesh when it is below a batch: the cluster LOD builder simplifies thousands of
    // small groups, and a full batch per call is megabytes of zeroing each time.
    std::vector<FaceQuadrics> batch(std::min(kBatch, face_count));
    for (uint32_t base = 0; base < face_count; base += kBatch) {
        const uint32_t count = std::min(kBatch, face_count - base);
        LODBAKE_RETURN_IF_ERROR(forChunks(count, [&](size_t, uint32_t first, uint32_t last) {
            for (uint32_t i = first; i < last; ++i) {
                const uint32_t f = base + i;
                FaceQuadrics& out = batch[i];
                const Vec3d p0 = toD(position_[he_[f * 3].point]);
                const Vec3d p1 = toD(position_[he_[f * 3 + 1].point]);
                const Vec3d p2 = toD(position_[he_[f * 3 + 2].point]);
                out.face = Quadric::fromTriangle(p0, p1, p2);
                const Vec3d n = normalize(cross(p1 - p0, p2 - p0));
                for (uint32_t k = 0; k < 3; ++k) {
                    out.has_constraint[k] = 0;
                    const uint32_t h = f * 3 + k;
                    if (!isFeature(h) || (he_[h].twin != kNone && he_[h].twin < h)) continue;
                    const Vec3d a = toD(position_[he_[h].point]);
                    const Vec3d b = toD(position_[he_[nextHe(h)].point]);
                    const Vec3d e = b - a;
                    const Vec3d m = normalize(cross(e, n));
                    if (!(length2(m) > 0.0)) continue;
                    double weight = double(options_.border_weight) * length2(e);
                    if (!covered_border.empty() && covered_border[h]) weight *= kCoveredBorderFactor;
                    out.constraint[k] = Quadric::fromPlane(m, -dot(m, a), weight);
                    out.constraint[k].weight = 0; // constraints steer placement; they are not surface area
                    out.has_constraint[k] = 1;
                }
            }
        }));
        for (uint32_t i = 0; i < count; ++i) {
            const uint32_t f = base + i;
            const FaceQuadrics& in = batch[i];
            for (uint32_t k = 0; k < 3; ++k) quadric_[he_[f * 3 + k].point] += in.face;
            for (uint32_t k = 0; k < 3; ++k) {
                if (!in.has_constraint[k]) continue;
                const uint32_t h = f * 3 + k;
                quadric_[he_[h].point] += in.constraint[k];
                quadric_[he_[nextHe(h)].point] += in.constraint[k];
            }
        }
    }
    return Status::okStatus();
}

LODBAKE_STEP Status EdgeCollapser::accumulateAttributeBlocks() {
    const uint32_t face_count = uint32_t(he_.size() / 3);
    // Each face's attribute block is computed in parallel (fixed chunks of a batch of faces, into
    // a small buffer) and added to its wedges in face order: the same sums as a serial loop.
    constexpr uint32_t kBatch = 2 * kInitChunk;
    std::vector<double> face_blocks(size_t(std::min(kBatch, face_count)) * block_size_);
    for (uint32_t base = 0; base < face_count; base += kBatch) {
        const uint32_t count = std::min(kBatch, face_count - base);
        LODBAKE_RETURN_IF_ERROR(forChunks(count, [&](size_t, uint32_t first, uint32_t last) {
            for (uint32_t i = first; i < last; ++i) {
                const uint32_t f = base + i;
                const Vec3d p0 = toD(position_[he_[f * 3].point]);
                const Vec3d p1 = toD(position_[he_[f * 3 + 1].point]);
                const Vec3d p2 = toD(position_[he_[f * 3 + 2].point]);
                const size_t w0 = size_t(corner_wedge_[f * 3]) * channel_count_;
                const size_t w1 = size_t(corner_wedge_[f * 3 + 1]) * channel_count_;
                const size_t w2 = size_t(corner_wedge_[f * 3 + 2]) * channel_count_;
                double* face_block = &face_blocks[size_t(i) * block_size_];
                std::fill(face_block, face_block + block_size_, 0.0);
                addTriangleToAttributeBlock(face_block, channel_count_, p0, p1, p2, &wedge_value_[w0],
                                            &wedge_value_[w1], &wedge_value_[w2], channel_weight_.data());
            }
        }));
        for (uint32_t i = 0; i < count; ++i) {
            const uint32_t f = base + i;
            const double* face_block = &face_blocks[size_t(i) * block_size_];
            for (uint32_t k = 0; k < 3; ++k) {
                double* block = &wedge_block_[size_t(corner_wedge_[f * 3 + k]) * block_size_];
                for (size_t j = 0; j < block_size_; ++j) block[j] += face_block[j];
            }
        }
    }
    return Status::okStatus();
}

LODBAKE_STEP void EdgeCollapser::buildUvCharts(const Mesh& mesh) {
    const uint32_t face_count = uint32_t(he_.size() / 3);
    const uint32_t he_count = uint32_t(he_.size());
    // UV charts: faces joined across edges whose two corners share wedges (union-find).
    uv_set_count_ = uint32_t(mesh.uvs.size());
    uv_channel_ = uv_set_count_ > 0 ? (mesh.hasNormals() ? 3u : 0u) : kNone;
    face_chart_.clear();
    chart_alive_.clear();
    chart_count_ = 0;
    dropped_charts_ = 0;
    if (uv_channel_ != kNone) {
        face_chart_.resize(face_count);
        for (uint32_t f = 0; f < face_count; ++f) face_chart_[f] = f;
        auto root = [&](uint32_t x) {
            while (face_chart_[x] != x) x = face_chart_[x] = face_chart_[face_chart_[x]];
            return x;
        };
        for (uint32_t h = 0; h < he_count; ++h) {
            const uint32_t t = he_[h].twin;
            if (t == kNone || t < h || isFeature(h)) continue;
            const uint32_t a = root(h / 3), b = root(t / 3);
            if (a != b) face_chart_[std::max(a, b)] = std::min(a, b);
        }
        chart_alive_.assign(face_count, 0);
        for (uint32_t f = 0; f < face_count; ++f) {
            face_chart_[f] = root(f);
            chart_count_ += chart_alive_[face_chart_[f]]++ == 0;
        }
    }
}

LODBAKE_STEP Status EdgeCollapser::queueInitialKeys() {
    const uint32_t he_count = uint32_t(he_.size());
    // Room for every canonical half-edge (half the interior ones plus the open ones): the queue never
    // holds more, and growing it by doubling would copy it and keep up to twice the memory.
    {
        size_t canonical_count = 0;
        for (uint32_t h = 0; h < he_count; ++h) canonical_count += canonical(h) == h;
        queue_.reserve(canonical_count);
    }
    // Initial keys: evaluated in parallel over fixed chunks of a batch into a small buffer, pushed in
    // half-edge order (the heap's content and so its layout are those of a serial build).
    {
        constexpr uint32_t kBatch = 64 * kInitChunk;
        std::vector<float> batch_cost(std::min(kBatch, he_count));
        std::vector<uint8_t> batch_valid(std::min(kBatch, he_count));
        for (uint32_t base = 0; base < he_count; base += kBatch) {
            const uint32_t count = std::min(kBatch, he_count - base);
            LODBAKE_RETURN_IF_ERROR(forChunks(count, [&](size_t, uint32_t first, uint32_t last) {
                Candidate c;
                for (uint32_t i = first; i < last; ++i) {
                    const uint32_t h = base + i;
                    batch_valid[i] = canonical(h) == h && evaluate(h, c);
                    batch_cost[i] = batch_valid[i] ? float(c.cost) : 0.0f;
                }
            }));
            for (uint32_t i = 0; i < count; ++i)
                if (batch_valid[i]) queue_.pushUnordered(base + i, batch_cost[i]);
        }
    }
    queue_.heapify();
    return Status::okStatus();
}

Status EdgeCollapser::init(const Mesh& mesh, const SimplifyOptions& options, Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkSimplifyInput(mesh, options));
    source_ = &mesh;
    options_ = options;
    cos_max_normal_change_ = std::cos(std::min(double(options.max_normal_change_deg), 180.0) * kPi / 180.0);

    // Attribute channels: normal xyz, each UV set, colour rgba.
    channel_count_ = (mesh.hasNormals() ? 3 : 0) + 2 * uint32_t(mesh.uvs.size()) + (mesh.hasColors() ? 4 : 0);
    const Aabb box = computeBounds(mesh);
    const double diagonal = box.isEmpty() ? 1.0 : std::max(box.diagonal(), 1e-30);
    channel_weight_.clear();
    const AttributeWeights& aw = options.attribute_weights;
    if (mesh.hasNormals())
        for (int k = 0; k < 3; ++k) channel_weight_.push_back(float(aw.normal * aw.normal * diagonal * diagonal));
    for (size_t s = 0; s < mesh.uvs.size(); ++s)
        for (int k = 0; k < 2; ++k) channel_weight_.push_back(float(aw.uv * aw.uv * diagonal * diagonal));
    if (mesh.hasColors())
        for (int k = 0; k < 4; ++k) channel_weight_.push_back(float(aw.color * aw.color * diagonal * diagonal));
    const bool has_wedges = channel_count_ > 0 || mesh.hasTangents();

    InputMap map{mesh, has_wedges, {}, {}};
    weldPoints(map);
    renumberPointsByFirstUse(map);
    const uint32_t point_count = uint32_t(position_.size());
    const uint32_t wedge_count = uint32_t(wedge_vertex_.size());
    // The attribute values and blocks, the point quadrics, far_ and the queue's slots are large
    // arrays (sized by the mesh) that mostly land on fresh pages, whose first
    // touch costs far more than the filling. Background tasks allocate and fill them while this
    // thread builds the faces, twins and point kinds. The quadrics and the queue start once the
    // twins' corner lists are freed: the memory in use then stays below that at the end of init.
    BackgroundTasks fill_attributes, fill_quadrics, fill_queue;
    block_size_ = channel_count_ > 0 ? attributeBlockSize(channel_count_) : 0;
    fill_attributes.run([&, wedge_count] {
        wedge_value_.assign(size_t(wedge_count) * channel_count_, 0.0f);
        for (uint32_t w = 0; w < wedge_count; ++w)
            for (uint32_t ch = 0; ch < channel_count_; ++ch)
                wedge_value_[size_t(w) * channel_count_ + ch] = channelValue(mesh, wedge_vertex_[w], ch);
        wedge_block_.assign(size_t(wedge_count) * block_size_, 0.0);
    });

    const uint32_t face_count = buildFaces(map, diagnostics);
    const uint32_t he_count = face_count * 3;
    initial_faces_ = face_count;
    alive_faces_ = face_count;
    collapses_ = 0;
    max_error_done_ = 0;

    // Twins: pair a->b with b->a when each occurs exactly once; otherwise lock both points.
    kind_.assign(point_count, kFree);
    {
        LargeArray<uint32_t> start(size_t(point_count) + 1, 0);
        for (uint32_t h = 0; h < he_count; ++h) ++start[he_[h].point + 1];
        for (uint32_t p = 0; p < point_count; ++p) start[p + 1] += start[p];
        LODBAKE_RETURN_IF_ERROR(linkTwins(start));
        fill_quadrics.run([this, point_count, penalty = options.tip_distance_weight > 0] {
            quadric_.assign(point_count, Quadric());
            // Late stage (see run()): the penalty also measures each point's far input point, so far_
            // is kept from the start.
            if (penalty)
                far_ = position_;
            else
                LargeArray<Vec3f>().swap(far_);
        });
        fill_queue.run([this, he_count] { queue_ = CollapseQueue(he_count); });
        LODBAKE_RETURN_IF_ERROR(classifyPoints(start, diagnostics));
    }

    // remove_covered_components: a scan's open border lying on another component (merged
    // overlapping scans) is not a border of the object; its constraint planes weigh less.
    remove_components_ = options.remove_covered_components && options.placement == CollapsePlacement::Optimal;
    std::vector<uint8_t> covered_border;
    if (remove_components_) markCoveredBorders(covered_border);
    // Quadrics: area-weighted face planes plus constraint planes along feature edges.
    // Each face's quadric and its feature edges' constraint quadrics are computed in parallel (fixed
    // chunks of a batch of faces, into a small buffer) and added to the points in face order: the
    // same sums as a serial loop.
    LODBAKE_RETURN_IF_ERROR(fill_quadrics.wait());
    LODBAKE_RETURN_IF_ERROR(accumulateQuadrics(covered_border));
    LODBAKE_RETURN_IF_ERROR(fill_attributes.wait());
    if (channel_count_ > 0) LODBAKE_RETURN_IF_ERROR(accumulateAttributeBlocks());
    has_penalty_ = options.tip_distance_weight > 0;
    // A PFRep record is a vertex removal (KeepEndpoint): no component removals there (above).
    next_component_check_ = size_t(double(face_count) * kComponentCheckStep);
    removals_ = 0;
    removed_faces_ = 0;
    // Late stage (see run()); far_ is filled above. The quadric weights sum to three times the
    // surface area whatever collapses.
    late_ = false;
    late_faces_ = size_t(kLateFraction * double(initial_faces_));
    total_weight_ = 0;
    for (const Quadric& q : quadric_) total_weight_ += q.weight;
    buildUvCharts(mesh);
    LODBAKE_RETURN_IF_ERROR(fill_queue.wait());
    return queueInitialKeys();
}

void EdgeCollapser::describe(CollapseSequence& sequence) {
    sequence.point_triangles.clear();
    sequence.created_triangles.clear();
    sequence.created_end.clear();
    face_triangle_.clear();
    triangle_count_ = 0;
    if (options_.placement == CollapsePlacement::KeepEndpoint && !remove_components_) {
        const uint32_t face_count = uint32_t(he_.size() / 3);
        sequence.point_triangles.resize(he_.size());
        face_triangle_.resize(face_count);
        for (uint32_t h = 0; h < uint32_t(he_.size()); ++h) sequence.point_triangles[h] = he_[h].point;
        for (uint32_t f = 0; f < face_count; ++f) face_triangle_[f] = f;
        triangle_count_ = face_count;
    }
    sequence.point_positions.assign(position_.begin(), position_.end());
    sequence.wedge_point.assign(wedge_point_.begin(), wedge_point_.end());
    sequence.attribute_stride = channel_count_;
    sequence.records.clear();
    sequence.wedge_updates.clear();
    sequence.wedge_attributes.clear();
}

Mesh EdgeCollapser::extract() const {
    const Mesh& src = *source_;
    Mesh out;
    const size_t wedge_count = wedge_point_.size();
    std::vector<uint32_t> remap(wedge_count, kNone);
    std::vector<uint32_t> used;
    out.indices.reserve(alive_faces_ * 3);
    const size_t group_count = src.submeshes.size();
    out.submeshes = src.submeshes;
    for (size_t g = 0; g < std::max<size_t>(group_count, 1); ++g) {
        const uint32_t first = group_count ? group_first_face_[g] : 0;
        const uint32_t last = group_count ? group_first_face_[g + 1] : uint32_t(he_.size() / 3);
        const size_t first_index = out.indices.size();
        for (uint32_t f = first; f < last; ++f) {
            if (he_[f * 3].point == kNone) continue;
            for (uint32_t k = 0; k < 3; ++k) {
                const uint32_t w = wedgeAt(f * 3 + k);
                if (remap[w] == kNone) {
                    remap[w] = uint32_t(used.size());
                    used.push_back(w);
                }
                out.indices.push_back(remap[w]);
            }
        }
        if (group_count) {
            out.submeshes[g].first_index = uint32_t(first_index);
            out.submeshes[g].index_count = uint32_t(out.indices.size() - first_index);
        }
    }
    const size_t n = used.size();
    out.positions.resize(n);
    if (src.hasNormals()) out.normals.resize(n);
    if (src.hasTangents()) out.tangents.resize(n);
    out.uvs.assign(src.uvs.size(), std::vector<Vec2f>(n));
    if (src.hasColors()) out.colors.resize(n);
    for (size_t i = 0; i < n; ++i) {
        const uint32_t w = used[i];
        // Without attribute streams wedges are points.
        const uint32_t point = corner_wedge_.empty() ? w : wedge_point_[w];
        out.positions[i] = position_[point];
        const float* value = channel_count_ ? &wedge_value_[size_t(w) * channel_count_] : nullptr;
        uint32_t ch = 0;
        if (src.hasNormals()) {
            out.normals[i] = Vec3f(value[0], value[1], value[2]);
            ch = 3;
        }
        for (size_t s = 0; s < src.uvs.size(); ++s, ch += 2) out.uvs[s][i] = Vec2f(value[ch], value[ch + 1]);
        if (src.hasColors()) out.colors[i] = Vec4f(value[ch], value[ch + 1], value[ch + 2], value[ch + 3]);
        if (src.hasTangents()) out.tangents[i] = src.tangents[wedge_vertex_[w]];
    }
    out.materials = src.materials;
    out.textures = src.textures;
    return out;
}

} // namespace lodbake::detail
