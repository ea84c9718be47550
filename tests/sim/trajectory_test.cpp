// Tests of the continuous-time trajectories, the built-in generators, the synthetic IMU and
// priors, and the IMU integrator.
#include "vkloc/sim/trajectory.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
const Vector3d kGravity(0.0, 0.0, -9.81);

Aabb box(const Vector3d& lo, const Vector3d& hi) {
  Aabb b;
  for (size_t a = 0; a < 3; ++a) {
    b.min[a] = static_cast<float>(lo[static_cast<Eigen::Index>(a)]);
    b.max[a] = static_cast<float>(hi[static_cast<Eigen::Index>(a)]);
  }
  return b;
}
/// The demo city's extent and the demo room (6 x 5 x 3 m).
const Aabb kCity = box(Vector3d(-100, -100, 0), Vector3d(100, 100, 60));
const Aabb kRoom = box(Vector3d(-3, -2.5, 0), Vector3d(3, 2.5, 3));

/// Independent SO(3) maps (Eigen's angle-axis).
Matrix3d expRot(const Vector3d& w) {
  const double angle = w.norm();
  if (angle == 0.0) return Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}
Vector3d logRot(const Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}
double angleBetweenDeg(const Matrix3d& A, const Matrix3d& B) { return logRot(A.transpose() * B).norm() / kDeg; }

SplineTrajectory makeKind(TrajectoryKind kind, double duration_s, uint64_t seed,
                          const Pose& T_body_camera = Pose::Identity()) {
  TrajectoryOptions o;
  o.kind = kind;
  o.duration_s = duration_s;
  o.seed = seed;
  o.T_body_camera = T_body_camera;
  const bool outdoor = isDroneKind(kind) || kind == TrajectoryKind::kOrbit;
  const Aabb& bounds = outdoor ? kCity : kRoom;
  auto t = makeTrajectory(o, bounds);
  EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  return t.ok() ? *t : SplineTrajectory{};
}

/// A non-trivial camera mounting: camera looking along body x, 10 cm ahead and 5 cm below.
Pose mounting() {
  Pose T = Pose::Identity();
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // camera z = body x, camera x = -body y.
  T.translation() = Vector3d(0.1, 0.0, -0.05);
  return T;
}

/// Random control poses: positions on a random walk, rotations with steps up to ~0.6 rad.
std::vector<Pose> randomControls(size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Pose> poses;
  Pose T = Pose::Identity();
  T.translation() = Vector3d(50, -20, 30);
  for (size_t k = 0; k < n; ++k) {
    T.translation() += Vector3d(u(rng), u(rng), u(rng));
    T.linear() = T.linear() * expRot(0.35 * Vector3d(u(rng), u(rng), u(rng)));
    poses.push_back(T);
  }
  return poses;
}

const TrajectoryKind kAllKinds[] = {TrajectoryKind::kDroneFlight, TrajectoryKind::kDroneAgile,
                                    TrajectoryKind::kHandheld,    TrajectoryKind::kAggressive,
                                    TrajectoryKind::kOrbit,       TrajectoryKind::kDroneAcro};

// ------------------------------------------------------------------------------------------------
// (1) Exact derivatives against central finite differences of evaluate().
// ------------------------------------------------------------------------------------------------

void expectDerivativesMatch(const SplineTrajectory& s, int64_t dt_ns, const char* what) {
  const int64_t h1 = 10000;    // 10 us for first derivatives.
  const int64_t h2 = 1000000;  // 1 ms for the second difference (exact within a cubic segment).
  double worst_v = 0.0, worst_a = 0.0, worst_w = 0.0;
  for (int64_t t = s.startNs() + dt_ns / 2; t < s.endNs(); t += dt_ns * 7 / 3) {
    const TrajectoryState c = s.evaluate(t);
    const TrajectoryState m1 = s.evaluate(t - h1), p1 = s.evaluate(t + h1);
    const TrajectoryState m2 = s.evaluate(t - h2), p2 = s.evaluate(t + h2);
    const double s1 = static_cast<double>(h1) * 1e-9, s2 = static_cast<double>(h2) * 1e-9;
    const Vector3d v_fd = (p1.T_world_body.translation() - m1.T_world_body.translation()) / (2.0 * s1);
    const Vector3d a_fd =
        (p2.T_world_body.translation() - 2.0 * c.T_world_body.translation() + m2.T_world_body.translation()) /
        (s2 * s2);
    const Vector3d w_fd = logRot(m1.T_world_body.linear().transpose() * p1.T_world_body.linear()) / (2.0 * s1);
    worst_v = std::max(worst_v, (v_fd - c.v_world_body).norm());
    worst_a = std::max(worst_a, (a_fd - c.a_world_body).norm());
    worst_w = std::max(worst_w, (w_fd - c.omega_body).norm());
  }
  EXPECT_LT(worst_v, 1e-6) << what << " velocity, m/s";
  EXPECT_LT(worst_a, 1e-4) << what << " acceleration, m/s^2";
  EXPECT_LT(worst_w, 1e-6) << what << " angular velocity, rad/s";
}

