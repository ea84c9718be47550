// Tests of the sequence simulator's appearance effects, model damage and sequence output,
// against closed-form values and analytic scenes (CPU reference renderer only).
#include "vkloc/sim/simulate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <random>

#include "support/analytic_scenes.hpp"
#include "support/test_support.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// sRGB encode written out independently of the library (IEC 61966-2-1).
double srgbEncodeOracle(double x) { return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055; }

ImageF32 constantImage(int w, int h, float value) { return ImageF32(w, h, 3, value); }

double triangleArea(const Model& m, size_t t) {
  const Eigen::Vector3d a = test::modelVertex(m, m.indices[3 * t]);
  const Eigen::Vector3d b = test::modelVertex(m, m.indices[3 * t + 1]);
  const Eigen::Vector3d c = test::modelVertex(m, m.indices[3 * t + 2]);
  return 0.5 * (b - a).cross(c - a).norm();
}

double modelArea(const Model& m) {
  double sum = 0;
  for (size_t t = 0; t < m.triangleCount(); ++t) sum += triangleArea(m, t);
  return sum;
}

/// A grid of n x n unit quads on z = height(x, y), 2 n^2 triangles, shared vertices.
Model makeGrid(int n, double spacing, double bump = 0.0) {
  Model m;
  m.source = "grid";
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i * spacing, y = j * spacing;
      test::addVertex(m, {x, y, bump * std::sin(0.3 * x) * std::cos(0.2 * y)},
                      {static_cast<double>(i) / n, static_cast<double>(j) / n});
    }
  }
  auto id = [n](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.indices.insert(m.indices.end(),
                       {id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  test::finishSingleBlock(m);
  return m;
}

TEST(SimulateAppearance, SrgbRoundTripIsIdentityOnBytes) {
  ImageU8 rgba(256, 1, 4);
  for (int i = 0; i < 256; ++i) {
    for (int c = 0; c < 3; ++c) rgba.at(i, 0, c) = static_cast<uint8_t>((i + 85 * c) % 256);
    rgba.at(i, 0, 3) = 255;
  }
  const ImageU8 rgb = encodeImage(decodeRender(rgba), 1.0);
  for (int i = 0; i < 256; ++i) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(rgb.at(i, 0, c), rgba.at(i, 0, c)) << i << " " << c;
  }
}

TEST(SimulateAppearance, ExposureWhiteBalanceGammaMatchClosedForm) {
  const double gain = std::exp2(0.5);
  const std::array<double, 3> wb{1.1, 1.0, 0.9};
  const double gamma = 1.3;
  for (double x : {0.001, 0.02, 0.1, 0.3, 0.6}) {
    ImageF32 img = constantImage(4, 3, static_cast<float>(x));
    applyExposure(img, gain, wb);
    const ImageU8 out = encodeImage(img, gamma);
    for (int c = 0; c < 3; ++c) {
      const double lin = std::min(1.0, x * gain * wb[static_cast<size_t>(c)]);
      const double expected = 255.0 * std::pow(srgbEncodeOracle(lin), 1.0 / gamma);
      EXPECT_NEAR(out.at(2, 1, c), expected, 0.51) << "x " << x << " channel " << c;
    }
  }
}

TEST(SimulateAppearance, VignettingIsCosFourthOfRayAngle) {
  PinholeCamera cam{200.0, 180.0, 63.5, 47.5, 128, 96};
  const double strength = 0.7;
  ImageF32 img = constantImage(cam.width, cam.height, 0.5f);
  applyVignetting(img, cam, strength);
  for (auto [u, v] : std::vector<std::pair<int, int>>{{0, 0}, {127, 95}, {64, 48}, {10, 80}, {100, 5}}) {
    // Angle between the pixel's ray and the optical axis.
    const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
    const double theta = std::acos(ray.normalized().z());
    const double expected = 0.5 * (1.0 - strength * (1.0 - std::pow(std::cos(theta), 4)));
    EXPECT_NEAR(img.at(u, v, 1), expected, 1e-6) << u << "," << v;
  }
}

TEST(SimulateAppearance, NoiseSigmaMatchesShotAndReadModel) {
  const double shot = 0.05, read = 0.01;
  for (double level : {0.0, 0.25, 0.8}) {
    ImageF32 img = constantImage(200, 200, static_cast<float>(level));
    addSensorNoise(img, shot, read, 42);
    double mean = 0, var = 0;
    for (float v : img.data) mean += v;
    mean /= static_cast<double>(img.data.size());
    for (float v : img.data) var += (v - mean) * (v - mean);
    const double sigma = std::sqrt(var / static_cast<double>(img.data.size() - 1));
    const double expected = std::sqrt(shot * shot * level + read * read);
    EXPECT_NEAR(sigma, expected, 0.10 * expected) << "level " << level;
    EXPECT_NEAR(mean, level, 0.05 * expected) << "level " << level;
  }
}

TEST(SimulateAppearance, NoiseIsDeterministicInSeed) {
  ImageF32 a = constantImage(32, 32, 0.5f), b = a, c = a;
  addSensorNoise(a, 0.02, 0.01, 7);
  addSensorNoise(b, 0.02, 0.01, 7);
  addSensorNoise(c, 0.02, 0.01, 8);
  EXPECT_EQ(a.data, b.data);
  EXPECT_NE(a.data, c.data);
}

TEST(SimulateAppearance, ColorJitterChangesColoursOnlyAndIsDeterministic) {
  Model m = test::makeCheckerQuad({-1, -1, 0}, {2, 0, 0}, {0, 2, 0}, 4);
  const Model a = jitterModelColors(m, 0.1, 0.03, 3);
  const Model b = jitterModelColors(m, 0.1, 0.03, 3);
  const Model c = jitterModelColors(m, 0.1, 0.03, 4);
  EXPECT_EQ(a.positions, m.positions);
  EXPECT_EQ(a.indices, m.indices);
  EXPECT_EQ(a.textures[0].rgba, b.textures[0].rgba);
  EXPECT_NE(a.textures[0].rgba, m.textures[0].rgba);
  EXPECT_NE(a.textures[0].rgba, c.textures[0].rgba);
  // White texels (255) scale by at most 1.1 and shift by at most 0.03 * 255.
  for (size_t i = 0; i < a.textures[0].rgba.size(); ++i) {
    const int before = m.textures[0].rgba[i];
    const int after = a.textures[0].rgba[i];
    if (i % 4 == 3) {
      EXPECT_EQ(after, before);
    } else {
      EXPECT_LE(std::abs(after - before), static_cast<int>(std::ceil(0.1 * before + 0.03 * 255)) + 1);
    }
  }
}

// A 2 m box on a 20 m plane, lit by the sun at azimuth 0 (from +x), elevation 45 deg, seen from
// 15 m straight above (13 px per metre on the ground). Ground points are shadowed iff the ray towards the sun hits the
// box.
TEST(SimulateAppearance, ShadowsMatchAnalyticShadowRegion) {
  Model scene = test::makePlane({0, 0, 0}, {0, 0, 1}, 10.0);
  const Model box = test::makeBox({-1, -1, 0}, {1, 1, 2});
  const auto offset = static_cast<uint32_t>(scene.vertexCount());
  scene.positions.insert(scene.positions.end(), box.positions.begin(), box.positions.end());
  scene.uvs.insert(scene.uvs.end(), box.uvs.begin(), box.uvs.end());
  for (uint32_t i : box.indices) scene.indices.push_back(i + offset);
  test::finishSingleBlock(scene);

  LightingOptions light;
  light.enabled = true;
  light.sun_azimuth_deg = 0.0;
  light.sun_elevation_deg = 45.0;
  light.shadow_map_size = 512;
  auto factory = cpuRendererFactory();
  auto renderer = factory(scene);
  ASSERT_TRUE(renderer.ok());
  auto map = renderShadowMap(**renderer, scene.bounds, light);
  ASSERT_TRUE(map.ok()) << map.error().message;

  PinholeCamera cam{200.0, 200.0, 79.5, 59.5, 160, 120};
  const Pose T_world_camera = test::cameraLookingAt({0, 0, 15}, {0, 0, 0}, Eigen::Vector3d::UnitY());
  auto view = renderReference(scene, cam, T_world_camera);
  ASSERT_TRUE(view.ok());
  ImageF32 shade = constantImage(cam.width, cam.height, 1.0f);
  applyLighting(shade, *view, cam, T_world_camera, *map, light);

  const Eigen::Vector3d to_sun = sunDirection(0.0, 45.0);
  ASSERT_NEAR(to_sun.x(), std::sqrt(0.5), 1e-12);
  const Eigen::Vector3d lo(-1, -1, 0), hi(1, 1, 2);
  auto shadowed = [&](const Eigen::Vector3d& p) {
    return test::rayBox(test::Ray{p + 1e-9 * to_sun, to_sun}, lo, hi).has_value();
  };
  const double lit_ground = light.ambient + light.direct * to_sun.z();
  const double threshold = 0.5 * (light.ambient + lit_ground);
  int checked = 0, agree = 0, in_shadow = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const test::Ray ray = test::pixelRay(cam, T_world_camera, u, v);
      if (test::rayBox(ray, lo, hi)) continue;  // Box surfaces: not part of the ground test.
      const auto t = test::rayPlane(ray, {0, 0, 0}, {0, 0, 1});
      if (!t) continue;
      const Eigen::Vector3d p = ray.origin + *t * ray.direction;
      if (std::abs(p.x()) > 9.5 || std::abs(p.y()) > 9.5) continue;
      // Away from the shadow boundary: the same status 0.3 m around.
      const bool s = shadowed(p);
      bool interior = true;
      for (double dx : {-0.3, 0.0, 0.3}) {
        for (double dy : {-0.3, 0.0, 0.3}) interior = interior && shadowed(p + Eigen::Vector3d(dx, dy, 0)) == s;
      }
      if (!interior) continue;
      ++checked;
      in_shadow += s;
      const bool dark = shade.at(u, v, 0) < threshold;
      agree += dark == s;
    }
  }
  ASSERT_GT(checked, 10000);
  ASSERT_GT(checked - in_shadow, 5000);
  ASSERT_GT(in_shadow, 300);  // The shadow region (about 2 x 2 m) is in view.
  EXPECT_GE(agree, 0.95 * checked) << agree << " of " << checked;
  EXPECT_GE(agree, checked - 20) << "more than 20 pixels disagree";
}

