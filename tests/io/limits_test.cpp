// Hostile and borderline input to the sequence and calibration readers: size, line and entry
// limits, load and save agreeing on images.txt, YAML that yaml-cpp gets wrong, and messages that
// stay one printable line.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/io/calibration.hpp"
#include "vkloc/io/sequence.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using test::writeFile;

constexpr const char* kCameraTail = "fy: 500\ncx: 320\ncy: 240\nwidth: 640\nheight: 480\n";

// The error of a failed result: kMalformedInput, "path:line: ..." when line > 0, one line of
// printable text, containing `contains`.
template <typename R>
void expectFileError(const R& result, const std::string& path, int line, const std::string& contains) {
  ASSERT_FALSE(result.ok());
  const std::string& message = result.error().message;
  EXPECT_EQ(result.error().code, ErrorCode::kMalformedInput) << message;
  const std::string prefix = line > 0 ? path + ":" + std::to_string(line) + ":" : path + ":";
  EXPECT_EQ(message.rfind(prefix, 0), 0u) << message << " (expected " << prefix << ")";
  for (const char c : message) {
    EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << "control character in: " << message;
  }
  EXPECT_NE(message.find(contains), std::string::npos) << message;
}

Sequence smallSequence() {
  Sequence s;
  s.name = "limits";
  s.model = "city";
  s.camera.model = "pinhole";
  s.camera.intrinsics = PinholeCamera{500, 500, 320, 240, 640, 480};
  s.images = {{1000000000, "a.png"}, {2000000000, "b.png"}};
  return s;
}

TEST(ImageList, LoadRefusesThePathsSaveRefuses) {
  TempDir dir("limits_images");
  const std::string path = dir.file("images.txt");
  // A path that starts with '#', and one with a carriage return inside: save refuses both.
  for (const std::string& bad : {std::string("#a"), std::string("a\rb")}) {
    EXPECT_FALSE(saveImageList({{0, bad}}, path).ok()) << bad;
    ASSERT_TRUE(writeFile(path, "0.5 ok.png\n1 " + bad + "\n"));
    expectFileError(loadImageList(path), path, 2, "image path");
  }
  // A CRLF file still loads: the line's trailing '\r' is not part of the path.
  ASSERT_TRUE(writeFile(path, "0.5 a b.png\r\n1 c.png\r\n"));
  auto loaded = loadImageList(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->size(), 2u);
  EXPECT_EQ((*loaded)[0].path, "a b.png");
  EXPECT_EQ((*loaded)[1].path, "c.png");
}

TEST(SequenceFolder, SaveRefusesNonUtf8NameAndModelInsteadOfReplacingBytes) {
  TempDir dir("limits_utf8");
  const std::string folder = dir.file("seq");
  Sequence s = smallSequence();
  s.name = "caf\xe9";  // Latin-1, not UTF-8.
  const Status saved = saveSequence(s, folder);
  ASSERT_FALSE(saved.ok());
  EXPECT_EQ(saved.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(saved.error().message.find("not valid UTF-8 (byte 0xe9 at offset 3)"), std::string::npos)
      << saved.error().message;
  EXPECT_FALSE(fs::exists(folder));  // Nothing written.
  s = smallSequence();
  s.model = "models/\xff.glb";
  EXPECT_FALSE(saveSequence(s, folder).ok());
  // UTF-8 and control characters round-trip exactly.
  s = smallSequence();
  s.name = "caf\xc3\xa9 \x01\t\"q\" #";
  s.model = "m\xe2\x82\xac.obj";
  const Status ok = saveSequence(s, folder);
  ASSERT_TRUE(ok.ok()) << ok.error().message;
  auto loaded = loadSequence(folder);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_EQ(loaded->name, s.name);
  EXPECT_EQ(loaded->model, s.model);
}

TEST(SequenceFolder, LoadRefusesTheNonUtf8NamesSaveRefuses) {
  TempDir dir("limits_utf8_load");
  const std::string folder = dir.file("seq");
  ASSERT_TRUE(saveSequence(smallSequence(), folder).ok());
  const std::string yaml = folder + "/sequence.yaml";
  writeFile(yaml, "name: a\xeb\nmodel: city\n");
  auto loaded = loadSequence(folder);
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("not valid UTF-8"), std::string::npos) << loaded.error().message;
  for (const char c : loaded.error().message) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f);
}

