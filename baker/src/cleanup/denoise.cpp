// Denoising: Laplacian smoothing (umbrella, cotangent after Meyer et al. 2003, Fujiwara 1995 edge
// lengths), Taubin 1995 λ|μ smoothing, and the p-Laplacian diffusion with curvature-adaptive
// fidelity of Guerra 2012 (seed 003). Feature-preserving mode: vertices on a crease line move only
// along the crease tangent and crease corners stay fixed, so dihedral angles at creases survive.
#include "lodbake/cleanup/denoise.h"

#include <algorithm>
#include <cmath>

#include "mesh_edit.h"

namespace lodbake {

using namespace cleanup_detail;

PassCounters DenoiseReport::counters() const {
    return {{"vertices_moved", vertices_moved},
            {"fixed_vertices", fixed_vertices},
            {"feature_edges", feature_edges},
            {"roughness_before_millideg", uint64_t(std::llround(roughness_before_deg * 1000.0))},
            {"roughness_after_millideg", uint64_t(std::llround(roughness_after_deg * 1000.0))},
            {"mean_displacement_1e9_diag", uint64_t(std::llround(mean_displacement_rel * 1e9))},
            {"max_displacement_1e9_diag", uint64_t(std::llround(max_displacement_rel * 1e9))}};
}

double meanDihedralDeviation(const Mesh& mesh) {
    const EdgeTable table = buildEdgeTable(mesh);
    double sum = 0.0;
    size_t count = 0;
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        if (table.uses(e) != 2) continue;
        const uint32_t* c = &table.corners[table.begin[e]];
        const Vec3d n0 = normalize(faceNormal(mesh, c[0] / 3)), n1 = normalize(faceNormal(mesh, c[1] / 3));
        const double d = std::max(-1.0, std::min(1.0, dot(n0, n1)));
        sum += std::acos(d);
        ++count;
    }
    return count ? sum / double(count) * 180.0 / M_PI : 0.0;
}

