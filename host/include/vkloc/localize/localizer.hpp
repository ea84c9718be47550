// vkloc: frame-to-model localization, the product's main class. The data flow of one frame:
//
//   image --> content check: a frame with nothing to align (black, saturated, uniform) is reported
//             at once (ImageContent); the motion prior bridges it and nothing is searched
//         --> edge backend: live stages (pyramid, edges, distance fields)
//         --> alignment of the current keyframe's 3D edge points (seed 000 sec. IV-C) from the
//             motion prior's guess (constant velocity, or the IMU: MotionPrior)
//         --> initializer while nothing was tracked since create/reset (Initializer)
//         --> the motion prior accepts the pose (gate) or bridges the frame
//   keyframe manager: when the keyframe no longer fits, a new one is rendered at the predicted
//   pose of a future frame on a worker thread while tracking goes on (STAR, seed 001 sec. II),
//   or on the caller's thread in the synchronous mode.
//
// Backends: keyframes render on the Accelerator's device when one is given (else on the CPU
// reference renderer); the live stages and the alignment run on the CPU (OpenCV / Eigen) or on
// the device. No Vulkan types are exposed; the engine provides the Accelerator of a Vulkan
// device (engine/gpu_accelerator.hpp).
//
// Frames and units: poses are T_world_camera (camera to world, metres; camera x right, y down,
// z forward); covariances are of xi = [rho; phi] in the camera frame (m^2, rad^2); times are
// int64 nanoseconds; durations in the result are milliseconds of wall time.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/sensors.hpp"
#include "vkloc/localize/camera_front.hpp"
#include "vkloc/localize/feature_pose.hpp"
#include "vkloc/localize/image_content.hpp"
#include "vkloc/localize/initializer.hpp"
#include "vkloc/localize/keyframe_database.hpp"
#include "vkloc/localize/keyframe_manager.hpp"
#include "vkloc/localize/motion_prior.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/edge_backend.hpp"
#include "vkloc/track/edge_tracker.hpp"
#include "vkloc/track/live_frame.hpp"
#include "vkloc/track/pose_verification.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// Where the live-image stages and the alignment run.
enum class LocalizerBackend {
  kAuto,    ///< The device on a real GPU; the CPU when the device is itself a CPU (lavapipe) or absent.
  kVulkan,  ///< The Accelerator's edge backend (needs one).
  kCpu,     ///< OpenCV / Eigen on the host.
};

/// Parses "auto" | "vulkan" | "cpu"; kInvalidArgument otherwise.
Result<LocalizerBackend> parseLocalizerBackend(const std::string& name);
const char* localizerBackendName(LocalizerBackend backend);

