// vkloc: where the per-frame work of edge tracking runs. An EdgeTrackingBackend prepares each
// live image (pyramid, edges, distance fields) and aligns a keyframe's edge points with it
// (trackFrame). The CPU backend here works in host memory; the engine's GPU backend keeps the
// live frame and the keyframe's points on the device. The Localizer sees only this interface.
#pragma once

#include <memory>
#include <string>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/remap.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/edge_tracker.hpp"
#include "vkloc/track/live_frame.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// Live-image stages and alignment for one camera. Used by one thread at a time.
class EdgeTrackingBackend {
 public:
  virtual ~EdgeTrackingBackend() = default;

  /// Runs the live-image stages on an 8-bit gray image of the camera's size; the live frame
  /// stays in the backend until the next call. `levels`: the pyramid levels the caller's
  /// alignments will read (finest first; 0 or more than the options' levels: all of them); a
  /// backend may build more (the GPU backend builds all), and an alignment asked to start deeper
  /// than what was built starts at the deepest built level. Returns the number of levels built
  /// (fewer than asked only where the options' levels or the image's size allow no more).
  /// kInvalidArgument for a wrong size or channel count; kGpuError when a device fails.
  virtual Result<int> setLiveImage(const ImageU8& gray, int levels) = 0;

  /// Makes `keyframe` the reference whose point lists later align() calls use; a GPU backend
  /// uploads them once here. The object must stay alive and unchanged until the next
  /// setKeyframe() or the backend's destruction.
  virtual Status setKeyframe(const EdgeReference& keyframe) = 0;

  /// trackFrame of `points` (the keyframe given to setKeyframe, or a subset of it with the same
  /// T_world_ref) against the last live image from T_world_camera_guess. Errors as trackFrame's;
  /// kInvalidArgument before setLiveImage.
  virtual Result<TrackResult> align(const EdgeReference& points, const Pose& T_world_camera_guess,
                                    const EdgeTrackerOptions& options) = 0;

  /// One line naming where the stages run, for logs.
  virtual std::string describe() const = 0;
};

/// The CPU backend: buildLiveFrame into buffers reused frame after frame (no allocation once
/// warm) and trackFrame over the LiveFrame.
class CpuEdgeTrackingBackend final : public EdgeTrackingBackend {
 public:
  /// kInvalidArgument for a bad camera or options.
  static Result<std::unique_ptr<CpuEdgeTrackingBackend>> create(const PinholeCamera& camera,
                                                                const LiveFrameOptions& options);
  /// Builds min(levels, the options' levels) levels (all for 0).
  Result<int> setLiveImage(const ImageU8& gray, int levels) override;
  Status setKeyframe(const EdgeReference& keyframe) override;
  Result<TrackResult> align(const EdgeReference& points, const Pose& T_world_camera_guess,
                            const EdgeTrackerOptions& options) override;
  std::string describe() const override;
  /// The last live frame (empty before setLiveImage).
  const LiveFrame& liveFrame() const { return live_; }

 private:
  CpuEdgeTrackingBackend(const PinholeCamera& camera, const LiveFrameOptions& options)
      : camera_(camera), options_(options) {}
  PinholeCamera camera_;
  LiveFrameOptions options_;
  LiveFrame live_;
  bool ready_ = false;
};

/// A compute device that can take over the heavy stages of localization: rendering keyframes
/// and the per-frame edge stages. The engine provides one for a Vulkan device
/// (engine/gpu_accelerator.hpp); without one everything runs on the CPU. Objects it creates
/// may outlive it. Thread-safety: create*() may be called from any thread; each created object
/// is used by one thread at a time, and different objects may run concurrently.
class Accelerator {
 public:
  virtual ~Accelerator() = default;
  /// One line naming the device, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (cpu)".
  virtual std::string describe() const = 0;
  /// True when the device is itself a CPU driver (lavapipe): the host's OpenCV/Eigen stages
  /// are then faster than the device's edge stages.
  virtual bool isCpuDriver() const = 0;
  /// A renderer of `model` on the device (the model is uploaded; it may be destroyed afterwards).
  virtual Result<std::unique_ptr<Renderer>> createRenderer(const Model& model) = 0;
  /// Edge stages on the device for `camera`.
  virtual Result<std::unique_ptr<EdgeTrackingBackend>> createEdgeBackend(const PinholeCamera& camera,
                                                                         const LiveFrameOptions& options) = 0;
  /// The camera front's remap on the device (kUnsupported when the device has none).
  virtual Result<std::unique_ptr<ImageRemapper>> createRemapper(const RemapTable& /*table*/,
                                                                RemapInterpolation /*interpolation*/) {
    return makeError(ErrorCode::kUnsupported, "this device has no remap stage");
  }
};

}  // namespace vkloc
