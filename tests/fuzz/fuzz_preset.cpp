// libFuzzer target for bake presets (lodbake/config/bake_config.h): parse, validate, print, and
// check that the printout reads back to the same settings. Run with scripts/fuzz.sh preset SECONDS.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lodbake/config/bake_config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    lodbake::BakeSettings settings;
    const lodbake::Status status =
        lodbake::applyPresetJson(std::string(reinterpret_cast<const char*>(data), size), "fuzz.json", settings);
    if (!status.ok()) {
        // Errors are one line naming the file.
        const std::string& m = status.message();
        if (m.rfind("fuzz.json", 0) != 0 || m.find('\n') != std::string::npos) __builtin_trap();
        return 0;
    }
    const std::string printed = lodbake::settingsToJson(settings);
    lodbake::BakeSettings again;
    if (!lodbake::applyPresetJson(printed, "printed.json", again).ok()) __builtin_trap();
    if (lodbake::settingsToJson(again) != printed) __builtin_trap();
    return 0;
}
