// The out-of-core level error (lodbake/ooc/level_error.h) on a generated scan cut into several
// partitions: it equals measureSurfaceDistance of the same level against the whole input in
// partition order (the same points; the level side bit for bit, the input side's sums up to their
// rounding), stays within sampling noise of the measurement against the input in file order, gives
// the known error of a shifted copy, is the same bits at 1 and 2 threads and for several levels at
// once, keeps its accounted memory under its bound, refuses damaged partition files (and stops at a
// cancel) naming them, and measures what buildOutOfCore leaves with keep_intermediate.

#include "lodbake/ooc/level_error.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/ooc/driver.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/simplify/simplify.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

std::string levelErrorDir(const std::string& name) { return lodbake_test::freshOocDir("level_error", name); }

struct LevelFixture {
    std::string dir;
    lodbake::Mesh input;           // as read, file order
    lodbake::Mesh partition_order; // the partitions' triangles in order, over vertices numbered by global id
    PartitionSet set;
};

// A generated scan cut into partitions of about 12,000 triangles (small reader buffers, a 3 MiB limit).
LevelFixture levelFixture(const std::string& name, uint64_t triangles) {
    lodbake_test::PartitionedScan scan = lodbake_test::partitionedScan(levelErrorDir(name), triangles);
    LevelFixture f;
    f.dir = scan.dir;
    f.input = std::move(scan.input);
    f.set = std::move(scan.set);
    f.partition_order.positions.resize(f.set.vertex_count);
    for (const PartitionFile& p : f.set.partitions) {
        auto data = readPartitionFile(p.path);
        EXPECT_TRUE(data.ok());
        if (!data.ok()) continue;
        for (size_t v = 0; v < data->global_ids.size(); ++v) f.partition_order.positions[data->global_ids[v]] = data->positions[v];
        for (uint32_t i : data->indices) f.partition_order.indices.push_back(data->global_ids[i]);
    }
    return f;
}

lodbake::Mesh simplified(const lodbake::Mesh& input, float ratio) {
    lodbake::SimplifyOptions so;
    so.target_ratio = ratio;
    lodbake::Diagnostics d;
    auto out = lodbake::simplify(input, so, d);
    EXPECT_TRUE(out.ok()) << out.status().message();
    return out.ok() ? out->mesh : lodbake::Mesh();
}

LevelErrorOptions levelOptions(int threads) {
    LevelErrorOptions o;
    o.threads = threads;
    o.distance.sample_count = 50000;
    o.bound_triangles = 2000; // a coarse subsample: the level side must still find the exact nearest
    return o;
}

void expectSameBits(double a, double b, const char* what) {
    EXPECT_EQ(std::memcmp(&a, &b, sizeof a), 0) << what << ": " << a << " vs " << b;
}

// The out-of-core result against the in-memory measurement of the same points.
void expectSameMeasurement(const lodbake::DistanceResult& ooc, const lodbake::DistanceResult& mem) {
    expectSameBits(ooc.max_approx_to_ref, mem.max_approx_to_ref, "level side max");
    expectSameBits(ooc.max_ref_to_approx, mem.max_ref_to_approx, "input side max");
    expectSameBits(ooc.hausdorff, mem.hausdorff, "hausdorff");
    expectSameBits(ooc.diagonal, mem.diagonal, "diagonal");
    // The input side's sums are the same terms added in another order.
    EXPECT_NEAR(ooc.mean, mem.mean, 1e-12 * mem.mean);
    EXPECT_NEAR(ooc.rms, mem.rms, 1e-12 * mem.rms);
}

} // namespace