TEST(YamlFiles, UnterminatedQuotedStringIsRefused) {
  TempDir dir("limits_quote");
  const std::string camera = dir.file("camera.yaml");
  // yaml-cpp reads `fx: "500` plus a line break as the string "500 ".
  for (const std::string& head :
       {std::string("fx: \"500\n"), std::string("fx: '500\n"), std::string("fx: !!str \"5\n")}) {
    ASSERT_TRUE(writeFile(camera, std::string("model: pinhole\n") + kCameraTail + head));
    expectFileError(loadSequenceCamera(camera), camera, 7, "never closed");
    expectFileError(loadCalibration(camera), camera, 7, "never closed");
  }
  // Closed strings with escapes and doubled quotes still read.
  ASSERT_TRUE(writeFile(camera, std::string("model: 'pin''hole'\nname: \"a\\\"b\"\nfx: \"500\"\n") + kCameraTail));
  const auto read = loadSequenceCamera(camera);
  ASSERT_FALSE(read.ok());  // "pin'hole" is not a model, but the file parsed.
  EXPECT_EQ(read.error().message.find("never closed"), std::string::npos) << read.error().message;
  ASSERT_TRUE(writeFile(camera, std::string("model: \"pinhole\"\nfx: \"500\"\n") + kCameraTail));
  EXPECT_TRUE(loadSequenceCamera(camera).ok());
  // sequence.yaml goes through the same reader.
  const std::string folder = dir.file("seq");
  ASSERT_TRUE(saveSequence(smallSequence(), folder).ok());
  ASSERT_TRUE(writeFile(folder + "/sequence.yaml", "name: \"open\nmodel: city\n"));
  expectFileError(loadSequence(folder), folder + "/sequence.yaml", 1, "never closed");
}

TEST(YamlFiles, LibraryMessagesQuotingRawBytesStayOnePrintableLine) {
  TempDir dir("limits_escape");
  const std::string camera = dir.file("camera.yaml");
  // yaml-cpp's "unknown escape character: <the byte>" for a NUL, a line break, a carriage
  // return and an escape byte after a backslash.
  for (const char byte : {'\0', '\n', '\r', '\x1b'}) {
    if (byte == '\n') continue;  // "\<line break>" is a valid YAML line continuation.
    std::string text = std::string("model: pinhole\n") + kCameraTail + "fx: \"\\";
    text += byte;
    text += "\"\n";
    ASSERT_TRUE(writeFile(camera, text));
    expectFileError(loadSequenceCamera(camera), camera, 7, "unknown escape character");
    expectFileError(loadCalibration(camera), camera, 7, "unknown escape character");
    auto plain = loadCamera(camera);
    ASSERT_FALSE(plain.ok());
    for (const char c : plain.error().message) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20);
  }
}

TEST(TableFiles, LongLinesAndHugeFilesAreRefusedWithTheLimit) {
  TempDir dir("limits_tables");
  const std::string images = dir.file("images.txt");
  ASSERT_TRUE(writeFile(images, "0 a.png\n1 " + std::string(70000, 'x') + ".png\n"));
  expectFileError(loadImageList(images), images, 2, "line is longer than 65536 bytes");
  const std::string imu = dir.file("imu.csv");
  ASSERT_TRUE(writeFile(imu, "0,0,0,0,0,0,0\n" + std::string(70000, ' ') + "1,0,0,0,0,0,0\n"));
  expectFileError(loadImuCsv(imu), imu, 2, "line is longer than 65536 bytes");
  // A file above 256 MiB (sparse: nothing is written) is refused before it is read.
  const std::string gt = dir.file("groundtruth.txt");
  ASSERT_TRUE(writeFile(gt, std::string("0 0 0 0 0 0 0 1\n")));
  fs::resize_file(gt, (uintmax_t{1} << 28) + 1);
  expectFileError(loadTumTrajectory(gt), gt, 0, "is larger than 268435456 bytes");
  // YAML above 1 MiB, even when it is valid.
  const std::string camera = dir.file("camera.yaml");
  ASSERT_TRUE(writeFile(
      camera, std::string("model: pinhole\nfx: 500\n") + kCameraTail + "#" + std::string(size_t{1} << 20, 'c') + "\n"));
  expectFileError(loadSequenceCamera(camera), camera, 0, "is larger than 1048576 bytes");
  expectFileError(loadCalibration(camera), camera, 0, "larger than 1048576 bytes");
}

TEST(TableFiles, ManyColmapCamerasLoadInLinearTime) {
  // Duplicate camera ids were found by comparing every pair: 40,000 cameras took seconds.
  TempDir dir("limits_colmap");
  const std::string path = dir.file("cameras.txt");
  std::string text = "# Camera list\n";
  for (int i = 1; i <= 40000; ++i) text += std::to_string(i) + " PINHOLE 640 480 500 500 320 240\n";
  ASSERT_TRUE(writeFile(path, text + "7 PINHOLE 640 480 500 500 320 240\n"));
  expectFileError(loadCalibration(path), path, 40002, "camera 7 is listed twice (also line 8)");
  ASSERT_TRUE(writeFile(path, text));
  auto last = loadCalibration(path, "40000");
  ASSERT_TRUE(last.ok()) << last.error().message;
}

}  // namespace
}  // namespace vkloc
