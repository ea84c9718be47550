#include "common.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "vkloc/core/image.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/io/calibration.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::cli {

bool isDemoModel(const std::string& name) { return name == "city" || name == "room"; }

void ModelArgs::add(CLI::App& app) {
  app.add_option("--model,-m", model, "Model file (.obj .ply .gltf .glb .drc ...) or built-in: city, room")
      ->capture_default_str();
  app.add_option("--unit-scale", unit_scale, "Metres per model unit")->capture_default_str();
  app.add_option("--model-pose", T_world_model, "T_world_model: 'tx ty tz qx qy qz qw' or 16 numbers (row-major 4x4)");
  app.add_option("--block-triangles", block_triangles, "Target triangles per spatial block (0 = one block)")
      ->capture_default_str();
}

Model ModelArgs::load() const {
  if (isDemoModel(model) && !std::filesystem::exists(model)) {
    Model m = take(makeDemoModel(model));
    if (block_triangles != 32768) buildBlocks(m, block_triangles);
    return m;
  }
  ModelLoadOptions options;
  options.unit_scale = unit_scale;
  options.max_block_triangles = block_triangles;
  if (!T_world_model.empty()) {
    const Pose T = take(parsePose(T_world_model));
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) options.T_world_model[r * 4 + c] = T.matrix()(r, c);
    }
  }
  std::vector<std::string> warnings;
  Model m = take(loadModel(model, options, &warnings));
  for (const auto& w : warnings) std::fprintf(stderr, "vkloc: warning: %s\n", w.c_str());
  return m;
}

void CameraArgs::add(CLI::App& app) {
  app.add_option("--camera,-c", file,
                 "Calibration file: vkloc camera.yaml, Kalibr camchain, EuRoC sensor.yaml, OpenCV, ROS camera_info, "
                 "CamOdoCal, COLMAP cameras.txt, or flat fx fy cx cy width height (without a mounting, the "
                 "sequence's T_body_camera stays)");
  app.add_option("--camera-name", select, "Camera of a multi-camera file (Kalibr cam1, COLMAP id): name or index");
  app.add_option("--intrinsics", intrinsics,
                 "Inline camera 'fx,fy,cx,cy,width,height' (default 525,525,319.5,239.5,640,480)");
}

namespace {

PinholeCamera inlineIntrinsics(const std::string& intrinsics) {
  PinholeCamera cam;
  if (!intrinsics.empty()) {
    const std::vector<double> v = take(parseNumbers(intrinsics, "--intrinsics (fx,fy,cx,cy,width,height)", 6));
    for (int k = 4; k < 6; ++k) {
      if (!(v[k] >= 1 && v[k] <= 16384) || v[k] != std::floor(v[k])) {
        throw Failure{fmt::format("--intrinsics: image {} must be a whole number of pixels in 1..16384, got {}",
                                  k == 4 ? "width" : "height", v[k])};
      }
    }
    cam = PinholeCamera{v[0], v[1], v[2], v[3], static_cast<int>(v[4]), static_cast<int>(v[5])};
  }
  check(validateCamera(cam));
  return cam;
}

}  // namespace

SequenceCamera CameraArgs::getFull(const SequenceCamera& fallback) const {
  if (!file.empty() && !intrinsics.empty()) throw Failure{"give either --camera or --intrinsics, not both"};
  if (!file.empty()) {
    SequenceCamera camera = take(loadCalibration(file, select));
    // Most calibration formats carry no camera-to-IMU mounting (read as the identity): the
    // sequence's stays.
    if (camera.T_body_camera.isApprox(Pose::Identity(), 1e-12)) camera.T_body_camera = fallback.T_body_camera;
    return camera;
  }
  if (!select.empty()) throw Failure{"--camera-name needs --camera"};
  SequenceCamera camera = fallback;
  if (!intrinsics.empty()) {
    camera = SequenceCamera{};
    camera.T_body_camera = fallback.T_body_camera;
    camera.intrinsics = inlineIntrinsics(intrinsics);
  }
  return camera;
}

