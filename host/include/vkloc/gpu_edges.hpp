// vkloc: the edge stages of edge-alignment tracking on the GPU (Vulkan compute). The results
// follow the CPU backend (edges.hpp, edge_tracker.hpp) on the same layouts; no Vulkan types are
// exposed.
//
// Live image (processLiveImage), per pyramid level, resident on the device:
//   gray -> [1 3 3 1]/8 pyramid -> Sobel/8 -> contrast quantile (exact radix select over the
//   magnitude's float bits, three histogram passes on the GPU, nothing read back) -> thresholds
//   -> non-maximum suppression -> hysteresis (passes over the weak candidates until one changes
//   nothing; the only host round trip) -> jump flooding JFA+2 from step 2^ceil(log2(truncation))
//   -> truncated distance -> gradient (G_u, G_v).
// Tracking (residuals, accumulate): per reference point the residual and the 29 values of the
// normal equations (EdgeNormalEquations), reduced on the GPU into per-workgroup partials that
// the host sums in double.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vkloc/edge_tracker.hpp"
#include "vkloc/edges.hpp"
#include "vkloc/gpu.hpp"

namespace vkloc {

/// Device time of one stage of the last call, summed over levels and submissions.
struct GpuStageTiming {
  std::string stage;  ///< e.g. "sobel", "jfa".
  double ms = 0;      ///< Milliseconds (GPU timestamps; host wall time where they are missing).
};

/// Edge stages on the GPU for one camera. Not thread-safe; one live frame and one reference are
/// resident at a time.
class GpuEdgeStages {
 public:
  /// Allocates the per-level images for `camera` (levels as buildLiveFrame: a level is built
  /// while the previous one is at least 16x16). kInvalidArgument for a bad camera or options,
  /// kGpuError when the device lacks a needed format (r32f / rg32f / r32ui storage images) or
  /// memory.
  static Result<std::unique_ptr<GpuEdgeStages>> create(std::shared_ptr<GpuContext> context, const PinholeCamera& camera,
                                                       const LiveFrameOptions& options = {});
  ~GpuEdgeStages();
  GpuEdgeStages(const GpuEdgeStages&) = delete;
  GpuEdgeStages& operator=(const GpuEdgeStages&) = delete;

  /// Number of pyramid levels built per live image.
  int levelCount() const;
  /// Intrinsics of a level (pyramidCamera); level must be in [0, levelCount()).
  PinholeCamera levelCamera(int level) const;

  /// Runs the live-image stages on an 8-bit gray image (pixels 0..255) of the camera's size;
  /// the results stay on the device. kInvalidArgument for a wrong size or channel count.
  Status processLiveImage(const ImageU8& gray);

  /// Reads the last live frame back: per level camera, gray, edges (255 = edge) and distance
  /// field, as buildLiveFrame returns them. kInvalidArgument before processLiveImage.
  Result<LiveFrame> readLiveFrame();

  /// Hysteresis passes run per level in the last processLiveImage (the last one changed nothing
  /// unless the bound of 60 passes, 10 submissions of 6, was hit: weak pixels not reached by
  /// then stay non-edges).
  std::vector<int> lastHysteresisPasses() const;

  /// Uploads the reference's edge points (reference camera frame, metres); replaces the
  /// previous reference. An empty list is allowed (every reduction is then zero).
  Status setReference(const std::vector<EdgePoint>& points);
  Status setReference(const EdgeReference& reference) { return setReference(reference.points); }

  /// Residual per reference point at T_camera_ref on `level` (pixels), kInvalidResidual where
  /// the point does not contribute (rules of evaluateEdgePoint). kInvalidArgument for a bad
  /// level or pose or before processLiveImage.
  Result<std::vector<float>> residuals(const Pose& T_camera_ref, int level);

  /// Normal equations (layout EdgeNormalEquations) over the valid points with weights
  /// tDistributionWeight(r, sigma_px, nu). kInvalidArgument as residuals(), or for
  /// sigma_px <= 0 or nu <= 0.
  Result<EdgeNormalEquations> accumulate(const Pose& T_camera_ref, int level, double sigma_px, double nu);

  /// Per-stage device times of the last processLiveImage / residuals / accumulate call.
  const std::vector<GpuStageTiming>& lastTimings() const;

  struct Impl;

 private:
  explicit GpuEdgeStages(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkloc
