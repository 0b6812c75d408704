// A level's error against the input, measured partition by partition (lodbake/ooc/level_error.h).
//
// Why the numbers are the in-memory measurement's: measureSurfaceDistance draws sample i of the
// reference side on the first triangle whose running area total (the CDF, accumulated in triangle
// order) exceeds x_i = (i + u0_i) / N * total, with u0_i and the point's barycentrics from a
// counter-based generator. Accumulating the CDF partition after partition, each starting from the
// running total where the one before ended, gives the very CDF values of one pass over the input in
// partition order, so every sample lands on the same triangle at the same point; x_i never decreases
// with i, so each partition's samples are one range of i, found before the distances are measured.
// A point's distance is the exact minimum over triangles (DistanceIndex), so it does not depend on
// which index holds the nearest triangle: the level side's minimum over the partitions is the
// in-memory value bit for bit, and is combined in the in-memory order.
#include "lodbake/ooc/level_error.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/task_arena.h>

#include "core/large_array.h"
#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/core/spill_file.h"
#include "lodrt/format.h"
#include "simplify/distance_sides.h"
#include "simplify/surface_sampling.h"

namespace lodbake::ooc {

namespace {

using detail::kDistanceChunkSize;
using detail::LargeArray;

constexpr size_t kHeaderBytes = lodrt::format::kPartitionHeaderBytes;
// The level side skips a partition whose box is farther than a point's nearest distance so far, with
// the relative slack of DistanceIndex's own pruning: rounding never skips a nearer triangle.
constexpr double kPruneRelative = 1.0 + 1.0 / (1 << 20);

// A partition file as its header states it, and what the area pass found in it.
struct PartInfo {
    std::string path;
    uint32_t vertices = 0, triangles = 0;
    Vec3f lo, hi;
    uint32_t last_id = 0;
    uint64_t hash = 0;            // of the bytes read in the area pass
    double area_begin = 0.0;      // the running area total before its first triangle
    double area_end = 0.0;        // after its last
    uint32_t sample_begin = 0, sample_end = 0; // its reference samples [begin, end)
};

// What the area pass gathers over the whole input.
struct InputSummary {
    double total = 0.0;
    size_t last_positive_part = 0; // the last triangle of non-zero area (where samples past the CDF go)
    uint32_t last_positive_tri = 0;
    bool any_positive = false;
    Aabb box;
    uint64_t id_count = 0;      // largest global id + 1
    uint32_t leftover_begin = 0; // samples from here on fall past the CDF's end
    std::vector<Vec3f> sub_positions; // the subsample's corners, 3 per triangle
    std::vector<uint32_t> sub_indices;
};

// The bytes held, counted as they are allocated.
struct Account {
    uint64_t now = 0, peak = 0;
    void add(uint64_t b) { peak = std::max(peak, now += b); }
    void sub(uint64_t b) { now -= std::min(now, b); }
};

std::string stemOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = name.find('.');
    return dot == std::string::npos ? name : name.substr(0, dot);
}

std::string folderOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : path.substr(0, slash);
}

bool cancelled(const LevelErrorOptions& o) { return o.cancel && o.cancel->load(); }

// The header's counts and bounds, the file's size against them, and its last global id.
Status readHeader(const std::string& path, PartInfo& info) {
    info.path = path;
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return ioError(path + ": cannot open: " + std::strerror(errno));
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    LODBAKE_ASSIGN_OR_RETURN(const PartitionHeader header, readPartitionHeader(fd, path));
    if (header.vertex_count == 0 || header.triangle_count == 0)
        return invalidInput(path + ": header: expected vertices and triangles");
    info.vertices = header.vertex_count;
    info.triangles = header.triangle_count;
    info.lo = header.bounds_min;
    info.hi = header.bounds_max;
    LODBAKE_RETURN_IF_ERROR(readAt(fd, kHeaderBytes + 4 * (uint64_t(info.vertices) - 1), &info.last_id, 4, path));
    return Status::okStatus();
}

