// Tests of the shared text helpers (core/text.hpp): one timestamp rule, number parsing, message
// hygiene, whole-file reads.
#include "vkloc/core/text.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <random>
#include <string_view>
#include <utility>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {
namespace {

int64_t seconds(const std::string& token) {
  int64_t t = 0;
  const std::string wrong = text::parseSecondsToNs(token, t);
  EXPECT_TRUE(wrong.empty()) << token << ": " << wrong;
  return t;
}

TEST(Text, SecondsToNanosecondsRoundHalfAwayFromZero) {
  EXPECT_EQ(seconds("1305031102.175304"), 1305031102175304000);
  EXPECT_EQ(seconds("1.000000001"), 1000000001);
  // Beyond 1 ns: half away from zero, on both signs.
  EXPECT_EQ(seconds("1.0000000005"), 1000000001);
  EXPECT_EQ(seconds("1.0000000004999"), 1000000000);
  EXPECT_EQ(seconds("-1.0000000005"), -1000000001);
  EXPECT_EQ(seconds("-1.0000000004"), -1000000000);
  EXPECT_EQ(seconds("0.9999999995"), 1000000000);
  EXPECT_EQ(seconds("0.0000000004"), 0);
  // Exponents, signs, no integer part.
  EXPECT_EQ(seconds("1.3e9"), 1300000000000000000);
  EXPECT_EQ(seconds("5E-9"), 5);
  EXPECT_EQ(seconds("+2"), 2000000000);
  EXPECT_EQ(seconds(".5"), 500000000);
  EXPECT_EQ(seconds("-0.5"), -500000000);
  // The limits of int64_t nanoseconds.
  EXPECT_EQ(seconds("9223372036.854775807"), std::numeric_limits<int64_t>::max());
  EXPECT_EQ(seconds("-9223372036.854775808"), std::numeric_limits<int64_t>::min());
}

TEST(Text, BadTimestampsSayWhatIsWrong) {
  int64_t t = 0;
  for (const char* bad : {"", "abc", "1.2.3", "1e", "1e+", "--1", "1 ", " 1", "0x10", "nan", "inf"}) {
    EXPECT_FALSE(text::parseSecondsToNs(bad, t).empty()) << "'" << bad << "'";
  }
  EXPECT_NE(text::parseSecondsToNs("9223372036.854775808", t).find("out of range"), std::string::npos);
  EXPECT_NE(text::parseSecondsToNs("1e30", t).find("out of range"), std::string::npos);
  EXPECT_NE(text::parseSecondsToNs("1e99999999", t).find("out of range"), std::string::npos);
}

TEST(Text, FormatSecondsIsTheExactInverse) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 2000; ++i) {
    const auto t = static_cast<int64_t>(rng());
    EXPECT_EQ(seconds(text::formatSeconds(t)), t);
  }
  EXPECT_EQ(text::formatSeconds(-500000000), "-0.500000000");
  EXPECT_EQ(text::formatSeconds(std::numeric_limits<int64_t>::min()), "-9223372036.854775808");
}

TEST(Text, NumbersParseFiniteValuesOnly) {
  double d = 0;
  EXPECT_TRUE(text::parseDouble("+1.5e3", d).empty());
  EXPECT_EQ(d, 1500.0);
  EXPECT_FALSE(text::parseDouble("nan", d).empty());
  EXPECT_FALSE(text::parseDouble("inf", d).empty());
  EXPECT_NE(text::parseDouble("1e999", d).find("out of range"), std::string::npos);
  EXPECT_FALSE(text::parseDouble("1,5", d).empty());
  int64_t i = 0;
  EXPECT_TRUE(text::parseInt64("-42", i).empty());
  EXPECT_EQ(i, -42);
  EXPECT_FALSE(text::parseInt64("4.2", i).empty());
  EXPECT_NE(text::parseInt64("99999999999999999999", i).find("out of range"), std::string::npos);
}

