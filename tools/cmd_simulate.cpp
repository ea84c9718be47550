// vkloc simulate: render a sequence with ground truth, IMU and priors whose camera images differ
// from the localization model the way real photos differ from a reconstructed model.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "common.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc::cli {
namespace {

struct SimulateArgs {
  std::string scene;       ///< city | room (built-in scenario) or empty.
  std::string difficulty;  ///< easy | hard.
  ModelArgs model;
  CameraArgs camera;
  DeviceArgs device;
  std::string trajectory;
  std::string lens;  ///< pinhole | radtan | fisheye (scenarioCamera).
  double duration_s = 15.0;
  double rate_hz = 20.0;
  std::string out_dir;
  uint64_t seed = 1;
  size_t frames = 0;
  bool reference = false;
  // Per-effect overrides (applied on top of the scenario or of "easy").
  bool hard = false;
  std::string sun;  ///< "azimuth,elevation" degrees.
  bool no_lighting = false;
  double exposure_ev = 0;
  double gamma = 1;
  std::string white_balance;
  double color_jitter = 0;
  double vignetting = 0;
  std::string noise;  ///< "shot,read".
  int motion_blur = 1;
  int supersample = 1;
  double exposure_time_s = 0;
  int jpeg_quality = 0;
  bool png = false;
  double holes = 0;
  double simplify = 1;
  bool draco = false;
  bool no_imu = false;
  bool no_priors = false;
};

bool given(const CLI::App& cmd, const char* name) { return cmd.get_option(name)->count() > 0; }

void applyOverrides(const CLI::App& cmd, const SimulateArgs& a, SimulationOptions& o) {
  AppearanceOptions& ap = o.appearance;
  if (given(cmd, "--sun")) {
    const auto v = take(parseNumbers(a.sun, "--sun (azimuth,elevation degrees)", 2));
    ap.lighting.enabled = true;
    ap.lighting.spot = false;
    ap.lighting.sun_azimuth_deg = v[0];
    ap.lighting.sun_elevation_deg = v[1];
  }
  if (a.no_lighting) ap.lighting.enabled = false;
  if (given(cmd, "--exposure")) ap.exposure_ev = a.exposure_ev;
  if (given(cmd, "--gamma")) ap.gamma = a.gamma;
  if (given(cmd, "--white-balance")) {
    const auto v = take(parseNumbers(a.white_balance, "--white-balance (r,g,b gains)", 3));
    ap.white_balance = {v[0], v[1], v[2]};
  }
  if (given(cmd, "--color-jitter")) {
    ap.color_jitter_gain = a.color_jitter;
    ap.color_jitter_offset = a.color_jitter / 4;
  }
  if (given(cmd, "--vignetting")) ap.vignetting = a.vignetting;
  if (given(cmd, "--noise")) {
    const auto v = take(parseNumbers(a.noise, "--noise (shot,read sigmas)", 2));
    ap.shot_noise = v[0];
    ap.read_noise = v[1];
  }
  if (given(cmd, "--motion-blur")) ap.motion_blur_subframes = a.motion_blur;
  if (given(cmd, "--exposure-time")) ap.exposure_time_s = a.exposure_time_s;
  if (given(cmd, "--supersample")) ap.supersampling = a.supersample;
  if (given(cmd, "--jpeg")) {
    o.jpeg = true;
    o.jpeg_quality = a.jpeg_quality;
  }
  if (a.png) o.jpeg = false;
  if (given(cmd, "--holes")) o.damage.hole_fraction = a.holes;
  if (given(cmd, "--simplify")) o.damage.simplify_ratio = a.simplify;
  if (a.draco) o.damage.draco = true;
  if (a.no_imu) o.write_imu = false;
  if (a.no_priors) o.write_priors = false;
  if (given(cmd, "--duration")) o.duration_s = a.duration_s;
  if (given(cmd, "--rate")) o.rate_hz = a.rate_hz;
  o.max_frames = a.frames;
}

void run(const CLI::App& cmd, const SimulateArgs& a) {
  Model model;
  SimulationOptions options;
  std::string out_dir = a.out_dir;
  if (!a.scene.empty()) {
    if (given(cmd, "--model")) throw Failure{"a built-in scenario (city|room easy|hard) fixes the model; drop --model"};
    const std::string difficulty = a.difficulty.empty() ? (a.hard ? "hard" : "easy") : a.difficulty;
    model = take(scenarioModel(a.scene));
    options = take(scenarioOptions(a.scene, difficulty, a.seed, model.bounds));
    std::string suffix;
    if (!a.trajectory.empty()) {
      options.trajectory = take(parseTrajectoryKind(a.trajectory));
      options.camera.T_body_camera = defaultBodyCamera(options.trajectory);
      suffix += "_" + a.trajectory;
    }
    if (!a.lens.empty()) {
      options.camera = take(scenarioCamera(a.lens, options.trajectory));
      if (a.lens != "pinhole") suffix += "_" + a.lens;
    }
    options.name += suffix;
    if (out_dir.empty()) out_dir = fmt::format("sim/{}_{}{}", a.scene, difficulty, suffix);
  } else {
    if (!a.difficulty.empty()) throw Failure{"give a scenario name (city or room) before the difficulty"};
    model = a.model.load();
    const std::string name = std::filesystem::path(a.model.model).stem().string();
    const bool indoor = a.model.model == "room";
    std::string kind = a.trajectory.empty() ? (indoor ? "handheld" : "drone") : a.trajectory;
    options.trajectory = take(parseTrajectoryKind(kind));
    options.name = fmt::format("{}_{}", name, kind);
    options.seed = a.seed;
    options.camera = take(scenarioCamera(a.lens.empty() ? "pinhole" : a.lens, options.trajectory));
    options.duration_s = a.duration_s;
    options.rate_hz = a.rate_hz;
    if (indoor) options.far_m = 100.0;
    if (a.hard) {
      options.appearance = hardAppearance(a.seed, indoor, model.bounds);
      options.damage.hole_fraction = 0.2;
      options.damage.simplify_ratio = 0.6;
      options.damage.draco = true;
      options.jpeg = true;
    }
    if (out_dir.empty()) out_dir = fmt::format("sim/{}_{}", name, kind);
  }
  options.camera = a.camera.getFull(options.camera);
  applyOverrides(cmd, a, options);

  RendererFactory factory;
  if (a.reference) {
    factory = cpuRendererFactory();
    std::printf("renderer: CPU reference\n");
  } else {
    auto context = a.device.create();
    std::printf("device: %s (%s)\n", context->device().name.c_str(), context->device().type.c_str());
    factory = gpuRendererFactory(context);
  }
  std::printf("model: %zu triangles; camera %dx%d; %s, %.1f s at %.1f Hz; seed %llu -> %s\n", model.triangleCount(),
              options.camera.intrinsics.width, options.camera.intrinsics.height, trajectoryKindName(options.trajectory),
              options.duration_s, options.rate_hz, static_cast<unsigned long long>(options.seed), out_dir.c_str());
  std::fflush(stdout);

  const bool tty = isatty(fileno(stdout)) != 0;
  const auto t0 = std::chrono::steady_clock::now();
  size_t last_decile = 0;
  auto progress = [&](size_t done, size_t total) {
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double fps = s > 0 ? static_cast<double>(done) / s : 0.0;
    if (tty) {
      std::printf("\rframe %zu/%zu  %.2f fps", done, total, fps);
      if (done == total) std::printf("\n");
      std::fflush(stdout);
    } else {
      const size_t decile = done * 10 / std::max<size_t>(total, 1);
      if (decile > last_decile || done == total) {
        last_decile = decile;
        std::printf("frame %zu/%zu (%zu %%), %.2f fps\n", done, total, done * 100 / std::max<size_t>(total, 1), fps);
        std::fflush(stdout);
      }
    }
  };
  const SimulationReport report = take(simulateSequence(model, options, factory, out_dir, progress));
  if (options.damage.hole_fraction > 0 || options.damage.simplify_ratio != 1.0) {
    std::printf("model damage: %.1f %% of the area removed in %zu holes, %zu -> %zu triangles%s\n",
                100.0 * report.damage.removed_area_fraction, report.damage.hole_patches, report.damage.triangles_before,
                report.damage.triangles_after, options.damage.draco ? ", Draco-compressed" : "");
  }
  const double fps = report.seconds > 0 ? static_cast<double>(report.frames) / report.seconds : 0.0;
  std::printf("simulated %zu frames in %.1f s (%.2f fps) -> %s (model %s)\n", report.frames, report.seconds, fps,
              report.directory.c_str(), std::filesystem::path(report.model_file).filename().c_str());
}

}  // namespace

