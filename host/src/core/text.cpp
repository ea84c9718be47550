#include "vkloc/core/text.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

namespace vkloc::text {

std::string_view trim(std::string_view s) {
  const char* ws = " \t\r\n\v\f";
  const size_t begin = s.find_first_not_of(ws);
  if (begin == std::string_view::npos) return {};
  const size_t end = s.find_last_not_of(ws);
  return s.substr(begin, end - begin + 1);
}

bool isBlankOrComment(std::string_view line) {
  const std::string_view t = trim(line);
  return t.empty() || t.front() == '#';
}

std::vector<std::string_view> splitLines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

size_t invalidUtf8Offset(std::string_view s) {
  size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t n = 0;         // Continuation bytes.
    uint32_t low = 0x80;  // Bounds of the second byte (rules out overlong forms and surrogates).
    uint32_t high = 0xbf;
    if (c >= 0xc2 && c <= 0xdf) {
      n = 1;
    } else if (c >= 0xe0 && c <= 0xef) {
      n = 2;
      if (c == 0xe0) low = 0xa0;
      if (c == 0xed) high = 0x9f;
    } else if (c >= 0xf0 && c <= 0xf4) {
      n = 3;
      if (c == 0xf0) low = 0x90;
      if (c == 0xf4) high = 0x8f;
    } else {
      return i;
    }
    if (n >= s.size() - i) return i;  // Cut short.
    for (size_t k = 1; k <= n; ++k) {
      const auto b = static_cast<unsigned char>(s[i + k]);
      if (k == 1 ? (b < low || b > high) : (b < 0x80 || b > 0xbf)) return i;
    }
    i += n + 1;
  }
  return std::string_view::npos;
}

std::vector<std::string_view> splitFields(std::string_view line, bool commas_too) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  auto is_sep = [&](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || c == '\n' || (commas_too && c == ',');
  };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !is_sep(line[i])) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

std::vector<std::string_view> splitCsv(std::string_view line) {
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

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

namespace {
void appendEscaped(std::string& out, unsigned char c) {
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "\\x%02x", c);
  out += buffer;
}
}  // namespace

std::string shown(std::string_view token) {
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < 40; ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      appendEscaped(out, c);
    }
  }
  return out + (token.size() > 40 ? "...'" : "'");
}

std::string oneLine(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  bool space = false;
  for (const char ch : message) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f') {
      space = !out.empty();
      continue;
    }
    if (space) out += ' ';
    space = false;
    if (c < 0x20 || c == 0x7f) {
      appendEscaped(out, c);
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

std::string number(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  if (ec != std::errc()) return "?";
  return std::string(buffer, end);
}

std::string parseDouble(std::string_view token, double& out) {
  std::string_view t = token;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size()) {
    if (ec == std::errc::result_out_of_range) return shown(token) + " is out of range";
    return shown(token) + " is not a number";
  }
  if (!std::isfinite(out)) return "non-finite value " + shown(token);
  return {};
}

std::string parseInt64(std::string_view token, int64_t& out) {
  std::string_view t = token;
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), out);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size()) {
    if (ec == std::errc::result_out_of_range) return shown(token) + " is out of range";
    return shown(token) + " is not an integer";
  }
  return {};
}

std::string parseUint64(std::string_view token, uint64_t& out) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size()) {
    if (ec == std::errc::result_out_of_range) return shown(token) + " is out of range";
    return shown(token) + " is not a whole number";
  }
  return {};
}

