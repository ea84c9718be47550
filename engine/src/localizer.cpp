// Frame-to-model localization: reference rendering policy, backends, motion model (see
// localizer.hpp).
#include "vkloc/localizer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "vkloc/gpu.hpp"
#include "vkloc/gpu_edges.hpp"

namespace vkloc {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

double rotationDeg(const Eigen::Matrix3d& R) { return logSO3(R).norm() * 180.0 / M_PI; }

bool finiteIn(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

/// Median of the positive depths of a render (metres); 0 when nothing is seen.
double medianDepth(const ImageF32& depth) {
  std::vector<float> values;
  values.reserve(depth.data.size() / 4 + 1);
  for (size_t i = 0; i < depth.data.size(); i += 4) {
    if (depth.data[i] > 0.0f) values.push_back(depth.data[i]);
  }
  if (values.empty()) return 0.0;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
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
  if (!finiteIn(o.max_point_motion_px, 0.0, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: max_point_motion_px must be in 0..1e6");
  }
  if (!finiteIn(o.kind_visibility_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: kind_visibility_ratio must be in 0..1");
  }
  if (o.init_refinements < 0 || o.init_refinements > 100) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: init_refinements must be in 0..100");
  }
  if (o.init_search_steps < 0 || o.init_search_steps > 10 || !finiteIn(o.init_search_deg, 0.0, 90.0) ||
      !finiteIn(o.init_confident_inlier_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need init_search_steps in 0..10, init_search_deg in 0..90 and "
                     "init_confident_inlier_ratio in 0..1");
  }
  if (r.max_frames < 1) return makeError(ErrorCode::kInvalidArgument, "Localizer: rerender.max_frames must be >= 1");
  const InertialAiding& ia = o.inertial;
  if (!isValidPose(ia.T_body_camera)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: inertial.T_body_camera is not a finite rigid transform");
  }
  if (!finiteIn(ia.gate_depth_ratio, 0.0, 1e3) || !finiteIn(ia.gate_sigmas, 0.0, 1e3) ||
      !finiteIn(ia.gate_rotation_deg, 0.0, 180.0) || !finiteIn(ia.max_inertial_s, 0.0, 1e4)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need inertial.gate_depth_ratio and gate_sigmas in 0..1e3, gate_rotation_deg in "
                     "0..180 and max_inertial_s in 0..1e4");
  }
  VKLOC_TRY_STATUS(validateInertialOptions(ia.predictor));
  VKLOC_TRY_STATUS(validateRenderSettings(o.render));
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

}  // namespace

Result<LocalizerBackend> parseLocalizerBackend(const std::string& name) {
  if (name == "auto") return LocalizerBackend::kAuto;
  if (name == "vulkan") return LocalizerBackend::kVulkan;
  if (name == "cpu") return LocalizerBackend::kCpu;
  return makeError(ErrorCode::kInvalidArgument, fmt::format("backend '{}': expected auto, vulkan or cpu", name));
}

Result<RerenderPolicy> parseRerenderPolicy(const std::string& name) {
  if (name == "every-frame") return RerenderPolicy::kEveryFrame;
  if (name == "when-needed") return RerenderPolicy::kWhenNeeded;
  return makeError(ErrorCode::kInvalidArgument,
                   fmt::format("re-render policy '{}': expected every-frame or when-needed", name));
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

const char* rerenderPolicyName(RerenderPolicy policy) {
  return policy == RerenderPolicy::kEveryFrame ? "every-frame" : "when-needed";
}

struct Localizer::Impl {
  LocalizerOptions options;
  PinholeCamera camera;
  std::shared_ptr<GpuContext> context;
  Model model;  // kept only for the CPU reference renderer
  std::unique_ptr<GpuRenderer> renderer;
  std::unique_ptr<GpuEdgeStages> gpu_stages;
  bool live_on_gpu = false;
  bool calibration_pending = false;
  std::string renderer_name;
  std::string backend_reason;

  // Reference view.
  std::optional<EdgeReference> reference;
  double reference_depth_m = 0;  // median scene depth of the reference render
  int frames_on_reference = 0;

  // Edge kinds the live images show: running inlier ratio per kind [texture, occlusion, crease,
  // near background] (-1: not measured yet) and the kinds left out of references. A property of
  // the model and the camera, so reset() keeps it.
  std::array<double, 4> kind_inlier_mean{-1.0, -1.0, -1.0, -1.0};
  std::array<bool, 4> kind_dropped{false, false, false, false};

  // Motion state.
  std::optional<Pose> last_pose;  // last tracked (or reset) pose
  std::optional<Pose> prev_pose;  // the tracked pose before it
  int64_t last_pose_t_ns = 0;
  int64_t prev_pose_t_ns = 0;
  std::optional<int64_t> last_t_ns;  // last frame given to localize
  double last_inlier_ratio = 1.0;
  bool last_lost = false;
  bool gpu_frame_ready = false;                 // the current image is already processed on the device
  LiveFrame cpu_live;                           // CPU live stages of the current image; buffers reused per frame
  bool tracked_since_reset = false;             // a frame was tracked since create/reset
  InertialPredictor inertial;                   // accepted visual poses (body) and IMU readings
  Matrix6d last_covariance = Matrix6d::Zero();  // of the last accepted visual pose

  Result<RenderOutput> render(const Pose& T_world_camera) {
    RenderSettings settings = options.render;
    settings.outputs = kRenderAll;
    if (renderer) return renderer->render(camera, T_world_camera, settings);
    return renderReference(model, camera, T_world_camera, settings);
  }

  /// Renders and extracts a new reference at T_world_camera.
  Status makeReference(const Pose& T_world_camera, LocalizationResult& out) {
    auto t0 = Clock::now();
    Result<RenderOutput> view = render(T_world_camera);
    if (!view.ok()) return view.error();
    out.render_ms += msSince(t0);
    t0 = Clock::now();
    const double depth_m = medianDepth(view->depth);
    // The render's depth and normals are handed to the reference stage (no 5 MB copy).
    Result<EdgeReference> ref = buildEdgeReference(std::move(*view), camera, T_world_camera, options.reference);
    if (!ref.ok()) return ref.error();
    if (kind_dropped[1] || kind_dropped[2] || kind_dropped[3]) {
      auto dropped = [&](uint32_t kind) {
        if (kind & kEdgeBackground) return kind_dropped[3];
        return (kind_dropped[1] && kind == kEdgeOcclusion) || (kind_dropped[2] && kind == kEdgeCrease);
      };
      auto keep = [&](std::vector<EdgePoint>& points) {
        points.erase(std::remove_if(points.begin(), points.end(), [&](const EdgePoint& p) { return dropped(p.kind); }),
                     points.end());
      };
      keep(ref->points);
      for (std::vector<EdgePoint>& level : ref->coarse_points) keep(level);
    }
    out.reference_ms += msSince(t0);
    reference = std::move(*ref);
    if (gpu_stages) VKLOC_TRY_STATUS(gpu_stages->setLevelPoints(*reference));
    reference_depth_m = depth_m;
    frames_on_reference = 0;
    out.reference_rendered = true;
    return Status::success();
  }

  bool needsReference(const Pose& guess) const {
    if (!reference || reference->points.size() < 6) return true;
    if (options.policy == RerenderPolicy::kEveryFrame) return true;
    if (last_lost) return true;
    const RerenderThresholds& r = options.rerender;
    if (frames_on_reference >= r.max_frames) return true;
    if (last_inlier_ratio < r.min_inlier_ratio) return true;
    const Pose T_ref_camera = reference->T_world_ref.inverse() * guess;
    const double depth = reference_depth_m > 0 ? reference_depth_m : 1.0;
    if (T_ref_camera.translation().norm() > r.max_translation_depth_ratio * depth) return true;
    return rotationDeg(T_ref_camera.linear()) > r.max_rotation_deg;
  }

  Pose predict(int64_t t_ns) const {
    if (options.motion == MotionModel::kLastPose || !prev_pose || last_pose_t_ns <= prev_pose_t_ns) return *last_pose;
    // Constant velocity: the last inter-frame motion (body frame) scaled to the time step.
    const Vector6d xi = logSE3(prev_pose->inverse() * *last_pose);
    const double scale =
        static_cast<double>(t_ns - last_pose_t_ns) / static_cast<double>(last_pose_t_ns - prev_pose_t_ns);
    if (!std::isfinite(scale) || scale <= 0 || scale > 10) return *last_pose;
    return *last_pose * expSE3(scale * xi);
  }

  /// Updates the running inlier ratio per edge kind from a tracked frame and drops the geometric
  /// kinds the live images do not show (adapt_edge_kinds).
  void learnEdgeKinds(const TrackQuality& q) {
    if (!options.adapt_edge_kinds) return;
    constexpr int kMinPoints = 20;
    for (size_t k = 0; k < kind_inlier_mean.size(); ++k) {
      if (kind_dropped[k] || q.kind_points_in_image[k] < kMinPoints) continue;
      const double r = q.kind_inlier_ratio[k];
      kind_inlier_mean[k] = kind_inlier_mean[k] < 0 ? r : 0.7 * kind_inlier_mean[k] + 0.3 * r;
    }
    if (kind_inlier_mean[0] < 0) return;
    for (size_t k = 1; k < kind_inlier_mean.size(); ++k) {
      if (kind_inlier_mean[k] >= 0 && kind_inlier_mean[k] < options.kind_visibility_ratio * kind_inlier_mean[0]) {
        kind_dropped[k] = true;
      }
    }
  }

  /// The reference without the points that the predicted motion from the last tracked pose to
  /// `guess` moves more than max_point_motion_px in the image (finest level), or nullopt when
  /// none is dropped or too few would remain (motion blur smears those points' edges).
  std::optional<EdgeReference> slowPoints(const Pose& guess) const {
    if (!(options.max_point_motion_px > 0) || !last_pose || !tracked_since_reset) return std::nullopt;
    const Pose T_guess_ref = guess.inverse() * reference->T_world_ref;
    const Pose T_last_ref = last_pose->inverse() * reference->T_world_ref;
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
    out.camera = reference->camera;
    out.T_world_ref = reference->T_world_ref;
    size_t dropped = 0;
    auto filter = [&](const std::vector<EdgePoint>& in, std::vector<EdgePoint>& kept) {
      kept.reserve(in.size());
      for (const EdgePoint& p : in) {
        if (motionPx(p) <= options.max_point_motion_px) kept.push_back(p);
      }
      dropped += in.size() - kept.size();
      return 5 * kept.size() >= in.size() && kept.size() >= 100;
    };
    if (!filter(reference->points, out.points)) return std::nullopt;
    out.coarse_points.resize(reference->coarse_points.size());
    for (size_t k = 0; k < out.coarse_points.size(); ++k) {
      if (!filter(reference->coarse_points[k], out.coarse_points[k])) return std::nullopt;
    }
    if (dropped == 0) return std::nullopt;
    return out;
  }

  /// Live stages + alignment on the chosen backend.
  Result<TrackResult> align(const ImageU8& gray, const Pose& guess, bool gpu, LocalizationResult& out,
                            bool& cpu_live_ready) {
    if (reference->points.size() < 6) {
      // Nothing of the model is seen from the guess: a lost frame, not an error.
      TrackResult lost;
      lost.T_world_camera = guess;
      lost.T_camera_ref = guess.inverse() * reference->T_world_ref;
      return lost;
    }
    if (gpu) {
      auto t0 = Clock::now();
      if (!gpu_frame_ready) {
        VKLOC_TRY_STATUS(gpu_stages->processLiveImage(gray));
        gpu_frame_ready = true;
        out.live_ms += msSince(t0);
      }
      t0 = Clock::now();
      const std::optional<EdgeReference> slow = slowPoints(guess);
      GpuEdgeAlignment backend(*gpu_stages, slow ? nullptr : &*reference);
      Result<TrackResult> r = trackFrame(slow ? *slow : *reference, backend, guess, options.tracker);
      out.align_ms += msSince(t0);
      return r;
    }
    auto t0 = Clock::now();
    if (!cpu_live_ready) {
      // Built into the previous frame's buffers: a fresh LiveFrame per frame costs ~8 MB of
      // new pages at 640x480 (distance, gradient and edge lines of every level).
      LiveFrameOptions live = options.live;
      live.keep_intermediate = false;
      VKLOC_TRY_STATUS(buildLiveFrame(gray, camera, live, cpu_live));
      cpu_live_ready = true;
      out.live_ms += msSince(t0);
    }
    t0 = Clock::now();
    const std::optional<EdgeReference> slow = slowPoints(guess);
    Result<TrackResult> r = trackFrame(slow ? *slow : *reference, cpu_live, guess, options.tracker);
    out.align_ms += msSince(t0);
    return r;
  }

  /// First-frame calibration of kAuto with calibrate_backend: run both and keep the faster.
  Status calibrate(const ImageU8& gray, const Pose& guess) {
    calibration_pending = false;
    double best[2] = {0, 0};
    for (int gpu = 0; gpu < 2; ++gpu) {
      // Twice each: the first run includes shader compilation / allocation.
      for (int run = 0; run < 2; ++run) {
        LocalizationResult scratch;
        bool live_ready = false;
        gpu_frame_ready = false;
        Result<TrackResult> r = align(gray, guess, gpu == 1, scratch, live_ready);
        if (!r.ok()) return r.error();
        best[gpu] = scratch.live_ms + scratch.align_ms;
      }
    }
    live_on_gpu = best[1] < best[0];
    backend_reason = fmt::format("calibrated on the first frame: CPU {:.1f} ms, Vulkan {:.1f} ms", best[0], best[1]);
    return Status::success();
  }
};

Localizer::Localizer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Localizer::~Localizer() = default;

Result<std::unique_ptr<Localizer>> Localizer::create(const Model& model, const PinholeCamera& camera,
                                                     const LocalizerOptions& options,
                                                     std::shared_ptr<GpuContext> context) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateOptions(options));
  VKLOC_TRY_STATUS(validateModel(model));
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->inertial = InertialPredictor(options.inertial.predictor);
  // Pyramid levels nobody reads are not built: the tracker starts at coarsest_level and the
  // far-points-first hypothesis at far_first_coarsest_level (-1: the live frame's coarsest).
  const EdgeTrackerOptions& t = options.tracker;
  if (t.coarsest_level >= 0 && (t.far_first_depth_quantile <= 0 || t.far_first_coarsest_level >= 0)) {
    const int deepest = std::max(t.coarsest_level, t.far_first_depth_quantile > 0 ? t.far_first_coarsest_level : 0);
    impl->options.live.levels = std::min(options.live.levels, std::max(deepest, t.finest_level) + 1);
  }
  impl->options.reference.levels = impl->options.live.levels;
  impl->camera = camera;
  impl->context = context;
  if (context) {
    Result<std::unique_ptr<GpuRenderer>> renderer = GpuRenderer::create(context, model);
    if (!renderer.ok()) return renderer.error();
    impl->renderer = std::move(*renderer);
    impl->renderer_name = fmt::format("render on {} ({})", context->device().name, context->device().type);
  } else {
    impl->model = model;
    impl->renderer_name = "render on the CPU reference rasterizer (no Vulkan device)";
  }
  switch (options.backend) {
    case LocalizerBackend::kCpu:
      impl->backend_reason = "asked for";
      break;
    case LocalizerBackend::kVulkan:
      if (!context) {
        return makeError(ErrorCode::kNoDevice, "Localizer: backend vulkan needs a Vulkan device (none given)");
      }
      impl->live_on_gpu = true;
      impl->backend_reason = "asked for";
      break;
    case LocalizerBackend::kAuto:
      if (!context) {
        impl->backend_reason = "no Vulkan device";
      } else if (options.calibrate_backend) {
        impl->calibration_pending = true;
        impl->backend_reason = "to be calibrated on the first frame";
      } else if (context->device().type == "cpu") {
        impl->backend_reason = "the Vulkan device is a CPU driver, where OpenCV is several times faster";
      } else {
        impl->live_on_gpu = true;
        impl->backend_reason = fmt::format("the Vulkan device is a {} GPU", context->device().type);
      }
      break;
  }
  if (context && (impl->live_on_gpu || impl->calibration_pending)) {
    LiveFrameOptions live = impl->options.live;
    live.keep_intermediate = false;
    Result<std::unique_ptr<GpuEdgeStages>> stages = GpuEdgeStages::create(context, camera, live);
    if (!stages.ok()) return stages.error();
    impl->gpu_stages = std::move(*stages);
  }
  return std::unique_ptr<Localizer>(new Localizer(std::move(impl)));
}

void Localizer::reset(const Pose& T_world_camera) {
  Impl& m = *impl_;
  m.reference.reset();
  m.prev_pose.reset();
  m.last_pose.reset();
  m.last_t_ns.reset();
  m.last_inlier_ratio = 1.0;
  m.last_lost = false;
  m.tracked_since_reset = false;
  m.inertial.reset();  // timestamps may start over
  if (isValidPose(T_world_camera)) m.last_pose = T_world_camera;
}

Status Localizer::addImu(const ImuSample& sample) { return impl_->inertial.addImu(sample); }

std::string Localizer::backendSummary() const {
  const Impl& m = *impl_;
  const char* where = m.calibration_pending ? "auto (not yet calibrated)" : (m.live_on_gpu ? "Vulkan" : "CPU");
  std::string policy = rerenderPolicyName(m.options.policy);
  if (m.options.policy == RerenderPolicy::kWhenNeeded) {
    const RerenderThresholds& r = m.options.rerender;
    policy += fmt::format(" (moved > {:g} x depth or > {:g} deg, inliers < {:g}, or {} frames)",
                          r.max_translation_depth_ratio, r.max_rotation_deg, r.min_inlier_ratio, r.max_frames);
  }
  return fmt::format("{}; live edges + alignment on {} ({}); re-render {}", m.renderer_name, where, m.backend_reason,
                     policy);
}

Result<LocalizationResult> Localizer::localize(int64_t t_ns, const ImageU8& gray,
                                               const std::optional<Pose>& T_world_camera_guess) {
  const auto t_start = Clock::now();
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
  if (!T_world_camera_guess && !m.last_pose) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: no pose guess and no previous pose; call reset() first");
  }
  // Inertial prediction (when readings are given and enough visual poses were accepted).
  const InertialAiding& aiding = m.options.inertial;
  std::optional<InertialPrediction> inertial;
  std::optional<Pose> T_world_camera_inertial;
  if (aiding.enabled && m.inertial.hasImu()) inertial = m.inertial.predict(t_ns);
  if (inertial && inertial->since_fix_s > aiding.max_inertial_s) inertial.reset();
  if (inertial) T_world_camera_inertial = inertial->T_world_body * aiding.T_body_camera;
  const Pose guess = T_world_camera_guess      ? *T_world_camera_guess
                     : T_world_camera_inertial ? *T_world_camera_inertial
                                               : m.predict(t_ns);

