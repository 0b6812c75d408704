// PfrepChainTest: the PFRep blob read from a discrete chain's own simplification pass
// (LodChainOptions::record_removals, buildPfrepFromChain): the point numbering the builder rebuilds
// is the simplifier's, the blob level at each chain level's collapse count has exactly the chain's
// faces (checked against an independent replay of the chain's collapses, whichever end each rule
// keeps), and the pack extension lists those levels.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <numeric>
#include <set>

#include "lodbake/io/mesh_io.h"
#include "lodbake/pfrep/pfrep_builder.h"
#include "lodbake/pfrep/pfrep_extension.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodrt/pfrep.h"
#include "../simplify/simplify_test_meshes.h"
#include "mesh_builders.h"
#include "test_paths.h"

namespace {

using Tri = std::array<uint32_t, 3>;

Tri canonical(uint32_t a, uint32_t b, uint32_t c) {
    // Rotation keeps orientation: start at the smallest.
    if (b < a && b < c) return {b, c, a};
    if (c < a && c < b) return {c, a, b};
    return {a, b, c};
}

bool sameBits(const lodbake::Vec3f& a, const lodbake::Vec3f& b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// The chain's points merged by its collapses so far: find() names each point by the point its cluster
// has merged into (a union by the collapses' removed -> kept pairs, with path halving).
struct MergedPoints {
    explicit MergedPoints(size_t count) : parent(count) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t x) {
        while (parent[x] != x) x = parent[x] = parent[parent[x]];
        return x;
    }
    void merge(uint32_t removed, uint32_t kept) { parent[removed] = kept; }
    size_t size() const { return parent.size(); }
    std::vector<uint32_t> parent;
};

// The log's flag against a replay of the full records: kept_stays says the merged position is the
// kept point's position before the collapse.
// Returns how many collapses kept their point in place.
size_t checkFlags(const lodbake::LodChain& chain) {
    std::vector<lodbake::Vec3f> at = chain.sequence.point_positions;
    lodbake::CollapsePairLog::Reader reader(chain.removals);
    size_t stays_count = 0;
    for (const lodbake::CollapseRecord& r : chain.sequence.records) {
        uint32_t u = 0, v = 0;
        bool stays = false;
        EXPECT_TRUE(reader.next(u, v, stays));
        EXPECT_EQ(stays, sameBits(at[v], r.position));
        stays_count += stays;
        at[v] = r.position;
    }
    return stays_count;
}

class PfrepChainTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        if (!lodbake_test::haveSharedMeshes()) return;
        lodbake::Diagnostics d;
        auto loaded = lodbake::readMesh(lodbake_test::sharedMesh("rocker_arm.obj"), {}, d);
        ASSERT_TRUE(loaded.ok());
        mesh_ = new lodbake::Mesh(std::move(loaded->mesh));
        lodbake::LodChainOptions options;
        options.ratios = {0.5, 0.1, 0.02};
        options.measure_error = false;
        options.record_removals = true; // with record_collapses (default): the full records too
        auto chain = lodbake::buildLodChain(*mesh_, options, d);
        ASSERT_TRUE(chain.ok()) << chain.status().message();
        chain_ = new lodbake::LodChain(std::move(*chain));
    }
    static void TearDownTestSuite() {
        delete mesh_;
        delete chain_;
        mesh_ = nullptr;
        chain_ = nullptr;
    }
    static lodbake::Mesh* mesh_;
    static lodbake::LodChain* chain_;
};
lodbake::Mesh* PfrepChainTest::mesh_ = nullptr;
lodbake::LodChain* PfrepChainTest::chain_ = nullptr;