TEST(LevelErrorTest, SimplifiedLevelEqualsTheInMemoryMeasurement) {
    LevelFixture f = levelFixture("simplified", 40000);
    ASSERT_GE(f.set.partitions.size(), 3u);
    const lodbake::Mesh level = simplified(f.input, 0.1f);
    ASSERT_GT(level.faceCount(), 0u);
    const LevelErrorOptions o = levelOptions(2);
    auto ooc = measureLevelError(f.set, level, o);
    ASSERT_TRUE(ooc.ok()) << ooc.status().message();
    auto mem = lodbake::measureSurfaceDistance(f.partition_order, level, o.distance);
    ASSERT_TRUE(mem.ok());
    expectSameMeasurement(ooc->distance, *mem);
    EXPECT_GT(ooc->distance.hausdorff, 0.0);
    EXPECT_EQ(ooc->partition_count, f.set.partitions.size());
    EXPECT_EQ(ooc->input_triangles, f.input.faceCount());
    EXPECT_EQ(ooc->input_vertices, f.set.vertex_count);
    // Level points near a cut are measured against more than one partition; most against one.
    EXPECT_GT(ooc->level_queries, ooc->level_points);
    EXPECT_LT(ooc->level_queries, 2 * ooc->level_points);
    // Against the input in file order the samples are stratified over another triangle order: the
    // same surface, other samples, so the figures agree within sampling noise.
    auto file_order = lodbake::measureSurfaceDistance(f.input, level, o.distance);
    ASSERT_TRUE(file_order.ok());
    EXPECT_NEAR(ooc->distance.mean, file_order->mean, 0.01 * file_order->mean);
    EXPECT_NEAR(ooc->distance.rms, file_order->rms, 0.01 * file_order->rms);
    EXPECT_NEAR(ooc->distance.hausdorff, file_order->hausdorff, 0.1 * file_order->hausdorff);
    expectSameBits(ooc->distance.diagonal, file_order->diagonal, "diagonal against the file order");
}

TEST(LevelErrorTest, ShiftedCopyHasItsKnownError) {
    LevelFixture f = levelFixture("shifted", 30000);
    ASSERT_GE(f.set.partitions.size(), 2u);
    lodbake::Mesh level = f.input;
    const double diagonal = f.set.partitions.empty() ? 0.0 : lodbake::computeBounds(f.input).diagonal();
    const float shift = float(0.01 * diagonal);
    for (lodbake::Vec3f& p : level.positions) p.x += shift;
    const LevelErrorOptions o = levelOptions(2);
    auto ooc = measureLevelError(f.set, level, o);
    ASSERT_TRUE(ooc.ok()) << ooc.status().message();
    auto mem = lodbake::measureSurfaceDistance(f.partition_order, level, o.distance);
    ASSERT_TRUE(mem.ok());
    expectSameMeasurement(ooc->distance, *mem);
    // No point of a copy moved by d lies farther than d from the original; on a closed surface some
    // (where the surface faces the shift) lie nearly d away.
    EXPECT_LE(ooc->distance.hausdorff, double(shift) + 1e-6 * diagonal); // the shift rounded per vertex
    EXPECT_GT(ooc->distance.hausdorff, 0.5 * double(shift));
    EXPECT_GT(ooc->distance.mean, 0.05 * double(shift));
    EXPECT_LT(ooc->distance.mean, double(shift));
    // The level itself: exactly zero error on the level side's samples that lie on the input.
    auto same = measureLevelError(f.set, f.input, o);
    ASSERT_TRUE(same.ok());
    EXPECT_LT(same->distance.hausdorffRel(), 1e-6);
}

TEST(LevelErrorTest, SameBitsAtOneAndTwoThreads) {
    LevelFixture f = levelFixture("threads", 30000);
    const lodbake::Mesh level = simplified(f.input, 0.05f);
    auto one = measureLevelError(f.set, level, levelOptions(1));
    auto two = measureLevelError(f.set, level, levelOptions(2));
    ASSERT_TRUE(one.ok() && two.ok());
    expectSameBits(one->distance.hausdorff, two->distance.hausdorff, "hausdorff");
    expectSameBits(one->distance.mean, two->distance.mean, "mean");
    expectSameBits(one->distance.rms, two->distance.rms, "rms");
    expectSameBits(one->distance.max_ref_to_approx, two->distance.max_ref_to_approx, "input side max");
    EXPECT_EQ(one->level_queries, two->level_queries);
}