TEST(SplineTrajectory, DerivativesMatchFiniteDifferences) {
  const int64_t dt = 100000000;
  auto s = SplineTrajectory::fromControlPoses(randomControls(30, 7), 0, dt);
  ASSERT_TRUE(s.ok());
  expectDerivativesMatch(*s, dt, "random");
  for (TrajectoryKind kind : kAllKinds) {
    const SplineTrajectory g = makeKind(kind, 5.0, 2, mounting());
    expectDerivativesMatch(g, kind == TrajectoryKind::kAggressive ? 50000000 : 100000000, trajectoryKindName(kind));
  }
}

// ------------------------------------------------------------------------------------------------
// (2) B-spline properties.
// ------------------------------------------------------------------------------------------------

TEST(SplineTrajectory, ConstantControlPosesGiveAConstantPose) {
  Pose T = Pose::Identity();
  T.linear() = expRot(Vector3d(0.3, -1.2, 2.0));
  T.translation() = Vector3d(1, 2, 3);
  auto s = SplineTrajectory::fromControlPoses(std::vector<Pose>(6, T), 1000, 50000000);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->startNs(), 1000 + 50000000);
  EXPECT_EQ(s->endNs(), 1000 + 4 * 50000000);
  for (int64_t t = s->startNs(); t <= s->endNs(); t += 7000000) {
    const TrajectoryState st = s->evaluate(t);
    EXPECT_LT((st.T_world_body.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT(st.v_world_body.norm(), 1e-12);
    EXPECT_LT(st.a_world_body.norm(), 1e-12);
    EXPECT_LT(st.omega_body.norm(), 1e-12);
  }
}

TEST(SplineTrajectory, UniformStepsGiveConstantVelocityExactly) {
  // p_k = p0 + k dp, R_k = R0 exp(k phi): a B-spline reproduces linear functions, and the
  // cumulative weights sum to s = (t - t0) / dt, so p(t) = p0 + s dp and R(t) = R0 exp(s phi).
  const Vector3d p0(3, -4, 5), dp(0.2, 0.05, -0.1), phi(0.1, -0.2, 0.15);
  const Matrix3d R0 = expRot(Vector3d(0.5, 0.1, -0.7));
  const int64_t t0 = -20000000, dt = 20000000;
  std::vector<Pose> controls;
  for (int k = 0; k < 10; ++k) {
    Pose T = Pose::Identity();
    T.translation() = p0 + k * dp;
    T.linear() = R0 * expRot(k * phi);
    controls.push_back(T);
  }
  auto s = SplineTrajectory::fromControlPoses(controls, t0, dt);
  ASSERT_TRUE(s.ok());
  const double dts = static_cast<double>(dt) * 1e-9;
  for (int64_t t = s->startNs(); t <= s->endNs(); t += 3333333) {
    const double sk = static_cast<double>(t - t0) / static_cast<double>(dt);
    const TrajectoryState st = s->evaluate(t);
    EXPECT_LT((st.T_world_body.translation() - (p0 + sk * dp)).norm(), 1e-12);
    EXPECT_LT((st.v_world_body - dp / dts).norm(), 1e-10);
    EXPECT_LT(st.a_world_body.norm(), 1e-8);
    EXPECT_LT(angleBetweenDeg(st.T_world_body.linear(), R0 * expRot(sk * phi)), 1e-10);
    EXPECT_LT((st.omega_body - phi / dts).norm(), 1e-10);
  }
}

TEST(SplineTrajectory, KnotValuesAreTheBSplineAverages) {
  // At knot t_i: p = (p_{i-1} + 4 p_i + p_{i+1}) / 6, v = (p_{i+1} - p_{i-1}) / (2 dt),
  // a = (p_{i-1} - 2 p_i + p_{i+1}) / dt^2.
  const std::vector<Pose> c = randomControls(8, 3);
  const int64_t dt = 100000000;
  auto s = SplineTrajectory::fromControlPoses(c, 0, dt);
  ASSERT_TRUE(s.ok());
  for (size_t i = 1; i + 1 < c.size(); ++i) {
    const TrajectoryState st = s->evaluate(static_cast<int64_t>(i) * dt);
    const Vector3d pm = c[i - 1].translation(), p = c[i].translation(), pp = c[i + 1].translation();
    EXPECT_LT((st.T_world_body.translation() - (pm + 4 * p + pp) / 6.0).norm(), 1e-12) << i;
    EXPECT_LT((st.v_world_body - (pp - pm) / 0.2).norm(), 1e-10) << i;
    EXPECT_LT((st.a_world_body - (pm - 2 * p + pp) / 0.01).norm(), 1e-8) << i;
  }
  // Clamping outside the domain.
  EXPECT_EQ(s->evaluate(-5).T_world_body.matrix(), s->evaluate(s->startNs()).T_world_body.matrix());
  EXPECT_EQ(s->evaluate(s->endNs() + 99).T_world_body.matrix(), s->evaluate(s->endNs()).T_world_body.matrix());
}

TEST(SplineTrajectory, RejectsBadInput) {
  const std::vector<Pose> three(3, Pose::Identity());
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(three, 0, 1000).ok());
  std::vector<Pose> four(4, Pose::Identity());
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(four, 0, 0).ok());
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(four, 0, -5).ok());
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(four, 0, int64_t{1} << 62).ok());
  four[2].translation().x() = std::nan("");
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(four, 0, 1000).ok());
  four[2] = Pose::Identity();
  four[1].linear() *= 1.1;
  EXPECT_FALSE(SplineTrajectory::fromControlPoses(four, 0, 1000).ok());
  // An empty trajectory evaluates to identity without crashing.
  const SplineTrajectory empty;
  EXPECT_EQ(empty.evaluate(123).T_world_body.matrix(), Pose::Identity().matrix());
}

