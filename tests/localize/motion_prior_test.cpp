// Tests of the motion priors (localize/motion_prior.hpp): constant velocity, IMU propagation,
// the consistency gate and bridging, without any rendering.
#include "vkloc/localize/motion_prior.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "vkloc/core/se3.hpp"
#include "vkloc/sim/trajectory.hpp"

namespace vkloc {
namespace {

constexpr int64_t kFrameNs = 50'000'000;

Pose poseAt(double x, double yaw_deg) {
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(x, 0.1 * x, 1.0);
  T.linear() = expSO3(Eigen::Vector3d(0, 0, yaw_deg * M_PI / 180.0));
  return T;
}

TEST(ConstantVelocityPrior, ExtrapolatesTheLastMotion) {
  ConstantVelocityPrior prior;
  EXPECT_FALSE(prior.predict(0).has_value());
  prior.reset(poseAt(0, 0));
  ASSERT_TRUE(prior.predict(kFrameNs).has_value());
  EXPECT_TRUE(prior.predict(kFrameNs)->T_world_camera.isApprox(poseAt(0, 0)));  // no motion known yet
  EXPECT_TRUE(prior.predict(kFrameNs)->velocity_unobserved);
  prior.addVisualPose(0, poseAt(0, 0), Matrix6d::Identity());
  EXPECT_TRUE(prior.predict(kFrameNs)->velocity_unobserved);  // one pose: still no motion
  prior.addVisualPose(kFrameNs, poseAt(0.1, 2), Matrix6d::Identity());
  EXPECT_FALSE(prior.predict(2 * kFrameNs)->velocity_unobserved);
  // Twice the interval: twice the motion (a screw motion, here translation + yaw).
  const Pose expected = poseAt(0.1, 2) * expSE3(2.0 * logSE3(poseAt(0, 0).inverse() * poseAt(0.1, 2)));
  const auto p = prior.predict(3 * kFrameNs);
  ASSERT_TRUE(p.has_value());
  EXPECT_FALSE(p->inertial);
  EXPECT_TRUE(p->T_world_camera.isApprox(expected, 1e-12));
  // More than 10 intervals ahead: the last pose.
  EXPECT_TRUE(prior.predict(13 * kFrameNs)->T_world_camera.isApprox(poseAt(0.1, 2)));
  // A frame without a visual pose keeps the motion; nothing is reported for it.
  EXPECT_FALSE(prior.bridge(2 * kFrameNs, prior.predict(2 * kFrameNs), poseAt(5, 0)).has_value());
  EXPECT_TRUE(prior.lastPose()->isApprox(poseAt(0.1, 2)));
  EXPECT_TRUE(prior.consistent(*p, poseAt(100, 90), Matrix6d::Identity(), 1.0));  // no IMU: no gate
}

// A camera already in motion: the caller's velocity moves the first guesses until two timed
// poses give the motion; without it the start pose is held.
TEST(ConstantVelocityPrior, StartsInMotionWithTheCallersVelocity) {
  ConstantVelocityPrior prior;
  const Eigen::Vector3d v(25.0, 0.0, -2.0);  // m/s
  prior.reset(poseAt(0, 0), v);
  EXPECT_TRUE(prior.predict(0)->T_world_camera.isApprox(poseAt(0, 0)));  // no time yet
  prior.addVisualPose(kFrameNs, poseAt(0, 0), Matrix6d::Identity());
  const Pose guess = prior.predict(2 * kFrameNs)->T_world_camera;
  EXPECT_TRUE(guess.translation().isApprox(poseAt(0, 0).translation() + 0.05 * v, 1e-12));
  EXPECT_TRUE(guess.linear().isApprox(poseAt(0, 0).linear()));
  EXPECT_FALSE(prior.predict(2 * kFrameNs)->velocity_unobserved);  // the caller's velocity
  // Two timed poses: their motion takes over.
  prior.addVisualPose(2 * kFrameNs, poseAt(0.1, 2), Matrix6d::Identity());
  const Pose expected = poseAt(0.1, 2) * expSE3(logSE3(poseAt(0, 0).inverse() * poseAt(0.1, 2)));
  EXPECT_TRUE(prior.predict(3 * kFrameNs)->T_world_camera.isApprox(expected, 1e-12));
  // A non-finite velocity is not taken.
  prior.reset(poseAt(0, 0), Eigen::Vector3d(std::nan(""), 0, 0));
  prior.addVisualPose(kFrameNs, poseAt(0, 0), Matrix6d::Identity());
  EXPECT_TRUE(prior.predict(2 * kFrameNs)->T_world_camera.isApprox(poseAt(0, 0)));
}

TEST(ConstantVelocityPrior, LastPoseModelAndReset) {
  ConstantVelocityPrior prior(MotionModel::kLastPose);
  prior.reset(poseAt(0, 0));
  prior.addVisualPose(0, poseAt(0, 0), Matrix6d::Identity());
  prior.addVisualPose(kFrameNs, poseAt(0.1, 2), Matrix6d::Identity());
  EXPECT_TRUE(prior.predict(2 * kFrameNs)->T_world_camera.isApprox(poseAt(0.1, 2)));
  Pose invalid = Pose::Identity();
  invalid.linear() *= 2.0;
  prior.reset(invalid);
  EXPECT_FALSE(prior.predict(0).has_value());
  // A bridged frame without any pose takes the guess as the last pose.
  prior.bridge(0, std::nullopt, poseAt(3, 0));
  EXPECT_TRUE(prior.lastPose()->isApprox(poseAt(3, 0)));
  // Readings are checked even without an IMU model.
  ImuSample s;
  s.t_ns = 10;
  EXPECT_TRUE(prior.addImu(s).ok());
  EXPECT_FALSE(prior.addImu(s).ok());
  s.t_ns = 20;
  s.gyro_body.x() = NAN;
  EXPECT_FALSE(prior.addImu(s).ok());
}

/// A drone-like trajectory with exact IMU readings; camera = body.
struct Flight {
  SplineTrajectory trajectory;
  std::vector<ImuSample> imu;
};

/// Aiding options of the flight's world (z up, gravity -9.81 m/s^2).
InertialAiding flightAiding() {
  InertialAiding aiding;
  aiding.predictor.gravity_world = Eigen::Vector3d(0, 0, -9.81);
  return aiding;
}

/// Gives `prior` the readings of `imu` from index `next` up to and including time t_ns.
void feedImu(MotionPrior& prior, const std::vector<ImuSample>& imu, size_t& next, int64_t t_ns) {
  for (; next < imu.size() && imu[next].t_ns <= t_ns; ++next) ASSERT_TRUE(prior.addImu(imu[next]).ok());
}

/// An EKF prior reset at the flight's start state, its velocity given.
EkfPrior ekfAtStart(const InertialAiding& aiding, const TrajectoryState& start) {
  EkfPrior prior(aiding, MotionModel::kConstantVelocity);
  prior.reset(start.T_world_body, start.v_world_body);
  return prior;
}

Flight flight() {
  TrajectoryOptions o;
  o.kind = TrajectoryKind::kDroneFlight;
  o.duration_s = 4.0;
  o.seed = 3;
  Aabb box;
  box.min = {-50, -50, 0};
  box.max = {50, 50, 20};
  Flight f;
  f.trajectory = *makeTrajectory(o, box);
  f.imu = simulateImu(f.trajectory, std::nullopt, Eigen::Vector3d(0, 0, -9.81), 1);
  return f;
}

TEST(InertialPrior, PredictsFromTheImuGatesAndBridges) {
  const Flight f = flight();
  const InertialAiding aiding = flightAiding();
  InertialPrior prior(aiding, MotionModel::kConstantVelocity);
  const int64_t t0 = f.trajectory.startNs();
  prior.reset(f.trajectory.evaluate(t0).T_world_body);
  size_t next = 0;
  auto feed = [&](int64_t t) { feedImu(prior, f.imu, next, t); };
  // Visual poses (the truth) at 20 Hz for 1 s: then the IMU predicts.
  int64_t t = t0;
  for (int i = 0; i < 20; ++i, t += kFrameNs) {
    feed(t);
    prior.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, Matrix6d::Identity() * 1e-6);
  }
  feed(t);
  const auto p = prior.predict(t);
  ASSERT_TRUE(p.has_value());
  EXPECT_TRUE(p->inertial);
  const Pose truth = f.trajectory.evaluate(t).T_world_body;
  EXPECT_LT((p->T_world_camera.translation() - truth.translation()).norm(), 0.01);
  EXPECT_GT(p->sigma_m, 0.0);
  // The gate: the truth passes, a pose 1 m off or 5 degrees turned does not.
  EXPECT_TRUE(prior.consistent(*p, truth, Matrix6d::Identity() * 1e-6, 10.0));
  Pose off = truth;
  off.translation().x() += 1.0;
  EXPECT_FALSE(prior.consistent(*p, off, Matrix6d::Identity() * 1e-6, 10.0));
  Pose turned = truth;
  turned.linear() = truth.linear() * expSO3(Eigen::Vector3d(0, 0, 5.0 * M_PI / 180.0));
  EXPECT_FALSE(prior.consistent(*p, turned, Matrix6d::Identity() * 1e-6, 10.0));
  // A frame without a visual pose reports the inertial one, with its uncertainty.
  const auto bridged = prior.bridge(t, p, truth);
  ASSERT_TRUE(bridged.has_value());
  EXPECT_TRUE(bridged->T_world_camera.isApprox(p->T_world_camera));
  EXPECT_NEAR(bridged->covariance(0, 0), p->sigma_m * p->sigma_m, 1e-15);
  EXPECT_NEAR(bridged->covariance(3, 3), 1e-6, 1e-15);
  // Past max_inertial_s without a visual pose the IMU prediction expires (constant velocity then).
  const int64_t late = t + static_cast<int64_t>((aiding.max_inertial_s + 0.2) * 1e9);
  feed(late);
  const auto expired = prior.predict(late);
  ASSERT_TRUE(expired.has_value());
  EXPECT_FALSE(expired->inertial);
}

TEST(InertialPrior, DisabledAidingPredictsLikeConstantVelocity) {
  const Flight f = flight();
  InertialAiding aiding;
  aiding.enabled = false;
  InertialPrior prior(aiding, MotionModel::kConstantVelocity);
  ConstantVelocityPrior plain;
  const int64_t t0 = f.trajectory.startNs();
  prior.reset(f.trajectory.evaluate(t0).T_world_body);
  plain.reset(f.trajectory.evaluate(t0).T_world_body);
  for (const ImuSample& s : f.imu) ASSERT_TRUE(prior.addImu(s).ok());
  for (int i = 0; i < 10; ++i) {
    const int64_t t = t0 + i * kFrameNs;
    prior.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, Matrix6d::Identity());
    plain.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, Matrix6d::Identity());
  }
  const int64_t t = t0 + 10 * kFrameNs;
  ASSERT_FALSE(prior.predict(t)->inertial);
  EXPECT_TRUE(prior.predict(t)->T_world_camera.isApprox(plain.predict(t)->T_world_camera, 0));
  EXPECT_FALSE(prior.bridge(t, prior.predict(t), Pose::Identity()).has_value());
}

