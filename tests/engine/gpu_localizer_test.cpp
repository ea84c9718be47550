// Localizer: CPU and Vulkan backends on a rendered demo view, motion model, bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "support/gpu_test_support.hpp"
#include "vkloc/engine/gpu.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::test {
namespace {

PinholeCamera vga() { return PinholeCamera{520.0, 520.0, 319.5, 239.5, 640, 480}; }

double translationError(const Pose& a, const Pose& b) { return (a.translation() - b.translation()).norm(); }
double rotationErrorDeg(const Pose& a, const Pose& b) {
  return logSO3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}

/// A small known perturbation of the true pose: 1.5 cm and 1 degree.
Pose perturbed(const Pose& T) {
  Vector6d xi;
  xi << 0.01, -0.008, 0.008, 0.01, -0.012, 0.008;
  return T * expSE3(xi);
}

class LocalizerTest : public GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    model_ = makeDemoRoom();
    truth_ = demoViewpoints("room").at(0);
    // The live image is a render of the model at the true pose (an independent oracle: the
    // renderer, not the tracker, says where the edges are).
    auto renderer = GpuRenderer::create(context_, model_);
    ASSERT_TRUE(renderer.ok()) << renderer.error().message;
    auto view = (*renderer)->render(vga(), truth_);
    ASSERT_TRUE(view.ok()) << view.error().message;
    gray_ = view->gray;
  }
  std::shared_ptr<Accelerator> accelerator() { return *makeGpuAccelerator(context_); }
  Model model_;
  Pose truth_;
  ImageU8 gray_;
};

TEST_F(LocalizerTest, CpuAndVulkanBackendsAgreeOnARenderedView) {
  Pose poses[2];
  for (int b = 0; b < 2; ++b) {
    LocalizerOptions options;
    options.backend = b == 0 ? LocalizerBackend::kCpu : LocalizerBackend::kVulkan;
    options.policy = RerenderPolicy::kEveryFrame;
    options.keyframe_threading = KeyframeThreading::kSynchronous;  // reference_rendered below
    auto localizer = Localizer::create(model_, vga(), options, accelerator());
    ASSERT_TRUE(localizer.ok()) << localizer.error().message;
    EXPECT_NE((*localizer)->backendSummary().find(b == 0 ? "on CPU" : "on Vulkan"), std::string::npos)
        << (*localizer)->backendSummary();
    (*localizer)->reset(perturbed(truth_));
    auto r = (*localizer)->localize(0, gray_);
    ASSERT_TRUE(r.ok()) << r.error().message;
    // Second frame from the first's estimate: converges further, exercises the motion model.
    r = (*localizer)->localize(50'000'000, gray_);
    ASSERT_TRUE(r.ok()) << r.error().message;
    const TrackQuality& q = r->quality;
    EXPECT_EQ(r->state, TrackingState::kTracking)
        << "backend " << b << ": inliers " << q.inlier_ratio << ", chance " << q.chance_inlier_ratio << ", spread "
        << q.spread_ratio << ", visible " << q.visible_ratio << ", mean residual " << q.mean_residual_px << " px";
    EXPECT_TRUE(r->reference_rendered);
    EXPECT_GT(r->reference_points, 100);
    EXPECT_GT(r->scene_depth_m, 0.5);
    poses[b] = r->T_world_camera;
    // Against the true pose: within 5 mm and 0.2 degrees at ~2-4 m depth and 640x480.
    EXPECT_LT(translationError(poses[b], truth_), 5e-3) << "backend " << b;
    EXPECT_LT(rotationErrorDeg(poses[b], truth_), 0.2) << "backend " << b;
  }
  // The two backends run the same Gauss-Newton on the same data up to float rounding and the
  // GPU's jump-flooding distance (exact to 0.3 px on 0.001 % of pixels): 1 mm, 0.05 degrees.
  EXPECT_LT(translationError(poses[0], poses[1]), 1e-3);
  EXPECT_LT(rotationErrorDeg(poses[0], poses[1]), 0.05);
}