std::string parseSecondsToNs(std::string_view token, int64_t& out) {
  const std::string bad = "timestamp " + shown(token) + " is not a number of seconds";
  const std::string range = "timestamp " + shown(token) + " is out of range";
  size_t i = 0;
  bool negative = false;
  if (i < token.size() && (token[i] == '-' || token[i] == '+')) negative = token[i++] == '-';
  std::string digits;    // Mantissa digits without the decimal point.
  int64_t exponent = 0;  // Value = digits * 10^exponent seconds.
  bool any_digit = false;
  while (i < token.size() && token[i] >= '0' && token[i] <= '9') {
    digits += token[i++];
    any_digit = true;
  }
  if (i < token.size() && token[i] == '.') {
    ++i;
    while (i < token.size() && token[i] >= '0' && token[i] <= '9') {
      digits += token[i++];
      --exponent;
      any_digit = true;
    }
  }
  if (!any_digit) return bad;
  if (i < token.size() && (token[i] == 'e' || token[i] == 'E')) {
    ++i;
    int64_t e = 0;
    bool e_negative = false;
    if (i < token.size() && (token[i] == '-' || token[i] == '+')) e_negative = token[i++] == '-';
    if (i >= token.size()) return bad;
    while (i < token.size() && token[i] >= '0' && token[i] <= '9') {
      if (e > 1000) return range;
      e = e * 10 + (token[i++] - '0');
    }
    exponent += e_negative ? -e : e;
  }
  if (i != token.size()) return bad;
  // Nanoseconds = digits * 10^(exponent + 9).
  const int64_t shift = exponent + 9;
  if (shift < 0) {
    const auto drop = static_cast<size_t>(-shift);
    bool round_up = false;
    if (drop <= digits.size()) {
      round_up = digits[digits.size() - drop] >= '5';
      digits = digits.substr(0, digits.size() - drop);  // (not resize(): GCC 12 -Wrestrict false positive)
    } else {
      digits.clear();
    }
    if (round_up) {
      // Add one to the decimal string (half away from zero: the sign is applied afterwards).
      int k = static_cast<int>(digits.size()) - 1;
      while (k >= 0 && digits[static_cast<size_t>(k)] == '9') digits[static_cast<size_t>(k--)] = '0';
      if (k < 0) {
        digits.insert(digits.begin(), '1');
      } else {
        ++digits[static_cast<size_t>(k)];
      }
    }
  } else {
    const size_t first_nonzero = digits.find_first_not_of('0');
    if (first_nonzero != std::string::npos) {
      if (digits.size() - first_nonzero + static_cast<size_t>(shift) > 19) return range;
      digits.append(static_cast<size_t>(shift), '0');
    }
  }
  uint64_t magnitude = 0;
  for (char c : digits) {
    const auto d = static_cast<uint64_t>(c - '0');
    if (magnitude > (std::numeric_limits<uint64_t>::max() - d) / 10) return range;
    magnitude = magnitude * 10 + d;
  }
  const auto limit = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  if (magnitude > limit + (negative ? 1 : 0)) return range;
  if (negative) {
    out = magnitude == limit + 1 ? std::numeric_limits<int64_t>::min() : -static_cast<int64_t>(magnitude);
  } else {
    out = static_cast<int64_t>(magnitude);
  }
  return {};
}

std::string formatSeconds(int64_t t_ns) {
  const bool negative = t_ns < 0;
  const uint64_t magnitude = negative ? 0 - static_cast<uint64_t>(t_ns) : static_cast<uint64_t>(t_ns);
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000u),
                static_cast<unsigned long long>(magnitude % 1000000000u));
  return buffer;
}

Result<std::string> readFile(const std::string& path, const char* what, uint64_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) return makeError(ErrorCode::kNotFound, cat(path, ": ", what, " not found"));
  if (fs::is_directory(status)) {
    return makeError(ErrorCode::kNotFound, cat(path, ": ", what, " not found (this is a folder)"));
  }
  const uintmax_t size = fs::is_regular_file(status) ? fs::file_size(path, ec) : 0;
  if (!ec && size > max_bytes) {
    return makeError(ErrorCode::kMalformedInput, cat(path, ": ", what, " is larger than ", max_bytes, " bytes"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(ErrorCode::kIoError, cat(path, ": cannot open ", what));
  std::string content;
  char buffer[1 << 16];
  while (in) {
    in.read(buffer, sizeof buffer);
    const auto got = static_cast<size_t>(in.gcount());
    if (content.size() + got > max_bytes) {
      return makeError(ErrorCode::kMalformedInput, cat(path, ": ", what, " is larger than ", max_bytes, " bytes"));
    }
    content.append(buffer, got);
  }
  if (in.bad()) return makeError(ErrorCode::kIoError, cat(path, ": cannot read ", what));
  return content;
}

Error lineError(const std::string& path, size_t line, const std::string& what) {
  return makeError(ErrorCode::kMalformedInput, oneLine(cat(path, ":", line, ": ", what)));
}

}  // namespace vkloc::text
