#include "core/module_loader.h"

#include <dlfcn.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <vector>

namespace lodbake::detail {

namespace {

std::string executableDir() {
    char buf[PATH_MAX];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
    if (n <= 0) return "";
    std::string path(buf, size_t(n));
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? "" : path.substr(0, slash);
}

std::vector<std::string> candidates(const ModuleSpec& spec) {
    std::vector<std::string> out;
    if (const char* env = std::getenv(spec.env_var)) out.push_back(env);
    const std::string dir = executableDir();
    if (!dir.empty()) {
        out.push_back(dir + "/../lib/lodbake/" + spec.file_name);
        out.push_back(dir + "/" + spec.file_name);
    }
    out.push_back(spec.build_path);
    return out;
}

} // namespace

void* openNextModule(const ModuleSpec& spec, size_t* next_candidate, std::string* path, std::string* tried) {
    const std::vector<std::string> paths = candidates(spec);
    while (*next_candidate < paths.size()) {
        *path = paths[(*next_candidate)++];
        if (void* handle = dlopen(path->c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
        const char* why = dlerror();
        *tried += (tried->empty() ? "" : "; ") + (why ? std::string(why) : *path + ": cannot be opened");
    }
    return nullptr;
}

void closeModule(void* handle) { dlclose(handle); }

void* moduleSymbol(void* handle, const char* name) { return dlsym(handle, name); }

} // namespace lodbake::detail
