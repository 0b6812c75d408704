// ClusterStreamingTest: the Streamer streams LODBAKE_cluster_lod pages by range read under its memory
// budget (lodrt/streaming.h), and the cut over the resident pages (selectClusterCutResident) draws
// the finest resident ancestor until a page arrives. Lives in lodbake_tests because the pack is
// baked with the baker; the code under test is runtime code only.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cluster_edges.h"
#include "lodbake/bake/bake.h"
#include "lodrt/cluster_lod.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/streaming.h"
#include "manual_jobs.h"
#include "mesh_builders.h"

namespace {

using lodrt::LevelState;
using lodrt::PackSource;
using lodrt::Result;
using lodrt::Streamer;
using lodrt_test::ManualJobs;

// A wavy n x n height field over the unit square.
lodbake::Mesh wavyGrid(int n) {
    return lodbake_test::wavyField(n, 0.04f, 0.35f, 0.3f);
}

const std::vector<uint8_t>& bakedPack() {
    static const std::vector<uint8_t>* glb = [] {
        lodbake::BakeSettings settings;
        settings.cluster_lod = true;
        settings.lod_ratios = {0.25};
        settings.error_samples = 2000;
        settings.threads = 2;
        std::vector<lodbake::BakeInput> inputs(1);
        inputs[0].name = "grid";
        inputs[0].mesh = wavyGrid(120);
        lodbake::Diagnostics diagnostics;
        auto baked = lodbake::bake(std::move(inputs), settings, diagnostics);
        EXPECT_TRUE(baked.ok()) << baked.status().message();
        return new std::vector<uint8_t>(baked.ok() ? baked->glb : std::vector<uint8_t>());
    }();
    return *glb;
}

// A range reader over a file in memory; reads overlapping [fail_begin, fail_end) fail (a bad disk).
struct File {
    std::vector<uint8_t> bytes;
    uint64_t fail_begin = 0, fail_end = 0;
    static Result read(void* user, uint64_t offset, void* dst, size_t size) {
        File* f = static_cast<File*>(user);
        if (offset > f->bytes.size() || size > f->bytes.size() - offset) return Result::Truncated;
        if (offset < f->fail_end && offset + size > f->fail_begin) return Result::Truncated;
        std::memcpy(dst, f->bytes.data() + offset, size);
        return Result::Ok;
    }
    lodrt::RangeReader reader() { return lodrt::RangeReader{&File::read, this}; }
    // File offset of byte 0 of the GLB BIN chunk's payload.
    uint64_t binOffset() const {
        uint32_t json_length = 0;
        std::memcpy(&json_length, bytes.data() + 12, 4);
        return 20 + uint64_t(json_length) + 8;
    }
};

// Counts the allocations lodrt makes through the hook (the streamer's and the source's).
struct CountingAllocator {
    std::atomic<uint64_t> allocations{0};
    static void* allocate(void* user, size_t size) {
        static_cast<CountingAllocator*>(user)->allocations.fetch_add(1, std::memory_order_relaxed);
        return std::malloc(size);
    }
    static void deallocate(void*, void* ptr) { std::free(ptr); }
    lodrt::Allocator hook() { return lodrt::Allocator{&CountingAllocator::allocate, &CountingAllocator::deallocate, this}; }
};

lodrt::SelectionParams params() {
    lodrt::SelectionParams p;
    p.pixel_threshold = 1;
    p.viewport_height = 1080;
    p.vertical_fov = 1.0471976f;
    return p;
}

// Every page decoded straight from the pack, as the reference for the streamed ones and for the
// crack check.
struct Reference {
    std::vector<std::vector<float>> positions;
    std::vector<std::vector<uint32_t>> indices;
    std::vector<lodrt_tools::ClusterEdges::Edge> lod0_boundary;
    std::unique_ptr<lodrt_tools::ClusterEdges> edges;
};

Reference decodeAll(const PackSource& source, const lodrt::ClusterLodPack& pack) {
    Reference ref;
    lodrt::ClusterPackSource where;
    EXPECT_EQ(lodrt::clusterPackFind(source.pack(), source.models().modelLevel(0, 0).mesh, &where), Result::Ok);
    ref.positions.resize(pack.page_count);
    ref.indices.resize(pack.page_count);
    for (uint32_t p = 0; p < pack.page_count; ++p) {
        const lodrt::ClusterPage& page = pack.pages[p];
        std::vector<uint8_t> bytes(page.byte_length);
        EXPECT_EQ(source.readBufferView(where.pages_view, page.byte_offset, bytes.data(), bytes.size()), Result::Ok);
        lodrt::ClusterPageInfo info;
        EXPECT_EQ(lodrt::clusterPageReadInfo(pack, p, bytes.data(), bytes.size(), &info), Result::Ok);
        std::vector<uint64_t> scratch(info.scratch_bytes / 8 + 1);
        ref.positions[p].resize(size_t(info.vertex_count) * 3);
        ref.indices[p].resize(size_t(info.triangle_count) * 3);
        EXPECT_EQ(lodrt::clusterPageDecode(pack, p, bytes.data(), bytes.size(), ref.positions[p].data(),
                                           ref.positions[p].size(), ref.indices[p].data(), ref.indices[p].size(),
                                           scratch.data(), scratch.size() * 8),
                  Result::Ok);
    }
    ref.edges.reset(new lodrt_tools::ClusterEdges(pack.view.cluster_count, [&](uint32_t c, auto&& fn) {
        const lodrt::ClusterPlace& place = pack.places[c];
        const std::vector<float>& pos = ref.positions[place.page];
        const std::vector<uint32_t>& idx = ref.indices[place.page];
        for (uint32_t t = place.first_triangle; t < place.first_triangle + place.triangle_count; ++t) {
            const float* q[3];
            for (int i = 0; i < 3; ++i) q[i] = &pos[3 * size_t(idx[3 * size_t(t) + size_t(i)])];
            fn(q);
        }
    }));
    std::vector<uint32_t> lod0;
    for (uint32_t c = 0; c < pack.view.cluster_count; ++c)
        if (pack.view.clusters[c].self_group == lodrt::kClusterNone) lod0.push_back(c);
    ref.lod0_boundary = ref.edges->boundary(lod0);
    return ref;
}

// One engine: the pack opened through range reads, a streamer, and the per-frame cut buffers
// (allocated once, as an engine would).
struct Engine {
    File file;
    CountingAllocator counter;
    PackSource source;
    ManualJobs jobs;
    lodrt::JobSystem job_system;
    Streamer streamer;
    const lodrt::ClusterLodPack* pack = nullptr;
    std::vector<uint32_t> scratch, out, missing;
    lodrt::ClusterCutScratch cut_scratch;
    uint32_t drawn = 0, missing_count = 0;
    const lodrt::JobSystem* threads = nullptr; // set before open() to run jobs on worker threads