// A partition read whole and checked against its name, its header and (after the area pass) the
// bytes that pass read.
Result<PartitionData> loadPartition(const PartInfo& info) {
    LODBAKE_ASSIGN_OR_RETURN(PartitionData d, readPartitionFile(info.path));
    const std::string stem = stemOf(info.path);
    if (stem.size() == 16 && stem.find_first_not_of("0123456789abcdef") == std::string::npos &&
        stem != hashToHex(d.content_hash))
        return invalidInput(info.path + ": content: expected bytes hashing to the file's name (" + stem + "), got " +
                            hashToHex(d.content_hash) + ": the file is corrupted");
    if (info.hash != 0 && d.content_hash != info.hash)
        return invalidInput(info.path + ": content: changed while the level error was measured");
    if (d.global_ids.size() != info.vertices || d.indices.size() != 3 * size_t(info.triangles) ||
        d.global_ids.back() != info.last_id)
        return invalidInput(info.path + ": header: changed while the level error was measured");
    Aabb box;
    for (size_t v = 0; v < d.positions.size(); ++v) {
        if (!isFinite(d.positions[v]))
            return invalidInput(info.path + ": vertex " + std::to_string(v) + ": expected finite coordinates");
        box.expand(d.positions[v]);
    }
    if (!(box.min == info.lo) || !(box.max == info.hi))
        return invalidInput(info.path + ": header: expected the bounds of the partition's vertices");
    return d;
}

// Pass 1: every partition's place in the area CDF, the last triangle of non-zero area, the bounds,
// the largest id and every `stride`-th triangle of the input (the subsample).
Status areaPass(std::vector<PartInfo>& parts, uint64_t stride, const LevelErrorOptions& o, InputSummary& s,
                Account& acc) {
    double running = 0.0;
    uint64_t g = 0; // global triangle number, partition order
    for (size_t p = 0; p < parts.size(); ++p) {
        PartInfo& info = parts[p];
        if (cancelled(o)) return ioError(info.path + ": level error measurement cancelled");
        const uint64_t bytes = 16 * uint64_t(info.vertices) + 12 * uint64_t(info.triangles);
        acc.add(bytes);
        LODBAKE_ASSIGN_OR_RETURN(PartitionData d, loadPartition(info));
        info.hash = d.content_hash;
        info.area_begin = running;
        for (uint32_t t = 0; t < info.triangles; ++t, ++g) {
            const Vec3f& a = d.positions[d.indices[size_t(t) * 3]];
            const Vec3f& b = d.positions[d.indices[size_t(t) * 3 + 1]];
            const Vec3f& c = d.positions[d.indices[size_t(t) * 3 + 2]];
            const double area = detail::samplingTriangleArea(a, b, c);
            if (area > 0.0) {
                s.any_positive = true;
                s.last_positive_part = p;
                s.last_positive_tri = t;
            }
            running += area;
            if (g % stride == 0) {
                for (const Vec3f* q : {&a, &b, &c}) {
                    s.sub_indices.push_back(uint32_t(s.sub_positions.size()));
                    s.sub_positions.push_back(*q);
                }
            }
        }
        info.area_end = running;
        s.box.expand(info.lo);
        s.box.expand(info.hi);
        s.id_count = std::max(s.id_count, uint64_t(info.last_id) + 1);
        acc.sub(bytes);
    }
    s.total = running;
    if (!s.any_positive || !std::isfinite(running))
        return invalidInput(parts[0].path + ": triangles: expected at least one triangle of non-zero area in the input");
    return Status::okStatus();
}

// Sample i's position in the CDF, as measureSurfaceDistance computes it.
double sampleX(uint64_t key, size_t i, size_t sample_count, double total) {
    const double u0 = detail::toUnit(detail::splitmix64(key + uint64_t(i) * 3));
    return (double(i) + u0) / double(sample_count) * total;
}

// Each partition's range of reference samples: sample i belongs to the first partition whose CDF ends
// above x_i (x_i never decreases with i); those past the CDF's end go to the last triangle of
// non-zero area.
void assignSamples(std::vector<PartInfo>& parts, uint64_t key, size_t sample_count, InputSummary& s) {
    size_t p = 0;
    uint32_t i = 0;
    for (; i < sample_count; ++i) {
        const double x = sampleX(key, i, sample_count, s.total);
        while (p < parts.size() && !(x < parts[p].area_end)) {
            parts[p].sample_end = i;
            if (++p < parts.size()) parts[p].sample_begin = i;
        }
        if (p == parts.size()) break;
    }
    for (; p < parts.size(); ++p) {
        parts[p].sample_end = i;
        if (p + 1 < parts.size()) parts[p + 1].sample_begin = i;
    }
    s.leftover_begin = i;
}