TEST(Text, NumbersFormatShortestRoundTrip) {
  EXPECT_EQ(text::number(0.1), "0.1");
  EXPECT_EQ(text::number(1e300), "1e+300");
  EXPECT_EQ(text::number(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(text::cat("fx = ", 0.5, " px, ", 3, " levels, ", 'c'), "fx = 0.5 px, 3 levels, c");
}

TEST(Text, MessagesStayOnOneLine) {
  EXPECT_EQ(text::oneLine("a\nb\r\n  c\tX\x1b[31m"), "a b c X\\x1b[31m");
  EXPECT_EQ(text::oneLine(std::string("nul\0here", 8)), "nul\\x00here");
  EXPECT_EQ(text::shown("ok\n"), "'ok\\x0a'");
  EXPECT_EQ(text::shown(std::string(50, 'a')), "'" + std::string(40, 'a') + "...'");
}

// Every Error is built by makeError, so no message a library or a file hands through can break
// a log line or send terminal escapes, whichever module built it.
TEST(Text, EveryErrorMessageIsOneLine) {
  const Error error = makeError(ErrorCode::kMalformedInput, std::string("camera.yaml:3: bad\n\0 \x1b[2J\r\n", 27));
  EXPECT_EQ(error.code, ErrorCode::kMalformedInput);
  EXPECT_EQ(error.message, "camera.yaml:3: bad \\x00 \\x1b[2J");
  EXPECT_EQ(makeError(ErrorCode::kIoError, "plain message").message, "plain message");
}

TEST(Text, SplitsLinesFieldsAndCsv) {
  const auto lines = text::splitLines("a\nb\r\n\nc");
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[1], "b\r");
  EXPECT_TRUE(text::isBlankOrComment("   # x"));
  EXPECT_TRUE(text::isBlankOrComment(" \t"));
  EXPECT_FALSE(text::isBlankOrComment("1 # x"));
  const auto fields = text::splitFields(" 1, 2\t3 ", true);
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[2], "3");
  const auto csv = text::splitCsv("a, ,b ");
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[1], "");
  EXPECT_EQ(csv[2], "b");
}

TEST(Text, ReadFileReportsMissingFoldersAndSize) {
  test::TempDir dir;
  ASSERT_TRUE(test::writeFile(dir.file("a.txt"), std::string("hello")));
  auto ok = text::readFile(dir.file("a.txt"), "test file");
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(*ok, "hello");
  auto missing = text::readFile(dir.file("nope.txt"), "test file");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("test file not found"), std::string::npos);
  auto folder = text::readFile(dir.path().string(), "test file");
  ASSERT_FALSE(folder.ok());
  EXPECT_EQ(folder.error().code, ErrorCode::kNotFound);
  auto big = text::readFile(dir.file("a.txt"), "test file", 3);
  ASSERT_FALSE(big.ok());
  EXPECT_EQ(big.error().code, ErrorCode::kMalformedInput);
  EXPECT_NE(big.error().message.find("test file is larger than 3 bytes"), std::string::npos) << big.error().message;
}

TEST(Text, LineCursorWalksLinesWithTheirNumbers) {
  text::LineCursor cursor("a\nb\r\n\nc");
  std::vector<std::pair<size_t, std::string>> seen;
  for (std::string_view line; cursor.next(line);) seen.emplace_back(cursor.number(), std::string(line));
  ASSERT_EQ(seen.size(), 4u);
  EXPECT_EQ(seen[1], (std::pair<size_t, std::string>{2, "b\r"}));
  EXPECT_EQ(seen[2], (std::pair<size_t, std::string>{3, ""}));
  EXPECT_EQ(seen[3], (std::pair<size_t, std::string>{4, "c"}));
  std::string_view line;
  EXPECT_FALSE(text::LineCursor("").next(line));
}

TEST(Text, InvalidUtf8OffsetFindsTheFirstBadByte) {
  EXPECT_EQ(text::invalidUtf8Offset("plain ascii"), std::string::npos);
  EXPECT_EQ(text::invalidUtf8Offset("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"), std::string::npos);
  EXPECT_EQ(text::invalidUtf8Offset("ab\xff"), 2u);            // Never valid.
  EXPECT_EQ(text::invalidUtf8Offset("ab\xc3"), 2u);            // Cut short.
  EXPECT_EQ(text::invalidUtf8Offset("\xc0\xaf"), 0u);          // Overlong '/'.
  EXPECT_EQ(text::invalidUtf8Offset("x\xed\xa0\x80"), 1u);     // UTF-16 surrogate.
  EXPECT_EQ(text::invalidUtf8Offset("\xf4\x90\x80\x80"), 0u);  // Above U+10FFFF.
  EXPECT_EQ(text::invalidUtf8Offset("a\xe2\x82"), 1u);
}

TEST(Text, LineErrorsNeverCarryControlCharacters) {
  // A message quoting file content (or a library's message) with NUL, line breaks and an
  // escape sequence stays one printable line.
  const char raw[] = "bad \0 byte\nnext line\r\x1b[31m red";
  const std::string quoted(raw, sizeof raw - 1);
  const Error e = text::lineError("dir/cam\nera.yaml", 3, "not valid YAML: " + quoted);
  EXPECT_EQ(e.code, ErrorCode::kMalformedInput);
  for (const char c : e.message) {
    EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << e.message;
  }
  EXPECT_EQ(e.message, "dir/cam era.yaml:3: not valid YAML: bad \\x00 byte next line \\x1b[31m red");
}

}  // namespace
}  // namespace vkloc
