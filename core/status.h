// Status and Result<T>: how every hairrig call that can fail reports it.
//
// Device I/O, file parsing and solver calls return a Status (or a Result<T>
// carrying either a value or a Status) whose message names the file, field or
// device and says what to do. Nothing in the libraries aborts or throws on bad
// input; asserts are reserved for programming errors, exceptions for the CLI edge.
#pragma once

#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace hairrig {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,     // bad config value, bad CLI argument, NaN where a number is needed
  kNotFound,            // file, device or field that is not there
  kIoError,             // read/write/ioctl/bus failure
  kCorruptData,         // a file or frame whose content is inconsistent or truncated
  kTimeout,             // a device did not answer in time
  kUnavailable,         // a device that is gone (unplugged, claimed by another process)
  kFailedPrecondition,  // a call made in the wrong device state
  kDeviceFault,         // a device that reports a fault of its own
  kOutOfRange,          // a value outside what a device or model accepts
  kUnimplemented,       // a device or backend that cannot do this (a camera without live view)
  kInternal,            // a bug; please report
};

const char* StatusCodeName(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status Ok() { return {}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // "CorruptData: Bangs.hair: header claims 1165 points but only 120 bytes follow".
  std::string ToString() const;

  // Returns a copy whose message is "<context>: <message>".
  Status WithContext(const std::string& context) const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status InvalidArgument(std::string m) {
  return {StatusCode::kInvalidArgument, std::move(m)};
}
inline Status NotFound(std::string m) { return {StatusCode::kNotFound, std::move(m)}; }
inline Status IoError(std::string m) { return {StatusCode::kIoError, std::move(m)}; }
inline Status CorruptData(std::string m) { return {StatusCode::kCorruptData, std::move(m)}; }
inline Status Timeout(std::string m) { return {StatusCode::kTimeout, std::move(m)}; }
inline Status Unavailable(std::string m) { return {StatusCode::kUnavailable, std::move(m)}; }
inline Status FailedPrecondition(std::string m) {
  return {StatusCode::kFailedPrecondition, std::move(m)};
}
inline Status DeviceFault(std::string m) { return {StatusCode::kDeviceFault, std::move(m)}; }
inline Status OutOfRange(std::string m) { return {StatusCode::kOutOfRange, std::move(m)}; }
inline Status Unimplemented(std::string m) { return {StatusCode::kUnimplemented, std::move(m)}; }
inline Status Internal(std::string m) { return {StatusCode::kInternal, std::move(m)}; }

// Either a T or a non-ok Status.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : data_(std::move(value)) {}        // NOLINT: implicit by design
  Result(Status status) : data_(std::move(status)) {  // NOLINT: implicit by design
    assert(!std::get<Status>(data_).ok() && "Result built from an ok Status has no value");
  }

  bool ok() const { return std::holds_alternative<T>(data_); }
  Status status() const { return ok() ? Status::Ok() : std::get<Status>(data_); }

  T& value() & { return std::get<T>(data_); }
  const T& value() const& { return std::get<T>(data_); }
  T&& value() && { return std::get<T>(std::move(data_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

 private:
  std::variant<T, Status> data_;
};

}  // namespace hairrig

#define HR_CONCAT_INNER(a, b) a##b
#define HR_CONCAT(a, b) HR_CONCAT_INNER(a, b)

// Returns the Status from the enclosing function if `expr` is not ok.
#define HR_RETURN_IF_ERROR(expr)             \
  do {                                       \
    ::hairrig::Status hr_status_ = (expr);   \
    if (!hr_status_.ok()) return hr_status_; \
  } while (false)

// `HR_ASSIGN_OR_RETURN(auto x, MakeX());` declares x from a Result or returns its Status.
#define HR_ASSIGN_OR_RETURN(lhs, expr) \
  HR_ASSIGN_OR_RETURN_IMPL(HR_CONCAT(hr_result_, __LINE__), lhs, expr)
#define HR_ASSIGN_OR_RETURN_IMPL(tmp, lhs, expr) \
  auto tmp = (expr);                             \
  if (!tmp.ok()) return tmp.status();            \
  lhs = std::move(tmp).value()
