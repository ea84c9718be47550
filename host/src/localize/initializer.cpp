#include "vkloc/localize/initializer.hpp"

#include <cmath>
#include <optional>

#include "vkloc/core/numeric.hpp"
#include "vkloc/core/se3.hpp"

namespace vkloc {
Status validateInitializerOptions(const InitializerOptions& o) {
  if (o.refinements < 0 || o.refinements > 100) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: init_refinements must be in 0..100");
  }
  if (o.search_steps < 0 || o.search_steps > 10 || !finiteIn(o.search_deg, 0.0, 90.0) ||
      !finiteIn(o.confident_inlier_ratio, 0.0, 1.0) || !finiteIn(o.min_inlier_gain, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need init_search_steps in 0..10, init_search_deg in 0..90, "
                     "init_confident_inlier_ratio in 0..1 and init_min_inlier_gain in 0..1");
  }
  return Status::success();
}

Result<TrackResult> Initializer::refine(const Pose& guess, TrackResult track, const InitializerSteps& steps) const {
  // A result that is not clearly right: the alignment also starts from the guess turned about
  // the camera's x and y axes on a grid (search_deg steps); the best of those (tracking over
  // lost, then the inlier ratio) replaces it when tracking where it is lost, or in the same state
  // by min_inlier_gain.
  if (options_.search_steps > 0 &&
      !(track.state == TrackingState::kTracking && track.quality.inlier_ratio >= options_.confident_inlier_ratio)) {
    const int n = options_.search_steps;
    const double step_rad = options_.search_deg * M_PI / 180.0;
    auto better = [](const TrackResult& a, const TrackResult& b) {
      const bool a_tracking = a.state == TrackingState::kTracking;
      const bool b_tracking = b.state == TrackingState::kTracking;
      if (a_tracking != b_tracking) return a_tracking;
      return a.quality.inlier_ratio > b.quality.inlier_ratio;
    };
    std::optional<TrackResult> best;
    for (int i = -n; i <= n; ++i) {
      for (int j = -n; j <= n; ++j) {
        if (i == 0 && j == 0) continue;
        Pose start = guess;
        start.linear() = guess.linear() * expSO3(Eigen::Vector3d(i * step_rad, j * step_rad, 0.0));
        Result<TrackResult> candidate = steps.align(start);
        if (!candidate.ok()) return candidate.error();
        if (!best || better(*candidate, *best)) best = std::move(candidate).value();
      }
    }
    const bool tracking = track.state == TrackingState::kTracking;
    if (best && (best->state == TrackingState::kTracking) != tracking) {
      if (!tracking) track = std::move(*best);
    } else if (best && best->quality.inlier_ratio >= track.quality.inlier_ratio + options_.min_inlier_gain) {
      track = std::move(*best);
    }
  }
  // A guess far off converges in steps, each rendering a fresh keyframe at the last estimate.
  for (int step = 0;
       step < options_.refinements && track.state == TrackingState::kLost && isValidPose(track.T_world_camera);
       ++step) {
    VKLOC_TRY_STATUS(steps.rekey(track.T_world_camera));
    Result<TrackResult> again = steps.align(track.T_world_camera);
    if (!again.ok()) return again.error();
    track = std::move(again).value();
  }
  return track;
}

}  // namespace vkloc
