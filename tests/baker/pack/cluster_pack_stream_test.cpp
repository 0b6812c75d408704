// The streamed LODBAKE_cluster_lod writer (lodbake/pack/cluster_pack_stream.h) and the GLB file
// writer (writePackGlbFile, pack_glb.h): the same bytes as the in-memory writers for any thread
// count and any number of pages in flight, a pack that lodrt and loddump accept, the memory formula
// and its accounting, and nothing left behind (no output, no spill) after a failing source, a cancel
// or a full disk.

#include "lodbake/pack/cluster_pack_stream.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "../gltf/gltf_test_util.h"
#include "cli_runner.h"
#include "core/parallel.h"
#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "lodbake/pack/pack.h"
#include "lodbake/pack/pack_glb.h"
#include "lodbake/stream/stream.h"
#include "lodrt/format.h"
#include "stream_level.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake::ClusterLodHierarchy;
using lodbake::Mesh;
using lodbake::Vec3f;

using lodbake_test::bumpySphere;

ClusterLodHierarchy build(const Mesh& mesh) {
    lodbake::Diagnostics d;
    auto h = lodbake::buildClusterLod(lodbake::MeshView(mesh), lodbake::ClusterLodOptions(), d);
    EXPECT_TRUE(h.ok()) << h.status().message();
    return h.ok() ? std::move(h.value()) : ClusterLodHierarchy();
}

std::string freshDir(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/cluster_pack_stream/" + name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::vector<std::string> filesIn(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

lodbake::Result<lodbake::ClusterPackStreamResult> streamed(const ClusterLodHierarchy& h, const std::string& out,
                                                           size_t in_flight, lodbake::ClusterPageSource* source = nullptr,
                                                           const std::atomic<bool>* cancel = nullptr) {
    lodbake::HierarchyPageSource memory(h);
    lodbake::ClusterPackStreamOptions o;
    o.pages_in_flight = in_flight;
    o.cancel = cancel;
    return lodbake::writeClusterLodPackStreamed(h.view(), lodbake::clusterPackBounds(h), source ? *source : memory,
                                                out, o);
}

// The streamed pages and table equal the in-memory writer's, whatever the threads and pages in flight.
void expectSameAsInMemory(const ClusterLodHierarchy& h, const std::string& dir) {
    auto memory = lodbake::writeClusterLodPack(h, lodbake::ClusterPackOptions());
    ASSERT_TRUE(memory.ok()) << memory.status().message();
    for (size_t threads : {1, 2})
        for (size_t in_flight : {1, 3, 0}) {
            lodbake::ScopedThreadLimit limit(threads);
            auto s = streamed(h, dir + "/out.glb", in_flight);
            ASSERT_TRUE(s.ok()) << s.status().message();
            EXPECT_EQ(s->extension.blobs[0], memory->extension.blobs[0]) << threads << " threads, " << in_flight;
            ASSERT_EQ(s->extension.spilled.size(), 2u);
            EXPECT_EQ(s->extension.spilled[1], s->pages);
            auto spill = lodbake::readFileBytes(s->pages->tempPath());
            ASSERT_TRUE(spill.ok()) << spill.status().message();
            EXPECT_EQ(*spill, memory->extension.blobs[1]) << threads << " threads, " << in_flight;
            EXPECT_EQ(s->stats.page_bytes, memory->stats.page_bytes);
            EXPECT_EQ(s->stats.cone_clusters, memory->stats.cone_clusters);
            EXPECT_EQ(s->stats.lod0_page_bytes, memory->stats.lod0_page_bytes);
        }
    EXPECT_TRUE(filesIn(dir).empty()); // every spill gone with its result
}

TEST(ClusterPackStream, PagesAndTableAreTheInMemoryWritersBytes) {
    const std::string dir = freshDir("same");
    expectSameAsInMemory(build(bumpySphere(60, 90)), dir);
}

TEST(ClusterPackStream, SharedScanGivesTheInMemoryWritersBytes) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics d;
    auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("bunny_zipper.ply"), lodbake::ReadOptions(), d);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message();
    expectSameAsInMemory(build(loaded->mesh), freshDir("scan"));
}

