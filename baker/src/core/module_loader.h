#pragma once
// The baker's optional shared modules (lodbake_oiio, lodbake_open3d) are opened with dlopen on first
// use, so that the large libraries behind them load only in the processes that need them. This finds
// and opens one of them the same way for every module.

#include <cstddef>
#include <string>

namespace lodbake::detail {

/// Where a module is looked for, in order: $env_var, <exe dir>/../lib/lodbake/<file_name> (the
/// install layout), <exe dir>/<file_name>, then build_path (the build tree).
struct ModuleSpec {
    const char* env_var;
    const char* file_name;
    const char* build_path;
    const char* entry_symbol; // a C function taking nothing and returning the module's Api table
    const char* what;         // the library it wraps, for the error message ("OpenImageIO")
};

/// The first candidate that opens and whose entry point returns a table (a struct with an `int
/// version` member) of version `api_version`, as that entry point returned it; null
/// with *error naming every candidate tried. The module stays loaded for the life of the process.
template <class Api>
const Api* openModule(const ModuleSpec& spec, int api_version, std::string* error);

/// The next candidate from *next_candidate on that opens: its dlopen handle and *path, with the
/// reasons the candidates before it did not open appended to *tried; null after the last.
void* openNextModule(const ModuleSpec& spec, size_t* next_candidate, std::string* path, std::string* tried);
void closeModule(void* handle);
void* moduleSymbol(void* handle, const char* name);

template <class Api>
const Api* openModule(const ModuleSpec& spec, int api_version, std::string* error) {
    std::string tried;
    std::string path;
    size_t next = 0;
    while (void* handle = openNextModule(spec, &next, &path, &tried)) {
        // The entry point is typed as the module defines it, so the call matches its signature.
        using Entry = const Api* (*)();
        auto entry = reinterpret_cast<Entry>(moduleSymbol(handle, spec.entry_symbol));
        const Api* api = entry ? entry() : nullptr;
        if (api && api->version == api_version) return api;
        tried += (tried.empty() ? "" : "; ") + path + ": not a compatible lodbake " + spec.what + " module";
        closeModule(handle);
    }
    *error = std::string("cannot load the ") + spec.what + " module (" + tried + ")";
    return nullptr;
}

} // namespace lodbake::detail
