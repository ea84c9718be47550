// GpuRenderer: model rendering to colour, linear metric depth and normals with Vulkan.
#include <fmt/format.h>
#include <meshoptimizer.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>

#include "context.hpp"
#include "lod.hpp"
#include "render_layout.h"
#include "shader_registry.hpp"
#include "textures.hpp"
#include "vkloc/engine/gpu.hpp"

namespace vkloc {

using engine::Buffer;
using engine::DeviceHandle;

static_assert(sizeof(engine::ModelPush) == 112, "ModelPush must match the GLSL std430 push block");
static_assert(offsetof(engine::ModelPush, intrinsics) == 64);
static_assert(offsetof(engine::ModelPush, base_color) == 80);
static_assert(offsetof(engine::ModelPush, texture) == 96);

namespace {

constexpr VkFormat kColorFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkFormat kLinearDepthFormat = VK_FORMAT_R32_SFLOAT;
constexpr VkFormat kNormalFormat = VK_FORMAT_R32_UINT;   // octahedral, packSnorm2x16
constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;  // reverse-Z
// Colour targets: rendered, copied (readback on the copy path) and sampled by later stages.
constexpr VkImageUsageFlags kTargetUsage =
    VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;

// Interleaved per-vertex attributes of binding 1 (binding 0 holds positions alone, so
// depth-only passes can skip these).
struct VertexAttributes {
  float uv[2];
  uint8_t rgba[4];
};
static_assert(sizeof(VertexAttributes) == 12);

// Inverse of octEncode in shaders/include/octahedral.glsl.
void octDecode(float ex, float ey, float out[3]) {
  float x = ex, y = ey, z = 1.0f - std::abs(ex) - std::abs(ey);
  if (z < 0.0f) {
    x = (1.0f - std::abs(ey)) * (ex >= 0.0f ? 1.0f : -1.0f);
    y = (1.0f - std::abs(ex)) * (ey >= 0.0f ? 1.0f : -1.0f);
  }
  const float n = std::sqrt(x * x + y * y + z * z);
  out[0] = x / n;
  out[1] = y / n;
  out[2] = z / n;
}

Result<DeviceHandle<VkShaderModule>> shaderModule(VkDevice device, const char* name) {
  const engine::ShaderBlob* blob = engine::findShader(name);
  if (blob == nullptr) return makeError(ErrorCode::kGpuError, fmt::format("shader {} is not embedded", name));
  VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  ci.codeSize = blob->word_count * 4;
  ci.pCode = blob->words;
  VkShaderModule module = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateShaderModule(device, &ci, nullptr, &module));
  return DeviceHandle<VkShaderModule>(device, module, vkDestroyShaderModule);
}

// Render targets for one image size.
struct Targets {
  uint32_t width = 0, height = 0;
  engine::Image color, linear_depth, normals, depth;
  DeviceHandle<VkFramebuffer> framebuffer[2];  // [with normals]
  Buffer readback;                             // rgba8 | float depth | rg16f normals (copy path only)
};

// Copies `height` rows of `row_bytes` from a pitched source into a packed destination.
void copyRows(void* dst, const void* src, size_t row_bytes, size_t pitch, uint32_t height) {
  auto* d = static_cast<uint8_t*>(dst);
  const auto* s = static_cast<const uint8_t*>(src);
  if (pitch == row_bytes) {
    std::memcpy(d, s, row_bytes * height);
    return;
  }
  for (uint32_t y = 0; y < height; ++y) std::memcpy(d + y * row_bytes, s + y * pitch, row_bytes);
}

}  // namespace

struct GpuRenderer::Impl {
  std::shared_ptr<GpuContext> context;
  GpuContext::Impl* ctx = nullptr;
  VkDevice device = VK_NULL_HANDLE;