/// Relocalization and global initialization from a keyframe database (seed 001 sec. II-D;
/// Localizer::setKeyframeDatabase). A search takes the database's keyframes nearest to the live
/// image's descriptor in a region (grown by KeyframeDatabase::positionReach), renders a keyframe
/// at each in turn, turns it by the image shift between that render and the live image (phase
/// correlation: the rotation left), aligns from the deepest search level, refines against
/// keyframes rendered at the estimate and keeps the best pose whose verification score reaches
/// min_score, or tracking's score when alignments from agreeing_candidates keyframes reached it.
/// The keyframes' starts are first probed on the deepest level alone; only the best
/// refined_probes are aligned fully.
struct RelocalizationOptions {
  int candidates = 6;  ///< Database keyframes aligned per search, nearest descriptor first (1..100).
  /// When larger than `candidates`: this many nearest keyframes are rendered small (160 pixels
  /// wide) and ranked by the phase-correlation peak of the render against the live image, less
  /// rerank_bits_weight per bit of the descriptor's Hamming distance; the best `candidates` are
  /// aligned (0..1000). The finer the database's grid, the less of the search window a given
  /// number of nearest keyframes covers (measured on grids of 0.2-4 m: README, relocalization).
  int rerank_candidates = 120;
  /// Peak lost per bit of Hamming distance in the re-ranking (0..1; 0: the peak alone). The two
  /// are independent evidence: the descriptor sees the whole image's layout at 80x64, the peak
  /// how well the render and the image agree up to a shift. Neither alone orders the nearest
  /// keyframes well on a room whose renders lack its lighting (cycles-room: the first within 1 m
  /// and 30 deg 72 % by the descriptor, 83 % by the peak, 90 % together; README).
  double rerank_bits_weight = 0.005;
  /// After a loss: search the database on the frame that makes this many untracked frames in a
  /// row (tracked frames neither lost nor bridged by the IMU). 0 = never search the database
  /// after a loss (without a database: local_after_untracked_frames).
  int after_untracked_frames = 1;
  /// Radius of the region searched after a loss, around the motion prior's prediction: min_radius_m
  /// + growth_m_s x the seconds since the last tracked frame + 3 x the prediction's 1-sigma, doubled
  /// with every search that found nothing since (a camera that jumped), at most max_radius_m.
  double min_radius_m = 2.0;
  double growth_m_s = 2.0;
  double max_radius_m = 1e4;
  /// Frames whose thumbnail's contrast (thumbnailContrast) is below this have nothing to
  /// recognise (black, saturated, a blank wall): no search runs on them.
  double min_contrast = 4.0;
  /// Verification score a relocalized pose needs on its own: more than tracking's, as a search
  /// has many chances to converge somewhere wrong (wrong places of a room score up to ~0.6).
  double min_score = 0.7;
  /// Or a pose verified at tracking's score (VerificationOptions::min_score) that the alignments
  /// from at least this many different database keyframes reached (0 = off): within
  /// agree_depth_fraction x the scene depth and agree_deg of each other. True poses seen from few
  /// edges score 0.2-0.55, and a wrong minimum that two candidates' alignments both reach and that
  /// verifies too is rare.
  int agreeing_candidates = 2;
  double agree_depth_fraction = 0.01;
  double agree_deg = 1.0;
  /// While a verified pose waits for agreement after the refined_probes: the best probe of each
  /// candidate not refined yet is refined too, at most this many (0..100).
  int agreement_probes = 3;
  /// A search stops at a pose verified with this score.
  double confident_score = 0.75;
  /// Global initialization (Localizer::startSearch): the pose a search finds is confirmed by the
  /// next frame before it is reported. That frame tracks from it (IMU-propagated) and must be
  /// tracked and taken by the filter, verified as any tracked frame; it is then the kRelocalized
  /// frame, and the search's frame stays kInitializing with LocalizationResult::confirming set.
  /// A pose the next frame does not confirm is dropped and that frame is searched anew in the
  /// prior's region. A region only a prior bounds (metres wide, no motion history) holds places
  /// that look alike from one view (a look-alike corner of a room verified at 0.92) whose
  /// alignment does not survive the next frame's motion. Searches after a loss are not delayed:
  /// the filter's prediction bounds them, and recovering on the first usable frame counts.
  /// Only with the IMU (readings given since startSearch), whose propagation carries the pose to
  /// the next frame: without it that frame aligns from an unknown velocity, from the deepest
  /// level, and confirmed too few true poses (the room's STAR queries: 47 % recovered, not 83 %)
  /// and too weakly (one wrong pose at a score of 0.18). The same holds, with no database, IMU or
  /// not, for a first pose after reset() taken after lost frames (a local search's around the
  /// start pose, or an alignment from the start pose held while the camera moved on), without
  /// the IMU also by the next frame's local search finding a pose within local_offset_fraction x
  /// the depth + growth_m_s x the seconds since of it; else the track goes back to the start pose.
  /// Without the IMU too, as there the pose taken is the only anchor of the local search, and a
  /// look-alike taken kept it away from the truth (the room started 0.87 m off: three poses
  /// 2.5-5 m off, then lost for seconds). And for a pose tracked on the start's own frame
  /// farther than local_offset_fraction x the depth from the start pose (a start pose metres
  /// off whose first alignment slid onto a look-alike): with the IMU database or not, without
  /// it with no database (without the IMU such a pose is taken only at
  /// LocalizerOptions::motion_search_confident_score). And, with the IMU, for the pose of the
  /// first frame after a start at an unknown velocity verified below
  /// LocalizerOptions::motion_search_start_score when the motion search's grid could not reach
  /// the prediction's search_sigmas sigma (motion_search_steps too few for the frame interval;
  /// not a feature start the edges agreed with): the search did not see every place the camera
  /// may be (the room at 2 Hz took a look-alike 2.4 m from the truth at 0.69). Such a frame,
  /// when it is the one that would confirm a global search's pose, confirms nothing either: the
  /// wait goes on one frame, which aligns at the velocity of the two poses.
  bool confirm_start = true;
  /// Starts (of all candidates) aligned fully after the probes on the deepest level, most
  /// inliers above chance first (1..100).
  int refined_probes = 4;
  /// The first of them (after the feature starts, see feature_starts) is the best probe of the
  /// best-ranked candidate (the re-ranking's first, else the nearest descriptor's), whatever its
  /// inliers.
  bool top_candidate_first = true;
  /// Each start is also probed this many steps of depth_step x the candidate's scene depth
  /// forwards and backwards along its optical axis (a shift of the image cannot show that).
  int depth_steps = 1;
  double depth_step = 0.2;
  /// Refinements against keyframes rendered at the estimate, per fully aligned start (0..10).
  int refinements = 2;
  /// A refined pose verified below min_score is aligned once more from itself, coarse to fine
  /// from this pyramid level (at most LocalizerOptions::max_search_level), then against a keyframe
  /// rendered at the result, and the better verified of the two is kept (-1 = never). Two
  /// alignments can end in the same wrong minimum along the valley where a turn trades for a shift
  /// across the view, and the agreement rule then takes it: the room's image 27 from two feature
  /// starts 2.6 and 8.4 cm off, 8.7 cm and 3.4 deg off at 0.44, while its true pose verifies at
  /// 0.81; the deeper level's wider basin reaches the truth from there (0.93).
  int realign_level = 2;
  /// Phase-correlation peaks between a candidate's render and the live image tried as starts
  /// (besides the candidate's own pose), with at least min_response (0..1).
  int shift_starts = 2;
  double min_response = 0.05;
  /// Each candidate's render also gives a start from ORB point features matched with the live
  /// image and lifted to 3D by the render's depth (a RANSAC PnP, localize/feature_pose.hpp): a
  /// start from many points' geometry, where the candidate's pose is outside the alignment's basin.
  bool feature_starts = true;
  FeaturePoseOptions features;
  /// Feature starts that another candidate's feature start agrees with (within this fraction of
  /// the scene depth and these degrees) are aligned first, by the RANSAC inliers of all that
  /// agree with them, then the best one no other agrees with; the other lone ones go last (one
  /// render's pose alone can be a repeated texture's, and must not crowd out the edge starts).
  double feature_agree_fraction = 0.05;
  double feature_agree_deg = 3.0;
  /// A pose a search finds is taken only inside the box of the database's keyframe positions
  /// grown by the grid's reach (KeyframeDatabase::positionBounds, positionReach): the navigable
  /// space the database was built for. A look-alike place can verify well from the floor or
  /// from inside a wall (the room: 2.9 m and 63 deg off at floor level, score 0.92). A database
  /// built at one height bounds the height to +- the reach; one with a single position (reach 0)
  /// bounds nothing.
  bool inside_database_box = true;
  /// Without a keyframe database, a search after a loss uses keyframes rendered when needed
  /// (seed 001 sec. II-D renders keyframes as tracking needs them): 160 pixels wide at the last
  /// tracked position (and at the prediction's, when it lies farther than local_offset_fraction x
  /// the scene depth from it), the last tracked orientation turned about the camera's own vertical
  /// axis (the image's) in local_headings steps over the full turn and tilted by each of
  /// local_tilts_deg about its horizontal one. They are made again after a tracked frame and when
  /// the prediction moves on by more than local_offset_fraction x the depth, and searched as a
  /// database's are while the loss is at most local_max_s old (a camera lost longer may be
  /// anywhere). A pose found is taken only within local_depth_fraction x the scene depth (the
  /// last tracked frame's) + growth_m_s x the seconds since the last tracked frame of the path
  /// from the last tracked position to the prediction's. With the IMU, only once the
  /// prediction's 3 sigma exceeds local_offset_fraction x that depth. Before a first pose is
  /// taken, the start pose (the first aligned frame's guess: Localizer::reset's pose, or the
  /// prediction from it after empty frames) stands for the last tracked one, the first frame's
  /// time and that keyframe's depth for theirs, and a tracked pose too must lie within that bound
  /// (not against a caller's guess).
  /// 0 headings: no search without a database.
  int local_headings = 12;
  std::vector<double> local_tilts_deg{-25.0, 0.0, 25.0};
  double local_offset_fraction = 0.1;
  double local_max_s = 10.0;
  double local_depth_fraction = 0.5;
  /// The local search starts on the frame that makes this many untracked frames in a row (>= 1).
  /// At once, as a database's: one frame later, the camera has moved on from the last tracked pose
  /// (README, relocalization without a database).
  int local_after_untracked_frames = 1;
};