    // The baked pack, or `bytes` with reads of [fail_begin, fail_end) failing.
    bool open(uint64_t budget, const std::vector<uint8_t>* bytes = nullptr, uint64_t fail_begin = 0,
              uint64_t fail_end = 0) {
        file.bytes = bytes ? *bytes : bakedPack();
        file.fail_begin = fail_begin;
        file.fail_end = fail_end;
        lodrt::LoadOptions load;
        load.allocator = counter.hook();
        char message[256] = {0};
        if (source.openReader(file.reader(), file.bytes.size(), &load, message, sizeof(message)) != Result::Ok) {
            ADD_FAILURE() << message;
            return false;
        }
        job_system = threads ? *threads : jobs.system();
        lodrt::StreamerOptions options;
        options.allocator = counter.hook();
        options.budget_bytes = budget;
        if (streamer.init(&source, &job_system, &options) != Result::Ok) return false;
        pack = streamer.clusterPack(0);
        if (!pack) return false;
        scratch.assign(lodrt::clusterCutScratchBytes(pack->view) / 4 + 1, 0);
        cut_scratch = lodrt::ClusterCutScratch{scratch.data(), scratch.size() * 4, 0};
        out.resize(pack->view.cluster_count);
        missing.resize(pack->view.group_count);
        return true;
    }