  // Model data.
  engine::LodModel lod;  // per-block draws at full and reduced detail
  std::vector<Material> materials;
  std::vector<bool> texture_ok;
  std::array<double, 3> origin{0, 0, 0};  // world frame, metres; vertices are stored relative to it
  Buffer positions, attributes, indices;
  engine::TextureSet textures;
  DeviceHandle<VkPipelineLayout> pipeline_layout;
  DeviceHandle<VkRenderPass> render_pass[2];  // [with normals]
  DeviceHandle<VkShaderModule> vert, frag;
  std::map<int, DeviceHandle<VkPipeline>> pipelines;  // key: normals | cull << 1

  /// Render targets are linear images in host-visible memory that the host reads directly
  /// (unified memory: lavapipe, integrated GPUs); otherwise they are copied to a buffer.
  bool direct_readback = false;
  Targets targets;
  DeviceHandle<VkCommandPool> command_pool;  // this object's own: it records on its user's thread
  VkCommandBuffer cmd = VK_NULL_HANDLE;      // from command_pool
  DeviceHandle<VkFence> fence;

  ~Impl() {
    if (device != VK_NULL_HANDLE) (void)ctx->waitQueueIdle();
  }

  Status init(const Model& model, const GpuRendererOptions& options);
  Status createRenderPasses();
  Result<VkPipeline> pipeline(bool normals, bool cull);
  Status ensureTargets(uint32_t width, uint32_t height);
  Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera, const RenderSettings& settings,
                              bool readback);
  /// Records the commands that make the targets readable by the host (barrier or copies).
  void recordReadback(bool normals);
  /// Reads the targets of the last render into host images.
  Result<RenderOutput> readTargets();
  Result<RenderOutput> readback();

  struct LastFrame {
    bool valid = false;
    uint32_t width = 0, height = 0;
    bool normals = false;
    uint32_t blocks_drawn = 0, triangles_drawn = 0;
  };
  LastFrame last;
};

