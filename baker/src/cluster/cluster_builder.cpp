// The cluster LOD builder (lodbake/cluster/cluster_lod.h; docs/cluster_lod.md). The scheme is the
// one of Karis et al., "Nanite: A Deep Dive" (SIGGRAPH 2021 course) and of meshoptimizer's
// clusterlod.h: cluster, then repeatedly group neighbouring clusters, simplify each group with its
// border locked and split it again. Positions only: points are welded by bit-identical position,
// and a group's border points keep their ids (the simplifier leaves locked points in place), so the
// adjacency of the next level is found by point ids.

#include "lodbake/cluster/cluster_lod.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "cluster/cluster_internal.h"
#include "core/parallel.h"
#include "lodbake/simplify/simplify.h"

namespace lodbake {

using namespace cluster_detail;

namespace {

constexpr uint32_t kNone = lodrt::kClusterNone;
constexpr uint32_t kNewPoint = kNewPointId; // an output vertex that is not one of the group's points

// A cluster's triangles in its local layout, the one the hierarchy stores: its distinct points in
// ascending id order, and 3 indices into them per triangle.
struct ClusterLayout {
    std::vector<uint32_t> verts;  // point ids, ascending (output vertex ids until the group commits)
    std::vector<uint8_t> local;   // 3 per triangle
    std::vector<uint16_t> border; // local edges (a << 8 | b, a < b) not used by exactly two of its triangles
};

struct BuildCluster {
    ClusterLayout layout;
    uint32_t self_group = kNone;
    uint32_t parent_group = kNone;
    float center[3] = {}; // geometry sphere
    float radius = 0;
    float lod_center[3] = {}; // own LOD sphere and error (its self group's; LOD0: geometry sphere, 0)
    float lod_radius = 0;
    float error = 0;
    // What a group of it must enclose in its culling sphere when it has no self group: an LOD0
    // cluster's own geometry, or the culling sphere a seed of a continued hierarchy carries (else
    // it is the self group's culling sphere, complete only once the group is committed).
    float below_center[3] = {};
    float below_radius = 0;
    uint32_t depth = 0; // its self group's depth (LOD0: 0; a seed: given)
};

// What simplifying one group produced, before it is committed (computed in parallel).
struct GroupResult {
    Status status = Status::okStatus();
    double hausdorff = 0;
    std::vector<Vec3f> positions;             // output vertices
    std::vector<uint32_t> point_of;           // per output vertex: point id, or kNewPoint
    std::vector<ClusterLayout> split;         // output clusters, vertices as output vertex ids
};

float roundUpFloat(double v) {
    float f = float(v);
    if (double(f) < v) f = std::nextafter(f, std::numeric_limits<float>::infinity());
    return f;
}

struct PositionKey {
    uint32_t bits[3];
    bool operator<(const PositionKey& o) const {
        if (bits[0] != o.bits[0]) return bits[0] < o.bits[0];
        if (bits[1] != o.bits[1]) return bits[1] < o.bits[1];
        return bits[2] < o.bits[2];
    }
    bool operator==(const PositionKey& o) const {
        return bits[0] == o.bits[0] && bits[1] == o.bits[1] && bits[2] == o.bits[2];
    }
};

// The local layout of the triangles `part` of `tris` (vertex ids, 3 per triangle): the distinct
// ids ordered by rank(id), which must order them as their final point ids will be. Only a cluster's
// border edges (used once inside it; more than twice: a non-manifold edge) can be shared with
// another cluster, so they are kept for the next level's adjacency.
template <class Rank>
ClusterLayout layoutOf(const std::vector<uint32_t>& tris, const std::vector<uint32_t>& part, Rank rank) {
    ClusterLayout c;
    // One sort of (rank, corner) keys gives the distinct vertices in rank order and each corner's
    // local index; two vertices of equal rank (an output vertex at a point of the merge that another
    // one also lands on) become one local vertex, as they become one point.
    const size_t corners = part.size() * 3;
    std::vector<uint64_t> keys(corners);
    for (size_t i = 0; i < corners; ++i) keys[i] = uint64_t(rank(tris[size_t(part[i / 3]) * 3 + i % 3])) << 10 | i;
    std::sort(keys.begin(), keys.end());
    c.local.resize(corners);
    for (size_t i = 0; i < corners; ++i) {
        const uint32_t corner = uint32_t(keys[i] & 1023);
        if (i == 0 || keys[i] >> 10 != keys[i - 1] >> 10) c.verts.push_back(tris[size_t(part[corner / 3]) * 3 + corner % 3]);
        c.local[corner] = uint8_t(c.verts.size() - 1);
    }
    std::vector<uint16_t> edges;
    edges.reserve(c.local.size());
    for (size_t f = 0; f < c.local.size(); f += 3)
        for (int k = 0; k < 3; ++k) {
            const uint8_t a = c.local[f + k], b = c.local[f + (k + 1) % 3];
            edges.push_back(uint16_t(std::min(a, b) << 8 | std::max(a, b)));
        }
    std::sort(edges.begin(), edges.end());
    for (size_t e = 0; e < edges.size();) {
        size_t j = e;
        while (j < edges.size() && edges[j] == edges[e]) ++j;
        if (j - e != 2) c.border.push_back(edges[e]);
        e = j;
    }
    return c;
}

PositionKey keyOf(const Vec3f& p) {
    PositionKey k;
    const float v[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f}; // -0 and +0 are one position
    for (int a = 0; a < 3; ++a) std::memcpy(&k.bits[a], &v[a], 4);
    return k;
}

Status checkOptions(const ClusterLodOptions& o) {
    if (o.max_triangles < 1 || o.max_triangles > lodrt::ClusterLodCluster::kMaxTriangles || o.max_vertices < 3 ||
        o.max_vertices > lodrt::ClusterLodCluster::kMaxVertices)
        return invalidInput("cluster lod: cluster limits: expected 1..128 triangles and 3..255 vertices");
    if (o.group_size < 2 || o.min_group_size < 1 || o.max_group_size < o.group_size || o.min_group_size > o.group_size)
        return invalidInput("cluster lod: group sizes: expected 1 <= min <= size <= max, size >= 2");
    if (!(o.simplify_ratio > 0 && o.simplify_ratio < 1) || !(o.samples_per_triangle >= 0) ||
        !(o.min_level_reduction >= 0 && o.min_level_reduction < 1))
        return invalidInput("cluster lod: simplify_ratio and min_level_reduction: expected values in (0, 1)");
    return Status::okStatus();
}

// Welds LOD0's vertices by bit-identical position into points; triangles with a repeated point are
// dropped (zero area: the simplifier drops them too, and they would break edge counting).
Status weldInput(const MeshView& lod0, std::vector<Vec3f>& points, std::vector<uint32_t>& tris) {
    const size_t n = lod0.vertexCount();
    for (size_t v = 0; v < n; ++v)
        if (!isFinite(lod0.positions[v]))
            return invalidInput("cluster lod: vertex " + std::to_string(v) + ": expected a finite position");
    std::vector<std::pair<PositionKey, uint32_t>> keys(n);
    for (size_t v = 0; v < n; ++v) keys[v] = {keyOf(lod0.positions[v]), uint32_t(v)};
    std::sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) {
        return a.first < b.first || (a.first == b.first && a.second < b.second);
    });
    std::vector<uint32_t> point_of(n);
    for (size_t i = 0; i < n; ++i) {
        if (i == 0 || !(keys[i].first == keys[i - 1].first)) points.push_back(lod0.positions[keys[i].second]);
        point_of[keys[i].second] = uint32_t(points.size() - 1);
    }
    const size_t face_count = lod0.faceCount();
    for (size_t f = 0; f < face_count; ++f) {
        uint32_t t[3];
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = lod0.indices[f * 3 + k];
            if (v >= n)
                return invalidInput("cluster lod: triangle " + std::to_string(f) + ": index " + std::to_string(v) +
                                    " out of range (" + std::to_string(n) + " vertices)");
            t[k] = point_of[v];
        }
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        tris.insert(tris.end(), t, t + 3);
    }
    if (tris.empty()) return invalidInput("cluster lod: mesh: expected at least one triangle");
    return Status::okStatus();
}

