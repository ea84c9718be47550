// Tests of the edge-alignment tracker (edge_tracker.hpp): Jacobians, normal equations, scale
// estimation, and convergence on rendered analytic scenes and the demo city.
#include "vkloc/track/edge_tracker.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "support/analytic_scenes.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/track/edge_backend.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A level whose distance field is the affine function D(u, v) = c + a u + b v with the exact
/// gradient (a, b) everywhere: bilinear interpolation reproduces it exactly, so the residual is
/// smooth and its derivative is known.
LiveLevel affineLevel(int w, int h, double c, double a, double b) {
  LiveLevel level;
  level.camera.width = w;
  level.camera.height = h;
  level.camera.fx = 280;
  level.camera.fy = 270;
  level.camera.cx = w / 2.0 - 0.3;
  level.camera.cy = h / 2.0 + 0.2;
  level.field.truncation_px = 1e6f;
  level.field.distance = ImageF32(w, h, 1);
  level.field.gradient = ImageF32(w, h, 2);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      level.field.distance.at(x, y) = static_cast<float>(c + a * x + b * y);
      level.field.gradient.at(x, y, 0) = static_cast<float>(a);
      level.field.gradient.at(x, y, 1) = static_cast<float>(b);
    }
  }
  return level;
}

std::vector<EdgePoint> randomPoints(int n, uint32_t seed, const PinholeCamera& cam) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(20, cam.width - 20.0), v(20, cam.height - 20.0), z(1.0, 4.0);
  std::vector<EdgePoint> points;
  for (int i = 0; i < n; ++i) {
    const double zz = z(rng);
    EdgePoint p;
    p.x = static_cast<float>(zz * (u(rng) - cam.cx) / cam.fx);
    p.y = static_cast<float>(zz * (v(rng) - cam.cy) / cam.fy);
    p.z = static_cast<float>(zz);
    points.push_back(p);
  }
  return points;
}

Pose smallMotion() {
  Vector6d xi;
  xi << 0.03, -0.02, 0.05, 0.01, -0.015, 0.02;
  return expSE3(xi);
}

TEST(EdgeTrackerMath, AnalyticJacobianMatchesNumericDerivative) {
  const LiveLevel level = affineLevel(320, 240, 400.0, 0.7, -0.45);
  const Pose T = smallMotion();
  const double h = 1e-6;
  int checked = 0;
  for (const EdgePoint& p : randomPoints(50, 3, level.camera)) {
    const EdgePointEvaluation e = evaluateEdgePoint(p, T, level, true);
    ASSERT_TRUE(e.valid);
    Vector6d numeric;
    for (int k = 0; k < 6; ++k) {
      const Vector6d d = h * Vector6d::Unit(k);
      const auto plus = evaluateEdgePoint(p, applyLeftIncrement(T, d), level, false);
      const auto minus = evaluateEdgePoint(p, applyLeftIncrement(T, -d), level, false);
      ASSERT_TRUE(plus.valid && minus.valid);
      numeric[k] = (plus.residual - minus.residual) / (2 * h);
    }
    EXPECT_LT((e.jacobian - numeric).norm() / numeric.norm(), 1e-4)
        << e.jacobian.transpose() << " vs " << numeric.transpose();
    ++checked;
  }
  EXPECT_EQ(checked, 50);
}