// ------------------------------------------------------------------------------------------------
// (3) Exact IMU readings integrate back to the ground truth.
// ------------------------------------------------------------------------------------------------

TEST(Imu, ReadingsAtRestAreGravityOnly) {
  auto s = SplineTrajectory::fromControlPoses(std::vector<Pose>(5, Pose::Identity()), 0, 100000000);
  ASSERT_TRUE(s.ok());
  const std::vector<ImuSample> imu = simulateImu(*s, std::nullopt, kGravity, 1);
  ASSERT_EQ(imu.size(), 41u);  // 0.2 s at 200 Hz, both ends included.
  for (size_t k = 0; k < imu.size(); ++k) {
    EXPECT_EQ(imu[k].t_ns, s->startNs() + static_cast<int64_t>(k) * 5000000);
    EXPECT_LT((imu[k].accel_body - Vector3d(0, 0, 9.81)).norm(), 1e-12);
    EXPECT_LT(imu[k].gyro_body.norm(), 1e-12);
  }
}

TEST(Imu, IntegratorIsExactForLinearAccelerationAndConstantRate) {
  // Hand-made readings: no rotation and specific force (j t, 0, 9.81) give a = (j t, 0, 0), so
  // p(t) = p0 + v0 t + j t^3 / 6; a constant rate w gives R(t) = exp(w t). Biases added to the
  // readings and passed to the integrator cancel.
  const double j = 2.0;
  const Vector3d bg(0.01, -0.02, 0.03), ba(0.1, 0.2, -0.3);
  std::vector<ImuSample> linear, rotating;
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.01 * k;
    ImuSample s;
    s.t_ns = static_cast<int64_t>(k) * 10000000;
    s.gyro_body = bg;
    s.accel_body = Vector3d(j * t, 0.0, 9.81) + ba;
    linear.push_back(s);
    s.gyro_body = Vector3d(0.3, -0.4, 1.2);
    s.accel_body = Vector3d::Zero();
    rotating.push_back(s);
  }
  TrajectoryState initial;
  initial.T_world_body.translation() = Vector3d(1, 2, 3);
  initial.v_world_body = Vector3d(0.5, -1, 0.25);
  const std::vector<TrajectoryState> a = integrateImu(initial, linear, kGravity, bg, ba);
  ASSERT_EQ(a.size(), linear.size());
  for (size_t k = 0; k < a.size(); ++k) {
    const double t = 0.01 * static_cast<double>(k);
    const Vector3d p = Vector3d(1, 2, 3) + t * Vector3d(0.5, -1, 0.25) + Vector3d(j * t * t * t / 6.0, 0, 0);
    EXPECT_LT((a[k].T_world_body.translation() - p).norm(), 1e-12) << k;
    EXPECT_LT((a[k].v_world_body - Vector3d(0.5 + 0.5 * j * t * t, -1, 0.25)).norm(), 1e-12) << k;
    EXPECT_LT(angleBetweenDeg(a[k].T_world_body.linear(), Matrix3d::Identity()), 1e-12);
  }
  const std::vector<TrajectoryState> r = integrateImu(TrajectoryState{}, rotating, Vector3d::Zero());
  EXPECT_LT(angleBetweenDeg(r.back().T_world_body.linear(), expRot(Vector3d(0.3, -0.4, 1.2))), 1e-10);
  // No samples: just the initial state.
  EXPECT_EQ(integrateImu(initial, {}, kGravity).size(), 1u);
}

TEST(Imu, ExactReadingsIntegrateToGroundTruth) {
  for (TrajectoryKind kind : kAllKinds) {
    const SplineTrajectory s = makeKind(kind, 10.0, 5, mounting());
    const std::vector<ImuSample> imu = simulateImu(s, std::nullopt, kGravity, 0);
    ASSERT_EQ(imu.size(), 2001u) << trajectoryKindName(kind);
    double worst_p = 0.0, worst_r = 0.0;
    for (size_t start = 0; start + 200 < imu.size(); start += 450) {
      const std::vector<ImuSample> window(imu.begin() + static_cast<std::ptrdiff_t>(start),
                                          imu.begin() + static_cast<std::ptrdiff_t>(start + 201));
      const std::vector<TrajectoryState> states = integrateImu(s.evaluate(window.front().t_ns), window, kGravity);
      ASSERT_EQ(states.size(), window.size());
      const TrajectoryState truth = s.evaluate(window.back().t_ns);
      EXPECT_EQ(states.back().t_ns, truth.t_ns);
      worst_p = std::max(worst_p, (states.back().T_world_body.translation() - truth.T_world_body.translation()).norm());
      worst_r = std::max(worst_r, angleBetweenDeg(states.back().T_world_body.linear(), truth.T_world_body.linear()));
    }
    EXPECT_LT(worst_p, 1e-3) << trajectoryKindName(kind) << ": position error after 1 s, m";
    EXPECT_LT(worst_r, 0.01) << trajectoryKindName(kind) << ": rotation error after 1 s, deg";
  }
}

