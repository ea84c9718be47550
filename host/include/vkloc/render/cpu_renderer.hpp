// vkloc: the CPU reference renderer: a scanline rasterizer with the GPU renderer's conventions,
// the test oracle of every GPU render and the renderer when no Vulkan device is there.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/renderer.hpp"

namespace vkloc {

/// CPU reference renderer: scanline rasterizer with the same conventions as the GPU renderer
/// (pixel-centre sampling, top-left fill rule, perspective-correct attributes, trilinear
/// mip-mapped REPEAT texture sampling with a per-quad level of detail, nearest depth wins).
/// Slow; meant as a test oracle. Builds the mip chains of the model's textures on every call
/// (CpuRenderer builds them once).
Result<RenderOutput> renderReference(const Model& model, const PinholeCamera& camera, const Pose& T_world_camera,
                                     const RenderSettings& settings = {});

/// renderReference behind the Renderer interface, on its own copy of the model and of its
/// textures' mip chains.
class CpuRenderer final : public Renderer {
 public:
  /// kInvalidArgument (validateModel's message) for an invalid model.
  static Result<std::unique_ptr<CpuRenderer>> create(const Model& model);
  Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera,
                              const RenderSettings& settings) override;
  std::string describe() const override;

 private:
  CpuRenderer(std::shared_ptr<const Model> model, std::shared_ptr<const std::vector<std::vector<Texture>>> mip_levels)
      : model_(std::move(model)), mip_levels_(std::move(mip_levels)) {}
  std::shared_ptr<const Model> model_;
  /// Levels 1.. of each of model_->textures (buildMipLevels); empty for unused textures.
  std::shared_ptr<const std::vector<std::vector<Texture>>> mip_levels_;
};

/// A RendererFactory making CpuRenderers.
RendererFactory cpuRendererFactory();

}  // namespace vkloc
