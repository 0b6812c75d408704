// The partition job (lodbake/ooc/partition_build.h) on generated scans: partitions built
// independently cover the input exactly and their cuts meet without cracks, the output is the same
// bytes at 1 and 2 threads, a damaged partition is an error naming it with no output left, and the
// memory accounting stays within the limit.

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "cluster_checks.h"
#include "core/parallel.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/ooc/partition.h"
#include "lodbake/ooc/partition_build.h"
#include "ooc_scans.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;
using lodbake_test::PositionIds;

namespace {

using Fixture = lodbake_test::PartitionedScan;

Fixture partitioned(const std::string& name, uint64_t triangles, uint64_t limit = uint64_t(3) << 20) {
    return lodbake_test::partitionedScan(lodbake_test::freshOocDir("partition_build", name), triangles, limit);
}

PartitionBuildOptions buildOptions(const std::string& work) {
    PartitionBuildOptions o;
    o.work_dir = work;
    o.memory_limit_bytes = uint64_t(64) << 20;
    return o;
}

// The partitions' hierarchies side by side in one hierarchy (a forest with every partition's roots):
// its cuts are the union of each partition's own cut.
lodbake::ClusterLodHierarchy unionOf(const std::vector<PartitionLod>& parts) {
    lodbake::ClusterLodHierarchy u;
    for (const PartitionLod& p : parts) {
        const lodbake::ClusterLodHierarchy& h = p.hierarchy;
        const uint32_t c0 = uint32_t(u.clusters.size()), g0 = uint32_t(u.groups.size()),
                       k0 = uint32_t(u.group_children.size()), v0 = uint32_t(u.positions.size()),
                       t0 = uint32_t(u.indices.size() / 3);
        for (lodrt::ClusterLodCluster c : h.clusters) {
            if (c.self_group != lodrt::kClusterNone) c.self_group += g0;
            if (c.parent_group != lodrt::kClusterNone) c.parent_group += g0;
            c.first_vertex += v0;
            c.first_triangle += t0;
            u.clusters.push_back(c);
        }
        for (lodrt::ClusterLodGroup g : h.groups) {
            g.first_child += k0;
            u.groups.push_back(g);
        }
        for (uint32_t c : h.group_children) u.group_children.push_back(c + c0);
        for (uint32_t r : h.roots) u.roots.push_back(r + c0);
        u.positions.insert(u.positions.end(), h.positions.begin(), h.positions.end());
        u.indices.insert(u.indices.end(), h.indices.begin(), h.indices.end());
    }
    return u;
}

// A triangle as point ids, rotated so the smallest comes first (orientation kept).
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

} // namespace