// ------------------------------------------------------------------------------------------------
// (4) Noise statistics and drift.
// ------------------------------------------------------------------------------------------------

double stddev(const std::vector<double>& x) {
  double mean = 0.0;
  for (double v : x) mean += v;
  mean /= static_cast<double>(x.size());
  double var = 0.0;
  for (double v : x) var += (v - mean) * (v - mean);
  return std::sqrt(var / static_cast<double>(x.size() - 1));
}

TEST(Imu, NoiseMatchesTheDensities) {
  const SplineTrajectory s = makeKind(TrajectoryKind::kHandheld, 10.0, 9);
  const ImuNoise noise;  // Defaults.
  const std::vector<ImuSample> imu = simulateImu(s, noise, kGravity, 42);
  ASSERT_EQ(imu.size(), 2001u);
  std::vector<double> gyro, gyro_diff, accel_diff;
  double gyro_mean = 0.0;
  Vector3d prev_g = Vector3d::Zero(), prev_a = Vector3d::Zero();
  for (size_t k = 0; k < imu.size(); ++k) {
    // Truth from the trajectory directly: body rate and specific force.
    const TrajectoryState st = s.evaluate(imu[k].t_ns);
    const Vector3d eg = imu[k].gyro_body - st.omega_body;
    const Vector3d ea = imu[k].accel_body - st.T_world_body.linear().transpose() * (st.a_world_body - kGravity);
    for (int a = 0; a < 3; ++a) {
      gyro.push_back(eg[a]);
      gyro_mean += eg[a];
      if (k > 0) {
        gyro_diff.push_back(eg[a] - prev_g[a]);
        accel_diff.push_back(ea[a] - prev_a[a]);
      }
    }
    prev_g = eg;
    prev_a = ea;
  }
  gyro_mean /= static_cast<double>(gyro.size());
  const double sq = std::sqrt(noise.rate_hz);
  const double gyro_sigma = noise.gyro_noise_density * sq, accel_sigma = noise.accel_noise_density * sq;
  const double gyro_step = noise.gyro_random_walk / sq, accel_step = noise.accel_random_walk / sq;
  EXPECT_NEAR(stddev(gyro) / gyro_sigma, 1.0, 0.1);
  EXPECT_LT(std::abs(gyro_mean), 0.1 * gyro_sigma);
  // Differences of consecutive errors: variance 2 sigma^2 + (bias step)^2.
  const double gd = stddev(gyro_diff), ad = stddev(accel_diff);
  EXPECT_NEAR(std::sqrt((gd * gd - gyro_step * gyro_step) / 2.0) / gyro_sigma, 1.0, 0.1);
  EXPECT_NEAR(std::sqrt((ad * ad - accel_step * accel_step) / 2.0) / accel_sigma, 1.0, 0.1);

  // Pure bias random walk: the per-sample increments have sigma rw / sqrt(rate).
  ImuNoise walk_only = noise;
  walk_only.gyro_noise_density = 0.0;
  walk_only.accel_noise_density = 0.0;
  walk_only.gyro_random_walk = 1e-3;
  walk_only.accel_random_walk = 1e-2;
  const std::vector<ImuSample> walk = simulateImu(s, walk_only, kGravity, 43);
  const std::vector<ImuSample> exact = simulateImu(s, std::nullopt, kGravity, 43);
  ASSERT_EQ(walk.size(), exact.size());
  EXPECT_EQ((walk[0].gyro_body - exact[0].gyro_body).norm(), 0.0);  // Biases start at zero.
  std::vector<double> dg, da;
  for (size_t k = 1; k < walk.size(); ++k) {
    for (int a = 0; a < 3; ++a) {
      dg.push_back((walk[k].gyro_body - exact[k].gyro_body - walk[k - 1].gyro_body + exact[k - 1].gyro_body)[a]);
      da.push_back((walk[k].accel_body - exact[k].accel_body - walk[k - 1].accel_body + exact[k - 1].accel_body)[a]);
    }
  }
  EXPECT_NEAR(stddev(dg) / (1e-3 / sq), 1.0, 0.1);
  EXPECT_NEAR(stddev(da) / (1e-2 / sq), 1.0, 0.1);

  // Deterministic in the seed.
  const std::vector<ImuSample> again = simulateImu(s, noise, kGravity, 42);
  EXPECT_EQ(again.back().gyro_body, imu.back().gyro_body);
  EXPECT_NE(simulateImu(s, noise, kGravity, 44).back().gyro_body, imu.back().gyro_body);
}

