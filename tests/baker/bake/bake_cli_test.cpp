// `lodbake bake` end to end: the bundled sample and shared scans baked into packs that pass the
// Khronos validator, whose LODBAKE_lod_metrics objects match their schema, that loddump reads
// without failed checks, and whose bytes do not depend on the thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "../gltf/gltf_test_util.h"
#include "lodbake/core/file_io.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;

std::string outDir() {
    const std::string dir = lodbake_test::scratchDir() + "/bake_cli";
    fs::create_directories(dir);
    return dir;
}

std::string src(const std::string& relative) {
    return lodbake_test::sourceDir() + "/" + relative;
}

CommandResult bake(const std::string& args) {
    return runCommand(shellQuote(lodbake_test::lodbakeCli()) + " bake " + args);
}

CommandResult loddump(const std::string& args) {
    return runCommand(shellQuote(LODBAKE_TEST_LODDUMP) + " " + args);
}

CommandResult validateGltf(const std::vector<std::string>& files) {
    std::string command = shellQuote(LODBAKE_TEST_NODE) + " " + shellQuote(src("scripts/node/validate-gltf.js"));
    for (const std::string& f : files) command += " " + shellQuote(f);
    return runCommand(command);
}

CommandResult validateMetrics(const std::vector<std::string>& files) {
    std::string command = lodbake_test::python() + " " + shellQuote(src("tests/support/validate_schema.py")) + " " +
                          shellQuote(src("schemas/LODBAKE_lod_metrics/schema/node.LODBAKE_lod_metrics.schema.json")) +
                          " --node-extension LODBAKE_lod_metrics";
    for (const std::string& f : files) command += " " + shellQuote(f);
    return runCommand(command);
}

std::vector<uint8_t> bytesOf(const std::string& path) {
    auto r = lodbake::readFileBytes(path);
    return r.ok() ? *r : std::vector<uint8_t>();
}