  LocalizationResult out;
  out.t_ns = t_ns;
  out.T_world_camera = guess;
  if (m.needsReference(guess)) VKLOC_TRY_STATUS(m.makeReference(guess, out));
  if (m.calibration_pending) VKLOC_TRY_STATUS(m.calibrate(gray, guess));

  bool cpu_live_ready = false;  // the CPU live stages ran on this image (m.cpu_live)
  m.gpu_frame_ready = false;
  Result<TrackResult> track = m.align(gray, guess, m.live_on_gpu, out, cpu_live_ready);
  if (!track.ok()) return track.error();
  if (track->state == TrackingState::kLost && !out.reference_rendered && m.options.retry_lost_with_fresh_reference) {
    VKLOC_TRY_STATUS(m.makeReference(guess, out));
    Result<TrackResult> retry = m.align(gray, guess, m.live_on_gpu, out, cpu_live_ready);
    if (!retry.ok()) return retry.error();
    track = std::move(retry);
  }
  // Initialization (no frame tracked since reset) with a result that is not clearly right: the
  // alignment also starts from the guess turned about the camera's x and y axes on a grid
  // (init_search_deg steps); the best result wins (tracking over lost, then the inlier ratio).
  if (!m.tracked_since_reset && m.options.init_search_steps > 0 &&
      !(track->state == TrackingState::kTracking &&
        track->quality.inlier_ratio >= m.options.init_confident_inlier_ratio)) {
    const int n = m.options.init_search_steps;
    const double step_rad = m.options.init_search_deg * M_PI / 180.0;
    auto better = [](const TrackResult& a, const TrackResult& b) {
      const bool a_tracking = a.state == TrackingState::kTracking;
      const bool b_tracking = b.state == TrackingState::kTracking;
      if (a_tracking != b_tracking) return a_tracking;
      return a.quality.inlier_ratio > b.quality.inlier_ratio;
    };
    for (int i = -n; i <= n; ++i) {
      for (int j = -n; j <= n; ++j) {
        if (i == 0 && j == 0) continue;
        Pose start = guess;
        start.linear() = guess.linear() * expSO3(Eigen::Vector3d(i * step_rad, j * step_rad, 0.0));
        Result<TrackResult> candidate = m.align(gray, start, m.live_on_gpu, out, cpu_live_ready);
        if (!candidate.ok()) return candidate.error();
        if (better(*candidate, *track)) track = std::move(candidate);
      }
    }
  }
  // Initialization: a guess far off converges in steps, each rendering a fresh reference at the
  // last estimate.
  for (int step = 0; step < m.options.init_refinements && !m.tracked_since_reset &&
                     track->state == TrackingState::kLost && isValidPose(track->T_world_camera);
       ++step) {
    VKLOC_TRY_STATUS(m.makeReference(track->T_world_camera, out));
    Result<TrackResult> again = m.align(gray, track->T_world_camera, m.live_on_gpu, out, cpu_live_ready);
    if (!again.ok()) return again.error();
    track = std::move(again);
  }
  m.last_t_ns = t_ns;
  ++m.frames_on_reference;
  out.quality = track->quality;
  out.state = track->state;
  out.T_world_camera = track->T_world_camera;
  out.covariance = track->covariance;
  out.reference_points = static_cast<int>(m.reference->points.size());
  out.scene_depth_m = m.reference_depth_m;
  if (inertial) {
    out.inertial_sigma_m = inertial->sigma_m;
    if (track->state == TrackingState::kTracking) {
      // Consistency gate: the visual pose must agree with the IMU-propagated one.
      const Pose d = T_world_camera_inertial->inverse() * track->T_world_camera;
      const double depth = m.reference_depth_m > 0 ? m.reference_depth_m : 1.0;
      const double gate_m =
          aiding.gate_depth_ratio * depth + aiding.gate_sigmas * std::hypot(inertial->sigma_m, inertial->fit_rms_m);
      out.visual_rejected = d.translation().norm() > gate_m || rotationDeg(d.linear()) > aiding.gate_rotation_deg;
    }
  }
  if (track->state == TrackingState::kTracking && !out.visual_rejected) {
    m.inertial.addFix(t_ns, track->T_world_camera * aiding.T_body_camera.inverse());
    m.last_covariance = track->covariance;
    m.prev_pose = m.last_pose;
    m.prev_pose_t_ns = m.last_pose_t_ns;
    m.last_pose = track->T_world_camera;
    m.last_pose_t_ns = t_ns;
    m.last_inlier_ratio = track->quality.inlier_ratio;
    m.learnEdgeKinds(track->quality);
    m.last_lost = false;
    m.tracked_since_reset = true;
  } else {
    // Keep the last trusted pose and its motion: the next guess extrapolates the last tracked
    // velocity over the time since (predict() scales it by at most 10 frame intervals), so a
    // camera that keeps moving through a few untrackable frames is found again; with the IMU
    // the inertial prediction is reported and is the next guess.
    if (!m.last_pose) m.last_pose = guess;
    m.last_lost = true;
    if (inertial) {
      out.state = TrackingState::kInertial;
      out.T_world_camera = *T_world_camera_inertial;
      // The inertial pose carries the motion on: should the prediction expire (max_inertial_s),
      // the constant-velocity guess continues from it, not from the last visual pose.
      m.prev_pose = m.last_pose;
      m.prev_pose_t_ns = m.last_pose_t_ns;
      m.last_pose = *T_world_camera_inertial;
      m.last_pose_t_ns = t_ns;
      // The last accepted frame's rotation uncertainty (gyro drift over max_inertial_s is far
      // below it), the prediction's in translation.
      out.covariance = Matrix6d::Zero();
      out.covariance.bottomRightCorner<3, 3>() = m.last_covariance.bottomRightCorner<3, 3>();
      out.covariance.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * (inertial->sigma_m * inertial->sigma_m);
    } else {
      out.state = TrackingState::kLost;
    }
  }
  out.total_ms = msSince(t_start);
  return out;
}

}  // namespace vkloc
