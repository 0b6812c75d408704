#pragma once
// Where test data lives. Paths come from compile definitions relative to the source tree (STYLE.md §9);
// tests write only into the build tree.

#include <string>

namespace lodbake_test {

/// Repository root (the folder holding the top-level CMakeLists.txt).
inline std::string sourceDir() { return LODBAKE_TEST_SOURCE_DIR; }
/// `../shared/meshes` next to the repository: the real scans (never copied into the project).
inline std::string sharedMeshesDir() { return LODBAKE_TEST_SHARED_MESHES_DIR; }
inline std::string sharedMesh(const std::string& name) { return sharedMeshesDir() + "/" + name; }
/// A scratch folder inside the build tree, created on first use.
std::string scratchDir();
/// Path of the lodbake CLI built alongside the tests.
inline std::string lodbakeCli() { return LODBAKE_TEST_CLI; }
/// The Python interpreter that has the Debian packages the tests need (jsonschema, numpy, open3d).
inline std::string python() { return LODBAKE_TEST_PYTHON; }
/// True if the shared scans are present (a clone without `../shared` skips the tests that need them).
bool haveSharedMeshes();

} // namespace lodbake_test

/// Skips the current test, with a message, when the shared scans are missing.
#define LODBAKE_REQUIRE_SHARED_MESHES()                                                                        \
    do {                                                                                                       \
        if (!lodbake_test::haveSharedMeshes())                                                                 \
            GTEST_SKIP() << "../shared/meshes not found next to the repository";                               \
    } while (0)