TEST(SimulateDamage, HoleAreaFractionWithinTwoPoints) {
  const Model grid = makeGrid(60, 1.0);
  for (double fraction : {0.05, 0.2, 0.4}) {
    DamageReport report;
    auto holed = punchHoles(grid, fraction, 3.0, 11, &report);
    ASSERT_TRUE(holed.ok()) << holed.error().message;
    ASSERT_TRUE(validateModel(*holed).ok());
    const double removed = 1.0 - modelArea(*holed) / modelArea(grid);
    EXPECT_NEAR(removed, fraction, 0.02);
    EXPECT_NEAR(report.removed_area_fraction, removed, 1e-6);
    EXPECT_GT(report.hole_patches, 1u);
  }
}

TEST(SimulateDamage, HoleFractionOnDemoRoom) {
  const Model room = makeDemoRoom();
  auto holed = punchHoles(room, 0.2, 0.0, 5);
  ASSERT_TRUE(holed.ok()) << holed.error().message;
  EXPECT_NEAR(1.0 - modelArea(*holed) / modelArea(room), 0.2, 0.02);
}

TEST(SimulateDamage, HolesAreSpatiallyClustered) {
  const Model grid = makeGrid(50, 1.0);
  std::vector<uint32_t> removed;
  auto holed = punchHoles(grid, 0.2, 3.0, 21, nullptr, &removed);
  ASSERT_TRUE(holed.ok());
  ASSERT_FALSE(removed.empty());
  // Random removal of the same number of triangles for comparison.
  std::vector<uint32_t> random_removed(grid.triangleCount());
  std::iota(random_removed.begin(), random_removed.end(), 0u);
  std::mt19937 rng(5);
  std::shuffle(random_removed.begin(), random_removed.end(), rng);
  random_removed.resize(removed.size());

  std::vector<Eigen::Vector3d> centroid(grid.triangleCount());
  for (size_t t = 0; t < centroid.size(); ++t) {
    centroid[t] = (test::modelVertex(grid, grid.indices[3 * t]) + test::modelVertex(grid, grid.indices[3 * t + 1]) +
                   test::modelVertex(grid, grid.indices[3 * t + 2])) /
                  3.0;
  }
  // Mean over removed triangles of the fraction of triangles within 1.5 m that are removed too.
  auto neighbourRemovedFraction = [&](const std::vector<uint32_t>& set) {
    std::vector<char> is_removed(grid.triangleCount(), 0);
    for (uint32_t t : set) is_removed[t] = 1;
    double sum = 0;
    for (uint32_t t : set) {
      int near = 0, near_removed = 0;
      for (size_t k = 0; k < centroid.size(); ++k) {
        if (k == t || (centroid[k] - centroid[t]).squaredNorm() > 1.5 * 1.5) continue;
        ++near;
        near_removed += is_removed[k];
      }
      sum += near ? static_cast<double>(near_removed) / near : 0.0;
    }
    return sum / static_cast<double>(set.size());
  };
  const double clustered = neighbourRemovedFraction(removed);
  const double random = neighbourRemovedFraction(random_removed);
  EXPECT_NEAR(random, 0.2, 0.05);
  EXPECT_GT(clustered, 0.6);
  EXPECT_GT(clustered, 3.0 * random);
}

