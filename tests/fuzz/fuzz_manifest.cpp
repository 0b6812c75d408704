// libFuzzer target for bake manifests (lodbake/config/bake_manifest.h): parse and validate; a
// failure must be one line starting with the manifest's path, a success a non-empty list of assets,
// each with inputs, a distinct .glb output and settings that print and read back unchanged. Preset
// files a manifest names are read from disk (relative ones under a folder that does not exist);
// inputs holding a string that starts with '/' are skipped, so no file of the machine is read: a run
// never blocks on /dev/stdin and, with a fixed seed, does not depend on what /tmp holds.
// Run with scripts/fuzz.sh manifest SECONDS.
#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

#include "lodbake/config/bake_manifest.h"
#include "lodbake/core/file_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    for (const char* absolute : {"\"/", "\"\\/", "\"\\u002f", "\"\\u002F"})
        if (text.find(absolute) != std::string::npos) return 0;
    const std::string path = "lodbake-fuzz-missing/manifest.json";
    const lodbake::Result<lodbake::BakeManifest> manifest =
        lodbake::parseBakeManifest(text, path, lodbake::BakeSettings(), "");
    if (!manifest.ok()) {
        const std::string& m = manifest.status().message();
        if (m.rfind(path, 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
        return 0;
    }
    if (manifest->assets.empty()) __builtin_trap();
    std::set<std::string> outputs;
    for (const lodbake::ManifestAsset& asset : manifest->assets) {
        if (asset.inputs.empty() || lodbake::lowerExtension(asset.output) != ".glb") __builtin_trap();
        if (!outputs.insert(asset.output).second) __builtin_trap();
        const std::string printed = lodbake::settingsToJson(asset.settings);
        lodbake::BakeSettings again;
        if (!lodbake::applyPresetJson(printed, "printed.json", again).ok()) __builtin_trap();
        if (lodbake::settingsToJson(again) != printed) __builtin_trap();
    }
    return 0;
}
