// vkloc: error values returned by every fallible public call.
#pragma once

#include <cassert>
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace vkloc {

/// What went wrong, grouped so that callers can branch on the kind of failure.
enum class ErrorCode {
  kInvalidArgument,  ///< A parameter is out of range or inconsistent (e.g. width 0, NaN pose).
  kNotFound,         ///< A file or named device does not exist.
  kIoError,          ///< A file exists but could not be read or written.
  kMalformedInput,   ///< A file was read but its content is invalid (truncated, garbage, NaN).
  kUnsupported,      ///< Valid input that vkloc does not handle (unknown format, missing feature).
  kNoDevice,         ///< No Vulkan driver or no usable device.
  kGpuError,         ///< A Vulkan call failed (out of memory, device lost, ...).
};

/// Short lower-case name of an error code, e.g. "malformed input".
const char* errorCodeName(ErrorCode code);

/// An error: a code and a one-line message that tells the user what to fix.
struct Error {
  ErrorCode code = ErrorCode::kInvalidArgument;
  std::string message;
};

/// Either a value or an Error. No exceptions cross the public API.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : storage_(std::move(value)) {}      // NOLINT(google-explicit-constructor)
  Result(Error error) : storage_(std::move(error)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return storage_.index() == 0; }
  explicit operator bool() const { return ok(); }

  /// Precondition: ok().
  T& value() & {
    assert(ok());
    return std::get<0>(storage_);
  }
  const T& value() const& {
    assert(ok());
    return std::get<0>(storage_);
  }
  T&& value() && {
    assert(ok());
    return std::get<0>(std::move(storage_));
  }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  /// Precondition: !ok().
  const Error& error() const {
    assert(!ok());
    return std::get<1>(storage_);
  }

 private:
  std::variant<T, Error> storage_;
};

/// Result of a call that returns nothing on success.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), ok_(false) {}  // NOLINT(google-explicit-constructor)
  static Status success() { return Status(); }
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  /// Precondition: !ok().
  const Error& error() const {
    assert(!ok_);
    return error_;
  }

 private:
  Error error_;
  bool ok_ = true;
};

/// Receives a warning: one line, no trailing newline. The library never prints; it hands
/// warnings to a handler the caller gives (null handlers drop them) or returns them.
using WarningHandler = std::function<void(const std::string& message)>;

/// Builds an Error; message is one line naming the thing at fault and the fix. Whatever the
/// message holds (a file's bytes, a library's text), the Error's message is one line: line
/// breaks and runs of white space become one space, other control characters are escaped
/// (`\x00`), leading and trailing space is dropped.
Error makeError(ErrorCode code, std::string_view message);

}  // namespace vkloc

/// Returns the error of a failed Status/Result expression from the enclosing function.
#define VKLOC_TRY_STATUS(expr)                                     \
  do {                                                             \
    auto vkloc_try_status_ = (expr);                               \
    if (!vkloc_try_status_.ok()) return vkloc_try_status_.error(); \
  } while (0)
