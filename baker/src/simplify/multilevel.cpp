// Multilevel simplification (Guerra 2012, "Semplificazione multilivello di mesh da scanner 3D",
// seed document 003, chapter 3): OUT_ITS outer iterations, each an explicit p-Laplacian smoothing
// with a fidelity term (Rucci's p-Laplacian regularisation) followed by an edge-collapse
// decimation that removes 1/OUT_ITS of the requested edges, shortest and flattest first.
//
//   TOLL  = length under which PERC % of the edges lie (100-bin histogram of normalised lengths)
//   H0    = per-vertex curvature of the input, kept (interpolated, never recomputed) for all levels
//   for each outer iteration:  X <- Smoothing(X, H0);  X <- Decimation(X, H0, TOLL, ne)
//
// Collapse placement: v = lerp(v0, v1, t), t = (c1 - c0)/2 + 0.5 with c the normalised curvature,
// so the new vertex is drawn toward the more curved end. A collapse is refused when (a) a vertex
// opposite the edge has valence 3, or (b) the endpoints share a neighbour besides the two opposite
// vertices (the link condition); we also refuse triangle flips, and keep open-boundary and
// non-manifold vertices fixed (the document does not treat borders).
#include "lodbake/simplify/multilevel.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <queue>
#include <string>
#include <tuple>
#include <vector>

