// vkloc: frame-to-model localization. Renders the model at a predicted pose, extracts 3D edge
// points from the render (edges.hpp) and aligns them with the live image's edges
// (edge_tracker.hpp, seed paper 000 sec. IV-C). When to re-render the reference follows either
// seed 000 (every frame, at the predicted pose) or STAR (seed 001 sec. II-C: only when the view
// moved too far from the reference, tracking quality dropped, or too many frames passed).
//
// Backends per stage: the render runs on the Vulkan device when one is given (else on the CPU
// reference renderer); the live-image stages and the alignment run on the CPU (OpenCV / Eigen)
// or on the Vulkan device (GpuEdgeStages). No Vulkan types are exposed.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "vkloc/camera.hpp"
#include "vkloc/edge_tracker.hpp"
#include "vkloc/edges.hpp"
#include "vkloc/image.hpp"
#include "vkloc/inertial.hpp"
#include "vkloc/model.hpp"
#include "vkloc/pose.hpp"
#include "vkloc/render.hpp"
#include "vkloc/se3.hpp"
#include "vkloc/status.hpp"

namespace vkloc {

class GpuContext;

/// Where the live-image stages and the alignment run.
enum class LocalizerBackend {
  kAuto,    ///< Vulkan on a real GPU; CPU when the Vulkan device is itself a CPU (lavapipe) or absent.
  kVulkan,  ///< GpuEdgeStages on the Vulkan device (needs a context).
  kCpu,     ///< OpenCV / Eigen on the host.
};

/// When the reference view (render + 3D edge points) is made anew.
enum class RerenderPolicy {
  kEveryFrame,  ///< Seed 000: render at the predicted pose for every frame.
  kWhenNeeded,  ///< STAR (seed 001 sec. II-C): keep the reference while it still fits (RerenderThresholds).
};

/// How the pose guess for a frame is predicted when the caller gives none.
enum class MotionModel {
  kConstantVelocity,  ///< Last pose moved by the last inter-frame motion, scaled to the time step.
  kLastPose,          ///< The last pose as it is.
};

/// Parses "auto" | "vulkan" | "cpu"; kInvalidArgument otherwise.
Result<LocalizerBackend> parseLocalizerBackend(const std::string& name);
/// Parses "every-frame" | "when-needed"; kInvalidArgument otherwise.
Result<RerenderPolicy> parseRerenderPolicy(const std::string& name);
const char* localizerBackendName(LocalizerBackend backend);
const char* rerenderPolicyName(RerenderPolicy policy);

/// Thresholds of RerenderPolicy::kWhenNeeded; a new reference is rendered when any is exceeded.
struct RerenderThresholds {
  /// Camera moved more than this fraction of the reference's median scene depth (translation of
  /// the predicted pose relative to the reference camera).
  double max_translation_depth_ratio = 0.03;
  double max_rotation_deg = 3.0;   ///< Camera turned more than this since the reference, degrees.
  double min_inlier_ratio = 0.85;  ///< Last frame's TrackQuality::inlier_ratio fell below this.
  int max_frames = 10;             ///< This many frames were tracked against the same reference.
};

/// Inertial aiding, active once IMU readings are given (Localizer::addImu): the guess for a frame
/// is the IMU-propagated pose (InertialPredictor, fed with the accepted visual poses), a visual
/// result farther from it than the gate is rejected, and a frame whose alignment is lost or
/// rejected reports the inertial pose (state kInertial) for up to max_inertial_s after the last
/// accepted visual pose. Gate: translation <= gate_depth_ratio x scene depth + gate_sigmas x
/// sqrt(sigma_pred^2 + fit_rms^2) (InertialPrediction), rotation <= gate_rotation_deg.
struct InertialAiding {
  bool enabled = true;                    ///< Use readings given with addImu.
  Pose T_body_camera = Pose::Identity();  ///< Camera frame into the body (IMU) frame, metres.
  InertialOptions predictor;              ///< Gravity, velocity-fit window, uncertainty model.
  double gate_depth_ratio = 0.005;        ///< Translation gate floor, fraction of the median scene depth.
  double gate_sigmas = 4.0;               ///< Translation gate, prediction sigmas added to the floor.
  double gate_rotation_deg = 1.5;         ///< Rotation gate, degrees.
  double max_inertial_s = 2.0;            ///< Longest inertial-only stretch before frames are lost, seconds.
};

/// Everything the Localizer can be tuned with. Plain data; checked by Localizer::create.
struct LocalizerOptions {
  LocalizerBackend backend = LocalizerBackend::kAuto;   ///< Backend of the live stages and alignment.
  RerenderPolicy policy = RerenderPolicy::kWhenNeeded;  ///< When the reference is rendered anew.
  RerenderThresholds rerender;                          ///< Thresholds of kWhenNeeded.
  /// Near/far clip planes (metres) and back-face culling of the reference render; `outputs` is
  /// set by the Localizer (colour, depth and normals are always rendered).
  RenderSettings render;
  LiveFrameOptions live;                                ///< Live-image pyramid, edges and distance fields.
  ReferenceEdgeOptions reference;                       ///< Reference edge points (levels are set to live.levels).
  EdgeTrackerOptions tracker;                           ///< Gauss-Newton alignment and lost-frame thresholds.
  MotionModel motion = MotionModel::kConstantVelocity;  ///< Guess when the caller gives none.
  /// When a frame is lost against an old reference (kWhenNeeded), render a fresh one at the guess
  /// and align once more before reporting the frame lost.
  bool retry_lost_with_fresh_reference = true;
  /// Until the first frame is tracked after create/reset: when a frame is lost, render a new
  /// reference at the estimate and align again, up to this many times (widens the basin of
  /// convergence of the initial pose).
  int init_refinements = 4;
  /// Until the first frame is tracked after create/reset, when the first alignment is lost or
  /// below init_confident_inlier_ratio: align again from the guess turned by i x init_search_deg
  /// about the camera's x axis and j x init_search_deg about its y axis, i, j in
  /// -init_search_steps..init_search_steps, and keep the best (tracking first, then the inlier
  /// ratio). 0 steps = off. Castle-simu from 2 cm / 5 deg off: the plain alignment settles 0.7 m
  /// off at 0.45 inliers (wrong, but above min_inlier_ratio).
  int init_search_steps = 1;
  double init_search_deg = 4.0;               ///< Grid step of the start-up search, degrees.
  double init_confident_inlier_ratio = 0.75;  ///< No start-up search at or above this inlier ratio.
  /// Learn which geometric edges the live images show (an unlit render's creases and silhouettes
  /// may have no intensity edge in them, and rims of model holes none at all): after each tracked
  /// frame, the running mean (weight 0.3) of the inlier ratio of occlusion points, of crease
  /// points and of points near background (kEdgeBackground) is compared with the texture
  /// points'; a kind below kind_visibility_ratio times the texture's is left out of later
  /// references. Measured at true poses: room_easy creases 0.02 and silhouettes 0.00 against
  /// texture 0.99; city_hard silhouettes 0.03 and points near background 0.43-0.52 against
  /// 0.83 (they pull frame 12 to 1.2 m); Castle-simu all kinds 0.86-1.0 (kept).
  bool adapt_edge_kinds = true;
  double kind_visibility_ratio = 0.7;  ///< See adapt_edge_kinds (0..1).
  /// Leave out of a frame's alignment the reference points that the predicted motion (last
  /// tracked pose to the guess) moves more than this in the image, pixels (0 = keep all; not
  /// applied when fewer than a fifth of a level's points, or fewer than 100, would remain):
  /// surfaces passing close to the camera are smeared by motion blur and their edges alias onto
  /// wrong ones (city_hard frames 52-58, 0.3 m from a wall: errors 3-11 mm instead of 6-24 mm).
  double max_point_motion_px = 40.0;
  InertialAiding inertial;  ///< IMU-propagated guesses and consistency gate (when readings are given).
  /// With kAuto and a Vulkan device: time the CPU and Vulkan live stages + alignment on the first
  /// frame and keep the faster one (instead of deciding by the device type alone).
  bool calibrate_backend = false;
};

/// Outcome of one localized frame.
struct LocalizationResult {
  int64_t t_ns = 0;                        ///< Frame time, nanoseconds.
  Pose T_world_camera = Pose::Identity();  ///< Estimated pose (not trusted when lost).
  /// Covariance of xi (m^2, rad^2, [rho; phi], live camera frame; see TrackResult::covariance).
  Matrix6d covariance = Matrix6d::Zero();
  TrackQuality quality;  ///< Alignment quality on the finest level.
  /// kTracking: the visual alignment is trusted; kInertial: it was lost or disagreed with the
  /// IMU, T_world_camera is the inertial prediction (InertialAiding); kLost: no trusted pose.
  TrackingState state = TrackingState::kLost;
  bool visual_rejected = false;     ///< The alignment tracked but lay outside the inertial gate.
  double inertial_sigma_m = 0;      ///< 1-sigma of the inertial prediction, metres (0: none made).
  bool reference_rendered = false;  ///< A new reference was rendered for this frame.
  int reference_points = 0;         ///< Edge points of the finest reference level.
  double scene_depth_m = 0;         ///< Median depth of the reference render's surfaces, metres (0: none seen).
  double render_ms = 0;             ///< Rendering the reference, ms (0 when kept).
  double reference_ms = 0;          ///< Extracting reference edge points, ms.
  double live_ms = 0;               ///< Live pyramid, edges and distance fields, ms.
  double align_ms = 0;              ///< Gauss-Newton alignment, ms.
  double total_ms = 0;              ///< Whole localize() call, ms.
};

/// Tracks a camera through a model, one frame at a time. Not thread-safe.
class Localizer {
 public:
  /// Prepares the renderer (on `context`'s device, or the CPU reference renderer when `context`
  /// is null) and the backends. kInvalidArgument for a bad camera, invalid model or options out
  /// of range; kNoDevice when backend kVulkan is asked for without a context; kGpuError when
  /// the device fails. The model is copied (uploaded) and not referenced afterwards.
  static Result<std::unique_ptr<Localizer>> create(const Model& model, const PinholeCamera& camera,
                                                   const LocalizerOptions& options,
                                                   std::shared_ptr<GpuContext> context);
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /// Localizes an 8-bit gray image (camera size, 1 channel) taken at t_ns. The guess, when
  /// given, replaces the motion model's prediction. A lost frame is not an error (state kLost);
  /// the next frame is predicted from the last tracked pose. Errors (kInvalidArgument): wrong
  /// image size or channels, a non-finite or non-rigid guess, t_ns not after the previous
  /// frame's, no guess and no pose yet (call reset() first); kGpuError when the device fails.
  Result<LocalizationResult> localize(int64_t t_ns, const ImageU8& gray,
                                      const std::optional<Pose>& T_world_camera_guess = std::nullopt);

  /// Gives one IMU reading (body frame; InertialAiding). Readings up to a frame's time should be
  /// given before the frame. kInvalidArgument for a non-finite reading or a time not after the
  /// previous reading's (the reading is ignored; tracking goes on).
  Status addImu(const ImuSample& sample);
  /// Forgets the motion, the IMU readings and the reference and restarts from T_world_camera (e.g. the known
  /// initial pose, or after relocalization). Timestamps may start over. An invalid pose is
  /// ignored (the next localize() then needs a guess).
  void reset(const Pose& T_world_camera);

  /// One line: renderer, live/alignment backend and why it was chosen, re-render policy.
  std::string backendSummary() const;

  struct Impl;

 private:
  explicit Localizer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkloc
