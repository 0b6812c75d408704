#include "lodbake/simplify/multilevel.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "cli_runner.h"
#include "lodbake/cleanup/topology.h"
#include "lodbake/io/mesh_io.h"
#include "mesh_builders.h"
#include "simplify_test_meshes.h"
#include "test_paths.h"

namespace {

using lodbake::Diagnostics;
using lodbake::Mesh;
using lodbake::MultilevelOptions;
using lodbake::MultilevelOutput;
using lodbake::Vec3f;

MultilevelOutput run(const Mesh& mesh, const MultilevelOptions& options, Diagnostics* diagnostics = nullptr) {
    Diagnostics local;
    auto result = lodbake::simplifyMultilevel(mesh, options, diagnostics ? *diagnostics : local);
    EXPECT_TRUE(result.ok()) << result.status().message();
    return result.ok() ? std::move(result).value() : MultilevelOutput();
}

double maxRadiusError(const Mesh& m) {
    double worst = 0.0;
    for (const Vec3f& p : m.positions) worst = std::max(worst, std::fabs(double(lodbake::length(p)) - 1.0));
    return worst;
}

TEST(MultilevelTest, RemovesTheRequestedShareOfEdgesOnAClosedSphere) {
    const Mesh sphere = lodbake_test::icosphere(4); // 5120 faces, 7680 edges
    MultilevelOptions o;
    o.percentage = 60.0;
    const MultilevelOutput out = run(sphere, o);
    EXPECT_TRUE(out.reached_target);
    EXPECT_EQ(out.collapses_requested, size_t(0.6 * 7680 / 3));
    EXPECT_EQ(out.collapses, out.collapses_requested);
    // A closed manifold loses exactly two faces per collapse.
    EXPECT_EQ(out.mesh.faceCount(), 5120 - 2 * out.collapses);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.non_manifold_vertex_count, 0u);
    EXPECT_EQ(t.inconsistent_edge_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2); // genus kept
    EXPECT_EQ(t.unreferenced_vertex_count, 0u);
    // Vertices stay near the sphere: collapses interpolate along edges, smoothing is held by λ.
    EXPECT_LT(maxRadiusError(out.mesh), 0.05);
}

TEST(MultilevelTest, NoDecimationKeepsConnectivityAndSmoothsNoise) {
    Mesh noisy = lodbake_test::icosphere(3);
    for (size_t i = 0; i < noisy.positions.size(); ++i)
        noisy.positions[i] = noisy.positions[i] * (1.0f + 0.02f * ((i * 7919) % 13 / 6.0f - 1.0f));
    MultilevelOptions o;
    o.has_decimation = false;
    o.ple = 2.0;
    o.lambda = 0.5;
    const MultilevelOutput out = run(noisy, o);
    EXPECT_EQ(out.collapses, 0u);
    EXPECT_EQ(out.mesh.indices, noisy.indices);
    // The radial spread (noise) shrinks.
    auto spread = [](const Mesh& m) {
        double lo = 1e9, hi = -1e9;
        for (const Vec3f& p : m.positions) {
            lo = std::min(lo, double(lodbake::length(p)));
            hi = std::max(hi, double(lodbake::length(p)));
        }
        return hi - lo;
    };
    EXPECT_LT(spread(out.mesh), 0.7 * spread(noisy));
}

TEST(MultilevelTest, NoSmoothingNoDecimationIsIdentity) {
    const Mesh sphere = lodbake_test::icosphere(2);
    MultilevelOptions o;
    o.has_smoothing = false;
    o.has_decimation = false;
    const MultilevelOutput out = run(sphere, o);
    EXPECT_EQ(out.mesh.positions, sphere.positions);
    EXPECT_EQ(out.mesh.indices, sphere.indices);
}

TEST(MultilevelTest, BorderVerticesNeverMoveOrVanish) {
    const Mesh g = lodbake_test::grid(20, [](float x, float y) { return 0.1f * std::sin(6 * x) * std::cos(5 * y); });
    MultilevelOptions o;
    o.percentage = 70.0;
    const MultilevelOutput out = run(g, o);
    EXPECT_GT(out.collapses, 0u);
    size_t border_found = 0;
    for (const Vec3f& p : g.positions) {
        const bool border = p.x == 0.0f || p.x == 1.0f || p.y == 0.0f || p.y == 1.0f;
        if (!border) continue;
        for (const Vec3f& q : out.mesh.positions)
            if (q == p) {
                ++border_found;
                break;
            }
    }
    EXPECT_EQ(border_found, 80u); // 4 × 20 border vertices, all kept exactly
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.boundary_edge_count, 80u);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.inconsistent_edge_count, 0u);
}

