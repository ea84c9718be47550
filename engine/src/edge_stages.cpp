// GpuEdgeStages: live-image edge stages and edge-alignment reductions as Vulkan compute passes.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <map>

#include "context.hpp"
#include "edge_layout.h"
#include "shader_registry.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/engine/gpu_edges.hpp"

namespace vkloc {

using engine::Buffer;
using engine::DeviceHandle;
using engine::EdgeControl;
using engine::EdgePush;

static_assert(sizeof(EdgePush) == 128, "EdgePush must match the GLSL std430 push block");
static_assert(offsetof(EdgePush, rank) == 32);
static_assert(offsetof(EdgePush, pose_row0) == 48);
static_assert(offsetof(EdgePush, intrinsics) == 96);
static_assert(offsetof(EdgePush, robust) == 112);
static_assert(offsetof(EdgeControl, candidate_count) == 20);
static_assert(offsetof(EdgeControl, line_span_count) == 28);
static_assert(offsetof(EdgeControl, changes) == 64);
static_assert(sizeof(EdgeControl) == 64 + 4 * EDGE_MAX_HYSTERESIS_PASSES);
static_assert(sizeof(EdgePoint) == 16);
static_assert(static_cast<float>(EDGE_LINE_RADIUS_PX) == kEdgeLineRadiusPx);

namespace {

constexpr uint32_t kGridGroups = 16;  // workgroups of grid-stride dispatches
// Workgroups of the image-wide grid-stride passes (histogram, hysteresis) on a GPU: 16 leave
// most of a discrete GPU idle (H100: hysteresis 2.6 ms, threshold 0.8 ms per frame); on a CPU
// driver (lavapipe runs workgroups as coroutines) few large groups stay best.
constexpr uint32_t kWideGridGroups = 512;
// Hysteresis passes per submission. On CPU drivers the first submission of a level records as
// many passes as the level needed in the last frame (at least kHysteresisFirstMin): a pass
// after the fixed point returns at once but still costs a dispatch (~50 us on lavapipe).
constexpr int kHysteresisBatch = 6;
constexpr int kHysteresisFirstMin = 2;
constexpr uint32_t kMaxTimestamps = 512;  // per submission

enum Kernel : int {
  kConvert,
  kPyramid,
  kSobel,
  kHist,
  kNms,
  kHysteresis,
  kJfaInit,
  kJfaStep,
  kJfaStepFromB,
  kDistance,
  kEdtColumns,
  kEdtRows,
  kEdgeLines,
  kResiduals,
  kNormalEquations,
  kScale,
  kKernelCount
};

struct KernelSpec {
  const char* shader;
  int mode;  // specialization constant 0 (reduce_edges.comp, jfa_step.comp), -1 = none
  // Specialization constant 2 of the per-pixel kernels: rows per invocation on a GPU and on a
  // CPU driver (0: the kernel has no such constant). lavapipe runs every 8 invocations as one
  // coroutine whose set-up cost is about that of a light kernel's work (measured: dispatching
  // the edge-lines kernel with nothing to do, 8 x 8 groups of one row each over the three
  // levels, cost 1.6 ms of a frame; with a sixteenth of the invocations, 0.4 ms).
  int rows_gpu = 0;
  int rows_cpu = 0;
};
// KernelSpec::mode of edt_rows.comp: constant 0 is the separable transform's radius R.
constexpr int kModeEdtRadius = -2;
constexpr KernelSpec kKernels[kKernelCount] = {{"edge_convert.comp", -1, 1, 16},
                                               {"pyramid_down.comp", -1, 1, 16},
                                               {"edge_sobel.comp", -1, 1, 16},
                                               {"edge_hist.comp", -1},
                                               {"edge_nms.comp", -1, 1, 16},
                                               {"edge_hysteresis.comp", -1},
                                               {"jfa_init.comp", -1},
                                               {"jfa_step.comp", 0},
                                               {"jfa_step.comp", 1},
                                               {"edge_distance.comp", -1},
                                               {"edt_columns.comp", -1},
                                               {"edt_rows.comp", kModeEdtRadius, 1, 16},
                                               {"edge_lines.comp", -1, 1, 16},
                                               {"reduce_edges.comp", 0},
                                               {"reduce_edges.comp", 1},
                                               {"edge_scale.comp", -1}};

constexpr bool everyKernelHasAShader() {
  for (const KernelSpec& k : kKernels) {
    if (k.shader == nullptr) return false;
  }
  return true;
}
static_assert(everyKernelHasAShader(), "kKernels lists fewer shaders than Kernel has values");

uint32_t groups(int n, int local) { return static_cast<uint32_t>((n + local - 1) / local); }

void computeBarrier(VkCommandBuffer cmd) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

// Shader writes -> transfer reads (image read-backs).
void transferReadBarrier(VkCommandBuffer cmd) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 1, &mb, 0, nullptr,
                       0, nullptr);
}

void hostBarrier(VkCommandBuffer cmd) {
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT,
                       VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0, nullptr);
}

uint32_t nextPowerOfTwo(double v) {
  uint32_t p = 1;
  while (p < v && p < (1u << 15)) p <<= 1;
  return p;
}

}  // namespace

struct GpuEdgeStages::Impl {
  std::shared_ptr<GpuContext> context;
  GpuContext::Impl* ctx = nullptr;
  VkDevice device = VK_NULL_HANDLE;
  PinholeCamera camera;
  LiveFrameOptions options;

  struct Level {
    PinholeCamera camera;
    engine::Image gray, mag, grad, state, seed_a, seed_b, distance, lines, epoints;
    Buffer hist, control, candidates;
    VkDescriptorSet set = VK_NULL_HANDLE;
    bool seeds_in_b = false;  // where the final jump-flooding seeds are
    int hysteresis_passes = 0;
    int hysteresis_first = kHysteresisBatch;  // passes of the first submission (last frame's need)
    int hysteresis_recorded = 0;              // passes of the last submission
  };
  std::vector<Level> levels;
  Buffer input8;
  Buffer points, residuals, partials;
  Buffer distance_readback;     // nearEdgeFraction's read-back of a level's distance image
  uint32_t point_count = 0;     // points of the single list (setReference)
  uint32_t point_capacity = 0;  // capacity of `points`, in points
  // Per-level lists (setLevelPoints): first point and count per level; empty = single list.
  std::vector<uint32_t> level_offsets, level_counts;
  bool have_frame = false;
  uint32_t wide_groups = kGridGroups;  // workgroups of histogram and hysteresis passes
  GpuDistanceMethod distance_method = GpuDistanceMethod::kJumpFlooding;  // resolved (never kAuto)
  // Pixels per invocation of the Sobel, NMS and edge-lines kernels: 8 on CPU
  // drivers (one window read serves 8 pixels: lavapipe gathers lane by lane), 1 on GPUs.
  int32_t span = 1;
  GpuKernelShapes kernel_shapes = GpuKernelShapes::kAuto;  // as asked for at creation
  bool cpu_shapes = false;  // kernel shapes of CPU drivers (device type or kernel_shapes)
  /// Rows per invocation of kernel k (KernelSpec::rows_gpu / rows_cpu), >= 1.
  int32_t rowsPerInvocation(Kernel k) const {
    return std::max(cpu_shapes ? kKernels[k].rows_cpu : kKernels[k].rows_gpu, 1);
  }

