// Vulkan instance/device creation, device selection, validation and memory helpers.
#include "context.hpp"

#include <dlfcn.h>
#include <fmt/format.h>
#include <link.h>
#include <malloc.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
constexpr const char* kNoDriverMessage =
    "no Vulkan device found: install a Vulkan driver (apt-get install mesa-vulkan-drivers for "
    "the CPU driver lavapipe, or your GPU vendor's driver)";

using text::lower;

const char* deviceTypeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return "discrete";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return "integrated";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return "virtual";
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return "cpu";
    default:
      return "other";
  }
}

int deviceTypeScore(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      return 1;
    default:
      return 0;
  }
}

std::string versionString(uint32_t v) {
  return fmt::format("{}.{}.{}", VK_API_VERSION_MAJOR(v), VK_API_VERSION_MINOR(v), VK_API_VERSION_PATCH(v));
}

VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                             VkDebugUtilsMessageTypeFlagsEXT types,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* impl = static_cast<GpuContext::Impl*>(user);
  const bool counts =
      (severity & (VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT)) !=
          0 &&
      (types & (VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT)) != 0;
  if (counts) {
    impl->validation_messages.fetch_add(1);
    if (impl->on_validation_message) {
      impl->on_validation_message(text::oneLine(data->pMessage ? data->pMessage : "(no message)"));
    }
  }
  return VK_FALSE;
}

bool layerAvailable(const char* name) {
  uint32_t count = 0;
  vkEnumerateInstanceLayerProperties(&count, nullptr);
  std::vector<VkLayerProperties> layers(count);
  vkEnumerateInstanceLayerProperties(&count, layers.data());
  for (const auto& l : layers) {
    if (std::strcmp(l.layerName, name) == 0) return true;
  }
  return false;
}

bool formatSupports(VkPhysicalDevice pd, VkFormat format, VkFormatFeatureFlags features) {
  VkFormatProperties p{};
  vkGetPhysicalDeviceFormatProperties(pd, format, &p);
  return (p.optimalTilingFeatures & features) == features;
}

// Fills `info` for a physical device, including whether vkloc can use it.
GpuDeviceInfo describe(VkPhysicalDevice pd, int index) {
  VkPhysicalDeviceProperties props{};
  vkGetPhysicalDeviceProperties(pd, &props);
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props2.pNext = &driver;
  if (props.apiVersion >= VK_API_VERSION_1_2) vkGetPhysicalDeviceProperties2(pd, &props2);
  GpuDeviceInfo info;
  info.index = index;
  info.name = props.deviceName;
  info.type = deviceTypeName(props.deviceType);
  info.api_version = versionString(props.apiVersion);
  info.driver = fmt::format("{} {}", driver.driverName, driver.driverInfo);
  std::vector<std::string> problems;
  if (props.apiVersion < VK_API_VERSION_1_2) problems.push_back("needs Vulkan 1.2");
  uint32_t qcount = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &qcount, nullptr);
  std::vector<VkQueueFamilyProperties> families(qcount);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &qcount, families.data());
  bool graphics = false;
  for (const auto& f : families) {
    graphics = graphics || ((f.queueFlags & VK_QUEUE_GRAPHICS_BIT) && (f.queueFlags & VK_QUEUE_COMPUTE_BIT));
  }
  if (!graphics) problems.push_back("no graphics+compute queue");
  if (!formatSupports(pd, VK_FORMAT_D32_SFLOAT, VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT)) {
    problems.push_back("no D32_SFLOAT depth attachment");
  }
  for (VkFormat f : {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_R32_SFLOAT, VK_FORMAT_R32_UINT}) {
    if (!formatSupports(pd, f, VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT)) {
      problems.push_back(fmt::format("format {} not renderable", static_cast<int>(f)));
    }
  }
  info.usable = problems.empty();
  for (size_t i = 0; i < problems.size(); ++i) info.why_unusable += (i ? ", " : "") + problems[i];
  return info;
}

// RAII for the instance while devices are being enumerated.
struct InstanceGuard {
  VkInstance instance = VK_NULL_HANDLE;
  ~InstanceGuard() {
    if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
  }
};

