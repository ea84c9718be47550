// vkloc: the start of tracking. Until a first frame is tracked after create/reset, the pose
// guess may be far off (a GPS-like prior, a user's estimate): the alignment's basin is widened
// by a search over start rotations and by alignments repeated from fresh keyframes rendered at
// each estimate.
#pragma once

#include <functional>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/track/edge_tracker.hpp"

namespace vkloc {

/// Options of the Initializer. Plain data; validateInitializerOptions checks them.
struct InitializerOptions {
  /// When a frame is lost, render a new keyframe at the estimate and align again, up to this
  /// many times (widens the basin of convergence of the initial pose).
  int refinements = 4;
  /// When the first alignment is lost or below confident_inlier_ratio: align again from the
  /// guess turned by i x search_deg about the camera's x axis and j x search_deg about its y
  /// axis, i, j in -search_steps..search_steps, and keep the best (tracking first, then the
  /// inlier ratio). 0 steps = off (README, "Accuracy": Castle-simu from 2 cm / 5 deg off).
  int search_steps = 1;
  double search_deg = 4.0;               ///< Grid step of the start-up search, degrees.
  double confident_inlier_ratio = 0.75;  ///< No start-up search at or above this inlier ratio.
  /// A grid start replaces the first alignment in the same state only with an inlier ratio at
  /// least this much higher: ratios of one frame's alignments differ by a few hundredths from
  /// where their points fall, and the first alignment starts from the guess (the fisheye's
  /// central crop over the hard city, 640x480: from the exact start pose 0.16 m off at 0.548,
  /// replaced by a grid start 2.29 m off at 0.554, and every frame after was lost).
  double min_inlier_gain = 0.05;
};

/// kInvalidArgument naming the field for values out of range.
Status validateInitializerOptions(const InitializerOptions& options);

/// The tracking steps the Initializer drives (the Localizer's, or a test's).
struct InitializerSteps {
  /// Aligns the current frame with the current keyframe from a start pose.
  std::function<Result<TrackResult>(const Pose& T_world_camera_start)> align;
  /// Makes a new keyframe at a pose and makes it current (waits for it).
  std::function<Status(const Pose& T_world_ref)> rekey;
};

/// Refines the first alignment of a frame while no frame has been tracked since create/reset.
/// Stateless; safe to share between threads.
class Initializer {
 public:
  explicit Initializer(const InitializerOptions& options) : options_(options) {}
  /// `first` is the plain alignment from `guess`. Returns the best result found (the start-up
  /// search, then the refinements from fresh keyframes while it is lost). Step errors are
  /// returned as they are.
  Result<TrackResult> refine(const Pose& guess, TrackResult first, const InitializerSteps& steps) const;

 private:
  InitializerOptions options_;
};

}  // namespace vkloc
