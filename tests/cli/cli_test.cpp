// The lodbake command line as a build system and a person see it: exit codes, one-line errors that
// name the file, no output left behind on failure, input never modified. The malformed corpus lives
// in tests/malformed/<format>/, described by each folder's expect.tsv.

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "lodbake/core/file_io.h"
#include "lodbake/core/hash.h"
#include "cli_runner.h"
#include "test_paths.h"

namespace fs = std::filesystem;

namespace {

using RunResult = lodbake_test::CliRun;
using lodbake_test::readTextFile;

RunResult runCli(const std::vector<std::string>& args) { return lodbake_test::runLodbake(args); }

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream ss(text);
    std::string line;
    while (std::getline(ss, line)) out.push_back(line);
    return out;
}

uint64_t hashFile(const std::string& path) {
    auto bytes = lodbake::readFileBytes(path);
    lodbake::Hasher h;
    if (bytes.ok()) h.addBytes(bytes->data(), bytes->size());
    return h.digest();
}

// A case of the malformed corpus: a file that every command must refuse cleanly.
struct MalformedCase {
    std::string path;
    std::string expected;             // substring the error line must contain (the element that is wrong)
    std::vector<std::string> command; // from the folder's "command" line; empty: info and convert
};

// Shown by ctest instead of the struct's bytes.
void PrintTo(const MalformedCase& c, std::ostream* os) { *os << c.path; }

std::vector<MalformedCase> malformedCases() {
    std::vector<MalformedCase> cases;
    const fs::path root = fs::path(lodbake_test::sourceDir()) / "tests" / "malformed";
    if (!fs::is_directory(root)) return cases;
    std::vector<fs::path> dirs;
    for (const auto& e : fs::directory_iterator(root))
        if (e.is_directory()) dirs.push_back(e.path());
    std::sort(dirs.begin(), dirs.end());
    for (const fs::path& dir : dirs) {
        std::ifstream tsv(dir / "expect.tsv");
        std::string line;
        // Formats that `info` does not read (.lbm, .lbp, presets) name their command in a line
        // "command<TAB>ARG<TAB>ARG...", where {in} is the case, {dir} its folder and {out} a scratch
        // folder that must stay empty.
        std::vector<std::string> command;
        while (std::getline(tsv, line)) {
            if (line.empty() || line[0] == '#') continue;
            const size_t tab = line.find('\t');
            const std::string name = line.substr(0, tab);
            const std::string expected = tab == std::string::npos ? "" : line.substr(tab + 1);
            if (name == "side") continue; // a side file (MTL, texture) used by another case
            if (name == "command") {
                std::istringstream fields(expected);
                for (std::string arg; std::getline(fields, arg, '\t');) command.push_back(arg);
                continue;
            }
            cases.push_back({(dir / name).string(), expected, command});
        }
    }
    return cases;
}

std::string caseName(const testing::TestParamInfo<MalformedCase>& info) {
    const fs::path p(info.param.path);
    std::string n = p.parent_path().filename().string() + "_" + p.filename().string();
    for (char& c : n)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return n;
}

} // namespace

TEST(CliTest, HelpExitsZero) {
    const RunResult r = runCli({"--help"});
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_NE(r.out.find("usage: lodbake"), std::string::npos);
    for (const char* cmd : {"info", "convert"}) {
        const RunResult c = runCli({cmd, "--help"});
        EXPECT_EQ(c.exit_code, 0) << cmd;
        EXPECT_NE(c.out.find(std::string("usage: lodbake ") + cmd), std::string::npos) << cmd;
    }
}

TEST(CliTest, UsageErrorsExitTwo) {
    EXPECT_EQ(runCli({}).exit_code, 2);
    EXPECT_EQ(runCli({"frobnicate"}).exit_code, 2);
    EXPECT_EQ(runCli({"info"}).exit_code, 2);
    EXPECT_EQ(runCli({"info", "a.ply", "b.ply"}).exit_code, 2);
    EXPECT_EQ(runCli({"info", "--no-such-flag", "a.ply"}).exit_code, 2);
    EXPECT_EQ(runCli({"convert", "a.ply"}).exit_code, 2);
    EXPECT_EQ(runCli({"convert", "a.ply", "-o"}).exit_code, 2);
    EXPECT_EQ(runCli({"convert", "a.ply", "-o", "out.xyz"}).exit_code, 2);
}

TEST(CliTest, MissingFileIsOneLineErrorNamingIt) {
    const std::string missing = lodbake_test::scratchDir() + "/does_not_exist.ply";
    const RunResult r = runCli({"info", missing});
    EXPECT_EQ(r.exit_code, 1);
    const auto err = lines(r.err);
    ASSERT_EQ(err.size(), 1u) << r.err;
    EXPECT_EQ(err[0].rfind("error: ", 0), 0u);
    EXPECT_NE(err[0].find(missing), std::string::npos);
}

