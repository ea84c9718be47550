// Texture mip chains: the filter of vkCmdBlitImage with VK_FILTER_LINEAR, on the host.
#include "vkloc/render/mipmap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace vkloc {

int textureMipLevelCount(int width, int height) {
  if (width <= 0 || height <= 0) return 0;
  int levels = 1;
  for (int size = std::max(width, height); size > 1; size /= 2) ++levels;
  return levels;
}

Texture downsampleTexture(const Texture& level) {
  Texture out;
  out.name = level.name;
  out.width = std::max(1, level.width / 2);
  out.height = std::max(1, level.height / 2);
  if (out.width == level.width && out.height == level.height) return level;
  out.rgba.resize(static_cast<size_t>(out.width) * out.height * 4);
  const double scale_x = static_cast<double>(level.width) / out.width;
  const double scale_y = static_cast<double>(level.height) / out.height;
  // Source texel coordinate of the sample for destination index k, its two neighbours and the
  // weight of the second: bilinear with clamp-to-edge at x = (k + 0.5) scale - 0.5.
  struct Tap {
    int lo, hi;
    double w;
  };
  auto taps = [](int count, double scale, int size) {
    std::vector<Tap> t(static_cast<size_t>(count));
    for (int k = 0; k < count; ++k) {
      const double x = (k + 0.5) * scale - 0.5;
      const double x0 = std::floor(x);
      const int lo = static_cast<int>(x0);
      t[static_cast<size_t>(k)] = {std::clamp(lo, 0, size - 1), std::clamp(lo + 1, 0, size - 1), x - x0};
    }
    return t;
  };
  const std::vector<Tap> tx = taps(out.width, scale_x, level.width);
  const std::vector<Tap> ty = taps(out.height, scale_y, level.height);
  auto texel = [&](int x, int y, int c) -> double {
    return level.rgba[(static_cast<size_t>(y) * level.width + x) * 4 + c];
  };
  for (int y = 0; y < out.height; ++y) {
    const Tap& b = ty[static_cast<size_t>(y)];
    for (int x = 0; x < out.width; ++x) {
      const Tap& a = tx[static_cast<size_t>(x)];
      uint8_t* px = &out.rgba[(static_cast<size_t>(y) * out.width + x) * 4];
      for (int c = 0; c < 4; ++c) {
        const double top = (1 - a.w) * texel(a.lo, b.lo, c) + a.w * texel(a.hi, b.lo, c);
        const double bottom = (1 - a.w) * texel(a.lo, b.hi, c) + a.w * texel(a.hi, b.hi, c);
        px[c] = static_cast<uint8_t>(std::lround(std::clamp((1 - b.w) * top + b.w * bottom, 0.0, 255.0)));
      }
    }
  }
  return out;
}

std::vector<Texture> buildMipLevels(const Texture& base) {
  std::vector<Texture> levels;
  const int count = textureMipLevelCount(base.width, base.height);
  if (count <= 1) return levels;
  levels.reserve(static_cast<size_t>(count - 1));
  levels.push_back(downsampleTexture(base));
  while (static_cast<int>(levels.size()) + 1 < count) levels.push_back(downsampleTexture(levels.back()));
  return levels;
}

}  // namespace vkloc