// A pack of two levels with the hierarchy on LOD0, the pages in memory or spilled. Compact: both
// levels carry a valence stream and their plain accessors lose their views, so the binary chunk is
// rebuilt around the pages view.
lodbake::PackDescription twoLevels(const Mesh& lod0, lodbake::PackExtension clusters, bool compact = false) {
    lodbake::PackDescription d;
    d.compact = compact;
    lodbake::PackAsset a;
    a.name = "sphere";
    a.levels.resize(2);
    a.levels[0].mesh = lod0;
    a.levels[1].mesh = bumpySphere(10, 14);
    for (size_t l = 0; l < 2 && compact; ++l)
        EXPECT_TRUE(
            lodbake_test::encodeStreamLevel(lodbake::valenceStreamEncoder(), lodbake::LodChain{}, l, a.levels[l]).ok());
    a.levels[0].mesh_extensions.push_back(std::move(clusters));
    a.screen_coverage = {0.5, 0};
    d.assets.push_back(std::move(a));
    return d;
}

TEST(ClusterPackStream, GlbFileIsTheInMemoryPackAndLoddumpAcceptsIt) {
    const std::string dir = freshDir("glb");
    const Mesh lod0 = bumpySphere(60, 90);
    const ClusterLodHierarchy h = build(lod0);
    auto memory = lodbake::writeClusterLodPack(h, lodbake::ClusterPackOptions());
    ASSERT_TRUE(memory.ok()) << memory.status().message();
    const std::string out = dir + "/sphere.glb";
    size_t sizes[2] = {0, 0};
    for (bool compact : {true, false}) {
        auto glb = lodbake::writePackGlb(twoLevels(lod0, memory->extension, compact));
        ASSERT_TRUE(glb.ok()) << glb.status().message();
        sizes[compact] = glb->size();
        auto s = streamed(h, out, 2);
        ASSERT_TRUE(s.ok()) << s.status().message();
        s->pages.reset();
        auto written = lodbake::writePackGlbFile(twoLevels(lod0, std::move(s->extension), compact), out);
        ASSERT_TRUE(written.ok()) << written.status().message();
        auto bytes = lodbake::readFileBytes(out);
        ASSERT_TRUE(bytes.ok());
        EXPECT_TRUE(*bytes == *glb) << "compact " << compact;
    }
    EXPECT_LT(sizes[1], sizes[0]); // the compact pack did drop plain accessors' views
    auto glb = lodbake::writePackGlb(twoLevels(lod0, memory->extension));
    ASSERT_TRUE(glb.ok()) << glb.status().message();
    {
        auto s = streamed(h, out, 2);
        ASSERT_TRUE(s.ok()) << s.status().message();
        lodbake::PackDescription spilled = twoLevels(lod0, std::move(s->extension));
        // The in-memory writer refuses a blob it does not hold.
        auto refused = lodbake::writePackGlb(spilled);
        ASSERT_FALSE(refused.ok());
        EXPECT_NE(refused.status().message().find("writePackGlbFile"), std::string::npos);
        s->pages.reset();
        auto written = lodbake::writePackGlbFile(std::move(spilled), out);
        ASSERT_TRUE(written.ok()) << written.status().message();
        EXPECT_EQ(*written, glb->size());
    }
    auto bytes = lodbake::readFileBytes(out);
    ASSERT_TRUE(bytes.ok());
    EXPECT_TRUE(*bytes == *glb);
    EXPECT_EQ(filesIn(dir), std::vector<std::string>{"sphere.glb"}); // the spill went with the description
    const lodbake_test::CommandResult dump =
        lodbake_test::runCommand(lodbake_test::shellQuote(LODBAKE_TEST_LODDUMP) + " " + lodbake_test::shellQuote(out));
    ASSERT_EQ(dump.exit_code, 0) << dump.output;
    EXPECT_NE(dump.output.find("cluster LOD on mesh 0 (LODBAKE_cluster_lod)"), std::string::npos) << dump.output;
    EXPECT_NE(dump.output.find("cuts crack-free"), std::string::npos) << dump.output;
}