TEST(CliTest, ConvertRefusesToOverwriteInput) {
    const std::string path = lodbake_test::scratchDir() + "/self.ply";
    const std::string text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    ASSERT_TRUE(lodbake::writeFileAtomic(path, text.data(), text.size()).ok());
    const RunResult r = runCli({"convert", path, "-o", path});
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_EQ(readTextFile(path), text);
}

TEST(CliTest, ReaderLimitsComeFromTheCommandLine) {
    const std::string path = lodbake_test::scratchDir() + "/two_faces.off";
    const std::string text = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n";
    ASSERT_TRUE(lodbake::writeFileAtomic(path, text.data(), text.size()).ok());
    const std::string out = lodbake_test::scratchDir() + "/two_faces_limited.ply";
    std::remove(out.c_str());
    EXPECT_EQ(runCli({"convert", path, "-o", out, "--max-faces", "2"}).exit_code, 0);
    std::remove(out.c_str());
    for (const char* limit : {"--max-faces", "--max-vertices"}) {
        const RunResult r = runCli({"convert", path, "-o", out, limit, limit[6] == 'f' ? "1" : "3"});
        EXPECT_EQ(r.exit_code, 1) << limit;
        const auto err = lines(r.err);
        ASSERT_EQ(err.size(), 1u) << r.err;
        EXPECT_NE(err[0].find(path), std::string::npos) << err[0];
        EXPECT_FALSE(fs::exists(out)) << limit;
    }
    EXPECT_EQ(runCli({"info", path, "--max-faces", "0"}).exit_code, 2);
    EXPECT_EQ(runCli({"info", path, "--max-vertices", "1.5"}).exit_code, 2);
    EXPECT_EQ(runCli({"info", path, "--max-vertices"}).exit_code, 2);
    EXPECT_EQ(readTextFile(path), text);
}

class MalformedInputTest : public testing::TestWithParam<MalformedCase> {};

TEST_P(MalformedInputTest, FailsCleanlyWithoutOutput) {
    const MalformedCase& c = GetParam();
    const uint64_t before = hashFile(c.path);
    const std::string out_dir = lodbake_test::scratchDir() + "/malformed_" + fs::path(c.path).filename().string();
    fs::remove_all(out_dir);
    fs::create_directories(out_dir);

    std::vector<std::string> first{"info", c.path};
    if (!c.command.empty()) {
        first.clear();
        for (std::string arg : c.command) {
            for (const auto& [key, value] : {std::pair<std::string, std::string>{"{in}", c.path},
                                             {"{dir}", fs::path(c.path).parent_path().string()},
                                             {"{out}", out_dir}}) {
                const size_t at = arg.find(key);
                if (at != std::string::npos) arg.replace(at, key.size(), value);
            }
            first.push_back(arg);
        }
    }
    const RunResult info = runCli(first);
    EXPECT_EQ(info.exit_code, 1) << info.err;
    std::vector<std::string> errors;
    for (const std::string& l : lines(info.err))
        if (l.rfind("error: ", 0) == 0) errors.push_back(l);
    ASSERT_EQ(errors.size(), 1u) << "expected exactly one error line, got:\n" << info.err;
    EXPECT_NE(errors[0].find(c.path), std::string::npos) << "error must name the file: " << errors[0];
    EXPECT_NE(errors[0].find(c.expected), std::string::npos)
        << "error must mention '" << c.expected << "': " << errors[0];

    for (const char* ext : {".glb", ".ply"}) {
        if (!c.command.empty()) break; // `convert` does not read this format
        const RunResult conv = runCli({"convert", c.path, "-o", out_dir + "/out" + ext});
        EXPECT_EQ(conv.exit_code, 1) << conv.err;
    }
    EXPECT_TRUE(fs::is_empty(out_dir)) << "a failed convert left files in " << out_dir;
    EXPECT_EQ(hashFile(c.path), before) << "the input was modified";
}

INSTANTIATE_TEST_SUITE_P(Corpus, MalformedInputTest, testing::ValuesIn(malformedCases()), caseName);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(MalformedInputTest);

TEST(MalformedCorpusTest, EveryFileIsListed) {
    const fs::path root = fs::path(lodbake_test::sourceDir()) / "tests" / "malformed";
    size_t listed = 0;
    for (const auto& dir : fs::directory_iterator(root)) {
        if (!dir.is_directory()) continue;
        // Runtime packs are no CLI input: NAME.glb + NAME.expected, checked by PackCorpusTest.
        if (dir.path().filename() == "pack") continue;
        std::ifstream tsv(dir.path() / "expect.tsv");
        ASSERT_TRUE(tsv.good()) << dir.path() << " has no expect.tsv";
        std::vector<std::string> names;
        std::string line;
        while (std::getline(tsv, line)) {
            if (line.empty() || line[0] == '#') continue;
            const size_t tab = line.find('\t');
            if (line.rfind("command\t", 0) == 0) continue;
            names.push_back(line.rfind("side\t", 0) == 0 ? line.substr(5) : line.substr(0, tab));
        }
        for (const auto& f : fs::directory_iterator(dir.path())) {
            const std::string n = f.path().filename().string();
            if (n == "expect.tsv") continue;
            EXPECT_NE(std::find(names.begin(), names.end(), n), names.end())
                << f.path() << " is not listed in expect.tsv";
        }
        listed += names.size();
    }
    EXPECT_GT(listed, 0u);
}

