// pfrep_region_bench: PFRep region blocks (docs/format/pfrep.md "Region blocks"), issue 30's region
// loading bar: a camera flying close past one end of a scan at 1 px loads <= 30 % of the region
// blob's bytes (header, directory and skeleton plus the blocks pfrepRegionBlocksNeeded listed at
// any frame, loaded as the flight goes and never evicted), with the same triangles on screen as the
// whole blob gives. The anchor is the whole blob: it is refined alongside from the same masks, the
// two masks are compared after every refinement step and the meshes at every settled frame.
// Refinement time of the region model and of the whole blob (thread CPU over the flight, median of
// the runs) shows what residency costs. Then the same flight through the shipping path: the mesh
// baked into a pack with `pfrep_format` 5, read by a lodrt::Streamer through a range reader that
// counts the blob's bytes, the views reported with wantPfrepBlocks; its bytes over the region blob
// are the bar again, and every settled mesh is compared with the whole table's. The pack is baked
// with --block as pfrep_region_block (its root block keeps the bake's 4,096 vertices), from the mesh
// as the bake repairs it, so its blob is not the first pass's.
// usage: pfrep_region_bench [--mesh PATH] [--frames N] [--height H] [--block V] [--root V] [--runs R] [--check]
//   height: the flight's height above the bounding box in diagonals (0.15).
//   default mesh: dragon_poisson.ply from the shared meshes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "../baker/pfrep/pfrep_region_view.h"
#include "bench_bar.h"
#include "bench_timing.h"
#include "lodbake/bake/bake.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/pfrep/pfrep_region.h"
#include "lodrt/pfrep.h"
#include "lodrt/streaming.h"

