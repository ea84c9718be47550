// vkloc demo: the main job on built-in data (for now: render the demo models at their demo
// viewpoints and report where the images are and how long each render took).
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "common.hpp"
#include "vkloc/demo.hpp"

namespace vkloc::cli {
namespace {

struct DemoArgs {
  std::string out_dir = "vkloc_demo";
  DeviceArgs device;
  CameraArgs camera;
};

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
}

}  // namespace

static void addDemoVerb(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  CLI::App* cmd = app.add_subcommand("demo", "Render the built-in city and room models and report timings");
  cmd->add_option("--out,-o", args->out_dir, "Output directory")->capture_default_str();
  args->device.add(*cmd);
  args->camera.add(*cmd);
  cmd->callback([args] { run(*args); });
}

VKLOC_REGISTER_VERB(10, addDemoVerb);

}  // namespace vkloc::cli
