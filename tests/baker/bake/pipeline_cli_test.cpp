// `lodbake bake` at pipeline scale, end to end through the CLI: batch and manifest modes, depfiles,
// exit codes, the cache, quiet and plain progress output, independence from the current directory
// and input paths, and interrupted bakes. Inputs are the small OBJ+MTL+PNG and PLY assets that
// tests/pipeline/make_sample_assets.py writes.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "lodbake/bake/cache.h"
#include "lodbake/core/file_io.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake_test::CommandResult;
using lodbake_test::runCommand;
using lodbake_test::shellQuote;

std::vector<uint8_t> bytesOf(const std::string& path) {
    auto r = lodbake::readFileBytes(path);
    return r.ok() ? *r : std::vector<uint8_t>();
}

std::string textOf(const std::string& path) {
    const std::vector<uint8_t> b = bytesOf(path);
    return std::string(b.begin(), b.end());
}

// A fresh folder per test holding the sample assets (generated, deterministic).
std::string sampleDir(const std::string& name) {
    const std::string d = lodbake_test::scratchDir() + "/pipeline_" + name + "_" + std::to_string(::getpid());
    fs::remove_all(d);
    fs::create_directories(d);
    const CommandResult r = runCommand(lodbake_test::python() + " " +
                                       shellQuote(lodbake_test::sourceDir() + "/tests/pipeline/make_sample_assets.py") +
                                       " " + shellQuote(d + "/assets"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return d;
}

// `lodbake bake ARGS` run in `cwd` (stdout and stderr apart).
struct BakeRun {
    int exit_code = -1;
    std::string out, err;
};

BakeRun bakeIn(const std::string& cwd, const std::string& args, const std::string& env = "") {
    static int counter = 0;
    const std::string base =
        lodbake_test::scratchDir() + "/pipeline_run_" + std::to_string(::getpid()) + "_" + std::to_string(++counter);
    // A subshell: runCommand appends its own 2>&1, which must not redirect the bake's stderr.
    const CommandResult r =
        runCommand("(cd " + shellQuote(cwd) + " && " + env + shellQuote(lodbake_test::lodbakeCli()) + " bake " + args + " >" +
                   shellQuote(base + ".out") + " 2>" + shellQuote(base + ".err") + " </dev/null)");
    return {r.exit_code, textOf(base + ".out"), textOf(base + ".err")};
}

std::vector<std::string> listDir(const std::string& dir) {
    std::vector<std::string> names;
    if (!fs::is_directory(dir)) return names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

TEST(PipelineCliTest, BatchWritesOnePackPerInputWithTheBytesOfSingleBakes) {
    const std::string d = sampleDir("batch");
    const BakeRun batch =
        bakeIn(d, "assets/crate.obj assets/barrel.obj assets/rock.ply -o out/ --preset assets/light.json "
                  "--threads 2");
    ASSERT_EQ(batch.exit_code, 0) << batch.err;
    EXPECT_EQ(listDir(d + "/out"), (std::vector<std::string>{"barrel.glb", "crate.glb", "rock.glb"}));
    // Summaries in input order whatever order the packs finished in.
    const size_t c = batch.out.find("crate:"), b = batch.out.find("barrel:"), r = batch.out.find("rock:");
    ASSERT_NE(r, std::string::npos) << batch.out;
    EXPECT_LT(c, b);
    EXPECT_LT(b, r);
    for (const char* stem : {"crate", "barrel", "rock"}) {
        const std::string single = d + "/" + stem + "_single.glb";
        const BakeRun one = bakeIn(d, std::string("assets/") + stem + (std::string(stem) == "rock" ? ".ply" : ".obj") +
                                          " -o " + shellQuote(single) + " --preset assets/light.json --threads 1");
        ASSERT_EQ(one.exit_code, 0) << one.err;
        EXPECT_EQ(bytesOf(single), bytesOf(d + "/out/" + stem + ".glb")) << stem;
    }
}

TEST(PipelineCliTest, ManifestBakesEachAssetWithItsOverrides) {
    const std::string d = sampleDir("manifest");
    std::ofstream(d + "/assets/assets.json") << R"({
  "version": 1,
  "preset": "light.json",
  "output_dir": "../packs",
  "assets": [
    {"input": "crate.obj"},
    {"input": "rock.ply", "output": "rock_one_level.glb", "settings": {"lod_ratios": [0.25]}},
    {"inputs": ["barrel.obj", "rock.ply"], "output": "group.glb"}
  ]
})";
    const BakeRun run = bakeIn(d, "--manifest assets/assets.json --report report.json --depfile deps.d");
    ASSERT_EQ(run.exit_code, 0) << run.err << run.out;
    EXPECT_EQ(listDir(d + "/packs"), (std::vector<std::string>{"crate.glb", "group.glb", "rock_one_level.glb"}));
    const nlohmann::json report = nlohmann::json::parse(textOf(d + "/report.json"));
    ASSERT_EQ(report["packs"].size(), 3u);
    EXPECT_EQ(report["packs"][0]["assets"][0]["levels"].size(), 3u); // LOD0 + the preset's two
    EXPECT_EQ(report["packs"][1]["assets"][0]["levels"].size(), 2u); // LOD0 + the override's one
    EXPECT_EQ(report["packs"][2]["assets"].size(), 2u);              // two LOD groups in one pack
    EXPECT_EQ(report["packs"][0]["cache"], "miss");
    EXPECT_TRUE(report["packs"][0]["timings"].contains("lod_chain"));
    EXPECT_TRUE(report["packs"][0].contains("packBytes")); // the pack report's own keys are kept
    const std::string deps = textOf(d + "/deps.d");
    for (const char* needle : {"assets/assets.json", "assets/light.json", "packs/group.glb:", "assets/barrel.mtl",
                               "assets/textures/barrel.png"})
        EXPECT_NE(deps.find(needle), std::string::npos) << needle << "\n" << deps;
    // Each rule lists what its own pack read: rock_one_level.glb reads no MTL or texture.
    const size_t rock_rule = deps.find("packs/rock_one_level.glb:");
    const size_t next_rule = deps.find("packs/group.glb:");
    ASSERT_LT(rock_rule, next_rule);
    const std::string rock_deps = deps.substr(rock_rule, next_rule - rock_rule);
    EXPECT_NE(rock_deps.find("assets/rock.ply"), std::string::npos) << rock_deps;
    EXPECT_EQ(rock_deps.find(".mtl"), std::string::npos) << rock_deps;
    // Unknown keys are errors (exit 1, the manifest and the pointer named); so is a missing input.
    std::ofstream(d + "/assets/typo.json") << R"({"version": 1, "assets": [{"input": "crate.obj", "preset_": "x"}]})";
    const BakeRun typo = bakeIn(d, "--manifest assets/typo.json");
    EXPECT_EQ(typo.exit_code, 1);
    EXPECT_NE(typo.err.find("assets/typo.json: /assets/0/preset_: unknown key"), std::string::npos) << typo.err;
    EXPECT_EQ(bakeIn(d, "--manifest assets/assets.json assets/crate.obj").exit_code, 2);
}

TEST(PipelineCliTest, DepfileListsEveryFileReadWithSpacesEscaped) {
    const std::string d = sampleDir("depfile");
    fs::rename(d + "/assets", d + "/my assets");
    fs::create_directories(d + "/out dir");
    const BakeRun ok = bakeIn(d, "'my assets/crate.obj' -o 'out dir/crate.glb' --preset 'my assets/light.json' "
                                 "--depfile 'out dir/crate.glb.d'");
    ASSERT_EQ(ok.exit_code, 0) << ok.err;
    EXPECT_EQ(textOf(d + "/out dir/crate.glb.d"), "out\\ dir/crate.glb: \\\n"
                                                  "  my\\ assets/light.json \\\n"
                                                  "  my\\ assets/crate.obj \\\n"
                                                  "  my\\ assets/crate.mtl \\\n"
                                                  "  my\\ assets/textures/crate.png\n");
}

TEST(PipelineCliTest, CacheHitReusesThePackAndAnyChangedInputMisses) {
    const std::string d = sampleDir("cache");
    const std::string common =
        "assets/crate.obj -o out.glb --preset assets/light.json --cache-dir cache --report r.json "
        "--depfile out.d";
    const BakeRun cold = bakeIn(d, common);
    ASSERT_EQ(cold.exit_code, 0) << cold.err;
    const std::vector<uint8_t> cold_bytes = bytesOf(d + "/out.glb");
    const std::string cold_deps = textOf(d + "/out.d");
    EXPECT_EQ(nlohmann::json::parse(textOf(d + "/r.json"))["cache"], "miss");
    EXPECT_EQ(cold.out.find("cache hit"), std::string::npos);
    fs::remove(d + "/out.glb");

    const BakeRun warm = bakeIn(d, common + " --threads 1");
    ASSERT_EQ(warm.exit_code, 0) << warm.err;
    EXPECT_EQ(bytesOf(d + "/out.glb"), cold_bytes);
    EXPECT_EQ(textOf(d + "/out.d"), cold_deps); // a hit still lists the MTL and the texture
    const nlohmann::json report = nlohmann::json::parse(textOf(d + "/r.json"));
    EXPECT_EQ(report["cache"], "hit");
    EXPECT_EQ(report["assets"][0]["name"], "crate");
    // A hit prints one line, naming the cache entry, and nothing else (no summary, note or progress).
    const std::vector<std::string> entries = listDir(d + "/cache/v2/packs");
    ASSERT_EQ(entries.size(), 1u);
    const std::string key = entries[0].substr(0, entries[0].find('.'));
    EXPECT_EQ(warm.out, "cache hit: out.glb (" + std::to_string(cold_bytes.size()) + " bytes, key " + key +
                            ", written)\n");
    EXPECT_EQ(warm.err, "");

    // Again, with the pack in place: the output, the depfile and their time stamps are left alone.
    const fs::file_time_type pack_time = fs::last_write_time(d + "/out.glb");
    const fs::file_time_type deps_time = fs::last_write_time(d + "/out.d");
    const BakeRun again = bakeIn(d, common);
    ASSERT_EQ(again.exit_code, 0) << again.err;
    EXPECT_EQ(again.out, "cache hit: out.glb (" + std::to_string(cold_bytes.size()) + " bytes, key " + key +
                             ", file unchanged)\n");
    EXPECT_EQ(again.err, "");
    EXPECT_EQ(fs::last_write_time(d + "/out.glb"), pack_time);
    EXPECT_EQ(fs::last_write_time(d + "/out.d"), deps_time);
    EXPECT_EQ(bytesOf(d + "/out.glb"), cold_bytes);
    // A pack that differs from the cached one is replaced.
    std::vector<uint8_t> damaged = cold_bytes;
    damaged[damaged.size() / 2] ^= 1;
    ASSERT_TRUE(lodbake::writeFileAtomic(d + "/out.glb", damaged.data(), damaged.size()).ok());
    const BakeRun replaced = bakeIn(d, common);
    ASSERT_EQ(replaced.exit_code, 0) << replaced.err;
    EXPECT_NE(replaced.out.find(", written)"), std::string::npos) << replaced.out;
    EXPECT_EQ(bytesOf(d + "/out.glb"), cold_bytes);

    // A changed texture (named only inside the MTL) misses and bakes different bytes.
    fs::copy_file(d + "/assets/textures/barrel.png", d + "/assets/textures/crate.png",
                  fs::copy_options::overwrite_existing);
    const BakeRun texture = bakeIn(d, common);
    ASSERT_EQ(texture.exit_code, 0) << texture.err;
    EXPECT_EQ(texture.out.find("cache hit"), std::string::npos);
    EXPECT_NE(bytesOf(d + "/out.glb"), cold_bytes);
    // Other settings miss too; the same settings again hit.
    EXPECT_EQ(bakeIn(d, common + " --levels 0.5").out.find("cache hit"), std::string::npos);
    EXPECT_NE(bakeIn(d, common + " --levels 0.5").out.find("cache hit"), std::string::npos);
    // Bakers sharing one cache concurrently: all succeed with the same bytes, one entry per key.
    fs::remove_all(d + "/cache");
    std::string parallel = "(cd " + shellQuote(d) + " || exit 1; ";
    for (int i = 0; i < 4; ++i)
        parallel += shellQuote(lodbake_test::lodbakeCli()) + " bake assets/rock.ply -o rock" + std::to_string(i) +
                    ".glb --preset assets/light.json --cache-dir cache --quiet --threads 1 & ";
    parallel += "wait)";
    ASSERT_EQ(runCommand(parallel).exit_code, 0);
    for (int i = 1; i < 4; ++i) EXPECT_EQ(bytesOf(d + "/rock" + std::to_string(i) + ".glb"), bytesOf(d + "/rock0.glb"));
    EXPECT_FALSE(bytesOf(d + "/rock0.glb").empty());
    EXPECT_EQ(listDir(d + "/cache/v2/packs").size(), 1u);
    EXPECT_NE(
        bakeIn(d, "assets/rock.ply -o rock4.glb --preset assets/light.json --cache-dir cache").out.find("cache hit"),
        std::string::npos);
    // No temporaries left in the cache.
    for (const char* sub : {"cache/v2/packs", "cache/v2/deps"})
        for (const std::string& name : listDir(d + "/" + sub)) EXPECT_NE(name[0], '.') << name;
}

// A damaged cache (an entry cut short, a garbled byte in its pack, a garbled side-file list) is a
// miss: the bake runs again, writes the right bytes and repairs the entry; it never copies a broken pack.
TEST(PipelineCliTest, DamagedCacheEntriesMissAndAreRebaked) {
    const std::string d = sampleDir("damaged_cache");
    const std::string common = "assets/crate.obj -o out.glb --preset assets/light.json --cache-dir cache --quiet";
    ASSERT_EQ(bakeIn(d, common).exit_code, 0);
    const std::vector<uint8_t> good = bytesOf(d + "/out.glb");
    ASSERT_FALSE(good.empty());
    const std::vector<std::string> packs = listDir(d + "/cache/v2/packs"), deps = listDir(d + "/cache/v2/deps");
    ASSERT_EQ(packs.size(), 1u);
    ASSERT_EQ(deps.size(), 1u);
    const std::string entry = d + "/cache/v2/packs/" + packs[0], list = d + "/cache/v2/deps/" + deps[0];
    const std::vector<uint8_t> entry_bytes = bytesOf(entry);
    const std::vector<uint8_t> list_bytes = bytesOf(list);
    auto damage = [&](const std::string& path, std::vector<uint8_t> bytes, const char* what) {
        SCOPED_TRACE(what);
        ASSERT_TRUE(lodbake::writeFileAtomic(path, bytes.data(), bytes.size()).ok());
        fs::remove(d + "/out.glb");
        const BakeRun run = bakeIn(d, common + " --report r.json");
        ASSERT_EQ(run.exit_code, 0) << run.err;
        EXPECT_EQ(nlohmann::json::parse(textOf(d + "/r.json"))["cache"], "miss");
        EXPECT_EQ(bytesOf(d + "/out.glb"), good);
        lodbake::CacheEntry stored;
        EXPECT_TRUE(lodbake::parseCacheEntry(bytesOf(entry), stored)) << "the bake must store the entry again";
        EXPECT_EQ(stored.glb, good);
        EXPECT_EQ(bytesOf(list), list_bytes);
    };
    std::vector<uint8_t> cut(entry_bytes.begin(), entry_bytes.begin() + long(entry_bytes.size() / 2));
    damage(entry, cut, "entry cut in half");
    std::vector<uint8_t> head_only(entry_bytes.begin(), entry_bytes.begin() + 10);
    damage(entry, head_only, "entry cut inside its header");
    std::vector<uint8_t> garbled = entry_bytes;
    garbled[garbled.size() - 100] ^= 0x01; // one bit inside the GLB: same sizes, different bytes
    damage(entry, garbled, "one flipped bit in the pack");
    std::vector<uint8_t> sizes = entry_bytes;
    const size_t eol = size_t(std::find(sizes.begin() + 16, sizes.end(), uint8_t('\n')) - sizes.begin());
    // The last digit of the GLB's size (before " <16 hex digits>"): one more or nine fewer bytes.
    sizes[eol - 18] = uint8_t(sizes[eol - 18] == '9' ? '0' : sizes[eol - 18] + 1);
    damage(entry, sizes, "a section size lies");
    damage(entry, {}, "empty entry");
    std::vector<uint8_t> bad_list = list_bytes; // the first side file's name, first letter case-flipped
    const auto first_line_end = std::find(bad_list.begin(), bad_list.end(), uint8_t('\n'));
    const auto second_line_end = std::find(first_line_end + 1, bad_list.end(), uint8_t('\n'));
    ASSERT_LT(second_line_end + 1, bad_list.end()) << "the crate reads side files (MTL, texture)";
    second_line_end[1] ^= 0x20;
    damage(list, bad_list, "garbled side-file list");
    std::vector<uint8_t> short_list(list_bytes.begin(), list_bytes.begin() + long(list_bytes.size() / 3));
    damage(list, short_list, "side-file list cut short");
    // Undamaged, it hits again.
    fs::remove(d + "/out.glb");
    EXPECT_NE(bakeIn(d, "assets/crate.obj -o out.glb --preset assets/light.json --cache-dir cache").out.find(
                  "cache hit"),
              std::string::npos);
    EXPECT_EQ(bytesOf(d + "/out.glb"), good);
}

// The entry format itself: every truncation and every single flipped bit is refused.
TEST(PipelineCliTest, CacheEntryParserRefusesEveryTruncationAndFlippedBit) {
    lodbake::CacheEntry entry;
    entry.summary = "crate: 3 levels\n";
    entry.report_json = "{\"cache\":\"miss\"}";
    entry.glb = {'g', 'l', 'T', 'F', 2, 0, 0, 0, 1, 2, 3, 4};
    const std::vector<uint8_t> bytes = lodbake::serializeCacheEntry(entry);
    lodbake::CacheEntry back;
    ASSERT_TRUE(lodbake::parseCacheEntry(bytes, back));
    EXPECT_EQ(back.summary, entry.summary);
    EXPECT_EQ(back.report_json, entry.report_json);
    EXPECT_EQ(back.glb, entry.glb);
    for (size_t n = 0; n < bytes.size(); ++n) {
        const std::vector<uint8_t> cut(bytes.begin(), bytes.begin() + long(n));
        EXPECT_FALSE(lodbake::parseCacheEntry(cut, back)) << "cut to " << n << " bytes";
    }
    for (size_t i = 0; i < bytes.size(); ++i)
        for (int bit = 0; bit < 8; ++bit) {
            std::vector<uint8_t> flipped = bytes;
            flipped[i] ^= uint8_t(1u << bit);
            EXPECT_FALSE(lodbake::parseCacheEntry(flipped, back)) << "byte " << i << " bit " << bit;
        }
    std::vector<std::vector<std::string>> side;
    EXPECT_TRUE(lodbake::parseCacheDeps("lodbake-deps 1\ninput 0 1\ncrate.mtl\n", 1, side));
    EXPECT_EQ(side, (std::vector<std::vector<std::string>>{{"crate.mtl"}}));
    for (const char* bad : {"", "lodbake-deps 1\n", "lodbake-deps 1\ninput 0 2\ncrate.mtl\n",
                            "lodbake-deps 1\ninput 1 0\n", "lodbake-deps 1\ninput 0 1x\n", "lodbake-deps 2\ninput 0 0\n",
                            "lodbake-deps 1\ninput 0 1\n\n"})
        EXPECT_FALSE(lodbake::parseCacheDeps(bad, 1, side)) << bad;
}

TEST(PipelineCliTest, BytesDoNotDependOnTheCurrentDirectoryOrTheInputPath) {
    const std::string d = sampleDir("cwd");
    const std::string abs_assets = fs::absolute(d + "/assets").string();
    const BakeRun from_assets = bakeIn(d + "/assets", "crate.obj -o ../a.glb --preset light.json");
    const BakeRun from_root = bakeIn("/", shellQuote(abs_assets + "/crate.obj") + " -o " + shellQuote(d + "/b.glb") +
                                              " --preset " + shellQuote(abs_assets + "/light.json"));
    ASSERT_EQ(from_assets.exit_code, 0) << from_assets.err;
    ASSERT_EQ(from_root.exit_code, 0) << from_root.err;
    const std::vector<uint8_t> a = bytesOf(d + "/a.glb");
    EXPECT_EQ(a, bytesOf(d + "/b.glb"));
    const std::string text(a.begin(), a.end());
    EXPECT_EQ(text.find(abs_assets), std::string::npos) << "the pack names an absolute path";
    EXPECT_EQ(text.find("pipeline_cwd"), std::string::npos) << "the pack names the input folder";
}

// The huge-page heap a user may ask glibc for (docs/cli.md, "Environment") changes no output: the same
// bytes and the same summary as a bake without it.
TEST(PipelineCliTest, HugePageHeapSettingKeepsOutputAndBytes) {
    const std::string d = sampleDir("hugetlb");
    const std::string args = "assets/crate.obj assets/rock.ply -o 'out dir/' --preset assets/light.json --threads 2";
    const BakeRun huge = bakeIn(d, args, "GLIBC_TUNABLES=glibc.malloc.hugetlb=1 ");
    ASSERT_EQ(huge.exit_code, 0) << huge.err;
    fs::rename(d + "/out dir", d + "/first");
    const BakeRun kept = bakeIn(d, args);
    ASSERT_EQ(kept.exit_code, 0) << kept.err;
    EXPECT_EQ(huge.out, kept.out);
    // stderr: the same notes; the progress lines differ only in their times.
    auto withoutProgress = [](const std::string& err) {
        std::string kept_lines, line;
        std::istringstream in(err);
        while (std::getline(in, line))
            if (line.rfind("lodbake: [", 0) != 0) kept_lines += line + "\n";
        return kept_lines;
    };
    EXPECT_EQ(withoutProgress(huge.err), withoutProgress(kept.err));
    EXPECT_NE(huge.err.find("note: assets/crate.obj"), std::string::npos) << huge.err;
    for (const char* name : {"crate.glb", "rock.glb"}) {
        const std::vector<uint8_t> a = bytesOf(d + "/first/" + name);
        EXPECT_FALSE(a.empty()) << name;
        EXPECT_EQ(a, bytesOf(d + "/out dir/" + name)) << name;
    }
}

TEST(PipelineCliTest, ExitCodesQuietAndPlainProgress) {
    const std::string d = sampleDir("exit");
    EXPECT_EQ(bakeIn(d, "assets/crate.obj -o x.glb --no-such-flag").exit_code, 2);
    EXPECT_EQ(bakeIn(d, "-o out/").exit_code, 2);
    EXPECT_EQ(bakeIn(d, "assets/crate.obj -o x.glb --threads two").exit_code, 2);
    EXPECT_EQ(bakeIn(d, "assets/crate.obj assets/textures/../crate.obj -o out/").exit_code, 2); // same output twice
    // One missing input: exit 1, naming it; the other pack is still baked.
    const BakeRun missing = bakeIn(d, "assets/nothing.ply assets/rock.ply -o out/ --preset assets/light.json");
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_NE(missing.err.find("error: assets/nothing.ply"), std::string::npos) << missing.err;
    EXPECT_EQ(listDir(d + "/out"), std::vector<std::string>{"rock.glb"});
    // Not a terminal: one plain line per pack on stderr, no bar redraws.
    const BakeRun plain = bakeIn(d, "assets/rock.ply -o plain.glb --preset assets/light.json");
    ASSERT_EQ(plain.exit_code, 0);
    EXPECT_NE(plain.err.find("lodbake: [1/1] plain.glb: baked in"), std::string::npos) << plain.err;
    // The line names the three stages that took the most time, slowest first.
    std::smatch m;
    const std::string stage = "(load|repair|lod_chain|measure|pfrep|textures|encode|pack|write) ([0-9]+\\.[0-9]{2}) s";
    ASSERT_TRUE(std::regex_search(plain.err, m, std::regex("baked in [0-9.]+ s \\(" + stage + ", " + stage + ", " + stage + "\\)\n")))
        << plain.err;
    EXPECT_GE(std::stod(m[2].str()), std::stod(m[4].str()));
    EXPECT_GE(std::stod(m[4].str()), std::stod(m[6].str()));
    EXPECT_EQ(plain.err.find('\r'), std::string::npos);
    // --quiet: nothing at all on success (crate.obj has notes: two unused vertices).
    const BakeRun quiet = bakeIn(d, "assets/crate.obj -o quiet.glb --preset assets/light.json --quiet");
    ASSERT_EQ(quiet.exit_code, 0);
    EXPECT_EQ(quiet.out, "");
    EXPECT_EQ(quiet.err, "");
}

// SIGTERM or SIGINT mid-bake: the process dies by the signal and leaves neither the output nor a
// temporary. Delays spread over the run so some signals land while outputs are being written.
TEST(PipelineCliTest, InterruptedBakeLeavesNoOutputAndNoTemporaries) {
    LODBAKE_REQUIRE_SHARED_MESHES();
    const std::string d = sampleDir("signal");
    const std::string input = lodbake_test::sharedMesh("bunny_zipper.ply");
    int killed = 0;
    for (int attempt = 0; attempt < 6; ++attempt) {
        const std::string out = d + "/out" + std::to_string(attempt);
        fs::create_directories(out);
        const int sig = attempt % 2 ? SIGINT : SIGTERM;
        const pid_t pid = ::fork();
        if (pid == 0) {
            // A process group of its own, as a build system runs it; stdout/stderr silenced.
            ::setpgid(0, 0);
            const std::string cli = lodbake_test::lodbakeCli();
            const std::string preset = lodbake_test::sourceDir() + "/configs/mobile.json";
            const std::string pack = out + "/bunny.glb";
            const std::string report = out + "/report.json";
            std::freopen("/dev/null", "w", stdout);
            std::freopen("/dev/null", "w", stderr);
            ::execl(cli.c_str(), cli.c_str(), "bake", input.c_str(), "-o", pack.c_str(), "--preset", preset.c_str(),
                    "--report", report.c_str(), "--depfile", (out + "/bunny.d").c_str(), static_cast<char*>(nullptr));
            ::_exit(127);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(150 + 250 * attempt));
        ::kill(pid, sig);
        int status = 0;
        ::waitpid(pid, &status, 0);
        if (WIFSIGNALED(status)) {
            ++killed;
            EXPECT_EQ(WTERMSIG(status), sig);
            EXPECT_EQ(listDir(out), std::vector<std::string>{}) << "after signal " << sig << " at attempt " << attempt;
        } else {
            // Finished before the signal: then everything is there and nothing else.
            EXPECT_EQ(WEXITSTATUS(status), 0);
            EXPECT_EQ(listDir(out), (std::vector<std::string>{"bunny.d", "bunny.glb", "report.json"}));
        }
    }
    EXPECT_GE(killed, 1) << "every bake finished before its signal; the test did not interrupt anything";
}

} // namespace