TEST(InertialAiding, OptionsOutOfRangeAreErrors) {
  InertialAiding a;
  EXPECT_TRUE(validateInertialAiding(a).ok());
  a.gate_rotation_deg = 200;
  EXPECT_FALSE(validateInertialAiding(a).ok());
  a = InertialAiding{};
  a.T_body_camera.linear() *= 2.0;
  EXPECT_FALSE(validateInertialAiding(a).ok());
  a = InertialAiding{};
  a.predictor.window_fixes = 1;
  EXPECT_FALSE(validateInertialAiding(a).ok());
}

}  // namespace
}  // namespace vkloc

namespace vkloc {
namespace {

// The EKF prior: from the first frame on, the gyro predicts the rotation and, with the
// caller's velocity, the IMU the position; unknown velocity is pinned down by the next poses.
// The chi-square gate passes the truth and refuses a pose 1 m off; a frame without a pose is
// bridged by the filter with its covariance, and the filter's states come out at the IMU rate.
TEST(EkfPrior, PredictsFromTheFirstFrameGatesBridgesAndOutputsAtTheImuRate) {
  const Flight f = flight();
  for (bool velocity_given : {true, false}) {
    SCOPED_TRACE(velocity_given ? "velocity given" : "velocity unknown");
    const InertialAiding aiding = flightAiding();
    EkfPrior prior(aiding, MotionModel::kConstantVelocity);
    const int64_t t0 = f.trajectory.startNs();
    const TrajectoryState start = f.trajectory.evaluate(t0);
    prior.reset(start.T_world_body, velocity_given ? std::optional<Eigen::Vector3d>(start.v_world_body) : std::nullopt);
    size_t next = 0;
    auto feed = [&](int64_t t) { feedImu(prior, f.imu, next, t); };
    const Matrix6d visual = Matrix6d::Identity() * 1e-6;  // 1 mm, 1 mrad
    feed(t0);
    prior.setSceneDepth(10.0);
    prior.addVisualPose(t0, start.T_world_body, visual);
    int64_t t = t0 + kFrameNs;
    feed(t);
    auto p = prior.predict(t);
    ASSERT_TRUE(p.has_value());
    EXPECT_TRUE(p->inertial);
    const Pose truth1 = f.trajectory.evaluate(t).T_world_body;
    // The rotation comes from the gyro at once.
    EXPECT_LT(rotationAngleDeg(p->T_world_camera.linear().transpose() * truth1.linear()), 0.01);
    const double err1 = (p->T_world_camera.translation() - truth1.translation()).norm();
    if (velocity_given) {
      EXPECT_LT(err1, 0.01);
    }
    // Until a second pose, an unknown start velocity is flagged (the gate cannot judge a pose).
    EXPECT_EQ(p->velocity_unobserved, !velocity_given);
    EXPECT_TRUE(prior.consistent(*p, truth1, visual, 10.0)) << prior.lastInnovation();
    EXPECT_TRUE(std::isfinite(prior.lastInnovation()));
    prior.addVisualPose(t, truth1, visual);
    // A second of poses: the velocity is known either way.
    for (int i = 0; i < 20; ++i) {
      t += kFrameNs;
      feed(t);
      prior.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, visual);
    }
    t += kFrameNs;
    feed(t);
    p = prior.predict(t);
    ASSERT_TRUE(p.has_value());
    EXPECT_FALSE(p->velocity_unobserved);
    const Pose truth = f.trajectory.evaluate(t).T_world_body;
    EXPECT_LT((p->T_world_camera.translation() - truth.translation()).norm(), 0.005);
    Pose off = truth;
    off.translation().x() += 1.0;
    EXPECT_FALSE(prior.consistent(*p, off, visual, 10.0));
    EXPECT_GT(prior.lastInnovation(), prior.filter().gateThreshold());
    // A pose the chi-square test refuses (a covariance of 0.1 mm) is still taken within the gate's
    // floor of the prediction (gate_depth_ratio x depth: 5 cm at 10 m), and refused beyond it.
    const Matrix6d tight = Matrix6d::Identity() * 1e-8;
    Pose near = p->T_world_camera;
    near.translation().x() += 0.04;
    EXPECT_TRUE(prior.consistent(*p, near, tight, 10.0));
    EXPECT_GT(prior.lastInnovation(), prior.filter().gateThreshold());
    near.translation().x() += 0.02;
    EXPECT_FALSE(prior.consistent(*p, near, tight, 10.0));
    const auto bridged = prior.bridge(t, p, truth);
    ASSERT_TRUE(bridged.has_value());
    EXPECT_TRUE(bridged->T_world_camera.isApprox(p->T_world_camera));
    EXPECT_GT(bridged->covariance(0, 0), 0.0);
    const std::vector<FilterOutput> outputs = prior.takeOutputs();
    ASSERT_GT(outputs.size(), 150u);  // 200 Hz over ~1.1 s
    for (size_t i = 1; i < outputs.size(); ++i) EXPECT_GT(outputs[i].t_ns, outputs[i - 1].t_ns);
    const TrajectoryState last = f.trajectory.evaluate(outputs.back().t_ns);
    EXPECT_LT((outputs.back().v_world_body - last.v_world_body).norm(), 0.05);
    EXPECT_TRUE(prior.takeOutputs().empty());
  }
}

// The filter's prediction carries its velocity and that velocity's sigma (what a restart keeps);
// a reset with a velocity starts the filter at it, tight (0.1 m/s) unless a sigma is given.
TEST(EkfPrior, PredictionsCarryTheVelocityAndAResetTakesItsSigma) {
  const Flight f = flight();
  const int64_t t0 = f.trajectory.startNs();
  const TrajectoryState start = f.trajectory.evaluate(t0);
  const Matrix6d visual = Matrix6d::Identity() * 1e-6;
  for (const double sigma_v : {0.0, 2.0}) {
    SCOPED_TRACE(sigma_v);
    EkfPrior prior(flightAiding(), MotionModel::kConstantVelocity);
    prior.reset(start.T_world_body, start.v_world_body, sigma_v);
    size_t next = 0;
    feedImu(prior, f.imu, next, t0);
    prior.setSceneDepth(10.0);
    prior.addVisualPose(t0, start.T_world_body, visual);
    const auto p = prior.predict(t0 + kFrameNs / 10);
    ASSERT_TRUE(p.has_value());
    ASSERT_TRUE(p->v_world_body.has_value());
    EXPECT_LT((*p->v_world_body - start.v_world_body).norm(), 0.05);
    // Started at the given sigma, hardly grown over 5 ms.
    EXPECT_NEAR(p->sigma_velocity_m_s, sigma_v > 0 ? sigma_v : 0.1, 0.02);
  }
  ConstantVelocityPrior plain;
  plain.reset(start.T_world_body, start.v_world_body, 2.0);
  const auto q = plain.predict(t0 + kFrameNs);
  ASSERT_TRUE(q.has_value());
  EXPECT_FALSE(q->v_world_body.has_value());
}

// Past max_inertial_s without a pose the prediction goes back to the motion model, whose attitude
// is the last pose's; the filter's attitude goes on with the gyro (what a stabilised view turns
// with), and through a ViewPrior it is the view's.
TEST(EkfPrior, TheAttitudeGoesOnPastTheInertialStretch) {
  const Flight f = flight();
  const InertialAiding aiding = flightAiding();
  const int64_t t0 = f.trajectory.startNs();
  ViewPrior view(std::make_unique<EkfPrior>(ekfAtStart(aiding, f.trajectory.evaluate(t0))));
  EXPECT_FALSE(view.attitude(t0).has_value());  // before the filter starts
  size_t next = 0;
  const Matrix6d visual = Matrix6d::Identity() * 1e-6;
  for (int i = 0; i < 3; ++i) {
    const int64_t t = t0 + i * kFrameNs;
    feedImu(view, f.imu, next, t);
    view.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, visual);  // the view is the camera
  }
  const int64_t t_late = t0 + 2 * kFrameNs + static_cast<int64_t>((aiding.max_inertial_s + 0.5) * 1e9);
  feedImu(view, f.imu, next, t_late);
  const auto p = view.cameraPrior().predict(t_late);
  ASSERT_TRUE(p.has_value());
  EXPECT_FALSE(p->inertial);
  const Eigen::Matrix3d R_truth = f.trajectory.evaluate(t_late).T_world_body.linear();
  EXPECT_GT(rotationAngleDeg(p->T_world_camera.linear().transpose() * R_truth), 1.0);  // the stale one
  const std::optional<Eigen::Matrix3d> R = view.cameraPrior().attitude(t_late);
  ASSERT_TRUE(R.has_value());
  EXPECT_LT(rotationAngleDeg(R->transpose() * R_truth), 0.1);
  // Through a view turned by T_camera_view: R_world_camera R_camera_view.
  Pose T_camera_view = Pose::Identity();
  T_camera_view.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  view.setView(T_camera_view);
  const std::optional<Eigen::Matrix3d> R_view = view.attitude(t_late);
  ASSERT_TRUE(R_view.has_value());
  EXPECT_LT(rotationAngleDeg(R_view->transpose() * (*R * T_camera_view.linear())), 1e-9);