TEST(CollapsePairLogTest, RoundTripsPairsInBothDirectionsAndRefusesACutStream) {
    lodbake::CollapsePairLog log;
    const std::vector<std::pair<uint32_t, uint32_t>> pairs = {
        {0, 1}, {1, 0}, {5, 5000000}, {5000000, 5}, {0x7fffffffu, 0}, {0, 0x7fffffffu}, {127, 128}, {128, 127}};
    for (const auto& [u, v] : pairs) log.add(u, v);
    EXPECT_EQ(log.size(), pairs.size());
    lodbake::CollapsePairLog::Reader reader(log);
    for (const auto& [u, v] : pairs) {
        uint32_t a = 0, b = 0;
        ASSERT_TRUE(reader.next(a, b));
        EXPECT_EQ(a, u);
        EXPECT_EQ(b, v);
    }
    uint32_t a = 0, b = 0;
    EXPECT_FALSE(reader.next(a, b));
    // The flag travels with its entry.
    lodbake::CollapsePairLog flagged;
    for (uint32_t i = 0; i < 8; ++i) flagged.add(1000 + i, 999 - i * 100, i & 1);
    lodbake::CollapsePairLog::Reader flags(flagged);
    for (uint32_t i = 0; i < 8; ++i) {
        bool stays = false;
        ASSERT_TRUE(flags.next(a, b, stays));
        EXPECT_EQ(a, 1000 + i);
        EXPECT_EQ(b, 999 - i * 100);
        EXPECT_EQ(stays, bool(i & 1));
    }
}

TEST(PfrepChainPointsTest, NumbersPointsLikeTheSimplifier) {
    // Duplicated positions (welded), a face degenerate by position (dropped) and vertices listed far
    // from the order of the faces that use them.
    lodbake::Mesh mesh = lodbake_test::makeMesh(
        {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {1, 0, 0}, {2, 0, 0}, {2, 1, 0}, {0, 0, 0}, {3, 3, 3}},
        {2, 3, 7, 4, 5, 6, 4, 6, 2, 0, 1, 4, 1, 2, 4, 8, 8, 8});
    lodbake::Diagnostics d;
    lodbake::LodChainOptions options;
    options.ratios = {1.0};
    options.measure_error = false;
    auto chain = lodbake::buildLodChain(mesh, options, d);
    ASSERT_TRUE(chain.ok());
    std::vector<lodbake::Vec3f> positions;
    std::vector<uint32_t> triangles;
    ASSERT_TRUE(lodbake::chainPoints(mesh, positions, triangles).ok());
    const auto& expected = chain->sequence.point_positions;
    ASSERT_GE(expected.size(), positions.size());
    for (size_t p = 0; p < positions.size(); ++p) EXPECT_TRUE(sameBits(positions[p], expected[p])) << p;
    // Faces: the three degenerate by position go; points by first use.
    EXPECT_EQ(triangles.size(), 3u * 3u);
    EXPECT_EQ(positions.size(), 6u);
    EXPECT_EQ(triangles[0], 0u);
    EXPECT_EQ(triangles[1], 1u);
    EXPECT_EQ(triangles[2], 2u);
}

TEST_F(PfrepChainTest, PointNumberingMatchesTheSimplifiersOnAScan) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    std::vector<lodbake::Vec3f> positions;
    std::vector<uint32_t> triangles;
    ASSERT_TRUE(lodbake::chainPoints(*mesh_, positions, triangles).ok());
    const auto& expected = chain_->sequence.point_positions;
    ASSERT_LE(positions.size(), expected.size());
    for (size_t p = 0; p < positions.size(); ++p) ASSERT_TRUE(sameBits(positions[p], expected[p])) << p;
}

TEST_F(PfrepChainTest, LogHoldsEveryCollapseAndRunsToTheEnd) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    ASSERT_TRUE(chain_->removals_complete);
    // The full records cover the same pass (tail included), pair for pair.
    ASSERT_EQ(chain_->removals.size(), chain_->sequence.records.size());
    EXPECT_GT(chain_->removals.size(), chain_->levels.back().collapse_count);
    lodbake::CollapsePairLog::Reader reader(chain_->removals);
    for (const lodbake::CollapseRecord& r : chain_->sequence.records) {
        uint32_t u = 0, v = 0;
        ASSERT_TRUE(reader.next(u, v));
        ASSERT_EQ(u, r.removed_point);
        ASSERT_EQ(v, r.kept_point);
    }
    // About 5 bytes per collapse, not 8.
    EXPECT_LT(chain_->removals.byteSize(), chain_->removals.size() * 6);
}

