// The out-of-core partitioner (lodbake/ooc/partition.h) on generated scans: the partitions hold
// exactly the input's triangles over the input's positions, stay within their target and the
// memory accounting within the limit, are the same files at 1 and 2 threads, and an error, a cancel
// or a full disk leaves no file behind.

#include <algorithm>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <sys/resource.h>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/ooc/partition.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

std::string freshDir(const std::string& name) { return lodbake_test::freshOocDir("partition", name); }

std::string makeScan(const std::string& dir, uint64_t triangles) { return lodbake_test::writeGeneratedScan(dir, triangles); }

// Small buffers so that a few-MiB limit gives several partitions of a 40,000-triangle scan.
PartitionOptions smallOptions(const std::string& work, int threads) {
    return lodbake_test::smallPartitionOptions(work, threads, uint64_t(4) << 20);
}

using Tri = std::tuple<uint32_t, uint32_t, uint32_t>;

std::vector<std::string> filesIn(const std::string& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

// Partitions `scan` and checks the set against `input`, the same file read whole; `hashes` gets the
// partitions' content hashes.
void checkUnion(const std::string& scan, const lodbake::Mesh& input, PartitionOptions o,
                std::vector<uint64_t>* hashes = nullptr) {
    lodbake::Diagnostics d;
    lodbake::Result<PartitionSet> set = partitionMesh(scan, o, d);
    ASSERT_TRUE(set.ok()) << set.status().message();
    if (hashes)
        for (const PartitionFile& f : set->partitions) hashes->push_back(f.content_hash);
    EXPECT_GE(set->partitions.size(), 3u);
    EXPECT_EQ(set->triangle_count, input.faceCount());
    EXPECT_EQ(set->vertex_count, input.vertexCount());
    EXPECT_LE(set->largest_partition, set->target_triangles);
    EXPECT_LE(set->accounted_peak_bytes, o.memory_limit_bytes);
    EXPECT_LE(set->accounted_peak_bytes, set->memory_bound_bytes);

    std::vector<Tri> expected, got;
    for (size_t t = 0; t < input.faceCount(); ++t)
        expected.emplace_back(input.indices[3 * t], input.indices[3 * t + 1], input.indices[3 * t + 2]);
    for (const PartitionFile& f : set->partitions) {
        EXPECT_EQ(fs::path(f.path).extension(), ".lbpart");
        lodbake::Result<PartitionData> p = readPartitionFile(f.path);
        ASSERT_TRUE(p.ok()) << p.status().message();
        EXPECT_EQ(p->global_ids.size(), f.vertex_count);
        EXPECT_EQ(p->indices.size(), 3 * size_t(f.triangle_count));
        for (size_t v = 0; v < p->global_ids.size(); ++v) ASSERT_EQ(p->positions[v], input.positions[p->global_ids[v]]);
        for (size_t t = 0; t < p->indices.size(); t += 3)
            got.emplace_back(p->global_ids[p->indices[t]], p->global_ids[p->indices[t + 1]],
                             p->global_ids[p->indices[t + 2]]);
    }
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected);
    // Only the partitions remain in the work folder: the spill and raw files are gone.
    EXPECT_EQ(filesIn(o.work_dir).size(), set->partitions.size());
    removePartitionFiles(*set);
    EXPECT_TRUE(fs::is_empty(o.work_dir));
}

} // namespace

TEST(PartitionTest, UnionIsExactlyTheInputWithinTargetAndLimit) {
    const std::string dir = freshDir("union");
    const std::string scan = makeScan(dir, 40000);
    lodbake::Diagnostics d;
    auto input = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
    ASSERT_TRUE(input.ok());
    checkUnion(scan, input->mesh, smallOptions(dir + "/work", 2));
}

TEST(PartitionTest, ScatteredVertexOrderGivesTheSameUnion) {
    // A scan with its vertices in a scattered order: a leaf's ids span the whole range.
    const std::string dir = freshDir("scattered");
    const std::string scan = makeScan(dir, 120000);
    lodbake::Diagnostics d;
    auto input = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
    ASSERT_TRUE(input.ok());
    lodbake::Mesh shuffled = input->mesh;
    std::vector<uint32_t> order(shuffled.vertexCount());
    for (size_t i = 0; i < order.size(); ++i) order[i] = uint32_t((i * 7919) % order.size());
    ASSERT_EQ(std::set<uint32_t>(order.begin(), order.end()).size(), order.size());
    for (size_t i = 0; i < order.size(); ++i) shuffled.positions[order[i]] = input->mesh.positions[i];
    for (uint32_t& v : shuffled.indices) v = order[v];
    ASSERT_TRUE(lodbake::writeMesh(shuffled, dir + "/shuffled.ply", lodbake::WriteOptions(), d).ok());
    // 3 MiB on one thread: leaves of about 5,000 triangles, so about 24 of them, their vertices
    // numbered through the bitmap over their id range, then by sorting.
    PartitionOptions o = smallOptions(dir + "/work", 1);
    o.memory_limit_bytes = uint64_t(3) << 20;
    std::vector<uint64_t> by_bitmap, by_sort;
    checkUnion(dir + "/shuffled.ply", shuffled, o, &by_bitmap);
    o.bitmap_ids_per_triangle = 0;
    checkUnion(dir + "/shuffled.ply", shuffled, o, &by_sort);
    EXPECT_EQ(by_bitmap, by_sort);
    EXPECT_GE(by_sort.size(), 20u);
}