TEST(EdgeTrackerMath, NormalEquationsMatchDenseProduct) {
  const LiveLevel level = affineLevel(320, 240, -60.0, 0.3, 0.25);  // residuals of both signs
  const Pose T = smallMotion();
  std::vector<EdgePoint> points = randomPoints(300, 8, level.camera);
  EdgePoint behind;
  behind.z = -1.0f;  // must be skipped
  points.push_back(behind);
  const double sigma = 7.5, nu = 5.0;
  const EdgeNormalEquations packed = accumulateEdgeNormalEquations(points, T, level, sigma, nu);
  Eigen::MatrixXd J(300, 6);
  Eigen::VectorXd r(300), w(300);
  for (int i = 0; i < 300; ++i) {
    const auto e = evaluateEdgePoint(points[i], T, level, true);
    ASSERT_TRUE(e.valid);
    J.row(i) = e.jacobian.transpose();
    r[i] = e.residual;
    w[i] = (nu + 1) / (nu + (r[i] * r[i]) / (sigma * sigma));
  }
  const Eigen::MatrixXd H = J.transpose() * w.asDiagonal() * J;
  const Eigen::VectorXd g = J.transpose() * w.asDiagonal() * r;
  int index = 0;
  for (int row = 0; row < 6; ++row) {
    for (int col = row; col < 6; ++col, ++index) {
      EXPECT_EQ(edgeNormalIndex(row, col), index);
      EXPECT_NEAR(packed[index], H(row, col), 1e-9 * H.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_EQ(index, kEdgeNormalGradientOffset);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(packed[kEdgeNormalGradientOffset + k], g[k], 1e-9 * g.cwiseAbs().maxCoeff());
  EXPECT_NEAR(packed[kEdgeNormalCostIndex], (w.array() * r.array().square()).sum(), 1e-6);
  EXPECT_EQ(packed[kEdgeNormalCountIndex], 300.0);
  Matrix6d H6;
  Vector6d g6;
  unpackEdgeNormalEquations(packed, H6, g6);
  EXPECT_LT((H6 - H).cwiseAbs().maxCoeff(), 1e-9 * H.cwiseAbs().maxCoeff());
}

TEST(EdgeTrackerMath, TDistributionScaleRecoversTrueScale) {
  std::mt19937 rng(21);
  std::student_t_distribution<double> t(5.0);
  for (double sigma : {0.4, 2.5}) {
    std::vector<float> residuals;
    for (int i = 0; i < 40000; ++i) residuals.push_back(static_cast<float>(sigma * t(rng)));
    residuals.push_back(kInvalidResidual);
    // Residuals are signed here (the distance field gives r >= 0; the estimator only uses
    // r^2), so feed |r| and mark invalid as negative: drop the sign by squaring symmetry.
    for (float& r : residuals) {
      if (r != kInvalidResidual) r = std::abs(r);
    }
    EXPECT_NEAR(estimateTDistributionScale(residuals, 5.0, 30), sigma, 0.03 * sigma);
  }
  EXPECT_DOUBLE_EQ(estimateTDistributionScale({kInvalidResidual}, 5.0, 5, 0.05), 0.05);
}

TEST(EdgeTrackerMath, SubpixelEdgeLinesGiveTheDistanceToATiltedStep) {
  // A step edge along the line n . (u, v) = c, n at 20 degrees, c off the pixel grid; pixel
  // values are the area fraction of the pixel on the bright side (box-filtered step).
  const int w = 160, h = 120;
  const double angle = 20.0 * kPi / 180.0;
  const Eigen::Vector2d n(std::cos(angle), std::sin(angle));
  const double c = n.dot(Eigen::Vector2d(80.3, 60.0));
  const ImageU8 gray = test::makeTiltedStepImage(w, h, n, c);
  PinholeCamera cam;
  cam.width = w;
  cam.height = h;
  cam.fx = cam.fy = 200;
  cam.cx = 79.5;
  cam.cy = 59.5;
  LiveFrameOptions options;
  options.levels = 1;
  auto live = buildLiveFrame(gray, cam, options);
  ASSERT_TRUE(live.ok());
  ASSERT_EQ(live->levels[0].edge_lines.channels, 3);
  const Eigen::Vector2d tangent(-n.y(), n.x());
  double worst_on = 0, worst_off = 0;
  for (int k = -20; k <= 20; ++k) {
    for (double offset : {0.0, 0.7, -0.7}) {
      const Eigen::Vector2d uv = n * c + tangent * (1.7 * k) + n * offset;
      EdgePoint p;
      p.x = static_cast<float>((uv.x() - cam.cx) / cam.fx);
      p.y = static_cast<float>((uv.y() - cam.cy) / cam.fy);
      p.z = 1.0f;
      const EdgePointEvaluation e = evaluateEdgePoint(p, Pose::Identity(), live->levels[0], true);
      ASSERT_TRUE(e.valid);
      const double err = std::abs(e.residual - std::abs(offset));
      (offset == 0.0 ? worst_on : worst_off) = std::max(offset == 0.0 ? worst_on : worst_off, err);
      if (offset != 0.0) {
        // The residual's image gradient is the edge normal pointing away from the edge.
        const Eigen::Vector2d g(e.jacobian[0] * p.z / cam.fx, e.jacobian[1] * p.z / cam.fy);
        EXPECT_GT(g.dot(n) * offset, 0.9 * std::abs(offset)) << g.transpose();
      }
    }
  }
  // Measured 0.02 px on the line and 0.03 px at 0.7 px off it (pixel-centre edges: up to 0.5 px).
  EXPECT_LT(worst_on, 0.08);
  EXPECT_LT(worst_off, 0.08);
}

// --- convergence on rendered scenes -------------------------------------------------------------

PinholeCamera smallCamera() {
  PinholeCamera cam;
  cam.width = 320;
  cam.height = 240;
  cam.fx = cam.fy = 262.5;
  cam.cx = 159.5;
  cam.cy = 119.5;
  return cam;
}

/// 640x480: the 1 mm / 0.05 deg target at 2 m is ~0.1 px at 320x240, below what pixel-grid
/// edges from two different viewpoints agree on; at 640x480 it is ~0.25 px.
PinholeCamera vgaCamera() { return PinholeCamera{}; }

Model boxOnGround() { return test::makeBoxOnGround(); }

RenderOutput render(const Model& model, const PinholeCamera& cam, const Pose& T_world_camera) {
  auto view = renderReference(model, cam, T_world_camera);
  EXPECT_TRUE(view.ok()) << (view.ok() ? "" : view.error().message);
  return view.ok() ? std::move(view).value() : RenderOutput{};
}

Pose perturb(const Pose& T, double translation_m, double rotation_deg, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  Eigen::Vector3d dt(n(rng), n(rng), n(rng)), dr(n(rng), n(rng), n(rng));
  Vector6d xi;
  xi.head<3>() = translation_m * dt.normalized();
  xi.tail<3>() = rotation_deg * kPi / 180 * dr.normalized();
  return T * expSE3(xi);  // perturbation in the camera frame
}

struct PoseError {
  double translation_m;
  double rotation_deg;
};

PoseError poseError(const Pose& estimate, const Pose& truth) {
  const Pose d = truth.inverse() * estimate;
  return {d.translation().norm(), logSO3(d.linear()).norm() * 180 / kPi};
}

/// Renders the reference at `T_world_ref` and the live image at `T_world_live`, tracks from
/// the reference pose.
TrackResult trackScene(const Model& model, const PinholeCamera& cam, const Pose& T_world_ref, const Pose& T_world_live,
                       const ImageU8* live_override = nullptr) {
  const RenderOutput ref_view = render(model, cam, T_world_ref);
  auto reference = buildEdgeReference(ref_view, cam, T_world_ref);
  EXPECT_TRUE(reference.ok());
  const RenderOutput live_view = render(model, cam, T_world_live);
  auto live = buildLiveFrame(live_override ? *live_override : live_view.gray, cam);
  EXPECT_TRUE(live.ok());
  if (!reference.ok() || !live.ok()) return {};
  auto result = trackFrame(*reference, *live, T_world_ref);
  EXPECT_TRUE(result.ok());
  return result.ok() ? std::move(result).value() : TrackResult{};
}

TEST(EdgeTracker, ConvergesOnTexturedBoxScene) {
  const Model model = boxOnGround();
  const PinholeCamera cam = vgaCamera();
  const Pose T_gt = test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2});
  for (uint32_t seed : {1u, 2u}) {
    const Pose T_ref = perturb(T_gt, 0.02, 2.0, seed);
    const PoseError before = poseError(T_ref, T_gt);
    const TrackResult r = trackScene(model, cam, T_ref, T_gt);
    const PoseError after = poseError(r.T_world_camera, T_gt);
    EXPECT_EQ(r.state, TrackingState::kTracking);
    // Target 1 mm / 0.05 deg; measured 1.05-1.15 mm / 0.025-0.03 deg with sub-pixel edges
    // (1.3-1.9 mm / 0.02-0.055 deg with pixel-centre distances only).
    EXPECT_LT(after.translation_m, 0.0016) << "before " << before.translation_m << " m";
    EXPECT_LT(after.rotation_deg, 0.05) << "before " << before.rotation_deg << " deg";
    EXPECT_GT(r.quality.inlier_ratio, 0.8);
    EXPECT_TRUE(r.covariance.allFinite());
    EXPECT_GT(r.covariance.diagonal().minCoeff(), 0.0);
    std::printf(
        "box scene seed %u: %.2f mm %.4f deg (from %.1f mm %.2f deg), inliers %.3f, mean %.3f px, %d points, "
        "%d iterations, sigma_t %.2e m\n",
        seed, after.translation_m * 1e3, after.rotation_deg, before.translation_m * 1e3, before.rotation_deg,
        r.quality.inlier_ratio, r.quality.mean_residual_px, r.quality.points_used, r.quality.iterations,
        std::sqrt(r.covariance.topLeftCorner<3, 3>().trace()));
  }
}

TEST(EdgeTracker, PointsNearABackFaceAreCountedAsTheirOwnKind) {
  // The box without its top from above, tracked at the keyframe's pose in its own render: the
  // per-kind counts put points near a back face under index 4 only (the keyframes learn that
  // kind apart from the others).
  const Eigen::Vector3d lo(-0.5, -0.375, 0.0), hi(0.625, 0.5, 1.25);
  const Model model = test::makeBox(lo, hi, true);
  const PinholeCamera cam = vgaCamera();
  const Pose T = test::cameraLookingAt({1.3, -1.5, 3.6}, {0.06, 0.06, 0.4});
  const RenderOutput view = render(model, cam, T);
  auto reference = buildEdgeReference(view, cam, T);
  ASSERT_TRUE(reference.ok());
  std::array<int, 5> expected{};
  for (const EdgePoint& p : reference->points) {
    const uint32_t base = p.kind & ~(kEdgeBackground | kEdgeBackFace);
    ++expected[(p.kind & kEdgeBackFace)     ? 4
               : (p.kind & kEdgeBackground) ? 3
               : base == kEdgeOcclusion     ? 1
               : base == kEdgeCrease        ? 2
                                            : 0];
  }
  ASSERT_GT(expected[4], 50);
  ASSERT_GT(expected[3], 50);
  auto live = buildLiveFrame(view.gray, cam);
  ASSERT_TRUE(live.ok());
  auto r = trackFrame(*reference, *live, T);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->quality.kind_points_in_image, expected);
  EXPECT_EQ(r->quality.points_in_image, expected[0] + expected[1] + expected[2] + expected[3] + expected[4]);
}