  DeviceHandle<VkDescriptorSetLayout> set_layout;
  DeviceHandle<VkDescriptorPool> descriptor_pool;
  DeviceHandle<VkPipelineLayout> pipeline_layout;
  std::array<DeviceHandle<VkShaderModule>, kKernelCount> modules;
  std::array<DeviceHandle<VkPipeline>, kKernelCount> pipelines;
  DeviceHandle<VkFence> fence;
  DeviceHandle<VkQueryPool> query_pool;
  DeviceHandle<VkCommandPool> command_pool;  // this object's own: it records on its user's thread
  VkCommandBuffer cmd = VK_NULL_HANDLE;      // from command_pool
  double timestamp_ns = 0;                   // ns per tick; 0 = no timestamps
  bool stage_timings = false;                // write timestamps between stages (setStageTimings)
  uint64_t timestamp_mask = ~0ull;

  // Timing of the current submission: query index -> stage whose end it marks.
  std::vector<std::string> marks;
  std::vector<GpuStageTiming> timings;

  ~Impl() {}

  Status init();
  Result<engine::Image> storageImage(int w, int h, VkFormat format);
  Status updatePointBindings();

  Status begin();
  Status submit();
  void mark(const char* stage);
  void dispatch(Kernel k, int level, const EdgePush& push, uint32_t gx, uint32_t gy = 1);
  /// A row-span kernel over the level (push.width x push.height): 8 x 8 workgroups of
  /// invocations of `span` pixels across and rowsPerInvocation(k) rows.
  void dispatchSpans(Kernel k, int level, const EdgePush& push) {
    dispatch(k, level, push, groups(static_cast<int>(groups(push.width, span)), 8),
             groups(push.height, 8 * rowsPerInvocation(k)));
  }
  EdgePush levelPush(int level) const;
  void recordFront(int level);
  void recordHysteresis(int level, int passes);
  void recordDistance(int level);
  void recordEdgeLines(int level, EdgePush push, bool listed);
  Status checkTracking(const Pose& T_camera_ref, int level) const;
  /// Normal equations: the per-workgroup partial sums of the last normal-equation pass, added.
  EdgeNormalEquations summedPartials() const {
    EdgeNormalEquations eq{};
    const auto* partial = static_cast<const float*>(partials.mapped);
    for (uint32_t g = 0; g < kGridGroups; ++g) {
      for (int i = 0; i < kEdgeNormalEquationSize; ++i) eq[i] += partial[g * EDGE_REDUCE_VEC4S * 4 + i];
    }
    return eq;
  }
  EdgePush trackingPush(const Pose& T_camera_ref, int level) const;
};

Result<engine::Image> GpuEdgeStages::Impl::storageImage(int w, int h, VkFormat format) {
  return ctx->createImage(
      static_cast<uint32_t>(w), static_cast<uint32_t>(h), format,
      VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
      VK_IMAGE_ASPECT_COLOR_BIT);
}