/// Everything the Localizer can be tuned with. Plain data; checked by Localizer::create.
struct LocalizerOptions {
  LocalizerBackend backend = LocalizerBackend::kAuto;   ///< Backend of the live stages and alignment.
  RerenderPolicy policy = RerenderPolicy::kWhenNeeded;  ///< When a keyframe is made anew.
  RerenderThresholds rerender;                          ///< Thresholds of kWhenNeeded.
  /// Keyframes on a worker thread beside tracking (default), or on the caller's thread
  /// (deterministic: the same input gives the same output, for tests and debugging).
  KeyframeThreading keyframe_threading = KeyframeThreading::kWorkerThread;
  /// Worker mode: a keyframe is requested at the pose predicted for the frame at which it will
  /// be ready (its measured making time over the measured wall time between frames: the time
  /// per frame when frames come back to back, the camera's period when they come at its pace),
  /// at most this many frames ahead.
  int max_keyframe_lead_frames = 4;
  /// Worker mode: run the worker thread at the lowest scheduling priority (Linux SCHED_IDLE):
  /// tracking frames are then never slowed by keyframe making, but on a machine whose cores
  /// other work keeps busy the worker may get no time at all and keyframes age (README,
  /// "Performance"). Waiting keyframes (start, loss) are made on the caller's thread either way.
  bool keyframe_worker_background = false;
  /// Near/far clip planes (metres) and back-face culling of keyframe renders; `outputs` and
  /// `threads` are set by the Localizer (colour, depth and normals are always rendered; threads:
  /// keyframe_render_threads).
  RenderSettings render;
  /// Threads of the CPU rasterizer's keyframe renders (RenderSettings::threads; 0..64). 0 =
  /// automatic: every core this process may use (availableCores) where the caller waits for the
  /// render (synchronous keyframes; with the worker, the waiting keyframes of a start or a loss
  /// and the relocalization's renders), and 1 on the keyframe worker, which runs beside
  /// tracking. Another count applies everywhere. GPU renderers ignore it.
  int keyframe_render_threads = 0;
  LiveFrameOptions live;                                ///< Live-image pyramid, edges and distance fields.
  ReferenceEdgeOptions reference;                       ///< Keyframe edge points (levels are set to live.levels).
  EdgeTrackerOptions tracker;                           ///< Gauss-Newton alignment and lost-frame thresholds.
  MotionModel motion = MotionModel::kConstantVelocity;  ///< Guess when the caller gives none.
  /// When a frame is lost against an older keyframe (kWhenNeeded), render a fresh one at the
  /// guess and align once more before reporting the frame lost.
  bool retry_lost_with_fresh_reference = true;
  /// Worker mode, with the IMU: a pose the filter's gate refuses, aligned against a keyframe the
  /// synchronous mode would have replaced for this frame (KeyframeManager::needsKeyframe at the
  /// guess), is aligned once more against a keyframe made at the guess (waiting for it).
  bool retry_refused_with_fresh_reference = true;
  /// Initializer (until the first frame is tracked after create/reset): refinements from fresh
  /// keyframes, and the start-up search over rotations (see InitializerOptions).
  int init_refinements = 4;
  int init_search_steps = 1;
  double init_search_deg = 4.0;               ///< Grid step of the start-up search, degrees.
  double init_confident_inlier_ratio = 0.75;  ///< No start-up search at or above this inlier ratio.
  double init_min_inlier_gain = 0.05;         ///< A grid start's gain over the first alignment to replace it.
  /// Learn which geometric edge kinds the live images show (KeyframeManagerOptions).
  bool adapt_edge_kinds = true;
  double kind_visibility_ratio = 0.7;  ///< See adapt_edge_kinds (0..1).
  /// Leave out of a frame's alignment the keyframe points that the predicted motion (last
  /// tracked pose to the guess) moves more than this in the image, pixels (0 = keep all; not
  /// applied when fewer than a fifth of a level's points, or fewer than 100, would remain):
  /// surfaces passing close to the camera are smeared by motion blur and their edges alias onto
  /// wrong ones.
  double max_point_motion_px = 40.0;
  InertialAiding inertial;  ///< IMU-propagated guesses and consistency gate (when readings are given).
  /// Constants of LocalizationResult::verify_score (inlier_threshold_px is taken from `tracker`).
  VerificationOptions verification;
  /// The prior's uncertainty sets how far the alignment searches: with a covariance (kEkf), a
  /// frame's alignment starts at the pyramid level where search_sigmas x the predicted 1-sigma
  /// image displacement (translation across the view at the keyframe's median depth, and
  /// rotation) is at most search_basin_px pixels of that level, up to max_search_level (the live
  /// pyramid is built that deep; 0 = never deeper than the tracker's own coarsest levels). A start
  /// with an unknown velocity thus searches coarse, a settled filter fine. Without a covariance
  /// (no IMU, or before its first reading) the first frame after a start, whose motion is unknown
  /// (MotionPrediction::velocity_unobserved), starts at max_search_level. A frame started deeper
  /// than the tracker's own levels is aligned from those as well, and the result with more
  /// inliers on the finest level is kept (a coarse level may slide along the valley where a
  /// translation across the view trades for a rotation, and the finer ones not pull it back).
  int max_search_level = 2;
  double search_sigmas = 3.0;
  double search_basin_px = 6.0;
  /// Motion search: when a frame is lost, or its pose refused by the prior's gate, while the
  /// prior's translation uncertainty across the view spans more than the basin of the deepest
  /// search level (a start in motion with an unknown velocity), the alignment is tried from
  /// other starts: first those the image shifts since the last tracked frame point at (see
  /// below), then a grid of start translations across the view (spaced 1.5 basins of that level
  /// apart, out to search_sigmas sigma but at most motion_search_steps steps each way), probed
  /// with a few Gauss-Newton steps on that level alone, and aligned fully, each against a
  /// keyframe rendered at it, from the motion_search_candidates probes with the most inliers
  /// (ties: the lower mean residual) that ended at distinct poses. Of the results tracked, passing the
  /// gate and verified (verification.min_score; motion_search_confident_score while the prior's
  /// velocity is unobserved, MotionPrediction::velocity_unobserved) the best score is kept. On
  /// the first frame after an inertial start at an unknown velocity the search also runs when the
  /// plain alignment verifies below motion_search_start_score (that pose would set the
  /// velocity); a searched pose then replaces the plain one only when it verifies higher.
  /// Without the IMU (a constant-velocity prior: no covariance, no gate) a frame that does not
  /// verify gets the starts from the last tracked frame alone (point features, image shifts; no
  /// grid), unless that frame's pose is on probation (relocalization.confirm_start); a result is
  /// then taken only at motion_search_confident_score (or, when the edges agree with the feature
  /// start, at the score any pose needs without the IMU) and within the local search's bound of
  /// the path from the last tracked pose to the prediction (relocalization.local_depth_fraction,
  /// growth_m_s).
  /// 0 steps = off.
  int motion_search_steps = 6;
  int motion_search_candidates = 3;
  /// Before the grid, the motion search aligns from the start the image shift since the last
  /// tracked frame points at (track/image_motion.hpp), when that frame is at most
  /// motion_search_max_gap_s old and the shift's phase correlation response is at least
  /// motion_search_min_response; a start more than a grid step from the current keyframe's pose
  /// is aligned against a keyframe rendered at it. In a stream slower than this (its interval:
  /// the least of its last 8 frame intervals, so a pause does not count) the bound is 1.5 of its
  /// intervals, at most 1 s: the frame before is recent. The same bound ("recent") holds wherever
  /// frames must follow each other: the feature start below, refusals in a row, a refused
  /// stretch, a kept velocity's check (0 = no frame is recent).
  double motion_search_max_gap_s = 0.25;
  double motion_search_min_response = 0.1;
  /// First of all, the motion search aligns from the pose of ORB point features matched between
  /// the last tracked frame (when recent, see motion_search_max_gap_s) and this one, lifted to 3D by a
  /// depth render at the last tracked pose (featurePose with relocalization.features). Two
  /// camera images match where a render and an image do not (blur, light), and the pose needs
  /// no guess of the motion: a start at an unknown velocity, a frame rate too low for the
  /// shift and the grid (a blurred drone 2.5 m a frame).
  bool motion_search_feature_start = true;
  /// The alignment from that start is taken without its verification score when it ends within
  /// relocalization.feature_agree_fraction x the scene depth and feature_agree_deg of the
  /// feature pose, and that pose has at least this many RANSAC inliers making at least this
  /// fraction of its matches (two independent poses agree; a consensus among wrong matches, a
  /// repeated facade, leaves most matches out). Otherwise it is verified as any other start.
  int motion_search_feature_min_inliers = 30;
  double motion_search_feature_min_inlier_fraction = 0.5;
  /// While the prior's velocity is unobserved (the first frame after a start or a restart at an
  /// unknown velocity: the pose taken sets the filter's velocity), an agreeing pair as above keeps
  /// the feature pose rather than the alignment's when the gyro sides with it
  /// (attitudeFavoursFeaturePose: the alignment's own attitude, without the filter's prior, more
  /// than this many sigmas of the prediction's attitude from it, the feature pose's within half as
  /// many). An edge alignment on a model that lacks the image's texture (geometry only) can end
  /// off the truth along the valley where a turn trades for a translation across the view; two
  /// camera images' features are not misled by the model. The feature pose carries the previous
  /// pose's error, as the gyro's prediction does: the velocity between the two is the camera's
  /// even then. 0 = always the alignment's (measured: README, "The pose a frame reports").
  double motion_search_feature_attitude_sigmas = 2.5;
  /// The motion search keeps the best verified result of its starts and stops at one whose
  /// verification score reaches this (true poses of the development sequences score 0.5-1);
  /// while the prior's velocity is unobserved, at motion_search_start_score if higher. Without
  /// the IMU it is also the score a tracked pose needs on the frame after a relocalized one or
  /// after lost ones (its guess is a searched pose, or a motion carried across the loss).
  double motion_search_confident_score = 0.5;
  /// The first frame after an inertial start at an unknown velocity sets the filter's velocity
  /// for the frames to come, and the plain alignment starts from the pose of the frame before (no
  /// motion): where the scene repeats along the path (a street of alike facades) and the camera
  /// moved more than half a period, the nearest look-alike is nearer than the truth and verifies
  /// too (the development city at a third of its frame rate, 3.75 m per frame: 6 m behind the
  /// truth at 0.68, the truth 0.81, and the filter then flew backwards at 15 m/s). Such a frame
  /// goes to the motion search unless its plain alignment verifies with this score; the search
  /// keeps the best verified of its poses and the plain one, and stops early only at this score
  /// while the velocity is unobserved (0..1; a value at or below motion_search_confident_score
  /// gives the rule before this option: search below the confident score, stop at it).
  double motion_search_start_score = 0.8;
  /// Restart of the motion prior: after this many poses in a row (each recent to the one before,
  /// see motion_search_max_gap_s) that the prior's gate refused although their verification score was at least
  /// restart_min_score, or at least verification.min_score and above the scores of each of the
  /// last five poses the prior took (refusalCountsAgainstPrior), the prior restarts at the last of
  /// them (Localizer result prior_restarted; its velocity: restart_sigma_velocity_m_s). 0 = never.
  int restart_after_refusals = 2;
  double restart_min_score = 0.5;
  /// Restart of the motion prior whatever the scores: after the prior's gate has refused every
  /// tracked pose for this long (seconds; each pose recent to the one before, see
  /// motion_search_max_gap_s: in a stream of 3 images a second two poses make 0.3 s; a pose
  /// refused only because a restarted prior takes verified poses alone does not count), it
  /// restarts at the last one (prior_restarted); where one of the stretch's poses verified
  /// (verification.min_score), at the first verified one from then on. A prior that refuses
  /// alignments frame after frame for that long has drifted (a wrong velocity or tilt taken from
  /// biased poses, with a covariance too small to admit it) more often than the alignments are
  /// all wrong, and an inertial stretch goes on drifting until max_inertial_s ends it anyway.
  /// 0 = never.
  double restart_after_refused_s = 0.3;
  /// 1-sigma (m/s, at least the filter's own) of the velocity a restarted prior keeps: the
  /// filter's velocity at that frame, when it has an observed one (kEkf), else an unknown
  /// velocity as at a start. The poses it refused disagree with its position; its velocity,
  /// integrated from the accelerometer, may be off by what the refusals say but not by the
  /// camera's speed, which is what a start at rest is off by (a drone restarted so drifts off at
  /// its speed, and the only poses a restarted prior takes, verified ones, may not come where
  /// the refusals came from). A restarted prior that refuses the next verified pose had the
  /// velocity wrong: it restarts at that pose at an unknown velocity. 0 = an unknown velocity.
  double restart_sigma_velocity_m_s = 1.0;
  /// Align each frame the filter predicts from the IMU with the filter's attitude as a prior
  /// (EdgeTrackerOptions::rotation_prior: the prediction's attitude and its rotation covariance,
  /// kEkf only); the filter then takes the edges' own pose (TrackResult::T_world_camera_edges),
  /// so the attitude is not counted twice. The gyro pins the rotation that a narrow view barely
  /// tells from a translation across it. Not for a caller's guess or a relocalization. The
  /// tracker options' own rotation_prior is not used (this sets it per frame).
  bool rotation_prior_from_filter = true;
  /// Factor on the filter's rotation covariance in that prior (> 1 trusts the gyro less).
  double rotation_prior_covariance_scale = 1.0;
  /// With kAuto and an Accelerator: time the CPU and device live stages + alignment on the
  /// first frame and keep the faster one (instead of deciding by the device type alone).
  bool calibrate_backend = false;
  /// With a prior that fuses the visual poses with the IMU (InertialFilter::kEkf), a tracked
  /// frame reports the filter's estimate at the frame's time after it took the frame's pose (its
  /// posterior: LocalizationResult::pose_filtered), the alignment's own pose in
  /// LocalizationResult::T_world_camera_visual; false reports the alignment's pose. The filter
  /// weighs each alignment against the IMU's propagation: an alignment that slid along an
  /// ambiguity (rotation against translation across the view, a poorly verified fit) moves the
  /// estimate by what its covariance allows, not all the way.
  bool report_filtered_pose = true;
  /// Relocalization and global initialization (used only when a keyframe database is given).
  RelocalizationOptions relocalization;
  /// Frames with nothing to align (checkImageContent; min_contrast 0 = check off): no alignment,
  /// search or relocalization runs on them; the motion prior bridges them (kInertial with the
  /// IMU, else kLost) and LocalizationResult::image_content says why.
  ImageContentOptions image_content;
};