// Sample i's point on triangle `tri`, as measureSurfaceDistance's sampler computes it.
Vec3d samplePoint(const PartitionData& d, uint64_t key, size_t i, size_t tri) {
    const uint64_t base = key + uint64_t(i) * 3;
    const double u1 = detail::toUnit(detail::splitmix64(base + 1)), u2 = detail::toUnit(detail::splitmix64(base + 2));
    const Vec3d a = toDouble(d.positions[d.indices[tri * 3]]);
    const Vec3d b = toDouble(d.positions[d.indices[tri * 3 + 1]]);
    const Vec3d c = toDouble(d.positions[d.indices[tri * 3 + 2]]);
    return detail::pointOnTriangle(a, b, c, u1, u2);
}

void addStats(OneSidedDistance& total, const OneSidedDistance& s) {
    total.max = std::max(total.max, s.max);
    total.sum += s.sum;
    total.sum_sq += s.sum_sq;
    total.count += s.count;
}

// The input side of one loaded partition: its samples (and, in the partition of the last triangle of
// non-zero area, the samples past the CDF's end), then its vertices no earlier partition held, each
// measured against the level. Chunks of fixed size, combined in order into `total`.
Status inputSide(const PartitionData& d, const PartInfo& info, const std::vector<double>& cdf, bool last_positive,
                 const InputSummary& s, size_t sample_count, uint64_t key, const std::vector<uint32_t>& new_vertices,
                 const DistanceIndex& level, OneSidedDistance& total) {
    std::vector<uint32_t> samples;
    for (uint32_t i = info.sample_begin; i < info.sample_end; ++i) samples.push_back(i);
    const size_t in_cdf = samples.size();
    if (last_positive)
        for (uint32_t i = s.leftover_begin; i < sample_count; ++i) samples.push_back(i);
    const size_t count = samples.size() + new_vertices.size();
    std::vector<OneSidedDistance> chunks(chunkCount(count, kDistanceChunkSize));
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(count, kDistanceChunkSize, [&](size_t chunk, size_t first, size_t end) {
        OneSidedDistance st;
        DistanceIndex::Cursor cursor;
        size_t t = 0;
        if (first < in_cdf) {
            const double x = sampleX(key, samples[first], sample_count, s.total);
            t = size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
        }
        for (size_t j = first; j < end; ++j) {
            Vec3d point;
            if (j < in_cdf) {
                const double x = sampleX(key, samples[j], sample_count, s.total);
                while (t < cdf.size() && !(cdf[t] > x)) ++t; // the first triangle whose CDF exceeds x
                point = samplePoint(d, key, samples[j], t);
            } else if (j < samples.size()) {
                point = samplePoint(d, key, samples[j], s.last_positive_tri);
            } else {
                point = toDouble(d.positions[new_vertices[j - samples.size()]]);
            }
            const double dist = std::sqrt(level.closestDistanceSq(point, cursor));
            st.max = std::max(st.max, dist);
            st.sum += dist;
            st.sum_sq += dist * dist;
            st.count++;
        }
        chunks[chunk] = st;
    }));
    for (const OneSidedDistance& c : chunks) addStats(total, c);
    return Status::okStatus();
}

// The level side against one loaded partition: every level point whose distance to the partition's
// box is within its nearest distance so far is measured against the partition's index.
Status levelSide(const PartInfo& info, const DistanceIndex& index, const LargeArray<Vec3d>& points, double tiny,
                 std::vector<double>& best, std::vector<uint32_t>& candidates, uint64_t& queries) {
    candidates.clear();
    const Vec3d lo = toDouble(info.lo), hi = toDouble(info.hi);
    for (size_t k = 0; k < points.size(); ++k) {
        const Vec3d& p = points[k];
        double box = 0.0;
        for (int a = 0; a < 3; ++a) {
            const double e = p[a] < lo[a] ? lo[a] - p[a] : (p[a] > hi[a] ? p[a] - hi[a] : 0.0);
            box += e * e;
        }
        if (box <= best[k] * kPruneRelative + tiny) candidates.push_back(uint32_t(k));
    }
    queries += candidates.size();
    return parallelForChunks(candidates.size(), kDistanceChunkSize, [&](size_t, size_t first, size_t end) {
        DistanceIndex::Cursor cursor;
        for (size_t j = first; j < end; ++j) {
            const uint32_t k = candidates[j];
            const double dsq = index.closestDistanceSq(points[k], cursor);
            if (dsq < best[k]) best[k] = dsq;
        }
    });
}