Result<VkInstance> createInstance(bool validation, GpuContext::Impl* impl, VkDebugUtilsMessengerCreateInfoEXT* dbg) {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "vkloc";
  app.pEngineName = "vkloc";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pApplicationInfo = &app;
  const char* layers[] = {kValidationLayer};
  const char* extensions[] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
  if (validation) {
    ci.enabledLayerCount = 1;
    ci.ppEnabledLayerNames = layers;
    ci.enabledExtensionCount = 1;
    ci.ppEnabledExtensionNames = extensions;
    dbg->sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
    dbg->messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    dbg->messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                       VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    dbg->pfnUserCallback = debugCallback;
    dbg->pUserData = impl;
    ci.pNext = dbg;  // also reports problems in vkCreateInstance / vkDestroyInstance
  }
  VkInstance instance = VK_NULL_HANDLE;
  VkResult r = vkCreateInstance(&ci, nullptr, &instance);
  if (r == VK_ERROR_INCOMPATIBLE_DRIVER) return makeError(ErrorCode::kNoDevice, kNoDriverMessage);
  if (r == VK_ERROR_LAYER_NOT_PRESENT) {
    return makeError(ErrorCode::kNoDevice,
                     "Vulkan validation layer requested but not installed: apt-get install vulkan-validationlayers");
  }
  if (r != VK_SUCCESS) return engine::vkError("vkCreateInstance", r);
  return instance;
}

#if defined(__SANITIZE_ADDRESS__)
#define VKLOC_KEEP_DRIVERS_LOADED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define VKLOC_KEEP_DRIVERS_LOADED 1
#endif
#endif

#ifdef VKLOC_KEEP_DRIVERS_LOADED
// AddressSanitizer builds only: the loader unloads the ICDs at vkDestroyInstance, and memory a
// driver still references from its own globals (lavapipe keeps 128 bytes) then looks leaked to
// LeakSanitizer, with no module left to name in a suppression. Loaded drivers stay resident.
void keepDriversLoaded() {
  std::vector<std::string> drivers;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* out) {
        const std::string name = info->dlpi_name ? info->dlpi_name : "";
        if (name.find("libvulkan_") != std::string::npos) static_cast<std::vector<std::string>*>(out)->push_back(name);
        return 0;
      },
      &drivers);
  for (const std::string& name : drivers) dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
}
#else
void keepDriversLoaded() {}
#endif

Result<std::vector<VkPhysicalDevice>> physicalDevices(VkInstance instance) {
  uint32_t count = 0;
  VkResult r = vkEnumeratePhysicalDevices(instance, &count, nullptr);
  if (r != VK_SUCCESS && r != VK_INCOMPLETE) return engine::vkError("vkEnumeratePhysicalDevices", r);
  if (count == 0) return makeError(ErrorCode::kNoDevice, kNoDriverMessage);
  std::vector<VkPhysicalDevice> devices(count);
  vkEnumeratePhysicalDevices(instance, &count, devices.data());
  devices.resize(count);
  keepDriversLoaded();
  return devices;
}

}  // namespace

