// Reader of LODBAKE_cluster_lod (lodrt/cluster_pack.h, docs/format/cluster_lod.md): the table is
// validated record by record into caller memory, pages are decoded one at a time with the valence
// decoder and scattered into cluster order. Nothing is allocated; every byte is hostile.

#include "lodrt/cluster_pack.h"

#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <new>

#include "lodrt/format.h"
#include "lodrt/valence.h"
#include "little_endian.h"

namespace lodrt {

namespace {

namespace fmt = format;

using detail::loadF32;
using detail::loadU16;
using detail::loadU32;

Result fail(Result code, char* message, size_t size, const char* format, ...) {
    if (message && size > 0) {
        va_list args;
        va_start(args, format);
        std::vsnprintf(message, size, format, args);
        va_end(args);
    }
    return code;
}

size_t align8(size_t n) {
    return (n + 7) & ~size_t(7);
}

// Byte offsets of the record arrays in the table.
struct TableLayout {
    uint64_t clusters, groups, children, roots, pages, end;
};

TableLayout layoutOf(const ClusterPackInfo& info) {
    TableLayout t;
    t.clusters = fmt::kClusterHeaderSize;
    t.groups = t.clusters + uint64_t(info.cluster_count) * fmt::kClusterRecordSize;
    t.children = t.groups + uint64_t(info.group_count) * fmt::kClusterGroupRecordSize;
    t.roots = t.children + uint64_t(info.group_child_count) * 4;
    t.pages = t.roots + uint64_t(info.root_count) * 4;
    t.end = t.pages + uint64_t(info.page_count) * fmt::kClusterPageRecordSize;
    return t;
}

// Offsets of the arrays in the caller's memory.
struct MemoryLayout {
    size_t clusters, groups, children, roots, places, pages, page_clusters, end;
};

MemoryLayout memoryOf(const ClusterPackInfo& info) {
    MemoryLayout m;
    m.clusters = 0;
    m.groups = align8(m.clusters + size_t(info.cluster_count) * sizeof(ClusterLodCluster));
    m.children = align8(m.groups + size_t(info.group_count) * sizeof(ClusterLodGroup));
    m.roots = align8(m.children + size_t(info.group_child_count) * sizeof(uint32_t));
    m.places = align8(m.roots + size_t(info.root_count) * sizeof(uint32_t));
    m.pages = align8(m.places + size_t(info.cluster_count) * sizeof(ClusterPlace));
    m.page_clusters = align8(m.pages + size_t(info.page_count) * sizeof(ClusterPage));
    m.end = align8(m.page_clusters + size_t(info.cluster_count) * sizeof(uint32_t));
    return m;
}

bool finite3(const float v[3]) {
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]);
}

