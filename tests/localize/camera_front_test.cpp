// The camera front (lens image -> tracker view) and tracking through it, without Vulkan: radial-
// tangential and fisheye lenses on the box scene, undistorted and stabilised views, the view
// wrapper of the motion prior, and bad input.
#include "vkloc/localize/camera_front.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "localize/localize_scene.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc {
namespace {

constexpr int64_t kFrameNs = 50'000'000;

/// A radial-tangential lens with the scene camera's intrinsics (barrel distortion).
LensCamera radtanLens() {
  LensCamera lens;
  lens.intrinsics = test::localizeCamera();
  lens.k = {-0.25, 0.06, 3e-4, -2e-4, 0.0};
  return lens;
}

/// A wide equidistant lens (120 deg field of view).
LensCamera fisheyeLens() {
  LensCamera lens;
  lens.model = LensModel::kKannalaBrandt;
  lens.intrinsics = PinholeCamera{140.0, 140.0, 199.5, 199.5, 400, 400};
  lens.k = {0.01, -0.002, 0.0, 0.0, 0.0};
  lens.max_angle_deg = 60.0;
  return lens;
}

/// The lens image of the box scene at T_world_camera (gray, through the simulator's rig).
ImageU8 lensImage(Renderer& renderer, const LensRig& rig, const Pose& T_world_camera) {
  std::vector<ImageF32> faces;
  for (size_t f = 0; f < rig.faces.size(); ++f) {
    auto r = renderer.render(rig.faces[f], T_world_camera * rig.T_camera_face[f], RenderSettings{});
    EXPECT_TRUE(r.ok());
    faces.push_back(decodeRender(r->rgba));
  }
  const ImageU8 rgb = encodeImage(resampleLens(rig, faces), 1.0);
  ImageU8 gray(rgb.width, rgb.height, 1);
  for (size_t i = 0; i < gray.data.size(); ++i) {
    gray.data[i] = static_cast<uint8_t>(
        std::lround(0.299 * rgb.data[3 * i] + 0.587 * rgb.data[3 * i + 1] + 0.114 * rgb.data[3 * i + 2]));
  }
  return gray;
}

ImageU8 randomImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255);
  ImageU8 img(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) img.at(x, y) = static_cast<uint8_t>((x / 7 + y / 5) % 2 ? 200 : 40);
  }
  for (uint8_t& v : img.data) v = static_cast<uint8_t>(std::clamp(v + value(rng) / 32 - 4, 0, 255));
  return img;
}

TEST(CameraFront, UndistortedPinholeKeepsTheIntrinsicsAndAnIdealLensIsTheIdentity) {
  auto front = CameraFront::create(radtanLens(), ViewOptions{});
  ASSERT_TRUE(front.ok()) << front.error().message;
  EXPECT_FALSE((*front)->identity());
  EXPECT_TRUE((*front)->needsRemap());
  EXPECT_EQ((*front)->view().fx, radtanLens().intrinsics.fx);
  EXPECT_EQ((*front)->view().width, 320);
  EXPECT_TRUE((*front)->viewRotation(Eigen::Matrix3d::Identity()).isIdentity());
  LensCamera ideal;
  ideal.intrinsics = test::localizeCamera();
  auto same = CameraFront::create(ideal, ViewOptions{});
  ASSERT_TRUE(same.ok());
  EXPECT_TRUE((*same)->identity());
  EXPECT_FALSE((*same)->needsRemap());
  const ImageU8 img = randomImage(320, 240, 3);
  ImageU8 out;
  ASSERT_TRUE((*same)->remap(img, Eigen::Matrix3d::Identity(), out).ok());
  EXPECT_EQ(out.data, img.data);
}

TEST(CameraFront, OpenCvRemapMatchesTheReference) {
  // The fast path (OpenCV, positions in 1/32 px fixed point) against remapBilinear (float) on a
  // rendered image: within 1 gray level on 99 % of the pixels and 8 everywhere (the fixed point
  // moves an edge by up to 1/64 px: a few levels on the strongest edges).
  ViewOptions bilinear;
  bilinear.interpolation = RemapInterpolation::kBilinear;
  auto front = CameraFront::create(radtanLens(), bilinear);
  ASSERT_TRUE(front.ok());
  const ImageU8& img = test::localizeFrames(1)[0];
  ImageU8 fast;
  ASSERT_TRUE((*front)->remap(img, Eigen::Matrix3d::Identity(), fast).ok());
  auto reference = remapBilinear(img, (*front)->table(Eigen::Matrix3d::Identity()));
  ASSERT_TRUE(reference.ok());
  size_t close = 0;
  int worst = 0;
  for (size_t i = 0; i < fast.data.size(); ++i) {
    const int d = std::abs(fast.data[i] - reference->data[i]);
    close += d <= 1 ? 1 : 0;
    worst = std::max(worst, d);
  }
  EXPECT_GT(static_cast<double>(close) / static_cast<double>(fast.data.size()), 0.99);
  EXPECT_LE(worst, 8);
  EXPECT_GT((*front)->validFraction(), 0.99);
}

TEST(CameraFront, BicubicRemapIsTheFixedPointPathOnEveryRowAndZeroesPixelsWithoutASource) {
  // The default interpolation on the CPU: remapBicubicFixedRows over stripes of rows on OpenCV's
  // threads, equal pixel for pixel to the one-thread remapBicubicFixed of the same table, for views
  // of few rows too (fewer than a stripe's 16); pixels without a source are 0.
  for (const int height : {7, 17, 150}) {
    ViewOptions o;
    o.kind = ViewKind::kStabilised;
    o.width = 200;
    o.height = height;
    o.hfov_deg = 110;  // the 120-deg lens's field ends inside the view's corners: pixels without a source
    o.dead_band_deg = 0;
    auto front = CameraFront::create(fisheyeLens(), o);
    ASSERT_TRUE(front.ok()) << front.error().message;
    const ImageU8 img = randomImage(400, 400, 5);
    const Eigen::Matrix3d R = (*front)->viewRotation(Eigen::Matrix3d::Identity());
    ImageU8 view;
    ASSERT_TRUE((*front)->remap(img, R, view).ok());
    const RemapTable& table = (*front)->table(R);
    auto expected = remapBicubicFixed(img, table);
    ASSERT_TRUE(expected.ok());
    EXPECT_EQ(view.data, expected->data) << height;
    size_t without_source = 0;
    for (size_t i = 0; i < view.data.size(); ++i) {
      const float u = table.uv[2 * i], v = table.uv[2 * i + 1];
      if (!(u >= 0 && v >= 0 && u <= static_cast<float>(table.source_width - 1) &&
            v <= static_cast<float>(table.source_height - 1))) {
        ++without_source;
        EXPECT_EQ(view.data[i], 0) << i;
      }
    }
    EXPECT_GT(without_source, 0u) << height;
  }
}

/// A 200x150 stabilised view with its axis 30 deg below the horizon.
ViewOptions stabilisedThirtyDown() {
  ViewOptions o;
  o.kind = ViewKind::kStabilised;
  o.width = 200;
  o.height = 150;
  o.pitch_deg = 30;
  o.dead_band_deg = 0;  // every frame fully compensated
  return o;
}

/// A camera looking 30 deg down along heading psi (rad), then turned by yaw_rad about its own
/// axis and pitched by pitch_rad.
Eigen::Matrix3d shakenCamera(double psi, double yaw_rad, double pitch_rad) {
  const Pose level = test::cameraLookingAt({0, 0, 0}, {std::cos(psi), std::sin(psi), -std::tan(M_PI / 6)});
  return level.linear() * Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
         Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

TEST(CameraFront, StabilisedViewHoldsItsPitchWithoutRollAndFollowsTheHeading) {
  const ViewOptions o = stabilisedThirtyDown();
  auto front = CameraFront::create(fisheyeLens(), o);
  ASSERT_TRUE(front.ok()) << front.error().message;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-0.4, 0.4);
  for (int k = 0; k < 50; ++k) {
    // A camera looking 30 deg down along heading psi, then rolled and pitched at random.
    const double psi = 6.0 * U(rng);
    const double yaw = U(rng);
    const Eigen::Matrix3d R_world_camera = shakenCamera(psi, yaw, U(rng));
    const Eigen::Matrix3d R_world_view = R_world_camera * (*front)->viewRotation(R_world_camera);
    EXPECT_NEAR(R_world_view.determinant(), 1.0, 1e-12);
    // Axis 30 deg below the horizon, x axis level (no roll).
    EXPECT_NEAR(std::asin(-R_world_view(2, 2)) * 180 / M_PI, 30.0, 1e-9);
    EXPECT_NEAR(R_world_view(2, 0), 0.0, 1e-12);
    // Heading within the perturbation of the camera's.
    const double view_heading = std::atan2(R_world_view(1, 2), R_world_view(0, 2));
    EXPECT_LT(std::abs(std::remainder(view_heading - psi, 2 * M_PI)), 0.6);
  }
  // Cameras looking steeply up or straight down along +x: the view still heads along +x.
  for (double elevation : {60.0, 85.0, -89.0, -60.0}) {
    const double e = elevation * M_PI / 180;
    const Pose camera = test::cameraLookingAt({0, 0, 0}, {std::cos(e), 0, std::sin(e)}, {0, 0, 1});
    const Eigen::Matrix3d R_world_view = camera.linear() * (*front)->viewRotation(camera.linear());
    EXPECT_GT(R_world_view(0, 2), 0.5) << elevation << " deg";
    EXPECT_NEAR(R_world_view(1, 2), 0.0, 1e-9) << elevation << " deg";
  }
}

