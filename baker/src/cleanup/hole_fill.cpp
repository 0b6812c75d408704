// Hole filling after Liepa 2003, "Filling holes in meshes" (SGP): an O(n^3) dynamic program picks the
// triangulation of a boundary loop that minimises the largest dihedral angle, then the total area;
// the patch is refined (centroid splits until triangles match the loop's edge lengths, with
// Delaunay-style edge flips) and faired with umbrella smoothing. Loops above max_dp_edges use
// min-angle ear clipping (O(n^2)), the greedy scheme MeshLab applies, before the same refinement.
#include <algorithm>
#include <cmath>
#include <functional>
#include <unordered_map>

#include "lodbake/cleanup/passes.h"
#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters HoleFillReport::counters() const {
    return {{"seam_loops", seam_loops},
            {"holes_found", holes_found},
            {"holes_filled", holes_filled},
            {"holes_skipped_too_large", uint64_t(skipped_lengths.size())},
            {"holes_unfillable", holes_unfillable},
            {"faces_added", faces_added},
            {"vertices_added", vertices_added}};
}

namespace {

using Tri = std::array<uint32_t, 3>;

struct Patch {
    std::vector<Vec3d> pos;    // loop vertices first (0..n-1), then new ones
    std::vector<double> sigma; // target edge length per vertex
    std::vector<Tri> tris;     // local ids, oriented like the surrounding surface
    std::vector<Tri> parents;  // per new vertex (index - loop size): the triangle it split
};

Vec3d triNormal(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    return cross(b - a, c - a);
}

double angleBetween(const Vec3d& n0, const Vec3d& n1) {
    const double l = length(n0) * length(n1);
    if (l <= 0.0) return M_PI; // degenerate: worst case
    return std::acos(std::max(-1.0, std::min(1.0, dot(n0, n1) / l)));
}

struct Weight {
    double angle = 0.0;
    double area = 0.0;
    bool operator<(const Weight& o) const { return angle != o.angle ? angle < o.angle : area < o.area; }
};

// Liepa's DP over the loop 0..n-1. `outside[i]` is the normal of the mesh face on loop edge (i, i+1).
bool triangulateDp(const std::vector<Vec3d>& p, const std::vector<Vec3d>& outside,
                   const std::function<bool(uint32_t, uint32_t)>& diagonalExists, std::vector<Tri>& out) {
    const uint32_t n = uint32_t(p.size());
    const Weight kInf{1e300, 1e300};
    std::vector<Weight> w(size_t(n) * n, kInf);
    std::vector<uint32_t> apex(size_t(n) * n, kNone);
    auto at = [n](uint32_t i, uint32_t k) { return size_t(i) * n + k; };
    for (uint32_t i = 0; i + 1 < n; ++i) w[at(i, i + 1)] = Weight{};
    // Patch triangle (i,m,k), i<m<k, is emitted as (k,m,i).
    auto normalOf = [&](uint32_t i, uint32_t m, uint32_t k) { return triNormal(p[k], p[m], p[i]); };
    for (uint32_t len = 2; len < n; ++len) {
        for (uint32_t i = 0; i + len < n; ++i) {
            const uint32_t k = i + len;
            Weight best = kInf;
            uint32_t best_m = kNone;
            for (uint32_t m = i + 1; m < k; ++m) {
                const Weight& a = w[at(i, m)];
                const Weight& b = w[at(m, k)];
                if (a.angle >= 1e300 || b.angle >= 1e300) continue;
                if ((m > i + 1 && diagonalExists(i, m)) || (m + 1 < k && diagonalExists(m, k))) continue;
                const Vec3d nt = normalOf(i, m, k);
                if (dot(nt, nt) == 0.0)
                    continue; // coincident or collinear corners (e.g. both halves of a split pinch vertex)
                double ang = std::max(a.angle, b.angle);
                ang = std::max(ang, angleBetween(nt, m == i + 1 ? outside[i] : normalOf(i, apex[at(i, m)], m)));
                ang = std::max(ang, angleBetween(nt, k == m + 1 ? outside[m] : normalOf(m, apex[at(m, k)], k)));
                if (i == 0 && k == n - 1) ang = std::max(ang, angleBetween(nt, outside[n - 1]));
                const Weight cand{ang, a.area + b.area + 0.5 * length(nt)};
                if (cand < best) {
                    best = cand;
                    best_m = m;
                }
            }
            w[at(i, k)] = best;
            apex[at(i, k)] = best_m;
        }
    }
    if (apex[at(0, n - 1)] == kNone) return false;
    std::vector<std::pair<uint32_t, uint32_t>> stack = {{0, n - 1}};
    while (!stack.empty()) {
        const auto [i, k] = stack.back();
        stack.pop_back();
        if (k < i + 2) continue;
        const uint32_t m = apex[at(i, k)];
        out.push_back({k, m, i});
        stack.push_back({i, m});
        stack.push_back({m, k});
    }
    return true;
}

// Min-angle ear clipping for large loops. `normal` is the fill direction.
bool triangulateEars(const std::vector<Vec3d>& p, const Vec3d& normal,
                     const std::function<bool(uint32_t, uint32_t)>& diagonalExists, std::vector<Tri>& out) {
    const uint32_t n = uint32_t(p.size());
    std::vector<uint32_t> prev(n), next(n);
    for (uint32_t i = 0; i < n; ++i) {
        prev[i] = (i + n - 1) % n;
        next[i] = (i + 1) % n;
    }
    std::vector<double> angle(n);
    std::vector<uint8_t> alive(n, 1);
    auto interior = [&](uint32_t b) {
        const Vec3d u = p[prev[b]] - p[b], v = p[next[b]] - p[b];
        double a = std::atan2(dot(normal, cross(u, v)), dot(u, v));
        if (a < 0) a += 2 * M_PI;
        return a;
    };
    for (uint32_t i = 0; i < n; ++i) angle[i] = interior(i);
    for (uint32_t remaining = n; remaining > 3; --remaining) {
        uint32_t best = kNone;
        for (uint32_t i = 0; i < n; ++i)
            if (alive[i] && (best == kNone || angle[i] < angle[best]) && !diagonalExists(prev[i], next[i])) {
                const Vec3d nt = cross(p[i] - p[prev[i]], p[next[i]] - p[prev[i]]);
                if (dot(nt, nt) > 0.0) best = i;
            }
        if (best == kNone) return false;
        const uint32_t a = prev[best], c = next[best];
        out.push_back({c, best, a});
        alive[best] = 0;
        next[a] = c;
        prev[c] = a;
        angle[a] = interior(a);
        angle[c] = interior(c);
    }
    uint32_t first = 0;
    while (!alive[first]) ++first;
    out.push_back({next[next[first]], next[first], first});
    return true;
}

// Edge -> its (up to two) patch triangles, kept up to date through splits and flips. Looked up only,
// never iterated, so its order cannot reach the output.
class PatchEdges {
public:
    explicit PatchEdges(const std::vector<Tri>& tris) {
        map_.reserve(tris.size() * 4);
        for (uint32_t t = 0; t < tris.size(); ++t)
            for (int k = 0; k < 3; ++k) add(tris[t][k], tris[t][(k + 1) % 3], t);
    }
    void add(uint32_t a, uint32_t b, uint32_t t) {
        auto& slot = map_.try_emplace(edgeKey(a, b), std::array<uint32_t, 2>{kNone, kNone}).first->second;
        slot[slot[0] == kNone ? 0 : 1] = t;
    }
    void replace(uint32_t a, uint32_t b, uint32_t from, uint32_t to) {
        auto& slot = map_[edgeKey(a, b)];
        for (uint32_t& s : slot)
            if (s == from) {
                s = to;
                return;
            }
    }
    void erase(uint32_t a, uint32_t b) { map_.erase(edgeKey(a, b)); }
    bool has(uint32_t a, uint32_t b) const { return map_.count(edgeKey(a, b)) != 0; }
    uint32_t other(uint32_t a, uint32_t b, uint32_t t) const {
        auto it = map_.find(edgeKey(a, b));
        if (it == map_.end()) return kNone;
        return it->second[0] == t ? it->second[1] : it->second[0];
    }

private:
    std::unordered_map<uint64_t, std::array<uint32_t, 2>> map_;
};

void refinePatch(Patch& patch, uint32_t loop_size, const std::function<bool(uint32_t, uint32_t)>& diagonalExists,
                 size_t max_vertices) {
    const double kSqrt2 = std::sqrt(2.0);
    PatchEdges edges(patch.tris);
    std::vector<uint32_t> degree(patch.pos.size(), 0);
    for (const Tri& t : patch.tris)
        for (uint32_t v : t) ++degree[v];
    auto isLoopEdge = [&](uint32_t a, uint32_t b) {
        return a < loop_size && b < loop_size && (b == (a + 1) % loop_size || a == (b + 1) % loop_size);
    };
    // Flips edge (a,b) of triangle t if it is not locally Delaunay; returns whether it flipped.
    auto tryFlip = [&](uint32_t t, uint32_t a, uint32_t b, std::vector<std::pair<uint32_t, uint32_t>>& work) {
        if (isLoopEdge(a, b)) return false; // borders the mesh
        // Orient (a,b) as triangle t runs it.
        const Tri& tt = patch.tris[t];
        int k = 0;
        while (k < 3 && !(tt[k] == a && tt[(k + 1) % 3] == b)) ++k;
        if (k == 3) std::swap(a, b);
        k = 0;
        while (k < 3 && !(tt[k] == a && tt[(k + 1) % 3] == b)) ++k;
        if (k == 3) return false;
        const uint32_t c = tt[(k + 2) % 3];
        const uint32_t u = edges.other(a, b, t);
        if (u == kNone) return false;
        uint32_t d = kNone;
        for (uint32_t v : patch.tris[u])
            if (v != a && v != b) d = v;
        if (d == kNone || d == c || edges.has(c, d)) return false;
        if (c < loop_size && d < loop_size && diagonalExists(c, d)) return false;
        // An inner vertex must keep at least three triangles, or it folds onto a neighbour.
        if ((a >= loop_size && degree[a] <= 3) || (b >= loop_size && degree[b] <= 3)) return false;
        auto angleAt = [&](uint32_t x) {
            return angleBetween(patch.pos[a] - patch.pos[x], patch.pos[b] - patch.pos[x]);
        };
        if (angleAt(c) + angleAt(d) <= M_PI + 1e-9) return false;
        const Vec3d n0 = triNormal(patch.pos[a], patch.pos[d], patch.pos[c]);
        const Vec3d n1 = triNormal(patch.pos[d], patch.pos[b], patch.pos[c]);
        if (dot(n0, n0) == 0.0 || dot(n1, n1) == 0.0 || dot(n0, n1) <= 0.0) return false; // would fold
        // t = (a,b,c), u = (b,a,d) -> t = (a,d,c), u = (d,b,c)
        patch.tris[t] = {a, d, c};
        patch.tris[u] = {d, b, c};
        edges.erase(a, b);
        edges.add(c, d, t);
        edges.add(c, d, u);
        edges.replace(a, d, u, t);
        edges.replace(b, c, t, u);
        --degree[a];
        --degree[b];
        ++degree[c];
        ++degree[d];
        work.push_back({a, d});
        work.push_back({d, b});
        work.push_back({b, c});
        work.push_back({c, a});
        return true;
    };
    // Worklist of edges to check, processed in order; bounded so a 3D configuration that keeps
    // flipping cannot loop forever.
    auto relax = [&](std::vector<std::pair<uint32_t, uint32_t>> work) {
        size_t budget = 20 * patch.tris.size() + 100;
        std::vector<std::pair<uint32_t, uint32_t>> more;
        for (size_t i = 0; i < work.size() && budget > 0; ++i, --budget) {
            const auto [a, b] = work[i];
            const uint32_t t = edges.other(a, b, kNone); // any triangle on the edge
            if (t == kNone) continue;
            more.clear();
            if (tryFlip(t, a, b, more)) work.insert(work.end(), more.begin(), more.end());
        }
    };
    {
        std::vector<std::pair<uint32_t, uint32_t>> all;
        for (const Tri& t : patch.tris)
            for (int k = 0; k < 3; ++k) all.push_back({t[k], t[(k + 1) % 3]});
        relax(std::move(all));
    }
    for (int round = 0; round < 60; ++round) {
        const size_t tri_count = patch.tris.size();
        std::vector<std::pair<uint32_t, uint32_t>> work;
        for (size_t t = 0; t < tri_count && patch.pos.size() < max_vertices; ++t) {
            const Tri tri = patch.tris[t];
            const Vec3d c = (patch.pos[tri[0]] + patch.pos[tri[1]] + patch.pos[tri[2]]) / 3.0;
            const double sc = (patch.sigma[tri[0]] + patch.sigma[tri[1]] + patch.sigma[tri[2]]) / 3.0;
            bool split = true;
            for (uint32_t v : tri) {
                const double d = kSqrt2 * length(c - patch.pos[v]);
                if (d <= sc || d <= patch.sigma[v]) split = false;
            }
            if (!split) continue;
            const uint32_t x = uint32_t(patch.pos.size());
            const uint32_t t1 = uint32_t(patch.tris.size()), t2 = t1 + 1;
            patch.pos.push_back(c);
            patch.sigma.push_back(sc);
            patch.parents.push_back(tri);
            degree.push_back(3);
            for (uint32_t v : tri) ++degree[v];
            patch.tris[t] = {tri[0], tri[1], x};
            patch.tris.push_back({tri[1], tri[2], x});
            patch.tris.push_back({tri[2], tri[0], x});
            edges.replace(tri[1], tri[2], uint32_t(t), t1);
            edges.replace(tri[2], tri[0], uint32_t(t), t2);
            edges.add(tri[0], x, uint32_t(t));
            edges.add(tri[0], x, t2);
            edges.add(tri[1], x, uint32_t(t));
            edges.add(tri[1], x, t1);
            edges.add(tri[2], x, t1);
            edges.add(tri[2], x, t2);
            work.push_back({tri[0], tri[1]});
            work.push_back({tri[1], tri[2]});
            work.push_back({tri[2], tri[0]});
        }
        if (work.empty()) break;
        relax(std::move(work));
    }
}

void fairPatch(Patch& patch, uint32_t loop_size, uint32_t iterations) {
    const uint32_t n = uint32_t(patch.pos.size());
    if (n == loop_size) return;
    std::vector<std::vector<uint32_t>> nb(n);
    for (const Tri& t : patch.tris)
        for (int k = 0; k < 3; ++k) {
            nb[t[k]].push_back(t[(k + 1) % 3]);
            nb[t[k]].push_back(t[(k + 2) % 3]);
        }
    for (auto& v : nb) {
        std::sort(v.begin(), v.end());
        v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    for (uint32_t it = 0; it < iterations; ++it)
        for (uint32_t v = loop_size; v < n; ++v) {
            if (nb[v].size() < 3) continue;
            Vec3d s;
            for (uint32_t u : nb[v]) s += patch.pos[u];
            patch.pos[v] = s / double(nb[v].size());
        }
}

} // namespace

HoleFillReport fillHoles(Mesh& mesh, const HoleFillOptions& options) {
    Scratch scratch;
    return fillHoles(mesh, options, scratch);
}

HoleFillReport cleanup_detail::fillHoles(Mesh& mesh, const HoleFillOptions& options, Scratch& scratch) {
    HoleFillReport r;
    if (mesh.faceCount() == 0) return r;
    EdgeTable& table = scratch.table;
    buildEdgeTable(mesh.indices, mesh.vertexCount(), table);
    const std::vector<BoundaryLoop> loops = findBoundaryLoops(mesh, table);
    const std::vector<uint32_t> face_sub = faceSubmeshes(mesh);
    // Boundary edges along an attribute seam (UV island borders) are not holes: loops containing
    // one are left alone.
    const bool has_attributes = mesh.hasNormals() || mesh.hasTangents() || mesh.hasColors() || !mesh.uvs.empty();
    const std::vector<uint8_t> seam = has_attributes ? seamCorners(mesh, table, positionWeldMap(mesh))
                                                     : std::vector<uint8_t>(mesh.indices.size(), 0); // no seams
    auto isSeam = [&](uint32_t c) { return seam[c] != 0; };
    std::vector<Tri> new_faces;
    std::vector<uint32_t> new_face_sub;
    for (const BoundaryLoop& loop : loops) {
        const uint32_t n = uint32_t(loop.vertices.size());
        if (!loop.closed || n < 3) {
            ++r.holes_found;
            ++r.holes_unfillable;
            continue;
        }
        if (std::any_of(loop.corners.begin(), loop.corners.end(), isSeam)) {
            ++r.seam_loops;
            continue;
        }
        ++r.holes_found;
        if (n == 3 && loop.corners[0] / 3 == loop.corners[1] / 3 && loop.corners[1] / 3 == loop.corners[2] / 3) {
            ++r.holes_unfillable; // a lone triangle: filling would only add its back face
            continue;
        }
        if (n > options.max_hole_edges) {
            r.skipped_lengths.push_back(n);
            continue;
        }
        Patch patch;
        std::vector<Vec3d> outside(n);
        Vec3d newell;
        for (uint32_t i = 0; i < n; ++i) {
            patch.pos.push_back(toDouble(mesh.positions[loop.vertices[i]]));
            outside[i] = faceNormal(mesh, loop.corners[i] / 3);
        }
        for (uint32_t i = 0; i < n; ++i) {
            const Vec3d& a = patch.pos[i];
            const Vec3d& b = patch.pos[(i + 1) % n];
            newell += cross(a, b);
            const double prev_len = length(patch.pos[i] - patch.pos[(i + n - 1) % n]);
            patch.sigma.push_back(0.5 * (prev_len + length(b - a)));
        }
        auto diagonalExists = [&](uint32_t i, uint32_t k) {
            return table.find(loop.vertices[i], loop.vertices[k]) != kNone;
        };
        // The DP needs n^2 memory and n^3 time: above kMaxDpEdges it is never used, whatever the options say.
        constexpr uint32_t kMaxDpEdges = 400;
        bool ok = n <= std::min(options.max_dp_edges, kMaxDpEdges)
                      ? triangulateDp(patch.pos, outside, diagonalExists, patch.tris)
                      : triangulateEars(patch.pos, normalize(newell) * -1.0, diagonalExists, patch.tris);
        if (!ok) {
            ++r.holes_unfillable;
            continue;
        }
        if (options.refine) refinePatch(patch, n, diagonalExists, std::min<size_t>(size_t(n) * 200 + 1000, 4000000));
        if (options.fair) fairPatch(patch, n, options.fair_iterations);
        std::vector<uint32_t> global(patch.pos.size());
        for (uint32_t i = 0; i < n; ++i) global[i] = loop.vertices[i];
        for (uint32_t i = n; i < patch.pos.size(); ++i) {
            // Attributes (UVs, colours, ...) are the mean of the split triangle's corners, which are
            // all older than this vertex; the normals pass recomputes normals afterwards.
            const Tri& from = patch.parents[i - n];
            global[i] = blendedVertex(mesh, {global[from[0]], global[from[1]], global[from[2]]});
            mesh.positions[global[i]] = Vec3f(patch.pos[i]);
        }
        for (const Tri& t : patch.tris) {
            new_faces.push_back({global[t[0]], global[t[1]], global[t[2]]});
            new_face_sub.push_back(face_sub[loop.corners[0] / 3]);
        }
        ++r.holes_filled;
        r.filled_lengths.push_back(n);
        r.faces_added += patch.tris.size();
        r.vertices_added += patch.pos.size() - n;
    }
    insertFaces(mesh, new_faces, new_face_sub);
    std::sort(r.filled_lengths.begin(), r.filled_lengths.end(), std::greater<uint32_t>());
    std::sort(r.skipped_lengths.begin(), r.skipped_lengths.end(), std::greater<uint32_t>());
    return r;
}

} // namespace lodbake