class Builder {
public:
    explicit Builder(const ClusterLodOptions& options) : o_(options) {}

    Status run(const MeshView& lod0, ClusterLodHierarchy& out);
    Status runFrom(const ClusterLodSeed& seed, ClusterLodHierarchy& out);

private:
    Status addSeedClusters(const ClusterLodSeed& seed, std::vector<uint32_t>& level);
    Status grow(std::vector<uint32_t>& level, size_t triangles, ClusterLodHierarchy& out);
    Status addLod0Clusters(const std::vector<uint32_t>& tris, std::vector<uint32_t>& level);
    void addCluster(ClusterLayout layout, uint32_t self_group, std::vector<uint32_t>& level);
    WeightedGraph adjacency(const std::vector<uint32_t>& level) const;
    GroupResult simplifyGroup(const std::vector<uint32_t>& members) const;
    void commitGroup(const std::vector<uint32_t>& members, GroupResult& r, std::vector<uint32_t>& next_level);
    Status buildLevel(std::vector<uint32_t>& level, uint32_t group_size);
    void rollBack(const std::vector<uint32_t>& level, size_t clusters, size_t groups, size_t points);
    void flatten(ClusterLodHierarchy& out) const;

    const ClusterLodOptions& o_;
    std::vector<Vec3f> points_;
    std::vector<BuildCluster> clusters_;
    std::vector<lodrt::ClusterLodGroup> groups_;
    std::vector<std::vector<uint32_t>> group_members_;
};