TEST(PartitionTest, SameFilesForAnyThreadCountAndForObj) {
    const std::string dir = freshDir("threads");
    const std::string scan = makeScan(dir, 30000);
    lodbake::Diagnostics d;
    lodbake::Result<PartitionSet> one = partitionMesh(scan, smallOptions(dir + "/one", 1), d);
    lodbake::Result<PartitionSet> two = partitionMesh(scan, smallOptions(dir + "/two", 2), d);
    ASSERT_TRUE(one.ok() && two.ok());
    ASSERT_EQ(one->partitions.size(), two->partitions.size());
    for (size_t i = 0; i < one->partitions.size(); ++i)
        EXPECT_EQ(one->partitions[i].content_hash, two->partitions[i].content_hash) << i;
    EXPECT_EQ(filesIn(dir + "/one"), filesIn(dir + "/two"));
    // The same scan as OBJ: the same vertices and triangles, so the same partitions.
    auto mesh = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
    ASSERT_TRUE(mesh.ok());
    ASSERT_TRUE(lodbake::writeMesh(mesh->mesh, dir + "/scan.obj", lodbake::WriteOptions(), d).ok());
    lodbake::Result<PartitionSet> obj = partitionMesh(dir + "/scan.obj", smallOptions(dir + "/obj", 2), d);
    ASSERT_TRUE(obj.ok()) << obj.status().message();
    EXPECT_EQ(filesIn(dir + "/obj"), filesIn(dir + "/one"));
}

TEST(PartitionTest, ErrorsCancelsAndFullDisksLeaveNoFiles) {
    const std::string dir = freshDir("errors");
    const std::string scan = makeScan(dir, 30000);
    lodbake::Diagnostics d;
    // A limit too small for the input.
    PartitionOptions tiny = smallOptions(dir + "/tiny", 1);
    tiny.memory_limit_bytes = 1 << 20;
    lodbake::Result<PartitionSet> small = partitionMesh(scan, tiny, d);
    ASSERT_FALSE(small.ok());
    EXPECT_EQ(small.status().code(), lodbake::StatusCode::ResourceLimit);
    EXPECT_NE(small.status().message().find("is too small"), std::string::npos) << small.status().message();
    EXPECT_TRUE(fs::is_empty(tiny.work_dir));
    // A cancel.
    std::atomic<bool> cancel{true};
    PartitionOptions cancelled = smallOptions(dir + "/cancel", 2);
    cancelled.cancel = &cancel;
    lodbake::Result<PartitionSet> c = partitionMesh(scan, cancelled, d);
    ASSERT_FALSE(c.ok());
    EXPECT_NE(c.status().message().find("cancelled"), std::string::npos);
    EXPECT_TRUE(fs::is_empty(cancelled.work_dir));
    // A cancelled run in a folder that holds an earlier run's partitions leaves them as they were.
    cancel = false;
    ASSERT_TRUE(partitionMesh(scan, cancelled, d).ok());
    const std::vector<std::string> earlier = filesIn(cancelled.work_dir);
    cancel = true;
    ASSERT_FALSE(partitionMesh(scan, cancelled, d).ok());
    EXPECT_EQ(filesIn(cancelled.work_dir), earlier);
    fs::remove_all(cancelled.work_dir);
    // A full disk, simulated by a file size limit: the spill (180 KB) cannot be written.
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit old{};
    ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
    rlimit low = old;
    low.rlim_cur = 100000;
    const PartitionOptions full = smallOptions(dir + "/full", 2);
    ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &low), 0);
    lodbake::Result<PartitionSet> f = partitionMesh(scan, full, d);
    setrlimit(RLIMIT_FSIZE, &old);
    ASSERT_FALSE(f.ok());
    EXPECT_EQ(f.status().code(), lodbake::StatusCode::IoError);
    EXPECT_EQ(f.status().message().rfind(full.work_dir + "/", 0), 0u) << f.status().message();
    EXPECT_NE(f.status().message().find("write failed"), std::string::npos) << f.status().message();
    EXPECT_TRUE(fs::is_empty(full.work_dir));
    // A broken input.
    lodbake::Result<PartitionSet> missing = partitionMesh(dir + "/missing.ply", smallOptions(dir + "/missing", 1), d);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find(dir + "/missing.ply"), std::string::npos);
}

TEST(PartitionTest, ReadPartitionFileRefusesDamage) {
    const std::string dir = freshDir("damage");
    const std::string scan = makeScan(dir, 18);
    lodbake::Diagnostics d;
    lodbake::Result<PartitionSet> set = partitionMesh(scan, smallOptions(dir + "/work", 1), d);
    ASSERT_TRUE(set.ok() && set->partitions.size() == 1);
    const std::string path = set->partitions[0].path;
    auto bytes = lodbake::readFileBytes(path);
    ASSERT_TRUE(bytes.ok());
    ASSERT_TRUE(readPartitionFile(path).ok());
    const std::string damaged = dir + "/damaged.lbpart";
    auto refused = [&](const std::vector<uint8_t>& b) {
        EXPECT_TRUE(lodbake::writeFileAtomic(damaged, b.data(), b.size()).ok());
        lodbake::Result<PartitionData> r = readPartitionFile(damaged);
        if (r.ok()) return false;
        EXPECT_EQ(r.status().message().rfind(damaged + ": ", 0), 0u) << r.status().message();
        return true;
    };
    for (size_t n = 0; n < bytes->size(); ++n)
        EXPECT_TRUE(refused(std::vector<uint8_t>(bytes->begin(), bytes->begin() + std::ptrdiff_t(n)))) << n;
    std::vector<uint8_t> longer = *bytes;
    longer.push_back(0);
    EXPECT_TRUE(refused(longer)) << "trailing bytes";
    std::vector<uint8_t> magic = *bytes;
    magic[7] = '2';
    EXPECT_TRUE(refused(magic)) << "unknown version";
    std::vector<uint8_t> index = *bytes;
    index[index.size() - 4] = 0xff; // the last local index, far out of range
    EXPECT_TRUE(refused(index)) << "index out of range";
}