TEST(PartitionBuildTest, IndependentPartitionsCoverTheInputAndMeetWithoutCracks) {
    Fixture f = partitioned("union", 30000);
    ASSERT_GE(f.set.partitions.size(), 3u);
    std::vector<PartitionLod> parts;
    PartitionBuildOptions o = buildOptions(f.dir + "/lods");
    for (const PartitionFile& pf : f.set.partitions) {
        lodbake::Diagnostics d;
        auto built = buildPartition(pf.path, o, d);
        ASSERT_TRUE(built.ok()) << built.status().message();
        EXPECT_EQ(built->source_hash, pf.content_hash);
        EXPECT_EQ(built->triangle_count, pf.triangle_count);
        EXPECT_GT(built->level_count, 1u) << pf.path;
        EXPECT_GT(built->border_edge_count, 0u);
        auto back = readPartitionLodFile(built->path);
        ASSERT_TRUE(back.ok()) << back.status().message();
        EXPECT_EQ(back->hierarchy.roots.size(), built->root_count);
        lodbake_test::expectLimitsAndMonotonic(back->hierarchy);
        parts.push_back(std::move(*back));
    }

    // LOD0: the union of the partitions' LOD0 clusters is the input's triangle set.
    PositionIds ids;
    std::vector<std::array<uint32_t, 3>> expected, got;
    for (size_t t = 0; t < f.input.faceCount(); ++t) {
        const uint32_t* v = &f.input.indices[3 * t];
        expected.push_back(canonical(ids.of(f.input.positions[v[0]]), ids.of(f.input.positions[v[1]]),
                                     ids.of(f.input.positions[v[2]])));
    }
    const size_t input_points = ids.ids.size();
    for (const PartitionLod& p : parts)
        for (uint32_t c = 0; c < p.hierarchy.lod0_cluster_count; ++c) {
            const lodrt::ClusterLodCluster& cl = p.hierarchy.clusters[c];
            for (uint32_t t = 0; t < cl.triangle_count; ++t) {
                uint32_t v[3];
                for (int k = 0; k < 3; ++k)
                    v[k] = ids.of(p.hierarchy.positions[cl.first_vertex +
                                                        p.hierarchy.indices[(size_t(cl.first_triangle) + t) * 3 + k]]);
                got.push_back(canonical(v[0], v[1], v[2]));
            }
        }
    EXPECT_EQ(ids.ids.size(), input_points) << "LOD0 has a position the input lacks";
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected);

    // The border between partitions is part of each partition's recorded border (an open boundary
    // of the partition, which the builder locks): an edge, by global id, in two partitions' triangles.
    std::vector<std::pair<uint64_t, size_t>> edge_owner;
    for (size_t i = 0; i < f.set.partitions.size(); ++i) {
        auto data = readPartitionFile(f.set.partitions[i].path);
        ASSERT_TRUE(data.ok());
        std::set<uint64_t> own;
        for (size_t t = 0; t < data->indices.size(); t += 3)
            for (int k = 0; k < 3; ++k) {
                const uint32_t a = data->global_ids[data->indices[t + k]];
                const uint32_t b = data->global_ids[data->indices[t + (k + 1) % 3]];
                own.insert(uint64_t(std::min(a, b)) << 32 | std::max(a, b));
            }
        for (uint64_t e : own) edge_owner.push_back({e, i});
    }
    std::sort(edge_owner.begin(), edge_owner.end());
    size_t shared = 0;
    for (size_t i = 0; i + 1 < edge_owner.size(); ++i) {
        if (edge_owner[i].first != edge_owner[i + 1].first) continue;
        for (size_t side : {edge_owner[i].second, edge_owner[i + 1].second}) {
            const PartitionLod& p = parts[side];
            const uint32_t a = uint32_t(edge_owner[i].first >> 32), b = uint32_t(edge_owner[i].first);
            const auto ia = std::lower_bound(p.border_ids.begin(), p.border_ids.end(), a);
            const auto ib = std::lower_bound(p.border_ids.begin(), p.border_ids.end(), b);
            ASSERT_TRUE(ia != p.border_ids.end() && *ia == a && ib != p.border_ids.end() && *ib == b);
            bool found = false;
            const uint32_t la = uint32_t(ia - p.border_ids.begin()), lb = uint32_t(ib - p.border_ids.begin());
            for (size_t e = 0; e < p.border_edges.size() && !found; e += 2)
                found = p.border_edges[e] == la && p.border_edges[e + 1] == lb;
            EXPECT_TRUE(found) << "shared edge " << a << "-" << b << " not on partition " << side << "'s border";
        }
        ++shared;
    }
    EXPECT_GT(shared, 100u);
    // And nothing else: the scan is closed and manifold, so each partition's border is exactly its
    // edges shared with other partitions.
    size_t border_edges = 0;
    for (const PartitionLod& p : parts) border_edges += p.border_edges.size() / 2;
    EXPECT_EQ(border_edges, 2 * shared);

    // Cuts of the partitions side by side: no boundary edge the input lacks, at any view.
    const lodbake::ClusterLodHierarchy u = unionOf(parts);
    ASSERT_EQ(lodrt::validateClusterLod(u.view()), lodrt::Result::Ok);
    lodbake_test::expectCrackFree(f.input, u, 300, 13);
}

TEST(PartitionBuildTest, SameBytesAtOneAndTwoThreads) {
    Fixture f = partitioned("threads", 20000);
    ASSERT_GE(f.set.partitions.size(), 2u);
    for (int threads : {1, 2}) {
        lodbake::ScopedThreadLimit limit{size_t(threads)};
        for (const PartitionFile& pf : f.set.partitions) {
            lodbake::Diagnostics d;
            auto built = buildPartition(pf.path, buildOptions(f.dir + "/t" + std::to_string(threads)), d);
            ASSERT_TRUE(built.ok()) << built.status().message();
        }
    }
    const std::vector<std::string> one = filesIn(f.dir + "/t1"), two = filesIn(f.dir + "/t2");
    EXPECT_EQ(one.size(), f.set.partitions.size());
    ASSERT_EQ(one, two);
    for (const std::string& name : one) {
        auto a = lodbake::readFileBytes(f.dir + "/t1/" + name), b = lodbake::readFileBytes(f.dir + "/t2/" + name);
        ASSERT_TRUE(a.ok() && b.ok());
        EXPECT_TRUE(*a == *b) << name;
    }
}