namespace {

enum class VertexRole : uint8_t { Free, Crease, Fixed };

// What each vertex may do during smoothing; a crease vertex slides between its two crease neighbours.
struct VertexRoles {
    std::vector<VertexRole> role;
    std::vector<std::array<uint32_t, 2>> crease_nb;
};

// Working positions: `x` the current ones, `x0` the input, `next` the scratch for a Jacobi step.
struct Positions {
    std::vector<Vec3d> x, x0, next;
};

// Per-vertex weighted neighbour list parallel to the adjacency.
void computeWeights(const Mesh& mesh, const std::vector<Vec3d>& x, const VertexAdjacency& adj, LaplacianWeights kind,
                    std::vector<double>& w) {
    w.assign(adj.neighbours.size(), 1.0);
    if (kind == LaplacianWeights::Umbrella) return;
    if (kind == LaplacianWeights::Fujiwara) {
        for (size_t v = 0; v + 1 < adj.begin.size(); ++v)
            for (uint32_t i = adj.begin[v]; i < adj.begin[v + 1]; ++i) {
                const double l = length(x[adj.neighbours[i]] - x[v]);
                w[i] = l > 0 ? 1.0 / l : 0.0;
            }
        return;
    }
    std::fill(w.begin(), w.end(), 0.0);
    auto slot = [&](uint32_t v, uint32_t u) -> double& {
        auto b = adj.neighbours.begin() + adj.begin[v], e = adj.neighbours.begin() + adj.begin[v + 1];
        return w[size_t(std::lower_bound(b, e, u) - adj.neighbours.begin())];
    };
    for (size_t f = 0; f < mesh.faceCount(); ++f) {
        if (hasRepeatedIndex(mesh, f)) continue;
        for (int k = 0; k < 3; ++k) {
            const uint32_t o = mesh.indices[3 * f + k], a = mesh.indices[3 * f + (k + 1) % 3],
                           b = mesh.indices[3 * f + (k + 2) % 3];
            const Vec3d u = x[a] - x[o], v = x[b] - x[o];
            const double s = length(cross(u, v));
            const double cot = s > 0 ? dot(u, v) / s : 0.0;
            slot(a, b) += 0.5 * cot;
            slot(b, a) += 0.5 * cot;
        }
    }
    for (double& wi : w) wi = std::max(wi, 0.0);
}

// Fixed: unreferenced, non-finite, on a pinned boundary or a non-manifold edge, or a crease corner
// (feature degree other than 2); Crease: on exactly two feature edges; Free otherwise.
VertexRoles classifyVertices(const Mesh& mesh, const EdgeTable& table, const DenoiseOptions& options,
                             DenoiseReport& r) {
    const size_t n = mesh.vertexCount();
    const std::vector<uint8_t> on_boundary = boundaryVertices(mesh, table);
    VertexRoles roles;
    std::vector<VertexRole>& role = roles.role;
    std::vector<std::array<uint32_t, 2>>& crease_nb = roles.crease_nb;
    role.assign(n, VertexRole::Free);
    crease_nb.assign(n, {kNone, kNone});
    std::vector<uint8_t> referenced(n, 0);
    for (uint32_t i : mesh.indices) referenced[i] = 1;
    for (size_t v = 0; v < n; ++v)
        if (!referenced[v] || (options.fix_boundary && on_boundary[v]) || !isFinite(mesh.positions[v]))
            role[v] = VertexRole::Fixed;
    // Non-manifold edges pin their vertices: the smoothing has no single surface there.
    for (uint32_t e = 0; e < table.edgeCount(); ++e)
        if (table.uses(e) > 2) {
            const uint32_t c = table.corners[table.begin[e]];
            role[halfStart(mesh, c)] = role[halfEnd(mesh, c)] = VertexRole::Fixed;
        }
    if (options.preserve_features) {
        const double cos_limit = std::cos(options.feature_angle_deg * M_PI / 180.0);
        std::vector<uint32_t> feature_degree(n, 0);
        for (uint32_t e = 0; e < table.edgeCount(); ++e) {
            if (table.uses(e) != 2) continue;
            const uint32_t* c = &table.corners[table.begin[e]];
            const Vec3d n0 = normalize(faceNormal(mesh, c[0] / 3)), n1 = normalize(faceNormal(mesh, c[1] / 3));
            if (dot(n0, n1) >= cos_limit) continue;
            ++r.feature_edges;
            const uint32_t a = halfStart(mesh, c[0]), b = halfEnd(mesh, c[0]);
            for (auto [v, u] : {std::make_pair(a, b), std::make_pair(b, a)}) {
                if (feature_degree[v] < 2) crease_nb[v][feature_degree[v]] = u;
                ++feature_degree[v];
            }
        }
        for (size_t v = 0; v < n; ++v) {
            if (role[v] == VertexRole::Fixed || feature_degree[v] == 0) continue;
            role[v] = feature_degree[v] == 2 ? VertexRole::Crease : VertexRole::Fixed;
        }
    }
    for (VertexRole ro : role) r.fixed_vertices += ro == VertexRole::Fixed;
    return roles;
}

// One explicit (Jacobi) step x += step * (weighted mean of neighbours - x), constrained by role.
void laplacianStep(Positions& p, const VertexRoles& roles, const VertexAdjacency& adj, double step,
                   const std::vector<double>& weights) {
    std::vector<Vec3d>& x = p.x;
    std::vector<Vec3d>& next = p.next;
    const size_t n = x.size();
    for (size_t v = 0; v < n; ++v) {
        next[v] = x[v];
        if (roles.role[v] == VertexRole::Fixed) continue;
        Vec3d delta;
        if (roles.role[v] == VertexRole::Crease) {
            const Vec3d q0 = x[roles.crease_nb[v][0]], q1 = x[roles.crease_nb[v][1]];
            delta = (q0 + q1) * 0.5 - x[v];
            const Vec3d t = normalize(q1 - q0);
            delta = t * dot(delta, t);
        } else {
            double ws = 0.0;
            Vec3d s;
            for (uint32_t i = adj.begin[v]; i < adj.begin[v + 1]; ++i) {
                s += x[adj.neighbours[i]] * weights[i];
                ws += weights[i];
            }
            if (ws <= 0.0) continue;
            delta = s / ws - x[v];
        }
        next[v] = x[v] + delta * step;
    }
    x.swap(next);
}

// Faces around each vertex, as a CSR list.
struct VertexFaces {
    std::vector<uint32_t> begin, faces;
};

VertexFaces buildVertexFaces(const Mesh& mesh) {
    const size_t n = mesh.vertexCount();
    VertexFaces vf;
    vf.begin.assign(n + 1, 0);
    for (uint32_t i : mesh.indices) ++vf.begin[i + 1];
    for (size_t v = 0; v < n; ++v) vf.begin[v + 1] += vf.begin[v];
    vf.faces.resize(mesh.indices.size());
    std::vector<uint32_t> fill(vf.begin.begin(), vf.begin.end() - 1);
    for (size_t c = 0; c < mesh.indices.size(); ++c) vf.faces[fill[mesh.indices[c]]++] = uint32_t(c / 3);
    return vf;
}

// Dihedral angle in degrees between the normals of faces f0 and f1 at positions x.
double dihedralDeg(const Mesh& mesh, const std::vector<Vec3d>& x, uint32_t f0, uint32_t f1) {
    const uint32_t* a = &mesh.indices[3 * f0];
    const uint32_t* b = &mesh.indices[3 * f1];
    const Vec3d n0 = normalize(cross(x[a[1]] - x[a[0]], x[a[2]] - x[a[0]]));
    const Vec3d n1 = normalize(cross(x[b[1]] - x[b[0]], x[b[2]] - x[b[0]]));
    return std::acos(std::max(-1.0, std::min(1.0, dot(n0, n1)))) * 180.0 / M_PI;
}

// Crease guard: the two faces of every crease edge, with the input dihedral angle.
struct Crease {
    uint32_t f0, f1;
    double angle;
};

std::vector<Crease> findCreases(const Mesh& mesh, const EdgeTable& table, const std::vector<Vec3d>& x,
                                double feature_angle_deg) {
    std::vector<Crease> creases;
    for (uint32_t e = 0; e < table.edgeCount(); ++e) {
        if (table.uses(e) != 2) continue;
        const uint32_t* c = &table.corners[table.begin[e]];
        const double a = dihedralDeg(mesh, x, c[0] / 3, c[1] / 3);
        if (a > feature_angle_deg) creases.push_back({c[0] / 3, c[1] / 3, a});
    }
    return creases;
}

// Three passes of Sun et al.'s bilateral normal filter over the unit face normals `fn`.
void filterFaceNormals(const Mesh& mesh, const VertexFaces& vf, const std::vector<double>& area, double cos_limit,
                       std::vector<Vec3d>& fn, std::vector<Vec3d>& filtered) {
    const size_t face_count = mesh.faceCount();
    for (int pass = 0; pass < 3; ++pass) {
        for (size_t f = 0; f < face_count; ++f) {
            Vec3d s = fn[f] * area[f];
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = mesh.indices[3 * f + k];
                for (uint32_t i = vf.begin[v]; i < vf.begin[v + 1]; ++i) {
                    const uint32_t g = vf.faces[i];
                    // Sun et al.'s weight: zero at the feature angle, growing quadratically inside it.
                    const double d = dot(fn[f], fn[g]) - cos_limit;
                    if (g != f && d > 0) s += fn[g] * (area[g] * d * d / ((1 - cos_limit) * (1 - cos_limit)));
                }
            }
            filtered[f] = length(s) > 0 ? normalize(s) : fn[f];
        }
        fn.swap(filtered);
    }
}

