// The range-scan merge (reconstruct module): the overlap test `auto` uses, the merged surface, its
// trimming, colours, limits and errors, determinism, and the bake's `merge` setting end to end.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "lodbake/bake/bake.h"
#include "lodbake/cleanup/validate.h"
#include "lodbake/config/bake_config.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/reconstruct/merge.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace {

using namespace lodbake;
constexpr double kPi = 3.14159265358979323846;

// A unit-sphere sheet as a range grid would give it: a latitude-longitude grid, rotated by `turn`
// radians about the x axis (so two sheets sample different points), wound outwards, keeping the
// triangles whose centroid satisfies `keep`. Appended to `mesh` as its own component and sub-mesh.
template <class Keep> void addSphereSheet(Mesh& mesh, int rows, int cols, double turn, Keep keep) {
    const uint32_t base = uint32_t(mesh.positions.size());
    const double c = std::cos(turn), s = std::sin(turn);
    for (int r = 0; r <= rows; ++r)
        for (int k = 0; k < cols; ++k) {
            const double theta = kPi * double(r) / rows, phi = 2.0 * kPi * double(k) / cols;
            const double x = std::sin(theta) * std::cos(phi), y = std::sin(theta) * std::sin(phi), z = std::cos(theta);
            mesh.positions.push_back(Vec3f(Vec3d(x, c * y - s * z, s * y + c * z)));
        }
    const uint32_t first_index = uint32_t(mesh.indices.size());
    auto id = [&](int r, int k) { return base + uint32_t(r * cols + (k % cols)); };
    auto tri = [&](uint32_t a, uint32_t b, uint32_t d) {
        const Vec3d m = (toDouble(mesh.positions[a]) + toDouble(mesh.positions[b]) + toDouble(mesh.positions[d])) / 3.0;
        if (keep(m)) mesh.indices.insert(mesh.indices.end(), {a, b, d});
    };
    for (int r = 0; r < rows; ++r)
        for (int k = 0; k < cols; ++k) {
            tri(id(r, k), id(r + 1, k), id(r + 1, k + 1));
            tri(id(r, k), id(r + 1, k + 1), id(r, k + 1));
        }
    mesh.submeshes.push_back({"sheet" + std::to_string(mesh.submeshes.size()), first_index,
                              uint32_t(mesh.indices.size()) - first_index, MaterialId::invalid()});
}

// Two sheets of one sphere that overlap in a band around the equator (z in [-0.3, 0.3]).
Mesh twoOverlappingSheets() {
    Mesh mesh;
    addSphereSheet(mesh, 60, 120, 0.0, [](const Vec3d& m) { return m.z > -0.3; });
    addSphereSheet(mesh, 57, 113, 0.013, [](const Vec3d& m) { return m.z < 0.3; });
    return mesh;
}

size_t componentCount(const Mesh& mesh) {
    ValidateOptions o;
    o.weld_by_position = true;
    return validate(mesh, o).component_face_counts.size();
}

// Distance from the origin's unit sphere, largest over the vertices.
double maxSphereDeviation(const Mesh& mesh) {
    double worst = 0.0;
    for (const Vec3f& p : mesh.positions) worst = std::max(worst, std::fabs(length(toDouble(p)) - 1.0));
    return worst;
}

} // namespace

TEST(MergeTest, OverlappingSheetsAreDetectedAndSeparatePiecesAreNot) {
    EXPECT_GE(overlappingSheetFraction(twoOverlappingSheets()), kOverlappingSheetFraction);
    Mesh one;
    addSphereSheet(one, 40, 80, 0.0, [](const Vec3d&) { return true; });
    EXPECT_EQ(overlappingSheetFraction(one), 0.0);
    // Two caps that meet only at the equator: separate pieces touching along a line, not sheets.
    Mesh touching;
    addSphereSheet(touching, 60, 120, 0.0, [](const Vec3d& m) { return m.z > 0.0; });
    addSphereSheet(touching, 60, 120, 0.0, [](const Vec3d& m) { return m.z < 0.0; });
    EXPECT_LT(overlappingSheetFraction(touching), kOverlappingSheetFraction);
}

TEST(MergeTest, UvChartsOfOneSurfaceAreNotSheets) {
    // A sphere cut into two charts along its equator, the seam vertices duplicated (same positions).
    Mesh mesh;
    addSphereSheet(mesh, 40, 80, 0.0, [](const Vec3d& m) { return m.z >= 0.0; });
    Mesh lower;
    addSphereSheet(lower, 40, 80, 0.0, [](const Vec3d& m) { return m.z < 0.0; });
    appendMesh(mesh, lower);
    EXPECT_EQ(overlappingSheetFraction(mesh), 0.0);
}

TEST(MergeTest, TwoSheetsBecomeOneSurfaceNearTheSamples) {
    Mesh mesh = twoOverlappingSheets();
    ASSERT_EQ(componentCount(mesh), 2u);
    Result<MergeReport> r = mergeRangeViews(mesh, MergeOptions(), "sheets");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_EQ(r->views, 2u);
    EXPECT_TRUE(r->views_are_scans);
    EXPECT_GE(r->depth, 5);
    EXPECT_EQ(componentCount(mesh), 1u);
    EXPECT_EQ(r->faces, mesh.faceCount());
    // The sample spacing is about 0.05: the merged sphere stays within a fraction of it.
    EXPECT_LT(r->p95_distance, 0.01);
    EXPECT_LT(r->mean_distance, r->p95_distance);
    EXPECT_LT(maxSphereDeviation(mesh), 0.05);
    EXPECT_EQ(mergeReportLines(*r).size(), 3u);
}

TEST(MergeTest, RealHolesStayOpen) {
    // Neither sheet sees the polar caps (|z| > 0.8): the reconstruction closes them, the trim reopens.
    Mesh mesh;
    addSphereSheet(mesh, 60, 120, 0.0, [](const Vec3d& m) { return m.z > -0.3 && m.z < 0.8; });
    addSphereSheet(mesh, 57, 113, 0.013, [](const Vec3d& m) { return m.z < 0.3 && m.z > -0.8; });
    Result<MergeReport> r = mergeRangeViews(mesh, MergeOptions(), "holes");
    ASSERT_TRUE(r.ok()) << r.status().message();
    EXPECT_GT(r->trimmed_area, 0.0);
    double top = -1.0, bottom = 1.0;
    for (const Vec3f& p : mesh.positions) {
        top = std::max(top, double(p.z));
        bottom = std::min(bottom, double(p.z));
    }
    EXPECT_LT(top, 0.95) << "the unseen top cap was kept";
    EXPECT_GT(bottom, -0.95) << "the unseen bottom cap was kept";
    EXPECT_GT(validate(mesh).topology.boundary_edge_count, 0u);
}

TEST(MergeTest, ColoursComeFromTheNearestSamples) {
    Mesh mesh = twoOverlappingSheets();
    mesh.colors.resize(mesh.vertexCount());
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
        mesh.colors[v] = mesh.positions[v].x > 0.0f ? Vec4f{1, 0, 0, 1} : Vec4f{0, 0, 1, 1};
    Result<MergeReport> r = mergeRangeViews(mesh, MergeOptions(), "colours");
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(mesh.colors.size(), mesh.vertexCount());
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        if (std::fabs(mesh.positions[v].x) < 0.1f) continue; // near the colour border
        EXPECT_EQ(mesh.colors[v].x, mesh.positions[v].x > 0.0f ? 1.0f : 0.0f) << "vertex " << v;
    }
}

TEST(MergeTest, SameBytesOnEveryRun) {
    Mesh a = twoOverlappingSheets(), b = twoOverlappingSheets();
    ASSERT_TRUE(mergeRangeViews(a, MergeOptions(), "a").ok());
    ASSERT_TRUE(mergeRangeViews(b, MergeOptions(), "b").ok());
    ASSERT_EQ(a.indices, b.indices);
    ASSERT_EQ(a.positions.size(), b.positions.size());
    for (size_t v = 0; v < a.positions.size(); ++v) {
        ASSERT_EQ(a.positions[v].x, b.positions[v].x);
        ASSERT_EQ(a.positions[v].y, b.positions[v].y);
        ASSERT_EQ(a.positions[v].z, b.positions[v].z);
    }
}