    // Update, cut (when drawable) and report the demand for the next update, as an engine's frame
    // does; then the job system runs up to `jobs_to_run` jobs (all when negative) before the next
    // frame. The cut's clusters are drawable until the next update.
    void frame(const float eye[3], int jobs_to_run = -1) {
        drawn = 0;
        missing_count = 0;
        streamer.update(nullptr);
        if (const uint8_t* groups = streamer.clusterGroupResident(0)) {
            lodrt::ClusterResidency residency{groups, missing.data(), uint32_t(missing.size()), 0};
            lodrt::ClusterCutStats stats;
            ASSERT_EQ(lodrt::selectClusterCutResident(pack->view, lodrt::ClusterInstance(), eye, nullptr, params(),
                                                      cut_scratch, &residency, out.data(), uint32_t(out.size()), &stats),
                      Result::Ok);
            drawn = stats.written;
            missing_count = std::min(residency.missing_count, uint32_t(missing.size()));
            streamer.wantClusterPages(0, out.data(), drawn, missing.data(), missing_count, 1.0f);
        }
        for (int k = 0; !jobs.queue.empty() && (jobs_to_run < 0 || k < jobs_to_run); ++k) {
            auto job = jobs.queue.front();
            jobs.queue.pop_front();
            job.first(job.second);
        }
    }

    std::vector<uint32_t> drawnClusters() const { return std::vector<uint32_t>(out.begin(), out.begin() + drawn); }

    // Frames at `eye` until nothing is missing (or nothing more can arrive); returns the frames.
    int settle(const float eye[3], int max_frames = 400) {
        int quiet = 0;
        for (int f = 1; f <= max_frames; ++f) {
            const uint32_t reads = streamer.stats().cluster_page_reads;
            frame(eye);
            const bool is_quiet = streamer.clusterGroupResident(0) && streamer.idle() && jobs.queue.empty() &&
                                  reads == streamer.stats().cluster_page_reads;
            if (is_quiet && missing_count == 0) return f;
            quiet = is_quiet ? quiet + 1 : 0;
            if (quiet >= 3) return f; // what is still missing cannot arrive (failed pages)
        }
        return -1;
    }
};

std::vector<uint32_t> fullCut(const lodrt::ClusterLodView& view, const float eye[3]) {
    std::vector<uint32_t> scratch(lodrt::clusterCutScratchBytes(view) / 4 + 1, 0), out(view.cluster_count);
    lodrt::ClusterCutScratch s{scratch.data(), scratch.size() * 4, 0};
    lodrt::ClusterCutStats st;
    EXPECT_EQ(lodrt::selectClusterCut(view, lodrt::ClusterInstance(), eye, nullptr, params(), s, out.data(),
                                      uint32_t(out.size()), &st),
              Result::Ok);
    out.resize(st.written);
    return out;
}

// Largest projected error (pixels) of the drawn clusters' own errors at `eye`.
float maxDrawnError(const lodrt::ClusterLodView& view, const std::vector<uint32_t>& drawn, const float eye[3]) {
    const float k = lodrt::pixelsPerUnitAtDistanceOne(params());
    float worst = 0;
    for (uint32_t c : drawn) {
        const uint32_t g = view.clusters[c].self_group;
        if (g == lodrt::kClusterNone) continue;
        const lodrt::ClusterLodGroup& gr = view.groups[g];
        const float dx = gr.lod_center[0] - eye[0], dy = gr.lod_center[1] - eye[1], dz = gr.lod_center[2] - eye[2];
        const float d = std::sqrt(dx * dx + dy * dy + dz * dz) - gr.lod_radius;
        worst = std::max(worst, d > 0 ? gr.error * k / d : (gr.error > 0 ? INFINITY : 0.0f));
    }
    return worst;
}

// Every drawn cluster's page is resident in the streamer and decoded exactly as the reference.
void expectDrawnResident(const Engine& e, const Reference& ref) {
    for (uint32_t c : e.drawnClusters()) {
        const lodrt::ClusterPlace& place = e.pack->places[c];
        lodrt::ClusterPageData data;
        ASSERT_TRUE(e.streamer.clusterPageData(0, place.page, &data)) << "cluster " << c << " drawn, page absent";
        ASSERT_EQ(size_t(data.vertex_count) * 3, ref.positions[place.page].size());
        ASSERT_EQ(size_t(data.triangle_count) * 3, ref.indices[place.page].size());
        ASSERT_EQ(std::memcmp(data.positions, ref.positions[place.page].data(), size_t(data.vertex_count) * 12), 0);
        ASSERT_EQ(std::memcmp(data.indices, ref.indices[place.page].data(), size_t(data.triangle_count) * 12), 0);
    }
}

std::vector<std::array<float, 3>> flyBy(size_t n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0, 1);
    std::vector<std::array<float, 3>> eyes;
    for (size_t i = 0; i < n; ++i) {
        const float h = 0.02f + 2.0f * u(rng) * u(rng) * u(rng);
        eyes.push_back({u(rng), u(rng), h});
    }
    return eyes;
}

