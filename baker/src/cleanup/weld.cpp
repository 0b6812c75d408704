// Vertex welding: exact (bit-identical positions, by sorting) or within a tolerance relative to the
// bounding-box diagonal (cells of the tolerance size, sorted, 27-cell lookup).
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "core/parallel.h"
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

// Cell coordinate of x along one axis: cells of size 1/inv counted from lo. Clamped so far-away
// unreferenced strays cannot overflow (they only share clamped cells).
int64_t cellOf(float x, float lo, double inv) {
    return int64_t(std::max(-1e15, std::min(1e15, std::floor((double(x) - lo) * inv))));
}

// The tolerance weld with cell coordinates of type Coord: int32_t when every cell fits (half the
// memory and a faster sort than int64_t; the order and the neighbourhoods are the same).
template <class Coord>
void toleranceWeld(const Mesh& mesh, const WeldOptions& options, const Aabb& box, double tol,
                   std::vector<uint32_t>& target, WeldReport& r) {
    const uint32_t n = uint32_t(mesh.vertexCount());
    using Cell = std::array<Coord, 3>;
    // Cells of the tolerance size, counted from the box minimum, sorted x-major: for a vertex in
    // cell (x, y, z) every point within tol lies in cells (x±1, y±1, z±1).
    // A parallel pre-pass finds the vertices with any neighbour in range; only those take part in
    // the sequential index-order rule (join the lowest earlier representative in range, else
    // become one), so clean input costs one sort and a read-only parallel scan.
    const double inv = 1.0 / tol;
    std::vector<std::pair<Cell, uint32_t>> cells; // (cell, vertex), finite vertices only
    cells.reserve(n);
    for (VertexId v(0); v.value < n; ++v.value) {
        const Vec3f& p = mesh.positions[v.value];
        if (!isFinite(p)) continue;
        cells.push_back({Cell{Coord(cellOf(p.x, box.min.x, inv)), Coord(cellOf(p.y, box.min.y, inv)),
                              Coord(cellOf(p.z, box.min.z, inv))},
                         v.value});
    }
    std::sort(cells.begin(), cells.end());
    std::vector<uint32_t> cell_index(n, kNone); // vertex -> its slot in `cells`
    for (uint32_t i = 0; i < cells.size(); ++i) cell_index[cells[i].second] = i;
    const double tol2 = tol * tol;
    // Calls fn(u) for every other finite vertex u within tol of vertex v.
    auto forEachInRange = [&](VertexId v, auto&& fn) {
        const Cell& c = cells[cell_index[v.value]].first;
        const Vec3d p = toDouble(mesh.positions[v.value]);
        // Per x slab, the cells (x, y-1..y+1, any z) are one run of the sorted list: three
        // searches instead of nine; cells more than one z step away are skipped in the scan.
        for (int64_t dx = -1; dx <= 1; ++dx) {
            const Cell lo{Coord(c[0] + dx), Coord(c[1] - 1), std::numeric_limits<Coord>::min()};
            auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(lo, uint32_t(0)));
            for (; it != cells.end() && it->first[0] == lo[0] && it->first[1] <= c[1] + 1; ++it) {
                if (it->second == v.value || it->first[2] < c[2] - 1 || it->first[2] > c[2] + 1) continue;
                const Vec3d d = toDouble(mesh.positions[it->second]) - p;
                if (dot(d, d) <= tol2) fn(VertexId(it->second));
            }
        }
    };
    // The pre-pass, per fixed chunk of the sorted list: the start of each x slab's run moves
    // forward with the cell, so three cursors advance through the list instead of three
    // binary searches per vertex; the scan stops at the first neighbour in range.
    std::vector<uint8_t> has_neighbour(n, 0);
    constexpr size_t kScanChunk = 4096;
    auto scanChunk = [&](size_t, size_t first, size_t last) {
        size_t cursor[3] = {0, 0, 0};
        for (size_t i = first; i < last; ++i) {
            const Cell& c = cells[i].first;
            const uint32_t v = cells[i].second;
            const Vec3d p = toDouble(mesh.positions[v]);
            bool found = false;
            for (int64_t dx = -1; dx <= 1 && !found; ++dx) {
                const Cell lo{Coord(c[0] + dx), Coord(c[1] - 1), std::numeric_limits<Coord>::min()};
                size_t& k = cursor[dx + 1];
                if (i == first)
                    k = size_t(std::lower_bound(cells.begin(), cells.end(), std::make_pair(lo, uint32_t(0))) -
                               cells.begin());
                else
                    while (k < cells.size() && cells[k].first < lo) ++k;
                for (size_t j = k; j < cells.size() && cells[j].first[0] == lo[0] && cells[j].first[1] <= c[1] + 1;
                     ++j) {
                    if (cells[j].second == v || cells[j].first[2] < c[2] - 1 || cells[j].first[2] > c[2] + 1)
                        continue;
                    const Vec3d d = toDouble(mesh.positions[cells[j].second]) - p;
                    if (dot(d, d) <= tol2) {
                        found = true;
                        break;
                    }
                }
            }
            if (found) has_neighbour[v] = 1;
        }
    };
    // Out of memory in a worker: the same scan on this thread, as one chunk.
    if (!parallelForChunks(cells.size(), kScanChunk, scanChunk).ok()) scanChunk(0, 0, cells.size());
    std::vector<uint8_t> is_rep(n, 0);
    for (VertexId v(0); v.value < n; ++v.value) {
        if (cell_index[v.value] == kNone) continue; // non-finite: never merges
        if (!has_neighbour[v.value]) {
            is_rep[v.value] = 1;
            continue;
        }
        uint32_t best = kNone;
        bool seam = false;
        forEachInRange(v, [&](VertexId u) {
            if (u.value >= v.value || !is_rep[u.value] || u.value >= best) return;
            if (!attributesMatch(mesh, u.value, v.value, options)) {
                seam = true;
                return;
            }
            best = u.value;
        });
        if (best != kNone) {
            target[v.value] = best;
        } else {
            r.seam_pairs_kept += seam;
            is_rep[v.value] = 1;
        }
    }
}

} // namespace

