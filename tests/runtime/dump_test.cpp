// loddump end to end: exit codes, the one-line error contract and deterministic --json output.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <unistd.h>

#include <gtest/gtest.h>

#include "glb_builder.h"
#include "lod_pack_builder.h"
#include "lodrt/json.h"

namespace {

struct DumpRun {
    int exit_code;
    std::string out, err;
};

std::string readText(const std::string& path) {
    std::string text;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return text;
    char buf[4096];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof(buf), file)) > 0) text.append(buf, n);
    std::fclose(file);
    return text;
}

std::string scratchPath(const std::string& name) {
    // The process id keeps parallel ctest processes (one per test) from sharing scratch files.
    return std::string(LODRT_TEST_BINARY_DIR) + "/dump_test_" + std::to_string(::getpid()) + "_" + name;
}

void writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
    std::FILE* file = std::fopen(path.c_str(), "wb");
    ASSERT_NE(file, nullptr) << path;
    std::fwrite(bytes.data(), 1, bytes.size(), file);
    std::fclose(file);
}

DumpRun runDump(const std::string& args) {
    const std::string out = scratchPath("stdout.txt"), err = scratchPath("stderr.txt");
    const std::string command =
        std::string("\"") + LODRT_TEST_LODDUMP + "\" " + args + " >\"" + out + "\" 2>\"" + err + "\"";
    const int status = std::system(command.c_str());
    DumpRun run;
    run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    run.out = readText(out);
    run.err = readText(err);
    return run;
}

size_t lineCount(const std::string& text) {
    size_t n = 0;
    for (char c : text) n += c == '\n';
    return n;
}

} // namespace

TEST(DumpTest, PrintsMeshTableTotalsAndProblems) {
    const std::string path = scratchPath("quad.glb");
    writeBytes(path, lodrt_test::quadGlb());
    const DumpRun run = runDump("\"" + path + "\"");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.err, "");
    EXPECT_NE(run.out.find("mesh 0 \"Quad\": 1 primitive\n"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("primitive 0: TRIANGLES, 4 vertices, 2 triangles, material 0"), std::string::npos);
    EXPECT_NE(run.out.find("POSITION"), std::string::npos);
    EXPECT_NE(run.out.find("totals: 1 meshes, 1 primitives, 4 vertices, 2 triangles, 108 accessor bytes, 1 "
                           "materials, 2 nodes"),
              std::string::npos)
        << run.out;
    EXPECT_NE(run.out.find("problems: none"), std::string::npos);
}

TEST(DumpTest, JsonOutputParsesAndIsDeterministic) {
    std::string json = lodrt_test::quadJson(R"(,"extensionsRequired":["EXT_x"])");
    const std::string path = scratchPath("quad_ext.glb");
    writeBytes(path, lodrt_test::makeGlb(json, lodrt_test::quadBin()));
    const DumpRun first = runDump("\"" + path + "\" --json");
    const DumpRun second = runDump("--json \"" + path + "\"");
    ASSERT_EQ(first.exit_code, 0) << first.err;
    EXPECT_EQ(first.out, second.out);
    lodrt::JsonDocument doc;
    ASSERT_EQ(lodrt::parseJson(first.out.data(), first.out.size(), nullptr, nullptr, &doc), lodrt::Result::Ok)
        << first.out;
    const lodrt::JsonValue root = doc.root();
    EXPECT_TRUE(root.find("ok").boolean());
    EXPECT_EQ(root.find("totals").find("triangles").number(), 2.0);
    EXPECT_EQ(root.find("totals").find("bytes").number(), 108.0);
    const lodrt::JsonValue accessors = root.find("meshes").at(0).find("primitives").at(0).find("accessors");
    ASSERT_EQ(accessors.size(), 3u);
    EXPECT_EQ(accessors.at(1).find("semantic").string(), "POSITION");
    EXPECT_EQ(accessors.at(1).find("bytes").number(), 48.0);
    ASSERT_EQ(root.find("problems").size(), 1u);
    EXPECT_EQ(root.find("problems").at(0).find("pointer").string(), "/extensionsRequired/0");
}

