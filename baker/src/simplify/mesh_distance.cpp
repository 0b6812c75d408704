// Two-sided surface distance in the manner of Metro (Cignoni, Rocchini, Scopigno, "Metro: measuring
// error on simplified surfaces", 1998): area-uniform random samples on each surface plus its
// referenced vertices, each measured exactly against the other surface (closest point on triangle
// through a TriangleBvh). Same definitions as ../shared/eval/meshdist.py.
//
// Speed: the points of a side are measured in Morton (Z-curve) order of their position, so
// consecutive queries are close in space and the previous answer bounds the next query tightly.
// measureSurfaceDistances draws the reference side's points once for all levels and measures the
// levels one after the other (each level's chunks in parallel), so one level's BVH and points exist
// at a time.
//
// Determinism: sample k of a side is drawn from a counter-based generator (splitmix64 of seed, side
// and k), so it does not depend on which thread draws it. Points are processed in chunks of a fixed
// size; each chunk writes its max / sum / sum of squares into its own slot and the slots are combined
// in chunk order, so the result is bit-identical for any thread count.

#include "lodbake/simplify/mesh_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/parallel.h"
#include "lodbake/core/bvh.h"

namespace lodbake {
namespace {

constexpr size_t kChunkSize = 2048; // points per task; fixed so the reduction order never changes
constexpr uint64_t kReferenceStream = 0x5265664d65736821ull; // decorrelates the two sides' samples
constexpr uint64_t kApproxStream = 0x417070726f782121ull;

// Leaves of up to kLeafTriangles triangles: fewer, smaller nodes than the default at about the same
// query cost (Morton-ordered queries start with a tight bound). The tree's shape never changes a
// result: the closest distance is exact.
TriangleBvhOptions bvhOptions() {
    TriangleBvhOptions options;
    options.max_leaf_triangles = 8;
    return options;
}

uint64_t splitmix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

// Uniform in [0, 1) with 53 random bits.
double toUnit(uint64_t bits) {
    return double(bits >> 11) * (1.0 / 9007199254740992.0);
}

constexpr uint32_t kMortonCells = 1u << 21; // per axis: 3 x 21 bits fill a 63-bit code

// Spreads the low 21 bits of x so that bit i lands at bit 3i.
uint64_t spreadBits(uint64_t x) {
    x &= 0x1fffffull;
    x = (x | (x << 32)) & 0x1f00000000ffffull;
    x = (x | (x << 16)) & 0x1f0000ff0000ffull;
    x = (x | (x << 8)) & 0x100f00f00f00f00full;
    x = (x | (x << 4)) & 0x10c30c30c30c30c3ull;
    x = (x | (x << 2)) & 0x1249249249249249ull;
    return x;
}

// Z-order code of a point already scaled to [0, kMortonCells - 1] per axis (clamped).
uint64_t mortonCode(const Vec3d& q) {
    auto cell = [](double v) { return uint64_t(std::min(std::max(v, 0.0), double(kMortonCells - 1))); };
    return spreadBits(cell(q.x)) | (spreadBits(cell(q.y)) << 1) | (spreadBits(cell(q.z)) << 2);
}

double triangleArea(const Mesh& mesh, size_t t) {
    Vec3d a = toDouble(mesh.positions[mesh.indices[t * 3]]);
    Vec3d b = toDouble(mesh.positions[mesh.indices[t * 3 + 1]]);
    Vec3d c = toDouble(mesh.positions[mesh.indices[t * 3 + 2]]);
    return 0.5 * length(cross(b - a, c - a));
}

// Checks what this module relies on; the whole-mesh checks belong to cleanup::validate().
Status checkSurface(const Mesh& mesh, const char* role) {
    if (mesh.indices.size() % 3 != 0) {
        return invalidInput(std::string(role) + " mesh: indices: expected a multiple of 3, got " +
                            std::to_string(mesh.indices.size()));
    }
    std::vector<uint8_t> checked(mesh.positions.size(), 0);
    for (size_t c = 0; c < mesh.indices.size(); ++c) {
        uint32_t v = mesh.indices[c];
        if (v >= mesh.positions.size()) {
            return invalidInput(std::string(role) + " mesh: triangle " + std::to_string(c / 3) + ": index " +
                                std::to_string(v) + " out of range (" + std::to_string(mesh.positions.size()) +
                                " vertices)");
        }
        if (!checked[v]) {
            checked[v] = 1;
            if (!isFinite(mesh.positions[v])) {
                return invalidInput(std::string(role) + " mesh: vertex " + std::to_string(v) +
                                    ": expected finite coordinates");
            }
        }
    }
    for (size_t t = 0; t < mesh.faceCount(); ++t) {
        if (triangleArea(mesh, t) > 0.0) return Status::okStatus();
    }
    return invalidInput(std::string(role) + " mesh: expected at least one triangle of non-zero area, found " +
                        (mesh.faceCount() == 0 ? std::string("no triangles") : std::string("only degenerate ones")));
}

struct SideStats {
    double max = 0.0;
    double sum = 0.0;
    double sum_sq = 0.0;
    uint64_t count = 0;
};

// The points measured from one side: area-uniform stratified samples, then the referenced
// vertices, stored in Morton order of their position (ties by point index).
Result<std::vector<Vec3d>> samplePoints(const Mesh& from, const DistanceOptions& options, uint64_t stream,
                                        const char* role) {
    const size_t tri_count = from.faceCount();
    std::vector<double> cdf(tri_count);
    double total = 0.0;
    size_t last_positive = 0;
    for (size_t t = 0; t < tri_count; ++t) {
        double area = triangleArea(from, t);
        if (area > 0.0) last_positive = t;
        total += area;
        cdf[t] = total;
    }
    if (!(total > 0.0) || !std::isfinite(total)) {
        return invalidInput(std::string(role) + " mesh: expected at least one triangle of non-zero area, found " +
                            (tri_count == 0 ? std::string("no triangles") : std::string("only degenerate ones")));
    }

    std::vector<uint32_t> vertices;
    if (options.include_vertices) {
        std::vector<uint8_t> used(from.positions.size(), 0);
        for (uint32_t v : from.indices) used[v] = 1;
        for (size_t v = 0; v < used.size(); ++v) {
            if (used[v]) vertices.push_back(uint32_t(v));
        }
    }

    const size_t sample_count = options.sample_count;
    const size_t point_count = sample_count + vertices.size();
    const size_t chunk_count = (point_count + kChunkSize - 1) / kChunkSize;
    const uint64_t key = splitmix64(options.seed ^ stream);

    auto pointAt = [&](size_t i, size_t& t) -> Vec3d {
        if (i >= sample_count) return toDouble(from.positions[vertices[i - sample_count]]);
        uint64_t base = key + uint64_t(i) * 3;
        double u0 = toUnit(splitmix64(base)), u1 = toUnit(splitmix64(base + 1)), u2 = toUnit(splitmix64(base + 2));
        // Stratified over the area CDF: sample i falls in the i-th of sample_count equal slices of the
        // total area. Each sample is still area-uniform and the estimate has less variance.
        double x = (double(i) + u0) / double(sample_count) * total;
        // x grows with i, so the triangle is found by walking forward from the previous sample's
        // (`t`, the first triangle whose CDF exceeds x: what upper_bound returns). Zero-area
        // triangles own an empty interval of the CDF and are never chosen.
        while (t < tri_count && !(cdf[t] > x)) ++t;
        const size_t tri = t < tri_count ? t : last_positive;
        Vec3d a = toDouble(from.positions[from.indices[tri * 3]]);
        Vec3d b = toDouble(from.positions[from.indices[tri * 3 + 1]]);
        Vec3d c = toDouble(from.positions[from.indices[tri * 3 + 2]]);
        double r1 = std::sqrt(u1);
        return a * (1.0 - r1) + b * (r1 * (1.0 - u2)) + c * (r1 * u2);
    };

    // Points and their Morton codes, then the points put in code order (ties by point index) in
    // place, following the permutation's cycles: no second array of points at the peak.
    std::vector<Vec3d> points(point_count);
    std::vector<std::pair<uint64_t, uint32_t>> order(point_count);
    const Aabb box = computeBounds(from);
    const Vec3d box_min = toDouble(box.min);
    const Vec3d extent = toDouble(box.max) - box_min;
    const double max_extent = std::max({extent.x, extent.y, extent.z, 1e-300});
    const double scale = double(kMortonCells - 1) / max_extent;
    LODBAKE_RETURN_IF_ERROR(parallelFor(chunk_count, 1, [&](size_t chunk) {
        const size_t begin = chunk * kChunkSize, end = std::min(point_count, (chunk + 1) * kChunkSize);
        size_t t = 0;
        if (begin < sample_count) {
            const double x = double(begin) / double(sample_count) * total;
            t = size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
        }
        for (size_t i = begin; i < end; ++i) {
            points[i] = pointAt(i, t);
            const Vec3d q = (points[i] - box_min) * scale;
            order[i] = {mortonCode(q), uint32_t(i)};
        }
    }));
    std::vector<double>().swap(cdf);
    std::sort(order.begin(), order.end());
    // Sorted slot k takes point order[k].second. Each cycle of that permutation is rotated once;
    // a finished slot is marked by pointing at itself.
    for (size_t k = 0; k < point_count; ++k) {
        if (order[k].second == k) continue;
        const Vec3d first = points[k];
        size_t slot = k;
        while (order[slot].second != k) {
            const size_t source = order[slot].second;
            points[slot] = points[source];
            order[slot].second = uint32_t(slot);
            slot = source;
        }
        points[slot] = first;
        order[slot].second = uint32_t(slot);
    }
    return points;
}

// Distances from `points` to the surface in `to`.
Result<SideStats> measurePoints(const std::vector<Vec3d>& points, const Mesh& to_mesh, const TriangleBvh& to) {
    const size_t point_count = points.size();
    const size_t chunk_count = (point_count + kChunkSize - 1) / kChunkSize;
    std::vector<SideStats> chunks(chunk_count);
    LODBAKE_RETURN_IF_ERROR(parallelFor(chunk_count, 1, [&](size_t chunk) {
        SideStats s;
        const size_t end = std::min(point_count, (chunk + 1) * kChunkSize);
        FaceId previous = FaceId::invalid();
        for (size_t k = chunk * kChunkSize; k < end; ++k) {
            const Vec3d& p = points[k];
            // Consecutive points (Morton order) are near each other: the previous answer's distance
            // is a tight bound that prunes most of the tree. The minimum found is the same either way.
            double previous_sq = std::numeric_limits<double>::infinity();
            if (previous.isValid()) {
                const uint32_t* tri = &to_mesh.indices[size_t(previous.value) * 3];
                Vec3d q =
                    closestPointOnTriangle(p, toDouble(to_mesh.positions[tri[0]]), toDouble(to_mesh.positions[tri[1]]),
                                           toDouble(to_mesh.positions[tri[2]]));
                previous_sq = dot(p - q, p - q);
            }
            ClosestHit hit = to.closest(p, std::nextafter(previous_sq, std::numeric_limits<double>::infinity()));
            // Not found only if rounding let a box prune the previous triangle itself: keep it.
            double distance_sq = previous_sq;
            if (hit.isFound()) {
                previous = hit.face;
                distance_sq = hit.distance_sq;
            }
            double d = std::sqrt(distance_sq);
            s.max = std::max(s.max, d);
            s.sum += d;
            s.sum_sq += d * d;
            s.count++;
        }
        chunks[chunk] = s;
    }));

    SideStats total_stats;
    for (const SideStats& s : chunks) {
        total_stats.max = std::max(total_stats.max, s.max);
        total_stats.sum += s.sum;
        total_stats.sum_sq += s.sum_sq;
        total_stats.count += s.count;
    }
    return total_stats;
}

Status checkOptions(const DistanceOptions& options) {
    if (options.sample_count == 0 && !options.include_vertices) {
        return invalidInput("distance options: expected sample_count > 0 or include_vertices, got neither");
    }
    return Status::okStatus();
}

// One approximation against a reference whose side's points are already drawn.
Result<DistanceResult> measureWithReferencePoints(const DistanceReference& reference,
                                                  const std::vector<Vec3d>& reference_points, const Mesh& approx,
                                                  const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    const Mesh& ref_mesh = reference.mesh();
    LODBAKE_ASSIGN_OR_RETURN(TriangleBvh approx_bvh,
                             TriangleBvh::build(approx.positions, approx.indices, bvhOptions()));
    LODBAKE_ASSIGN_OR_RETURN(SideStats ref_to_approx, measurePoints(reference_points, approx, approx_bvh));
    LODBAKE_ASSIGN_OR_RETURN(std::vector<Vec3d> approx_points,
                             samplePoints(approx, options, kApproxStream, "approximation"));
    LODBAKE_ASSIGN_OR_RETURN(SideStats approx_to_ref, measurePoints(approx_points, ref_mesh, reference.bvh()));

    DistanceResult r;
    r.max_ref_to_approx = ref_to_approx.max;
    r.max_approx_to_ref = approx_to_ref.max;
    r.hausdorff = std::max(r.max_ref_to_approx, r.max_approx_to_ref);
    const double n12 = double(ref_to_approx.count), n21 = double(approx_to_ref.count);
    r.mean = (ref_to_approx.sum / n12 + approx_to_ref.sum / n21) / 2.0;
    r.rms = std::sqrt((ref_to_approx.sum_sq / n12 + approx_to_ref.sum_sq / n21) / 2.0);
    r.diagonal = computeBounds(ref_mesh).diagonal();
    return r;
}

} // namespace

Result<DistanceReference> DistanceReference::prepare(const Mesh& reference) {
    LODBAKE_RETURN_IF_ERROR(checkSurface(reference, "reference"));
    DistanceReference prepared;
    prepared.mesh_ = &reference;
    LODBAKE_ASSIGN_OR_RETURN(prepared.bvh_, TriangleBvh::build(reference.positions, reference.indices, bvhOptions()));
    return prepared;
}

Result<DistanceResult> measureSurfaceDistance(const DistanceReference& reference, const Mesh& approx,
                                              const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    LODBAKE_ASSIGN_OR_RETURN(std::vector<Vec3d> reference_points,
                             samplePoints(reference.mesh(), options, kReferenceStream, "reference"));
    return measureWithReferencePoints(reference, reference_points, approx, options);
}

std::vector<Result<DistanceResult>> measureSurfaceDistances(const DistanceReference& reference,
                                                            const std::vector<const Mesh*>& approximations,
                                                            const DistanceOptions& options) {
    std::vector<Result<DistanceResult>> results(approximations.size(), Result<DistanceResult>(DistanceResult{}));
    Status status = checkOptions(options);
    Result<std::vector<Vec3d>> reference_points =
        status.ok() ? samplePoints(reference.mesh(), options, kReferenceStream, "reference")
                    : Result<std::vector<Vec3d>>(status);
    if (!reference_points.ok()) {
        for (auto& r : results) r = reference_points.status();
        return results;
    }
    // One approximation at a time (each is parallel inside), so only one approximation's BVH and
    // points exist at once beside the reference's.
    for (size_t i = 0; i < approximations.size(); ++i)
        results[i] = measureWithReferencePoints(reference, *reference_points, *approximations[i], options);
    return results;
}

Result<DistanceResult> measureSurfaceDistance(const Mesh& reference, const Mesh& approx,
                                              const DistanceOptions& options) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    // Check the approximation before the (costly) reference BVH is built.
    LODBAKE_RETURN_IF_ERROR(checkSurface(approx, "approximation"));
    LODBAKE_ASSIGN_OR_RETURN(DistanceReference prepared, DistanceReference::prepare(reference));
    return measureSurfaceDistance(prepared, approx, options);
}

} // namespace lodbake