Status GpuEdgeStages::Impl::init() {
  device = ctx->device;
  // The device type's kernel shapes unless the caller chose (the GPU variants are tested on
  // lavapipe too).
  cpu_shapes = kernel_shapes == GpuKernelShapes::kAuto ? ctx->properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU
                                                       : kernel_shapes == GpuKernelShapes::kCpu;
  wide_groups = cpu_shapes ? kGridGroups : kWideGridGroups;
  span = cpu_shapes ? 8 : 1;
  for (VkFormat f :
       {VK_FORMAT_R32_SFLOAT, VK_FORMAT_R32G32_SFLOAT, VK_FORMAT_R32_UINT, VK_FORMAT_R32G32B32A32_SFLOAT}) {
    VkFormatProperties p{};
    vkGetPhysicalDeviceFormatProperties(ctx->physical, f, &p);
    if (!(p.optimalTilingFeatures & VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT)) {
      return makeError(ErrorCode::kGpuError,
                       fmt::format("edge stages: device cannot use format {} as a storage image", static_cast<int>(f)));
    }
  }
  VkFormatProperties ui{};
  vkGetPhysicalDeviceFormatProperties(ctx->physical, VK_FORMAT_R32_UINT, &ui);
  if (!(ui.optimalTilingFeatures & VK_FORMAT_FEATURE_STORAGE_IMAGE_ATOMIC_BIT)) {
    return makeError(ErrorCode::kGpuError, "edge stages: device has no r32ui storage-image atomics");
  }
  VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 props2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props2.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(ctx->physical, &props2);
  const VkSubgroupFeatureFlags need =
      VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT | VK_SUBGROUP_FEATURE_BALLOT_BIT;
  if ((subgroup.supportedOperations & need) != need || !(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT)) {
    return makeError(ErrorCode::kGpuError, "edge stages: device lacks subgroup basic/arithmetic/ballot in compute");
  }

  // Levels as buildLiveFrame: level k > 0 only while level k - 1 is at least 16x16.
  int w = camera.width, h = camera.height;
  for (int k = 0; k < options.levels; ++k) {
    if (k > 0) {
      if (w < 16 || h < 16) break;
      w = (w + 1) / 2;
      h = (h + 1) / 2;
    }
    Level level;
    level.camera = pyramidCamera(camera, k);
    for (auto [image, format] : {std::pair{&level.gray, VK_FORMAT_R32_SFLOAT},
                                 {&level.mag, VK_FORMAT_R32_SFLOAT},
                                 {&level.grad, VK_FORMAT_R32G32_SFLOAT},
                                 {&level.state, VK_FORMAT_R32_UINT},
                                 {&level.seed_a, VK_FORMAT_R32_UINT},
                                 {&level.seed_b, VK_FORMAT_R32_UINT},
                                 {&level.distance, VK_FORMAT_R32_SFLOAT},
                                 {&level.lines, VK_FORMAT_R32G32B32A32_SFLOAT},
                                 {&level.epoints, VK_FORMAT_R32G32_SFLOAT}}) {
      auto img = storageImage(w, h, format);
      if (!img.ok()) return img.error();
      *image = std::move(*img);
    }
    const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    auto hist = ctx->createBuffer(EDGE_HIST_BINS * 4, ssbo, false);
    if (!hist.ok()) return hist.error();
    level.hist = std::move(*hist);
    auto control = ctx->createBuffer(sizeof(EdgeControl), ssbo, true);
    if (!control.ok()) return control.error();
    level.control = std::move(*control);
    auto candidates = ctx->createBuffer(static_cast<VkDeviceSize>(w) * h * 4, ssbo, false);
    if (!candidates.ok()) return candidates.error();
    level.candidates = std::move(*candidates);
    levels.push_back(std::move(level));
  }
  // The live image and the reference points are written by the host every frame: host-visible
  // buffers take a memcpy where a device-local one takes a staging buffer and a submission
  // (0.4-0.6 ms each on an H100); the shaders read them once per pass.
  auto input = ctx->createBuffer((static_cast<VkDeviceSize>(camera.width) * camera.height + 3) / 4 * 4,
                                 VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  if (!input.ok()) return input.error();
  input8 = std::move(*input);
  auto partial = ctx->createBuffer(kGridGroups * EDGE_REDUCE_VEC4S * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
  if (!partial.ok()) return partial.error();
  partials = std::move(*partial);

  // One descriptor layout for every kernel; one set per level.
  std::vector<VkDescriptorSetLayoutBinding> bindings(EDGE_BINDING_COUNT);
  for (uint32_t b = 0; b < EDGE_BINDING_COUNT; ++b) {
    bindings[b].binding = b;
    const bool image = (b >= EDGE_BINDING_GRAY_PREV && b <= EDGE_BINDING_DISTANCE) || b == EDGE_BINDING_LINES ||
                       b == EDGE_BINDING_EPOINTS;
    bindings[b].descriptorType = image ? VK_DESCRIPTOR_TYPE_STORAGE_IMAGE : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[b].descriptorCount = 1;
    bindings[b].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = EDGE_BINDING_COUNT;
  lci.pBindings = bindings.data();
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorSetLayout(device, &lci, nullptr, &layout));
  set_layout = DeviceHandle<VkDescriptorSetLayout>(device, layout, vkDestroyDescriptorSetLayout);
  const uint32_t n_sets = static_cast<uint32_t>(levels.size());
  VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 10 * n_sets},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 7 * n_sets}};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = n_sets;
  dpci.poolSizeCount = 2;
  dpci.pPoolSizes = sizes;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorPool(device, &dpci, nullptr, &pool));
  descriptor_pool = DeviceHandle<VkDescriptorPool>(device, pool, vkDestroyDescriptorPool);
  for (size_t k = 0; k < levels.size(); ++k) {
    Level& L = levels[k];
    VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    ai.descriptorPool = pool;
    ai.descriptorSetCount = 1;
    ai.pSetLayouts = &layout;
    VKLOC_VK(vkAllocateDescriptorSets(device, &ai, &L.set));
    const engine::Image* images[10] = {k > 0 ? &levels[k - 1].gray : &L.gray,
                                       &L.gray,
                                       &L.mag,
                                       &L.grad,
                                       &L.state,
                                       &L.seed_a,
                                       &L.seed_b,
                                       &L.distance,
                                       &L.lines,
                                       &L.epoints};
    VkDescriptorImageInfo image_infos[10];
    VkWriteDescriptorSet writes[14];
    for (int i = 0; i < 10; ++i) {
      image_infos[i] = {VK_NULL_HANDLE, images[i]->view.get(), VK_IMAGE_LAYOUT_GENERAL};
      writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[i].dstSet = L.set;
      writes[i].dstBinding = i < 8 ? EDGE_BINDING_GRAY_PREV + i : (i == 8 ? EDGE_BINDING_LINES : EDGE_BINDING_EPOINTS);
      writes[i].descriptorCount = 1;
      writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
      writes[i].pImageInfo = &image_infos[i];
    }
    const Buffer* buffers[4] = {&input8, &L.hist, &L.control, &L.candidates};
    const uint32_t buffer_bindings[4] = {EDGE_BINDING_INPUT8, EDGE_BINDING_HIST, EDGE_BINDING_CONTROL,
                                         EDGE_BINDING_CANDIDATES};
    VkDescriptorBufferInfo buffer_infos[4];
    for (int i = 0; i < 4; ++i) {
      buffer_infos[i] = {buffers[i]->buffer.get(), 0, VK_WHOLE_SIZE};
      writes[10 + i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
      writes[10 + i].dstSet = L.set;
      writes[10 + i].dstBinding = buffer_bindings[i];
      writes[10 + i].descriptorCount = 1;
      writes[10 + i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
      writes[10 + i].pBufferInfo = &buffer_infos[i];
    }
    vkUpdateDescriptorSets(device, 14, writes, 0, nullptr);
  }
  VKLOC_TRY_STATUS(updatePointBindings());

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(EdgePush)};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &layout;
  plci.pushConstantRangeCount = 1;
  plci.pPushConstantRanges = &range;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  VKLOC_VK(vkCreatePipelineLayout(device, &plci, nullptr, &pl));
  pipeline_layout = DeviceHandle<VkPipelineLayout>(device, pl, vkDestroyPipelineLayout);
  for (int k = 0; k < kKernelCount; ++k) {
    const engine::ShaderBlob* blob = engine::findShader(kKernels[k].shader);
    if (blob == nullptr) {
      return makeError(ErrorCode::kGpuError, fmt::format("shader {} is not embedded", kKernels[k].shader));
    }
    VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    smci.codeSize = blob->word_count * 4;
    smci.pCode = blob->words;
    VkShaderModule module = VK_NULL_HANDLE;
    VKLOC_VK(vkCreateShaderModule(device, &smci, nullptr, &module));
    modules[k] = DeviceHandle<VkShaderModule>(device, module, vkDestroyShaderModule);
    // R = ceil(truncation) - 1 for the separable transform (unused by jump flooding).
    const int32_t edt_radius =
        std::clamp(static_cast<int32_t>(std::ceil(options.truncation_px)) - 1, 0, int32_t{EDGE_EDT_MAX_RADIUS});
    // Constant 0: the kernel's mode; 1: pixels per invocation of the row-span kernels; 2: their
    // rows per invocation; 3: kFusedSobel, 1 on CPU drivers (edge_sobel.comp writes only the
    // quantile's samples, NMS and edge lines recompute the gradient from the gray image).
    // Constants a shader does not declare are ignored.
    const int32_t constants[4] = {kKernels[k].mode == kModeEdtRadius ? edt_radius : std::max(kKernels[k].mode, 0), span,
                                  rowsPerInvocation(static_cast<Kernel>(k)), cpu_shapes ? 1 : 0};
    const VkSpecializationMapEntry entries[4] = {{0, 0, sizeof(int32_t)},
                                                 {1, sizeof(int32_t), sizeof(int32_t)},
                                                 {2, 2 * sizeof(int32_t), sizeof(int32_t)},
                                                 {3, 3 * sizeof(int32_t), sizeof(int32_t)}};
    VkSpecializationInfo spec{4, entries, sizeof(constants), constants};
    VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    cpci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    cpci.stage.module = module;
    cpci.stage.pName = "main";
    cpci.stage.pSpecializationInfo = &spec;
    cpci.layout = pl;
    VkPipeline pipe = VK_NULL_HANDLE;
    VKLOC_VK(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipe));
    pipelines[k] = DeviceHandle<VkPipeline>(device, pipe, vkDestroyPipeline);
  }

  auto created_fence = ctx->createFence();
  if (!created_fence.ok()) return created_fence.error();
  fence = std::move(*created_fence);
  auto created_pool = ctx->createCommandPool();
  if (!created_pool.ok()) return created_pool.error();
  command_pool = std::move(*created_pool);
  auto command = ctx->allocateCommandBuffer(command_pool.get());
  if (!command.ok()) return command.error();
  cmd = *command;

  // Timestamps where the queue supports them.
  auto created_queries = ctx->createTimestampPool(kMaxTimestamps);
  if (!created_queries.ok()) return created_queries.error();
  query_pool = std::move(*created_queries);
  if (query_pool) {
    timestamp_ns = ctx->properties.limits.timestampPeriod;
    timestamp_mask = ctx->timestampMask();
  }

  // Every image lives in GENERAL.
  return ctx->runOnce([&](VkCommandBuffer c) {
    std::vector<VkImageMemoryBarrier> barriers;
    for (Level& L : levels) {
      for (engine::Image* image :
           {&L.gray, &L.mag, &L.grad, &L.state, &L.seed_a, &L.seed_b, &L.distance, &L.lines, &L.epoints}) {
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
        b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        b.newLayout = VK_IMAGE_LAYOUT_GENERAL;
        b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        b.image = image->image.get();
        b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        barriers.push_back(b);
      }
    }
    vkCmdPipelineBarrier(c, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 0, nullptr, 0,
                         nullptr, static_cast<uint32_t>(barriers.size()), barriers.data());
  });
}

