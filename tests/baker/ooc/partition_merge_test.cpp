// The merge step of the out-of-core bake (lodbake/ooc/partition_merge.h) on generated scans:
// continuing from clusters gives exactly the build from LOD0 when the seed is LOD0's clusters,
// partitions merged level by level reach one root on a closed scan with crack-free cuts over the
// assembled hierarchy, the files are the same bytes at 1 and 2 threads, a damaged input is an error
// naming it with no output left, the memory bound is checked, and one partition assembles into the
// in-memory build.

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cluster_checks.h"
#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_build.h"
#include "lodbake/ooc/partition_merge.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;
using lodbake_test::PositionIds;

namespace {

std::string freshDir(const std::string& name) { return lodbake_test::freshOocDir("partition_merge", name); }

// A generated scan cut into partitions (small reader buffers and a small limit on one thread give
// leaves of about 12,000 triangles at 3 MiB), each built by the partition job to kLevelsPerJob
// levels, as mergeAll's jobs below the top are (a single partition is the top: built in full).
struct Fixture {
    std::string dir;
    lodbake::Mesh input;
    PartitionSet set;
    std::vector<std::string> lods; // leaf order
};

Fixture built(const std::string& name, uint64_t triangles, uint64_t limit = uint64_t(3) << 20) {
    lodbake_test::PartitionedScan scan = lodbake_test::partitionedScan(freshDir(name), triangles, limit);
    Fixture f{scan.dir, std::move(scan.input), std::move(scan.set), {}};
    f.lods = lodbake_test::buildLeafLods(f.set, f.dir + "/lods");
    return f;
}

MergeOptions mergeOptions(const std::string& work) {
    MergeOptions o;
    o.work_dir = work;
    o.memory_limit_bytes = uint64_t(64) << 20;
    return o;
}

std::array<uint32_t, 3> canonical(uint32_t a, uint32_t b, uint32_t c) {
    if (b < a && b < c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
}

std::vector<std::string> filesIn(const std::string& dir) {
    std::vector<std::string> names;
    if (fs::exists(dir))
        for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

void expectSameHierarchy(const lodbake::ClusterLodHierarchy& a, const lodbake::ClusterLodHierarchy& b) {
    ASSERT_EQ(a.clusters.size(), b.clusters.size());
    ASSERT_EQ(a.groups.size(), b.groups.size());
    EXPECT_EQ(0, std::memcmp(a.clusters.data(), b.clusters.data(), a.clusters.size() * sizeof a.clusters[0]));
    EXPECT_EQ(0, std::memcmp(a.groups.data(), b.groups.data(), a.groups.size() * sizeof a.groups[0]));
    EXPECT_EQ(a.group_children, b.group_children);
    EXPECT_EQ(a.roots, b.roots);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.indices, b.indices);
    EXPECT_EQ(a.lod0_cluster_count, b.lod0_cluster_count);
    EXPECT_EQ(a.level_count, b.level_count);
    EXPECT_EQ(a.reached_single_group, b.reached_single_group);
}

} // namespace

TEST(PartitionMergeTest, ContinuingFromLod0ClustersIsTheBuildFromLod0) {
    // The seed entry point adds nothing to the builder but where it starts: LOD0's clusters as the
    // seed (points welded as buildClusterLod welds them, in its point order) give the same hierarchy.
    Fixture f;
    lodbake::scansim::SurfaceOptions so;
    so.triangles = 6000;
    f.dir = freshDir("seed");
    ASSERT_TRUE(lodbake::scansim::writeSurfacePly(so, f.dir + "/scan.ply").ok());
    lodbake::Diagnostics d;
    auto input = lodbake::readMesh(f.dir + "/scan.ply", lodbake::ReadOptions(), d);
    ASSERT_TRUE(input.ok());
    auto whole = lodbake::buildClusterLod(input->mesh, lodbake::ClusterLodOptions(), d);
    ASSERT_TRUE(whole.ok());
    lodbake::ClusterLodSeed seed;
    PositionIds ids;
    std::vector<std::pair<std::array<uint32_t, 3>, uint32_t>> keys; // position bits -> first id
    for (const lodbake::Vec3f& p : input->mesh.positions) {
        std::array<uint32_t, 3> k;
        const float v[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f};
        std::memcpy(k.data(), v, 12);
        keys.push_back({k, 0});
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    for (const auto& k : keys) {
        lodbake::Vec3f p;
        std::memcpy(&p.x, &k.first[0], 4);
        std::memcpy(&p.y, &k.first[1], 4);
        std::memcpy(&p.z, &k.first[2], 4);
        seed.points.push_back(p);
    }
    const auto pointOf = [&](const lodbake::Vec3f& p) {
        std::array<uint32_t, 3> k;
        const float v[3] = {p.x + 0.0f, p.y + 0.0f, p.z + 0.0f};
        std::memcpy(k.data(), v, 12);
        return uint32_t(std::lower_bound(keys.begin(), keys.end(), std::make_pair(k, 0u)) - keys.begin());
    };
    for (uint32_t c = 0; c < whole->lod0_cluster_count; ++c) {
        const lodrt::ClusterLodCluster& cl = whole->clusters[c];
        lodbake::ClusterLodSeed::Cluster s;
        s.first_triangle = uint32_t(seed.triangles.size() / 3);
        s.triangle_count = cl.triangle_count;
        std::copy(cl.center, cl.center + 3, s.lod_center);
        s.lod_radius = cl.radius;
        std::copy(cl.center, cl.center + 3, s.bounds_center);
        s.bounds_radius = cl.radius;
        for (uint32_t t = 0; t < 3 * cl.triangle_count; ++t)
            seed.triangles.push_back(
                pointOf(whole->positions[cl.first_vertex + whole->indices[size_t(cl.first_triangle) * 3 + t]]));
        seed.clusters.push_back(s);
    }
    auto continued = lodbake::continueClusterLod(seed, lodbake::ClusterLodOptions(), d);
    ASSERT_TRUE(continued.ok()) << continued.status().message();
    EXPECT_GT(whole->level_count, 3u);
    expectSameHierarchy(*continued, *whole);

    // A seed outside its ranges is refused.
    seed.clusters.back().triangle_count += 1;
    EXPECT_FALSE(lodbake::continueClusterLod(seed, lodbake::ClusterLodOptions(), d).ok());
}

// What every merge tree of a closed scan must give: one root, every merge under its bound, siblings
// sharing their cut, jobs below the top within kLevelsPerJob levels, and an assembled hierarchy whose
// LOD0 is the input and whose cuts show no crack across the old cuts.
static void expectMergedWithoutCracks(const Fixture& f, const MergeTree& merged) {
    const MergeTree* tree = &merged;
    EXPECT_EQ(tree->merges.size(), f.lods.size() - 1);
    EXPECT_GE(tree->merge_levels, 2u);
    uint64_t shared = 0;
    for (const MergeFile& m : tree->merges) {
        EXPECT_LE(m.accounted_peak_bytes, m.memory_bound_bytes) << m.path;
        EXPECT_GT(m.shared_edges, 0u) << m.path; // siblings share their cut
        if (&m != &tree->merges.back()) {
            EXPECT_LE(m.level_count, kLevelsPerJob) << m.path;
        }
        shared += m.shared_edges;
    }
    EXPECT_GT(shared, 100u);
    const MergeFile& top = tree->merges.back();
    EXPECT_EQ(top.path, tree->top);
    // A closed scan: nothing of the border is left, and the merged hierarchy reaches one root.
    EXPECT_EQ(top.border_edge_count, 0u);
    EXPECT_EQ(top.root_count, 1u) << "the top merge stopped at " << top.root_count << " roots, "
                                  << top.root_triangles << " triangles";

    auto whole = assembleHierarchy(*tree, uint64_t(256) << 20);
    ASSERT_TRUE(whole.ok()) << whole.status().message();
    lodbake_test::expectLimitsAndMonotonic(*whole);
    EXPECT_EQ(whole->roots.size(), top.root_count);
    // Every cluster is reachable from the roots once: each non-root has a parent group.
    size_t orphans = 0;
    for (uint32_t c = 0; c < whole->clusters.size(); ++c)
        orphans += whole->clusters[c].parent_group == lodrt::kClusterNone &&
                   std::find(whole->roots.begin(), whole->roots.end(), c) == whole->roots.end();
    EXPECT_EQ(orphans, 0u);

    // LOD0 of the assembled hierarchy is the input's triangle set.
    PositionIds ids;
    std::vector<std::array<uint32_t, 3>> expected, got;
    for (size_t t = 0; t < f.input.faceCount(); ++t) {
        const uint32_t* v = &f.input.indices[3 * t];
        expected.push_back(canonical(ids.of(f.input.positions[v[0]]), ids.of(f.input.positions[v[1]]),
                                     ids.of(f.input.positions[v[2]])));
    }
    for (uint32_t c = 0; c < whole->lod0_cluster_count; ++c) {
        const lodrt::ClusterLodCluster& cl = whole->clusters[c];
        EXPECT_EQ(cl.self_group, lodrt::kClusterNone);
        for (uint32_t t = 0; t < cl.triangle_count; ++t) {
            uint32_t v[3];
            for (int k = 0; k < 3; ++k)
                v[k] = ids.of(whole->positions[cl.first_vertex + whole->indices[(size_t(cl.first_triangle) + t) * 3 + k]]);
            got.push_back(canonical(v[0], v[1], v[2]));
        }
    }
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected);

    // Cuts over the whole merged hierarchy, across the old cuts: no boundary edge the input lacks.
    lodbake_test::expectCrackFree(f.input, *whole, 300, 29);
}

TEST(PartitionMergeTest, MergedPartitionsReachOneRootWithoutCracks) {
    Fixture f = built("union", 30000);
    ASSERT_GE(f.lods.size(), 3u);
    lodbake::Diagnostics d;
    MergeOptions o = mergeOptions(f.dir + "/merges");
    o.group_by_memory = false; // two files per job
    auto tree = mergeAll(f.lods, o, d);
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    for (const MergeFile& m : tree->merges) EXPECT_GT(m.group_count, 0u) << m.path; // the old cut let it build on
    expectMergedWithoutCracks(f, *tree);
}

// Grouping by memory under a limit that fits three of the largest partitions' roots.
static MergeOptions groupedOptions(const Fixture& f, const std::string& work) {
    uint64_t largest = 0;
    for (const std::string& p : f.lods) {
        auto size = mergeInputSize(p);
        EXPECT_TRUE(size.ok()) << size.status().message();
        if (size.ok()) largest = std::max(largest, size->boundBytes());
    }
    MergeOptions o = mergeOptions(work);
    o.memory_limit_bytes = kMergeFixedBytes + 3 * largest;
    return o;
}

// Grouped by memory under a limit that fits about three partitions' roots: a round joins several
// k-d siblings in one job (merges that build no level below it, the one at its top one level), and
// the result is as sound as the pairwise tree's.
TEST(PartitionMergeTest, GroupedMergesReachOneRootWithoutCracks) {
    Fixture f = built("grouped", 60000);
    ASSERT_GE(f.lods.size(), 5u);
    lodbake::Diagnostics d;
    const MergeOptions o = groupedOptions(f, f.dir + "/merges");
    auto tree = mergeAll(f.lods, o, d);
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    uint32_t carried = 0;
    for (const MergeFile& m : tree->merges) {
        EXPECT_LE(m.memory_bound_bytes, o.memory_limit_bytes) << m.path;
        if (m.group_count == 0) {
            ++carried; // built no level: its roots are its inputs' roots
            EXPECT_EQ(m.root_count, m.seed_count) << m.path;
        }
    }
    EXPECT_GT(carried, 0u);
    uint32_t pairwise_rounds = 0; // the height of the k-d tree over the leaves
    while ((size_t(1) << pairwise_rounds) < f.lods.size()) ++pairwise_rounds;
    EXPECT_LT(tree->merge_levels, pairwise_rounds);
    expectMergedWithoutCracks(f, *tree);
}

TEST(PartitionMergeTest, SameBytesAtOneAndTwoThreads) {
    Fixture f = built("threads", 60000);
    ASSERT_GE(f.lods.size(), 5u);
    for (int threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit{size_t(threads)};
        lodbake::Diagnostics d;
        auto tree = mergeAll(f.lods, groupedOptions(f, f.dir + "/t" + std::to_string(threads)), d);
        ASSERT_TRUE(tree.ok()) << tree.status().message();
        EXPECT_GE(tree->merge_levels, 2u);
        EXPECT_TRUE(std::any_of(tree->merges.begin(), tree->merges.end(),
                                [](const MergeFile& m) { return m.group_count == 0; })); // a merge that builds no level
    }
    const std::vector<std::string> one = filesIn(f.dir + "/t1"), two = filesIn(f.dir + "/t2");
    EXPECT_EQ(one.size(), f.lods.size() - 1);
    ASSERT_EQ(one, two);
    for (const std::string& name : one) {
        auto a = lodbake::readFileBytes(f.dir + "/t1/" + name), b = lodbake::readFileBytes(f.dir + "/t2/" + name);
        ASSERT_TRUE(a.ok() && b.ok());
        EXPECT_TRUE(*a == *b) << name;
    }
}

TEST(PartitionMergeTest, DamagedInputIsAnErrorNamingItWithNoOutput) {
    Fixture f = built("damaged", 20000);
    ASSERT_GE(f.lods.size(), 2u);
    const std::string other = f.lods[1];
    auto bytes = lodbake::readFileBytes(f.lods[0]);
    ASSERT_TRUE(bytes.ok());
    const std::string out = f.dir + "/merges";
    auto expectError = [&](const std::string& path, const std::vector<uint8_t>& content, const std::string& what,
                           bool path_first) {
        {
            std::ofstream file(path, std::ios::binary | std::ios::trunc);
            file.write(reinterpret_cast<const char*>(content.data()), std::streamsize(content.size()));
        }
        lodbake::Diagnostics d;
        auto merged = path_first ? mergePartitionLods(path, other, mergeOptions(out), d)
                                 : mergePartitionLods(other, path, mergeOptions(out), d);
        ASSERT_FALSE(merged.ok()) << what;
        EXPECT_EQ(merged.status().code(), lodbake::StatusCode::InvalidInput) << what;
        EXPECT_EQ(merged.status().message().rfind(path + ": ", 0), 0u) << what << ": " << merged.status().message();
        EXPECT_TRUE(filesIn(out).empty()) << what;
        // The driver too, with nothing left behind.
        std::vector<std::string> lods = f.lods;
        lods[path_first ? 0 : 1] = path;
        auto tree = mergeAll(lods, mergeOptions(out), d);
        ASSERT_FALSE(tree.ok()) << what;
        EXPECT_NE(tree.status().message().find(path), std::string::npos) << tree.status().message();
        EXPECT_TRUE(filesIn(out).empty()) << what;
    };
    const std::string source = f.lods[0];
    std::vector<uint8_t> truncated(bytes->begin(), bytes->begin() + std::ptrdiff_t(bytes->size() / 2));
    expectError(source, truncated, "truncated", true);
    // One border position changed: the sizes still agree, the content no longer hashes to the name.
    std::vector<uint8_t> flipped = *bytes;
    flipped[flipped.size() - 1] ^= 0x01;
    expectError(source, flipped, "border edge changed", false);
    // A root out of range, under a name that is not a hash.
    std::vector<uint8_t> root = *bytes;
    uint32_t counts[11];
    std::memcpy(counts, root.data() + 16, sizeof counts);
    const size_t roots_at = 60 + 60 * size_t(counts[0]) + 48 * size_t(counts[1]) + 4 * size_t(counts[2]);
    std::fill(root.begin() + std::ptrdiff_t(roots_at), root.begin() + std::ptrdiff_t(roots_at + 4), uint8_t(0xff));
    expectError(f.dir + "/renamed.lbplod", root, "root out of range", true);
    // The same hierarchy twice.
    lodbake::Diagnostics d;
    auto twice = mergePartitionLods(other, other, mergeOptions(out), d);
    ASSERT_FALSE(twice.ok());
    EXPECT_EQ(twice.status().code(), lodbake::StatusCode::InvalidInput);
    EXPECT_TRUE(filesIn(out).empty());
    // Missing.
    auto missing = mergePartitionLods(f.dir + "/none.lbplod", other, mergeOptions(out), d);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find(f.dir + "/none.lbplod"), std::string::npos);
    EXPECT_TRUE(filesIn(out).empty());
}

