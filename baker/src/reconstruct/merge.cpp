// Range-scan merging (merge.h): sample normals, depth choice, the Poisson call through
// liblodbake_open3d, density trimming, colour transfer and the distance report.
#include "lodbake/reconstruct/merge.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <numeric>
#include <tuple>
#include <utility>
#include <vector>

#include "core/module_loader.h"
#include "core/parallel.h"
#include "lodbake/core/bvh.h"
#include "lodbake/core/mapped_array.h"
#include "reconstruct/open3d_module.h"

namespace lodbake {

namespace {

struct Loaded {
    const open3d_module::Api* api = nullptr;
    std::string error;
};

const Loaded& loadModule() {
    static Loaded loaded;
    static std::once_flag once;
    std::call_once(once, [] {
        const detail::ModuleSpec spec{"LODBAKE_OPEN3D_MODULE", LODBAKE_OPEN3D_MODULE_NAME,
                                      LODBAKE_OPEN3D_MODULE_BUILD_PATH, "lodbake_open3d_api", "Open3D"};
        loaded.api = detail::openModule<open3d_module::Api>(spec, open3d_module::kApiVersion, &loaded.error);
    });
    return loaded;
}

// Per-vertex labels and flags live in storage mapped on their own: the overlap test runs on every
// bake with --merge auto, and freeing blocks of this size from malloc would raise glibc's adaptive
// mmap threshold, so that the bake's later arrays of that size stay resident in its arenas.
using VertexLabels = detail::MappedArray<uint32_t, detail::MappedPages::Small>;
using VertexFlags = detail::MappedArray<uint8_t, detail::MappedPages::Small>;

uint32_t findRoot(VertexLabels& parent, uint32_t v) {
    while (parent[v] != v) {
        parent[v] = parent[parent[v]];
        v = parent[v];
    }
    return v;
}

void unite(VertexLabels& parent, uint32_t x, uint32_t y) {
    uint32_t a = findRoot(parent, x), b = findRoot(parent, y);
    if (a == b) return;
    if (b < a) std::swap(a, b);
    parent[b] = a;
}

// Component of every vertex (the smallest vertex id in it; unreferenced vertices are their own).
// With `join_positions`, vertices at one position are joined: attribute seams (UV charts) split
// vertices, not surfaces.
VertexLabels vertexComponents(const Mesh& mesh, bool join_positions = true) {
    VertexLabels parent(mesh.vertexCount());
    std::iota(parent.begin(), parent.end(), 0u);
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
        for (size_t k = 1; k < 3; ++k) unite(parent, mesh.indices[i], mesh.indices[i + k]);
    if (!join_positions) {
        for (uint32_t v = 0; v < parent.size(); ++v) parent[v] = findRoot(parent, v);
        return parent;
    }
    VertexLabels order(mesh.vertexCount());
    std::iota(order.begin(), order.end(), 0u);
    auto key = [&](uint32_t v) {
        const Vec3f& p = mesh.positions[v];
        return std::make_tuple(p.x, p.y, p.z, v);
    };
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    for (size_t i = 1; i < order.size(); ++i) {
        const Vec3f& a = mesh.positions[order[i - 1]];
        const Vec3f& b = mesh.positions[order[i]];
        if (a.x == b.x && a.y == b.y && a.z == b.z) unite(parent, order[i - 1], order[i]);
    }
    for (uint32_t v = 0; v < parent.size(); ++v) parent[v] = findRoot(parent, v);
    return parent;
}

VertexFlags referencedVertices(const Mesh& mesh) {
    VertexFlags used(mesh.vertexCount(), 0);
    for (uint32_t i : mesh.indices) used[i] = 1;
    return used;
}

// Median edge length of the triangles (every edge of every triangle, shared edges twice).
double medianEdgeLength(const Mesh& mesh) {
    std::vector<double> lengths;
    lengths.reserve(mesh.indices.size());
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3)
        for (size_t k = 0; k < 3; ++k) {
            const Vec3d a = toDouble(mesh.positions[mesh.indices[i + k]]);
            const Vec3d b = toDouble(mesh.positions[mesh.indices[i + (k + 1) % 3]]);
            const double l = length(b - a);
            if (l > 0.0) lengths.push_back(l);
        }
    if (lengths.empty()) return 0.0;
    const size_t mid = lengths.size() / 2;
    std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(mid), lengths.end());
    return lengths[mid];
}

double triangleArea(const Vec3d& a, const Vec3d& b, const Vec3d& c) { return 0.5 * length(cross(b - a, c - a)); }

double surfaceArea(const std::vector<Vec3f>& positions, const std::vector<uint32_t>& indices) {
    double area = 0.0;
    for (size_t i = 0; i + 2 < indices.size(); i += 3)
        area += triangleArea(toDouble(positions[indices[i]]), toDouble(positions[indices[i + 1]]),
                             toDouble(positions[indices[i + 2]]));
    return area;
}