WeldReport weldVertices(Mesh& mesh, const WeldOptions& options) {
    WeldReport r;
    const uint32_t n = uint32_t(mesh.vertexCount());
    r.vertices_before = r.vertices_after = n;
    if (n == 0) return r;
    std::vector<uint32_t> target(n); // representative (lowest index) of each vertex
    for (uint32_t v = 0; v < n; ++v) target[v] = v;

    const Aabb box = options.tolerance_rel > 0 ? computeBounds(mesh) : Aabb();
    const double tol = options.tolerance_rel > 0 ? options.tolerance_rel * box.diagonal() : 0.0;
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
        // Cells of int32_t when every finite vertex's cell (and its neighbours) fits: cellOf is
        // monotone, so the extreme coordinates tell.
        const double inv = 1.0 / tol;
        Aabb all;
        for (const Vec3f& p : mesh.positions)
            if (isFinite(p)) all.expand(p);
        bool small = true;
        if (!all.isEmpty())
            for (int64_t c : {cellOf(all.min.x, box.min.x, inv), cellOf(all.min.y, box.min.y, inv),
                              cellOf(all.min.z, box.min.z, inv), cellOf(all.max.x, box.min.x, inv),
                              cellOf(all.max.y, box.min.y, inv), cellOf(all.max.z, box.min.z, inv)})
                small = small && c > -(int64_t(1) << 30) && c < (int64_t(1) << 30);
        if (small)
            toleranceWeld<int32_t>(mesh, options, box, tol, target, r);
        else
            toleranceWeld<int64_t>(mesh, options, box, tol, target, r);
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