Status GpuEdgeStages::Impl::updatePointBindings() {
  uint32_t needed = point_count;
  for (size_t k = 0; k < level_offsets.size(); ++k) needed = std::max(needed, level_offsets[k] + level_counts[k]);
  const uint32_t capacity = std::max<uint32_t>(needed, 256);
  if (capacity > point_capacity || !points.buffer) {
    const uint32_t grown = std::max(capacity, point_capacity * 2);
    auto p = ctx->createBuffer(static_cast<VkDeviceSize>(grown) * sizeof(EdgePoint),
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
    if (!p.ok()) return p.error();
    auto r = ctx->createBuffer(static_cast<VkDeviceSize>(grown) * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    if (!r.ok()) return r.error();
    points = std::move(*p);
    residuals = std::move(*r);
    point_capacity = grown;
    for (Level& L : levels) {
      const Buffer* buffers[3] = {&points, &residuals, &partials};
      VkDescriptorBufferInfo infos[3];
      VkWriteDescriptorSet writes[3];
      for (int i = 0; i < 3; ++i) {
        infos[i] = {buffers[i]->buffer.get(), 0, VK_WHOLE_SIZE};
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = L.set;
        writes[i].dstBinding = EDGE_BINDING_POINTS + i;
        writes[i].descriptorCount = 1;
        writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
        writes[i].pBufferInfo = &infos[i];
      }
      vkUpdateDescriptorSets(device, 3, writes, 0, nullptr);
    }
  }
  // Each level's set sees its own list (offsets are multiples of 256 bytes, the largest
  // minStorageBufferOffsetAlignment Vulkan allows), or the single list at offset 0.
  for (size_t k = 0; k < levels.size(); ++k) {
    const VkDeviceSize offset =
        level_offsets.empty() ? 0 : static_cast<VkDeviceSize>(level_offsets[k]) * sizeof(EdgePoint);
    VkDescriptorBufferInfo info{points.buffer.get(), offset, VK_WHOLE_SIZE};
    VkWriteDescriptorSet write{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    write.dstSet = levels[k].set;
    write.dstBinding = EDGE_BINDING_POINTS;
    write.descriptorCount = 1;
    write.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    write.pBufferInfo = &info;
    vkUpdateDescriptorSets(device, 1, &write, 0, nullptr);
  }
  return Status::success();
}

Status GpuEdgeStages::Impl::begin() {
  VKLOC_VK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VKLOC_VK(vkBeginCommandBuffer(cmd, &bi));
  marks.clear();
  if (query_pool && stage_timings) {
    vkCmdResetQueryPool(cmd, query_pool.get(), 0, kMaxTimestamps);
    mark("");
  }
  return Status::success();
}

void GpuEdgeStages::Impl::mark(const char* stage) {
  if (!query_pool || !stage_timings || marks.size() >= kMaxTimestamps) return;
  vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, query_pool.get(), static_cast<uint32_t>(marks.size()));
  marks.emplace_back(stage);
}

static void addTiming(std::vector<GpuStageTiming>& timings, const std::string& stage, double ms) {
  for (GpuStageTiming& t : timings) {
    if (t.stage == stage) {
      t.ms += ms;
      return;
    }
  }
  timings.push_back({stage, ms});
}

Status GpuEdgeStages::Impl::submit() {
  hostBarrier(cmd);
  VKLOC_VK(vkEndCommandBuffer(cmd));
  const auto t0 = SteadyClock::now();
  VKLOC_TRY_STATUS(ctx->submitAndWait(cmd, fence.get()));
  const double host_ms = msSince(t0);
  if (query_pool && marks.size() > 1) {
    std::vector<uint64_t> ticks(marks.size());
    VKLOC_VK(vkGetQueryPoolResults(device, query_pool.get(), 0, static_cast<uint32_t>(marks.size()),
                                   ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    for (size_t i = 1; i < marks.size(); ++i) {
      const uint64_t dt = (ticks[i] - ticks[i - 1]) & timestamp_mask;
      addTiming(timings, marks[i], static_cast<double>(dt) * timestamp_ns * 1e-6);
    }
  } else {
    addTiming(timings, "submission (host)", host_ms);
  }
  return Status::success();
}

EdgePush GpuEdgeStages::Impl::levelPush(int level) const {
  EdgePush push{};
  push.width = levels[level].camera.width;
  push.height = levels[level].camera.height;
  push.high_factor = static_cast<float>(options.detector.high_factor);
  push.min_high_gradient = static_cast<float>(options.detector.min_high_gradient);
  push.low_ratio = static_cast<float>(options.detector.low_ratio);
  push.truncation_px = options.truncation_px;
  push.group_count = kGridGroups;
  return push;
}

void GpuEdgeStages::Impl::dispatch(Kernel k, int level, const EdgePush& push, uint32_t gx, uint32_t gy) {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelines[k].get());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout.get(), 0, 1, &levels[level].set, 0,
                          nullptr);
  vkCmdPushConstants(cmd, pipeline_layout.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(EdgePush), &push);
  vkCmdDispatch(cmd, gx, gy, 1);
  computeBarrier(cmd);
}

// Pyramid level, gradient, thresholds, NMS and the first hysteresis passes of one level.
void GpuEdgeStages::Impl::recordFront(int level) {
  Level& L = levels[level];
  EdgePush push = levelPush(level);
  if (level == 0) {
    // 4 pixels (one uint of the input) per invocation.
    dispatch(kConvert, level, push, groups(static_cast<int>(groups(push.width, 4)), 16),
             groups(push.height, 16 * rowsPerInvocation(kConvert)));
    mark("upload");
  } else {
    dispatchSpans(kPyramid, level, push);
    mark("pyramid");
  }
  dispatchSpans(kSobel, level, push);
  mark("sobel");
  vkCmdFillBuffer(cmd, L.hist.buffer.get(), 0, VK_WHOLE_SIZE, 0);
  // NMS writes only the pixels it keeps; the rest of STATE is this fill's 0 (on lavapipe ~1 %
  // fewer instructions per frame than a store per pixel).
  const VkClearColorValue zero{};
  const VkImageSubresourceRange whole{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  vkCmdClearColorImage(cmd, L.state.image.get(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &whole);
  vkCmdFillBuffer(cmd, L.control.buffer.get(), 0, VK_WHOLE_SIZE, 0);
  computeBarrier(cmd);
  const uint64_t n = static_cast<uint64_t>((push.width + 1) / 2) * ((push.height + 1) / 2);
  push.rank = static_cast<uint32_t>(std::min<uint64_t>(
      n - 1, static_cast<uint64_t>(options.detector.contrast_percentile * static_cast<double>(n - 1))));
  const bool noise_floor = options.detector.noise_sigmas > 0.0 && push.rank > 0;
  if (noise_floor) {
    // Rank of the noise quantile: as detectEdges, at most one below the contrast's.
    push.pad0 = static_cast<uint32_t>(std::min<uint64_t>(
        push.rank - 1, static_cast<uint64_t>(options.detector.noise_quantile * static_cast<double>(n - 1))));
    push.robust[0] =
        static_cast<float>(options.detector.noise_sigmas / rayleighQuantileFactor(options.detector.noise_quantile));
  }
  for (int pass = noise_floor ? 0 : 3; pass < 6; ++pass) {
    push.step = pass;
    EdgePush hist_push = push;
    hist_push.group_count = wide_groups;
    dispatch(kHist, level, hist_push, wide_groups);  // its last workgroup also selects
  }
  mark("threshold");
  dispatchSpans(kNms, level, push);
  mark("nms");
  L.hysteresis_passes = 0;
  recordHysteresis(level, L.hysteresis_first);
}

void GpuEdgeStages::Impl::recordHysteresis(int level, int passes) {
  Level& L = levels[level];
  L.hysteresis_recorded = passes;
  EdgePush push = levelPush(level);
  vkCmdFillBuffer(cmd, L.control.buffer.get(), offsetof(EdgeControl, changes), 4 * EDGE_MAX_HYSTERESIS_PASSES, 0);
  computeBarrier(cmd);
  push.group_count = wide_groups;
  for (int i = 0; i < passes; ++i) {
    push.step = i;
    dispatch(kHysteresis, level, push, wide_groups);
  }
  mark("hysteresis");
}

void GpuEdgeStages::Impl::recordDistance(int level) {
  Level& L = levels[level];
  EdgePush push = levelPush(level);
  const uint32_t gx = groups(push.width, 16), gy = groups(push.height, 16);
  if (distance_method == GpuDistanceMethod::kSeparable) {
    dispatch(kEdtColumns, level, push, groups(push.width, 64));
    mark("edt columns");
    // One invocation per 8-pixel row span and block of rows; groups laid out 2D past the 65535
    // limit of one axis.
    const uint32_t row_groups = groups(
        static_cast<int>(groups(push.width, 8)) * static_cast<int>(groups(push.height, rowsPerInvocation(kEdtRows))),
        64);
    const uint32_t row_gx = std::min<uint32_t>(row_groups, 65535);
    dispatch(kEdtRows, level, push, row_gx, (row_groups + row_gx - 1) / row_gx);
    mark("distance transform");
    recordEdgeLines(level, push, true);
    mark("edge lines");
    return;
  }
  dispatch(kJfaInit, level, push, gx, gy);
  // JFA+2 from the smallest step S whose passes reach the truncation distance (S, S/2, .., 1
  // move a seed up to 2S - 1 pixels along each axis: S = 16 for 20 px), then 2, 1.
  const uint32_t start = std::min(nextPowerOfTwo(std::ceil((options.truncation_px + 1.0) / 2.0)),
                                  std::max<uint32_t>(1, nextPowerOfTwo(std::max(push.width, push.height)) / 2));
  std::vector<int> steps;
  for (uint32_t s = start; s >= 1; s /= 2) steps.push_back(static_cast<int>(s));
  if (start >= 2) steps.push_back(2);
  steps.push_back(1);
  bool in_b = false;
  for (int s : steps) {
    push.step = s;
    push.flags = in_b ? 1u : 0u;
    dispatch(in_b ? kJfaStepFromB : kJfaStep, level, push, gx, gy);
    in_b = !in_b;
  }
  L.seeds_in_b = in_b;
  mark("jfa");
  push.flags = in_b ? 1u : 0u;
  dispatch(kDistance, level, push, gx, gy);
  mark("distance");
  recordEdgeLines(level, push, false);
  mark("edge lines");
}

// Edge lines of a level (edge_lines.comp): over every pixel, or (`listed`, after edt_rows.comp
// listed the near-edge spans) only the listed spans.
void GpuEdgeStages::Impl::recordEdgeLines(int level, EdgePush push, bool listed) {
  push.flags = options.subpixel_edges ? 1u : 0u;
  if (!listed) {
    dispatchSpans(kEdgeLines, level, push);
    return;
  }
  if (!options.subpixel_edges) {
    // Zeros everywhere. (With sub-pixel edges, pixels off the list keep stale values, which
    // readers mask with the distance: clearing the image cost ~0.9 ms of a frame on lavapipe.)
    const VkClearColorValue zero{};
    const VkImageSubresourceRange whole{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdClearColorImage(cmd, levels[level].lines.image.get(), VK_IMAGE_LAYOUT_GENERAL, &zero, 1, &whole);
    computeBarrier(cmd);
    return;
  }
  push.flags |= EDGE_LINES_LISTED;
  push.group_count = kGridGroups;
  dispatch(kEdgeLines, level, push, kGridGroups);
}

GpuEdgeStages::GpuEdgeStages(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GpuEdgeStages::~GpuEdgeStages() = default;

Result<std::unique_ptr<GpuEdgeStages>> GpuEdgeStages::create(std::shared_ptr<GpuContext> context,
                                                             const PinholeCamera& camera,
                                                             const LiveFrameOptions& options,
                                                             GpuDistanceMethod distance_method,
                                                             GpuKernelShapes kernel_shapes) {
  if (!context) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: no GPU context");
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(options.detector));
  if (options.levels < 1 || options.levels > 8) {
    return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: levels must be in 1..8");
  }
  if (!(options.truncation_px > 0) || !std::isfinite(options.truncation_px) || options.truncation_px > 16384) {
    return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: truncation_px must be in (0, 16384]");
  }
  if (camera.width > 65535 || camera.height > 65535) {
    return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: images wider or taller than 65535 px");
  }
  auto impl = std::make_unique<Impl>();
  impl->context = context;
  impl->ctx = &context->impl();
  impl->camera = camera;
  impl->options = options;
  impl->kernel_shapes = kernel_shapes;
  const bool separable_fits = std::ceil(options.truncation_px) - 1 <= EDGE_EDT_MAX_RADIUS;
  if (distance_method == GpuDistanceMethod::kSeparable && !separable_fits) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuEdgeStages: the separable distance transform needs truncation_px <= {}",
                                 EDGE_EDT_MAX_RADIUS + 1));
  }
  if (distance_method == GpuDistanceMethod::kAuto) {
    // One sequential loop per column and a shared-memory row pass on CPU drivers (lavapipe:
    // 640x480 in ~3 ms against ~15 ms of jump flooding); jump flooding's fully parallel passes
    // on GPUs.
    const bool cpu_driver = impl->ctx->properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
    distance_method = cpu_driver && separable_fits ? GpuDistanceMethod::kSeparable : GpuDistanceMethod::kJumpFlooding;
    // (Decided by the device, not VKLOC_KERNEL_SHAPES: tests pick the method explicitly.)
  }
  impl->distance_method = distance_method;
  VKLOC_TRY_STATUS(impl->init());
  return std::unique_ptr<GpuEdgeStages>(new GpuEdgeStages(std::move(impl)));
}

int GpuEdgeStages::levelCount() const { return static_cast<int>(impl_->levels.size()); }

GpuDistanceMethod GpuEdgeStages::distanceMethod() const { return impl_->distance_method; }

const char* gpuDistanceMethodName(GpuDistanceMethod method) {
  switch (method) {
    case GpuDistanceMethod::kAuto:
      return "auto";
    case GpuDistanceMethod::kJumpFlooding:
      return "jump flooding";
    case GpuDistanceMethod::kSeparable:
      return "separable";
  }
  return "?";
}

PinholeCamera GpuEdgeStages::levelCamera(int level) const {
  if (level < 0 || level >= levelCount()) return {};
  return impl_->levels[level].camera;
}

std::vector<int> GpuEdgeStages::lastHysteresisPasses() const {
  std::vector<int> out;
  for (const auto& L : impl_->levels) out.push_back(L.hysteresis_passes);
  return out;
}

const std::vector<GpuStageTiming>& GpuEdgeStages::lastTimings() const { return impl_->timings; }

void GpuEdgeStages::setStageTimings(bool enabled) { impl_->stage_timings = enabled; }

Status GpuEdgeStages::processLiveImage(const ImageU8& gray) {
  Impl& m = *impl_;
  if (gray.channels != 1 || gray.width != m.camera.width || gray.height != m.camera.height ||
      gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuEdgeStages::processLiveImage: image is {}x{}x{}, camera expects {}x{} "
                                 "single-channel",
                                 gray.width, gray.height, gray.channels, m.camera.width, m.camera.height));
  }
  m.timings.clear();
  m.have_frame = false;
  VKLOC_TRY_STATUS(m.ctx->upload(m.input8, gray.data.data(), gray.data.size()));
  VKLOC_TRY_STATUS(m.begin());
  for (int k = 0; k < static_cast<int>(m.levels.size()); ++k) m.recordFront(k);
  VKLOC_TRY_STATUS(m.submit());
  // Hysteresis until a pass promotes nothing (bounded by EDGE_MAX_HYSTERESIS_PASSES).
  std::vector<int> pending;
  for (int k = 0; k < static_cast<int>(m.levels.size()); ++k) pending.push_back(k);
  for (;;) {
    const std::vector<int> checked = std::move(pending);
    pending.clear();
    for (int k : checked) {
      // Passes that ran: up to and including the first that promoted nothing.
      const auto* control = static_cast<const EdgeControl*>(m.levels[k].control.mapped);
      int ran = 0;
      Impl::Level& L = m.levels[k];
      while (ran < L.hysteresis_recorded && control->changes[ran] != 0) ++ran;
      const bool changed = ran == L.hysteresis_recorded;
      L.hysteresis_passes += changed ? ran : ran + 1;
      if (changed && L.hysteresis_passes + kHysteresisBatch <= EDGE_MAX_HYSTERESIS_PASSES) {
        pending.push_back(k);
      }
    }
    if (pending.empty()) break;
    VKLOC_TRY_STATUS(m.begin());
    for (int k : pending) m.recordHysteresis(k, kHysteresisBatch);
    VKLOC_TRY_STATUS(m.submit());
  }
  // On a GPU an idle pass costs microseconds and a second submission 0.4-0.6 ms (H100 host):
  // the first submission keeps the full batch there.
  if (m.cpu_shapes) {
    for (Impl::Level& L : m.levels) {
      L.hysteresis_first = std::clamp(L.hysteresis_passes, kHysteresisFirstMin, kHysteresisBatch);
    }
  }
  VKLOC_TRY_STATUS(m.begin());
  for (int k = 0; k < static_cast<int>(m.levels.size()); ++k) m.recordDistance(k);
  VKLOC_TRY_STATUS(m.submit());
  m.have_frame = true;
  return Status::success();
}