// One test so the sample is baked once per process (ctest runs every test in its own process).
TEST(BakeCliTest, RockSampleBakesIntoAValidDeterministicPackThatLoddumpReads) {
    const std::string rock1 = outDir() + "/rock_t1.glb";
    const std::string rock2 = outDir() + "/rock_t2.glb";
    const std::string report_path = outDir() + "/rock_report.json";
    const std::string in = shellQuote(src("assets/samples/rock_scan/rock.conf"));
    const std::string preset = " --preset " + shellQuote(src("configs/desktop.json"));
    const CommandResult run1 =
        bake(in + preset + " --threads 1 -o " + shellQuote(rock1) + " --report " + shellQuote(report_path));
    const CommandResult run2 = bake(in + preset + " --threads 2 -o " + shellQuote(rock2));
    ASSERT_EQ(run1.exit_code, 0) << run1.output;
    {
        SCOPED_TRACE("RockSampleBakesIntoAValidPack");
        EXPECT_NE(run1.output.find("6 levels"), std::string::npos) << run1.output;
        const CommandResult v = validateGltf({rock1});
        EXPECT_EQ(v.exit_code, 0) << v.output;
        EXPECT_NE(v.output.find("errors 0 warnings 0"), std::string::npos) << v.output;
        const CommandResult m = validateMetrics({rock1});
        EXPECT_EQ(m.exit_code, 0) << m.output;
    }
    {
        SCOPED_TRACE("SameBytesForOneAndTwoThreads");
        ASSERT_EQ(run2.exit_code, 0) << run2.output;
        const std::vector<uint8_t> a = bytesOf(rock1), b = bytesOf(rock2);
        ASSERT_FALSE(a.empty());
        EXPECT_TRUE(a == b) << "thread count changed the pack";
    }
    {
        SCOPED_TRACE("PackHasMsftLodChainAndMonotoneMetrics");
        const std::vector<uint8_t> glb = bytesOf(rock1);
        const nlohmann::json doc = lodbake_test::glbJson(glb);
        ASSERT_EQ(doc["scenes"][0]["nodes"].size(), 1u);
        const nlohmann::json& root = doc["nodes"][doc["scenes"][0]["nodes"][0].get<int>()];
        const nlohmann::json& ids = root["extensions"]["MSFT_lod"]["ids"];
        ASSERT_EQ(ids.size(), 5u);
        const nlohmann::json& coverage = root["extras"]["MSFT_screencoverage"];
        ASSERT_EQ(coverage.size(), 6u);
        const nlohmann::json& levels = root["extensions"]["LODBAKE_lod_metrics"]["levels"];
        ASSERT_EQ(levels.size(), 6u);
        for (size_t l = 1; l < 6; ++l) {
            EXPECT_LE(coverage[l].get<double>(), coverage[l - 1].get<double>());
            EXPECT_GE(levels[l]["hausdorffError"].get<double>(), levels[l - 1]["hausdorffError"].get<double>());
            EXPECT_LT(levels[l]["triangles"].get<double>(), levels[l - 1]["triangles"].get<double>());
            EXPECT_GT(levels[l]["switchDistance"].get<double>(), 0.0);
            // Each level is a plain mesh with the level's triangle count.
            const nlohmann::json& node = doc["nodes"][ids[l - 1].get<int>()];
            EXPECT_TRUE(node.contains("mesh"));
        }
        EXPECT_EQ(coverage[5].get<double>(), 0.0);
        EXPECT_EQ(doc.value("extensionsRequired", nlohmann::json::array()).size(), 0u);
    }
    {
        SCOPED_TRACE("LoddumpShowsTheLodTableWithoutProblems");
        const CommandResult d = loddump(shellQuote(rock1));
        EXPECT_EQ(d.exit_code, 0) << d.output;
        EXPECT_NE(d.output.find("lod group \"rock\" (node 0): 6 levels"), std::string::npos) << d.output;
        // No error; a warning (a Hausdorff step above 4 times between the sample's coarse levels) is
        // allowed.
        EXPECT_EQ(d.output.find("  error "), std::string::npos) << d.output;
        const CommandResult one = loddump("--level 2 " + shellQuote(rock1));
        EXPECT_EQ(one.exit_code, 0) << one.output;
        EXPECT_NE(one.output.find("\n  2 "), std::string::npos) << one.output;
        EXPECT_EQ(one.output.find("\n  3 "), std::string::npos) << one.output;
        EXPECT_NE(one.output.find("\"rock_lod2\""), std::string::npos) << one.output;
        EXPECT_EQ(one.output.find("\"rock_lod1\""), std::string::npos) << one.output;
    }
    {
        SCOPED_TRACE("ReportListsEveryLevel");
        std::ifstream report_stream(report_path);
        const nlohmann::json report = nlohmann::json::parse(report_stream);
        ASSERT_EQ(report["assets"].size(), 1u);
        EXPECT_EQ(report["assets"][0]["levels"].size(), 6u);
        EXPECT_EQ(report["packBytes"].get<size_t>(), bytesOf(rock1).size());
    }
    {
        // loddump's coverage column and the report's screenCoverage are one quantity: the screen
        // coverage at which the level takes over (1 for LOD0), as the pack stores it (7 digits).
        SCOPED_TRACE("LoddumpCoverageIsTheReportsCoverage");
        std::ifstream report_stream(report_path);
        const nlohmann::json report = nlohmann::json::parse(report_stream);
        const nlohmann::json& levels = report["assets"][0]["levels"];
        const CommandResult json_run =
            runCommand("(" + shellQuote(LODBAKE_TEST_LODDUMP) + " --json " + shellQuote(rock1) + " 2>/dev/null)");
        ASSERT_EQ(json_run.exit_code, 0) << json_run.output;
        const nlohmann::json dump = nlohmann::json::parse(json_run.output);
        const nlohmann::json& rows = dump["lodGroups"][0]["levels"];
        ASSERT_EQ(rows.size(), levels.size());
        const CommandResult text = loddump(shellQuote(rock1));
        const nlohmann::json msft =
            lodbake_test::glbJson(bytesOf(rock1))["nodes"][0]["extras"]["MSFT_screencoverage"];
        for (size_t l = 0; l < levels.size(); ++l) {
            const double reported = levels[l]["screenCoverage"].get<double>();
            const double dumped = rows[l]["screenCoverage"].get<double>();
            EXPECT_NEAR(dumped, reported, 1e-6 * reported) << "level " << l;
            EXPECT_EQ(rows[l]["msftScreenCoverage"].get<double>(), msft[l].get<double>()) << "level " << l;
            char cell[32];
            std::snprintf(cell, sizeof(cell), " %.4g ", reported);
            const size_t row = text.output.find("\n  " + std::to_string(l) + "  ");
            ASSERT_NE(row, std::string::npos) << text.output;
            const std::string line = text.output.substr(row + 1, text.output.find('\n', row + 1) - row - 1);
            EXPECT_NE(line.find(cell), std::string::npos) << "level " << l << ": " << line << " lacks" << cell;
        }
        EXPECT_EQ(levels[0]["screenCoverage"].get<double>(), 1.0);
    }
    {
        SCOPED_TRACE("ReportTimelineListsEveryStageRunAsItBegan");
        std::ifstream report_stream(report_path);
        const nlohmann::json report = nlohmann::json::parse(report_stream);
        const nlohmann::json& timeline = report["timeline"];
        ASSERT_TRUE(timeline.is_array());
        const double total = report["timings"]["total"].get<double>();
        std::map<std::string, int> runs;
        std::set<uint64_t> coded_levels;
        double previous_start = 0.0, stage_sum = 0.0;
        for (const nlohmann::json& run : timeline) {
            const std::string stage = run["stage"].get<std::string>();
            ++runs[stage];
            const double start = run["start"].get<double>(), seconds = run["seconds"].get<double>();
            EXPECT_GE(start, previous_start) << stage; // as the runs began
            EXPECT_GE(seconds, 0.0) << stage;
            EXPECT_LE(start + seconds, total + 1e-3) << stage;
            previous_start = start;
            if (stage == "encode") coded_levels.insert(run["level"].get<uint64_t>());
            if (stage == "pack" || stage == "write") {
                EXPECT_FALSE(run.contains("input")) << stage;
            }
            if (stage == "lod_chain") stage_sum += seconds;
        }
        for (const char* stage : {"load", "repair", "lod_chain", "pfrep", "pack", "write"})
            EXPECT_EQ(runs[stage], 1) << stage; // PFRep codes LOD0 only: no empty runs for the other levels
        EXPECT_GE(runs["measure"], 1);
        // The valence coding of every level, each its own run.
        EXPECT_EQ(coded_levels, (std::set<uint64_t>{0, 1, 2, 3, 4, 5}));
        // The stage sums are the timeline's runs added up.
        EXPECT_DOUBLE_EQ(stage_sum, report["timings"]["lod_chain"].get<double>());
    }
}

