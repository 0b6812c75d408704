// The repair pipeline on hand-built meshes and on the shared scans (loaded once per suite).
#include "lodbake/cleanup/repair.h"

#include <chrono>
#include <memory>

#include <gtest/gtest.h>

#include "cleanup_builders.h"
#include "core/parallel.h"
#include "lodbake/io/mesh_io.h"
#include "test_paths.h"

using namespace lodbake;
using namespace lodbake_test;

namespace {
const PassSummary* findPass(const RepairReport& r, const std::string& name) {
    for (const PassSummary& p : r.passes)
        if (p.name == name) return &p;
    return nullptr;
}
uint64_t counter(const RepairReport& r, const std::string& pass, const std::string& name) {
    const PassSummary* p = findPass(r, pass);
    if (!p) return UINT64_MAX;
    for (const auto& [n, v] : p->counters)
        if (n == name) return v;
    return UINT64_MAX;
}
} // namespace

TEST(RepairTest, PipelineFixesABrokenMesh) {
    Mesh m = uvSphere(10, 20);
    // Break it: drop a face (hole), flip another, add a duplicate, a degenerate face, a stray vertex
    // and a speckle triangle far away.
    m.indices.erase(m.indices.begin() + 90, m.indices.begin() + 93);
    std::swap(m.indices[31], m.indices[32]);
    m.indices.insert(m.indices.end(), {m.indices[60], m.indices[61], m.indices[62]});
    m.indices.insert(m.indices.end(), {5, 5, 6});
    m.positions.push_back({7, 7, 7});
    Mesh t = singleTriangle();
    for (auto& p : t.positions) p = p * 0.01f + Vec3f(3, 0, 0);
    appendMesh(m, t);
    Diagnostics d;
    Result<RepairReport> r = repairMesh(m, RepairOptions(), "broken", d);
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_FALSE(r->before.isClosedManifold());
    EXPECT_TRUE(r->after.isClosedManifold());
    EXPECT_TRUE(r->unresolved.empty());
    EXPECT_EQ(counter(*r, "degenerate", "duplicate_faces"), 1u);
    EXPECT_EQ(counter(*r, "degenerate", "repeated_index_faces"), 1u);
    EXPECT_EQ(counter(*r, "unreferenced", "vertices_removed"), 1u);
    EXPECT_EQ(counter(*r, "orient", "faces_flipped"), 1u);
    EXPECT_EQ(counter(*r, "small_components", "components_removed"), 1u);
    EXPECT_EQ(counter(*r, "holes", "holes_filled"), 1u);
    EXPECT_EQ(m.normals.size(), m.vertexCount());
    EXPECT_EQ(findPass(*r, "denoise"), nullptr); // off by default
    EXPECT_TRUE(d.empty());
}

TEST(RepairTest, RejectsInconsistentMesh) {
    Mesh m = singleTriangle();
    m.indices[2] = 99;
    Diagnostics d;
    Result<RepairReport> r = repairMesh(m, RepairOptions(), "bad.ply", d);
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("bad.ply"), std::string::npos);
}

TEST(RepairTest, DegenerateConfigurationsAreClean) {
    std::vector<Mesh> cases;
    cases.push_back(Mesh());                                                          // empty
    cases.push_back(makeMesh({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {0, 1, 2, 1, 1, 2})); // all faces degenerate
    cases.push_back(singleTriangle());
    cases.push_back(strip(20)); // all-boundary strip
    Mesh isolated;
    isolated.positions = {{0, 0, 0}, {1, 1, 1}, {2, 0, 1}};
    cases.push_back(isolated);
    cases.push_back(moebius(10));
    cases.push_back(bowTie());
    cases.push_back(finEdge());
    for (size_t i = 0; i < cases.size(); ++i) {
        Mesh m = cases[i];
        Diagnostics d;
        Result<RepairReport> r = repairMesh(m, RepairOptions(), "case" + std::to_string(i), d);
        ASSERT_TRUE(r.ok()) << i;
        EXPECT_TRUE(checkMeshConsistency(m, "out").ok()) << i;
        if (m.faceCount())
            EXPECT_TRUE(r->after.isManifold()) << i;
        else
            EXPECT_FALSE(r->unresolved.empty()) << i; // "no triangles left" is reported
    }
}

TEST(RepairTest, DenoiseRunsWhenEnabled) {
    Mesh m = uvSphere(16, 32);
    for (size_t v = 0; v < m.vertexCount(); ++v) m.positions[v] = m.positions[v] * (1 + 0.01f * hashNoise(uint32_t(v)));
    RepairOptions o;
    o.denoise = true;
    Diagnostics d;
    Result<RepairReport> r = repairMesh(m, o, "noisy", d);
    ASSERT_TRUE(r.ok());
    ASSERT_NE(findPass(*r, "denoise"), nullptr);
    EXPECT_LT(counter(*r, "denoise", "roughness_after_millideg"), counter(*r, "denoise", "roughness_before_millideg"));
}

TEST(RepairTest, IsDeterministic) {
    Mesh a = moebius(14), b = moebius(14);
    appendMesh(a, twoConesAtVertex());
    appendMesh(b, twoConesAtVertex());
    Diagnostics d;
    ASSERT_TRUE(repairMesh(a, RepairOptions(), "a", d).ok());
    ASSERT_TRUE(repairMesh(b, RepairOptions(), "b", d).ok());
    EXPECT_EQ(a.indices, b.indices);
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.normals, b.normals);
}