TEST(ClusterStreaming, PagesArriveAndTheSettledCutIsTheFullCutWithinThreshold) {
    Engine e;
    ASSERT_TRUE(e.open(0));
    const Reference ref = decodeAll(e.source, *e.pack);
    EXPECT_EQ(e.streamer.clusterGroupResident(0), nullptr); // root pages not read yet
    size_t views = 0;
    for (const auto& eye : flyBy(6, 3)) {
        const int frames = e.settle(eye.data());
        ASSERT_GT(frames, 0) << "did not settle";
        EXPECT_EQ(e.missing_count, 0u);
        std::vector<uint32_t> drawn = e.drawnClusters(), full = fullCut(e.pack->view, eye.data());
        std::sort(drawn.begin(), drawn.end());
        std::sort(full.begin(), full.end());
        ASSERT_EQ(drawn, full) << "eye " << eye[0] << " " << eye[1] << " " << eye[2];
        EXPECT_LE(maxDrawnError(e.pack->view, drawn, eye.data()), params().pixel_threshold);
        expectDrawnResident(e, ref);
        ++views;
    }
    const lodrt::StreamStats st = e.streamer.stats();
    EXPECT_EQ(st.failures, 0u);
    EXPECT_GT(st.cluster_page_reads, 2u);
    EXPECT_EQ(st.cluster_resident_pages, st.cluster_page_reads); // unlimited budget: nothing evicted
    EXPECT_EQ(st.cluster_page_evictions, 0u);
    EXPECT_LE(st.cluster_resident_bytes, st.resident_bytes);
    EXPECT_EQ(views, 6u);
}

// While pages are missing (one job runs per frame), the cut draws resident clusters only and has no
// crack; it does stand in for missing groups on the way.
TEST(ClusterStreaming, CutWhilePagesAreMissingHasNoCrack) {
    Engine e;
    ASSERT_TRUE(e.open(0));
    const Reference ref = decodeAll(e.source, *e.pack);
    size_t frames_missing = 0;
    for (const auto& eye : flyBy(40, 5))
        for (int f = 0; f < 4; ++f) {
            e.frame(eye.data(), 1);
            if (!e.streamer.clusterGroupResident(0)) continue;
            expectDrawnResident(e, ref);
            const auto cracks = ref.edges->cracks(e.drawnClusters(), ref.lod0_boundary);
            ASSERT_TRUE(cracks.empty()) << cracks.size() << " boundary edges LOD0 lacks";
            frames_missing += e.missing_count > 0;
        }
    EXPECT_GT(frames_missing, 20u); // the cut did run with missing pages
}

