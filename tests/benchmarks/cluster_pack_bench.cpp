// LODBAKE_cluster_lod sizes and page decode speed (docs/format/cluster_lod.md), with anchors from the
// same run: per scan (repaired as the bake does), the extension's bytes (table + pages) per LOD0
// triangle; the bytes of the pages that hold only LOD0 clusters against LOD0 coded as one
// positions-only valence stream at the same bits (what paging LOD0 costs); and the decode rate of
// all pages (lodrt::clusterPageDecode) against one decode of that LOD0 stream (lodrt::valenceDecode).
// Then, for the first scan, the pages streamed by lodrt::Streamer from range reads on a close orbit
// (baked with --clusters, jobs run one frame after they are submitted): per budget (none, and the
// pinned bytes plus a quarter of all pages), the frames until the first view settles, the frames
// with missing pages, the pages and bytes resident at most, reads and evictions, and the largest
// projected error of a drawn cluster on settled frames (the bar: at most the 1 px threshold).
//
// With --stream, the streamed writer (lodbake/pack/cluster_pack_stream.h) against the in-memory one on
// one scan's hierarchy: the in-memory writer and writePackGlb first, then the hierarchy's geometry is
// written to a file in page order and dropped (the table records stay), and the streamed writer
// reads it back a page at a time (pread) and writes the GLB with writePackGlbFile. For each: wall
// time and the peak resident memory above the resident memory before it (VmHWM, reset through
// /proc/self/clear_refs), against the streamed writer's memory formula and accounted peak; and
// whether the two GLBs are the same bytes.
//
// usage: cluster_pack_bench [MESH...]   (default: bunny_zipper, igea, dragon_poisson from ../shared/meshes)
//        cluster_pack_bench --stream MESH [--dir DIR] [--in-flight J]   (DIR: where the files go, default /tmp)
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <cstdlib>
#include <fstream>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "bench_mesh.h"
#include "bench_timing.h"
#include "lodbake/bake/bake.h"
#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/pack/cluster_pack_stream.h"
#include "lodbake/pack/pack_glb.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/streaming.h"
#include "lodrt/valence.h"

#include <fcntl.h>
#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

