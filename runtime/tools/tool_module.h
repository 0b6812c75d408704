#pragma once
// loddump and lodview open loddump's OpenImageIO module (png_module.cpp) with dlopen, so they link
// only lodrt and load no image library unless a picture is asked for. This finds and opens it the
// same way for both: $env_var, <exe dir>/../lib/lodbake/<file_name> (the install layout),
// <exe dir>/<file_name>, then build_path (the build tree). Internal to the runtime's tools.

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace lodtools {

/// The dlopen handle of the first candidate that opens and for which has_symbols(handle) holds; null
/// with *error naming every candidate tried and why it was passed over. The module stays loaded.
template <class HasSymbols>
void* openToolModule(const char* env_var, const char* file_name, const char* build_path, const char* what,
                     HasSymbols has_symbols, std::string* error) {
    std::vector<std::string> candidates;
    if (const char* env = std::getenv(env_var)) candidates.push_back(env);
    char exe[4096];
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n > 0) {
        exe[n] = '\0';
        std::string dir(exe);
        dir = dir.substr(0, dir.find_last_of('/'));
        candidates.push_back(dir + "/../lib/lodbake/" + file_name);
        candidates.push_back(dir + "/" + file_name);
    }
    candidates.push_back(build_path);
    std::string tried;
    for (const std::string& path : candidates) {
        void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* why = dlerror();
            tried += "\n  " + path + ": " + (why ? why : "?");
            continue;
        }
        if (has_symbols(handle)) return handle;
        tried += "\n  " + path + ": not " + what;
        dlclose(handle);
    }
    *error = std::string("cannot load ") + what + ":" + tried;
    return nullptr;
}

} // namespace lodtools
