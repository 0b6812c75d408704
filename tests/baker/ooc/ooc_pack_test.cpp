// The pack of an out-of-core bake (lodbake/ooc/ooc_pack.h) and its CLI route: a generated scan cut
// into several partitions and merge rounds, forced out of core by a small limit. The pack loads in
// lodrt with its chain's triangle counts near the ratios, LODBAKE_cluster_lod on the chain's finest
// level, the metrics saying where the chain starts; the same bytes at 1 and 2 threads and at two
// limits that keep the same levels; a smaller limit drops the finest levels; a failed bake leaves no
// output and no work files; the Khronos validator accepts the pack. Through the CLI, the same input
// over the limit bakes with --clusters and is refused without it (the control that the route, not
// an in-memory bake, made the pack).

#include "lodbake/ooc/ooc_pack.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "../gltf/gltf_test_util.h"
#include "cli_runner.h"
#include "lodbake/bake/memory_budget.h"
#include "lodbake/core/file_io.h"
#include "lodbake/io/mesh_io.h"
#include "lodbake/simplify/mesh_distance.h"
#include "lodrt/cluster_pack.h"
#include "lodrt/format.h"
#include "lodrt/model.h"
#include "lodrt/pack.h"
#include "scansim.h"
#include "test_paths.h"

namespace fs = std::filesystem;
using namespace lodbake::ooc;

