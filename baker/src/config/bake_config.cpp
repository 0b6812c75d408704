// Bake presets: JSON (nlohmann-json, its exceptions caught here) applied over BakeSettings. Every
// key is known; anything else is an error naming the key and the file, so a typo never bakes with
// defaults silently.
#include "lodbake/config/bake_config.h"

#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <map>

#include <nlohmann/json.hpp>

#include "lodbake/core/file_io.h"
#include "lodbake/core/json_limits.h"
#include "lodbake/core/json_writer.h"

namespace lodbake {

namespace {

using Json = nlohmann::json;

std::string typeName(const Json& v) {
    return v.is_number()    ? "a number"
           : v.is_boolean() ? "a boolean"
           : v.is_string()  ? "a string"
           : v.is_array()   ? "an array"
           : v.is_object()  ? "an object"
                            : "null";
}

// The offending value as JSON text, cut short so that one huge value cannot make a huge message.
std::string shortDump(const Json& v) {
    std::string text = v.dump();
    constexpr size_t kMaxChars = 80;
    if (text.size() > kMaxChars) text = text.substr(0, kMaxChars - 3) + "...";
    return text;
}

Status expected(const std::string& where, const std::string& what, const Json& got) {
    return invalidInput(where + ": expected " + what + ", got " + typeName(got) + " " + shortDump(got));
}

Status readNumber(const Json& v, const std::string& where, double lo, double hi, bool lo_exclusive, double& out) {
    if (!v.is_number()) return expected(where, "a number", v);
    const double d = v.get<double>();
    if (!std::isfinite(d) || (lo_exclusive ? !(d > lo) : !(d >= lo)) || !(d <= hi))
        return invalidInput(where + ": expected a number in " + (lo_exclusive ? "(" : "[") +
                            JsonWriter::formatNumber(lo) + ", " + JsonWriter::formatNumber(hi) + "], got " +
                            shortDump(v));
    out = d;
    return Status::okStatus();
}

Status readUint(const Json& v, const std::string& where, uint32_t lo, uint32_t hi, uint32_t& out) {
    if (!v.is_number_integer() && !(v.is_number_float() && std::floor(v.get<double>()) == v.get<double>()))
        return expected(where, "an integer", v);
    const double d = v.get<double>();
    if (!(d >= lo && d <= hi))
        return invalidInput(where + ": expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                            "], got " + shortDump(v));
    out = uint32_t(d);
    return Status::okStatus();
}

Status readBool(const Json& v, const std::string& where, bool& out) {
    if (!v.is_boolean()) return expected(where, "true or false", v);
    out = v.get<bool>();
    return Status::okStatus();
}

std::string minSwitchRatioExpected() {
    char text[80];
    std::snprintf(text, sizeof text, "expected 0 or a number in [%g, %g]", kMinSwitchRatioLow, kMinSwitchRatioHigh);
    return text;
}

// A member handler gets the value and its location "<file>: <JSON pointer>" for messages.
using Handler = std::function<Status(const Json&, const std::string&)>;

// Applies the members of `object` (at `file`: `pointer`) through `handlers`; unknown keys are errors.
Status applyObject(const Json& object, const std::string& file, const std::string& pointer,
                   const std::map<std::string, Handler>& handlers) {
    if (!object.is_object()) return expected(file + ": " + (pointer.empty() ? "/" : pointer), "an object", object);
    for (auto it = object.begin(); it != object.end(); ++it) {
        // Keys are quoted the JSON way (control characters escaped) so that a message stays one line.
        const std::string quoted = Json(it.key()).dump();
        const std::string member = pointer + "/" + quoted.substr(1, quoted.size() - 2);
        const auto h = handlers.find(it.key());
        if (h == handlers.end()) {
            std::string known;
            for (const auto& k : handlers) known += (known.empty() ? "" : ", ") + k.first;
            return invalidInput(file + ": " + member + ": unknown key (known keys: " + known + ")");
        }
        LODBAKE_RETURN_IF_ERROR(h->second(it.value(), file + ": " + member));
    }
    return Status::okStatus();
}

Status applyImpl(const Json& root, const std::string& name, BakeSettings& s) {
    if (!root.is_object()) return expected(name, "a JSON object", root);
    if (!root.contains("version")) return invalidInput(name + ": /version: required key missing");
    const Json& version = root["version"];
    if (!version.is_number_integer() || version.get<int64_t>() != kBakePresetVersion)
        return invalidInput(name + ": /version: expected " + std::to_string(kBakePresetVersion) + ", got " +
                            shortDump(version));
    TextureLodSettings& t = s.textures;
    const std::map<std::string, Handler> texture_handlers{
        {"enabled", [&](const Json& v, const std::string& w) { return readBool(v, w, t.enabled); }},
        {"max_size_px", [&](const Json& v, const std::string& w) { return readUint(v, w, 1, 65536, t.max_size_px); }},
        {"min_size_px", [&](const Json& v, const std::string& w) { return readUint(v, w, 1, 65536, t.min_size_px); }},
        {"texels_per_pixel",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 0.0, 64.0, true, t.texels_per_pixel); }},
        {"keep_unreadable_images",
         [&](const Json& v, const std::string& w) { return readBool(v, w, t.keep_unreadable_images); }},
    };
    StreamPrecisionSettings& q = s.stream_precision;
    const std::map<std::string, Handler> precision_handlers{
        {"adaptive", [&](const Json& v, const std::string& w) { return readBool(v, w, q.adaptive); }},
        {"error_fraction",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 0.0, 1.0, true, q.error_fraction); }},
        {"normal_bits", [&](const Json& v, const std::string& w) { return readUint(v, w, 4, 16, q.normal_bits); }},
        {"position_bits", [&](const Json& v, const std::string& w) { return readUint(v, w, 8, 16, q.position_bits); }},
    };
    const std::map<std::string, Handler> handlers{
        {"version", [&](const Json&, const std::string&) { return Status::okStatus(); }},
        {"lod_ratios",
         [&](const Json& v, const std::string& w) -> Status {
             if (!v.is_array() || v.empty() || v.size() > 16)
                 return expected(w, "an array of 1 to 16 numbers in (0, 1]", v);
             std::vector<double> ratios(v.size());
             for (size_t i = 0; i < v.size(); ++i)
                 LODBAKE_RETURN_IF_ERROR(readNumber(v[i], w + "/" + std::to_string(i), 0.0, 1.0, true, ratios[i]));
             s.lod_ratios = ratios;
             return Status::okStatus();
         }},
        {"pixel_threshold",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 0.0, 1e4, true, s.pixel_threshold); }},
        {"viewport_height_px",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 1.0, 1e5, false, s.viewport_height_px); }},
        {"vertical_fov_deg",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 1.0, 179.0, false, s.vertical_fov_deg); }},
        {"hysteresis",
         [&](const Json& v, const std::string& w) { return readNumber(v, w, 0.0, 0.9, false, s.hysteresis); }},
        {"lod_min_switch_ratio",
         [&](const Json& v, const std::string& w) -> Status {
             if (!v.is_number()) return expected(w, "a number", v);
             const double d = v.get<double>();
             if (!isValidMinSwitchRatio(d))
                 return invalidInput(w + ": " + minSwitchRatioExpected() + ", got " + shortDump(v));
             s.lod_min_switch_ratio = d;
             return Status::okStatus();
         }},
        {"repair", [&](const Json& v, const std::string& w) { return readBool(v, w, s.repair); }},
        {"error_samples",
         [&](const Json& v, const std::string& w) { return readUint(v, w, 1000, 100000000, s.error_samples); }},
        {"textures",
         [&](const Json& v, const std::string&) { return applyObject(v, name, "/textures", texture_handlers); }},
        {"threads", [&](const Json& v, const std::string& w) { return readUint(v, w, 0, 1024, s.threads); }},
        {"memory_limit_mib",
         [&](const Json& v, const std::string& w) { return readUint(v, w, 0, 1u << 30, s.memory_limit_mib); }},
        {"compact", [&](const Json& v, const std::string& w) { return readBool(v, w, s.compact); }},
        {"web", [&](const Json& v, const std::string& w) { return readBool(v, w, s.web); }},
        {"progressive_fans", [&](const Json& v, const std::string& w) { return readBool(v, w, s.progressive_fans); }},
        {"pfrep_from_chain", [&](const Json& v, const std::string& w) { return readBool(v, w, s.pfrep_from_chain); }},
        {"pfrep_format", [&](const Json& v, const std::string& w) { return readUint(v, w, 2, 5, s.pfrep_format); }},
        {"pfrep_region_block",
         [&](const Json& v, const std::string& w) {
             return readUint(v, w, kMinPfrepRegionBlock, kMaxPfrepRegionBlock, s.pfrep_region_block);
         }},
        {"cluster_lod", [&](const Json& v, const std::string& w) { return readBool(v, w, s.cluster_lod); }},
        {"remove_covered_components",
         [&](const Json& v, const std::string& w) { return readBool(v, w, s.remove_covered_components); }},
        {"merge",
         [&](const Json& v, const std::string& w) -> Status {
             if (!v.is_string() || !parseMergeMode(v.get<std::string>(), s.merge))
                 return expected(w, "one of \"auto\", \"poisson\", \"off\"", v);
             return Status::okStatus();
         }},
        {"merge_scene", [&](const Json& v, const std::string& w) { return readBool(v, w, s.merge_scene); }},
        {"stream_precision",
         [&](const Json& v, const std::string&) {
             return applyObject(v, name, "/stream_precision", precision_handlers);
         }},
    };
    return applyObject(root, name, "", handlers);
}

} // namespace

