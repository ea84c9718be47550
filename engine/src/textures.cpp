// TextureSet: model textures with mip chains, a trilinear sampler and batched descriptor sets.
#include "textures.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <initializer_list>

#include "vkloc/render/mipmap.hpp"

namespace vkloc::engine {
namespace {

constexpr VkFormat kTextureFormat = VK_FORMAT_R8G8B8A8_UNORM;
/// Colour attachments of the model pass; they count against maxPerStageResources.
constexpr uint32_t kColorAttachments = 3;
/// Staging bytes per upload submission: bounds the host memory of a large model's upload.
constexpr VkDeviceSize kStagingChunkBytes = VkDeviceSize(64) << 20;

/// One texture ready for upload: level 0 (reduced to the device's largest image when needed)
/// and, on the host-mipmap path, its other levels.
struct Pending {
  Texture base;
  std::vector<Texture> levels;
  uint32_t level_count = 1;
  VkDeviceSize bytes = 0;  ///< Staging bytes: level 0, plus the other levels on the host path.
};

uint32_t minOf(std::initializer_list<uint32_t> values) { return std::min(values); }

/// Textures per set that the device's limits allow for a fragment-stage sampler2D array.
uint32_t slotLimit(const VkPhysicalDeviceLimits& l) {
  return minOf({l.maxPerStageDescriptorSamplers, l.maxPerStageDescriptorSampledImages, l.maxDescriptorSetSamplers,
                l.maxDescriptorSetSampledImages,
                l.maxPerStageResources > kColorAttachments ? l.maxPerStageResources - kColorAttachments : 1u});
}

uint32_t slotLimitUpdateAfterBind(const VkPhysicalDeviceVulkan12Properties& p) {
  return minOf({p.maxPerStageDescriptorUpdateAfterBindSamplers, p.maxPerStageDescriptorUpdateAfterBindSampledImages,
                p.maxDescriptorSetUpdateAfterBindSamplers, p.maxDescriptorSetUpdateAfterBindSampledImages,
                p.maxPerStageUpdateAfterBindResources > kColorAttachments
                    ? p.maxPerStageUpdateAfterBindResources - kColorAttachments
                    : 1u});
}

/// Records the copies (and blits) that fill `image` from `staging` at `offset` and leave every
/// level in SHADER_READ_ONLY_OPTIMAL.
void recordUpload(VkCommandBuffer cmd, const Pending& p, const Image& image, VkBuffer staging, VkDeviceSize offset,
                  bool blit) {
  // A layout transition of levels [first, first + count) of the image.
  auto transition = [&](uint32_t first, uint32_t count, VkAccessFlags src, VkAccessFlags dst, VkImageLayout from,
                        VkImageLayout to) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image.image.get();
    b.srcAccessMask = src;
    b.dstAccessMask = dst;
    b.oldLayout = from;
    b.newLayout = to;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, first, count, 0, 1};
    return b;
  };
  auto barrier = [&](VkPipelineStageFlags src, VkPipelineStageFlags dst,
                     std::initializer_list<VkImageMemoryBarrier> bs) {
    vkCmdPipelineBarrier(cmd, src, dst, 0, 0, nullptr, 0, nullptr, static_cast<uint32_t>(bs.size()), bs.begin());
  };
  barrier(VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
          {transition(0, p.level_count, 0, VK_ACCESS_TRANSFER_WRITE_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL)});
  std::vector<VkBufferImageCopy> regions;
  VkDeviceSize at = offset;
  auto add = [&](const Texture& t, uint32_t level) {
    VkBufferImageCopy r{};
    r.bufferOffset = at;
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, 0, 1};
    r.imageExtent = {static_cast<uint32_t>(t.width), static_cast<uint32_t>(t.height), 1};
    regions.push_back(r);
    at += t.rgba.size();
  };
  add(p.base, 0);
  for (size_t k = 0; k < p.levels.size(); ++k) add(p.levels[k], static_cast<uint32_t>(k + 1));
  vkCmdCopyBufferToImage(cmd, staging, image.image.get(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                         static_cast<uint32_t>(regions.size()), regions.data());

  const uint32_t last = p.level_count - 1;
  if (!blit || last == 0) {
    barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
            {transition(0, p.level_count, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT,
                        VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)});
    return;
  }
  int32_t w = p.base.width, h = p.base.height;
  for (uint32_t level = 1; level <= last; ++level) {
    // Level - 1 is complete: make it the blit source.
    barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
            {transition(level - 1, 1, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
                        VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL)});
    const int32_t nw = std::max(1, w / 2), nh = std::max(1, h / 2);
    VkImageBlit blit_region{};
    blit_region.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level - 1, 0, 1};
    blit_region.srcOffsets[1] = {w, h, 1};
    blit_region.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, level, 0, 1};
    blit_region.dstOffsets[1] = {nw, nh, 1};
    vkCmdBlitImage(cmd, image.image.get(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, image.image.get(),
                   VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit_region, VK_FILTER_LINEAR);
    w = nw;
    h = nh;
  }
  // Levels 0 .. last - 1 were blit sources, the last one only written.
  barrier(VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
          {transition(0, last, VK_ACCESS_TRANSFER_READ_BIT, VK_ACCESS_SHADER_READ_BIT,
                      VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL),
           transition(last, 1, VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_SHADER_READ_BIT,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)});
}

}  // namespace

