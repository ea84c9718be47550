// Simulated sequences: trajectory, sensors, rendered camera images and the damaged model,
// written as a sequence folder.
#include "vkloc/sim/simulate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/threads.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Writes bytes to `path` atomically.
Status writeBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  return writeFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

Status writeJpeg(const std::string& path, const ImageU8& rgb, int quality) {
  cv::Mat bgr(rgb.height, rgb.width, CV_8UC3);
  for (int y = 0; y < rgb.height; ++y) {
    auto* row = bgr.ptr<uint8_t>(y);
    for (int x = 0; x < rgb.width; ++x) {
      row[3 * x + 0] = rgb.at(x, y, 2);
      row[3 * x + 1] = rgb.at(x, y, 1);
      row[3 * x + 2] = rgb.at(x, y, 0);
    }
  }
  std::vector<uint8_t> bytes;
  bool ok = false;
  try {
    ok = cv::imencode(".jpg", bgr, bytes, {cv::IMWRITE_JPEG_QUALITY, quality});
  } catch (const cv::Exception& e) {
    return makeError(ErrorCode::kIoError, fmt::format("{}: JPEG encoding failed: {}", path, e.what()));
  }
  if (!ok) return makeError(ErrorCode::kIoError, path + ": JPEG encoding failed");
  return writeBytes(path, bytes);
}

Status validateOptions(const SimulationOptions& o) {
  auto bad = [](const std::string& what) { return makeError(ErrorCode::kInvalidArgument, "simulate: " + what); };
  if (!(o.duration_s > 0.0 && o.duration_s < 1e6)) return bad(fmt::format("duration {} s must be > 0", o.duration_s));
  if (!(o.rate_hz > 0.0 && o.rate_hz <= 10000.0))
    return bad(fmt::format("rate {} Hz is outside (0, 10000]", o.rate_hz));
  const AppearanceOptions& a = o.appearance;
  if (a.motion_blur_subframes < 1 || a.motion_blur_subframes > 64)
    return bad(fmt::format("motion blur sub-frames {} is outside 1..64", a.motion_blur_subframes));
  if (a.supersampling < 1 || a.supersampling > 4)
    return bad(fmt::format("supersampling {} is outside 1..4", a.supersampling));
  if (!(a.exposure_time_s >= 0.0 && a.exposure_time_s <= 1.0))
    return bad(fmt::format("exposure time {} s is outside 0..1", a.exposure_time_s));
  if (!(a.gamma >= 0.1 && a.gamma <= 10.0)) return bad(fmt::format("gamma {} is outside 0.1..10", a.gamma));
  if (!(a.vignetting >= 0.0 && a.vignetting <= 1.0))
    return bad(fmt::format("vignetting {} is outside 0..1", a.vignetting));
  if (!(a.shot_noise >= 0.0 && a.read_noise >= 0.0 && a.shot_noise < 10 && a.read_noise < 10))
    return bad("noise sigmas must be in 0..10");
  if (!std::isfinite(a.exposure_ev) || std::abs(a.exposure_ev) > 20 || !std::isfinite(a.exposure_drift_ev) ||
      !(a.exposure_drift_period_s > 0))
    return bad("exposure values must be finite (|ev| <= 20) and the drift period > 0");
  for (double w : a.white_balance) {
    if (!(w > 0.0 && w < 100.0)) return bad(fmt::format("white balance gain {} is outside (0, 100)", w));
  }
  if (!(a.color_jitter_gain >= 0.0 && a.color_jitter_gain < 1.0 && a.color_jitter_offset >= 0.0 &&
        a.color_jitter_offset < 1.0))
    return bad("colour jitter gain and offset must be in [0, 1)");
  if (o.jpeg && (o.jpeg_quality < 1 || o.jpeg_quality > 100))
    return bad(fmt::format("JPEG quality {} is outside 1..100", o.jpeg_quality));
  if (Result<LensCamera> lens = lensCamera(o.camera); !lens.ok()) return bad(lens.error().message);
  if (!isValidPose(o.camera.T_body_camera)) return bad("T_body_camera is not a valid rigid transform");
  const DamageOptions& d = o.damage;
  if (!(d.simplify_ratio > 0.0 && d.simplify_ratio <= 1.0))
    return bad(fmt::format("simplify ratio {} is outside (0, 1]", d.simplify_ratio));
  if (!(d.hole_fraction >= 0.0 && d.hole_fraction <= 0.9))
    return bad(fmt::format("hole fraction {} is outside 0..0.9", d.hole_fraction));
  if (o.render_threads < 0 || o.render_threads > 64)
    return bad(fmt::format("render threads {} are outside 0..64", o.render_threads));
  RenderSettings s;
  s.near_m = o.near_m;
  s.far_m = o.far_m;
  return validateRenderSettings(s);
}

}  // namespace

