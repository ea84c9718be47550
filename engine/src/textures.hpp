// Model textures on the GPU: mip-mapped images, one trilinear REPEAT sampler and the descriptor
// sets through which model.frag samples them.
//
// Design: any number of textures on every device.
//  - Each texture keeps its own image at its own size (plus a third for its mip chain): no
//    atlas, no texture array of one common size, so hundreds of 1-2k textures of different sizes
//    cost what they weigh.
//  - The fragment shader indexes a sampler2D array with a dynamically uniform index (a push
//    constant, one per draw). The array lives in descriptor sets of `slots` textures each:
//    texture i is slot i % slots of set i / slots. The renderer binds a set only when a draw's
//    texture lies in another set than the bound one, so a model whose textures fit in one set
//    binds once per frame, and a larger one once per change of batch (at most once per draw).
//  - `slots` is as many textures as the device's per-stage and per-set limits allow, capped at
//    the texture count. Where those limits are too small for all textures and the device has
//    descriptor indexing (descriptorBindingSampledImageUpdateAfterBind), the set is created
//    update-after-bind, whose much larger limits usually hold every texture in one set (the
//    bindless case). Otherwise the textures are split into batches of `slots` (lavapipe: 32 per
//    stage, so the 35 textures of a room are two sets, 300 textures ten). Without dynamic
//    indexing of sampler arrays (shaderSampledImageArrayDynamicIndexing) a set holds one texture.
//    All of this works with core Vulkan 1.0 descriptor sets; the update-after-bind case only
//    raises the limits.
//  - Mip chains are made at upload: vkCmdBlitImage level by level with a linear filter where the
//    format supports linear blits (optimal tiling BLIT_SRC, BLIT_DST, SAMPLED_IMAGE_FILTER_LINEAR),
//    else on the host with buildMipLevels (the same filter, so both paths agree to rounding).
//    Textures larger than maxImageDimension2D are reduced on the host by whole levels until they fit.
#pragma once

#include <cstdint>
#include <vector>

#include "context.hpp"
#include "vk_common.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc::engine {

/// How textures are uploaded and grouped.
struct TextureSetOptions {
  /// Builds mip levels on the host even where the device can blit them (tests that path).
  bool host_mipmaps = false;
  /// Most textures per descriptor set below the device's limits; 0: as many as the device allows.
  uint32_t max_per_set = 0;
};

/// Textures of one model, uploaded with their mip chains and exposed through descriptor sets.
struct TextureSet {
  std::vector<Image> images;  ///< One per input texture, same order.
  DeviceHandle<VkSampler> sampler;
  DeviceHandle<VkDescriptorSetLayout> layout;  ///< Binding 0: sampler2D[slots], fragment stage.
  DeviceHandle<VkDescriptorPool> pool;
  std::vector<VkDescriptorSet> sets;  ///< Set k holds textures k * slots .. k * slots + slots - 1.
  uint32_t slots = 1;                 ///< Array size of each set (model.frag's kTextureCount).
  bool update_after_bind = false;     ///< The sets use the update-after-bind limits.
  bool blit_mipmaps = false;          ///< Mip levels were made with vkCmdBlitImage, not on the host.
  uint64_t texels = 0;                ///< Texels of all images, mip levels included.

  /// Uploads `textures` (each consistent: width, height > 0 and width * height * 4 bytes; an
  /// empty list uploads one white texel so that the set is never empty). kGpuError when the
  /// device runs out of memory or descriptors.
  static Result<TextureSet> create(GpuContext::Impl& ctx, const std::vector<Texture>& textures,
                                   const TextureSetOptions& options);

  /// The set that holds texture `index` and its slot in that set's array.
  uint32_t setOf(int index) const { return static_cast<uint32_t>(index) / slots; }
  int slotOf(int index) const { return static_cast<int>(static_cast<uint32_t>(index) % slots); }
};

}  // namespace vkloc::engine