// What the streamer pins whatever the budget (the coarsest level, the PFRep directory or decoded
// blob, the root pages): what it holds after its first requests, before any cut asks for more.
uint64_t pinnedBytes(Engine& e) {
    for (int f = 0; f < 8; ++f) {
        e.streamer.update(nullptr);
        e.jobs.runAll();
    }
    e.streamer.update(nullptr);
    EXPECT_TRUE(e.streamer.idle());
    EXPECT_NE(e.streamer.clusterGroupResident(0), nullptr);
    return e.streamer.stats().resident_bytes;
}

TEST(ClusterStreaming, SmallBudgetEvictsAndStaysCrackFree) {
    Engine probe;
    ASSERT_TRUE(probe.open(0));
    const Reference ref = decodeAll(probe.source, *probe.pack);
    const uint64_t pinned = pinnedBytes(probe);
    // Settled everywhere with no budget: what the whole hierarchy's pages take.
    for (const auto& eye : flyBy(12, 9)) ASSERT_GT(probe.settle(eye.data()), 0);
    const uint64_t all = probe.streamer.stats().cluster_resident_bytes;
    Engine e;
    const uint64_t budget = pinned + all / 4;
    ASSERT_TRUE(e.open(budget));
    uint64_t peak = 0;
    for (const auto& eye : flyBy(60, 9))
        for (int f = 0; f < 6; ++f) {
            e.frame(eye.data());
            const lodrt::StreamStats st = e.streamer.stats();
            peak = std::max(peak, st.resident_bytes + st.in_flight_bytes);
            ASSERT_LE(st.resident_bytes + st.in_flight_bytes, budget);
            if (!e.streamer.clusterGroupResident(0)) continue;
            // The group residency the cut used is the one of the pages resident now.
            std::vector<uint8_t> pages(e.pack->page_count), groups(e.pack->view.group_count);
            for (uint32_t p = 0; p < e.pack->page_count; ++p)
                pages[p] = e.streamer.clusterPageState(0, p) == LevelState::Resident;
            lodrt::clusterGroupResidency(*e.pack, pages.data(), groups.data());
            ASSERT_EQ(std::memcmp(groups.data(), e.streamer.clusterGroupResident(0), groups.size()), 0);
            expectDrawnResident(e, ref);
            const auto cracks = ref.edges->cracks(e.drawnClusters(), ref.lod0_boundary);
            ASSERT_TRUE(cracks.empty()) << cracks.size() << " boundary edges LOD0 lacks";
        }
    const lodrt::StreamStats st = e.streamer.stats();
    EXPECT_GT(st.cluster_page_evictions, 0u);
    EXPECT_EQ(st.failures, 0u);
    EXPECT_GT(peak, budget / 2);
    // A view whose pages fit the budget settles to its full cut even though the budget is full of
    // other views' pages: the pages above the drawn ones stay wanted, so making room never evicts
    // what the view needs. Views from beside the grid need part of it only.
    const uint64_t budget2 = pinned + all * 3 / 4;
    Engine e2;
    ASSERT_TRUE(e2.open(budget2));
    for (const auto& eye : flyBy(30, 13))
        for (int f = 0; f < 4; ++f) e2.frame(eye.data());
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> u(0, 1);
    size_t fitting = 0;
    for (int v = 0; v < 12; ++v) {
        const float eye[3] = {-0.4f - 1.0f * u(rng), u(rng), 0.2f + 0.8f * u(rng)};
        Engine alone;
        ASSERT_TRUE(alone.open(0));
        ASSERT_GT(alone.settle(eye), 0);
        if (alone.streamer.stats().resident_bytes > budget2) continue; // this view does not fit
        std::vector<LevelState> start(e2.pack->page_count);
        for (uint32_t p = 0; p < e2.pack->page_count; ++p) start[p] = e2.streamer.clusterPageState(0, p);
        const uint32_t reads_before = e2.streamer.stats().cluster_page_reads;
        ASSERT_GT(e2.settle(eye), 0);
        // Every page read while settling is one the view keeps: none is evicted and read again.
        uint32_t arrived = 0;
        for (uint32_t p = 0; p < e2.pack->page_count; ++p)
            arrived += start[p] != LevelState::Resident && e2.streamer.clusterPageState(0, p) == LevelState::Resident;
        EXPECT_EQ(e2.streamer.stats().cluster_page_reads - reads_before, arrived);
        EXPECT_EQ(e2.missing_count, 0u);
        std::vector<uint32_t> drawn = e2.drawnClusters(), full = fullCut(e2.pack->view, eye);
        std::sort(drawn.begin(), drawn.end());
        std::sort(full.begin(), full.end());
        EXPECT_EQ(drawn, full);
        // Settled means steady: nothing is read or evicted again while the view holds.
        const lodrt::StreamStats before = e2.streamer.stats();
        for (int f = 0; f < 5; ++f) e2.frame(eye);
        EXPECT_EQ(e2.streamer.stats().cluster_page_reads, before.cluster_page_reads);
        EXPECT_EQ(e2.streamer.stats().cluster_page_evictions, before.cluster_page_evictions);
        ++fitting;
    }
    EXPECT_GE(fitting, 4u);
}

