// SimplifyOptions::remove_covered_components: a component lying within the accepted error of the
// rest of the surface may go (recorded in the collapse sequence); anything else stays.
#include <algorithm>
#include <cmath>
#include <array>
#include <map>
#include <set>

#include <gtest/gtest.h>

#include "lodbake/cleanup/topology.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/simplify/lod_chain.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodbake/simplify/simplify.h"
#include "simplify_test_meshes.h"

namespace {

using lodbake::Diagnostics;
using lodbake::LodChain;
using lodbake::LodChainOptions;
using lodbake::Mesh;
using lodbake::Vec3f;

// Appends `part` to `mesh` with its positions scaled by `scale` and moved by `offset`.
void append(Mesh& mesh, const Mesh& part, float scale, Vec3f offset) {
    const uint32_t base = uint32_t(mesh.positions.size());
    for (const Vec3f& p : part.positions) mesh.positions.push_back(p * scale + offset);
    for (uint32_t i : part.indices) mesh.indices.push_back(base + i);
}

// A 64×64 grid over [0,1]², flat for x < 0.5 and wavy beyond (so collapses there accept a growing
// error); a 10×10 flat patch over [0.1, 0.3]² lying 0.0001 above it (a second scan of the same
// surface: covered once the accepted error passes 0.0001); a small sphere far away (not covered).
Mesh scanLike() {
    Mesh mesh;
    append(mesh, lodbake_test::grid(64, [](float x, float y) {
               return x < 0.5f ? 0.0f : 0.05f * std::sin(20.0f * (x - 0.5f)) * std::cos(12.0f * y);
           }), 1.0f, Vec3f(0, 0, 0));
    append(mesh, lodbake_test::grid(10, [](float, float) { return 0.0f; }), 0.2f, Vec3f(0.1f, 0.1f, 0.0001f));
    append(mesh, lodbake_test::icosphere(1), 0.1f, Vec3f(5, 0, 0));
    return mesh;
}

LodChain chainOf(const Mesh& mesh, bool remove, lodbake::CollapsePlacement placement = lodbake::CollapsePlacement::Optimal) {
    LodChainOptions options;
    options.ratios = {0.5, 0.1, 0.03};
    options.distance.sample_count = 20000;
    options.simplify.remove_covered_components = remove;
    options.simplify.placement = placement;
    options.simplify.refine_late_levels = false; // the sequence's replay gives the levels' positions exactly
    Diagnostics diagnostics;
    auto chain = lodbake::buildLodChain(mesh, options, diagnostics);
    EXPECT_TRUE(chain.ok()) << chain.status().message();
    return chain.ok() ? std::move(chain).value() : LodChain();
}

bool hasVertexBeyondX(const Mesh& mesh, float x) {
    return std::any_of(mesh.positions.begin(), mesh.positions.end(), [&](const Vec3f& p) { return p.x > x; });
}

class CoveredComponentsTest : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        mesh_ = new Mesh(scanLike());
        kept_ = new LodChain(chainOf(*mesh_, false));
        removed_ = new LodChain(chainOf(*mesh_, true));
    }
    static void TearDownTestSuite() {
        delete mesh_;
        delete kept_;
        delete removed_;
    }
    static Mesh* mesh_;
    static LodChain* kept_;
    static LodChain* removed_;
};
Mesh* CoveredComponentsTest::mesh_ = nullptr;
LodChain* CoveredComponentsTest::kept_ = nullptr;
LodChain* CoveredComponentsTest::removed_ = nullptr;

TEST_F(CoveredComponentsTest, OffByDefaultKeepsEveryComponent) {
    EXPECT_FALSE(lodbake::SimplifyOptions().remove_covered_components);
    ASSERT_EQ(lodbake::computeTopologyStats(*mesh_).component_count, 3u);
    for (const lodbake::LodLevel& level : kept_->levels) {
        EXPECT_EQ(lodbake::computeTopologyStats(level.mesh).component_count, 3u) << level.target_ratio;
        EXPECT_EQ(level.removal_count, 0u);
    }
    EXPECT_TRUE(kept_->sequence.removals.empty());
}

TEST_F(CoveredComponentsTest, RemovesTheCoveredPatchOnlyAndSpendsItsFacesElsewhere) {
    const lodbake::LodLevel& last = removed_->levels.back();
    EXPECT_EQ(lodbake::computeTopologyStats(last.mesh).component_count, 2u);
    EXPECT_TRUE(hasVertexBeyondX(last.mesh, 4.0f)) << "the far sphere is not covered and must stay";
    EXPECT_EQ(lodbake::computeTopologyStats(kept_->levels.back().mesh).component_count, 3u);
    ASSERT_EQ(removed_->sequence.removals.size(), 1u);
    EXPECT_EQ(last.removal_count, 1u);
    // Same triangle budget: the faces the patch had now go to the rest.
    EXPECT_EQ(last.mesh.faceCount(), kept_->levels.back().mesh.faceCount());
    // The level's Hausdorff error grows by less than the level's own error, and the mean does not grow.
    ASSERT_TRUE(last.has_distance && kept_->levels.back().has_distance);
    const lodbake::DistanceResult& with = last.distance;
    const lodbake::DistanceResult& without = kept_->levels.back().distance;
    EXPECT_LE(with.hausdorff, 2.0 * without.hausdorff);
    EXPECT_LE(with.mean, without.mean * 1.05);
}

