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
// usage: cluster_pack_bench [MESH...]   (default: bunny_zipper, igea, dragon_poisson from ../shared/meshes)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <string>
#include <utility>
#include <vector>

#include "bench_mesh.h"
#include "bench_timing.h"
#include "lodbake/bake/bake.h"
#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/codec/valence_encoder.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/streaming.h"
#include "lodrt/valence.h"

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

int main(int argc, char** argv) {
    std::vector<std::string> meshes;
    for (int i = 1; i < argc; ++i) meshes.push_back(argv[i]);
    if (meshes.empty())
        for (const char* name : {"bunny_zipper.ply", "igea.ply", "dragon_poisson.ply"})
            meshes.push_back(std::string(LODBAKE_BENCH_MESHES_DIR) + "/" + name);
    bool ok = true;
    for (const std::string& m : meshes) ok = run(m) && ok;
    ok = runStreaming(meshes[0]) && ok;
    return ok ? 0 : 1;
}
