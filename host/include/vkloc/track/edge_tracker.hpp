// vkloc: edge-alignment pose tracking (seed paper 000, sec. IV-C, eqs. 9-15), CPU backend.
//
// The reference's 3D edge points P_ref (reference camera frame) are projected into the live
// image with the relative pose T_camera_ref, and the residual of a point is the live image's
// distance field at the projection, r = V(pi(T_camera_ref P_ref)) (eq. 12). Gauss-Newton on
// SE(3) with t-distribution weights (nu = 5, scale re-estimated every iteration as in Kerl et
// al., the paper's ref. [9]) minimises sum w r^2 (eq. 13-14), coarse to fine over the pyramid.
//
// Tangent order and perturbation: se3.hpp. T_camera_ref is updated as
// T_camera_ref <- expSE3(delta) * T_camera_ref with delta = [rho; phi] in the live camera frame,
// so a point's Jacobian is (eq. 15 in this convention)
//   J = [G_u G_v] * [fx/z 0 -fx x/z^2; 0 fy/z -fy y/z^2] * [I | -hat(p)],  p = T_camera_ref P_ref.
// Poses are compounded as T_world_camera = T_world_ref * T_camera_ref^-1 (eqs. 4-5).
//
// Stages (each replaceable by a GPU kernel on the same data): evaluateEdgeResiduals (one float
// per point), estimateTDistributionScale (a few reductions over the residuals),
// accumulateEdgeNormalEquations (one reduction to 29 numbers), then the 6x6 solve on the host.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// Layout of the reduced normal equations, as a GPU reduction writes them (29 values):
///  [0, 21): upper triangle of H = sum w J^T J, row-major: (0,0) (0,1) .. (0,5) (1,1) .. (5,5)
///  [21, 27): g = sum w J^T r (J is 1x6, [rho; phi] order)
///  27: sum w r^2 (pixels^2)
///  28: number of points that contributed (valid projection, distance below truncation)
constexpr int kEdgeNormalEquationSize = 29;
constexpr int kEdgeNormalGradientOffset = 21;
constexpr int kEdgeNormalCostIndex = 27;
constexpr int kEdgeNormalCountIndex = 28;
using EdgeNormalEquations = std::array<double, kEdgeNormalEquationSize>;

/// Index of H(row, col), row <= col, in EdgeNormalEquations.
constexpr int edgeNormalIndex(int row, int col) { return row * 6 - row * (row - 1) / 2 + (col - row); }

/// Unpacks the 29 values into H (symmetric 6x6) and g.
void unpackEdgeNormalEquations(const EdgeNormalEquations& packed, Matrix6d& H, Vector6d& g);

/// Marks a residual of a point that does not contribute: projects behind the camera, outside
/// the image (bilinear footprint) or where the distance is truncated.
constexpr float kInvalidResidual = -1.0f;

/// One point's residual and Jacobian (the per-thread work of the GPU kernels).
struct EdgePointEvaluation {
  bool valid = false;                    ///< False when the point does not contribute.
  double u = 0;                          ///< Projection in the level image, pixels.
  double v = 0;                          ///< Projection, pixels.
  double residual = 0;                   ///< Bilinear distance at (u, v), pixels.
  Vector6d jacobian = Vector6d::Zero();  ///< d residual / d delta, [rho; phi] order (pixels per m, per rad).
};

/// Evaluates one point at T_camera_ref on `level` (its camera and distance field): projection,
/// bilinear distance and gradient (G_u, G_v), and the Jacobian when with_jacobian. Invalid
/// when z <= 1e-6 m, the 2x2 bilinear footprint leaves the image or any of its four distances
/// is truncated.
EdgePointEvaluation evaluateEdgePoint(const EdgePoint& point, const Pose& T_camera_ref, const LiveLevel& level,
                                      bool with_jacobian);

/// Residuals of all points (pixels), kInvalidResidual for points that do not contribute.
std::vector<float> evaluateEdgeResiduals(const std::vector<EdgePoint>& points, const Pose& T_camera_ref,
                                         const LiveLevel& level);

/// Scale sigma (pixels) of the t-distribution fitted to the valid residuals (Kerl et al.):
/// iterates sigma^2 <- mean(r^2 (nu + 1) / (nu + r^2 / sigma^2)) `iterations` times from
/// sigma^2 = mean(r^2). At least min_sigma_px; min_sigma_px when no residual is valid.
double estimateTDistributionScale(const std::vector<float>& residuals, double nu, int iterations,
                                  double min_sigma_px = 0.05);

/// t-distribution weight (nu + 1) / (nu + (r / sigma)^2).
inline double tDistributionWeight(double r, double sigma, double nu) {
  const double s = r / sigma;
  return (nu + 1.0) / (nu + s * s);
}

