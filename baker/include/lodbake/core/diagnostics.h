#pragma once
// Diagnostics: the explicit sink for warnings (STYLE.md §6). Library code never prints; it records
// here, and the CLI decides what to show.

#include <string>
#include <vector>

namespace lodbake {

enum class Severity { Note, Warning };

struct Diagnostic {
    Severity severity = Severity::Warning;
    std::string message; // "<file>: <element>: <what happened>", one line
};

class Diagnostics {
public:
    void warn(std::string message) { items_.push_back({Severity::Warning, std::move(message)}); }
    void note(std::string message) { items_.push_back({Severity::Note, std::move(message)}); }

    const std::vector<Diagnostic>& items() const { return items_; }
    size_t warningCount() const;
    bool empty() const { return items_.empty(); }
    void clear() { items_.clear(); }

private:
    std::vector<Diagnostic> items_;
};

} // namespace lodbake