PinholeCamera CameraArgs::get() const {
  if (!file.empty()) {
    const SequenceCamera full = getFull(SequenceCamera{});
    const LensCamera lens = take(lensCamera(full));
    if (!lens.isIdealPinhole()) {
      throw Failure{fmt::format("{}: a {} lens{}; this verb takes an ideal pinhole camera", file, full.model,
                                full.model == "pinhole" ? " with distortion" : "")};
    }
    return full.intrinsics;
  }
  return getFull(SequenceCamera{}).intrinsics;
}

void ViewArgs::add(CLI::App& app) {
  app.add_option("--view", view,
                 "Tracker view of a lens image: undistorted (fixed to the lens) | stabilised (EIS: roll and pitch "
                 "compensated beyond --view-dead-band, axis --view-pitch below the horizon)")
      ->check(CLI::IsMember({"undistorted", "stabilised", "stabilized"}))
      ->capture_default_str();
  app.add_option("--view-interpolation", interpolation, "Sampling of the lens image: bicubic | bilinear")
      ->check(CLI::IsMember({"bilinear", "bicubic"}))
      ->capture_default_str();
  app.add_option("--view-size", size, "View size 'WxH', pixels (default: the lens image's)");
  app.add_option("--view-hfov", hfov_deg,
                 "View's horizontal field of view, degrees (default: a pinhole lens's own focal length, so a smaller "
                 "--view-size is a central crop; else 90)");
  app.add_option("--view-pitch", pitch_deg, "Stabilised view: axis angle below the horizon, degrees (90 = down)")
      ->capture_default_str();
  app.add_option("--view-dead-band", dead_band_deg,
                 "Stabilised view: fixed to the lens while the compensation is at most this angle, degrees, and "
                 "turned by the excess beyond (0 = every frame fully compensated)")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  app.add_option("--view-flat-field", flat_field_sigma_px,
                 "Divide the view by its local mean brightness (Gaussian sigma, view pixels; 0 = off): evens out "
                 "vignetting before the edge thresholds")
      ->check(CLI::Range(0.0, 1e4))
      ->capture_default_str();
}

ViewOptions ViewArgs::options(const Sequence& seq) const {
  ViewOptions o;
  o.kind = take(parseViewKind(view));
  if (!size.empty()) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(size.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X') || w < 1 || h < 1) {
      throw Failure{fmt::format("--view-size '{}': expected WxH, e.g. 640x480", size)};
    }
    o.width = w;
    o.height = h;
  }
  o.hfov_deg = hfov_deg;
  o.pitch_deg = pitch_deg;
  o.dead_band_deg = dead_band_deg;
  o.flat_field_sigma_px = flat_field_sigma_px;
  o.interpolation = interpolation == "bicubic" ? RemapInterpolation::kBicubic : RemapInterpolation::kBilinear;
  if (seq.gravity_world.norm() > 0) o.up_world = -seq.gravity_world.normalized();
  return o;
}

SequenceView sequenceView(const SequenceCamera& camera, const ViewOptions& options) {
  SequenceView out;
  out.front = take(CameraFront::create(take(lensCamera(camera)), options));
  out.camera = out.front->view();
  if (out.front->identity()) out.front.reset();  // the images are the view already
  return out;
}