namespace {

using lodbake_bench::Limit;
using lodbake_bench::threadCpuSeconds;

double wallSeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Options {
    std::string mesh = std::string(LODBAKE_BENCH_SHARED_MESHES_DIR) + "/dragon_poisson.ply";
    int frames = 48;
    int runs = 3;
    float height = 0.15f; // the flight's height above the box, in diagonals
    lodbake::PfrepRegionOptions region;
};

// The flight: along the second-longest axis, past the low end of the longest axis, `height`
// diagonals above the box's top face on the third axis, looking at a point near that end.
lodrt::PfrepView flightView(const float lo[3], const float hi[3], float height, int frame, int frames) {
    float size[3], diag = 0;
    int axis[3] = {0, 1, 2};
    for (int k = 0; k < 3; ++k) {
        size[k] = hi[k] - lo[k];
        diag += size[k] * size[k];
    }
    diag = std::sqrt(diag);
    std::sort(axis, axis + 3, [&](int a, int b) { return size[a] > size[b]; });
    const int l = axis[0], s = axis[1], t = axis[2];
    const float u = float(frame) / float(std::max(frames - 1, 1));
    float eye[3], target[3];
    eye[l] = lo[l] + 0.1f * size[l];
    eye[s] = lo[s] - 0.2f * size[s] + 1.4f * size[s] * u;
    eye[t] = hi[t] + height * diag;
    target[l] = lo[l] + 0.1f * size[l];
    target[s] = lo[s] + size[s] * (0.25f + 0.5f * u);
    target[t] = lo[t] + 0.5f * size[t];
    return lodbake_test::cameraView(eye, target, 1.0471976f, 16.0f / 9.0f, 0.001f * diag, 100.0f * diag, 1080.0f, 1.0f);
}

struct Flight {
    bool same = true;         // masks equal after every step, meshes at every settled frame
    size_t max_triangles = 0; // largest settled mesh
    size_t steps = 0;
    double region_cpu = 0, whole_cpu = 0;
    std::vector<uint8_t> keep_listed; // blocks listed at the keep threshold at some frame
    double load_cpu = 0;               // pfrepRegionLoadBlock, thread CPU
    uint64_t load_bytes = 0, load_vertices = 0;
};

// Runs the flight on both models from their coarsest masks; loads needed blocks when `regions_blob`
// is given (the first run), else uses what is loaded.
Flight fly(lodrt::PfrepRegions& g, const std::vector<uint8_t>* regions_blob, lodrt::PfrepModel& whole,
           const float lo[3], const float hi[3], float height, int frames, std::vector<float>& region_table) {
    Flight f;
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(whole)), mask_b(mask_a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(whole));
    std::vector<uint32_t> needed(g.block_count), ia(size_t(whole.level0_triangles) * 3), ib(ia.size());
    f.keep_listed.assign(g.block_count, 0);
    for (int frame = 0; frame < frames; ++frame) {
        const lodrt::PfrepView view = flightView(lo, hi, height, frame, frames);
        if (regions_blob) {
            size_t count = 0;
            // At the insert threshold: what the whole blob's insertions need (blocks are never evicted
            // here, so kept vertices stay resident).
            lodrt::PfrepView insert = view;
            insert.hysteresis = 1.0f;
            insert.cull_hysteresis = 0.0f;
            (void)lodrt::pfrepRegionBlocksNeeded(g, view, needed.data(), needed.size(), &count);
            for (size_t k = 0; k < count; ++k) f.keep_listed[needed[k]] = 1;
            (void)lodrt::pfrepRegionBlocksNeeded(g, insert, needed.data(), needed.size(), &count);
            bool loaded = false;
            for (size_t k = 0; k < count; ++k) {
                if (g.block_loaded[needed[k]]) continue;
                const lodrt::PfrepRegionBlock& b = g.blocks[needed[k]];
                const double t = threadCpuSeconds();
                if (lodrt::pfrepRegionLoadBlock(&g, needed[k], regions_blob->data() + b.offset, b.size) !=
                    lodrt::Result::Ok)
                    f.same = false;
                f.load_cpu += threadCpuSeconds() - t;
                f.load_bytes += b.size;
                f.load_vertices += b.vertices;
                loaded = true;
            }
            if (loaded) (void)lodrt::pfrepAttachCriterionTable(&g.model, region_table.data(), region_table.size());
        }
        if (frame == 0) {
            lodrt::pfrepMaskCoarsest(g.model, mask_a.data());
            lodrt::pfrepMaskCoarsest(whole, mask_b.data());
        }
        for (int step = 0; step < 64; ++step) {
            size_t ca = 0, cb = 0;
            // Alternating which model goes first, so neither always finds the other's data in cache.
            for (int which = 0; which < 2; ++which) {
                const double t = threadCpuSeconds();
                if ((which == 0) == (step % 2 == 0)) {
                    (void)lodrt::pfrepRefine(g.model, view, mask_a.data(), scratch.data(), scratch.size(), &ca);
                    f.region_cpu += threadCpuSeconds() - t;
                } else {
                    (void)lodrt::pfrepRefine(whole, view, mask_b.data(), scratch.data(), scratch.size(), &cb);
                    f.whole_cpu += threadCpuSeconds() - t;
                }
            }
            ++f.steps;
            if (mask_a != mask_b) f.same = false;
            if (ca == 0 && cb == 0) break;
        }
        size_t na = 0, nb = 0;
        (void)lodrt::pfrepExtractSelective(g.model, mask_a.data(), ia.data(), ia.size() / 3, &na);
        (void)lodrt::pfrepExtractSelective(whole, mask_b.data(), ib.data(), ib.size() / 3, &nb);
        if (na != nb || !std::equal(ia.begin(), ia.begin() + long(na * 3), ib.begin())) f.same = false;
        f.max_triangles = std::max(f.max_triangles, na);
    }
    return f;
}

// The same flight as a streamer that evicts would run it: each frame the blocks listed at the view's
// own keep threshold are resident and every other block (but the root) is released from the mask and
// evicted. Counts refinement steps whose masks differ from the whole blob's and settled frames whose
// meshes differ, the peak resident bytes and every byte read (reloads included).
struct Evicting {
    size_t differing_steps = 0, differing_frames = 0, steps = 0, evictions = 0, loads = 0;
    uint64_t peak_bytes = 0, read_bytes = 0;
};

