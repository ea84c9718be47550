// Reading images: complete files load, truncated JPEG and PNG files are one-line errors naming
// the file (a truncated JPEG used to decode into a partly grey frame with only libjpeg's warning).
#include "vkloc/io/image_io.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "support/test_support.hpp"

namespace vkloc {
namespace {

std::vector<uint8_t> encoded(const std::string& ext) {
  cv::Mat img(48, 64, CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) img.at<uint8_t>(y, x) = static_cast<uint8_t>((x * 7 + y * 13) % 256);
  }
  std::vector<uint8_t> bytes;
  EXPECT_TRUE(cv::imencode(ext, img, bytes));
  return bytes;
}

std::string writeTemp(const std::string& name, const std::vector<uint8_t>& bytes) {
  const std::string path = (std::filesystem::temp_directory_path() / ("vkloc_image_io_" + name)).string();
  EXPECT_TRUE(test::writeFile(path, bytes));
  return path;
}

TEST(ImageIo, TruncatedJpegAndPngAreOneLineErrors) {
  for (const std::string ext : {".jpg", ".png"}) {
    const std::vector<uint8_t> full = encoded(ext);
    const std::string whole = writeTemp("whole" + ext, full);
    auto loaded = readImageU8(whole, 1);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->width, 64);
    for (double keep : {0.3, 0.7, 0.98}) {
      std::vector<uint8_t> cut(full.begin(), full.begin() + static_cast<std::ptrdiff_t>(full.size() * keep));
      const std::string path = writeTemp("cut" + ext, cut);
      auto r = readImageU8(path, 1);
      ASSERT_FALSE(r.ok()) << ext << " cut to " << keep;
      EXPECT_EQ(r.error().code, ErrorCode::kMalformedInput);
      EXPECT_NE(r.error().message.find(path), std::string::npos) << r.error().message;
      EXPECT_NE(r.error().message.find("truncated"), std::string::npos) << r.error().message;
      EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
    }
  }
  // Bytes after a JPEG's end marker (some writers pad) are fine.
  std::vector<uint8_t> padded = encoded(".jpg");
  padded.insert(padded.end(), 16, 0);
  auto r = readImageU8(writeTemp("padded.jpg", padded), 1);
  EXPECT_TRUE(r.ok()) << r.error().message;
}

}  // namespace
}  // namespace vkloc
