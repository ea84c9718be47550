// vkloc demo: the main job on built-in data: render the demo models at their demo viewpoints
// (timings), then simulate a short built-in sequence, localize every frame in the model and print
// accuracy, frame rate and the report's path.
#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "common.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc::cli {

namespace {

struct DemoArgs {
  std::string out_dir = "vkloc_demo";
  DeviceArgs device;
  CameraArgs camera;
  std::string scene = "room";
  std::string difficulty = "hard";
  size_t frames = 100;
  /// The simulator's hard scenarios (motion blur of 3-6 px, a biased IMU) are tracked with the
  /// window fit: with the EKF, `vkloc track`'s default, room hard bridges tens of frames by the
  /// IMU alone (README, "Filter"; test accuracy.room_hard_ekf, open).
  LocalizerArgs localizer = [] {
    LocalizerArgs l;
    l.filter = "window";
    return l;
  }();
  bool no_track = false;
};

void runLocalization(const DemoArgs& a, const std::shared_ptr<GpuContext>& context) {
  const std::string name = fmt::format("{}_{}", a.scene, a.difficulty);
  const std::string seq_dir = (std::filesystem::path(a.out_dir) / name).string();
  std::printf("\nlocalization: simulating %zu frames of '%s %s' -> %s\n", a.frames, a.scene.c_str(),
              a.difficulty.c_str(), seq_dir.c_str());
  std::fflush(stdout);
  const Model model = take(scenarioModel(a.scene));
  SimulationOptions options = take(scenarioOptions(a.scene, a.difficulty, 1, model.bounds));
  options.max_frames = a.frames;
  options.duration_s = std::max(1.0, static_cast<double>(a.frames) / options.rate_hz + 0.5);
  const bool tty = isatty(fileno(stdout)) != 0;
  auto progress = [tty](size_t done, size_t total) {
    if (tty) {
      std::printf("\rsimulated %zu/%zu", done, total);
      if (done == total) std::printf("\n");
      std::fflush(stdout);
    }
  };
  const SimulationReport report =
      take(simulateSequence(model, options, gpuRendererFactory(context), seq_dir, progress));
  std::printf("simulated %zu frames in %.1f s\n", report.frames, report.seconds);
  std::fflush(stdout);
  const std::string out = (std::filesystem::path(a.out_dir) / (name + "_trajectory.txt")).string();
  const std::string report_dir = (std::filesystem::path(a.out_dir) / (name + "_report")).string();
  std::vector<std::string> args = {"--sequence", seq_dir, "--out", out, "--report", report_dir};
  for (const std::string& arg : a.localizer.arguments()) args.push_back(arg);
  if (!a.device.device.empty()) {
    args.push_back("--device");
    args.push_back(a.device.device);
  }
  runTrackArguments(args);
}

void run(const DemoArgs& a) {
  const PinholeCamera camera = a.camera.get();
  auto t0 = std::chrono::steady_clock::now();
  auto context = a.device.create();
  std::printf("device: %s (%s, Vulkan %s), created in %.0f ms\n", context->device().name.c_str(),
              context->device().type.c_str(), context->device().api_version.c_str(), msSince(t0));
  for (const std::string name : {"city", "room"}) {
    t0 = std::chrono::steady_clock::now();
    const Model model = take(makeDemoModel(name));
    std::printf("\n%s: %zu triangles, %zu textures, %zu blocks, built in %.0f ms\n", name.c_str(),
                model.triangleCount(), model.textures.size(), model.blocks.size(), msSince(t0));
    t0 = std::chrono::steady_clock::now();
    auto renderer = take(GpuRenderer::create(context, model));
    std::printf("  uploaded in %.0f ms\n", msSince(t0));
    const auto poses = demoViewpoints(name);
    const std::string dir = (std::filesystem::path(a.out_dir) / name).string();
    for (size_t i = 0; i < poses.size(); ++i) {
      // The first render of a pipeline includes shader compilation (JIT on lavapipe); render
      // twice and report both so the steady-state cost is visible.
      t0 = std::chrono::steady_clock::now();
      RenderOutput out = take(renderer->render(camera, poses[i]));
      const double first_ms = msSince(t0);
      t0 = std::chrono::steady_clock::now();
      out = take(renderer->render(camera, poses[i]));
      const double ms = msSince(t0);
      const auto paths = writeRender(dir, fmt::format("view{:02d}", i), out);
      size_t seen = 0;
      for (float z : out.depth.data) seen += z > 0.0f;
      std::printf(
          "  view %zu: %6.2f ms (first %6.1f ms), %3u/%zu blocks, %6u triangles, %4.1f%% pixels covered -> %s\n", i, ms,
          first_ms, out.blocks_drawn, model.blocks.size(), out.triangles_drawn,
          100.0 * static_cast<double>(seen) / out.depth.data.size(), paths[0].c_str());
    }
  }
  std::printf("\nimages written under %s/ (rgba, gray, depth_mm 16-bit PNG, depth float TIFF, normals)\n",
              std::filesystem::absolute(a.out_dir).string().c_str());
  if (!a.no_track && a.frames > 0) runLocalization(a, context);
}

}  // namespace

static void addDemoVerb(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "demo", "Render the built-in models (timings), then simulate a short sequence, localize it and report accuracy");
  cmd->add_option("--out,-o", args->out_dir, "Output directory")->capture_default_str();
  cmd->add_option("--scene", args->scene, "Simulated scenario: room | city")
      ->check(CLI::IsMember({"room", "city"}))
      ->capture_default_str();
  cmd->add_option("--difficulty", args->difficulty, "easy | hard")
      ->check(CLI::IsMember({"easy", "hard"}))
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames to simulate and localize (0 = render views only)")
      ->capture_default_str();
  args->localizer.add(*cmd);
  cmd->add_flag("--no-track", args->no_track, "Only render the demo views");
  args->device.add(*cmd);
  args->camera.add(*cmd);
  cmd->callback([args] { run(*args); });
}

VKLOC_REGISTER_VERB(10, addDemoVerb);

}  // namespace vkloc::cli
