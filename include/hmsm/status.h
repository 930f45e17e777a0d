// Errors are values: every fallible call returns a Status or a Result<T> whose message names
// the offending input. Nothing in hmsm throws across the API or terminates the process.
#pragma once

#include <hmsm/export.h>

#include <string>
#include <utility>
#include <variant>

namespace hmsm {

/// Why a call failed. Bad input (the caller can fix it) is separated from device and internal
/// failures, so the CLI can map them to exit codes 2 and 1.
enum class ErrorCode {
    ok = 0,
    invalid_argument,  ///< an option or parameter out of its valid range
    invalid_tree,      ///< a tree or forest file that violates docs/model.md section 3.1 or 4
    io,                ///< a file could not be read or written
    no_device,         ///< the requested backend has no usable device on this machine
    device_error,      ///< a device call failed (launch failure, device lost, ...)
    out_of_memory,     ///< host or device memory exhausted
    unsupported,       ///< a limit of this build or device was exceeded
    internal,          ///< a bug in hmsm
};

/// True for the error classes a user causes with bad input (CLI exit code 2).
constexpr bool is_input_error(ErrorCode code) {
    return code == ErrorCode::invalid_argument || code == ErrorCode::invalid_tree ||
           code == ErrorCode::io;
}

HMSM_API const char* to_string(ErrorCode code);

class [[nodiscard]] Status {
public:
    Status() = default;
    Status(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}
    static Status success() { return {}; }

    bool ok() const { return code_ == ErrorCode::ok; }
    explicit operator bool() const { return ok(); }
    ErrorCode code() const { return code_; }
    const std::string& message() const { return message_; }

private:
    ErrorCode code_ = ErrorCode::ok;
    std::string message_;
};

/// A value or the Status that explains why there is none.
template <class T>
class [[nodiscard]] Result {
public:
    Result(T value) : data_(std::move(value)) {}
    Result(Status error) : data_(std::move(error)) {}

    bool ok() const { return std::holds_alternative<T>(data_); }
    explicit operator bool() const { return ok(); }
    T& value() & { return std::get<T>(data_); }
    const T& value() const& { return std::get<T>(data_); }
    T&& value() && { return std::get<T>(std::move(data_)); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const T& operator*() const& { return value(); }
    Status status() const { return ok() ? Status{} : std::get<Status>(data_); }

private:
    std::variant<T, Status> data_;
};

}  // namespace hmsm

/// Propagates a failed Status from the enclosing function.
#define HMSM_TRY(expr)                                  \
    do {                                                \
        ::hmsm::Status hmsm_try_status_ = (expr);       \
        if (!hmsm_try_status_.ok()) return hmsm_try_status_; \
    } while (0)
