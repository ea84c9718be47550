// Small text helpers shared by the line-oriented file readers (sequence files and importers).
#pragma once

#include <fmt/format.h>

#include <string>
#include <string_view>
#include <vector>

#include "vkloc/status.hpp"

namespace vkloc::text {

/// `s` without leading and trailing white space.
inline std::string_view trim(std::string_view s) {
  const char* ws = " \t\r\n\v\f";
  const size_t begin = s.find_first_not_of(ws);
  if (begin == std::string_view::npos) return {};
  const size_t end = s.find_last_not_of(ws);
  return s.substr(begin, end - begin + 1);
}

/// Splits a CSV line on commas and trims every field (empty fields are kept).
inline std::vector<std::string_view> splitCsv(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(trim(line.substr(start)));
      return fields;
    }
    fields.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

/// Quotes a token for an error message (at most 40 bytes, non-printable bytes escaped).
inline std::string shown(std::string_view token) {
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    out += (c >= 0x20 && c < 0x7f) ? std::string(1, static_cast<char>(c)) : fmt::format("\\x{:02x}", c);
  }
  return out + (token.size() > 40 ? "...'" : "'");
}

/// kMalformedInput "path:line: what".
inline Error lineError(const std::string& path, size_t line, const std::string& what) {
  return makeError(ErrorCode::kMalformedInput, fmt::format("{}:{}: {}", path, line, what));
}

}  // namespace vkloc::text
