#pragma once
// Quadric error metric (Garland & Heckbert 1997) and its attribute extension (Hoppe 1999 style,
// with the attribute values eliminated in closed form), in double precision.
//
// A Quadric measures Q(p) = pᵀ A p + 2 bᵀ p + c, a weighted sum of squared distances from p to a
// set of planes. `weight` is the summed weight of those planes (the face AREA for face planes),
// so Q(p) / weight is a mean squared distance in object units².

#include <cstddef>

#include "lodbake/core/math.h"

namespace lodbake {

struct Quadric {
    double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0; // symmetric A
    double b0 = 0, b1 = 0, b2 = 0;
    double c = 0;
    double weight = 0;

    /// The quadric of the plane n·p + d = 0 (n unit length) times `weight`.
    static Quadric fromPlane(const Vec3d& n, double d, double weight);
    /// Plane through p0,p1,p2 weighted by the triangle's area. Zero for a degenerate triangle.
    static Quadric fromTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2);

    Quadric& operator+=(const Quadric& o) { // inline: the collapse loop sums two per evaluated edge
        a00 += o.a00;
        a01 += o.a01;
        a02 += o.a02;
        a11 += o.a11;
        a12 += o.a12;
        a22 += o.a22;
        b0 += o.b0;
        b1 += o.b1;
        b2 += o.b2;
        c += o.c;
        weight += o.weight;
        return *this;
    }
    Quadric& operator*=(double s);
    /// Q(p); clamped at 0 (rounding can make it slightly negative).
    double evaluate(const Vec3d& p) const {
        const double x = p.x, y = p.y, z = p.z;
        const double r = a00 * x * x + a11 * y * y + a22 * z * z + 2.0 * (a01 * x * y + a02 * x * z + a12 * y * z) +
                         2.0 * (b0 * x + b1 * y + b2 * z) + c;
        return r > 0.0 ? r : 0.0;
    }
};

/// Solves A p = -b for the minimiser of q. Returns false, leaving `out` untouched, when A is
/// singular or ill-conditioned (smallest/largest eigenvalue ratio, estimated from the
/// determinant, below `min_condition`); callers then fall back to a line search or endpoints.
bool solveQuadric(const Quadric& q, Vec3d& out, double min_condition = 1e-7);

/// Minimiser of q on the segment [p0, p1] (exact for the 1-D quadratic, clamped to the segment).
Vec3d minimizeOnSegment(const Quadric& q, const Vec3d& p0, const Vec3d& p1);

/// The quadric of one scalar attribute channel s over a set of faces. Each face contributes the
/// linear field s(p) = g·p + d interpolating its three corner values (g lies in the face plane),
/// weighted by area. For a point p the best attribute value is s*(p) = (h·p + D) / A, and the
/// remaining error Σ a (s* − g·p − d)² is a quadric in p (toQuadric), so attributes take part in
/// the placement solve and are optimised, not snapped.
struct AttributeQuadric {
    double g00 = 0, g01 = 0, g02 = 0, g11 = 0, g12 = 0, g22 = 0; // Σ a g gᵀ
    double e0 = 0, e1 = 0, e2 = 0;                               // Σ a d g
    double h0 = 0, h1 = 0, h2 = 0;                               // Σ a g
    double dd = 0;                                               // Σ a d²
    double d = 0;                                                // Σ a d
    double area = 0;                                             // Σ a

    /// Adds the face (p0,p1,p2) with corner values s0,s1,s2, weighted by `weight` (area × channel weight²).
    void addTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, double s0, double s1, double s2, double weight);
    AttributeQuadric& operator+=(const AttributeQuadric& o);
    /// The optimal attribute value at p (the area-weighted mean of the face fields at p).
    double optimalValue(const Vec3d& p) const;
    /// Adds the post-elimination error quadric to `q` (its weight is left unchanged).
    void addTo(Quadric& q) const;
};

/// The attribute quadrics of `channel_count` channels over the same faces, packed into
/// attributeBlockSize(channel_count) doubles instead of 16 per channel. The error parts
/// (Σ w a g gᵀ, Σ w a d g, Σ w a d², w the channel weight) only ever enter the collapse cost summed
/// over the channels, so they are stored once, summed; per channel only what the optimal value
/// needs is kept (Σ a g, Σ a d, unweighted), plus the faces' area Σ a shared by all channels.
/// The result equals the sum of one AttributeQuadric per channel (up to rounding), except that a
/// channel of weight 0 still gets its area-weighted mean as optimal value.
/// Layout: [0..5] summed G (00 01 02 11 12 22), [6..8] summed e, [9] summed F, [10] area,
/// then per channel k: [11 + 4k .. 13 + 4k] h, [14 + 4k] D.
inline size_t attributeBlockSize(size_t channel_count) {
    return 11 + 4 * channel_count;
}
/// Adds the face (p0,p1,p2) with corner values s0[k], s1[k], s2[k] and channel weights weight[k].
void addTriangleToAttributeBlock(double* block, size_t channel_count, const Vec3d& p0, const Vec3d& p1,
                                 const Vec3d& p2, const float* s0, const float* s1, const float* s2,
                                 const float* weight);
/// The optimal value of `channel` at p for the block a, or for a + b when b is not null (the same
/// bits as adding b into a first).
double attributeBlockOptimalValue(const double* a, const double* b, size_t channel, const Vec3d& p);
/// Adds the post-elimination error quadric of a (or a + b when b is not null) to `q`.
void addAttributeBlockTo(const double* a, const double* b, size_t channel_count, const float* weight, Quadric& q);

} // namespace lodbake
