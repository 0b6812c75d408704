// LODBAKE_cluster_lod writer (lodbake/pack/cluster_lod_pack.h, docs/format/cluster_lod.md).
#include "lodbake/pack/cluster_lod_pack.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/parallel.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodrt/cluster_lod.h"
#include "lodrt/format.h"

namespace lodbake {

namespace {

namespace fmt = lodrt::format;

// Roots get pages of their own, this many clusters each (a group's inputs are one page).
constexpr size_t kRootPageClusters = 32;
// Cone cutoffs are lowered by this much (a wider cone), so rounding can only make culling rarer.
constexpr double kConeMargin = 1e-4;
// Clusters whose normals spread this far (cosine of the half angle) get no cone: a cone so wide
// culls from almost no view and costs a test per frame.
constexpr double kMinConeCutoff = 0.1;

void putU32(std::vector<uint8_t>& out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out.push_back(uint8_t(v >> (8 * k)));
}

void putF32(std::vector<uint8_t>& out, float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    putU32(out, bits);
}

float roundUp(double v) {
    const float f = float(v);
    return double(f) >= v ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
}

float roundDown(double v) {
    const float f = float(v);
    return double(f) <= v ? f : std::nextafter(f, -std::numeric_limits<float>::infinity());
}

// The shared grid: the hierarchy's bounding cube.
struct Grid {
    float min[3] = {0, 0, 0};
    float size = 0;
    uint32_t bits = 14;
    float error = 0; // largest distance quantization (and dequantization in float) moves a vertex
};

Grid gridOf(const ClusterLodHierarchy& h, uint32_t bits) {
    Grid g;
    g.bits = bits;
    float hi[3] = {0, 0, 0};
    for (size_t i = 0; i < h.positions.size(); ++i) {
        const float c[3] = {h.positions[i].x, h.positions[i].y, h.positions[i].z};
        for (int j = 0; j < 3; ++j) {
            if (i == 0 || c[j] < g.min[j]) g.min[j] = c[j];
            if (i == 0 || c[j] > hi[j]) hi[j] = c[j];
        }
    }
    g.size = std::max({hi[0] - g.min[0], hi[1] - g.min[1], hi[2] - g.min[2], 0.0f});
    // The cube must hold every vertex in float arithmetic too (min + size may round below the top).
    for (int j = 0; j < 3; ++j)
        while (g.min[j] + g.size < hi[j]) g.size = std::nextafter(g.size, std::numeric_limits<float>::infinity());
    const double step = double(g.size) / double((1u << bits) - 1);
    // Half a step per axis, plus the float rounding of min + q * step (a few ulps of the cube's far
    // corner), widened by a thousandth so the bound holds after the float arithmetic of the decoder.
    const double ulps = 4.0 * double(std::numeric_limits<float>::epsilon()) *
                        (std::max({std::fabs(g.min[0]), std::fabs(g.min[1]), std::fabs(g.min[2])}) + double(g.size));
    g.error = roundUp((std::sqrt(3.0) / 2.0 * step + ulps) * 1.001);
    return g;
}

// One page: its clusters (ascending, the table order), and after coding its bytes and per cluster
// (local order) the decoded distinct vertex count, cone and sphere radius.
struct Page {
    std::vector<uint32_t> clusters;
    std::vector<uint8_t> bytes; // stream then runs
    uint32_t stream_bytes = 0;
    uint32_t run_count = 0;
    std::vector<uint32_t> first_triangle, vertex_count;
    std::vector<float> cone; // 4 per cluster: axis, cutoff
    std::vector<float> radius;
    Status status = Status::okStatus();
};

std::vector<Page> planPages(const ClusterLodHierarchy& h) {
    std::vector<Page> pages;
    auto add = [&](const uint32_t* list, size_t count) {
        for (size_t first = 0; first < count; first += kRootPageClusters) {
            Page p;
            p.clusters.assign(list + first, list + std::min(count, first + kRootPageClusters));
            std::sort(p.clusters.begin(), p.clusters.end());
            pages.push_back(std::move(p));
        }
    };
    for (const lodrt::ClusterLodGroup& g : h.groups) {
        // A group's inputs are one page (at most kClusterPageMaxClusters, checked by the caller).
        Page p;
        p.clusters.assign(h.group_children.begin() + g.first_child,
                          h.group_children.begin() + g.first_child + g.child_count);
        std::sort(p.clusters.begin(), p.clusters.end());
        pages.push_back(std::move(p));
    }
    add(h.roots.data(), h.roots.size());
    return pages;
}

struct BitsHash {
    size_t operator()(const Vec3f& v) const {
        uint32_t b[3];
        std::memcpy(b, &v, sizeof(b));
        return size_t(b[0]) * 73856093u ^ size_t(b[1]) * 19349663u ^ size_t(b[2]) * 83492791u;
    }
};
struct BitsEqual {
    bool operator()(const Vec3f& a, const Vec3f& b) const { return std::memcmp(&a, &b, sizeof(Vec3f)) == 0; }
};

// The page's clusters as one mesh, vertices welded by bit-identical position; cluster_of[t] is the
// local cluster of triangle t.
Mesh pageMesh(const ClusterLodHierarchy& h, const Page& page, std::vector<uint8_t>& cluster_of) {
    Mesh mesh;
    std::unordered_map<Vec3f, uint32_t, BitsHash, BitsEqual> index;
    for (size_t k = 0; k < page.clusters.size(); ++k) {
        const lodrt::ClusterLodCluster& c = h.clusters[page.clusters[k]];
        for (uint32_t t = 0; t < c.triangle_count; ++t) {
            for (int i = 0; i < 3; ++i) {
                const Vec3f& p = h.positions[c.first_vertex + h.indices[3 * size_t(c.first_triangle + t) + size_t(i)]];
                const auto [it, inserted] = index.emplace(p, uint32_t(mesh.positions.size()));
                if (inserted) mesh.positions.push_back(p);
                mesh.indices.push_back(it->second);
            }
            cluster_of.push_back(uint8_t(k));
        }
    }
    return mesh;
}

// Normal cone of triangles with normals `normals` (unit; degenerate ones left out): the axis is
// their normalised sum, the cutoff the smallest cosine to it less a margin, or none.
void coneOf(const std::vector<Vec3d>& normals, float out[4]) {
    out[0] = out[1] = out[2] = 0;
    out[3] = -1;
    Vec3d sum(0, 0, 0);
    for (const Vec3d& n : normals) sum = sum + n;
    const double len = std::sqrt(dot(sum, sum));
    if (normals.empty() || !(len > 1e-12)) return;
    const Vec3d axis = sum * (1.0 / len);
    double min_dot = 1;
    for (const Vec3d& n : normals) min_dot = std::min(min_dot, dot(n, axis));
    const double cutoff = min_dot - kConeMargin;
    if (cutoff < kMinConeCutoff) return;
    out[0] = float(axis.x);
    out[1] = float(axis.y);
    out[2] = float(axis.z);
    out[3] = roundDown(cutoff);
}

// Codes one page, decodes it back and derives per cluster the distinct vertices, the cone and the
// radius that holds the decoded vertices.
Status codePage(const ClusterLodHierarchy& h, const Grid& grid, Page& page) {
    std::vector<uint8_t> cluster_of;
    const Mesh mesh = pageMesh(h, page, cluster_of);
    codec::ValenceEncodeOptions options;
    options.position_bits = grid.bits;
    options.encode_normals = false;
    options.encode_attributes = false;
    for (int j = 0; j < 3; ++j) options.cube_min[j] = grid.min[j];
    options.cube_size = grid.size;
    LODBAKE_ASSIGN_OR_RETURN(codec::ValenceEncodeResult coded, codec::encodeValence(mesh, options));
    LODBAKE_ASSIGN_OR_RETURN(Mesh decoded, codec::decodeValence(coded.bytes, "cluster page"));
    if (decoded.faceCount() != mesh.faceCount() || coded.old_face_of.size() != mesh.faceCount())
        return internalError("cluster page: decoded triangle count differs");
    const size_t n = page.clusters.size();
    page.stream_bytes = uint32_t(coded.bytes.size());
    page.bytes = std::move(coded.bytes);
    // Runs of decoded triangles of one cluster.
    for (size_t t = 0; t < decoded.faceCount();) {
        const uint8_t k = cluster_of[coded.old_face_of[t]];
        size_t e = t;
        while (e < decoded.faceCount() && e - t < 255 && cluster_of[coded.old_face_of[e]] == k) ++e;
        page.bytes.push_back(k);
        page.bytes.push_back(uint8_t(e - t));
        ++page.run_count;
        t = e;
    }
    // Per cluster, from the decoded triangles: distinct vertices, normals, farthest vertex.
    std::vector<std::vector<Vec3d>> normals(n);
    std::vector<std::vector<uint32_t>> used(n);
    page.radius.assign(n, 0);
    for (size_t t = 0; t < decoded.faceCount(); ++t) {
        const size_t k = cluster_of[coded.old_face_of[t]];
        const lodrt::ClusterLodCluster& c = h.clusters[page.clusters[k]];
        Vec3d p[3];
        for (int i = 0; i < 3; ++i) {
            const uint32_t v = decoded.indices[3 * t + size_t(i)];
            used[k].push_back(v);
            p[i] = toDouble(decoded.positions[v]);
            const Vec3d d = p[i] - Vec3d(c.center[0], c.center[1], c.center[2]);
            page.radius[k] = std::max(page.radius[k], roundUp(std::sqrt(dot(d, d))));
        }
        const Vec3d normal = cross(p[1] - p[0], p[2] - p[0]);
        const double len = std::sqrt(dot(normal, normal));
        if (len > 0) normals[k].push_back(normal * (1.0 / len));
    }
    page.cone.assign(4 * n, 0);
    page.vertex_count.assign(n, 0);
    page.first_triangle.assign(n, 0);
    uint32_t first = 0;
    for (size_t k = 0; k < n; ++k) {
        std::sort(used[k].begin(), used[k].end());
        page.vertex_count[k] = uint32_t(std::unique(used[k].begin(), used[k].end()) - used[k].begin());
        coneOf(normals[k], &page.cone[4 * k]);
        page.first_triangle[k] = first;
        first += h.clusters[page.clusters[k]].triangle_count;
    }
    return Status::okStatus();
}

Status checkLimits(const ClusterLodHierarchy& h, const std::vector<Page>& pages) {
    if (h.clusters.empty() || h.roots.empty()) return invalidInput("cluster pack: the hierarchy has no clusters");
    if (lodrt::validateClusterLod(h.view()) != lodrt::Result::Ok)
        return invalidInput("cluster pack: the hierarchy fails validateClusterLod");
    for (size_t count : {h.clusters.size(), h.groups.size(), h.group_children.size(), h.roots.size(), pages.size()})
        if (count > fmt::kClusterMaxCount) return invalidInput("cluster pack: more records than the format holds");
    for (const lodrt::ClusterLodCluster& c : h.clusters)
        if (c.triangle_count == 0 || c.triangle_count > fmt::kClusterMaxTriangles ||
            c.vertex_count > fmt::kClusterMaxVertices)
            return invalidInput("cluster pack: a cluster outside 1..128 triangles, 255 vertices");
    for (const Page& p : pages) {
        size_t triangles = 0;
        for (uint32_t c : p.clusters) triangles += h.clusters[c].triangle_count;
        if (p.clusters.size() > fmt::kClusterPageMaxClusters || triangles > fmt::kClusterPageMaxTriangles)
            return invalidInput("cluster pack: a group of more than 256 clusters or 65535 triangles");
    }
    return Status::okStatus();
}

void putHeader(std::vector<uint8_t>& t, const ClusterLodHierarchy& h, size_t page_count, const Grid& grid) {
    putU32(t, fmt::kClusterMagic);
    putU32(t, fmt::kClusterVersion);
    for (size_t count : {h.clusters.size(), h.groups.size(), h.group_children.size(), h.roots.size(), page_count})
        putU32(t, uint32_t(count));
    putU32(t, grid.bits);
    for (int j = 0; j < 3; ++j) putF32(t, grid.min[j]);
    putF32(t, grid.size);
    putF32(t, grid.error);
    while (t.size() < fmt::kClusterHeaderSize) t.push_back(0);
}

// The table: header, clusters, groups, children, roots, pages. Spheres and errors widened by the
// grid's error so they hold for the decoded geometry.
std::vector<uint8_t> tableBytes(const ClusterLodHierarchy& h, const std::vector<Page>& pages, const Grid& grid,
                                const std::vector<uint32_t>& page_offsets) {
    struct Place {
        uint32_t page = 0, local = 0;
    };
    std::vector<Place> place(h.clusters.size());
    for (size_t p = 0; p < pages.size(); ++p)
        for (size_t k = 0; k < pages[p].clusters.size(); ++k) place[pages[p].clusters[k]] = {uint32_t(p), uint32_t(k)};
    std::vector<uint8_t> t;
    putHeader(t, h, pages.size(), grid);
    for (size_t c = 0; c < h.clusters.size(); ++c) {
        const lodrt::ClusterLodCluster& cl = h.clusters[c];
        const Page& page = pages[place[c].page];
        const size_t k = place[c].local;
        for (int j = 0; j < 3; ++j) putF32(t, cl.center[j]);
        putF32(t, std::max(roundUp(double(cl.radius) + grid.error), page.radius[k]));
        for (int j = 0; j < 4; ++j) putF32(t, page.cone[4 * k + size_t(j)]);
        putU32(t, cl.self_group);
        putU32(t, cl.parent_group);
        putU32(t, place[c].page);
        t.push_back(uint8_t(page.first_triangle[k]));
        t.push_back(uint8_t(page.first_triangle[k] >> 8));
        t.push_back(uint8_t(cl.triangle_count));
        t.push_back(uint8_t(page.vertex_count[k]));
    }
    for (const lodrt::ClusterLodGroup& g : h.groups) {
        for (int j = 0; j < 3; ++j) putF32(t, g.lod_center[j]);
        putF32(t, g.lod_radius);
        putF32(t, roundUp(double(g.error) + grid.error));
        for (int j = 0; j < 3; ++j) putF32(t, g.bounds_center[j]);
        putF32(t, roundUp(double(g.bounds_radius) + grid.error));
        putU32(t, g.first_child);
        putU32(t, g.child_count);
        putU32(t, g.depth);
    }
    for (uint32_t c : h.group_children) putU32(t, c);
    for (uint32_t c : h.roots) putU32(t, c);
    for (size_t p = 0; p < pages.size(); ++p) {
        putU32(t, page_offsets[p]);
        putU32(t, pages[p].stream_bytes);
        putU32(t, pages[p].run_count);
        putU32(t, uint32_t(pages[p].clusters.size()));
    }
    return t;
}

} // namespace

Result<ClusterPackResult> writeClusterLodPack(const ClusterLodHierarchy& h, const ClusterPackOptions& options) {
    if (options.position_bits < fmt::kValenceMinPositionBits || options.position_bits > fmt::kValenceMaxPositionBits)
        return invalidInput("cluster pack: position bits outside 8..16");
    std::vector<Page> pages = planPages(h);
    LODBAKE_RETURN_IF_ERROR(checkLimits(h, pages));
    const Grid grid = gridOf(h, options.position_bits);
    LODBAKE_RETURN_IF_ERROR(parallelFor(pages.size(), 1, [&](size_t p) { pages[p].status = codePage(h, grid, pages[p]); }));
    ClusterPackResult result;
    std::vector<uint8_t> blob;
    std::vector<uint32_t> offsets;
    for (Page& p : pages) {
        LODBAKE_RETURN_IF_ERROR(p.status);
        if (blob.size() + p.bytes.size() > 0xffffffffu) return resourceLimit("cluster pack: pages exceed 4 GiB");
        offsets.push_back(uint32_t(blob.size()));
        blob.insert(blob.end(), p.bytes.begin(), p.bytes.end());
        ClusterPackStats& s = result.stats;
        s.max_page_bytes = std::max(s.max_page_bytes, p.bytes.size());
        s.run_bytes += p.bytes.size() - p.stream_bytes;
        bool lod0 = true;
        for (uint32_t c : p.clusters) lod0 = lod0 && h.clusters[c].self_group == lodrt::kClusterNone;
        for (uint32_t c : p.clusters)
            if (h.clusters[c].self_group == lodrt::kClusterNone) s.lod0_triangles += h.clusters[c].triangle_count;
        if (lod0) s.lod0_page_bytes += p.bytes.size();
        for (size_t k = 0; k < p.clusters.size(); ++k) s.cone_clusters += p.cone[4 * k + 3] > 0 ? 1 : 0;
    }
    std::vector<uint8_t> table = tableBytes(h, pages, grid, offsets);
    result.stats.table_bytes = table.size();
    result.stats.page_bytes = blob.size();
    result.stats.page_count = pages.size();
    result.stats.quantization_error = grid.error;
    PackExtension& e = result.extension;
    e.name = fmt::kExtClusterLod;
    e.json = JsonNode::object();
    e.blobs.push_back(std::move(table));
    e.blob_view_members.push_back(fmt::kClusterTableMember);
    e.blobs.push_back(std::move(blob));
    e.blob_view_members.push_back(fmt::kClusterPagesMember);
    // Beside LOD0 and its MSFT_lod chain, never instead of them: not a stream --compact requires.
    e.is_stream = false;
    return result;
}

} // namespace lodbake