/// Accumulates the normal equations over all valid points at T_camera_ref with weights
/// tDistributionWeight(r, sigma_px, nu). Layout: EdgeNormalEquations.
EdgeNormalEquations accumulateEdgeNormalEquations(const std::vector<EdgePoint>& points, const Pose& T_camera_ref,
                                                  const LiveLevel& level, double sigma_px, double nu);

/// A Gaussian prior on the live camera's attitude: R_world_camera_true = R_world_camera *
/// expSO3(phi), phi ~ N(0, covariance) in the camera frame (rad^2; the rotation block of a
/// MotionPrediction's covariance).
struct RotationPrior {
  Eigen::Matrix3d R_world_camera = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Identity();
};

/// Options of trackFrame. Why the defaults are what they are (the sequences and frames they were
/// measured on) is in the README, "Tracker defaults".
struct EdgeTrackerOptions {
  double nu = 5.0;           ///< Degrees of freedom of the t-distribution weights.
  int scale_iterations = 5;  ///< Fixed-point iterations of the scale per GN iteration.
  int max_iterations = 30;   ///< Gauss-Newton iterations per pyramid level.
  /// First (coarsest) level of the plain coarse-to-fine pass; -1 = the live frame's coarsest.
  /// The wider basin comes from the far-points-first hypothesis (far_first_coarsest_level).
  int coarsest_level = 0;
  int finest_level = 0;  ///< Last level used (0 = full resolution).
  /// Parallax-ordered second hypothesis: besides the plain coarse-to-fine pass from the guess,
  /// one that first aligns only the points whose depth is at least this quantile (0..1) of the
  /// level's point depths, then all points (0 = off). Near points move most when the camera
  /// translates and alias onto the wrong texture edges; far ones first pull the pose into the
  /// basin. The pose with more finest-level inliers wins.
  double far_first_depth_quantile = 0.3;
  /// Coarsest level of the far-points-first hypothesis; -1 = coarsest_level.
  int far_first_coarsest_level = 1;
  /// Skip the far-points-first hypothesis when the plain pass already has at least this
  /// fraction of all finest-level points as inliers (> 1 = never skip).
  double far_first_skip_inlier_ratio = 0.85;
  /// Stop a level when |delta| (m and rad combined) falls below this (10 um / 10 urad: 0.005 px
  /// at 1.4 m with fx = 700).
  double min_step = 1e-5;
  /// Stop a level when an accepted step lowers the robust cost by less than this fraction.
  double min_cost_decrease = 1e-3;
  double initial_damping = 1e-4;     ///< Levenberg damping (relative to diag(H)) after a rejected step.
  double max_damping = 1e4;          ///< Give up a level when the damping exceeds this.
  double inlier_threshold_px = 1.5;  ///< A valid residual below this (finest level pixels) is an inlier.
  double min_inlier_ratio = 0.4;     ///< Lost below this inliers / points projected into the image.
  /// Lost below this (inlier_ratio - chance) / (1 - chance), chance = fraction of live pixels
  /// within inlier_threshold_px of an edge (dense edge maps make any pose look good).
  double min_inlier_ratio_above_chance = 0.25;
  /// Lost when the RMS spread of the projected points about their centroid changes by more than
  /// this factor from the reference view (a pose that shrinks the points onto a few edges).
  double max_spread_change = 1.5;
  double min_visible_ratio = 0.5;     ///< Lost below this (points projected into the image) / (all points).
  double max_mean_residual_px = 0.8;  ///< Lost above this mean inlier residual, finest level pixels.
  int min_points = 30;                ///< Lost with fewer points projected into the image.
  double max_translation_m = 1e6;     ///< Lost when the correction of the guess exceeds this (m).
  /// Attitude the camera is known to have from elsewhere (a gyro-propagated filter), added to
  /// the alignment's cost as a Gaussian on the rotation (a MAP estimate). Edges fix the rotation
  /// well only where the view is wide: through a narrow view a small rotation and a translation
  /// across it move the edges alike, and the alignment slides along that valley. nullopt = none.
  std::optional<RotationPrior> rotation_prior;
};

/// Checks ranges of EdgeTrackerOptions; kInvalidArgument naming the field otherwise.
Status validateEdgeTrackerOptions(const EdgeTrackerOptions& options);

/// Tracking state decided from TrackQuality (never by silently diverging).
enum class TrackingState {
  kTracking,  ///< The alignment is trusted.
  kLost,      ///< No trusted pose.
  kInertial,  ///< Localizer only: the pose is the IMU prediction (see InertialAiding).
  /// Localizer only: searching for a first pose (global initialization), none found yet.
  kInitializing,
  /// Localizer only: the pose was found anew from the keyframe database and verified (after a
  /// loss, or the first pose of a global initialization); trusted as kTracking is.
  kRelocalized,
};