TEST_F(CoveredComponentsTest, IsDeterministic) {
    const LodChain again = chainOf(*mesh_, true);
    ASSERT_EQ(again.levels.size(), removed_->levels.size());
    for (size_t i = 0; i < again.levels.size(); ++i) {
        EXPECT_EQ(again.levels[i].mesh.indices, removed_->levels[i].mesh.indices);
        EXPECT_TRUE(again.levels[i].mesh.positions == removed_->levels[i].mesh.positions);
    }
    EXPECT_EQ(again.sequence.removed_points, removed_->sequence.removed_points);
}

TEST_F(CoveredComponentsTest, SequenceWithRemovalsReplaysToEveryLevel) {
    // Points are matched by position (every input position is distinct here).
    const lodbake::CollapseSequence& s = removed_->sequence;
    std::map<std::array<float, 3>, uint32_t> point_at;
    for (uint32_t p = 0; p < s.point_positions.size(); ++p)
        point_at[{s.point_positions[p].x, s.point_positions[p].y, s.point_positions[p].z}] = p;
    ASSERT_EQ(point_at.size(), mesh_->vertexCount());
    std::vector<uint32_t> point_of(mesh_->vertexCount());
    for (uint32_t v = 0; v < mesh_->vertexCount(); ++v)
        point_of[v] = point_at.at({mesh_->positions[v].x, mesh_->positions[v].y, mesh_->positions[v].z});
    std::vector<uint32_t> parent(s.point_positions.size());
    for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    std::vector<uint8_t> gone(s.point_positions.size(), 0);
    std::vector<Vec3f> pos = s.point_positions;
    auto find = [&](uint32_t v) {
        while (parent[v] != v) v = parent[v];
        return v;
    };
    size_t applied = 0, removals = 0;
    auto applyRemovals = [&](size_t upto_record, size_t upto_removal) {
        for (; removals < upto_removal && s.removals[removals].record_index <= upto_record; ++removals) {
            const lodbake::ComponentRemoval& r = s.removals[removals];
            for (uint32_t k = 0; k < r.point_count; ++k) {
                const uint32_t p = s.removed_points[r.first_point + k];
                ASSERT_EQ(find(p), p);
                ASSERT_FALSE(gone[p]);
                gone[p] = 1;
            }
        }
    };
    for (const lodbake::LodLevel& level : removed_->levels) {
        for (; applied < level.collapse_count; ++applied) {
            applyRemovals(applied, level.removal_count);
            const lodbake::CollapseRecord& r = s.records[applied];
            ASSERT_FALSE(gone[r.removed_point] || gone[r.kept_point]);
            parent[r.removed_point] = r.kept_point;
            pos[r.kept_point] = r.position;
        }
        applyRemovals(applied, level.removal_count);
        ASSERT_EQ(removals, level.removal_count);
        std::multiset<std::array<float, 9>> replayed, actual;
        for (size_t f = 0; f < mesh_->faceCount(); ++f) {
            const uint32_t a = find(point_of[mesh_->indices[f * 3]]), b = find(point_of[mesh_->indices[f * 3 + 1]]),
                           c = find(point_of[mesh_->indices[f * 3 + 2]]);
            if (a == b || b == c || a == c || gone[a] || gone[b] || gone[c]) continue;
            replayed.insert({pos[a].x, pos[a].y, pos[a].z, pos[b].x, pos[b].y, pos[b].z, pos[c].x, pos[c].y, pos[c].z});
        }
        const Mesh& m = level.mesh;
        for (size_t f = 0; f < m.faceCount(); ++f) {
            const Vec3f a = m.positions[m.indices[f * 3]], b = m.positions[m.indices[f * 3 + 1]],
                        c = m.positions[m.indices[f * 3 + 2]];
            actual.insert({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
        }
        EXPECT_TRUE(replayed == actual) << "level " << level.target_ratio;
    }
}

TEST_F(CoveredComponentsTest, HalfEdgeCollapseChainsNeverRemoveComponents) {
    // PFRep is built from KeepEndpoint chains, whose records must all be vertex removals.
    const LodChain chain = chainOf(*mesh_, true, lodbake::CollapsePlacement::KeepEndpoint);
    EXPECT_TRUE(chain.sequence.removals.empty());
    EXPECT_EQ(lodbake::computeTopologyStats(chain.levels.back().mesh).component_count, 3u);
}

TEST_F(CoveredComponentsTest, SimplifyTakesTheOptionToo) {
    lodbake::SimplifyOptions options;
    options.target_ratio = 0.03f;
    options.remove_covered_components = true;
    options.refine_late_levels = false;
    Diagnostics diagnostics;
    auto out = lodbake::simplify(*mesh_, options, diagnostics);
    ASSERT_TRUE(out.ok());
    EXPECT_EQ(out->mesh.indices, removed_->levels.back().mesh.indices);
    bool noted = false;
    for (const auto& m : diagnostics.items()) noted = noted || m.message.find("covered components") != std::string::npos;
    EXPECT_TRUE(noted);
}

TEST(CoveredComponentsPresetTest, PresetKeyIsReadValidatedAndPrinted) {
    lodbake::BakeSettings settings;
    EXPECT_FALSE(settings.remove_covered_components);
    ASSERT_TRUE(lodbake::applyPresetJson(R"({"version": 1, "remove_covered_components": true})", "p.json", settings).ok());
    EXPECT_TRUE(settings.remove_covered_components);
    EXPECT_NE(lodbake::settingsToJson(settings).find("\"remove_covered_components\": true"), std::string::npos);
    const lodbake::Status bad = lodbake::applyPresetJson(R"({"version": 1, "remove_covered_components": 1})", "p.json", settings);
    EXPECT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("/remove_covered_components"), std::string::npos) << bad.message();
}

} // namespace
