#pragma once
// The cluster hierarchy checks shared by the cluster LOD tests and the out-of-core partition tests:
// the runtime's limits and monotonic errors, and the crack-free bar over random views
// (cluster_cracks.h: the cut has no boundary edge, by position, that LOD0 lacks).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iterator>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/cluster/cluster_lod.h"
#include "lodbake/core/mesh.h"
#include "lodrt/cluster_lod.h"
#include "cluster_cracks.h"

namespace lodbake_test {

using lodbake::ClusterLodHierarchy;
using lodbake::Mesh;
using lodbake::Vec3f;

inline void expectLimitsAndMonotonic(const ClusterLodHierarchy& h) {
    ASSERT_EQ(lodrt::validateClusterLod(h.view()), lodrt::Result::Ok);
    for (const auto& c : h.clusters) {
        EXPECT_LE(c.triangle_count, 128u);
        EXPECT_LE(c.vertex_count, 255u);
        EXPECT_GT(c.triangle_count, 0u);
        for (uint32_t i = 0; i < c.triangle_count * 3; ++i)
            EXPECT_LT(h.indices[c.first_triangle * 3 + i], c.vertex_count);
    }
    for (size_t g = 0; g < h.groups.size(); ++g) {
        const auto& group = h.groups[g];
        EXPECT_LE(group.child_count, 32u);
        for (uint32_t i = 0; i < group.child_count; ++i) {
            const auto& child = h.clusters[h.group_children[group.first_child + i]];
            float err = 0, r = child.radius;
            const float* c = child.center;
            if (child.self_group != lodrt::kClusterNone) {
                const auto& below = h.groups[child.self_group];
                err = below.error;
                r = below.lod_radius;
                c = below.lod_center;
                EXPECT_LT(below.depth, group.depth);
                const double bd = std::sqrt(std::pow(double(below.bounds_center[0]) - group.bounds_center[0], 2) +
                                            std::pow(double(below.bounds_center[1]) - group.bounds_center[1], 2) +
                                            std::pow(double(below.bounds_center[2]) - group.bounds_center[2], 2));
                EXPECT_LE(bd + below.bounds_radius, double(group.bounds_radius)) << "group " << g;
            }
            EXPECT_GE(group.error, err) << "group " << g;
            const double d = std::sqrt(std::pow(double(c[0]) - group.lod_center[0], 2) +
                                       std::pow(double(c[1]) - group.lod_center[1], 2) +
                                       std::pow(double(c[2]) - group.lod_center[2], 2));
            EXPECT_LE(d + r, double(group.lod_radius)) << "group " << g;
        }
    }
}

struct CutRunner {
    const ClusterLodHierarchy& h;
    std::vector<uint32_t> scratch_words;
    lodrt::ClusterCutScratch scratch;
    std::vector<uint32_t> out;

    explicit CutRunner(const ClusterLodHierarchy& hierarchy) : h(hierarchy) {
        scratch_words.assign(lodrt::clusterCutScratchBytes(h.view()) / 4 + 1, 0);
        scratch.memory = scratch_words.data();
        scratch.size_bytes = scratch_words.size() * 4;
        out.resize(h.clusters.size());
    }
    lodrt::ClusterCutStats cut(const float eye[3], const lodrt::Frustum* frustum, float threshold) {
        lodrt::SelectionParams params;
        params.pixel_threshold = threshold;
        lodrt::ClusterCutStats stats;
        EXPECT_EQ(lodrt::selectClusterCut(h.view(), lodrt::ClusterInstance(), eye, frustum, params, scratch, out.data(),
                                          uint32_t(out.size()), &stats),
                  lodrt::Result::Ok);
        return stats;
    }
};

// Random views around the mesh: eye at 0.3 to 30 bounding radii from a random surface point, pixel
// thresholds from 0.25 to 16.
inline void expectCrackFree(const Mesh& lod0, const ClusterLodHierarchy& h, int views, uint32_t seed) {
    CrackChecker checker(lod0, h);
    EXPECT_EQ(checker.groupBorderMismatch(), "");
    CutRunner runner(h);
    lodbake::Aabb box;
    for (const Vec3f& p : lod0.positions) box.expand(p);
    const float radius = float(box.diagonal() * 0.5);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    size_t total = 0, finest = 0, coarsest = h.clusters.size();
    for (int v = 0; v < views; ++v) {
        const Vec3f& anchor = lod0.positions[rng() % lod0.positions.size()];
        const float z = 2 * unit(rng) - 1, phi = 6.2831853f * unit(rng), s = std::sqrt(1 - z * z);
        const float dist = radius * 0.3f * std::pow(100.0f, unit(rng));
        const float eye[3] = {anchor.x + dist * s * std::cos(phi), anchor.y + dist * s * std::sin(phi),
                              anchor.z + dist * z};
        const float threshold = 0.25f * std::pow(64.0f, unit(rng));
        const lodrt::ClusterCutStats st = runner.cut(eye, nullptr, threshold);
        ASSERT_EQ(st.written, st.selected);
        std::string first;
        ASSERT_EQ(checker.cracks(runner.out.data(), st.written, &first), 0u)
            << "view " << v << " eye distance " << dist << ": " << first;
        total += st.selected;
        finest = std::max<size_t>(finest, st.selected);
        coarsest = std::min<size_t>(coarsest, st.selected);
    }
    // The views reach different depths: a cut that never changes would pass trivially.
    EXPECT_LT(coarsest, finest);
    ::testing::Test::RecordProperty("mean_cut_clusters", std::to_string(total / size_t(views)));
}

} // namespace lodbake_test