TEST(ClusterPackStream, MemoryBoundIsTheFormulaAndHoldsTheAccountedPeak) {
    const std::string dir = freshDir("memory");
    const ClusterLodHierarchy h = build(bumpySphere(60, 90));
    const lodbake::ClusterPagePlan plan = lodbake::planClusterPages(h.view());
    // The formula by hand: table, plan, J pages at the largest page's working set, spill buffer.
    uint64_t largest = 0, largest_triangles = 0;
    for (size_t p = 0; p < plan.pageCount(); ++p) {
        uint64_t v = 0, t = 0;
        for (uint32_t i = plan.page_first[p]; i < plan.page_first[p + 1]; ++i) {
            v += h.clusters[plan.page_clusters[i]].vertex_count;
            t += h.clusters[plan.page_clusters[i]].triangle_count;
        }
        largest = std::max(largest, 12 * v + 3 * t + lodbake::kClusterPageBytesPerTriangle * t);
        largest_triangles = std::max(largest_triangles, t);
    }
    const uint64_t table = 64 + 48 * (h.clusters.size() + h.groups.size()) + 4 * (h.group_children.size() + h.roots.size()) +
                           16 * plan.pageCount();
    const uint64_t planned = 4 * (h.clusters.size() + plan.pageCount() + 1);
    uint64_t previous = 0;
    for (size_t in_flight : {1, 4}) {
        auto s = streamed(h, dir + "/out.glb", in_flight);
        ASSERT_TRUE(s.ok()) << s.status().message();
        EXPECT_EQ(s->stats.table_bytes, table);
        EXPECT_EQ(s->memory_bound_bytes, table + planned + in_flight * largest + (uint64_t(1) << 20));
        EXPECT_LE(s->accounted_peak_bytes, s->memory_bound_bytes);
        // At least the table, the spill buffer and the largest page at its allowance were held.
        EXPECT_GE(s->accounted_peak_bytes,
                  table + (uint64_t(1) << 20) + lodbake::kClusterPageBytesPerTriangle * largest_triangles);
        EXPECT_GT(s->accounted_peak_bytes, previous); // more pages in flight hold more
        previous = s->accounted_peak_bytes;
    }
}

// A source that fails at page `fail_at`, or sets `cancel` there.
class FailingSource : public lodbake::ClusterPageSource {
public:
    FailingSource(const ClusterLodHierarchy& h, uint32_t fail_at, std::atomic<bool>* cancel)
        : memory_(h), fail_at_(fail_at), cancel_(cancel) {}
    lodbake::Status readPage(uint32_t page, const uint32_t* clusters, size_t count,
                             lodbake::ClusterPageGeometry& out) override {
        EXPECT_EQ(page, next_++); // in page order, once each
        if (page == fail_at_) {
            if (!cancel_) return lodbake::ioError("partition.lbplod: read failed at page " + std::to_string(page));
            cancel_->store(true);
        }
        return memory_.readPage(page, clusters, count, out);
    }

private:
    lodbake::HierarchyPageSource memory_;
    uint32_t fail_at_, next_ = 0;
    std::atomic<bool>* cancel_;
};