  ConstantVelocityPrior plain;
  plain.reset(poseAt(0, 0));
  EXPECT_FALSE(plain.attitude(0).has_value());
}

// Frames delivered late (the IMU fed 60 ms past each frame): the prediction, the gate and the
// update are at the frame's time, so the truth passes and the filter ends where it would have
// with the frames on time; a pose 1 m off is still refused.
TEST(EkfPrior, FramesDeliveredLateAreGatedAndAppliedAtTheirOwnTime) {
  const Flight f = flight();
  const int64_t delay = 60'000'000;
  const Matrix6d visual = Matrix6d::Identity() * 1e-6;
  const InertialAiding aiding = flightAiding();
  std::optional<Pose> on_time_end;
  for (int64_t lag : {int64_t{0}, delay}) {
    SCOPED_TRACE(lag > 0 ? "late" : "on time");
    const int64_t t0 = f.trajectory.startNs();
    const TrajectoryState start = f.trajectory.evaluate(t0);
    EkfPrior prior = ekfAtStart(aiding, start);
    size_t next = 0;
    auto feed = [&](int64_t t) { feedImu(prior, f.imu, next, t); };
    feed(t0);
    prior.addVisualPose(t0, start.T_world_body, visual);
    int64_t t = t0;
    for (int i = 0; i < 25; ++i) {
      t += kFrameNs;
      feed(t + lag);
      auto p = prior.predict(t);
      ASSERT_TRUE(p.has_value());
      const Pose truth = f.trajectory.evaluate(t).T_world_body;
      EXPECT_LT((p->T_world_camera.translation() - truth.translation()).norm(), 0.01) << i;
      EXPECT_TRUE(prior.consistent(*p, truth, visual, 10.0)) << i << " " << prior.lastInnovation();
      Pose off = truth;
      off.translation().x() += 1.0;
      EXPECT_FALSE(prior.consistent(*p, off, visual, 10.0)) << i;
      prior.addVisualPose(t, truth, visual);
    }
    feed(t + delay);
    const auto end = prior.predict(t + delay);
    ASSERT_TRUE(end.has_value());
    if (!on_time_end) {
      on_time_end = end->T_world_camera;
    } else {
      EXPECT_LT((end->T_world_camera.translation() - on_time_end->translation()).norm(), 1e-6);
    }
  }
}