// One cluster record into `cl` and `place`; a message names the first bad field.
Result readCluster(const uint8_t* r, uint32_t c, const ClusterPackInfo& info, ClusterLodCluster& cl,
                   ClusterPlace& place, char* message, size_t size) {
    for (int j = 0; j < 3; ++j) cl.center[j] = loadF32(r + 4 * j);
    cl.radius = loadF32(r + 12);
    for (int j = 0; j < 3; ++j) cl.cone_axis[j] = loadF32(r + 16 + 4 * j);
    cl.cone_cutoff = loadF32(r + 28);
    cl.self_group = loadU32(r + 32);
    cl.parent_group = loadU32(r + 36);
    place.page = loadU32(r + 40);
    place.first_triangle = loadU16(r + 44);
    place.triangle_count = r[46];
    place.vertex_count = r[47];
    if (!finite3(cl.center) || !std::isfinite(cl.radius) || cl.radius < 0)
        return fail(Result::BadStructure, message, size, "cluster %u: sphere is not finite and non-negative", c);
    if ((cl.self_group != fmt::kClusterNoGroup && cl.self_group >= info.group_count) ||
        (cl.parent_group != fmt::kClusterNoGroup && cl.parent_group >= info.group_count))
        return fail(Result::OutOfBounds, message, size, "cluster %u: group index outside the %u groups", c,
                    info.group_count);
    if (place.page >= info.page_count)
        return fail(Result::OutOfBounds, message, size, "cluster %u: page %u outside the %u pages", c, place.page,
                    info.page_count);
    if (place.triangle_count == 0 || place.triangle_count > fmt::kClusterMaxTriangles || place.vertex_count < 3 ||
        place.vertex_count > 3 * place.triangle_count)
        return fail(Result::BadStructure, message, size,
                    "cluster %u: %u triangles over %u vertices (expected 1..%u triangles, 3..3x as many vertices)", c,
                    place.triangle_count, place.vertex_count, fmt::kClusterMaxTriangles);
    if (!finite3(cl.cone_axis) || !std::isfinite(cl.cone_cutoff) || cl.cone_cutoff > 1)
        return fail(Result::BadStructure, message, size, "cluster %u: normal cone is not finite", c);
    cl.cone_sin = 1;
    if (cl.cone_cutoff > 0) {
        const double len = std::sqrt(double(cl.cone_axis[0]) * cl.cone_axis[0] +
                                     double(cl.cone_axis[1]) * cl.cone_axis[1] +
                                     double(cl.cone_axis[2]) * cl.cone_axis[2]);
        if (!(std::fabs(len - 1.0) < 1e-3))
            return fail(Result::BadStructure, message, size, "cluster %u: normal cone axis is not a unit vector", c);
        // Unit length exactly as the cut tests it, and the sine rounded up (a wider cone is safe).
        for (int j = 0; j < 3; ++j) cl.cone_axis[j] = float(cl.cone_axis[j] / len);
        cl.cone_sin = std::nextafter(float(std::sqrt(1.0 - double(cl.cone_cutoff) * cl.cone_cutoff)), 2.0f);
    }
    cl.first_vertex = 0;
    cl.vertex_count = place.vertex_count;
    cl.triangle_count = place.triangle_count;
    return Result::Ok;
}

Result readGroup(const uint8_t* r, uint32_t g, ClusterLodGroup& group, char* message, size_t size) {
    for (int j = 0; j < 3; ++j) group.lod_center[j] = loadF32(r + 4 * j);
    group.lod_radius = loadF32(r + 12);
    group.error = loadF32(r + 16);
    for (int j = 0; j < 3; ++j) group.bounds_center[j] = loadF32(r + 20 + 4 * j);
    group.bounds_radius = loadF32(r + 32);
    group.first_child = loadU32(r + 36);
    group.child_count = loadU32(r + 40);
    group.depth = loadU32(r + 44);
    if (!finite3(group.lod_center) || !finite3(group.bounds_center) || !std::isfinite(group.lod_radius) ||
        !std::isfinite(group.bounds_radius) || !std::isfinite(group.error) || group.lod_radius < 0 ||
        group.bounds_radius < 0 || group.error < 0)
        return fail(Result::BadStructure, message, size, "group %u: sphere or error not finite and non-negative", g);
    return Result::Ok;
}