Evicting flyEvicting(lodrt::PfrepRegions& g, const std::vector<uint8_t>& blob, lodrt::PfrepModel& whole,
                     const float lo[3], const float hi[3], float height, int frames,
                     std::vector<float>& region_table) {
    Evicting e;
    e.read_bytes = g.loaded_bytes;
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(whole)), mask_b(mask_a.size()), listed(g.block_count);
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(whole));
    std::vector<uint32_t> needed(g.block_count), ia(size_t(whole.level0_triangles) * 3), ib(ia.size());
    lodrt::pfrepMaskCoarsest(g.model, mask_a.data());
    lodrt::pfrepMaskCoarsest(whole, mask_b.data());
    for (int frame = 0; frame < frames; ++frame) {
        const lodrt::PfrepView view = flightView(lo, hi, height, frame, frames);
        size_t count = 0;
        (void)lodrt::pfrepRegionBlocksNeeded(g, view, needed.data(), needed.size(), &count);
        std::fill(listed.begin(), listed.end(), 0);
        for (size_t k = 0; k < count; ++k) listed[needed[k]] = 1;
        for (uint32_t k = 1; k < g.block_count; ++k) {
            if (!g.block_loaded[k] || listed[k]) continue;
            (void)lodrt::pfrepRegionReleaseMask(g, k, mask_a.data(), scratch.data(), scratch.size());
            (void)lodrt::pfrepRegionEvictBlock(&g, k);
            ++e.evictions;
        }
        for (size_t k = 0; k < count; ++k) {
            if (g.block_loaded[needed[k]]) continue;
            const lodrt::PfrepRegionBlock& b = g.blocks[needed[k]];
            (void)lodrt::pfrepRegionLoadBlock(&g, needed[k], blob.data() + b.offset, b.size);
            e.read_bytes += b.size;
            ++e.loads;
        }
        (void)lodrt::pfrepAttachCriterionTable(&g.model, region_table.data(), region_table.size());
        e.peak_bytes = std::max(e.peak_bytes, g.loaded_bytes);
        for (int step = 0; step < 64; ++step) {
            size_t ca = 0, cb = 0;
            (void)lodrt::pfrepRefine(g.model, view, mask_a.data(), scratch.data(), scratch.size(), &ca);
            (void)lodrt::pfrepRefine(whole, view, mask_b.data(), scratch.data(), scratch.size(), &cb);
            ++e.steps;
            e.differing_steps += mask_a != mask_b;
            if (ca == 0 && cb == 0) break;
        }
        size_t na = 0, nb = 0;
        (void)lodrt::pfrepExtractSelective(g.model, mask_a.data(), ia.data(), ia.size() / 3, &na);
        (void)lodrt::pfrepExtractSelective(whole, mask_b.data(), ib.data(), ib.size() / 3, &nb);
        e.differing_frames += na != nb || !std::equal(ia.begin(), ia.begin() + long(na * 3), ib.begin());
    }
    return e;
}

// A pack in memory served by range reads, counting the bytes read inside [watch_begin, watch_end).
struct CountingReader {
    const std::vector<uint8_t>* bytes = nullptr;
    uint64_t watch_begin = 0, watch_end = 0, watched = 0;
    static lodrt::Result read(void* user, uint64_t offset, void* dst, size_t size) {
        CountingReader* r = static_cast<CountingReader*>(user);
        if (offset > r->bytes->size() || size > r->bytes->size() - offset) return lodrt::Result::Truncated;
        const uint64_t lo = std::max(offset, r->watch_begin), hi = std::min(offset + size, r->watch_end);
        if (hi > lo) r->watched += hi - lo;
        std::memcpy(dst, r->bytes->data() + offset, size);
        return lodrt::Result::Ok;
    }
};