TEST(CameraFront, ADeadBandKeepsTheLensViewUntilTheCompensationExceedsIt) {
  ViewOptions o = stabilisedThirtyDown();
  auto full = CameraFront::create(fisheyeLens(), o);
  o.dead_band_deg = 10;
  auto banded = CameraFront::create(fisheyeLens(), o);
  ASSERT_TRUE(full.ok() && banded.ok());
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> U(-0.3, 0.3);
  int inside = 0, outside = 0;
  for (int k = 0; k < 100; ++k) {
    const double yaw = U(rng);
    const Eigen::Matrix3d R_world_camera = shakenCamera(0.0, yaw, U(rng));
    const Eigen::AngleAxisd compensation((*full)->viewRotation(R_world_camera));
    const Eigen::Matrix3d R_camera_view = (*banded)->viewRotation(R_world_camera);
    EXPECT_NEAR(R_camera_view.determinant(), 1.0, 1e-12);
    const Eigen::AngleAxisd turn(R_camera_view);
    if (compensation.angle() <= 10 * M_PI / 180) {
      // Within the band: the lens's own view.
      EXPECT_TRUE(R_camera_view.isIdentity(1e-12)) << k;
      ++inside;
    } else {
      // Beyond: the excess about the same axis, so the view's axis lies 10 deg from the
      // stabilised one.
      EXPECT_NEAR(turn.angle(), compensation.angle() - 10 * M_PI / 180, 1e-9) << k;
      EXPECT_GT(turn.axis().dot(compensation.axis()), 1 - 1e-9) << k;
      const Eigen::Matrix3d R_view_stabilised = R_camera_view.transpose() * compensation.toRotationMatrix();
      EXPECT_NEAR(Eigen::AngleAxisd(R_view_stabilised).angle() * 180 / M_PI, 10.0, 1e-6) << k;
      ++outside;
    }
  }
  EXPECT_GT(inside, 10);
  EXPECT_GT(outside, 10);
  o.dead_band_deg = -1;
  EXPECT_FALSE(CameraFront::create(fisheyeLens(), o).ok());
  o.dead_band_deg = NAN;
  EXPECT_FALSE(CameraFront::create(fisheyeLens(), o).ok());
}

TEST(CameraFront, AStabilisedViewInsideItsDeadBandIsTheUndistortedViewPixelForPixel) {
  // The lens's own view through the stabilised path is the undistorted view's exact table, kept
  // across frames whose view turned (not the grid's interpolation of it).
  ViewOptions o = stabilisedThirtyDown();
  o.dead_band_deg = 10;
  auto banded = CameraFront::create(fisheyeLens(), o);
  o.kind = ViewKind::kUndistorted;
  o.dead_band_deg = 0;
  auto undistorted = CameraFront::create(fisheyeLens(), o);
  ASSERT_TRUE(banded.ok() && undistorted.ok());
  const ImageU8 lens_image = randomImage(400, 400, 5);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  ImageU8 expected, view;
  ASSERT_TRUE((*undistorted)->remap(lens_image, I, expected).ok());
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d* R : {&I, &turned, &I, &turned, &I}) {
    ASSERT_TRUE((*banded)->remap(lens_image, *R, view).ok());
    const bool fixed = R == &I;
    EXPECT_EQ(view.data == expected.data, fixed);
    EXPECT_EQ((*banded)->validFraction() == (*undistorted)->validFraction(), fixed);
    if (fixed) {
      const RemapTable& t = (*banded)->table(I);
      EXPECT_EQ(t.uv, (*banded)->exactTable(I).uv);
    }
  }
}

