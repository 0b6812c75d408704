#pragma once
// Makefile-syntax dependency files (`--depfile OUT.d`), as `cc -MD -MF` writes them, readable by
// Make, Ninja (`depfile =`, `deps = gcc`) and CMake's add_custom_command(DEPFILE).

#include <string>
#include <vector>

namespace lodbake {

struct DepfileRule {
    std::string target;                     // the output file, as named on the command line
    std::vector<std::string> prerequisites; // every file read to make it, in first-read order
};

/// One path escaped for a Makefile rule: space and '#' get a backslash, '$' is doubled, and the
/// backslashes before a space or '#' are doubled (GNU Make and Ninja read it back unchanged).
std::string escapeMakePath(const std::string& path);

/// The depfile text: one rule per entry ("target: dep \\\n  dep ..."), prerequisites de-duplicated
/// (first occurrence kept), a trailing newline. Paths are written as given, never made absolute.
std::string formatDepfile(const std::vector<DepfileRule>& rules);

} // namespace lodbake
