// Bake presets: parsing, unknown keys, overrides, the printed config and the preset schema.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "../gltf/gltf_test_util.h"
#include "lodbake/config/bake_config.h"
#include "test_paths.h"

namespace {

using namespace lodbake;

std::string presetPath(const std::string& name) {
    return lodbake_test::sourceDir() + "/configs/" + name + ".json";
}

std::string schemaCheck(const std::string& schema, const std::string& args) {
    return lodbake_test::python() + " " +
           lodbake_test::shellQuote(lodbake_test::sourceDir() + "/tests/support/validate_schema.py") + " " +
           lodbake_test::shellQuote(lodbake_test::sourceDir() + "/schemas/" + schema) + " " + args;
}

TEST(BakeConfigTest, EveryBundledPresetParsesAndMatchesTheSchema) {
    std::string files;
    for (const char* name : {"desktop", "mobile", "vr", "archive"}) {
        BakeSettings settings;
        const Status s = applyPresetFile(presetPath(name), settings);
        EXPECT_TRUE(s.ok()) << s.message();
        files += " " + lodbake_test::shellQuote(presetPath(name));
    }
    const auto r = lodbake_test::runCommand(schemaCheck("config/bake_preset.schema.json", files));
    EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(BakeConfigTest, PresetOverridesOnlyWhatItNames) {
    BakeSettings settings;
    ASSERT_TRUE(applyPresetJson(R"({"version": 1, "pixel_threshold": 2.5, "textures": {"max_size_px": 512}})", "p.json",
                                settings)
                    .ok());
    EXPECT_EQ(settings.pixel_threshold, 2.5);
    EXPECT_EQ(settings.textures.max_size_px, 512u);
    const BakeSettings defaults;
    EXPECT_EQ(settings.lod_ratios, defaults.lod_ratios);
    EXPECT_EQ(settings.textures.min_size_px, defaults.textures.min_size_px);
}

// Adaptive stream precision is on in the size-minded presets and off in archive (docs/bake.md).
TEST(BakeConfigTest, AdaptivePrecisionIsOnExceptInArchive) {
    EXPECT_FALSE(BakeSettings{}.stream_precision.adaptive);
    for (const char* name : {"desktop", "mobile", "vr", "archive"}) {
        BakeSettings settings;
        ASSERT_TRUE(applyPresetFile(presetPath(name), settings).ok()) << name;
        EXPECT_EQ(settings.stream_precision.adaptive, std::string(name) != "archive") << name;
        EXPECT_EQ(settings.stream_precision.position_bits, 14u) << name;
        EXPECT_EQ(settings.stream_precision.normal_bits, 8u) << name;
    }
}

TEST(BakeConfigTest, UnknownKeyIsAnErrorNamingKeyAndFile) {
    BakeSettings settings;
    Status s = applyPresetJson(R"({"version": 1, "pixel_treshold": 2})", "my.json", settings);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message().rfind("my.json: /pixel_treshold: unknown key", 0), 0u) << s.message();
    s = applyPresetJson(R"({"version": 1, "textures": {"max_px": 2}})", "my.json", settings);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.message().rfind("my.json: /textures/max_px: unknown key", 0), 0u) << s.message();
    EXPECT_EQ(settings.pixel_threshold, BakeSettings{}.pixel_threshold); // untouched on error
}

TEST(BakeConfigTest, WrongTypesRangesAndVersionsAreErrors) {
    const std::pair<const char*, const char*> cases[] = {
        {R"({"pixel_threshold": 1})", "/version: required key missing"},
        {R"({"version": 2})", "/version: expected 1, got 2"},
        {R"({"version": 1, "repair": "yes"})", "/repair: expected true or false"},
        {R"({"version": 1, "lod_ratios": [0.5, 1.5]})", "/lod_ratios/1: expected a number in (0, 1]"},
        {R"({"version": 1, "lod_ratios": []})", "/lod_ratios: expected an array"},
        {R"({"version": 1, "threads": 1.5})", "/threads: expected an integer"},
        {R"({"version": 1, "textures": {"min_size_px": 64, "max_size_px": 32}})", "min_size_px 64 must not exceed"},
        {R"({"version": 1, "stream_precision": {"position_bits": 20}})",
         "/stream_precision/position_bits: expected an integer in [8, 16]"},
        {R"({"version": 1, "stream_precision": {"error_fraction": 0}})",
         "/stream_precision/error_fraction: expected a number in (0, 1]"},
        {R"({"version": 1, "stream_precision": {"adaptive": 1}})",
         "/stream_precision/adaptive: expected true or false"},
        {R"({"version": 1, "stream_precision": {"bits": 8}})", "/stream_precision/bits: unknown key"},
        {R"({"version": 1, "pfrep_format": 6})", "/pfrep_format: expected an integer in [2, 5]"},
        {R"({"version": 1, "pfrep_region_block": 32})", "/pfrep_region_block: expected an integer in [64, 65536]"},
        {R"([1, 2])", "expected a JSON object"},
        {R"({"version": 1,)", "not valid JSON"},
    };
    for (const auto& c : cases) {
        BakeSettings settings;
        const Status s = applyPresetJson(c.first, "x.json", settings);
        ASSERT_FALSE(s.ok()) << c.first;
        EXPECT_EQ(s.message().rfind("x.json: ", 0), 0u) << s.message();
        EXPECT_NE(s.message().find(c.second), std::string::npos) << s.message();
    }
}

TEST(BakeConfigTest, PrintedConfigHasSortedKeysRoundTripsAndMatchesTheSchema) {
    BakeSettings settings;
    ASSERT_TRUE(applyPresetFile(presetPath("vr"), settings).ok());
    const std::string text = settingsToJson(settings);
    // Top-level keys in sorted order.
    std::vector<std::string> keys;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);)
        if (line.rfind("  \"", 0) == 0) keys.push_back(line.substr(3, line.find('"', 3) - 3));
    // Every schema property, each once (the schema lists "version" too).
    std::ifstream schema_in(lodbake_test::sourceDir() + "/schemas/config/bake_preset.schema.json");
    ASSERT_EQ(keys.size(), nlohmann::json::parse(schema_in)["properties"].size()) << text;
    EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end())) << text;
    BakeSettings again;
    ASSERT_TRUE(applyPresetJson(text, "printed", again).ok());
    EXPECT_EQ(settingsToJson(again), text);
    const std::string path = lodbake_test::scratchDir() + "/printed_config.json";
    std::ofstream(path) << text;
    const auto r =
        lodbake_test::runCommand(schemaCheck("config/bake_preset.schema.json", lodbake_test::shellQuote(path)));
    EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(BakeConfigTest, SchemaDefaultsMirrorTheCode) {
    std::ifstream in(lodbake_test::sourceDir() + "/schemas/config/bake_preset.schema.json");
    const nlohmann::json schema = nlohmann::json::parse(in);
    const nlohmann::json printed = nlohmann::json::parse(settingsToJson(BakeSettings{}));
    for (auto it = printed.begin(); it != printed.end(); ++it) {
        if (it.key() == "version") continue;
        if (it.key() == "textures" || it.key() == "stream_precision") {
            const nlohmann::json& props = schema["$defs"][it.key()]["properties"];
            for (auto t = it.value().begin(); t != it.value().end(); ++t)
                EXPECT_EQ(props[t.key()]["default"], t.value()) << it.key() << "." << t.key();
            EXPECT_EQ(props.size(), it.value().size());
            continue;
        }
        EXPECT_EQ(schema["properties"][it.key()]["default"], it.value()) << it.key();
    }
    EXPECT_EQ(schema["properties"].size(), printed.size());
}

} // namespace
