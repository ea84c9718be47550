// vkloc: when and where keyframes are made (STAR, seed paper 001 sec. II-C), which edge kinds
// they keep, and whether they are made on the tracking thread or beside it.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/localize/keyframe.hpp"
#include "vkloc/track/edge_tracker.hpp"

namespace vkloc {

/// When the reference view (keyframe) is made anew.
enum class RerenderPolicy {
  kEveryFrame,  ///< Seed 000: render at the predicted pose for every frame.
  kWhenNeeded,  ///< STAR (seed 001 sec. II-C): keep the keyframe while it still fits (RerenderThresholds).
};

/// Parses "every-frame" | "when-needed"; kInvalidArgument otherwise.
Result<RerenderPolicy> parseRerenderPolicy(const std::string& name);
const char* rerenderPolicyName(RerenderPolicy policy);

/// Thresholds of RerenderPolicy::kWhenNeeded; a new keyframe is made when any is exceeded.
struct RerenderThresholds {
  /// Camera moved more than this fraction of the keyframe's median scene depth (translation of
  /// the pose relative to the keyframe camera).
  double max_translation_depth_ratio = 0.03;
  double max_rotation_deg = 3.0;   ///< Camera turned more than this since the keyframe, degrees.
  double min_inlier_ratio = 0.85;  ///< Last frame's TrackQuality::inlier_ratio fell below this.
  int max_frames = 10;             ///< This many frames were tracked against the same keyframe.
};

/// Where keyframes are made.
enum class KeyframeThreading {
  /// On a worker thread beside tracking (STAR's two processes): the tracking thread goes on
  /// with the newest finished keyframe and waits only when it has none it can use (start,
  /// reset, loss). Timing decides which keyframe a frame uses, so runs may differ slightly.
  kWorkerThread,
  /// On the tracking thread when needed, at the frame's guess: deterministic (tests, debugging).
  kSynchronous,
};

/// Parses "worker" | "sync"; kInvalidArgument otherwise.
Result<KeyframeThreading> parseKeyframeThreading(const std::string& name);
const char* keyframeThreadingName(KeyframeThreading threading);

/// Everything KeyframeManager is set up with.
struct KeyframeManagerOptions {
  RerenderPolicy policy = RerenderPolicy::kWhenNeeded;
  RerenderThresholds thresholds;
  KeyframeThreading threading = KeyframeThreading::kWorkerThread;
  /// Worker mode: run the worker thread at the lowest priority (KeyframeWorker).
  bool background_worker = false;
  /// Learn which geometric edges the live images show (an unlit render's creases and silhouettes
  /// may have no intensity edge in them, and rims of model holes none at all): after each tracked
  /// frame, the running mean (weight 0.3) of the inlier ratio of occlusion points, of crease
  /// points, of points near background (kEdgeBackground) and of points near a back face
  /// (kEdgeBackFace) is compared with the texture points'; a kind below kind_visibility_ratio times the texture's is
  /// left out of later keyframes (README, "Accuracy", has the measured ratios).
  bool adapt_edge_kinds = true;
  double kind_visibility_ratio = 0.7;  ///< See adapt_edge_kinds (0..1).
};

/// Owns the current keyframe and the maker (or worker) that makes the next. Policy decisions
/// read only the current keyframe and the last frame's outcome, so they are unit-testable with
/// any Renderer. Not thread-safe (the tracking thread's object); the worker it owns is.
class KeyframeManager {
 public:
  KeyframeManager(std::unique_ptr<KeyframeMaker> maker, const KeyframeManagerOptions& options);
  ~KeyframeManager();
  KeyframeManager(const KeyframeManager&) = delete;
  KeyframeManager& operator=(const KeyframeManager&) = delete;

  /// The keyframe frames are tracked against (null before the first).
  const std::shared_ptr<const Keyframe>& current() const { return current_; }
  const KeyframeManagerOptions& options() const { return options_; }
  /// The maker's renderer, described.
  std::string rendererDescription() const { return renderer_description_; }

  /// The policy: true when there is no usable keyframe (none, or fewer than 6 points), the
  /// last frame was not tracked, the policy is kEveryFrame, or one RerenderThresholds limit is
  /// passed by T_world_camera (the pose the keyframe must serve) or by the last frames.
  bool needsKeyframe(const Pose& T_world_camera) const;
  /// True when the current keyframe cannot be tracked against at all: there is none, it has
  /// fewer than 6 points, or the last frame was not tracked with it (the worker mode then
  /// waits for a fresh keyframe instead of going on).
  bool mustWait() const;

  /// Makes a keyframe at `request` (its dropped kinds are set here) and makes it current;
  /// waits for it (in worker mode after the keyframe in progress). `render_ms` / `reference_ms`
  /// get its times added.
  Status makeNow(KeyframeRequest request, double& render_ms, double& reference_ms);
  /// Worker mode: asks for a keyframe at `request` unless one is being made; returns whether
  /// it asked. Synchronous mode: false.
  bool request(KeyframeRequest request);
  /// Worker mode: makes the newest finished keyframe current; returns whether it changed.
  Result<bool> adoptFinished();
  /// A plain render (colour, depth) at any camera and pose with the keyframes' renderer, on the
  /// calling thread (worker mode: drops the waiting request). Renderer errors as they are.
  Result<RenderOutput> renderView(const PinholeCamera& camera, const Pose& T_world_camera);
  /// Makes an earlier keyframe current again (a search going back to a candidate's). Null is
  /// ignored.
  void restore(std::shared_ptr<const Keyframe> keyframe) {
    if (keyframe) setCurrent(std::move(keyframe));
  }

  /// Frame outcomes (each frame reports one): tracked with `quality` (edge kinds are learnt
  /// from it), or not tracked.
  void frameTracked(const TrackQuality& quality);
  void frameNotTracked();
  /// Forgets the keyframe and the last frame's outcome, drops requests (edge kinds are a
  /// property of the model and camera and are kept).
  void reset();

  /// Edge kinds left out of new keyframes.
  EdgeKindMask droppedKinds() const { return {kind_dropped_[1], kind_dropped_[2], kind_dropped_[3], kind_dropped_[4]}; }
  /// Frames tracked with the current keyframe.
  int framesOnKeyframe() const { return frames_on_keyframe_; }

 private:
  void setCurrent(std::shared_ptr<const Keyframe> keyframe);
  void learnEdgeKinds(const TrackQuality& q);

  KeyframeManagerOptions options_;
  std::string renderer_description_;
  std::unique_ptr<KeyframeMaker> maker_;    ///< Synchronous mode.
  std::unique_ptr<KeyframeWorker> worker_;  ///< Worker mode.
  std::shared_ptr<const Keyframe> current_;
  int frames_on_keyframe_ = 0;
  double last_inlier_ratio_ = 1.0;
  bool last_lost_ = false;
  // Running inlier ratio per kind [texture, occlusion, crease, near background, near a back
  // face] (-1: not measured yet) and the kinds left out of keyframes.
  std::array<double, 5> kind_inlier_mean_{-1.0, -1.0, -1.0, -1.0, -1.0};
  std::array<bool, 5> kind_dropped_{};
};

}  // namespace vkloc
