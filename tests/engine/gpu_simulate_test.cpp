// GPU tests of the sequence simulator: frames rendered through GpuRenderer.
#include <filesystem>
#include <map>

#include "support/analytic_scenes.hpp"
#include "support/gpu_test_support.hpp"
#include "support/test_support.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc {
namespace {

using SimulateGpu = test::GpuTest;

TEST_F(SimulateGpu, AppearanceOffFrameEqualsRendererOutput) {
  const Model room = makeDemoRoom();
  SimulationOptions options;
  options.trajectory = TrajectoryKind::kHandheld;
  options.duration_s = 2.0;
  options.camera.T_body_camera = defaultBodyCamera(options.trajectory);
  auto traj = simulationTrajectory(options, room.bounds);
  ASSERT_TRUE(traj.ok()) << traj.error().message;
  auto renderer = gpuRendererFactory(context_)(room);
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  auto direct_renderer = GpuRenderer::create(context_, room);
  ASSERT_TRUE(direct_renderer.ok());
  const PinholeCamera cam{120.0, 120.0, 79.5, 59.5, 160, 120};
  RenderSettings settings;
  for (int64_t dt : {int64_t{0}, int64_t{700'000'000}}) {
    const int64_t t = traj->startNs() + dt;
    auto frame = simulateFrame(**renderer, *traj, options.camera.T_body_camera, cam, t, AppearanceOptions{}, nullptr,
                               settings, 1);
    ASSERT_TRUE(frame.ok()) << frame.error().message;
    const Pose T_world_camera = traj->evaluate(t).T_world_body * options.camera.T_body_camera;
    auto direct = (*direct_renderer)->render(cam, T_world_camera, settings);
    ASSERT_TRUE(direct.ok());
    ImageU8 rgba(cam.width, cam.height, 4, 255);
    int off = 0;
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        for (int c = 0; c < 3; ++c) {
          off += frame->at(x, y, c) != direct->rgba.at(x, y, c);
          rgba.at(x, y, c) = frame->at(x, y, c);
        }
      }
    }
    EXPECT_EQ(off, 0);
    const ImageU8 gray = rgbaToGray(rgba);
    int gray_off = 0;
    for (size_t i = 0; i < gray.data.size(); ++i) gray_off += std::abs(gray.data[i] - direct->gray.data[i]) > 1;
    EXPECT_EQ(gray_off, 0);
  }
}

/// Every regular file under `dir` with its bytes, by relative path.
std::map<std::string, std::vector<uint8_t>> folderBytes(const std::filesystem::path& dir) {
  std::map<std::string, std::vector<uint8_t>> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file()) {
      files[std::filesystem::relative(entry.path(), dir).string()] = test::readFile(entry.path().string());
    }
  }
  return files;
}

TEST_F(SimulateGpu, SameSeedGivesIdenticalFilesOtherSeedDiffers) {
  test::TempDir dir("vkloc_sim_gpu");
  const Model room = makeDemoRoom();
  auto run = [&](uint64_t seed, const std::string& name) {
    auto options = scenarioOptions("room", "hard", seed, room.bounds);
    EXPECT_TRUE(options.ok());
    options->camera.intrinsics = PinholeCamera{80, 80, 47.5, 35.5, 96, 72};
    options->max_frames = 2;
    options->appearance.lighting.shadow_map_size = 256;
    auto report = simulateSequence(room, *options, gpuRendererFactory(context_), dir.file(name));
    EXPECT_TRUE(report.ok()) << report.error().message;
    return folderBytes(dir.file(name));
  };
  const auto a = run(3, "a");
  const auto b = run(3, "b");
  const auto c = run(4, "c");
  ASSERT_TRUE(a.count("images/000001.jpg"));
  ASSERT_TRUE(a.count("groundtruth.txt"));
  EXPECT_EQ(a, b);
  EXPECT_NE(a.at("images/000000.jpg"), c.at("images/000000.jpg"));
  EXPECT_NE(a.at("groundtruth.txt"), c.at("groundtruth.txt"));
}

}  // namespace
}  // namespace vkloc