/// Outcome of one localized frame.
struct LocalizationResult {
  int64_t t_ns = 0;                        ///< Frame time, nanoseconds.
  Pose T_world_camera = Pose::Identity();  ///< Estimated pose (not trusted when lost).
  /// Covariance of xi (m^2, rad^2, [rho; phi], live camera frame; see TrackResult::covariance).
  Matrix6d covariance = Matrix6d::Zero();
  /// T_world_camera and covariance are the filter's posterior at the frame's time
  /// (LocalizerOptions::report_filtered_pose), and T_world_camera_visual the pose the frame's
  /// alignment found and the filter took. Otherwise T_world_camera_visual is T_world_camera.
  bool pose_filtered = false;
  Pose T_world_camera_visual = Pose::Identity();
  TrackQuality quality;  ///< Alignment quality on the finest level.
  /// Verification score of the frame's alignment (0..1, track/pose_verification.hpp): at or
  /// above LocalizerOptions::verification.min_score the pose is the true one with the measured
  /// rates of `vkloc bench verify`. A pose scoring below it is not taken (state kLost or
  /// kInertial) with a keyframe database, without the IMU, and before a first pose is taken since
  /// create/reset (but on the first frame near the start pose or the caller's guess); otherwise
  /// the IMU's gate decides.
  double verify_score = 0;
  /// kTracking: the visual alignment is trusted; kInertial: it was lost or disagreed with the
  /// IMU, T_world_camera is the inertial prediction (InertialAiding); kLost: no trusted pose.
  TrackingState state = TrackingState::kLost;
  bool visual_rejected = false;  ///< The alignment tracked but lay outside the inertial gate.
  /// kOk, or why the frame had nothing to align (then nothing was aligned or searched, and
  /// state is kInertial, kLost or kInitializing), and the contrast it was decided on
  /// (ImageContentCheck::contrast, gray levels; 0 when the check is off).
  ImageContent image_content = ImageContent::kOk;
  double image_contrast = 0;
  /// The motion prior was restarted at this frame's pose (LocalizerOptions::restart_after_refusals).
  bool prior_restarted = false;
  /// Squared Mahalanobis distance of the tracked pose to the filter's prediction (kEkf; NaN when
  /// not tested: no filter yet, or the frame was not tracked). Chi-square with 6 DOF when consistent.
  double innovation = std::numeric_limits<double>::quiet_NaN();
  double inertial_sigma_m = 0;      ///< 1-sigma of the inertial prediction, metres (0: none made).
  bool reference_rendered = false;  ///< A keyframe was made on this call (the caller waited for it).
  bool keyframe_adopted = false;    ///< Worker mode: a keyframe finished by the worker was taken up.
  bool keyframe_requested = false;  ///< Worker mode: a new keyframe was requested after this frame.
  uint64_t keyframe_id = 0;         ///< Keyframe the frame was tracked against (1, 2, ...).
  /// Frames between the frame the keyframe's pose was made for and this one (negative: it was
  /// made for a frame still to come).
  int64_t keyframe_age_frames = 0;
  /// Worker mode: the pose found against a lagging keyframe was refused, and the frame was
  /// aligned again against one made at the guess (LocalizerOptions::retry_refused_with_fresh_reference).
  bool keyframe_retried = false;
  int reference_points = 0;      ///< Edge points of the finest keyframe level.
  int search_level = 0;          ///< Deepest pyramid level the prior's uncertainty made the alignment start at.
  int motion_search_probes = 0;  ///< Start translations probed by the motion search (0: none ran).
  double image_shift_px = 0;     ///< Image shift the motion search measured, pixels (0: none).
  /// This frame's pose is on probation until a later frame confirms it
  /// (RelocalizationOptions::confirm_start): state is kInitializing, T_world_camera that pose (a
  /// global search's, a first pose after lost frames, or a frame tracked from such a pose whose
  /// motion search fell short, which waits one frame more).
  bool confirming = false;
  /// Database keyframes aligned by a relocalization search on this frame (0: none ran), the
  /// radius of its region (metres; infinite: the whole database; a local search's: its bound,
  /// RelocalizationOptions::local_headings) and its time (ms, in total_ms).
  int relocalization_candidates = 0;
  /// Candidates whose render gave a start from matched point features (RelocalizationOptions::
  /// feature_starts).
  int relocalization_feature_starts = 0;
  /// Database index of the keyframe the search ranked first (nearest descriptor, re-ranked by
  /// the phase-correlation peak less RelocalizationOptions::rerank_bits_weight per bit of
  /// descriptor distance when rerank_candidates is on; -1: no search
  /// ran or none lay in the region): the retrieval's answer, before any alignment. After a local
  /// search, an index into the keyframes rendered for it.
  int64_t relocalization_top_keyframe = -1;
  double search_radius_m = 0;
  double relocalization_ms = 0;
  double scene_depth_m = 0;  ///< Median depth of the keyframe render's surfaces, metres (0: none seen).
  double render_ms = 0;      ///< Rendering keyframes on this call, ms (0 when none was made here).
  double reference_ms = 0;   ///< Extracting their edge points, ms.
  double live_ms = 0;        ///< Live pyramid, edges and distance fields, ms.
  double align_ms = 0;       ///< Gauss-Newton alignment (and a search's feature poses), ms.
  double total_ms = 0;       ///< Whole localize() call, ms.
  /// With a camera front: the view the frame was tracked in (T_world_camera is the camera's,
  /// T_world_camera * T_camera_view the view's) and the remap's time (ms, in total_ms).
  Pose T_camera_view = Pose::Identity();
  double front_ms = 0;
};

