// Discrete levels cut from an out-of-core cluster hierarchy (lodbake/ooc/level_cut.h).
#include "lodbake/ooc/level_cut.h"

#include <algorithm>
#include <cstring>
#include <limits>

namespace lodbake::ooc {

namespace {

constexpr uint32_t kNone = lodrt::kClusterNone;
constexpr uint32_t kClustersPerRead = 256; // clusters handed to the source at once

float ownError(const TreeClusterTable& t, const lodrt::ClusterLodCluster& c) {
    return c.self_group == kNone ? 0.0f : t.groups[c.self_group].error;
}

float parentError(const TreeClusterTable& t, const lodrt::ClusterLodCluster& c) {
    return c.parent_group == kNone ? std::numeric_limits<float>::infinity() : t.groups[c.parent_group].error;
}

bool inCut(const TreeClusterTable& t, const lodrt::ClusterLodCluster& c, float threshold) {
    return ownError(t, c) <= threshold && parentError(t, c) > threshold;
}

// A cluster vertex's weld key: its position bits and its index in the cut's vertex order.
struct WeldKey {
    uint32_t bits[3];
    uint32_t index;
    bool operator<(const WeldKey& o) const {
        for (int k = 0; k < 3; ++k)
            if (bits[k] != o.bits[k]) return bits[k] < o.bits[k];
        return index < o.index;
    }
    bool samePoint(const WeldKey& o) const { return std::memcmp(bits, o.bits, sizeof(bits)) == 0; }
};

// Every cluster vertex of the cut is mapped to the first cluster vertex at its position; the kept
// ones are numbered in order of first use, so the numbering does not depend on the sort.
std::vector<uint32_t> weldByPosition(const std::vector<Vec3f>& points, uint32_t& welded_count) {
    std::vector<WeldKey> keys(points.size());
    for (size_t i = 0; i < points.size(); ++i) {
        std::memcpy(keys[i].bits, &points[i], sizeof(keys[i].bits));
        keys[i].index = uint32_t(i);
    }
    std::sort(keys.begin(), keys.end());
    std::vector<uint32_t> first(points.size());
    for (size_t i = 0; i < keys.size();) {
        size_t j = i;
        while (j < keys.size() && keys[j].samePoint(keys[i])) first[keys[j++].index] = keys[i].index;
        i = j;
    }
    keys = std::vector<WeldKey>();
    std::vector<uint32_t> number(points.size(), kNone);
    welded_count = 0;
    for (size_t i = 0; i < points.size(); ++i)
        if (first[i] == i) number[i] = welded_count++;
    for (size_t i = 0; i < points.size(); ++i) first[i] = number[first[i]];
    return first;
}

// A vertex all of whose triangles welding made degenerate is left out (the numbering keeps its
// order of first use).
void dropUnusedVertices(Mesh& mesh) {
    std::vector<uint32_t> number(mesh.positions.size(), kNone);
    for (uint32_t v : mesh.indices) number[v] = 0;
    uint32_t kept = 0;
    for (uint32_t& n : number)
        if (n == 0) n = kept++;
    if (kept == mesh.positions.size()) return;
    for (size_t v = 0; v < number.size(); ++v)
        if (number[v] != kNone) mesh.positions[number[v]] = mesh.positions[v];
    mesh.positions.resize(kept);
    for (uint32_t& v : mesh.indices) v = number[v];
}

} // namespace

uint64_t levelCutBytes(const LevelCut& cut) {
    return 4 * uint64_t(cut.clusters) + 32 * cut.cluster_vertices + 24 * cut.triangles + 24 * cut.cluster_vertices;
}

LevelCut measureLevelCut(const TreeClusterTable& table, float threshold) {
    LevelCut cut;
    cut.threshold = threshold;
    for (const lodrt::ClusterLodCluster& c : table.clusters) {
        if (!inCut(table, c, threshold)) continue;
        cut.triangles += c.triangle_count;
        cut.cluster_vertices += c.vertex_count;
        ++cut.clusters;
        cut.error_bound = std::max(cut.error_bound, ownError(table, c));
    }
    return cut;
}

LevelCut findLevelCut(const TreeClusterTable& table, uint64_t target_triangles) {
    std::vector<float> thresholds{0.0f};
    for (const lodrt::ClusterLodGroup& g : table.groups) thresholds.push_back(g.error);
    std::sort(thresholds.begin(), thresholds.end());
    thresholds.erase(std::unique(thresholds.begin(), thresholds.end()), thresholds.end());
    // The last threshold whose cut still holds at least the target (the counts do not increase).
    size_t lo = 0, hi = thresholds.size(); // invariant: cut(thresholds[i]) >= target for i < lo
    LevelCut at_lo = measureLevelCut(table, thresholds[0]);
    if (at_lo.triangles <= target_triangles) return at_lo;
    lo = 1;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (measureLevelCut(table, thresholds[mid]).triangles >= target_triangles)
            lo = mid + 1;
        else
            hi = mid;
    }
    const LevelCut above = measureLevelCut(table, thresholds[lo - 1]); // >= target
    if (lo == thresholds.size()) return above;
    const LevelCut below = measureLevelCut(table, thresholds[lo]); // < target
    return above.triangles - target_triangles <= target_triangles - below.triangles ? above : below;
}