TEST(CameraFront, GridTableIsCloseToTheExactOne) {
  ViewOptions o;
  o.kind = ViewKind::kStabilised;
  o.width = 320;
  o.height = 240;
  o.pitch_deg = 20;
  o.dead_band_deg = 0;
  auto front = CameraFront::create(fisheyeLens(), o);
  ASSERT_TRUE(front.ok());
  const Eigen::Matrix3d R = (*front)->viewRotation(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                                                   test::cameraLookingAt({0, 0, 0}, {1, 0.2, -0.3}).linear());
  ASSERT_FALSE(R.isIdentity(1e-6));  // a turned view: the grid's table
  const RemapTable grid = (*front)->table(R);
  const RemapTable exact = (*front)->exactTable(R);
  ASSERT_EQ(grid.uv.size(), exact.uv.size());
  double worst = 0;
  size_t both = 0;
  for (size_t i = 0; i < grid.uv.size(); i += 2) {
    const bool a = grid.uv[i] > -1, b = exact.uv[i] > -1;
    EXPECT_EQ(a, b) << "pixel " << i / 2;
    if (!a || !b) continue;
    ++both;
    worst =
        std::max(worst, static_cast<double>(std::hypot(grid.uv[i] - exact.uv[i], grid.uv[i + 1] - exact.uv[i + 1])));
  }
  EXPECT_GT(both, grid.uv.size() / 4);
  EXPECT_LT(worst, 0.05) << "px";
}

TEST(CameraFront, ASmallerViewOfAPinholeLensIsTheCentralCropAtItsScale) {
  const PinholeCamera K = test::localizeCamera();
  ViewOptions o;
  o.width = K.width - 40;
  o.height = K.height - 20;
  for (const bool distorted : {false, true}) {
    LensCamera lens = radtanLens();
    if (!distorted) lens.k = {};
    auto front = CameraFront::create(lens, o);
    ASSERT_TRUE(front.ok()) << front.error().message;
    const PinholeCamera& view = (*front)->view();
    EXPECT_EQ(view.fx, K.fx);
    EXPECT_EQ(view.fy, K.fy);
    EXPECT_EQ(view.cx, K.cx - 20);
    EXPECT_EQ(view.cy, K.cy - 10);
    EXPECT_FALSE((*front)->identity());
    EXPECT_GT((*front)->validFraction(), 0.999) << distorted;
    if (distorted) continue;
    // An ideal lens: the view is the lens image's central pixels, unchanged.
    const ImageU8 img = randomImage(K.width, K.height, 5);
    ImageU8 crop;
    ASSERT_TRUE((*front)->remap(img, Eigen::Matrix3d::Identity(), crop).ok());
    ASSERT_EQ(crop.width, o.width);
    size_t differ = 0;
    for (int y = 0; y < o.height; ++y) {
      for (int x = 0; x < o.width; ++x) {
        differ +=
            crop.data[static_cast<size_t>(y) * o.width + x] != img.data[static_cast<size_t>(y + 10) * K.width + x + 20];
      }
    }
    EXPECT_EQ(differ, 0u);
  }
  // A field of view asked for overrides the lens's scale; a stabilised view keeps the scale
  // with its principal point at its centre.
  o.hfov_deg = 60;
  auto wide = CameraFront::create(radtanLens(), o);
  ASSERT_TRUE(wide.ok());
  EXPECT_NEAR((*wide)->view().fx, 0.5 * o.width / std::tan(M_PI / 6), 1e-9);
  o.hfov_deg = 0;
  o.kind = ViewKind::kStabilised;
  auto stabilised = CameraFront::create(radtanLens(), o);
  ASSERT_TRUE(stabilised.ok());
  EXPECT_EQ((*stabilised)->view().fx, K.fx);
  EXPECT_EQ((*stabilised)->view().cx, 0.5 * (o.width - 1));
}

