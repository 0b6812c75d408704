#include "test_paths.h"

#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace lodbake_test {

std::string scratchDir() {
    const std::string dir = LODBAKE_TEST_BINARY_DIR "/scratch";
    std::filesystem::create_directories(dir);
    return dir;
}

bool haveSharedMeshes() { return std::filesystem::is_directory(sharedMeshesDir()); }

bool sharedDataRequired() {
    const char* value = std::getenv("LODBAKE_REQUIRE_SHARED_MESHES");
    return value && *value && std::strcmp(value, "0") != 0;
}

std::string missingSharedDir(const std::string& dir) {
    if (std::filesystem::is_directory(dir)) return std::string();
    return dir + " not found (the shared data next to the repository)" +
           (sharedDataRequired() ? "; LODBAKE_REQUIRE_SHARED_MESHES is set, so this test fails"
                                 : "; set LODBAKE_REQUIRE_SHARED_MESHES=1 to fail instead of skipping");
}

} // namespace lodbake_test