/// "tracking" | "lost" | "inertial" | "initializing" | "relocalized" (the frames log's state column).
const char* trackingStateName(TrackingState state);

/// How well the final pose explains the live edges, measured on the finest level used.
struct TrackQuality {
  double inlier_ratio = 0;         ///< Inliers / points projecting inside the image (0..1).
  double mean_residual_px = 0;     ///< Mean residual of the inliers, pixels of the finest level used.
  double scale_px = 0;             ///< Final t-distribution scale sigma, pixels.
  double chance_inlier_ratio = 0;  ///< Fraction of live pixels within inlier_threshold_px of an edge.
  double spread_ratio = 0;         ///< RMS spread of projected points, live / reference view.
  double visible_ratio = 0;        ///< Points projecting inside the image / all points of the level (0..1).
  int points_in_image = 0;         ///< Points projecting inside the finest level's image.
  int points_used = 0;             ///< Points with a valid residual (not truncated) at the end.
  int iterations = 0;              ///< Gauss-Newton iterations over all levels.
  /// inlier_ratio of the points of each kind: [texture, occlusion, crease, near background,
  /// near a back face] (the first three without either modifier, the fourth without
  /// kEdgeBackFace; 0 without points).
  std::array<double, 5> kind_inlier_ratio{};
  std::array<int, 5> kind_points_in_image{};  ///< points_in_image per kind, as kind_inlier_ratio.
};

/// Output of trackFrame.
struct TrackResult {
  Pose T_world_camera = Pose::Identity();  ///< Estimated live camera pose.
  Pose T_camera_ref = Pose::Identity();    ///< Estimated reference -> live camera transform.
  /// Covariance of xi (m^2, rad^2, [rho; phi]) with T_world_camera_true = T_world_camera *
  /// expSE3(xi), xi in the live camera frame: sigma^2 H^-1 at the final pose (finest level), the
  /// edges' information alone (with a rotation prior it belongs to T_world_camera_edges).
  Matrix6d covariance = Matrix6d::Zero();
  /// With a rotation prior: the pose the edges alone say, to first order (the prior's information
  /// taken back out of T_world_camera, whose information is that of `covariance` plus the
  /// prior's). A filter that predicted the prior fuses this pose with `covariance`, so that its
  /// attitude is not counted twice. nullopt without a prior (it is then T_world_camera).
  std::optional<Pose> T_world_camera_edges;
  TrackQuality quality;                        ///< Quality figures.
  TrackingState state = TrackingState::kLost;  ///< kTracking when quality passes the thresholds.
};

/// The data-parallel work of trackFrame, behind which the live frame lives: a CPU backend over a
/// LiveFrame (CpuEdgeAlignment) or a GPU backend whose distance fields stay on the device (an
/// adapter over GpuEdgeStages maps levelCount/levelCamera one to one, setPoints to
/// setReference(points), residuals(level, T) to residuals(T, level) and accumulate(level, T,
/// sigma, nu) to accumulate(T, level, sigma, nu)). The Gauss-Newton loop, scale estimation,
/// step control and the quality decision run on the host in trackFrame and only see these
/// results, so every backend gives the same tracking behaviour up to float rounding.
///
/// Call order: trackFrame calls setPoints(level's points) before the residuals/accumulate
/// calls of each level, so a backend uploads a point list at most once per level and frame.
/// Levels are 0 (full resolution) .. levelCount() - 1. A backend is not thread-safe.
/// Result of EdgeAlignmentBackend::evaluate.
struct EdgeEvaluation {
  std::vector<float> residuals;           ///< Per point, pixels; kInvalidResidual where invalid.
  double sigma_px = 0;                    ///< t-distribution scale of these residuals, pixels.
  std::optional<EdgeNormalEquations> eq;  ///< Normal equations weighted with sigma_px, if computed.
};

class EdgeAlignmentBackend {
 public:
  virtual ~EdgeAlignmentBackend() = default;

  /// Number of pyramid levels of the live frame (0 when there is no live frame).
  virtual int levelCount() const = 0;

  /// Intrinsics of level `level` (pyramidCamera of the live camera); precondition:
  /// 0 <= level < levelCount().
  virtual PinholeCamera levelCamera(int level) const = 0;

  /// Distance truncation of level `level`, pixels of that level (residuals are < this).
  virtual float truncationPx(int level) const = 0;