// The samples: every referenced vertex with a non-zero area-weighted normal of its triangles
// (the range-grid triangulation winds them towards the scanner, so these face outwards).
struct Samples {
    std::vector<float> positions, normals;
    std::vector<uint32_t> vertex; // input vertex of each sample
};

Samples collectSamples(const Mesh& mesh) {
    std::vector<Vec3d> sum(mesh.vertexCount(), Vec3d(0.0, 0.0, 0.0));
    for (size_t i = 0; i + 2 < mesh.indices.size(); i += 3) {
        const uint32_t a = mesh.indices[i], b = mesh.indices[i + 1], c = mesh.indices[i + 2];
        const Vec3d pa = toDouble(mesh.positions[a]);
        const Vec3d n = cross(toDouble(mesh.positions[b]) - pa, toDouble(mesh.positions[c]) - pa);
        sum[a] = sum[a] + n;
        sum[b] = sum[b] + n;
        sum[c] = sum[c] + n;
    }
    Samples s;
    for (uint32_t v = 0; v < mesh.vertexCount(); ++v) {
        const double len = length(sum[v]);
        if (!(len > 0.0)) continue;
        const Vec3f& p = mesh.positions[v];
        s.positions.insert(s.positions.end(), {p.x, p.y, p.z});
        s.normals.insert(s.normals.end(), {float(sum[v].x / len), float(sum[v].y / len), float(sum[v].z / len)});
        s.vertex.push_back(v);
    }
    return s;
}

size_t countViews(const Mesh& mesh) {
    if (mesh.submeshes.size() > 1) return mesh.submeshes.size();
    const VertexLabels comp = vertexComponents(mesh);
    const VertexFlags used = referencedVertices(mesh);
    size_t n = 0;
    for (uint32_t v = 0; v < comp.size(); ++v) n += used[v] && comp[v] == v;
    return n;
}

int pickDepth(const Aabb& box, double spacing, const MergeOptions& options) {
    if (options.depth > 0) return options.depth;
    const Vec3f e = box.extent();
    const double cube = double(options.scale) * double(std::max({e.x, e.y, e.z}));
    int depth = options.min_depth;
    while (depth < options.max_depth && cube / std::ldexp(1.0, depth) > options.cell_per_spacing * spacing) ++depth;
    return depth;
}

// Removes the triangles with a vertex whose density lies more than `trim_log2` below the median
// (Open3D's density is the octree depth at which the samples around a vertex were splatted, so
// one unit is a factor of two in sample spacing), then the vertices no triangle uses.
void trimByDensity(open3d_module::PoissonOutput& out, double trim_log2) {
    std::vector<double> sorted = out.density;
    const size_t mid = sorted.size() / 2;
    std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(mid), sorted.end());
    const double threshold = sorted[mid] - trim_log2;
    std::vector<uint32_t> kept;
    kept.reserve(out.indices.size());
    for (size_t i = 0; i + 2 < out.indices.size(); i += 3) {
        const uint32_t a = out.indices[i], b = out.indices[i + 1], c = out.indices[i + 2];
        if (a == b || b == c || a == c) continue;
        if (out.density[a] < threshold || out.density[b] < threshold || out.density[c] < threshold) continue;
        kept.insert(kept.end(), {a, b, c});
    }
    out.indices = std::move(kept);
}

// Carries colours over: each vertex of `merged` takes the colour of the input corner nearest to its
// closest point on the input surface.
Status transferColors(const Mesh& input, const TriangleBvh& input_bvh, Mesh& merged) {
    merged.colors.assign(merged.vertexCount(), Vec4f{1.0f, 1.0f, 1.0f, 1.0f});
    return parallelFor(merged.vertexCount(), 1024, [&](size_t v) {
        const ClosestHit hit = input_bvh.closest(toDouble(merged.positions[v]));
        if (!hit.isFound()) return;
        const std::array<VertexId, 3> t = input.triangle(hit.face);
        uint32_t best = t[0].value;
        double best_d = INFINITY;
        for (const VertexId& c : t) {
            const double d = length(toDouble(input.positions[c.value]) - hit.point);
            if (d < best_d) {
                best_d = d;
                best = c.value;
            }
        }
        merged.colors[v] = input.colors[best];
    });
}