// One step moving free vertices to fit the filtered normals `fn`; crease vertices slide along the crease.
void fitVerticesToNormals(const Mesh& mesh, const VertexFaces& vf, const VertexRoles& roles,
                          const std::vector<Vec3d>& fn, double lambda, Positions& p) {
    std::vector<Vec3d>& x = p.x;
    std::vector<Vec3d>& next = p.next;
    const size_t n = x.size();
    for (size_t v = 0; v < n; ++v) {
        next[v] = x[v];
        if (roles.role[v] == VertexRole::Fixed) continue;
        if (roles.role[v] == VertexRole::Crease) {
            const Vec3d q0 = x[roles.crease_nb[v][0]], q1 = x[roles.crease_nb[v][1]];
            const Vec3d t = normalize(q1 - q0);
            next[v] = x[v] + t * (dot((q0 + q1) * 0.5 - x[v], t) * lambda);
            continue;
        }
        const uint32_t count = vf.begin[v + 1] - vf.begin[v];
        if (!count) continue;
        Vec3d d;
        for (uint32_t i = vf.begin[v]; i < vf.begin[v + 1]; ++i) {
            const uint32_t f = vf.faces[i];
            const uint32_t* t = &mesh.indices[3 * f];
            const Vec3d c = (x[t[0]] + x[t[1]] + x[t[2]]) / 3.0;
            d += fn[f] * dot(fn[f], c - x[v]);
        }
        next[v] = x[v] + d / double(count);
    }
    x.swap(next); // `next` now holds the previous positions
}

