#include "test_paths.h"

#include <filesystem>

namespace lodbake_test {

std::string scratchDir() {
    const std::string dir = LODBAKE_TEST_BINARY_DIR "/scratch";
    std::filesystem::create_directories(dir);
    return dir;
}

bool haveSharedMeshes() { return std::filesystem::is_directory(sharedMeshesDir()); }

} // namespace lodbake_test