namespace {

struct Pages {
    std::vector<uint64_t> memory;
    lodrt::ClusterLodPack pack;
    std::vector<uint64_t> scratch;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
};

bool openPages(const std::vector<uint8_t>& table, const std::vector<uint8_t>& pages, Pages& p) {
    lodrt::ClusterPackInfo info;
    if (lodrt::clusterPackReadInfo(table.data(), table.size(), &info) != lodrt::Result::Ok) return false;
    p.memory.assign(info.memory_bytes / 8 + 1, 0);
    if (lodrt::clusterPackOpen(table.data(), table.size(), pages.size(), p.memory.data(), p.memory.size() * 8,
                               &p.pack) != lodrt::Result::Ok)
        return false;
    size_t scratch = 0, vertices = 0, triangles = 0;
    for (uint32_t i = 0; i < p.pack.page_count; ++i) {
        lodrt::ClusterPageInfo pi;
        const lodrt::ClusterPage& page = p.pack.pages[i];
        if (lodrt::clusterPageReadInfo(p.pack, i, pages.data() + page.byte_offset, page.byte_length, &pi) !=
            lodrt::Result::Ok)
            return false;
        scratch = std::max(scratch, pi.scratch_bytes);
        vertices = std::max<size_t>(vertices, pi.vertex_count);
        triangles = std::max<size_t>(triangles, pi.triangle_count);
    }
    p.scratch.assign(scratch / 8 + 1, 0);
    p.positions.resize(3 * vertices);
    p.indices.resize(3 * triangles);
    return true;
}

bool decodeAll(const std::vector<uint8_t>& pages, Pages& p, size_t* triangles) {
    *triangles = 0;
    for (uint32_t i = 0; i < p.pack.page_count; ++i) {
        const lodrt::ClusterPage& page = p.pack.pages[i];
        if (lodrt::clusterPageDecode(p.pack, i, pages.data() + page.byte_offset, page.byte_length, p.positions.data(),
                                     p.positions.size(), p.indices.data(), p.indices.size(), p.scratch.data(),
                                     p.scratch.size() * 8) != lodrt::Result::Ok)
            return false;
        *triangles += page.triangle_count;
    }
    return true;
}

bool run(const std::string& path) {
    lodbake::Diagnostics diagnostics;
    lodbake::Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return false;
    auto built = lodbake::buildClusterLod(lodbake::MeshView(mesh), lodbake::ClusterLodOptions{}, diagnostics);
    if (!built.ok()) return std::fprintf(stderr, "error: %s\n", built.status().message().c_str()), false;
    lodbake::Result<lodbake::ClusterPackResult> written = lodbake::internalError("not run");
    const double write_s =
        1e-3 * lodbake_bench::bestMs(1, [&] { written = lodbake::writeClusterLodPack(*built, lodbake::ClusterPackOptions{}); });
    if (!written.ok()) return std::fprintf(stderr, "error: %s\n", written.status().message().c_str()), false;
    const std::vector<uint8_t>& table = written->extension.blobs[0];
    const std::vector<uint8_t>& pages = written->extension.blobs[1];
    const lodbake::ClusterPackStats& s = written->stats;
    // Anchor: LOD0 as one positions-only stream at the same bits.
    lodbake::Mesh lod0;
    lod0.positions = mesh.positions;
    lod0.indices = mesh.indices;
    lodbake::codec::ValenceEncodeOptions options;
    options.position_bits = lodbake::ClusterPackOptions{}.position_bits;
    auto stream = lodbake::codec::encodeValence(lod0, options);
    if (!stream.ok()) return std::fprintf(stderr, "error: %s\n", stream.status().message().c_str()), false;
    Pages p;
    if (!openPages(table, pages, p)) return std::fprintf(stderr, "error: the pages do not open\n"), false;
    size_t page_triangles = 0;
    bool ok = true;
    const double pages_ms = lodbake_bench::bestMs(3, [&] { ok = ok && decodeAll(pages, p, &page_triangles); });
    lodrt::ValenceInfo info;
    const std::vector<uint8_t>& lbm = stream->bytes;
    ok = ok && lodrt::valenceReadInfo(lbm.data(), lbm.size(), &info) == lodrt::Result::Ok;
    std::vector<uint64_t> scratch(lodrt::valenceScratchSize(info) / 8 + 1);
    std::vector<float> positions(3 * size_t(info.vertex_count));
    std::vector<uint32_t> indices(3 * size_t(info.triangle_count));
    lodrt::ValenceOutput out;
    out.indices = indices.data();
    out.index_capacity = indices.size();
    out.positions = positions.data();
    out.position_capacity = positions.size();
    out.scratch = scratch.data();
    out.scratch_size = scratch.size() * 8;
    ok = ok && lodrt::valenceDecode(lbm.data(), lbm.size(), out) == lodrt::Result::Ok;
    const double lod0_ms =
        lodbake_bench::bestMs(3, [&] { ok = ok && lodrt::valenceDecode(lbm.data(), lbm.size(), out) == lodrt::Result::Ok; });
    if (!ok) return std::fprintf(stderr, "error: decoding failed\n"), false;
    const double lod0_tris = double(s.lod0_triangles);
    std::printf("%s: LOD0 %zu triangles, %zu clusters, %zu groups, %zu pages (largest %zu bytes), written in %.2f s (wall, all threads)\n",
                path.c_str(), s.lod0_triangles, built->clusters.size(), built->groups.size(), s.page_count,
                s.max_page_bytes, write_s);
    std::printf("  extension %zu bytes = %.3f per LOD0 triangle (table %zu, pages %zu, runs %zu)\n",
                s.table_bytes + s.page_bytes, double(s.table_bytes + s.page_bytes) / lod0_tris, s.table_bytes,
                s.page_bytes, s.run_bytes);
    std::printf("  LOD0-only pages %zu bytes vs LOD0 valence stream (positions, %u bits) %zu bytes: %.3fx\n",
                s.lod0_page_bytes, options.position_bits, lbm.size(), double(s.lod0_page_bytes) / double(lbm.size()));
    std::printf("  decode: all pages %.1f ms (%.2f M triangles/s) vs LOD0 stream %.1f ms (%.2f M triangles/s): %.2fx "
                "the time per triangle\n",
                pages_ms, double(page_triangles) / pages_ms / 1e3, lod0_ms, double(info.triangle_count) / lod0_ms / 1e3,
                (pages_ms / double(page_triangles)) / (lod0_ms / double(info.triangle_count)));
    return true;
}


// ---- Streaming fly-by ----

struct File {
    const std::vector<uint8_t>* bytes = nullptr;
    static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
        const File* f = static_cast<const File*>(user);
        if (offset > f->bytes->size() || size > f->bytes->size() - offset) return lodrt::Result::Truncated;
        std::memcpy(dst, f->bytes->data() + offset, size);
        return lodrt::Result::Ok;
    }
};

