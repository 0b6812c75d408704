#pragma once
// Bake settings: the options struct with its defaults (the single source of truth, mirrored with
// descriptions in schemas/config/bake_preset.schema.json), preset parsing and the resolved-settings
// printout. JSON parsing (nlohmann-json) stays inside this module.

#include <cstdint>
#include <string>
#include <vector>

#include "lodbake/core/status.h"

namespace lodbake {

/// Preset format version this baker reads.
constexpr int kBakePresetVersion = 1;

struct TextureLodSettings {
    bool enabled = true;           // downscale each level's textures to its expected on-screen size
    uint32_t max_size_px = 4096;   // no texture of any level, LOD0 included, is larger (nor larger than its source)
    uint32_t min_size_px = 16;     // no level texture is made smaller than this
    double texels_per_pixel = 1.0; // texels per screen pixel of the object's projected size at the switch distance
    bool keep_unreadable_images = false; // ship an image that is not a decodable PNG/JPEG byte for byte in every
                                         // level (with a warning) instead of failing the bake
};

/// Quantization of the LODBAKE_valence_compression streams (ValenceStreamOptions, docs/bake.md).
struct StreamPrecisionSettings {
    uint32_t position_bits = 14;  // LOD0's (and every level's without `adaptive`), 8..16
    uint32_t normal_bits = 8;     // octahedral bits per component, 4..16
    bool adaptive = false;        // levels after LOD0: bits from their own measured error
    double error_fraction = 0.25; // adaptive: largest quantization displacement / the level's mean error
};

/// Merging of range views before the chain (reconstruct module, docs/bake.md "Merging range scans").
enum class MergeMode {
    Off,     // never
    Auto,    // when the (repaired) input's components overlap as sheets
    Poisson, // always
};

/// "off", "auto", "poisson".
const char* mergeModeName(MergeMode mode);
/// Parses a mergeModeName(); false for anything else.
bool parseMergeMode(const std::string& text, MergeMode& mode);

/// BakeSettings::lod_min_switch_ratio is 0 (keep every level) or a factor in this range: far enough
/// above 1 that the pack's 7-digit rounding can never make two distinct switch distances equal.
inline constexpr double kMinSwitchRatioLow = 1.001;
inline constexpr double kMinSwitchRatioHigh = 100.0;

/// BakeSettings::pfrep_region_block range: smaller blocks let a view load less beside what it
/// refines, at 40 directory bytes per block and one bounds test per block per view and frame.
inline constexpr uint32_t kMinPfrepRegionBlock = 64;
inline constexpr uint32_t kMaxPfrepRegionBlock = 65536;

/// Whether `ratio` is a valid lod_min_switch_ratio.
inline bool isValidMinSwitchRatio(double ratio) {
    return ratio == 0.0 || (ratio >= kMinSwitchRatioLow && ratio <= kMinSwitchRatioHigh);
}

struct BakeSettings {
    int version = kBakePresetVersion;
    std::vector<double> lod_ratios{0.5, 0.25, 0.1, 0.03,
                                   0.01}; // levels after LOD0 (the repaired input), triangle fractions
    double pixel_threshold = 1.0;         // largest tolerated screen-space error, pixels
    double viewport_height_px = 1080.0;
    double vertical_fov_deg = 60.0;
    double hysteresis = 0.1;         // band around each switch distance, fraction of it: [d(1-h), d(1+h)]
    double lod_min_switch_ratio = 1.05; // a level is kept only when the next kept coarser level is taken more
                                        // than this many times farther (docs/bake.md "Dead levels"); 0 keeps all
    bool repair = true;              // run the default repair pipeline before simplifying
    uint32_t error_samples = 200000; // area-uniform samples per side when measuring each level's error
    TextureLodSettings textures;
    uint32_t threads = 0;         // worker threads; 0: all cores (the output does not depend on it)
    uint32_t memory_limit_mib = 0; // resident memory the run's bakes may be allowed together (docs/bake.md
                                   // "Memory"); 0: half of physical memory. The output does not depend on it
    bool compact = false;         // list our stream extensions in extensionsRequired
    bool web = false; // levels as KHR_mesh_quantization + EXT_meshopt_compression, no LODBAKE_ streams (docs/format/web.md)
    bool progressive_fans = true; // embed LOD0's PFRep blob (LODBAKE_progressive_fans) in the pack
    bool pfrep_from_chain = false; // build that blob from the chain's own collapses (one simplification,
                                   // faster, coarser PFRep levels) instead of its own half-edge pass
    uint32_t pfrep_format = 4;     // that blob's format: 4 against LOD0's stream, 3 range-coded, 2 a prefix,
                                   // 5 region blocks
    uint32_t pfrep_region_block = 1024; // format 5: vertices per region block (the unit a runtime loads)
    bool cluster_lod = false;      // LOD0's cluster LOD hierarchy as LODBAKE_cluster_lod (docs/cluster_lod.md)
    bool remove_covered_components = false; // levels may drop whole components lying within their accepted
                                            // error of the rest (SimplifyOptions::remove_covered_components)
    StreamPrecisionSettings stream_precision;
    MergeMode merge = MergeMode::Auto; // merge overlapping range views into one surface before the chain
    bool merge_scene = false; // glTF scenes: all mesh nodes as one LOD group (transforms applied) instead of
                              // one group per mesh node with the hierarchy kept
};

/// Applies the preset text `json_text` (from file `name`, used in messages) over `settings`. Keys are
/// checked against the schema's: an unknown key, a wrong type, an out-of-range value or a missing or
/// unsupported "version" is an error "<name>: <key path>: <what was expected>".
Status applyPresetJson(const std::string& json_text, const std::string& name, BakeSettings& settings);

/// Reads the file at `path` and applies it (applyPresetJson).
Status applyPresetFile(const std::string& path, BakeSettings& settings);

/// Checks cross-field rules the schema cannot state (min_size_px <= max_size_px); `name` prefixes messages.
Status validateSettings(const BakeSettings& settings, const std::string& name);

/// The resolved settings as a preset document with sorted keys (two-space indent, trailing newline).
/// Feeding it back through applyPresetJson reproduces `settings`.
std::string settingsToJson(const BakeSettings& settings);

} // namespace lodbake