// Undo the last step around any crease whose dihedral drifted too far, and pin those vertices;
// repeat, since an undo can disturb a crease sharing a vertex. `p.next` holds the previous positions.
void undoCreaseDrift(const Mesh& mesh, const std::vector<Crease>& creases, double max_change_deg, Positions& p,
                     VertexRoles& roles, DenoiseReport& r) {
    for (bool changed = true; changed;) {
        changed = false;
        for (const Crease& cr : creases) {
            if (std::fabs(dihedralDeg(mesh, p.x, cr.f0, cr.f1) - cr.angle) <= max_change_deg) continue;
            for (uint32_t f : {cr.f0, cr.f1})
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = mesh.indices[3 * f + k];
                    if (p.x[v] != p.next[v]) changed = true;
                    p.x[v] = p.next[v];
                    if (roles.role[v] != VertexRole::Fixed) {
                        roles.role[v] = VertexRole::Fixed;
                        ++r.fixed_vertices;
                    }
                }
        }
    }
}

// Sun et al. 2007, "Fast and effective feature-preserving mesh denoising": face normals are
// averaged only with neighbours (sharing a vertex) within the feature angle, so nothing is
// averaged across a crease; free vertices then move to fit the filtered normals, which
// leaves an already clean surface where it is. Crease vertices slide along the crease.
void smoothPreservingFeatures(const Mesh& mesh, const EdgeTable& table, const DenoiseOptions& options,
                              VertexRoles& roles, Positions& p, DenoiseReport& r) {
    const size_t face_count = mesh.faceCount();
    const VertexFaces vf = buildVertexFaces(mesh);
    const double cos_limit = std::cos(options.feature_angle_deg * M_PI / 180.0);
    const std::vector<Crease> creases = findCreases(mesh, table, p.x, options.feature_angle_deg);
    std::vector<Vec3d> fn(face_count), filtered(face_count);
    std::vector<double> area(face_count);
    for (uint32_t it = 0; it < options.iterations; ++it) {
        for (size_t f = 0; f < face_count; ++f) {
            const uint32_t* t = &mesh.indices[3 * f];
            const Vec3d c = cross(p.x[t[1]] - p.x[t[0]], p.x[t[2]] - p.x[t[0]]);
            area[f] = 0.5 * length(c);
            fn[f] = normalize(c);
        }
        filterFaceNormals(mesh, vf, area, cos_limit, fn, filtered);
        for (int step = 0; step < 5; ++step) {
            fitVerticesToNormals(mesh, vf, roles, fn, options.lambda, p);
            undoCreaseDrift(mesh, creases, options.max_crease_change_deg, p, roles, r);
        }
    }
}

// Per-vertex fidelity weight; with adaptive fidelity it is scaled by a curvature proxy
// (|umbrella Laplacian| / mean incident edge length, on the input) relative to its mean, clamped to [1/4, 4].
std::vector<double> vertexFidelity(const VertexAdjacency& adj, const std::vector<Vec3d>& x0,
                                   const DenoiseOptions& options) {
    const size_t n = x0.size();
    std::vector<double> fidelity(n, options.fidelity);
    if (!options.adaptive_fidelity) return fidelity;
    std::vector<double> kappa(n, 0.0);
    double sum = 0.0;
    size_t count = 0;
    for (size_t v = 0; v < n; ++v) {
        const uint32_t deg = adj.begin[v + 1] - adj.begin[v];
        if (!deg) continue;
        Vec3d s;
        double len = 0.0;
        for (uint32_t i = adj.begin[v]; i < adj.begin[v + 1]; ++i) {
            s += x0[adj.neighbours[i]];
            len += length(x0[adj.neighbours[i]] - x0[v]);
        }
        len /= deg;
        kappa[v] = len > 0 ? length(s / double(deg) - x0[v]) / len : 0.0;
        sum += kappa[v];
        ++count;
    }
    const double mean = count ? sum / double(count) : 0.0;
    for (size_t v = 0; v < n; ++v)
        fidelity[v] = mean > 0 ? options.fidelity * std::min(4.0, std::max(0.25, kappa[v] / mean)) : options.fidelity;
    return fidelity;
}