TEST(LoddumpLodCheckTest, FlagsCyclesRisingCoverageAndFallingErrors) {
    std::ifstream in(src("schemas/LODBAKE_lod_metrics/examples/minimal.gltf"));
    const nlohmann::json example = nlohmann::json::parse(in);
    const CommandResult good = loddump(shellQuote(src("schemas/LODBAKE_lod_metrics/examples/minimal.gltf")));
    EXPECT_EQ(good.exit_code, 0) << good.output;
    EXPECT_EQ(good.output.find("  error "), std::string::npos) << good.output;
    struct Case {
        const char* name;
        void (*edit)(nlohmann::json&);
        const char* expected;
    };
    const Case cases[] = {
        {"self", [](nlohmann::json& d) { d["nodes"][0]["extensions"]["MSFT_lod"]["ids"][0] = 0; }, "MSFT_lod cycle"},
        {"back", [](nlohmann::json& d) { d["nodes"][1]["extensions"]["MSFT_lod"]["ids"] = {0}; }, "MSFT_lod cycle"},
        {"range", [](nlohmann::json& d) { d["nodes"][0]["extensions"]["MSFT_lod"]["ids"][0] = 7; },
         "/nodes/0/extensions/MSFT_lod/ids/0: expected a node index below 2"},
        {"coverage",
         [](nlohmann::json& d) {
             d["nodes"][0]["extras"]["MSFT_screencoverage"] = {0.2, 0.5};
         },
         "level 1: screen coverage increases"},
        {"error",
         [](nlohmann::json& d) {
             d["nodes"][0]["extensions"]["LODBAKE_lod_metrics"]["levels"][0]["hausdorffError"] = 1.0;
         },
         "level 1: error decreases"},
    };
    for (const Case& c : cases) {
        nlohmann::json doc = example;
        c.edit(doc);
        const std::string path = outDir() + "/lod_check_" + c.name + ".gltf";
        std::ofstream(path) << doc.dump();
        const CommandResult d = loddump(shellQuote(path));
        EXPECT_EQ(d.exit_code, 1) << c.name << ": " << d.output;
        EXPECT_NE(d.output.find(c.expected), std::string::npos) << c.name << ": " << d.output;
    }
}

