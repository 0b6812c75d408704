// Bake manifests: paths relative to the manifest, per-asset presets and overrides, every error
// naming the manifest and the JSON pointer, and the manifest schema (which must agree with the code
// and with the preset schema it repeats).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "../gltf/gltf_test_util.h"
#include "lodbake/config/bake_manifest.h"
#include "test_paths.h"

namespace {

namespace fs = std::filesystem;
using lodbake::BakeSettings;
using lodbake::parseBakeManifest;

std::string dir() {
    const std::string d = lodbake_test::scratchDir() + "/manifest_" + std::to_string(::getpid());
    fs::create_directories(d + "/presets");
    std::ofstream(d + "/presets/light.json") << R"({"version": 1, "lod_ratios": [0.5, 0.2], "error_samples": 2000})";
    return d;
}

std::string schemaCheck(const std::string& file) {
    return lodbake_test::python() + " " +
           lodbake_test::shellQuote(lodbake_test::sourceDir() + "/tests/support/validate_schema.py") + " " +
           lodbake_test::shellQuote(lodbake_test::sourceDir() + "/schemas/config/bake_manifest.schema.json") + " " +
           lodbake_test::shellQuote(file);
}

constexpr const char* kGood = R"({
  "version": 1,
  "preset": "presets/light.json",
  "output_dir": "packs",
  "assets": [
    {"input": "meshes/rock.ply"},
    {"inputs": ["a.obj", "b.obj"], "output": "ab.glb", "settings": {"lod_ratios": [0.3], "textures": {"enabled": false}}},
    {"input": "c.glb", "output": "sub/c_mobile.glb", "preset": "presets/light.json", "settings": {"pixel_threshold": 3}}
  ]
})";

TEST(BakeManifestTest, ResolvesPathsPresetsAndOverrides) {
    const std::string d = dir();
    const std::string path = d + "/assets.json";
    auto m = parseBakeManifest(kGood, path, BakeSettings{}, "");
    ASSERT_TRUE(m.ok()) << m.status().message();
    ASSERT_EQ(m->assets.size(), 3u);
    EXPECT_EQ(m->assets[0].inputs, std::vector<std::string>{d + "/meshes/rock.ply"});
    EXPECT_EQ(m->assets[0].output, d + "/packs/rock.glb");
    EXPECT_EQ(m->assets[0].settings.lod_ratios, (std::vector<double>{0.5, 0.2}));
    EXPECT_EQ(m->assets[0].settings_files, std::vector<std::string>{d + "/presets/light.json"});
    EXPECT_EQ(m->assets[1].inputs.size(), 2u);
    EXPECT_EQ(m->assets[1].output, d + "/packs/ab.glb");
    EXPECT_EQ(m->assets[1].settings.lod_ratios, std::vector<double>{0.3});
    EXPECT_FALSE(m->assets[1].settings.textures.enabled);
    EXPECT_EQ(m->assets[1].settings.error_samples, 2000u); // from the manifest preset
    EXPECT_EQ(m->assets[2].output, d + "/packs/sub/c_mobile.glb");
    EXPECT_EQ(m->assets[2].settings.pixel_threshold, 3.0);
    // -o DIR/ replaces output_dir.
    auto o = parseBakeManifest(kGood, path, BakeSettings{}, "elsewhere");
    ASSERT_TRUE(o.ok());
    EXPECT_EQ(o->assets[0].output, "elsewhere/rock.glb");
    // The example passes the schema.
    const std::string file = d + "/good.json";
    std::ofstream(file) << kGood;
    const auto r = lodbake_test::runCommand(schemaCheck(file));
    EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(BakeManifestTest, ErrorsNameTheManifestAndThePointer) {
    const std::string d = dir();
    const std::string path = d + "/m.json";
    struct Case {
        const char* json;
        const char* expected;
    };
    const Case cases[] = {
        {R"({"version": 1, "assets": [{"input": "a.ply", "ouput": "x.glb"}]})", "/assets/0/ouput: unknown key"},
        {R"({"version": 1, "asets": []})", "/asets: unknown key"},
        {R"({"assets": [{"input": "a.ply"}]})", "/version: required key missing"},
        {R"({"version": 2, "assets": [{"input": "a.ply"}]})", "/version: expected 1"},
        {R"({"version": 1, "assets": []})", "/assets: expected a non-empty array"},
        {R"({"version": 1, "assets": [{"output": "a.glb"}]})", "/assets/0: expected exactly one of"},
        {R"({"version": 1, "assets": [{"input": "a.ply", "inputs": ["b.ply"]}]})",
         "/assets/0: expected exactly one of"},
        {R"({"version": 1, "assets": [{"input": "a.ply", "output": "a.gltf"}]})", "/assets/0/output: expected a .glb"},
        {R"({"version": 1, "assets": [{"input": "x/a.ply"}, {"input": "y/a.obj"}]})",
         "is also the output of /assets/0"},
        {R"({"version": 1, "assets": [{"input": "a.ply", "settings": {"lod_ratio": [0.5]}}]})",
         "/assets/0/settings: /lod_ratio: unknown key"},
        {R"({"version": 1, "assets": [{"input": "a.ply", "settings": {"version": 1}}]})",
         "/settings/version: not allowed"},
        {R"({"version": 1, "assets": [{"input": 7}]})", "/assets/0/input: expected a non-empty path string"},
        {R"({"version": 1, "assets": [{"input": "a.ply", "preset": "a\nngltf"}]})",
         "/assets/0/preset: expected a path without control characters"}, // found by the manifest fuzzer
        {R"({"version": 1, "assets": [{"input": "a\tb.ply"}]})", "/assets/0/input: expected a path without control"},
        {R"({"version": 1, "preset": "missing.json", "assets": [{"input": "a.ply"}]})", "missing.json"},
        {R"({"version": 1, "assets": [)", "not valid JSON"},
    };
    for (const Case& c : cases) {
        auto m = parseBakeManifest(c.json, path, BakeSettings{}, "");
        ASSERT_FALSE(m.ok()) << c.json;
        EXPECT_NE(m.status().message().find(c.expected), std::string::npos) << m.status().message();
        EXPECT_EQ(m.status().message().rfind(path, 0), 0u) << m.status().message();
    }
    // The schema rejects the same unknown keys.
    const std::string file = d + "/bad.json";
    std::ofstream(file) << cases[0].json;
    EXPECT_NE(lodbake_test::runCommand(schemaCheck(file)).exit_code, 0);
}

// Damaged manifests: every truncation of a good one, single bytes garbled into control characters,
// quotes and brackets, and hostile shapes (deep nesting, keys and paths holding line breaks) are
// refused with one line naming the manifest, or (a truncation that is still a whole document)
// read as what they say.
TEST(BakeManifestTest, TruncatedAndGarbledManifestsFailOnOneLine) {
    const std::string d = dir();
    const std::string path = d + "/m.json";
    const std::string good = kGood;
    auto check = [&](const std::string& text, const std::string& what) {
        auto m = parseBakeManifest(text, path, BakeSettings{}, "");
        if (m.ok()) return true;
        const std::string& message = m.status().message();
        EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << what << ": " << message;
        EXPECT_EQ(message.find('\n'), std::string::npos) << what << ": " << message;
        return false;
    };
    size_t accepted = 0;
    for (size_t n = 0; n < good.size(); ++n) accepted += check(good.substr(0, n), "cut to " + std::to_string(n));
    EXPECT_EQ(accepted, 0u) << "a strict prefix of the manifest is never a whole JSON document";
    for (size_t i = 0; i < good.size(); ++i)
        for (char c : {'\0', '\n', '"', '{', ']', '\x7f'}) {
            std::string garbled = good;
            garbled[i] = c;
            check(garbled, "byte " + std::to_string(i) + " set to " + std::to_string(int(c)));
        }
    const std::string deep = std::string(100000, '[') + std::string(100000, ']');
    EXPECT_FALSE(check(R"({"version": 1, "assets": )" + deep + "}", "deep nesting"));
    auto m = parseBakeManifest(R"({"version": 1, "assets": )" + deep + "}", path, BakeSettings{}, "");
    EXPECT_NE(m.status().message().find("levels of nested arrays and objects"), std::string::npos)
        << m.status().message();
    EXPECT_FALSE(check(R"({"version": 1, "assets": [{"input": "a.ply", "a\nb": 1}]})", "key with a line break"));
    EXPECT_FALSE(check(R"({"version": 1, "assets": [{"input": "a.ply", "output": "x\ny.gltf"}]})",
                       "output with a line break"));
    EXPECT_FALSE(check(R"({"version": 1, "assets": [{"input": "a\n.ply"}, {"input": "a\n.obj"}]})",
                       "two outputs with a line break"));
}

TEST(BakeManifestTest, SchemaSettingsRepeatThePresetSchema) {
    auto load = [](const std::string& name) {
        std::ifstream in(lodbake_test::sourceDir() + "/schemas/config/" + name);
        return nlohmann::json::parse(in);
    };
    const nlohmann::json preset = load("bake_preset.schema.json");
    const nlohmann::json manifest = load("bake_manifest.schema.json");
    nlohmann::json props = preset["properties"];
    props.erase("version");
    EXPECT_EQ(manifest["$defs"]["settings"]["properties"], props);
    EXPECT_EQ(manifest["$defs"]["textures"], preset["$defs"]["textures"]);
    EXPECT_EQ(manifest["$defs"]["stream_precision"], preset["$defs"]["stream_precision"]);
    EXPECT_EQ(manifest["properties"]["version"]["enum"][0].get<int>(), lodbake::kBakeManifestVersion);
}

} // namespace