// The filter's estimate at a frame it took a pose at (LocalizerOptions::report_filtered_pose):
// the posterior lies between the prediction and the pose, weighed by their covariances, and is
// closer to the truth than a pose that slid off; priors that do not fuse have none, nor has a
// frame the filter took no pose at.
TEST(EkfPrior, FilteredIsThePosteriorAtTheFrameOfAnUpdate) {
  const Flight f = flight();
  const InertialAiding aiding = flightAiding();
  const int64_t t0 = f.trajectory.startNs();
  const TrajectoryState start = f.trajectory.evaluate(t0);
  EkfPrior prior = ekfAtStart(aiding, start);
  size_t next = 0;
  auto feed = [&](int64_t t) { feedImu(prior, f.imu, next, t); };
  const Matrix6d visual = Matrix6d::Identity() * 1e-4;  // 1 cm, 10 mrad
  feed(t0);
  EXPECT_FALSE(prior.filtered(t0).has_value());  // no filter before the first pose
  prior.addVisualPose(t0, start.T_world_body, visual);
  int64_t t = t0;
  for (int i = 0; i < 20; ++i) {
    t += kFrameNs;
    feed(t);
    prior.addVisualPose(t, f.trajectory.evaluate(t).T_world_body, visual);
    ASSERT_TRUE(prior.filtered(t).has_value()) << i;
  }
  t += kFrameNs;
  feed(t);
  const auto p = prior.predict(t);
  ASSERT_TRUE(p.has_value());
  EXPECT_FALSE(prior.filtered(t).has_value());  // no pose taken at t yet
  const Pose truth = f.trajectory.evaluate(t).T_world_body;
  Pose slid = truth;
  slid.translation().x() += 0.03;  // 3 sigma of the pose's own covariance
  prior.addVisualPose(t, slid, visual);
  const auto post = prior.filtered(t);
  ASSERT_TRUE(post.has_value());
  EXPECT_TRUE(post->inertial);
  const double x_pred = p->T_world_camera.translation().x(), x_post = post->T_world_camera.translation().x();
  EXPECT_GT(x_post, std::min(x_pred, slid.translation().x()) - 1e-9);
  EXPECT_LT(x_post, std::max(x_pred, slid.translation().x()) + 1e-9);
  EXPECT_LT((post->T_world_camera.translation() - truth.translation()).norm(),
            0.5 * (slid.translation() - truth.translation()).norm());
  // Tighter than either: the pose (its covariance x the filter's calibration) and the prediction.
  EXPECT_LT(post->covariance(0, 0), aiding.ekf.measurement_covariance_scale * visual(0, 0));
  EXPECT_LT(post->covariance(0, 0), p->covariance(0, 0));
  EXPECT_FALSE(prior.filtered(t - kFrameNs).has_value());  // only the last update's frame

  // Seen through a view turned about the optical centre: the same posterior, in the view.
  ViewPrior view(std::make_unique<EkfPrior>(prior));
  Pose T_camera_view = Pose::Identity();
  T_camera_view.linear() = expSO3(Eigen::Vector3d(0.3, 0, 0));
  view.setView(T_camera_view);
  const auto in_view = view.filtered(t);
  ASSERT_TRUE(in_view.has_value());
  EXPECT_TRUE(view.toCamera(in_view->T_world_camera).isApprox(post->T_world_camera, 1e-9));

  ConstantVelocityPrior plain;
  plain.reset(poseAt(0, 0));
  plain.addVisualPose(kFrameNs, poseAt(0.1, 1), visual);
  EXPECT_FALSE(plain.filtered(kFrameNs).has_value());
}

