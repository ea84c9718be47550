// The Localizer: one frame's data flow over its parts (see localizer.hpp).
#include "vkloc/localize/localizer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "vkloc/core/clock.hpp"
#include "vkloc/core/numeric.hpp"
#include "vkloc/core/threads.hpp"
#include "vkloc/localize/feature_pose.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/track/image_motion.hpp"

namespace vkloc {
namespace {

InitializerOptions initializerOptions(const LocalizerOptions& o) {
  InitializerOptions i;
  i.refinements = o.init_refinements;
  i.search_steps = o.init_search_steps;
  i.search_deg = o.init_search_deg;
  i.confident_inlier_ratio = o.init_confident_inlier_ratio;
  i.min_inlier_gain = o.init_min_inlier_gain;
  return i;
}

KeyframeManagerOptions keyframeOptions(const LocalizerOptions& o) {
  KeyframeManagerOptions k;
  k.policy = o.policy;
  k.thresholds = o.rerender;
  k.threading = o.keyframe_threading;
  k.background_worker = o.keyframe_worker_background;
  k.adapt_edge_kinds = o.adapt_edge_kinds;
  k.kind_visibility_ratio = o.kind_visibility_ratio;
  return k;
}

Status validateOptions(const LocalizerOptions& o) {
  const RerenderThresholds& r = o.rerender;
  if (!finiteIn(r.max_translation_depth_ratio, 0.0, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: rerender.max_translation_depth_ratio must be >= 0");
  }
  if (!finiteIn(r.max_rotation_deg, 0.0, 360.0)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: rerender.max_rotation_deg must be in 0..360");
  }
  if (!finiteIn(r.min_inlier_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: rerender.min_inlier_ratio must be in 0..1");
  }
  if (o.max_search_level < 0 || o.max_search_level > 7 || !finiteIn(o.search_sigmas, 0.0, 100.0) ||
      !finiteIn(o.search_basin_px, 0.1, 1e4)) {
    return makeError(
        ErrorCode::kInvalidArgument,
        "Localizer: need max_search_level in 0..7, search_sigmas in 0..100 and search_basin_px in 0.1..1e4");
  }
  if (o.motion_search_steps < 0 || o.motion_search_steps > 10 || o.motion_search_candidates < 1 ||
      o.motion_search_candidates > 50 || !finiteIn(o.motion_search_max_gap_s, 0.0, 10.0) ||
      !finiteIn(o.motion_search_min_response, 0.0, 1.0) || !finiteIn(o.motion_search_confident_score, 0.0, 1.0) ||
      !finiteIn(o.motion_search_start_score, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need motion_search_steps in 0..10, motion_search_candidates in 1..50, "
                     "motion_search_max_gap_s in 0..10, motion_search_min_response, "
                     "motion_search_confident_score and motion_search_start_score in 0..1");
  }
  if (o.motion_search_feature_min_inliers < 4 || o.motion_search_feature_min_inliers > 100000 ||
      !finiteIn(o.motion_search_feature_min_inlier_fraction, 0.0, 1.0) ||
      !finiteIn(o.motion_search_feature_attitude_sigmas, 0.0, 1e3)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need motion_search_feature_min_inliers in 4..100000, "
                     "motion_search_feature_min_inlier_fraction in 0..1 and "
                     "motion_search_feature_attitude_sigmas in 0..1e3");
  }
  if (o.restart_after_refusals < 0 || !finiteIn(o.restart_min_score, 0.0, 1.0) ||
      !finiteIn(o.restart_after_refused_s, 0.0, 1e4) || !finiteIn(o.restart_sigma_velocity_m_s, 0.0, 1e3)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need restart_after_refusals >= 0, restart_min_score in 0..1, "
                     "restart_after_refused_s in 0..1e4 and restart_sigma_velocity_m_s in 0..1e3");
  }
  if (!finiteIn(o.rotation_prior_covariance_scale, 1e-3, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: need rotation_prior_covariance_scale in 1e-3..1e6");
  }
  const RelocalizationOptions& l = o.relocalization;
  if (l.candidates < 1 || l.candidates > 100 || l.rerank_candidates < 0 || l.rerank_candidates > 1000 ||
      l.refined_probes < 1 || l.refined_probes > 100 || l.depth_steps < 0 || l.depth_steps > 5 ||
      !finiteIn(l.depth_step, 0.0, 1.0) || l.after_untracked_frames < 0 || l.refinements < 0 || l.refinements > 10 ||
      l.shift_starts < 0 || l.shift_starts > 5 || !finiteIn(l.min_radius_m, 0.0, 1e7) ||
      !finiteIn(l.growth_m_s, 0.0, 1e4) || !finiteIn(l.max_radius_m, 0.0, 1e7) ||
      !finiteIn(l.min_contrast, 0.0, 255.0) || !finiteIn(l.min_score, 0.0, 1.0) ||
      !finiteIn(l.confident_score, 0.0, 1.0) || !finiteIn(l.min_response, 0.0, 1.0) || l.agreeing_candidates < 0 ||
      l.agreeing_candidates > 100 || l.agreement_probes < 0 || l.agreement_probes > 100 ||
      !finiteIn(l.agree_depth_fraction, 0.0, 1.0) || !finiteIn(l.agree_deg, 0.0, 180.0) ||
      !finiteIn(l.rerank_bits_weight, 0.0, 1.0) || l.realign_level < -1 || l.realign_level > 7) {
    return makeError(
        ErrorCode::kInvalidArgument,
        "Localizer: relocalization needs candidates and refined_probes in 1..100, rerank_candidates in "
        "0..1000, depth_steps in 0..5, "
        "depth_step in 0..1, after_untracked_frames >= 0, refinements "
        "in 0..10, shift_starts in 0..5, radii and growth >= 0, min_contrast in 0..255 and scores and "
        "min_response in 0..1, agreeing_candidates and agreement_probes in 0..100, agree_depth_fraction in "
        "0..1, agree_deg in 0..180, rerank_bits_weight in 0..1 and realign_level in -1..7");
  }
  if (l.local_headings < 0 || l.local_headings > 360 || l.local_tilts_deg.size() > 16 ||
      !std::all_of(l.local_tilts_deg.begin(), l.local_tilts_deg.end(),
                   [](double t) { return finiteIn(t, -90.0, 90.0); }) ||
      !finiteIn(l.local_offset_fraction, 0.0, 1e3) || !finiteIn(l.local_max_s, 0.0, 1e6) ||
      !finiteIn(l.local_depth_fraction, 0.0, 1e3) || l.local_after_untracked_frames < 1) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: relocalization needs local_headings in 0..360, at most 16 local_tilts_deg in "
                     "-90..90, local_offset_fraction and local_depth_fraction in 0..1e3, local_max_s in "
                     "0..1e6 and local_after_untracked_frames >= 1");
  }
  if (l.feature_starts) VKLOC_TRY_STATUS(validateFeaturePoseOptions(l.features));
  if (!finiteIn(l.feature_agree_fraction, 0.0, 1.0) || !finiteIn(l.feature_agree_deg, 0.0, 180.0)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: relocalization needs feature_agree_fraction in 0..1 and feature_agree_deg in 0..180");
  }
  if (!finiteIn(o.max_point_motion_px, 0.0, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: max_point_motion_px must be in 0..1e6");
  }
  if (!finiteIn(o.kind_visibility_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: kind_visibility_ratio must be in 0..1");
  }
  VKLOC_TRY_STATUS(validateInitializerOptions(initializerOptions(o)));
  VKLOC_TRY_STATUS(validateImageContentOptions(o.image_content));
  if (r.max_frames < 1) return makeError(ErrorCode::kInvalidArgument, "Localizer: rerender.max_frames must be >= 1");
  if (o.max_keyframe_lead_frames < 0 || o.max_keyframe_lead_frames > 100) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: max_keyframe_lead_frames must be in 0..100");
  }
  VKLOC_TRY_STATUS(validateInertialAiding(o.inertial));
  VKLOC_TRY_STATUS(validateRenderSettings(o.render));
  if (o.keyframe_render_threads < 0 || o.keyframe_render_threads > 64) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: keyframe_render_threads must be in 0..64");
  }
  VKLOC_TRY_STATUS(validateReferenceEdgeOptions(o.reference));
  VKLOC_TRY_STATUS(validateEdgeTrackerOptions(o.tracker));
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(o.live.detector));
  if (o.live.levels < 1 || o.live.levels > 8) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: live.levels must be in 1..8");
  }
  if (!finiteIn(o.live.truncation_px, 1e-3, 16384.0)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: live.truncation_px must be in (0, 16384]");
  }
  return Status::success();
}

/// The keyframe without the points that the predicted motion from `last_pose` to `guess` moves
/// more than max_px in the image (finest level), or nullopt when none is dropped or too few would
/// remain (motion blur smears those points' edges).
std::optional<EdgeReference> slowPoints(const EdgeReference& reference, const Pose& guess, const Pose& last_pose,
                                        double max_px) {
  const PinholeCamera& camera = reference.camera;
  const Pose T_guess_ref = guess.inverse() * reference.T_world_ref;
  const Pose T_last_ref = last_pose.inverse() * reference.T_world_ref;
  auto motionPx = [&](const EdgePoint& p) {
    const Eigen::Vector3d P(p.x, p.y, p.z);
    const Eigen::Vector3d a = T_guess_ref * P;
    const Eigen::Vector3d b = T_last_ref * P;
    if (!(a.z() > 1e-6) || !(b.z() > 1e-6)) return std::numeric_limits<double>::infinity();
    const double du = camera.fx * (a.x() / a.z() - b.x() / b.z());
    const double dv = camera.fy * (a.y() / a.z() - b.y() / b.z());
    return std::sqrt(du * du + dv * dv);
  };
  EdgeReference out;
  out.camera = reference.camera;
  out.T_world_ref = reference.T_world_ref;
  size_t dropped = 0;
  auto filter = [&](const std::vector<EdgePoint>& in, std::vector<EdgePoint>& kept) {
    kept.reserve(in.size());
    for (const EdgePoint& p : in) {
      if (motionPx(p) <= max_px) kept.push_back(p);
    }
    dropped += in.size() - kept.size();
    return 5 * kept.size() >= in.size() && kept.size() >= 100;
  };
  if (!filter(reference.points, out.points)) return std::nullopt;
  out.coarse_points.resize(reference.coarse_points.size());
  for (size_t k = 0; k < out.coarse_points.size(); ++k) {
    if (!filter(reference.coarse_points[k], out.coarse_points[k])) return std::nullopt;
  }
  if (dropped == 0) return std::nullopt;
  return out;
}

/// An untracked frame: the motion prior's bridged pose (inertial) when it has one, else lost.
void applyBridge(const std::optional<BridgedPose>& bridged, LocalizationResult& out) {
  if (bridged) {
    out.state = TrackingState::kInertial;
    out.T_world_camera = bridged->T_world_camera;
    out.covariance = bridged->covariance;
  } else {
    out.state = TrackingState::kLost;
  }
}

/// A frame whose pose was tracked and accepted: its image, pose (metres) and time (ns). At
/// namespace scope: an optional of a nested type with member initialisers is not default
/// constructible inside its enclosing class on every compiler.
struct TrackedImage {
  ImageU8 gray;
  Pose T_world_camera = Pose::Identity();
  int64_t t_ns = 0;
  double scene_depth_m = 0;  ///< Median depth of the keyframe it was tracked against, metres.
};

/// A pose the local search renders its keyframes around (RelocalizationOptions::local_headings).
struct SearchAnchor {
  Pose T_world_camera = Pose::Identity();
  int64_t t_ns = 0;
  double scene_depth_m = 0;  ///< Median depth of its keyframe, metres.
};

}  // namespace

Result<LocalizerBackend> parseLocalizerBackend(const std::string& name) {
  if (name == "auto") return LocalizerBackend::kAuto;
  if (name == "vulkan") return LocalizerBackend::kVulkan;
  if (name == "cpu") return LocalizerBackend::kCpu;
  return makeError(ErrorCode::kInvalidArgument, fmt::format("backend '{}': expected auto, vulkan or cpu", name));
}

const char* localizerBackendName(LocalizerBackend backend) {
  switch (backend) {
    case LocalizerBackend::kAuto:
      return "auto";
    case LocalizerBackend::kVulkan:
      return "vulkan";
    case LocalizerBackend::kCpu:
      return "cpu";
  }
  return "?";
}

struct Localizer::Impl {
  LocalizerOptions options;
  PinholeCamera camera;
  std::unique_ptr<KeyframeManager> keyframes;
  std::unique_ptr<MotionPrior> motion;
  /// The camera front (setCameraFront) and the prior's view wrapper (inside `motion`), the view
  /// image of the frame and the last camera pose reported (for the next frame's view).
  std::unique_ptr<CameraFront> front;
  ViewPrior* view_prior = nullptr;
  std::shared_ptr<Accelerator> accelerator;  ///< Null: everything on the CPU.
  ImageU8 view_image;
  std::optional<Pose> last_camera_pose;
  Initializer initializer{InitializerOptions{}};
  /// The backends frames may be tracked on: both only until the first-frame calibration.
  std::unique_ptr<EdgeTrackingBackend> cpu_backend;
  std::unique_ptr<EdgeTrackingBackend> device_backend;  ///< When the device runs (or may run) the edge stages.
  EdgeTrackingBackend* active = nullptr;                ///< The backend frames are tracked on.
  bool calibration_pending = false;
  std::string device_name;  ///< The accelerator's, or "" without one.
  std::string backend_reason;
  std::string render_threads;  ///< ", N threads" of the CPU rasterizer's keyframes ("" on a device).

  std::optional<int64_t> last_t_ns;  ///< Last frame given to localize.
  int64_t frame_index = -1;          ///< Frames given to localize since create.
  bool tracked_since_reset = false;  ///< A frame was tracked since create/reset.
  /// The last frame whose pose was tracked and accepted: its image, pose and time.
  std::optional<TrackedImage> last_tracked_gray;
  /// Until a pose is taken after create/reset: the pose given to start at, at the first frame
  /// (its time, its keyframe's depth). The local search renders around it when the start's
  /// frames do not verify (a start pose decimetres off in a room).
  std::optional<SearchAnchor> start_anchor;
  std::optional<int64_t> first_t_ns;  ///< The first frame's time since create/reset (forgetTrack).
  /// A first pose taken after lost frames without a database, or on the start's own frame beyond
  /// where the start pose vouches (without the IMU: and without a database), or on the track's
  /// second frame from a motion search that fell short (SearchGrid::capped), waits for the next
  /// frame to confirm it (RelocalizationOptions::confirm_start): that pose and its frame's time while it waits;
  /// start_anchor and first_t_ns stay as they were before it (neither changes once a pose is taken).
  std::optional<SearchAnchor> start_on_probation;
  /// Consecutive poses the motion prior refused that count against it (refusalCountsAgainstPrior),
  /// the last one's time.
  struct Refusals {
    int count = 0;
    int64_t t_ns = 0;
    bool restarted = false;  ///< Restarted, and no pose accepted under its gate since.
    /// Verification scores of the last kTakenScores poses the prior took (oldest first).
    std::vector<double> taken_scores;
  } refusals;
  static constexpr size_t kTakenScores = 5;
  /// Tracked poses the motion prior refused in a row, whatever their scores
  /// (LocalizerOptions::restart_after_refused_s): the first one's time and the last one's.
  struct RefusedStretch {
    std::optional<int64_t> first_t_ns;
    int64_t last_t_ns = 0;
    bool verified = false;  ///< One of them verified (VerificationOptions::min_score).
  } refused_stretch;
  /// The time of a restart of the motion prior that kept the filter's velocity, until a pose is
  /// taken after it.
  std::optional<int64_t> restart_kept_velocity_t_ns;
  /// Records the verification score of a pose the motion prior took.
  void poseTaken(double score) {
    std::vector<double>& s = refusals.taken_scores;
    if (s.size() == kTakenScores) s.erase(s.begin());
    s.push_back(score);
  }
  int search_level = 0;  ///< This frame's alignment starts at least this deep (searchLevel).
  /// This frame's attitude prior for align() (rotation_prior_from_filter); nullopt outside the
  /// tracking of a frame the filter predicted.
  std::optional<RotationPrior> rotation_prior;