void LocalizerArgs::add(CLI::App& app) {
  app.add_option("--filter", filter, "Inertial fusion: ekf (error-state EKF) | window (velocity fit over fixes)")
      ->check(CLI::IsMember({"ekf", "window"}))
      ->capture_default_str();
  app.add_option("--max-search-level", max_search_level,
                 "Deepest pyramid level the filter's uncertainty may start an alignment at (0 = off)")
      ->check(CLI::Range(0, 7))
      ->capture_default_str();
  app.add_option("--visual-covariance-scale", visual_covariance_scale,
                 "Factor on the alignment's covariance in the filter (its calibration)")
      ->check(CLI::Range(1e-3, 1e6))
      ->capture_default_str();
  app.add_option("--frame-pose", frame_pose,
                 "Pose of a tracked frame: filter (the EKF's estimate after taking the alignment) | visual (the "
                 "alignment's own)")
      ->check(CLI::IsMember({"filter", "visual"}))
      ->capture_default_str();
  app.add_option("--rotation-prior", rotation_prior,
                 "Attitude prior of the alignment: filter (the EKF's predicted attitude, where it predicts from the "
                 "IMU) | off")
      ->check(CLI::IsMember({"filter", "off"}))
      ->capture_default_str();
  app.add_option("--rotation-prior-scale", rotation_prior_scale,
                 "Factor on the filter's rotation covariance in the alignment's attitude prior")
      ->check(CLI::Range(1e-3, 1e6))
      ->capture_default_str();
  app.add_option("--local-search", local_search,
                 "Without a keyframe database, after a loss: search keyframes rendered around the last tracked "
                 "pose (on | off)")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_option("--keyframe-edge-floor", keyframe_edge_floor,
                 "Least gradient of a keyframe render's texture edge, gray levels per pixel (Sobel / 8): fainter "
                 "texture a camera image does not show above its noise")
      ->check(CLI::Range(0.0, 255.0))
      ->capture_default_str();
  app.add_option("--backend", backend, "Live edges + alignment: auto | vulkan | cpu")
      ->check(CLI::IsMember({"auto", "vulkan", "cpu"}))
      ->capture_default_str();
  app.add_option("--policy", policy, "Keyframe re-rendering: every-frame | when-needed")
      ->check(CLI::IsMember({"every-frame", "when-needed"}))
      ->capture_default_str();
  app.add_option("--keyframes", keyframes,
                 "Where keyframes are made: worker (a thread beside tracking) | sync (deterministic)")
      ->check(CLI::IsMember({"worker", "sync"}))
      ->capture_default_str();
}

void LocalizerArgs::apply(LocalizerOptions& options) const {
  options.backend = take(parseLocalizerBackend(backend));
  options.policy = take(parseRerenderPolicy(policy));
  options.keyframe_threading = take(parseKeyframeThreading(keyframes));
  options.inertial.filter = filter == "window" ? InertialFilter::kWindowFit : InertialFilter::kEkf;
  options.max_search_level = max_search_level;
  options.inertial.ekf.measurement_covariance_scale = visual_covariance_scale;
  options.report_filtered_pose = frame_pose == "filter";
  options.rotation_prior_from_filter = rotation_prior == "filter";
  options.rotation_prior_covariance_scale = rotation_prior_scale;
  if (local_search == "off") options.relocalization.local_headings = 0;
  options.reference.detector.min_high_gradient = keyframe_edge_floor;
}

std::vector<std::string> LocalizerArgs::arguments() const {
  return {"--backend",
          backend,
          "--policy",
          policy,
          "--keyframes",
          keyframes,
          "--filter",
          filter,
          "--max-search-level",
          std::to_string(max_search_level),
          "--visual-covariance-scale",
          fmt::format("{:g}", visual_covariance_scale),
          "--frame-pose",
          frame_pose,
          "--rotation-prior",
          rotation_prior,
          "--rotation-prior-scale",
          fmt::format("{:g}", rotation_prior_scale),
          "--local-search",
          local_search,
          "--keyframe-edge-floor",
          fmt::format("{:g}", keyframe_edge_floor)};
}

void DeviceArgs::add(CLI::App& app) {
  app.add_option("--device,-d", device, "Vulkan device: index or part of its name (default: best; env VKLOC_DEVICE)");
}

std::shared_ptr<GpuContext> DeviceArgs::create() const {
  GpuOptions options;
  // The tool reads the environment; the library does not.
  options.device = device;
  if (options.device.empty()) {
    if (const char* env = std::getenv("VKLOC_DEVICE"); env) options.device = env;
  }
  if (const char* env = std::getenv("VKLOC_VALIDATION"); env && *env) options.validation = std::strcmp(env, "0") != 0;
  options.on_validation_message = [](const std::string& m) {
    std::fprintf(stderr, "vkloc: Vulkan validation: %s\n", m.c_str());
  };
  options.on_warning = [](const std::string& m) { std::fprintf(stderr, "vkloc: warning: %s\n", m.c_str()); };
  // lavapipe allocates and frees multi-megabyte buffers per draw: a whole-process allocator
  // setting the tool owns (GpuOptions::tune_allocator).
  options.tune_allocator = true;
  return take(GpuContext::create(options));
}

