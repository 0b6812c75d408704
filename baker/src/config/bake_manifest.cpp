// Bake manifests: JSON (nlohmann-json, exceptions caught here) into one ManifestAsset per pack.
// Setting overrides go through applyPresetJson, so they obey exactly the preset schema.
#include "lodbake/config/bake_manifest.h"

#include <exception>
#include <filesystem>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "lodbake/core/file_io.h"
#include "lodbake/core/json_limits.h"

namespace lodbake {

namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

std::string kindOf(const Json& v) {
    return v.is_number()    ? "a number"
           : v.is_boolean() ? "a boolean"
           : v.is_string()  ? "a string"
           : v.is_array()   ? "an array"
           : v.is_object()  ? "an object"
                            : "null";
}

Status expected(const std::string& where, const std::string& what, const Json& got) {
    return invalidInput(where + ": expected " + what + ", got " + kindOf(got) + " " + got.dump());
}

Status checkKeys(const Json& object, const std::string& where, const std::set<std::string>& known) {
    for (auto it = object.begin(); it != object.end(); ++it) {
        if (known.count(it.key())) continue;
        std::string list;
        for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
        // Quoted the JSON way (control characters escaped) so that the message stays one line.
        const std::string quoted = Json(it.key()).dump();
        return invalidInput(where + "/" + quoted.substr(1, quoted.size() - 2) + ": unknown key (known keys: " + list +
                            ")");
    }
    return Status::okStatus();
}

Result<std::string> readPath(const Json& v, const std::string& where) {
    if (!v.is_string() || v.get<std::string>().empty()) return expected(where, "a non-empty path string", v);
    // A line break or other control character in a path would split the errors that name the file.
    for (const char c : v.get<std::string>())
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
            return expected(where, "a path without control characters", v);
    return v.get<std::string>();
}

// Relative paths are relative to `base_dir`; absolute ones are kept.
std::string resolve(const std::string& base_dir, const std::string& p) {
    if (fs::path(p).is_absolute()) return fs::path(p).lexically_normal().string();
    return fs::path(joinPath(base_dir, p)).lexically_normal().string();
}

// A preset error as the manifest sees it: "<manifest>: <pointer>: <preset error>".
Status inContext(const Status& status, const std::string& where) {
    if (status.ok()) return status;
    return Status(status.code(), where + ": " + status.message());
}

std::string stemOf(const std::string& p) {
    return fs::path(p).stem().string();
}

Result<BakeManifest> parseImpl(const Json& root, const std::string& path, const BakeSettings& base,
                               const std::string& output_dir_override) {
    const std::string dir = parentDirectory(path);
    if (!root.is_object()) return expected(path + ": /", "a JSON object", root);
    LODBAKE_RETURN_IF_ERROR(checkKeys(root, path + ": ", {"version", "preset", "output_dir", "assets"}));
    if (!root.contains("version")) return invalidInput(path + ": /version: required key missing");
    const Json& version = root["version"];
    if (!version.is_number_integer() || version.get<int64_t>() != kBakeManifestVersion)
        return invalidInput(path + ": /version: expected " + std::to_string(kBakeManifestVersion) + ", got " +
                            version.dump());
    BakeSettings manifest_settings = base;
    std::vector<std::string> manifest_presets;
    if (root.contains("preset")) {
        LODBAKE_ASSIGN_OR_RETURN(std::string preset, readPath(root["preset"], path + ": /preset"));
        preset = resolve(dir, preset);
        LODBAKE_RETURN_IF_ERROR(inContext(applyPresetFile(preset, manifest_settings), path + ": /preset"));
        manifest_presets.push_back(preset);
    }
    std::string output_dir = dir;
    if (!output_dir_override.empty()) {
        output_dir = output_dir_override;
    } else if (root.contains("output_dir")) {
        LODBAKE_ASSIGN_OR_RETURN(std::string d, readPath(root["output_dir"], path + ": /output_dir"));
        output_dir = resolve(dir, d);
    }
    if (!root.contains("assets")) return invalidInput(path + ": /assets: required key missing");
    const Json& assets = root["assets"];
    if (!assets.is_array() || assets.empty()) return expected(path + ": /assets", "a non-empty array", assets);

    BakeManifest manifest;
    std::map<std::string, size_t> outputs; // normalised output path -> asset index
    for (size_t i = 0; i < assets.size(); ++i) {
        const std::string where = path + ": /assets/" + std::to_string(i);
        const Json& a = assets[i];
        if (!a.is_object()) return expected(where, "an object", a);
        LODBAKE_RETURN_IF_ERROR(checkKeys(a, where, {"input", "inputs", "output", "preset", "settings"}));
        ManifestAsset asset;
        asset.settings = manifest_settings;
        asset.settings_files = manifest_presets;
        if (a.contains("input") == a.contains("inputs"))
            return invalidInput(where +
                                ": expected exactly one of \"input\" (a path) or \"inputs\" (an array of paths)");
        if (a.contains("input")) {
            LODBAKE_ASSIGN_OR_RETURN(std::string in, readPath(a["input"], where + "/input"));
            asset.inputs.push_back(resolve(dir, in));
        } else {
            const Json& list = a["inputs"];
            if (!list.is_array() || list.empty())
                return expected(where + "/inputs", "a non-empty array of paths", list);
            for (size_t k = 0; k < list.size(); ++k) {
                LODBAKE_ASSIGN_OR_RETURN(std::string in, readPath(list[k], where + "/inputs/" + std::to_string(k)));
                asset.inputs.push_back(resolve(dir, in));
            }
        }
        if (a.contains("output")) {
            LODBAKE_ASSIGN_OR_RETURN(std::string out, readPath(a["output"], where + "/output"));
            asset.output = resolve(output_dir, out);
        } else {
            asset.output = joinPath(output_dir, stemOf(asset.inputs.front()) + ".glb");
        }
        if (lowerExtension(asset.output) != ".glb")
            return invalidInput(where + "/output: expected a .glb path, got " + Json(asset.output).dump());
        if (a.contains("preset")) {
            LODBAKE_ASSIGN_OR_RETURN(std::string preset, readPath(a["preset"], where + "/preset"));
            preset = resolve(dir, preset);
            asset.settings = base; // an asset preset replaces the manifest's
            asset.settings_files = {preset};
            LODBAKE_RETURN_IF_ERROR(inContext(applyPresetFile(preset, asset.settings), where + "/preset"));
        }
        if (a.contains("settings")) {
            const Json& overrides = a["settings"];
            if (!overrides.is_object()) return expected(where + "/settings", "an object of preset keys", overrides);
            if (overrides.contains("version"))
                return invalidInput(where + "/settings/version: not allowed here (the manifest's version applies)");
            Json preset = overrides;
            preset["version"] = kBakePresetVersion;
            LODBAKE_RETURN_IF_ERROR(applyPresetJson(preset.dump(), where + "/settings", asset.settings));
        }
        const std::string key = fs::path(asset.output).lexically_normal().string();
        const auto [it, inserted] = outputs.emplace(key, i);
        if (!inserted)
            return invalidInput(where + "/output: " + Json(asset.output).dump() + " is also the output of /assets/" +
                                std::to_string(it->second));
        manifest.assets.push_back(std::move(asset));
    }
    return manifest;
}

} // namespace