Result<LiveFrame> GpuEdgeStages::readLiveFrame() {
  Impl& m = *impl_;
  if (!m.have_frame) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages::readLiveFrame: no live image yet");
  // Gray, state, distance (4 bytes per pixel) and edge lines (16) of every level, packed. The
  // distance gradient is not kept on the device (reduce_edges.comp computes it where a point
  // needs it): it is computed here from the distance, as computeDistanceField does.
  VkDeviceSize total = 0;
  for (const auto& L : m.levels) total += static_cast<VkDeviceSize>(L.camera.width) * L.camera.height * 28 + 64;
  auto staging = m.ctx->createBuffer(total, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
  if (!staging.ok()) return staging.error();
  std::vector<std::array<VkDeviceSize, 4>> offsets;
  VKLOC_TRY_STATUS(m.ctx->runOnce([&](VkCommandBuffer c) {
    transferReadBarrier(c);
    VkDeviceSize offset = 0;
    for (auto& L : m.levels) {
      std::array<VkDeviceSize, 4> o{};
      const engine::Image* images[4] = {&L.gray, &L.state, &L.distance, &L.lines};
      constexpr VkDeviceSize kPixelBytes[4] = {4, 4, 4, 16};
      for (int i = 0; i < 4; ++i) {
        o[i] = offset;
        VkBufferImageCopy region{};
        region.bufferOffset = offset;
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        region.imageExtent = {images[i]->width, images[i]->height, 1};
        vkCmdCopyImageToBuffer(c, images[i]->image.get(), VK_IMAGE_LAYOUT_GENERAL, staging->buffer.get(), 1, &region);
        offset += (static_cast<VkDeviceSize>(images[i]->width) * images[i]->height * kPixelBytes[i] + 15) / 16 * 16;
      }
      offsets.push_back(o);
    }
    hostBarrier(c);
  }));
  const auto* base = static_cast<const uint8_t*>(staging->mapped);
  LiveFrame frame;
  for (size_t k = 0; k < m.levels.size(); ++k) {
    const auto& L = m.levels[k];
    const int w = L.camera.width, h = L.camera.height;
    const size_t n = static_cast<size_t>(w) * h;
    LiveLevel out;
    out.camera = L.camera;
    out.field.truncation_px = m.options.truncation_px;
    out.field.distance = ImageF32(w, h, 1);
    std::memcpy(out.field.distance.data.data(), base + offsets[k][2], n * 4);
    computeDistanceGradient(out.field);
    if (m.options.subpixel_edges) {
      out.edge_lines = ImageF32(w, h, 3);
      const auto* lines = reinterpret_cast<const float*>(base + offsets[k][3]);
      const float* distance = out.field.distance.data.data();
      for (size_t i = 0; i < n; ++i) {
        // Stale beyond EDGE_LINE_NEAR_PX on the listed path (edge_lines.comp): zero there.
        const bool near_edge = distance[i] < static_cast<float>(EDGE_LINE_NEAR_PX);
        for (int c = 0; c < 3; ++c) out.edge_lines.data[i * 3 + c] = near_edge ? lines[i * 4 + c] : 0.0f;
      }
    }
    if (m.options.keep_intermediate) {
      out.gray = ImageF32(w, h, 1);
      std::memcpy(out.gray.data.data(), base + offsets[k][0], n * 4);
      out.edges = ImageU8(w, h, 1);
      const auto* state = reinterpret_cast<const uint32_t*>(base + offsets[k][1]);
      for (size_t i = 0; i < n; ++i) out.edges.data[i] = state[i] == 2 ? 255 : 0;
    }
    frame.levels.push_back(std::move(out));
  }
  return frame;
}

Status GpuEdgeStages::setReference(const std::vector<EdgePoint>& points) {
  Impl& m = *impl_;
  if (points.size() > (1u << 28)) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: too many points");
  m.point_count = static_cast<uint32_t>(points.size());
  m.level_offsets.clear();
  m.level_counts.clear();
  VKLOC_TRY_STATUS(m.updatePointBindings());
  return m.ctx->upload(m.points, points.data(), points.size() * sizeof(EdgePoint));
}

Status GpuEdgeStages::setLevelPoints(const EdgeReference& reference) {
  Impl& m = *impl_;
  std::vector<uint32_t> offsets, counts;
  size_t total = 0;
  for (int k = 0; k < static_cast<int>(m.levels.size()); ++k) {
    const size_t n = edgePointsForLevel(reference, k).size();
    offsets.push_back(static_cast<uint32_t>(total));
    counts.push_back(static_cast<uint32_t>(n));
    total += (n + 15) / 16 * 16;  // 256-byte aligned starts
    if (total > (1u << 28)) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: too many points");
  }
  std::vector<EdgePoint> packed(std::max<size_t>(total, 1));
  for (int k = 0; k < static_cast<int>(m.levels.size()); ++k) {
    const std::vector<EdgePoint>& points = edgePointsForLevel(reference, k);
    std::copy(points.begin(), points.end(), packed.begin() + offsets[k]);
  }
  m.point_count = 0;
  m.level_offsets = std::move(offsets);
  m.level_counts = std::move(counts);
  VKLOC_TRY_STATUS(m.updatePointBindings());
  const size_t used = m.level_offsets.empty() ? 0 : m.level_offsets.back() + m.level_counts.back();
  if (used == 0) return Status::success();
  return m.ctx->upload(m.points, packed.data(), used * sizeof(EdgePoint));
}

bool GpuEdgeStages::hasLevelPoints() const { return !impl_->level_offsets.empty(); }

float GpuEdgeStages::truncationPx() const { return impl_->options.truncation_px; }

Result<double> GpuEdgeStages::nearEdgeFraction(int level, double threshold_px) {
  Impl& m = *impl_;
  VKLOC_TRY_STATUS(m.checkTracking(Pose::Identity(), level));
  const auto& L = m.levels[level];
  const size_t n = static_cast<size_t>(L.camera.width) * L.camera.height;
  // One read-back buffer kept for every level (sized for level 0): the call runs once per frame.
  if (!m.distance_readback.buffer) {
    const auto& L0 = m.levels[0];
    auto b = m.ctx->createBuffer(static_cast<VkDeviceSize>(L0.camera.width) * L0.camera.height * 4,
                                 VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
    if (!b.ok()) return b.error();
    m.distance_readback = std::move(*b);
  }
  const Buffer* staging = &m.distance_readback;
  VKLOC_TRY_STATUS(m.ctx->runOnce([&](VkCommandBuffer c) {
    transferReadBarrier(c);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {L.distance.width, L.distance.height, 1};
    vkCmdCopyImageToBuffer(c, L.distance.image.get(), VK_IMAGE_LAYOUT_GENERAL, staging->buffer.get(), 1, &region);
    hostBarrier(c);
  }));
  const auto* d = static_cast<const float*>(staging->mapped);
  size_t near = 0;
  for (size_t i = 0; i < n; ++i) near += d[i] < threshold_px;
  return n > 0 ? static_cast<double>(near) / static_cast<double>(n) : 0.0;
}

int GpuEdgeAlignment::levelCount() const { return stages_->levelCount(); }

PinholeCamera GpuEdgeAlignment::levelCamera(int level) const { return stages_->levelCamera(level); }

float GpuEdgeAlignment::truncationPx(int /*level*/) const { return stages_->truncationPx(); }

Status GpuEdgeAlignment::setPoints(const std::vector<EdgePoint>& points) {
  if (resident_ && stages_->hasLevelPoints()) {
    for (int k = 0; k < stages_->levelCount(); ++k) {
      if (&edgePointsForLevel(*resident_, k) == &points) return Status::success();
    }
  }
  resident_ = nullptr;  // the stages now hold a single list
  return stages_->setReference(points);
}

Result<EdgeEvaluation> GpuEdgeAlignment::evaluate(int level, const Pose& T_camera_ref, double nu, int scale_iterations,
                                                  double min_sigma_px) {
  return stages_->evaluate(T_camera_ref, level, nu, scale_iterations, min_sigma_px);
}

Result<std::vector<float>> GpuEdgeAlignment::residuals(int level, const Pose& T_camera_ref) {
  return stages_->residuals(T_camera_ref, level);
}

Result<EdgeNormalEquations> GpuEdgeAlignment::accumulate(int level, const Pose& T_camera_ref, double sigma_px,
                                                         double nu) {
  return stages_->accumulate(T_camera_ref, level, sigma_px, nu);
}

Result<double> GpuEdgeAlignment::nearEdgeFraction(int level, double threshold_px) {
  return stages_->nearEdgeFraction(level, threshold_px);
}

Status GpuEdgeStages::Impl::checkTracking(const Pose& T_camera_ref, int level) const {
  if (!have_frame) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: no live image processed yet");
  if (level < 0 || level >= static_cast<int>(levels.size())) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuEdgeStages: level {} outside 0..{}", level, levels.size() - 1));
  }
  if (!isValidPose(T_camera_ref)) {
    return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages: T_camera_ref is not a valid rigid transform");
  }
  return Status::success();
}

EdgePush GpuEdgeStages::Impl::trackingPush(const Pose& T_camera_ref, int level) const {
  EdgePush push = levelPush(level);
  const Eigen::Matrix4d T = T_camera_ref.matrix();
  float* rows[3] = {push.pose_row0, push.pose_row1, push.pose_row2};
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) rows[r][c] = static_cast<float>(T(r, c));
  }
  const PinholeCamera& cam = levels[level].camera;
  push.intrinsics[0] = static_cast<float>(cam.fx);
  push.intrinsics[1] = static_cast<float>(cam.fy);
  push.intrinsics[2] = static_cast<float>(cam.cx);
  push.intrinsics[3] = static_cast<float>(cam.cy);
  push.point_count = level_offsets.empty() ? point_count : level_counts[level];
  return push;
}