TEST(SimulateDamage, SimplifyReachesTargetWithinTenPercent) {
  for (double bump : {0.0, 2.0}) {
    const Model grid = makeGrid(60, 1.0, bump);
    for (double ratio : {0.5, 0.2}) {
      auto simple = simplifyModel(grid, ratio);
      ASSERT_TRUE(simple.ok()) << simple.error().message;
      ASSERT_TRUE(validateModel(*simple).ok());
      const double target = ratio * static_cast<double>(grid.triangleCount());
      EXPECT_NEAR(static_cast<double>(simple->triangleCount()), target, 0.1 * target) << "bump " << bump;
    }
  }
  const Model sphere = test::makeUvSphere({0, 0, 0}, 1.0, 64, 32);
  auto simple = simplifyModel(sphere, 0.3);
  ASSERT_TRUE(simple.ok());
  const double target = 0.3 * static_cast<double>(sphere.triangleCount());
  EXPECT_NEAR(static_cast<double>(simple->triangleCount()), target, 0.1 * target);
}

TEST(SimulateDamage, RejectsBadArguments) {
  const Model grid = makeGrid(4, 1.0);
  EXPECT_FALSE(punchHoles(grid, 0.95, 1.0, 1).ok());
  EXPECT_FALSE(punchHoles(grid, -0.1, 1.0, 1).ok());
  EXPECT_FALSE(punchHoles(grid, 0.1, std::nan(""), 1).ok());
  EXPECT_FALSE(simplifyModel(grid, 0.0).ok());
  EXPECT_FALSE(simplifyModel(grid, 1.5).ok());
  Model broken = grid;
  broken.indices[0] = 100000;
  EXPECT_FALSE(punchHoles(broken, 0.1, 1.0, 1).ok());
}

