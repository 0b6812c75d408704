// The in-process out-of-core driver (lodbake/ooc/driver.h) on a generated scan cut into several
// partitions: the same output bytes at 1 and 2 threads and at two memory limits that both run, the
// pages equal writeClusterLodPack(assembleHierarchy(tree)) of the same tree, the accounted peak
// within the limit, and a cancel, a job refused by the limit and a failure at the last step each
// leave the work folder and the output as they were.

#include "lodbake/ooc/driver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/pack/cluster_lod_pack.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

std::string driverDir(const std::string& name) { return lodbake_test::freshOocDir("ooc_driver", name); }

std::vector<std::string> driverFilesIn(const std::string& dir) {
    std::vector<std::string> names;
    if (fs::exists(dir))
        for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::string driverScan(const std::string& dir, uint64_t triangles) { return lodbake_test::writeGeneratedScan(dir, triangles); }

OutOfCoreOptions driverOptions(const std::string& work, uint64_t limit_mib, int threads) {
    return lodbake_test::smallDriverOptions(work, limit_mib << 20, threads);
}

struct DriverOutput {
    lodbake::Result<OutOfCoreResult> result = lodbake::internalError("not run");
    std::vector<uint8_t> output;
};

DriverOutput runDriver(const std::string& scan, const std::string& out, const OutOfCoreOptions& o) {
    DriverOutput r;
    lodbake::Diagnostics d;
    r.result = buildOutOfCore(scan, out, o, d);
    EXPECT_TRUE(r.result.ok()) << r.result.status().message();
    if (!r.result.ok()) return r;
    auto bytes = lodbake::readFileBytes(out);
    EXPECT_TRUE(bytes.ok());
    if (bytes.ok()) r.output = std::move(*bytes);
    return r;
}

TEST(OocDriverTest, SameBytesAtAnyThreadCountAndLimit) {
    const std::string dir = driverDir("same");
    const std::string scan = driverScan(dir, 60000);
    const DriverOutput one = runDriver(scan, dir + "/one.bin", driverOptions(dir + "/work", 512, 1));
    const DriverOutput two = runDriver(scan, dir + "/two.bin", driverOptions(dir + "/work", 512, 2));
    const DriverOutput tight = runDriver(scan, dir + "/tight.bin", driverOptions(dir + "/work", 12, 2));
    ASSERT_TRUE(one.result.ok() && two.result.ok() && tight.result.ok());
    EXPECT_GT(one.result->partition_count, 2u);
    EXPECT_GT(one.result->merge_count, 1u);
    EXPECT_FALSE(one.output.empty());
    EXPECT_EQ(one.output, two.output);
    EXPECT_EQ(one.output, tight.output);
    EXPECT_EQ(one.result->table, two.result->table);
    EXPECT_EQ(one.result->table, tight.result->table);
    EXPECT_LE(tight.result->accounted_peak_bytes, uint64_t(12) << 20);
    EXPECT_LE(two.result->jobs_peak_bytes, uint64_t(512) << 20);
    // Intermediate files are removed after a run; the work folder was created by the first run.
    EXPECT_TRUE(driverFilesIn(dir + "/work").empty());
}

TEST(OocDriverTest, PagesEqualTheInMemoryWriterOnTheSameTree) {
    const std::string dir = driverDir("pages");
    const std::string scan = driverScan(dir, 60000);
    OutOfCoreOptions o = driverOptions(dir + "/work", 256, 2);
    o.keep_intermediate = true;
    const DriverOutput run = runDriver(scan, dir + "/out.bin", o);
    ASSERT_TRUE(run.result.ok());
    auto h = assembleHierarchy(run.result->tree, uint64_t(1) << 30);
    ASSERT_TRUE(h.ok()) << h.status().message();
    auto pack = lodbake::writeClusterLodPack(*h, lodbake::ClusterPackOptions());
    ASSERT_TRUE(pack.ok()) << pack.status().message();
    EXPECT_EQ(run.result->cluster_count, h->clusters.size());
    EXPECT_EQ(run.result->table, pack->extension.blobs[0]);
    EXPECT_EQ(run.output, pack->extension.blobs[1]);
}

TEST(OocDriverTest, CancelAndFailuresLeaveNothingBehind) {
    const std::string dir = driverDir("fail");
    const std::string scan = driverScan(dir, 60000);
    const std::string work = dir + "/work";
    fs::create_directories(work);
    {
        std::ofstream keep(work + "/keep.txt");
        keep << "the caller's";
    }
    const std::vector<std::string> before = driverFilesIn(work);
    const std::vector<std::string> dir_before = driverFilesIn(dir);
    const std::string out = dir + "/out.bin";
    lodbake::Diagnostics d;
    {
        std::atomic<bool> cancel{true};
        OutOfCoreOptions o = driverOptions(work, 256, 2);
        o.cancel = &cancel;
        auto r = buildOutOfCore(scan, out, o, d);
        ASSERT_FALSE(r.ok());
        EXPECT_NE(r.status().message().find(scan), std::string::npos) << r.status().message();
    }
    EXPECT_EQ(driverFilesIn(work), before);
    EXPECT_EQ(driverFilesIn(dir), dir_before);
    {
        // Merge jobs larger than the limit (the grouping allows more than the limit holds): refused
        // after every partition and partition job has written its file.
        OutOfCoreOptions o = driverOptions(work, 10, 1);
        o.merge_group_bytes = uint64_t(64) << 20;
        auto r = buildOutOfCore(scan, out, o, d);
        ASSERT_FALSE(r.ok());
        EXPECT_EQ(r.status().code(), lodbake::StatusCode::ResourceLimit) << r.status().message();
        EXPECT_NE(r.status().message().find("MiB"), std::string::npos) << r.status().message();
    }
    EXPECT_EQ(driverFilesIn(work), before);
    EXPECT_EQ(driverFilesIn(dir), dir_before);
    {
        // The output's folder does not exist: the last step fails after every job has run.
        auto r = buildOutOfCore(scan, dir + "/missing/out.bin", driverOptions(work, 256, 2), d);
        ASSERT_FALSE(r.ok());
    }
    EXPECT_EQ(driverFilesIn(work), before);
    EXPECT_EQ(driverFilesIn(dir), dir_before);
    {
        // A leaf whose job cannot fit the limit is refused before any file is written.
        OutOfCoreOptions o = driverOptions(work, 8, 1);
        o.leaf_triangles = 60000;
        auto r = buildOutOfCore(scan, out, o, d);
        ASSERT_FALSE(r.ok());
        EXPECT_EQ(r.status().code(), lodbake::StatusCode::ResourceLimit);
        EXPECT_NE(r.status().message().find(scan), std::string::npos) << r.status().message();
    }
    EXPECT_EQ(driverFilesIn(work), before);
    EXPECT_EQ(driverFilesIn(dir), dir_before);
}

} // namespace