// Appends a cluster whose layout holds point ids, with its bounding sphere and its LOD sphere and
// error (its self group's; an LOD0 cluster's are its bounding sphere and 0).
void Builder::addCluster(ClusterLayout layout, uint32_t self_group, std::vector<uint32_t>& level) {
    BuildCluster c;
    c.layout = std::move(layout);
    boundingSphere(points_.data(), c.layout.verts.data(), c.layout.verts.size(), c.center, c.radius);
    c.self_group = self_group;
    if (self_group == kNone) {
        std::copy(c.center, c.center + 3, c.lod_center);
        c.lod_radius = c.radius;
        std::copy(c.center, c.center + 3, c.below_center);
        c.below_radius = c.radius;
    } else {
        const lodrt::ClusterLodGroup& g = groups_[self_group];
        std::copy(g.lod_center, g.lod_center + 3, c.lod_center);
        c.lod_radius = g.lod_radius;
        c.error = g.error;
        c.depth = g.depth;
    }
    level.push_back(uint32_t(clusters_.size()));
    clusters_.push_back(std::move(c));
}

// LOD0's clusters: the split of the welded triangles, laid out in parallel (slots in split order).
Status Builder::addLod0Clusters(const std::vector<uint32_t>& tris, std::vector<uint32_t>& level) {
    const std::vector<std::vector<uint32_t>> split = splitIntoClusters(points_, tris, o_.max_triangles, o_.max_vertices);
    std::vector<ClusterLayout> layouts(split.size());
    LODBAKE_RETURN_IF_ERROR(parallelFor(split.size(), 16, [&](size_t i) {
        layouts[i] = layoutOf(tris, split[i], [](uint32_t p) { return p; });
    }));
    for (ClusterLayout& layout : layouts) addCluster(std::move(layout), kNone, level);
    return Status::okStatus();
}

// Clusters of the level as a graph: an edge between two clusters weighted by the triangle edges
// (point pairs) they share; vertex weights are triangle counts, so groups balance their size.
WeightedGraph Builder::adjacency(const std::vector<uint32_t>& level) const {
    std::vector<std::pair<uint64_t, uint32_t>> edges;
    for (uint32_t i = 0; i < level.size(); ++i) {
        const ClusterLayout& c = clusters_[level[i]].layout;
        for (uint16_t e : c.border) {
            // Local order is point order, so the pair is (smaller, larger) already.
            const uint32_t a = c.verts[e >> 8], b = c.verts[e & 0xff];
            edges.push_back({uint64_t(a) << 32 | b, i});
        }
    }
    std::sort(edges.begin(), edges.end());
    std::vector<std::pair<uint32_t, uint32_t>> pairs; // (cluster, neighbour), both directions
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j].first == edges[i].first) ++j;
        for (size_t a = i; a < j; ++a)
            for (size_t b = a + 1; b < j; ++b)
                if (edges[a].second != edges[b].second) {
                    pairs.push_back({edges[a].second, edges[b].second});
                    pairs.push_back({edges[b].second, edges[a].second});
                }
        i = j;
    }
    std::sort(pairs.begin(), pairs.end());
    WeightedGraph g;
    g.row_begin.assign(level.size() + 1, 0);
    for (size_t i = 0; i < pairs.size();) {
        size_t j = i;
        while (j < pairs.size() && pairs[j] == pairs[i]) ++j;
        g.neighbour.push_back(pairs[i].second);
        g.weight.push_back(uint32_t(j - i));
        ++g.row_begin[pairs[i].first + 1];
        i = j;
    }
    for (size_t v = 0; v < level.size(); ++v) g.row_begin[v + 1] += g.row_begin[v];
    g.vertex_weight.resize(level.size());
    for (size_t v = 0; v < level.size(); ++v) g.vertex_weight[v] = uint32_t(clusters_[level[v]].layout.local.size() / 3);
    return g;
}

