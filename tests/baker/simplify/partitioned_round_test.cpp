// detail::EdgeCollapser's partitioned rounds (docs/simplify.md, "Partitioned rounds"): two parts of the
// mesh collapsed side by side, then merged. The result may not depend on the thread count, and must be
// a valid mesh with the face count asked for.
#include "simplify/edge_collapse.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/parallel.h"
#include "simplify/collapse_queue.h"
#include "simplify_test_meshes.h"

namespace {

using lodbake::Diagnostics;
using lodbake::Mesh;
using lodbake::detail::CollapseQueue;
using lodbake::detail::EdgeCollapser;
using lodbake::detail::PartHeap;

Mesh bumpySphere() {
    return lodbake_test::bumpyIcosphere(6); // 81920 faces
}

Mesh bumpyGrid() {
    return lodbake_test::grid(200, [](float x, float y) { return 0.1f * std::sin(9.0f * x) * std::cos(7.0f * y); });
}

struct Levels {
    std::vector<Mesh> meshes;
    size_t rounds = 0;
    std::vector<size_t> targets;
};

Levels collapse(const Mesh& mesh, size_t round_min_faces, size_t threads) {
    lodbake::ScopedThreadLimit limit(threads);
    Diagnostics d;
    EdgeCollapser engine;
    EXPECT_TRUE(engine.init(mesh, lodbake::SimplifyOptions(), d).ok());
    engine.setRoundMinFaces(round_min_faces);
    Levels out;
    for (double ratio : {0.5, 0.25, 0.1}) {
        const size_t target = size_t(std::ceil(ratio * double(engine.initialFaceCount())));
        EXPECT_TRUE(engine.run(target, HUGE_VAL, nullptr));
        // A collapse removes two faces, one on a border: an open mesh may end one below the target.
        EXPECT_LE(engine.faceCount(), target);
        EXPECT_GE(engine.faceCount() + 1, target);
        out.targets.push_back(target);
        out.meshes.push_back(engine.extract());
    }
    out.rounds = engine.roundCount();
    return out;
}

// Every directed edge occurs once; on a closed mesh its reverse occurs once too; no face repeats
// a point.
void expectManifold(const Mesh& m, bool closed) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t f = 0; f < m.indices.size(); f += 3) {
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = m.indices[f + k], b = m.indices[f + (k + 1) % 3];
            ASSERT_NE(a, b);
            ++directed[{a, b}];
        }
    }
    for (const auto& [edge, count] : directed) {
        ASSERT_EQ(count, 1) << edge.first << "-" << edge.second;
        if (closed) {
            ASSERT_EQ(directed.count({edge.second, edge.first}), 1u);
        }
    }
    if (closed) {
        // Euler characteristic of a sphere: V - E + F = 2.
        const long long edges = (long long)(directed.size() / 2);
        EXPECT_EQ((long long)m.vertexCount() - edges + (long long)m.faceCount(), 2);
    }
}

TEST(PartitionedRoundTest, SameLevelsAtOneAndTwoThreads) {
    for (const bool closed : {true, false}) {
        const Mesh mesh = closed ? bumpySphere() : bumpyGrid();
        const Levels one = collapse(mesh, 10000, 1);
        const Levels two = collapse(mesh, 10000, 2);
        // Each level starts above 10000 faces; the 10 % run (20480 to 8192 faces) takes two rounds, the
        // first to half the faces alive.
        EXPECT_EQ(one.rounds, 4u);
        EXPECT_EQ(one.rounds, two.rounds);
        ASSERT_EQ(one.meshes.size(), two.meshes.size());
        for (size_t i = 0; i < one.meshes.size(); ++i) {
            EXPECT_LE(one.meshes[i].faceCount(), one.targets[i]);
            EXPECT_EQ(one.meshes[i].indices, two.meshes[i].indices) << "level " << i;
            ASSERT_EQ(one.meshes[i].positions.size(), two.meshes[i].positions.size());
            EXPECT_EQ(std::memcmp(one.meshes[i].positions.data(), two.meshes[i].positions.data(),
                                  one.meshes[i].positions.size() * sizeof(lodbake::Vec3f)),
                      0)
                << "level " << i;
            expectManifold(one.meshes[i], closed);
        }
    }
}

TEST(PartitionedRoundTest, SmallMeshesKeepTheSerialLoop) {
    const Mesh mesh = bumpySphere();
    const Levels serial = collapse(mesh, EdgeCollapser::kRoundMinFaces, 2);
    EXPECT_EQ(serial.rounds, 0u);
    // Rounds change the collapse order, so the levels differ (but keep the face counts).
    const Levels rounds = collapse(mesh, 10000, 2);
    ASSERT_GT(rounds.rounds, 0u);
    EXPECT_NE(serial.meshes[0].indices, rounds.meshes[0].indices);
    EXPECT_EQ(serial.meshes[0].faceCount(), rounds.meshes[0].faceCount());
}