// loddump checks the PFRep blob against the chain: the extension's header fields, one level entry per
// chain level, removal counts in order and within the blob, each entry's triangles what the blob
// extracts, and no PFRep level finer than the chain level it stands for. A baked pack passes; each edit
// of its extension is reported (exit status 1).
TEST(LoddumpLodCheckTest, FlagsPfrepLevelsThatDisagreeWithTheChain) {
    const std::string out = outDir() + "/pfrep_check.glb";
    const CommandResult r = bake(shellQuote(src("assets/samples/rock_scan/rock_000.ply")) + " -o " + shellQuote(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<uint8_t> glb = bytesOf(out);
    const nlohmann::json doc = lodbake_test::glbJson(glb);
    const std::vector<uint8_t> bin = lodbake_test::glbBin(glb);
    const nlohmann::json& fans = doc["meshes"][0]["extensions"]["LODBAKE_progressive_fans"];
    ASSERT_GE(fans["levels"].size(), 3u) << fans;
    struct Case {
        const char* name;
        void (*edit)(nlohmann::json& fans);
        const char* expected;
    };
    const Case cases[] = {
        {"same", [](nlohmann::json&) {}, nullptr},
        {"count", [](nlohmann::json& f) { f["levels"].erase(f["levels"].size() - 1); }, "levels (one per level of"},
        {"header", [](nlohmann::json& f) { f["vertexCount"] = f["vertexCount"].get<uint64_t>() + 1; },
         "vertexCount: expected the blob's"},
        {"extract",
         [](nlohmann::json& f) { f["levels"][1]["triangles"] = f["levels"][1]["triangles"].get<uint64_t>() + 2; },
         "triangles, the extension says"},
        {"range", [](nlohmann::json& f) { f["levels"][1]["removals"] = f["removedCount"].get<uint64_t>() + 1; },
         "at most removedCount"},
        {"order",
         [](nlohmann::json& f) { f["levels"][2]["removals"] = f["levels"][1]["removals"].get<uint64_t>() - 1; },
         "at least the previous level's"},
        {"finer", [](nlohmann::json& f) { f["levels"][1] = f["levels"][0]; }, "finer than the level it stands for"},
    };
    for (const Case& c : cases) {
        nlohmann::json edited = doc;
        c.edit(edited["meshes"][0]["extensions"]["LODBAKE_progressive_fans"]);
        const std::string path = outDir() + "/pfrep_check_" + c.name + ".glb";
        const std::vector<uint8_t> bytes = lodbake_test::makeGlb(edited, bin);
        std::ofstream(path, std::ios::binary)
            .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        const CommandResult d = loddump(shellQuote(path));
        if (!c.expected) {
            EXPECT_EQ(d.exit_code, 0) << c.name << ": " << d.output;
            continue;
        }
        EXPECT_EQ(d.exit_code, 1) << c.name << ": " << d.output;
        EXPECT_NE(d.output.find(c.expected), std::string::npos) << c.name << ": " << d.output;
        EXPECT_NE(d.output.find("/meshes/0/extensions/LODBAKE_progressive_fans"), std::string::npos) << d.output;
    }
}

// A compact pack requires the valence stream (it replaces the plain data); the progressive-fans
// blob is extra data a viewer may ignore, so it is used but not required.
TEST(BakeCliUsageTest, CompactPackRequiresTheValenceStreamAndLoddumpDecodesIt) {
    const std::string out = outDir() + "/compact.glb";
    const CommandResult r =
        bake(shellQuote(src("assets/samples/rock_scan/rock_000.ply")) + " --compact -o " + shellQuote(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json doc = lodbake_test::glbJson(bytesOf(out));
    EXPECT_EQ(doc["extensionsRequired"], nlohmann::json::array({"LODBAKE_valence_compression"}));
    const CommandResult d = loddump(shellQuote(out));
    EXPECT_EQ(d.exit_code, 0) << d.output;
    const nlohmann::json used = doc.value("extensionsUsed", nlohmann::json::array());
    EXPECT_NE(std::find(used.begin(), used.end(), "LODBAKE_progressive_fans"), used.end()) << used;
}

TEST(BakeCliUsageTest, PresetErrorsAndOverrides) {
    const std::string bad = outDir() + "/bad_preset.json";
    std::ofstream(bad) << R"({"version": 1, "lod_ratio": [0.5]})";
    CommandResult r = bake("--print-config --preset " + shellQuote(bad));
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.output.find("error: " + bad + ": /lod_ratio: unknown key"), std::string::npos) << r.output;
    r = bake("--print-config --preset " + shellQuote(src("configs/mobile.json")) + " --pixels 3 --threads 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json printed = nlohmann::json::parse(r.output);
    EXPECT_EQ(printed["pixel_threshold"].get<double>(), 3.0);
    EXPECT_EQ(printed["threads"].get<int>(), 2);
    EXPECT_EQ(printed["viewport_height_px"].get<double>(), 720.0); // from the preset
    EXPECT_TRUE(printed["progressive_fans"].get<bool>());
    r = bake("--print-config --no-progressive-fans");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(nlohmann::json::parse(r.output)["progressive_fans"].get<bool>());
    r = bake("--print-config --preset " + shellQuote(src("configs/archive.json")) + " --adaptive-precision");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(nlohmann::json::parse(r.output)["stream_precision"]["adaptive"].get<bool>());
    r = bake("--print-config --preset " + shellQuote(src("configs/desktop.json")) + " --no-adaptive-precision");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(nlohmann::json::parse(r.output)["stream_precision"]["adaptive"].get<bool>());
    EXPECT_EQ(bake("--print-config --adaptive-precision --no-adaptive-precision").exit_code, 2);
    r = bake("--print-config --preset " + shellQuote(src("configs/desktop.json")));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(nlohmann::json::parse(r.output)["remove_covered_components"].get<bool>());
    r = bake("--print-config --preset " + shellQuote(src("configs/desktop.json")) + " --remove-covered-components");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(nlohmann::json::parse(r.output)["remove_covered_components"].get<bool>());
    EXPECT_TRUE(printed["pfrep_from_chain"].get<bool>()); // on in mobile.json, desktop.json and vr.json
    r = bake("--print-config --preset " + shellQuote(src("configs/desktop.json")) + " --no-pfrep-from-chain");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(nlohmann::json::parse(r.output)["pfrep_from_chain"].get<bool>());
    r = bake("--print-config --preset " + shellQuote(src("configs/archive.json")));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_FALSE(nlohmann::json::parse(r.output)["pfrep_from_chain"].get<bool>()); // archive: the separate pass
    r = bake("--print-config --preset " + shellQuote(src("configs/archive.json")) + " --pfrep-from-chain");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(nlohmann::json::parse(r.output)["pfrep_from_chain"].get<bool>());
    EXPECT_EQ(bake("--print-config --pfrep-from-chain --no-pfrep-from-chain").exit_code, 2);
    EXPECT_EQ(printed["pfrep_format"].get<uint32_t>(), 4u); // the PFRep blob coded against LOD0 by default
    r = bake("--print-config --preset " + shellQuote(src("configs/desktop.json")) + " --pfrep-format 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(r.output)["pfrep_format"].get<uint32_t>(), 2u);
    r = bake("--print-config --pfrep-format 4");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(r.output)["pfrep_format"].get<uint32_t>(), 4u);
    r = bake("--print-config --pfrep-format 5");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(r.output)["pfrep_format"].get<uint32_t>(), 5u);
    r = bake("--print-config --pfrep-format 5 --pfrep-region-block 256");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(nlohmann::json::parse(r.output)["pfrep_region_block"].get<uint32_t>(), 256u);
    EXPECT_EQ(printed["pfrep_region_block"].get<uint32_t>(), 1024u);
    r = bake("--print-config --pfrep-region-block 32");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("--pfrep-region-block expects an integer in [64, 65536], got '32'"), std::string::npos)
        << r.output;
    r = bake("--print-config --pfrep-format 6");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.output.find("--pfrep-format expects 2, 3, 4 or 5, got '6'"), std::string::npos) << r.output;
    EXPECT_EQ(bake("x.ply -o out.gltf").exit_code, 2);
    EXPECT_EQ(bake("-o out.glb").exit_code, 2);
}

// The shared scans through the mobile preset: each pack passes the validator and the metrics schema.
TEST(BakeSharedMeshesTest, ScansBakeIntoValidPacks) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    std::vector<std::string> packs;
    for (const char* name :
         {"bunny_zipper.ply", "lee_perry_smith/LeePerrySmith.glb", "nefertiti_fraunhofer_textured.glb"}) {
        const std::string stem = fs::path(name).stem().string();
        const std::string out = outDir() + "/" + stem + ".glb";
        // Textured scans load the OpenImageIO module: LeakSanitizer's tracer can crash at exit (gltf_test_util.h).
        const CommandResult r = runCommand(lodbake_test::withoutLeakCheck() + shellQuote(lodbake_test::lodbakeCli()) +
                                           " bake " + shellQuote(lodbake_test::sharedMesh(name)) + " --preset " +
                                           shellQuote(src("configs/mobile.json")) + " -o " + shellQuote(out));
        ASSERT_EQ(r.exit_code, 0) << name << ": " << r.output;
        packs.push_back(out);
        const CommandResult d = loddump(shellQuote(out));
        EXPECT_EQ(d.exit_code, 0) << d.output;
    }
    const CommandResult v = validateGltf(packs);
    EXPECT_EQ(v.exit_code, 0) << v.output;
    const CommandResult m = validateMetrics(packs);
    EXPECT_EQ(m.exit_code, 0) << m.output;
    // Nefertiti's textures shrink level by level (its base colour is 2048 or larger).
    const nlohmann::json doc = lodbake_test::glbJson(bytesOf(packs[2]));
    EXPECT_GT(doc["images"].size(), 2u);
}

TEST(LodMetricsSchemaTest, ExampleMatchesTheSchemaAndPassesTheValidator) {
    const std::string example = src("schemas/LODBAKE_lod_metrics/examples/minimal.gltf");
    const CommandResult m = validateMetrics({example});
    EXPECT_EQ(m.exit_code, 0) << m.output;
    const CommandResult v = validateGltf({example});
    EXPECT_EQ(v.exit_code, 0) << v.output;
}

} // namespace