/// A short straight trajectory over a checker plane for frame tests.
SplineTrajectory slideTrajectory() {
  std::vector<Pose> control;
  for (int k = 0; k < 8; ++k) {
    control.push_back(test::cameraLookingAt({0.3 * k - 1.0, 0, 5}, {0.3 * k - 1.0, 0, 0}, Eigen::Vector3d::UnitY()));
  }
  return SplineTrajectory::fromControlPoses(control, 0, 100'000'000).value();
}

TEST(SimulateFrame, AppearanceOffEqualsReferenceRender) {
  const Model plane = test::makeCheckerQuad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}, 16);
  const SplineTrajectory traj = slideTrajectory();
  auto renderer = cpuRendererFactory()(plane);
  ASSERT_TRUE(renderer.ok());
  PinholeCamera cam{80, 80, 39.5, 29.5, 80, 60};
  const int64_t t = traj.startNs() + 123'456'789;
  auto frame = simulateFrame(**renderer, traj, Pose::Identity(), cam, t, AppearanceOptions{}, nullptr, {}, 1);
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  auto direct = renderReference(plane, cam, traj.evaluate(t).T_world_body);
  ASSERT_TRUE(direct.ok());
  const ImageU8 gray = rgbaToGray(direct->rgba);
  ImageU8 frame_rgba(cam.width, cam.height, 4, 255);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(frame->at(x, y, c), direct->rgba.at(x, y, c));
        frame_rgba.at(x, y, c) = frame->at(x, y, c);
      }
    }
  }
  EXPECT_EQ(rgbaToGray(frame_rgba).data, gray.data);
}