// A keyframe render shows texture a camera does not: faint shading of a model's textures (painted
// walls, plaster, wood grain) that the camera's image, under its own light, tone curve and noise,
// does not show. Here every face of the box scene is a plain texture with a dark border and cross
// (the strong edges) over a faint checker, +-10 gray levels in the model, +-2 in the world the
// camera sees through sensor noise (sigma 4 gray levels): a keyframe whose edges include the
// faint checker aligns many of its points to nothing. The keyframes' texture-edge floor
// (keyframeDetector: 13 gray levels per pixel, a step of 26) leaves it out of the keyframe.
Texture faintTexture(int faint) {
  Texture tex;
  tex.name = "faint";
  tex.width = tex.height = 128;
  tex.rgba.assign(static_cast<size_t>(tex.width) * tex.height * 4, 255);
  for (int y = 0; y < tex.height; ++y) {
    for (int x = 0; x < tex.width; ++x) {
      const bool strong = x < 6 || y < 6 || x >= 122 || y >= 122 || std::abs(x - 64) < 3 || std::abs(y - 64) < 3;
      const int v = strong ? 30 : 128 + (((x / 8 + y / 8) % 2 == 0) ? faint : -faint);
      for (int c = 0; c < 3; ++c) tex.rgba[(static_cast<size_t>(y) * tex.width + x) * 4 + c] = static_cast<uint8_t>(v);
    }
  }
  return tex;
}