namespace engine {

const char* vkResultName(VkResult r) {
  switch (r) {
    // clang-format off
#define VKLOC_CASE(x) case x: return #x;
    VKLOC_CASE(VK_SUCCESS) VKLOC_CASE(VK_NOT_READY) VKLOC_CASE(VK_TIMEOUT) VKLOC_CASE(VK_INCOMPLETE)
    VKLOC_CASE(VK_ERROR_OUT_OF_HOST_MEMORY) VKLOC_CASE(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    VKLOC_CASE(VK_ERROR_INITIALIZATION_FAILED) VKLOC_CASE(VK_ERROR_DEVICE_LOST)
    VKLOC_CASE(VK_ERROR_MEMORY_MAP_FAILED) VKLOC_CASE(VK_ERROR_LAYER_NOT_PRESENT)
    VKLOC_CASE(VK_ERROR_EXTENSION_NOT_PRESENT) VKLOC_CASE(VK_ERROR_FEATURE_NOT_PRESENT)
    VKLOC_CASE(VK_ERROR_INCOMPATIBLE_DRIVER) VKLOC_CASE(VK_ERROR_TOO_MANY_OBJECTS)
    VKLOC_CASE(VK_ERROR_FORMAT_NOT_SUPPORTED) VKLOC_CASE(VK_ERROR_FRAGMENTED_POOL)
    VKLOC_CASE(VK_ERROR_OUT_OF_POOL_MEMORY)
#undef VKLOC_CASE
        // clang-format on
        default : return "VK_ERROR_UNKNOWN";
  }
}

Error vkError(const char* call, VkResult result) {
  return makeError(ErrorCode::kGpuError, fmt::format("Vulkan call failed: {} returned {}", call, vkResultName(result)));
}

}  // namespace engine

Result<std::vector<GpuDeviceInfo>> GpuContext::listDevices() {
  InstanceGuard guard;
  Result<VkInstance> instance = createInstance(false, nullptr, nullptr);
  if (!instance.ok()) return instance.error();
  guard.instance = *instance;
  auto devices = physicalDevices(*instance);
  if (!devices.ok()) return devices.error();
  std::vector<GpuDeviceInfo> out;
  for (size_t i = 0; i < devices->size(); ++i) out.push_back(describe((*devices)[i], static_cast<int>(i)));
  return out;
}

GpuContext::GpuContext(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GpuContext::~GpuContext() = default;
const GpuDeviceInfo& GpuContext::device() const { return impl_->info; }
bool GpuContext::validationEnabled() const { return impl_->validation; }
uint64_t GpuContext::validationMessages() const { return impl_->validation_messages.load(); }

GpuContext::Impl::~Impl() {
  if (device != VK_NULL_HANDLE) vkDeviceWaitIdle(device);
  command_pool.reset();
  if (device != VK_NULL_HANDLE) vkDestroyDevice(device, nullptr);
  if (messenger != VK_NULL_HANDLE) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance, messenger, nullptr);
  }
  if (instance != VK_NULL_HANDLE) vkDestroyInstance(instance, nullptr);
}