struct StreamedFlight {
    bool ok = false, same = true;
    uint64_t blob_bytes = 0, read_bytes = 0;
    uint32_t blocks = 0, blocks_loaded = 0, requests = 0;
    size_t max_triangles = 0;
};

// The flight through a Streamer (jobs inline) over a pack baked with format 5: each frame the view is
// reported and update() called until it requests nothing more; then the streamed model and the whole
// table (every block loaded from the pack's blob) are refined to a fixed point from the same masks.
StreamedFlight flyStreamer(const lodbake::Mesh& mesh, uint32_t block_vertices, float height, int frames) {
    StreamedFlight f;
    lodbake::BakeSettings settings;
    settings.pfrep_format = lodrt::format::kPfrepFormatRegions;
    settings.pfrep_region_block = block_vertices;
    std::vector<lodbake::BakeInput> inputs(1);
    inputs[0].name = "scan";
    inputs[0].mesh = mesh;
    lodbake::Diagnostics d;
    auto baked = lodbake::bake(std::move(inputs), settings, d);
    if (!baked.ok()) {
        std::printf("bake failed: %s\n", baked.status().message().c_str());
        return f;
    }
    const std::vector<uint8_t>& glb = baked->glb;
    CountingReader reader;
    reader.bytes = &glb;
    lodrt::PackSource source;
    if (source.openReader(lodrt::RangeReader{&CountingReader::read, &reader}, glb.size(), nullptr) != lodrt::Result::Ok)
        return f;
    const lodrt::JsonValue ext = source.pack()
                                     .mesh(source.models().modelLevel(0, 0).mesh)
                                     .json.find("extensions")
                                     .find(lodrt::format::kExtProgressiveFans);
    uint64_t view_index = 0;
    if (!ext.find("bufferView").asUint64(&view_index)) return f;
    const lodrt::BufferViewInfo& view_info = source.pack().bufferView(uint32_t(view_index));
    uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    reader.watch_begin = 20 + uint64_t(json_length) + 8 + view_info.byte_offset;
    reader.watch_end = reader.watch_begin + view_info.byte_length;
    f.blob_bytes = view_info.byte_length;
    // The anchor: the whole table, every block of the pack's blob loaded.
    const uint8_t* blob = glb.data() + reader.watch_begin;
    lodrt::PfrepRegionInfo info;
    if (lodrt::pfrepRegionInfo(blob, size_t(f.blob_bytes), &info) != lodrt::Result::Ok) return f;
    std::vector<uint8_t> table(info.decoded_bytes);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions all;
    if (lodrt::pfrepRegionOpen(blob, size_t(f.blob_bytes), table.data(), table.size(), state.data(), state.size() * 8,
                               &all) != lodrt::Result::Ok)
        return f;
    for (uint32_t k = 0; k < all.block_count; ++k)
        if (lodrt::pfrepRegionLoadBlock(&all, k, blob + all.blocks[k].offset, all.blocks[k].size) != lodrt::Result::Ok)
            return f;
    lodrt::PfrepModel whole;
    if (lodrt::openPfrep(table.data(), table.size(), &whole) != lodrt::Result::Ok) return f;
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = whole.position_min[k];
        hi[k] = whole.position_min[k] + 65535.0f * whole.position_step[k];
    }
    lodrt::Streamer streamer;
    if (streamer.init(&source, nullptr, nullptr) != lodrt::Result::Ok) return f;
    for (int i = 0; i < 4; ++i) streamer.update(nullptr);
    const lodrt::PfrepModel* model = streamer.pfrepModel(0);
    if (!model) return f;
    std::vector<uint8_t> mask_a(lodrt::pfrepMaskBytes(whole)), mask_b(mask_a.size());
    std::vector<uint32_t> scratch(lodrt::pfrepScratchValues(whole));
    std::vector<uint32_t> ia(size_t(whole.level0_triangles) * 3), ib(ia.size());
    lodrt::pfrepMaskCoarsest(*model, mask_a.data());
    lodrt::pfrepMaskCoarsest(whole, mask_b.data());
    for (int frame = 0; frame < frames; ++frame) {
        const lodrt::PfrepView view = flightView(lo, hi, height, frame, frames);
        for (int i = 0; i < 1000; ++i) {
            const uint32_t before = streamer.stats().requests;
            streamer.wantPfrepBlocks(0, view, 1.0f);
            streamer.update(nullptr);
            if (streamer.stats().requests == before) break;
        }
        for (int step = 0; step < 64; ++step) {
            size_t ca = 0, cb = 0;
            (void)lodrt::pfrepRefine(*model, view, mask_a.data(), scratch.data(), scratch.size(), &ca);
            (void)lodrt::pfrepRefine(whole, view, mask_b.data(), scratch.data(), scratch.size(), &cb);
            if (mask_a != mask_b) f.same = false;
            if (ca == 0 && cb == 0) break;
        }
        size_t na = 0, nb = 0;
        (void)lodrt::pfrepExtractSelective(*model, mask_a.data(), ia.data(), ia.size() / 3, &na);
        (void)lodrt::pfrepExtractSelective(whole, mask_b.data(), ib.data(), ib.size() / 3, &nb);
        if (na != nb || !std::equal(ia.begin(), ia.begin() + long(na * 3), ib.begin())) f.same = false;
        f.max_triangles = std::max(f.max_triangles, na);
    }
    const lodrt::PfrepRegions* regions = streamer.pfrepRegions(0);
    f.blocks = regions->block_count;
    for (uint32_t k = 0; k < regions->block_count; ++k) f.blocks_loaded += regions->block_loaded[k];
    f.read_bytes = reader.watched;
    f.requests = streamer.stats().requests;
    f.ok = streamer.stats().failures == 0;
    return f;
}