// Jobs queued by update() and run after the frame: a page arrives one or two frames after it is asked for.
struct FrameJobs {
    std::deque<std::pair<void (*)(void*), void*>> queue;
    static void submit(void* user, void (*run)(void*), void* task) {
        static_cast<FrameJobs*>(user)->queue.push_back({run, task});
    }
    void runAll() {
        while (!queue.empty()) {
            auto job = queue.front();
            queue.pop_front();
            job.first(job.second);
        }
    }
};

struct FlyResult {
    int first_settled = -1, frames_missing = 0, frames = 0;
    uint32_t max_pages = 0, reads = 0, evictions = 0, failures = 0;
    uint64_t max_page_bytes = 0, max_resident = 0;
    float settled_error = 0; // px, largest on frames with nothing missing
};

float drawnError(const lodrt::ClusterLodView& v, const uint32_t* drawn, uint32_t count, const float eye[3], float k) {
    float worst = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t g = v.clusters[drawn[i]].self_group;
        if (g == lodrt::kClusterNone) continue;
        const lodrt::ClusterLodGroup& gr = v.groups[g];
        const float dx = gr.lod_center[0] - eye[0], dy = gr.lod_center[1] - eye[1], dz = gr.lod_center[2] - eye[2];
        const float d = std::sqrt(dx * dx + dy * dy + dz * dz) - gr.lod_radius;
        worst = std::max(worst, d > 0 ? gr.error * k / d : (gr.error > 0 ? INFINITY : 0.0f));
    }
    return worst;
}

