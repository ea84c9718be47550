// Edge overlays on the checker box scene (CPU reference renderer): at the true pose most model
// edge points lie on live edges (green), at a pose 10 pixels off most do not (red); the points
// drawn at the true pose then agree again; bad input is an error; the caption font draws.
#include "vkloc/eval/overlay.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "localize/localize_scene.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc {
namespace {

struct PixelCounts {
  int green = 0;
  int red = 0;
  int cyan = 0;
};

PixelCounts countColours(const ImageU8& rgb) {
  PixelCounts n;
  for (int y = 0; y < rgb.height; ++y) {
    for (int x = 0; x < rgb.width; ++x) {
      const int r = rgb.at(x, y, 0), g = rgb.at(x, y, 1), b = rgb.at(x, y, 2);
      n.green += g > 200 && r < 100 && b < 100;
      n.red += r > 200 && g < 100 && b < 100;
      n.cyan += b > 200 && g > 150 && r < 50;
    }
  }
  return n;
}

// The true pose moved so that the image moves by about 10 pixels (5 right, 5 down, 7 diagonal
// and a yaw of 10 px at the image centre): rotation about the camera's x and y axes.
Pose shiftedPose(const Pose& T_world_camera, const PinholeCamera& camera, double pixels) {
  const double a = std::atan(pixels / std::sqrt(2.0) / camera.fx);
  const Eigen::Matrix3d R = expSO3(Eigen::Vector3d(-a, a, 0.0));
  Pose T = T_world_camera;
  T.linear() = T_world_camera.linear() * R;
  return T;
}

class OverlayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    camera_ = test::localizeCamera();
    truth_ = test::localizeTruth(0);
    gray_ = test::localizeFrames(1).front();
    renderer_ = CpuRenderer::create(test::makeBoxOnGround()).value();
  }
  PinholeCamera camera_;
  Pose truth_;
  ImageU8 gray_;
  std::unique_ptr<CpuRenderer> renderer_;
};

TEST_F(OverlayTest, TruePoseIsMostlyGreen) {
  Result<EdgeOverlay> o = makeEdgeOverlay(*renderer_, gray_, camera_, truth_, std::nullopt, {});
  ASSERT_TRUE(o.ok()) << o.error().message;
  EXPECT_EQ(o->image.channels, 3);
  EXPECT_EQ(o->image.width, camera_.width);
  EXPECT_FALSE(o->truth.has_value());
  EXPECT_GT(o->estimate.in_image, 300);
  EXPECT_GT(o->estimate.inlier_ratio, 0.85);
  EXPECT_LT(o->estimate.median_distance_px, 0.75);
  const PixelCounts n = countColours(o->image);
  EXPECT_GT(n.green, 4 * n.red) << n.green << " green, " << n.red << " red";
}

TEST_F(OverlayTest, PoseTenPixelsOffIsMostlyRedAndTheTruthGreen) {
  const Pose off = shiftedPose(truth_, camera_, 10.0);
  Result<EdgeOverlay> o = makeEdgeOverlay(*renderer_, gray_, camera_, off, truth_, {});
  ASSERT_TRUE(o.ok()) << o.error().message;
  // The checker texture leaves about a third of the points on some other edge by chance.
  EXPECT_LT(o->estimate.inlier_ratio, 0.4);
  EXPECT_GT(o->estimate.median_distance_px, 3.0);
  ASSERT_TRUE(o->truth.has_value());
  // The edges seen from the wrong pose, put at the true one, lie on the image's edges again.
  EXPECT_GT(o->truth->inlier_ratio, 0.75);
  const PixelCounts n = countColours(o->image);
  EXPECT_GT(n.red, 3 * n.green / 2) << n.green << " green, " << n.red << " red";
  EXPECT_GT(n.cyan, 100);

  EdgeOverlayOptions no_truth;
  no_truth.draw_truth = false;
  Result<EdgeOverlay> plain = makeEdgeOverlay(*renderer_, gray_, camera_, off, truth_, no_truth);
  ASSERT_TRUE(plain.ok());
  EXPECT_TRUE(plain->truth.has_value());
  EXPECT_EQ(countColours(plain->image).cyan, 0);
}

TEST_F(OverlayTest, ClassifiesAgainstTheLiveDistanceField) {
  // Two points in front of the camera (one on the image, one outside it) and one behind.
  LiveFrameOptions live;
  live.levels = 1;
  Result<LiveFrame> frame = buildLiveFrame(gray_, camera_, live);
  ASSERT_TRUE(frame.ok());
  const Pose T = Pose::Identity();
  const std::vector<Eigen::Vector3d> points{{0.0, 0.0, 2.0}, {10.0, 0.0, 1.0}, {0.0, 0.0, -1.0}};
  std::vector<ProjectedEdgePoint> projected;
  const EdgeAgreement a = classifyEdgePoints(points, camera_, T, frame->levels[0], 1.5, &projected);
  EXPECT_EQ(a.points, 3);
  EXPECT_EQ(a.in_image, 1);
  ASSERT_EQ(projected.size(), 1u);
  EXPECT_NEAR(projected[0].u, camera_.cx, 1e-4);
  EXPECT_NEAR(projected[0].v, camera_.cy, 1e-4);
  EXPECT_EQ(projected[0].inlier, projected[0].distance_px <= 1.5);
  EXPECT_EQ(a.inliers, projected[0].inlier ? 1 : 0);
}

TEST_F(OverlayTest, BadInputIsAnError) {
  const ImageU8 small(10, 10, 1);
  Result<EdgeOverlay> wrong_size = makeEdgeOverlay(*renderer_, small, camera_, truth_, std::nullopt, {});
  ASSERT_FALSE(wrong_size.ok());
  EXPECT_EQ(wrong_size.error().code, ErrorCode::kInvalidArgument);
  EdgeOverlayOptions bad;
  bad.inlier_threshold_px = 0;
  EXPECT_FALSE(makeEdgeOverlay(*renderer_, gray_, camera_, truth_, std::nullopt, bad).ok());
  bad = {};
  bad.dim = 1.5;
  EXPECT_FALSE(validateEdgeOverlayOptions(bad).ok());
  Pose not_rigid = truth_;
  not_rigid.linear() *= 2.0;
  EXPECT_FALSE(makeEdgeOverlay(*renderer_, gray_, camera_, not_rigid, std::nullopt, {}).ok());
}

TEST(OverlayText, DrawsGlyphsClippedAtTheBorder) {
  ImageU8 image(40, 12, 3);
  drawOverlayText(image, 1, 1, "1a", {255, 255, 255});
  // '1' has a full-width foot (row 6, columns 1..3); 'A' the top row's middle three columns.
  EXPECT_EQ(image.at(1 + 2, 1 + 6, 0), 255);
  EXPECT_EQ(image.at(1 + 0, 1 + 6, 0), 0);
  EXPECT_EQ(image.at(7 + 1, 1 + 0, 1), 255);
  EXPECT_EQ(image.at(7 + 0, 1 + 0, 1), 0);
  // Off the image and unknown characters draw nothing outside and do not crash.
  drawOverlayText(image, 35, -3, "\x01~W", {255, 0, 0}, 3);
  ImageU8 gray(64, 40, 1);
  drawOverlayCaption(gray, {"frame 1", "tracking"});
  int lit = 0;
  for (uint8_t v : gray.data) lit += v == 255;
  EXPECT_GT(lit, 20);
  EXPECT_EQ(overlayCaptionHeight(2, 1), 18);
}

}  // namespace
}  // namespace vkloc