  // Relocalization and global initialization (RelocalizationOptions).
  std::shared_ptr<const KeyframeDatabase> database;
  double database_reach_m = 0;  ///< KeyframeDatabase::positionReach: a search region grows by it.
  /// KeyframeDatabase::positionBounds grown by database_reach_m; infinite when
  /// RelocalizationOptions::inside_database_box is off or the reach is 0.
  Eigen::Vector3d database_min = Eigen::Vector3d::Zero(), database_max = Eigen::Vector3d::Zero();
  /// Without a database: the keyframes rendered around the last tracked pose after a loss
  /// (RelocalizationOptions::local_headings), and that pose (rendered anew when it changes).
  std::optional<KeyframeDatabase> local_database;
  std::vector<ImageU8> local_views;  ///< Its keyframes' renders (the re-ranking's).
  std::optional<Pose> local_database_pose;
  Eigen::Vector3d local_database_guess = Eigen::Vector3d::Zero();  ///< The predicted position it was made at.
  uint64_t model_fingerprint = 0;
  bool searching = false;                     ///< Global initialization in progress (startSearch).
  std::optional<SearchRegion> search_region;  ///< Its region (nullopt: the whole database).
  bool confirming = false;        ///< Its pose waits for the next frame (RelocalizationOptions::confirm_start).
  bool confirm_extended = false;  ///< That wait went on a frame (5a: the frame after fell short).
  bool relocalizing = false;      ///< A relocalization search is aligning (no point filter).
  int untracked = 0;              ///< Frames in a row not tracked.
  int failed_searches = 0;        ///< Searches since the last tracked frame that found nothing.
  std::optional<int64_t> last_tracked_t_ns;  ///< Time of the last tracked frame.
  std::optional<ImuSample> last_imu;  ///< Newest IMU reading taken (given again when the prior restarts: restartPrior).
  std::optional<int64_t> last_relocalized_t_ns;  ///< Time of the last relocalized frame.

  /// Pyramid level whose basin covers the prediction's uncertainty (LocalizerOptions::max_search_level).
  int searchLevel(const std::optional<MotionPrediction>& prediction, double scene_depth_m) const {
    if (!prediction || options.max_search_level <= 0) return 0;
    const int deepest = std::min(options.max_search_level, options.live.levels - 1);
    // Without the IMU (or before its first reading) the first frame after a start has no motion
    // to extrapolate and no covariance to size the search by: it starts at the deepest level, as
    // an inertial start at an unknown velocity does.
    if (!prediction->inertial) return prediction->velocity_unobserved && tracked_since_reset ? deepest : 0;
    const Matrix6d& C = prediction->covariance;
    const double sigma_t = std::sqrt(std::max({C(0, 0), C(1, 1), 0.0}));  // across the view, m
    const double sigma_r = std::sqrt(std::max({C(3, 3), C(4, 4), 0.0}));  // about x and y, rad
    const double depth = scene_depth_m > 0 ? scene_depth_m : 1.0;
    const double sigma_px = std::max(camera.fx, camera.fy) * (sigma_t / depth + sigma_r);
    const double ratio = options.search_sigmas * sigma_px / options.search_basin_px;
    if (!(ratio > 1.0)) return 0;
    const int level = static_cast<int>(std::ceil(std::log2(ratio)));
    return std::clamp(level, 0, deepest);
  }
  /// Pyramid levels of the current image's live frame the active backend holds (0: none).
  int live_levels = 0;
  /// Live levels the tracker's own options read; the deeper search levels (max_search_level)
  /// are built only for the frames whose alignment or search starts there.
  int usual_levels = 1;
  /// Live levels an alignment starting at `start_level` reads.
  int liveLevelsFor(int start_level) const {
    return std::clamp(std::max(usual_levels, start_level + 1), 1, options.live.levels);
  }
  uint64_t uploaded_id = 0;  ///< Id of the keyframe the backends hold (setKeyframe; 0: none).
  // Worker mode: running means of a keyframe's making time and of the wall time between the
  // starts of successive frames (ms: the caller's thread's time per frame when frames come back
  // to back, the camera's period when they come at its pace), and the last frame interval in
  // the images' time (ns), for the request's lead.
  double keyframe_ms_mean = 0;
  double frame_period_ms_mean = 0;
  std::optional<SteadyClock::time_point> last_frame_start;
  bool last_frame_waited = false;  ///< The last frame waited for a keyframe (its period is not counted).
  int64_t frame_interval_ns = 0;

  /// The last kStreamIntervals frame intervals (ns, oldest first). Their least is the stream's
  /// own interval: a pause in a stream is not its rate.
  static constexpr size_t kStreamIntervals = 8;
  std::deque<int64_t> stream_intervals_ns;
  /// Longest time (seconds) between two frames that still follow each other for the motion
  /// search's starts from the last tracked frame and for the refusals counted in a row:
  /// motion_search_max_gap_s (0: none), or in a stream slower than that 1.5 of its intervals, at
  /// most kLongestRecentGapS: the frame before is recent however slow the stream (else a start at
  /// an unknown velocity gets no feature or image-shift start below 4 images a second; README,
  /// "Slower streams").
  static constexpr double kLongestRecentGapS = 1.0;
  double recentGapS() const {
    if (!(options.motion_search_max_gap_s > 0)) return 0.0;
    if (stream_intervals_ns.empty()) return options.motion_search_max_gap_s;
    const int64_t interval_ns = *std::min_element(stream_intervals_ns.begin(), stream_intervals_ns.end());
    return std::max(options.motion_search_max_gap_s,
                    std::min(1.5e-9 * static_cast<double>(interval_ns), kLongestRecentGapS));
  }
  /// Whether a frame at earlier_t_ns is recent to one at t_ns (recentGapS).
  bool recent(int64_t t_ns, int64_t earlier_t_ns) const {
    return static_cast<double>(t_ns - earlier_t_ns) * 1e-9 <= recentGapS();
  }

  bool worker() const { return options.keyframe_threading == KeyframeThreading::kWorkerThread; }

  /// Gives every backend the current keyframe's points when it changed.
  Status uploadKeyframe() {
    const Keyframe* current = keyframes->current().get();
    if (current == nullptr || current->id == uploaded_id) return Status::success();
    uploaded_id = 0;
    for (EdgeTrackingBackend* backend : {cpu_backend.get(), device_backend.get()}) {
      if (backend) VKLOC_TRY_STATUS(backend->setKeyframe(current->reference));
    }
    uploaded_id = current->id;
    return Status::success();
  }

  /// Makes an earlier keyframe current again (and the backends' keyframe), unless it is.
  Status restoreKeyframe(const std::shared_ptr<const Keyframe>& keyframe) {
    if (keyframes->current() == keyframe) return Status::success();
    keyframes->restore(keyframe);
    return uploadKeyframe();
  }

  /// Makes a keyframe at T_world_ref for this frame and waits for it.
  Status makeKeyframe(const Pose& T_world_ref, int64_t t_ns, LocalizationResult& out) {
    // Built whole (not default-made and assigned): GCC 12 at -O1 with the sanitizers took the
    // default pose's construction for a read of uninitialized memory (-Wmaybe-uninitialized).
    const KeyframeRequest request{T_world_ref, t_ns, frame_index};
    VKLOC_TRY_STATUS(keyframes->makeNow(request, out.render_ms, out.reference_ms));
    out.reference_rendered = true;
    return uploadKeyframe();
  }

  /// The live stages of `gray` on `backend` with `levels` pyramid levels, unless `built` says
  /// they ran for this image with as many (built: the levels the backend holds, 0 for none; a
  /// frame built shallower is built again, deeper). A backend that built more than asked (the
  /// GPU backend builds all) is not asked again for those.
  Status ensureLive(EdgeTrackingBackend& backend, const ImageU8& gray, LocalizationResult& out, int& built,
                    int levels) {
    if (built >= levels) return Status::success();
    const auto t0 = SteadyClock::now();
    built = 0;
    auto made = backend.setLiveImage(gray, levels);
    if (!made.ok()) return made.error();
    // Fewer than asked only where no more levels exist (liveLevelsFor caps `levels` at the
    // options' levels; a small image has fewer): asking again would not add any.
    built = std::max(levels, *made);
    out.live_ms += msSince(t0);
    return Status::success();
  }

  /// Options of a probe: a few Gauss-Newton steps on one pyramid level alone (the motion
  /// search's and the relocalization's starts are ranked by them).
  EdgeTrackerOptions probeOptions(int level, int iterations) const {
    EdgeTrackerOptions probe = options.tracker;
    probe.coarsest_level = level;
    probe.finest_level = level;
    probe.far_first_depth_quantile = 0;
    probe.max_iterations = iterations;
    return probe;
  }

  /// The pose the filter takes from an alignment: the edges' own (without the rotation prior,
  /// which came from the filter).
  static const Pose& filterPose(const TrackResult& r) {
    return r.T_world_camera_edges ? *r.T_world_camera_edges : r.T_world_camera;
  }

  /// The attitude prior of a frame's alignments from the filter's prediction
  /// (rotation_prior_from_filter): nullopt when off, for a prediction not from the IMU or
  /// without a rotation covariance (not the EKF's). A floor of (1e-5 rad)^2 keeps the
  /// information finite where the filter reports none smaller.
  std::optional<RotationPrior> rotationPriorFrom(const std::optional<MotionPrediction>& prediction) const {
    if (!options.rotation_prior_from_filter || !prediction || !prediction->inertial) return std::nullopt;
    const Eigen::Matrix3d covariance = prediction->covariance.bottomRightCorner<3, 3>();
    RotationPrior prior;
    prior.R_world_camera = prediction->T_world_camera.linear();
    prior.covariance = options.rotation_prior_covariance_scale * 0.5 * (covariance + covariance.transpose()) +
                       1e-10 * Eigen::Matrix3d::Identity();
    if (!prior.covariance.allFinite() || !(covariance.trace() > 0) ||
        Eigen::LLT<Eigen::Matrix3d>(prior.covariance).info() != Eigen::Success) {
      return std::nullopt;
    }
    return prior;
  }

  /// The pose the local search renders around: the last tracked one, else the start's.
  std::optional<SearchAnchor> searchAnchor() const {
    if (last_tracked_gray) {
      return SearchAnchor{last_tracked_gray->T_world_camera, last_tracked_gray->t_ns, last_tracked_gray->scene_depth_m};
    }
    return start_anchor;
  }

  /// Seconds from the last tracked frame (before one: the start's first frame) to t_ns (0 when none).
  double sinceTrackedS(int64_t t_ns) const {
    if (last_tracked_t_ns) return static_cast<double>(t_ns - *last_tracked_t_ns) * 1e-9;
    return start_anchor ? static_cast<double>(t_ns - start_anchor->t_ns) * 1e-9 : 0.0;
  }

  /// Whether the local search (RelocalizationOptions::local_headings) may run at t_ns: it is on,
  /// and a pose to search around (searchAnchor) lies within local_max_s.
  bool localSearchInReach(int64_t t_ns) const {
    const RelocalizationOptions& o = options.relocalization;
    return o.local_headings > 0 && !o.local_tilts_deg.empty() && (last_tracked_gray || start_anchor) &&
           sinceTrackedS(t_ns) <= o.local_max_s;
  }

  /// The verification score a pose needs: tracking's, or while the motion prior's velocity is
  /// unobserved (the pose taken sets it) at least motion_search_confident_score.
  double minTakenScore(bool velocity_unobserved) const {
    return velocity_unobserved ? std::max(options.verification.min_score, options.motion_search_confident_score)
                               : options.verification.min_score;
  }

  /// Inliers on the finest level of a result (0 unless tracked).
  static double finestInliers(const TrackResult& r) {
    return r.state == TrackingState::kTracking ? r.quality.inlier_ratio * r.quality.points_in_image : 0.0;
  }

  /// Live stages (once per image) + alignment on `backend` from `start` (from search_level when
  /// deeper than the usual levels, and from the usual ones as a second hypothesis).
  Result<TrackResult> align(EdgeTrackingBackend& backend, const ImageU8& gray, const Pose& start,
                            LocalizationResult& out, int& live_built) {
    const EdgeReference& reference = keyframes->current()->reference;
    if (reference.points.size() < 6) {
      // Nothing of the model is seen from the keyframe: a lost frame, not an error.
      TrackResult lost;
      lost.T_world_camera = start;
      lost.T_camera_ref = start.inverse() * reference.T_world_ref;
      return lost;
    }
    VKLOC_TRY_STATUS(ensureLive(backend, gray, out, live_built, liveLevelsFor(search_level)));
    const auto t0 = SteadyClock::now();
    std::optional<EdgeReference> slow;
    const std::optional<Pose> last_pose = motion->lastPose();
    if (options.max_point_motion_px > 0 && last_pose && tracked_since_reset && !relocalizing) {
      slow = slowPoints(reference, start, *last_pose, options.max_point_motion_px);
    }
    EdgeTrackerOptions usual = options.tracker;
    usual.rotation_prior = rotation_prior;
    EdgeTrackerOptions tracker = usual;
    if (search_level > 0) {
      tracker.coarsest_level = std::max(tracker.coarsest_level, search_level);
      if (tracker.far_first_coarsest_level >= 0) {
        tracker.far_first_coarsest_level = std::max(tracker.far_first_coarsest_level, search_level);
      }
    }
    const EdgeReference& points = slow ? *slow : reference;
    Result<TrackResult> r = backend.align(points, start, tracker);
    if (r.ok() && (tracker.coarsest_level != usual.coarsest_level ||
                   tracker.far_first_coarsest_level != usual.far_first_coarsest_level)) {
      // A deep start widens the basin, but where the scene is far and the view wide a coarse
      // level barely tells a translation across the view from a rotation, and the finer levels
      // do not pull back a start that slid along that valley: the alignment from the usual
      // levels is a second hypothesis, and the one with more inliers on the finest level wins.
      Result<TrackResult> from_usual = backend.align(points, start, usual);
      if (!from_usual.ok()) return from_usual.error();
      if (finestInliers(*from_usual) > finestInliers(*r)) r = std::move(from_usual);
    }
    out.align_ms += msSince(t0);
    return r;
  }

  /// Grid of the motion search: the deepest search level, the spacing (1.5 basins of that level at
  /// the keyframe's scene depth, metres) and the steps each way across the view (x, y).
  struct SearchGrid {
    int level = 0;
    double step_m = 0;
    int steps[2] = {0, 0};
    /// The prediction's reach (search_sigmas sigma) across the view spans more steps than
    /// motion_search_steps on x or y: poses beyond the grid were not probed, a look-alike within it
    /// may be the best. (Along the view the image shift's starts try at most 2 steps; not counted.)
    bool capped = false;
  };
  /// The grid when the prediction's uncertainty across the view spans more than one step; nullopt
  /// when the search does not apply (off, no depth or edge points, a settled prior).
  std::optional<SearchGrid> searchGrid(const MotionPrediction& prediction) const {
    std::optional<SearchGrid> grid = startsGrid();
    if (!grid) return std::nullopt;
    for (int a = 0; a < 2; ++a) {
      const double reach = options.search_sigmas * std::sqrt(std::max(0.0, prediction.covariance(a, a)));
      const double steps = std::ceil(reach / grid->step_m - 0.5);  // compared as a double: reach may be huge
      grid->capped = grid->capped || steps > options.motion_search_steps;
      grid->steps[a] = steps > options.motion_search_steps ? options.motion_search_steps : static_cast<int>(steps);
    }
    if (grid->steps[0] == 0 && grid->steps[1] == 0) return std::nullopt;
    return grid;
  }
  /// The grid with no steps: the motion search's starts from the last tracked frame alone (point
  /// features, image shifts); nullopt when the search does not apply.
  std::optional<SearchGrid> startsGrid() const {
    const Keyframe& keyframe = *keyframes->current();
    SearchGrid grid;
    grid.level = std::min(options.max_search_level, options.live.levels - 1);
    if (options.motion_search_steps <= 0 || grid.level < 0 || !(keyframe.scene_depth_m > 0) ||
        keyframe.reference.points.size() < 6) {
      return std::nullopt;
    }
    // Basin of the deepest level across the view, metres at the scene depth (as in searchLevel).
    const double basin_m =
        options.search_basin_px * std::ldexp(1.0, grid.level) / std::max(camera.fx, camera.fy) * keyframe.scene_depth_m;
    grid.step_m = 1.5 * basin_m;
    return grid;
  }