Pose defaultBodyCamera(TrajectoryKind kind) {
  // Body: x forward, y left, z up. Columns of R_body_camera are the camera axes in the body.
  Pose T = Pose::Identity();
  Eigen::Matrix3d R;
  if (isDroneKind(kind)) {
    const double c = std::cos(kPi / 4), s = std::sin(kPi / 4);
    // Camera z = forward and 45 deg down, x = right (-y), y = z x x (down and back).
    R.col(2) = Eigen::Vector3d(c, 0, -s);
    R.col(0) = Eigen::Vector3d(0, -1, 0);
    R.col(1) = R.col(2).cross(R.col(0));
    T.translation() = Eigen::Vector3d(0.10, 0.0, -0.05);
  } else {
    R.col(2) = Eigen::Vector3d(1, 0, 0);
    R.col(0) = Eigen::Vector3d(0, -1, 0);
    R.col(1) = R.col(2).cross(R.col(0));
    T.translation() = Eigen::Vector3d(0.05, 0.02, 0.0);
  }
  T.linear() = R;
  return T;
}

Result<SequenceCamera> scenarioCamera(const std::string& lens, TrajectoryKind kind) {
  SequenceCamera camera;
  camera.T_body_camera = defaultBodyCamera(kind);
  camera.intrinsics = PinholeCamera{500.0, 500.0, 319.5, 239.5, 640, 480};
  if (lens == "pinhole") return camera;
  if (lens == "radtan") {
    camera.distortion = {-0.28, 0.074, 2e-4, 1.8e-5, 0.0};
    return camera;
  }
  if (lens == "fisheye") {
    camera.model = "kannala_brandt";
    camera.intrinsics = PinholeCamera{200.0, 200.0, 399.5, 399.5, 800, 800};
    camera.distortion = {0.02, -0.005, 0.001, -0.0001};
    camera.max_angle_deg = 105.0;
    return camera;
  }
  return makeError(ErrorCode::kNotFound, fmt::format("unknown lens '{}'; available: pinhole, radtan, fisheye", lens));
}

Result<SimulationOptions> scenarioOptions(const std::string& scene, const std::string& difficulty, uint64_t seed,
                                          const Aabb& scene_bounds) {
  if (scene != "city" && scene != "room")
    return makeError(ErrorCode::kNotFound, fmt::format("unknown scenario '{}'; available: city, room", scene));
  if (difficulty != "easy" && difficulty != "hard")
    return makeError(ErrorCode::kNotFound, fmt::format("unknown difficulty '{}'; available: easy, hard", difficulty));
  const bool indoor = scene == "room";
  const bool hard = difficulty == "hard";
  SimulationOptions o;
  o.name = scene + "_" + difficulty;
  o.seed = seed;
  o.trajectory = indoor ? TrajectoryKind::kHandheld : TrajectoryKind::kDroneFlight;
  o.duration_s = 15.0;
  o.rate_hz = 20.0;
  o.camera.intrinsics = PinholeCamera{500.0, 500.0, 319.5, 239.5, 640, 480};
  o.camera.T_body_camera = defaultBodyCamera(o.trajectory);
  if (indoor) {
    // Indoors a GPS-like prior is an ultra-wideband or motion-capture-free beacon fix.
    o.priors.sigma = Eigen::Vector3d(0.3, 0.3, 0.5);
    o.near_m = 0.05;
    o.far_m = 100.0;
  } else {
    o.near_m = 0.5;
    o.far_m = 2000.0;
  }
  if (hard) {
    o.appearance = hardAppearance(seed, indoor, scene_bounds);
    o.damage.hole_fraction = 0.20;
    o.damage.simplify_ratio = 0.6;
    o.damage.draco = true;
    o.damage.draco_position_bits = 14;
    o.damage.draco_uv_bits = 12;
    o.jpeg = true;
    o.jpeg_quality = 90;
  }
  return o;
}