  /// Replaces the reference points (reference camera frame, metres) the next calls use; the
  /// backend keeps its own copy. An empty list is allowed (every reduction is then zero).
  virtual Status setPoints(const std::vector<EdgePoint>& points) = 0;

  /// Residual per point at T_camera_ref on `level` (pixels, rules of evaluateEdgePoint),
  /// kInvalidResidual where a point does not contribute. kInvalidArgument for a bad level.
  virtual Result<std::vector<float>> residuals(int level, const Pose& T_camera_ref) = 0;

  /// Normal equations (EdgeNormalEquations layout) over the valid points at T_camera_ref on
  /// `level` with weights tDistributionWeight(r, sigma_px, nu). kInvalidArgument for a bad
  /// level, sigma_px <= 0 or nu <= 0.
  virtual Result<EdgeNormalEquations> accumulate(int level, const Pose& T_camera_ref, double sigma_px, double nu) = 0;

  /// One Gauss-Newton evaluation at T_camera_ref on `level`: the residuals, the t-distribution
  /// scale estimated from them (estimateTDistributionScale with nu, scale_iterations and
  /// min_sigma_px) and, when the backend computes them in the same pass, the normal equations
  /// with that scale (else nullopt: the tracker calls accumulate when it needs them). The default
  /// runs residuals() and estimates the scale on the host; a GPU backend does all three in one
  /// submission (one host round trip per Gauss-Newton iteration instead of two).
  virtual Result<EdgeEvaluation> evaluate(int level, const Pose& T_camera_ref, double nu, int scale_iterations,
                                          double min_sigma_px);

  /// Fraction (0..1) of the pixels of `level` whose distance to the nearest live edge is below
  /// threshold_px (that level's pixels): the chance that a random projection is an inlier,
  /// used by the lost decision. kInvalidArgument for a bad level.
  virtual Result<double> nearEdgeFraction(int level, double threshold_px) = 0;
};

/// EdgeAlignmentBackend over a LiveFrame in host memory (evaluateEdgeResiduals,
/// accumulateEdgeNormalEquations). Holds a reference to `live`, which must outlive it and
/// stay unchanged while it is used.
class CpuEdgeAlignment final : public EdgeAlignmentBackend {
 public:
  explicit CpuEdgeAlignment(const LiveFrame& live) : live_(&live) {}
  int levelCount() const override;
  PinholeCamera levelCamera(int level) const override;
  float truncationPx(int level) const override;
  Status setPoints(const std::vector<EdgePoint>& points) override;
  Result<std::vector<float>> residuals(int level, const Pose& T_camera_ref) override;
  Result<EdgeNormalEquations> accumulate(int level, const Pose& T_camera_ref, double sigma_px, double nu) override;
  /// Residuals and scale as the default, evaluating each point's Jacobian in the same pass; a
  /// following accumulate() at the same level and pose sums the kept Jacobians instead of
  /// evaluating the points again (the same numbers, in the same order).
  Result<EdgeEvaluation> evaluate(int level, const Pose& T_camera_ref, double nu, int scale_iterations,
                                  double min_sigma_px) override;
  Result<double> nearEdgeFraction(int level, double threshold_px) override;

 private:
  Status checkLevel(int level) const;
  const LiveFrame* live_;
  std::vector<EdgePoint> points_;
  /// The points evaluated by the last evaluate(): level, pose, and per point validity, residual
  /// and Jacobian (invalid when the points or the frame changed since).
  struct Evaluated {
    bool valid = false;
    int level = -1;
    Pose T_camera_ref = Pose::Identity();
    std::vector<uint8_t> point_valid;
    std::vector<double> residual;
    std::vector<Vector6d> jacobian;
  };
  Evaluated evaluated_;
};

/// Aligns the reference's edge points (level k's points on live level k) with the live frame's
/// distance fields, starting from
/// T_world_camera_guess. The live frame must come from the camera the reference is projected
/// into (its levels carry their intrinsics). Returns kInvalidArgument for an invalid guess,
/// an empty live frame, a reference without points or bad options; a failed alignment is not
/// an error but state kLost.
Result<TrackResult> trackFrame(const EdgeReference& reference, const LiveFrame& live, const Pose& T_world_camera_guess,
                               const EdgeTrackerOptions& options = {});

/// trackFrame on any backend (the one above is this with CpuEdgeAlignment(live)). The
/// backend's levels play the live frame's; it must hold a live frame of the camera the
/// reference is projected into. Same errors as above (an empty backend is kInvalidArgument);
/// a backend error is returned as is.
Result<TrackResult> trackFrame(const EdgeReference& reference, EdgeAlignmentBackend& backend,
                               const Pose& T_world_camera_guess, const EdgeTrackerOptions& options = {});

}  // namespace vkloc