TEST(MergeTest, BadInputIsAClearErrorAndLeavesTheMeshAlone) {
    Mesh tiny;
    addSphereSheet(tiny, 3, 4, 0.0, [](const Vec3d&) { return true; });
    const Mesh before = tiny;
    Result<MergeReport> r = mergeRangeViews(tiny, MergeOptions(), "tiny.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::InvalidInput);
    EXPECT_EQ(r.status().message().rfind("tiny.ply: merge: expected at least 64 samples", 0), 0u)
        << r.status().message();
    EXPECT_EQ(tiny.indices, before.indices);

    Mesh points = twoOverlappingSheets();
    points.indices.clear();
    points.submeshes.clear();
    r = mergeRangeViews(points, MergeOptions(), "points.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("points.ply: merge:"), std::string::npos);

    Mesh big = twoOverlappingSheets();
    MergeOptions limited;
    limited.max_points = 1000;
    r = mergeRangeViews(big, limited, "big.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::ResourceLimit);
    EXPECT_NE(r.status().message().find("more than the limit of 1000"), std::string::npos);

    MergeOptions deep;
    deep.depth = 40;
    r = mergeRangeViews(big, deep, "big.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().message().find("depth 40"), std::string::npos);

    Mesh broken = twoOverlappingSheets();
    broken.indices.back() = uint32_t(broken.vertexCount() + 5);
    EXPECT_FALSE(mergeRangeViews(broken, MergeOptions(), "broken.ply").ok());
}

TEST(MergeTest, PresetKeyAndOption) {
    BakeSettings s;
    EXPECT_EQ(s.merge, MergeMode::Auto);
    ASSERT_TRUE(applyPresetJson(R"({"version": 1, "merge": "off"})", "p.json", s).ok());
    EXPECT_EQ(s.merge, MergeMode::Off);
    ASSERT_TRUE(applyPresetJson(R"({"version": 1, "merge": "poisson"})", "p.json", s).ok());
    EXPECT_EQ(s.merge, MergeMode::Poisson);
    const Status bad = applyPresetJson(R"({"version": 1, "merge": "vrip"})", "p.json", s);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("p.json: /merge: expected one of"), std::string::npos) << bad.message();
    EXPECT_NE(settingsToJson(s).find("\"merge\": \"poisson\""), std::string::npos);
}

// The rock sample: `auto` merges its six views into one surface, the same bytes at 1 and 2 threads.
TEST(MergeBakeTest, RockScanSetMergesToOneSurfaceDeterministically) {
    const std::string conf = lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock.conf";
    std::vector<std::vector<uint8_t>> packs;
    for (uint32_t threads : {1u, 2u}) {
        Diagnostics diagnostics;
        Result<LoadedMesh> loaded = readMesh(conf, ReadOptions(), diagnostics);
        ASSERT_TRUE(loaded.ok()) << loaded.status().message();
        std::vector<BakeInput> inputs(1);
        inputs[0].name = "rock";
        inputs[0].mesh = std::move(loaded->mesh);
        BakeSettings settings;
        settings.threads = threads;
        Result<BakeOutput> out = bake(std::move(inputs), settings, diagnostics);
        ASSERT_TRUE(out.ok()) << out.status().message();
        ASSERT_EQ(out->assets.size(), 1u);
        const BakeAssetReport& a = out->assets[0];
        EXPECT_EQ(a.merge.size(), 3u);
        EXPECT_NE(a.merge[0].find("merged 6 scans"), std::string::npos) << a.merge[0];
        for (const std::string& u : a.repair_unresolved)
            EXPECT_EQ(u.find("components remain"), std::string::npos) << u;
        // The coarsest level keeps the rock's shape: its error stays a few percent of the diagonal.
        EXPECT_LT(a.metrics.levels.back().hausdorff_error, 0.03 * 0.146827);
        packs.push_back(std::move(out->glb));
    }
    EXPECT_EQ(packs[0], packs[1]);
}

// `auto` is a no-op on single surfaces: the pack is byte-identical to `off`.
TEST(MergeBakeTest, AutoLeavesSingleSurfacesByteIdentical) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string dir = lodbake_test::scratchDir();
    for (const char* name : {"bunny_zipper.ply", "nefertiti.obj", "lucy100k.ply", "igea.ply"}) {
        std::vector<std::string> shas;
        for (const char* mode : {"auto", "off"}) {
            const std::string out = dir + "/merge_noop_" + mode + ".glb";
            const lodbake_test::CliRun r =
                lodbake_test::runLodbake({"bake", lodbake_test::sharedMesh(name), "-o", out, "--merge", mode,
                                          "--levels", "0.1", "--no-progressive-fans", "--quiet"});
            ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
            EXPECT_EQ(r.err.find("merge:"), std::string::npos) << name << ": " << r.err;
            shas.push_back(lodbake_test::readTextFile(out));
            ASSERT_FALSE(shas.back().empty());
        }
        EXPECT_TRUE(shas[0] == shas[1]) << name << ": --merge auto changed the pack";
    }
}

TEST(MergeCliTest, UsageErrorsAndBadInput) {
    const std::string dir = lodbake_test::scratchDir();
    EXPECT_EQ(lodbake_test::runLodbake({"merge"}).exit_code, 2);
    EXPECT_EQ(lodbake_test::runLodbake({"merge", "a.ply"}).exit_code, 2);
    EXPECT_EQ(lodbake_test::runLodbake({"merge", "a.ply", "-o", dir + "/m.ply", "--depth", "99"}).exit_code, 2);
    EXPECT_EQ(lodbake_test::runLodbake({"merge", "a.ply", "-o", dir + "/m.ply", "--trim", "x"}).exit_code, 2);
    EXPECT_EQ(lodbake_test::runLodbake({"bake", "a.ply", "-o", dir + "/m.glb", "--merge", "vrip"}).exit_code, 2);
    const lodbake_test::CliRun help = lodbake_test::runLodbake({"merge", "--help"});
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("usage: lodbake merge"), std::string::npos);

    // A single triangle cannot define a surface: one error line naming the file, no output.
    const std::string in = dir + "/merge_one_triangle.ply";
    {
        Mesh tri;
        tri.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        tri.indices = {0, 1, 2};
        Diagnostics d;
        ASSERT_TRUE(writeMesh(tri, in, WriteOptions(), d).ok());
    }
    const std::string out = dir + "/merge_one_triangle_out.ply";
    std::filesystem::remove(out);
    const lodbake_test::CliRun r = lodbake_test::runLodbake({"merge", in, "-o", out});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(r.err, "error: " + in + ": merge: expected at least 64 samples on triangles, got 3\n");
    EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(MergeCliTest, RockReportsWhatWasMerged) {
    const std::string conf = lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock.conf";
    const std::string out = lodbake_test::scratchDir() + "/merge_rock.ply";
    const lodbake_test::CliRun r = lodbake_test::runLodbake({"merge", conf, "-o", out});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("merged 6 scans, "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("density trim removed"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("95th percentile"), std::string::npos) << r.out;
    Diagnostics d;
    Result<LoadedMesh> merged = readMesh(out, ReadOptions(), d);
    ASSERT_TRUE(merged.ok());
    EXPECT_EQ(componentCount(merged->mesh), 1u);
}

// The overlap test on real scans: the 15 registered dragon scans are sheets; one raw view with its
// speckle, and the bunny's single range image, are not.
TEST(MergeTest, RegisteredScansAreSheetsAndASingleViewIsNot) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    auto fraction = [](const char* name) {
        Diagnostics d;
        Result<LoadedMesh> loaded = readMesh(lodbake_test::sharedMesh(name), ReadOptions(), d);
        EXPECT_TRUE(loaded.ok()) << name;
        return loaded.ok() ? overlappingSheetFraction(loaded->mesh) : -1.0;
    };
    EXPECT_GE(fraction("dragon_stand_merged.ply"), kOverlappingSheetFraction);
    EXPECT_LT(fraction("dragon_scan_stand0_tri.ply"), kOverlappingSheetFraction);
    EXPECT_LT(fraction("bunny_scan_bun000_tri.ply"), kOverlappingSheetFraction);
    EXPECT_EQ(fraction("fandisk.obj"), 0.0);
}
