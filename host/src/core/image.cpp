#include "vkloc/core/image.hpp"

#include <algorithm>
#include <cmath>

namespace vkloc {

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