bool parse(int argc, char** argv, Options& o) {
    for (int a = 1; a < argc; ++a) {
        const bool has = a + 1 < argc;
        if (std::strcmp(argv[a], "--mesh") == 0 && has)
            o.mesh = argv[++a];
        else if (std::strcmp(argv[a], "--frames") == 0 && has)
            o.frames = std::max(2, std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--height") == 0 && has)
            o.height = float(std::atof(argv[++a]));
        else if (std::strcmp(argv[a], "--runs") == 0 && has)
            o.runs = std::max(1, std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--block") == 0 && has)
            o.region.block_vertices = uint32_t(std::atoi(argv[++a]));
        else if (std::strcmp(argv[a], "--root") == 0 && has)
            o.region.root_vertices = uint32_t(std::atoi(argv[++a]));
        else {
            std::fprintf(stderr, "pfrep_region_bench: unknown argument %s\n", argv[a]);
            return false;
        }
    }
    return true;
}

} // namespace

int main(int argc, char** argv) {
    const bool check = lodbake_bench::takeCheckFlag(argc, argv);
    Options o;
    if (!parse(argc, argv, o)) return 2;
    lodbake_bench::Bars bars("pfrep_region_bench");
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(o.mesh, {}, d);
    if (!loaded.ok()) {
        std::printf("%s\n", loaded.status().message().c_str());
        bars.unmeasured("region bytes loaded / region blob", 0.30, Limit::AtMost, false);
        return bars.finish(check);
    }
    const double t0 = wallSeconds();
    auto built = lodbake::buildPfrep(loaded->mesh, {}, d);
    if (!built.ok()) {
        std::printf("build failed: %s\n", built.status().message().c_str());
        return 1;
    }
    const double t1 = wallSeconds();
    lodbake::PfrepRegionStats stats;
    auto region = lodbake::writePfrepRegions(built->blob, o.region, &stats);
    if (!region.ok()) {
        std::printf("region writer failed: %s\n", region.status().message().c_str());
        return 1;
    }
    const double t2 = wallSeconds();
    const std::vector<uint8_t>& blob = *region;
    std::printf("%s: V %zu, format 2 blob %zu bytes, region blob %zu bytes (%.3f x), %u blocks in %u bands, "
                "open part %llu bytes, root block %llu bytes; build %.1f s, region writer %.1f s\n",
                o.mesh.c_str(), built->rank_point.size(), built->blob.size(), blob.size(),
                double(blob.size()) / double(built->blob.size()), stats.blocks, stats.bands,
                (unsigned long long)stats.open_bytes, (unsigned long long)stats.root_bytes, t1 - t0, t2 - t1);
    lodrt::PfrepModel whole;
    if (lodrt::openPfrep(built->blob.data(), built->blob.size(), &whole) != lodrt::Result::Ok) return 1;
    std::vector<float> whole_table(lodrt::pfrepCriterionTableFloats(whole)), region_table(whole_table.size());
    (void)lodrt::pfrepAttachCriterionTable(&whole, whole_table.data(), whole_table.size());
    lodrt::PfrepRegionInfo info;
    if (lodrt::pfrepRegionInfo(blob.data(), blob.size(), &info) != lodrt::Result::Ok) return 1;
    std::vector<uint8_t> decoded(info.decoded_bytes);
    std::vector<uint64_t> state((info.state_bytes + 7) / 8);
    lodrt::PfrepRegions g;
    if (lodrt::pfrepRegionOpen(blob.data(), blob.size(), decoded.data(), decoded.size(), state.data(), info.state_bytes,
                               &g) != lodrt::Result::Ok ||
        lodrt::pfrepRegionLoadBlock(&g, 0, blob.data() + g.blocks[0].offset, g.blocks[0].size) != lodrt::Result::Ok)
        return 1;
    (void)lodrt::pfrepAttachCriterionTable(&g.model, region_table.data(), region_table.size());
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = whole.position_min[k];
        hi[k] = whole.position_min[k] + 65535.0f * whole.position_step[k];
    }
    std::vector<double> region_cpu, whole_cpu;
    bool same = true;
    Flight first;
    for (int run = 0; run < o.runs; ++run) {
        const Flight f = fly(g, run == 0 ? &blob : nullptr, whole, lo, hi, o.height, o.frames, region_table);
        if (run == 0) first = f;
        same &= f.same;
        region_cpu.push_back(f.region_cpu);
        whole_cpu.push_back(f.whole_cpu);
    }
    std::sort(region_cpu.begin(), region_cpu.end());
    std::sort(whole_cpu.begin(), whole_cpu.end());
    const double rc = region_cpu[region_cpu.size() / 2], wc = whole_cpu[whole_cpu.size() / 2];
    uint32_t blocks_loaded = 0;
    for (uint32_t k = 0; k < g.block_count; ++k) blocks_loaded += g.block_loaded[k];
    const double fraction = double(g.loaded_bytes) / double(blob.size());
    std::printf("flight %.2f diagonals above the box: %d frames, %zu refinement steps, largest settled mesh %zu "
                "triangles; loaded %u of %u blocks, "
                "%llu of %zu bytes = %.3f of the region blob (%.3f of the format 2 blob); masks and meshes %s\n",
                double(o.height), o.frames, first.steps, first.max_triangles, blocks_loaded, g.block_count,
                (unsigned long long)g.loaded_bytes, blob.size(), fraction,
                double(g.loaded_bytes) / double(built->blob.size()), same ? "equal to the whole blob's" : "DIFFER");
    uint64_t keep_bytes = g.open_bytes;
    for (uint32_t k = 0; k < g.block_count; ++k) keep_bytes += first.keep_listed[k] ? g.blocks[k].size : 0;
    std::printf("blocks listed at the keep threshold (hysteresis %.2f, for a streamer that evicts): %.3f of the "
                "region blob\n",
                double(lodrt::PfrepView().hysteresis), double(keep_bytes) / double(blob.size()));
    // Anchor: validating the whole format 2 blob in place (openPfrep).
    lodrt::PfrepModel reopened;
    const double t_open = threadCpuSeconds();
    (void)lodrt::openPfrep(built->blob.data(), built->blob.size(), &reopened);
    const double open_cpu = threadCpuSeconds() - t_open;
    std::printf("block loading (validate and lay out), thread CPU: %.1f MB/s, %.1f M vertices/s; openPfrep of the "
                "whole format 2 blob: %.1f M vertices/s\n",
                double(first.load_bytes) / first.load_cpu * 1e-6, double(first.load_vertices) / first.load_cpu * 1e-6,
                double(reopened.vertex_count) / open_cpu * 1e-6);
    std::printf("refinement over the flight, thread CPU, median of %d runs: region model %.2f ms, whole blob %.2f ms "
                "(ratio %.3f)\n",
                o.runs, rc * 1e3, wc * 1e3, rc / wc);
    {
        // A fresh open for the evicting flight (root loaded, nothing else).
        std::vector<uint8_t> decoded2(info.decoded_bytes);
        std::vector<uint64_t> state2((info.state_bytes + 7) / 8);
        lodrt::PfrepRegions g2;
        if (lodrt::pfrepRegionOpen(blob.data(), blob.size(), decoded2.data(), decoded2.size(), state2.data(),
                                   info.state_bytes, &g2) == lodrt::Result::Ok &&
            lodrt::pfrepRegionLoadBlock(&g2, 0, blob.data() + g2.blocks[0].offset, g2.blocks[0].size) ==
                lodrt::Result::Ok) {
            const Evicting e = flyEvicting(g2, blob, whole, lo, hi, o.height, o.frames, region_table);
            std::printf("evicting flight (blocks listed at the keep threshold resident, the others released and "
                        "evicted): %zu block loads, %zu evictions, peak resident %.3f of the region blob, bytes read %.3f; "
                        "%zu of %zu steps with masks differing from the whole blob's, %zu of %d settled frames "
                        "with differing meshes\n",
                        e.loads, e.evictions, double(e.peak_bytes) / double(blob.size()), double(e.read_bytes) / double(blob.size()),
                        e.differing_steps, e.steps, e.differing_frames, o.frames);
        }
    }
    const StreamedFlight sf = flyStreamer(loaded->mesh, o.region.block_vertices, o.height, o.frames);
    const double streamed_fraction = sf.blob_bytes ? double(sf.read_bytes) / double(sf.blob_bytes) : 1.0;
    std::printf("streamer flight (pack with pfrep_format 5, views reported with wantPfrepBlocks): read %llu of %llu "
                "blob bytes = %.3f (header included), %u of %u blocks in %u requests, largest settled mesh %zu "
                "triangles; settled meshes %s\n",
                (unsigned long long)sf.read_bytes, (unsigned long long)sf.blob_bytes, streamed_fraction,
                sf.blocks_loaded, sf.blocks, sf.requests, sf.max_triangles,
                !sf.ok    ? "NOT MEASURED (stream failed)"
                : sf.same ? "equal to the whole table's"
                          : "DIFFER");
    bars.absolute("region bytes loaded / region blob (1 px fly-by)", fraction, 0.30, Limit::AtMost);
    bars.absolute("streamer: blob bytes read / region blob (1 px fly-by, pack)", sf.ok ? streamed_fraction : 1.0, 0.30,
                  Limit::AtMost);
    bars.absolute("streamer: settled meshes differing from the whole table's", sf.ok && sf.same ? 0 : 1, 0,
                  Limit::AtMost);
    bars.absolute("settled meshes or masks differing from the whole blob's", same ? 0 : 1, 0, Limit::AtMost);
    bars.ratio("refinement CPU, region model / whole blob", rc, wc, 1.10, Limit::AtMost);
    return bars.finish(check);
}