/// Tracks a camera through a model, one frame at a time. Thread-safety: one thread calls
/// localize(), addImu(), reset() and backendSummary() (they are not reentrant); the keyframe
/// worker the Localizer owns runs on its own thread and shares nothing else with the caller.
class Localizer {
 public:
  /// Prepares the renderer and the edge backends (on `accelerator`'s device, or the CPU when it
  /// is null). kInvalidArgument for a bad camera, invalid model or options out of range;
  /// kNoDevice when backend kVulkan is asked for without an accelerator; the device's errors
  /// (kGpuError) when it fails. The model is copied (uploaded) and not referenced afterwards.
  static Result<std::unique_ptr<Localizer>> create(const Model& model, const PinholeCamera& camera,
                                                   const LocalizerOptions& options,
                                                   std::shared_ptr<Accelerator> accelerator);
  ~Localizer();
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  /// Localizes an 8-bit gray image (camera size, 1 channel; the lens's with a camera front) taken at t_ns. The guess,
  /// when given, replaces the motion prior's prediction. A lost frame is not an error (state kLost); the next frame is
  /// predicted from the last tracked pose. Errors (kInvalidArgument): wrong image size or channels, a non-finite or
  /// non-rigid guess, t_ns not after the previous frame's, no guess and no pose yet (call reset() first); device errors
  /// as they come.
  Result<LocalizationResult> localize(int64_t t_ns, const ImageU8& gray,
                                      const std::optional<Pose>& T_world_camera_guess = std::nullopt);