Result<TextureSet> TextureSet::create(GpuContext::Impl& ctx, const std::vector<Texture>& input,
                                      const TextureSetOptions& options) {
  TextureSet out;
  const VkDevice device = ctx.device;
  const VkPhysicalDeviceLimits& limits = ctx.properties.limits;
  VkFormatProperties format{};
  vkGetPhysicalDeviceFormatProperties(ctx.physical, kTextureFormat, &format);
  constexpr VkFormatFeatureFlags kBlit = VK_FORMAT_FEATURE_BLIT_SRC_BIT | VK_FORMAT_FEATURE_BLIT_DST_BIT |
                                         VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
  out.blit_mipmaps = !options.host_mipmaps && (format.optimalTilingFeatures & kBlit) == kBlit;

  const Texture white{"white", 1, 1, {255, 255, 255, 255}};
  const size_t count = input.empty() ? 1 : input.size();
  const int max_side = static_cast<int>(limits.maxImageDimension2D);

  // Upload in chunks of about kStagingChunkBytes: one staging buffer and one submission each.
  out.images.reserve(count);
  size_t next = 0;
  while (next < count) {
    std::vector<Pending> chunk;
    VkDeviceSize chunk_bytes = 0;
    while (next < count && (chunk.empty() || chunk_bytes < kStagingChunkBytes)) {
      Pending p;
      p.base = input.empty() ? white : input[next];
      while (p.base.width > max_side || p.base.height > max_side) p.base = downsampleTexture(p.base);
      p.level_count = static_cast<uint32_t>(textureMipLevelCount(p.base.width, p.base.height));
      if (!out.blit_mipmaps) p.levels = buildMipLevels(p.base);
      p.bytes = p.base.rgba.size();
      for (const Texture& l : p.levels) p.bytes += l.rgba.size();
      chunk_bytes += p.bytes;
      chunk.push_back(std::move(p));
      ++next;
    }
    auto staging = ctx.createBuffer(chunk_bytes, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
    if (!staging.ok()) return staging.error();
    auto* dst = static_cast<uint8_t*>(staging->mapped);
    std::vector<VkDeviceSize> offsets;
    VkDeviceSize at = 0;
    const size_t first_image = out.images.size();
    for (const Pending& p : chunk) {
      offsets.push_back(at);
      std::memcpy(dst + at, p.base.rgba.data(), p.base.rgba.size());
      at += p.base.rgba.size();
      for (const Texture& l : p.levels) {
        std::memcpy(dst + at, l.rgba.data(), l.rgba.size());
        at += l.rgba.size();
      }
      VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
      if (out.blit_mipmaps) usage |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
      auto img = ctx.createImage(static_cast<uint32_t>(p.base.width), static_cast<uint32_t>(p.base.height),
                                 kTextureFormat, usage, VK_IMAGE_ASPECT_COLOR_BIT, false, p.level_count);
      if (!img.ok()) return img.error();
      out.images.push_back(std::move(*img));
      for (int w = p.base.width, h = p.base.height, l = 0; l < static_cast<int>(p.level_count); ++l) {
        out.texels += static_cast<uint64_t>(w) * h;
        w = std::max(1, w / 2);
        h = std::max(1, h / 2);
      }
    }
    VKLOC_TRY_STATUS(ctx.runOnce([&](VkCommandBuffer cmd) {
      for (size_t k = 0; k < chunk.size(); ++k) {
        recordUpload(cmd, chunk[k], out.images[first_image + k], staging->buffer.get(), offsets[k], out.blit_mipmaps);
      }
    }));
  }

  // Trilinear, REPEAT, every level (maxLod unclamped: each image stops at its own last level).
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.minLod = 0.0f;
  sci.maxLod = VK_LOD_CLAMP_NONE;
  VkSampler s = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateSampler(device, &sci, nullptr, &s));
  out.sampler = DeviceHandle<VkSampler>(device, s, vkDestroySampler);

  // Slots per set: all textures when the plain limits allow, else the update-after-bind limits
  // where the device has them, else batches of the plain limit.
  const uint32_t n = static_cast<uint32_t>(count);
  uint32_t slots = std::max(1u, slotLimit(limits));
  if (slots < n && ctx.sampled_image_update_after_bind) {
    const uint32_t uab = slotLimitUpdateAfterBind(ctx.vulkan12_properties);
    if (uab > slots) {
      slots = uab;
      out.update_after_bind = true;
    }
  }
  if (!ctx.dynamic_sampler_indexing) slots = 1;
  if (options.max_per_set > 0) slots = std::min(slots, options.max_per_set);
  slots = std::min(slots, n);
  if (out.update_after_bind && slots <= std::max(1u, slotLimit(limits))) out.update_after_bind = false;
  out.slots = slots;
  const uint32_t set_count = (n + slots - 1) / slots;

  VkDescriptorSetLayoutBinding binding{};
  binding.binding = 0;
  binding.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  binding.descriptorCount = slots;
  binding.stageFlags = VK_SHADER_STAGE_FRAGMENT_BIT;
  const VkDescriptorBindingFlags binding_flags = VK_DESCRIPTOR_BINDING_UPDATE_AFTER_BIND_BIT;
  VkDescriptorSetLayoutBindingFlagsCreateInfo flags_info{
      VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_BINDING_FLAGS_CREATE_INFO};
  flags_info.bindingCount = 1;
  flags_info.pBindingFlags = &binding_flags;
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 1;
  lci.pBindings = &binding;
  if (out.update_after_bind) {
    lci.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_UPDATE_AFTER_BIND_POOL_BIT;
    lci.pNext = &flags_info;
  }
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorSetLayout(device, &lci, nullptr, &layout));
  out.layout = DeviceHandle<VkDescriptorSetLayout>(device, layout, vkDestroyDescriptorSetLayout);

  VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, slots * set_count};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  if (out.update_after_bind) dpci.flags = VK_DESCRIPTOR_POOL_CREATE_UPDATE_AFTER_BIND_BIT;
  dpci.maxSets = set_count;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &pool_size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorPool(device, &dpci, nullptr, &pool));
  out.pool = DeviceHandle<VkDescriptorPool>(device, pool, vkDestroyDescriptorPool);

  const std::vector<VkDescriptorSetLayout> layouts(set_count, layout);
  out.sets.resize(set_count);
  VkDescriptorSetAllocateInfo dsai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  dsai.descriptorPool = pool;
  dsai.descriptorSetCount = set_count;
  dsai.pSetLayouts = layouts.data();
  VKLOC_VK(vkAllocateDescriptorSets(device, &dsai, out.sets.data()));
  // Every slot is written (slots past the last texture repeat the set's first one), so no
  // partially-bound support is needed.
  std::vector<VkDescriptorImageInfo> infos(static_cast<size_t>(slots) * set_count);
  std::vector<VkWriteDescriptorSet> writes(set_count);
  for (uint32_t k = 0; k < set_count; ++k) {
    for (uint32_t slot = 0; slot < slots; ++slot) {
      const uint32_t index = k * slots + slot < n ? k * slots + slot : k * slots;
      infos[static_cast<size_t>(k) * slots + slot] = {out.sampler.get(), out.images[index].view.get(),
                                                      VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    VkWriteDescriptorSet& w = writes[k];
    w = VkWriteDescriptorSet{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = out.sets[k];
    w.dstBinding = 0;
    w.descriptorCount = slots;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = &infos[static_cast<size_t>(k) * slots];
  }
  vkUpdateDescriptorSets(device, set_count, writes.data(), 0, nullptr);
  return out;
}

}  // namespace vkloc::engine