// Merges the group's clusters, simplifies the merge with its border locked, measures the distance
// between the two and splits the result (read-only on the builder: runs in parallel).
GroupResult Builder::simplifyGroup(const std::vector<uint32_t>& members) const {
    GroupResult r;
    // The merge's vertices are the members' points in ascending id order; its triangles are the
    // members' in member order.
    std::vector<uint32_t> point_ids;
    for (uint32_t c : members)
        point_ids.insert(point_ids.end(), clusters_[c].layout.verts.begin(), clusters_[c].layout.verts.end());
    std::sort(point_ids.begin(), point_ids.end());
    point_ids.erase(std::unique(point_ids.begin(), point_ids.end()), point_ids.end());
    Mesh merged;
    merged.positions.reserve(point_ids.size());
    for (uint32_t p : point_ids) merged.positions.push_back(points_[p]);
    std::vector<uint32_t> merged_of;
    for (uint32_t c : members) {
        const ClusterLayout& layout = clusters_[c].layout;
        merged_of.clear();
        for (uint32_t p : layout.verts)
            merged_of.push_back(uint32_t(std::lower_bound(point_ids.begin(), point_ids.end(), p) - point_ids.begin()));
        for (uint8_t v : layout.local) merged.indices.push_back(merged_of[v]);
    }

    SimplifyOptions so;
    so.target_ratio = 0;
    so.target_triangles = std::max<uint32_t>(1, uint32_t(std::lround(double(merged.faceCount()) * o_.simplify_ratio)));
    so.lock_border = true;
    so.refine_late_levels = false;
    Diagnostics ignored; // notes about unreachable targets: the level's progress is judged by the caller
    Result<SimplifyOutput> s = simplify(merged, so, ignored);
    if (!s.ok()) {
        r.status = s.status();
        return r;
    }
    Mesh& out = s->mesh;
    // Output vertices at a point of the merge (the locked border, and points that did not move)
    // keep its id; the others are new points.
    std::vector<std::pair<PositionKey, uint32_t>> keys(merged.positions.size());
    for (size_t i = 0; i < keys.size(); ++i) keys[i] = {keyOf(merged.positions[i]), point_ids[i]};
    std::sort(keys.begin(), keys.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    r.point_of.resize(out.positions.size(), kNewPoint);
    for (size_t v = 0; v < out.positions.size(); ++v) {
        const PositionKey k = keyOf(out.positions[v]);
        auto it = std::lower_bound(keys.begin(), keys.end(), k,
                                   [](const auto& e, const PositionKey& key) { return e.first < key; });
        if (it != keys.end() && it->first == k) r.point_of[v] = it->second;
    }
    const GroupMeshes meshes{merged.positions, merged.indices, point_ids, out.positions, out.indices, r.point_of};
    Result<double> d = groupDistance(meshes, o_.samples_per_triangle, o_.seed);
    if (!d.ok()) {
        r.status = d.status();
        return r;
    }
    r.hausdorff = *d;
    if (!std::isfinite(r.hausdorff)) {
        // No output triangle: the group's own extent bounds the distance.
        Aabb box;
        for (const Vec3f& p : merged.positions) box.expand(p);
        r.hausdorff = box.diagonal();
    }
    // Output clusters, their vertices ordered as their point ids will be: the merge's points by id,
    // then the new points, which commitGroup numbers after every existing point in output order.
    const auto rank = [&](uint32_t v) {
        return r.point_of[v] == kNewPoint ? uint64_t(1) << 32 | v : uint64_t(r.point_of[v]);
    };
    for (const auto& part : splitIntoClusters(out.positions, out.indices, o_.max_triangles, o_.max_vertices))
        r.split.push_back(layoutOf(out.indices, part, rank));
    r.positions = std::move(out.positions);
    return r;
}

// Records the group (error and spheres, monotonic over its inputs), gives new points their ids in
// output order and adds its output clusters to the next level.
void Builder::commitGroup(const std::vector<uint32_t>& members, GroupResult& r, std::vector<uint32_t>& next_level) {
    const uint32_t g = uint32_t(groups_.size());
    lodrt::ClusterLodGroup group;
    double child_error = 0;
    uint32_t child_depth = 0;
    std::vector<const float*> centers;
    std::vector<float> radii;
    for (uint32_t c : members) {
        child_error = std::max(child_error, double(clusters_[c].error));
        child_depth = std::max(child_depth, clusters_[c].depth);
        centers.push_back(clusters_[c].lod_center);
        radii.push_back(clusters_[c].lod_radius);
        clusters_[c].parent_group = g;
    }
    group.error = roundUpFloat(child_error + r.hausdorff);
    enclosingSphere(centers, radii, group.lod_center, group.lod_radius);
    // One more than its deepest input: the level number in a build from LOD0 (every input of a
    // level was made by the level below), and still increasing up the DAG in a continued one.
    group.depth = child_depth + 1;
    groups_.push_back(group);
    group_members_.push_back(members);

    for (uint32_t& p : r.point_of)
        if (p == kNewPoint) {
            p = uint32_t(points_.size());
            points_.push_back(r.positions[&p - r.point_of.data()]);
        }
    const size_t first_output = clusters_.size();
    for (ClusterLayout& layout : r.split) {
        for (uint32_t& v : layout.verts) v = r.point_of[v];
        addCluster(std::move(layout), g, next_level);
    }
    // The culling sphere encloses the outputs and everything below the group (an input's own
    // group's culling sphere, or an LOD0 input's geometry), so spheres nest down the DAG and culling
    // a group never hides a finer cluster that is in view.
    centers.clear();
    radii.clear();
    for (uint32_t c : members) {
        const uint32_t below = clusters_[c].self_group;
        centers.push_back(below == kNone ? clusters_[c].below_center : groups_[below].bounds_center);
        radii.push_back(below == kNone ? clusters_[c].below_radius : groups_[below].bounds_radius);
    }
    for (size_t c = first_output; c < clusters_.size(); ++c) {
        centers.push_back(clusters_[c].center);
        radii.push_back(clusters_[c].radius);
    }
    enclosingSphere(centers, radii, groups_[g].bounds_center, groups_[g].bounds_radius);
}

Status Builder::buildLevel(std::vector<uint32_t>& level, uint32_t group_size) {
    const WeightedGraph graph = adjacency(level);
    LODBAKE_ASSIGN_OR_RETURN(std::vector<std::vector<uint32_t>> parts,
                             partitionGraph(graph, group_size, std::min(o_.min_group_size, group_size),
                                            o_.max_group_size, o_.seed));
    for (auto& part : parts)
        for (uint32_t& v : part) v = level[v];
    std::vector<GroupResult> results(parts.size());
    LODBAKE_RETURN_IF_ERROR(parallelFor(parts.size(), 1, [&](size_t i) { results[i] = simplifyGroup(parts[i]); }));
    std::vector<uint32_t> next;
    for (size_t i = 0; i < parts.size(); ++i) {
        LODBAKE_RETURN_IF_ERROR(results[i].status);
        commitGroup(parts[i], results[i], next);
        GroupResult().positions.swap(results[i].positions); // free as we go
    }
    level.swap(next);
    return Status::okStatus();
}

// Undoes a level: drops the clusters, groups and points it added and frees its input clusters again.
void Builder::rollBack(const std::vector<uint32_t>& level, size_t clusters, size_t groups, size_t points) {
    clusters_.resize(clusters);
    groups_.resize(groups);
    group_members_.resize(groups);
    points_.resize(points);
    for (uint32_t c : level) clusters_[c].parent_group = kNone;
}

void Builder::flatten(ClusterLodHierarchy& out) const {
    out.clusters.reserve(clusters_.size());
    for (const BuildCluster& c : clusters_) {
        lodrt::ClusterLodCluster rec;
        std::copy(c.center, c.center + 3, rec.center);
        rec.radius = c.radius;
        rec.self_group = c.self_group;
        rec.parent_group = c.parent_group;
        rec.first_vertex = uint32_t(out.positions.size());
        rec.first_triangle = uint32_t(out.indices.size() / 3);
        rec.triangle_count = uint32_t(c.layout.local.size() / 3);
        for (uint32_t p : c.layout.verts) out.positions.push_back(points_[p]);
        out.indices.insert(out.indices.end(), c.layout.local.begin(), c.layout.local.end());
        rec.vertex_count = uint32_t(c.layout.verts.size());
        out.clusters.push_back(rec);
    }
    out.groups = groups_;
    for (size_t g = 0; g < groups_.size(); ++g) {
        out.groups[g].first_child = uint32_t(out.group_children.size());
        out.groups[g].child_count = uint32_t(group_members_[g].size());
        out.group_children.insert(out.group_children.end(), group_members_[g].begin(), group_members_[g].end());
    }
}

Status Builder::run(const MeshView& lod0, ClusterLodHierarchy& out) {
    std::vector<uint32_t> tris;
    LODBAKE_RETURN_IF_ERROR(weldInput(lod0, points_, tris));
    std::vector<uint32_t> level;
    LODBAKE_RETURN_IF_ERROR(addLod0Clusters(tris, level));
    out.lod0_cluster_count = uint32_t(level.size());
    const size_t triangles = tris.size() / 3;
    std::vector<uint32_t>().swap(tris);
    return grow(level, triangles, out);
}

// The levels above `level` (the first level's clusters, of `triangles` triangles in all), until one
// cluster remains or a level stalls; then the hierarchy is flattened into `out`.
Status Builder::grow(std::vector<uint32_t>& level, size_t triangles, ClusterLodHierarchy& out) {
    uint32_t depth = 0, group_size = o_.group_size;
    while (level.size() > 1 && depth < o_.max_levels) {
        const std::vector<uint32_t> input = level;
        const size_t clusters = clusters_.size(), groups = groups_.size(), points = points_.size();
        LODBAKE_RETURN_IF_ERROR(buildLevel(level, group_size));
        size_t next_triangles = 0;
        for (uint32_t c : level) next_triangles += clusters_[c].layout.local.size() / 3;
        const bool stalled = double(next_triangles) > double(triangles) * (1.0 - o_.min_level_reduction);
        if (stalled && group_size < o_.max_group_size) {
            // The locked borders between groups hold the level: group again with larger groups, so
            // that most of those borders fall inside a group and can be simplified; the larger size
            // stays for the levels above.
            rollBack(input, clusters, groups, points);
            level = input;
            group_size = std::min(o_.max_group_size, group_size * 2);
            continue;
        }
        ++depth;
        triangles = next_triangles;
        if (stalled) break;
    }
    out.level_count = depth;
    out.reached_single_group = level.size() == 1;
    out.roots = level;
    flatten(out);
    return Status::okStatus();
}

// The seed's clusters as the first level, with the errors, LOD spheres, culling spheres and depths
// they carry from the hierarchy they are the roots of.
Status Builder::addSeedClusters(const ClusterLodSeed& seed, std::vector<uint32_t>& level) {
    const uint64_t triangle_total = seed.triangles.size() / 3;
    for (size_t i = 0; i < seed.clusters.size(); ++i) {
        const ClusterLodSeed::Cluster& s = seed.clusters[i];
        const std::string at = "cluster lod: seed cluster " + std::to_string(i) + ": ";
        if (s.triangle_count == 0 || s.triangle_count > lodrt::ClusterLodCluster::kMaxTriangles ||
            uint64_t(s.first_triangle) + s.triangle_count > triangle_total)
            return invalidInput(at + "expected 1..128 triangles within the seed's triangles");
        const bool finite = std::isfinite(s.error) && s.error >= 0 && std::isfinite(s.lod_radius) &&
                            s.lod_radius >= 0 && std::isfinite(s.bounds_radius) && s.bounds_radius >= 0 &&
                            isFinite(Vec3f{s.lod_center[0], s.lod_center[1], s.lod_center[2]}) &&
                            isFinite(Vec3f{s.bounds_center[0], s.bounds_center[1], s.bounds_center[2]});
        if (!finite) return invalidInput(at + "expected a finite, non-negative error and spheres");
        std::vector<uint32_t> part(s.triangle_count);
        for (uint32_t t = 0; t < s.triangle_count; ++t) part[t] = s.first_triangle + t;
        ClusterLayout layout = layoutOf(seed.triangles, part, [](uint32_t p) { return p; });
        if (layout.verts.size() > lodrt::ClusterLodCluster::kMaxVertices)
            return invalidInput(at + "expected at most 255 distinct points");
        addCluster(std::move(layout), kNone, level);
        BuildCluster& c = clusters_.back();
        c.error = s.error;
        std::copy(s.lod_center, s.lod_center + 3, c.lod_center);
        c.lod_radius = s.lod_radius;
        std::copy(s.bounds_center, s.bounds_center + 3, c.below_center);
        c.below_radius = s.bounds_radius;
        c.depth = s.depth;
    }
    return Status::okStatus();
}

Status Builder::runFrom(const ClusterLodSeed& seed, ClusterLodHierarchy& out) {
    if (seed.clusters.empty() || seed.triangles.size() % 3 != 0)
        return invalidInput("cluster lod: seed: expected at least one cluster and 3 point ids per triangle");
    for (size_t v = 0; v < seed.points.size(); ++v)
        if (!isFinite(seed.points[v]))
            return invalidInput("cluster lod: seed point " + std::to_string(v) + ": expected a finite position");
    for (size_t i = 0; i < seed.triangles.size(); ++i)
        if (seed.triangles[i] >= seed.points.size())
            return invalidInput("cluster lod: seed triangle " + std::to_string(i / 3) + ": point " +
                                std::to_string(seed.triangles[i]) + " out of range");
    points_ = seed.points;
    std::vector<uint32_t> level;
    LODBAKE_RETURN_IF_ERROR(addSeedClusters(seed, level));
    out.lod0_cluster_count = uint32_t(level.size());
    size_t triangles = 0;
    for (uint32_t c : level) triangles += clusters_[c].layout.local.size() / 3;
    return grow(level, triangles, out);
}

} // namespace