  /// Gives the camera front (null: none): localize() then takes the lens's images (its size),
  /// remaps each to the view (undistorted, or stabilised at the camera's predicted attitude) and
  /// tracks in it; poses, covariances and guesses stay the physical camera's. The view must be the
  /// camera this Localizer was made for (kInvalidArgument otherwise). Give it before the first
  /// frame or call reset() after.
  Status setCameraFront(std::unique_ptr<CameraFront> front);
  const CameraFront* cameraFront() const;

  /// Gives one IMU reading (body frame; InertialAiding). Readings up to a frame's time should be
  /// given before the frame. kInvalidArgument for a non-finite reading or a time not after the
  /// previous reading's (the reading is ignored; tracking goes on).
  Status addImu(const ImuSample& sample);
  /// The inertial filter's states since the last call, oldest first, one per IMU reading after
  /// the filter started (InertialFilter::kEkf; empty otherwise): the output at the IMU rate.
  std::vector<FilterOutput> takeFilterOutputs();
  /// Forgets the motion, the IMU readings and the keyframe and restarts from T_world_camera
  /// (e.g. the known initial pose, or after relocalization). Timestamps may start over. An
  /// invalid pose is ignored (the next localize() then needs a guess). v_world_camera: the
  /// camera's velocity in the world frame (m/s) when known (a camera already in motion), else
  /// the motion prior starts from an unknown velocity.
  void reset(const Pose& T_world_camera, const std::optional<Eigen::Vector3d>& v_world_camera = std::nullopt);

  /// Gives the keyframe database that relocalization and global initialization search (null:
  /// none; they are off). Shared, not copied. kInvalidArgument when it was built for another
  /// model, or for a camera whose field of view differs from this one's by more than 5 %.
  Status setKeyframeDatabase(std::shared_ptr<const KeyframeDatabase> database);
  /// Global initialization: forgets the pose and searches the following frames in `region` (a
  /// GPS-like prior; the whole database when nullopt) until a pose is verified (state
  /// kRelocalized; with RelocalizationOptions::confirm_start on the frame after the search's,
  /// which confirms it), then tracks on. Frames before are kInitializing. localize() then needs no
  /// guess. kInvalidArgument without a database or for a non-finite region.
  Status startSearch(const std::optional<SearchRegion>& region);

  /// One line: renderer, live/alignment backend and why it was chosen, keyframe policy and threading.
  std::string backendSummary() const;

  struct Impl;

 private:
  explicit Localizer(std::unique_ptr<Impl> impl);
  Result<LocalizationResult> localizeView(int64_t t_ns, const ImageU8& gray,
                                          const std::optional<Pose>& T_world_view_guess);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkloc
