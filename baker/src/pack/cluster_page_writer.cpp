// LODBAKE_cluster_lod page writer (pack/cluster_page_writer.h, docs/format/cluster_lod.md).
#include "pack/cluster_page_writer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/parallel.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodrt/format.h"

namespace lodbake::detail {

namespace {

namespace fmt = lodrt::format;

// Cone cutoffs are lowered by this much (a wider cone), so rounding can only make culling rarer.
constexpr double kConeMargin = 1e-4;
// Clusters whose normals spread this far (cosine of the half angle) get no cone: a cone so wide
// culls from almost no view and costs a test per frame.
constexpr double kMinConeCutoff = 0.1;

void setU32(uint8_t* out, uint32_t v) {
    for (int k = 0; k < 4; ++k) out[k] = uint8_t(v >> (8 * k));
}

void setF32(uint8_t* out, float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof(bits));
    setU32(out, bits);
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

Grid gridOf(const ClusterPackBounds& b, uint32_t bits) {
    Grid g;
    g.bits = bits;
    const float hi[3] = {b.max[0], b.max[1], b.max[2]};
    for (int j = 0; j < 3; ++j) g.min[j] = b.min[j];
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

// One page after coding: its bytes and, per cluster (local order), the decoded distinct vertex
// count, cone and sphere radius.
struct CodedPage {
    std::vector<uint8_t> bytes; // stream then runs
    uint32_t stream_bytes = 0;
    uint32_t run_count = 0;
    std::vector<uint32_t> first_triangle, vertex_count;
    std::vector<float> cone; // 4 per cluster: axis, cutoff
    std::vector<float> radius;
};

// A page being written: its clusters, the geometry the source gave, and the coded result.
struct PageSlot {
    const uint32_t* clusters = nullptr;
    size_t count = 0;
    size_t triangles = 0;
    ClusterPageGeometry geometry;
    CodedPage coded;
};

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

// The geometry must be what the table says: each cluster's vertices and triangles, indices in range.
Status checkGeometry(const lodrt::ClusterLodView& t, const PageSlot& slot, uint32_t page) {
    size_t vertices = 0, triangles = 0;
    for (size_t k = 0; k < slot.count; ++k) {
        vertices += t.clusters[slot.clusters[k]].vertex_count;
        triangles += t.clusters[slot.clusters[k]].triangle_count;
    }
    const std::string where = "cluster pack: page " + std::to_string(page) + ": ";
    if (slot.geometry.positions.size() != vertices || slot.geometry.indices.size() != 3 * triangles)
        return invalidInput(where + "the source's geometry does not match the clusters' vertex and triangle counts");
    const uint8_t* index = slot.geometry.indices.data();
    for (size_t k = 0; k < slot.count; ++k) {
        const lodrt::ClusterLodCluster& c = t.clusters[slot.clusters[k]];
        for (size_t i = 0; i < 3 * size_t(c.triangle_count); ++i, ++index)
            if (*index >= c.vertex_count)
                return invalidInput(where + "cluster " + std::to_string(slot.clusters[k]) +
                                    ": a triangle index beyond its vertices");
    }
    return Status::okStatus();
}

// The page's clusters as one mesh, vertices welded by bit-identical position; cluster_of[t] is the
// local cluster of triangle t.
Mesh pageMesh(const lodrt::ClusterLodView& t, const PageSlot& slot, std::vector<uint8_t>& cluster_of) {
    Mesh mesh;
    mesh.positions.reserve(slot.geometry.positions.size());
    mesh.indices.reserve(3 * slot.triangles);
    cluster_of.reserve(slot.triangles);
    std::unordered_map<Vec3f, uint32_t, BitsHash, BitsEqual> index;
    const Vec3f* base = slot.geometry.positions.data();
    const uint8_t* local = slot.geometry.indices.data();
    for (size_t k = 0; k < slot.count; ++k) {
        const lodrt::ClusterLodCluster& c = t.clusters[slot.clusters[k]];
        for (uint32_t tri = 0; tri < c.triangle_count; ++tri) {
            for (int i = 0; i < 3; ++i) {
                const Vec3f& p = base[*local++];
                const auto [it, inserted] = index.emplace(p, uint32_t(mesh.positions.size()));
                if (inserted) mesh.positions.push_back(p);
                mesh.indices.push_back(it->second);
            }
            cluster_of.push_back(uint8_t(k));
        }
        base += c.vertex_count;
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

// Per cluster, from the decoded triangles: distinct vertices, cone, the radius that holds the
// decoded vertices.
void deriveClusters(const lodrt::ClusterLodView& t, const PageSlot& slot, const Mesh& decoded,
                    const std::vector<uint32_t>& old_face_of, const std::vector<uint8_t>& cluster_of, CodedPage& page) {
    const size_t n = slot.count;
    std::vector<std::vector<Vec3d>> normals(n);
    std::vector<std::vector<uint32_t>> used(n);
    page.radius.assign(n, 0);
    for (size_t tri = 0; tri < decoded.faceCount(); ++tri) {
        const size_t k = cluster_of[old_face_of[tri]];
        const lodrt::ClusterLodCluster& c = t.clusters[slot.clusters[k]];
        Vec3d p[3];
        for (int i = 0; i < 3; ++i) {
            const uint32_t v = decoded.indices[3 * tri + size_t(i)];
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
        first += t.clusters[slot.clusters[k]].triangle_count;
    }
}

// Codes one page, decodes it back and derives its clusters' records.
Status codePage(const lodrt::ClusterLodView& t, const Grid& grid, const PageSlot& slot, CodedPage& page) {
    std::vector<uint8_t> cluster_of;
    const Mesh mesh = pageMesh(t, slot, cluster_of);
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
    page.stream_bytes = uint32_t(coded.bytes.size());
    page.bytes = std::move(coded.bytes);
    // Runs of decoded triangles of one cluster.
    for (size_t tri = 0; tri < decoded.faceCount();) {
        const uint8_t k = cluster_of[coded.old_face_of[tri]];
        size_t e = tri;
        while (e < decoded.faceCount() && e - tri < 255 && cluster_of[coded.old_face_of[e]] == k) ++e;
        page.bytes.push_back(k);
        page.bytes.push_back(uint8_t(e - tri));
        ++page.run_count;
        tri = e;
    }
    deriveClusters(t, slot, decoded, coded.old_face_of, cluster_of, page);
    return Status::okStatus();
}

size_t tableSize(const lodrt::ClusterLodView& t, size_t pages) {
    return fmt::kClusterHeaderSize + 48 * (size_t(t.cluster_count) + t.group_count) +
           4 * (size_t(t.group_child_count) + t.root_count) + 16 * pages;
}

// The table with everything but the cluster and page records, which commitPage fills. Spheres and
// errors widened by the grid's error so they hold for the decoded geometry.
std::vector<uint8_t> tableShell(const lodrt::ClusterLodView& t, size_t page_count, const Grid& grid) {
    std::vector<uint8_t> out(tableSize(t, page_count), 0);
    uint8_t* p = out.data();
    setU32(p, fmt::kClusterMagic);
    setU32(p + 4, fmt::kClusterVersion);
    const size_t counts[5] = {t.cluster_count, t.group_count, t.group_child_count, t.root_count, page_count};
    for (size_t i = 0; i < 5; ++i) setU32(p + 8 + 4 * i, uint32_t(counts[i]));
    setU32(p + 28, grid.bits);
    for (int j = 0; j < 3; ++j) setF32(p + 32 + 4 * j, grid.min[j]);
    setF32(p + 44, grid.size);
    setF32(p + 48, grid.error);
    p += fmt::kClusterHeaderSize + 48 * size_t(t.cluster_count);
    for (uint32_t g = 0; g < t.group_count; ++g, p += 48) {
        const lodrt::ClusterLodGroup& gr = t.groups[g];
        for (int j = 0; j < 3; ++j) setF32(p + 4 * j, gr.lod_center[j]);
        setF32(p + 12, gr.lod_radius);
        setF32(p + 16, roundUp(double(gr.error) + grid.error));
        for (int j = 0; j < 3; ++j) setF32(p + 20 + 4 * j, gr.bounds_center[j]);
        setF32(p + 32, roundUp(double(gr.bounds_radius) + grid.error));
        setU32(p + 36, gr.first_child);
        setU32(p + 40, gr.child_count);
        setU32(p + 44, gr.depth);
    }
    for (uint32_t i = 0; i < t.group_child_count; ++i, p += 4) setU32(p, t.group_children[i]);
    for (uint32_t i = 0; i < t.root_count; ++i, p += 4) setU32(p, t.roots[i]);
    return out;
}

// Page `p`'s cluster records and page record into the table, and its share of the statistics.
void commitPage(const lodrt::ClusterLodView& t, const Grid& grid, const PageSlot& slot, uint32_t p, uint32_t offset,
                size_t page_count, std::vector<uint8_t>& table, ClusterPackStats& s) {
    const CodedPage& page = slot.coded;
    bool lod0 = true;
    for (size_t k = 0; k < slot.count; ++k) {
        const uint32_t c = slot.clusters[k];
        const lodrt::ClusterLodCluster& cl = t.clusters[c];
        uint8_t* r = table.data() + fmt::kClusterHeaderSize + 48 * size_t(c);
        for (int j = 0; j < 3; ++j) setF32(r + 4 * j, cl.center[j]);
        setF32(r + 12, std::max(roundUp(double(cl.radius) + grid.error), page.radius[k]));
        for (int j = 0; j < 4; ++j) setF32(r + 16 + 4 * j, page.cone[4 * k + size_t(j)]);
        setU32(r + 32, cl.self_group);
        setU32(r + 36, cl.parent_group);
        setU32(r + 40, p);
        r[44] = uint8_t(page.first_triangle[k]);
        r[45] = uint8_t(page.first_triangle[k] >> 8);
        r[46] = uint8_t(cl.triangle_count);
        r[47] = uint8_t(page.vertex_count[k]);
        lod0 = lod0 && cl.self_group == lodrt::kClusterNone;
        if (cl.self_group == lodrt::kClusterNone) s.lod0_triangles += cl.triangle_count;
        s.cone_clusters += page.cone[4 * k + 3] > 0 ? 1 : 0;
    }
    uint8_t* r = table.data() + table.size() - 16 * (page_count - p);
    setU32(r, offset);
    setU32(r + 4, page.stream_bytes);
    setU32(r + 8, page.run_count);
    setU32(r + 12, uint32_t(slot.count));
    s.max_page_bytes = std::max(s.max_page_bytes, page.bytes.size());
    s.run_bytes += page.bytes.size() - page.stream_bytes;
    if (lod0) s.lod0_page_bytes += page.bytes.size();
}

// What a slot holds: its geometry arrays (capacity kept between batches) and, while its page is in
// flight, the coding at its per-triangle allowance.
uint64_t slotBytes(const PageSlot& slot, bool in_flight) {
    return 12 * uint64_t(slot.geometry.positions.capacity()) + slot.geometry.indices.capacity() +
           (in_flight ? kClusterPageBytesPerTriangle * slot.triangles : 0);
}

} // namespace

Status checkClusterPackTable(const lodrt::ClusterLodView& t) {
    if (t.cluster_count == 0 || t.root_count == 0) return invalidInput("cluster pack: the hierarchy has no clusters");
    if (lodrt::validateClusterLod(t) != lodrt::Result::Ok)
        return invalidInput("cluster pack: the hierarchy fails validateClusterLod");
    return Status::okStatus();
}

Status checkClusterPackLimits(const lodrt::ClusterLodView& t, const ClusterPagePlan& plan) {
    for (size_t count : {size_t(t.cluster_count), size_t(t.group_count), size_t(t.group_child_count),
                         size_t(t.root_count), plan.pageCount()})
        if (count > fmt::kClusterMaxCount) return invalidInput("cluster pack: more records than the format holds");
    for (uint32_t c = 0; c < t.cluster_count; ++c) {
        const lodrt::ClusterLodCluster& cl = t.clusters[c];
        if (cl.triangle_count == 0 || cl.triangle_count > fmt::kClusterMaxTriangles ||
            cl.vertex_count > fmt::kClusterMaxVertices)
            return invalidInput("cluster pack: a cluster outside 1..128 triangles, 255 vertices");
    }
    for (size_t p = 0; p < plan.pageCount(); ++p) {
        size_t triangles = 0;
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i)
            triangles += t.clusters[plan.page_clusters[i]].triangle_count;
        if (plan.page_first[p + 1] - plan.page_first[p] > fmt::kClusterPageMaxClusters ||
            triangles > fmt::kClusterPageMaxTriangles)
            return invalidInput("cluster pack: a group of more than 256 clusters or 65535 triangles");
    }
    return Status::okStatus();
}

Result<ClusterPagesWritten> writeClusterPages(const lodrt::ClusterLodView& t, const ClusterPagePlan& plan,
                                              const ClusterPackBounds& bounds, ClusterPageSource& source,
                                              const ClusterPageWriterOptions& options, const ClusterPageSink& sink) {
    const Grid grid = gridOf(bounds, options.pack.position_bits);
    const size_t page_count = plan.pageCount();
    ClusterPagesWritten out;
    out.table = tableShell(t, page_count, grid);
    const uint64_t fixed = out.table.capacity() + 4 * uint64_t(plan.page_first.capacity() + plan.page_clusters.capacity()) +
                           options.sink_bytes;
    out.accounted_peak_bytes = fixed;
    std::vector<PageSlot> slots(std::max<size_t>(options.pages_in_flight, 1));
    uint64_t offset = 0;
    // Read in page order, coded in parallel, committed in page order (orderedPipeline): slot s holds
    // page p while p is in flight, for p = s modulo the slots, so a page read next to the others
    // never waits for a batch to finish.
    auto read = [&](size_t p, size_t s) -> Status {
        if (options.cancel && options.cancel->load()) return options.cancelled;
        PageSlot& slot = slots[s];
        slot.clusters = plan.page_clusters.data() + plan.page_first[p];
        slot.count = plan.page_first[p + 1] - plan.page_first[p];
        slot.triangles = 0;
        size_t vertices = 0;
        for (size_t k = 0; k < slot.count; ++k) {
            slot.triangles += t.clusters[slot.clusters[k]].triangle_count;
            vertices += t.clusters[slot.clusters[k]].vertex_count;
        }
        // An array larger than this page needs is given back: positions kept from one page beside
        // indices kept from another could hold more than the largest page, which the bound counts.
        if (slot.geometry.positions.capacity() > vertices) std::vector<Vec3f>().swap(slot.geometry.positions);
        if (slot.geometry.indices.capacity() > 3 * slot.triangles) std::vector<uint8_t>().swap(slot.geometry.indices);
        slot.geometry.positions.clear();
        slot.geometry.indices.clear();
        LODBAKE_RETURN_IF_ERROR(source.readPage(uint32_t(p), slot.clusters, slot.count, slot.geometry));
        LODBAKE_RETURN_IF_ERROR(checkGeometry(t, slot, uint32_t(p)));
        // Every slot counted as in flight with the page it holds last (the pages p - J + 1 .. p): at
        // most J pages are, and which pages the slots hold does not depend on the schedule.
        uint64_t held = fixed;
        for (size_t i = 0; i < slots.size(); ++i) held += slotBytes(slots[i], i <= p);
        out.accounted_peak_bytes = std::max(out.accounted_peak_bytes, held);
        return Status::okStatus();
    };
    auto code = [&](size_t, size_t s) -> Status {
        slots[s].coded = CodedPage();
        return codePage(t, grid, slots[s], slots[s].coded);
    };
    auto commit = [&](size_t p, size_t s) -> Status {
        PageSlot& slot = slots[s];
        if (offset + slot.coded.bytes.size() > 0xffffffffu) return resourceLimit("cluster pack: pages exceed 4 GiB");
        LODBAKE_RETURN_IF_ERROR(sink(slot.coded.bytes.data(), slot.coded.bytes.size()));
        commitPage(t, grid, slot, uint32_t(p), uint32_t(offset), page_count, out.table, out.stats);
        offset += slot.coded.bytes.size();
        slot.coded = CodedPage();
        return Status::okStatus();
    };
    LODBAKE_RETURN_IF_ERROR(orderedPipeline(page_count, slots.size(), read, code, commit));
    out.stats.table_bytes = out.table.size();
    out.stats.page_bytes = size_t(offset);
    out.stats.page_count = page_count;
    out.stats.quantization_error = grid.error;
    return out;
}

} // namespace lodbake::detail