// Mean and 95th percentile of the distance from the samples to `merged`.
Status measureDistances(const Samples& samples, const TriangleBvh& merged_bvh, uint32_t max_samples,
                        MergeReport& report) {
    const size_t n = samples.vertex.size();
    const size_t stride = max_samples && n > max_samples ? (n + max_samples - 1) / max_samples : 1;
    const size_t count = (n + stride - 1) / stride;
    std::vector<double> d(count, 0.0);
    LODBAKE_RETURN_IF_ERROR(parallelFor(count, 1024, [&](size_t i) {
        const size_t s = i * stride;
        const Vec3d p(samples.positions[3 * s], samples.positions[3 * s + 1], samples.positions[3 * s + 2]);
        const ClosestHit hit = merged_bvh.closest(p);
        d[i] = hit.isFound() ? std::sqrt(hit.distance_sq) : INFINITY;
    }));
    double sum = 0.0;
    for (double x : d) sum += x;
    report.mean_distance = count ? sum / double(count) : 0.0;
    const size_t k = count ? std::min(count - 1, size_t(std::ceil(0.95 * double(count))) - 1) : 0;
    if (count) {
        std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(k), d.end());
        report.p95_distance = d[k];
    }
    return Status::okStatus();
}

// The Poisson output as a Mesh: used vertices only, in the order of their first use.
Mesh compactSurface(const open3d_module::PoissonOutput& out) {
    Mesh mesh;
    std::vector<uint32_t> remap(out.positions.size() / 3, UINT32_MAX);
    mesh.indices.reserve(out.indices.size());
    for (uint32_t i : out.indices) {
        if (remap[i] == UINT32_MAX) {
            remap[i] = uint32_t(mesh.positions.size());
            mesh.positions.push_back({out.positions[3 * size_t(i)], out.positions[3 * size_t(i) + 1],
                                      out.positions[3 * size_t(i) + 2]});
        }
        mesh.indices.push_back(remap[i]);
    }
    return mesh;
}

Status checkInput(const Mesh& mesh, const Samples& samples, const MergeOptions& options, const std::string& name) {
    if (samples.vertex.size() < options.min_points)
        return invalidInput(name + ": merge: expected at least " + std::to_string(options.min_points) +
                            " samples on triangles, got " + std::to_string(samples.vertex.size()));
    if (samples.vertex.size() > options.max_points)
        return resourceLimit(name + ": merge: " + std::to_string(samples.vertex.size()) +
                             " samples, more than the limit of " + std::to_string(options.max_points));
    if (options.depth != 0 && (options.depth < 1 || options.depth > options.max_depth))
        return invalidInput(name + ": merge: depth " + std::to_string(options.depth) + ": expected 1.." +
                            std::to_string(options.max_depth));
    if (mesh.indices.empty()) return invalidInput(name + ": merge: expected triangles, got none");
    return Status::okStatus();
}

} // namespace

std::vector<std::string> mergeReportLines(const MergeReport& r) {
    const double diag = r.diagonal > 0.0 ? r.diagonal : 1.0;
    const double total = r.area + r.trimmed_area;
    char buf[3][320];
    std::snprintf(buf[0], sizeof(buf[0]), "merged %zu %s, %zu points at octree depth %d (sample spacing %.6g)",
                  r.views, r.views_are_scans ? "scans" : "sheets (connected components)", r.points, r.depth,
                  r.sample_spacing);
    std::snprintf(buf[1], sizeof(buf[1]),
                  "surface of %zu triangles, area %.6g; density trim removed %zu triangles, area %.6g (%.2f%%)",
                  r.faces, r.area, r.faces_before_trim - r.faces, r.trimmed_area,
                  total > 0.0 ? 100.0 * r.trimmed_area / total : 0.0);
    std::snprintf(buf[2], sizeof(buf[2]),
                  "input samples to the merged surface: mean %.6g (%.4f%% of the diagonal %.6g), 95th percentile "
                  "%.6g (%.4f%%)",
                  r.mean_distance, 100.0 * r.mean_distance / diag, r.diagonal, r.p95_distance,
                  100.0 * r.p95_distance / diag);
    return {buf[0], buf[1], buf[2]};
}

