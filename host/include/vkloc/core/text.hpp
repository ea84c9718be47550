// vkloc: text helpers shared by every reader and writer of text files and by error messages:
// splitting lines and fields, parsing numbers and timestamps with one set of rules, quoting
// tokens for messages, reading a whole file. Standard library only.
//
// Parsers return an empty string on success and otherwise what is wrong with the token, so a
// caller prefixes "file:line: " and returns one line to the user.
#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "vkloc/core/status.hpp"

namespace vkloc::text {

/// `s` without leading and trailing white space (space, \t, \r, \n, \v, \f).
std::string_view trim(std::string_view s);

/// True when the line is empty, white space only, or its first non-blank character is '#'.
bool isBlankOrComment(std::string_view line);

/// Splits text into lines at '\n' (a trailing '\r' stays in the line); lines[i] is line i + 1.
std::vector<std::string_view> splitLines(std::string_view text);

/// Walks text line by line without copying or storing the lines (memory independent of the
/// line count): `while (cursor.next(line))`. Lines end at '\n' (a trailing '\r' stays in the
/// line); number() is the 1-based number of the line last returned.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  size_t number() const { return number_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t number_ = 0;
};

/// Offset of the first byte that is not part of well-formed UTF-8 (overlong forms, surrogates
/// and code points above U+10FFFF are not), or npos when all of `s` is.
size_t invalidUtf8Offset(std::string_view s);

/// Splits on white space (and on commas when `commas_too`), dropping empty fields.
std::vector<std::string_view> splitFields(std::string_view line, bool commas_too = false);

/// Splits a CSV line on commas and trims every field (empty fields are kept).
std::vector<std::string_view> splitCsv(std::string_view line);

/// Lower-case copy (ASCII letters only).
std::string lower(std::string_view s);

/// Quotes a token for an error message: at most 40 bytes, bytes outside printable ASCII
/// written as \xNN, "..." appended when cut.
std::string shown(std::string_view token);

/// A message made safe to print on one line: control characters (line breaks, escapes, NUL)
/// become \xNN, runs of white space collapse to one space. Messages from third-party libraries
/// pass through this before they reach a user.
std::string oneLine(std::string_view message);

/// Shortest decimal that reads back to the same double ("0.1", "1e+300", "nan", "inf").
std::string number(double v);

/// Concatenates strings, characters and numbers (integers in decimal, floating point with
/// number()) into one string: cat("fx = ", 0.5, " px") == "fx = 0.5 px".
template <typename... Parts>
std::string cat(const Parts&... parts);

/// Parses a finite double ('+' allowed, exponents allowed, no surrounding spaces).
std::string parseDouble(std::string_view token, double& out);

/// Parses a decimal integer ('+' allowed) that fits in int64_t.
std::string parseInt64(std::string_view token, int64_t& out);

/// Parses a decimal unsigned integer (no sign) that fits in uint64_t.
std::string parseUint64(std::string_view token, uint64_t& out);

/// Parses a decimal number of seconds ("1305031102.175304", "-0.5", "1.3e9") into integer
/// nanoseconds exactly, without floating point. The one rounding rule of vkloc: digits beyond
/// 1 ns are rounded half away from zero (1.0000000005 s -> 1000000001 ns, -1.0000000005 s ->
/// -1000000001 ns). Out of the int64_t range is an error.
std::string parseSecondsToNs(std::string_view token, int64_t& out);

/// Formats nanoseconds as seconds with 9 decimals ("1305031102.175304000", "-0.500000000"); the
/// exact inverse of parseSecondsToNs.
std::string formatSeconds(int64_t t_ns);

/// Reads a whole file. kNotFound when it does not exist or is a folder; kIoError when it
/// cannot be read; kMalformedInput "path: <what> is larger than N bytes" when it is larger than
/// max_bytes (checked before reading). `what` names the file's role in messages ("camera file").
Result<std::string> readFile(const std::string& path, const char* what, uint64_t max_bytes = uint64_t{1} << 32);

/// kMalformedInput "path:line: what", made one line by oneLine() (no raw control characters).
Error lineError(const std::string& path, size_t line, const std::string& what);

// --- implementation -----------------------------------------------------------------------------

namespace detail {
inline void append(std::string& out, std::string_view s) { out.append(s); }
inline void append(std::string& out, const char* s) { out.append(s ? s : "(null)"); }
inline void append(std::string& out, const std::string& s) { out.append(s); }
inline void append(std::string& out, char c) { out.push_back(c); }
template <typename T>
std::enable_if_t<std::is_arithmetic_v<T> && !std::is_same_v<T, char> && !std::is_same_v<T, bool>> append(
    std::string& out, T v) {
  if constexpr (std::is_floating_point_v<T>) {
    out.append(number(static_cast<double>(v)));
  } else {
    out.append(std::to_string(v));
  }
}
inline void append(std::string& out, bool v) { out.append(v ? "true" : "false"); }
}  // namespace detail

template <typename... Parts>
std::string cat(const Parts&... parts) {
  std::string out;
  (detail::append(out, parts), ...);
  return out;
}

}  // namespace vkloc::text
