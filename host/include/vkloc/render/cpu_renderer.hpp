// vkloc: the CPU reference renderer: a scanline rasterizer with the GPU renderer's conventions,
// the test oracle of every GPU render and the renderer when no Vulkan device is there.
#pragma once

#include <memory>
#include <string>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/renderer.hpp"

namespace vkloc {

/// CPU reference renderer: scanline rasterizer with the same conventions as the GPU renderer
/// (pixel-centre sampling, top-left fill rule, perspective-correct attributes, bilinear
/// repeat texture sampling, nearest depth wins). Slow; meant as a test oracle.
Result<RenderOutput> renderReference(const Model& model, const PinholeCamera& camera, const Pose& T_world_camera,
                                     const RenderSettings& settings = {});

/// renderReference behind the Renderer interface, on its own copy of the model.
class CpuRenderer final : public Renderer {
 public:
  /// kInvalidArgument (validateModel's message) for an invalid model.
  static Result<std::unique_ptr<CpuRenderer>> create(const Model& model);
  Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera,
                              const RenderSettings& settings) override;
  std::string describe() const override;

 private:
  explicit CpuRenderer(std::shared_ptr<const Model> model) : model_(std::move(model)) {}
  std::shared_ptr<const Model> model_;
};

/// A RendererFactory making CpuRenderers.
RendererFactory cpuRendererFactory();

}  // namespace vkloc
