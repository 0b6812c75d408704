// Polygon triangulation for the text readers. Ear clipping after Meisters, "Polygons have ears"
// (American Mathematical Monthly, 1975), run in the polygon's Newell plane (Newell's method for the
// best-fit normal, as in Sutherland, Sproull and Schumacker 1974).

#include "io/polygon_triangulation.h"

#include <cmath>

namespace lodbake::detail {

namespace {

void appendFan(uint32_t n, std::vector<uint32_t>& out) {
    for (uint32_t i = 1; i + 1 < n; ++i) {
        out.push_back(0);
        out.push_back(i);
        out.push_back(i + 1);
    }
}

Vec3d newellNormal(const Vec3f* p, uint32_t n) {
    Vec3d normal;
    for (uint32_t i = 0; i < n; ++i) {
        const Vec3d a = toDouble(p[i]);
        const Vec3d b = toDouble(p[(i + 1) % n]);
        normal.x += (a.y - b.y) * (a.z + b.z);
        normal.y += (a.z - b.z) * (a.x + b.x);
        normal.z += (a.x - b.x) * (a.y + b.y);
    }
    return normal;
}

struct P2 {
    double x, y;
};

double cross2(const P2& o, const P2& a, const P2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

// Strictly inside or on the boundary of the counter-clockwise triangle abc.
bool inTriangle(const P2& p, const P2& a, const P2& b, const P2& c) {
    return cross2(a, b, p) >= 0.0 && cross2(b, c, p) >= 0.0 && cross2(c, a, p) >= 0.0;
}

} // namespace

bool triangulatePolygon(const Vec3f* corners, uint32_t n, std::vector<uint32_t>& out) {
    if (n < 3) return false;
    if (n == 3) {
        out.insert(out.end(), {0u, 1u, 2u});
        return true;
    }
    const Vec3d normal = newellNormal(corners, n);
    const double normal_len = length(normal);
    if (!(normal_len > 0.0) || !std::isfinite(normal_len)) {
        appendFan(n, out);
        return false;
    }
    if (n == 4) {
        const Vec3d p[4] = {toDouble(corners[0]), toDouble(corners[1]), toDouble(corners[2]), toDouble(corners[3])};
        // A split is valid when both triangles face the same way as the quad (false for the diagonal
        // outside a concave quad).
        auto faces_forward = [&](int a, int b, int c) { return dot(cross(p[b] - p[a], p[c] - p[a]), normal) > 0.0; };
        const bool split02_ok = faces_forward(0, 1, 2) && faces_forward(0, 2, 3);
        const bool split13_ok = faces_forward(1, 2, 3) && faces_forward(1, 3, 0);
        const double d02 = dot(p[2] - p[0], p[2] - p[0]);
        const double d13 = dot(p[3] - p[1], p[3] - p[1]);
        const bool use02 = split02_ok && (!split13_ok || d02 <= d13);
        if (use02 || !split13_ok) {
            out.insert(out.end(), {0u, 1u, 2u, 0u, 2u, 3u});
        } else {
            out.insert(out.end(), {1u, 2u, 3u, 1u, 3u, 0u});
        }
        return split02_ok || split13_ok;
    }

    // Project onto the plane through the two axes most perpendicular to the normal, mirrored so the
    // polygon is counter-clockwise in 2D.
    const double ax = std::fabs(normal.x), ay = std::fabs(normal.y), az = std::fabs(normal.z);
    int u_axis = 0, v_axis = 1;
    double sign = normal.z;
    if (ax >= ay && ax >= az) {
        u_axis = 1, v_axis = 2, sign = normal.x;
    } else if (ay >= az) {
        u_axis = 2, v_axis = 0, sign = normal.y;
    }
    std::vector<P2> pts(n);
    for (uint32_t i = 0; i < n; ++i) {
        pts[i] = {double(corners[i][u_axis]), double(corners[i][v_axis])};
        if (sign < 0.0) pts[i].x = -pts[i].x;
    }

    std::vector<uint32_t> prev(n), next(n);
    for (uint32_t i = 0; i < n; ++i) {
        prev[i] = (i + n - 1) % n;
        next[i] = (i + 1) % n;
    }
    const size_t first_out = out.size();
    uint32_t remaining = n;
    uint32_t cur = 0;
    uint32_t since_last_ear = 0;
    while (remaining > 3) {
        const uint32_t a = prev[cur], b = cur, c = next[cur];
        bool is_ear = cross2(pts[a], pts[b], pts[c]) > 0.0;
        if (is_ear) {
            for (uint32_t k = next[c]; k != a; k = next[k]) {
                // Only reflex or collinear vertices can lie inside a candidate ear; skip corners that
                // coincide with the ear's own corners (repeated positions in the file).
                if (cross2(pts[prev[k]], pts[k], pts[next[k]]) > 0.0) continue;
                const P2& q = pts[k];
                const bool same_as_corner = (q.x == pts[a].x && q.y == pts[a].y) ||
                                            (q.x == pts[b].x && q.y == pts[b].y) ||
                                            (q.x == pts[c].x && q.y == pts[c].y);
                if (!same_as_corner && inTriangle(q, pts[a], pts[b], pts[c])) {
                    is_ear = false;
                    break;
                }
            }
        }
        if (is_ear) {
            out.insert(out.end(), {a, b, c});
            next[a] = c;
            prev[c] = a;
            --remaining;
            cur = c;
            since_last_ear = 0;
        } else {
            cur = next[cur];
            if (++since_last_ear > remaining) {
                // No ear left: the polygon self-intersects. Fan the rest so no face is lost.
                out.resize(first_out);
                appendFan(n, out);
                return false;
            }
        }
    }
    out.insert(out.end(), {prev[cur], cur, next[cur]});
    return true;
}

} // namespace lodbake::detail