// Pages: byte ranges inside the pages view; each page's clusters (in table order) tile its triangles.
Result readPages(const uint8_t* table, const TableLayout& t, uint64_t pages_size, ClusterLodPack& out,
                 ClusterPage* pages, uint32_t* page_clusters, ClusterLodCluster* clusters, ClusterPlace* places,
                 char* message, size_t size) {
    const ClusterPackInfo& info = out.info;
    uint32_t first = 0;
    for (uint32_t p = 0; p < info.page_count; ++p) {
        const uint8_t* r = table + t.pages + uint64_t(p) * fmt::kClusterPageRecordSize;
        ClusterPage& page = pages[p];
        page.byte_offset = loadU32(r);
        page.stream_bytes = loadU32(r + 4);
        page.run_count = loadU32(r + 8);
        page.cluster_count = loadU32(r + 12);
        const uint64_t length = uint64_t(page.stream_bytes) + uint64_t(page.run_count) * fmt::kClusterRunSize;
        if (page.byte_offset + length > pages_size || length > 0xffffffffu)
            return fail(Result::OutOfBounds, message, size, "page %u: bytes [%llu, %llu) outside the %llu-byte pages view",
                        p, (unsigned long long)page.byte_offset, (unsigned long long)(page.byte_offset + length),
                        (unsigned long long)pages_size);
        if (page.stream_bytes < fmt::kValenceHeaderSize || page.cluster_count == 0 ||
            page.cluster_count > fmt::kClusterPageMaxClusters || page.run_count == 0)
            return fail(Result::BadStructure, message, size,
                        "page %u: expected a stream of at least %u bytes, 1..%u clusters and runs", p,
                        fmt::kValenceHeaderSize, fmt::kClusterPageMaxClusters);
        page.byte_length = uint32_t(length);
        page.first_cluster = first;
        page.triangle_count = 0;
        if (uint64_t(first) + page.cluster_count > info.cluster_count)
            return fail(Result::BadStructure, message, size, "page %u: more clusters than the table holds", p);
        first += page.cluster_count;
    }
    if (first != info.cluster_count)
        return fail(Result::BadStructure, message, size, "pages: hold %u clusters, the table %u", first,
                    info.cluster_count);
    // Each page's clusters in table order (a counting sort by page), then the tiling of its triangles.
    uint32_t* fill = page_clusters; // reuse: cursor per page is pages[p].first_cluster + filled
    for (uint32_t p = 0; p < info.page_count; ++p) pages[p].triangle_count = 0; // as a fill counter first
    for (uint32_t c = 0; c < info.cluster_count; ++c) {
        ClusterPage& page = pages[places[c].page];
        if (page.triangle_count >= page.cluster_count)
            return fail(Result::BadStructure, message, size, "page %u: more clusters name it than its %u",
                        places[c].page, page.cluster_count);
        fill[page.first_cluster + page.triangle_count++] = c;
    }
    uint64_t base = 0;
    for (uint32_t p = 0; p < info.page_count; ++p) {
        ClusterPage& page = pages[p];
        if (page.triangle_count != page.cluster_count)
            return fail(Result::BadStructure, message, size, "page %u: %u clusters name it, its record says %u", p,
                        page.triangle_count, page.cluster_count);
        uint32_t next = 0;
        for (uint32_t k = 0; k < page.cluster_count; ++k) {
            const uint32_t c = page_clusters[page.first_cluster + k];
            if (places[c].first_triangle != next)
                return fail(Result::BadStructure, message, size,
                            "cluster %u: first triangle %u, expected %u (the page's clusters in order)", c,
                            places[c].first_triangle, next);
            next += places[c].triangle_count;
            clusters[c].first_triangle = uint32_t(base + places[c].first_triangle);
        }
        if (next > fmt::kClusterPageMaxTriangles)
            return fail(Result::BadStructure, message, size, "page %u: %u triangles, more than %u", p, next,
                        fmt::kClusterPageMaxTriangles);
        page.triangle_count = next;
        base += next;
    }
    out.view.triangle_count = uint32_t(base); // <= 2^26 clusters * 128 < 2^33: checked below
    if (base > 0xffffffffu) return fail(Result::BadStructure, message, size, "pages: more than 2^32 triangles");
    return Result::Ok;
}

} // namespace

