#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vkloc/image.hpp"

namespace vkloc {
namespace {

// Writes through a temporary file in the same directory and renames it into place.
template <typename T>
Status writeAtomic(const std::string& path, const cv::Mat& mat, const std::vector<int>& params, const char* ext) {
  namespace fs = std::filesystem;
  const std::string tmp = path + ".tmp" + ext;
  try {
    if (!cv::imwrite(tmp, mat, params)) {
      return makeError(ErrorCode::kIoError, fmt::format("{}: cannot write image", path));
    }
  } catch (const cv::Exception& e) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return makeError(ErrorCode::kIoError, fmt::format("{}: cannot write image: {}", path, e.what()));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return makeError(ErrorCode::kIoError, fmt::format("{}: cannot rename into place: {}", path, ec.message()));
  }
  return Status::success();
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
  return writeAtomic<uint8_t>(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 3}, ".png");
}

Status writePng(const std::string& path, const ImageU16& image) {
  VKLOC_TRY_STATUS(checkImage(path, image));
  if (image.channels != 1)
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: 16-bit PNG must be gray", path));
  cv::Mat src(image.height, image.width, CV_16UC1, const_cast<uint16_t*>(image.data.data()));
  return writeAtomic<uint16_t>(path, src, {cv::IMWRITE_PNG_COMPRESSION, 3}, ".png");
}

Status writeFloatTiff(const std::string& path, const ImageF32& image) {
  VKLOC_TRY_STATUS(checkImage(path, image));
  if (image.channels != 1)
    return makeError(ErrorCode::kInvalidArgument, fmt::format("{}: float TIFF must be 1 channel", path));
  cv::Mat src(image.height, image.width, CV_32FC1, const_cast<float*>(image.data.data()));
  return writeAtomic<float>(path, src, {cv::IMWRITE_TIFF_COMPRESSION, 1}, ".tiff");
}

Result<ImageU8> readImageU8(const std::string& path, int channels) {
  if (channels != 1 && channels != 4) {
    return makeError(ErrorCode::kInvalidArgument, "readImageU8: channels must be 1 or 4");
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: image not found", path));
  }
  cv::Mat m;
  try {
    m = cv::imread(path, channels == 1 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
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

ImageU16 depthToMillimetres(const ImageF32& depth_m) {
  ImageU16 out(depth_m.width, depth_m.height, 1);
  for (size_t i = 0; i < out.data.size(); ++i) {
    const float z = depth_m.data[i * depth_m.channels];
    if (!std::isfinite(z) || z <= 0.0f) continue;
    out.data[i] = static_cast<uint16_t>(std::min(65535.0f, std::round(z * 1000.0f)));
  }
  return out;
}

ImageU8 rgbaToGray(const ImageU8& rgba) {
  ImageU8 out(rgba.width, rgba.height, 1);
  const size_t n = static_cast<size_t>(rgba.width) * rgba.height;
  const uint8_t* p = rgba.data.data();
  for (size_t i = 0; i < n; ++i, p += rgba.channels) {
    // BT.601 in 16.16 fixed point, rounded.
    out.data[i] = static_cast<uint8_t>((19595u * p[0] + 38470u * p[1] + 7471u * p[2] + 32768u) >> 16);
  }
  return out;
}

}  // namespace vkloc
