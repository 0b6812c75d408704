// Depfile writer. The escaping is the subset Ninja's depfile lexer and GNU Make agree on; paths
// holding a newline or a ':' followed by a space cannot be expressed and are left to the caller.
#include "lodbake/bake/depfile.h"

#include <set>

namespace lodbake {

std::string escapeMakePath(const std::string& path) {
    std::string out;
    out.reserve(path.size() + 8);
    size_t backslashes = 0;
    for (char c : path) {
        if (c == '\\') {
            ++backslashes;
            out += c;
            continue;
        }
        if (c == ' ' || c == '#') {
            out.append(backslashes, '\\'); // a backslash run before an escaped character doubles
            out += '\\';
            out += c;
        } else if (c == '$') {
            out += "$$";
        } else {
            out += c;
        }
        backslashes = 0;
    }
    return out;
}

std::string formatDepfile(const std::vector<DepfileRule>& rules) {
    std::string out;
    for (const DepfileRule& rule : rules) {
        out += escapeMakePath(rule.target) + ":";
        std::set<std::string> seen;
        for (const std::string& p : rule.prerequisites) {
            if (!seen.insert(p).second) continue;
            out += " \\\n  " + escapeMakePath(p);
        }
        out += "\n";
    }
    return out;
}

} // namespace lodbake
