#include "vkloc/localize/keyframe_manager.hpp"

#include <fmt/format.h>

#include <cmath>

#include "vkloc/core/se3.hpp"

namespace vkloc {
Result<RerenderPolicy> parseRerenderPolicy(const std::string& name) {
  if (name == "every-frame") return RerenderPolicy::kEveryFrame;
  if (name == "when-needed") return RerenderPolicy::kWhenNeeded;
  return makeError(ErrorCode::kInvalidArgument,
                   fmt::format("re-render policy '{}': expected every-frame or when-needed", name));
}

const char* rerenderPolicyName(RerenderPolicy policy) {
  return policy == RerenderPolicy::kEveryFrame ? "every-frame" : "when-needed";
}

Result<KeyframeThreading> parseKeyframeThreading(const std::string& name) {
  if (name == "worker") return KeyframeThreading::kWorkerThread;
  if (name == "sync") return KeyframeThreading::kSynchronous;
  return makeError(ErrorCode::kInvalidArgument, fmt::format("keyframes '{}': expected worker or sync", name));
}

const char* keyframeThreadingName(KeyframeThreading threading) {
  return threading == KeyframeThreading::kWorkerThread ? "worker" : "sync";
}

KeyframeManager::KeyframeManager(std::unique_ptr<KeyframeMaker> maker, const KeyframeManagerOptions& options)
    : options_(options), renderer_description_(maker->describe()) {
  if (options.threading == KeyframeThreading::kWorkerThread) {
    worker_ = std::make_unique<KeyframeWorker>(std::move(maker), options.background_worker);
  } else {
    maker_ = std::move(maker);
  }
}

KeyframeManager::~KeyframeManager() = default;

bool KeyframeManager::mustWait() const { return !current_ || current_->reference.points.size() < 6 || last_lost_; }

bool KeyframeManager::needsKeyframe(const Pose& T_world_camera) const {
  if (!current_ || current_->reference.points.size() < 6) return true;
  if (options_.policy == RerenderPolicy::kEveryFrame) return true;
  if (last_lost_) return true;
  const RerenderThresholds& r = options_.thresholds;
  if (frames_on_keyframe_ >= r.max_frames) return true;
  if (last_inlier_ratio_ < r.min_inlier_ratio) return true;
  const Pose T_ref_camera = current_->reference.T_world_ref.inverse() * T_world_camera;
  const double depth = current_->scene_depth_m > 0 ? current_->scene_depth_m : 1.0;
  if (T_ref_camera.translation().norm() > r.max_translation_depth_ratio * depth) return true;
  return rotationAngleDeg(T_ref_camera.linear()) > r.max_rotation_deg;
}

void KeyframeManager::setCurrent(std::shared_ptr<const Keyframe> keyframe) {
  current_ = std::move(keyframe);
  frames_on_keyframe_ = 0;
}

Status KeyframeManager::makeNow(KeyframeRequest request, double& render_ms, double& reference_ms) {
  request.dropped_kinds = droppedKinds();
  Result<std::shared_ptr<const Keyframe>> made = worker_ ? worker_->makeNow(request) : maker_->make(request);
  if (!made.ok()) return made.error();
  render_ms += (*made)->render_ms;
  reference_ms += (*made)->reference_ms;
  setCurrent(std::move(made).value());
  return Status::success();
}

Result<RenderOutput> KeyframeManager::renderView(const PinholeCamera& camera, const Pose& T_world_camera) {
  return worker_ ? worker_->renderNow(camera, T_world_camera) : maker_->renderView(camera, T_world_camera);
}

bool KeyframeManager::request(KeyframeRequest request) {
  if (!worker_ || worker_->busy()) return false;
  request.dropped_kinds = droppedKinds();
  worker_->request(request);
  return true;
}

Result<bool> KeyframeManager::adoptFinished() {
  if (!worker_) return false;
  Result<std::shared_ptr<const Keyframe>> finished = worker_->takeFinished();
  if (!finished.ok()) return finished.error();
  if (!*finished) return false;
  setCurrent(std::move(finished).value());
  return true;
}

void KeyframeManager::frameTracked(const TrackQuality& quality) {
  ++frames_on_keyframe_;
  last_inlier_ratio_ = quality.inlier_ratio;
  learnEdgeKinds(quality);
  last_lost_ = false;
}

void KeyframeManager::frameNotTracked() {
  ++frames_on_keyframe_;
  last_lost_ = true;
}

void KeyframeManager::reset() {
  if (worker_) worker_->discard();
  current_.reset();
  frames_on_keyframe_ = 0;
  last_inlier_ratio_ = 1.0;
  last_lost_ = false;
}

void KeyframeManager::learnEdgeKinds(const TrackQuality& q) {
  if (!options_.adapt_edge_kinds) return;
  constexpr int kMinPoints = 20;
  for (size_t k = 0; k < kind_inlier_mean_.size(); ++k) {
    if (kind_dropped_[k] || q.kind_points_in_image[k] < kMinPoints) continue;
    const double r = q.kind_inlier_ratio[k];
    kind_inlier_mean_[k] = kind_inlier_mean_[k] < 0 ? r : 0.7 * kind_inlier_mean_[k] + 0.3 * r;
  }
  if (kind_inlier_mean_[0] < 0) return;
  for (size_t k = 1; k < kind_inlier_mean_.size(); ++k) {
    if (kind_inlier_mean_[k] >= 0 && kind_inlier_mean_[k] < options_.kind_visibility_ratio * kind_inlier_mean_[0]) {
      kind_dropped_[k] = true;
    }
  }
}

}  // namespace vkloc