// Real scans: each is loaded once for the whole suite.
class RepairScanTest : public ::testing::Test {
protected:
    static std::map<std::string, std::unique_ptr<Mesh>>& cache() {
        static std::map<std::string, std::unique_ptr<Mesh>> c;
        return c;
    }
    static const Mesh* scan(const std::string& name) {
        auto& c = cache();
        auto it = c.find(name);
        if (it != c.end()) return it->second.get();
        Diagnostics d;
        Result<LoadedMesh> loaded = readMesh(sharedMesh(name), ReadOptions(), d);
        EXPECT_TRUE(loaded.ok()) << loaded.status().message();
        if (!loaded.ok()) return nullptr;
        return (c[name] = std::make_unique<Mesh>(std::move(loaded->mesh))).get();
    }
    static void TearDownTestSuite() { cache().clear(); }
};

TEST_F(RepairScanTest, BunnyZipperClosesWithDefaults) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh* input = scan("bunny_zipper.ply");
    ASSERT_NE(input, nullptr);
    Mesh m = *input;
    Diagnostics d;
    Result<RepairReport> r = repairMesh(m, RepairOptions(), "bunny_zipper.ply", d);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->before.boundary_loop_lengths, (std::vector<uint32_t>{80, 42, 40, 39, 22}));
    EXPECT_EQ(r->before.topology.unreferenced_vertex_count, 1113u);
    EXPECT_EQ(counter(*r, "unreferenced", "vertices_removed"), 1113u);
    EXPECT_EQ(counter(*r, "holes", "holes_filled"), 5u);
    EXPECT_TRUE(r->after.isClosedManifold());
    EXPECT_EQ(r->after.topology.euler_characteristic, 2);
    EXPECT_TRUE(r->unresolved.empty());
}

TEST_F(RepairScanTest, Lucy100kIsAlreadyCleanAndFast) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh* input = scan("lucy100k.ply");
    ASSERT_NE(input, nullptr);
    Mesh m = *input;
    Diagnostics d;
    const auto t0 = std::chrono::steady_clock::now();
    Result<RepairReport> r = repairMesh(m, RepairOptions(), "lucy100k.ply", d);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    RecordProperty("repair_seconds", std::to_string(seconds));
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->after.isClosedManifold());
    EXPECT_EQ(m.faceCount(), input->faceCount());
    EXPECT_EQ(m.positions, input->positions); // nothing to fix, so geometry is untouched
    EXPECT_LT(seconds, 5.0);                  // budget is 1 s (see repair_bench); loose here for loaded CI machines
}

TEST_F(RepairScanTest, RawScanBecomesManifoldAndDenoiseStaysInNoiseBand) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh* input = scan("bunny_scan_bun000_tri.ply");
    ASSERT_NE(input, nullptr);
    Mesh m = *input;
    RepairOptions o;
    Diagnostics d;
    Result<RepairReport> r = repairMesh(m, o, "bunny_scan_bun000_tri.ply", d);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->before.component_face_counts.size(), 10u);
    EXPECT_TRUE(r->after.isManifold());
    EXPECT_GT(counter(*r, "small_components", "components_removed"), 0u);
    for (uint32_t faces : r->after.component_face_counts) EXPECT_GE(faces, o.component_options.min_face_count);
    EXPECT_EQ(r->after.topology.degenerate_face_count, 0u);

    // Denoise the repaired scan: vertices move off the input surface (along its normal) by less
    // than 2e-4 of the diagonal on average, and the surface gets smoother.
    Mesh smooth = m;
    const DenoiseReport dr = denoise(smooth);
    const double diag = computeBounds(m).diagonal();
    double off_surface = 0;
    for (size_t v = 0; v < m.vertexCount(); ++v)
        off_surface += std::fabs(dot(toDouble(smooth.positions[v]) - toDouble(m.positions[v]), toDouble(m.normals[v])));
    off_surface /= double(m.vertexCount()) * diag;
    RecordProperty("mean_normal_displacement_rel", std::to_string(off_surface));
    RecordProperty("roughness_before_deg", std::to_string(dr.roughness_before_deg));
    RecordProperty("roughness_after_deg", std::to_string(dr.roughness_after_deg));
    EXPECT_LT(off_surface, 2e-4);
    EXPECT_LT(dr.roughness_after_deg, 0.8 * dr.roughness_before_deg);
}

TEST_F(RepairScanTest, FandiskCreasesSurviveFeaturePreservingDenoise) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh* input = scan("fandisk.obj");
    ASSERT_NE(input, nullptr);
    Mesh m = *input;
    weldVertices(m);
    removeUnreferencedVertices(m);
    const Mesh before = m;
    DenoiseOptions o;
    o.preserve_features = true;
    const DenoiseReport r = denoise(m, o);
    EXPECT_GT(r.feature_edges, 100u);
    // Dihedral change at every crease (> 30 degrees in the input) stays under 2 degrees.
    std::map<std::pair<uint32_t, uint32_t>, std::vector<size_t>> edges;
    for (size_t f = 0; f < before.faceCount(); ++f)
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = before.indices[3 * f + k], b = before.indices[3 * f + (k + 1) % 3];
            edges[{std::min(a, b), std::max(a, b)}].push_back(f);
        }
    auto angle = [](const Mesh& mesh, size_t f, size_t g) {
        auto n = [&](size_t h) {
            const Vec3d a = toDouble(mesh.positions[mesh.indices[3 * h]]);
            return normalize(cross(toDouble(mesh.positions[mesh.indices[3 * h + 1]]) - a,
                                   toDouble(mesh.positions[mesh.indices[3 * h + 2]]) - a));
        };
        return std::acos(std::max(-1.0, std::min(1.0, dot(n(f), n(g))))) * 180 / M_PI;
    };
    double worst = 0;
    size_t creases = 0;
    for (const auto& [e, faces] : edges) {
        if (faces.size() != 2) continue;
        const double a0 = angle(before, faces[0], faces[1]);
        if (a0 < 30) continue;
        ++creases;
        worst = std::max(worst, std::fabs(angle(m, faces[0], faces[1]) - a0));
    }
    RecordProperty("fandisk_worst_crease_change_deg", std::to_string(worst));
    EXPECT_GT(creases, 100u);
    EXPECT_LT(worst, 2.0);
}

TEST(RepairTest, RandomSmallMeshesNeverBreakInvariants) {
    // Deterministic pseudo-random soups: repeated indices, coincident and NaN vertices, fins,
    // duplicates. Every pass must finish and leave a consistent mesh.
    uint32_t state = 12345;
    auto next = [&]() {
        state = state * 1664525u + 1013904223u;
        return state >> 8;
    };
    for (int round = 0; round < 300; ++round) {
        Mesh m;
        const uint32_t vertex_count = 1 + next() % 12;
        for (uint32_t v = 0; v < vertex_count; ++v) {
            Vec3f p(float(next() % 4), float(next() % 4), float(next() % 3));
            if (next() % 40 == 0) p.x = std::nanf("");
            m.positions.push_back(p);
        }
        if (round % 3 == 0) m.uvs.push_back(std::vector<Vec2f>(vertex_count, Vec2f(float(next() % 2), 0)));
        const uint32_t face_count = next() % 24;
        for (uint32_t f = 0; f < 3 * face_count; ++f) m.indices.push_back(next() % vertex_count);
        RepairOptions o;
        o.denoise = round % 2 == 0;
        o.denoise_options.preserve_features = round % 4 == 0;
        o.denoise_options.method = DenoiseMethod(round % 3);
        o.normal_options.crease_angle_deg = round % 5 == 0 ? 45.0 : 180.0;
        o.component_options.min_face_count = round % 7;
        o.hole_options.max_dp_edges = round % 2 ? 200 : 3; // exercise ear clipping on small loops too
        Diagnostics d;
        Result<RepairReport> r = repairMesh(m, o, "random", d);
        ASSERT_TRUE(r.ok()) << round;
        ASSERT_TRUE(checkMeshConsistency(m, "out").ok()) << round;
        for (const Vec3f& p : m.positions) EXPECT_TRUE(isFinite(p)) << round;
        EXPECT_EQ(r->after.topology.non_manifold_edge_count, 0u) << round;
        EXPECT_EQ(r->after.topology.non_manifold_vertex_count, 0u) << round;
        EXPECT_EQ(r->after.topology.inconsistent_edge_count, 0u) << round;
    }
}

TEST_F(RepairScanTest, SameResultForAnyThreadCount) {
    // The weld's neighbour scan and the normals' per-face work run in parallel: the repaired mesh
    // must not depend on the number of threads.
    LODBAKE_REQUIRE_SHARED_MESHES();
    const Mesh* input = scan("dragon_scan_stand0_tri.ply");
    ASSERT_NE(input, nullptr);
    RepairOptions o;
    o.weld_options.tolerance_rel = 4e-3; // above the grid spacing (2.9e-3): many pairs to merge
    o.denoise = true;
    std::vector<Mesh> results;
    uint64_t merged = 0;
    for (size_t threads : {1u, 2u, 4u}) {
        ScopedThreadLimit limit(threads);
        Mesh m = *input;
        Diagnostics d;
        Result<RepairReport> r = repairMesh(m, o, "dragon", d);
        ASSERT_TRUE(r.ok());
        merged = counter(*r, "weld", "vertices_merged");
        results.push_back(std::move(m));
    }
    EXPECT_GT(merged, 0u);
    for (size_t i = 1; i < results.size(); ++i) {
        EXPECT_EQ(results[i].indices, results[0].indices);
        EXPECT_EQ(results[i].positions, results[0].positions);
        EXPECT_EQ(results[i].normals, results[0].normals);
    }
}
