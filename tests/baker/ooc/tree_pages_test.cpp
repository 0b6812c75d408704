// The pages of a merge tree written without its geometry (lodbake/ooc/tree_pages.h) on generated
// scans cut into several partitions: the table's records are assembleHierarchy's exactly, the
// streamed bounds are the assembled hierarchy's, the extension's table and pages are the bytes of
// writeClusterLodPack(assembleHierarchy(tree)) at 1 and 2 threads, the memory bound holds the
// accounted peak and refuses a smaller limit, and a truncated or changed file or a cancel is an
// error naming the file (or the output) with no spill left.

#include "lodbake/ooc/tree_pages.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/ooc/partition_merge.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

std::string freshDir(const std::string& name) { return lodbake_test::freshOocDir("tree_pages", name); }

std::vector<std::string> filesIn(const std::string& dir) {
    std::vector<std::string> names;
    if (fs::exists(dir))
        for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// A generated scan cut into partitions of about 12,000 triangles (small reader buffers and a 3 MiB
// limit on one thread, as PartitionMergeTest cuts it), each built to kLevelsPerJob levels, merged.
struct Tree {
    std::string dir;
    MergeTree tree;
};

Tree mergedScan(const std::string& name, uint64_t triangles) {
    const lodbake_test::PartitionedScan scan = lodbake_test::partitionedScan(freshDir(name), triangles);
    Tree t;
    t.dir = scan.dir;
    MergeOptions mo;
    mo.work_dir = t.dir + "/lods";
    mo.memory_limit_bytes = uint64_t(64) << 20;
    lodbake::Diagnostics d;
    auto tree = mergeAll(lodbake_test::buildLeafLods(scan.set, t.dir + "/lods"), mo, d);
    EXPECT_TRUE(tree.ok()) << tree.status().message();
    if (tree.ok()) t.tree = std::move(*tree);
    return t;
}

void writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
    std::ofstream f(path, std::ios::binary | std::ios::trunc);
    f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    ASSERT_TRUE(bool(f)) << path;
}

void expectSameBounds(const lodbake::ClusterPackBounds& a, const lodbake::ClusterPackBounds& b) {
    EXPECT_EQ(a.empty, b.empty);
    EXPECT_EQ(0, std::memcmp(a.min, b.min, sizeof a.min));
    EXPECT_EQ(0, std::memcmp(a.max, b.max, sizeof a.max));
}

// Stops the writer at page `at` through its cancel flag.
class CancellingSource : public lodbake::ClusterPageSource {
public:
    CancellingSource(TreePageSource& inner, uint32_t at, std::atomic<bool>& cancel)
        : inner_(inner), at_(at), cancel_(cancel) {}
    lodbake::Status readPage(uint32_t page, const uint32_t* clusters, size_t count,
                             lodbake::ClusterPageGeometry& out) override {
        if (page == at_) cancel_ = true;
        return inner_.readPage(page, clusters, count, out);
    }

private:
    TreePageSource& inner_;
    uint32_t at_;
    std::atomic<bool>& cancel_;
};

} // namespace

