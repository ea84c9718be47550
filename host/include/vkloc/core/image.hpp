// vkloc: plain host images (reading and writing image files: io/image_io.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/status.hpp"

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

/// Converts metric depth (metres, 0 = no surface) to 16-bit millimetres, clamped to 65535;
/// background and non-finite values become 0.
ImageU16 depthToMillimetres(const ImageF32& depth_m);

/// Converts RGBA8 to 8-bit gray with ITU-R BT.601 weights (0.299 R + 0.587 G + 0.114 B).
ImageU8 rgbaToGray(const ImageU8& rgba);

}  // namespace vkloc