TEST(LevelErrorTest, SeveralLevelsInOnePassEqualEachAlone) {
    LevelFixture f = levelFixture("batch", 30000);
    const lodbake::Mesh fine = simplified(f.input, 0.2f), coarse = simplified(f.input, 0.02f);
    const LevelErrorOptions o = levelOptions(2);
    auto both = measureLevelErrors({f.set.partitions[0].path, f.set.partitions[1].path}, {&fine, &coarse}, o);
    ASSERT_TRUE(both.ok()) << both.status().message();
    ASSERT_EQ(both->size(), 2u);
    const lodbake::Mesh* levels[2] = {&fine, &coarse};
    for (size_t i = 0; i < 2; ++i) {
        auto alone = measureLevelError({f.set.partitions[0].path, f.set.partitions[1].path}, *levels[i], o);
        ASSERT_TRUE(alone.ok());
        const lodbake::DistanceResult& a = alone->distance;
        const lodbake::DistanceResult& b = (*both)[i].distance;
        expectSameBits(a.hausdorff, b.hausdorff, "hausdorff");
        expectSameBits(a.mean, b.mean, "mean");
        expectSameBits(a.rms, b.rms, "rms");
        EXPECT_EQ(alone->level_queries, (*both)[i].level_queries);
        EXPECT_LT(alone->memory_bound_bytes, (*both)[i].memory_bound_bytes);
    }
    EXPECT_LT((*both)[0].distance.mean, (*both)[1].distance.mean);
}

TEST(LevelErrorTest, MemoryStaysUnderItsBoundAndTheLimit) {
    LevelFixture f = levelFixture("memory", 30000);
    const lodbake::Mesh level = simplified(f.input, 0.1f);
    LevelErrorOptions o = levelOptions(2);
    auto r = measureLevelError(f.set, level, o);
    ASSERT_TRUE(r.ok());
    EXPECT_GT(r->accounted_peak_bytes, 0u);
    EXPECT_LE(r->accounted_peak_bytes, r->memory_bound_bytes);
    std::vector<std::string> files;
    for (const PartitionFile& p : f.set.partitions) files.push_back(p.path);
    auto bound = levelErrorBound(files, {&level}, o);
    ASSERT_TRUE(bound.ok());
    EXPECT_EQ(*bound, r->memory_bound_bytes);
    o.memory_limit_bytes = r->memory_bound_bytes - 1;
    auto refused = measureLevelError(f.set, level, o);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::ResourceLimit);
    EXPECT_EQ(refused.status().message().rfind(f.set.partitions[0].path + ": ", 0), 0u) << refused.status().message();
    o.memory_limit_bytes = r->memory_bound_bytes;
    EXPECT_TRUE(measureLevelError(f.set, level, o).ok());
}

TEST(LevelErrorTest, DamagedPartitionFilesAreRefusedNamingThem) {
    LevelFixture f = levelFixture("damaged", 30000);
    ASSERT_GE(f.set.partitions.size(), 2u);
    const lodbake::Mesh level = simplified(f.input, 0.1f);
    const std::string path = f.set.partitions[1].path;
    auto bytes = lodbake::readFileBytes(path);
    ASSERT_TRUE(bytes.ok());
    std::vector<std::string> files;
    for (const PartitionFile& p : f.set.partitions) files.push_back(p.path);
    auto expectRefused = [&](const std::vector<std::string>& list, const std::string& named, const std::string& what) {
        auto r = measureLevelError(list, level, levelOptions(2));
        ASSERT_FALSE(r.ok()) << what;
        EXPECT_EQ(r.status().message().rfind(named + ": ", 0), 0u) << what << ": " << r.status().message();
    };
    auto write = [](const std::string& to, const std::vector<uint8_t>& content) {
        std::ofstream file(to, std::ios::binary | std::ios::trunc);
        file.write(reinterpret_cast<const char*>(content.data()), std::streamsize(content.size()));
    };
    // Truncated: the header's counts no longer match the size.
    write(path, std::vector<uint8_t>(bytes->begin(), bytes->begin() + std::ptrdiff_t(bytes->size() / 2)));
    expectRefused(files, path, "truncated");
    // One position changed: the bytes no longer hash to the name.
    std::vector<uint8_t> flipped = *bytes;
    flipped[40 + 4 * f.set.partitions[1].vertex_count + 5] ^= 0x10;
    write(path, flipped);
    expectRefused(files, path, "position changed");
    // Not a partition file.
    std::vector<uint8_t> magic = *bytes;
    magic[0] = 'X';
    write(path, magic);
    expectRefused(files, path, "magic");
    // Under a name that is not a hash, an index out of range.
    const std::string renamed = f.dir + "/renamed.lbpart";
    std::vector<uint8_t> index = *bytes;
    std::fill(index.end() - 4, index.end(), uint8_t(0xff));
    write(renamed, index);
    std::vector<std::string> with_renamed = files;
    with_renamed[1] = renamed;
    expectRefused(with_renamed, renamed, "index out of range");
    // Missing.
    std::vector<std::string> with_missing = files;
    with_missing[1] = f.dir + "/none.lbpart";
    expectRefused(with_missing, with_missing[1], "missing");
    write(path, *bytes);
    EXPECT_TRUE(measureLevelError(files, level, levelOptions(2)).ok());
    // A cancel is an error naming the file it stopped at.
    std::atomic<bool> cancel{true};
    LevelErrorOptions o = levelOptions(2);
    o.cancel = &cancel;
    auto cancelled = measureLevelError(files, level, o);
    ASSERT_FALSE(cancelled.ok());
    EXPECT_EQ(cancelled.status().message().rfind(files[0] + ": ", 0), 0u) << cancelled.status().message();
}

