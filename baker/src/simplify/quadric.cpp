// Quadric error metric: M. Garland, P. Heckbert, "Surface Simplification Using Quadric Error
// Metrics", SIGGRAPH 1997 (face quadrics, area weighting, optimal placement). Attribute quadrics:
// H. Hoppe, "New Quadric Metric for Simplifying Meshes with Appearance Attributes", IEEE Vis 1999
// (per-face linear attribute fields); here the attribute unknowns are eliminated in closed form.
#include "lodbake/simplify/quadric.h"

#include <algorithm>
#include <cmath>

namespace lodbake {

Quadric Quadric::fromPlane(const Vec3d& n, double d, double weight) {
    Quadric q;
    q.a00 = weight * n.x * n.x;
    q.a01 = weight * n.x * n.y;
    q.a02 = weight * n.x * n.z;
    q.a11 = weight * n.y * n.y;
    q.a12 = weight * n.y * n.z;
    q.a22 = weight * n.z * n.z;
    q.b0 = weight * d * n.x;
    q.b1 = weight * d * n.y;
    q.b2 = weight * d * n.z;
    q.c = weight * d * d;
    q.weight = weight;
    return q;
}

Quadric Quadric::fromTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2) {
    const Vec3d n = cross(p1 - p0, p2 - p0);
    const double len = length(n);
    if (!(len > 0.0)) return Quadric();
    const Vec3d unit = n / len;
    return fromPlane(unit, -dot(unit, p0), 0.5 * len);
}

Quadric& Quadric::operator*=(double s) {
    a00 *= s;
    a01 *= s;
    a02 *= s;
    a11 *= s;
    a12 *= s;
    a22 *= s;
    b0 *= s;
    b1 *= s;
    b2 *= s;
    c *= s;
    weight *= s;
    return *this;
}

bool solveQuadric(const Quadric& q, Vec3d& out, double min_condition) {
    // Cofactors of the symmetric matrix A.
    const double c00 = q.a11 * q.a22 - q.a12 * q.a12;
    const double c01 = q.a02 * q.a12 - q.a01 * q.a22;
    const double c02 = q.a01 * q.a12 - q.a02 * q.a11;
    const double det = q.a00 * c00 + q.a01 * c01 + q.a02 * c02;
    const double trace = q.a00 + q.a11 + q.a22;
    if (!(trace > 0.0)) return false;
    // A is positive semi-definite, so det / (trace/3)³ ≤ 1 and it is small exactly when the
    // smallest eigenvalue is small against the others: a cheap conditioning test.
    const double s = trace / 3.0;
    if (!(det > min_condition * s * s * s)) return false;
    const double c11 = q.a00 * q.a22 - q.a02 * q.a02;
    const double c12 = q.a01 * q.a02 - q.a00 * q.a12;
    const double c22 = q.a00 * q.a11 - q.a01 * q.a01;
    const double inv = 1.0 / det;
    const Vec3d p(-(c00 * q.b0 + c01 * q.b1 + c02 * q.b2) * inv, -(c01 * q.b0 + c11 * q.b1 + c12 * q.b2) * inv,
                  -(c02 * q.b0 + c12 * q.b1 + c22 * q.b2) * inv);
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return false;
    out = p;
    return true;
}

Vec3d minimizeOnSegment(const Quadric& q, const Vec3d& p0, const Vec3d& p1) {
    // Q(p0 + t d) = Q(p0) + 2 t (A p0 + b)·d + t² dᵀ A d.
    const Vec3d d = p1 - p0;
    const Vec3d ap(q.a00 * p0.x + q.a01 * p0.y + q.a02 * p0.z + q.b0, q.a01 * p0.x + q.a11 * p0.y + q.a12 * p0.z + q.b1,
                   q.a02 * p0.x + q.a12 * p0.y + q.a22 * p0.z + q.b2);
    const Vec3d ad(q.a00 * d.x + q.a01 * d.y + q.a02 * d.z, q.a01 * d.x + q.a11 * d.y + q.a12 * d.z,
                   q.a02 * d.x + q.a12 * d.y + q.a22 * d.z);
    const double curvature = dot(d, ad);
    double t = 0.5;
    if (curvature > 0.0) t = std::clamp(-dot(ap, d) / curvature, 0.0, 1.0);
    return p0 + d * t;
}

void AttributeQuadric::addTriangle(const Vec3d& p0, const Vec3d& p1, const Vec3d& p2, double s0, double s1, double s2,
                                   double weight) {
    const Vec3d edge1 = p1 - p0;
    const Vec3d edge2 = p2 - p0;
    const Vec3d n = cross(edge1, edge2);
    const double n2 = dot(n, n);
    if (!(n2 > 0.0)) return;
    // The gradient lies in the face plane and reproduces the value differences along both edges:
    // g = (Δs1 (e2 × n) + Δs2 (n × e1)) / |n|².
    const Vec3d g = (cross(edge2, n) * (s1 - s0) + cross(n, edge1) * (s2 - s0)) / n2;
    const double dv = s0 - dot(g, p0);
    const double a = 0.5 * std::sqrt(n2) * weight;
    g00 += a * g.x * g.x;
    g01 += a * g.x * g.y;
    g02 += a * g.x * g.z;
    g11 += a * g.y * g.y;
    g12 += a * g.y * g.z;
    g22 += a * g.z * g.z;
    e0 += a * dv * g.x;
    e1 += a * dv * g.y;
    e2 += a * dv * g.z;
    h0 += a * g.x;
    h1 += a * g.y;
    h2 += a * g.z;
    dd += a * dv * dv;
    d += a * dv;
    area += a;
}

AttributeQuadric& AttributeQuadric::operator+=(const AttributeQuadric& o) {
    g00 += o.g00;
    g01 += o.g01;
    g02 += o.g02;
    g11 += o.g11;
    g12 += o.g12;
    g22 += o.g22;
    e0 += o.e0;
    e1 += o.e1;
    e2 += o.e2;
    h0 += o.h0;
    h1 += o.h1;
    h2 += o.h2;
    dd += o.dd;
    d += o.d;
    area += o.area;
    return *this;
}

double AttributeQuadric::optimalValue(const Vec3d& p) const {
    if (!(area > 0.0)) return 0.0;
    return (h0 * p.x + h1 * p.y + h2 * p.z + d) / area;
}

void AttributeQuadric::addTo(Quadric& q) const {
    if (!(area > 0.0)) return;
    // E(p) = pᵀ(G − h hᵀ/A) p + 2 (e − D h / A)·p + (F − D²/A).
    const double inv = 1.0 / area;
    q.a00 += g00 - h0 * h0 * inv;
    q.a01 += g01 - h0 * h1 * inv;
    q.a02 += g02 - h0 * h2 * inv;
    q.a11 += g11 - h1 * h1 * inv;
    q.a12 += g12 - h1 * h2 * inv;
    q.a22 += g22 - h2 * h2 * inv;
    q.b0 += e0 - d * h0 * inv;
    q.b1 += e1 - d * h1 * inv;
    q.b2 += e2 - d * h2 * inv;
    q.c += dd - d * d * inv;
}

void addTriangleToAttributeBlock(double* block, size_t channel_count, const Vec3d& p0, const Vec3d& p1,
                                 const Vec3d& p2, const float* s0, const float* s1, const float* s2,
                                 const float* weight) {
    const Vec3d edge1 = p1 - p0;
    const Vec3d edge2 = p2 - p0;
    const Vec3d n = cross(edge1, edge2);
    const double n2 = dot(n, n);
    if (!(n2 > 0.0)) return;
    const Vec3d grad1 = cross(edge2, n), grad2 = cross(n, edge1);
    const double a = 0.5 * std::sqrt(n2);
    for (size_t k = 0; k < channel_count; ++k) {
        // As AttributeQuadric::addTriangle: the face's linear field g·p + dv.
        const Vec3d g = (grad1 * (double(s1[k]) - double(s0[k])) + grad2 * (double(s2[k]) - double(s0[k]))) / n2;
        const double dv = double(s0[k]) - dot(g, p0);
        const double aw = a * double(weight[k]);
        block[0] += aw * g.x * g.x;
        block[1] += aw * g.x * g.y;
        block[2] += aw * g.x * g.z;
        block[3] += aw * g.y * g.y;
        block[4] += aw * g.y * g.z;
        block[5] += aw * g.z * g.z;
        block[6] += aw * dv * g.x;
        block[7] += aw * dv * g.y;
        block[8] += aw * dv * g.z;
        block[9] += aw * dv * dv;
        double* c = block + 11 + 4 * k;
        c[0] += a * g.x;
        c[1] += a * g.y;
        c[2] += a * g.z;
        c[3] += a * dv;
    }
    block[10] += a;
}

double attributeBlockOptimalValue(const double* a, const double* b, size_t channel, const Vec3d& p) {
    const double* ca = a + 11 + 4 * channel;
    double area = a[10], h0 = ca[0], h1 = ca[1], h2 = ca[2], d = ca[3];
    if (b) {
        const double* cb = b + 11 + 4 * channel;
        area += b[10];
        h0 += cb[0];
        h1 += cb[1];
        h2 += cb[2];
        d += cb[3];
    }
    if (!(area > 0.0)) return 0.0;
    return (h0 * p.x + h1 * p.y + h2 * p.z + d) / area;
}

void addAttributeBlockTo(const double* a, const double* b, size_t channel_count, const float* weight, Quadric& q) {
    const double area = b ? a[10] + b[10] : a[10];
    if (!(area > 0.0)) return;
    double sum[10];
    for (int i = 0; i < 10; ++i) sum[i] = b ? a[i] + b[i] : a[i];
    // Per channel E(p) = pᵀ(G − w h hᵀ/A) p + 2 (e − w D h / A)·p + (F − w D²/A); the G, e, F
    // parts are already summed.
    for (size_t k = 0; k < channel_count; ++k) {
        const double* ca = a + 11 + 4 * k;
        double h0 = ca[0], h1 = ca[1], h2 = ca[2], d = ca[3];
        if (b) {
            const double* cb = b + 11 + 4 * k;
            h0 += cb[0];
            h1 += cb[1];
            h2 += cb[2];
            d += cb[3];
        }
        const double inv = double(weight[k]) / area;
        sum[0] -= h0 * h0 * inv;
        sum[1] -= h0 * h1 * inv;
        sum[2] -= h0 * h2 * inv;
        sum[3] -= h1 * h1 * inv;
        sum[4] -= h1 * h2 * inv;
        sum[5] -= h2 * h2 * inv;
        sum[6] -= d * h0 * inv;
        sum[7] -= d * h1 * inv;
        sum[8] -= d * h2 * inv;
        sum[9] -= d * d * inv;
    }
    q.a00 += sum[0];
    q.a01 += sum[1];
    q.a02 += sum[2];
    q.a11 += sum[3];
    q.a12 += sum[4];
    q.a22 += sum[5];
    q.b0 += sum[6];
    q.b1 += sum[7];
    q.b2 += sum[8];
    q.c += sum[9];
}

} // namespace lodbake