// simplify() (one target) keeps the serial order above kRoundMinFaces too: the same mesh as the
// engine run with rounds off, not the one with rounds.
TEST(PartitionedRoundTest, SimplifyKeepsTheSerialLoop) {
    const Mesh mesh = lodbake_test::icosphere(7); // 327,680 faces, above kRoundMinFaces
    ASSERT_GE(mesh.faceCount(), EdgeCollapser::kRoundMinFaces);
    lodbake::SimplifyOptions options;
    options.target_ratio = 0.4f;
    Diagnostics d;
    const auto simplified = lodbake::simplify(mesh, options, d);
    ASSERT_TRUE(simplified.ok()) << simplified.status().message();
    auto engineMesh = [&](size_t round_min_faces, size_t& rounds) {
        EdgeCollapser engine;
        EXPECT_TRUE(engine.init(mesh, options, d).ok());
        engine.setRoundMinFaces(round_min_faces);
        engine.run(size_t(std::ceil(0.4 * double(engine.initialFaceCount()))), HUGE_VAL, nullptr);
        rounds = engine.roundCount();
        return engine.extract();
    };
    size_t serial_rounds = 0, round_rounds = 0;
    const Mesh serial = engineMesh(SIZE_MAX, serial_rounds);
    const Mesh with_rounds = engineMesh(EdgeCollapser::kRoundMinFaces, round_rounds);
    EXPECT_EQ(serial_rounds, 0u);
    EXPECT_GE(round_rounds, 1u);
    EXPECT_EQ(simplified->mesh.indices, serial.indices);
    EXPECT_EQ(simplified->mesh.positions, serial.positions);
    EXPECT_NE(simplified->mesh.indices, with_rounds.indices);
}

TEST(PartitionedRoundTest, TargetAtOrAboveTheFaceCountCollapsesNothing) {
    const Mesh mesh = bumpySphere();
    Diagnostics d;
    EdgeCollapser engine;
    ASSERT_TRUE(engine.init(mesh, lodbake::SimplifyOptions(), d).ok());
    engine.setRoundMinFaces(10000);
    for (size_t target : {engine.initialFaceCount(), engine.initialFaceCount() + 5}) {
        EXPECT_TRUE(engine.run(target, HUGE_VAL, nullptr));
        EXPECT_EQ(engine.faceCount(), engine.initialFaceCount());
        EXPECT_EQ(engine.roundCount(), 0u);
    }
}

TEST(PartitionedRoundTest, QueueSplitAndMergeKeepEveryId) {
    constexpr uint32_t kIds = 5000;
    CollapseQueue q(kIds);
    q.reserve(kIds + 64);
    for (uint32_t id = 0; id < kIds; ++id)
        if (id % 7 != 3) q.set(id, float((id * 2654435761u) % 1000));
    // Part 0: ids ≡ 0 mod 3, part 1: ≡ 1 mod 3, the rest stays.
    const uint32_t capacity[2] = {kIds / 3 + 1, kIds / 3 + 1};
    PartHeap parts[2];
    ASSERT_TRUE(q.split([](uint32_t id) { return id % 3; }, capacity, parts, 2));
    for (const PartHeap& part : parts) EXPECT_TRUE(part.isConsistent());
    // Pop a few from each part in order, insert one id that was absent.
    for (uint32_t p = 0; p < 2; ++p) {
        float last = -1.0f;
        for (int i = 0; i < 100; ++i) {
            const uint32_t id = parts[p].topId();
            EXPECT_EQ(id % 3, p);
            EXPECT_GE(float((id * 2654435761u) % 1000), last);
            last = float((id * 2654435761u) % 1000);
            parts[p].remove(id);
        }
        parts[p].set(p == 0 ? 3 : 10, 0.5f); // ≡ 3 mod 7: never queued
        EXPECT_TRUE(parts[p].isConsistent());
    }
    q.merge(parts, 2);
    EXPECT_TRUE(q.isConsistent());
    EXPECT_TRUE(q.contains(3));
    EXPECT_TRUE(q.contains(10));
    size_t expected = 0;
    for (uint32_t id = 0; id < kIds; ++id) expected += id % 7 != 3;
    EXPECT_EQ(q.size(), expected - 200 + 2);
}

TEST(PartitionedRoundTest, SplitBuildsThePartsAlikeInAnyOrder) {
    // runRound builds the part heaps side by side (split's for_parts): built last part first, the
    // parts must pop the same ids in the same order as when built one after the other.
    constexpr uint32_t kIds = 3000;
    auto fill = [](CollapseQueue& q) {
        q.reserve(kIds + 64);
        for (uint32_t id = 0; id < kIds; ++id) q.set(id, float((id * 2654435761u) % 97));
    };
    const uint32_t capacity[2] = {kIds / 3 + 1, kIds / 3 + 1};
    auto part_of = [](uint32_t id) { return id % 3; };
    CollapseQueue serial(kIds), reversed(kIds);
    fill(serial);
    fill(reversed);
    PartHeap a[2], b[2];
    ASSERT_TRUE(serial.split(part_of, capacity, a, 2));
    std::vector<uint32_t> order;
    ASSERT_TRUE(reversed.split(part_of, capacity, b, 2, [&](uint32_t count, const auto& build) {
        for (uint32_t p = count; p-- > 0;) {
            order.push_back(p);
            build(p);
        }
    }));
    EXPECT_EQ(order, (std::vector<uint32_t>{1, 0}));
    for (uint32_t p = 0; p < 2; ++p) {
        EXPECT_TRUE(b[p].isConsistent());
        ASSERT_EQ(a[p].size(), b[p].size());
        while (!a[p].empty()) {
            ASSERT_FALSE(b[p].empty());
            EXPECT_EQ(a[p].topId(), b[p].topId());
            EXPECT_EQ(a[p].topCost(), b[p].topCost());
            a[p].remove(a[p].topId());
            b[p].remove(b[p].topId());
        }
        EXPECT_TRUE(b[p].empty());
    }
}

TEST(PartitionedRoundTest, SplitRefusesPartsThatDoNotFit) {
    CollapseQueue q(100);
    for (uint32_t id = 0; id < 100; ++id) q.set(id, float(id));
    const uint32_t capacity[2] = {1000000, 1000000};
    PartHeap parts[2];
    EXPECT_FALSE(q.split([](uint32_t id) { return id % 2; }, capacity, parts, 2));
    EXPECT_TRUE(q.isConsistent());
    EXPECT_EQ(q.size(), 100u);
    EXPECT_EQ(q.topId(), 0u);
}

} // namespace
