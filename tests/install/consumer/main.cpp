// The external consumer: writes a small textured model file, loads it, renders the view a camera
// would see, and localizes that frame with a Localizer started 3 cm and 2 degrees off (on the
// Vulkan device when there is one, else on the CPU). Exit code 0 when the pose is found.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "vkloc/vkloc.hpp"

namespace {

int fail(const std::string& what) {
  std::fprintf(stderr, "vkloc_consumer: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  const fs::path dir = argc > 1 ? fs::path(argv[1]) : fs::temp_directory_path() / "vkloc_consumer";
  fs::create_directories(dir);

  // A checkerboard texture and a box on a ground plane, as an OBJ file with its material.
  vkloc::ImageU8 checker(256, 256, 3);
  for (int y = 0; y < 256; ++y) {
    for (int x = 0; x < 256; ++x) {
      const uint8_t v = ((x / 32) + (y / 32)) % 2 ? 220 : 40;
      for (int c = 0; c < 3; ++c) checker.at(x, y, c) = v;
    }
  }
  if (auto s = vkloc::writePng((dir / "checker.png").string(), checker); !s.ok()) return fail(s.error().message);
  {
    std::ofstream mtl(dir / "scene.mtl");
    mtl << "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n";
    std::ofstream obj(dir / "scene.obj");
    obj << "mtllib scene.mtl\nusemtl checker\n";
    // Ground 2.4 m square (z = 0, facing +z) and a 0.6 x 0.45 x 0.4 m box.
    auto quad = [&](const double p[4][3]) {
      static int base = 1;
      for (int i = 0; i < 4; ++i) obj << "v " << p[i][0] << " " << p[i][1] << " " << p[i][2] << "\n";
      obj << "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
      obj << "f " << base << "/" << base << " " << base + 1 << "/" << base + 1 << " " << base + 2 << "/" << base + 2
          << "\n";
      obj << "f " << base << "/" << base << " " << base + 2 << "/" << base + 2 << " " << base + 3 << "/" << base + 3
          << "\n";
      base += 4;
    };
    const double ground[4][3] = {{-1.2, -1.2, 0}, {1.2, -1.2, 0}, {1.2, 1.2, 0}, {-1.2, 1.2, 0}};
    quad(ground);
    const double x0 = -0.3, x1 = 0.3, y0 = -0.2, y1 = 0.25, z1 = 0.4;
    const double faces[5][4][3] = {{{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}},
                                   {{x0, y0, 0}, {x1, y0, 0}, {x1, y0, z1}, {x0, y0, z1}},
                                   {{x1, y0, 0}, {x1, y1, 0}, {x1, y1, z1}, {x1, y0, z1}},
                                   {{x1, y1, 0}, {x0, y1, 0}, {x0, y1, z1}, {x1, y1, z1}},
                                   {{x0, y1, 0}, {x0, y0, 0}, {x0, y0, z1}, {x0, y1, z1}}};
    for (const auto& f : faces) quad(f);
  }

  vkloc::Result<vkloc::Model> model = vkloc::loadModel((dir / "scene.obj").string());
  if (!model.ok()) return fail(model.error().message);
  std::printf("model: %zu triangles, %zu textures\n", model->triangleCount(), model->textures.size());

  const vkloc::PinholeCamera camera{260.0, 260.0, 159.5, 119.5, 320, 240};
  auto truth = vkloc::lookAt({1.4, -1.4, 1.2}, {0.0, 0.0, 0.15});
  if (!truth.ok()) return fail(truth.error().message);
  auto cpu = vkloc::CpuRenderer::create(*model);
  if (!cpu.ok()) return fail(cpu.error().message);
  vkloc::RenderSettings settings;
  auto view = (*cpu)->render(camera, *truth, settings);
  if (!view.ok()) return fail(view.error().message);

  // The Vulkan device when there is one, else everything on the CPU.
  std::shared_ptr<vkloc::Accelerator> accelerator;
  if (auto context = vkloc::GpuContext::create(); context.ok()) {
    if (auto a = vkloc::makeGpuAccelerator(*context); a.ok()) accelerator = *a;
  }
  std::printf("device: %s\n", accelerator ? accelerator->describe().c_str() : "none (CPU)");

  vkloc::LocalizerOptions options;
  options.keyframe_threading = vkloc::KeyframeThreading::kSynchronous;
  auto localizer = vkloc::Localizer::create(*model, camera, options, accelerator);
  if (!localizer.ok()) return fail(localizer.error().message);
  vkloc::Pose start = *truth;
  start.translation() += vkloc::Pose::LinearMatrixType(truth->linear()) * Eigen::Vector3d(0.03, -0.02, 0.01);
  start.linear() = start.linear() * vkloc::expSO3(Eigen::Vector3d(0.0, 2.0 * M_PI / 180.0, 0.0));
  (*localizer)->reset(start);
  auto result = (*localizer)->localize(0, view->gray);
  if (!result.ok()) return fail(result.error().message);
  const double error_m = (result->T_world_camera.translation() - truth->translation()).norm();
  std::printf("%s; state %s, error %.2f mm (started %.1f mm off)\n", (*localizer)->backendSummary().c_str(),
              vkloc::trackingStateName(result->state), error_m * 1e3,
              (start.translation() - truth->translation()).norm() * 1e3);
  if (result->state != vkloc::TrackingState::kTracking || !(error_m < 5e-3)) return fail("the pose was not found");
  return 0;
}