Result<Mesh> extractLevelCut(const TreeClusterTable& table, TreePageSource& source, const LevelCut& cut) {
    std::vector<uint32_t> ids;
    ids.reserve(cut.clusters);
    for (uint32_t i = 0; i < table.clusters.size(); ++i)
        if (inCut(table, table.clusters[i], cut.threshold)) ids.push_back(i);
    std::vector<Vec3f> points;
    std::vector<uint32_t> corners;
    points.reserve(cut.cluster_vertices);
    corners.reserve(size_t(cut.triangles) * 3);
    ClusterPageGeometry geometry;
    for (size_t first = 0; first < ids.size(); first += kClustersPerRead) {
        const size_t count = std::min<size_t>(kClustersPerRead, ids.size() - first);
        geometry.positions.clear();
        geometry.indices.clear();
        LODBAKE_RETURN_IF_ERROR(source.readPage(0, ids.data() + first, count, geometry));
        size_t v = 0, t = 0;
        for (size_t i = 0; i < count; ++i) {
            const lodrt::ClusterLodCluster& c = table.clusters[ids[first + i]];
            const uint32_t base = uint32_t(points.size());
            points.insert(points.end(), geometry.positions.begin() + std::ptrdiff_t(v),
                          geometry.positions.begin() + std::ptrdiff_t(v + c.vertex_count));
            for (size_t k = 0; k < size_t(c.triangle_count) * 3; ++k) {
                const uint8_t local = geometry.indices[t + k];
                if (local >= c.vertex_count) return invalidInput("level cut: cluster " + std::to_string(ids[first + i]) +
                                                                 ": a triangle names a vertex outside the cluster");
                corners.push_back(base + local);
            }
            v += c.vertex_count;
            t += size_t(c.triangle_count) * 3;
        }
    }
    ids = std::vector<uint32_t>();
    geometry = ClusterPageGeometry();
    uint32_t welded = 0;
    const std::vector<uint32_t> number = weldByPosition(points, welded);
    Mesh mesh;
    mesh.positions.resize(welded);
    for (size_t i = 0; i < points.size(); ++i) mesh.positions[number[i]] = points[i];
    points = std::vector<Vec3f>();
    mesh.indices.reserve(corners.size());
    for (size_t k = 0; k < corners.size(); k += 3) {
        const uint32_t a = number[corners[k]], b = number[corners[k + 1]], c = number[corners[k + 2]];
        if (a == b || b == c || a == c) continue;
        mesh.indices.insert(mesh.indices.end(), {a, b, c});
    }
    dropUnusedVertices(mesh);
    return mesh;
}

} // namespace lodbake::ooc
