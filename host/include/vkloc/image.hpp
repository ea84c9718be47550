// vkloc: plain host images.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/status.hpp"

namespace vkloc {

/// A dense image with `channels` interleaved values per pixel, rows top to bottom, no padding.
template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  int channels = 1;
  std::vector<T> data;  ///< width * height * channels values.

  Image() = default;
  Image(int w, int h, int c, T fill = T{})
      : width(w), height(h), channels(c), data(static_cast<size_t>(w) * h * c, fill) {}
  bool empty() const { return data.empty(); }
  T& at(int x, int y, int c = 0) { return data[(static_cast<size_t>(y) * width + x) * channels + c]; }
  const T& at(int x, int y, int c = 0) const { return data[(static_cast<size_t>(y) * width + x) * channels + c]; }
};

using ImageU8 = Image<uint8_t>;
using ImageU16 = Image<uint16_t>;
using ImageF32 = Image<float>;

/// Writes an 8-bit gray/RGB/RGBA image or a 16-bit gray image as PNG. The file is written to a
/// temporary name and renamed, so an existing file is never left half-written.
Status writePng(const std::string& path, const ImageU8& image);
Status writePng(const std::string& path, const ImageU16& image);

/// Writes a single-channel float image as TIFF (32-bit float, lossless; readable by OpenCV,
/// GDAL, Python's tifffile). Same atomic-rename guarantee as writePng.
Status writeFloatTiff(const std::string& path, const ImageF32& image);

/// Reads an image file (PNG, JPEG, TIFF, ...) as 8-bit with `channels` = 1 (gray) or 4 (RGBA).
Result<ImageU8> readImageU8(const std::string& path, int channels);

/// Reads a single-channel 32-bit float TIFF written by writeFloatTiff.
Result<ImageF32> readFloatTiff(const std::string& path);

/// Converts metric depth (metres, 0 = no surface) to 16-bit millimetres, clamped to 65535;
/// background and non-finite values become 0.
ImageU16 depthToMillimetres(const ImageF32& depth_m);

/// Converts RGBA8 to 8-bit gray with ITU-R BT.601 weights (0.299 R + 0.587 G + 0.114 B).
ImageU8 rgbaToGray(const ImageU8& rgba);

}  // namespace vkloc
