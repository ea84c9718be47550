// GpuRemap: image remapping through a table as one Vulkan compute pass (shaders/remap.comp).
#include <fmt/format.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <vector>

#include "context.hpp"
#include "remap_layout.h"
#include "shader_registry.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/engine/gpu_remap.hpp"

namespace vkloc {

using engine::Buffer;
using engine::DeviceHandle;
using engine::RemapPush;

static_assert(sizeof(RemapPush) == 32, "RemapPush must match the GLSL std430 push block");
static_assert(offsetof(RemapPush, pixel_count) == 8);
static_assert(offsetof(RemapPush, max_u) == 16);
static_assert(offsetof(RemapPush, source_last_word) == 24);

namespace {

// Output uints per invocation on CPU drivers (specialization constant 0 of remap.comp; 1 on
// GPUs). lavapipe runs every 8 invocations as one coroutine: more work per invocation amortises
// its set-up. Measured at 640x480 on a loaded 2-core machine (GpuRemapTest.TimingReport640x480,
// process CPU time per call, best of 60): 1 / 4 / 16 / 64 words gave 2.6-2.8 / 2.9-3.1 /
// 2.6-2.8 / 2.6-2.9 ms, within the noise of each other; 16 as the edge stages' rows.
constexpr int32_t kCpuWordsPerInvocation = 16;
constexpr uint32_t kTableBytesPerWord = 32;  // 4 pixels x (u, v) floats

uint32_t ceilDiv(uint64_t n, uint64_t d) { return static_cast<uint32_t>((n + d - 1) / d); }

}  // namespace

struct GpuRemap::Impl {
  std::shared_ptr<GpuContext> context;
  GpuContext::Impl* ctx = nullptr;
  VkDevice device = VK_NULL_HANDLE;
  int width = 0, height = 0, source_width = 0, source_height = 0;
  RemapPush push{};
  RemapInterpolation interpolation = RemapInterpolation::kBilinear;
  int32_t words_per_invocation = 1;

  Buffer table;   // device-local: (u, v) per output pixel, padded to whole words with zeros
  Buffer source;  // host-visible: packed 8-bit source
  Buffer output;  // host-visible: packed 8-bit output

  DeviceHandle<VkDescriptorSetLayout> set_layout;
  DeviceHandle<VkDescriptorPool> descriptor_pool;
  VkDescriptorSet set = VK_NULL_HANDLE;
  DeviceHandle<VkPipelineLayout> pipeline_layout;
  DeviceHandle<VkShaderModule> module;
  DeviceHandle<VkPipeline> pipeline;
  DeviceHandle<VkFence> fence;
  DeviceHandle<VkQueryPool> query_pool;      // 2 timestamps around the dispatch; null without
  DeviceHandle<VkCommandPool> command_pool;  // this object's own: it submits on its user's thread
  VkCommandBuffer cmd = VK_NULL_HANDLE;      // recorded once: every remap runs the same commands
  double timestamp_ns = 0;                   // ns per tick
  uint64_t timestamp_mask = ~0ull;
  double last_ms = 0;

