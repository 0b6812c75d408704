#pragma once
// Runs the lodbake CLI as a build system would: a fresh process, stdin closed, stdout and stderr
// captured. Every CLI suite uses this one helper.

#include <string>
#include <vector>

namespace lodbake_test {

struct CliRun {
    int exit_code = -1; // 128 + signal number if the process was killed
    std::string out;
    std::string err;
};

/// Runs `lodbake ARGS...` (arguments are shell-quoted) and captures its output. Scratch file names
/// include the process id so parallel ctest processes never share them.
CliRun runLodbake(const std::vector<std::string>& args);

/// Whole file as text; empty if it cannot be read.
std::string readTextFile(const std::string& path);

/// `s` quoted for /bin/sh.
std::string shellQuote(const std::string& s);

} // namespace lodbake_test