  /// Motion search (LocalizerOptions::motion_search_steps) over `grid`: `lost` is the frame's
  /// alignment from `guess` (lost, refused by the motion prior's gate: `refused`, or verified
  /// below motion_search_start_score on the first frame after a start at an unknown velocity, at
  /// `incumbent_score`: 0 for the others); returns it unchanged when the search finds nothing
  /// tracked, not refused and verified above both the search's minimum and incumbent_score.
  /// `confident_only`: the search's minimum is motion_search_confident_score (no gate checks a
  /// result; a feature start the edges agree with is returned as always, and the caller's rules
  /// for any pose then apply). `feature_agreed`, when given, is set to whether the pose returned
  /// is the feature start's that the edges agreed with (two independent poses).
  template <typename AlignFrom, typename Refused>
  Result<TrackResult> motionSearch(const SearchGrid& grid, const MotionPrediction& prediction, const Pose& guess,
                                   const ImageU8& gray_now, TrackResult lost, double incumbent_score,
                                   AlignFrom& alignFrom, Refused& refused, LocalizationResult& out,
                                   bool confident_only = false, bool* feature_agreed = nullptr) {
    if (feature_agreed) *feature_agreed = false;
    // Held: the shift's starts may make keyframes of their own current (the guess's is restored).
    const std::shared_ptr<const Keyframe> guess_keyframe = keyframes->current();
    const Keyframe& keyframe = *guess_keyframe;
    const VerificationOptions& verification = options.verification;
    // Many starts give many chances to converge somewhere wrong: a result must be tracked, pass
    // the prior's gate and the pose verification; the best verified one is kept, and the search
    // stops early at one verified with stop_score (below).
    // A filter started at an unknown velocity has a gate that admits whatever its velocity's sigma
    // reaches, and the first pose after the start sets that velocity for the frames to come (a
    // start that converged only part of the way, on a near wall beside a far facade, would carry
    // its error on): until a second pose has pinned the velocity down, a searched pose must be
    // verified with motion_search_confident_score.
    const double min_score = confident_only ? minTakenScore(true) : minTakenScore(prediction.velocity_unobserved);
    // While the velocity is unobserved the pose taken sets it: the search goes on past a merely
    // confident pose (a look-alike a period along a repetitive street verifies at 0.6-0.7).
    const double stop_score = prediction.velocity_unobserved
                                  ? std::max(options.motion_search_confident_score, options.motion_search_start_score)
                                  : options.motion_search_confident_score;
    std::optional<TrackResult> best;
    double best_score = incumbent_score;            // a result must beat the plain alignment's
    std::shared_ptr<const Keyframe> best_keyframe;  // the keyframe `best` was aligned against
    auto consider = [&](TrackResult r) {
      if (r.state != TrackingState::kTracking || refused(r)) return false;
      const double score =
          verificationScore(verificationFeatures(r, keyframes->current()->scene_depth_m), verification);
      if (score < min_score || score <= best_score) return false;
      best = std::move(r);
      best_score = score;
      best_keyframe = keyframes->current();
      return score >= stop_score;
    };
    // First the starts the image motion since the last tracked frame points at: the gyro turns
    // that frame into this view, and the shift left is the translation across the view at the
    // scene depth (shift = -f t / depth). Motion along the view (a zoom) does not shift the
    // image: steps along it of 1.5 basins at a quarter of the image diagonal are tried in turn.
    // The shift is good to a few pixels, so these starts align from level 1 at most.
    // A start near the last tracked frame, aligned from level 1 at most (it is good to a few
    // pixels). One more than a grid step from the guess's keyframe is aligned against a keyframe
    // rendered at it (or an earlier start's within a step of it), as the grid's candidates are:
    // near surfaces show other parallax and occlusion edges from there (cycles-room at a third of
    // its rate, start 6: a step of 0.36 m and 20 deg at 1.5 m, the image shift 119 px, did not
    // converge against the keyframe at the previous pose).
    const int shift_level = std::min(search_level, 1);
    auto alignNearStart = [&](const Pose& start) -> Result<TrackResult> {
      const auto beyondStep = [&](const Keyframe& from) {
        return (start.translation() - from.request.T_world_ref.translation()).norm() > grid.step_m;
      };
      if (!beyondStep(keyframe)) {
        VKLOC_TRY_STATUS(restoreKeyframe(guess_keyframe));
      } else if (beyondStep(*keyframes->current())) {
        VKLOC_TRY_STATUS(makeKeyframe(start, out.t_ns, out));
      }
      const int saved_level = search_level;
      search_level = shift_level;
      Result<TrackResult> r = alignFrom(start);
      search_level = saved_level;
      ++out.motion_search_probes;
      return r;
    };
    const bool recent_frame = last_tracked_gray && recent(out.t_ns, last_tracked_gray->t_ns);
    // A start at the pose of point features matched with the last tracked frame (its depth
    // rendered at its pose): against a keyframe rendered there when it lies beyond a grid step.
    if (recent_frame && options.motion_search_feature_start) {
      const Pose& T_previous = last_tracked_gray->T_world_camera;
      const auto t_render = SteadyClock::now();
      Result<RenderOutput> previous_view = keyframes->renderView(camera, T_previous);
      if (!previous_view.ok()) return previous_view.error();
      out.render_ms += msSince(t_render);
      const auto t_features = SteadyClock::now();
      const FeaturePoseOptions& f = options.relocalization.features;
      Result<PointFeatures> previous = detectPointFeatures(last_tracked_gray->gray, f.max_features);
      if (!previous.ok()) return previous.error();
      Result<PointFeatures> now = detectPointFeatures(gray_now, f.max_features);
      if (!now.ok()) return now.error();
      Result<std::optional<FeaturePose>> pose =
          featurePose(*now, *previous, previous_view->depth, camera, T_previous, f);
      if (!pose.ok()) return pose.error();
      out.align_ms += msSince(t_features);
      if (pose->has_value()) {
        const Pose start = (*pose)->T_world_camera;
        Result<TrackResult> r = alignNearStart(start);
        if (!r.ok()) return r.error();
        // Two independent poses that agree: the edges' alignment within feature_agree_fraction of
        // the depth and feature_agree_deg of a feature pose most of whose matches are inliers
        // (motion_search_feature_min_inliers, _min_inlier_fraction). Such a pose is taken
        // without the verification score, which scores true poses low on blurred images (a
        // blurred copy of cycles-city at a third of its frame rate: 1.8 cm from the truth at 0.13).
        const RelocalizationOptions& ro = options.relocalization;
        const Pose delta = start.inverse() * r->T_world_camera;
        const bool agreed =
            r->state == TrackingState::kTracking && !refused(*r) &&
            (*pose)->inliers >= options.motion_search_feature_min_inliers &&
            (*pose)->inliers >= options.motion_search_feature_min_inlier_fraction * (*pose)->matches &&
            delta.translation().norm() <= ro.feature_agree_fraction * keyframes->current()->scene_depth_m &&
            rotationAngleDeg(delta.linear()) <= ro.feature_agree_deg;
        if (agreed && prediction.velocity_unobserved &&
            attitudeFavoursFeaturePose(prediction, start, filterPose(*r),
                                       options.motion_search_feature_attitude_sigmas)) {
          // The feature pose replaces the pose; the alignment's quality and covariance stay as the
          // figures of a pose within the agreement's bounds of it (verification, the filter's weight).
          r->T_world_camera = start;
          r->T_world_camera_edges = start;
          r->T_camera_ref = start.inverse() * keyframes->current()->reference.T_world_ref;
        }
        if (agreed) {
          if (feature_agreed) *feature_agreed = true;
          return std::move(r).value();
        }
        if (consider(std::move(r).value())) return std::move(*best);
      }
    }
    if (recent_frame) {
      const Eigen::Matrix3d R_current_previous =
          guess.linear().transpose() * last_tracked_gray->T_world_camera.linear();
      const Result<std::vector<ImageShift>> shifts =
          estimateImageShifts(last_tracked_gray->gray, gray_now, camera, R_current_previous);
      std::vector<ImageShift> peaks;
      if (shifts.ok()) {
        for (const ImageShift& shift : *shifts) {
          if (shift.response >= options.motion_search_min_response) peaks.push_back(shift);
        }
      }
      if (!peaks.empty()) out.image_shift_px = std::hypot(peaks.front().dx_px, peaks.front().dy_px);
      const double radius_px = 0.25 * std::hypot(camera.width, camera.height);
      const double step_z =
          1.5 * options.search_basin_px * std::ldexp(1.0, shift_level) / radius_px * keyframe.scene_depth_m;
      const double reach_z = options.search_sigmas * std::sqrt(std::max(0.0, prediction.covariance(2, 2)));
      const int steps_z = std::min(2, static_cast<int>(std::ceil(reach_z / step_z - 0.5)));
      for (int k = 0; k <= 2 * steps_z; ++k) {
        const int z = (k + 1) / 2 * (k % 2 == 1 ? 1 : -1);  // 0, +1, -1, +2, -2
        for (const ImageShift& shift : peaks) {
          Pose start = guess;
          const Eigen::Vector3d t_camera(-shift.dx_px * keyframe.scene_depth_m / camera.fx,
                                         -shift.dy_px * keyframe.scene_depth_m / camera.fy, z * step_z);
          start.translation() = last_tracked_gray->T_world_camera.translation() + guess.linear() * t_camera;
          Result<TrackResult> r = alignNearStart(start);
          if (!r.ok()) return r.error();
          if (consider(std::move(r).value())) return std::move(*best);
        }
      }
    }
    // The grid's probes align against the guess's keyframe.
    VKLOC_TRY_STATUS(restoreKeyframe(guess_keyframe));
    // Probes: a few Gauss-Newton steps on the deepest level alone, scored by their inliers there.
    VKLOC_TRY_STATUS(ensureLive(*active, gray_now, out, live_levels, liveLevelsFor(grid.level)));
    const EdgeTrackerOptions probe = probeOptions(grid.level, 5);
    struct Candidate {
      Pose start;
      double inliers;
      double residual_px;  ///< Mean inlier residual (ties of inliers: the deepest level has few points).
    };
    std::vector<Candidate> candidates;
    const auto t0 = SteadyClock::now();
    for (int i = -grid.steps[0]; i <= grid.steps[0]; ++i) {
      for (int j = -grid.steps[1]; j <= grid.steps[1]; ++j) {
        if (i == 0 && j == 0) continue;
        Pose start = guess;
        start.translation() += guess.linear() * Eigen::Vector3d(i * grid.step_m, j * grid.step_m, 0.0);
        Result<TrackResult> r = active->align(keyframe.reference, start, probe);
        if (!r.ok()) return r.error();
        ++out.motion_search_probes;
        candidates.push_back(
            {r->T_world_camera, r->quality.inlier_ratio * r->quality.points_in_image, r->quality.mean_residual_px});
      }
    }
    out.align_ms += msSince(t0);
    // The best probes by inliers (ties, common on the deepest level's few points, by the lower
    // mean residual); probes that converged to the same pose (within half a grid step and a
    // degree) are one candidate: aligning it again would only repeat the same result.
    std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.inliers != b.inliers ? a.inliers > b.inliers : a.residual_px < b.residual_px;
    });
    const size_t wanted = static_cast<size_t>(std::max(1, options.motion_search_candidates));
    std::vector<const Candidate*> distinct;
    for (const Candidate& c : candidates) {
      if (distinct.size() == wanted) break;
      const bool repeated = std::any_of(distinct.begin(), distinct.end(), [&](const Candidate* d) {
        const Pose delta = d->start.inverse() * c.start;
        return delta.translation().norm() < 0.5 * grid.step_m && rotationAngleDeg(delta.linear()) < 1.0;
      });
      if (!repeated) distinct.push_back(&c);
    }
    // Each is aligned against a keyframe rendered at it: the keyframe of the guess, a grid step or
    // more away, shows near surfaces with another parallax and other occlusion edges, and a full
    // alignment against it slides off a start the probe had brought within a few centimetres
    // (cycles-room start 50: three starts 2-5 cm from the truth all ended 19 cm off, lost).
    for (const Candidate* c : distinct) {
      VKLOC_TRY_STATUS(makeKeyframe(c->start, out.t_ns, out));
      Result<TrackResult> r = alignFrom(c->start);
      if (!r.ok()) return r.error();
      if (consider(std::move(r).value())) break;
    }
    // The keyframe the result was aligned against is the current one again (nothing found: the
    // guess's), for the frames that follow from there.
    if (best) {
      if (keyframes->current() != best_keyframe) {
        VKLOC_TRY_STATUS(makeKeyframe(best_keyframe->request.T_world_ref, out.t_ns, out));
      }
      return std::move(*best);
    }
    // A plain pose kept (incumbent_score) goes on with the keyframe it was aligned against.
    if (incumbent_score > 0) {
      VKLOC_TRY_STATUS(restoreKeyframe(guess_keyframe));
    } else if (!distinct.empty()) {
      VKLOC_TRY_STATUS(makeKeyframe(guess, out.t_ns, out));
    }
    return lost;
  }

  /// The keyframes a search without a database uses (RelocalizationOptions::local_headings)
  /// around the last tracked pose `T_world_last` and the predicted position `p_world_guess`.
  /// Views with less than a fifth of their pixels on the model, a surface nearer than 5 cm or
  /// too little contrast to describe are left out, as a database's build leaves them out.
  /// `views` receives each kept keyframe's render (the re-ranking's, when of its size).
  Result<KeyframeDatabase> localDatabase(const Pose& T_world_last, const Eigen::Vector3d& p_world_guess,
                                         double scene_depth_m, std::vector<ImageU8>& views, LocalizationResult& out) {
    const RelocalizationOptions& o = options.relocalization;
    const auto t0 = SteadyClock::now();
    const PinholeCamera small = keyframeViewCamera(camera);  // as a database's views
    const size_t pixels = static_cast<size_t>(small.width) * small.height;
    KeyframeDatabase db(model_fingerprint, camera);
    views.clear();
    std::vector<Eigen::Vector3d> positions{T_world_last.translation()};
    std::vector<float> depths;
    for (size_t p = 0; p < positions.size(); ++p) {
      for (double tilt_deg : o.local_tilts_deg) {
        for (int h = 0; h < o.local_headings; ++h) {
          Pose T = Pose::Identity();
          T.translation() = positions[p];
          T.linear() =
              T_world_last.linear() *
              Eigen::AngleAxisd(2.0 * M_PI * h / o.local_headings, Eigen::Vector3d::UnitY()).toRotationMatrix() *
              Eigen::AngleAxisd(tilt_deg * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
          Result<RenderOutput> view = keyframes->renderView(small, T);
          if (!view.ok()) return view.error();
          const float nearest = surfaceDepths(view->depth, depths);
          if (depths.size() * 5 < pixels || nearest < 0.05f) continue;
          auto mid = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
          std::nth_element(depths.begin(), mid, depths.end());
          Result<ImageU8> thumbnail = descriptorThumbnail(view->gray);
          if (!thumbnail.ok()) return thumbnail.error();
          if (thumbnailContrast(*thumbnail) < o.min_contrast) continue;
          Result<GlobalDescriptor> descriptor = globalDescriptor(view->gray);
          if (!descriptor.ok()) return descriptor.error();
          DatabaseKeyframe k;
          k.T_world_camera = T;
          k.scene_depth_m = *mid;
          k.descriptor = *descriptor;
          db.add(k);
          views.push_back(std::move(view->gray));
        }
      }
      if (p == 0 && scene_depth_m > 0 && p_world_guess.allFinite() &&
          (p_world_guess - positions[0]).norm() > o.local_offset_fraction * scene_depth_m) {
        positions.push_back(p_world_guess);
      }
    }
    out.render_ms += msSince(t0);
    return db;
  }

  /// Where a local search's pose may lie: within radius_m of the segment from a to b (world,
  /// metres).
  struct LocalBound {
    Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
    double radius_m = 0;
    bool holds(const Eigen::Vector3d& x) const {
      const Eigen::Vector3d ab = b - a;
      const double len2 = ab.squaredNorm();
      const double s = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
      return (x - (a + s * ab)).norm() <= radius_m;
    }
  };

  /// Where the local search takes a pose at t_ns: within local_depth_fraction x the anchor's depth
  /// + growth_m_s x the seconds since it (sinceTrackedS) of the path from the anchor to `guess`.
  LocalBound localBound(const SearchAnchor& anchor, const Pose& guess, int64_t t_ns) const {
    const RelocalizationOptions& o = options.relocalization;
    LocalBound bound;
    bound.a = anchor.T_world_camera.translation();
    bound.b = guess.translation().allFinite() ? guess.translation() : bound.a;
    bound.radius_m = o.local_depth_fraction * anchor.scene_depth_m + o.growth_m_s * sinceTrackedS(t_ns);
    return bound;
  }

  /// Relocalization search (RelocalizationOptions) of this frame in `region` (nullopt: the whole
  /// database) of `db`: the attached database (a pose taken inside its box), or with `local` the
  /// keyframes rendered around the last tracked pose (no grid reach; a pose taken only within the
  /// bound; `views`: its keyframes' renders, re-ranked without rendering them again). True with
  /// `found` and its keyframe current when a pose reached min_score; false when none did (or the
  /// frame has too little contrast), the keyframes then reset.
  Result<bool> relocalize(const KeyframeDatabase& db, const std::optional<LocalBound>& local, const ImageU8& gray,
                          int64_t t_ns, const std::optional<SearchRegion>& region, TrackResult& found,
                          LocalizationResult& out, const std::vector<ImageU8>* views = nullptr) {
    const RelocalizationOptions& o = options.relocalization;
    const auto t0 = SteadyClock::now();
    // The keyframes nearest a camera at the region's border may lie outside it: the region grows
    // by the reach of the database's grid.
    std::optional<SearchRegion> searched = region;
    if (searched && !local) searched->radius_m += database_reach_m;
    out.search_radius_m = local      ? local->radius_m
                          : searched ? searched->radius_m
                                     : std::numeric_limits<double>::infinity();
    Result<ImageU8> thumbnail = descriptorThumbnail(gray);
    if (!thumbnail.ok()) return thumbnail.error();
    if (thumbnailContrast(*thumbnail) < o.min_contrast) {
      out.relocalization_ms = msSince(t0);
      return false;  // nothing to recognise: black, saturated, blank
    }
    Result<GlobalDescriptor> descriptor = globalDescriptor(gray);
    if (!descriptor.ok()) return descriptor.error();
    std::vector<KeyframeCandidate> candidates =
        db.query(*descriptor, static_cast<size_t>(std::max(o.candidates, o.rerank_candidates)), searched);
    if (candidates.size() > static_cast<size_t>(o.candidates)) {
      // Re-ranking: each candidate rendered 160 pixels wide and compared with the live image by
      // the peak of their phase correlation (a shift of the whole view does not lower it), less
      // rerank_bits_weight per bit of its descriptor's distance.
      const auto t_rank = SteadyClock::now();
      const PinholeCamera small = scaledCamera(camera, 160);
      ImageU8 live_small(small.width, small.height, 1);
      cv::resize(cv::Mat(gray.height, gray.width, CV_8UC1, const_cast<uint8_t*>(gray.data.data())),
                 cv::Mat(small.height, small.width, CV_8UC1, live_small.data.data()),
                 cv::Size(small.width, small.height), 0, 0, cv::INTER_AREA);
      std::vector<std::pair<double, size_t>> ranked;
      for (size_t k = 0; k < candidates.size(); ++k) {
        const size_t index = candidates[k].index;
        std::optional<RenderOutput> rendered;
        if (!views || index >= views->size() || (*views)[index].width != small.width ||
            (*views)[index].height != small.height) {
          Result<RenderOutput> view = keyframes->renderView(small, db.keyframes()[index].T_world_camera);
          if (!view.ok()) return view.error();
          rendered = std::move(view).value();
        }
        const ImageU8& render = rendered ? rendered->gray : (*views)[index];
        Result<std::vector<ImageShift>> shift =
            estimateImageShifts(render, live_small, small, Eigen::Matrix3d::Identity(), 0, 1);
        const double peak = shift.ok() && !shift->empty() ? shift->front().response : 0.0;
        ranked.emplace_back(peak - o.rerank_bits_weight * candidates[k].distance, k);
      }
      std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
      std::vector<KeyframeCandidate> kept;
      for (size_t k = 0; k < static_cast<size_t>(o.candidates); ++k) kept.push_back(candidates[ranked[k].second]);
      candidates = std::move(kept);
      out.render_ms += msSince(t_rank);
    }
    if (candidates.empty()) {  // no keyframe in the region: the current keyframe stays
      out.relocalization_ms = msSince(t0);
      return false;
    }
    out.relocalization_top_keyframe = static_cast<int64_t>(candidates.front().index);
    keyframes->reset();
    uploaded_id = 0;
    const int deepest = std::max(0, std::min(options.max_search_level, options.live.levels - 1));
    const int saved_level = search_level;
    relocalizing = true;
    struct Restore {
      Impl& m;
      int level;
      ~Restore() {
        m.search_level = level;
        m.relocalizing = false;
      }
    } restore{*this, saved_level};
    auto alignAt = [&](const Pose& start, int level) {
      search_level = level;
      return align(*active, gray, start, out, live_levels);
    };
    // Stage 1: a keyframe at each candidate; starts at its pose and at that pose turned by the
    // image shifts between its render and the live image; each start probed with a few
    // Gauss-Newton steps on the deepest level alone and scored there.
    VKLOC_TRY_STATUS(ensureLive(*active, gray, out, live_levels, liveLevelsFor(deepest)));
    const EdgeTrackerOptions probe = probeOptions(deepest, 10);
    struct Probe {
      std::shared_ptr<const Keyframe> keyframe;
      size_t candidate = 0;  ///< Database index of the keyframe it started from.
      Pose start = Pose::Identity();
      double inliers = 0;       ///< Above chance, on the deepest level.
      int feature_inliers = 0;  ///< RANSAC inliers of a start from point features (0: another start).
    };
    std::vector<Probe> probes;
    std::optional<PointFeatures> live_features;  ///< Of the live image, once a render needs them.
    KeyframeRequest request;
    request.t_ns = t_ns;
    request.frame_index = frame_index;
    for (const KeyframeCandidate& c : candidates) {
      ++out.relocalization_candidates;
      const Pose& T_candidate = db.keyframes()[c.index].T_world_camera;
      request.T_world_ref = T_candidate;
      request.keep_gray = o.shift_starts > 0 || o.feature_starts;
      request.keep_depth = o.feature_starts;
      VKLOC_TRY_STATUS(keyframes->makeNow(request, out.render_ms, out.reference_ms));
      // The backends hold the keyframe the probes align against (a device backend keeps it).
      VKLOC_TRY_STATUS(uploadKeyframe());
      out.reference_rendered = true;
      const std::shared_ptr<const Keyframe> keyframe = keyframes->current();
      if (keyframe->reference.points.size() < 6) continue;
      std::vector<Pose> starts{T_candidate};
      if (o.shift_starts > 0 && !keyframe->gray.data.empty()) {
        // The candidate render's principal ray is seen at the principal point + (dx, dy) in the
        // live view: the start turned so that it is (the rotation left between the two views; a
        // shift from a translation across the view is turned into a rotation too, which the
        // alignment's basin takes).
        Result<std::vector<ImageShift>> shifts =
            estimateImageShifts(keyframe->gray, gray, camera, Eigen::Matrix3d::Identity(), 2, o.shift_starts);
        if (shifts.ok()) {
          for (const ImageShift& shift : *shifts) {
            if (shift.response < o.min_response) continue;
            const Eigen::Vector3d ray_live =
                Eigen::Vector3d(shift.dx_px / camera.fx, shift.dy_px / camera.fy, 1.0).normalized();
            const Eigen::Matrix3d R_live_candidate =
                Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), ray_live).toRotationMatrix();
            Pose start = T_candidate;
            start.linear() = T_candidate.linear() * R_live_candidate.transpose();
            starts.push_back(start);
          }
        }
      }
      // Motion along the view does not shift the image: each start also at +-depth_steps x
      // depth_step of the candidate's scene depth along its optical axis.
      const size_t turned = starts.size();
      for (size_t k = 0; k < turned; ++k) {
        for (int step = 1; step <= o.depth_steps; ++step) {
          for (int sign : {1, -1}) {
            Pose start = starts[k];
            start.translation() += start.linear().col(2) * (sign * step * o.depth_step * keyframe->scene_depth_m);
            starts.push_back(start);
          }
        }
      }
      // The pose of point features matched with the render (its own depth: no depth steps).
      if (o.feature_starts && !keyframe->gray.data.empty() && !keyframe->depth.data.empty()) {
        const auto t_features = SteadyClock::now();
        if (!live_features) {
          Result<PointFeatures> detected = detectPointFeatures(gray, o.features.max_features);
          if (!detected.ok()) return detected.error();
          live_features = std::move(detected).value();
        }
        Result<PointFeatures> render_features = detectPointFeatures(keyframe->gray, o.features.max_features);
        if (!render_features.ok()) return render_features.error();
        Result<std::optional<FeaturePose>> pose =
            featurePose(*live_features, *render_features, keyframe->depth, camera, T_candidate, o.features);
        if (!pose.ok()) return pose.error();
        if (pose->has_value()) {  // featurePose gives only valid poses
          // Aligned fully from the feature pose itself (no probe on the deepest level, whose
          // few points can wander decimetres from a start a few centimetres off); ranked by
          // feature support below.
          Probe p;
          p.keyframe = keyframe;
          p.candidate = c.index;
          p.start = (*pose)->T_world_camera;
          p.feature_inliers = (*pose)->inliers;
          probes.push_back(std::move(p));
          ++out.relocalization_feature_starts;
        }
        out.align_ms += msSince(t_features);
      }
      const auto t_probe = SteadyClock::now();
      for (const Pose& start : starts) {
        Result<TrackResult> r = active->align(keyframe->reference, start, probe);
        if (!r.ok()) return r.error();
        Probe p;
        p.keyframe = keyframe;
        p.candidate = c.index;
        p.start = r->T_world_camera;
        // Inliers beyond those a random pose would have (the scene's own edge density).
        p.inliers = (r->quality.inlier_ratio - r->quality.chance_inlier_ratio) * r->quality.points_in_image;
        if (isValidPose(p.start)) probes.push_back(std::move(p));
      }
      out.align_ms += msSince(t_probe);
    }
    // Stage 2: the best probes aligned fully, refined against keyframes rendered at the estimate
    // (the candidate's may be a metre off) and verified.
    std::stable_sort(probes.begin(), probes.end(),
                     [](const Probe& a, const Probe& b) { return a.inliers > b.inliers; });
    if (o.top_candidate_first && !probes.empty()) {
      // The deepest level's few points rank a near start below wrong ones with more inliers:
      // the best-ranked candidate's best probe goes first whatever its inliers.
      const size_t top = candidates.front().index;
      auto it = std::find_if(probes.begin(), probes.end(), [top](const Probe& p) { return p.candidate == top; });
      if (it != probes.end()) std::rotate(probes.begin(), it, std::next(it));
    }
    if (o.feature_starts) {
      // Feature starts that another candidate's agrees with go first, by their support: the
      // RANSAC inliers of every feature start that agrees with theirs (within
      // feature_agree_fraction of the scene depth and feature_agree_deg); then the best lone one;
      // the other lone ones last. One render's pose alone can be wrong with many inliers: a
      // texture the model repeats (books on shelves, a poster twice) matches as well at the
      // wrong copy, and the poses of several renders then outvote it.
      std::vector<std::pair<int, size_t>> agreed, lone;  // (support, probe)
      for (size_t i = 0; i < probes.size(); ++i) {
        const Probe& a = probes[i];
        if (a.feature_inliers == 0) continue;
        const double depth_m = a.keyframe->scene_depth_m;
        int support = 0, others = 0;
        for (size_t j = 0; j < probes.size(); ++j) {
          const Probe& b = probes[j];
          if (b.feature_inliers == 0) continue;
          if ((a.start.translation() - b.start.translation()).norm() <= o.feature_agree_fraction * depth_m &&
              rotationAngleDeg(a.start.linear().transpose() * b.start.linear()) <= o.feature_agree_deg) {
            support += b.feature_inliers;
            others += j != i;
          }
        }
        (others > 0 ? agreed : lone).emplace_back(support, i);
      }
      const auto by_support = [](const auto& a, const auto& b) { return a.first > b.first; };
      std::stable_sort(agreed.begin(), agreed.end(), by_support);
      std::stable_sort(lone.begin(), lone.end(), by_support);
      std::vector<Probe> ordered;
      for (const auto& [support, i] : agreed) ordered.push_back(probes[i]);
      if (!lone.empty()) ordered.push_back(probes[lone.front().second]);
      for (size_t i = 0; i < probes.size(); ++i) {
        if (probes[i].feature_inliers == 0) ordered.push_back(probes[i]);
      }
      for (size_t k = 1; k < lone.size(); ++k) ordered.push_back(probes[lone[k].second]);
      probes = std::move(ordered);
    }
    // A refined pose verified at tracking's score; taken alone at min_score, or when alignments
    // from agreeing_candidates different keyframes reached it.
    struct Refined {
      TrackResult track;
      double score = 0;
      std::shared_ptr<const Keyframe> keyframe;
      size_t candidate = 0;
    };
    std::vector<Refined> refined;
    auto agreeing = [&](const Refined& r) {
      const double depth_m = r.keyframe->scene_depth_m;
      std::vector<size_t> seen{r.candidate};
      for (const Refined& other : refined) {
        const Pose& a = r.track.T_world_camera;
        const Pose& b = other.track.T_world_camera;
        if (std::find(seen.begin(), seen.end(), other.candidate) == seen.end() &&
            (a.translation() - b.translation()).norm() <= o.agree_depth_fraction * depth_m &&
            rotationAngleDeg(a.linear().transpose() * b.linear()) <= o.agree_deg) {
          seen.push_back(other.candidate);
        }
      }
      return seen.size();
    };
    auto best = [&]() -> const Refined* {
      const Refined* chosen = nullptr;
      for (const Refined& r : refined) {
        const bool taken = r.score >= o.min_score ||
                           (o.agreeing_candidates > 0 && agreeing(r) >= static_cast<size_t>(o.agreeing_candidates));
        if (taken && (!chosen || r.score > chosen->score)) chosen = &r;
      }
      return chosen;
    };
    request.keep_gray = false;
    request.keep_depth = false;
    // The frame aligned from `T` against a keyframe rendered at `T` (a refinement).
    auto alignAgainstRenderAt = [&](const Pose& T) -> Result<TrackResult> {
      request.T_world_ref = T;
      VKLOC_TRY_STATUS(keyframes->makeNow(request, out.render_ms, out.reference_ms));
      VKLOC_TRY_STATUS(uploadKeyframe());
      return alignAt(T, 0);
    };
    auto refine = [&](const Probe& p) -> Status {
      keyframes->restore(p.keyframe);
      VKLOC_TRY_STATUS(uploadKeyframe());
      Result<TrackResult> r = alignAt(p.start, std::min(1, deepest));
      if (!r.ok()) return r.error();
      TrackResult track = std::move(r).value();
      for (int k = 0; k < o.refinements && isValidPose(track.T_world_camera); ++k) {
        Result<TrackResult> again = alignAgainstRenderAt(track.T_world_camera);
        if (!again.ok()) return again.error();
        track = std::move(again).value();
      }
      double score =
          verificationScore(verificationFeatures(track, keyframes->current()->scene_depth_m), options.verification);
      if (o.realign_level >= 0 && track.state == TrackingState::kTracking && score < o.min_score) {
        // Verified below min_score: once more from itself from a deeper level (realign_level),
        // then against a keyframe rendered at that result; the better verified pose is kept.
        const std::shared_ptr<const Keyframe> kept = keyframes->current();
        Result<TrackResult> wide = alignAt(track.T_world_camera, std::min(o.realign_level, deepest));
        if (!wide.ok()) return wide.error();
        std::optional<TrackResult> again;
        if (wide->state == TrackingState::kTracking && isValidPose(wide->T_world_camera)) {
          Result<TrackResult> fine = alignAgainstRenderAt(wide->T_world_camera);
          if (!fine.ok()) return fine.error();
          if (fine->state == TrackingState::kTracking) again = std::move(fine).value();
        }
        const double again_score =
            again ? verificationScore(verificationFeatures(*again, keyframes->current()->scene_depth_m),
                                      options.verification)
                  : 0.0;
        if (again && again_score > score) {
          track = std::move(*again);
          score = again_score;
        } else if (keyframes->current() != kept) {
          keyframes->restore(kept);
          VKLOC_TRY_STATUS(uploadKeyframe());
        }
      }
      const Eigen::Vector3d& position = track.T_world_camera.translation();
      const bool inside =
          local ? local->holds(position)
                : (position.array() >= database_min.array()).all() && (position.array() <= database_max.array()).all();
      if (track.state == TrackingState::kTracking && score >= options.verification.min_score && inside) {
        refined.push_back(Refined{std::move(track), score, keyframes->current(), p.candidate});
      }
      return Status::success();
    };
    // The best refined_probes probes; then, while a verified pose waits for agreement, the best
    // probe of each other candidate (at most agreement_probes more) until one agrees.
    std::vector<size_t> refined_candidates;
    int refined_count = 0, extra = 0;
    for (const Probe& p : probes) {
      const Refined* b = best();
      if (b && b->score >= o.confident_score) break;
      if (refined_count >= o.refined_probes) {
        if (b || refined.empty() || extra >= o.agreement_probes) break;
        if (std::find(refined_candidates.begin(), refined_candidates.end(), p.candidate) != refined_candidates.end()) {
          continue;
        }
        ++extra;
      }
      ++refined_count;
      refined_candidates.push_back(p.candidate);
      VKLOC_TRY_STATUS(refine(p));
    }
    const Refined* chosen = best();
    const bool have = chosen != nullptr;
    if (have) {
      found = chosen->track;
      keyframes->restore(chosen->keyframe);
      VKLOC_TRY_STATUS(uploadKeyframe());
    } else {
      keyframes->reset();
      uploaded_id = 0;
    }
    out.relocalization_ms = msSince(t0);
    return have;
  }

  /// Restarts the motion prior at a pose of the frame at t_ns, moving at v_world (m/s) or at an
  /// unknown velocity. The reset forgets the IMU readings and the filter starts at a visual pose
  /// only after one: the newest reading is given again, so the pose the prior takes next starts
  /// the filter now. (Without it the frames after the restart would be predicted by constant
  /// velocity, and lost ones neither bridged nor searched, until a frame is tracked again.)
  void restartPrior(const Pose& T_world_camera, const std::optional<Eigen::Vector3d>& v_world, int64_t t_ns,
                    double sigma_velocity_m_s = 0) {
    motion->reset(T_world_camera, v_world, sigma_velocity_m_s);
    if (last_imu && last_imu->t_ns <= t_ns) (void)motion->addImu(*last_imu);
  }

  /// Takes a relocalized pose; the frame counts as tracked. The motion prior restarts there
  /// (velocity unknown) unless `prediction` is an IMU prediction the pose agrees with (its gate):
  /// a prior that bridged the loss keeps its velocity.
  void adoptRelocalized(const TrackResult& track, int64_t t_ns, const ImageU8& gray,
                        const std::optional<MotionPrediction>& prediction, std::optional<int64_t> previous_t_ns,
                        LocalizationResult& out, bool local_search = false) {
    const Keyframe& keyframe = *keyframes->current();
    const bool agrees = prediction && prediction->inertial &&
                        motion->consistent(*prediction, filterPose(track), track.covariance, keyframe.scene_depth_m);
    if (!agrees) {
      // The velocity from the previous frame when that one was relocalized too (a search that
      // goes on frame after frame), else unknown (a pose tracked before a jump is no reference).
      // Without the IMU a local search's pose lies within its bound of the last tracked one (no
      // jump), and the motion from that one over the time between them (a few frames: errors of
      // a centimetre over 0.1-0.5 s) is the velocity; at rest instead, a camera found again whose
      // next frame is lost too (the frame after a relocalized one must verify confidently without
      // the IMU) is searched for where it was found while it moves on (the room without its IMU,
      // walking at 2.5 m/s: 17 frames lost in a row). With the IMU the search runs only after a
      // long bridge and the filter restarts at an unknown velocity, as after a database's search.
      const bool after_relocalized = previous_t_ns && last_relocalized_t_ns == previous_t_ns && last_tracked_gray &&
                                     last_tracked_gray->t_ns == *previous_t_ns;
      std::optional<Eigen::Vector3d> v_world;
      if (last_tracked_gray && t_ns > last_tracked_gray->t_ns && (after_relocalized || (local_search && !last_imu))) {
        v_world = (track.T_world_camera.translation() - last_tracked_gray->T_world_camera.translation()) /
                  (static_cast<double>(t_ns - last_tracked_gray->t_ns) * 1e-9);
      }
      restartPrior(track.T_world_camera, v_world, t_ns);
    }
    motion->setSceneDepth(keyframe.scene_depth_m);
    motion->addVisualPose(t_ns, filterPose(track), track.covariance);
    keyframes->frameTracked(track.quality);
    tracked_since_reset = true;
    refusals = {};
    refused_stretch = {};
    restart_kept_velocity_t_ns.reset();
    untracked = 0;
    failed_searches = 0;
    last_tracked_t_ns = t_ns;
    if (!last_tracked_gray) last_tracked_gray.emplace();
    last_tracked_gray->gray = gray;
    last_tracked_gray->T_world_camera = track.T_world_camera;
    last_tracked_gray->t_ns = t_ns;
    last_tracked_gray->scene_depth_m = keyframe.scene_depth_m;
    last_relocalized_t_ns = t_ns;
    out.state = TrackingState::kRelocalized;
    out.T_world_camera = track.T_world_camera;
    out.covariance = track.covariance;
    out.quality = track.quality;
    out.visual_rejected = false;
    out.scene_depth_m = keyframe.scene_depth_m;
    out.reference_points = static_cast<int>(keyframe.reference.points.size());
    out.verify_score = verificationScore(verificationFeatures(track, keyframe.scene_depth_m), options.verification);
    poseTaken(out.verify_score);
    out.keyframe_id = keyframe.id;
    out.keyframe_age_frames = frame_index - keyframe.request.frame_index;
  }

  /// Forgets what tracking learnt since the last pose was taken (the motion prior's pose is
  /// reset by the caller): as at a start.
  void forgetTrack() {
    tracked_since_reset = false;
    last_tracked_gray.reset();
    start_anchor.reset();
    first_t_ns.reset();
    start_on_probation.reset();
    refusals = {};
    refused_stretch = {};
    restart_kept_velocity_t_ns.reset();
    untracked = 0;
    failed_searches = 0;
    last_tracked_t_ns.reset();
    last_relocalized_t_ns.reset();
    last_camera_pose.reset();
    local_database.reset();
    local_views.clear();
    local_database_pose.reset();
  }

  /// Takes the pose global initialization's search found (adoptRelocalized); with the IMU and
  /// RelocalizationOptions::confirm_start it waits for the next frame to confirm it.
  void adoptStartPose(const TrackResult& found, int64_t t_ns, const ImageU8& gray, std::optional<int64_t> previous_t_ns,
                      LocalizationResult& out) {
    adoptRelocalized(found, t_ns, gray, std::nullopt, previous_t_ns, out);
    if (options.relocalization.confirm_start && last_imu) {
      confirming = true;
      out.state = TrackingState::kInitializing;
      out.confirming = true;
    }
  }

  /// A frame with nothing to align (checkImageContent): no alignment or search; the motion prior
  /// bridges it (kInertial with the IMU, else kLost; kInitializing while a search is on). It
  /// counts as a lost frame: a later frame that is not tracked is searched for at once.
  LocalizationResult emptyFrame(int64_t t_ns, const ImageContentCheck& content,
                                const std::optional<Pose>& guess_given) {
    LocalizationResult out;
    out.t_ns = t_ns;
    out.image_content = content.content;
    out.image_contrast = content.contrast;
    live_levels = 0;
    last_t_ns = t_ns;
    if (searching) {
      out.state = TrackingState::kInitializing;
      return out;
    }
    const std::optional<MotionPrediction> prediction = motion->predict(t_ns);
    const Pose guess = guess_given ? *guess_given : prediction->T_world_camera;
    out.T_world_camera = guess;
    if (prediction && prediction->inertial) out.inertial_sigma_m = prediction->sigma_m;
    applyBridge(motion->bridge(t_ns, prediction, guess), out);
    keyframes->frameNotTracked();  // the next frame aligns against a keyframe made at its guess
    ++untracked;
    if (confirming || start_on_probation) {  // the search's (a first) pose waits for a frame to confirm it
      out.state = TrackingState::kInitializing;
      out.confirming = true;
    }
    if (const Keyframe* current = keyframes->current().get()) {
      out.keyframe_id = current->id;
      out.keyframe_age_frames = frame_index - current->request.frame_index;
    }
    return out;
  }

  /// First-frame calibration of kAuto with calibrate_backend: run both and keep the faster.
  Status calibrate(const ImageU8& gray, const Pose& guess) {
    calibration_pending = false;
    double best[2] = {0, 0};
    EdgeTrackingBackend* backends[2] = {cpu_backend.get(), device_backend.get()};
    for (int b = 0; b < 2; ++b) {
      // Twice each: the first run includes shader compilation / allocation.
      for (int run = 0; run < 2; ++run) {
        LocalizationResult scratch;
        int built = 0;
        Result<TrackResult> r = align(*backends[b], gray, guess, scratch, built);
        if (!r.ok()) return r.error();
        best[b] = scratch.live_ms + scratch.align_ms;
      }
    }
    // The other backend is released: it would only take keyframe uploads (device memory).
    if (best[1] < best[0]) {
      active = device_backend.get();
      cpu_backend.reset();
    } else {
      active = cpu_backend.get();
      device_backend.reset();
    }
    backend_reason = fmt::format("calibrated on the first frame: CPU {:.1f} ms, device {:.1f} ms", best[0], best[1]);
    return Status::success();
  }

  /// Worker mode: after a frame, asks for the next keyframe when the pose the camera will have
  /// once it is ready no longer fits the current one.
  void requestNextKeyframe(int64_t t_ns, const Pose& fallback, LocalizationResult& out) {
    // A keyframe is adopted by the first frame that starts after it is made.
    int lead = 1;
    if (keyframe_ms_mean > 0 && frame_period_ms_mean > 0) {
      lead = static_cast<int>(std::ceil(keyframe_ms_mean / frame_period_ms_mean));
    }
    lead = std::clamp(lead, std::min(1, options.max_keyframe_lead_frames), options.max_keyframe_lead_frames);
    const int64_t t_target = t_ns + lead * frame_interval_ns;
    Pose T_target = fallback;
    if (front && front->options().kind == ViewKind::kStabilised) {
      // The view the camera will have then: stabilised at the attitude predicted for then.
      if (std::optional<MotionPrediction> camera_then = view_prior->cameraPrior().predict(t_target)) {
        T_target = camera_then->T_world_camera * front->viewExtrinsic(camera_then->T_world_camera);
      }
    } else if (std::optional<MotionPrediction> predicted = motion->predict(t_target)) {
      T_target = predicted->T_world_camera;
    }
    if (!keyframes->needsKeyframe(T_target)) return;
    KeyframeRequest request;
    request.T_world_ref = T_target;
    request.t_ns = t_target;
    request.frame_index = frame_index + lead;
    out.keyframe_requested = keyframes->request(request);
  }
};