Result<BakeManifest> parseBakeManifest(const std::string& json_text, const std::string& path, const BakeSettings& base,
                                       const std::string& output_dir_override) {
    // A manifest nests four levels (assets, an asset, its settings, a setting's object); refuse deep
    // documents before nlohmann-json's recursion sees them.
    constexpr uint32_t kMaxManifestDepth = 16;
    const JsonDepthScan depth =
        scanJsonDepth(reinterpret_cast<const uint8_t*>(json_text.data()), json_text.size(), kMaxManifestDepth);
    if (depth.is_too_deep)
        return invalidInput(path + ": byte " + std::to_string(depth.offset) + ": expected at most " +
                            std::to_string(kMaxManifestDepth) + " levels of nested arrays and objects");
    try {
        const Json root = Json::parse(json_text);
        return parseImpl(root, path, base, output_dir_override);
    } catch (const Json::parse_error& e) {
        return invalidInput(path + ": not valid JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    } catch (const std::exception& e) {
        return invalidInput(path + ": " + e.what());
    }
}

Result<BakeManifest> readBakeManifest(const std::string& path, const BakeSettings& base,
                                      const std::string& output_dir_override) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path, uint64_t(1) << 26));
    return parseBakeManifest(std::string(bytes.begin(), bytes.end()), path, base, output_dir_override);
}

} // namespace lodbake