static void addSimulateVerb(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand("simulate",
                                     "Simulate a sequence (images, ground truth, IMU, priors, damaged model): "
                                     "'city|room easy|hard' or --model/--trajectory");
  cmd->add_option("scenario", args->scene, "Built-in scenario: city (drone) or room (handheld)")
      ->check(CLI::IsMember({"city", "room"}));
  cmd->add_option("difficulty", args->difficulty,
                  "easy: no appearance change, intact model; hard: every appearance change, 20 % holes, "
                  "simplified to 60 %, Draco")
      ->check(CLI::IsMember({"easy", "hard"}));
  args->model.add(*cmd);
  args->camera.add(*cmd);
  args->device.add(*cmd);
  cmd->add_option("--trajectory,-t", args->trajectory,
                  "drone | drone_agile | drone_acro | handheld | aggressive | orbit (default by model or scenario)");
  cmd->add_option("--lens", args->lens,
                  "pinhole (640x480) | radtan (the same, barrel distortion) | fisheye (800x800, 210 deg)");
  cmd->add_option("--duration", args->duration_s, "Trajectory length, seconds")->capture_default_str();
  cmd->add_option("--rate", args->rate_hz, "Camera frame rate, Hz")->capture_default_str();
  cmd->add_option("--out,-o", args->out_dir, "Output folder (default sim/<scenario>_<difficulty>)");
  cmd->add_option("--seed", args->seed, "Seed of every random choice; same seed, identical files")
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Stop after this many images (0 = all)")->capture_default_str();
  cmd->add_flag("--reference", args->reference, "Render with the CPU reference rasterizer instead of Vulkan");
  cmd->add_flag("--hard", args->hard, "With --model: start from the 'hard' appearance and damage settings");
  cmd->add_option("--sun", args->sun, "Sun 'azimuth,elevation' in degrees (turns lighting with shadows on)");
  cmd->add_flag("--no-lighting", args->no_lighting, "No sun, no shadows");
  cmd->add_option("--exposure", args->exposure_ev, "Exposure change, stops");
  cmd->add_option("--gamma", args->gamma, "Tone curve exponent after sRGB (out = s^(1/gamma))");
  cmd->add_option("--white-balance", args->white_balance, "Linear 'r,g,b' gains");
  cmd->add_option("--color-jitter", args->color_jitter, "Per-texture colour gain range (offset a quarter of it)");
  cmd->add_option("--vignetting", args->vignetting, "Vignetting strength 0..1 (cos^4 falloff)");
  cmd->add_option("--noise", args->noise, "Sensor noise 'shot,read' sigmas (linear 0..1 units)");
  cmd->add_option("--motion-blur", args->motion_blur, "Sub-frames averaged per image (1 = none)");
  cmd->add_option("--exposure-time", args->exposure_time_s, "Shutter time for motion blur, seconds");
  cmd->add_option("--supersample", args->supersample,
                  "Samples per pixel along each axis, box-averaged (1..4; 1 = one at the centre, aliased edges)");
  cmd->add_option("--jpeg", args->jpeg_quality, "Write JPEG images with this quality (1..100)");
  cmd->add_flag("--png", args->png, "Write PNG images (lossless)");
  cmd->add_option("--holes", args->holes, "Fraction of the model's area removed in patches (0..0.9)");
  cmd->add_option("--simplify", args->simplify, "Simplify the model to this fraction of its triangles (0..1]");
  cmd->add_flag("--draco", args->draco, "Write the model Draco-compressed (quantized)");
  cmd->add_flag("--no-imu", args->no_imu, "Do not write imu.csv");
  cmd->add_flag("--no-priors", args->no_priors, "Do not write prior.csv");
  cmd->callback([args, cmd] { run(*cmd, *args); });
}

VKLOC_REGISTER_VERB(20, addSimulateVerb);

}  // namespace vkloc::cli