Result<Model> scenarioModel(const std::string& scene) {
  if (scene != "city" && scene != "room")
    return makeError(ErrorCode::kNotFound, fmt::format("unknown scenario '{}'; available: city, room", scene));
  DemoModelOptions options;
  options.target_triangles = scene == "city" ? 200000 : 50000;
  return makeDemoModel(scene, options);
}

namespace {

/// One render in linear RGB, lit and with the sky painted, one sample per pixel.
Result<ImageF32> renderSamples(Renderer& renderer, const PinholeCamera& camera, const Pose& T_world_camera,
                               const RenderSettings& settings, const AppearanceOptions& a, const ShadowMap* map) {
  auto rendered = renderer.render(camera, T_world_camera, settings);
  if (!rendered.ok()) return rendered.error();
  ImageF32 linear = decodeRender(rendered->rgba);
  if (a.lighting.enabled && map != nullptr) applyLighting(linear, *rendered, camera, T_world_camera, *map, a.lighting);
  if (a.sky) {
    for (size_t i = 0; i < rendered->depth.data.size(); ++i) {
      if (rendered->depth.data[i] != kBackgroundDepth) continue;
      for (int c = 0; c < 3; ++c) linear.data[3 * i + c] = static_cast<float>((*a.sky)[c]);
    }
  }
  return linear;
}

/// One render in linear RGB with AppearanceOptions::supersampling samples per pixel and axis:
/// rendered n times larger and box-averaged. Pixel (i, j) of `camera` has its centre at (i, j)
/// (core/camera.hpp), and its n x n samples at i + (k + 0.5) / n - 0.5, k = 0..n-1: the large
/// camera's pixel n i + k, i.e. f' = n f and c' = n c + (n - 1) / 2.
Result<ImageF32> renderLinear(Renderer& renderer, const PinholeCamera& camera, const Pose& T_world_camera,
                              const RenderSettings& settings, const AppearanceOptions& a, const ShadowMap* map) {
  const int n = a.supersampling;
  if (n <= 1) return renderSamples(renderer, camera, T_world_camera, settings, a, map);
  const double half = 0.5 * (n - 1);
  const PinholeCamera large{n * camera.fx,        n * camera.fy,    n * camera.cx + half,
                            n * camera.cy + half, n * camera.width, n * camera.height};
  auto samples = renderSamples(renderer, large, T_world_camera, settings, a, map);
  if (!samples.ok()) return samples.error();
  ImageF32& big = *samples;
  ImageF32 out(camera.width, camera.height, 3, 0.0f);
  // Area interpolation by a whole factor is the n x n box mean.
  cv::Mat dst(out.height, out.width, CV_32FC3, out.data.data());
  cv::resize(cv::Mat(big.height, big.width, CV_32FC3, big.data.data()), dst, dst.size(), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace

Result<ImageU8> simulateFrame(Renderer& renderer, const SplineTrajectory& trajectory, const Pose& T_body_camera,
                              const PinholeCamera& camera, int64_t t_ns, const AppearanceOptions& a,
                              const ShadowMap* map, const RenderSettings& base_settings, uint64_t noise_seed,
                              const LensRig* rig) {
  if (a.supersampling < 1 || a.supersampling > 4) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("simulate: supersampling {} is outside 1..4", a.supersampling));
  }
  const bool lighting = a.lighting.enabled && map != nullptr;
  RenderSettings settings = base_settings;
  settings.outputs = kRenderColor | kRenderDepth | (lighting ? kRenderNormals : 0u);
  const int n = std::max(1, a.motion_blur_subframes);
  ImageF32 sum;
  for (int k = 0; k < n; ++k) {
    // Sub-frame k samples the exposure [t - T/2, t + T/2] at its centre; one sub-frame is t.
    const double offset_s = a.exposure_time_s * ((k + 0.5) / n - 0.5);
    const int64_t t_k = t_ns + std::llround(offset_s * 1e9);
    const Pose T_world_camera = trajectory.evaluate(t_k).T_world_body * T_body_camera;
    ImageF32 linear;
    if (rig != nullptr) {
      std::vector<ImageF32> faces;
      for (size_t f = 0; f < rig->faces.size(); ++f) {
        auto face = renderLinear(renderer, rig->faces[f], T_world_camera * rig->T_camera_face[f], settings, a, map);
        if (!face.ok()) return face.error();
        faces.push_back(std::move(face).value());
      }
      linear = resampleLens(*rig, faces);
    } else {
      auto rendered = renderLinear(renderer, camera, T_world_camera, settings, a, map);
      if (!rendered.ok()) return rendered.error();
      linear = std::move(rendered).value();
    }
    if (k == 0) {
      sum = std::move(linear);
    } else {
      for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += linear.data[i];
    }
  }
  if (n > 1) {
    const float inv = 1.0f / static_cast<float>(n);
    for (float& v : sum.data) v *= inv;
  }
  const double t_s = static_cast<double>(t_ns) * 1e-9;
  const double phase = 2.0 * kPi * t_s / a.exposure_drift_period_s;
  const double ev = a.exposure_ev + a.exposure_drift_ev * std::sin(phase);
  std::array<double, 3> wb = a.white_balance;
  const double wb_change = a.white_balance_drift * std::sin(phase / 1.7 + 1.0);
  wb[0] *= 1.0 + wb_change;
  wb[2] *= 1.0 - wb_change;
  if (ev != 0.0 || wb != std::array<double, 3>{1.0, 1.0, 1.0}) applyExposure(sum, std::exp2(ev), wb);
  if (rig != nullptr) {
    if (a.vignetting > 0) {
      for (size_t i = 0; i < rig->cos_angle.size(); ++i) {
        const double c = std::max(0.0, static_cast<double>(rig->cos_angle[i]));
        const float factor = static_cast<float>(1.0 - a.vignetting * (1.0 - c * c * c * c));
        for (int ch = 0; ch < 3; ++ch) sum.data[3 * i + static_cast<size_t>(ch)] *= factor;
      }
    }
  } else {
    applyVignetting(sum, camera, a.vignetting);
  }
  addSensorNoise(sum, a.shot_noise, a.read_noise, noise_seed);
  return encodeImage(sum, a.gamma);
}

namespace {

TrajectoryOptions trajectoryOptions(const SimulationOptions& options) {
  TrajectoryOptions t;
  t.kind = options.trajectory;
  t.duration_s = options.duration_s;
  t.seed = subSeed(options.seed, 1);
  t.T_body_camera = options.camera.T_body_camera;
  return t;
}

}  // namespace

Result<SplineTrajectory> simulationTrajectory(const SimulationOptions& options, const Aabb& scene_bounds) {
  return makeTrajectory(trajectoryOptions(options), scene_bounds);
}

Result<SplineTrajectory> simulationTrajectory(const SimulationOptions& options, const Model& model) {
  TrajectoryOptions t = trajectoryOptions(options);
  if (isDroneKind(t.kind)) {
    // A drone flies over the buildings, not through them: 10 m above anything within 5 m.
    auto obstacles = HeightField::fromModel(model, 5.0);
    if (!obstacles.ok()) return obstacles.error();
    t.obstacles = std::move(*obstacles);
  }
  return makeTrajectory(t, model.bounds);
}

Result<SimulationReport> simulateSequence(const Model& model, const SimulationOptions& options,
                                          const RendererFactory& renderers, const std::string& directory,
                                          const SimulationProgress& progress) {
  VKLOC_TRY_STATUS(validateOptions(options));
  VKLOC_TRY_STATUS(validateModel(model));
  if (!renderers) return makeError(ErrorCode::kInvalidArgument, "simulate: no renderer factory given");
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(fs::path(directory) / "images", ec);
  if (ec) {
    return makeError(ErrorCode::kIoError,
                     fmt::format("{}: cannot create the output folder: {}", directory, ec.message()));
  }
  const uint64_t seed = options.seed;

  // Trajectory and sensors.
  auto trajectory = simulationTrajectory(options, model);
  if (!trajectory.ok()) return trajectory.error();

  Sequence seq;
  seq.directory = directory;
  seq.name = options.name;
  seq.camera = options.camera;
  if (options.write_imu) {
    seq.imu = simulateImu(*trajectory, options.imu_noise, seq.gravity_world, subSeed(seed, 2));
    seq.imu_noise = options.imu_noise;
  }
  if (options.write_priors) seq.priors = simulatePriors(*trajectory, options.priors, subSeed(seed, 3));

  // The localization model, damaged and written first (its name goes into sequence.yaml).
  SimulationReport report;
  report.directory = directory;
  auto damaged = damageModel(model, options.damage, subSeed(seed, 4), &report.damage);
  if (!damaged.ok()) return damaged.error();
  const std::string model_name = options.damage.draco ? "model_draco.glb" : "model.glb";
  ModelWriteOptions write_options;
  write_options.draco = options.damage.draco;
  write_options.draco_position_bits = options.damage.draco_position_bits;
  write_options.draco_uv_bits = options.damage.draco_uv_bits;
  VKLOC_TRY_STATUS(saveModel(*damaged, (fs::path(directory) / model_name).string(), write_options));
  seq.model = model_name;
  report.model_file = (fs::path(directory) / model_name).string();

  // Renderers: camera images from the colour-jittered intact model; shadows from the model.
  const AppearanceOptions& a = options.appearance;
  const Model camera_model = jitterModelColors(model, a.color_jitter_gain, a.color_jitter_offset, subSeed(seed, 5));
  auto created = renderers(camera_model);
  if (!created.ok()) return created.error();
  if (!*created) return makeError(ErrorCode::kInvalidArgument, "simulate: the renderer factory made no renderer");
  Renderer& renderer = **created;
  std::optional<ShadowMap> shadow;
  if (a.lighting.enabled) {
    auto map = renderShadowMap(renderer, model.bounds, a.lighting);
    if (!map.ok()) return map.error();
    shadow = std::move(map).value();
  }
  RenderSettings settings;
  settings.near_m = options.near_m;
  settings.far_m = options.far_m;
  settings.threads = options.render_threads > 0 ? options.render_threads : availableCores();
  // A lens other than the ideal pinhole: its image is resampled from pinhole renders.
  std::optional<LensRig> rig;
  if (Result<LensCamera> lens = lensCamera(options.camera); lens.ok() && !lens->isIdealPinhole()) {
    auto made = makeLensRig(*lens);
    if (!made.ok()) return made.error();
    rig = std::move(made).value();
  }

  // Image times: from the trajectory start at 1 / rate.
  const int64_t start = trajectory->startNs();
  const int64_t end = trajectory->endNs();
  const double period_ns = 1e9 / options.rate_hz;
  size_t total = static_cast<size_t>(std::floor(static_cast<double>(end - start) / period_ns)) + 1;
  if (options.max_frames > 0) total = std::min(total, options.max_frames);
  seq.initial_T_world_camera = trajectory->evaluate(start).T_world_body * options.camera.T_body_camera;

  auto writeText = [&]() -> Status {
    if (!seq.groundtruth.empty()) seq.initial_T_world_camera = seq.groundtruth.front().T_world_camera;
    return saveSequence(seq, directory);
  };
  const auto t0 = std::chrono::steady_clock::now();
  for (size_t i = 0; i < total; ++i) {
    const int64_t t_ns = start + std::llround(static_cast<double>(i) * period_ns);
    const std::string rel = fmt::format("images/{:06d}.{}", i, options.jpeg ? "jpg" : "png");
    const std::string path = (fs::path(directory) / rel).string();
    auto image = simulateFrame(renderer, *trajectory, options.camera.T_body_camera, options.camera.intrinsics, t_ns, a,
                               shadow ? &*shadow : nullptr, settings, subSeed(seed, 1000 + i), rig ? &*rig : nullptr);
    Status written = image.ok()
                         ? (options.jpeg ? writeJpeg(path, *image, options.jpeg_quality) : writePng(path, *image))
                         : Status(image.error());
    if (!written.ok()) {
      const Status partial = writeText();
      return makeError(written.error().code,
                       fmt::format("frame {}: {} ({} frames written to {}{})", i, written.error().message, i, directory,
                                   partial.ok() ? "" : "; sequence files not written"));
    }
    seq.images.push_back(ImageEntry{t_ns, rel});
    seq.groundtruth.push_back(
        StampedPose{t_ns, trajectory->evaluate(t_ns).T_world_body * options.camera.T_body_camera});
    if (progress) progress(i + 1, total);
  }
  report.frames = total;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  VKLOC_TRY_STATUS(writeText());
  return report;
}

}  // namespace vkloc
