#pragma once
// Status and Result<T>: how every fallible baker function reports bad input or environment errors
// (STYLE.md §6, after Draco's core/status.h and status_or.h). Our code never throws.

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace lodbake {

enum class StatusCode {
    Ok = 0,
    InvalidInput,  // the input file or data is malformed: message names file, element and expectation
    Unsupported,   // well-formed input that uses a feature we do not handle
    IoError,       // the environment: cannot open, read or write a file
    ResourceLimit, // the input asks for more memory or work than the configured limits allow
    Internal,      // a bug on our side that was caught instead of crashing
};

const char* statusCodeName(StatusCode code);

class Status {
public:
    Status() = default;
    Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

    static Status okStatus() { return Status(); }

    bool ok() const { return code_ == StatusCode::Ok; }
    StatusCode code() const { return code_; }
    /// One line: "<file>: <element>: <what was expected>" for input errors.
    const std::string& message() const { return message_; }

    /// Returns a copy whose message is "<prefix>: <message>" (adds context at a module boundary).
    Status withPrefix(const std::string& prefix) const;

private:
    StatusCode code_ = StatusCode::Ok;
    std::string message_;
};

inline Status invalidInput(std::string message) { return Status(StatusCode::InvalidInput, std::move(message)); }
inline Status ioError(std::string message) { return Status(StatusCode::IoError, std::move(message)); }
inline Status unsupported(std::string message) { return Status(StatusCode::Unsupported, std::move(message)); }
inline Status resourceLimit(std::string message) { return Status(StatusCode::ResourceLimit, std::move(message)); }
inline Status internalError(std::string message) { return Status(StatusCode::Internal, std::move(message)); }

/// A value or the Status explaining why there is none.
template <class T> class Result {
public:
    Result(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design, like StatusOr
    Result(Status status) : status_(std::move(status)) { assert(!status_.ok() && "Result needs a value or an error"); }

    bool ok() const { return status_.ok(); }
    const Status& status() const { return status_; }

    T& value() & { assert(ok()); return *value_; }
    const T& value() const& { assert(ok()); return *value_; }
    T&& value() && { assert(ok()); return std::move(*value_); }

    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }

private:
    Status status_;
    std::optional<T> value_;
};

} // namespace lodbake

#define LODBAKE_CONCAT_INNER_(a, b) a##b
#define LODBAKE_CONCAT_(a, b) LODBAKE_CONCAT_INNER_(a, b)

/// Returns the Status from the enclosing function if `expr` (a Status) is not ok.
#define LODBAKE_RETURN_IF_ERROR(expr)                                                                          \
    do {                                                                                                       \
        ::lodbake::Status lodbake_status_ = (expr);                                                            \
        if (!lodbake_status_.ok()) return lodbake_status_;                                                     \
    } while (0)

/// `LODBAKE_ASSIGN_OR_RETURN(auto x, f());` declares x from a Result or returns its Status.
#define LODBAKE_ASSIGN_OR_RETURN(lhs, expr) LODBAKE_ASSIGN_OR_RETURN_IMPL_(LODBAKE_CONCAT_(lodbake_result_, __LINE__), lhs, expr)
#define LODBAKE_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr)                                                         \
    auto tmp = (expr);                                                                                         \
    if (!tmp.ok()) return tmp.status();                                                                        \
    lhs = std::move(tmp).value()
