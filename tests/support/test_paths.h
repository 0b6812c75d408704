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
/// `../shared/eval` next to the repository: the reference evaluation scripts (meshdist.py).
inline std::string sharedEvalDir() { return LODBAKE_TEST_SHARED_EVAL_DIR; }
/// True if the shared scans are present (a clone without `../shared` skips the tests that need them).
bool haveSharedMeshes();
/// True when the environment sets LODBAKE_REQUIRE_SHARED_MESHES (to anything but empty or 0), as
/// scripts/setup-and-test.sh does: then a missing shared folder fails the tests that need it.
bool sharedDataRequired();
/// Empty when `dir` is a directory; otherwise the message naming it, for the skip or the failure.
std::string missingSharedDir(const std::string& dir);

} // namespace lodbake_test

/// Skips the current test when shared folder `dir` is missing, or fails it, naming the folder, when
/// LODBAKE_REQUIRE_SHARED_MESHES is set.
#define LODBAKE_REQUIRE_SHARED_DIR(dir)                                                                        \
    do {                                                                                                       \
        const std::string lodbake_missing_shared_ = lodbake_test::missingSharedDir(dir);                       \
        if (!lodbake_missing_shared_.empty()) {                                                                \
            if (lodbake_test::sharedDataRequired()) FAIL() << lodbake_missing_shared_;                         \
            GTEST_SKIP() << lodbake_missing_shared_;                                                           \
        }                                                                                                      \
    } while (0)

/// The shared scans (../shared/meshes).
#define LODBAKE_REQUIRE_SHARED_MESHES() LODBAKE_REQUIRE_SHARED_DIR(lodbake_test::sharedMeshesDir())
/// The shared evaluation scripts (../shared/eval).
#define LODBAKE_REQUIRE_SHARED_EVAL() LODBAKE_REQUIRE_SHARED_DIR(lodbake_test::sharedEvalDir())