// One orbit at `distance` (times the bounding radius) from the centre; budget 0 = none.
bool flyBy(const std::vector<uint8_t>& glb, const float center[3], float radius, float distance, uint64_t budget,
           int frames, FlyResult* result) {
    File file{&glb};
    lodrt::PackSource source;
    if (source.openReader(lodrt::RangeReader{&File::read, &file}, glb.size(), nullptr) != lodrt::Result::Ok) return false;
    FrameJobs jobs;
    const lodrt::JobSystem system{&FrameJobs::submit, &jobs};
    lodrt::StreamerOptions options;
    options.budget_bytes = budget;
    lodrt::Streamer streamer;
    if (streamer.init(&source, &system, &options) != lodrt::Result::Ok || !streamer.clusterPack(0)) return false;
    const lodrt::ClusterLodPack& pack = *streamer.clusterPack(0);
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(pack.view) / 4 + 1, 0), out(pack.view.cluster_count),
        missing(pack.view.group_count);
    lodrt::ClusterCutScratch cut_scratch{scratch.data(), scratch.size() * 4, 0};
    lodrt::SelectionParams params;
    params.pixel_threshold = 1;
    params.viewport_height = 1080;
    params.vertical_fov = 1.0471976f;
    const float k = lodrt::pixelsPerUnitAtDistanceOne(params);
    FlyResult r;
    for (int f = 0; f < frames; ++f) {
        // The first quarter holds the first view (settling), then the camera orbits once.
        const float a = f < frames / 4 ? 0.0f : 6.2831853f * float(f - frames / 4) / float(frames - frames / 4);
        const float eye[3] = {center[0] + distance * radius * std::cos(a), center[1] + 0.3f * radius * std::sin(2 * a),
                              center[2] + distance * radius * std::sin(a)};
        streamer.update(nullptr);
        const uint8_t* groups = streamer.clusterGroupResident(0);
        uint32_t missing_count = 1;
        if (groups) {
            lodrt::ClusterResidency residency{groups, missing.data(), uint32_t(missing.size()), 0};
            lodrt::ClusterCutStats stats;
            if (lodrt::selectClusterCutResident(pack.view, lodrt::ClusterInstance(), eye, nullptr, params, cut_scratch,
                                                &residency, out.data(), uint32_t(out.size()), &stats) != lodrt::Result::Ok)
                return false;
            missing_count = std::min(residency.missing_count, uint32_t(missing.size()));
            streamer.wantClusterPages(0, out.data(), stats.written, missing.data(), missing_count, 1.0f);
            if (missing_count == 0) {
                r.settled_error = std::max(r.settled_error, drawnError(pack.view, out.data(), stats.written, eye, k));
                if (r.first_settled < 0) r.first_settled = f + 1;
            }
        }
        r.frames_missing += missing_count > 0;
        const lodrt::StreamStats st = streamer.stats();
        r.max_pages = std::max(r.max_pages, st.cluster_resident_pages);
        r.max_page_bytes = std::max(r.max_page_bytes, st.cluster_resident_bytes);
        r.max_resident = std::max(r.max_resident, st.resident_bytes + st.in_flight_bytes);
        jobs.runAll();
    }
    const lodrt::StreamStats st = streamer.stats();
    r.frames = frames;
    r.reads = st.cluster_page_reads;
    r.evictions = st.cluster_page_evictions;
    r.failures = st.failures;
    *result = r;
    return true;
}

bool runStreaming(const std::string& path) {
    lodbake::Diagnostics diagnostics;
    lodbake::Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return false;
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (const lodbake::Vec3f& p : mesh.positions)
        for (int j = 0; j < 3; ++j) {
            lo[j] = std::min(lo[j], p[j]);
            hi[j] = std::max(hi[j], p[j]);
        }
    const float center[3] = {0.5f * (lo[0] + hi[0]), 0.5f * (lo[1] + hi[1]), 0.5f * (lo[2] + hi[2])};
    const float radius = 0.5f * std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                          (hi[2] - lo[2]) * (hi[2] - lo[2]));
    lodbake::BakeSettings settings;
    settings.cluster_lod = true;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "scan";
    inputs[0].mesh = std::move(mesh);
    auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
    if (!baked.ok()) return std::fprintf(stderr, "error: %s\n", baked.status().message().c_str()), false;
    const std::vector<uint8_t>& glb = baked->glb;
    // Everything resident once (an orbit with no budget) sizes the small budget.
    FlyResult unlimited, small;
    const int frames = 400;
    if (!flyBy(glb, center, radius, 1.2f, 0, frames, &unlimited)) return false;
    FlyResult pinned_only;
    if (!flyBy(glb, center, radius, 1e6f, 0, 8, &pinned_only)) return false; // far away: root pages only
    const uint64_t budget = pinned_only.max_resident + unlimited.max_page_bytes / 4;
    if (!flyBy(glb, center, radius, 1.2f, budget, frames, &small)) return false;
    std::printf("  streamed orbit at 1.2x the bounding radius, %d frames (first %d at one view), 1 px at 1080 p:\n",
                frames, frames / 4);
    for (const auto& row : {std::make_pair("no budget", &unlimited), std::make_pair("small budget", &small)}) {
        const FlyResult& r = *row.second;
        std::printf("    %-12s budget %llu: first view settled after %d frames, %d frames with pages missing, "
                    "at most %u pages / %llu page bytes (resident + in flight %llu), %u reads, %u evictions, "
                    "%u failures, drawn error on settled frames %.3f px\n",
                    row.first, (unsigned long long)(row.second == &small ? budget : 0), r.first_settled,
                    r.frames_missing, r.max_pages, (unsigned long long)r.max_page_bytes,
                    (unsigned long long)r.max_resident, r.reads, r.evictions, r.failures, r.settled_error);
    }
    return true;
}

} // namespace