// p-Laplacian diffusion (Guerra 2012): weights |x_u - x_v|^(p-2), pulled back towards the input by
// the per-vertex fidelity.
void smoothPLaplacian(const Mesh& mesh, const VertexAdjacency& adj, const DenoiseOptions& options,
                      const VertexRoles& roles, Positions& p) {
    const size_t n = p.x.size();
    const std::vector<double> fidelity = vertexFidelity(adj, p.x0, options);
    std::vector<double> wp(adj.neighbours.size());
    const double scale = computeBounds(mesh).diagonal() * 1e-9 + 1e-30; // keeps |d|^(p-2) finite
    for (uint32_t outer = 0; outer < options.outer_iterations; ++outer)
        for (int inner = 0; inner < 10; ++inner) {
            for (size_t v = 0; v < n; ++v)
                for (uint32_t i = adj.begin[v]; i < adj.begin[v + 1]; ++i)
                    wp[i] = std::pow(std::max(length(p.x[adj.neighbours[i]] - p.x[v]), scale), options.p - 2.0);
            laplacianStep(p, roles, adj, options.time_step, wp);
            for (size_t v = 0; v < n; ++v)
                if (roles.role[v] != VertexRole::Fixed) p.x[v] -= (p.x[v] - p.x0[v]) * (options.time_step * fidelity[v]);
        }
}

// Laplacian smoothing, and Taubin's λ|μ variant.
void smoothLaplacian(const Mesh& mesh, const VertexAdjacency& adj, const DenoiseOptions& options,
                     const VertexRoles& roles, Positions& p) {
    std::vector<double> w;
    const bool static_weights = options.weights == LaplacianWeights::Umbrella;
    if (static_weights) computeWeights(mesh, p.x, adj, options.weights, w);
    for (uint32_t it = 0; it < options.iterations; ++it) {
        if (!static_weights) computeWeights(mesh, p.x, adj, options.weights, w);
        laplacianStep(p, roles, adj, options.lambda, w);
        if (options.method == DenoiseMethod::Taubin) {
            if (!static_weights) computeWeights(mesh, p.x, adj, options.weights, w);
            laplacianStep(p, roles, adj, options.mu, w);
        }
    }
}

// Writes the smoothed positions back and records the displacements relative to the bounds diagonal.
void storePositions(const std::vector<Vec3d>& x, const std::vector<Vec3d>& x0, Mesh& mesh, DenoiseReport& r) {
    const double diag = computeBounds(mesh).diagonal();
    double sum = 0.0;
    for (size_t v = 0; v < x.size(); ++v) {
        const Vec3f p(x[v]);
        if (p == mesh.positions[v]) continue;
        mesh.positions[v] = p;
        ++r.vertices_moved;
        const double d = length(x[v] - x0[v]) / (diag > 0 ? diag : 1.0);
        sum += d;
        r.max_displacement_rel = std::max(r.max_displacement_rel, d);
    }
    r.mean_displacement_rel = r.vertices_moved ? sum / double(r.vertices_moved) : 0.0;
}

} // namespace

DenoiseReport denoise(Mesh& mesh, const DenoiseOptions& options) {
    DenoiseReport r;
    const size_t n = mesh.vertexCount();
    if (mesh.faceCount() == 0 || n == 0) return r;
    r.roughness_before_deg = meanDihedralDeviation(mesh);
    const EdgeTable table = buildEdgeTable(mesh);
    const VertexAdjacency adj = buildVertexAdjacency(mesh);
    VertexRoles roles = classifyVertices(mesh, table, options, r);

    Positions p;
    p.x.resize(n);
    p.x0.resize(n);
    p.next.resize(n);
    for (size_t v = 0; v < n; ++v) p.x[v] = p.x0[v] = toDouble(mesh.positions[v]);

    if (options.preserve_features)
        smoothPreservingFeatures(mesh, table, options, roles, p, r);
    else if (options.method == DenoiseMethod::PLaplacian)
        smoothPLaplacian(mesh, adj, options, roles, p);
    else
        smoothLaplacian(mesh, adj, options, roles, p);

    storePositions(p.x, p.x0, mesh, r);
    r.roughness_after_deg = meanDihedralDeviation(mesh);
    return r;
}

} // namespace lodbake