Result clusterPackFind(const Pack& pack, uint32_t mesh, ClusterPackSource* out, char* message, size_t size) {
    if (!out || mesh >= pack.meshCount()) return fail(Result::InvalidArgument, message, size, "no such mesh");
    *out = ClusterPackSource();
    const JsonValue ext = pack.mesh(mesh).json.find("extensions").find(fmt::kExtClusterLod);
    if (!ext.isValid()) return Result::NotLoaded;
    if (!ext.isObject())
        return fail(Result::BadGltf, message, size, "/meshes/%u/extensions/%s: expected an object", mesh,
                    fmt::kExtClusterLod);
    uint64_t views[2] = {0, 0};
    const char* members[2] = {fmt::kClusterTableMember, fmt::kClusterPagesMember};
    for (int i = 0; i < 2; ++i) {
        if (!ext.find(members[i]).asUint64(&views[i]) || views[i] >= pack.bufferViewCount())
            return fail(Result::OutOfBounds, message, size, "/meshes/%u/extensions/%s/%s: expected a buffer view index",
                        mesh, fmt::kExtClusterLod, members[i]);
        const BufferViewInfo& view = pack.bufferView(uint32_t(views[i]));
        if (!pack.buffer(view.buffer).is_glb_bin || view.byte_stride != 0)
            return fail(Result::BadGltf, message, size,
                        "/meshes/%u/extensions/%s/%s: expected a tightly packed view of the GLB BIN chunk", mesh,
                        fmt::kExtClusterLod, members[i]);
    }
    const BufferViewInfo& table = pack.bufferView(uint32_t(views[0]));
    const BufferViewInfo& pages = pack.bufferView(uint32_t(views[1]));
    // loadPack and loadPackJson checked both views against the buffer and the buffer against the
    // BIN chunk's length.
    out->table_view = uint32_t(views[0]);
    out->pages_view = uint32_t(views[1]);
    out->table_offset = table.byte_offset;
    out->table_size = size_t(table.byte_length);
    out->pages_offset = pages.byte_offset;
    out->pages_size = pages.byte_length;
    const GlbView& glb = pack.container();
    if (glb.bin) {
        out->table = glb.bin + table.byte_offset;
        out->pages = glb.bin + pages.byte_offset;
    }
    return Result::Ok;
}

Result clusterPackReadInfo(const uint8_t* table, size_t table_size, ClusterPackInfo* info, char* message,
                           size_t size) {
    if (!info || (!table && table_size > 0)) return fail(Result::InvalidArgument, message, size, "null argument");
    if (table_size < fmt::kClusterHeaderSize)
        return fail(Result::Truncated, message, size, "table: %zu bytes, shorter than its %u-byte header", table_size,
                    fmt::kClusterHeaderSize);
    if (loadU32(table) != fmt::kClusterMagic)
        return fail(Result::BadMagic, message, size, "table: bad magic (expected \"LBCL\")");
    if (loadU32(table + 4) != fmt::kClusterVersion)
        return fail(Result::UnsupportedVersion, message, size, "table: version %u (expected %u)", loadU32(table + 4),
                    fmt::kClusterVersion);
    ClusterPackInfo in;
    in.cluster_count = loadU32(table + 8);
    in.group_count = loadU32(table + 12);
    in.group_child_count = loadU32(table + 16);
    in.root_count = loadU32(table + 20);
    in.page_count = loadU32(table + 24);
    in.position_bits = loadU32(table + 28);
    for (int j = 0; j < 3; ++j) in.grid_min[j] = loadF32(table + 32 + 4 * j);
    in.grid_size = loadF32(table + 44);
    in.quantization_error = loadF32(table + 48);
    for (uint32_t counts : {in.cluster_count, in.group_count, in.group_child_count, in.root_count, in.page_count})
        if (counts > fmt::kClusterMaxCount)
            return fail(Result::BadStructure, message, size, "table: a count above the format's limit of %u",
                        fmt::kClusterMaxCount);
    if (in.cluster_count == 0 || in.root_count == 0 || in.page_count == 0 || in.root_count > in.cluster_count ||
        in.group_child_count > in.cluster_count)
        return fail(Result::BadStructure, message, size,
                    "table: %u clusters, %u roots, %u group children, %u pages (expected clusters, roots and pages, "
                    "no more roots or children than clusters)",
                    in.cluster_count, in.root_count, in.group_child_count, in.page_count);
    if (in.position_bits < fmt::kValenceMinPositionBits || in.position_bits > fmt::kValenceMaxPositionBits ||
        !finite3(in.grid_min) || !std::isfinite(in.grid_size) || in.grid_size < 0 ||
        !std::isfinite(in.quantization_error) || in.quantization_error < 0)
        return fail(Result::BadStructure, message, size, "table: bad position grid (bits %u)", in.position_bits);
    for (uint32_t o = 52; o < fmt::kClusterHeaderSize; o += 4)
        if (loadU32(table + o) != 0) return fail(Result::BadStructure, message, size, "table: reserved bytes not 0");
    const TableLayout t = layoutOf(in);
    if (table_size < t.end)
        return fail(Result::Truncated, message, size, "table: %zu bytes, its counts need %llu", table_size,
                    (unsigned long long)t.end);
    if (table_size > t.end)
        return fail(Result::TrailingBytes, message, size, "table: %zu bytes, its counts need %llu", table_size,
                    (unsigned long long)t.end);
    in.memory_bytes = memoryOf(in).end;
    *info = in;
    return Result::Ok;
}