TEST(LevelErrorTest, PartitionFilesOfAMergeTree) {
    LevelFixture f = levelFixture("tree", 30000);
    ASSERT_GE(f.set.partitions.size(), 2u);
    MergeTree tree;
    PartitionBuildOptions bo;
    bo.work_dir = f.dir + "/parts";
    bo.cluster.max_levels = 1;
    for (const PartitionFile& p : f.set.partitions) {
        lodbake::Diagnostics d;
        auto built = buildPartition(p.path, bo, d);
        ASSERT_TRUE(built.ok()) << built.status().message();
        tree.partitions.push_back(built->path);
    }
    auto files = partitionFilesOf(tree);
    ASSERT_TRUE(files.ok()) << files.status().message();
    ASSERT_EQ(files->size(), f.set.partitions.size());
    for (size_t i = 0; i < files->size(); ++i) EXPECT_EQ((*files)[i], f.set.partitions[i].path);
    fs::remove(f.set.partitions[0].path);
    auto missing = partitionFilesOf(tree);
    ASSERT_FALSE(missing.ok());
    EXPECT_EQ(missing.status().message().rfind(tree.partitions[0] + ": ", 0), 0u) << missing.status().message();
}

TEST(LevelErrorTest, WhatTheDriverLeavesIsMeasuredAgainstTheInput) {
    const std::string dir = levelErrorDir("driver");
    lodbake::scansim::SurfaceOptions so;
    so.triangles = 40000;
    const std::string scan = dir + "/scan.ply";
    ASSERT_TRUE(lodbake::scansim::writeSurfacePly(so, scan).ok());
    OutOfCoreOptions o;
    o.work_dir = dir + "/work";
    o.memory_limit_bytes = uint64_t(512) << 20;
    o.threads = 2;
    o.sample_cap = 4096;
    o.leaf_triangles = 12000;
    o.merge_group_bytes = uint64_t(8) << 20;
    o.keep_intermediate = true;
    lodbake::Diagnostics d;
    auto baked = buildOutOfCore(scan, dir + "/pages.bin", o, d);
    ASSERT_TRUE(baked.ok()) << baked.status().message();
    auto files = partitionFilesOf(baked->tree);
    ASSERT_TRUE(files.ok()) << files.status().message();
    ASSERT_EQ(files->size(), baked->partition_count);
    ASSERT_GE(files->size(), 3u);
    // The input in partition order, from the files, for the in-memory measurement.
    lodbake::Mesh input;
    input.positions.resize(baked->vertex_count);
    for (const std::string& path : *files) {
        auto data = readPartitionFile(path);
        ASSERT_TRUE(data.ok());
        for (size_t v = 0; v < data->global_ids.size(); ++v) input.positions[data->global_ids[v]] = data->positions[v];
        for (uint32_t i : data->indices) input.indices.push_back(data->global_ids[i]);
    }
    ASSERT_EQ(input.faceCount(), baked->triangle_count);
    const lodbake::Mesh level = simplified(input, 0.05f);
    const LevelErrorOptions lo = levelOptions(2);
    auto ooc = measureLevelError(*files, level, lo);
    ASSERT_TRUE(ooc.ok()) << ooc.status().message();
    auto mem = lodbake::measureSurfaceDistance(input, level, lo.distance);
    ASSERT_TRUE(mem.ok());
    expectSameMeasurement(ooc->distance, *mem);
}
