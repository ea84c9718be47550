// vkloc: the edge stages of edge-alignment tracking on the GPU (Vulkan compute). The results
// follow the CPU backend (edges.hpp, edge_tracker.hpp) on the same layouts; no Vulkan types are
// exposed.
//
// Live image (processLiveImage), per pyramid level, resident on the device:
//   gray -> [1 3 3 1]/8 pyramid -> Sobel/8 -> contrast quantile (exact radix select over the
//   magnitude's float bits, three histogram passes on the GPU, nothing read back) -> thresholds
//   -> non-maximum suppression -> hysteresis (passes over the weak candidates until one changes
//   nothing; the only host round trip) -> truncated distance (GpuDistanceMethod: jump flooding
//   JFA+2 from step 2^ceil(log2(truncation)), or the exact separable transform) -> sub-pixel
//   edge lines (LiveLevel::edge_lines, when LiveFrameOptions::subpixel_edges), which
//   residuals/accumulate use as the CPU does. The distance gradient (G_u, G_v) is not stored:
//   residuals/accumulate compute it from the distances around each point, and readLiveFrame
//   from the read-back distance (computeDistanceGradient).
// On CPU drivers (lavapipe) the Sobel pass stores only the quantile's samples (NMS and edge
// lines recompute the gradient from the gray image) and the edge lines visit only the row spans
// near an edge, which the separable transform lists.
// Tracking (residuals, accumulate): per reference point the residual and the 29 values of the
// normal equations (EdgeNormalEquations), reduced on the GPU into per-workgroup partials that
// the host sums in double.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "vkloc/engine/gpu.hpp"
#include "vkloc/track/edge_tracker.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// Device time of one stage of the last call, summed over levels and submissions.
struct GpuStageTiming {
  std::string stage;  ///< e.g. "sobel", "jfa".
  double ms = 0;      ///< Milliseconds (GPU timestamps; host wall time where they are missing).
};

/// How the GPU computes a level's truncated distance field.
enum class GpuDistanceMethod {
  kAuto,  ///< kSeparable on CPU drivers (lavapipe), kJumpFlooding on GPUs.
  /// JFA+2: log2(truncation) + 3 passes of 9 gathers per pixel (0.001 % of the pixels off by
  /// at most 0.3 px); every pass fully parallel.
  kJumpFlooding,
  /// Exact (the CPU's values): one sequential pass per column, then per pixel the minimum over
  /// 2R + 1 row neighbours from shared memory, R = ceil(truncation) - 1 <= 64.
  kSeparable,
};
const char* gpuDistanceMethodName(GpuDistanceMethod method);

/// How the per-pixel kernels are shaped (pixels and rows per invocation, Sobel recomputed in
/// NMS, grid sizes); the results are the same either way.
enum class GpuKernelShapes {
  kAuto,  ///< By the device type: kCpu on CPU drivers (lavapipe), kGpu on GPUs.
  kGpu,   ///< One pixel per invocation, Sobel stored for NMS, dense edge lines, wide grids.
  kCpu,   ///< 8 pixels x 16 rows per invocation, Sobel recomputed, edge lines over listed spans.
};

/// Edge stages on the GPU for one camera. Not thread-safe; one live frame and one reference are
/// resident at a time.
class GpuEdgeStages {
 public:
  /// Allocates the per-level images for `camera` (levels as buildLiveFrame: a level is built
  /// while the previous one is at least 16x16). kInvalidArgument for a bad camera or options,
  /// kGpuError when the device lacks a needed format (r32f / rg32f / r32ui storage images) or
  /// memory; kInvalidArgument for kSeparable with truncation_px > 65.
  /// Kernel shapes follow the device type unless `kernel_shapes` chooses (GpuKernelShapes).
  static Result<std::unique_ptr<GpuEdgeStages>> create(std::shared_ptr<GpuContext> context, const PinholeCamera& camera,
                                                       const LiveFrameOptions& options = {},
                                                       GpuDistanceMethod distance_method = GpuDistanceMethod::kAuto,
                                                       GpuKernelShapes kernel_shapes = GpuKernelShapes::kAuto);
  ~GpuEdgeStages();
  GpuEdgeStages(const GpuEdgeStages&) = delete;
  GpuEdgeStages& operator=(const GpuEdgeStages&) = delete;