Result clusterPackOpen(const uint8_t* table, size_t table_size, uint64_t pages_size, void* memory, size_t memory_size,
                       ClusterLodPack* out, char* message, size_t size) {
    if (!out) return fail(Result::InvalidArgument, message, size, "null argument");
    ClusterPackInfo info;
    Result r = clusterPackReadInfo(table, table_size, &info, message, size);
    if (r != Result::Ok) return r;
    if (!memory || memory_size < info.memory_bytes || (reinterpret_cast<uintptr_t>(memory) & 7) != 0)
        return fail(Result::InvalidArgument, message, size, "memory: %zu bytes aligned to 8 needed", info.memory_bytes);
    const TableLayout t = layoutOf(info);
    const MemoryLayout m = memoryOf(info);
    uint8_t* base = static_cast<uint8_t*>(memory);
    auto* clusters = reinterpret_cast<ClusterLodCluster*>(base + m.clusters);
    auto* groups = reinterpret_cast<ClusterLodGroup*>(base + m.groups);
    auto* children = reinterpret_cast<uint32_t*>(base + m.children);
    auto* roots = reinterpret_cast<uint32_t*>(base + m.roots);
    auto* places = reinterpret_cast<ClusterPlace*>(base + m.places);
    auto* pages = reinterpret_cast<ClusterPage*>(base + m.pages);
    auto* page_clusters = reinterpret_cast<uint32_t*>(base + m.page_clusters);
    ClusterLodPack pack;
    pack.info = info;
    for (uint32_t c = 0; c < info.cluster_count; ++c) {
        new (&clusters[c]) ClusterLodCluster();
        new (&places[c]) ClusterPlace();
        r = readCluster(table + t.clusters + uint64_t(c) * fmt::kClusterRecordSize, c, info, clusters[c], places[c],
                        message, size);
        if (r != Result::Ok) return r;
    }
    for (uint32_t g = 0; g < info.group_count; ++g) {
        new (&groups[g]) ClusterLodGroup();
        r = readGroup(table + t.groups + uint64_t(g) * fmt::kClusterGroupRecordSize, g, groups[g], message, size);
        if (r != Result::Ok) return r;
    }
    for (uint32_t i = 0; i < info.group_child_count; ++i) children[i] = loadU32(table + t.children + 4 * uint64_t(i));
    for (uint32_t i = 0; i < info.root_count; ++i) roots[i] = loadU32(table + t.roots + 4 * uint64_t(i));
    for (uint32_t p = 0; p < info.page_count; ++p) new (&pages[p]) ClusterPage();
    r = readPages(table, t, pages_size, pack, pages, page_clusters, clusters, places, message, size);
    if (r != Result::Ok) return r;
    pack.view.clusters = clusters;
    pack.view.cluster_count = info.cluster_count;
    pack.view.groups = groups;
    pack.view.group_count = info.group_count;
    pack.view.group_children = children;
    pack.view.group_child_count = info.group_child_count;
    pack.view.roots = roots;
    pack.view.root_count = info.root_count;
    pack.view.vertex_count = fmt::kClusterMaxVertices; // vertex ranges are [0, distinct count) of the page
    r = validateClusterLod(pack.view);
    if (r != Result::Ok)
        return fail(r, message, size,
                    "table: the hierarchy is inconsistent (%s: a group's children, a cluster's parent group or the "
                    "roots disagree)",
                    resultName(r));
    pack.places = places;
    pack.pages = pages;
    pack.page_count = info.page_count;
    pack.page_clusters = page_clusters;
    *out = pack;
    return Result::Ok;
}