namespace {

// scansim rounds the count to its grid (60,060 for this target); the tests take the driver's count.
constexpr uint64_t kScanTriangles = 60000;

std::string packDir(const std::string& name) {
    const std::string dir = lodbake_test::scratchDir() + "/ooc_pack/" + name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::vector<std::string> filesUnder(const std::string& dir) {
    std::vector<std::string> names;
    if (fs::exists(dir))
        for (const auto& e : fs::recursive_directory_iterator(dir)) names.push_back(e.path().string());
    std::sort(names.begin(), names.end());
    return names;
}

std::string packScan(const std::string& dir, uint64_t triangles = kScanTriangles) {
    lodbake::scansim::SurfaceOptions so;
    so.triangles = triangles;
    const std::string scan = dir + "/scan.ply";
    EXPECT_TRUE(lodbake::scansim::writeSurfacePly(so, scan).ok());
    return scan;
}

// As the driver's tests: partitions of about 12,000 triangles, so the scan makes several partitions
// and merge rounds.
OocPackOptions packOptions(const std::string& work, uint64_t limit_mib, int threads) {
    OocPackOptions o;
    o.driver.work_dir = work;
    o.driver.memory_limit_bytes = limit_mib << 20;
    o.driver.threads = threads;
    o.driver.read.buffer_bytes = 64 << 10;
    o.driver.read.max_record_bytes = 256 << 10;
    o.driver.read.vertex_chunk = 4096;
    o.driver.read.triangle_chunk = 4096;
    o.driver.sample_cap = 4096;
    o.driver.leaf_triangles = 12000;
    o.driver.merge_group_bytes = uint64_t(8) << 20;
    o.name = "scan";
    return o;
}

struct PackRun {
    lodbake::Result<OocPackResult> result = lodbake::internalError("not run");
    std::vector<uint8_t> glb;
};

PackRun runPack(const std::string& scan, const std::string& out, const OocPackOptions& o) {
    PackRun r;
    lodbake::Diagnostics d;
    r.result = writeOutOfCorePack(scan, out, o, d);
    if (!r.result.ok()) return r;
    auto bytes = lodbake::readFileBytes(out);
    EXPECT_TRUE(bytes.ok());
    if (bytes.ok()) r.glb = std::move(*bytes);
    return r;
}

// The budget the levels get at a limit is the limit less the table and fixed bytes: this limit (MiB)
// keeps every level but the input's when `tight`, and every level with room to spare otherwise.
uint64_t keptLevels(const OocPackResult& r) {
    uint64_t n = 0;
    for (const OocPackLevel& l : r.levels) n += l.kept ? 1 : 0;
    return n;
}

struct LoadedPack {
    lodrt::Pack pack;
    lodrt::ModelSet models;
};

void loadInLodrt(const std::vector<uint8_t>& glb, LoadedPack& out) {
    char message[256] = "";
    ASSERT_EQ(lodrt::loadPack(glb.data(), glb.size(), nullptr, &out.pack, message, sizeof(message)),
              lodrt::Result::Ok)
        << message;
    ASSERT_EQ(lodrt::buildModels(out.pack, nullptr, &out.models, message, sizeof(message)), lodrt::Result::Ok)
        << message;
}

TEST(OocPackTest, ChainNearTheRatiosWithTheClustersOnItsFinestLevel) {
    const std::string dir = packDir("chain");
    const std::string scan = packScan(dir);
    OocPackOptions o = packOptions(dir + "/work", 256, 2);
    o.lod_ratios = {0.5, 0.25, 0.1, 0.03};
    const PackRun run = runPack(scan, dir + "/out.glb", o);
    ASSERT_TRUE(run.result.ok()) << run.result.status().message();
    const OocPackResult& r = *run.result;
    EXPECT_GT(r.driver.partition_count, 2u);
    EXPECT_GT(r.driver.merge_count, 1u);
    EXPECT_NEAR(double(r.input_triangles), double(kScanTriangles), 0.01 * kScanTriangles);
    ASSERT_EQ(r.levels.size(), 5u); // the input and four ratios, each a distinct cut
    for (const OocPackLevel& l : r.levels) {
        EXPECT_TRUE(l.kept) << l.ratio;
        // Nearest cut to the target: within 10 % of it (the cut moves a group at a time).
        EXPECT_NEAR(double(l.cut.triangles), double(l.target_triangles), 0.1 * double(l.target_triangles)) << l.ratio;
    }
    EXPECT_EQ(r.levels[0].cut.triangles, r.input_triangles); // the cut at 0 is LOD0: the input
    EXPECT_LE(r.level_peak_bytes, r.level_budget_bytes);

    LoadedPack loaded;
    loadInLodrt(run.glb, loaded);
    ASSERT_EQ(loaded.models.modelCount(), 1u);
    const lodrt::ModelInfo& model = loaded.models.model(0);
    ASSERT_EQ(model.level_count, 5u);
    EXPECT_EQ(model.error_source, lodrt::ErrorSource::Measured);
    EXPECT_EQ(model.input_triangle_count, r.input_triangles);
    float previous_error = -1;
    for (uint32_t l = 0; l < model.level_count; ++l) {
        const lodrt::LevelInfo& level = loaded.models.modelLevel(0, l);
        EXPECT_EQ(level.triangle_count, r.metrics.levels[l].triangles);
        // Level 0 is the cut (welding drops only triangles it made degenerate); the coarser levels are
        // the simplifier's, run on it down to the same targets.
        EXPECT_EQ(r.levels[l].simplified, l > 0) << l;
        const double expected = l == 0 ? double(r.levels[l].cut.triangles) : double(r.levels[l].target_triangles);
        EXPECT_NEAR(double(level.triangle_count), expected, 0.01 * expected) << l;
        EXPECT_GE(level.hausdorff_error, previous_error);
        previous_error = level.hausdorff_error;
        lodrt::ClusterPackSource source;
        const lodrt::Result found = lodrt::clusterPackFind(loaded.pack, level.mesh, &source);
        EXPECT_EQ(found, l == 0 ? lodrt::Result::Ok : lodrt::Result::NotLoaded) << l;
        if (l == 0) {
            EXPECT_GT(source.table_size, 64u);
            EXPECT_GT(source.pages_size, 0u);
        }
    }
    EXPECT_EQ(loaded.models.modelLevel(0, 0).hausdorff_error, 0.0f); // the input itself
    EXPECT_GT(loaded.models.modelLevel(0, 4).hausdorff_error, 0.0f);
    EXPECT_TRUE(filesUnder(dir + "/work").empty()) << filesUnder(dir + "/work").front();
}

// Level `mesh` of a pack (not compact): its positions and triangles from the GLB's accessors.
lodbake::Mesh glbLevelMesh(const std::vector<uint8_t>& glb, uint32_t mesh) {
    const nlohmann::json json = lodbake_test::glbJson(glb);
    const std::vector<uint8_t> bin = lodbake_test::glbBin(glb);
    const nlohmann::json& primitive = json["meshes"][mesh]["primitives"][0];
    auto accessorBytes = [&](const nlohmann::json& accessor, size_t& count) {
        const nlohmann::json& view = json["bufferViews"][accessor["bufferView"].get<size_t>()];
        count = accessor["count"].get<size_t>();
        return bin.data() + view.value("byteOffset", size_t(0)) + accessor.value("byteOffset", size_t(0));
    };
    lodbake::Mesh m;
    size_t count = 0;
    const nlohmann::json& position = json["accessors"][primitive["attributes"]["POSITION"].get<size_t>()];
    EXPECT_EQ(position["componentType"].get<int>(), 5126);
    const uint8_t* p = accessorBytes(position, count);
    m.positions.resize(count);
    std::memcpy(m.positions.data(), p, count * 12);
    const nlohmann::json& index = json["accessors"][primitive["indices"].get<size_t>()];
    const uint8_t* q = accessorBytes(index, count);
    const int type = index["componentType"].get<int>();
    m.indices.resize(count);
    for (size_t i = 0; i < count; ++i) {
        if (type == 5125) std::memcpy(&m.indices[i], q + 4 * i, 4);
        else if (type == 5123) {
            uint16_t v = 0;
            std::memcpy(&v, q + 2 * i, 2);
            m.indices[i] = v;
        } else {
            ADD_FAILURE() << "index type " << type;
        }
    }
    return m;
}

// Each recorded level error is the level's measured distance to the input: the level read back
// from the pack and measured in memory against the whole input (its triangles in file order, so
// other samples of the same surface: within sampling noise), never the cut's bound. The control:
// the same level shifted by 1 % of the diagonal measures far outside that tolerance.
TEST(OocPackTest, RecordedErrorsAreTheLevelsMeasuredAgainstTheInput) {
    const std::string dir = packDir("measured");
    const std::string scan = packScan(dir);
    OocPackOptions o = packOptions(dir + "/work", 256, 2);
    o.distance.sample_count = 50000;
    const PackRun run = runPack(scan, dir + "/out.glb", o);
    ASSERT_TRUE(run.result.ok()) << run.result.status().message();
    const OocPackResult& r = *run.result;
    ASSERT_EQ(keptLevels(r), r.levels.size());
    ASSERT_GE(r.levels.size(), 4u);
    EXPECT_EQ(r.levels[0].error_source, LevelErrorSource::Input);
    for (size_t l = 1; l < r.levels.size(); ++l) EXPECT_EQ(r.levels[l].error_source, LevelErrorSource::Measured) << l;
    EXPECT_EQ(r.measured_levels, r.levels.size() - 1);
    EXPECT_GT(r.measure_bound_bytes, 0u);
    EXPECT_LE(r.measure_peak_bytes, r.measure_bound_bytes);
    EXPECT_LE(r.level_peak_bytes, r.level_budget_bytes);

    lodbake::Diagnostics d;
    auto input = lodbake::readMesh(scan, lodbake::ReadOptions(), d);
    ASSERT_TRUE(input.ok());
    lodbake::DistanceOptions distance;
    distance.sample_count = 50000;
    LoadedPack loaded;
    loadInLodrt(run.glb, loaded);
    ASSERT_EQ(loaded.models.model(0).level_count, r.levels.size());
    EXPECT_EQ(loaded.models.modelLevel(0, 0).hausdorff_error, 0.0f);
    double finer_h = 0, finer_mean = 0;
    for (uint32_t l = 1; l < r.levels.size(); ++l) {
        const lodrt::LevelInfo& level = loaded.models.modelLevel(0, l);
        const lodbake::Mesh mesh = glbLevelMesh(run.glb, level.mesh);
        ASSERT_EQ(mesh.faceCount(), level.triangle_count);
        auto mem = lodbake::measureSurfaceDistance(input->mesh, mesh, distance);
        ASSERT_TRUE(mem.ok());
        // The recorded errors keep the chain's rule: at least the finer level's.
        finer_h = std::max(finer_h, mem->hausdorff);
        finer_mean = std::max(finer_mean, mem->mean);
        EXPECT_NEAR(level.hausdorff_error, finer_h, 0.1 * finer_h) << l;
        EXPECT_NEAR(level.mean_error, finer_mean, 0.03 * finer_mean) << l;
        EXPECT_NEAR(r.metrics.levels[l].mean_error, finer_mean, 0.03 * finer_mean) << l;
        // Not the bound, which was recorded as both errors: the measured mean is far below it. (The
        // Hausdorff error can equal it: a group's error is its largest vertex distance, which the
        // measurement also finds when the cut is one level above the input.)
        const double bound = r.levels[l].cut.error_bound;
        EXPECT_LT(level.mean_error, 0.5 * bound) << l;
        // Control: a level 1 % of the diagonal away measures outside the tolerance.
        lodbake::Mesh shifted = mesh;
        for (lodbake::Vec3f& p : shifted.positions) p.x += float(0.01 * mem->diagonal);
        auto off = lodbake::measureSurfaceDistance(input->mesh, shifted, distance);
        ASSERT_TRUE(off.ok());
        EXPECT_GT(std::fabs(off->mean - level.mean_error), 0.03 * finer_mean) << l;
    }
}

// A limit that holds every level but not their measurement (its bound, beside the extracted meshes):
// the finest levels record their cut's bound, the coarsest that fit are measured, and a note says so.
TEST(OocPackTest, MeasurementThatDoesNotFitFallsBackToTheBoundWithANote) {
    const std::string dir = packDir("fallback");
    const std::string scan = packScan(dir);
    OocPackOptions o = packOptions(dir + "/work", 256, 2);
    const PackRun wide = runPack(scan, dir + "/wide.glb", o);
    ASSERT_TRUE(wide.result.ok()) << wide.result.status().message();
    const OocPackResult& w = *wide.result;
    ASSERT_EQ(keptLevels(w), w.levels.size());
    uint64_t held = 0, work = 0, meshes = 0;
    for (const OocPackLevel& l : w.levels) {
        held += l.held_bytes;
        work = std::max(work, l.work_bytes);
        meshes += 12 * l.cut.cluster_vertices + 12 * l.cut.triangles;
    }
    ASSERT_GT(meshes + w.measure_bound_bytes, held + work) << "the measurement would fit wherever the levels do";
    const uint64_t fixed = (uint64_t(256) << 20) - w.level_budget_bytes;
    o.driver.memory_limit_bytes = ((fixed + held + work) | ((uint64_t(1) << 20) - 1)) + 1; // rounded up to a MiB
    ASSERT_LT(o.driver.memory_limit_bytes - fixed, meshes + w.measure_bound_bytes);
    lodbake::Diagnostics d;
    auto r = writeOutOfCorePack(scan, dir + "/tight.glb", o, d);
    ASSERT_TRUE(r.ok()) << r.status().message();
    ASSERT_EQ(keptLevels(*r), r->levels.size());
    EXPECT_EQ(r->levels[0].error_source, LevelErrorSource::Input);
    EXPECT_EQ(r->levels[1].error_source, LevelErrorSource::Bound);
    uint64_t measured = 0;
    for (size_t l = 1; l < r->levels.size(); ++l) {
        const bool is_measured = r->levels[l].error_source == LevelErrorSource::Measured;
        measured += is_measured;
        if (!is_measured) {
            EXPECT_EQ(r->levels[l].error_source, LevelErrorSource::Bound) << l;
            EXPECT_EQ(measured, 0u) << "a bound level coarser than a measured one: " << l;
            EXPECT_GE(r->metrics.levels[l].hausdorff_error, double(r->levels[l].cut.error_bound)) << l;
        }
    }
    EXPECT_EQ(r->measured_levels, measured);
    EXPECT_LE(r->level_peak_bytes, r->level_budget_bytes);
    bool noted = false;
    for (const lodbake::Diagnostic& item : d.items())
        noted |= item.message.find("error bound") != std::string::npos && item.message.find(scan) != std::string::npos;
    EXPECT_TRUE(noted);
    EXPECT_TRUE(filesUnder(dir + "/work").empty());
}

TEST(OocPackTest, SmallerLimitStartsTheChainBelowTheInputAndSaysSo) {
    const std::string dir = packDir("below");
    const std::string scan = packScan(dir);
    OocPackOptions o = packOptions(dir + "/work", 256, 2);
    const PackRun wide = runPack(scan, dir + "/wide.glb", o);
    ASSERT_TRUE(wide.result.ok()) << wide.result.status().message();
    ASSERT_GE(wide.result->levels.size(), 3u);
    // A limit whose level budget holds every level but the input's.
    const std::vector<OocPackLevel>& levels = wide.result->levels;
    uint64_t held = 0, work = 0;
    for (size_t i = 1; i < levels.size(); ++i) {
        held += levels[i].held_bytes;
        work = std::max(work, levels[i].work_bytes);
    }
    const uint64_t fixed = (uint64_t(256) << 20) - wide.result->level_budget_bytes;
    const uint64_t needed = fixed + held + work;
    const uint64_t limit_mib = (needed + (uint64_t(1) << 20) - 1) >> 20;
    ASSERT_GT(needed + levels[0].held_bytes + std::max(work, levels[0].work_bytes) - work, limit_mib << 20)
        << "the input's level would fit too";
    o.driver.memory_limit_bytes = limit_mib << 20;
    const PackRun tight = runPack(scan, dir + "/tight.glb", o);
    ASSERT_TRUE(tight.result.ok()) << tight.result.status().message();
    EXPECT_FALSE(tight.result->levels[0].kept);
    EXPECT_EQ(keptLevels(*tight.result), levels.size() - 1);
    // The simplifier's allowance for the finest kept level does not fit this budget: every level is a
    // cut (the wide run's coarser levels are the simplifier's).
    EXPECT_TRUE(wide.result->levels.back().simplified);
    for (const OocPackLevel& l : tight.result->levels) EXPECT_FALSE(l.simplified) << l.ratio;
    ASSERT_LT(tight.result->level_budget_bytes, lodbake::kBakeBytesPerTriangle * tight.result->levels[1].cut.triangles);
    LoadedPack loaded;
    loadInLodrt(tight.glb, loaded);
    ASSERT_EQ(loaded.models.modelCount(), 1u);
    const lodrt::ModelInfo& model = loaded.models.model(0);
    EXPECT_EQ(model.level_count, levels.size() - 1);
    EXPECT_EQ(model.input_triangle_count, wide.result->input_triangles);
    const lodrt::LevelInfo& first = loaded.models.modelLevel(0, 0);
    EXPECT_LT(first.triangle_count, wide.result->input_triangles);
    EXPECT_GT(first.hausdorff_error, 0.0f); // a cut's error, allowed on level 0 with inputTriangles
    EXPECT_EQ(first.switch_distance, 0.0f);
    lodrt::ClusterPackSource source;
    ASSERT_EQ(lodrt::clusterPackFind(loaded.pack, first.mesh, &source), lodrt::Result::Ok);
    EXPECT_EQ(tight.result->metrics.input_triangles, wide.result->input_triangles);
    // The same table and pages as with every level kept: the hierarchy does not depend on the limit.
    LoadedPack wide_loaded;
    loadInLodrt(wide.glb, wide_loaded);
    lodrt::ClusterPackSource wide_source;
    ASSERT_EQ(lodrt::clusterPackFind(wide_loaded.pack, wide_loaded.models.modelLevel(0, 0).mesh, &wide_source),
              lodrt::Result::Ok);
    ASSERT_TRUE(source.table && source.pages && wide_source.table && wide_source.pages);
    EXPECT_EQ(std::vector<uint8_t>(source.table, source.table + source.table_size),
              std::vector<uint8_t>(wide_source.table, wide_source.table + wide_source.table_size));
    EXPECT_EQ(std::vector<uint8_t>(source.pages, source.pages + source.pages_size),
              std::vector<uint8_t>(wide_source.pages, wide_source.pages + wide_source.pages_size));
}

TEST(OocPackTest, SameBytesAtAnyThreadCountAndAtTwoLimitsKeepingTheSameLevels) {
    const std::string dir = packDir("same");
    const std::string scan = packScan(dir);
    const PackRun one = runPack(scan, dir + "/one.glb", packOptions(dir + "/work", 256, 1));
    const PackRun two = runPack(scan, dir + "/two.glb", packOptions(dir + "/work", 256, 2));
    const PackRun other = runPack(scan, dir + "/other.glb", packOptions(dir + "/work", 192, 2));
    ASSERT_TRUE(one.result.ok() && two.result.ok() && other.result.ok());
    ASSERT_EQ(keptLevels(*one.result), keptLevels(*other.result));
    // Both limits hold the simplifier beside the levels: the coarser levels are its, at both.
    EXPECT_TRUE(one.result->levels.back().simplified);
    EXPECT_TRUE(other.result->levels.back().simplified);
    EXPECT_FALSE(one.glb.empty());
    EXPECT_EQ(one.glb, two.glb);
    EXPECT_EQ(one.glb, other.glb);
}

TEST(OocPackTest, FailureLeavesNoOutputAndNoWorkFiles) {
    const std::string dir = packDir("fail");
    const std::string scan = packScan(dir);
    // A cancel before the first job.
    std::atomic<bool> cancel{true};
    OocPackOptions o = packOptions(dir + "/work", 256, 2);
    o.driver.cancel = &cancel;
    PackRun cancelled = runPack(scan, dir + "/out.glb", o);
    EXPECT_FALSE(cancelled.result.ok());
    // A limit that holds the hierarchy's jobs but no discrete level: the failure comes after the
    // driver has written every file.
    o = packOptions(dir + "/work", 256, 2);
    o.level_errors = [](const std::vector<LevelCut>&) -> lodbake::Result<std::vector<LevelError>> {
        return lodbake::invalidInput("measurement refused");
    };
    PackRun refused = runPack(scan, dir + "/out.glb", o);
    ASSERT_FALSE(refused.result.ok());
    EXPECT_NE(refused.result.status().message().find("measurement refused"), std::string::npos);
    // An output folder that does not exist: the GLB's write fails at the very end.
    o = packOptions(dir + "/work", 256, 2);
    PackRun unwritable = runPack(scan, dir + "/missing/out.glb", o);
    ASSERT_FALSE(unwritable.result.ok());
    EXPECT_NE(unwritable.result.status().message().find(dir + "/missing/out.glb"), std::string::npos)
        << unwritable.result.status().message();
    EXPECT_FALSE(fs::exists(dir + "/out.glb"));
    EXPECT_FALSE(fs::exists(dir + "/work")); // created by the run, removed with it
    std::vector<std::string> left = filesUnder(dir);
    EXPECT_EQ(left, std::vector<std::string>{dir + "/scan.ply"});
}

// ---- The CLI route ------------------------------------------------------------------------------

std::string nodeExecutable() { return LODBAKE_TEST_NODE; }

TEST(OocPackCliTest, ClustersBakeOverTheLimitOutOfCoreAndTheValidatorAcceptsThePack) {
    const std::string dir = packDir("cli");
    const std::string scan = packScan(dir);
    // 60,060 triangles are allowed 96 MiB + 640 B each (133 MiB) in memory: 100 MiB is over it.
    const std::string out = dir + "/scan.glb";
    const lodbake_test::CliRun refused =
        lodbake_test::runLodbake({"bake", scan, "--memory-limit", "100", "-o", out});
    EXPECT_EQ(refused.exit_code, 1) << refused.err;
    EXPECT_NE(refused.err.find("--clusters"), std::string::npos) << refused.err;
    EXPECT_FALSE(fs::exists(out));
    const lodbake_test::CliRun baked = lodbake_test::runLodbake(
        {"bake", scan, "--clusters", "--memory-limit", "100", "--threads", "2", "--report", dir + "/r.json", "-o", out});
    ASSERT_EQ(baked.exit_code, 0) << baked.err;
    ASSERT_TRUE(fs::exists(out));
    EXPECT_NE(lodbake_test::readTextFile(dir + "/r.json").find("\"outOfCore\""), std::string::npos);
    // Nothing but the input, the pack and the report next to them: the work folder is gone.
    EXPECT_EQ(filesUnder(dir), (std::vector<std::string>{dir + "/r.json", dir + "/scan.glb", dir + "/scan.ply"}));
    auto glb = lodbake::readFileBytes(out);
    ASSERT_TRUE(glb.ok());
    LoadedPack loaded;
    loadInLodrt(*glb, loaded);
    ASSERT_EQ(loaded.models.modelCount(), 1u);
    const uint64_t input_triangles = loaded.models.model(0).input_triangle_count;
    EXPECT_NEAR(double(input_triangles), double(kScanTriangles), 0.01 * kScanTriangles);
    // The same bytes at one thread, and through a --work-dir.
    const std::string one = dir + "/one/scan.glb";
    fs::create_directories(dir + "/one");
    const lodbake_test::CliRun again = lodbake_test::runLodbake({"bake", scan, "--clusters", "--memory-limit", "100",
                                                                 "--threads", "1", "--work-dir", dir + "/w", "-o", one});
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(lodbake::readFileBytes(one).value(), *glb);
    EXPECT_FALSE(fs::exists(dir + "/w"));
    // loddump says where the chain starts, in text and JSON.
    const std::string dump = std::string(LODBAKE_TEST_LODDUMP);
    const lodbake_test::CommandResult text = lodbake_test::runCommand(lodbake_test::shellQuote(dump) + " " + lodbake_test::shellQuote(out));
    EXPECT_NE(text.output.find("input: " + std::to_string(input_triangles) + " triangles"), std::string::npos)
        << text.output;
    const lodbake_test::CommandResult json =
        lodbake_test::runCommand(lodbake_test::shellQuote(dump) + " --json " + lodbake_test::shellQuote(out));
    EXPECT_NE(json.output.find("\"inputTriangles\": " + std::to_string(input_triangles)), std::string::npos)
        << json.output;
    // The Khronos validator.
    const std::string node = nodeExecutable();
    ASSERT_TRUE(!node.empty() && node.find("NOTFOUND") == std::string::npos && fs::exists(node));
    const lodbake_test::CommandResult valid = lodbake_test::runCommand(
        lodbake_test::shellQuote(node) + " " +
        lodbake_test::shellQuote(lodbake_test::sourceDir() + "/scripts/node/validate-gltf.js") + " " +
        lodbake_test::shellQuote(out));
    EXPECT_EQ(valid.exit_code, 0) << valid.output;
}

std::vector<std::string> outputLines(const std::string& out) {
    std::vector<std::string> lines;
    std::string line;
    for (char c : out) {
        if (c != '\n') line += c;
        else lines.push_back(line), line.clear();
    }
    return lines;
}

// A farm's bake: --plan and each job in processes of their own, the last --plan with -o writing
// the pack, gives the bytes of the in-process `lodbake bake --clusters --memory-limit N` of the same
// input. 90 MiB makes partitions of 131,072 triangles (leafTrianglesForLimit), so a scan of 300,000
// is three partitions and their merges. Once the pack is written the plan's files are gone.
TEST(OocPackCliTest, PlannedBakeWritesTheInProcessPack) {
    const std::string dir = packDir("cli_plan");
    const std::string scan = packScan(dir, 300000);
    const std::string limit = "90";
    const std::string reference = dir + "/ref/scan.glb";
    fs::create_directories(dir + "/ref");
    const lodbake_test::CliRun baked = lodbake_test::runLodbake(
        {"bake", scan, "--clusters", "--memory-limit", limit, "--threads", "2", "-o", reference});
    ASSERT_EQ(baked.exit_code, 0) << baked.err;
    const std::string work = dir + "/work", out = dir + "/farm/scan.glb";
    fs::create_directories(dir + "/farm");
    bool finished = false;
    size_t partitions = 0, jobs = 0;
    for (int step = 0; step < 20 && !finished; ++step) {
        const lodbake_test::CliRun plan = lodbake_test::runLodbake(
            {"bake", scan, "--clusters", "--plan", "--work-dir", work, "--memory-limit", limit, "-o", out});
        ASSERT_EQ(plan.exit_code, 0) << plan.err;
        const std::vector<std::string> lines = outputLines(plan.out);
        ASSERT_FALSE(lines.empty());
        finished = lines.size() == 1;
        // The pack is written only by the --plan that finds every job done.
        EXPECT_EQ(fs::exists(out), finished);
        for (size_t i = 1; i < lines.size(); ++i) {
            partitions += lines[i].rfind("partition-", 0) == 0;
            ++jobs;
            const lodbake_test::CliRun job = lodbake_test::runLodbake(
                {"bake", "--run-job", lines[i], "--work-dir", work, "--memory-limit", limit, "--threads", "1"});
            ASSERT_EQ(job.exit_code, 0) << job.err;
        }
    }
    ASSERT_TRUE(finished);
    EXPECT_GE(partitions, 3u);
    EXPECT_GT(jobs, partitions + 1); // merges and the pages job
    auto farm = lodbake::readFileBytes(out);
    auto ref = lodbake::readFileBytes(reference);
    ASSERT_TRUE(farm.ok() && ref.ok());
    EXPECT_FALSE(ref->empty());
    EXPECT_EQ(*farm, *ref);
    EXPECT_TRUE(filesUnder(work).empty()) << filesUnder(work).front();
    // --output belongs to --plan only.
    const lodbake_test::CliRun wrong =
        lodbake_test::runLodbake({"bake", "--run-job", "pages", "--work-dir", work, "-o", out});
    EXPECT_EQ(wrong.exit_code, 2) << wrong.err;
}

TEST(OocPackCliTest, AFailedOutOfCoreBakeLeavesNoOutputAndNoWorkFiles) {
    const std::string dir = packDir("cli_fail");
    const std::string scan = packScan(dir);
    // 8 MiB holds none of the partitioner's buffers: the driver refuses, naming the input.
    const std::string out = dir + "/scan.glb";
    const lodbake_test::CliRun r = lodbake_test::runLodbake({"bake", scan, "--clusters", "--memory-limit", "8", "-o", out});
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(scan), std::string::npos) << r.err;
    EXPECT_EQ(filesUnder(dir), std::vector<std::string>{scan});
}

} // namespace