Status GpuRenderer::Impl::init(const Model& model, const GpuRendererOptions& options) {
  ctx = &context->impl();
  device = ctx->device;
  direct_readback = options.direct_readback && ctx->unified_memory;
  for (VkFormat f : {kColorFormat, kLinearDepthFormat, kNormalFormat}) {
    direct_readback = direct_readback && ctx->linearImageSupported(f, kTargetUsage, 1, 1);
  }
  VKLOC_TRY_STATUS(validateModel(model));
  materials = model.materials;

  // Vertices relative to the model's centre keep float precision for large world coordinates.
  if (!model.bounds.empty()) {
    for (int i = 0; i < 3; ++i) origin[i] = std::floor(0.5 * (double(model.bounds.min[i]) + model.bounds.max[i]));
  }
  const size_t nv = model.vertexCount();
  std::vector<float> rel(model.positions.size());
  for (size_t i = 0; i < nv; ++i) {
    for (int k = 0; k < 3; ++k) rel[i * 3 + k] = static_cast<float>(model.positions[i * 3 + k] - origin[k]);
  }
  std::vector<VertexAttributes> attrs(nv);
  for (size_t i = 0; i < nv; ++i) {
    if (!model.uvs.empty()) {
      attrs[i].uv[0] = model.uvs[i * 2];
      attrs[i].uv[1] = model.uvs[i * 2 + 1];
    } else {
      attrs[i].uv[0] = attrs[i].uv[1] = 0.0f;
    }
    for (int k = 0; k < 4; ++k) attrs[i].rgba[k] = model.colors.empty() ? 255 : model.colors[i * 4 + k];
  }
  const VkBufferUsageFlags vb = VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  auto make = [&](Buffer& dst, const void* data, size_t bytes, VkBufferUsageFlags usage) -> Status {
    auto b = ctx->createBuffer(bytes, usage, false);
    if (!b.ok()) return b.error();
    dst = std::move(*b);
    return ctx->upload(dst, data, bytes);
  };
  VKLOC_TRY_STATUS(make(positions, rel.data(), rel.size() * sizeof(float), vb));
  VKLOC_TRY_STATUS(make(attributes, attrs.data(), attrs.size() * sizeof(VertexAttributes), vb));
  // Full-detail triangles reordered inside each draw range for the post-transform vertex cache
  // (fewer vertex shader invocations), then the simplified levels of every block.
  lod = engine::buildLodModel(model, options.lod_levels);
  VKLOC_TRY_STATUS(make(indices, lod.indices.data(), lod.indices.size() * sizeof(uint32_t),
                        VK_BUFFER_USAGE_INDEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT));

  // Textures with their mip chains, in descriptor sets of as many as the device allows (see
  // textures.hpp); a 1x1 white one when the model has none, so that no set is empty.
  engine::TextureSetOptions texture_options;
  texture_options.host_mipmaps = options.host_mipmaps;
  texture_options.max_per_set = static_cast<uint32_t>(std::max(0, options.max_textures_per_set));
  auto created_textures = engine::TextureSet::create(*ctx, model.textures, texture_options);
  if (!created_textures.ok()) return created_textures.error();
  textures = std::move(*created_textures);
  const VkDescriptorSetLayout layout = textures.layout.get();
  texture_ok.assign(materials.size(), false);
  for (size_t m = 0; m < materials.size(); ++m) {
    texture_ok[m] = materials[m].texture >= 0 && materials[m].texture < static_cast<int>(model.textures.size());
  }

  VkPushConstantRange push{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(engine::ModelPush)};
  VkPipelineLayoutCreateInfo plci{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  plci.setLayoutCount = 1;
  plci.pSetLayouts = &layout;
  plci.pushConstantRangeCount = 1;
  plci.pPushConstantRanges = &push;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  VKLOC_VK(vkCreatePipelineLayout(device, &plci, nullptr, &pl));
  pipeline_layout = DeviceHandle<VkPipelineLayout>(device, pl, vkDestroyPipelineLayout);

  auto v = shaderModule(device, "model.vert");
  if (!v.ok()) return v.error();
  vert = std::move(*v);
  auto f = shaderModule(device, "model.frag");
  if (!f.ok()) return f.error();
  frag = std::move(*f);
  VKLOC_TRY_STATUS(createRenderPasses());

  auto created_pool = ctx->createCommandPool();
  if (!created_pool.ok()) return created_pool.error();
  command_pool = std::move(*created_pool);
  auto c = ctx->allocateCommandBuffer(command_pool.get());
  if (!c.ok()) return c.error();
  cmd = *c;
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fe = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateFence(device, &fci, nullptr, &fe));
  fence = DeviceHandle<VkFence>(device, fe, vkDestroyFence);
  return Status::success();
}

