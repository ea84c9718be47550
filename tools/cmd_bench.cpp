// vkloc bench render: timing of model renders at 640x480 for ~10k, 100k and 1M triangles.
#include <algorithm>
#include <cstdio>
#include <sstream>

#include <fmt/format.h>

#include "common.hpp"
#include "vkloc/demo.hpp"

namespace vkloc::cli {
namespace {

struct BenchArgs {
  DeviceArgs device;
  CameraArgs camera;
  std::vector<uint32_t> triangles{10000, 100000, 1000000};
  int runs = 40;
  int warmup = 3;
  int reference_runs = 3;
  bool cull = true;
};

struct Stats {
  double median = 0, p10 = 0, p90 = 0;
};

Stats stats(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  auto q = [&](double f) { return v[std::min(v.size() - 1, static_cast<size_t>(f * (v.size() - 1) + 0.5))]; };
  return {q(0.5), q(0.1), q(0.9)};
}

void run(const BenchArgs& a) {
  const PinholeCamera camera = a.camera.get();
  auto context = a.device.create();
  std::printf("device: %s (%s); %dx%d, %d runs after %d warm-up, median [p10 p90] ms\n",
              context->device().name.c_str(), context->device().type.c_str(), camera.width, camera.height, a.runs,
              a.warmup);
  std::printf("%-9s %-8s %9s %8s %-26s %-26s %-26s %s\n", "model", "view", "triangles", "drawn", "colour+depth+normals",
              "colour+depth", "no readback", "CPU reference");
  for (uint32_t target : a.triangles) {
    DemoModelOptions options;
    options.target_triangles = target;
    const Model model = makeDemoCity(options);
    auto renderer = take(GpuRenderer::create(context, model));
    const auto views = demoViewpoints("city");
    // "drone": the demo's first drone view (45 deg down); "overview": far away, whole model in view.
    const Pose overview = take(lookAt({-180, -180, 220}, {0, 0, 0}));
    const std::pair<const char*, Pose> cases[2] = {{"drone", views.front()}, {"overview", overview}};
    for (const auto& [view_name, pose] : cases) {
      RenderSettings all;
      all.cull_back_faces = a.cull;
      RenderSettings no_normals = all;
      no_normals.outputs &= ~kRenderNormals;
      auto time = [&](const RenderSettings& s, bool readback, uint32_t* drawn) {
        std::vector<double> ms;
        for (int i = 0; i < a.warmup + a.runs; ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          RenderOutput out = readback ? take(renderer->render(camera, pose, s)) : take(renderer->renderOnGpu(camera, pose, s));
          if (i >= a.warmup) ms.push_back(msSince(t0));
          *drawn = out.triangles_drawn;
        }
        return stats(ms);
      };
      uint32_t drawn = 0;
      const Stats full = time(all, true, &drawn);
      const Stats color_depth = time(no_normals, true, &drawn);
      const Stats gpu_only = time(no_normals, false, &drawn);
      std::string ref = "-";
      if (a.reference_runs > 0 && model.triangleCount() <= 200000) {
        std::vector<double> ms;
        for (int i = 0; i < a.reference_runs; ++i) {
          const auto t0 = std::chrono::steady_clock::now();
          (void)take(renderReference(model, camera, pose, all));
          ms.push_back(msSince(t0));
        }
        const Stats r = stats(ms);
        ref = fmt::format("{:.1f} ({:.1f}x GPU)", r.median, r.median / full.median);
      }
      auto fmt_stats = [](const Stats& s) { return fmt::format("{:.2f} [{:.2f} {:.2f}]", s.median, s.p10, s.p90); };
      std::printf("%-9s %-8s %9zu %8u %-26s %-26s %-26s %s\n", fmt::format("city{}k", target / 1000).c_str(), view_name,
                  model.triangleCount(), drawn, fmt_stats(full).c_str(), fmt_stats(color_depth).c_str(),
                  fmt_stats(gpu_only).c_str(), ref.c_str());
      std::fflush(stdout);
    }
  }
}

}  // namespace

void addBenchVerb(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks (median of many runs)");
  bench->require_subcommand(1);
  auto args = std::make_shared<BenchArgs>();
  CLI::App* render = bench->add_subcommand("render", "Render the demo city at ~10k, 100k and 1M triangles");
  args->device.add(*render);
  args->camera.add(*render);
  render->add_option("--triangles", args->triangles, "Model sizes (triangles)")->delimiter(',')->capture_default_str();
  render->add_option("--runs", args->runs, "Timed runs per case")->capture_default_str();
  render->add_option("--warmup", args->warmup, "Untimed runs first (JIT, caches)")->capture_default_str();
  render->add_option("--reference-runs", args->reference_runs, "CPU reference runs (models up to 200k triangles)")
      ->capture_default_str();
  render->add_flag("!--no-cull", args->cull, "Disable back-face culling");
  render->callback([args] { run(*args); });
}

}  // namespace vkloc::cli