TEST_F(PfrepChainTest, BlobLevelsAreTheChainsFaces) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    std::vector<lodbake::Vec3f> positions;
    std::vector<uint32_t> triangles;
    ASSERT_TRUE(lodbake::chainPoints(*mesh_, positions, triangles).ok());
    {
        lodbake::Diagnostics d;
        auto build = lodbake::buildPfrepFromChain(*mesh_, chain_->removals, d);
        ASSERT_TRUE(build.ok()) << build.status().message();
        lodrt::PfrepModel m;
        ASSERT_EQ(lodrt::openPfrep(build->blob.data(), build->blob.size(), &m), lodrt::Result::Ok);
        EXPECT_EQ(m.removed_count, chain_->removals.size());
        // Independent replay in the engine's names: the chain's faces after k collapses, each point
        // named by the engine point its cluster has merged into (union by the records).
        MergedPoints points(positions.size());
        auto find = [&](uint32_t x) { return points.find(x); };
        const auto& records = chain_->sequence.records;
        std::vector<uint32_t> idx(lodrt::pfrepMaxTriangles(m) * 3);
        size_t applied = 0;
        for (const lodbake::LodLevel& level : chain_->levels) {
            for (; applied < level.collapse_count; ++applied)
                points.merge(records[applied].removed_point, records[applied].kept_point);
            std::multiset<Tri> expected;
            for (size_t t = 0; t < triangles.size(); t += 3) {
                const uint32_t a = find(triangles[t]), b = find(triangles[t + 1]), c = find(triangles[t + 2]);
                if (a != b && b != c && a != c) expected.insert(canonical(a, b, c));
            }
            size_t count = 0;
            ASSERT_EQ(lodrt::pfrepExtractLevel(m, uint32_t(level.collapse_count), idx.data(), idx.size() / 3, &count),
                      lodrt::Result::Ok);
            EXPECT_EQ(count, level.mesh.faceCount());
            std::multiset<Tri> got;
            for (size_t t = 0; t < count; ++t)
                got.insert(canonical(find(build->rank_point[idx[t * 3]]), find(build->rank_point[idx[t * 3 + 1]]),
                                     find(build->rank_point[idx[t * 3 + 2]])));
            EXPECT_TRUE(got == expected) << "level of " << level.mesh.faceCount();
        }
    }
}

TEST_F(PfrepChainTest, ExtensionListsTheChainLevelsExactly) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    lodbake::Diagnostics d;
    auto object = lodbake::buildPfrepExtension(*mesh_, *chain_, {}, d);
    ASSERT_TRUE(object.ok()) << object.status().message();
    ASSERT_EQ(object->levels.size(), chain_->levels.size() + 1);
    EXPECT_EQ(object->levels[0].removals, 0u);
    for (size_t l = 0; l < chain_->levels.size(); ++l) {
        EXPECT_EQ(object->levels[l + 1].removals, chain_->levels[l].collapse_count);
        EXPECT_EQ(object->levels[l + 1].triangles, chain_->levels[l].mesh.faceCount());
    }
}

TEST_F(PfrepChainTest, FlagsAgreeWithTheRecordedPositions) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    checkFlags(*chain_);
    // An open grid: its corners never move, nor do border points whose edge leaves the border.
    lodbake::Diagnostics d;
    lodbake::LodChainOptions options;
    options.ratios = {0.5, 0.1};
    options.measure_error = false;
    options.record_removals = true;
    auto grid = lodbake::buildLodChain(lodbake_test::flatGrid(16), options, d);
    ASSERT_TRUE(grid.ok());
    ASSERT_EQ(grid->removals.size(), grid->sequence.records.size());
    const size_t stays = checkFlags(*grid);
    EXPECT_GT(stays, 0u);
    EXPECT_LT(stays, grid->sequence.records.size());
}

TEST(PfrepChainFallbackTest, CoveredComponentRemovalLeavesNoLogAndTheExtensionSimplifiesItself) {
    // With component removal on, the chain records no vertex removals (a component removal is none).
    lodbake::Mesh mesh = lodbake_test::icosphere(2);
    lodbake::Diagnostics d;
    lodbake::LodChainOptions options;
    options.ratios = {0.5, 0.25};
    options.measure_error = false;
    options.record_removals = true;
    options.simplify.remove_covered_components = true;
    auto chain = lodbake::buildLodChain(mesh, options, d);
    ASSERT_TRUE(chain.ok());
    EXPECT_FALSE(chain->removals_complete);
    EXPECT_TRUE(chain->removals.empty());
    auto object = lodbake::buildPfrepExtension(mesh, *chain, {}, d);
    ASSERT_TRUE(object.ok()) << object.status().message();
    ASSERT_EQ(object->levels.size(), 3u);
    // The half-edge path picks levels by budget: at most half, at most a quarter of the triangles.
    EXPECT_LE(double(object->levels[1].triangles), 0.5 * double(mesh.faceCount()));
    EXPECT_LE(double(object->levels[2].triangles), 0.25 * double(mesh.faceCount()));
}