// A page whose bytes are corrupted and a page whose read fails: each fails alone, the cut draws the
// coarser clusters there, everything else streams and stays crack-free.
TEST(ClusterStreaming, BadPagesFailAloneAndTheRestKeepsWorking) {
    Engine clean;
    ASSERT_TRUE(clean.open(0));
    const Reference ref = decodeAll(clean.source, *clean.pack);
    const float eye[3] = {0.5f, 0.5f, 0.05f};
    ASSERT_GT(clean.settle(eye), 0);
    // Two finest-level pages the close view draws from (not root pages).
    std::set<uint32_t> used;
    for (uint32_t c : clean.drawnClusters())
        if (clean.pack->view.clusters[c].parent_group != lodrt::kClusterNone) used.insert(clean.pack->places[c].page);
    ASSERT_GE(used.size(), 2u);
    const uint32_t corrupt = *used.begin(), unreadable = *std::next(used.begin());
    lodrt::ClusterPackSource where;
    ASSERT_EQ(lodrt::clusterPackFind(clean.source.pack(), clean.source.models().modelLevel(0, 0).mesh, &where),
              Result::Ok);
    std::vector<uint8_t> bytes = bakedPack();
    const uint64_t pages_at = clean.file.binOffset() + where.pages_offset;
    for (int i = 0; i < 4; ++i) bytes[pages_at + clean.pack->pages[corrupt].byte_offset + uint64_t(i)] ^= 0x5a;
    const uint64_t fail_at = pages_at + clean.pack->pages[unreadable].byte_offset;
    Engine bad;
    ASSERT_TRUE(bad.open(0, &bytes, fail_at, fail_at + 1));
    ASSERT_GT(bad.settle(eye), 0);
    EXPECT_EQ(bad.streamer.clusterPageState(0, corrupt), LevelState::Failed);
    EXPECT_EQ(bad.streamer.clusterPageState(0, unreadable), LevelState::Failed);
    EXPECT_EQ(bad.streamer.stats().failures, 2u);
    EXPECT_GT(bad.missing_count, 0u); // the failed pages' groups stay missing, drawn coarser
    expectDrawnResident(bad, ref);
    const auto cracks = ref.edges->cracks(bad.drawnClusters(), ref.lod0_boundary);
    EXPECT_TRUE(cracks.empty()) << cracks.size() << " boundary edges LOD0 lacks";
    // Everywhere else the cut is the full one: the clusters drawn from the good pages match.
    size_t same = 0;
    const std::vector<uint32_t> full = fullCut(bad.pack->view, eye);
    const std::set<uint32_t> drawn(bad.out.begin(), bad.out.begin() + bad.drawn);
    for (uint32_t c : full) same += drawn.count(c);
    EXPECT_GT(same, full.size() / 2);
    // Every other page read became resident.
    const lodrt::StreamStats st = bad.streamer.stats();
    EXPECT_EQ(st.cluster_resident_pages + 2, st.cluster_page_reads);
}