Status applyPresetJson(const std::string& json_text, const std::string& name, BakeSettings& settings) {
    BakeSettings updated = settings; // all or nothing
    // A preset nests two levels; refuse deep documents before nlohmann-json's recursion sees them.
    constexpr uint32_t kMaxPresetDepth = 16;
    const JsonDepthScan depth =
        scanJsonDepth(reinterpret_cast<const uint8_t*>(json_text.data()), json_text.size(), kMaxPresetDepth);
    if (depth.is_too_deep)
        return invalidInput(name + ": byte " + std::to_string(depth.offset) + ": expected at most " +
                            std::to_string(kMaxPresetDepth) + " levels of nested arrays and objects");
    try {
        const Json root = Json::parse(json_text);
        LODBAKE_RETURN_IF_ERROR(applyImpl(root, name, updated));
    } catch (const Json::parse_error& e) {
        return invalidInput(name + ": not valid JSON at byte " + std::to_string(e.byte) + ": " + e.what());
    } catch (const std::exception& e) {
        return invalidInput(name + ": " + e.what());
    }
    LODBAKE_RETURN_IF_ERROR(validateSettings(updated, name));
    settings = updated;
    return Status::okStatus();
}

Status applyPresetFile(const std::string& path, BakeSettings& settings) {
    LODBAKE_ASSIGN_OR_RETURN(std::vector<uint8_t> bytes, readFileBytes(path, uint64_t(1) << 20));
    return applyPresetJson(std::string(bytes.begin(), bytes.end()), path, settings);
}