// ---- Streamed writer ----

// Live heap bytes (malloc_usable_size of every block from operator new) and their peak since
// resetHeapPeak(): what the writers hold, without the allocator's free lists and arenas that the
// resident memory also shows.
std::atomic<int64_t> g_heap_live{0}, g_heap_peak{0};

void resetHeapPeak() { g_heap_peak.store(g_heap_live.load()); }


double statusMiB(const char* key) {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line))
        if (line.rfind(key, 0) == 0) return std::strtod(line.c_str() + std::strlen(key), nullptr) / 1024.0;
    return NAN;
}

// Frees what malloc keeps, resets the peak and returns the resident memory now, in MiB.
double startMeasure() {
    malloc_trim(0);
    resetHeapPeak();
    std::ofstream("/proc/self/clear_refs") << "5";
    return statusMiB("VmRSS:");
}

double heapPeakMiB(int64_t before) { return double(g_heap_peak.load() - before) / (1024.0 * 1024.0); }

// CPU seconds of the process (every thread): on a shared machine wall time also counts waiting.
double cpuSeconds() {
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// Page geometry read back from a file written in page order, as an out-of-core hierarchy would
// hand it over.
class FilePageSource : public lodbake::ClusterPageSource {
public:
    int fd = -1;
    std::vector<uint64_t> offset; // per page, then the end
    std::vector<uint32_t> vertices;
    lodbake::Status readPage(uint32_t page, const uint32_t*, size_t, lodbake::ClusterPageGeometry& out) override {
        out.positions.resize(vertices[page]);
        const size_t position_bytes = 12 * size_t(vertices[page]);
        out.indices.resize(size_t(offset[page + 1] - offset[page]) - position_bytes);
        if (::pread(fd, out.positions.data(), position_bytes, off_t(offset[page])) != ssize_t(position_bytes) ||
            ::pread(fd, out.indices.data(), out.indices.size(), off_t(offset[page] + position_bytes)) !=
                ssize_t(out.indices.size()))
            return lodbake::ioError("page file: read failed");
        return lodbake::Status::okStatus();
    }
};

// Each page's positions, then its indices, cluster after cluster.
bool writePageFile(const lodbake::ClusterLodHierarchy& h, const std::string& path, FilePageSource& source) {
    const lodbake::ClusterPagePlan plan = lodbake::planClusterPages(h.view());
    std::ofstream file(path, std::ios::binary);
    uint64_t at = 0;
    for (size_t p = 0; p < plan.pageCount(); ++p) {
        source.offset.push_back(at);
        uint32_t v = 0;
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i) {
            const lodrt::ClusterLodCluster& c = h.clusters[plan.page_clusters[i]];
            file.write(reinterpret_cast<const char*>(h.positions.data() + c.first_vertex), 12 * std::streamsize(c.vertex_count));
            v += c.vertex_count;
        }
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i) {
            const lodrt::ClusterLodCluster& c = h.clusters[plan.page_clusters[i]];
            file.write(reinterpret_cast<const char*>(h.indices.data() + 3 * size_t(c.first_triangle)),
                       3 * std::streamsize(c.triangle_count));
        }
        source.vertices.push_back(v);
        at += 12 * uint64_t(v);
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i)
            at += 3 * uint64_t(h.clusters[plan.page_clusters[i]].triangle_count);
    }
    source.offset.push_back(at);
    file.close();
    source.fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    return bool(file) && source.fd >= 0;
}

// The roots' triangles as one mesh: the pack's one discrete level.
lodbake::Mesh rootsMesh(const lodbake::ClusterLodHierarchy& h) {
    lodbake::Mesh m;
    for (uint32_t r : h.roots) {
        const lodrt::ClusterLodCluster& c = h.clusters[r];
        const uint32_t base = uint32_t(m.positions.size());
        m.positions.insert(m.positions.end(), h.positions.begin() + c.first_vertex,
                           h.positions.begin() + c.first_vertex + c.vertex_count);
        for (uint32_t i = 0; i < 3 * c.triangle_count; ++i)
            m.indices.push_back(base + h.indices[3 * size_t(c.first_triangle) + i]);
    }
    return m;
}

