#include "cli_runner.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "test_paths.h"

namespace lodbake_test {

std::string readTextFile(const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

std::string shellQuote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

CliRun runLodbake(const std::vector<std::string>& args) {
    static int counter = 0;
    const std::string base =
        scratchDir() + "/cli_run_" + std::to_string(::getpid()) + "_" + std::to_string(++counter);
    std::string cmd = shellQuote(lodbakeCli());
    for (const std::string& a : args) cmd += " " + shellQuote(a);
    cmd += " >" + base + ".out 2>" + base + ".err </dev/null";
    const int status = std::system(cmd.c_str());
    CliRun r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = readTextFile(base + ".out");
    r.err = readTextFile(base + ".err");
    return r;
}

} // namespace lodbake_test