TEST(PartitionBuildTest, DamagedPartitionIsAnErrorNamingItWithNoOutput) {
    Fixture f = partitioned("damaged", 20000);
    ASSERT_FALSE(f.set.partitions.empty());
    const std::string source = f.set.partitions[0].path;
    auto bytes = lodbake::readFileBytes(source);
    ASSERT_TRUE(bytes.ok());
    const std::string out = f.dir + "/lods";
    auto expectError = [&](const std::string& path, const std::vector<uint8_t>& content, const std::string& what) {
        {
            std::ofstream file(path, std::ios::binary | std::ios::trunc);
            file.write(reinterpret_cast<const char*>(content.data()), std::streamsize(content.size()));
        }
        lodbake::Diagnostics d;
        auto built = buildPartition(path, buildOptions(out), d);
        ASSERT_FALSE(built.ok()) << what;
        EXPECT_EQ(built.status().code(), lodbake::StatusCode::InvalidInput) << what;
        EXPECT_EQ(built.status().message().rfind(path + ": ", 0), 0u) << what << ": " << built.status().message();
        EXPECT_TRUE(filesIn(out).empty()) << what;
    };
    // Truncated: the header's counts no longer match the size.
    std::vector<uint8_t> truncated(bytes->begin(), bytes->begin() + std::ptrdiff_t(bytes->size() / 2));
    expectError(source, truncated, "truncated");
    // One position changed: every structural check passes, the content no longer hashes to the name.
    std::vector<uint8_t> flipped = *bytes;
    flipped[40 + 4 * f.set.partitions[0].vertex_count + 5] ^= 0x10;
    expectError(source, flipped, "position changed");
    // One index out of range, under a name that is not a hash.
    std::vector<uint8_t> index = *bytes;
    std::fill(index.end() - 4, index.end(), uint8_t(0xff));
    expectError(f.dir + "/renamed.lbpart", index, "index out of range");
    // Missing.
    lodbake::Diagnostics d;
    auto missing = buildPartition(f.dir + "/none.lbpart", buildOptions(out), d);
    ASSERT_FALSE(missing.ok());
    EXPECT_NE(missing.status().message().find(f.dir + "/none.lbpart"), std::string::npos);
}

TEST(PartitionBuildTest, MemoryAccountingStaysUnderTheLimit) {
    Fixture f = partitioned("memory", 20000);
    ASSERT_FALSE(f.set.partitions.empty());
    const PartitionFile& pf = f.set.partitions[0];
    const uint64_t bound = 16 * uint64_t(pf.vertex_count) + 12 * uint64_t(pf.triangle_count) +
                           kClusterBuildBytesPerTriangle * pf.triangle_count + (uint64_t(1) << 20);
    PartitionBuildOptions o = buildOptions(f.dir + "/lods");
    o.memory_limit_bytes = bound;
    lodbake::Diagnostics d;
    auto built = buildPartition(pf.path, o, d);
    ASSERT_TRUE(built.ok()) << built.status().message();
    EXPECT_EQ(built->memory_bound_bytes, bound);
    EXPECT_LE(built->accounted_peak_bytes, built->memory_bound_bytes);
    EXPECT_LE(built->accounted_peak_bytes, o.memory_limit_bytes);
    // The output the builder holds is within its per-triangle share.
    auto back = readPartitionLodFile(built->path);
    ASSERT_TRUE(back.ok());
    const lodbake::ClusterLodHierarchy& h = back->hierarchy;
    const uint64_t held = h.clusters.size() * sizeof(h.clusters[0]) + h.groups.size() * sizeof(h.groups[0]) +
                          4 * (h.group_children.size() + h.roots.size()) + 12 * h.positions.size() + h.indices.size();
    EXPECT_LT(held, kClusterBuildBytesPerTriangle * pf.triangle_count / 2);
    // One byte less is a ResourceLimit error naming the file and the minimum, with no output.
    fs::remove_all(o.work_dir);
    o.memory_limit_bytes = bound - 1;
    auto refused = buildPartition(pf.path, o, d);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.status().code(), lodbake::StatusCode::ResourceLimit);
    EXPECT_EQ(refused.status().message().rfind(pf.path + ": memory limit", 0), 0u) << refused.status().message();
    EXPECT_TRUE(filesIn(o.work_dir).empty());
}

TEST(PartitionBuildTest, OnePartitionIsTheWholeBuild) {
    // The job adds nothing to buildClusterLod but the file: a partition holding the whole input gives
    // the hierarchy the in-memory build gives.
    Fixture f = partitioned("whole", 8000, uint64_t(64) << 20);
    ASSERT_EQ(f.set.partitions.size(), 1u);
    lodbake::Diagnostics d;
    auto built = buildPartition(f.set.partitions[0].path, buildOptions(f.dir + "/lods"), d);
    ASSERT_TRUE(built.ok()) << built.status().message();
    auto back = readPartitionLodFile(built->path);
    ASSERT_TRUE(back.ok()) << back.status().message();
    auto whole = lodbake::buildClusterLod(f.input, lodbake::ClusterLodOptions(), d);
    ASSERT_TRUE(whole.ok());
    const lodbake::ClusterLodHierarchy& a = back->hierarchy;
    ASSERT_EQ(a.clusters.size(), whole->clusters.size());
    ASSERT_EQ(a.groups.size(), whole->groups.size());
    EXPECT_EQ(0, std::memcmp(a.clusters.data(), whole->clusters.data(), a.clusters.size() * sizeof a.clusters[0]));
    EXPECT_EQ(0, std::memcmp(a.groups.data(), whole->groups.data(), a.groups.size() * sizeof a.groups[0]));
    EXPECT_EQ(a.group_children, whole->group_children);
    EXPECT_EQ(a.roots, whole->roots);
    EXPECT_EQ(a.positions, whole->positions);
    EXPECT_EQ(a.indices, whole->indices);
    EXPECT_EQ(a.lod0_cluster_count, whole->lod0_cluster_count);
    EXPECT_EQ(a.level_count, whole->level_count);
    // A closed scan: no border at all.
    EXPECT_EQ(built->border_edge_count, 0u);
}