Localizer::Localizer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Localizer::~Localizer() = default;

Result<std::unique_ptr<Localizer>> Localizer::create(const Model& model, const PinholeCamera& camera,
                                                     const LocalizerOptions& options,
                                                     std::shared_ptr<Accelerator> accelerator) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateOptions(options));
  VKLOC_TRY_STATUS(validateModel(model));
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  // Pyramid levels nobody reads are not built: the tracker starts at coarsest_level and the
  // far-points-first hypothesis at far_first_coarsest_level (-1: the live frame's coarsest).
  const EdgeTrackerOptions& t = options.tracker;
  if (t.coarsest_level >= 0 && (t.far_first_depth_quantile <= 0 || t.far_first_coarsest_level >= 0)) {
    const int deepest = std::max(t.coarsest_level, t.far_first_depth_quantile > 0 ? t.far_first_coarsest_level : 0);
    impl->options.live.levels = std::min(options.live.levels, std::max(deepest, t.finest_level) + 1);
  }
  // The deepest search level can be built whenever the search can start there: the EKF's
  // uncertain predictions, and without a covariance the first frame after a start (searchLevel);
  // a frame builds it only then (liveLevelsFor), the keyframes always.
  impl->usual_levels = impl->options.live.levels;
  if (options.max_search_level > 0) {
    impl->options.live.levels = std::max(impl->options.live.levels, std::min(8, options.max_search_level + 1));
  }
  impl->options.reference.levels = impl->options.live.levels;
  impl->options.verification.inlier_threshold_px = options.tracker.inlier_threshold_px;
  impl->camera = camera;
  impl->model_fingerprint = modelFingerprint(model);
  impl->initializer = Initializer(initializerOptions(options));
  if (options.inertial.filter == InertialFilter::kEkf) {
    impl->motion = std::make_unique<EkfPrior>(options.inertial, options.motion);
  } else {
    impl->motion = std::make_unique<InertialPrior>(options.inertial, options.motion);
  }

  std::unique_ptr<Renderer> renderer;
  if (accelerator) {
    auto created = accelerator->createRenderer(model);
    if (!created.ok()) return created.error();
    renderer = std::move(created).value();
    impl->device_name = accelerator->describe();
    impl->accelerator = accelerator;
  } else {
    auto created = CpuRenderer::create(model);
    if (!created.ok()) return created.error();
    renderer = std::move(created).value();
  }
  // Synchronous keyframes use every core (the CPU rasterizer's bands, the edge levels on
  // OpenCV's pool); the worker thread uses its own alone.
  const bool on_worker = options.keyframe_threading == KeyframeThreading::kWorkerThread;
  ReferenceEdgeOptions keyframe_edges = impl->options.reference;
  if (on_worker) keyframe_edges.parallel = false;
  RenderSettings keyframe_render = impl->options.render;
  const int cores = options.keyframe_render_threads > 0 ? options.keyframe_render_threads : availableCores();
  keyframe_render.threads = on_worker && options.keyframe_render_threads == 0 ? 1 : cores;
  auto maker = std::make_unique<KeyframeMaker>(std::move(renderer), camera, keyframe_render, keyframe_edges);
  // What the caller waits for (a start's or a loss's keyframe, the relocalization's renders)
  // runs while the worker and the tracking thread are idle: every core.
  maker->setWaitingThreads(cores, impl->options.reference.parallel);
  if (!accelerator) {
    impl->render_threads =
        keyframe_render.threads == cores
            ? fmt::format(", {} thread{}", cores, cores == 1 ? "" : "s")
            : fmt::format(", {} thread on the worker, {} while the caller waits", keyframe_render.threads, cores);
  }
  impl->keyframes = std::make_unique<KeyframeManager>(std::move(maker), keyframeOptions(options));

  bool on_device = false;
  switch (options.backend) {
    case LocalizerBackend::kCpu:
      impl->backend_reason = "asked for";
      break;
    case LocalizerBackend::kVulkan:
      if (!accelerator) {
        return makeError(ErrorCode::kNoDevice, "Localizer: backend vulkan needs a Vulkan device (none given)");
      }
      on_device = true;
      impl->backend_reason = "asked for";
      break;
    case LocalizerBackend::kAuto:
      if (!accelerator) {
        impl->backend_reason = "no Vulkan device";
      } else if (options.calibrate_backend) {
        impl->calibration_pending = true;
        impl->backend_reason = "to be calibrated on the first frame";
      } else if (accelerator->isCpuDriver()) {
        impl->backend_reason = "the Vulkan device is a CPU driver, where OpenCV is several times faster";
      } else {
        on_device = true;
        impl->backend_reason = "the Vulkan device is a GPU";
      }
      break;
  }
  if (!on_device || impl->calibration_pending) {
    auto cpu = CpuEdgeTrackingBackend::create(camera, impl->options.live);
    if (!cpu.ok()) return cpu.error();
    impl->cpu_backend = std::move(cpu).value();
  }
  if (on_device || impl->calibration_pending) {
    auto device = accelerator->createEdgeBackend(camera, impl->options.live);
    if (!device.ok()) return device.error();
    impl->device_backend = std::move(device).value();
  }
  impl->active = on_device ? impl->device_backend.get() : impl->cpu_backend.get();
  return std::unique_ptr<Localizer>(new Localizer(std::move(impl)));
}

