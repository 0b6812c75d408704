// Spatial splitting of triangles into clusters, and the bounding spheres of the cluster LOD builder.
// The split is a recursive median cut of the triangle centroids (a k-d tree built top down, as
// meshlet builders without connectivity do), which keeps each cluster compact in space and needs no
// adjacency; its leaves are about equally full because each cut divides the count in proportion to
// the number of clusters on each side.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "cluster/cluster_internal.h"

namespace lodbake::cluster_detail {

namespace {

struct Splitter {
    const std::vector<Vec3f>& points;
    const std::vector<uint32_t>& triangles;
    uint32_t max_triangles;
    uint32_t max_vertices;
    std::vector<Vec3f> centroid;
    std::vector<uint32_t> scratch;
    std::vector<std::vector<uint32_t>> out;

    uint32_t distinctPoints(const uint32_t* tris, size_t count) {
        scratch.clear();
        for (size_t i = 0; i < count; ++i)
            for (int k = 0; k < 3; ++k) scratch.push_back(triangles[size_t(tris[i]) * 3 + k]);
        std::sort(scratch.begin(), scratch.end());
        return uint32_t(std::unique(scratch.begin(), scratch.end()) - scratch.begin());
    }

    int longestAxis(const uint32_t* tris, size_t count) const {
        Vec3f lo(std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                 std::numeric_limits<float>::max());
        Vec3f hi = lo * -1.0f;
        for (size_t i = 0; i < count; ++i) {
            const Vec3f& c = centroid[tris[i]];
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], c[a]);
                hi[a] = std::max(hi[a], c[a]);
            }
        }
        int axis = 0;
        for (int a = 1; a < 3; ++a)
            if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
        return axis;
    }

    // Iterative (an explicit stack): a large mesh would otherwise recurse log2(n / 128) deep per
    // branch, which is fine, but the explicit order also fixes the output order (left before right).
    void run(std::vector<uint32_t>& tris) {
        struct Range {
            size_t first, count;
        };
        std::vector<Range> stack{{0, tris.size()}};
        while (!stack.empty()) {
            const Range r = stack.back();
            stack.pop_back();
            uint32_t* t = tris.data() + r.first;
            if (r.count <= max_triangles && distinctPoints(t, r.count) <= max_vertices) {
                out.emplace_back(t, t + r.count);
                continue;
            }
            const size_t parts = std::max<size_t>(2, (r.count + max_triangles - 1) / max_triangles);
            const size_t left = std::max<size_t>(1, r.count * ((parts + 1) / 2) / parts);
            const int axis = longestAxis(t, r.count);
            std::nth_element(t, t + left, t + r.count, [&](uint32_t a, uint32_t b) {
                const float ca = centroid[a][axis], cb = centroid[b][axis];
                return ca < cb || (ca == cb && a < b);
            });
            stack.push_back({r.first + left, r.count - left});
            stack.push_back({r.first, left});
        }
    }
};

float roundUp(double v) {
    float f = float(v);
    if (double(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

} // namespace

std::vector<std::vector<uint32_t>> splitIntoClusters(const std::vector<Vec3f>& points,
                                                     const std::vector<uint32_t>& triangles, uint32_t max_triangles,
                                                     uint32_t max_vertices) {
    Splitter s{points, triangles, max_triangles, max_vertices, {}, {}, {}};
    const size_t count = triangles.size() / 3;
    s.centroid.resize(count);
    for (size_t i = 0; i < count; ++i) {
        const Vec3f& a = points[triangles[i * 3]];
        const Vec3f& b = points[triangles[i * 3 + 1]];
        const Vec3f& c = points[triangles[i * 3 + 2]];
        s.centroid[i] = Vec3f((a.x + b.x + c.x) / 3.0f, (a.y + b.y + c.y) / 3.0f, (a.z + b.z + c.z) / 3.0f);
    }
    std::vector<uint32_t> order(count);
    std::iota(order.begin(), order.end(), 0u);
    if (count > 0) s.run(order);
    return std::move(s.out);
}

void boundingSphere(const Vec3f* points, const uint32_t* ids, size_t count, float center[3], float& radius) {
    Vec3d lo(std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
             std::numeric_limits<double>::max());
    Vec3d hi = lo * -1.0;
    for (size_t i = 0; i < count; ++i) {
        const Vec3d p = toDouble(points[ids ? ids[i] : i]);
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    }
    for (int a = 0; a < 3; ++a) center[a] = count ? float((lo[a] + hi[a]) * 0.5) : 0.0f;
    const Vec3d c(center[0], center[1], center[2]);
    double r = 0;
    for (size_t i = 0; i < count; ++i) r = std::max(r, length(toDouble(points[ids ? ids[i] : i]) - c));
    radius = roundUp(r);
}

void enclosingSphere(const std::vector<const float*>& centers, const std::vector<float>& radii, float center[3],
                     float& radius) {
    Vec3d lo(std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
             std::numeric_limits<double>::max());
    Vec3d hi = lo * -1.0;
    for (size_t i = 0; i < centers.size(); ++i)
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], double(centers[i][a]) - radii[i]);
            hi[a] = std::max(hi[a], double(centers[i][a]) + radii[i]);
        }
    for (int a = 0; a < 3; ++a) center[a] = centers.empty() ? 0.0f : float((lo[a] + hi[a]) * 0.5);
    const Vec3d c(center[0], center[1], center[2]);
    double r = 0, extent = 0;
    for (size_t i = 0; i < centers.size(); ++i) {
        const Vec3d ci(centers[i][0], centers[i][1], centers[i][2]);
        r = std::max(r, length(ci - c) + radii[i]);
        extent = std::max({extent, std::fabs(ci.x), std::fabs(ci.y), std::fabs(ci.z)});
    }
    // The margin covers the float rounding of |centre - eye| - radius in the runtime's test: a few
    // ulps of the coordinates' magnitude, and a relative part for the subtraction.
    radius = roundUp(r * (1.0 + 1e-5) + (extent + r) * 1e-6);
}

} // namespace lodbake::cluster_detail