Result<std::shared_ptr<GpuContext>> GpuContext::create(const GpuOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->on_validation_message = options.on_validation_message;

  bool validation = false;
#ifdef VKLOC_DEBUG_BUILD
  validation = true;
#endif
  bool validation_required = false;
  if (options.validation >= 0) {
    validation = options.validation != 0;
    validation_required = validation;
  }
  if (validation && !layerAvailable(kValidationLayer)) {
    if (validation_required) {
      return makeError(
          ErrorCode::kNoDevice,
          "Vulkan validation requested but the layer is not installed: apt-get install vulkan-validationlayers");
    }
    if (options.on_warning) options.on_warning("Vulkan validation layer not installed; running without it");
    validation = false;
  }
  impl->validation = validation;

  VkDebugUtilsMessengerCreateInfoEXT dbg{};
  Result<VkInstance> instance = createInstance(validation, impl.get(), &dbg);
  if (!instance.ok()) return instance.error();
  impl->instance = *instance;
  if (validation) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(impl->instance, "vkCreateDebugUtilsMessengerEXT"));
    if (create) VKLOC_VK(create(impl->instance, &dbg, nullptr, &impl->messenger));
  }

  auto devices = physicalDevices(impl->instance);
  if (!devices.ok()) return devices.error();
  std::vector<GpuDeviceInfo> infos;
  for (size_t i = 0; i < devices->size(); ++i) infos.push_back(describe((*devices)[i], static_cast<int>(i)));

  // Selection: explicit option, else the best usable type.
  const std::string& want = options.device;
  int chosen = -1;
  if (!want.empty()) {
    const bool numeric = std::all_of(want.begin(), want.end(), [](unsigned char c) { return std::isdigit(c); });
    for (const auto& info : infos) {
      const bool match =
          numeric ? std::to_string(info.index) == want : lower(info.name).find(lower(want)) != std::string::npos;
      if (match) {
        chosen = info.index;
        break;
      }
    }
    if (chosen < 0) {
      return makeError(ErrorCode::kNotFound, fmt::format("no Vulkan device matches '{}' (see 'vkloc devices')", want));
    }
    if (!infos[chosen].usable) {
      return makeError(ErrorCode::kNoDevice, fmt::format("Vulkan device '{}' is not usable: {}", infos[chosen].name,
                                                         infos[chosen].why_unusable));
    }
  } else {
    int best_score = -1;
    for (size_t i = 0; i < infos.size(); ++i) {
      VkPhysicalDeviceProperties p{};
      vkGetPhysicalDeviceProperties((*devices)[i], &p);
      const int score = infos[i].usable ? deviceTypeScore(p.deviceType) : -1;
      if (score > best_score) {
        best_score = score;
        chosen = static_cast<int>(i);
      }
    }
    if (chosen < 0 || !infos[chosen].usable) {
      return makeError(ErrorCode::kNoDevice,
                       fmt::format("no usable Vulkan device ({}: {})", infos[0].name, infos[0].why_unusable));
    }
  }
  impl->physical = (*devices)[chosen];
  impl->info = infos[chosen];
  vkGetPhysicalDeviceProperties(impl->physical, &impl->properties);
  vkGetPhysicalDeviceMemoryProperties(impl->physical, &impl->memory_properties);

  if (options.tune_allocator && impl->properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU) {
    // lavapipe allocates and frees multi-megabyte buffers per draw; with glibc's default
    // trimming every draw faults its pages back in (5x slower draws, LAVAPIPE.md pitfall 1).
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
  }

  // Unified memory: every device-local type is also host-visible.
  impl->unified_memory = !options.force_staging;
  for (uint32_t i = 0; i < impl->memory_properties.memoryTypeCount; ++i) {
    const VkMemoryPropertyFlags f = impl->memory_properties.memoryTypes[i].propertyFlags;
    if ((f & VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT) && !(f & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)) {
      impl->unified_memory = false;
    }
  }

  uint32_t qcount = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(impl->physical, &qcount, nullptr);
  std::vector<VkQueueFamilyProperties> families(qcount);
  vkGetPhysicalDeviceQueueFamilyProperties(impl->physical, &qcount, families.data());
  for (uint32_t i = 0; i < qcount; ++i) {
    if ((families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
      impl->queue_family = i;
      break;
    }
  }
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = impl->queue_family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkPhysicalDeviceFeatures supported{};
  vkGetPhysicalDeviceFeatures(impl->physical, &supported);
  VkPhysicalDeviceFeatures features{};
  features.shaderSampledImageArrayDynamicIndexing = supported.shaderSampledImageArrayDynamicIndexing;
  features.shaderStorageImageExtendedFormats = supported.shaderStorageImageExtendedFormats;
  impl->dynamic_sampler_indexing = supported.shaderSampledImageArrayDynamicIndexing == VK_TRUE;
  // Descriptor indexing is optional: only its update-after-bind limits for sampled images are
  // used, by models with more textures than the plain per-stage limits allow (textures.hpp).
  VkPhysicalDeviceVulkan12Features supported12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceFeatures2 supported2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  supported2.pNext = &supported12;
  vkGetPhysicalDeviceFeatures2(impl->physical, &supported2);
  VkPhysicalDeviceProperties2 properties2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  properties2.pNext = &impl->vulkan12_properties;
  vkGetPhysicalDeviceProperties2(impl->physical, &properties2);
  impl->vulkan12_properties.pNext = nullptr;
  VkPhysicalDeviceVulkan12Features features12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  features12.descriptorBindingSampledImageUpdateAfterBind = supported12.descriptorBindingSampledImageUpdateAfterBind;
  impl->sampled_image_update_after_bind = supported12.descriptorBindingSampledImageUpdateAfterBind == VK_TRUE;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &features12;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.pEnabledFeatures = &features;
  VKLOC_VK(vkCreateDevice(impl->physical, &dci, nullptr, &impl->device));
  vkGetDeviceQueue(impl->device, impl->queue_family, 0, &impl->queue);

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = impl->queue_family;
  VkCommandPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateCommandPool(impl->device, &pci, nullptr, &pool));
  impl->command_pool = engine::DeviceHandle<VkCommandPool>(impl->device, pool, vkDestroyCommandPool);

  return std::shared_ptr<GpuContext>(new GpuContext(std::move(impl)));
}