namespace {

// --preset NAME resolves a bundled preset from share/lodbake/presets beside the executable (the
// build tree has the install layout): the same settings as the file in configs/, listed as read in
// the depfile; a path still names a file; an unknown name is a usage error listing the names.
TEST(PresetCliTest, BundledPresetsByNameAndFilesByPath) {
    for (const char* name : {"desktop", "mobile", "vr", "archive"}) {
        const std::string file = lodbake_test::sourceDir() + "/configs/" + name + ".json";
        const RunResult by_name = runCli({"bake", "--print-config", "--preset", name});
        const RunResult by_path = runCli({"bake", "--print-config", "--preset", file});
        ASSERT_EQ(by_name.exit_code, 0) << name << ": " << by_name.err;
        ASSERT_EQ(by_path.exit_code, 0) << name << ": " << by_path.err;
        EXPECT_EQ(by_name.out, by_path.out) << name;
        EXPECT_NE(by_name.out, runCli({"bake", "--print-config"}).out) << name << " changes nothing";
    }
    const RunResult unknown = runCli({"bake", "--print-config", "--preset", "fastest"});
    EXPECT_EQ(unknown.exit_code, 2);
    ASSERT_EQ(lines(unknown.err).size(), 1u) << unknown.err;
    EXPECT_NE(unknown.err.find("unknown preset 'fastest': the bundled presets are archive, desktop, mobile, vr"),
              std::string::npos)
        << unknown.err;
    // Anything with '/' or '.' is a path: a missing file is an input error naming it.
    const RunResult missing = runCli({"bake", "--print-config", "--preset", "mobile.json"});
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.err.find("error: mobile.json: "), std::string::npos) << missing.err;

    const std::string dir = lodbake_test::scratchDir() + "/preset_cli_" + std::to_string(::getpid());
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string mesh = lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock.conf";
    const RunResult baked = runCli({"bake", mesh, "-o", dir + "/rock.glb", "--preset", "mobile", "--levels", "0.5",
                                    "--merge", "off", "--depfile", dir + "/rock.d", "--quiet"});
    ASSERT_EQ(baked.exit_code, 0) << baked.err;
    const std::string depfile = readTextFile(dir + "/rock.d");
    EXPECT_NE(depfile.find("share/lodbake/presets/mobile.json"), std::string::npos) << depfile;
    const std::string listed = depfile.substr(depfile.find(':') + 1);
    const size_t at = listed.find("/share/lodbake/presets/mobile.json");
    ASSERT_NE(at, std::string::npos);
    const size_t begin = listed.find_last_of(" \t\\\n", at) + 1;
    const std::string preset_path = listed.substr(begin, at + std::strlen("/share/lodbake/presets/mobile.json") - begin);
    EXPECT_EQ(readTextFile(preset_path), readTextFile(lodbake_test::sourceDir() + "/configs/mobile.json"))
        << preset_path;
}

// Every command that reads one file and writes one refuses the same usage mistakes the same way.
TEST(OutputCheckCliTest, OneInputAnOutputThatIsNotTheInput) {
    const std::string in = lodbake_test::sourceDir() + "/assets/samples/rock_scan/rock.conf";
    for (const char* command : {"convert", "repair", "merge", "simplify", "decode", "encode", "pfrep"}) {
        SCOPED_TRACE(command);
        const RunResult none = runCli({command, "-o", "x.ply"});
        EXPECT_EQ(none.exit_code, 2);
        EXPECT_NE(none.err.find(std::string(command) + " takes exactly one input file"), std::string::npos)
            << none.err;
        const RunResult no_output = runCli({command, in});
        EXPECT_EQ(no_output.exit_code, 2);
        EXPECT_NE(no_output.err.find(std::string(command) + " needs -o OUT"), std::string::npos) << no_output.err;
        const RunResult same = runCli({command, in, "-o", in});
        EXPECT_EQ(same.exit_code, 2);
        EXPECT_EQ(lines(same.err).size(), 1u) << same.err;
    }
    // A .conf scan set is read, never written.
    for (const char* command : {"convert", "repair", "merge", "decode"}) {
        const RunResult conf = runCli({command, in, "-o", lodbake_test::scratchDir() + "/out.conf"});
        EXPECT_EQ(conf.exit_code, 2) << command;
        EXPECT_NE(conf.err.find("has an unknown extension"), std::string::npos) << command << ": " << conf.err;
    }
}

} // namespace
