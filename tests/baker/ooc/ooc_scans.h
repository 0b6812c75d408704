#pragma once
// Shared set-up of the out-of-core tests: a fresh scratch folder, a generated scan written to it,
// and the partitioner's and the driver's options with small reader buffers, so that a few-MiB limit
// cuts a scan of tens of thousands of triangles into several partitions (about 12,000 triangles
// each at 3 MiB on one thread).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/diagnostics.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/ooc/driver.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/ooc/partition_merge.h"
#include "scansim.h"
#include "test_paths.h"

namespace lodbake_test {

/// `<scratch>/<suite>/<name>`, emptied.
inline std::string freshOocDir(const std::string& suite, const std::string& name) {
    const std::string dir = scratchDir() + "/" + suite + "/" + name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

/// A generated closed scan of `triangles` triangles written to `dir`/scan.ply; returns its path.
inline std::string writeGeneratedScan(const std::string& dir, uint64_t triangles) {
    lodbake::scansim::SurfaceOptions o;
    o.triangles = triangles;
    const std::string path = dir + "/scan.ply";
    EXPECT_TRUE(lodbake::scansim::writeSurfacePly(o, path).ok());
    return path;
}

/// Small reader buffers and sample, for the partitioner's options and the driver's alike.
template <class Options> void useSmallReads(Options& o) {
    o.read.buffer_bytes = 64 << 10;
    o.read.max_record_bytes = 256 << 10;
    o.read.vertex_chunk = 4096;
    o.read.triangle_chunk = 4096;
    o.sample_cap = 4096;
}

/// The partitioner's options with small reader buffers and sample.
inline lodbake::ooc::PartitionOptions smallPartitionOptions(const std::string& work, int threads, uint64_t limit) {
    lodbake::ooc::PartitionOptions o;
    o.work_dir = work;
    o.threads = threads;
    useSmallReads(o);
    o.memory_limit_bytes = limit;
    return o;
}

/// The driver's options with small reader buffers and partitions of about 12,000 triangles, so a
/// 60,000-triangle scan makes several partitions and merge rounds.
inline lodbake::ooc::OutOfCoreOptions smallDriverOptions(const std::string& work, uint64_t limit, int threads) {
    lodbake::ooc::OutOfCoreOptions o;
    o.work_dir = work;
    o.memory_limit_bytes = limit;
    o.threads = threads;
    useSmallReads(o);
    o.leaf_triangles = 12000;
    o.merge_group_bytes = uint64_t(8) << 20;
    return o;
}

/// A generated scan, read whole and cut into partitions in `dir`/parts on one thread.
struct PartitionedScan {
    std::string dir;
    std::string scan;
    lodbake::Mesh input;
    lodbake::ooc::PartitionSet set;
};

inline PartitionedScan partitionedScan(const std::string& dir, uint64_t triangles, uint64_t limit = uint64_t(3) << 20) {
    PartitionedScan f;
    f.dir = dir;
    f.scan = writeGeneratedScan(dir, triangles);
    lodbake::Diagnostics d;
    auto input = lodbake::readMesh(f.scan, lodbake::ReadOptions(), d);
    EXPECT_TRUE(input.ok());
    if (input.ok()) f.input = std::move(input->mesh);
    auto set = lodbake::ooc::partitionMesh(f.scan, smallPartitionOptions(dir + "/parts", 1, limit), d);
    EXPECT_TRUE(set.ok()) << set.status().message();
    if (set.ok()) f.set = std::move(*set);
    return f;
}

/// Every partition of `set` built by the partition job into `work`, to kLevelsPerJob levels as
/// mergeAll's jobs below the top are (a single partition is the top: built in full); the hierarchy
/// files in leaf order.
inline std::vector<std::string> buildLeafLods(const lodbake::ooc::PartitionSet& set, const std::string& work) {
    lodbake::ooc::PartitionBuildOptions o;
    o.work_dir = work;
    o.memory_limit_bytes = uint64_t(64) << 20;
    if (set.partitions.size() > 1) o.cluster.max_levels = lodbake::ooc::kLevelsPerJob;
    std::vector<std::string> lods;
    lodbake::Diagnostics d;
    for (const lodbake::ooc::PartitionFile& pf : set.partitions) {
        auto lod = lodbake::ooc::buildPartition(pf.path, o, d);
        EXPECT_TRUE(lod.ok()) << lod.status().message();
        if (lod.ok()) lods.push_back(lod->path);
    }
    return lods;
}

} // namespace lodbake_test
