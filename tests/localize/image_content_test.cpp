// Tests of the image content check and of the Localizer on frames with nothing to align (black,
// saturated, uniform grey with sensor noise): reported at once, bridged by the IMU when it runs,
// never aligned or searched, and a normal frame after them tracks again.
#include "vkloc/localize/image_content.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "localize/localize_scene.hpp"
#include "vkloc/localize/localizer.hpp"

namespace vkloc {
namespace {

constexpr int64_t kFrameNs = 50'000'000;

/// Uniform gray `level` with Gaussian noise of `sigma` gray levels (clamped to 0..255).
ImageU8 noisyUniform(int width, int height, double level, double sigma, uint32_t seed) {
  ImageU8 image(width, height, 1);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (uint8_t& v : image.data) v = static_cast<uint8_t>(std::clamp(std::lround(level + noise(rng)), 0L, 255L));
  return image;
}

TEST(ImageContent, BlackSaturatedAndUniformFramesHaveNothingToAlign) {
  const ImageU8 black(640, 480, 1, 0);
  const ImageU8 white(640, 480, 1, 255);
  Result<ImageContentCheck> c = checkImageContent(black);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->content, ImageContent::kBlack);
  EXPECT_EQ(c->contrast, 0.0);
  c = checkImageContent(white);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->content, ImageContent::kSaturated);
  // Sensor noise up to sigma 30 gray levels, at several levels: the noise is not structure.
  for (double sigma : {0.0, 3.0, 10.0, 30.0}) {
    for (double level : {8.0, 128.0, 250.0}) {
      c = checkImageContent(noisyUniform(640, 480, level, sigma, 7));
      ASSERT_TRUE(c.ok());
      EXPECT_NE(c->content, ImageContent::kOk) << "sigma " << sigma << " level " << level;
      EXPECT_LT(c->contrast, ImageContentOptions{}.min_contrast) << sigma;
    }
  }
  c = checkImageContent(noisyUniform(640, 480, 128, 10, 3));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->content, ImageContent::kUniform);
  EXPECT_STREQ(imageContentName(c->content), "uniform");
  // Its time at 640x480 (printed, not checked).
  const ImageU8 grey = noisyUniform(640, 480, 128, 10, 9);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 20; ++i) c = checkImageContent(grey);
  std::printf("checkImageContent at 640x480: %.0f us\n",
              std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / 20);
  // Any size, down to one pixel.
  c = checkImageContent(ImageU8(1, 1, 1, 0));
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->content, ImageContent::kBlack);
}

TEST(ImageContent, RenderedViewsAndFaintStructureAreContent) {
  // The box scene's rendered views.
  for (int i : {0, 10, 23}) {
    Result<ImageContentCheck> c = checkImageContent(test::localizeFrames(24)[static_cast<size_t>(i)]);
    ASSERT_TRUE(c.ok());
    EXPECT_EQ(c->content, ImageContent::kOk) << i;
    EXPECT_GT(c->contrast, 10.0) << i;
  }
  // A dim step of 16 gray levels across a dark, noisy frame (a door in a dark room): content.
  ImageU8 step = noisyUniform(640, 480, 20, 5, 11);
  for (int y = 0; y < 480; ++y) {
    for (int x = 320; x < 640; ++x) step.data[static_cast<size_t>(y) * 640 + x] += 16;
  }
  Result<ImageContentCheck> c = checkImageContent(step);
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->content, ImageContent::kOk);
  EXPECT_NEAR(c->contrast, 8.0, 0.5);  // half the frame 16 levels up: standard deviation 8
}

TEST(ImageContent, BadInputAndOptionsAreErrors) {
  EXPECT_FALSE(checkImageContent(ImageU8()).ok());
  EXPECT_FALSE(checkImageContent(ImageU8(4, 4, 3, 0)).ok());
  ImageContentOptions o;
  o.min_contrast = -1;
  EXPECT_FALSE(validateImageContentOptions(o).ok());
  o = {};
  o.dark_level = 200;
  o.saturated_level = 100;
  EXPECT_FALSE(validateImageContentOptions(o).ok());
  o = {};
  o.saturated_level = std::nan("");
  EXPECT_FALSE(checkImageContent(ImageU8(4, 4, 1, 0), o).ok());
  LocalizerOptions options;
  options.image_content.min_contrast = 300;
  EXPECT_FALSE(Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr).ok());
}

std::unique_ptr<Localizer> makeLocalizer(KeyframeThreading threading) {
  LocalizerOptions options;
  options.keyframe_threading = threading;
  auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
  EXPECT_TRUE(created.ok()) << created.error().message;
  return created.ok() ? std::move(created).value() : nullptr;
}

/// IMU readings of the scene's camera circle (localizeTruth: rotating rigidly about the world z
/// axis at 0.5 deg per frame), body = camera frame, gravity -z, from t0 to t1 at 200 Hz.
void feedImu(Localizer& localizer, int64_t t0_ns, int64_t t1_ns) {
  for (int64_t t = t0_ns; t <= t1_ns; t += 5'000'000)
    EXPECT_TRUE(localizer.addImu(test::localizeImuAt(t, kFrameNs)).ok());
}