// One level's state through pass 2.
struct LevelState {
    DistanceIndex index;
    LargeArray<Vec3d> points;
    std::vector<double> best; // squared nearest distance of each level point so far
    std::vector<uint32_t> candidates;
    double tiny = 0.0; // the absolute term of the pruning slack
    uint64_t queries = 0;
    OneSidedDistance input_side;
};

// Pass 2, one partition: read it again, rebuild its CDF from where the area pass placed it, index it
// and measure both sides of every level. `seen` has a bit per global id measured by an earlier partition.
Status distancePass(const PartInfo& info, bool last_positive, const InputSummary& s, const LevelErrorOptions& o,
                    uint64_t key, std::vector<uint64_t>& seen, std::vector<LevelState>& levels, Account& acc) {
    const uint64_t bytes = 20 * uint64_t(info.vertices) +
                           (20 + kDistanceIndexBytesPerTriangle) * uint64_t(info.triangles);
    acc.add(bytes);
    LODBAKE_ASSIGN_OR_RETURN(PartitionData d, loadPartition(info));
    std::vector<double> cdf(info.triangles);
    double running = info.area_begin;
    for (size_t t = 0; t < cdf.size(); ++t) {
        running += detail::samplingTriangleArea(d.positions[d.indices[t * 3]], d.positions[d.indices[t * 3 + 1]],
                                                d.positions[d.indices[t * 3 + 2]]);
        cdf[t] = running;
    }
    if (!(running == info.area_end)) // the same bytes give the same sums; a mismatch is a changed file
        return invalidInput(info.path + ": triangles: changed while the level error was measured");
    LODBAKE_ASSIGN_OR_RETURN(DistanceIndex index, DistanceIndex::build(d.positions, d.indices));
    std::vector<uint32_t> new_vertices;
    for (uint32_t v = 0; v < d.global_ids.size(); ++v) {
        const uint32_t id = d.global_ids[v];
        uint64_t& word = seen[id >> 6];
        const uint64_t bit = uint64_t(1) << (id & 63);
        if (!(word & bit) && o.distance.include_vertices) new_vertices.push_back(v);
        word |= bit;
    }
    for (LevelState& st : levels) {
        LODBAKE_RETURN_IF_ERROR(inputSide(d, info, cdf, last_positive, s, o.distance.sample_count, key, new_vertices,
                                          st.index, st.input_side));
        LODBAKE_RETURN_IF_ERROR(levelSide(info, index, st.points, st.tiny, st.best, st.candidates, st.queries));
    }
    acc.sub(bytes);
    return Status::okStatus();
}

size_t referencedVertices(const Mesh& mesh) {
    std::vector<uint8_t> used(mesh.positions.size(), 0);
    for (uint32_t v : mesh.indices)
        if (v < used.size()) used[v] = 1;
    return size_t(std::count(used.begin(), used.end(), uint8_t(1)));
}

// The memory formula of level_error.h; `level_triangles` and `level_points` are summed over the levels.
uint64_t memoryBound(const std::vector<PartInfo>& parts, uint64_t sub_triangles, uint64_t level_triangles,
                     uint64_t level_points, uint64_t id_count) {
    uint64_t v = 0, t = 0;
    for (const PartInfo& p : parts) {
        v = std::max<uint64_t>(v, p.vertices);
        t = std::max<uint64_t>(t, p.triangles);
    }
    const uint64_t bitmap = (id_count + 63) / 64 * 8;
    const uint64_t area_pass = 48 * sub_triangles + 16 * v + 12 * t;
    const uint64_t level = (48 + kDistanceIndexBytesPerTriangle) * sub_triangles +
                           (8 + kDistanceIndexBytesPerTriangle) * level_triangles + 52 * level_points + bitmap;
    const uint64_t distance_pass = (8 + kDistanceIndexBytesPerTriangle) * level_triangles + 40 * level_points +
                                   bitmap + 20 * v + (20 + kDistanceIndexBytesPerTriangle) * t;
    return std::max({area_pass, level, distance_pass});
}