// Without IMU readings the EKF prior is the constant-velocity prior.
TEST(EkfPrior, WithoutReadingsItIsTheConstantVelocityPrior) {
  InertialAiding aiding;
  EkfPrior prior(aiding, MotionModel::kConstantVelocity);
  ConstantVelocityPrior plain;
  prior.reset(poseAt(0, 0));
  plain.reset(poseAt(0, 0));
  for (int i = 0; i < 3; ++i) {
    prior.addVisualPose(i * kFrameNs, poseAt(0.1 * i, i), Matrix6d::Identity());
    plain.addVisualPose(i * kFrameNs, poseAt(0.1 * i, i), Matrix6d::Identity());
  }
  const auto a = prior.predict(3 * kFrameNs), b = plain.predict(3 * kFrameNs);
  ASSERT_TRUE(a && b);
  EXPECT_FALSE(a->inertial);
  EXPECT_TRUE(a->T_world_camera.isApprox(b->T_world_camera, 1e-12));
  EXPECT_FALSE(prior.bridge(3 * kFrameNs, a, poseAt(5, 0)).has_value());
}

// A refused pose counts against the prior when it verifies confidently, or above every one of
// the last poses the prior took (imagery whose true poses verify poorly: room hard's 0.2-0.3).
TEST(PriorRestart, ARefusedPoseCountsWhenConfidentOrBetterThanWhatThePriorTook) {
  const std::vector<double> poor = {0.22, 0.17, 0.11, 0.08, 0.04};
  EXPECT_TRUE(refusalCountsAgainstPrior(0.24, poor, 5, 0.5, 0.15));
  EXPECT_FALSE(refusalCountsAgainstPrior(0.21, poor, 5, 0.5, 0.15));                       // below the best taken
  EXPECT_FALSE(refusalCountsAgainstPrior(0.22, poor, 5, 0.5, 0.15));                       // equal is not above
  EXPECT_FALSE(refusalCountsAgainstPrior(0.12, {0.1, 0.1, 0.1, 0.1, 0.1}, 5, 0.5, 0.15));  // not verified
  EXPECT_TRUE(refusalCountsAgainstPrior(0.6, {0.9, 0.9, 0.9, 0.9, 0.9}, 5, 0.5, 0.15));    // confident
  // Only the last `window` poses are compared; fewer than that: only the confident bar applies.
  EXPECT_TRUE(refusalCountsAgainstPrior(0.3, {0.9, 0.2, 0.2, 0.2, 0.2, 0.2}, 5, 0.5, 0.15));
  EXPECT_FALSE(refusalCountsAgainstPrior(0.3, {0.2, 0.2}, 5, 0.5, 0.15));
  EXPECT_FALSE(refusalCountsAgainstPrior(0.3, poor, 0, 0.5, 0.15));
  EXPECT_FALSE(refusalCountsAgainstPrior(std::nan(""), poor, 5, 0.5, 0.15));
}