lodbake::PackDescription onePack(const lodbake::Mesh& level, lodbake::PackExtension clusters) {
    lodbake::PackDescription d;
    d.assets.resize(1);
    d.assets[0].name = "scan";
    d.assets[0].levels.resize(1);
    d.assets[0].levels[0].mesh = level;
    d.assets[0].levels[0].mesh_extensions.push_back(std::move(clusters));
    return d;
}

bool runStream(const std::string& path, const std::string& dir, size_t in_flight) {
    lodbake::Diagnostics diagnostics;
    lodbake::Mesh mesh;
    if (!lodbake_bench::loadRepaired(path, mesh, diagnostics)) return false;
    auto built = lodbake::buildClusterLod(lodbake::MeshView(mesh), lodbake::ClusterLodOptions{}, diagnostics);
    if (!built.ok()) return std::fprintf(stderr, "error: %s\n", built.status().message().c_str()), false;
    mesh = lodbake::Mesh();
    lodbake::ClusterLodHierarchy& h = *built;
    const lodbake::Mesh level = rootsMesh(h);
    size_t lod0_triangles = 0;
    for (uint32_t c = 0; c < h.lod0_cluster_count; ++c) lod0_triangles += h.clusters[c].triangle_count;
    std::printf("%s: %zu clusters, %zu groups, %zu LOD0 triangles, level (the roots) of %zu triangles\n", path.c_str(),
                h.clusters.size(), h.groups.size(), lod0_triangles, level.faceCount());
    // In memory: the extension and the GLB as bytes.
    uint64_t memory_hash = 0, memory_size = 0;
    {
        const double before = startMeasure();
        const int64_t heap_before = g_heap_live.load();
        const auto start = std::chrono::steady_clock::now();
        const double cpu = cpuSeconds();
        auto written = lodbake::writeClusterLodPack(h, lodbake::ClusterPackOptions{});
        if (!written.ok()) return std::fprintf(stderr, "error: %s\n", written.status().message().c_str()), false;
        auto glb = lodbake::writePackGlb(onePack(level, std::move(written->extension)));
        if (!glb.ok()) return std::fprintf(stderr, "error: %s\n", glb.status().message().c_str()), false;
        const double s = seconds(start), peak = statusMiB("VmHWM:") - before, cpu_s = cpuSeconds() - cpu;
        lodbake::Hasher hasher;
        hasher.addBytes(glb->data(), glb->size());
        memory_hash = hasher.digest();
        memory_size = glb->size();
        std::printf("  in memory (writeClusterLodPack + writePackGlb): %.2f s wall, %.2f s CPU, peak RSS +%.1f MiB, heap "
                    "+%.1f MiB, pack %llu bytes (pages %zu)\n",
                    s, cpu_s, peak, heapPeakMiB(heap_before), (unsigned long long)memory_size, written->stats.page_bytes);
    }
    // Streamed: the geometry to a file and dropped, then read back a page at a time.
    FilePageSource source;
    const std::string pages_path = dir + "/cluster_pack_bench_pages.bin", out = dir + "/cluster_pack_bench_stream.glb";
    if (!writePageFile(h, pages_path, source)) return std::fprintf(stderr, "error: cannot write %s\n", pages_path.c_str()), false;
    const lodrt::ClusterLodView view = h.view();
    const lodbake::ClusterPackBounds bounds = lodbake::clusterPackBounds(h);
    std::vector<lodbake::Vec3f>().swap(h.positions);
    std::vector<uint8_t>().swap(h.indices);
    const double before = startMeasure();
    const int64_t heap_before = g_heap_live.load();
    const auto start = std::chrono::steady_clock::now();
    const double cpu = cpuSeconds();
    lodbake::ClusterPackStreamOptions options;
    options.pages_in_flight = in_flight;
    auto streamed = lodbake::writeClusterLodPackStreamed(view, bounds, source, out, options);
    if (!streamed.ok()) return std::fprintf(stderr, "error: %s\n", streamed.status().message().c_str()), false;
    const uint64_t bound = streamed->memory_bound_bytes, accounted = streamed->accounted_peak_bytes;
    const double pages_peak = statusMiB("VmHWM:") - before, pages_heap = heapPeakMiB(heap_before);
    streamed->pages.reset();
    auto file_size = lodbake::writePackGlbFile(onePack(level, std::move(streamed->extension)), out);
    if (!file_size.ok()) return std::fprintf(stderr, "error: %s\n", file_size.status().message().c_str()), false;
    const double s = seconds(start), peak = statusMiB("VmHWM:") - before, heap = heapPeakMiB(heap_before),
                 cpu_s = cpuSeconds() - cpu;
    ::close(source.fd);
    ::unlink(pages_path.c_str());
    auto bytes = lodbake::readFileBytes(out);
    ::unlink(out.c_str());
    if (!bytes.ok()) return false;
    lodbake::Hasher hasher;
    hasher.addBytes(bytes->data(), bytes->size());
    const double mib = 1.0 / (1024.0 * 1024.0);
    std::printf("  streamed (writeClusterLodPackStreamed + writePackGlbFile, %zu pages in flight): %.2f s wall, %.2f s CPU, peak RSS "
                "+%.1f MiB, heap +%.1f MiB (pages alone: RSS +%.1f MiB, heap +%.1f MiB), formula %.1f MiB, accounted "
                "%.1f MiB; table records lent %.1f MiB, level %.1f MiB\n",
                in_flight, s, cpu_s, peak, heap, pages_peak, pages_heap, double(bound) * mib, double(accounted) * mib,
                double(view.cluster_count * sizeof(lodrt::ClusterLodCluster) +
                       view.group_count * sizeof(lodrt::ClusterLodGroup) + 4 * (view.group_child_count + view.root_count)) *
                    mib,
                double(level.positions.size() * 12 + level.indices.size() * 4) * mib);
    std::printf("  same bytes as in memory: %s (%llu bytes)\n",
                hasher.digest() == memory_hash && bytes->size() == memory_size ? "yes" : "NO",
                (unsigned long long)bytes->size());
    return hasher.digest() == memory_hash;
}