Status GpuRenderer::Impl::createRenderPasses() {
  for (int with_normals = 0; with_normals < 2; ++with_normals) {
    std::vector<VkAttachmentDescription> att;
    auto color_att = [&](VkFormat format) {
      VkAttachmentDescription a{};
      a.format = format;
      a.samples = VK_SAMPLE_COUNT_1_BIT;
      a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
      a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
      a.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
      a.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
      a.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
      // The host reads linear targets in GENERAL layout; the copy path reads optimal ones.
      a.finalLayout = direct_readback ? VK_IMAGE_LAYOUT_GENERAL : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
      att.push_back(a);
    };
    color_att(kColorFormat);
    color_att(kLinearDepthFormat);
    if (with_normals) color_att(kNormalFormat);
    VkAttachmentDescription d{};
    d.format = kDepthFormat;
    d.samples = VK_SAMPLE_COUNT_1_BIT;
    d.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    d.storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    d.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    d.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    d.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    d.finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    att.push_back(d);
    // Three colour slots in both variants; without normals slot 2 is VK_ATTACHMENT_UNUSED so
    // the fragment shader's normal output is discarded by definition.
    const uint32_t depth_index = with_normals ? 3 : 2;
    VkAttachmentReference refs[3] = {
        {0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
        {1, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL},
        {with_normals ? 2u : VK_ATTACHMENT_UNUSED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}};
    VkAttachmentReference depth_ref{depth_index, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub{};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 3;
    sub.pColorAttachments = refs;
    sub.pDepthStencilAttachment = &depth_ref;
    VkSubpassDependency deps[2]{};
    // Earlier reads of the targets (readback copies) finish before this pass writes them.
    deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    deps[0].dstSubpass = 0;
    deps[0].srcStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
    deps[0].srcAccessMask = 0;
    deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    // Colour writes are visible to the transfer (readback) and compute stages that follow.
    deps[1].srcSubpass = 0;
    deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    deps[1].dstStageMask = VK_PIPELINE_STAGE_TRANSFER_BIT | VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
    deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    deps[1].dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_SHADER_READ_BIT;
    VkRenderPassCreateInfo rpci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    rpci.attachmentCount = static_cast<uint32_t>(att.size());
    rpci.pAttachments = att.data();
    rpci.subpassCount = 1;
    rpci.pSubpasses = &sub;
    rpci.dependencyCount = 2;
    rpci.pDependencies = deps;
    VkRenderPass rp = VK_NULL_HANDLE;
    VKLOC_VK(vkCreateRenderPass(device, &rpci, nullptr, &rp));
    render_pass[with_normals] = DeviceHandle<VkRenderPass>(device, rp, vkDestroyRenderPass);
  }
  return Status::success();
}

Result<VkPipeline> GpuRenderer::Impl::pipeline(bool normals, bool cull) {
  const int key = (normals ? 1 : 0) | (cull ? 2 : 0);
  if (auto it = pipelines.find(key); it != pipelines.end()) return it->second.get();

  const VkSpecializationMapEntry entries[2] = {{0, 0, 4}, {1, 4, 4}};
  const int32_t spec_data[2] = {static_cast<int32_t>(textures.slots), normals ? 1 : 0};
  VkSpecializationInfo spec{2, entries, sizeof(spec_data), spec_data};
  VkPipelineShaderStageCreateInfo stages[2]{};
  stages[0].sType = stages[1].sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = vert.get();
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = frag.get();
  stages[1].pName = "main";
  stages[1].pSpecializationInfo = &spec;

  const VkVertexInputBindingDescription bindings[2] = {{0, 12, VK_VERTEX_INPUT_RATE_VERTEX},
                                                       {1, sizeof(VertexAttributes), VK_VERTEX_INPUT_RATE_VERTEX}};
  const VkVertexInputAttributeDescription attrs[3] = {
      {0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0}, {1, 1, VK_FORMAT_R32G32_SFLOAT, 0}, {2, 1, VK_FORMAT_R8G8B8A8_UNORM, 8}};
  VkPipelineVertexInputStateCreateInfo vin{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  vin.vertexBindingDescriptionCount = 2;
  vin.pVertexBindingDescriptions = bindings;
  vin.vertexAttributeDescriptionCount = 3;
  vin.pVertexAttributeDescriptions = attrs;
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = 1;
  vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  // Model triangles are counter-clockwise seen from their front; with the camera's y axis
  // pointing down the image they stay counter-clockwise in Vulkan framebuffer coordinates.
  rs.cullMode = cull ? VK_CULL_MODE_BACK_BIT : VK_CULL_MODE_NONE;
  rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = VK_TRUE;
  ds.depthWriteEnable = VK_TRUE;
  ds.depthCompareOp = VK_COMPARE_OP_GREATER;  // reverse-Z: nearer is larger
  VkPipelineColorBlendAttachmentState blend[3]{};
  for (auto& b : blend) b.colorWriteMask = 0xf;
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = 3;
  cb.pAttachments = blend;
  const VkDynamicState dyn_states[2] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
  VkPipelineDynamicStateCreateInfo dyn{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dyn.dynamicStateCount = 2;
  dyn.pDynamicStates = dyn_states;
  VkGraphicsPipelineCreateInfo gci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
  gci.stageCount = 2;
  gci.pStages = stages;
  gci.pVertexInputState = &vin;
  gci.pInputAssemblyState = &ia;
  gci.pViewportState = &vp;
  gci.pRasterizationState = &rs;
  gci.pMultisampleState = &ms;
  gci.pDepthStencilState = &ds;
  gci.pColorBlendState = &cb;
  gci.pDynamicState = &dyn;
  gci.layout = pipeline_layout.get();
  gci.renderPass = render_pass[normals ? 1 : 0].get();
  VkPipeline p = VK_NULL_HANDLE;
  VKLOC_VK(vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &gci, nullptr, &p));
  pipelines[key] = DeviceHandle<VkPipeline>(device, p, vkDestroyPipeline);
  return p;
}

Status GpuRenderer::Impl::ensureTargets(uint32_t width, uint32_t height) {
  if (targets.width == width && targets.height == height) return Status::success();
  const VkPhysicalDeviceLimits& limits = ctx->properties.limits;
  if (width > limits.maxFramebufferWidth || height > limits.maxFramebufferHeight ||
      width > limits.maxImageDimension2D || height > limits.maxImageDimension2D) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("render: {}x{} exceeds this device's largest framebuffer {}x{}", width, height,
                                 std::min(limits.maxFramebufferWidth, limits.maxImageDimension2D),
                                 std::min(limits.maxFramebufferHeight, limits.maxImageDimension2D)));
  }
  VKLOC_TRY_STATUS(ctx->waitQueueIdle());
  targets = Targets{};
  const VkImageUsageFlags color_usage = kTargetUsage;
  // Linear targets may be limited to smaller sizes than optimal ones: fall back to the copy path.
  if (direct_readback) {
    for (VkFormat f : {kColorFormat, kLinearDepthFormat, kNormalFormat}) {
      if (!ctx->linearImageSupported(f, kTargetUsage, width, height)) direct_readback = false;
    }
    if (!direct_readback) VKLOC_TRY_STATUS(createRenderPasses());
  }
  bool linear = direct_readback;
  auto mk = [&](engine::Image& dst, VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect) -> Status {
    auto img = ctx->createImage(width, height, format, usage, aspect, linear);
    if (!img.ok()) return img.error();
    dst = std::move(*img);
    return Status::success();
  };
  VKLOC_TRY_STATUS(mk(targets.color, kColorFormat, color_usage, VK_IMAGE_ASPECT_COLOR_BIT));
  VKLOC_TRY_STATUS(mk(targets.linear_depth, kLinearDepthFormat, color_usage, VK_IMAGE_ASPECT_COLOR_BIT));
  VKLOC_TRY_STATUS(mk(targets.normals, kNormalFormat, color_usage, VK_IMAGE_ASPECT_COLOR_BIT));
  linear = false;  // the depth buffer is never read by the host
  VKLOC_TRY_STATUS(
      mk(targets.depth, kDepthFormat, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT));
  for (int with_normals = 0; with_normals < 2; ++with_normals) {
    std::vector<VkImageView> views = {targets.color.view.get(), targets.linear_depth.view.get()};
    if (with_normals) views.push_back(targets.normals.view.get());
    views.push_back(targets.depth.view.get());
    VkFramebufferCreateInfo fci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    fci.renderPass = render_pass[with_normals].get();
    fci.attachmentCount = static_cast<uint32_t>(views.size());
    fci.pAttachments = views.data();
    fci.width = width;
    fci.height = height;
    fci.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    VKLOC_VK(vkCreateFramebuffer(device, &fci, nullptr, &fb));
    targets.framebuffer[with_normals] = DeviceHandle<VkFramebuffer>(device, fb, vkDestroyFramebuffer);
  }
  if (!direct_readback) {
    const VkDeviceSize pixels = static_cast<VkDeviceSize>(width) * height;
    auto rb = ctx->createBuffer(pixels * 12, VK_BUFFER_USAGE_TRANSFER_DST_BIT, true);
    if (!rb.ok()) return rb.error();
    targets.readback = std::move(*rb);
  }
  targets.width = width;
  targets.height = height;
  return Status::success();
}

Result<RenderOutput> GpuRenderer::Impl::render(const PinholeCamera& camera, const Pose& T_world_camera,
                                               const RenderSettings& settings, bool readback) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  if (!isValidPose(T_world_camera)) {
    return makeError(ErrorCode::kInvalidArgument, "render: T_world_camera is not a finite rigid transform");
  }
  VKLOC_TRY_STATUS(validateRenderSettings(settings));
  const uint32_t w = static_cast<uint32_t>(camera.width), h = static_cast<uint32_t>(camera.height);
  VKLOC_TRY_STATUS(ensureTargets(w, h));
  const bool normals = (settings.outputs & kRenderNormals) != 0;
  auto pipe = pipeline(normals, settings.cull_back_faces);
  if (!pipe.ok()) return pipe.error();

  // Block frustum culling and level-of-detail choice on the host, then adjacent draws of one
  // material are merged.
  RenderOutput out;
  struct Draw {
    uint32_t first, count;
    int material;
  };
  std::vector<Draw> draws;
  const Pose T_camera_world = T_world_camera.inverse();
  const double pixels_per_metre = engine::lodPixelsPerMetre(camera);
  for (const engine::LodBlock& b : lod.blocks) {
    if (!aabbInFrustumFromCamera(b.bounds, camera, T_camera_world, settings.near_m, settings.far_m)) continue;
    const int level_index = settings.lod_pixel_error > 0
                                ? engine::selectLodLevel(b, engine::minDepthOfBox(b.bounds, T_camera_world),
                                                         pixels_per_metre, settings.lod_pixel_error)
                                : 0;
    const engine::LodLevel& level = b.levels[static_cast<size_t>(level_index)];
    ++out.blocks_drawn;
    out.triangles_drawn += level.triangles;
    for (uint32_t d = level.first_draw; d < level.first_draw + level.draw_count; ++d) {
      const engine::LodDraw& ld = lod.draws[d];
      if (!draws.empty() && draws.back().material == ld.material &&
          draws.back().first + draws.back().count == ld.first_index) {
        draws.back().count += ld.index_count;
      } else {
        draws.push_back({ld.first_index, ld.index_count, ld.material});
      }
    }
  }

  // clip_from_origin = P * T_camera_world * T_world_origin, composed in double.
  Eigen::Matrix4d T_world_origin = Eigen::Matrix4d::Identity();
  T_world_origin.block<3, 1>(0, 3) = Eigen::Vector3d(origin[0], origin[1], origin[2]);
  const Eigen::Matrix4d clip =
      projectionMatrix(camera, settings.near_m, settings.far_m) * T_camera_world.matrix() * T_world_origin;
  engine::ModelPush push{};
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) push.clip_from_origin[c * 4 + r] = static_cast<float>(clip(r, c));
  }
  push.intrinsics[0] = static_cast<float>(camera.fx);
  push.intrinsics[1] = static_cast<float>(camera.fy);
  push.intrinsics[2] = static_cast<float>(camera.cx);
  push.intrinsics[3] = static_cast<float>(camera.cy);

  VKLOC_VK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VKLOC_VK(vkBeginCommandBuffer(cmd, &begin));
  VkClearValue clears[4]{};
  for (int k = 0; k < 4; ++k) clears[0].color.float32[k] = settings.background_rgba[k] / 255.0f;
  clears[1].color.float32[0] = kBackgroundDepth;  // clears[2] (normals, uint) stays 0
  const uint32_t nclear = normals ? 4 : 3;
  clears[nclear - 1].depthStencil = {0.0f, 0};  // reverse-Z: 0 is infinitely far
  VkRenderPassBeginInfo rpbi{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
  rpbi.renderPass = render_pass[normals ? 1 : 0].get();
  rpbi.framebuffer = targets.framebuffer[normals ? 1 : 0].get();
  rpbi.renderArea = {{0, 0}, {w, h}};
  rpbi.clearValueCount = nclear;
  rpbi.pClearValues = clears;
  vkCmdBeginRenderPass(cmd, &rpbi, VK_SUBPASS_CONTENTS_INLINE);
  if (!draws.empty()) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, *pipe);
    VkViewport viewport{0.0f, 0.0f, static_cast<float>(w), static_cast<float>(h), 0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, {w, h}};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);
    const VkBuffer vbs[2] = {positions.buffer.get(), attributes.buffer.get()};
    const VkDeviceSize offsets[2] = {0, 0};
    vkCmdBindVertexBuffers(cmd, 0, 2, vbs, offsets);
    vkCmdBindIndexBuffer(cmd, indices.buffer.get(), 0, VK_INDEX_TYPE_UINT32);
    // The shader statically uses the texture array: a set is bound before the first draw, then
    // another only when a draw's texture lies in another batch (textures.hpp).
    uint32_t bound_set = 0;
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout.get(), 0, 1, &textures.sets[0], 0,
                            nullptr);
    int bound_material = -2;
    for (const Draw& d : draws) {
      if (d.material != bound_material) {
        const Material& m = materials[static_cast<size_t>(d.material)];
        const bool textured = texture_ok[static_cast<size_t>(d.material)];
        for (int k = 0; k < 4; ++k) push.base_color[k] = m.base_color[k];
        push.texture = textured ? textures.slotOf(m.texture) : 0;
        push.flags = textured ? VKLOC_FLAG_TEXTURED : 0u;
        if (textured && textures.setOf(m.texture) != bound_set) {
          bound_set = textures.setOf(m.texture);
          vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline_layout.get(), 0, 1,
                                  &textures.sets[bound_set], 0, nullptr);
        }
        vkCmdPushConstants(cmd, pipeline_layout.get(), VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0,
                           sizeof(push), &push);
        bound_material = d.material;
      }
      vkCmdDrawIndexed(cmd, d.count, 1, d.first, 0, 0);
    }
  }
  vkCmdEndRenderPass(cmd);

  if (readback) recordReadback(normals);
  VKLOC_VK(vkEndCommandBuffer(cmd));
  VKLOC_TRY_STATUS(ctx->submitAndWait(cmd, fence.get()));
  last = LastFrame{true, w, h, normals, out.blocks_drawn, out.triangles_drawn};
  if (!readback) return out;
  return readTargets();
}

