#pragma once
// Bake manifests (`lodbake bake --manifest assets.json`): many packs in one run, each from one or
// more inputs with its own preset and setting overrides. The format is described by
// schemas/config/bake_manifest.schema.json and docs/pipeline.md; unknown keys are errors.

#include <string>
#include <vector>

#include "lodbake/config/bake_config.h"
#include "lodbake/core/status.h"

namespace lodbake {

/// Manifest format version this baker reads.
constexpr int kBakeManifestVersion = 1;

struct ManifestAsset {
    std::vector<std::string> inputs;         // mesh files, resolved against the manifest's folder
    std::string output;                      // .glb path, resolved likewise (or against the output folder)
    BakeSettings settings;                   // defaults <- manifest preset <- asset preset <- asset "settings"
    std::vector<std::string> settings_files; // preset files read for this asset (for depfiles)
};

struct BakeManifest {
    std::vector<ManifestAsset> assets;
};

/// Parses the manifest text `json_text` read from `path`. Relative paths inside it are relative to
/// the manifest's folder and come out joined to it (never made absolute). `output_dir_override`,
/// when not empty, replaces the manifest's "output_dir" (CLI `-o DIR/`). `base` holds the settings
/// every asset starts from. Preset files named in the manifest are read here.
/// Errors: "<path>: <JSON pointer>: <what was expected>" for bad JSON, unknown keys, wrong types,
/// a missing or unsupported "version", an empty asset list, a non-.glb output, and two assets
/// writing the same output; preset errors as applyPresetFile reports them.
Result<BakeManifest> parseBakeManifest(const std::string& json_text, const std::string& path, const BakeSettings& base,
                                       const std::string& output_dir_override);

/// Reads the file at `path` (at most 64 MiB) and parses it (parseBakeManifest).
Result<BakeManifest> readBakeManifest(const std::string& path, const BakeSettings& base,
                                      const std::string& output_dir_override);

} // namespace lodbake