TEST(SimulateFrame, OneSubframeBlurEqualsNoBlurAndMoreSubframesBlur) {
  const Model plane = test::makeCheckerQuad({-4, -4, 0}, {8, 0, 0}, {0, 8, 0}, 16);
  const SplineTrajectory traj = slideTrajectory();
  auto renderer = cpuRendererFactory()(plane);
  ASSERT_TRUE(renderer.ok());
  PinholeCamera cam{80, 80, 39.5, 29.5, 80, 60};
  const int64_t t = traj.startNs() + 200'000'000;
  AppearanceOptions none;
  AppearanceOptions one;
  one.motion_blur_subframes = 1;
  one.exposure_time_s = 0.05;
  AppearanceOptions many = one;
  many.motion_blur_subframes = 6;
  auto a = simulateFrame(**renderer, traj, Pose::Identity(), cam, t, none, nullptr, {}, 1);
  auto b = simulateFrame(**renderer, traj, Pose::Identity(), cam, t, one, nullptr, {}, 1);
  auto c = simulateFrame(**renderer, traj, Pose::Identity(), cam, t, many, nullptr, {}, 1);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->data, b->data);
  // The camera moves ~3 m/s: 0.05 s smears checker edges (5 px squares, 0.15 m ~ 2.4 px).
  int changed = 0;
  for (size_t i = 0; i < a->data.size(); ++i) changed += a->data[i] != c->data[i];
  EXPECT_GT(changed, static_cast<int>(a->data.size() / 10));
}

