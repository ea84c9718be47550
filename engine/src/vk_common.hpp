// Vulkan helpers private to the engine: error conversion and RAII handles.
#pragma once

#include <vulkan/vulkan.h>

#include <utility>

#include "vkloc/core/status.hpp"

namespace vkloc::engine {

/// Name of a VkResult, e.g. "VK_ERROR_OUT_OF_DEVICE_MEMORY".
const char* vkResultName(VkResult result);

/// Error for a failed Vulkan call: kGpuError with the call and result named.
Error vkError(const char* call, VkResult result);

/// Evaluates a Vulkan call; returns its Error from the enclosing function when it fails.
#define VKLOC_VK(call)                                                                            \
  do {                                                                                            \
    VkResult vkloc_vk_result_ = (call);                                                           \
    if (vkloc_vk_result_ != VK_SUCCESS) return ::vkloc::engine::vkError(#call, vkloc_vk_result_); \
  } while (0)

/// Owns one device-level Vulkan handle (everything destroyed with vkDestroyX(device, x, alloc)).
template <typename T>
class DeviceHandle {
 public:
  using DestroyFn = void (*)(VkDevice, T, const VkAllocationCallbacks*);
  DeviceHandle() = default;
  DeviceHandle(VkDevice device, T handle, DestroyFn destroy) : device_(device), handle_(handle), destroy_(destroy) {}
  ~DeviceHandle() { reset(); }
  DeviceHandle(DeviceHandle&& o) noexcept { *this = std::move(o); }
  DeviceHandle& operator=(DeviceHandle&& o) noexcept {
    if (this != &o) {
      reset();
      device_ = std::exchange(o.device_, VK_NULL_HANDLE);
      handle_ = std::exchange(o.handle_, VK_NULL_HANDLE);
      destroy_ = std::exchange(o.destroy_, nullptr);
    }
    return *this;
  }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;

  void reset() {
    if (handle_ != VK_NULL_HANDLE && destroy_ != nullptr) destroy_(device_, handle_, nullptr);
    handle_ = VK_NULL_HANDLE;
  }
  T get() const { return handle_; }
  const T* ptr() const { return &handle_; }
  explicit operator bool() const { return handle_ != VK_NULL_HANDLE; }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = VK_NULL_HANDLE;
  DestroyFn destroy_ = nullptr;
};

/// A buffer with its own memory, persistently mapped when host-visible.
// Members are destroyed in reverse order: the memory outlives the objects bound to it.
struct Buffer {
  DeviceHandle<VkDeviceMemory> memory;
  DeviceHandle<VkBuffer> buffer;
  VkDeviceSize size = 0;
  void* mapped = nullptr;  ///< Non-null when host-visible (unmapped by freeing the memory).
};

/// An image with its own memory and a view.
struct Image {
  DeviceHandle<VkDeviceMemory> memory;
  DeviceHandle<VkImage> image;
  DeviceHandle<VkImageView> view;
  VkFormat format = VK_FORMAT_UNDEFINED;
  uint32_t width = 0;
  uint32_t height = 0;
  void* mapped = nullptr;      ///< Linear host-visible images only: the first texel.
  VkDeviceSize row_pitch = 0;  ///< Linear host-visible images only: bytes between rows.
};

}  // namespace vkloc::engine
