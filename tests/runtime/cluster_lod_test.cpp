// lodrt/cluster_lod.h on a hand-made hierarchy: the cut at each distance, the caller's buffers, and
// the visit stamps across an epoch wrap. The builder's hierarchies are tested in
// tests/baker/cluster/cluster_lod_test.cpp (limits, monotonicity, crack-free cuts).

#include "lodrt/cluster_lod.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

namespace {

// Four LOD0 clusters -> group 0 (error 1) -> clusters 4, 5 -> group 1 (error 4) -> root 6.
struct TinyHierarchy {
    std::vector<lodrt::ClusterLodCluster> clusters{7};
    std::vector<lodrt::ClusterLodGroup> groups{2};
    std::vector<uint32_t> children{0, 1, 2, 3, 4, 5};
    std::vector<uint32_t> roots{6};

    TinyHierarchy() {
        for (uint32_t c = 0; c < 7; ++c) {
            clusters[c].radius = 0.5f;
            clusters[c].center[0] = c < 4 ? float(c) * 0.25f - 0.4f : 0.0f;
            clusters[c].parent_group = c < 4 ? 0 : (c < 6 ? 1 : lodrt::kClusterNone);
            clusters[c].self_group = c < 4 ? lodrt::kClusterNone : (c < 6 ? 0 : 1);
        }
        groups[0] = {{0, 0, 0}, 1.0f, 1.0f, {0, 0, 0}, 1.0f, 0, 4, 1};
        groups[1] = {{0, 0, 0}, 1.5f, 4.0f, {0, 0, 0}, 1.5f, 4, 2, 2};
    }
    lodrt::ClusterLodView view() const {
        lodrt::ClusterLodView v;
        v.clusters = clusters.data();
        v.cluster_count = uint32_t(clusters.size());
        v.groups = groups.data();
        v.group_count = uint32_t(groups.size());
        v.group_children = children.data();
        v.group_child_count = uint32_t(children.size());
        v.roots = roots.data();
        v.root_count = uint32_t(roots.size());
        return v;
    }
};

struct Cut {
    std::vector<uint32_t> clusters;
    lodrt::ClusterCutStats stats;
};

Cut cutAt(const TinyHierarchy& h, float distance, lodrt::ClusterCutScratch& scratch, uint32_t capacity = 16) {
    Cut cut;
    cut.clusters.resize(capacity);
    const float eye[3] = {distance, 0, 0};
    EXPECT_EQ(lodrt::selectClusterCut(h.view(), lodrt::ClusterInstance(), eye, nullptr, lodrt::SelectionParams(),
                                      scratch, cut.clusters.data(), capacity, &cut.stats),
              lodrt::Result::Ok);
    cut.clusters.resize(cut.stats.written);
    std::sort(cut.clusters.begin(), cut.clusters.end());
    return cut;
}

TEST(ClusterCutTest, SelectsTheLevelWhoseErrorFitsTheThreshold) {
    const TinyHierarchy h;
    ASSERT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::Ok);
    std::vector<uint32_t> memory(lodrt::clusterCutScratchBytes(h.view()) / 4, 0);
    lodrt::ClusterCutScratch scratch{memory.data(), memory.size() * 4, 0};
    // K = 1080 / (2 tan 30 deg) = 935.3 px per unit at distance 1: group 0 (error 1) fits from
    // about 936 units, group 1 (error 4) from about 3743.
    EXPECT_EQ(cutAt(h, 100, scratch).clusters, (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(cutAt(h, 2000, scratch).clusters, (std::vector<uint32_t>{4, 5}));
    EXPECT_EQ(cutAt(h, 10000, scratch).clusters, (std::vector<uint32_t>{6}));
    const Cut inside = cutAt(h, 0.1f, scratch);
    EXPECT_EQ(inside.clusters, (std::vector<uint32_t>{0, 1, 2, 3}));
    EXPECT_EQ(inside.stats.groups_visited, 2u);
}

TEST(ClusterCutTest, CountsBeyondTheCapacityAndRejectsSmallScratch) {
    const TinyHierarchy h;
    std::vector<uint32_t> memory(lodrt::clusterCutScratchBytes(h.view()) / 4, 0);
    lodrt::ClusterCutScratch scratch{memory.data(), memory.size() * 4, 0};
    const Cut cut = cutAt(h, 100, scratch, 2);
    EXPECT_EQ(cut.stats.written, 2u);
    EXPECT_EQ(cut.stats.selected, 4u);
    lodrt::ClusterCutScratch small{memory.data(), memory.size() * 4 - 4, 0};
    const float eye[3] = {0, 0, 0};
    uint32_t out[8];
    EXPECT_EQ(lodrt::selectClusterCut(h.view(), lodrt::ClusterInstance(), eye, nullptr, lodrt::SelectionParams(), small,
                                      out, 8, nullptr),
              lodrt::Result::InvalidArgument);
    lodrt::ClusterInstance flat;
    flat.scale = 0;
    EXPECT_EQ(lodrt::selectClusterCut(h.view(), flat, eye, nullptr, lodrt::SelectionParams(), scratch, out, 8, nullptr),
              lodrt::Result::InvalidArgument);
}

TEST(ClusterCutTest, StampsSurviveTheEpochWrap) {
    const TinyHierarchy h;
    std::vector<uint32_t> memory(lodrt::clusterCutScratchBytes(h.view()) / 4, 0);
    lodrt::ClusterCutScratch scratch{memory.data(), memory.size() * 4, 0xfffffffeu};
    // The stamps hold 0xffffffff after this cut; the next epoch wraps to 0 and clears them.
    EXPECT_EQ(cutAt(h, 100, scratch).clusters.size(), 4u);
    EXPECT_EQ(scratch.epoch, 0xffffffffu);
    EXPECT_EQ(cutAt(h, 100, scratch).clusters.size(), 4u);
    EXPECT_EQ(scratch.epoch, 1u);
    EXPECT_EQ(cutAt(h, 100, scratch).clusters.size(), 4u);
}

TEST(ClusterCutTest, ValidateRejectsHostileFields) {
    TinyHierarchy h;
    h.clusters[2].radius = -1;
    EXPECT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::BadStructure);
    h = TinyHierarchy();
    h.groups[1].first_child = 5;
    EXPECT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::OutOfBounds);
    h = TinyHierarchy();
    h.roots[0] = 3;
    EXPECT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::BadStructure);
    h = TinyHierarchy();
    h.clusters[0].triangle_count = 1; // the view holds no triangles
    EXPECT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::OutOfBounds);
}

} // namespace