TEST(MultilevelTest, RefusesCollapseAtValenceThreeOppositeVertex) {
    // A tetrahedron: every vertex has valence 3, so no collapse is valid (it would fold two faces
    // onto each other), and the target cannot be reached.
    Diagnostics d;
    MultilevelOptions o;
    o.percentage = 50.0;
    const MultilevelOutput out = run(lodbake_test::tetrahedron(), o, &d);
    EXPECT_EQ(out.collapses, 0u);
    EXPECT_FALSE(out.reached_target);
    EXPECT_EQ(out.mesh.faceCount(), 4u);
    EXPECT_FALSE(d.items().empty());
}

TEST(MultilevelTest, RefusesCollapseThatBreaksTheLinkCondition) {
    // An octahedron asked to lose 90 % of its edges: the valence-3 and link checks stop the
    // collapses at a tetrahedron at the latest, and the result stays a closed manifold with χ = 2.
    const Mesh octa = lodbake_test::makeMesh({{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
                                             {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5});
    MultilevelOptions o;
    o.percentage = 90.0;
    o.has_smoothing = false;
    const MultilevelOutput out = run(octa, o);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.boundary_edge_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2);
    EXPECT_GE(out.collapses, 1u);
    EXPECT_GE(out.mesh.faceCount(), 4u);
    EXPECT_EQ(out.mesh.faceCount(), 8 - 2 * out.collapses);
    EXPECT_FALSE(out.reached_target);
}

TEST(MultilevelTest, ShortEdgesGoFirst) {
    // A flat 10×10 grid whose column x = 0.4 is moved to x = 0.48, next to the column at x = 0.5:
    // sorted decimation must spend its budget on the 0.02-long edges of that strip only.
    Mesh g = lodbake_test::flatGrid(10);
    for (Vec3f& p : g.positions)
        if (std::fabs(p.x - 0.4f) < 1e-6f) p.x = 0.48f;
    MultilevelOptions o;
    o.percentage = 5.0; // 320 edges: 5 collapses
    o.iterations = 1;
    o.has_smoothing = false;
    const MultilevelOutput out = run(g, o);
    ASSERT_EQ(out.collapses_requested, 5u);
    ASSERT_EQ(out.collapses, 5u);
    size_t outside_before = 0, outside_after = 0;
    for (const Vec3f& p : g.positions) outside_before += p.x < 0.47f || p.x > 0.51f;
    for (const Vec3f& p : out.mesh.positions) outside_after += p.x < 0.47f || p.x > 0.51f;
    EXPECT_EQ(outside_after, outside_before);
    EXPECT_EQ(out.mesh.vertexCount(), g.vertexCount() - 5);
}

TEST(MultilevelTest, UnsortedModeOnlyCollapsesEdgesBelowTheThreshold) {
    const Mesh sphere = lodbake_test::icosphere(3);
    MultilevelOptions o;
    o.percentage = 30.0;
    o.is_sorted = false;
    o.has_smoothing = false;
    const MultilevelOutput out = run(sphere, o);
    EXPECT_GT(out.length_threshold, 0.0);
    EXPECT_GT(out.collapses, 0u);
    EXPECT_LE(out.collapses, out.collapses_requested);
    const lodbake::TopologyStats t = lodbake::computeTopologyStats(out.mesh);
    EXPECT_EQ(t.non_manifold_edge_count, 0u);
    EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(MultilevelTest, DeterministicAcrossRuns) {
    const Mesh sphere = lodbake_test::icosphere(4);
    MultilevelOptions o;
    o.percentage = 80.0;
    const MultilevelOutput a = run(sphere, o);
    const MultilevelOutput b = run(sphere, o);
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
}

TEST(MultilevelTest, RejectsBadOptionsAndNonFiniteInput) {
    Diagnostics d;
    MultilevelOptions o;
    o.percentage = 100.0;
    EXPECT_FALSE(lodbake::simplifyMultilevel(lodbake_test::tetrahedron(), o, d).ok());
    o = MultilevelOptions();
    o.iterations = 0;
    EXPECT_FALSE(lodbake::simplifyMultilevel(lodbake_test::tetrahedron(), o, d).ok());
    o = MultilevelOptions();
    o.time_step = 2.0;
    EXPECT_FALSE(lodbake::simplifyMultilevel(lodbake_test::tetrahedron(), o, d).ok());
    Mesh bad = lodbake_test::tetrahedron();
    bad.positions[2].y = std::numeric_limits<float>::quiet_NaN();
    auto r = lodbake::simplifyMultilevel(bad, MultilevelOptions(), d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("vertex 2"), std::string::npos);
}

TEST(MultilevelTest, EmptyAndDegenerateInputGiveACleanResult) {
    Diagnostics d;
    auto empty = lodbake::simplifyMultilevel(Mesh(), MultilevelOptions(), d);
    ASSERT_TRUE(empty.ok());
    EXPECT_EQ(empty->mesh.faceCount(), 0u);
    const Mesh degenerate = lodbake_test::makeMesh({{0, 0, 0}, {1, 0, 0}}, {0, 1, 1, 1, 0, 0});
    auto r = lodbake::simplifyMultilevel(degenerate, MultilevelOptions(), d);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->mesh.faceCount(), 0u);
}

// ---- CLI: lodbake simplify --method multilevel ----------------------------------------------------

const std::string& sphereFile() {
    static const std::string path = [] {
        const std::string p = lodbake_test::scratchDir() + "/multilevel_cli_sphere.ply";
        Diagnostics d;
        EXPECT_TRUE(lodbake::writeMesh(lodbake_test::icosphere(4), p, lodbake::WriteOptions(), d).ok());
        return p;
    }();
    return path;
}

TEST(MultilevelCliTest, RatioMapsToPercentageAndWritesTheMesh) {
    const std::string out = lodbake_test::scratchDir() + "/multilevel_cli_out.ply";
    const lodbake_test::CliRun run = lodbake_test::runLodbake(
        {"simplify", sphereFile(), "-o", out, "--method", "multilevel", "--ratio", "0.25", "--json"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("\"method\": \"multilevel\""), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("\"percentage\": 75,"), std::string::npos) << run.out;
    Diagnostics d;
    auto m = lodbake::readMesh(out, lodbake::ReadOptions(), d);
    ASSERT_TRUE(m.ok());
    // 75 % of the 7680 edges is 1920 collapses, two faces each.
    EXPECT_EQ(m->mesh.faceCount(), 5120u - 2u * 1920u);
}

TEST(MultilevelCliTest, AcceptsEveryDocumentOption) {
    const std::string out = lodbake_test::scratchDir() + "/multilevel_cli_opts.ply";
    const lodbake_test::CliRun run = lodbake_test::runLodbake(
        {"simplify", sphereFile(), "-o", out, "--method", "multilevel", "--percentage", "40", "--iterations", "2",
         "--ple", "1.5", "--lambda", "3", "--no-adaptive", "--no-sort", "--no-smoothing"});
    EXPECT_EQ(run.exit_code, 0) << run.err;
    const lodbake_test::CliRun smooth_only = lodbake_test::runLodbake(
        {"simplify", sphereFile(), "-o", out, "--method", "multilevel", "--percentage", "40", "--no-decimation"});
    ASSERT_EQ(smooth_only.exit_code, 0) << smooth_only.err;
    Diagnostics d;
    auto m = lodbake::readMesh(out, lodbake::ReadOptions(), d);
    ASSERT_TRUE(m.ok());
    EXPECT_EQ(m->mesh.faceCount(), 5120u);
}

TEST(MultilevelCliTest, UsageErrors) {
    const std::string out = lodbake_test::scratchDir() + "/multilevel_cli_bad.ply";
    const std::vector<std::vector<std::string>> bad = {
        {"--method", "bogus", "--ratio", "0.5"},
        {"--percentage", "50"},                                // multilevel option with qem
        {"--method", "multilevel", "--error", "0.1"},          // qem only
        {"--method", "multilevel", "--percentage", "100"},     // out of range
        {"--method", "multilevel", "--ratio", "0.5", "--percentage", "10"}, // two targets
        {"--method", "multilevel", "--ratio", "0.5", "--iterations", "0"},
    };
    for (const auto& extra : bad) {
        std::vector<std::string> args = {"simplify", sphereFile(), "-o", out};
        args.insert(args.end(), extra.begin(), extra.end());
        const lodbake_test::CliRun run = lodbake_test::runLodbake(args);
        EXPECT_EQ(run.exit_code, 2) << extra[0] << " " << extra[1] << ": " << run.err;
    }
}

} // namespace
