// vkloc render: render a model at one or more poses and write colour, depth and normals.
#include <fmt/format.h>

#include <cstdio>

#include "common.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::cli {
namespace {

struct RenderArgs {
  ModelArgs model;
  CameraArgs camera;
  DeviceArgs device;
  std::vector<std::string> poses;
  std::vector<std::string> look_at;
  std::string out_dir = "vkloc_render";
  double near_m = 0.05;
  double far_m = 5000.0;
  bool cull = false;
  bool no_normals = false;
  bool reference = false;
};

Pose parseLookAt(const std::string& text) {
  const std::vector<double> v = take(parseNumbers(text, "--look-at (ex,ey,ez,tx,ty,tz)", 6));
  return take(lookAt({v[0], v[1], v[2]}, {v[3], v[4], v[5]}));
}

void run(const RenderArgs& a) {
  const PinholeCamera camera = a.camera.get();
  std::vector<Pose> poses;
  for (const auto& p : a.poses) poses.push_back(take(parsePose(p)));
  for (const auto& p : a.look_at) poses.push_back(parseLookAt(p));
  if (poses.empty()) {
    if (!isDemoModel(a.model.model)) throw Failure{"give at least one --pose or --look-at"};
    poses = demoViewpoints(a.model.model);
  }
  const Model model = a.model.load();
  RenderSettings settings;
  settings.near_m = a.near_m;
  settings.far_m = a.far_m;
  settings.cull_back_faces = a.cull;
  if (a.no_normals) settings.outputs &= ~kRenderNormals;

  std::unique_ptr<GpuRenderer> renderer;
  if (!a.reference) {
    auto context = a.device.create();
    std::printf("device: %s (%s)\n", context->device().name.c_str(), context->device().type.c_str());
    renderer = take(GpuRenderer::create(context, model));
  }
  for (size_t i = 0; i < poses.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    RenderOutput out = a.reference ? take(renderReference(model, camera, poses[i], settings))
                                   : take(renderer->render(camera, poses[i], settings));
    const double ms = msSince(t0);
    const auto paths = writeRender(a.out_dir, fmt::format("view{:03d}", i), out);
    std::printf("view %zu: %.2f ms, %u/%zu blocks, %u triangles -> %s (+%zu files)\n", i, ms, out.blocks_drawn,
                model.blocks.size(), out.triangles_drawn, paths[0].c_str(), paths.size() - 1);
  }
}

}  // namespace

static void addRenderVerb(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a model at camera poses; write colour, gray, depth, normals");
  args->model.add(*cmd);
  args->camera.add(*cmd);
  args->device.add(*cmd);
  cmd->add_option("--pose,-p", args->poses, "T_world_camera 'tx ty tz qx qy qz qw' or 16 numbers; repeatable");
  cmd->add_option("--look-at", args->look_at, "Camera 'ex,ey,ez,tx,ty,tz' (eye, target; world z up); repeatable");
  cmd->add_option("--out,-o", args->out_dir, "Output directory")->capture_default_str();
  cmd->add_option("--near", args->near_m, "Near clip plane, metres")->capture_default_str();
  cmd->add_option("--far", args->far_m, "Far clip plane, metres")->capture_default_str();
  cmd->add_flag("--cull", args->cull, "Cull back faces (model must have consistent winding)");
  cmd->add_flag("--no-normals", args->no_normals, "Skip the normal and back-face outputs");
  cmd->add_flag("--reference", args->reference, "Use the CPU reference rasterizer instead of Vulkan");
  cmd->callback([args] { run(*args); });
}

VKLOC_REGISTER_VERB(40, addRenderVerb);

}  // namespace vkloc::cli
