// InertialPredictor (inertial.hpp): prediction across gaps in the visual fixes on simulated
// drone flights with exact and noisy IMU readings, uncertainty, and bad input.
#include "vkloc/fusion/inertial_predictor.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "vkloc/core/se3.hpp"
#include "vkloc/sim/trajectory.hpp"

namespace vkloc {
namespace {

using Eigen::Vector3d;

const Vector3d kGravity(0.0, 0.0, -9.81);
constexpr int64_t kFramePeriodNs = 50'000'000;  // 20 Hz

SplineTrajectory droneFlight(uint64_t seed) {
  TrajectoryOptions o;
  o.kind = TrajectoryKind::kDroneFlight;
  o.duration_s = 8.0;
  o.seed = seed;
  Aabb city;
  city.min = {-100.0f, -100.0f, 0.0f};
  city.max = {100.0f, 100.0f, 60.0f};
  auto t = makeTrajectory(o, city);
  EXPECT_TRUE(t.ok());
  return t.ok() ? *t : SplineTrajectory{};
}

double rotationDeg(const Pose& a, const Pose& b) {
  return logSO3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}

struct GapError {
  double translation_m = 0;
  double rotation_deg = 0;
  double sigma_m = 0;
  double speed_m_s = 0;
};

/// Fixes every frame for 1 s (ground truth plus Gaussian noise of fix_sigma_m per axis), then
/// predicts `gap_frames` frames later, with readings from simulateImu.
GapError predictAcrossGap(uint64_t seed, const std::optional<ImuNoise>& noise, double fix_sigma_m, int gap_frames) {
  const SplineTrajectory trajectory = droneFlight(seed);
  InertialPredictor predictor;
  for (const ImuSample& s : simulateImu(trajectory, noise, kGravity, seed)) {
    EXPECT_TRUE(predictor.addImu(s).ok());
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, fix_sigma_m);
  const int64_t start = 2'000'000'000;  // 2 s in
  for (int i = 0; i < 20; ++i) {
    const int64_t t = start + i * kFramePeriodNs;
    Pose T = trajectory.evaluate(t).T_world_body;
    T.translation() += Vector3d(normal(rng), normal(rng), normal(rng));
    predictor.addFix(t, T);
  }
  const int64_t t = start + (19 + gap_frames) * kFramePeriodNs;
  const std::optional<InertialPrediction> p = predictor.predict(t);
  EXPECT_TRUE(p.has_value());
  if (!p) return {};
  const TrajectoryState truth = trajectory.evaluate(t);
  GapError e;
  e.translation_m = (p->T_world_body.translation() - truth.T_world_body.translation()).norm();
  e.rotation_deg = rotationDeg(p->T_world_body, truth.T_world_body);
  e.sigma_m = p->sigma_m;
  e.speed_m_s = truth.v_world_body.norm();
  EXPECT_NEAR(p->since_fix_s, gap_frames * 0.05, 1e-9);
  EXPECT_EQ(p->fixes, 20);
  return e;
}

TEST(InertialPredictor, ExactReadingsAndFixesPredictAcrossTwoSeconds) {
  // Only integration error remains (200 Hz midpoint rule): 0.1 um after 2 s of a flight at
  // 5-7 m/s (measured); 10 um allowed.
  for (uint64_t seed : {1u, 2u, 3u}) {
    const GapError one = predictAcrossGap(seed, std::nullopt, 0.0, 1);
    const GapError gap = predictAcrossGap(seed, std::nullopt, 0.0, 40);
    std::printf("seed %d: %.1f m/s, 1 frame ahead %.4f mm, 2 s ahead %.4f mm %.5f deg\n", static_cast<int>(seed),
                gap.speed_m_s, one.translation_m * 1e3, gap.translation_m * 1e3, gap.rotation_deg);
    EXPECT_GT(gap.speed_m_s, 1.0) << "seed " << seed;
    EXPECT_LT(one.translation_m, 1e-5) << "seed " << seed;
    EXPECT_LT(gap.translation_m, 1e-5) << "seed " << seed;
    EXPECT_LT(gap.rotation_deg, 1e-3) << "seed " << seed;
  }
}

TEST(InertialPredictor, NoisyReadingsAndFixesStayWithinTheStatedUncertainty) {
  // Readings with the simulator's default noise and bias walk, fixes with 5 mm noise per axis:
  // one frame ahead within 1 cm (measured 3-5 mm), 1.5 s ahead within 4 cm (measured 10-19 mm:
  // the velocity fit over 1 s of fixes carries ~1 cm/s error), and within 4 stated sigmas.
  for (uint64_t seed : {11u, 12u, 13u, 14u}) {
    const GapError one = predictAcrossGap(seed, ImuNoise{}, 0.005, 1);
    const GapError gap = predictAcrossGap(seed, ImuNoise{}, 0.005, 30);
    std::printf("seed %d: 1 frame ahead %.2f mm (sigma %.2f), 1.5 s ahead %.1f mm (sigma %.1f) %.4f deg\n",
                static_cast<int>(seed), one.translation_m * 1e3, one.sigma_m * 1e3, gap.translation_m * 1e3,
                gap.sigma_m * 1e3, gap.rotation_deg);
    EXPECT_LT(one.translation_m, 0.01) << "seed " << seed;
    EXPECT_LT(gap.translation_m, 0.04) << "seed " << seed;
    EXPECT_LT(gap.rotation_deg, 0.1) << "seed " << seed;
    EXPECT_LT(gap.translation_m, 4.0 * gap.sigma_m) << "seed " << seed << ": sigma " << gap.sigma_m;
    EXPECT_GT(gap.sigma_m, one.sigma_m) << "seed " << seed;
  }
}

TEST(InertialPredictor, NoPredictionWithoutEnoughFixesOrReadings) {
  const SplineTrajectory trajectory = droneFlight(5);
  const std::vector<ImuSample> imu = simulateImu(trajectory, std::nullopt, kGravity, 5);
  InertialPredictor predictor;
  const int64_t start = 1'000'000'000;
  // No readings at all.
  for (int i = 0; i < 5; ++i) {
    predictor.addFix(start + i * kFramePeriodNs, trajectory.evaluate(start + i * kFramePeriodNs).T_world_body);
  }
  EXPECT_FALSE(predictor.predict(start + 5 * kFramePeriodNs).has_value());
  // Readings up to 0.5 s only: a prediction later than max_extrapolation_s after them is refused.
  for (const ImuSample& s : imu) {
    if (s.t_ns <= start + 10 * kFramePeriodNs) {
      ASSERT_TRUE(predictor.addImu(s).ok());
    }
  }
  EXPECT_TRUE(predictor.predict(start + 5 * kFramePeriodNs).has_value());
  EXPECT_FALSE(predictor.predict(start + 12 * kFramePeriodNs).has_value());
  // Not after the newest fix.
  EXPECT_FALSE(predictor.predict(start + 4 * kFramePeriodNs).has_value());
  // Too few fixes (min_fixes = 4 by default).
  predictor.clearFixes();
  for (int i = 0; i < 3; ++i) {
    predictor.addFix(start + i * kFramePeriodNs, trajectory.evaluate(start + i * kFramePeriodNs).T_world_body);
  }
  EXPECT_FALSE(predictor.predict(start + 5 * kFramePeriodNs).has_value());
  // Fixes that start before the first reading.
  InertialPredictor late;
  for (const ImuSample& s : imu) {
    if (s.t_ns >= start) {
      ASSERT_TRUE(late.addImu(s).ok());
    }
  }
  for (int i = -2; i < 4; ++i) {
    late.addFix(start + i * kFramePeriodNs, trajectory.evaluate(start + i * kFramePeriodNs).T_world_body);
  }
  EXPECT_FALSE(late.predict(start + 5 * kFramePeriodNs).has_value());
}

TEST(InertialPredictor, NoPredictionAcrossAReadingGapOrFromAStaleWindow) {
  const SplineTrajectory trajectory = droneFlight(6);
  const std::vector<ImuSample> imu = simulateImu(trajectory, std::nullopt, kGravity, 6);
  const int64_t start = 1'000'000'000;
  auto fixes = [&](InertialPredictor& p) {
    for (int i = 0; i < 5; ++i) {
      p.addFix(start + i * kFramePeriodNs, trajectory.evaluate(start + i * kFramePeriodNs).T_world_body);
    }
  };
  // Readings 0.15 s missing between the fixes: a gap above max_reading_gap_s (0.1 s), refused;
  // bridged with max_reading_gap_s 0.2 s.
  auto predictAcrossGap = [&](const InertialOptions& options) {
    InertialPredictor p(options);
    for (const ImuSample& s : imu) {
      const bool in_gap = s.t_ns >= start + 50'000'000 && s.t_ns <= start + 200'000'000;
      if (!in_gap) {
        EXPECT_TRUE(p.addImu(s).ok());
      }
      if (s.t_ns > start + 400'000'000) break;
    }
    fixes(p);
    return p.predict(start + 6 * kFramePeriodNs).has_value();
  };
  EXPECT_FALSE(predictAcrossGap(InertialOptions{}));
  InertialOptions wide;
  wide.max_reading_gap_s = 0.2;
  EXPECT_TRUE(predictAcrossGap(wide));
  // Readings going on for longer than buffer_s after the window: the window is dropped.
  InertialOptions short_buffer;
  short_buffer.buffer_s = 2.0;
  InertialPredictor stale(short_buffer);
  size_t k = 0;
  for (; k < imu.size() && imu[k].t_ns <= start + 5 * kFramePeriodNs; ++k) ASSERT_TRUE(stale.addImu(imu[k]).ok());
  fixes(stale);
  EXPECT_EQ(stale.fixCount(), 5u);
  for (; k < imu.size() && imu[k].t_ns <= start + 3'000'000'000; ++k) ASSERT_TRUE(stale.addImu(imu[k]).ok());
  EXPECT_EQ(stale.fixCount(), 0u);
}

TEST(InertialPredictor, BadReadingsAndOptionsAreErrors) {
  InertialPredictor predictor;
  ImuSample s;
  s.t_ns = 10;
  s.accel_body = Vector3d(0, 0, 9.81);
  ASSERT_TRUE(predictor.addImu(s).ok());
  // Same time again, earlier, NaN.
  EXPECT_EQ(predictor.addImu(s).error().code, ErrorCode::kInvalidArgument);
  s.t_ns = 5;
  EXPECT_FALSE(predictor.addImu(s).ok());
  s.t_ns = 20;
  s.gyro_body.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(predictor.addImu(s).ok());
  s.gyro_body.x() = 0;
  EXPECT_TRUE(predictor.addImu(s).ok());  // the bad ones were ignored
  // An invalid fix is ignored.
  Pose nan_pose = Pose::Identity();
  nan_pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  predictor.addFix(15, nan_pose);
  EXPECT_EQ(predictor.fixCount(), 0u);

  EXPECT_TRUE(validateInertialOptions(InertialOptions{}).ok());
  InertialOptions o;
  o.min_fixes = 1;
  EXPECT_FALSE(validateInertialOptions(o).ok());
  o = InertialOptions{};
  o.min_fixes = 30;  // more than window_fixes
  EXPECT_FALSE(validateInertialOptions(o).ok());
  o = InertialOptions{};
  o.gravity_world.z() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(validateInertialOptions(o).ok());
  o = InertialOptions{};
  o.window_s = -1;
  EXPECT_FALSE(validateInertialOptions(o).ok());
  o = InertialOptions{};
  o.buffer_s = 1.0;  // shorter than window_s
  EXPECT_FALSE(validateInertialOptions(o).ok());
  o = InertialOptions{};
  o.max_reading_gap_s = 0;
  EXPECT_FALSE(validateInertialOptions(o).ok());
}

}  // namespace
}  // namespace vkloc