// Above EdgeCollapser::kRoundMinFaces the chain collapses in partitioned rounds (two parts side by
// side). With a removal log it still does: each part logs its own collapses and the logs are appended
// in part order at the merge, which is a valid order because the parts never touch the same data. So
// the levels are the ones the chain makes without the log, and the log, replayed as vertex removals,
// gives exactly each level's faces.
TEST(PfrepChainRoundsTest, LogOfAPartitionedChainReplaysItsLevels) {
    const lodbake::Mesh mesh = lodbake_test::bumpyIcosphere(7); // 327,680 faces
    ASSERT_GE(mesh.faceCount(), size_t(200000));
    lodbake::LodChainOptions options;
    options.ratios = {0.5, 0.25, 0.05};
    options.measure_error = false;
    options.record_collapses = false; // a recorded sequence would keep the serial order
    lodbake::Diagnostics d;
    auto plain = lodbake::buildLodChain(mesh, options, d);
    ASSERT_TRUE(plain.ok()) << plain.status().message();
    options.record_removals = true;
    auto logged = lodbake::buildLodChain(mesh, options, d);
    ASSERT_TRUE(logged.ok()) << logged.status().message();
    ASSERT_TRUE(logged->removals_complete);
    ASSERT_EQ(plain->levels.size(), logged->levels.size());
    for (size_t l = 0; l < plain->levels.size(); ++l) {
        EXPECT_EQ(plain->levels[l].collapse_count, logged->levels[l].collapse_count) << "level " << l;
        EXPECT_EQ(plain->levels[l].mesh.indices, logged->levels[l].mesh.indices) << "level " << l;
    }
    EXPECT_GT(logged->removals.size(), logged->levels.back().collapse_count);

    // Replay: the engine's faces keep their input order and corner order, a collapse renames the removed
    // point in place and drops the faces that then repeat a point; the level's vertices are the points
    // in order of first use by those faces (no attributes: one wedge per point).
    std::vector<lodbake::Vec3f> positions;
    std::vector<uint32_t> triangles;
    ASSERT_TRUE(lodbake::chainPoints(mesh, positions, triangles).ok());
    MergedPoints points(positions.size());
    auto find = [&](uint32_t x) { return points.find(x); };
    lodbake::CollapsePairLog::Reader reader(logged->removals);
    size_t applied = 0;
    for (const lodbake::LodLevel& level : logged->levels) {
        for (; applied < level.collapse_count; ++applied) {
            uint32_t u = 0, v = 0;
            ASSERT_TRUE(reader.next(u, v));
            ASSERT_LT(u, points.size());
            ASSERT_LT(v, points.size());
            ASSERT_EQ(find(u), u) << "collapse " << applied << " removes a point that is gone";
            ASSERT_EQ(find(v), v) << "collapse " << applied << " keeps a point that is gone";
            points.merge(u, v);
        }
        std::vector<uint32_t> vertex_of(positions.size(), UINT32_MAX), expected;
        uint32_t next = 0;
        for (size_t t = 0; t < triangles.size(); t += 3) {
            const uint32_t a = find(triangles[t]), b = find(triangles[t + 1]), c = find(triangles[t + 2]);
            if (a == b || b == c || a == c) continue;
            for (uint32_t p : {a, b, c}) {
                if (vertex_of[p] == UINT32_MAX) vertex_of[p] = next++;
                expected.push_back(vertex_of[p]);
            }
        }
        EXPECT_EQ(level.mesh.indices, expected) << "level of " << level.mesh.faceCount() << " faces";
    }
    // The blob read from the log has each chain level at its collapse count (the extension checks it).
    auto object = lodbake::buildPfrepExtension(mesh, *logged, {}, d);
    ASSERT_TRUE(object.ok()) << object.status().message();
    ASSERT_EQ(object->levels.size(), logged->levels.size() + 1);
}

} // namespace