void Localizer::reset(const Pose& T_world_camera, const std::optional<Eigen::Vector3d>& v_world_camera) {
  Impl& m = *impl_;
  m.keyframes->reset();
  m.uploaded_id = 0;
  m.last_t_ns.reset();
  m.forgetTrack();
  m.searching = false;
  m.confirming = m.confirm_extended = false;
  m.search_region.reset();
  m.last_imu.reset();
  if (m.front && isValidPose(T_world_camera)) {
    // The motion prior works on the camera; its interface on the view of the pose given.
    m.view_prior->setView(m.front->viewExtrinsic(T_world_camera));
    m.motion->reset(m.view_prior->toView(T_world_camera), v_world_camera);
    m.last_camera_pose = T_world_camera;
    return;
  }
  m.motion->reset(T_world_camera, v_world_camera);  // timestamps may start over
}

Status Localizer::setKeyframeDatabase(std::shared_ptr<const KeyframeDatabase> database) {
  Impl& m = *impl_;
  if (database) {
    if (database->modelFingerprint() != m.model_fingerprint) {
      return makeError(ErrorCode::kInvalidArgument,
                       "Localizer: the keyframe database was built for another model (or another placement of it)");
    }
    const PinholeCamera& c = database->camera();
    const double fov_ratio_x = (c.fx / c.width) / (m.camera.fx / m.camera.width);
    const double fov_ratio_y = (c.fy / c.height) / (m.camera.fy / m.camera.height);
    if (std::abs(fov_ratio_x - 1.0) > 0.05 || std::abs(fov_ratio_y - 1.0) > 0.05) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("Localizer: the keyframe database was built for a camera of another field of view "
                                   "(fx/width {:.4g}, this camera's {:.4g})",
                                   c.fx / c.width, m.camera.fx / m.camera.width));
    }
  }
  m.database = std::move(database);
  m.database_reach_m = m.database ? m.database->positionReach() : 0.0;
  if (m.database && m.database_reach_m > 0 && m.options.relocalization.inside_database_box) {
    const auto [lo, hi] = m.database->positionBounds();
    m.database_min = lo.array() - m.database_reach_m;
    m.database_max = hi.array() + m.database_reach_m;
  } else {  // not asked for, or a single position (or none): nothing bounds a found pose
    m.database_min = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
    m.database_max = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  }
  if (!m.database) m.searching = m.confirming = m.confirm_extended = false;
  return Status::success();
}