void GpuRenderer::Impl::recordReadback(bool normals) {
  const uint32_t w = targets.width, h = targets.height;
  const VkDeviceSize pixels = static_cast<VkDeviceSize>(w) * h;
  if (direct_readback) {
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0,
                         nullptr, 0, nullptr);
  } else {
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {w, h, 1};
    region.bufferOffset = 0;
    vkCmdCopyImageToBuffer(cmd, targets.color.image.get(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           targets.readback.buffer.get(), 1, &region);
    region.bufferOffset = pixels * 4;
    vkCmdCopyImageToBuffer(cmd, targets.linear_depth.image.get(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                           targets.readback.buffer.get(), 1, &region);
    if (normals) {
      region.bufferOffset = pixels * 8;
      vkCmdCopyImageToBuffer(cmd, targets.normals.image.get(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                             targets.readback.buffer.get(), 1, &region);
    }
    VkMemoryBarrier mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    mb.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0,
                         nullptr);
  }
}

Result<RenderOutput> GpuRenderer::Impl::readback() {
  if (!last.valid) return makeError(ErrorCode::kInvalidArgument, "readback: nothing has been rendered yet");
  VKLOC_VK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VKLOC_VK(vkBeginCommandBuffer(cmd, &begin));
  recordReadback(last.normals);
  VKLOC_VK(vkEndCommandBuffer(cmd));
  VKLOC_TRY_STATUS(ctx->submitAndWait(cmd, fence.get()));
  return readTargets();
}

Result<RenderOutput> GpuRenderer::Impl::readTargets() {
  const uint32_t w = last.width, h = last.height;
  const bool normals = last.normals;
  const VkDeviceSize pixels = static_cast<VkDeviceSize>(w) * h;
  RenderOutput out;
  out.blocks_drawn = last.blocks_drawn;
  out.triangles_drawn = last.triangles_drawn;
  const int iw = static_cast<int>(w), ih = static_cast<int>(h);
  out.rgba = ImageU8(iw, ih, 4);
  out.depth = ImageF32(iw, ih, 1);
  std::vector<uint16_t> normal_words;
  const uint16_t* enc = nullptr;
  if (direct_readback) {
    copyRows(out.rgba.data.data(), targets.color.mapped, w * 4, targets.color.row_pitch, h);
    copyRows(out.depth.data.data(), targets.linear_depth.mapped, w * 4, targets.linear_depth.row_pitch, h);
    if (normals) {
      normal_words.resize(pixels * 2);
      copyRows(normal_words.data(), targets.normals.mapped, w * 4, targets.normals.row_pitch, h);
      enc = normal_words.data();
    }
  } else {
    const auto* base = static_cast<const uint8_t*>(targets.readback.mapped);
    std::memcpy(out.rgba.data.data(), base, pixels * 4);
    std::memcpy(out.depth.data.data(), base + pixels * 4, pixels * 4);
    enc = reinterpret_cast<const uint16_t*>(base + pixels * 8);
  }
  out.gray = rgbaToGray(out.rgba);
  if (normals) {
    out.normals = ImageF32(iw, ih, 3, 0.0f);
    out.back_faces = ImageU8(iw, ih, 1, 0);
    // unpackSnorm2x16: low half is x, high half is y, each clamp(v / 32767, -1, 1); bit 0 of x
    // is the back-face bit (shaders/model.frag).
    const auto* words = reinterpret_cast<const int16_t*>(enc);
    constexpr float kScale = 1.0f / 32767.0f;
    for (VkDeviceSize i = 0; i < pixels; ++i) {
      if (out.depth.data[i] == kBackgroundDepth) continue;
      const int16_t x = words[2 * i];
      out.back_faces.data[i] = (x & 1) ? 255 : 0;
      const auto x_even = static_cast<int16_t>(x & ~1);
      octDecode(std::max(-1.0f, x_even * kScale), std::max(-1.0f, words[2 * i + 1] * kScale), &out.normals.data[i * 3]);
    }
  }
  return out;
}

GpuRenderer::GpuRenderer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GpuRenderer::~GpuRenderer() = default;

Result<std::unique_ptr<GpuRenderer>> GpuRenderer::create(std::shared_ptr<GpuContext> context, const Model& model,
                                                         const GpuRendererOptions& options) {
  if (!context) return makeError(ErrorCode::kInvalidArgument, "GpuRenderer: null context");
  auto impl = std::make_unique<Impl>();
  impl->context = std::move(context);
  VKLOC_TRY_STATUS(impl->init(model, options));
  return std::unique_ptr<GpuRenderer>(new GpuRenderer(std::move(impl)));
}

Result<RenderOutput> GpuRenderer::render(const PinholeCamera& camera, const Pose& T_world_camera,
                                         const RenderSettings& settings) {
  return impl_->render(camera, T_world_camera, settings, true);
}

Result<RenderOutput> GpuRenderer::readback() { return impl_->readback(); }

Result<RenderOutput> GpuRenderer::renderOnGpu(const PinholeCamera& camera, const Pose& T_world_camera,
                                              const RenderSettings& settings) {
  return impl_->render(camera, T_world_camera, settings, false);
}

std::string GpuRenderer::describe() const {
  const GpuDeviceInfo& d = impl_->context->device();
  return fmt::format("Vulkan on {} ({})", d.name, d.type);
}

RendererFactory gpuRendererFactory(std::shared_ptr<GpuContext> context, const GpuRendererOptions& options) {
  return [context, options](const Model& model) -> Result<std::unique_ptr<Renderer>> {
    auto created = GpuRenderer::create(context, model, options);
    if (!created.ok()) return created.error();
    return std::unique_ptr<Renderer>(std::move(created).value());
  };
}

}  // namespace vkloc