// kAuto with calibrate_backend: the first frame runs both backends and keeps the faster; the
// frames after it track on that one alone (keyframes in both modes).
TEST_F(LocalizerTest, CalibratedAutoBackendPicksOneAndKeepsTracking) {
  for (KeyframeThreading threading : {KeyframeThreading::kSynchronous, KeyframeThreading::kWorkerThread}) {
    LocalizerOptions options;
    options.backend = LocalizerBackend::kAuto;
    options.calibrate_backend = true;
    options.keyframe_threading = threading;
    auto localizer = Localizer::create(model_, vga(), options, accelerator());
    ASSERT_TRUE(localizer.ok()) << localizer.error().message;
    EXPECT_NE((*localizer)->backendSummary().find("not yet calibrated"), std::string::npos)
        << (*localizer)->backendSummary();
    (*localizer)->reset(perturbed(truth_));
    for (int frame = 0; frame < 4; ++frame) {
      auto r = (*localizer)->localize(int64_t{frame} * 50'000'000, gray_);
      ASSERT_TRUE(r.ok()) << r.error().message;
      EXPECT_EQ(r->state, TrackingState::kTracking) << "frame " << frame;
      EXPECT_LT(translationError(r->T_world_camera, truth_), 5e-3) << "frame " << frame;
    }
    const std::string summary = (*localizer)->backendSummary();
    EXPECT_NE(summary.find("calibrated on the first frame"), std::string::npos) << summary;
    EXPECT_TRUE(summary.find("on CPU") != std::string::npos || summary.find("on Vulkan") != std::string::npos)
        << summary;
  }
}

TEST_F(LocalizerTest, WhenNeededKeepsTheReferenceForAStillCamera) {
  LocalizerOptions options;
  options.backend = LocalizerBackend::kCpu;
  options.policy = RerenderPolicy::kWhenNeeded;
  options.rerender.max_frames = 3;
  options.rerender.min_inlier_ratio = 0.0;  // only the frame count triggers here
  options.keyframe_threading = KeyframeThreading::kSynchronous;
  auto localizer = Localizer::create(model_, vga(), options, accelerator());
  ASSERT_TRUE(localizer.ok()) << localizer.error().message;
  (*localizer)->reset(truth_);
  int rendered = 0;
  for (int i = 0; i < 4; ++i) {
    auto r = (*localizer)->localize(int64_t{i} * 50'000'000, gray_);
    ASSERT_TRUE(r.ok()) << r.error().message;
    EXPECT_EQ(r->state, TrackingState::kTracking);
    rendered += r->reference_rendered;
  }
  // Frame 0 renders; frames 1, 2 reuse; frame 3 reaches max_frames = 3 and renders again.
  EXPECT_EQ(rendered, 2);
}