TEST(EdgeTracker, AKeyframeLeavesOutTextureTheCameraDoesNotShow) {
  Model world = boxOnGround();
  world.textures.front() = faintTexture(2);
  Model model = boxOnGround();
  model.textures.front() = faintTexture(10);
  const PinholeCamera cam = vgaCamera();
  const Pose T_gt = test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2});
  ImageU8 live = render(world, cam, T_gt).gray;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 4.0);
  for (uint8_t& v : live.data) v = static_cast<uint8_t>(std::clamp(std::lround(v + noise(rng)), 0L, 255L));
  auto live_frame = buildLiveFrame(live, cam);
  ASSERT_TRUE(live_frame.ok());
  for (uint32_t seed : {4u, 5u}) {
    const Pose T_ref = perturb(T_gt, 0.02, 1.0, seed);
    const RenderOutput ref_view = render(model, cam, T_ref);
    auto track = [&](double floor) {
      ReferenceEdgeOptions options;
      options.detector.min_high_gradient = floor;
      auto reference = buildEdgeReference(ref_view, cam, T_ref, options);
      EXPECT_TRUE(reference.ok());
      if (!reference.ok()) return TrackResult{};
      auto r = trackFrame(*reference, *live_frame, T_ref);
      EXPECT_TRUE(r.ok());
      return r.ok() ? std::move(r).value() : TrackResult{};
    };
    const TrackResult kept = track(keyframeDetector().min_high_gradient);
    const TrackResult faint = track(6.0);  // the floor before: the faint checker's edges in the keyframe
    const PoseError kept_error = poseError(kept.T_world_camera, T_gt);
    const PoseError faint_error = poseError(faint.T_world_camera, T_gt);
    std::printf(
        "seed %u: default floor: inliers %.3f, %.2f mm %.3f deg, %s; floor 6: inliers %.3f, %.2f mm %.3f deg, %s\n",
        seed, kept.quality.inlier_ratio, kept_error.translation_m * 1e3, kept_error.rotation_deg,
        kept.state == TrackingState::kTracking ? "tracking" : "lost", faint.quality.inlier_ratio,
        faint_error.translation_m * 1e3, faint_error.rotation_deg,
        faint.state == TrackingState::kTracking ? "tracking" : "lost");
    EXPECT_EQ(kept.state, TrackingState::kTracking);
    EXPECT_GT(kept.quality.inlier_ratio, 0.8);
    EXPECT_LT(kept_error.translation_m, 0.003);
    EXPECT_LT(kept_error.rotation_deg, 0.05);
    EXPECT_LT(faint.quality.inlier_ratio, kept.quality.inlier_ratio - 0.2);
  }
}

TEST(EdgeTracker, ReportsLostForFarPoseOrUnrelatedImage) {
  const Model model = boxOnGround();
  const PinholeCamera cam = smallCamera();
  const Pose T_gt = test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2});
  // Far off: the reference view looks 0.6 m and 25 degrees away.
  const TrackResult far = trackScene(model, cam, perturb(T_gt, 0.6, 25.0, 5), T_gt);
  EXPECT_EQ(far.state, TrackingState::kLost)
      << "inliers " << far.quality.inlier_ratio << " mean " << far.quality.mean_residual_px << " visible "
      << far.quality.visible_ratio << " chance " << far.quality.chance_inlier_ratio << " spread "
      << far.quality.spread_ratio << " sigma " << far.quality.scale_px << " error "
      << poseError(far.T_world_camera, T_gt).translation_m;
  // Unrelated live image: a textured sphere somewhere else.
  const Model sphere = test::makeUvSphere({0.3, 0.1, 0.5}, 0.5, 24, 12);
  Model textured = sphere;
  textured.textures = {test::makeBlockChecker(6, 8, 30, 230)};
  textured.materials = {Material{"checker", {1, 1, 1, 1}, 0}};
  const RenderOutput other = render(textured, cam, test::cameraLookingAt({-1.5, 1.0, 1.2}, {0.0, 0.0, 0.4}));
  const TrackResult unrelated = trackScene(model, cam, T_gt, T_gt, &other.gray);
  EXPECT_EQ(unrelated.state, TrackingState::kLost)
      << "inliers " << unrelated.quality.inlier_ratio << " mean " << unrelated.quality.mean_residual_px << " visible "
      << unrelated.quality.visible_ratio << " chance " << unrelated.quality.chance_inlier_ratio << " spread "
      << unrelated.quality.spread_ratio;
  // The same pair with the right image tracks (the thresholds are not simply too strict).
  const TrackResult same = trackScene(model, cam, T_gt, T_gt);
  EXPECT_EQ(same.state, TrackingState::kTracking);
  EXPECT_LT(poseError(same.T_world_camera, T_gt).translation_m, 0.001);
}

TEST(EdgeTracker, ConvergesOnDemoCity) {
  auto city = makeDemoModel("city");
  ASSERT_TRUE(city.ok());
  const std::vector<Pose> views = demoViewpoints("city");
  ASSERT_GE(views.size(), 3u);
  const PinholeCamera cam = smallCamera();
  for (size_t k : {size_t{0}, size_t{2}}) {
    const Pose T_gt = views[k];
    const Pose T_ref = perturb(T_gt, 0.5, 1.0, static_cast<uint32_t>(10 + k));
    const TrackResult r = trackScene(*city, cam, T_ref, T_gt);
    const PoseError after = poseError(r.T_world_camera, T_gt);
    EXPECT_EQ(r.state, TrackingState::kTracking);
    // Target a few cm; measured 53-58 mm, 0.07-0.25 deg from 0.5 m / 1 deg at 320x240 with
    // sub-pixel edges (15-18 cm, 0.1-0.8 deg with pixel-centre distances only).
    EXPECT_LT(after.translation_m, 0.09);
    EXPECT_LT(after.rotation_deg, 0.4);
    std::printf("city view %zu: %.1f mm %.4f deg, inliers %.3f, mean %.3f px, %d points, %d iterations\n", k,
                after.translation_m * 1e3, after.rotation_deg, r.quality.inlier_ratio, r.quality.mean_residual_px,
                r.quality.points_used, r.quality.iterations);
  }
}

// A guess behind the true pose along the optical axis, the keyframe rendered there: aligning
// zooms in and moves the keyframe's outer points out of the image. A step is judged over the
// points inside the image at both poses; when a point that left counted as a truncated one, the
// steps were refused and the alignment stopped short (the demo city from a drone 50 m up, 45 deg
// down, 90-degree view: 0.58 m off from 1 m behind, 0.20 m from 0.5 m; now 0.14 and 0.10 m;
// from ahead 0.03 m either way).
TEST(EdgeTracker, ZoomsInFromAKeyframeMadeFartherBack) {
  auto city = makeDemoModel("city");
  ASSERT_TRUE(city.ok());
  const PinholeCamera cam{160.0, 160.0, 159.5, 119.5, 320, 240};
  const Eigen::Vector3d p(-40.0, -30.0, 50.0);
  const double heading = 60.0 * kPi / 180.0;
  const Pose T_gt = test::cameraLookingAt(p, p + 50.0 * Eigen::Vector3d(std::cos(heading), std::sin(heading), -1.0));
  for (double dz_m : {-1.0, -0.5, 0.5, 1.0}) {
    SCOPED_TRACE(dz_m);
    Pose T_ref = T_gt;
    T_ref.translation() += dz_m * T_gt.linear().col(2);
    const TrackResult r = trackScene(*city, cam, T_ref, T_gt);
    EXPECT_EQ(r.state, TrackingState::kTracking);
    EXPECT_LT(poseError(r.T_world_camera, T_gt).translation_m, 0.2);
  }
}

// A narrow view of the demo city from a drone 50 m up: a small rotation and a translation across
// the view move the edges alike. A prior on the attitude (a gyro's) pins the rotation; the pose
// the edges alone say (T_world_camera_edges, the prior's information taken back out) is the
// alignment without the prior to first order, so a filter that made the prior can fuse it.
TEST(EdgeTracker, ARotationPriorPinsTheAttitudeAndGivesTheEdgesPoseBack) {
  auto city = makeDemoModel("city");
  ASSERT_TRUE(city.ok());
  const PinholeCamera cam{420.0, 420.0, 159.5, 119.5, 320, 240};  // 42 degrees across
  const Eigen::Vector3d p(-40.0, -30.0, 50.0);
  const double heading = 60.0 * kPi / 180.0;
  const Pose T_gt = test::cameraLookingAt(p, p + 50.0 * Eigen::Vector3d(std::cos(heading), std::sin(heading), -1.0));
  const Pose T_ref = perturb(T_gt, 0.6, 0.6, 21);
  const RenderOutput ref_view = render(*city, cam, T_ref);
  auto reference = buildEdgeReference(ref_view, cam, T_ref);
  ASSERT_TRUE(reference.ok());
  auto live = buildLiveFrame(render(*city, cam, T_gt).gray, cam);
  ASSERT_TRUE(live.ok());
  auto trackWith = [&](const std::optional<RotationPrior>& prior) {
    EdgeTrackerOptions options;
    options.rotation_prior = prior;
    auto r = trackFrame(*reference, *live, T_ref, options);
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
    return r.ok() ? std::move(r).value() : TrackResult{};
  };
  const double deg = kPi / 180;
  const TrackResult plain = trackWith(std::nullopt);
  ASSERT_EQ(plain.state, TrackingState::kTracking);
  EXPECT_FALSE(plain.T_world_camera_edges.has_value());
  const PoseError plain_error = poseError(plain.T_world_camera, T_gt);

  // A tight prior at the true attitude (0.005 deg): the rotation follows it, and the translation
  // that the rotation traded against comes with it.
  RotationPrior tight;
  tight.R_world_camera = T_gt.linear();
  tight.covariance = Eigen::Matrix3d::Identity() * std::pow(0.005 * deg, 2);
  const TrackResult pinned = trackWith(tight);
  ASSERT_EQ(pinned.state, TrackingState::kTracking);
  const PoseError pinned_error = poseError(pinned.T_world_camera, T_gt);
  EXPECT_LT(pinned_error.rotation_deg, 0.015);
  EXPECT_LE(pinned_error.rotation_deg, plain_error.rotation_deg);
  EXPECT_LE(pinned_error.translation_m, plain_error.translation_m + 0.005);

  // A prior 0.07 deg off the alignment with a sigma of 0.01 deg: the posterior moves towards it,
  // the edges' pose stays with the plain alignment to first order (measured: it keeps 27-28 % of
  // the posterior's move, from the robust weights changing along it and the solver's tolerance).
  RotationPrior off;
  off.R_world_camera = plain.T_world_camera.linear() * expSO3(Eigen::Vector3d(0.05, -0.04, 0.03) * deg);
  off.covariance = Eigen::Matrix3d::Identity() * std::pow(0.01 * deg, 2);
  const TrackResult pulled = trackWith(off);
  ASSERT_EQ(pulled.state, TrackingState::kTracking);
  ASSERT_TRUE(pulled.T_world_camera_edges.has_value());
  const PoseError moved = poseError(pulled.T_world_camera, plain.T_world_camera);
  const PoseError edges_moved = poseError(*pulled.T_world_camera_edges, plain.T_world_camera);
  EXPECT_GT(moved.rotation_deg, 0.005);
  EXPECT_LT(edges_moved.rotation_deg, 0.4 * moved.rotation_deg);
  EXPECT_LT(edges_moved.translation_m, 0.4 * moved.translation_m);

  // A prior of a radian: the alignment without it.
  RotationPrior loose = off;
  loose.covariance = Eigen::Matrix3d::Identity();
  const TrackResult unpinned = trackWith(loose);
  EXPECT_LT(poseError(unpinned.T_world_camera, plain.T_world_camera).translation_m, 1e-3);
  EXPECT_LT(poseError(*unpinned.T_world_camera_edges, plain.T_world_camera).translation_m, 1e-3);
  std::printf(
      "narrow city view: plain %.1f mm %.4f deg; prior at the truth %.1f mm %.4f deg; prior off: posterior moved "
      "%.1f mm %.4f deg, edges' pose %.1f mm %.4f deg\n",
      plain_error.translation_m * 1e3, plain_error.rotation_deg, pinned_error.translation_m * 1e3,
      pinned_error.rotation_deg, moved.translation_m * 1e3, moved.rotation_deg, edges_moved.translation_m * 1e3,
      edges_moved.rotation_deg);
}

// Timing loop (not a pass/fail test): per-stage CPU times at 640x480 on a demo city view.
// Run with --gtest_also_run_disabled_tests --gtest_filter='*StageTimings*'.
TEST(EdgeTracker, DISABLED_StageTimings640x480) {
  auto city = makeDemoModel("city");
  ASSERT_TRUE(city.ok());
  const PinholeCamera cam = vgaCamera();
  const Pose T_gt = demoViewpoints("city")[2];
  const Pose T_ref = perturb(T_gt, 0.5, 1.0, 3);
  const RenderOutput live_view = render(*city, cam, T_gt);
  const RenderOutput ref_view = render(*city, cam, T_ref);
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
  const int runs = 20;
  double t_live_plain = 0;
  double t_pyr = 0, t_edges = 0, t_dt = 0, t_live = 0, t_ref = 0, t_track = 0, t_resid = 0, t_normal = 0;
  int iterations = 0;
  for (int k = 0; k < runs; ++k) {
    auto t0 = Clock::now();
    ImageF32 g = toFloat(live_view.gray);
    ImageF32 g1 = downsampleHalf(g);
    ImageF32 g2 = downsampleHalf(g1);
    auto t1 = Clock::now();
    auto e = detectEdges(g);
    auto t2 = Clock::now();
    auto f = computeDistanceField(*e, 20.0f);
    auto t3 = Clock::now();
    auto live = buildLiveFrame(live_view.gray, cam);
    auto t4 = Clock::now();
    {
      LiveFrameOptions no_lines;
      no_lines.subpixel_edges = false;
      auto tl = Clock::now();
      auto plain = buildLiveFrame(live_view.gray, cam, no_lines);
      t_live_plain += ms(Clock::now() - tl);
    }
    auto ref = buildEdgeReference(ref_view, cam, T_ref);
    auto t5 = Clock::now();
    auto r = trackFrame(*ref, *live, T_ref);
    auto t6 = Clock::now();
    const Pose T_cr = T_gt.inverse() * T_ref;
    auto res = evaluateEdgeResiduals(ref->points, T_cr, live->levels[0]);
    auto t7 = Clock::now();
    auto eq = accumulateEdgeNormalEquations(ref->points, T_cr, live->levels[0], 1.0, 5.0);
    auto t8 = Clock::now();
    ASSERT_TRUE(e.ok() && f.ok() && live.ok() && ref.ok() && r.ok() && !res.empty() && eq[28] > 0);
    t_pyr += ms(t1 - t0);
    t_edges += ms(t2 - t1);
    t_dt += ms(t3 - t2);
    t_live += ms(t4 - t3);
    t_ref += ms(t5 - t4);
    t_track += ms(t6 - t5);
    t_resid += ms(t7 - t6);
    t_normal += ms(t8 - t7);
    iterations = r->quality.iterations;
    if (k == 0) std::printf("reference level-0 points: %zu\n", ref->points.size());
  }
  std::printf(
      "640x480 mean of %d runs (ms): gray->float + 2 pyramid halvings %.2f | edges level 0 %.2f | "
      "distance field + gradient level 0 %.2f | buildLiveFrame (3 levels) %.2f, without sub-pixel edge lines "
      "%.2f | buildEdgeReference (3 levels) "
      "%.2f | trackFrame %.2f (%d GN iterations) | residuals level 0 %.3f | normal equations level 0 %.3f\n",
      runs, t_pyr / runs, t_edges / runs, t_dt / runs, t_live / runs, t_live_plain / runs, t_ref / runs, t_track / runs,
      iterations, t_resid / runs, t_normal / runs);
}

/// Backend that forwards to CpuEdgeAlignment, counts calls and can fail on request.
class RecordingBackend : public EdgeAlignmentBackend {
 public:
  explicit RecordingBackend(const LiveFrame& live) : cpu_(live) {}
  int levelCount() const override { return cpu_.levelCount(); }
  PinholeCamera levelCamera(int level) const override { return cpu_.levelCamera(level); }
  float truncationPx(int level) const override { return cpu_.truncationPx(level); }
  Status setPoints(const std::vector<EdgePoint>& points) override {
    ++set_points_calls;
    return cpu_.setPoints(points);
  }
  Result<std::vector<float>> residuals(int level, const Pose& T_camera_ref) override {
    ++residual_calls;
    if (fail_residuals) return makeError(ErrorCode::kGpuError, "test backend: device lost");
    return cpu_.residuals(level, T_camera_ref);
  }
  Result<EdgeNormalEquations> accumulate(int level, const Pose& T_camera_ref, double sigma_px, double nu) override {
    ++accumulate_calls;
    if (astray_step_m > 0) {
      // Normal equations whose undamped step is astray_step_m along x.
      EdgeNormalEquations eq{};
      for (int i = 0; i < 6; ++i) eq[edgeNormalIndex(i, i)] = 1e3;
      eq[kEdgeNormalGradientOffset] = -1e3 * astray_step_m;
      eq[kEdgeNormalCountIndex] = 1000;
      return eq;
    }
    return cpu_.accumulate(level, T_camera_ref, sigma_px, nu);
  }
  Result<double> nearEdgeFraction(int level, double threshold_px) override {
    return cpu_.nearEdgeFraction(level, threshold_px);
  }
  int set_points_calls = 0;
  int residual_calls = 0;
  int accumulate_calls = 0;
  bool fail_residuals = false;
  double astray_step_m = 0;  ///< > 0: accumulate() asks for this step along x (metres).

 private:
  CpuEdgeAlignment cpu_;
};

TEST(EdgeTrackerBackend, SeamGivesTheLiveFrameResultAndPropagatesErrors) {
  const Model model = boxOnGround();
  const PinholeCamera cam = smallCamera();
  const Pose T_gt = test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2});
  const Pose T_ref = perturb(T_gt, 0.02, 2.0, 4);
  auto reference = buildEdgeReference(render(model, cam, T_ref), cam, T_ref);
  auto live = buildLiveFrame(render(model, cam, T_gt).gray, cam);
  ASSERT_TRUE(reference.ok() && live.ok());
  EdgeTrackerOptions options;
  options.coarsest_level = -1;             // all 3 levels
  options.far_first_depth_quantile = 0.0;  // one hypothesis: one upload per level
  auto direct = trackFrame(*reference, *live, T_ref, options);
  RecordingBackend backend(*live);
  auto seam = trackFrame(*reference, backend, T_ref, options);
  ASSERT_TRUE(direct.ok() && seam.ok());
  EXPECT_EQ(seam->state, TrackingState::kTracking);
  EXPECT_TRUE(seam->T_camera_ref.isApprox(direct->T_camera_ref, 0.0));  // same arithmetic: bit-identical
  EXPECT_EQ(seam->quality.iterations, direct->quality.iterations);
  EXPECT_EQ(seam->quality.points_used, direct->quality.points_used);
  EXPECT_LT(poseError(seam->T_world_camera, T_gt).translation_m, 0.005);
  // One upload per level (3 levels; the finest level's list is reused for the quality).
  EXPECT_EQ(backend.set_points_calls, static_cast<int>(live->levels.size()));
  // Per Gauss-Newton iteration one residual evaluation (the default evaluate()), plus one per
  // level start and for the final quality; the normal equations once per pose: at each level
  // start and after each accepted step (a rejected step re-solves with more damping only), and
  // once for the final covariance.
  const int levels = static_cast<int>(live->levels.size());
  EXPECT_LE(backend.residual_calls, seam->quality.iterations + levels + 2);
  EXPECT_GE(backend.accumulate_calls, levels);
  EXPECT_LE(backend.accumulate_calls, seam->quality.iterations + levels + 1);
  backend.fail_residuals = true;
  auto failed = trackFrame(*reference, backend, T_ref, options);
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::kGpuError);
}

// A step that would take every point out of the image has no point left to judge it by (a
// point that leaves the image counts for nothing): it is refused, as any step that takes more
// than half of the points in view out of it, and the damped steps that follow stay in view.
TEST(EdgeTrackerBackend, AStepThatTakesThePointsOutOfViewIsRefused) {
  const Model model = boxOnGround();
  const PinholeCamera cam = smallCamera();
  const Pose T_gt = test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2});
  auto reference = buildEdgeReference(render(model, cam, T_gt), cam, T_gt);
  auto live = buildLiveFrame(render(model, cam, T_gt).gray, cam);
  ASSERT_TRUE(reference.ok() && live.ok());
  EdgeTrackerOptions options;
  options.far_first_depth_quantile = 0.0;
  RecordingBackend backend(*live);
  backend.astray_step_m = 20.0;
  auto r = trackFrame(*reference, backend, T_gt, options);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_LT(poseError(r->T_world_camera, T_gt).translation_m, 0.5);
}

TEST(EdgeTrackerBackend, CpuBackendChecksLevelsAndCountsNearEdgePixels) {
  // Distance field 0, 1, 2, ... along u (10 x 4): 3 of 10 columns are below 2.5 px.
  LiveLevel level = affineLevel(10, 4, 0.0, 1.0, 0.0);
  level.field.truncation_px = 20.0f;
  LiveFrame live;
  live.levels = {level};
  CpuEdgeAlignment backend(live);
  EXPECT_EQ(backend.levelCount(), 1);
  auto fraction = backend.nearEdgeFraction(0, 2.5);
  ASSERT_TRUE(fraction.ok());
  EXPECT_DOUBLE_EQ(*fraction, 0.3);
  EXPECT_FALSE(backend.nearEdgeFraction(1, 2.5).ok());
  EXPECT_FALSE(backend.residuals(-1, Pose::Identity()).ok());
  EXPECT_FALSE(backend.accumulate(0, Pose::Identity(), 0.0, 5.0).ok());
  ASSERT_TRUE(backend.setPoints({}).ok());
  auto empty = backend.accumulate(0, Pose::Identity(), 1.0, 5.0);
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ((*empty)[kEdgeNormalCountIndex], 0.0);
}

// The CPU backend builds the levels it is asked for (0 or more than its options': all), and those
// are the same as the full frame's: a frame that needs no deep search level skips building it.
TEST(EdgeTrackerBackend, CpuBackendBuildsTheLevelsAskedFor) {
  const PinholeCamera cam = vgaCamera();
  const RenderOutput view = render(boxOnGround(), cam, test::cameraLookingAt({1.2, -1.4, 1.0}, {0.0, 0.0, 0.2}));
  LiveFrameOptions options;
  options.levels = 3;
  auto created = CpuEdgeTrackingBackend::create(cam, options);
  ASSERT_TRUE(created.ok()) << created.error().message;
  CpuEdgeTrackingBackend& backend = **created;
  for (int asked : {0, 3, 8, 1, 2, 3}) {
    SCOPED_TRACE(asked);
    auto built = backend.setLiveImage(view.gray, asked);
    ASSERT_TRUE(built.ok());
    const int expected = asked == 0 || asked > 3 ? 3 : asked;
    EXPECT_EQ(*built, expected);
    ASSERT_EQ(static_cast<int>(backend.liveFrame().levels.size()), expected);
    LiveFrameOptions one = options;
    one.keep_intermediate = false;
    one.distance_gradient = false;
    auto full = buildLiveFrame(view.gray, cam, one);
    ASSERT_TRUE(full.ok());
    for (int k = 0; k < expected; ++k) {
      const LiveLevel& a = backend.liveFrame().levels[static_cast<size_t>(k)];
      const LiveLevel& b = full->levels[static_cast<size_t>(k)];
      EXPECT_EQ(a.field.distance.data, b.field.distance.data) << k;
      EXPECT_EQ(a.edge_lines.data, b.edge_lines.data) << k;
    }
  }
  EXPECT_FALSE(backend.setLiveImage(ImageU8(8, 8, 1, 0), 1).ok());  // not the camera's size
}

TEST(EdgeTracker, RejectsBadInput) {
  const LiveLevel level = affineLevel(64, 48, 5, 0.1, 0.1);
  LiveFrame live;
  live.levels = {level};
  EdgeReference ref;
  ref.camera = level.camera;
  EXPECT_FALSE(trackFrame(ref, live, Pose::Identity()).ok());  // no points
  ref.points = randomPoints(40, 1, level.camera);
  Pose bad = Pose::Identity();
  bad.linear() *= 2.0;
  EXPECT_FALSE(trackFrame(ref, live, bad).ok());
  EXPECT_FALSE(trackFrame(ref, LiveFrame{}, Pose::Identity()).ok());
  EdgeTrackerOptions options;
  options.finest_level = 3;
  EXPECT_FALSE(trackFrame(ref, live, Pose::Identity(), options).ok());
  LiveFrame broken = live;
  broken.levels[0].field.gradient = ImageF32(3, 3, 2);
  EXPECT_FALSE(trackFrame(ref, broken, Pose::Identity()).ok());
  EdgeTrackerOptions far;
  far.far_first_depth_quantile = 1.5;
  EXPECT_FALSE(validateEdgeTrackerOptions(far).ok());
  far.far_first_depth_quantile = 0.3;
  far.far_first_coarsest_level = -2;
  EXPECT_FALSE(validateEdgeTrackerOptions(far).ok());
  // A rotation prior must be a rotation with a finite, symmetric, positive definite covariance.
  EdgeTrackerOptions prior;
  prior.rotation_prior = RotationPrior{};
  EXPECT_TRUE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior->R_world_camera(0, 0) = 2.0;
  EXPECT_FALSE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior = RotationPrior{};
  prior.rotation_prior->covariance(1, 1) = -1.0;
  EXPECT_FALSE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior->covariance = Eigen::Matrix3d::Zero();
  EXPECT_FALSE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior->covariance = Eigen::Matrix3d::Identity();
  prior.rotation_prior->covariance(0, 2) = 0.5;
  EXPECT_FALSE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior->covariance = Eigen::Matrix3d::Identity() * std::nan("");
  EXPECT_FALSE(validateEdgeTrackerOptions(prior).ok());
  prior.rotation_prior->covariance = -Eigen::Matrix3d::Identity();
  auto refused = trackFrame(ref, live, Pose::Identity(), prior);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace vkloc