TEST(SimulateFrame, SupersamplingIntegratesPixelsAndKeepsThePixelCentres) {
  // A uniform quad turned 17 deg in its plane, 2.2 m x 1.6 m, 5 m in front of the camera, on the
  // black background: its outline crosses the pixel grid at every phase.
  const double a = 17.0 * M_PI / 180.0;
  const Eigen::Vector3d s(std::cos(a), std::sin(a), 0), t(-std::sin(a), std::cos(a), 0);
  const Eigen::Vector3d centre(-0.62, 0.21, 0);
  const Model quad = test::makeQuad(centre - 1.1 * s - 0.8 * t, 2.2 * s, 1.6 * t);
  const SplineTrajectory traj = slideTrajectory();
  auto renderer = cpuRendererFactory()(quad);
  ASSERT_TRUE(renderer.ok());
  const PinholeCamera cam{80, 80, 39.5, 29.5, 80, 60};
  const int64_t t_ns = traj.startNs() + 150'000'000;
  const Pose T_world_camera = traj.evaluate(t_ns).T_world_body;
  const Eigen::Vector3d c = T_world_camera.inverse() * centre;
  const Eigen::Vector2d centre_px(cam.fx * c.x() / c.z() + cam.cx, cam.fy * c.y() / c.z() + cam.cy);
  struct Measured {
    Eigen::Vector2d centroid_px;
    int partial = 0;  ///< Pixels between the background and the quad's level.
  };
  auto measure = [&](int samples) {
    AppearanceOptions o;
    o.supersampling = samples;
    auto frame = simulateFrame(**renderer, traj, Pose::Identity(), cam, t_ns, o, nullptr, {}, 1);
    EXPECT_TRUE(frame.ok()) << frame.error().message;
    Measured m;
    if (!frame.ok()) return m;
    const ImageU8& rgb = *frame;  // the quad is gray: the red channel stands for all
    uint8_t inside = 0;
    for (size_t i = 0; i < rgb.data.size(); i += 3) inside = std::max(inside, rgb.data[i]);
    double sum = 0, sx = 0, sy = 0;
    for (int y = 0; y < rgb.height; ++y) {
      for (int x = 0; x < rgb.width; ++x) {
        const double v = rgb.at(x, y, 0);
        sum += v;
        sx += v * x;
        sy += v * y;
        m.partial += v > 0.1 * inside && v < 0.9 * inside;
      }
    }
    m.centroid_px = Eigen::Vector2d(sx / sum, sy / sum);
    return m;
  };
  const Measured one = measure(1), four = measure(4);
  // One sample per pixel: a hard outline; four: the outline's pixels take their covered part
  // (the outline is ~110 px long).
  EXPECT_LT(one.partial, 10);
  EXPECT_GT(four.partial, 80);
  // The quad's centre stays where the camera model puts it (a sample grid off by half a large
  // pixel would move it 0.375 px at 4 samples). Gray levels are sRGB-encoded, so the centroid is
  // a little off the area's: 0.15 px.
  EXPECT_LT((one.centroid_px - centre_px).norm(), 0.15);
  EXPECT_LT((four.centroid_px - centre_px).norm(), 0.15);
  AppearanceOptions bad;
  bad.supersampling = 5;
  EXPECT_FALSE(simulateFrame(**renderer, traj, Pose::Identity(), cam, t_ns, bad, nullptr, {}, 1).ok());
}

TEST(SimulateSequence, TinyRoomSequenceLoadsWithMatchingGroundTruth) {
  test::TempDir dir("vkloc_sim");
  const Model room = makeDemoRoom();
  auto options = scenarioOptions("room", "hard", 9, room.bounds);
  ASSERT_TRUE(options.ok()) << options.error().message;
  options->camera.intrinsics = PinholeCamera{40, 40, 31.5, 23.5, 64, 48};
  options->max_frames = 3;
  options->appearance.lighting.shadow_map_size = 128;
  options->appearance.motion_blur_subframes = 2;
  options->damage.simplify_ratio = 0.8;
  const std::string out = dir.file("room_hard");
  size_t last_progress = 0;
  auto report = simulateSequence(room, *options, cpuRendererFactory(), out, [&](size_t done, size_t total) {
    EXPECT_EQ(total, 3u);
    last_progress = done;
  });
  ASSERT_TRUE(report.ok()) << report.error().message;
  EXPECT_EQ(report->frames, 3u);
  EXPECT_EQ(last_progress, 3u);
  EXPECT_NEAR(report->damage.removed_area_fraction, 0.2, 0.02);

  auto seq = loadSequence(out);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  ASSERT_EQ(seq->images.size(), 3u);
  ASSERT_EQ(seq->groundtruth.size(), 3u);
  EXPECT_FALSE(seq->imu.empty());
  EXPECT_TRUE(seq->imu_noise.has_value());
  EXPECT_FALSE(seq->priors.empty());
  EXPECT_EQ(seq->camera.intrinsics.width, 64);
  for (size_t i = 0; i < 3; ++i) {
    auto img = readImageU8(seq->imagePath(i), 4);
    ASSERT_TRUE(img.ok()) << img.error().message;
    EXPECT_EQ(img->width, 64);
  }
  auto model = loadModel(seq->modelPath());
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_LT(model->triangleCount(), room.triangleCount());

  auto traj = simulationTrajectory(*options, room.bounds);
  ASSERT_TRUE(traj.ok());
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(seq->images[i].t_ns, seq->groundtruth[i].t_ns);
    EXPECT_EQ(seq->images[i].t_ns, traj->startNs() + static_cast<int64_t>(i) * 50'000'000);
    const Pose expected = traj->evaluate(seq->images[i].t_ns).T_world_body * options->camera.T_body_camera;
    const Pose& got = seq->groundtruth[i].T_world_camera;
    EXPECT_LT((got.translation() - expected.translation()).norm(), 1e-6);
    EXPECT_LT(Eigen::AngleAxisd(got.linear().transpose() * expected.linear()).angle(), 1e-6);
  }
}