// At the first frame after a start at an unknown velocity the gyro's attitude tells an alignment
// that slid along the turn-for-translation valley from a feature pose that did not.
TEST(FeatureStart, TheGyrosAttitudeSidesWithTheFeaturePoseOnlyWhenTheAlignmentTurnedAway) {
  MotionPrediction prediction;
  prediction.inertial = true;
  prediction.T_world_camera = poseAt(1.0, 90);  // turned, so that camera and world axes differ
  const double sigma_rad = 0.1 * EIGEN_PI / 180.0;
  prediction.covariance.bottomRightCorner<3, 3>() = sigma_rad * sigma_rad * Eigen::Matrix3d::Identity();
  const auto turned = [&](double deg, const Eigen::Vector3d& axis) {
    Pose T = prediction.T_world_camera;
    T.linear() = T.linear() * expSO3(deg * EIGEN_PI / 180.0 * axis.normalized());
    T.translation() += Eigen::Vector3d(0.03, 0, 0);  // the position plays no part
    return T;
  };
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  EXPECT_TRUE(attitudeFavoursFeaturePose(prediction, turned(0.09, y), turned(0.40, y), 2.5));   // 4 sigmas vs 0.9
  EXPECT_FALSE(attitudeFavoursFeaturePose(prediction, turned(0.09, y), turned(0.20, y), 2.5));  // 2 sigmas: within
  EXPECT_FALSE(
      attitudeFavoursFeaturePose(prediction, turned(0.25, y), turned(0.40, y), 2.5));  // feature not nearer by half
  // A feature pose beyond half the sigmas does not side with the gyro, however far the alignment.
  EXPECT_TRUE(attitudeFavoursFeaturePose(prediction, turned(0.12, y), turned(1.0, y), 2.5));   // 1.2 sigmas
  EXPECT_FALSE(attitudeFavoursFeaturePose(prediction, turned(0.13, y), turned(1.0, y), 2.5));  // 1.3 sigmas
  EXPECT_FALSE(
      attitudeFavoursFeaturePose(prediction, turned(0.79, y), turned(0.05, y), 2.5));  // the feature pose turned
  // The covariance's shape counts: 0.4 deg about an axis the gyro knows to 0.5 deg is nothing.
  MotionPrediction loose = prediction;
  loose.covariance(4, 4) = std::pow(0.5 * EIGEN_PI / 180.0, 2);
  EXPECT_FALSE(attitudeFavoursFeaturePose(loose, turned(0.09, y), turned(0.40, y), 2.5));
  EXPECT_TRUE(attitudeFavoursFeaturePose(loose, turned(0.09, Eigen::Vector3d::UnitX()),
                                         turned(0.40, Eigen::Vector3d::UnitX()), 2.5));
  // Off: sigmas 0, a prediction not from the IMU, no rotation covariance.
  EXPECT_FALSE(attitudeFavoursFeaturePose(prediction, turned(0.09, y), turned(0.40, y), 0.0));
  MotionPrediction not_inertial = prediction;
  not_inertial.inertial = false;
  EXPECT_FALSE(attitudeFavoursFeaturePose(not_inertial, turned(0.09, y), turned(0.40, y), 2.5));
  Pose not_finite = turned(0.09, y);
  not_finite.linear()(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(attitudeFavoursFeaturePose(prediction, not_finite, turned(0.40, y), 2.5));
  EXPECT_FALSE(attitudeFavoursFeaturePose(prediction, turned(0.09, y), not_finite, 2.5));
  MotionPrediction no_covariance = prediction;
  no_covariance.covariance.setZero();
  EXPECT_FALSE(attitudeFavoursFeaturePose(no_covariance, turned(0.09, y), turned(0.40, y), 2.5));
}

}  // namespace
}  // namespace vkloc