TEST(CameraFront, AFlatFieldEvensOutAFalloffAndLeavesAnEvenImage) {
  // An ideal pinhole lens (the view is its own image) seeing a 16-px checkerboard of gray levels
  // 60 and 180 under a falloff from 1 on the left to 0.25 on the right.
  LensCamera lens;
  lens.intrinsics = test::localizeCamera();
  const int w = lens.intrinsics.width, h = lens.intrinsics.height;
  ImageU8 even(w, h, 1), falloff(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double level = ((x / 16 + y / 16) % 2) ? 180.0 : 60.0;
      even.at(x, y) = static_cast<uint8_t>(level);
      falloff.at(x, y) = static_cast<uint8_t>(std::lround(level * (1.0 - 0.75 * x / (w - 1.0))));
    }
  }
  // Contrast (mean |horizontal step| across the squares' vertical edges) of the 64 columns at
  // either side.
  auto contrast = [&](const ImageU8& img, int x0) {
    double sum = 0;
    int n = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = std::max(x0, 1); x < x0 + 64; ++x) {
        if (x % 16 != 0) continue;
        sum += std::abs(img.at(x, y) - img.at(x - 1, y));
        ++n;
      }
    }
    return sum / n;
  };
  ViewOptions o;
  o.flat_field_sigma_px = 40;
  auto front = CameraFront::create(lens, o);
  ASSERT_TRUE(front.ok()) << front.error().message;
  EXPECT_FALSE((*front)->identity());    // the flat field runs on an ideal lens's image too
  EXPECT_FALSE((*front)->needsRemap());  // but nothing is resampled: no device remapper
  ImageU8 flat, flat_even;
  ASSERT_TRUE((*front)->remap(falloff, Eigen::Matrix3d::Identity(), flat).ok());
  ASSERT_TRUE((*front)->remap(even, Eigen::Matrix3d::Identity(), flat_even).ok());
  const double before = contrast(falloff, 0) / contrast(falloff, w - 64);
  const double after = contrast(flat, 0) / contrast(flat, w - 64);
  EXPECT_GT(before, 2.5);
  EXPECT_NEAR(after, 1.0, 0.2) << "left/right contrast " << before << " -> " << after;
  // An evenly lit image keeps its levels (within 8 %: the local mean of a checkerboard ripples).
  int worst = 0;
  for (size_t i = 0; i < even.data.size(); ++i) worst = std::max(worst, std::abs(flat_even.data[i] - even.data[i]));
  EXPECT_LE(worst, 15);
  o.flat_field_sigma_px = -1;
  EXPECT_FALSE(CameraFront::create(lens, o).ok());
}

TEST(CameraFront, BadInputIsAClearError) {
  auto front = CameraFront::create(radtanLens(), ViewOptions{});
  ASSERT_TRUE(front.ok());
  ImageU8 out;
  const Status wrong = (*front)->remap(ImageU8(640, 480, 1), Eigen::Matrix3d::Identity(), out);
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("640x480"), std::string::npos) << wrong.error().message;
  ViewOptions o;
  o.hfov_deg = 179;
  EXPECT_FALSE(CameraFront::create(radtanLens(), o).ok());
  o = ViewOptions{};
  o.width = 100;  // height missing
  EXPECT_FALSE(CameraFront::create(radtanLens(), o).ok());
  // A view wider than the lens: mostly outside its field.
  o = ViewOptions{};
  o.hfov_deg = 170;
  auto outside = CameraFront::create(fisheyeLens(), o);
  ASSERT_FALSE(outside.ok());
  EXPECT_NE(outside.error().message.find("field of view"), std::string::npos) << outside.error().message;
  LensCamera nan = radtanLens();
  nan.k[0] = std::nan("");
  EXPECT_FALSE(CameraFront::create(nan, ViewOptions{}).ok());
}

TEST(ViewPrior, PosesAndCovariancesRoundTrip) {
  auto prior = std::make_unique<ViewPrior>(std::make_unique<ConstantVelocityPrior>());
  Pose T_camera_view = Pose::Identity();
  T_camera_view.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  prior->setView(T_camera_view);
  const Pose T_world_view = test::cameraLookingAt({1, 2, 3}, {0, 0, 0});
  EXPECT_TRUE(prior->toView(prior->toCamera(T_world_view)).isApprox(T_world_view, 1e-12));
  EXPECT_LT((prior->toCamera(T_world_view).translation() - T_world_view.translation()).norm(), 1e-12);
  Matrix6d C = Matrix6d::Identity();
  C(0, 0) = 4;
  C(4, 4) = 0.01;
  EXPECT_TRUE(prior->covarianceToView(prior->covarianceToCamera(C)).isApprox(C, 1e-12));
  // The wrapped prior sees camera poses: reset with a view pose, read back the view pose.
  prior->reset(T_world_view);
  ASSERT_TRUE(prior->cameraPrior().lastPose());
  EXPECT_TRUE(prior->cameraPrior().lastPose()->isApprox(prior->toCamera(T_world_view), 1e-12));
  EXPECT_TRUE(prior->lastPose()->isApprox(T_world_view, 1e-12));
}

struct LensRun {
  double max_error_m = 0;
  double max_error_deg = 0;
  int tracked = 0;
};

/// Tracks `frames` frames of the box scene seen through `lens` (view `view`), from the truth.
LensRun trackThroughLens(const LensCamera& lens, const ViewOptions& view, int frames) {
  LensRun out;
  auto front = CameraFront::create(lens, view);
  EXPECT_TRUE(front.ok()) << (front.ok() ? "" : front.error().message);
  if (!front.ok()) return out;
  const PinholeCamera camera = (*front)->view();
  LocalizerOptions options;
  options.keyframe_threading = KeyframeThreading::kSynchronous;
  auto localizer = Localizer::create(test::makeBoxOnGround(), camera, options, nullptr);
  EXPECT_TRUE(localizer.ok());
  if (!localizer.ok()) return out;
  EXPECT_TRUE((*localizer)->setCameraFront(std::move(front).value()).ok());
  (*localizer)->reset(test::localizeTruth(0));
  auto renderer = CpuRenderer::create(test::makeBoxOnGround());
  auto rig = makeLensRig(lens);
  EXPECT_TRUE(renderer.ok() && rig.ok());
  if (!renderer.ok() || !rig.ok()) return out;
  for (int i = 0; i < frames; ++i) {
    const Pose truth = test::localizeTruth(3 * i);
    const ImageU8 image = lensImage(**renderer, *rig, truth);
    auto r = (*localizer)->localize(i * kFrameNs, image);
    EXPECT_TRUE(r.ok()) << r.error().message;
    if (!r.ok()) break;
    if (r->state != TrackingState::kTracking) continue;
    ++out.tracked;
    out.max_error_m = std::max(out.max_error_m, test::translationError(r->T_world_camera, truth));
    out.max_error_deg = std::max(out.max_error_deg, test::rotationErrorDeg(r->T_world_camera, truth));
    if (view.kind == ViewKind::kStabilised) {
      // The reported pose is the camera's, the view's is turned by T_camera_view.
      EXPECT_FALSE(r->T_camera_view.isApprox(Pose::Identity(), 1e-3)) << "frame " << i;
    }
  }
  return out;
}

/// How an image lies on another: the shift (x, y, pixels) that best takes `b` onto `a`
/// (Gauss-Newton on a(p) = b(p + d), `b` sampled bilinearly) and the RMS gray difference left.
struct ImageFit {
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
  double rms = 0;
};

ImageFit fitImages(const ImageU8& a, const ImageU8& b) {
  const auto sample = [&](double x, double y) {
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    return (1 - fy) * ((1 - fx) * b.at(x0, y0) + fx * b.at(x0 + 1, y0)) +
           fy * ((1 - fx) * b.at(x0, y0 + 1) + fx * b.at(x0 + 1, y0 + 1));
  };
  ImageFit fit;
  constexpr int kMargin = 12;  // shifts stay well inside it
  for (int iteration = 0; iteration < 20; ++iteration) {
    Eigen::Matrix2d H = Eigen::Matrix2d::Zero();
    Eigen::Vector2d g = Eigen::Vector2d::Zero();
    double sum2 = 0;
    int n = 0;
    for (int y = kMargin; y + kMargin < b.height; ++y) {
      for (int x = kMargin; x + kMargin < b.width; ++x) {
        const double u = x + fit.shift.x(), v = y + fit.shift.y();
        const Eigen::Vector2d grad(0.5 * (sample(u + 1, v) - sample(u - 1, v)),
                                   0.5 * (sample(u, v + 1) - sample(u, v - 1)));
        const double r = a.at(x, y) - sample(u, v);
        sum2 += r * r;
        ++n;
        H += grad * grad.transpose();
        g += grad * r;
      }
    }
    fit.rms = std::sqrt(sum2 / std::max(1, n));
    const Eigen::Vector2d step = H.ldlt().solve(g);
    if (!step.allFinite()) break;
    fit.shift += step.cwiseMax(-2.0).cwiseMin(2.0);
    if (fit.shift.cwiseAbs().maxCoeff() > kMargin - 2) break;
    if (step.norm() < 1e-4) break;
  }
  return fit;
}