// A corrupted table fails the model's cluster streaming only: no table, one failure, and the
// model's levels still stream.
TEST(ClusterStreaming, BadTableFailsTheClustersOnly) {
    Engine clean;
    ASSERT_TRUE(clean.open(0));
    lodrt::ClusterPackSource where;
    ASSERT_EQ(lodrt::clusterPackFind(clean.source.pack(), clean.source.models().modelLevel(0, 0).mesh, &where),
              Result::Ok);
    std::vector<uint8_t> bytes = bakedPack();
    bytes[clean.file.binOffset() + where.table_offset] ^= 0x5a; // the table's magic
    File file;
    file.bytes = bytes;
    PackSource source;
    ASSERT_EQ(source.openReader(file.reader(), file.bytes.size(), nullptr), Result::Ok);
    ManualJobs jobs;
    const lodrt::JobSystem system = jobs.system();
    Streamer streamer;
    ASSERT_EQ(streamer.init(&source, &system, nullptr), Result::Ok);
    EXPECT_EQ(streamer.clusterPack(0), nullptr);
    EXPECT_EQ(streamer.clusterGroupResident(0), nullptr);
    EXPECT_EQ(streamer.stats().failures, 1u);
    const uint32_t drawn[1] = {0};
    streamer.wantClusterPages(0, drawn, 1, nullptr, 0, 1.0f); // ignored
    std::vector<lodrt::ModelDemand> demand(1);
    demand[0] = {0, 1.0f};
    for (int f = 0; f < 6; ++f) {
        streamer.update(demand.data());
        jobs.runAll();
    }
    EXPECT_EQ(streamer.state(0, 0), LevelState::Resident);
    EXPECT_EQ(streamer.stats().cluster_page_reads, 0u);
}

// Jobs on their own threads while the frame keeps cutting: the same settled cut.
TEST(ClusterStreaming, WorkerThreadsSettleToTheFullCut) {
    lodrt_test::ThreadJobs threads;
    const lodrt::JobSystem system = threads.system();
    Engine e;
    e.threads = &system;
    ASSERT_TRUE(e.open(0));
    const float eye[3] = {0.7f, 0.2f, 0.06f};
    // Bounded by time: on a loaded machine the job threads may get little of the CPU.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    bool settled = false;
    while (!settled && std::chrono::steady_clock::now() < deadline) {
        e.frame(eye);
        settled = e.streamer.clusterGroupResident(0) && e.missing_count == 0 && e.streamer.idle();
        std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ASSERT_TRUE(settled);
    std::vector<uint32_t> drawn = e.drawnClusters(), full = fullCut(e.pack->view, eye);
    std::sort(drawn.begin(), drawn.end());
    std::sort(full.begin(), full.end());
    EXPECT_EQ(drawn, full);
    EXPECT_EQ(e.streamer.stats().failures, 0u);
}

TEST(ClusterStreaming, SteadyStateFramesAllocateNothing) {
    Engine e;
    ASSERT_TRUE(e.open(0));
    const float eye[3] = {0.3f, 0.6f, 0.04f};
    ASSERT_GT(e.settle(eye), 0);
    const uint64_t before = e.counter.allocations.load();
    for (int f = 0; f < 50; ++f) e.frame(eye);
    EXPECT_EQ(e.counter.allocations.load(), before);
    EXPECT_GT(before, 0u); // the hook does see the streamer's allocations
}

} // namespace