  Status init();
  Status uploadTable(const RemapTable& t);
  Status record();
};

Status GpuRemap::Impl::init() {
  device = ctx->device;
  const bool cpu_driver = ctx->properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  words_per_invocation = cpu_driver ? kCpuWordsPerInvocation : 1;
  const uint64_t pixels = static_cast<uint64_t>(width) * static_cast<uint64_t>(height);
  const uint64_t words = (pixels + 3) / 4;
  const uint64_t table_bytes = words * kTableBytesPerWord;
  const uint64_t source_bytes = (static_cast<uint64_t>(source_width) * source_height + 3) / 4 * 4;
  const uint64_t max_range = ctx->properties.limits.maxStorageBufferRange;
  if (table_bytes > max_range || source_bytes > max_range) {
    return makeError(
        ErrorCode::kUnsupported,
        fmt::format("GpuRemap: a {}x{} table from a {}x{} source needs storage buffers of {} bytes, the "
                    "device allows {}",
                    width, height, source_width, source_height, std::max(table_bytes, source_bytes), max_range));
  }
  push.source_width = source_width;
  push.source_height = source_height;
  push.pixel_count = static_cast<uint32_t>(pixels);
  push.word_count = static_cast<uint32_t>(words);
  push.max_u = static_cast<float>(source_width - 1);
  push.max_v = static_cast<float>(source_height - 1);
  push.source_last_word = static_cast<int32_t>((source_bytes / 4) - 1);

  const VkBufferUsageFlags ssbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  auto t = ctx->createBuffer(table_bytes, ssbo, false);
  if (!t.ok()) return t.error();
  table = std::move(*t);
  // The source is written by the host every call: a host-visible buffer takes a memcpy where a
  // device-local one takes a staging copy and a submission. The output is read once per call.
  auto s = ctx->createBuffer(source_bytes, ssbo, true);
  if (!s.ok()) return s.error();
  source = std::move(*s);
  auto o = ctx->createBuffer(words * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
  if (!o.ok()) return o.error();
  output = std::move(*o);

  VkDescriptorSetLayoutBinding bindings[REMAP_BINDING_COUNT];
  for (uint32_t b = 0; b < REMAP_BINDING_COUNT; ++b) {
    bindings[b] = {};
    bindings[b].binding = b;
    bindings[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    bindings[b].descriptorCount = 1;
    bindings[b].stageFlags = VK_SHADER_STAGE_COMPUTE_BIT;
  }
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = REMAP_BINDING_COUNT;
  lci.pBindings = bindings;
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorSetLayout(device, &lci, nullptr, &layout));
  set_layout = DeviceHandle<VkDescriptorSetLayout>(device, layout, vkDestroyDescriptorSetLayout);
  VkDescriptorPoolSize pool_size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, REMAP_BINDING_COUNT};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &pool_size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateDescriptorPool(device, &dpci, nullptr, &pool));
  descriptor_pool = DeviceHandle<VkDescriptorPool>(device, pool, vkDestroyDescriptorPool);
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &layout;
  VKLOC_VK(vkAllocateDescriptorSets(device, &ai, &set));
  const Buffer* buffers[REMAP_BINDING_COUNT] = {&table, &source, &output};
  VkDescriptorBufferInfo infos[REMAP_BINDING_COUNT];
  VkWriteDescriptorSet writes[REMAP_BINDING_COUNT];
  for (uint32_t b = 0; b < REMAP_BINDING_COUNT; ++b) {
    infos[b] = {buffers[b]->buffer.get(), 0, VK_WHOLE_SIZE};
    writes[b] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[b].dstSet = set;
    writes[b].dstBinding = b;
    writes[b].descriptorCount = 1;
    writes[b].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[b].pBufferInfo = &infos[b];
  }
  vkUpdateDescriptorSets(device, REMAP_BINDING_COUNT, writes, 0, nullptr);

  VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(RemapPush)};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &layout;
  plci.pushConstantRangeCount = 1;
  plci.pPushConstantRanges = &range;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  VKLOC_VK(vkCreatePipelineLayout(device, &plci, nullptr, &pl));
  pipeline_layout = DeviceHandle<VkPipelineLayout>(device, pl, vkDestroyPipelineLayout);
  const engine::ShaderBlob* blob = engine::findShader("remap.comp");
  if (blob == nullptr) return makeError(ErrorCode::kGpuError, "shader remap.comp is not embedded");
  VkShaderModuleCreateInfo smci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  smci.codeSize = blob->word_count * 4;
  smci.pCode = blob->words;
  VkShaderModule shader = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateShaderModule(device, &smci, nullptr, &shader));
  module = DeviceHandle<VkShaderModule>(device, shader, vkDestroyShaderModule);
  // Output uints per invocation; the interpolation (one pipeline each, the other path compiled out).
  const int32_t constants[2] = {words_per_invocation, interpolation == RemapInterpolation::kBicubic
                                                          ? REMAP_INTERPOLATION_BICUBIC
                                                          : REMAP_INTERPOLATION_BILINEAR};
  const VkSpecializationMapEntry entries[2] = {{REMAP_SPEC_WORDS, 0, sizeof(int32_t)},
                                               {REMAP_SPEC_INTERPOLATION, sizeof(int32_t), sizeof(int32_t)}};
  VkSpecializationInfo spec{2, entries, sizeof(constants), constants};
  VkComputePipelineCreateInfo cpci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  cpci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cpci.stage.module = shader;
  cpci.stage.pName = "main";
  cpci.stage.pSpecializationInfo = &spec;
  cpci.layout = pl;
  VkPipeline pipe = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &cpci, nullptr, &pipe));
  pipeline = DeviceHandle<VkPipeline>(device, pipe, vkDestroyPipeline);

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
  auto created_queries = ctx->createTimestampPool(2);
  if (!created_queries.ok()) return created_queries.error();
  query_pool = std::move(*created_queries);
  if (query_pool) {
    timestamp_ns = ctx->properties.limits.timestampPeriod;
    timestamp_mask = ctx->timestampMask();
  }
  return record();
}