Status Localizer::startSearch(const std::optional<SearchRegion>& region) {
  Impl& m = *impl_;
  if (!m.database) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: a search needs a keyframe database (setKeyframeDatabase)");
  }
  if (region && (!region->center_world.allFinite() || std::isnan(region->radius_m) || !(region->radius_m >= 0))) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: the search region must have a finite centre and radius >= 0");
  }
  reset(Pose::Identity());
  m.motion->reset(std::nullopt, std::nullopt);  // no pose until the search finds one
  m.last_camera_pose.reset();                   // nor an attitude for a stabilised view
  m.searching = true;
  m.search_region = region;
  return Status::success();
}

Status Localizer::addImu(const ImuSample& sample) {
  Status status = impl_->motion->addImu(sample);
  if (status.ok()) impl_->last_imu = sample;
  return status;
}

std::vector<FilterOutput> Localizer::takeFilterOutputs() { return impl_->motion->takeOutputs(); }

std::string Localizer::backendSummary() const {
  const Impl& m = *impl_;
  const std::string where = m.calibration_pending ? "auto (not yet calibrated)" : m.active->describe();
  std::string policy = rerenderPolicyName(m.options.policy);
  if (m.options.policy == RerenderPolicy::kWhenNeeded) {
    const RerenderThresholds& r = m.options.rerender;
    policy += fmt::format(" (moved > {:g} x depth or > {:g} deg, inliers < {:g}, or {} frames)",
                          r.max_translation_depth_ratio, r.max_rotation_deg, r.min_inlier_ratio, r.max_frames);
  }
  return fmt::format("render on {}{}; live edges + alignment on {} ({}); re-render {}, {}{}",
                     m.keyframes->rendererDescription(), m.render_threads, where, m.backend_reason, policy,
                     m.worker() ? "keyframes on a worker thread" : "keyframes made synchronously",
                     m.front && m.front->needsRemap() ? "; lens image remapped by " + m.front->remapDescription() : "");
}

Status Localizer::setCameraFront(std::unique_ptr<CameraFront> front) {
  Impl& m = *impl_;
  if (front) {
    const PinholeCamera& v = front->view();
    const PinholeCamera& c = m.camera;
    if (v.width != c.width || v.height != c.height || std::abs(v.fx - c.fx) > 1e-9 * c.fx ||
        std::abs(v.fy - c.fy) > 1e-9 * c.fy || std::abs(v.cx - c.cx) > 1e-9 || std::abs(v.cy - c.cy) > 1e-9) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("Localizer: the camera front's view ({}x{}, fx {:.6g}) is not the camera the "
                                   "Localizer was made for ({}x{}, fx {:.6g})",
                                   v.width, v.height, v.fx, c.width, c.height, c.fx));
    }
    if (!m.view_prior) {
      auto wrapped = std::make_unique<ViewPrior>(std::move(m.motion));
      m.view_prior = wrapped.get();
      m.motion = std::move(wrapped);
    }
  }
  if (m.view_prior) m.view_prior->setView(Pose::Identity());
  // The remap runs where the live stages do: on a GPU (its remap stage) when they run there.
  if (front && front->needsRemap() && m.accelerator && m.active == m.device_backend.get() &&
      !m.accelerator->isCpuDriver()) {
    Result<std::unique_ptr<ImageRemapper>> remapper =
        m.accelerator->createRemapper(front->table(Eigen::Matrix3d::Identity()), front->options().interpolation);
    if (remapper.ok()) front->setRemapper(std::move(remapper).value());
  }
  m.front = std::move(front);
  return Status::success();
}

const CameraFront* Localizer::cameraFront() const { return impl_->front.get(); }

Result<LocalizationResult> Localizer::localize(int64_t t_ns, const ImageU8& image,
                                               const std::optional<Pose>& T_world_camera_guess) {
  Impl& m = *impl_;
  if (!m.front) {
    Result<LocalizationResult> result = localizeView(t_ns, image, T_world_camera_guess);
    if (result.ok() && !result->pose_filtered) result->T_world_camera_visual = result->T_world_camera;
    return result;
  }
  const auto t_start = SteadyClock::now();
  if (T_world_camera_guess && !isValidPose(*T_world_camera_guess)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: the pose guess is not a finite rigid transform");
  }
  // The view of this frame (eq. 8): stabilised at the camera's attitude as the guess, the
  // filter's attitude (also past max_inertial_s without a pose, when its prediction has gone back
  // to the motion model: the gyro still carries the attitude), the prior's prediction or the last
  // pose has it (only the view's choice depends on it: the extrinsic used below is the exact one
  // of the image made).
  Pose T_camera_view = Pose::Identity();
  if (m.front->options().kind == ViewKind::kStabilised) {
    const MotionPrior& prior = m.view_prior->cameraPrior();
    std::optional<Eigen::Matrix3d> R_world_camera =
        T_world_camera_guess ? std::optional<Eigen::Matrix3d>(T_world_camera_guess->linear()) : prior.attitude(t_ns);
    if (!R_world_camera) {
      if (std::optional<MotionPrediction> p = prior.predict(t_ns)) R_world_camera = p->T_world_camera.linear();
    }
    if (!R_world_camera && m.last_camera_pose) R_world_camera = m.last_camera_pose->linear();
    if (R_world_camera) T_camera_view.linear() = m.front->viewRotation(*R_world_camera);
  }
  m.view_prior->setView(T_camera_view);
  VKLOC_TRY_STATUS(m.front->remap(image, T_camera_view.linear(), m.view_image));
  const double front_ms = msSince(t_start);
  std::optional<Pose> guess_view;
  if (T_world_camera_guess) guess_view = *T_world_camera_guess * T_camera_view;
  Result<LocalizationResult> result = localizeView(t_ns, m.view_image, guess_view);
  if (!result.ok()) return result;
  LocalizationResult out = std::move(result).value();
  if (!out.pose_filtered) out.T_world_camera_visual = out.T_world_camera;
  out.T_camera_view = T_camera_view;
  out.T_world_camera = m.view_prior->toCamera(out.T_world_camera);
  out.T_world_camera_visual = m.view_prior->toCamera(out.T_world_camera_visual);
  out.covariance = m.view_prior->covarianceToCamera(out.covariance);
  out.front_ms = front_ms;
  out.total_ms += front_ms;
  if (out.state != TrackingState::kLost && out.state != TrackingState::kInitializing) {
    m.last_camera_pose = out.T_world_camera;
  }
  return out;
}