  /// Number of pyramid levels built per live image.
  int levelCount() const;
  /// The distance method in use (kAuto resolved).
  GpuDistanceMethod distanceMethod() const;
  /// Intrinsics of a level (pyramidCamera); level must be in [0, levelCount()).
  PinholeCamera levelCamera(int level) const;

  /// Runs the live-image stages on an 8-bit gray image (pixels 0..255) of the camera's size;
  /// the results stay on the device. kInvalidArgument for a wrong size or channel count.
  Status processLiveImage(const ImageU8& gray);

  /// Reads the last live frame back: per level camera, gray, edges (255 = edge), distance field
  /// and edge lines (with subpixel_edges), as buildLiveFrame returns them. kInvalidArgument
  /// before processLiveImage.
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

  /// residuals(), the t-distribution scale of those residuals (estimateTDistributionScale with
  /// nu, scale_iterations, min_sigma_px; float on the device) and the normal equations weighted
  /// with it, in one submission. kInvalidArgument as accumulate.
  Result<EdgeEvaluation> evaluate(const Pose& T_camera_ref, int level, double nu, int scale_iterations,
                                  double min_sigma_px);

  /// Uploads one point list per pyramid level (level k: edgePointsForLevel(reference, k)) in
  /// one buffer; residuals/accumulate on level k then use level k's list, so a tracker switches
  /// levels without uploading again. Replaces the previous reference (as setReference does).
  Status setLevelPoints(const EdgeReference& reference);
  /// True while the lists of the last setLevelPoints are resident (no setReference since).
  bool hasLevelPoints() const;

  /// Fraction (0..1) of the pixels of `level` of the last live frame whose distance to the
  /// nearest edge is below threshold_px (that level's pixels). kInvalidArgument for a bad level
  /// or before processLiveImage.
  Result<double> nearEdgeFraction(int level, double threshold_px);

  /// Distance truncation of every level, pixels.
  float truncationPx() const;

  /// Per-stage device times of the last processLiveImage / residuals / accumulate / evaluate
  /// call with setStageTimings(true) (and timestamp support); otherwise one entry,
  /// "submission (host)", the host wall time of its submissions.
  const std::vector<GpuStageTiming>& lastTimings() const;
  /// Timestamps between stages, off by default: on CPU drivers each one drains the queue and
  /// slows the frame (README, "Performance").
  void setStageTimings(bool enabled);

  struct Impl;

 private:
  explicit GpuEdgeStages(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// EdgeAlignmentBackend over GpuEdgeStages: the live frame's distance fields stay on the
/// device and trackFrame's residuals and normal equations are computed there. Holds a
/// reference to `stages`, which must outlive it and hold a processed live image
/// (processLiveImage) while trackFrame runs. setPoints uploads the list (replacing the stages'
/// reference points), except when `resident` is the reference last given to
/// stages.setLevelPoints and the list is one of its level lists (same storage): those are on the
/// device already and used per level as they are.
class GpuEdgeAlignment final : public EdgeAlignmentBackend {
 public:
  explicit GpuEdgeAlignment(GpuEdgeStages& stages, const EdgeReference* resident = nullptr)
      : stages_(&stages), resident_(resident) {}
  int levelCount() const override;
  PinholeCamera levelCamera(int level) const override;
  float truncationPx(int level) const override;
  Status setPoints(const std::vector<EdgePoint>& points) override;
  Result<std::vector<float>> residuals(int level, const Pose& T_camera_ref) override;
  Result<EdgeNormalEquations> accumulate(int level, const Pose& T_camera_ref, double sigma_px, double nu) override;
  Result<EdgeEvaluation> evaluate(int level, const Pose& T_camera_ref, double nu, int scale_iterations,
                                  double min_sigma_px) override;
  Result<double> nearEdgeFraction(int level, double threshold_px) override;

 private:
  GpuEdgeStages* stages_;
  const EdgeReference* resident_;
};

}  // namespace vkloc