TEST(Imu, NoisyDriftAfterOneSecondMatchesTheNoiseModel) {
  // Continuous-time drift of the position after T = 1 s per axis: accel white noise
  // sa^2 T^3 / 3, accel bias walk wa^2 T^5 / 20, and through the tilt error (horizontal axes)
  // g^2 (sg^2 T^5 / 20 + wg^2 T^7 / 252).
  const ImuNoise n;
  const double T = 1.0, g = 9.81;
  const double vertical = std::sqrt(n.accel_noise_density * n.accel_noise_density * T * T * T / 3.0 +
                                    n.accel_random_walk * n.accel_random_walk * std::pow(T, 5) / 20.0);
  const double horizontal =
      std::sqrt(vertical * vertical + g * g * n.gyro_noise_density * n.gyro_noise_density * std::pow(T, 5) / 20.0 +
                g * g * n.gyro_random_walk * n.gyro_random_walk * std::pow(T, 7) / 252.0);
  const Vector3d sigma(horizontal, horizontal, vertical);
  Vector3d sum_sq = Vector3d::Zero();
  const int runs = 24;
  for (int r = 0; r < runs; ++r) {
    const SplineTrajectory s = makeKind(TrajectoryKind::kDroneFlight, T, 100 + static_cast<uint64_t>(r));
    const std::vector<ImuSample> imu = simulateImu(s, n, kGravity, 1000 + static_cast<uint64_t>(r));
    ASSERT_EQ(imu.size(), 201u);
    const std::vector<TrajectoryState> states = integrateImu(s.evaluate(imu.front().t_ns), imu, kGravity);
    const Vector3d e =
        states.back().T_world_body.translation() - s.evaluate(imu.back().t_ns).T_world_body.translation();
    for (int a = 0; a < 3; ++a) EXPECT_LT(std::abs(e[a]), 5.0 * sigma[a]) << "run " << r << " axis " << a;
    sum_sq += e.cwiseProduct(e);
  }
  // The noise is really there: the RMS drift is of the predicted size.
  const Vector3d rms = (sum_sq / runs).cwiseSqrt();
  for (int a = 0; a < 3; ++a) {
    EXPECT_GT(rms[a], 0.5 * sigma[a]) << a;
    EXPECT_LT(rms[a], 1.6 * sigma[a]) << a;
  }
}

// ------------------------------------------------------------------------------------------------
// (5) Generator envelopes and determinism.
// ------------------------------------------------------------------------------------------------

struct Envelope {
  double peak_rate = 0.0;   ///< rad/s.
  double peak_speed = 0.0;  ///< m/s.
  double min_speed = 1e9;
  double mean_speed = 0.0;
};

Envelope envelope(const SplineTrajectory& s) {
  Envelope e;
  int count = 0;
  for (int64_t t = s.startNs(); t <= s.endNs(); t += 5000000) {
    const TrajectoryState st = s.evaluate(t);
    e.peak_rate = std::max(e.peak_rate, st.omega_body.norm());
    e.peak_speed = std::max(e.peak_speed, st.v_world_body.norm());
    e.min_speed = std::min(e.min_speed, st.v_world_body.norm());
    e.mean_speed += st.v_world_body.norm();
    ++count;
  }
  e.mean_speed /= count;
  return e;
}

TEST(Generators, DroneFlightStaysInItsEnvelope) {
  const Pose mount = mounting();
  for (uint64_t seed : {1u, 2u}) {
    const SplineTrajectory s = makeKind(TrajectoryKind::kDroneFlight, 120.0, seed, mount);
    double pitch_sum = 0.0, worst_heading = 0.0;
    int count = 0;
    for (int64_t t = s.startNs(); t <= s.endNs(); t += 100000000) {
      const TrajectoryState st = s.evaluate(t);
      const Pose T_world_camera = st.T_world_body * mount;
      const Vector3d eye = T_world_camera.translation(), forward = T_world_camera.linear().col(2);
      EXPECT_GE(eye.z(), 10.0);
      EXPECT_LE(eye.z(), 60.0);
      EXPECT_LE(std::abs(eye.x()), 100.0);
      EXPECT_LE(std::abs(eye.y()), 100.0);
      const double pitch = std::asin(-forward.z()) / kDeg;  // Below the horizon, degrees.
      EXPECT_NEAR(pitch, 45.0, 5.0);
      pitch_sum += pitch;
      // Heading follows the horizontal velocity (the camera is rigid, so use the camera's).
      const Vector3d v = st.v_world_body + st.T_world_body.linear() * st.omega_body.cross(mount.translation());
      const double heading_error =
          std::abs(std::remainder(std::atan2(forward.y(), forward.x()) - std::atan2(v.y(), v.x()), 2 * kPi));
      worst_heading = std::max(worst_heading, heading_error / kDeg);
      ++count;
    }
    EXPECT_NEAR(pitch_sum / count, 45.0, 5.0);
    EXPECT_LT(worst_heading, 10.0);
    const Envelope e = envelope(makeKind(TrajectoryKind::kDroneFlight, 120.0, seed));
    EXPECT_GT(e.min_speed, 2.5);
    EXPECT_LT(e.peak_speed, 9.0);
    EXPECT_LT(e.peak_rate, 1.0);
  }
}

// A 100 m ground square at z = 0 and a 10 m tower top at z = 30 over [10, 20] x [10, 20].
Model groundAndTower() {
  Model m;
  m.positions = {-50, -50, 0, 50, -50, 0, 50, 50, 0, -50, 50, 0, 10, 10, 30, 20, 10, 30, 20, 20, 30, 10, 20, 30};
  m.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  m.materials.push_back(Material{"paint", {1, 1, 1, 1}, -1});
  m.ranges.push_back(DrawRange{0, 12, 0});
  buildBlocks(m, 32768);
  return m;
}

TEST(HeightField, HoldsTheHighestGeometryWithinTheRadius) {
  const auto field = HeightField::fromModel(groundAndTower(), 5.0);
  ASSERT_TRUE(field.ok()) << field.error().message;
  EXPECT_DOUBLE_EQ(field->top(15.0, 15.0), 30.0);
  EXPECT_DOUBLE_EQ(field->top(24.5, 15.0), 30.0);  // 4.5 m beside the tower
  EXPECT_DOUBLE_EQ(field->top(26.5, 15.0), 0.0);   // 6.5 m beside it: the ground
  EXPECT_DOUBLE_EQ(field->top(-40.0, -40.0), 0.0);
  EXPECT_EQ(field->top(-60.0, 0.0), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(field->top(std::nan(""), 0.0), -std::numeric_limits<double>::infinity());
  EXPECT_TRUE(HeightField().empty());
  EXPECT_FALSE(HeightField::fromModel(Model{}, 5.0).ok());
  EXPECT_FALSE(HeightField::fromModel(groundAndTower(), -1.0).ok());
  EXPECT_FALSE(HeightField::fromModel(groundAndTower(), 5.0, 0.0).ok());
}

// The drone keeps its clearance over the demo city's buildings, climbing at a drone's rate;
// without the height field the same paths pass below a roof (so the check can fail).
TEST(Generators, DroneFliesOverTheCityNotThroughIt) {
  const Model city = makeDemoCity();
  const auto obstacles = HeightField::fromModel(city, 5.0);
  const auto under = HeightField::fromModel(city, 1.0);
  ASSERT_TRUE(obstacles.ok() && under.ok());
  double lowest_without = 1e9;
  for (TrajectoryKind kind : {TrajectoryKind::kDroneFlight, TrajectoryKind::kDroneAgile, TrajectoryKind::kDroneAcro}) {
    for (uint64_t seed : {1u, 2u, 3u}) {
      SCOPED_TRACE(seed);
      TrajectoryOptions o;
      o.kind = kind;
      o.duration_s = 60.0;
      o.seed = seed;
      o.T_body_camera = mounting();
      auto free = makeTrajectory(o, city.bounds);
      o.obstacles = *obstacles;
      auto clear = makeTrajectory(o, city.bounds);
      ASSERT_TRUE(free.ok() && clear.ok());
      double lowest = 1e9, fastest_climb = 0.0;
      for (int64_t t = clear->startNs(); t <= clear->endNs(); t += 50000000) {
        const TrajectoryState st = clear->evaluate(t);
        const Vector3d eye = (st.T_world_body * o.T_body_camera).translation();
        lowest = std::min(lowest, eye.z() - under->top(eye.x(), eye.y()));
        fastest_climb = std::max(fastest_climb, std::abs(st.v_world_body.z()));
        const Vector3d free_eye = (free->evaluate(t).T_world_body * o.T_body_camera).translation();
        lowest_without = std::min(lowest_without, free_eye.z() - under->top(free_eye.x(), free_eye.y()));
      }
      EXPECT_GT(lowest, 9.0);
      EXPECT_LT(fastest_climb, 3.5);  // 2 m/s from the envelope, plus the planned altitude changes
    }
  }
  EXPECT_LT(lowest_without, 5.0);
  TrajectoryOptions bad;
  bad.drone_climb_rate = 0.0;
  EXPECT_FALSE(makeTrajectory(bad, city.bounds).ok());
  bad.drone_climb_rate = 2.0;
  bad.drone_clearance_m = std::nan("");
  EXPECT_FALSE(makeTrajectory(bad, city.bounds).ok());
}

TEST(Generators, HandheldStaysInsideTheRoom) {
  for (uint64_t seed : {1u, 2u}) {
    const SplineTrajectory s = makeKind(TrajectoryKind::kHandheld, 60.0, seed);
    for (int64_t t = s.startNs(); t <= s.endNs(); t += 50000000) {
      const TrajectoryState st = s.evaluate(t);
      const Vector3d eye = st.T_world_body.translation();
      EXPECT_LE(std::abs(eye.x()), 3.0 - 0.4);
      EXPECT_LE(std::abs(eye.y()), 2.5 - 0.4);
      EXPECT_GE(eye.z(), 1.2);
      EXPECT_LE(eye.z(), 1.8);
      const double pitch = std::asin(-st.T_world_body.linear()(2, 2)) / kDeg;
      EXPECT_GT(pitch, -5.0);  // Roughly horizontal to slightly down.
      EXPECT_LT(pitch, 30.0);
      // Looking into the room: the centre is in front of the camera.
      EXPECT_GT(st.T_world_body.linear().col(2).dot(Vector3d(0, 0, 1.5) - eye), 0.0);
    }
    const Envelope e = envelope(s);
    EXPECT_GT(e.mean_speed, 0.5);
    EXPECT_LT(e.peak_speed, 1.3);
    EXPECT_LT(e.peak_rate, 1.5);
  }
}

TEST(Generators, AggressiveRotatesFastInsideTheRoom) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const SplineTrajectory s = makeKind(TrajectoryKind::kAggressive, 10.0, seed);
    for (int64_t t = s.startNs(); t <= s.endNs(); t += 50000000) {
      const Vector3d eye = s.evaluate(t).T_world_body.translation();
      EXPECT_LE(std::abs(eye.x()), 3.0 - 0.4);
      EXPECT_LE(std::abs(eye.y()), 2.5 - 0.4);
      EXPECT_GT(eye.z(), 1.0);
      EXPECT_LT(eye.z(), 2.0);
    }
    const Envelope e = envelope(s);
    EXPECT_GT(e.peak_rate, 2.0) << seed;
    EXPECT_LT(e.peak_rate, 5.0) << seed;
  }
}

TEST(Generators, OrbitCirclesTheCentreLookingAtIt) {
  const SplineTrajectory s = makeKind(TrajectoryKind::kOrbit, 30.0, 4);
  double r_min = 1e9, r_max = 0.0, z_min = 1e9, z_max = -1e9;
  for (int64_t t = s.startNs(); t <= s.endNs(); t += 13000000) {
    const Pose T = s.evaluate(t).T_world_body;
    const Vector3d eye = T.translation(), centre(0, 0, 30);
    const double r = eye.head<2>().norm();
    r_min = std::min(r_min, r);
    r_max = std::max(r_max, r);
    z_min = std::min(z_min, eye.z());
    z_max = std::max(z_max, eye.z());
    EXPECT_LT(std::acos(std::min(1.0, T.linear().col(2).dot((centre - eye).normalized()))) / kDeg, 0.05);
    // The whole box is in front of the camera within 26 deg of the optical axis.
    for (int c = 0; c < 8; ++c) {
      const Vector3d corner((c & 1) ? 100 : -100, (c & 2) ? 100 : -100, (c & 4) ? 60 : 0);
      EXPECT_LT(std::acos(T.linear().col(2).dot((corner - eye).normalized())) / kDeg, 26.0);
    }
  }
  EXPECT_LT((r_max - r_min) / r_max, 1e-6);
  EXPECT_LT(z_max - z_min, 1e-9);
}

TEST(Generators, AgileDroneRollsAndPitchesFast) {
  // The agile drone's airframe tilts by up to ~25 deg at up to ~3 rad/s (seeds 1-5: 16-22 deg,
  // 2.0-2.2 rad/s), the acro drone's twice as far and as fast along the same path (the camera at
  // the same places); the plain drone's does not tilt.
  for (uint64_t seed : {1u, 2u, 3u, 4u, 5u}) {
    SCOPED_TRACE(seed);
    const SplineTrajectory agile = makeKind(TrajectoryKind::kDroneAgile, 20.0, seed, mounting());
    const SplineTrajectory acro = makeKind(TrajectoryKind::kDroneAcro, 20.0, seed, mounting());
    const SplineTrajectory calm = makeKind(TrajectoryKind::kDroneFlight, 20.0, seed, mounting());
    // The camera's tilt from its nominal 45 deg down, degrees.
    auto tilt = [](const TrajectoryState& s) {
      const Pose T = s.T_world_body * mounting();
      return std::abs(std::asin(-T.linear()(2, 2)) / kDeg - 45.0);
    };
    double tilt_agile = 0, tilt_acro = 0, tilt_calm = 0, rate_agile = 0, rate_acro = 0, apart_m = 0;
    for (int64_t t = agile.startNs(); t <= agile.endNs(); t += 20000000) {
      const TrajectoryState a = agile.evaluate(t), x = acro.evaluate(t), c = calm.evaluate(t);
      tilt_agile = std::max(tilt_agile, tilt(a));
      tilt_acro = std::max(tilt_acro, tilt(x));
      tilt_calm = std::max(tilt_calm, tilt(c));
      rate_agile = std::max(rate_agile, a.omega_body.norm());
      rate_acro = std::max(rate_acro, x.omega_body.norm());
      apart_m = std::max(
          apart_m, ((a.T_world_body * mounting()).translation() - (x.T_world_body * mounting()).translation()).norm());
    }
    EXPECT_GT(tilt_agile, 12.0);
    EXPECT_LT(tilt_agile, 40.0);
    EXPECT_GT(tilt_acro, 1.7 * tilt_agile);
    EXPECT_LT(tilt_acro, 80.0);
    EXPECT_LT(tilt_calm, 1.0);
    EXPECT_GT(rate_agile, 1.5);
    EXPECT_LT(rate_agile, 5.0);
    EXPECT_GT(rate_acro, 1.7 * rate_agile);
    EXPECT_LT(rate_acro, 10.0);
    EXPECT_LT(apart_m, 0.01) << "the same path (the splines through the body poses differ by millimetres)";
  }
}

TEST(Generators, DeterministicInSeedAndValidated) {
  for (TrajectoryKind kind : kAllKinds) {
    const SplineTrajectory a = makeKind(kind, 3.0, 11), b = makeKind(kind, 3.0, 11), c = makeKind(kind, 3.0, 12);
    ASSERT_EQ(a.controlPoses().size(), b.controlPoses().size());
    double same = 0.0, diff = 0.0;
    for (size_t k = 0; k < a.controlPoses().size(); ++k) {
      same = std::max(same, (a.controlPoses()[k].matrix() - b.controlPoses()[k].matrix()).cwiseAbs().maxCoeff());
      diff = std::max(diff, (a.controlPoses()[k].matrix() - c.controlPoses()[k].matrix()).cwiseAbs().maxCoeff());
    }
    EXPECT_EQ(same, 0.0) << trajectoryKindName(kind);
    EXPECT_GT(diff, 0.1) << trajectoryKindName(kind);
    EXPECT_EQ(a.startNs(), 0);
    EXPECT_EQ(a.endNs(), 3000000000);
    auto parsed = parseTrajectoryKind(trajectoryKindName(kind));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, kind);
  }
  EXPECT_FALSE(parseTrajectoryKind("helicopter").ok());
  // A degenerate (point) box still gives finite, valid trajectories.
  for (TrajectoryKind kind : kAllKinds) {
    TrajectoryOptions p;
    p.kind = kind;
    p.duration_s = 2.0;
    auto t = makeTrajectory(p, box(Vector3d(1, 2, 3), Vector3d(1, 2, 3)));
    ASSERT_TRUE(t.ok()) << trajectoryKindName(kind);
    for (int64_t ts = 0; ts <= t->endNs(); ts += 100000000) {
      const TrajectoryState st = t->evaluate(ts);
      EXPECT_TRUE(isValidPose(st.T_world_body) && st.v_world_body.allFinite() && st.omega_body.allFinite());
    }
  }
  TrajectoryOptions o;
  EXPECT_FALSE(makeTrajectory(o, Aabb{}).ok());
  o.duration_s = 0.0;
  EXPECT_FALSE(makeTrajectory(o, kCity).ok());
  o.duration_s = std::nan("");
  EXPECT_FALSE(makeTrajectory(o, kCity).ok());
  o.duration_s = 1.0;
  o.T_body_camera.translation().x() = INFINITY;
  EXPECT_FALSE(makeTrajectory(o, kCity).ok());
}

// ------------------------------------------------------------------------------------------------
// (6) Position priors.
// ------------------------------------------------------------------------------------------------

TEST(Priors, RateNoiseAndDropouts) {
  // A straight 2000 s flight at 5 m/s.
  const int64_t dt = 100000000;
  std::vector<Pose> controls;
  for (int k = 0; k < 20003; ++k) {
    Pose T = Pose::Identity();
    T.translation() = Vector3d(0.5 * k, 10.0, 30.0);
    controls.push_back(T);
  }
  auto s = SplineTrajectory::fromControlPoses(controls, -dt, dt);
  ASSERT_TRUE(s.ok());
  const PriorOptions o;
  const std::vector<PositionPrior> priors = simulatePriors(*s, o, 77);
  ASSERT_GT(priors.size(), 5000u);
  const int64_t period = 200000000;
  std::vector<double> nx, ny, nz;
  int gaps = 0;
  double gap_s = 0.0;
  for (size_t k = 0; k < priors.size(); ++k) {
    EXPECT_EQ((priors[k].t_ns - s->startNs()) % period, 0);
    EXPECT_EQ(priors[k].sigma, o.sigma);
    const Vector3d e =
        (priors[k].p_world_body - s->evaluate(priors[k].t_ns).T_world_body.translation()).cwiseQuotient(o.sigma);
    nx.push_back(e.x());
    ny.push_back(e.y());
    nz.push_back(e.z());
    if (k > 0) {
      const int64_t step = priors[k].t_ns - priors[k - 1].t_ns;
      EXPECT_GE(step, period);
      if (step > period) {
        ++gaps;
        gap_s += static_cast<double>(step) * 1e-9;
      }
    }
  }
  EXPECT_NEAR(stddev(nx), 1.0, 0.15);
  EXPECT_NEAR(stddev(ny), 1.0, 0.15);
  EXPECT_NEAR(stddev(nz), 1.0, 0.15);
  // Every fix outside a dropout starts one with probability p; back-to-back dropouts merge into
  // one gap, so gaps / (fixes + gaps) is about p (1 - p).
  const double p_hat = gaps / static_cast<double>(priors.size() + gaps);
  EXPECT_NEAR(p_hat, o.dropout_probability * (1.0 - o.dropout_probability), 0.3 * o.dropout_probability);
  // A gap spans the lost fix, the exponential dropout and rounding up to the next fix.
  EXPECT_NEAR(gap_s / gaps, o.dropout_mean_s + 1.5 / o.rate_hz, 0.35 * o.dropout_mean_s);

  PriorOptions none = o;
  none.dropout_probability = 0.0;
  EXPECT_EQ(simulatePriors(*s, none, 1).size(), 10001u);
  const std::vector<PositionPrior> again = simulatePriors(*s, o, 77);
  ASSERT_EQ(again.size(), priors.size());
  EXPECT_EQ(again.back().p_world_body, priors.back().p_world_body);
  PriorOptions bad = o;
  bad.sigma.x() = 0.0;
  EXPECT_TRUE(simulatePriors(*s, bad, 1).empty());
}

}  // namespace
}  // namespace vkloc
