// The Vulkan instance, device and memory helpers behind vkloc::GpuContext.
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "vk_common.hpp"
#include "vkloc/gpu.hpp"

namespace vkloc {

struct GpuContext::Impl {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t queue_family = 0;
  VkPhysicalDeviceProperties properties{};
  VkPhysicalDeviceMemoryProperties memory_properties{};
  /// True when device-local memory is also host-visible (integrated GPUs, lavapipe): buffers
  /// are then mapped directly and staging copies are skipped.
  bool unified_memory = false;
  GpuDeviceInfo info;
  bool validation = false;
  bool print_validation = true;
  std::atomic<uint64_t> validation_messages{0};
  engine::DeviceHandle<VkCommandPool> command_pool;

  Impl() = default;
  ~Impl();
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  /// Memory type index with the required property flags among `type_bits`, or -1.
  int findMemoryType(uint32_t type_bits, VkMemoryPropertyFlags required) const;

  /// Allocates memory for `req`: host-visible coherent (cached when `prefer_cached` and
  /// available) when `mapped`, else device-local. `what` names the resource in errors.
  Result<engine::DeviceHandle<VkDeviceMemory>> allocate(const VkMemoryRequirements& req, bool mapped,
                                                        bool prefer_cached, const char* what);

  /// Creates a buffer. host_visible: mapped, coherent memory (for uploads/readback); otherwise
  /// device-local (which is also host-visible on unified memory, and then mapped too).
  Result<engine::Buffer> createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible);

  /// Creates a 2D image with one mip level and a view of it: optimal tiling in device-local
  /// memory, or (linear_host) linear tiling in host-visible memory, mapped, so the host reads
  /// it without a copy.
  Result<engine::Image> createImage(uint32_t width, uint32_t height, VkFormat format, VkImageUsageFlags usage,
                                    VkImageAspectFlags aspect, bool linear_host = false);

  /// True when a linear-tiling 2D image of `format` with exactly `usage` and at least this
  /// size can be created.
  bool linearImageSupported(VkFormat format, VkImageUsageFlags usage, uint32_t width, uint32_t height) const;

  /// Copies host data into a buffer: directly when mapped, else through a staging buffer.
  Status upload(engine::Buffer& dst, const void* data, VkDeviceSize size);

  /// Copies RGBA8 pixels into an image and leaves it in SHADER_READ_ONLY_OPTIMAL.
  Status uploadImage(engine::Image& dst, const void* rgba, VkDeviceSize size);

  /// Allocates a primary command buffer from the context's pool.
  Result<VkCommandBuffer> allocateCommandBuffer();

  /// Records with `record`, submits and waits for completion.
  template <typename F>
  Status runOnce(F&& record);

  /// Submits a recorded command buffer and waits on `fence` (which is reset first).
  Status submitAndWait(VkCommandBuffer cmd, VkFence fence);
};

template <typename F>
Status GpuContext::Impl::runOnce(F&& record) {
  Result<VkCommandBuffer> cmd = allocateCommandBuffer();
  if (!cmd.ok()) return cmd.error();
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(*cmd, &begin);
  record(*cmd);
  vkEndCommandBuffer(*cmd);
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  VkResult r = vkCreateFence(device, &fence_info, nullptr, &fence);
  Status status = r == VK_SUCCESS ? submitAndWait(*cmd, fence) : Status(engine::vkError("vkCreateFence", r));
  if (fence != VK_NULL_HANDLE) vkDestroyFence(device, fence, nullptr);
  vkFreeCommandBuffers(device, command_pool.get(), 1, &*cmd);
  return status;
}

}  // namespace vkloc