// The one command buffer of every remap: timestamps around one dispatch, then the output made
// visible to the host. Nothing in it changes between calls (setTable rewrites the table buffer's
// contents only).
Status GpuRemap::Impl::record() {
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  VKLOC_VK(vkBeginCommandBuffer(cmd, &bi));
  if (query_pool) {
    vkCmdResetQueryPool(cmd, query_pool.get(), 0, 2);
    vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, query_pool.get(), 0);
  }
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.get());
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_layout.get(), 0, 1, &set, 0, nullptr);
  vkCmdPushConstants(cmd, pipeline_layout.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(RemapPush), &push);
  // Workgroups laid out 2D past the 65535 guaranteed along one axis; the shader linearises them.
  const uint32_t groups = ceilDiv(push.word_count, static_cast<uint64_t>(REMAP_LOCAL_SIZE) * words_per_invocation);
  const uint32_t gx = std::min<uint32_t>(groups, ctx->properties.limits.maxComputeWorkGroupCount[0]);
  vkCmdDispatch(cmd, gx, ceilDiv(groups, gx), 1);
  if (query_pool) vkCmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, query_pool.get(), 1);
  VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
  mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0,
                       nullptr);
  VKLOC_VK(vkEndCommandBuffer(cmd));
  return Status::success();
}

// Copies the table's (u, v) into the device buffer, the padding of the last word zeroed. No
// remap is in flight (remap waits for its submission), so the buffer is free to overwrite.
Status GpuRemap::Impl::uploadTable(const RemapTable& t) {
  const size_t bytes = t.uv.size() * sizeof(float);
  const size_t padded = static_cast<size_t>(push.word_count) * kTableBytesPerWord;
  if (table.mapped != nullptr) {
    std::memcpy(table.mapped, t.uv.data(), bytes);
    std::memset(static_cast<uint8_t*>(table.mapped) + bytes, 0, padded - bytes);
    return Status::success();
  }
  if (bytes == padded) return ctx->upload(table, t.uv.data(), bytes);
  std::vector<float> copy(padded / sizeof(float), 0.0f);
  std::copy(t.uv.begin(), t.uv.end(), copy.begin());
  return ctx->upload(table, copy.data(), padded);
}

GpuRemap::GpuRemap(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GpuRemap::~GpuRemap() = default;

Result<std::unique_ptr<GpuRemap>> GpuRemap::create(std::shared_ptr<GpuContext> context, const RemapTable& table,
                                                   RemapInterpolation interpolation) {
  if (!context) return makeError(ErrorCode::kInvalidArgument, "GpuRemap: no GPU context");
  if (interpolation != RemapInterpolation::kBilinear && interpolation != RemapInterpolation::kBicubic) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuRemap: unknown interpolation {}", static_cast<int>(interpolation)));
  }
  VKLOC_TRY_STATUS(validateRemapTable(table));
  auto impl = std::make_unique<Impl>();
  impl->context = context;
  impl->ctx = &context->impl();
  impl->width = table.width;
  impl->height = table.height;
  impl->source_width = table.source_width;
  impl->source_height = table.source_height;
  impl->interpolation = interpolation;
  VKLOC_TRY_STATUS(impl->init());
  VKLOC_TRY_STATUS(impl->uploadTable(table));
  return std::unique_ptr<GpuRemap>(new GpuRemap(std::move(impl)));
}

Status GpuRemap::setTable(const RemapTable& table) {
  Impl& m = *impl_;
  VKLOC_TRY_STATUS(validateRemapTable(table));
  if (table.width != m.width || table.height != m.height || table.source_width != m.source_width ||
      table.source_height != m.source_height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuRemap::setTable: table maps {}x{} to {}x{}, this remap was created for {}x{} to "
                                 "{}x{} (create another for other sizes)",
                                 table.source_width, table.source_height, table.width, table.height, m.source_width,
                                 m.source_height, m.width, m.height));
  }
  return m.uploadTable(table);
}

Result<ImageU8> GpuRemap::remap(const ImageU8& source) {
  Impl& m = *impl_;
  if (source.channels != 1 || source.width != m.source_width || source.height != m.source_height ||
      source.data.size() != static_cast<size_t>(source.width) * source.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("GpuRemap::remap: source image is {}x{}x{}, the table expects {}x{} single-channel",
                                 source.width, source.height, source.channels, m.source_width, m.source_height));
  }
  VKLOC_TRY_STATUS(m.ctx->upload(m.source, source.data.data(), source.data.size()));
  const auto t0 = SteadyClock::now();
  VKLOC_TRY_STATUS(m.ctx->submitAndWait(m.cmd, m.fence.get()));
  m.last_ms = msSince(t0);
  if (m.query_pool) {
    uint64_t ticks[2] = {0, 0};
    VKLOC_VK(vkGetQueryPoolResults(m.device, m.query_pool.get(), 0, 2, sizeof(ticks), ticks, sizeof(uint64_t),
                                   VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
    m.last_ms = static_cast<double>((ticks[1] - ticks[0]) & m.timestamp_mask) * m.timestamp_ns * 1e-6;
  }
  ImageU8 out(m.width, m.height, 1);
  std::memcpy(out.data.data(), m.output.mapped, out.data.size());
  return out;
}

double GpuRemap::lastGpuMs() const { return impl_->last_ms; }

std::string GpuRemap::describe() const {
  return fmt::format("GPU remap ({}) on {}", remapInterpolationName(impl_->interpolation),
                     impl_->context->device().name);
}

}  // namespace vkloc