Result<LocalizationResult> Localizer::localizeView(int64_t t_ns, const ImageU8& gray,
                                                   const std::optional<Pose>& T_world_camera_guess) {
  const auto t_start = SteadyClock::now();
  Impl& m = *impl_;
  if (gray.channels != 1 || gray.width != m.camera.width || gray.height != m.camera.height ||
      gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("Localizer: image is {}x{} with {} channel(s); the camera needs {}x{} gray",
                                 gray.width, gray.height, gray.channels, m.camera.width, m.camera.height));
  }
  if (m.last_t_ns && t_ns <= *m.last_t_ns) {
    return makeError(
        ErrorCode::kInvalidArgument,
        fmt::format("Localizer: frame time {} ns is not after the previous frame's {} ns", t_ns, *m.last_t_ns));
  }
  if (T_world_camera_guess && !isValidPose(*T_world_camera_guess)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: the pose guess is not a finite rigid transform");
  }
  if (!T_world_camera_guess && !m.motion->lastPose() && !m.searching) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: no pose guess and no previous pose; call reset() first");
  }
  ++m.frame_index;
  if (m.last_t_ns) {
    m.frame_interval_ns = t_ns - *m.last_t_ns;
    m.stream_intervals_ns.push_back(m.frame_interval_ns);
    if (m.stream_intervals_ns.size() > Impl::kStreamIntervals) m.stream_intervals_ns.pop_front();
  }
  if (!m.first_t_ns) m.first_t_ns = t_ns;
  if (m.worker()) {
    // Frames a second or more apart (a paused stream), and a frame that waited for a keyframe
    // (a start, a loss), say nothing of the next frame's wait.
    const double period_ms = m.last_frame_start ? msSince(*m.last_frame_start) : 0.0;
    if (period_ms > 0 && period_ms < 1000 && !m.last_frame_waited) {
      m.frame_period_ms_mean = m.frame_period_ms_mean > 0 ? 0.9 * m.frame_period_ms_mean + 0.1 * period_ms : period_ms;
    }
    m.last_frame_start = t_start;
  }
  const std::optional<int64_t> previous_t_ns = m.last_t_ns;

  // 0. A frame with nothing to align (black, saturated, uniform): reported at once; the motion
  // prior bridges it (the IMU keeps running), and no alignment, search or relocalization runs.
  if (T_world_camera_guess) {
    m.searching = m.confirming = m.confirm_extended = false;
    m.start_on_probation.reset();  // the caller's pose vouches
  }
  double image_contrast = 0;
  if (m.options.image_content.min_contrast > 0) {
    Result<ImageContentCheck> content = checkImageContent(gray, m.options.image_content);
    if (!content.ok()) return content.error();
    image_contrast = content->contrast;
    if (content->content != ImageContent::kOk) {
      LocalizationResult out = m.emptyFrame(t_ns, *content, T_world_camera_guess);
      out.total_ms = msSince(t_start);
      return out;
    }
  }

  // 0b. Global initialization (startSearch): the frame is searched in the region until a pose is
  // verified; a guess given meanwhile ends the search (a user's or a GPS's pose).
  if (m.searching) {
    LocalizationResult out;
    out.t_ns = t_ns;
    out.image_contrast = image_contrast;
    out.state = TrackingState::kInitializing;
    m.live_levels = 0;
    m.last_t_ns = t_ns;
    TrackResult found;
    Result<bool> searched = m.relocalize(*m.database, std::nullopt, gray, t_ns, m.search_region, found, out);
    if (!searched.ok()) return searched.error();
    if (*searched) {
      m.searching = false;
      m.adoptStartPose(found, t_ns, gray, previous_t_ns, out);
    }
    out.total_ms = msSince(t_start);
    return out;
  }

  // 1. The guess: the caller's, else the motion prior's (IMU-propagated when it can).
  const std::optional<MotionPrediction> prediction = m.motion->predict(t_ns);
  const Pose guess = T_world_camera_guess ? *T_world_camera_guess : prediction->T_world_camera;
  LocalizationResult out;
  out.t_ns = t_ns;
  out.image_contrast = image_contrast;
  out.T_world_camera = guess;

  // 2. The keyframe: the newest the worker finished; made here (waiting) when there is none to
  // track against (worker mode) or when the policy asks (synchronous mode).
  if (m.worker()) {
    Result<bool> adopted = m.keyframes->adoptFinished();
    if (!adopted.ok()) return adopted.error();
    if (*adopted) {
      out.keyframe_adopted = true;
      const Keyframe& k = *m.keyframes->current();
      const double made_ms = k.render_ms + k.reference_ms;
      m.keyframe_ms_mean = m.keyframe_ms_mean > 0 ? 0.7 * m.keyframe_ms_mean + 0.3 * made_ms : made_ms;
      VKLOC_TRY_STATUS(m.uploadKeyframe());
    }
  }
  const bool make_now = m.worker() ? m.keyframes->mustWait() : m.keyframes->needsKeyframe(guess);
  if (make_now) VKLOC_TRY_STATUS(m.makeKeyframe(guess, t_ns, out));
  if (m.calibration_pending) VKLOC_TRY_STATUS(m.calibrate(gray, guess));

  // 3. Tracking: live stages and alignment against the keyframe, as deep as the prior's
  // uncertainty asks.
  m.search_level =
      m.searchLevel(T_world_camera_guess ? std::nullopt : prediction, m.keyframes->current()->scene_depth_m);
  out.search_level = m.search_level;
  m.live_levels = 0;
  // The filter's attitude as a prior of this frame's alignments (cleared on every way out).
  struct ClearOnExit {
    std::optional<RotationPrior>& prior;
    ~ClearOnExit() { prior.reset(); }
  } clear_rotation_prior{m.rotation_prior};
  m.rotation_prior = T_world_camera_guess ? std::nullopt : m.rotationPriorFrom(prediction);
  auto alignFrom = [&](const Pose& start) { return m.align(*m.active, gray, start, out, m.live_levels); };
  Result<TrackResult> aligned = alignFrom(guess);
  if (!aligned.ok()) return aligned.error();
  TrackResult track = std::move(aligned).value();
  // The frame aligned once more against a keyframe made at the guess (waiting for it).
  auto realignAgainstFreshKeyframe = [&]() -> Status {
    VKLOC_TRY_STATUS(m.makeKeyframe(guess, t_ns, out));
    Result<TrackResult> retry = alignFrom(guess);
    if (!retry.ok()) return retry.error();
    track = std::move(retry).value();
    return Status::success();
  };
  if (track.state == TrackingState::kLost && !out.reference_rendered && m.options.retry_lost_with_fresh_reference) {
    VKLOC_TRY_STATUS(realignAgainstFreshKeyframe());
  }
  // A pose the filter's gate refuses that was aligned against a keyframe the synchronous mode
  // would have replaced for this frame (worker mode: the worker lags behind a fast camera) is
  // aligned once more against a keyframe made at the guess, waiting for it. Without it a stale
  // keyframe's pose refused at the start (the geometry-only room: the second frame aligned 5.5 cm
  // off against the first's keyframe, 8 % of the depth behind) left the filter to bridge the
  // plain whiteboard that follows on a velocity from one frame, and the run ended 3.4 m off.
  if (m.options.retry_refused_with_fresh_reference && m.worker() && !out.reference_rendered &&
      track.state == TrackingState::kTracking && prediction && prediction->inertial &&
      m.keyframes->needsKeyframe(guess) &&
      !m.motion->consistent(*prediction, Impl::filterPose(track), track.covariance,
                            m.keyframes->current()->scene_depth_m)) {
    VKLOC_TRY_STATUS(realignAgainstFreshKeyframe());
    out.keyframe_retried = true;
  }
  // 3b. Motion search: lost while the prior's uncertainty exceeds the deepest basin.
  // A pose the filter's gate refuses is as good as lost here.
  // On the first frame after a start at an unknown velocity the filter's gate admits whatever
  // that velocity's sigma reaches, and the pose it takes sets the velocity for the frames to come
  // (its error over one frame interval): a plain alignment that does not verify with
  // motion_search_start_score goes to the motion search, whose pose replaces it when verified
  // higher; else the plain pose is kept and gated as any other (imagery whose true poses verify
  // below that score still starts: refusing them there left a blurred city drone bridged at zero
  // velocity and lost for good).
  const auto scoreOf = [&](const TrackResult& r) {
    return verificationScore(verificationFeatures(r, m.keyframes->current()->scene_depth_m), m.options.verification);
  };
  auto gated = [&](const TrackResult& r) {
    return r.state == TrackingState::kTracking &&
           !m.motion->consistent(*prediction, Impl::filterPose(r), r.covariance, m.keyframes->current()->scene_depth_m);
  };
  const bool first_at_unknown_velocity =
      prediction && prediction->inertial && prediction->velocity_unobserved && m.untracked == 0;
  // The same, with no frame tracked since the start's own: the second frame of the track (not one
  // after a restart of the prior mid-stream, whose pose is no start to go back to).
  const bool second_frame_of_start =
      first_at_unknown_velocity && m.first_t_ns && m.last_tracked_t_ns && *m.last_tracked_t_ns == *m.first_t_ns;
  // The grid first: a settled prior has none, and its frames are not tested against the gate twice.
  std::optional<Impl::SearchGrid> grid =
      !T_world_camera_guess && prediction && prediction->inertial ? m.searchGrid(*prediction) : std::nullopt;
  // The score a searched pose must beat, when the search runs: the plain pose's, or 0 for a frame
  // lost or refused by the gate.
  std::optional<double> incumbent_score;
  // Without the IMU the constant-velocity prediction has no covariance to size a grid by, and a
  // turn that speeds up or slows down leaves it degrees off (the room's fast turn: 2-10 deg a
  // frame): where the plain pose would not be taken (below tracking's score, or the confident one
  // after a blind guess: step 5's rules) and the last tracked frame is recent, the frame is given
  // the search's starts from that frame (point features matched with it, image shifts) before a
  // relocalization search. With no gate to check them, a start's result is taken only when
  // confidently verified (a feature start the edges agree with: at the score any pose needs; a
  // 3 m jump in the room took an image shift's start 4 m and 78 deg off, verified above
  // tracking's score), and only within the local search's bound of the path from the last
  // tracked pose to the prediction (every 3rd image of the room: a look-alike 4.0 m away at 0.80,
  // the camera having moved 0.3 m). Not while the last pose is on probation (5a'): this frame
  // must confirm it on its own, and the motion from a look-alike's view to the next is as
  // consistent as the truth's (the room started 0.87 m off: a pose 4.9 m off confirmed at 0.68).
  const bool can_search = m.database || m.localSearchInReach(t_ns);
  const bool blind_guess = prediction && !prediction->inertial &&
                           ((previous_t_ns && m.last_relocalized_t_ns == previous_t_ns) ||
                            (m.untracked > 0 && can_search && !T_world_camera_guess));
  bool confident_only = false;
  std::optional<Impl::LocalBound> search_bound;
  if (!T_world_camera_guess && prediction && !prediction->inertial && !m.last_imu && m.tracked_since_reset &&
      !m.start_on_probation && m.last_tracked_gray && m.last_tracked_gray->scene_depth_m > 0 &&
      m.recent(t_ns, m.last_tracked_gray->t_ns)) {
    const double plain_score = track.state == TrackingState::kTracking ? scoreOf(track) : 0.0;
    if (plain_score < m.minTakenScore(prediction->velocity_unobserved || blind_guess)) {
      grid = m.startsGrid();
      if (grid) {
        incumbent_score = plain_score;
        confident_only = true;
        search_bound = m.localBound(*m.searchAnchor(), guess, t_ns);
      }
    }
  }
  if (grid && !incumbent_score) {
    if (track.state == TrackingState::kLost || gated(track)) {
      incumbent_score = 0.0;
    } else if (first_at_unknown_velocity) {
      const double plain_score = scoreOf(track);
      if (plain_score < m.options.motion_search_start_score) incumbent_score = plain_score;
    }
  }
  auto refused = [&](const TrackResult& r) {
    return gated(r) || (search_bound && !search_bound->holds(r.T_world_camera.translation()));
  };
  bool feature_agreed = false;  // the search's pose is a feature start the edges agreed with
  if (incumbent_score) {
    Result<TrackResult> searched = m.motionSearch(*grid, *prediction, guess, gray, std::move(track), *incumbent_score,
                                                  alignFrom, refused, out, confident_only, &feature_agreed);
    if (!searched.ok()) return searched.error();
    track = std::move(searched).value();
  }
  // The pose this frame takes may be a look-alike near the prediction: the motion search's grid
  // could not reach as far as the prediction's uncertainty (SearchGrid::capped), the pose verified
  // below motion_search_start_score and is not a feature start the edges agreed with (5a, 5a').
  auto searchFellShort = [&] {
    return grid && grid->capped && !feature_agreed && out.verify_score < m.options.motion_search_start_score;
  };
  // 4. Start-up: widen the basin until a first frame is tracked.
  if (!m.tracked_since_reset) {
    InitializerSteps steps;
    steps.align = alignFrom;
    steps.rekey = [&](const Pose& T_world_ref) { return m.makeKeyframe(T_world_ref, t_ns, out); };
    Result<TrackResult> refined = m.initializer.refine(guess, std::move(track), steps);
    if (!refined.ok()) return refined.error();
    track = std::move(refined).value();
  }
  m.rotation_prior.reset();
  m.last_t_ns = t_ns;
  const Keyframe& keyframe = *m.keyframes->current();
  if (!m.tracked_since_reset && !m.start_anchor) {
    m.start_anchor = SearchAnchor{guess, m.first_t_ns.value_or(t_ns), keyframe.scene_depth_m};
  }
  out.quality = track.quality;
  out.state = track.state;
  out.T_world_camera = track.T_world_camera;
  out.covariance = track.covariance;
  out.reference_points = static_cast<int>(keyframe.reference.points.size());
  out.scene_depth_m = keyframe.scene_depth_m;
  out.verify_score = verificationScore(verificationFeatures(track, keyframe.scene_depth_m), m.options.verification);
  out.keyframe_id = keyframe.id;
  out.keyframe_age_frames = m.frame_index - keyframe.request.frame_index;
  // With a database to relocalize from, a pose is taken only when it is verified: an alignment
  // that locked onto wrong edges (after a loss, a jump, a wrong prediction) goes to the search
  // instead of being tracked on. On the frame after a relocalized one with no IMU, the plain
  // alignment starts from that pose with no motion to go by (the velocity is unobserved), or with
  // only the velocity between two searched poses, and nothing but its own score checks it: it is
  // taken only at motion_search_confident_score, else the frame is searched again (the room after
  // a 3 m jump: the frame after a relocalized one slid 0.34 m across a window's plain frame and
  // verified at 0.28; the city after a 5 m jump, after six frames relocalized in a row, one
  // tracked 0.54 m off at 0.16).
  // So is a frame after lost ones, guessed by the motion before the loss carried across it (at
  // 5 Hz, after 7 frames lost, the room's frame 12 tracked 4.4 m and 173 deg off at 0.21), while
  // a search can find it instead (a database, or the local search's time since the last tracked
  // frame): with none, imagery whose true poses verify below the confident score would never be
  // tracked again. A caller's guess is not the carried motion. Before a first pose is taken the
  // guess is the start pose held while the camera moves on, as blind (the room started 0.87 m
  // off: frames after lost ones tracked 3.7 m off at 0.23-0.27).
  // Without an IMU (no reading since the start) nothing else checks a pose: it is taken only when
  // verified too, database or not (taken, a pose metres off was reported as tracked and tracked on: the
  // room without its IMU, after its 190 deg/s turn at frame 86, 2-3 m off at scores 0-0.12).
  // Nor does anything before the first pose is taken, IMU or not: the filter's gate then holds
  // only the start pose and an unknown velocity (the room started 0.87 m off: its second frame
  // tracked 2.25 m off at 0.02, and the filter bridged from it to 10 m off in 2 s). Except on the
  // start's own frame, ending within local_offset_fraction x the depth of the start pose: the
  // start pose vouches for it (imagery whose true poses verify below tracking's score: the
  // fisheye's central crop over the hard city started at its true pose at 0.04, and refused
  // there, lost 17 frames); a caller's guess for that frame vouches as the start pose does. A
  // pose taken at the start must also lie where the local search would take one, within
  // local_depth_fraction x the start keyframe's depth + growth_m_s x the seconds since the first
  // frame of the path from the start pose to the prediction: a look-alike verifies well (the room
  // started 0.87 m off: tracked 2.45 m off at 0.87). Not against a caller's guess.
  const bool starting = !m.tracked_since_reset;
  bool far_from_start = false, start_vouches = false;
  if (starting && m.start_anchor && m.start_anchor->scene_depth_m > 0 && track.state == TrackingState::kTracking) {
    const RelocalizationOptions& o = m.options.relocalization;
    const Pose& T_start = T_world_camera_guess ? *T_world_camera_guess : m.start_anchor->T_world_camera;
    start_vouches =
        t_ns == m.start_anchor->t_ns && (track.T_world_camera.translation() - T_start.translation()).norm() <=
                                            o.local_offset_fraction * m.start_anchor->scene_depth_m;
    if (!T_world_camera_guess) {
      far_from_start = !m.localBound(*m.start_anchor, guess, t_ns).holds(track.T_world_camera.translation());
    }
  }
  // Without the IMU a pose on the start's own frame that the start pose does not vouch for is
  // taken only at motion_search_confident_score, as one aligned from a blind guess: nothing but
  // its score checks it (the city started 5.8 m off took one 12.8 m off at 0.29, then lost every
  // frame; refused, the local search found the truth).
  const bool unvouched_start_frame_without_imu =
      starting && !m.last_imu && !start_vouches && m.start_anchor && t_ns == m.start_anchor->t_ns;
  if (((m.database || !m.last_imu || (starting && !start_vouches)) && track.state == TrackingState::kTracking &&
       out.verify_score < m.minTakenScore(blind_guess || unvouched_start_frame_without_imu)) ||
      far_from_start) {
    track.state = TrackingState::kLost;
    out.state = TrackingState::kLost;
  }

  const bool verified = out.verify_score >= m.options.verification.min_score;  // tracking's score

  // 5. The motion prior takes the pose (consistency gate with the IMU) or bridges the frame.
  if (prediction && prediction->inertial) {
    out.inertial_sigma_m = prediction->sigma_m;
    if (track.state == TrackingState::kTracking) {
      out.visual_rejected =
          !m.motion->consistent(*prediction, Impl::filterPose(track), track.covariance, keyframe.scene_depth_m);
      out.innovation = m.motion->lastInnovation();
    }
  }
  // A prior whose current stretch of refusals has a verified pose takes no unverified one: it
  // goes on refusing, and the stretch ends in a restart at a verified pose (below) or when it
  // takes one. Taking the unverified pose the gate admits ended the stretch and restarted none:
  // a fast drone's filter, 3.4 m off after its start, took poses verified at 0.01, refused one
  // at 0.78 and stayed 16 m off (the acrobatic drone, seed 7, on the GPU path).
  if (m.options.restart_after_refused_s > 0 && track.state == TrackingState::kTracking && !out.visual_rejected &&
      !verified && m.refused_stretch.first_t_ns && m.refused_stretch.verified && t_ns > m.refused_stretch.last_t_ns &&
      m.recent(t_ns, m.refused_stretch.last_t_ns)) {
    out.visual_rejected = true;
  }
  // A prior that refuses well verified poses frame after frame is the one that is wrong (a
  // velocity taken from a poor first fix, a bias, poorly verified poses it took): after
  // restart_after_refusals of them in a row (refusalCountsAgainstPrior) it restarts at this pose.
  // So it does, whatever the scores, after refusing every tracked pose for
  // restart_after_refused_s. Either way the filter's velocity goes on with a loosened sigma
  // (restart_sigma_velocity_m_s) for the next poses to correct: not the velocity between two
  // poses 1/20 s apart, which carries their errors divided by that interval (1 cm each: 0.3 m/s),
  // nor an unknown one, at which a drone is bridged at rest until a verified pose comes.
  bool restart = false;
  if (out.visual_rejected && refusalCountsAgainstPrior(out.verify_score, m.refusals.taken_scores, Impl::kTakenScores,
                                                       m.options.restart_min_score, m.options.verification.min_score)) {
    if (m.refusals.count > 0 && t_ns > m.refusals.t_ns && m.recent(t_ns, m.refusals.t_ns)) {
      ++m.refusals.count;
    } else {
      m.refusals.count = 1;
    }
    m.refusals.t_ns = t_ns;
    restart = m.options.restart_after_refusals > 0 && m.refusals.count >= m.options.restart_after_refusals;
  } else {
    m.refusals.count = 0;
  }
  bool refused_too_long = false;
  if (out.visual_rejected) {
    Impl::RefusedStretch& s = m.refused_stretch;
    if (!s.first_t_ns || t_ns <= s.last_t_ns || !m.recent(t_ns, s.last_t_ns)) {
      s = {};
      s.first_t_ns = t_ns;
    }
    s.last_t_ns = t_ns;
    // Where the stretch has verified poses, the restart waits for one: on imagery whose true poses
    // verify, an unverified one is as likely a look-alike as the truth (a fast drone's filter
    // refused poses verified at 0.47 and restarted at one of 0.03, then bridged 300 m off).
    s.verified = s.verified || verified;
    refused_too_long = m.options.restart_after_refused_s > 0 &&
                       static_cast<double>(t_ns - *s.first_t_ns) * 1e-9 >= m.options.restart_after_refused_s &&
                       (verified || !s.verified);
  } else if (track.state == TrackingState::kTracking) {
    m.refused_stretch = {};
  }
  // A prior restarted with its velocity that refuses the next verified pose has the velocity
  // wrong (a fast drone's start whose first alignments barely moved: 1 m/s for 6.7, every pose
  // after refused): it restarts at that pose at an unknown velocity, as at a start.
  const bool velocity_refused = out.visual_rejected && m.restart_kept_velocity_t_ns &&
                                t_ns > *m.restart_kept_velocity_t_ns && m.recent(t_ns, *m.restart_kept_velocity_t_ns) &&
                                verified;
  if (velocity_refused) m.restart_kept_velocity_t_ns.reset();
  if (restart || refused_too_long || velocity_refused) {
    // The prior keeps its velocity, loosened (restart_sigma_velocity_m_s).
    std::optional<Eigen::Vector3d> v_world;
    if (m.options.restart_sigma_velocity_m_s > 0 && prediction && prediction->inertial &&
        !prediction->velocity_unobserved && prediction->v_world_body && !velocity_refused) {
      v_world = prediction->v_world_body;
      m.restart_kept_velocity_t_ns = t_ns;
    }
    m.restartPrior(track.T_world_camera, v_world, t_ns,
                   std::max(m.options.restart_sigma_velocity_m_s, v_world ? prediction->sigma_velocity_m_s : 0.0));
    m.refusals.count = 0;
    m.refused_stretch = {};
    if (restart) {
      // Until the restarted prior has a pose of its own to gate with, only verified poses are
      // taken (below); after a stretch of refusals whatever the scores, any tracked pose is.
      m.refusals.taken_scores.clear();
      m.refusals.restarted = true;
    }
    out.visual_rejected = false;
    out.prior_restarted = true;
  } else if (m.refusals.restarted && track.state == TrackingState::kTracking && !out.visual_rejected &&
             out.verify_score < m.options.verification.min_score) {
    // Until the restarted prior has a pose of its own to gate with, only verified poses are taken.
    out.visual_rejected = true;
  }
  if (track.state == TrackingState::kTracking && !out.visual_rejected) {
    if (!out.prior_restarted && prediction && prediction->inertial) m.refusals.restarted = false;
    if (!out.prior_restarted) m.restart_kept_velocity_t_ns.reset();
    m.motion->setSceneDepth(keyframe.scene_depth_m);
    m.motion->addVisualPose(t_ns, Impl::filterPose(track), track.covariance);
    if (m.options.report_filtered_pose) {
      if (std::optional<MotionPrediction> posterior = m.motion->filtered(t_ns)) {
        out.T_world_camera_visual = out.T_world_camera;
        out.T_world_camera = posterior->T_world_camera;
        out.covariance = posterior->covariance;
        out.pose_filtered = true;
      }
    }
    m.poseTaken(out.verify_score);
    m.keyframes->frameTracked(track.quality);
    m.tracked_since_reset = true;
    // Kept for the motion search of the next frames (image shift from the last tracked frame).
    if (!m.last_tracked_gray) m.last_tracked_gray.emplace();
    m.last_tracked_gray->gray = gray;
    m.last_tracked_gray->T_world_camera = track.T_world_camera;
    m.last_tracked_gray->t_ns = t_ns;
    m.last_tracked_gray->scene_depth_m = keyframe.scene_depth_m;
  } else {
    m.keyframes->frameNotTracked();
    applyBridge(m.motion->bridge(t_ns, prediction, guess), out);
  }

  // 5a. Global initialization's pose on probation (confirm_start): this frame, tracked from it
  // and taken, confirms it; otherwise the pose is dropped and this frame is searched again in
  // the prior's region (as the frames before the search found it).
  // A frame tracked from it at the unknown velocity of the search's restart (the next frame, or
  // the first after black frames) whose motion search fell short (the grid capped below the
  // prediction's reach, verified below motion_search_start_score, not a feature start the edges
  // agreed with: a stream so slow that the camera moves farther between two frames than the grid
  // reaches) vouches for nothing: it may have taken a look-alike near the prediction. The wait
  // goes on one frame, which then aligns at the velocity the two poses give and confirms both or
  // drops them (once: that frame's velocity is known, so its search is not one at an unknown
  // velocity). The room at 2 Hz started from a prior of sigma 1 m confirmed a pose 2.7 m off at
  // 0.70 this way and bridged to 5.3 m off.
  bool confirmed = false;
  bool waits_on = false;
  if (m.confirming) {
    m.confirming = false;
    const bool taken = out.state == TrackingState::kTracking && !out.visual_rejected && !out.prior_restarted;
    const bool fell_short = prediction && prediction->inertial && prediction->velocity_unobserved && searchFellShort();
    if (taken && fell_short && !m.confirm_extended) {
      m.confirming = m.confirm_extended = true;  // reported kInitializing below, tracked meanwhile
      waits_on = true;
    } else if (taken) {
      m.confirm_extended = false;
      confirmed = true;  // reported kRelocalized below
    } else {
      m.confirm_extended = false;
      m.motion->reset(std::nullopt, std::nullopt);
      m.forgetTrack();
      // The frame is reported as the searches before the pose was found were: no pose, only
      // the work done on it.
      LocalizationResult searched_out;
      searched_out.t_ns = t_ns;
      searched_out.image_contrast = out.image_contrast;
      searched_out.state = TrackingState::kInitializing;
      searched_out.render_ms = out.render_ms;
      searched_out.reference_ms = out.reference_ms;
      searched_out.live_ms = out.live_ms;
      searched_out.align_ms = out.align_ms;
      searched_out.reference_rendered = out.reference_rendered;
      if (m.database) {
        TrackResult found;
        Result<bool> searched =
            m.relocalize(*m.database, std::nullopt, gray, t_ns, m.search_region, found, searched_out);
        if (!searched.ok()) return searched.error();
        if (*searched) {
          m.adoptStartPose(found, t_ns, gray, std::nullopt, searched_out);
        } else {
          m.searching = true;
        }
      }
      if (m.worker()) m.last_frame_waited = true;
      searched_out.total_ms = msSince(t_start);
      return searched_out;
    }
  }

  // 5a'. The same for a first pose taken after lost frames without a database (a search around
  // the start pose, or a plain alignment from the start pose held while the camera moved on):
  // this frame, tracked from it, taken and verified, confirms it; otherwise the track goes back
  // to the start (its pose, its first frame's time: the local search's bound) with the filter
  // restarted there at an unknown velocity, and this frame counts as lost (searched below). The
  // room started 0.87 m off took look-alikes 2.5-5 m off at 0.67-0.91 seconds later, each
  // followed by frames verified at 0-0.06. Before it is dropped, this frame is searched around
  // the pose (without the IMU or a database: the local search, where it runs; a database's
  // search is not known to miss a look-alike found once, and with the IMU a frame taken unverified
  // is the search's anchor, not the pose): found within local_offset_fraction x the depth
  // of it + growth_m_s x the seconds since its frame (the room's camera walks 0.11-0.14 m a
  // frame), that confirms it. Without the IMU the frame after a true first pose aligns from an
  // unknown velocity and fails where the camera turns fast, and the search finds it; a look-alike
  // taken was not found again (the room started 0.87 m off, without its IMU: every frame after
  // each of three look-alikes was lost, searched around them); without this, true first poses
  // were dropped frame after frame (the room started 0.3 m off without its IMU: 32 frames lost).
  bool start_dropped = false;
  auto dropStart = [&] {
    const std::optional<SearchAnchor> anchor = m.start_anchor;
    const std::optional<int64_t> first_t_ns = m.first_t_ns;
    m.forgetTrack();
    m.start_anchor = anchor;
    m.first_t_ns = first_t_ns;
    m.restartPrior(anchor->T_world_camera, std::nullopt, t_ns);
    m.keyframes->frameNotTracked();    // the next frame aligns against a keyframe made at its guess
    out.state = TrackingState::kLost;  // not bridged from the pose dropped
    out.pose_filtered = false;
    start_dropped = true;
  };
  std::optional<SearchAnchor> dropped;  // the pose on probation this frame did not confirm
  if (m.start_on_probation) {
    const SearchAnchor probation = *std::exchange(m.start_on_probation, std::nullopt);
    if (out.state == TrackingState::kTracking && !out.visual_rejected && !out.prior_restarted && verified) {
      confirmed = true;  // reported kRelocalized below
    } else if (m.database || m.last_imu) {
      dropStart();
    } else {
      dropped = probation;
      out.state = TrackingState::kLost;  // searched below, then dropped unless found near it
      out.pose_filtered = false;
    }
  }

  // 5b. Relocalization: with a keyframe database, a frame not tracked after
  // after_untracked_frames in a row is searched for around the prediction, in a region that
  // grows with the time since the last tracked frame (before one: since the first frame), the
  // prediction's uncertainty and every search that found nothing; without one, among keyframes
  // rendered around the last tracked pose, before one around the start pose
  // (local_after_untracked_frames).
  auto searchUntracked = [&]() -> Status {
    if (out.state == TrackingState::kTracking) {
      m.untracked = 0;
      m.failed_searches = 0;
      m.last_tracked_t_ns = t_ns;
    } else {
      ++m.untracked;
      const RelocalizationOptions& o = m.options.relocalization;
      const double since_s = m.sinceTrackedS(t_ns);
      const std::optional<SearchAnchor> anchor = m.searchAnchor();
      if (!m.database && m.localSearchInReach(t_ns) && m.untracked >= o.local_after_untracked_frames &&
          gray.width >= kThumbnailWidth && gray.height >= kThumbnailHeight && anchor->scene_depth_m > 0 &&
          (!prediction || !prediction->inertial || !m.tracked_since_reset ||
           3.0 * out.inertial_sigma_m > o.local_offset_fraction * anchor->scene_depth_m)) {
        // Without a database: keyframes rendered around the last tracked pose (before the first
        // one: the start pose) on the first frame with something to recognise (the depth: the last
        // tracked frame's keyframe's). With the IMU only once its prediction may lie outside the
        // alignment's basin (3 sigma beyond local_offset_fraction of the depth): bridged frames a
        // few millimetres uncertain need no search (the room's frame 92, relocalized 12.6 mm off at
        // a score of 0.27, was bridged 1.9 mm off); at the start at once (no pose has verified).
        const double depth_m = anchor->scene_depth_m;
        Result<ImageU8> thumbnail = descriptorThumbnail(gray);
        if (!thumbnail.ok()) return thumbnail.error();
        if (thumbnailContrast(*thumbnail) >= o.min_contrast) {
          const Pose& T_last = anchor->T_world_camera;
          // Made again after a tracked frame, and when the prediction has moved on by more than
          // local_offset_fraction of the depth from the one it was made at.
          if (!m.local_database || !m.local_database_pose || m.local_database_pose->matrix() != T_last.matrix() ||
              !((guess.translation() - m.local_database_guess).norm() <= o.local_offset_fraction * depth_m)) {
            Result<KeyframeDatabase> local = m.localDatabase(T_last, guess.translation(), depth_m, m.local_views, out);
            if (!local.ok()) return local.error();
            m.local_database = std::move(local).value();
            m.local_database_pose = T_last;
            m.local_database_guess = guess.translation();
            out.reference_rendered = true;  // the frame waited for renders (worker mode's pacing)
          }
          // A pose no farther than local_depth_fraction of the scene depth (a drone over a city
          // moves metres between frames, a hand in a room decimetres) + growth_m_s x the seconds
          // since the last tracked frame from the path between the last tracked position and the
          // prediction: a look-alike place elsewhere verifies as well (the room without its IMU:
          // 4.9 m off at 0.92, 0.65 s after its last tracked frame; at 10 Hz 2.06 m off at 1.0,
          // 0.1 s after it, under a bound of 2 m + 2 m/s).
          const Impl::LocalBound bound = m.localBound(*anchor, guess, t_ns);
          TrackResult found;
          Result<bool> searched =
              m.relocalize(*m.local_database, bound, gray, t_ns, std::nullopt, found, out, &m.local_views);
          if (!searched.ok()) return searched.error();
          if (*searched) {
            m.adoptRelocalized(found, t_ns, gray, T_world_camera_guess ? std::nullopt : prediction, previous_t_ns, out,
                               true);
          } else {
            ++m.failed_searches;
          }
        }
      }
      if (m.database && o.after_untracked_frames > 0 && m.untracked >= o.after_untracked_frames) {
        SearchRegion region;
        region.center_world = guess.translation();
        region.radius_m =
            std::min(o.max_radius_m, (o.min_radius_m + o.growth_m_s * since_s + 3.0 * out.inertial_sigma_m) *
                                         std::ldexp(1.0, std::min(m.failed_searches, 30)));
        TrackResult found;
        Result<bool> searched = m.relocalize(*m.database, std::nullopt, gray, t_ns, region, found, out);
        if (!searched.ok()) return searched.error();
        if (*searched) {
          m.adoptRelocalized(found, t_ns, gray, T_world_camera_guess ? std::nullopt : prediction, previous_t_ns, out);
        } else {
          ++m.failed_searches;
        }
      }
    }
    return Status::success();
  };
  std::optional<LocalizationResult> before_search;  // what a dropped pose's frame reports (below)
  if (dropped) before_search = out;
  if (Status searched = searchUntracked(); !searched.ok()) {
    if (dropped) dropStart();  // not kept unconfirmed
    return searched.error();
  }
  if (dropped) {
    const RelocalizationOptions& o = m.options.relocalization;
    const double dropped_s = static_cast<double>(t_ns - dropped->t_ns) * 1e-9;  // seconds since its frame
    if (out.state == TrackingState::kRelocalized && m.start_anchor &&
        (out.T_world_camera.translation() - dropped->T_world_camera.translation()).norm() <=
            o.local_offset_fraction * m.start_anchor->scene_depth_m + o.growth_m_s * dropped_s) {
      confirmed = true;
    } else {
      // The first search's pose is not this frame's: the frame reports what it had before that
      // search, and the time and candidates of both searches.
      const double first_search_ms = std::exchange(out.relocalization_ms, 0.0);
      out.T_world_camera = before_search->T_world_camera;
      out.covariance = before_search->covariance;
      out.quality = before_search->quality;
      out.verify_score = before_search->verify_score;
      out.visual_rejected = before_search->visual_rejected;
      out.scene_depth_m = before_search->scene_depth_m;
      out.reference_points = before_search->reference_points;
      out.keyframe_id = before_search->keyframe_id;
      out.keyframe_age_frames = before_search->keyframe_age_frames;
      dropStart();  // and the frame is searched again, around the start pose
      if (Status searched = searchUntracked(); !searched.ok()) return searched.error();
      out.relocalization_ms += first_search_ms;
    }
  }

  // A first pose after lost frames goes on probation (5a'), IMU or not, and so does one tracked
  // on the start's own frame that the start pose does not vouch for (it ended farther than
  // local_offset_fraction x the depth from it): the city started 5.8 m and 8.7 deg off took a
  // pose 12.8 m off at a score of 0.29 on its first frame, and the IMU bridged it for 2 s to 49 m
  // off (with a database the next frame was relocalized, the first still reported 12.8 m off).
  // Without the IMU, where the confirming frame aligns from an unknown velocity, only with no
  // database, which would otherwise find the truth (RelocalizationOptions::confirm_start): there
  // the pose taken anchors the local search, and the room started 0.87 m off without its IMU
  // took look-alikes 2.5-5 m off at 0.67-0.91 and lost every frame after them for seconds.
  const bool on_first_frame = m.first_t_ns && t_ns == *m.first_t_ns;
  const bool after_lost_frames = (starting || start_dropped) && !m.database && m.first_t_ns && !on_first_frame;
  const bool start_frame_unvouched = starting && on_first_frame && !start_vouches &&
                                     out.state == TrackingState::kTracking && (m.last_imu || !m.database);
  // So does a pose taken on the first frame after an inertial start at an unknown velocity that
  // verified below motion_search_start_score where the motion search's grid could not reach as far
  // as the prediction's uncertainty (SearchGrid::capped: a stream so slow that the camera moves
  // farther between two frames than the grid's steps reach): the search did not see every place
  // the camera may be, and the pose sets the velocity the gate then holds every pose to. The room
  // at 2 Hz (1.33 m between its first two frames, the grid's reach 0.62 m) took a look-alike 2.4 m
  // from the truth at 0.69 there and bridged from it to 6 m off; now its frames 1-8 have no
  // pose and frame 9 is relocalized. Only on the track's second frame: mid-stream, after a
  // restart of the prior at an unknown velocity, a dropped pose has no start to go back to. Not a feature start the
  // edges agreed with: point features matched with the frame before, whose pose was taken, do not match a look-alike
  // place elsewhere (the motion search's feature start).
  const bool search_fell_short =
      second_frame_of_start && out.state == TrackingState::kTracking && !out.visual_rejected && searchFellShort();
  if ((after_lost_frames || start_frame_unvouched || search_fell_short) && !confirmed && !waits_on &&
      m.tracked_since_reset && !T_world_camera_guess && m.options.relocalization.confirm_start && m.start_anchor &&
      (out.state == TrackingState::kTracking || out.state == TrackingState::kRelocalized)) {
    m.start_on_probation = SearchAnchor{out.T_world_camera, t_ns, out.scene_depth_m};
    out.state = TrackingState::kInitializing;
    out.confirming = true;
  }
  if (confirmed) out.state = TrackingState::kRelocalized;
  if (waits_on) {
    out.state = TrackingState::kInitializing;
    out.confirming = true;
  }

  // 6. Worker mode: the next keyframe, at the pose the camera will have when it is ready.
  if (m.worker()) {
    m.last_frame_waited = out.reference_rendered;
    m.requestNextKeyframe(t_ns, out.T_world_camera, out);
  }
  out.total_ms = msSince(t_start);
  return out;
}

}  // namespace vkloc