TEST(TreePagesTest, TableIsTheAssembledHierarchysRecordsAndBoundsAreItsBounds) {
    Tree t = mergedScan("table", 40000);
    ASSERT_GE(t.tree.partitions.size(), 3u);
    ASSERT_FALSE(t.tree.merges.empty());
    auto whole = assembleHierarchy(t.tree, uint64_t(1) << 30);
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    auto table = assembleClusterTable(t.tree, uint64_t(1) << 30);
    ASSERT_TRUE(table.ok()) << table.status().message();
    ASSERT_EQ(table->clusters.size(), whole->clusters.size());
    ASSERT_EQ(table->groups.size(), whole->groups.size());
    EXPECT_EQ(0, std::memcmp(table->clusters.data(), whole->clusters.data(), whole->clusters.size() * 60));
    EXPECT_EQ(0, std::memcmp(table->groups.data(), whole->groups.data(), whole->groups.size() * 48));
    EXPECT_EQ(table->group_children, whole->group_children);
    EXPECT_EQ(table->roots, whole->roots);
    EXPECT_EQ(table->lod0_cluster_count, whole->lod0_cluster_count);
    EXPECT_EQ(table->level_count, whole->level_count);
    EXPECT_EQ(table->reached_single_group, whole->reached_single_group);
    EXPECT_EQ(table->vertex_count, whole->positions.size());
    EXPECT_EQ(size_t(table->triangle_count) * 3, whole->indices.size());
    EXPECT_EQ(table->files.size(), t.tree.partitions.size() + t.tree.merges.size());
    EXPECT_GT(table->accounted_peak_bytes, 0u);
    EXPECT_LE(table->accounted_peak_bytes, table->memory_bound_bytes);
    auto bound = clusterTableBound(t.tree);
    ASSERT_TRUE(bound.ok());
    EXPECT_EQ(*bound, table->memory_bound_bytes);

    // The geometry the source reads is the assembled hierarchy's, cluster by cluster.
    TreePageSource source(*table, 4096);
    auto bounds = source.bounds();
    ASSERT_TRUE(bounds.ok()) << bounds.status().message();
    expectSameBounds(*bounds, lodbake::clusterPackBounds(*whole));
    lodbake::ClusterPageGeometry g;
    std::vector<uint32_t> all(whole->clusters.size());
    for (uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    ASSERT_TRUE(source.readPage(0, all.data(), all.size(), g).ok());
    EXPECT_EQ(g.positions, whole->positions);
    EXPECT_EQ(g.indices, whole->indices);
    // One descriptor at a time: every file closed and reopened (and checked again) as reads move on.
    TreePageSource one_open(*table, 4096, 1);
    auto again = one_open.bounds();
    ASSERT_TRUE(again.ok()) << again.status().message();
    expectSameBounds(*again, *bounds);
    lodbake::ClusterPageGeometry g1;
    ASSERT_TRUE(one_open.readPage(0, all.data(), all.size(), g1).ok());
    EXPECT_EQ(g1.positions, whole->positions);
    EXPECT_EQ(g1.indices, whole->indices);

    // A tree of one partition (its own top) gives its hierarchy's records.
    MergeTree single;
    single.partitions = {t.tree.partitions[0]};
    single.top = t.tree.partitions[0];
    auto one = assembleHierarchy(single, uint64_t(1) << 30);
    auto one_table = assembleClusterTable(single, uint64_t(1) << 30);
    ASSERT_TRUE(one.ok() && one_table.ok());
    ASSERT_EQ(one_table->clusters.size(), one->clusters.size());
    EXPECT_EQ(0, std::memcmp(one_table->clusters.data(), one->clusters.data(), one->clusters.size() * 60));
    EXPECT_EQ(one_table->roots, one->roots);
    EXPECT_EQ(one_table->group_children, one->group_children);

    // A limit below the bound is refused, naming the top file and the minimum.
    auto refused = assembleClusterTable(t.tree, *bound - 1);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::ResourceLimit);
    EXPECT_EQ(refused.status().message().rfind(t.tree.top + ": memory limit", 0), 0u) << refused.status().message();
}

TEST(TreePagesTest, PagesAndTableAreTheInMemoryWritersBytes) {
    Tree t = mergedScan("bytes", 40000);
    ASSERT_FALSE(t.tree.merges.empty());
    auto whole = assembleHierarchy(t.tree, uint64_t(1) << 30);
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    auto memory = lodbake::writeClusterLodPack(*whole, lodbake::ClusterPackOptions());
    ASSERT_TRUE(memory.ok()) << memory.status().message();
    const std::string out_dir = t.dir + "/out";
    fs::create_directories(out_dir);
    for (size_t threads : {1, 2})
        for (size_t in_flight : {1, 0}) {
            lodbake::ScopedThreadLimit limit(threads);
            TreePagesOptions o;
            o.stream.pages_in_flight = in_flight;
            auto s = writeTreeClusterPages(t.tree, out_dir + "/out.glb", o);
            ASSERT_TRUE(s.ok()) << s.status().message();
            EXPECT_EQ(s->pack.extension.blobs[0], memory->extension.blobs[0]) << threads << " threads, " << in_flight;
            auto spill = lodbake::readFileBytes(s->pack.pages->tempPath());
            ASSERT_TRUE(spill.ok()) << spill.status().message();
            EXPECT_EQ(*spill, memory->extension.blobs[1]) << threads << " threads, " << in_flight;
            EXPECT_EQ(s->pack.stats.page_bytes, memory->stats.page_bytes);
            EXPECT_EQ(s->cluster_count, whole->clusters.size());
            EXPECT_LE(s->table_accounted_bytes, s->table_bound_bytes);
            EXPECT_LE(s->pack.accounted_peak_bytes, s->pack.memory_bound_bytes);
            // The bounds pass and every page: each cluster's geometry read twice at most, by offset.
            const uint64_t geometry = 12 * uint64_t(whole->positions.size()) + whole->indices.size();
            EXPECT_GE(s->bytes_read, geometry);
            EXPECT_LE(s->bytes_read, geometry + 12 * uint64_t(whole->positions.size()));
        }
    EXPECT_TRUE(filesIn(out_dir).empty()); // every spill gone with its result
}

TEST(TreePagesTest, TruncatedOrChangedFileAndCancelLeaveNoSpill) {
    Tree t = mergedScan("fail", 30000);
    ASSERT_GE(t.tree.merges.size(), 2u);
    const std::string out_dir = t.dir + "/out";
    fs::create_directories(out_dir);
    const std::string out = out_dir + "/out.glb";
    {
        // Cancelled before the first page, then while the pages are written.
        std::atomic<bool> cancel{true};
        TreePagesOptions o;
        o.stream.cancel = &cancel;
        auto s = writeTreeClusterPages(t.tree, out, o);
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.status().code(), lodbake::StatusCode::IoError);
        EXPECT_EQ(s.status().message(), out + ": writing cancelled");
        EXPECT_TRUE(filesIn(out_dir).empty());
    }
    auto table = assembleClusterTable(t.tree, uint64_t(1) << 30);
    ASSERT_TRUE(table.ok()) << table.status().message();
    {
        std::atomic<bool> cancel{false};
        TreePageSource inner(*table);
        auto bounds = inner.bounds();
        ASSERT_TRUE(bounds.ok());
        CancellingSource source(inner, 3, cancel);
        lodbake::ClusterPackStreamOptions o;
        o.cancel = &cancel;
        o.pages_in_flight = 1;
        auto s = lodbake::writeClusterLodPackStreamed(table->view(), *bounds, source, out, o);
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.status().message(), out + ": writing cancelled");
        EXPECT_TRUE(filesIn(out_dir).empty());
    }
    // A partition file truncated after the table was read: the source refuses it by name, and the
    // writer leaves no spill.
    lodbake::ClusterPackBounds before;
    {
        TreePageSource source(*table);
        auto bounds = source.bounds();
        ASSERT_TRUE(bounds.ok()) << bounds.status().message();
        before = *bounds;
    }
    const std::string victim = t.tree.partitions[1];
    const auto size = fs::file_size(victim);
    auto original = lodbake::readFileBytes(victim);
    ASSERT_TRUE(original.ok());
    fs::resize_file(victim, size - 100);
    {
        TreePageSource source(*table);
        auto bounds = source.bounds();
        ASSERT_FALSE(bounds.ok());
        EXPECT_EQ(bounds.status().code(), lodbake::StatusCode::InvalidInput);
        EXPECT_EQ(bounds.status().message().rfind(victim + ": changed since", 0), 0u) << bounds.status().message();
        TreePageSource pages(*table);
        auto s = lodbake::writeClusterLodPackStreamed(table->view(), before, pages, out,
                                                      lodbake::ClusterPackStreamOptions());
        ASSERT_FALSE(s.ok());
        EXPECT_EQ(s.status().message().rfind(victim + ": ", 0), 0u) << s.status().message();
        EXPECT_TRUE(filesIn(out_dir).empty());
    }
    // Truncated before: the table refuses it by name, and so does the whole writer.
    auto refused = assembleClusterTable(t.tree, uint64_t(1) << 30);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::InvalidInput);
    EXPECT_EQ(refused.status().message().rfind(victim + ": header: the counts need", 0), 0u)
        << refused.status().message();
    auto s = writeTreeClusterPages(t.tree, out, TreePagesOptions());
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.status().message().rfind(victim + ": ", 0), 0u) << s.status().message();
    EXPECT_TRUE(filesIn(out_dir).empty());
    // Rewritten with other bytes of the same size (a changed record): refused by the source as changed.
    writeBytes(victim, *original);
    // A rewrite within the file system's timestamp granularity would keep the time: make it later.
    fs::last_write_time(victim, fs::last_write_time(victim) + std::chrono::seconds(2));
    {
        TreePageSource source(*table);
        auto bounds = source.bounds();
        ASSERT_FALSE(bounds.ok()); // same size, new modification time
        EXPECT_EQ(bounds.status().message().rfind(victim + ": changed since", 0), 0u) << bounds.status().message();
    }
    // A record out of range is an error naming the file, never a crash.
    std::vector<uint8_t> bad = *original;
    const uint32_t huge = 0x7fffffffu;
    std::memcpy(bad.data() + 60 + 24, &huge, 4); // the first cluster record's first_vertex
    writeBytes(victim, bad);
    auto corrupt = assembleClusterTable(t.tree, uint64_t(1) << 30);
    ASSERT_FALSE(corrupt.ok());
    EXPECT_EQ(corrupt.status().message(), victim + ": cluster 0: expected its groups and ranges within the file");
}