std::vector<std::string> writeRender(const std::string& dir, const std::string& stem, const RenderOutput& out) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Failure{fmt::format("{}: cannot create output directory: {}", dir, ec.message())};
  std::vector<std::string> paths;
  auto path = [&](const char* suffix) { return (std::filesystem::path(dir) / (stem + suffix)).string(); };
  paths.push_back(path("_rgba.png"));
  check(writePng(paths.back(), out.rgba));
  paths.push_back(path("_gray.png"));
  check(writePng(paths.back(), out.gray));
  paths.push_back(path("_depth_mm.png"));
  check(writePng(paths.back(), depthToMillimetres(out.depth)));
  paths.push_back(path("_depth.tiff"));
  check(writeFloatTiff(paths.back(), out.depth));
  if (!out.normals.empty()) {
    ImageU8 n(out.normals.width, out.normals.height, 3);
    for (size_t i = 0; i < n.data.size(); ++i) {
      n.data[i] = static_cast<uint8_t>(std::lround(127.5f + 127.5f * out.normals.data[i]));
    }
    paths.push_back(path("_normals.png"));
    check(writePng(paths.back(), n));
  }
  if (!out.back_faces.empty()) {
    paths.push_back(path("_back_faces.png"));
    check(writePng(paths.back(), out.back_faces));
  }
  return paths;
}

std::vector<Verb>& verbRegistry() {
  static std::vector<Verb> verbs;
  return verbs;
}

Model loadSequenceModel(const Sequence& seq) {
  const std::string path = seq.modelPath();
  if (path.empty()) throw Failure{fmt::format("{}: the sequence names no model", seq.directory)};
  std::array<double, 16> T{};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T[r * 4 + c] = seq.T_world_model.matrix()(r, c);
  }
  if (isDemoModel(path) && !std::filesystem::exists(path)) {
    Model m = take(makeDemoModel(path));
    if (!seq.T_world_model.isApprox(Pose::Identity()) || seq.unit_scale != 1.0) {
      transformModel(m, T, seq.unit_scale);
      buildBlocks(m, 32768);
    }
    return m;
  }
  ModelLoadOptions options;
  options.T_world_model = T;
  options.unit_scale = seq.unit_scale;
  std::vector<std::string> warnings;
  Model m = take(loadModel(path, options, &warnings));
  for (const auto& w : warnings) std::fprintf(stderr, "vkloc: warning: %s\n", w.c_str());
  return m;
}

std::optional<Pose> sequenceStartPose(const Sequence& seq, size_t start_frame) {
  if (start_frame > 0) {
    if (start_frame >= seq.images.size()) return std::nullopt;
    const int64_t t = seq.images[start_frame].t_ns;
    auto near = std::min_element(seq.groundtruth.begin(), seq.groundtruth.end(), [&](const auto& a, const auto& b) {
      return std::llabs(a.t_ns - t) < std::llabs(b.t_ns - t);
    });
    if (near == seq.groundtruth.end() || std::llabs(near->t_ns - t) > 1000000) return std::nullopt;
    return near->T_world_camera;
  }
  if (seq.initial_T_world_camera) return *seq.initial_T_world_camera;
  if (!seq.groundtruth.empty() && !seq.images.empty() &&
      std::llabs(seq.groundtruth.front().t_ns - seq.images.front().t_ns) < 10000000) {
    return seq.groundtruth.front().T_world_camera;
  }
  return std::nullopt;
}

