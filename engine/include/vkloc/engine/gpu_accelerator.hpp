// vkloc: a Vulkan device as the Localizer's Accelerator: keyframes rendered by GpuRenderer, live
// stages and alignment by GpuEdgeStages. No Vulkan types are exposed.
#pragma once

#include <memory>

#include "vkloc/engine/gpu.hpp"
#include "vkloc/engine/gpu_edges.hpp"
#include "vkloc/track/edge_backend.hpp"

namespace vkloc {

/// EdgeTrackingBackend over GpuEdgeStages: the live frame's distance fields and the keyframe's
/// point lists stay on the device; trackFrame's reductions run there. Used by one thread at a time.
class GpuEdgeTrackingBackend final : public EdgeTrackingBackend {
 public:
  /// GpuEdgeStages::create's errors.
  static Result<std::unique_ptr<GpuEdgeTrackingBackend>> create(std::shared_ptr<GpuContext> context,
                                                                const PinholeCamera& camera,
                                                                const LiveFrameOptions& options);
  /// Builds every level of the options given to create() whatever `levels` asks (one recorded
  /// command sequence), and returns that count.
  Result<int> setLiveImage(const ImageU8& gray, int levels) override;
  Status setKeyframe(const EdgeReference& keyframe) override;
  Result<TrackResult> align(const EdgeReference& points, const Pose& T_world_camera_guess,
                            const EdgeTrackerOptions& options) override;
  std::string describe() const override;
  /// The stages (for their timings and read-backs).
  GpuEdgeStages& stages() { return *stages_; }

 private:
  explicit GpuEdgeTrackingBackend(std::unique_ptr<GpuEdgeStages> stages) : stages_(std::move(stages)) {}
  std::unique_ptr<GpuEdgeStages> stages_;
  const EdgeReference* keyframe_ = nullptr;  ///< Whose point lists are resident (setKeyframe).
  bool ready_ = false;
};

/// The Accelerator of `context`'s device. Null context: kInvalidArgument.
Result<std::shared_ptr<Accelerator>> makeGpuAccelerator(std::shared_ptr<GpuContext> context);

}  // namespace vkloc