lodrt::ClusterLodView ClusterLodHierarchy::view() const {
    lodrt::ClusterLodView v;
    v.clusters = clusters.data();
    v.cluster_count = uint32_t(clusters.size());
    v.groups = groups.data();
    v.group_count = uint32_t(groups.size());
    v.group_children = group_children.data();
    v.group_child_count = uint32_t(group_children.size());
    v.roots = roots.data();
    v.root_count = uint32_t(roots.size());
    v.vertex_count = uint32_t(positions.size());
    v.triangle_count = uint32_t(indices.size() / 3);
    return v;
}

Result<ClusterLodHierarchy> buildClusterLod(const MeshView& lod0, const ClusterLodOptions& options,
                                            Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    ClusterLodHierarchy out;
    Builder builder(options);
    LODBAKE_RETURN_IF_ERROR(builder.run(lod0, out));
    if (!out.reached_single_group)
        diagnostics.note("cluster lod: " + std::to_string(out.roots.size()) +
                         " root clusters: a level stopped shrinking (locked borders or open boundaries)");
    return out;
}

Result<ClusterLodHierarchy> continueClusterLod(const ClusterLodSeed& seed, const ClusterLodOptions& options,
                                               Diagnostics& diagnostics) {
    LODBAKE_RETURN_IF_ERROR(checkOptions(options));
    ClusterLodHierarchy out;
    Builder builder(options);
    LODBAKE_RETURN_IF_ERROR(builder.runFrom(seed, out));
    if (!out.reached_single_group)
        diagnostics.note("cluster lod: " + std::to_string(out.roots.size()) +
                         " root clusters: a continued level stopped shrinking (locked borders or open boundaries)");
    return out;
}

} // namespace lodbake