Pose initialPose(const Sequence& seq, const std::string& offset, size_t start_frame) {
  const std::optional<Pose> start = sequenceStartPose(seq, start_frame);
  if (!start) {
    const std::string hint = "; give one, or pass --db DB (vkloc keyframes build) to search for the first pose";
    if (start_frame > 0) {
      throw Failure{fmt::format("{}: --start-frame {}: no ground-truth pose within 1 ms of that image{}", seq.directory,
                                start_frame, hint)};
    }
    throw Failure{fmt::format("{}: no initial_T_world_camera in sequence.yaml and no ground truth at the first image{}",
                              seq.directory, hint)};
  }
  Pose T = *start;
  if (!offset.empty()) {
    const auto v = take(parseNumbers(offset, "--init-offset (dx,dy,dz metres, rx,ry,rz degrees)", 6));
    for (int k = 0; k < 6; ++k) {
      const double limit = k < 3 ? 1e6 : 360.0;
      if (!(std::abs(v[k]) <= limit)) {
        static const char* const kNames[6] = {"dx", "dy", "dz", "rx", "ry", "rz"};
        throw Failure{
            fmt::format("--init-offset: {} = {} is outside +-{:g} {}", kNames[k], v[k], limit, k < 3 ? "m" : "deg")};
      }
    }
    Pose dR = Pose::Identity();
    dR.linear() = expSO3(Eigen::Vector3d(v[3], v[4], v[5]) * M_PI / 180.0);
    T = T * dR;
    T.translation() += Eigen::Vector3d(v[0], v[1], v[2]);
  }
  return T;
}

void setSequenceInertial(const Sequence& seq, bool use_imu, LocalizerOptions& options) {
  options.inertial.enabled = use_imu && !seq.imu.empty();
  options.inertial.T_body_camera = seq.camera.T_body_camera;
  options.inertial.predictor.gravity_world = seq.gravity_world;
  if (seq.imu_noise) options.inertial.ekf.imu_noise = *seq.imu_noise;
}

size_t feedSequenceImu(const Sequence& seq, size_t next, int64_t t_ns, Localizer& localizer) {
  for (; next < seq.imu.size() && seq.imu[next].t_ns <= t_ns; ++next) {
    const Status st = localizer.addImu(seq.imu[next]);
    if (!st.ok()) std::fprintf(stderr, "warning: imu.csv reading %zu: %s\n", next, st.error().message.c_str());
  }
  return next;
}

SearchRegion priorSearchRegion(const Eigen::Vector3d& center_world, double sigma_m, double min_radius_m) {
  SearchRegion region;
  region.center_world = center_world;
  region.radius_m = std::max(3.37 * sigma_m, min_radius_m);
  return region;
}

PinholeCamera sequenceCamera(const Sequence& seq) {
  const LensCamera lens = take(lensCamera(seq.camera));
  if (!lens.isIdealPinhole()) {
    throw Failure{
        fmt::format("{}/camera.yaml: a {} lens{}: this verb takes pinhole images; vkloc track tracks it "
                    "through an undistorted or stabilised view (--view)",
                    seq.directory, seq.camera.model, seq.camera.model == "pinhole" ? " with distortion" : "")};
  }
  return seq.camera.intrinsics;
}

std::optional<Pose> groundTruthAt(const std::vector<StampedPose>& gt, int64_t t_ns) {
  if (gt.empty()) return std::nullopt;
  const auto after =
      std::lower_bound(gt.begin(), gt.end(), t_ns, [](const StampedPose& p, int64_t t) { return p.t_ns < t; });
  if (after != gt.end() && after->t_ns == t_ns) return after->T_world_camera;
  if (after != gt.begin() && after != gt.end()) {
    const StampedPose& a = *(after - 1);
    const StampedPose& b = *after;
    if (b.t_ns - a.t_ns <= 50'000'000) {
      const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
      Pose T = Pose::Identity();
      const Eigen::Quaterniond qa(a.T_world_camera.linear()), qb(b.T_world_camera.linear());
      T.linear() = qa.slerp(s, qb).toRotationMatrix();
      T.translation() = (1 - s) * a.T_world_camera.translation() + s * b.T_world_camera.translation();
      return T;
    }
  }
  const StampedPose* nearest = nullptr;
  if (after != gt.end()) nearest = &*after;
  if (after != gt.begin() && (nearest == nullptr || t_ns - (after - 1)->t_ns < nearest->t_ns - t_ns)) {
    nearest = &*(after - 1);
  }
  if (nearest != nullptr && std::abs(nearest->t_ns - t_ns) <= 10'000'000) return nearest->T_world_camera;
  return std::nullopt;
}

}  // namespace vkloc::cli
