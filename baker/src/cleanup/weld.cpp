// Vertex welding: exact (bit-identical positions, by sorting) or within a tolerance relative to the
// bounding-box diagonal (uniform grid hash with cells of the tolerance size, 27-cell lookup).
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters WeldReport::counters() const {
    return {{"vertices_before", vertices_before},
            {"vertices_merged", vertices_merged},
            {"seam_pairs_kept", seam_pairs_kept},
            {"vertices_after", vertices_after}};
}

namespace {

bool attributesMatch(const Mesh& m, uint32_t a, uint32_t b, const WeldOptions& o) {
    if (!o.respect_attributes) return true;
    for (const auto& uv : m.uvs)
        if (std::fabs(uv[a].x - uv[b].x) > o.uv_tolerance || std::fabs(uv[a].y - uv[b].y) > o.uv_tolerance)
            return false;
    if (m.hasNormals()) {
        const Vec3d na = normalize(toDouble(m.normals[a])), nb = normalize(toDouble(m.normals[b]));
        const double cos_limit = std::cos(double(o.normal_angle_deg) * M_PI / 180.0);
        if (dot(na, nb) < cos_limit) return false;
    }
    return true;
}

} // namespace

WeldReport weldVertices(Mesh& mesh, const WeldOptions& options) {
    WeldReport r;
    const uint32_t n = uint32_t(mesh.vertexCount());
    r.vertices_before = r.vertices_after = n;
    if (n == 0) return r;
    std::vector<uint32_t> target(n); // representative (lowest index) of each vertex
    for (uint32_t v = 0; v < n; ++v) target[v] = v;

    const double tol = options.tolerance_rel > 0 ? options.tolerance_rel * computeBounds(mesh).diagonal() : 0.0;
    if (tol <= 0.0) {
        std::vector<uint32_t> order(n);
        for (uint32_t v = 0; v < n; ++v) order[v] = v;
        auto key = [&](uint32_t v) {
            std::array<uint32_t, 3> k;
            std::memcpy(k.data(), &mesh.positions[v], sizeof(k));
            return k;
        };
        std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
            const auto ka = key(a), kb = key(b);
            return ka != kb ? ka < kb : a < b;
        });
        for (size_t i = 0; i < n;) {
            size_t j = i;
            while (j < n && key(order[j]) == key(order[i])) ++j;
            // Within a run of equal positions (ascending index), each vertex joins the first
            // representative whose attributes match, else becomes one.
            std::vector<uint32_t> reps;
            for (size_t k = i; k < j; ++k) {
                const uint32_t v = order[k];
                if (!isFinite(mesh.positions[v])) continue;
                bool merged = false;
                for (uint32_t rep : reps)
                    if (attributesMatch(mesh, rep, v, options)) {
                        target[v] = rep;
                        merged = true;
                        break;
                    }
                if (!merged) {
                    if (!reps.empty()) ++r.seam_pairs_kept;
                    reps.push_back(v);
                }
            }
            i = j;
        }
    } else {
        // The hash map is only looked up, never iterated, so its order cannot reach the output.
        const double inv = 1.0 / tol;
        // Converting NaN (0 * inf) or an out-of-range double to int is undefined (UBSan): such cells
        // map to INT_MIN, which is what x86 produced before, so results do not change.
        auto toCell = [](double c) { return c >= -2147483648.0 && c < 2147483648.0 ? int(c) : INT_MIN; };
        auto cellOf = [&](const Vec3f& p, int d[3]) {
            d[0] = toCell(std::floor(p.x * inv));
            d[1] = toCell(std::floor(p.y * inv));
            d[2] = toCell(std::floor(p.z * inv));
        };
        // Unsigned: neighbour cells of INT_MIN/INT_MAX wrap instead of overflowing (same key bits).
        auto cellKey = [](uint32_t x, uint32_t y, uint32_t z) {
            return (uint64_t(x & 0x1FFFFF) << 42) | (uint64_t(y & 0x1FFFFF) << 21) | uint64_t(z & 0x1FFFFF);
        };
        std::unordered_map<uint64_t, std::vector<uint32_t>> reps;
        reps.reserve(n);
        const double tol2 = tol * tol;
        for (uint32_t v = 0; v < n; ++v) {
            const Vec3f& p = mesh.positions[v];
            if (!isFinite(p)) continue;
            int c[3];
            cellOf(p, c);
            uint32_t best = kNone;
            bool seam = false;
            for (int dx = -1; dx <= 1; ++dx)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dz = -1; dz <= 1; ++dz) {
                        auto it = reps.find(cellKey(uint32_t(c[0]) + uint32_t(dx), uint32_t(c[1]) + uint32_t(dy),
                                                      uint32_t(c[2]) + uint32_t(dz)));
                        if (it == reps.end()) continue;
                        for (uint32_t rep : it->second) {
                            if (rep >= best) continue;
                            const Vec3d d = toDouble(mesh.positions[rep]) - toDouble(p);
                            if (dot(d, d) > tol2) continue;
                            if (!attributesMatch(mesh, rep, v, options)) {
                                seam = true;
                                continue;
                            }
                            best = rep;
                        }
                    }
            if (best != kNone) {
                target[v] = best;
            } else {
                r.seam_pairs_kept += seam;
                reps[cellKey(uint32_t(c[0]), uint32_t(c[1]), uint32_t(c[2]))].push_back(v);
            }
        }
    }

    std::vector<uint32_t> old_to_new(n, kNone);
    uint32_t next = 0;
    for (uint32_t v = 0; v < n; ++v)
        if (target[v] == v) old_to_new[v] = next++;
    for (uint32_t v = 0; v < n; ++v)
        if (target[v] != v) {
            old_to_new[v] = old_to_new[target[v]];
            ++r.vertices_merged;
        }
    if (r.vertices_merged) remapVertices(mesh, old_to_new, next);
    r.vertices_after = next;
    return r;
}

} // namespace lodbake
