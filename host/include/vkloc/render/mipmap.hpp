// vkloc: texture mip chains shared by the CPU reference renderer and the GPU renderer's host path.
#pragma once

#include <vector>

#include "vkloc/model/model.hpp"

namespace vkloc {

/// Mip levels of a width x height texture down to 1 x 1: floor(log2(max(width, height))) + 1;
/// 0 when a side is not positive.
int textureMipLevelCount(int width, int height);

/// The next mip level of `level`: max(1, width / 2) x max(1, height / 2) texels (Vulkan's level
/// sizes), texel (x, y) being the bilinear sample of `level` at the point that maps onto its centre,
/// ((x + 0.5) width / new_width, (y + 0.5) height / new_height) in texels, with clamp-to-edge and
/// rounding to nearest: what vkCmdBlitImage with VK_FILTER_LINEAR computes. For even sizes that
/// is the mean of a 2 x 2 block. All four channels. Precondition: a consistent texture
/// (width, height > 0, rgba of width * height * 4 bytes); a 1 x 1 texture is returned unchanged.
Texture downsampleTexture(const Texture& level);

/// Levels 1 .. textureMipLevelCount - 1 of `base`'s mip chain (level 0 is `base` itself), each
/// made from the one above by downsampleTexture. About a third of `base`'s bytes in all. Both
/// renderers sample these (the GPU renderer where it builds its levels on the host).
std::vector<Texture> buildMipLevels(const Texture& base);

}  // namespace vkloc