TEST(ClusterPackStream, FailingSourceCancelAndFullDiskLeaveNothing) {
    const std::string dir = freshDir("fail");
    const ClusterLodHierarchy h = build(bumpySphere(60, 90));
    const std::string out = dir + "/out.glb";
    const uint32_t pages = uint32_t(lodbake::planClusterPages(h.view()).pageCount());
    ASSERT_GT(pages, 8u);
    {
        FailingSource source(h, pages / 2, nullptr);
        auto s = streamed(h, out, 2, &source);
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.status().message(), "partition.lbplod: read failed at page " + std::to_string(pages / 2));
        EXPECT_TRUE(filesIn(dir).empty());
    }
    {
        std::atomic<bool> cancel{false};
        FailingSource source(h, 3, &cancel);
        auto s = streamed(h, out, 2, &source, &cancel);
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.status().code(), lodbake::StatusCode::IoError);
        EXPECT_EQ(s.status().message(), out + ": writing cancelled");
        EXPECT_TRUE(filesIn(dir).empty());
    }
    const Mesh lod0 = bumpySphere(60, 90);
    {
        // Cancelled while the GLB is written: no output, and the spill goes with the description.
        auto s = streamed(h, out, 2);
        ASSERT_TRUE(s.ok());
        s->pages.reset();
        std::atomic<bool> cancel{true};
        auto written = lodbake::writePackGlbFile(twoLevels(lod0, std::move(s->extension)), out, &cancel);
        ASSERT_FALSE(written.ok());
        EXPECT_EQ(written.status().message(), out + ": writing cancelled");
        EXPECT_TRUE(filesIn(dir).empty());
    }
    // A full disk, simulated by a file size limit: first below the spill, then above the spill and
    // below the GLB.
    auto memory = lodbake::writeClusterLodPack(h, lodbake::ClusterPackOptions());
    ASSERT_TRUE(memory.ok());
    const uint64_t spill_bytes = memory->extension.blobs[1].size();
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit old{};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    for (uint64_t limit : {spill_bytes / 2, spill_bytes + 16}) {
        rlimit low = old;
        low.rlim_cur = limit;
        ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &low), 0);
        lodbake::Status failed = lodbake::Status::okStatus();
        {
            lodbake::ScopedThreadLimit one(1);
            lodbake::ClusterPackStreamOptions o;
            o.spill_buffer_bytes = 4096; // writes reach the file as pages come
            lodbake::HierarchyPageSource source(h);
            auto s = lodbake::writeClusterLodPackStreamed(h.view(), lodbake::clusterPackBounds(h), source, out, o);
            if (!s.ok()) {
                failed = s.status();
            } else {
                s->pages.reset();
                auto written = lodbake::writePackGlbFile(twoLevels(lod0, std::move(s->extension)), out, nullptr, 4096);
                failed = written.status();
            }
        }
        setrlimit(RLIMIT_FSIZE, &old);
        ASSERT_FALSE(failed.ok()) << limit;
        EXPECT_EQ(failed.code(), lodbake::StatusCode::IoError);
        EXPECT_EQ(failed.message().rfind(out + ": write failed", 0), 0u) << failed.message();
        EXPECT_TRUE(filesIn(dir).empty()) << limit;
    }
}

TEST(ClusterPackStream, GeometryThatDoesNotMatchTheTableIsRefused) {
    const std::string dir = freshDir("mismatch");
    const ClusterLodHierarchy h = build(bumpySphere(20, 30));
    class Short : public lodbake::ClusterPageSource {
    public:
        explicit Short(const ClusterLodHierarchy& h) : memory_(h) {}
        lodbake::Status readPage(uint32_t page, const uint32_t* clusters, size_t count,
                                 lodbake::ClusterPageGeometry& out) override {
            LODBAKE_RETURN_IF_ERROR(memory_.readPage(page, clusters, count, out));
            if (page == 1) out.indices.back() = 255; // beyond the last cluster's vertices
            return lodbake::Status::okStatus();
        }

    private:
        lodbake::HierarchyPageSource memory_;
    } source(h);
    auto s = streamed(h, dir + "/out.glb", 1, &source);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.status().code(), lodbake::StatusCode::InvalidInput);
    EXPECT_NE(s.status().message().find("cluster pack: page 1: cluster "), std::string::npos) << s.status().message();
    EXPECT_TRUE(filesIn(dir).empty());
}

} // namespace
