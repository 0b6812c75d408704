#include "lodbake/core/status.h"

#include "lodbake/core/diagnostics.h"

namespace lodbake {

const char* statusCodeName(StatusCode code) {
    switch (code) {
    case StatusCode::Ok: return "ok";
    case StatusCode::InvalidInput: return "invalid input";
    case StatusCode::Unsupported: return "unsupported";
    case StatusCode::IoError: return "i/o error";
    case StatusCode::ResourceLimit: return "resource limit";
    case StatusCode::Internal: return "internal error";
    }
    return "unknown";
}

Status Status::withPrefix(const std::string& prefix) const {
    if (ok()) return *this;
    return Status(code_, prefix + ": " + message_);
}

size_t Diagnostics::warningCount() const {
    size_t n = 0;
    for (const Diagnostic& d : items_) n += d.severity == Severity::Warning;
    return n;
}

} // namespace lodbake