double overlappingSheetFraction(const Mesh& mesh) {
    if (mesh.indices.size() % 3 != 0) return 0.0;
    for (uint32_t i : mesh.indices)
        if (i >= mesh.vertexCount()) return 0.0; // inconsistent: the repair that follows reports it
    const VertexFlags used = referencedVertices(mesh);
    auto countRoots = [&](const VertexLabels& c) {
        size_t n = 0;
        for (uint32_t v = 0; v < c.size(); ++v) n += used[v] && c[v] == v;
        return n;
    };
    // Most inputs are one connected surface: that needs no sort of the positions.
    if (countRoots(vertexComponents(mesh, false)) < 2) return 0.0;
    const VertexLabels comp = vertexComponents(mesh);
    size_t roots = 0, referenced = 0;
    for (uint32_t v = 0; v < comp.size(); ++v) {
        roots += used[v] && comp[v] == v;
        referenced += used[v];
    }
    if (roots < 2) return 0.0;
    const double spacing = medianEdgeLength(mesh);
    const Aabb box = computeBounds(mesh);
    if (!(spacing > 0.0) || box.isEmpty()) return 0.0;
    // Cells of two sample spacings: two sheets of one surface, registered to within a spacing, put
    // their samples into the same cells; pieces that merely touch share only the cells along the contact.
    const double cell = 2.0 * spacing;
    const Vec3f e = box.extent();
    const double cells_per_axis = double(std::max({e.x, e.y, e.z})) / cell + 1.0;
    if (cells_per_axis > double(1u << 21)) return 0.0; // finer than a 64-bit key holds: not a scan set
    std::vector<std::pair<uint64_t, uint32_t>> keyed; // (cell, component)
    std::vector<uint64_t> vertex_cell(mesh.vertexCount(), 0);
    for (uint32_t v = 0; v < mesh.vertexCount(); ++v) {
        if (!used[v]) continue;
        const Vec3f& p = mesh.positions[v];
        const uint64_t x = uint64_t((double(p.x) - double(box.min.x)) / cell);
        const uint64_t y = uint64_t((double(p.y) - double(box.min.y)) / cell);
        const uint64_t z = uint64_t((double(p.z) - double(box.min.z)) / cell);
        vertex_cell[v] = (x << 42) | (y << 21) | z;
        keyed.push_back({vertex_cell[v], comp[v]});
    }
    std::sort(keyed.begin(), keyed.end());
    keyed.erase(std::unique(keyed.begin(), keyed.end()), keyed.end());
    std::vector<uint64_t> shared; // cells holding two or more components
    for (size_t i = 1; i < keyed.size(); ++i)
        if (keyed[i].first == keyed[i - 1].first && (shared.empty() || shared.back() != keyed[i].first))
            shared.push_back(keyed[i].first);
    size_t on_shared = 0;
    for (uint32_t v = 0; v < mesh.vertexCount(); ++v)
        if (used[v]) on_shared += std::binary_search(shared.begin(), shared.end(), vertex_cell[v]);
    return double(on_shared) / double(referenced);
}

Result<MergeReport> mergeRangeViews(Mesh& mesh, const MergeOptions& options, const std::string& name) {
    LODBAKE_RETURN_IF_ERROR(checkMeshConsistency(mesh, name));
    const Samples samples = collectSamples(mesh);
    LODBAKE_RETURN_IF_ERROR(checkInput(mesh, samples, options, name));
    MergeReport report;
    report.views = countViews(mesh);
    report.views_are_scans = mesh.submeshes.size() > 1;
    report.points = samples.vertex.size();
    report.sample_spacing = medianEdgeLength(mesh);
    const Aabb box = computeBounds(mesh);
    report.diagonal = box.diagonal();
    report.depth = pickDepth(box, report.sample_spacing, options);

    const Loaded& module = loadModule();
    if (!module.api) return unsupported(name + ": merge: " + module.error);
    open3d_module::PoissonInput in;
    in.positions = samples.positions.data();
    in.normals = samples.normals.data();
    in.point_count = samples.vertex.size();
    in.depth = report.depth;
    in.scale = options.scale;
    in.threads = 1; // Open3D's parallel reductions are not ordered: one thread keeps the bytes fixed
    open3d_module::PoissonOutput out;
    std::string error;
    if (!module.api->poisson(&in, &out, &error)) return resourceLimit(name + ": merge: " + error);
    report.faces_before_trim = out.indices.size() / 3;
    std::vector<Vec3f> all_positions(out.positions.size() / 3);
    for (size_t v = 0; v < all_positions.size(); ++v)
        all_positions[v] = {out.positions[3 * v], out.positions[3 * v + 1], out.positions[3 * v + 2]};
    const double area_before = surfaceArea(all_positions, out.indices);
    trimByDensity(out, options.trim_log2);
    Mesh merged = compactSurface(out);
    if (merged.faceCount() == 0) return invalidInput(name + ": merge: the reconstruction left no surface");
    report.faces = merged.faceCount();
    report.area = surfaceArea(merged.positions, merged.indices);
    report.trimmed_area = area_before - report.area;

    LODBAKE_ASSIGN_OR_RETURN(TriangleBvh merged_bvh, TriangleBvh::build(merged.positions, merged.indices));
    LODBAKE_RETURN_IF_ERROR(measureDistances(samples, merged_bvh, options.distance_samples, report));
    if (mesh.hasColors()) {
        LODBAKE_ASSIGN_OR_RETURN(TriangleBvh input_bvh, TriangleBvh::build(mesh.positions, mesh.indices));
        LODBAKE_RETURN_IF_ERROR(transferColors(mesh, input_bvh, merged));
    }
    mesh = std::move(merged);
    return report;
}

} // namespace lodbake