int GpuContext::Impl::findMemoryType(uint32_t type_bits, VkMemoryPropertyFlags required) const {
  for (uint32_t i = 0; i < memory_properties.memoryTypeCount; ++i) {
    if ((type_bits & (1u << i)) && (memory_properties.memoryTypes[i].propertyFlags & required) == required) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

Result<engine::DeviceHandle<VkDeviceMemory>> GpuContext::Impl::allocate(const VkMemoryRequirements& req, bool mapped,
                                                                        bool prefer_cached, const char* what) {
  const VkMemoryPropertyFlags want = mapped
                                         ? (VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
                                         : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  int type = -1;
  if (prefer_cached) type = findMemoryType(req.memoryTypeBits, want | VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
  if (type < 0) type = findMemoryType(req.memoryTypeBits, want);
  if (type < 0)
    return makeError(ErrorCode::kGpuError, fmt::format("no suitable Vulkan memory type for {} memory", what));
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  mai.memoryTypeIndex = static_cast<uint32_t>(type);
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VKLOC_VK(vkAllocateMemory(device, &mai, nullptr, &memory));
  return engine::DeviceHandle<VkDeviceMemory>(device, memory, vkFreeMemory);
}

Result<engine::Buffer> GpuContext::Impl::createBuffer(VkDeviceSize size, VkBufferUsageFlags usage, bool host_visible) {
  engine::Buffer out;
  out.size = size;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = std::max<VkDeviceSize>(size, 4);
  bci.usage = usage;
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateBuffer(device, &bci, nullptr, &buffer));
  out.buffer = engine::DeviceHandle<VkBuffer>(device, buffer, vkDestroyBuffer);
  VkMemoryRequirements req{};
  vkGetBufferMemoryRequirements(device, buffer, &req);
  const bool mapped = host_visible || unified_memory;
  auto memory_result = allocate(req, mapped, host_visible, "buffer");
  if (!memory_result.ok()) return memory_result.error();
  out.memory = std::move(*memory_result);
  const VkDeviceMemory memory = out.memory.get();
  VKLOC_VK(vkBindBufferMemory(device, buffer, memory, 0));
  if (mapped) VKLOC_VK(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &out.mapped));
  return out;
}

bool GpuContext::Impl::linearImageSupported(VkFormat format, VkImageUsageFlags usage, uint32_t width,
                                            uint32_t height) const {
  VkImageFormatProperties p{};
  const VkResult r = vkGetPhysicalDeviceImageFormatProperties(physical, format, VK_IMAGE_TYPE_2D,
                                                              VK_IMAGE_TILING_LINEAR, usage, 0, &p);
  return r == VK_SUCCESS && p.maxExtent.width >= width && p.maxExtent.height >= height;
}

Result<engine::Image> GpuContext::Impl::createImage(uint32_t width, uint32_t height, VkFormat format,
                                                    VkImageUsageFlags usage, VkImageAspectFlags aspect,
                                                    bool linear_host, uint32_t mip_levels) {
  engine::Image out;
  out.format = format;
  out.width = width;
  out.height = height;
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = format;
  ici.extent = {width, height, 1};
  ici.mipLevels = linear_host ? 1 : std::max(1u, mip_levels);
  ici.arrayLayers = 1;
  ici.samples = VK_SAMPLE_COUNT_1_BIT;
  ici.tiling = linear_host ? VK_IMAGE_TILING_LINEAR : VK_IMAGE_TILING_OPTIMAL;
  ici.usage = usage;
  ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage image = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateImage(device, &ici, nullptr, &image));
  out.image = engine::DeviceHandle<VkImage>(device, image, vkDestroyImage);
  VkMemoryRequirements req{};
  vkGetImageMemoryRequirements(device, image, &req);
  auto memory_result = allocate(req, linear_host, linear_host, "image");
  if (!memory_result.ok()) return memory_result.error();
  out.memory = std::move(*memory_result);
  const VkDeviceMemory memory = out.memory.get();
  VKLOC_VK(vkBindImageMemory(device, image, memory, 0));
  if (linear_host) {
    VkImageSubresource sub{aspect, 0, 0};
    VkSubresourceLayout layout{};
    vkGetImageSubresourceLayout(device, image, &sub, &layout);
    void* base = nullptr;
    VKLOC_VK(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &base));
    out.mapped = static_cast<uint8_t*>(base) + layout.offset;
    out.row_pitch = layout.rowPitch;
  }
  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = image;
  vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vci.format = format;
  vci.subresourceRange = {aspect, 0, ici.mipLevels, 0, 1};
  VkImageView view = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateImageView(device, &vci, nullptr, &view));
  out.view = engine::DeviceHandle<VkImageView>(device, view, vkDestroyImageView);
  return out;
}

Result<VkCommandBuffer> GpuContext::Impl::allocateCommandBuffer(VkCommandPool pool) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VKLOC_VK(vkAllocateCommandBuffers(device, &ai, &cmd));
  return cmd;
}