TEST(SimulateSequence, EasyFramesEqualReferenceRenderAtGroundTruth) {
  test::TempDir dir("vkloc_sim");
  const Model room = makeDemoRoom();
  auto options = scenarioOptions("room", "easy", 4, room.bounds);
  ASSERT_TRUE(options.ok());
  options->camera.intrinsics = PinholeCamera{40, 40, 31.5, 23.5, 64, 48};
  options->max_frames = 2;
  const std::string out = dir.file("room_easy");
  auto report = simulateSequence(room, *options, cpuRendererFactory(), out);
  ASSERT_TRUE(report.ok()) << report.error().message;
  auto seq = loadSequence(out);
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  auto model = loadModel(seq->modelPath());
  ASSERT_TRUE(model.ok());
  EXPECT_EQ(model->triangleCount(), room.triangleCount());
  RenderSettings settings;
  settings.near_m = options->near_m;
  settings.far_m = options->far_m;
  auto traj = simulationTrajectory(*options, room.bounds);
  ASSERT_TRUE(traj.ok());
  ASSERT_EQ(seq->images.size(), 2u);
  for (size_t i = 0; i < seq->images.size(); ++i) {
    auto img = readImageU8(seq->imagePath(i), 4);
    ASSERT_TRUE(img.ok());
    const Pose T_world_camera = traj->evaluate(seq->images[i].t_ns).T_world_body * options->camera.T_body_camera;
    auto direct = renderReference(room, options->camera.intrinsics, T_world_camera, settings);
    ASSERT_TRUE(direct.ok());
    int off = 0;
    for (size_t k = 0; k < img->data.size(); ++k) {
      if (k % 4 != 3) off += std::abs(img->data[k] - direct->rgba.data[k]) > 1;
    }
    EXPECT_EQ(off, 0) << "frame " << i;
  }
}

TEST(SimulateSequence, RejectsBadOptions) {
  test::TempDir dir("vkloc_sim");
  const Model plane = test::makePlane({0, 0, 0}, {0, 0, 1}, 5);
  SimulationOptions o;
  o.rate_hz = 0;
  EXPECT_FALSE(simulateSequence(plane, o, cpuRendererFactory(), dir.file("a")).ok());
  o = SimulationOptions{};
  o.appearance.gamma = -1;
  EXPECT_FALSE(simulateSequence(plane, o, cpuRendererFactory(), dir.file("b")).ok());
  o = SimulationOptions{};
  o.damage.hole_fraction = 2;
  EXPECT_FALSE(simulateSequence(plane, o, cpuRendererFactory(), dir.file("c")).ok());
  EXPECT_FALSE(scenarioOptions("moon", "easy", 1, plane.bounds).ok());
  EXPECT_FALSE(scenarioOptions("city", "medium", 1, plane.bounds).ok());
}

}  // namespace
}  // namespace vkloc