// A level's points, its index, each point's first nearest distance (to the input's subsample, `sub`)
// and its pruning slack (from the largest coordinate of the input's bounds `box` and the level).
Status prepareLevel(const Mesh& level, const LevelErrorOptions& o, const DistanceIndex& sub, const Aabb& box,
                    LevelState& st, Account& acc) {
    acc.add((8 + kDistanceIndexBytesPerTriangle) * (level.indices.size() / 3));
    LODBAKE_ASSIGN_OR_RETURN(st.index, DistanceIndex::build(level.positions, level.indices));
    LODBAKE_ASSIGN_OR_RETURN(st.points, detail::approximationSidePoints(level, o.distance));
    acc.add(52 * uint64_t(st.points.size()));
    st.best.assign(st.points.size(), 0.0);
    LODBAKE_RETURN_IF_ERROR(parallelForChunks(st.points.size(), kDistanceChunkSize, [&](size_t, size_t first, size_t end) {
        DistanceIndex::Cursor cursor;
        for (size_t k = first; k < end; ++k) st.best[k] = sub.closestDistanceSq(st.points[k], cursor);
    }));
    // The sampling's sort keys are gone; the points, their distances, the candidates and a partition's
    // sample list (24 + 8 + 4 + 4 per point) stay.
    acc.sub(12 * uint64_t(st.points.size()));
    Aabb all = box;
    for (const Vec3f& v : level.positions) all.expand(v);
    const float magnitude = std::max({std::fabs(all.min.x), std::fabs(all.min.y), std::fabs(all.min.z),
                                      std::fabs(all.max.x), std::fabs(all.max.y), std::fabs(all.max.z)});
    const double absolute = double(magnitude) * std::ldexp(1.0, -24);
    st.tiny = absolute * absolute;
    return Status::okStatus();
}

// The headers, the bound, and the checks that need no file read.
Status planMeasurement(const std::vector<std::string>& files, const std::vector<const Mesh*>& levels,
                       const LevelErrorOptions& o, std::vector<PartInfo>& parts, InputSummary& s,
                       LevelErrorResult& common, std::vector<uint64_t>& level_points, uint64_t& stride) {
    if (files.empty()) return invalidInput("level error: expected at least one partition file");
    LODBAKE_RETURN_IF_ERROR(detail::checkDistanceOptions(o.distance));
    uint64_t level_triangles = 0, points = 0;
    for (const Mesh* level : levels) {
        LODBAKE_RETURN_IF_ERROR(detail::checkDistanceSurface(*level, "level"));
        level_points.push_back(o.distance.sample_count + (o.distance.include_vertices ? referencedVertices(*level) : 0));
        level_triangles += level->indices.size() / 3;
        points += level_points.back();
    }
    parts.resize(files.size());
    for (size_t p = 0; p < files.size(); ++p) {
        LODBAKE_RETURN_IF_ERROR(readHeader(files[p], parts[p]));
        common.input_triangles += parts[p].triangles;
        s.id_count = std::max(s.id_count, uint64_t(parts[p].last_id) + 1);
    }
    const uint64_t cap = std::max<uint64_t>(1, o.bound_triangles);
    stride = (common.input_triangles + cap - 1) / cap;
    common.subsample_triangles = (common.input_triangles + stride - 1) / stride;
    common.partition_count = parts.size();
    common.memory_bound_bytes = memoryBound(parts, common.subsample_triangles, level_triangles, points, s.id_count);
    if (common.memory_bound_bytes > o.memory_limit_bytes)
        return resourceLimit(files[0] + ": memory limit of " + std::to_string(o.memory_limit_bytes >> 20) +
                             " MiB is too small to measure the level" + (levels.size() > 1 ? "s" : "") +
                             " (needs at least " + std::to_string((common.memory_bound_bytes >> 20) + 1) + " MiB)");
    return Status::okStatus();
}