TEST(DumpTest, BadPackIsOneErrorLineAndExit1) {
    const std::string path = scratchPath("bad.glb");
    std::string json = lodrt_test::quadJson();
    json.replace(json.find(R"("count":6,)"), 10, R"("count":60,)");
    writeBytes(path, lodrt_test::makeGlb(json, lodrt_test::quadBin()));
    const DumpRun run = runDump("\"" + path + "\"");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_EQ(lineCount(run.err), 1u) << run.err;
    EXPECT_EQ(run.err.rfind("error: " + path + ": /accessors/2/count: 60 elements", 0), 0u) << run.err;
    EXPECT_NE(run.out.find("problems:\n  error /accessors/2/count: 60 elements"), std::string::npos) << run.out;

    std::vector<uint8_t> truncated = lodrt_test::quadGlb();
    truncated.resize(truncated.size() - 1);
    writeBytes(path, truncated);
    const DumpRun cut = runDump("\"" + path + "\" --json");
    EXPECT_EQ(cut.exit_code, 1);
    EXPECT_EQ(lineCount(cut.err), 1u);
    EXPECT_NE(cut.err.find(path), std::string::npos);
    lodrt::JsonDocument doc;
    ASSERT_EQ(lodrt::parseJson(cut.out.data(), cut.out.size(), nullptr, nullptr, &doc), lodrt::Result::Ok) << cut.out;
    EXPECT_FALSE(doc.root().find("ok").boolean());
    EXPECT_EQ(doc.root().find("problems").at(0).find("severity").string(), "error");
}

TEST(DumpTest, FlagsRepeatedLevelsAndErrorLeaps) {
    // Every level of the built pack is one triangle, and level 2's error is 5 times level 1's.
    lodrt_test::LodPackSpec spec;
    spec.errors = {0, 0.001, 0.005};
    const std::string path = scratchPath("leap.glb");
    writeBytes(path, lodrt_test::lodPackGlb(spec));
    const DumpRun run = runDump("\"" + path + "\"");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_EQ(lineCount(run.err), 1u) << run.err;
    EXPECT_NE(run.err.find("level 1: the same 1 triangles as level 0 (a repeated level)"), std::string::npos)
        << run.err;
    EXPECT_NE(run.out.find("level 2: the same 1 triangles as level 1"), std::string::npos) << run.out;
    EXPECT_NE(run.out.find("  warning /nodes/2: level 2: Hausdorff error 5 times level 1's (more than 4 times)"),
              std::string::npos)
        << run.out;
    // A step of exactly 4 times is not flagged; a larger one alone is a warning, not a failed check.
    spec.errors = {0, 0.001, 0.004};
    writeBytes(path, lodrt_test::lodPackGlb(spec));
    EXPECT_EQ(runDump("\"" + path + "\"").out.find("Hausdorff error"), std::string::npos);
}

TEST(DumpTest, FlagsLevelsSelectionNeverOrHardlyPicks) {
    // Levels 1 and 2 have the same error, so selection never picks level 1 (an error); level 3 is
    // taken at 1.02 times level 2's distance (a warning).
    lodrt_test::LodPackSpec spec;
    spec.errors = {0, 0.001, 0.001, 0.00102, 0.004};
    const std::string path = scratchPath("dead.glb");
    writeBytes(path, lodrt_test::lodPackGlb(spec));
    DumpRun run = runDump("\"" + path + "\"");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.out.find("/nodes/1: level 1 is never selected: level 2 is taken at the same switch distance"),
              std::string::npos)
        << run.out;
    EXPECT_NE(run.out.find("warning /nodes/2: level 2 is selected only from"), std::string::npos) << run.out;
    EXPECT_EQ(run.out.find("level 3 is selected only"), std::string::npos) << run.out;
    // Control: errors that grow by more than 1.05 at each step raise neither.
    spec.errors = {0, 0.001, 0.0011, 0.004};
    writeBytes(path, lodrt_test::lodPackGlb(spec));
    run = runDump("\"" + path + "\"");
    EXPECT_EQ(run.out.find("never selected"), std::string::npos) << run.out;
    EXPECT_EQ(run.out.find("selected only"), std::string::npos) << run.out;
    // Level 1 without error: LOD0 is never selected, a warning.
    spec.errors = {0, 0, 0.001, 0.004};
    writeBytes(path, lodrt_test::lodPackGlb(spec));
    run = runDump("\"" + path + "\"");
    EXPECT_NE(run.out.find("warning /nodes/1: level 0 is never selected"), std::string::npos) << run.out;
}

TEST(DumpTest, MissingFileIsExit1NamingTheFile) {
    const std::string path = scratchPath("does_not_exist.glb");
    std::remove(path.c_str());
    const DumpRun run = runDump("\"" + path + "\"");
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_EQ(lineCount(run.err), 1u);
    EXPECT_EQ(run.err.rfind("error: " + path + ": cannot open", 0), 0u) << run.err;
}

TEST(DumpTest, UsageErrorsExit2) {
    EXPECT_EQ(runDump("").exit_code, 2);
    EXPECT_EQ(runDump("--bogus x.glb").exit_code, 2);
    EXPECT_EQ(runDump("a.glb b.glb").exit_code, 2);
    const DumpRun help = runDump("--help");
    EXPECT_EQ(help.exit_code, 0);
    EXPECT_NE(help.out.find("usage: loddump"), std::string::npos);
}
