#include "vkloc/io/image_io.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <vector>

#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

// Encodes in memory and writes through core's atomic writer.
Status writeEncoded(const std::string& path, const cv::Mat& mat, const std::vector<int>& params, const char* ext) {
  std::vector<uint8_t> bytes;
  try {
    if (!cv::imencode(ext, mat, bytes, params)) {
      return makeError(ErrorCode::kIoError, fmt::format("{}: cannot encode image", path));
    }
  } catch (const cv::Exception& e) {
    return makeError(ErrorCode::kIoError, fmt::format("{}: cannot encode image: {}", path, text::oneLine(e.what())));
  }
  return writeFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

template <typename T>
Status checkImage(const std::string& path, const Image<T>& img) {
  if (img.width <= 0 || img.height <= 0 ||
      img.data.size() != static_cast<size_t>(img.width) * img.height * img.channels) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: image has inconsistent size", path));
  }
  return Status::success();
}

}  // namespace

Status writePng(const std::string& path, const ImageU8& image) {
  VKLOC_TRY_STATUS(checkImage(path, image));
  if (image.channels != 1 && image.channels != 3 && image.channels != 4) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: PNG needs 1, 3 or 4 channels", path));
  }
  const int type = CV_8UC(image.channels);
  cv::Mat src(image.height, image.width, type, const_cast<uint8_t*>(image.data.data()));
  cv::Mat bgr;
  if (image.channels == 4)
    cv::cvtColor(src, bgr, cv::COLOR_RGBA2BGRA);
  else if (image.channels == 3)
    cv::cvtColor(src, bgr, cv::COLOR_RGB2BGR);
  else
    bgr = src;
  return writeEncoded(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 3}, ".png");
}

Status writePng(const std::string& path, const ImageU16& image) {
  VKLOC_TRY_STATUS(checkImage(path, image));
  if (image.channels != 1)
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: 16-bit PNG must be gray", path));
  cv::Mat src(image.height, image.width, CV_16UC1, const_cast<uint16_t*>(image.data.data()));
  return writeEncoded(path, src, {cv::IMWRITE_PNG_COMPRESSION, 3}, ".png");
}

Status writeFloatTiff(const std::string& path, const ImageF32& image) {
  VKLOC_TRY_STATUS(checkImage(path, image));
  if (image.channels != 1)
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: float TIFF must be 1 channel", path));
  cv::Mat src(image.height, image.width, CV_32FC1, const_cast<float*>(image.data.data()));
  return writeEncoded(path, src, {cv::IMWRITE_TIFF_COMPRESSION, 1}, ".tiff");
}

namespace {

/// Why an encoded JPEG or PNG is cut short (no end marker), or nothing for a complete one (and for
/// other formats, which the decoder checks).
std::optional<std::string> truncation(const std::vector<uint8_t>& b) {
  const size_t n = b.size();
  if (n >= 2 && b[0] == 0xFF && b[1] == 0xD8) {
    // End of image FF D9 among the last bytes (writers may pad after it); inside the entropy-coded
    // data FF is always followed by 00 or a restart marker, so a cut file has none there.
    const size_t from = n > 64 ? n - 64 : 0;
    for (size_t i = n - 1; i > from; --i) {
      if (b[i - 1] == 0xFF && b[i] == 0xD9) return std::nullopt;
    }
    return std::string("truncated JPEG (no end-of-image marker)");
  }
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (n >= 8 && std::equal(kPng, kPng + 8, b.begin())) {
    // The IEND chunk closes every PNG: length 0, "IEND", CRC.
    static const uint8_t kIend[4] = {'I', 'E', 'N', 'D'};
    if (n < 20 || !std::equal(kIend, kIend + 4, b.end() - 8)) return std::string("truncated PNG (no IEND chunk)");
  }
  return std::nullopt;
}

}  // namespace

Result<ImageU8> readImageU8(const std::string& path, int channels) {
  if (channels != 1 && channels != 4) {
    return makeError(ErrorCode::kInvalidArgument, "readImageU8: channels must be 1 or 4");
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: image not found", path));
  }
  std::vector<uint8_t> bytes;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) return makeError(ErrorCode::kIoError, fmt::format("{}: cannot open the image", path));
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // A truncated JPEG or PNG decodes into a partly grey image (libjpeg only warns): refused here,
  // before the decoder prints its own line.
  if (const std::optional<std::string> cut = truncation(bytes)) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: {}", path, *cut));
  }
  cv::Mat m;
  try {
    m = cv::imdecode(bytes, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
  }
  if (m.empty()) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: not a readable image", path));
  if (m.depth() != CV_8U) m.convertTo(m, CV_8U, 1.0 / 256.0);
  ImageU8 out(m.cols, m.rows, channels);
  cv::Mat dst(m.rows, m.cols, CV_8UC(channels), out.data.data());
  if (channels == 4)
    cv::cvtColor(m, dst, cv::COLOR_BGR2RGBA);
  else
    m.copyTo(dst);
  return out;
}

Result<ImageF32> readFloatTiff(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: image not found", path));
  }
  cv::Mat m;
  try {
    m = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
  }
  if (m.empty() || m.type() != CV_32FC1) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: not a 1-channel float TIFF", path));
  }
  ImageF32 out(m.cols, m.rows, 1);
  cv::Mat dst(m.rows, m.cols, CV_32FC1, out.data.data());
  m.copyTo(dst);
  return out;
}

}  // namespace vkloc