Result<std::vector<float>> GpuEdgeStages::residuals(const Pose& T_camera_ref, int level) {
  Impl& m = *impl_;
  VKLOC_TRY_STATUS(m.checkTracking(T_camera_ref, level));
  m.timings.clear();
  const uint32_t count = m.level_offsets.empty() ? m.point_count : m.level_counts[level];
  if (count == 0) return std::vector<float>{};
  VKLOC_TRY_STATUS(m.begin());
  m.dispatch(kResiduals, level, m.trackingPush(T_camera_ref, level), kGridGroups);
  m.mark("residuals");
  VKLOC_TRY_STATUS(m.submit());
  const auto* r = static_cast<const float*>(m.residuals.mapped);
  return std::vector<float>(r, r + count);
}

Result<EdgeEvaluation> GpuEdgeStages::evaluate(const Pose& T_camera_ref, int level, double nu, int scale_iterations,
                                               double min_sigma_px) {
  Impl& m = *impl_;
  VKLOC_TRY_STATUS(m.checkTracking(T_camera_ref, level));
  if (!(nu > 0) || !std::isfinite(nu) || !(min_sigma_px > 0) || !std::isfinite(min_sigma_px) || scale_iterations < 0 ||
      scale_iterations > 1000) {
    return makeError(ErrorCode::kInvalidArgument,
                     "GpuEdgeStages::evaluate: need nu > 0, min_sigma_px > 0 and scale_iterations in 0..1000");
  }
  m.timings.clear();
  EdgeEvaluation out;
  out.sigma_px = min_sigma_px;
  const uint32_t count = m.level_offsets.empty() ? m.point_count : m.level_counts[level];
  if (count == 0) {
    out.eq = EdgeNormalEquations{};
    return out;
  }
  // Residuals -> scale -> normal equations weighted with that scale: one submission.
  EdgePush push = m.trackingPush(T_camera_ref, level);
  push.robust[1] = static_cast<float>(nu);
  push.robust[2] = static_cast<float>(min_sigma_px);
  push.step = scale_iterations;
  VKLOC_TRY_STATUS(m.begin());
  m.dispatch(kResiduals, level, push, kGridGroups);
  m.mark("residuals");
  m.dispatch(kScale, level, push, 1);
  m.mark("scale");
  push.robust[3] = 1.0f;
  m.dispatch(kNormalEquations, level, push, kGridGroups);
  m.mark("normal equations");
  VKLOC_TRY_STATUS(m.submit());
  const auto* r = static_cast<const float*>(m.residuals.mapped);
  out.residuals.assign(r, r + count);
  out.sigma_px = static_cast<const EdgeControl*>(m.levels[level].control.mapped)->sigma_px;
  out.eq = m.summedPartials();
  return out;
}

Result<EdgeNormalEquations> GpuEdgeStages::accumulate(const Pose& T_camera_ref, int level, double sigma_px, double nu) {
  Impl& m = *impl_;
  VKLOC_TRY_STATUS(m.checkTracking(T_camera_ref, level));
  if (!(sigma_px > 0) || !std::isfinite(sigma_px) || !(nu > 0) || !std::isfinite(nu)) {
    return makeError(ErrorCode::kInvalidArgument, "GpuEdgeStages::accumulate: sigma_px and nu must be > 0 and finite");
  }
  m.timings.clear();
  if ((m.level_offsets.empty() ? m.point_count : m.level_counts[level]) == 0) return EdgeNormalEquations{};
  EdgePush push = m.trackingPush(T_camera_ref, level);
  push.robust[0] = static_cast<float>(sigma_px);
  push.robust[1] = static_cast<float>(nu);
  VKLOC_TRY_STATUS(m.begin());
  m.dispatch(kNormalEquations, level, push, kGridGroups);
  m.mark("normal equations");
  VKLOC_TRY_STATUS(m.submit());
  return m.summedPartials();
}

}  // namespace vkloc
