// Bundled bake presets: `--preset mobile` names a preset installed with the baker
// (share/lodbake/presets/<name>.json beside bin/, and the same layout in the build tree), while a
// path names a file of one's own.

#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "cli_common.h"

namespace lodbake::cli {

namespace {

namespace fs = std::filesystem;

// <directory of the running executable>/../share/lodbake/presets: bin/ and share/ of an install
// prefix, and build/baker/ and build/share/ of a build tree (baker/CMakeLists.txt copies the
// presets there), so neither the install prefix nor the source tree is compiled in.
std::string bundledPresetDirectory() {
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (ec || exe.empty()) return "";
    return (exe.parent_path().parent_path() / "share" / "lodbake" / "presets").lexically_normal().string();
}

std::vector<std::string> bundledPresetNames(const std::string& dir) {
    std::vector<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
        if (it->path().extension() == ".json") names.push_back(it->path().stem().string());
    std::sort(names.begin(), names.end());
    return names;
}

} // namespace

bool isPresetName(const std::string& text) {
    if (text.empty()) return false;
    for (char c : text)
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-'))
            return false;
    return true;
}

int resolvePreset(const std::string& preset, std::string* path) {
    if (!isPresetName(preset)) {
        *path = preset;
        return kExitOk;
    }
    const std::string dir = bundledPresetDirectory();
    const std::vector<std::string> names = bundledPresetNames(dir);
    if (std::find(names.begin(), names.end(), preset) != names.end()) {
        *path = (fs::path(dir) / (preset + ".json")).string();
        return kExitOk;
    }
    if (names.empty())
        return reportError(ioError("--preset " + preset + ": no bundled presets in '" + dir +
                                   "' (give the path of a preset file instead)"));
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    return usageError("unknown preset '" + preset + "': the bundled presets are " + list +
                      " (a path names a preset file of your own)");
}

} // namespace lodbake::cli