// The stabilised view of a lens image is the scene as a pinhole camera at the view's pose sees
// it: turned by 0-20 deg from the lens's axis, it lies on a direct render of that pose within a
// small fraction of a pixel and with little gray difference left (a table or convention error
// would shift or turn it: a render turned 0.5 deg, the control, is found ~1.7 px off).
TEST(CameraFront, AStabilisedViewLiesOnARenderAtTheViewsPose) {
  ViewOptions view;
  view.kind = ViewKind::kStabilised;
  view.width = 320;
  view.height = 240;
  view.hfov_deg = 80;
  view.dead_band_deg = 0;
  view.interpolation = RemapInterpolation::kBilinear;
  auto renderer = CpuRenderer::create(test::makeBoxOnGround());
  auto rig = makeLensRig(fisheyeLens());
  ASSERT_TRUE(renderer.ok() && rig.ok());
  for (double pitch : {28.0, 38.0, 48.0}) {
    view.pitch_deg = pitch;
    auto front = CameraFront::create(fisheyeLens(), view);
    ASSERT_TRUE(front.ok()) << front.error().message;
    const Pose truth = test::localizeTruth(0);
    const ImageU8 lens = lensImage(**renderer, *rig, truth);
    const Eigen::Matrix3d R_camera_view = (*front)->viewRotation(truth.linear());
    ImageU8 stabilised;
    ASSERT_TRUE((*front)->remap(lens, R_camera_view, stabilised).ok());
    Pose T_world_view = truth;
    T_world_view.linear() = truth.linear() * R_camera_view;
    auto direct = (*renderer)->render((*front)->view(), T_world_view, RenderSettings{});
    ASSERT_TRUE(direct.ok());
    const ImageFit fit = fitImages(stabilised, direct->gray);
    const double turned_deg = Eigen::AngleAxisd(R_camera_view).angle() * 180 / M_PI;
    EXPECT_LT(fit.shift.norm(), 0.1) << "pitch " << pitch << ": turned " << turned_deg << " deg, shift "
                                     << fit.shift.transpose() << " px";
    EXPECT_LT(fit.rms, 20.0) << "pitch " << pitch << ": turned " << turned_deg << " deg";
    // The control: the render turned 0.5 deg about the view's y axis (a pan: fx tan(0.5 deg) px
    // along x) is found where it is.
    Pose T_world_panned = T_world_view;
    T_world_panned.linear() = T_world_view.linear() * Eigen::AngleAxisd(0.5 * M_PI / 180, Eigen::Vector3d::UnitY());
    auto panned = (*renderer)->render((*front)->view(), T_world_panned, RenderSettings{});
    ASSERT_TRUE(panned.ok());
    const ImageFit off = fitImages(stabilised, panned->gray);
    const double expected_px = (*front)->view().fx * std::tan(0.5 * M_PI / 180);
    EXPECT_NEAR(std::abs(off.shift.x()), expected_px, 0.3) << "pitch " << pitch << ": " << off.shift.transpose();
  }
}

TEST(CameraFront, LocalizerTracksThroughARadialTangentialLens) {
  const LensRun run = trackThroughLens(radtanLens(), ViewOptions{}, 8);
  EXPECT_EQ(run.tracked, 8);
  EXPECT_LT(run.max_error_m, 0.01);
  EXPECT_LT(run.max_error_deg, 0.3);
}

TEST(CameraFront, LocalizerTracksThroughAStabilisedFisheyeView) {
  ViewOptions view;
  view.kind = ViewKind::kStabilised;
  view.width = 320;
  view.height = 240;
  view.hfov_deg = 80;
  view.pitch_deg = 40;  // the scene's camera looks ~28 deg down: the view is turned 12 deg from it
  view.dead_band_deg = 0;
  const LensRun run = trackThroughLens(fisheyeLens(), view, 8);
  EXPECT_EQ(run.tracked, 8);
  EXPECT_LT(run.max_error_m, 0.015);
  EXPECT_LT(run.max_error_deg, 0.4);
}

}  // namespace
}  // namespace vkloc