Status validateSettings(const BakeSettings& settings, const std::string& name) {
    if (settings.textures.min_size_px > settings.textures.max_size_px)
        return invalidInput(name + ": /textures: min_size_px " + std::to_string(settings.textures.min_size_px) +
                            " must not exceed max_size_px " + std::to_string(settings.textures.max_size_px));
    if (!isValidMinSwitchRatio(settings.lod_min_switch_ratio))
        return invalidInput(name + ": /lod_min_switch_ratio: " + minSwitchRatioExpected() + ", got " +
                            JsonWriter::formatNumber(settings.lod_min_switch_ratio));
    // --compact keeps the level data only in LODBAKE_ streams, --web only in EXT_meshopt_compression.
    if (settings.compact && settings.web)
        return invalidInput(name + ": /web: cannot be combined with compact (a pack keeps its level data in one form)");
    // A --web pack carries no LODBAKE_ extension at all (docs/format/web.md).
    if (settings.web && settings.cluster_lod)
        return invalidInput(name + ": /cluster_lod: cannot be combined with web (a web pack has no LODBAKE_ extensions)");
    return Status::okStatus();
}

const char* mergeModeName(MergeMode mode) {
    switch (mode) {
    case MergeMode::Off: return "off";
    case MergeMode::Auto: return "auto";
    case MergeMode::Poisson: return "poisson";
    }
    return "off";
}

bool parseMergeMode(const std::string& text, MergeMode& mode) {
    for (MergeMode m : {MergeMode::Off, MergeMode::Auto, MergeMode::Poisson})
        if (text == mergeModeName(m)) {
            mode = m;
            return true;
        }
    return false;
}

std::string settingsToJson(const BakeSettings& s) {
    try {
        // nlohmann::json objects are std::map based: keys come out sorted.
        Json j;
        j["version"] = s.version;
        j["lod_ratios"] = s.lod_ratios;
        j["pixel_threshold"] = s.pixel_threshold;
        j["viewport_height_px"] = s.viewport_height_px;
        j["vertical_fov_deg"] = s.vertical_fov_deg;
        j["hysteresis"] = s.hysteresis;
        j["lod_min_switch_ratio"] = s.lod_min_switch_ratio;
        j["repair"] = s.repair;
        j["error_samples"] = s.error_samples;
        j["textures"] = {{"enabled", s.textures.enabled},
                         {"max_size_px", s.textures.max_size_px},
                         {"min_size_px", s.textures.min_size_px},
                         {"texels_per_pixel", s.textures.texels_per_pixel},
                         {"keep_unreadable_images", s.textures.keep_unreadable_images}};
        j["threads"] = s.threads;
        j["memory_limit_mib"] = s.memory_limit_mib;
        j["compact"] = s.compact;
        j["web"] = s.web;
        j["progressive_fans"] = s.progressive_fans;
        j["pfrep_from_chain"] = s.pfrep_from_chain;
        j["pfrep_format"] = s.pfrep_format;
        j["pfrep_region_block"] = s.pfrep_region_block;
        j["cluster_lod"] = s.cluster_lod;
        j["remove_covered_components"] = s.remove_covered_components;
        j["merge"] = mergeModeName(s.merge);
        j["merge_scene"] = s.merge_scene;
        j["stream_precision"] = {{"adaptive", s.stream_precision.adaptive},
                                 {"error_fraction", s.stream_precision.error_fraction},
                                 {"normal_bits", s.stream_precision.normal_bits},
                                 {"position_bits", s.stream_precision.position_bits}};
        return j.dump(2) + "\n";
    } catch (const std::exception&) {
        return "{}\n"; // dump only throws on invalid UTF-8, which these keys cannot contain
    }
}

} // namespace lodbake