TEST_F(LocalizerTest, InertialAidingBridgesBlankFramesAndRejectsDisagreeingAlignments) {
  // The live image of the true pose rendered 5 cm to the side (about 9 px at the room's depth,
  // well inside the alignment's basin): without the IMU the tracker follows it; with a still
  // camera's IMU readings the alignment lies outside the inertial gate and is rejected.
  Pose T_moved = truth_;
  T_moved.translation() += truth_.linear() * Eigen::Vector3d(0.05, 0.0, 0.0);
  auto renderer = GpuRenderer::create(context_, model_);
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  auto moved_view = (*renderer)->render(vga(), T_moved);
  ASSERT_TRUE(moved_view.ok()) << moved_view.error().message;
  const ImageU8 blank(640, 480, 1, 128);
  constexpr int64_t kFrameNs = 50'000'000;
  // The camera mounted as on the simulated drone (45 deg down, 10 cm ahead of the body), and
  // without an IMU.
  Pose T_body_camera = Pose::Identity();
  T_body_camera.linear() = expSO3(Eigen::Vector3d(0.0, 0.0, -M_PI / 2)) * expSO3(Eigen::Vector3d(-M_PI / 4, 0.0, 0.0));
  T_body_camera.translation() = Eigen::Vector3d(0.1, 0.0, -0.05);
  for (bool with_imu : {true, false}) {
    SCOPED_TRACE(with_imu ? "with IMU" : "without IMU");
    LocalizerOptions options;
    options.backend = LocalizerBackend::kCpu;
    options.policy = RerenderPolicy::kEveryFrame;
    options.inertial.T_body_camera = T_body_camera;
    auto created = Localizer::create(model_, vga(), options, accelerator());
    ASSERT_TRUE(created.ok()) << created.error().message;
    Localizer& localizer = **created;
    localizer.reset(truth_);
    // A still camera: no rotation rate, the accelerometer reads -R_world_body^T g.
    const Eigen::Matrix3d R_world_body = (truth_ * T_body_camera.inverse()).linear();
    int64_t t_imu = 0;
    auto feedImu = [&](int64_t until_ns) {
      for (; with_imu && t_imu <= until_ns; t_imu += 5'000'000) {
        ImuSample s;
        s.t_ns = t_imu;
        s.accel_body = -(R_world_body.transpose() * Eigen::Vector3d(0.0, 0.0, -9.81));
        ASSERT_TRUE(localizer.addImu(s).ok());
      }
    };
    int64_t t = 0;
    auto frame = [&](const ImageU8& image) {
      feedImu(t);
      auto r = localizer.localize(t, image);
      t += kFrameNs;
      EXPECT_TRUE(r.ok()) << r.error().message;
      return r.ok() ? *r : LocalizationResult{};
    };
    for (int i = 0; i < 6; ++i) {
      const LocalizationResult r = frame(gray_);
      EXPECT_EQ(r.state, TrackingState::kTracking) << "frame " << i;
      EXPECT_FALSE(r.visual_rejected);
    }
    // Nothing to align with: the inertial pose, or lost without the IMU.
    LocalizationResult r = frame(blank);
    if (with_imu) {
      EXPECT_EQ(r.state, TrackingState::kInertial);
      EXPECT_LT(translationError(r.T_world_camera, truth_), 2e-3);
      EXPECT_LT(rotationErrorDeg(r.T_world_camera, truth_), 0.05);
      EXPECT_GT(r.inertial_sigma_m, 0.0);
      EXPECT_GT(r.covariance(0, 0), 0.0);
    } else {
      EXPECT_EQ(r.state, TrackingState::kLost);
    }
    // Back to the true image: tracked again.
    r = frame(gray_);
    EXPECT_EQ(r.state, TrackingState::kTracking) << "with_imu " << with_imu;
    EXPECT_LT(translationError(r.T_world_camera, truth_), 5e-3);
    // The moved image: followed without the IMU, rejected with it.
    r = frame(moved_view->gray);
    if (with_imu) {
      EXPECT_TRUE(r.visual_rejected);
      EXPECT_EQ(r.state, TrackingState::kInertial);
      EXPECT_LT(translationError(r.T_world_camera, truth_), 2e-3);
    } else {
      EXPECT_EQ(r.state, TrackingState::kTracking);
      EXPECT_LT(translationError(r.T_world_camera, T_moved), 5e-3);
    }
  }
}

TEST_F(LocalizerTest, BadInputIsAnErrorNotACrash) {
  LocalizerOptions options;
  options.backend = LocalizerBackend::kCpu;
  auto created = Localizer::create(model_, vga(), options, accelerator());
  ASSERT_TRUE(created.ok()) << created.error().message;
  Localizer& localizer = **created;
  // No pose yet and no guess.
  auto r = localizer.localize(0, gray_);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  // Wrong size and wrong channel count.
  localizer.reset(truth_);
  r = localizer.localize(0, ImageU8(320, 240, 1));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("640x480"), std::string::npos) << r.error().message;
  r = localizer.localize(0, ImageU8(640, 480, 4));
  EXPECT_FALSE(r.ok());
  // NaN guess.
  Pose nan_pose = truth_;
  nan_pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  r = localizer.localize(0, gray_, nan_pose);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  // Timestamps must increase.
  r = localizer.localize(100, gray_);
  ASSERT_TRUE(r.ok()) << r.error().message;
  r = localizer.localize(100, gray_);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("not after"), std::string::npos) << r.error().message;
  r = localizer.localize(50, gray_);
  EXPECT_FALSE(r.ok());
  // Vulkan backend without a device; options out of range.
  options.backend = LocalizerBackend::kVulkan;
  auto no_device = Localizer::create(model_, vga(), options, nullptr);
  ASSERT_FALSE(no_device.ok());
  EXPECT_EQ(no_device.error().code, ErrorCode::kNoDevice);
  options.backend = LocalizerBackend::kCpu;
  options.rerender.max_frames = 0;
  EXPECT_FALSE(Localizer::create(model_, vga(), options, accelerator()).ok());
  options.rerender.max_frames = 10;
  EXPECT_FALSE(Localizer::create(model_, PinholeCamera{0, 0, 0, 0, 0, 0}, options, accelerator()).ok());
  EXPECT_FALSE(parseLocalizerBackend("gpu").ok());
  EXPECT_FALSE(parseRerenderPolicy("sometimes").ok());
}

}  // namespace
}  // namespace vkloc::test