Result<engine::DeviceHandle<VkCommandPool>> GpuContext::Impl::createCommandPool() {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = queue_family;
  VkCommandPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateCommandPool(device, &pci, nullptr, &pool));
  return engine::DeviceHandle<VkCommandPool>(device, pool, vkDestroyCommandPool);
}

Result<engine::DeviceHandle<VkFence>> GpuContext::Impl::createFence() {
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fence = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateFence(device, &fci, nullptr, &fence));
  return engine::DeviceHandle<VkFence>(device, fence, vkDestroyFence);
}

uint64_t GpuContext::Impl::timestampMask() const {
  if (!properties.limits.timestampComputeAndGraphics) return 0;
  uint32_t count = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, nullptr);
  std::vector<VkQueueFamilyProperties> families(count);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &count, families.data());
  const uint32_t valid_bits = families[queue_family].timestampValidBits;
  return valid_bits >= 64 ? ~0ull : ((1ull << valid_bits) - 1);
}

Result<engine::DeviceHandle<VkQueryPool>> GpuContext::Impl::createTimestampPool(uint32_t count) {
  if (timestampMask() == 0) return engine::DeviceHandle<VkQueryPool>();
  VkQueryPoolCreateInfo qpci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  qpci.queryType = VK_QUERY_TYPE_TIMESTAMP;
  qpci.queryCount = count;
  VkQueryPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateQueryPool(device, &qpci, nullptr, &pool));
  return engine::DeviceHandle<VkQueryPool>(device, pool, vkDestroyQueryPool);
}

Status GpuContext::Impl::submit(const VkSubmitInfo& si, VkFence fence) {
  std::lock_guard<std::mutex> lock(queue_mutex);
  VKLOC_VK(vkQueueSubmit(queue, 1, &si, fence));
  return Status::success();
}

Status GpuContext::Impl::waitQueueIdle() {
  std::lock_guard<std::mutex> lock(queue_mutex);
  VKLOC_VK(vkQueueWaitIdle(queue));
  return Status::success();
}

Status GpuContext::Impl::submitAndWait(VkCommandBuffer cmd, VkFence fence) {
  VKLOC_VK(vkResetFences(device, 1, &fence));
  VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
  si.commandBufferCount = 1;
  si.pCommandBuffers = &cmd;
  VKLOC_TRY_STATUS(submit(si, fence));
  VKLOC_VK(vkWaitForFences(device, 1, &fence, VK_TRUE, UINT64_MAX));
  return Status::success();
}

Status GpuContext::Impl::upload(engine::Buffer& dst, const void* data, VkDeviceSize size) {
  if (size == 0) return Status::success();
  if (dst.mapped != nullptr) {
    std::memcpy(dst.mapped, data, size);
    return Status::success();
  }
  auto staging = createBuffer(size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  if (!staging.ok()) return staging.error();
  std::memcpy(staging->mapped, data, size);
  return runOnce([&](VkCommandBuffer cmd) {
    VkBufferCopy region{0, 0, size};
    vkCmdCopyBuffer(cmd, staging->buffer.get(), dst.buffer.get(), 1, &region);
    // Make the copy visible to every later reader of the buffer (a fence wait alone is not a
    // memory dependency between submissions).
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_INDEX_READ_BIT | VK_ACCESS_SHADER_READ_BIT |
                       VK_ACCESS_UNIFORM_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT,
                         VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_VERTEX_SHADER_BIT |
                             VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                         0, 1, &mb, 0, nullptr, 0, nullptr);
  });
}

Status GpuContext::Impl::uploadImage(engine::Image& dst, const void* rgba, VkDeviceSize size) {
  auto staging = createBuffer(size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, true);
  if (!staging.ok()) return staging.error();
  std::memcpy(staging->mapped, rgba, size);
  return runOnce([&](VkCommandBuffer cmd) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = 0;
    b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = dst.image.get();
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                         nullptr, 1, &b);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {dst.width, dst.height, 1};
    vkCmdCopyBufferToImage(cmd, staging->buffer.get(), dst.image.get(), VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                           &region);
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    b.newLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0, 0, nullptr, 0,
                         nullptr, 1, &b);
  });
}

}  // namespace vkloc