TEST(PartitionMergeTest, MemoryBoundIsCheckedAndKept) {
    Fixture f = built("memory", 20000);
    ASSERT_GE(f.lods.size(), 2u);
    lodbake::Diagnostics d;
    MergeOptions o = mergeOptions(f.dir + "/probe");
    auto probe = mergePartitionLods(f.lods[0], f.lods[1], o, d);
    ASSERT_TRUE(probe.ok()) << probe.status().message();
    const uint64_t bound = probe->memory_bound_bytes;
    EXPECT_LE(probe->accounted_peak_bytes, bound);
    // The builder's allowance dominates: the bound follows the roots, not the partitions.
    EXPECT_GT(bound, kClusterBuildBytesPerTriangle * probe->seed_triangles);
    EXPECT_LT(bound, (uint64_t(3) << 20) + 400 * uint64_t(probe->seed_triangles));
    // mergeAll sizes its jobs by the same bound, summed over the inputs.
    auto a = mergeInputSize(f.lods[0]), b = mergeInputSize(f.lods[1]);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_EQ(bound, kMergeFixedBytes + a->boundBytes() + b->boundBytes());
    o.work_dir = f.dir + "/exact";
    o.memory_limit_bytes = bound;
    auto exact = mergePartitionLods(f.lods[0], f.lods[1], o, d);
    ASSERT_TRUE(exact.ok()) << exact.status().message();
    EXPECT_EQ(exact->content_hash, probe->content_hash);
    o.work_dir = f.dir + "/refused";
    o.memory_limit_bytes = bound - 1;
    auto refused = mergePartitionLods(f.lods[0], f.lods[1], o, d);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::ResourceLimit);
    EXPECT_EQ(refused.status().message().rfind(f.lods[0] + ": memory limit", 0), 0u) << refused.status().message();
    EXPECT_NE(refused.status().message().find("needs at least"), std::string::npos);
    EXPECT_TRUE(filesIn(o.work_dir).empty());
}

TEST(PartitionMergeTest, OnePartitionAssemblesIntoTheInMemoryBuild) {
    Fixture f = built("whole", 8000, uint64_t(64) << 20);
    ASSERT_EQ(f.lods.size(), 1u);
    lodbake::Diagnostics d;
    auto tree = mergeAll(f.lods, mergeOptions(f.dir + "/merges"), d);
    ASSERT_TRUE(tree.ok()) << tree.status().message();
    EXPECT_TRUE(tree->merges.empty());
    EXPECT_EQ(tree->top, f.lods[0]);
    auto assembled = assembleHierarchy(*tree, uint64_t(64) << 20);
    ASSERT_TRUE(assembled.ok()) << assembled.status().message();
    auto whole = lodbake::buildClusterLod(f.input, lodbake::ClusterLodOptions(), d);
    ASSERT_TRUE(whole.ok());
    expectSameHierarchy(*assembled, *whole);
    // Too small a limit to hold it is refused.
    auto refused = assembleHierarchy(*tree, 1024);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::ResourceLimit);
}