namespace lodbake {

namespace {

constexpr int kHistogramBins = 100; // the document's experimentally chosen resolution

std::string formatNumber(double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

// Candidate in the collapse queue; stale when either endpoint changed since it was pushed.
struct Candidate {
    double key;
    VertexId a, b; // a < b
    uint32_t stamp_a, stamp_b;
    bool operator>(const Candidate& o) const {
        return std::tie(key, a, b) > std::tie(o.key, o.a, o.b); // ties by vertex ids: heap-layout independent
    }
};

class MultilevelMesh {
public:
    Status init(const Mesh& mesh) {
        const size_t n = mesh.vertexCount();
        for (VertexId v(0); v.value < n; ++v.value)
            if (!isFinite(mesh.position(v)))
                return invalidInput("vertex " + std::to_string(v.value) + ": expected finite coordinates");
        pos_.resize(n);
        for (VertexId v(0); v.value < n; ++v.value) pos_[v.value] = toDouble(mesh.position(v));
        faces_of_.resize(n);
        for (FaceId f(0); f.value < mesh.faceCount(); ++f.value) {
            const std::array<VertexId, 3> t = mesh.triangle(f);
            if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
            const FaceId id(uint32_t(tri_.size()));
            tri_.push_back(t);
            for (VertexId v : t) faces_of_[v.value].push_back(id);
        }
        face_alive_.assign(tri_.size(), 1);
        vertex_alive_.assign(n, 0);
        for (const auto& t : tri_)
            for (VertexId v : t) vertex_alive_[v.value] = 1;
        stamp_.assign(n, 0);
        locked_.assign(n, 0);
        // Count the faces of every undirected edge: boundary and non-manifold vertices are locked.
        std::vector<std::pair<uint64_t, uint32_t>> keys;
        keys.reserve(tri_.size() * 3);
        for (const auto& t : tri_)
            for (int k = 0; k < 3; ++k) keys.push_back({edgeKey(t[k], t[(k + 1) % 3]), 0});
        std::sort(keys.begin(), keys.end());
        for (size_t i = 0; i < keys.size();) {
            size_t j = i;
            while (j < keys.size() && keys[j].first == keys[i].first) ++j;
            if (j - i != 2) {
                locked_[uint32_t(keys[i].first >> 32)] = 1;
                locked_[uint32_t(keys[i].first)] = 1;
            }
            edges_.push_back(keys[i].first);
            i = j;
        }
        computeCurvature();
        return Status::okStatus();
    }

    size_t edgeCount() const { return edges_.size(); }
    size_t faceCount() const {
        size_t c = 0;
        for (uint8_t a : face_alive_) c += a;
        return c;
    }

    // TOLL: the upper edge of the first histogram bin (normalised by the longest edge) at which the
    // cumulative share of edges reaches `percentage`.
    double lengthThreshold(double percentage) const {
        double max_len = 0.0;
        std::vector<double> len(edges_.size());
        for (size_t e = 0; e < edges_.size(); ++e) {
            len[e] = edgeLength(VertexId(uint32_t(edges_[e] >> 32)), VertexId(uint32_t(edges_[e])));
            max_len = std::max(max_len, len[e]);
        }
        if (max_len <= 0.0) return 0.0;
        std::array<size_t, kHistogramBins> bins{};
        for (double l : len) ++bins[std::min(kHistogramBins - 1, int(l / max_len * kHistogramBins))];
        const double wanted = percentage / 100.0 * double(edges_.size());
        size_t cumulative = 0;
        for (int b = 0; b < kHistogramBins; ++b) {
            cumulative += bins[b];
            if (double(cumulative) >= wanted) return max_len * double(b + 1) / kHistogramBins;
        }
        return max_len;
    }

    // Explicit p-Laplacian diffusion x += Δt·L_p x with the fidelity λ_i (x0 − x) taken implicitly,
    // so any λ is stable: x' = (x + Δt·L_p x + Δt·λ_i·x0) / (1 + Δt·λ_i). Jacobi order: every vertex
    // reads the previous positions, so the result does not depend on the visiting order.
    void smooth(const MultilevelOptions& o) {
        const size_t n = pos_.size();
        std::vector<uint32_t> begin;
        std::vector<VertexId> nb;
        buildNeighbours(begin, nb);
        const std::vector<Vec3d> x0 = pos_;
        std::vector<Vec3d> next(n);
        const double floor_len = diagonal_ * 1e-9 + 1e-300; // keeps |d|^(p-2) finite
        for (uint32_t step = 0; step < o.smoothing_iterations; ++step) {
            for (VertexId v(0); v.value < n; ++v.value) {
                const Vec3d& x = pos_[v.value];
                next[v.value] = x;
                if (!vertex_alive_[v.value] || locked_[v.value] || begin[v.value] == begin[v.value + 1]) continue;
                Vec3d sum;
                double wsum = 0.0;
                for (uint32_t i = begin[v.value]; i < begin[v.value + 1]; ++i) {
                    const Vec3d& y = pos_[nb[i].value];
                    const double w = std::pow(std::max(length(y - x), floor_len), o.ple - 2.0);
                    sum += y * w;
                    wsum += w;
                }
                const Vec3d lap = sum / wsum - x;
                const double lambda = o.lambda * (o.is_adaptive ? fidelity_scale_[v.value] : 1.0);
                const double dl = o.time_step * lambda;
                next[v.value] = (x + lap * o.time_step + x0[v.value] * dl) / (1.0 + dl);
            }
            pos_.swap(next);
        }
    }

    // Collapses up to `budget` edges; returns the number done. Sorted: a lazy min-heap over
    // length × (1 + mean curvature). Unsorted: one pass over the current edges in id order,
    // collapsing those shorter than `threshold`.
    size_t decimate(size_t budget, bool is_sorted, double threshold, size_t& refused) {
        size_t done = 0;
        if (is_sorted) {
            std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap;
            for (uint64_t key : currentEdges()) pushEdge(heap, VertexId(uint32_t(key >> 32)), VertexId(uint32_t(key)));
            while (done < budget && !heap.empty()) {
                const Candidate c = heap.top();
                heap.pop();
                if (!vertex_alive_[c.a.value] || !vertex_alive_[c.b.value] || stamp_[c.a.value] != c.stamp_a ||
                    stamp_[c.b.value] != c.stamp_b)
                    continue;
                VertexId survivor;
                if (!tryCollapse(c.a, c.b, survivor)) {
                    ++refused;
                    continue;
                }
                ++done;
                std::vector<VertexId> ring;
                neighbours(survivor, ring);
                for (VertexId w : ring) pushEdge(heap, std::min(survivor, w), std::max(survivor, w));
            }
        } else {
            for (uint64_t key : currentEdges()) {
                if (done >= budget) break;
                const VertexId a{uint32_t(key >> 32)}, b{uint32_t(key)};
                if (!vertex_alive_[a.value] || !vertex_alive_[b.value] || !(edgeLength(a, b) < threshold)) continue;
                VertexId survivor;
                if (tryCollapse(a, b, survivor))
                    ++done;
                else
                    ++refused;
            }
        }
        return done;
    }

    Mesh extract() const {
        Mesh out;
        std::vector<uint32_t> remap(pos_.size(), UINT32_MAX);
        for (FaceId f(0); f.value < tri_.size(); ++f.value) {
            if (!face_alive_[f.value]) continue;
            for (VertexId v : tri_[f.value]) {
                if (remap[v.value] == UINT32_MAX) remap[v.value] = 0; // mark referenced
            }
        }
        for (VertexId v(0); v.value < pos_.size(); ++v.value)
            if (remap[v.value] != UINT32_MAX) {
                remap[v.value] = uint32_t(out.positions.size());
                out.positions.push_back(Vec3f(pos_[v.value]));
            }
        for (FaceId f(0); f.value < tri_.size(); ++f.value)
            if (face_alive_[f.value])
                for (VertexId v : tri_[f.value]) out.indices.push_back(remap[v.value]);
        return out;
    }

private:
    static uint64_t edgeKey(VertexId a, VertexId b) {
        return a < b ? (uint64_t(a.value) << 32) | b.value : (uint64_t(b.value) << 32) | a.value;
    }

    double edgeLength(VertexId a, VertexId b) const { return length(pos_[a.value] - pos_[b.value]); }

    // H0: umbrella curvature |mean(neighbours) − x| / mean edge length, normalised to [0, 1] by its
    // 99th percentile (one spike must not flatten everyone else's value); fidelity_scale_ is the
    // curvature relative to the mean, clamped to [1/4, 4], for the adaptive λ.
    void computeCurvature() {
        const size_t n = pos_.size();
        Aabb box;
        for (VertexId v(0); v.value < n; ++v.value)
            if (vertex_alive_[v.value]) box.expand(Vec3f(pos_[v.value]));
        diagonal_ = box.diagonal();
        std::vector<uint32_t> begin;
        std::vector<VertexId> nb;
        buildNeighbours(begin, nb);
        std::vector<double> kappa(n, 0.0);
        std::vector<double> present;
        for (VertexId v(0); v.value < n; ++v.value) {
            const uint32_t deg = begin[v.value + 1] - begin[v.value];
            if (!deg) continue;
            Vec3d mean;
            double len = 0.0;
            for (uint32_t i = begin[v.value]; i < begin[v.value + 1]; ++i) {
                mean += pos_[nb[i].value];
                len += edgeLength(v, nb[i]);
            }
            mean = mean / double(deg);
            len /= deg;
            kappa[v.value] = len > 0.0 ? length(mean - pos_[v.value]) / len : 0.0;
            present.push_back(kappa[v.value]);
        }
        curvature_.assign(n, 0.0);
        fidelity_scale_.assign(n, 1.0);
        if (present.empty()) return;
        double sum = 0.0;
        for (double k : present) sum += k;
        const double mean = sum / double(present.size());
        const size_t p99 = std::min(present.size() - 1, size_t(0.99 * double(present.size())));
        std::nth_element(present.begin(), present.begin() + p99, present.end());
        const double top = present[p99];
        for (size_t v = 0; v < n; ++v) {
            curvature_[v] = top > 0.0 ? std::min(1.0, kappa[v] / top) : 0.0;
            fidelity_scale_[v] = mean > 0.0 ? std::min(4.0, std::max(0.25, kappa[v] / mean)) : 1.0;
        }
    }

    // Sorted unique neighbours of every live vertex (CSR).
    void buildNeighbours(std::vector<uint32_t>& begin, std::vector<VertexId>& nb) const {
        const size_t n = pos_.size();
        begin.assign(n + 1, 0);
        nb.clear();
        std::vector<VertexId> ring;
        for (VertexId v(0); v.value < n; ++v.value) {
            neighbours(v, ring);
            nb.insert(nb.end(), ring.begin(), ring.end());
            begin[v.value + 1] = uint32_t(nb.size());
        }
    }

    void neighbours(VertexId v, std::vector<VertexId>& ring) const {
        ring.clear();
        for (FaceId f : faces_of_[v.value])
            for (VertexId w : tri_[f.value])
                if (w != v) ring.push_back(w);
        std::sort(ring.begin(), ring.end());
        ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    }

    std::vector<uint64_t> currentEdges() const {
        std::vector<uint64_t> keys;
        for (FaceId f(0); f.value < tri_.size(); ++f.value) {
            if (!face_alive_[f.value]) continue;
            const auto& t = tri_[f.value];
            for (int k = 0; k < 3; ++k) keys.push_back(edgeKey(t[k], t[(k + 1) % 3]));
        }
        std::sort(keys.begin(), keys.end());
        keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
        return keys;
    }

    template <class Heap> void pushEdge(Heap& heap, VertexId a, VertexId b) const {
        if (locked_[a.value] && locked_[b.value]) return; // can never collapse
        const double c = 0.5 * (curvature_[a.value] + curvature_[b.value]);
        heap.push({edgeLength(a, b) * (1.0 + c), a, b, stamp_[a.value], stamp_[b.value]});
    }

    bool tryCollapse(VertexId a, VertexId b, VertexId& survivor) {
        if (locked_[a.value] && locked_[b.value]) return false;
        // The two faces of the edge and their opposite vertices; the edge must be interior manifold.
        std::array<FaceId, 2> edge_faces;
        std::array<VertexId, 2> opposite;
        int count = 0;
        for (FaceId f : faces_of_[a.value]) {
            const auto& t = tri_[f.value];
            if (t[0] != b && t[1] != b && t[2] != b) continue;
            if (count == 2) return false;
            edge_faces[count] = f;
            for (VertexId w : t)
                if (w != a && w != b) opposite[count] = w;
            ++count;
        }
        if (count != 2 || opposite[0] == opposite[1]) return false;
        // (a) an opposite vertex of valence 3 would be left with two faces on top of each other.
        std::vector<VertexId> ring_a, ring_b, ring_w;
        for (VertexId w : opposite) {
            neighbours(w, ring_w);
            if (ring_w.size() <= 3) return false;
        }
        // (b) link condition: the only common neighbours are the two opposite vertices.
        neighbours(a, ring_a);
        neighbours(b, ring_b);
        size_t common = 0;
        for (size_t i = 0, j = 0; i < ring_a.size() && j < ring_b.size();) {
            if (ring_a[i] < ring_b[j])
                ++i;
            else if (ring_b[j] < ring_a[i])
                ++j;
            else {
                ++common;
                ++i;
                ++j;
            }
        }
        if (common != 2) return false;
        // Placement: a locked endpoint stays where it is; otherwise lerp by curvature.
        VertexId keep = a, gone = b;
        double t = 0.5 * (curvature_[b.value] - curvature_[a.value]) + 0.5;
        if (locked_[b.value]) {
            keep = b;
            gone = a;
            t = 0.0;
        } else if (locked_[a.value]) {
            t = 0.0;
        }
        const Vec3d target = pos_[keep.value] + (pos_[gone.value] - pos_[keep.value]) * t;
        // No face of either fan may flip or collapse to zero area.
        for (VertexId v : {a, b})
            for (FaceId f : faces_of_[v.value]) {
                if (f == edge_faces[0] || f == edge_faces[1]) continue;
                std::array<Vec3d, 3> p, q;
                for (int k = 0; k < 3; ++k) {
                    const VertexId w = tri_[f.value][k];
                    p[k] = pos_[w.value];
                    q[k] = (w == a || w == b) ? target : p[k];
                }
                const Vec3d n0 = cross(p[1] - p[0], p[2] - p[0]);
                const Vec3d n1 = cross(q[1] - q[0], q[2] - q[0]);
                if (!(dot(n0, n1) > 0.0)) return false;
            }
        for (FaceId f : edge_faces) {
            face_alive_[f.value] = 0;
            for (VertexId w : tri_[f.value]) {
                auto& list = faces_of_[w.value];
                list.erase(std::remove(list.begin(), list.end(), f), list.end());
            }
        }
        for (FaceId f : faces_of_[gone.value]) {
            for (VertexId& w : tri_[f.value])
                if (w == gone) w = keep;
            faces_of_[keep.value].push_back(f);
        }
        std::sort(faces_of_[keep.value].begin(), faces_of_[keep.value].end());
        faces_of_[gone.value].clear();
        vertex_alive_[gone.value] = 0;
        pos_[keep.value] = target;
        curvature_[keep.value] += (curvature_[gone.value] - curvature_[keep.value]) * t;
        fidelity_scale_[keep.value] += (fidelity_scale_[gone.value] - fidelity_scale_[keep.value]) * t;
        ++stamp_[keep.value];
        survivor = keep;
        return true;
    }

    std::vector<Vec3d> pos_;
    std::vector<std::array<VertexId, 3>> tri_;
    std::vector<std::vector<FaceId>> faces_of_; // live faces around each vertex, ascending
    std::vector<uint8_t> face_alive_, vertex_alive_, locked_;
    std::vector<uint32_t> stamp_;               // bumped whenever a vertex moves or gains faces
    std::vector<uint64_t> edges_;               // E0, sorted keys
    std::vector<double> curvature_;             // H0 normalised to [0, 1]
    std::vector<double> fidelity_scale_;        // H0 relative to its mean, clamped to [1/4, 4]
    double diagonal_ = 0.0;
};

} // namespace

Result<MultilevelOutput> simplifyMultilevel(const Mesh& mesh, const MultilevelOptions& options,
                                            Diagnostics& diagnostics) {
    if (!(options.percentage >= 0.0 && options.percentage < 100.0))
        return invalidInput("multilevel options: percentage " + formatNumber(options.percentage) +
                            ": expected a value in [0, 100)");
    if (options.iterations < 1) return invalidInput("multilevel options: iterations: expected at least 1");
    if (!std::isfinite(options.ple)) return invalidInput("multilevel options: ple: expected a finite number");
    if (!(options.time_step > 0.0 && options.time_step <= 1.0))
        return invalidInput("multilevel options: time_step " + formatNumber(options.time_step) +
                            ": expected a value in (0, 1]");
    if (!(options.lambda >= 0.0 && std::isfinite(options.lambda)))
        return invalidInput("multilevel options: lambda " + formatNumber(options.lambda) +
                            ": expected a finite non-negative number");
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, "multilevel"));
    MultilevelMesh work;
    LODBAKE_RETURN_IF_ERROR(work.init(mesh));
    MultilevelOutput out;
    out.input_triangles = work.faceCount();
    out.collapses_requested = size_t(options.percentage / 100.0 * double(work.edgeCount()) / 3.0);
    out.length_threshold = work.lengthThreshold(options.percentage);
    for (uint32_t it = 0; it < options.iterations; ++it) {
        if (options.has_smoothing) work.smooth(options);
        if (!options.has_decimation) continue;
        // ne = edgetocollapse / OUT_ITS; the last level takes what the others could not do.
        const size_t budget = it + 1 == options.iterations
                                  ? out.collapses_requested - out.collapses
                                  : std::min(out.collapses_requested - out.collapses,
                                             out.collapses_requested / options.iterations);
        out.collapses += work.decimate(budget, options.is_sorted, out.length_threshold, out.collapses_refused);
    }
    out.reached_target = !options.has_decimation || out.collapses >= out.collapses_requested;
    if (!out.reached_target)
        diagnostics.note("multilevel: " + std::to_string(out.collapses) + " of " +
                         std::to_string(out.collapses_requested) + " collapses done: " +
                         (options.is_sorted ? std::string("no valid collapse left")
                                            : "no valid edge shorter than the threshold " +
                                                  formatNumber(out.length_threshold) + " left"));
    out.mesh = work.extract();
    return out;
}

} // namespace lodbake