int main(int argc, char** argv) {
    std::vector<std::string> meshes;
    std::string stream_mesh, dir = "/tmp";
    size_t in_flight = 0;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--stream" && i + 1 < argc) {
            stream_mesh = argv[++i];
        } else if (arg == "--dir" && i + 1 < argc) {
            dir = argv[++i];
        } else if (arg == "--in-flight" && i + 1 < argc) {
            in_flight = size_t(std::strtoul(argv[++i], nullptr, 10));
        } else {
            meshes.push_back(arg);
        }
    }
    if (!stream_mesh.empty()) return runStream(stream_mesh, dir, in_flight > 0 ? in_flight : 4) ? 0 : 1;
    if (meshes.empty())
        for (const char* name : {"bunny_zipper.ply", "igea.ply", "dragon_poisson.ply"})
            meshes.push_back(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name);
    bool ok = true;
    for (const std::string& m : meshes) ok = run(m) && ok;
    ok = runStreaming(meshes[0]) && ok;
    return ok ? 0 : 1;
}

void* operator new(size_t size) {
    void* p = std::malloc(size ? size : 1);
    if (!p) throw std::bad_alloc();
    const int64_t live = g_heap_live.fetch_add(int64_t(malloc_usable_size(p))) + int64_t(malloc_usable_size(p));
    int64_t peak = g_heap_peak.load();
    while (live > peak && !g_heap_peak.compare_exchange_weak(peak, live)) {
    }
    return p;
}
void operator delete(void* p) noexcept {
    if (!p) return;
    g_heap_live.fetch_sub(int64_t(malloc_usable_size(p)));
    std::free(p);
}
void operator delete(void* p, size_t) noexcept { operator delete(p); }