Result clusterPageReadInfo(const ClusterLodPack& pack, uint32_t page_index, const uint8_t* page, size_t page_size,
                           ClusterPageInfo* info, char* message, size_t size) {
    if (!info || page_index >= pack.page_count || (!page && page_size > 0))
        return fail(Result::InvalidArgument, message, size, "bad page argument");
    const ClusterPage& p = pack.pages[page_index];
    if (page_size != p.byte_length)
        return fail(page_size < p.byte_length ? Result::Truncated : Result::TrailingBytes, message, size,
                    "page %u: %zu bytes, its record says %u", page_index, page_size, p.byte_length);
    ValenceInfo v;
    const Result r = valenceReadInfo(page, p.stream_bytes, &v);
    if (r != Result::Ok)
        return fail(r, message, size, "page %u: stream header: %s", page_index, resultName(r));
    if (v.has_normals || v.attribute_count != 0 || v.position_bits != pack.info.position_bits ||
        std::memcmp(v.bounds_min, pack.info.grid_min, sizeof(v.bounds_min)) != 0 ||
        std::memcmp(&v.cube_size, &pack.info.grid_size, sizeof(float)) != 0)
        return fail(Result::BadStructure, message, size,
                    "page %u: expected a positions-only stream on the table's grid (%u bits)", page_index,
                    pack.info.position_bits);
    if (v.triangle_count != p.triangle_count)
        return fail(Result::BadStructure, message, size, "page %u: stream holds %u triangles, its clusters %u",
                    page_index, v.triangle_count, p.triangle_count);
    const uint8_t* runs = page + p.stream_bytes;
    uint64_t covered = 0;
    for (uint32_t i = 0; i < p.run_count; ++i) {
        if (runs[2 * i] >= p.cluster_count || runs[2 * i + 1] == 0)
            return fail(Result::BadStructure, message, size, "page %u: run %u names no cluster of the page or is empty",
                        page_index, i);
        covered += runs[2 * i + 1];
    }
    if (covered != p.triangle_count)
        return fail(Result::BadStructure, message, size, "page %u: runs cover %llu triangles, the stream %u",
                    page_index, (unsigned long long)covered, p.triangle_count);
    info->vertex_count = v.vertex_count;
    info->triangle_count = v.triangle_count;
    info->scratch_bytes = align8(valenceScratchSize(v)) + align8(size_t(v.triangle_count) * 3 * sizeof(uint32_t)) +
                          align8(size_t(v.vertex_count) * sizeof(uint32_t)) +
                          align8(size_t(p.cluster_count) * sizeof(uint32_t));
    return Result::Ok;
}

