#include "vkloc/engine/gpu_accelerator.hpp"

#include <fmt/format.h>

#include "vkloc/engine/gpu_remap.hpp"

namespace vkloc {

Result<std::unique_ptr<GpuEdgeTrackingBackend>> GpuEdgeTrackingBackend::create(std::shared_ptr<GpuContext> context,
                                                                               const PinholeCamera& camera,
                                                                               const LiveFrameOptions& options) {
  LiveFrameOptions live = options;
  live.keep_intermediate = false;
  auto stages = GpuEdgeStages::create(std::move(context), camera, live);
  if (!stages.ok()) return stages.error();
  return std::unique_ptr<GpuEdgeTrackingBackend>(new GpuEdgeTrackingBackend(std::move(stages).value()));
}

Result<int> GpuEdgeTrackingBackend::setLiveImage(const ImageU8& gray, int /*levels*/) {
  ready_ = false;
  VKLOC_TRY_STATUS(stages_->processLiveImage(gray));
  ready_ = true;
  return stages_->levelCount();
}

Status GpuEdgeTrackingBackend::setKeyframe(const EdgeReference& keyframe) {
  keyframe_ = nullptr;
  VKLOC_TRY_STATUS(stages_->setLevelPoints(keyframe));
  keyframe_ = &keyframe;
  return Status::success();
}

Result<TrackResult> GpuEdgeTrackingBackend::align(const EdgeReference& points, const Pose& T_world_camera_guess,
                                                  const EdgeTrackerOptions& options) {
  if (!ready_) return makeError(ErrorCode::kInvalidArgument, "GpuEdgeTrackingBackend: align before setLiveImage");
  // The keyframe's own lists are resident (same storage); any other list is uploaded per level.
  GpuEdgeAlignment backend(*stages_, stages_->hasLevelPoints() && &points == keyframe_ ? keyframe_ : nullptr);
  return trackFrame(points, backend, T_world_camera_guess, options);
}

std::string GpuEdgeTrackingBackend::describe() const { return "Vulkan"; }

namespace {

class GpuAccelerator final : public Accelerator {
 public:
  explicit GpuAccelerator(std::shared_ptr<GpuContext> context) : context_(std::move(context)) {}
  std::string describe() const override {
    return fmt::format("{} ({})", context_->device().name, context_->device().type);
  }
  bool isCpuDriver() const override { return context_->device().type == "cpu"; }
  Result<std::unique_ptr<Renderer>> createRenderer(const Model& model) override {
    auto renderer = GpuRenderer::create(context_, model);
    if (!renderer.ok()) return renderer.error();
    return std::unique_ptr<Renderer>(std::move(renderer).value());
  }
  Result<std::unique_ptr<EdgeTrackingBackend>> createEdgeBackend(const PinholeCamera& camera,
                                                                 const LiveFrameOptions& options) override {
    auto backend = GpuEdgeTrackingBackend::create(context_, camera, options);
    if (!backend.ok()) return backend.error();
    return std::unique_ptr<EdgeTrackingBackend>(std::move(backend).value());
  }
  Result<std::unique_ptr<ImageRemapper>> createRemapper(const RemapTable& table,
                                                        RemapInterpolation interpolation) override {
    auto remap = GpuRemap::create(context_, table, interpolation);
    if (!remap.ok()) return remap.error();
    return std::unique_ptr<ImageRemapper>(std::move(remap).value());
  }

 private:
  std::shared_ptr<GpuContext> context_;
};

}  // namespace

Result<std::shared_ptr<Accelerator>> makeGpuAccelerator(std::shared_ptr<GpuContext> context) {
  if (!context) return makeError(ErrorCode::kInvalidArgument, "makeGpuAccelerator: no GPU context");
  return std::shared_ptr<Accelerator>(std::make_shared<GpuAccelerator>(std::move(context)));
}

}  // namespace vkloc