Result<std::vector<LevelErrorResult>> measure(const std::vector<std::string>& files,
                                              const std::vector<const Mesh*>& levels, const LevelErrorOptions& o) {
    std::vector<PartInfo> parts;
    InputSummary s;
    LevelErrorResult common;
    std::vector<uint64_t> level_points;
    uint64_t stride = 1;
    LODBAKE_RETURN_IF_ERROR(planMeasurement(files, levels, o, parts, s, common, level_points, stride));
    Account acc;
    acc.add(48 * common.subsample_triangles); // the subsample's corners, gathered by the area pass
    LODBAKE_RETURN_IF_ERROR(areaPass(parts, stride, o, s, acc));
    const uint64_t key = detail::splitmix64(o.distance.seed ^ detail::kReferenceStream);
    assignSamples(parts, key, o.distance.sample_count, s);

    std::vector<uint64_t> seen(size_t((s.id_count + 63) / 64), 0);
    acc.add(8 * uint64_t(seen.size()));
    std::vector<LevelState> states(levels.size());
    {
        const uint64_t sub_bytes = (48 + kDistanceIndexBytesPerTriangle) * common.subsample_triangles;
        acc.add(kDistanceIndexBytesPerTriangle * common.subsample_triangles);
        LODBAKE_ASSIGN_OR_RETURN(DistanceIndex sub, DistanceIndex::build(s.sub_positions, s.sub_indices));
        for (size_t l = 0; l < levels.size(); ++l)
            LODBAKE_RETURN_IF_ERROR(prepareLevel(*levels[l], o, sub, s.box, states[l], acc));
        std::vector<Vec3f>().swap(s.sub_positions);
        std::vector<uint32_t>().swap(s.sub_indices);
        acc.sub(sub_bytes);
    }
    for (size_t p = 0; p < parts.size(); ++p) {
        if (cancelled(o)) return ioError(parts[p].path + ": level error measurement cancelled");
        LODBAKE_RETURN_IF_ERROR(distancePass(parts[p], p == s.last_positive_part, s, o, key, seen, states, acc));
    }
    for (uint64_t w : seen) common.input_vertices += uint64_t(__builtin_popcountll(w));
    common.accounted_peak_bytes = acc.peak;
    std::vector<LevelErrorResult> results(levels.size(), common);
    for (size_t l = 0; l < levels.size(); ++l) {
        LevelState& st = states[l];
        for (double& b : st.best) b = std::sqrt(b);
        const OneSidedDistance level_side = detail::combineSideDistances(st.best.data(), st.best.size());
        results[l].distance = detail::twoSidedDistance(st.input_side, level_side, s.box.diagonal());
        results[l].level_points = level_points[l];
        results[l].level_queries = st.queries;
    }
    return results;
}

} // namespace

Result<std::vector<LevelErrorResult>> measureLevelErrors(const std::vector<std::string>& partition_files,
                                                         const std::vector<const Mesh*>& levels,
                                                         const LevelErrorOptions& options) {
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(std::max(1, threads));
    Result<std::vector<LevelErrorResult>> result = internalError("level error: not run");
    arena.execute([&] { result = measure(partition_files, levels, options); });
    return result;
}

Result<uint64_t> levelErrorBound(const std::vector<std::string>& partition_files,
                                 const std::vector<const Mesh*>& levels, const LevelErrorOptions& options) {
    std::vector<PartInfo> parts;
    InputSummary s;
    LevelErrorResult common;
    std::vector<uint64_t> level_points;
    uint64_t stride = 1;
    LevelErrorOptions unlimited = options;
    unlimited.memory_limit_bytes = ~uint64_t(0);
    LODBAKE_RETURN_IF_ERROR(planMeasurement(partition_files, levels, unlimited, parts, s, common, level_points, stride));
    return common.memory_bound_bytes;
}

Result<LevelErrorResult> measureLevelError(const std::vector<std::string>& partition_files, const Mesh& level,
                                           const LevelErrorOptions& options) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<LevelErrorResult> results, measureLevelErrors(partition_files, {&level}, options));
    return std::move(results[0]);
}

Result<LevelErrorResult> measureLevelError(const PartitionSet& set, const Mesh& level, const LevelErrorOptions& options) {
    std::vector<std::string> files;
    for (const PartitionFile& f : set.partitions) files.push_back(f.path);
    return measureLevelError(files, level, options);
}

Result<std::vector<std::string>> partitionFilesOf(const MergeTree& tree) {
    std::vector<std::string> files;
    for (const std::string& lod : tree.partitions) {
        const int fd = ::open(lod.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0) return ioError(lod + ": cannot open: " + std::strerror(errno));
        uint8_t head[16];
        const Status read = readAt(fd, 0, head, sizeof head, lod);
        ::close(fd);
        if (!read.ok() || std::memcmp(head, lodrt::format::kPartitionLodMagic, 8) != 0)
            return invalidInput(lod + ": header: expected a partition hierarchy file (magic LBPLOD01)");
        uint64_t source = 0;
        std::memcpy(&source, head + 8, 8);
        const std::string path = joinPath(folderOf(lod), hashToHex(source) + lodrt::format::kPartitionExtension);
        if (::access(path.c_str(), R_OK) != 0)
            return ioError(lod + ": its partition file " + path + " is missing (kept only with keep_intermediate)");
        files.push_back(path);
    }
    return files;
}

} // namespace lodbake::ooc