/// Frames with nothing to align, one after another, then the scene again.
void checkEmptyFramesThenTracking(Localizer& localizer, bool imu) {
  localizer.reset(test::localizeTruth(0));
  const auto& frames = test::localizeFrames(16);
  int64_t imu_t = 0;
  auto step = [&](int i, const ImageU8& image) {
    if (imu) {
      feedImu(localizer, imu_t, i * kFrameNs);
      imu_t = i * kFrameNs + 5'000'000;
    }
    Result<LocalizationResult> r = localizer.localize(i * kFrameNs, image);
    EXPECT_TRUE(r.ok()) << r.error().message;
    return r.ok() ? *r : LocalizationResult{};
  };
  for (int i = 0; i < 6; ++i) EXPECT_EQ(step(i, frames[static_cast<size_t>(i)]).state, TrackingState::kTracking) << i;
  const ImageU8 empties[] = {ImageU8(320, 240, 1, 0), ImageU8(320, 240, 1, 255), noisyUniform(320, 240, 128, 8, 5)};
  const ImageContent expected[] = {ImageContent::kBlack, ImageContent::kSaturated, ImageContent::kUniform};
  for (int k = 0; k < 3; ++k) {
    const int i = 6 + k;
    const auto t0 = std::chrono::steady_clock::now();
    const LocalizationResult r = step(i, empties[k]);
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    std::printf("%s frame (%s): %.0f us, state %s\n", imageContentName(r.image_content), imu ? "IMU" : "no IMU", us,
                trackingStateName(r.state));
    EXPECT_EQ(r.image_content, expected[k]) << k;
    EXPECT_LT(r.image_contrast, 2.0);
    EXPECT_EQ(r.live_ms, 0.0) << "nothing aligned";
    EXPECT_EQ(r.align_ms, 0.0);
    EXPECT_FALSE(r.reference_rendered);
    EXPECT_EQ(r.motion_search_probes, 0);
    EXPECT_EQ(r.relocalization_candidates, 0);
    if (imu) {
      // The filter bridges the frame: the IMU-only pose, close to the truth over 3 frames.
      EXPECT_EQ(r.state, TrackingState::kInertial) << k;
      EXPECT_LT(test::translationError(r.T_world_camera, test::localizeTruth(i)), 0.02) << k;
      EXPECT_LT(test::rotationErrorDeg(r.T_world_camera, test::localizeTruth(i)), 0.5) << k;
    } else {
      EXPECT_EQ(r.state, TrackingState::kLost) << k;
    }
  }
  for (int i = 9; i < 16; ++i) {
    const LocalizationResult r = step(i, frames[static_cast<size_t>(i)]);
    EXPECT_EQ(r.image_content, ImageContent::kOk);
    EXPECT_EQ(r.state, TrackingState::kTracking) << i;
    EXPECT_LT(test::translationError(r.T_world_camera, test::localizeTruth(i)), 3e-3) << i;
  }
}

TEST(Localizer, FramesWithNothingToAlignAreReportedAndTrackingResumes) {
  auto localizer = makeLocalizer(KeyframeThreading::kSynchronous);
  ASSERT_TRUE(localizer);
  checkEmptyFramesThenTracking(*localizer, false);
}

TEST(Localizer, FramesWithNothingToAlignAreBridgedByTheImu) {
  auto localizer = makeLocalizer(KeyframeThreading::kWorkerThread);
  ASSERT_TRUE(localizer);
  checkEmptyFramesThenTracking(*localizer, true);
}

TEST(Localizer, EmptyFramesBeforeAnyPoseAndTheCheckSwitchedOff) {
  // The first frame after reset is black: lost (the reset pose is kept), then the scene tracks:
  // its first pose, after a lost frame, waits for the next frame to confirm it
  // (RelocalizationOptions::confirm_start), which it does.
  auto localizer = makeLocalizer(KeyframeThreading::kSynchronous);
  ASSERT_TRUE(localizer);
  localizer->reset(test::localizeTruth(0));
  Result<LocalizationResult> r = localizer->localize(0, ImageU8(320, 240, 1, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kLost);
  EXPECT_EQ(r->image_content, ImageContent::kBlack);
  const std::vector<ImageU8> frames = test::localizeFrames(3);
  r = localizer->localize(kFrameNs, frames[1]);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kInitializing);
  EXPECT_TRUE(r->confirming);
  r = localizer->localize(2 * kFrameNs, frames[2]);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kRelocalized);
  EXPECT_LT(test::translationError(r->T_world_camera, test::localizeTruth(2)), 3e-3);
  // min_contrast 0: the check is off and a black frame goes through the alignment (lost there).
  LocalizerOptions options;
  options.keyframe_threading = KeyframeThreading::kSynchronous;
  options.image_content.min_contrast = 0;
  auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
  ASSERT_TRUE(created.ok());
  (*created)->reset(test::localizeTruth(0));
  r = (*created)->localize(0, ImageU8(320, 240, 1, 0));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->image_content, ImageContent::kOk);
  EXPECT_EQ(r->state, TrackingState::kLost);
  EXPECT_TRUE(r->reference_rendered);
}

}  // namespace
}  // namespace vkloc