Result clusterPageDecode(const ClusterLodPack& pack, uint32_t page_index, const uint8_t* page, size_t page_size,
                         float* positions, size_t position_capacity, uint32_t* indices, size_t index_capacity,
                         void* scratch, size_t scratch_size, char* message, size_t size) {
    ClusterPageInfo info;
    Result r = clusterPageReadInfo(pack, page_index, page, page_size, &info, message, size);
    if (r != Result::Ok) return r;
    if (!scratch || scratch_size < info.scratch_bytes || (reinterpret_cast<uintptr_t>(scratch) & 7) != 0)
        return fail(Result::InvalidArgument, message, size, "page %u: scratch of %zu bytes aligned to 8 needed",
                    page_index, info.scratch_bytes);
    if (!positions || !indices || position_capacity < size_t(info.vertex_count) * 3 ||
        index_capacity < size_t(info.triangle_count) * 3)
        return fail(Result::BufferTooSmall, message, size, "page %u: outputs need %u vertices, %u triangles", page_index,
                    info.vertex_count, info.triangle_count);
    const ClusterPage& p = pack.pages[page_index];
    ValenceInfo v;
    (void)valenceReadInfo(page, p.stream_bytes, &v);
    uint8_t* s = static_cast<uint8_t*>(scratch);
    const size_t valence_bytes = align8(valenceScratchSize(v));
    auto* decoded = reinterpret_cast<uint32_t*>(s + valence_bytes);
    auto* stamps = reinterpret_cast<uint32_t*>(s + valence_bytes + align8(size_t(v.triangle_count) * 12));
    auto* cursor = reinterpret_cast<uint32_t*>(reinterpret_cast<uint8_t*>(stamps) +
                                               align8(size_t(v.vertex_count) * sizeof(uint32_t)));
    ValenceOutput output;
    output.indices = decoded;
    output.index_capacity = size_t(v.triangle_count) * 3;
    output.positions = positions;
    output.position_capacity = position_capacity;
    output.scratch = s;
    output.scratch_size = valence_bytes;
    r = valenceDecode(page, p.stream_bytes, output);
    if (r != Result::Ok) return fail(r, message, size, "page %u: stream fails to decode: %s", page_index, resultName(r));
    // Scatter the runs into cluster order, each cluster filling exactly its range.
    for (uint32_t k = 0; k < p.cluster_count; ++k) cursor[k] = 0;
    const uint8_t* runs = page + p.stream_bytes;
    uint32_t t = 0;
    for (uint32_t i = 0; i < p.run_count; ++i) {
        const uint32_t k = runs[2 * i], n = runs[2 * i + 1];
        const ClusterPlace& place = pack.places[pack.page_clusters[p.first_cluster + k]];
        if (cursor[k] + n > place.triangle_count)
            return fail(Result::BadStructure, message, size, "page %u: runs give local cluster %u more than its %u triangles",
                        page_index, k, place.triangle_count);
        std::memcpy(indices + 3 * size_t(place.first_triangle + cursor[k]), decoded + 3 * size_t(t),
                    size_t(n) * 3 * sizeof(uint32_t));
        cursor[k] += n;
        t += n;
    }
    // Every cluster full (the runs cover the page, so none is short unless another overflowed) and
    // using exactly the distinct vertices its record says.
    for (uint32_t v_i = 0; v_i < v.vertex_count; ++v_i) stamps[v_i] = 0;
    for (uint32_t k = 0; k < p.cluster_count; ++k) {
        const ClusterPlace& place = pack.places[pack.page_clusters[p.first_cluster + k]];
        uint32_t distinct = 0;
        for (uint32_t i = 3 * place.first_triangle; i < 3 * (place.first_triangle + place.triangle_count); ++i) {
            const uint32_t vertex = indices[i];
            if (stamps[vertex] != k + 1) {
                stamps[vertex] = k + 1;
                ++distinct;
            }
        }
        if (cursor[k] != place.triangle_count || distinct != place.vertex_count)
            return fail(Result::BadStructure, message, size,
                        "page %u: local cluster %u decodes to %u triangles over %u vertices, its record says %u over %u",
                        page_index, k, cursor[k], distinct, place.triangle_count, place.vertex_count);
    }
    return Result::Ok;
}

void clusterGroupResidency(const ClusterLodPack& pack, const uint8_t* page_resident, uint8_t* group_resident) {
    const ClusterLodView& v = pack.view;
    for (uint32_t g = 0; g < v.group_count; ++g) {
        uint8_t resident = 1;
        for (uint32_t i = 0; i < v.groups[g].child_count && resident; ++i)
            resident = page_resident[pack.places[v.group_children[v.groups[g].first_child + i]].page] ? 1 : 0;
        group_resident[g] = resident;
    }
    clusterResidencyClosure(v, group_resident);
}

} // namespace lodrt
