// The Vulkan instance, device and memory helpers behind vkloc::GpuContext.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <vector>

#include "vk_common.hpp"
#include "vkloc/engine/gpu.hpp"

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
  /// shaderSampledImageArrayDynamicIndexing is enabled: shaders may index sampler arrays with
  /// dynamically uniform values (a push constant).
  bool dynamic_sampler_indexing = false;
  /// descriptorBindingSampledImageUpdateAfterBind (descriptor indexing) is enabled: descriptor
  /// sets of sampled images may be created update-after-bind and use the larger limits of
  /// vulkan12_properties.
  bool sampled_image_update_after_bind = false;
  /// Vulkan 1.2 properties (descriptor indexing limits among them); pNext is null.
  VkPhysicalDeviceVulkan12Properties vulkan12_properties{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_PROPERTIES};
  GpuDeviceInfo info;
  bool validation = false;
  WarningHandler on_validation_message;
  std::atomic<uint64_t> validation_messages{0};
  /// Pool of the one-off command buffers of runOnce (guarded by pool_mutex). Renderers and edge
  /// stages record into pools of their own (createCommandPool), so that they can record on
  /// different threads.
  engine::DeviceHandle<VkCommandPool> command_pool;
  std::mutex pool_mutex;
  /// Guards `queue`: every vkQueueSubmit of every object on this context goes through submit().
  std::mutex queue_mutex;

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

  /// Creates a 2D image with `mip_levels` levels and a view of all of them: optimal tiling in
  /// device-local memory, or (linear_host, one level only) linear tiling in host-visible memory,
  /// mapped, so the host reads it without a copy.
  Result<engine::Image> createImage(uint32_t width, uint32_t height, VkFormat format, VkImageUsageFlags usage,
                                    VkImageAspectFlags aspect, bool linear_host = false, uint32_t mip_levels = 1);

  /// True when a linear-tiling 2D image of `format` with exactly `usage` and at least this
  /// size can be created.
  bool linearImageSupported(VkFormat format, VkImageUsageFlags usage, uint32_t width, uint32_t height) const;

  /// Copies host data into a buffer: directly when mapped, else through a staging buffer.
  Status upload(engine::Buffer& dst, const void* data, VkDeviceSize size);

  /// Copies RGBA8 pixels into an image and leaves it in SHADER_READ_ONLY_OPTIMAL.
  Status uploadImage(engine::Image& dst, const void* rgba, VkDeviceSize size);

  /// A command pool for one object's command buffers (resettable buffers), used by the thread
  /// that uses the object.
  Result<engine::DeviceHandle<VkCommandPool>> createCommandPool();

  /// Allocates a primary command buffer from `pool`.
  Result<VkCommandBuffer> allocateCommandBuffer(VkCommandPool pool);

  /// An unsignalled fence.
  Result<engine::DeviceHandle<VkFence>> createFence();

  /// Mask of the valid bits of a timestamp on `queue_family`; 0 when the queue does not
  /// support compute timestamps.
  uint64_t timestampMask() const;

  /// A timestamp query pool of `count` queries, or an empty handle when timestampMask() is 0.
  Result<engine::DeviceHandle<VkQueryPool>> createTimestampPool(uint32_t count);

  /// vkQueueSubmit of one submission under the queue lock.
  Status submit(const VkSubmitInfo& submit_info, VkFence fence);

  /// vkQueueWaitIdle under the queue lock (vkDeviceWaitIdle would race with other threads'
  /// submissions).
  Status waitQueueIdle();

  /// Records with `record`, submits and waits for completion.
  template <typename F>
  Status runOnce(F&& record);

  /// Submits a recorded command buffer and waits on `fence` (which is reset first).
  Status submitAndWait(VkCommandBuffer cmd, VkFence fence);
};

template <typename F>
Status GpuContext::Impl::runOnce(F&& record) {
  std::lock_guard<std::mutex> lock(pool_mutex);
  Result<VkCommandBuffer> cmd = allocateCommandBuffer(command_pool.get());
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
