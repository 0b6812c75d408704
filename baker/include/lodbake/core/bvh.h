#pragma once
// A bounding-volume hierarchy over the triangles of an indexed mesh, for nearest-surface queries
// (surface distance, attribute transfer). It lives in core because nothing about it is specific to
// simplification: any module that asks "which triangle is closest to this point" uses it.
//
// Layout: flat arrays. Nodes are 32 bytes; an inner node's children are stored next to each other
// (left = first, right = first + 1); a leaf owns `count` consecutive triangles whose corner positions
// are copied in leaf order, so a leaf visit reads one contiguous block. Built single-threaded with a
// binned surface-area heuristic, so the tree is the same on every run for the same input.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "lodbake/core/index_types.h"
#include "lodbake/core/math.h"
#include "lodbake/core/status.h"

namespace lodbake {

struct TriangleBvhOptions {
    uint32_t max_leaf_triangles = 4; // a range this small becomes a leaf
    uint32_t bin_count = 16;         // SAH bins per axis (clamped to [2, 64])
};

/// Result of a nearest-triangle query.
struct ClosestHit {
    double distance_sq = std::numeric_limits<double>::infinity(); // squared distance to `point`
    FaceId face = FaceId::invalid();                              // triangle index in the input, invalid if none found
    Vec3d point;                                                  // closest point on that triangle
    bool isFound() const { return face.isValid(); }
};

/// Closest point to `p` on a triangle with no area (collinear or coincident corners): the nearest
/// point of its three edges. Out of line; closestPointOnTriangle calls it for such triangles.
Vec3d closestPointOnDegenerateTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Closest point to `p` on triangle (a, b, c), in double (Ericson, Real-Time Collision Detection,
/// §5.1.5). Degenerate triangles (collinear or coincident corners) are handled as their edges.
/// Inline: the surface-distance search calls it for every leaf triangle it visits.
inline Vec3d closestPointOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    const Vec3d ab = b - a, ac = c - a;
    const Vec3d n = cross(ab, ac);
    // The region tests below would divide by zero.
    if (!(dot(n, n) > 0.0)) return closestPointOnDegenerateTriangle(p, a, b, c);
    const Vec3d ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return a; // vertex region A

    const Vec3d bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return b; // vertex region B

    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3)); // edge AB

    const Vec3d cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return c; // vertex region C

    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6)); // edge AC

    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))); // edge BC
    const double denom = 1.0 / (va + vb + vc); // interior
    const double v = vb * denom, w = vc * denom;
    return a + ab * v + ac * w;
}

class TriangleBvh {
public:
    TriangleBvh() = default;

    /// Builds over every triangle of `indices` (3 per triangle) into `positions`.
    /// \pre indices.size() % 3 == 0 and every index < positions.size() (callers validate input first);
    ///      positions are finite.
    /// Fails only when resources run out (more than 2^31 triangles, or a failed allocation).
    /// The tree is identical for any thread count.
    static Result<TriangleBvh> build(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices,
                                     const TriangleBvhOptions& options = {});

    /// The triangle nearest to `p`. Only triangles strictly closer than sqrt(max_distance_sq) are
    /// considered; returns a hit with face invalid when there are none (or the tree is empty).
    /// Equal distances keep the first triangle found, so results are deterministic. Thread-safe.
    ClosestHit closest(const Vec3d& p, double max_distance_sq = std::numeric_limits<double>::infinity()) const;

    size_t triangleCount() const { return face_of_slot_.size(); }
    size_t nodeCount() const { return nodes_.size(); }
    bool isEmpty() const { return nodes_.empty(); }
    /// Longest root-to-leaf path (1 for a single leaf); the query stack is sized for kMaxDepth.
    uint32_t depth() const { return depth_; }

    static constexpr uint32_t kMaxDepth = 96;
    /// Ranges up to this many triangles (or 1/64 of the mesh, if larger) are built as parallel subtrees.
    static constexpr uint32_t kSubtreeTriangles = 4096;

private:
    struct Node {
        Vec3f bounds_min;
        uint32_t first = 0; // inner: index of the left child; leaf: first triangle slot
        Vec3f bounds_max;
        uint32_t count = 0; // 0 for an inner node; triangles in the leaf otherwise
    };

    struct Prim;      // build-time triangle record (bvh.cpp)
    struct BuildTask; // build-time range (bvh.cpp)
    static void boundsOf(const std::vector<Prim>& prims, BuildTask& task);
    static void buildRange(std::vector<Prim>& prims, const BuildTask& root, const TriangleBvhOptions& options,
                           std::vector<Node>& nodes, uint32_t& depth, uint32_t defer_count,
                           std::vector<BuildTask>* deferred);

    std::vector<Node> nodes_;
    std::vector<Vec3f> corners_;         // 3 per triangle slot, leaf order
    std::vector<uint32_t> face_of_slot_; // input triangle index of each slot
    uint32_t depth_ = 0;
};

} // namespace lodbake
