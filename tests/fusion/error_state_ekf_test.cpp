// ErrorStateEkf (fusion/error_state_ekf.hpp): analytic vs numeric Jacobians, exact propagation,
// statistical consistency (NEES over seeded runs), delayed updates, gating, bad input and a long
// run.
#include "vkloc/fusion/error_state_ekf.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/fusion/imu_integration.hpp"
#include "vkloc/sim/trajectory.hpp"

namespace vkloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

const Vector3d kGravity(0.0, 0.0, -9.81);
constexpr int64_t kImuPeriodNs = 5'000'000;  // 200 Hz
constexpr int64_t kSecondNs = 1'000'000'000;
constexpr int kReadingsPerFrame = 10;  // 20 Hz poses

Pose makePose(const Vector3d& phi, const Vector3d& t) {
  Pose T = Pose::Identity();
  T.linear() = expSO3(phi);
  T.translation() = t;
  return T;
}

Pose bodyCamera() { return makePose({0.3, -0.2, 1.2}, {0.1, -0.05, 0.02}); }

ImuSample reading(int64_t t_ns, const Vector3d& gyro, const Vector3d& accel) {
  ImuSample s;
  s.t_ns = t_ns;
  s.gyro_body = gyro;
  s.accel_body = accel;
  return s;
}

/// A state away from every special case, with a random symmetric positive definite P.
EkfState someState() {
  EkfState x;
  x.t_ns = kSecondNs;
  x.p_world_body = {1.0, 2.0, 3.0};
  x.v_world_body = {0.5, -1.0, 0.3};
  x.R_world_body = expSO3({0.3, -0.5, 0.8});
  x.gyro_bias = {0.01, -0.02, 0.015};
  x.accel_bias = {0.1, -0.05, 0.2};
  Xoshiro256 rng(7);
  Matrix15d A;
  for (int i = 0; i < 15; ++i) {
    for (int j = 0; j < 15; ++j) A(i, j) = 0.1 * rng.gaussian();
  }
  x.P = A * A.transpose() + 1e-3 * Matrix15d::Identity();
  return x;
}

/// Covariance of the alignment's xi (camera frame) used by the simulated measurements:
/// 2-3 cm and 0.2-0.35 deg, correlated.
Matrix6d cameraCovariance() {
  Matrix6d L = Matrix6d::Zero();
  L.diagonal() << 0.02, 0.02, 0.03, 0.004, 0.004, 0.006;
  L(1, 0) = 0.005;
  L(3, 1) = 0.002;
  L(5, 2) = -0.003;
  L(4, 0) = 0.001;
  return L * L.transpose();
}

/// Draws xi ~ N(0, C) with C = L L^T.
Vector6d drawGaussian(Xoshiro256& rng, const Matrix6d& C) {
  const Eigen::LLT<Matrix6d> llt(C);
  Vector6d n;
  for (int i = 0; i < 6; ++i) n(i) = rng.gaussian();
  return llt.matrixL() * n;
}

/// Simulated IMU: exact readings of the trajectory plus, when noisy, discrete white noise
/// (density sqrt(rate)) and biases starting at bg0 / ba0 and walking (rw / sqrt(rate) per
/// reading). bg[k], ba[k] are the true biases of reading k.
struct SimImu {
  std::vector<ImuSample> imu;
  std::vector<Vector3d> bg, ba;
};

SimImu simulate(const SplineTrajectory& trajectory, const ImuNoise& noise, const Vector3d& bg0, const Vector3d& ba0,
                uint64_t seed, bool noisy) {
  Xoshiro256 rng(seed);
  auto draw = [&]() { return Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()); };
  const double rate = 1e9 / static_cast<double>(kImuPeriodNs);
  SimImu sim;
  Vector3d bg = bg0;
  Vector3d ba = ba0;
  for (int64_t t = trajectory.startNs(); t <= trajectory.endNs(); t += kImuPeriodNs) {
    const TrajectoryState s = trajectory.evaluate(t);
    ImuSample r = reading(t, s.omega_body + bg, s.T_world_body.linear().transpose() * (s.a_world_body - kGravity) + ba);
    if (noisy) {
      r.gyro_body += noise.gyro_noise_density * std::sqrt(rate) * draw();
      r.accel_body += noise.accel_noise_density * std::sqrt(rate) * draw();
    }
    sim.imu.push_back(r);
    sim.bg.push_back(bg);
    sim.ba.push_back(ba);
    if (noisy) {
      bg += noise.gyro_random_walk / std::sqrt(rate) * draw();
      ba += noise.accel_random_walk / std::sqrt(rate) * draw();
    }
  }
  return sim;
}

SplineTrajectory makeFlight(TrajectoryKind kind, double duration_s, uint64_t seed) {
  TrajectoryOptions o;
  o.kind = kind;
  o.duration_s = duration_s;
  o.seed = seed;
  o.T_body_camera = bodyCamera();
  Aabb room;
  room.min = {-4.0f, -3.0f, 0.0f};
  room.max = {4.0f, 3.0f, 2.8f};
  auto t = makeTrajectory(o, room);
  EXPECT_TRUE(t.ok());
  return t.ok() ? *t : SplineTrajectory{};
}

EkfState truthAt(const SplineTrajectory& trajectory, const SimImu& sim, size_t k) {
  const TrajectoryState s = trajectory.evaluate(sim.imu[k].t_ns);
  EkfState x;
  x.t_ns = s.t_ns;
  x.p_world_body = s.T_world_body.translation();
  x.v_world_body = s.v_world_body;
  x.R_world_body = s.T_world_body.linear();
  x.gyro_bias = sim.bg[k];
  x.accel_bias = sim.ba[k];
  return x;
}

double maxAbs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

void expectStatesNear(const EkfState& a, const EkfState& b, double tol) {
  EXPECT_EQ(a.t_ns, b.t_ns);
  EXPECT_LT((a.p_world_body - b.p_world_body).norm(), tol);
  EXPECT_LT((a.v_world_body - b.v_world_body).norm(), tol);
  EXPECT_LT(logSO3(a.R_world_body.transpose() * b.R_world_body).norm(), tol);
  EXPECT_LT((a.gyro_bias - b.gyro_bias).norm(), tol);
  EXPECT_LT((a.accel_bias - b.accel_bias).norm(), tol);
  EXPECT_LT(maxAbs(a.P - b.P), tol);
}

bool symmetricPositiveDefinite(const Matrix15d& P) {
  if (!P.allFinite() || maxAbs(P - P.transpose()) > 1e-12 * std::max(1.0, maxAbs(P))) return false;
  return Eigen::SelfAdjointEigenSolver<Matrix15d>(P, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() > 0.0;
}

// ---------------------------------------------------------------------------------------------
// 1. Jacobians.

TEST(ErrorStateEkf, TransitionMatchesNumericJacobian) {
  // F of one step against central differences of the propagated nominal state (step 1e-6):
  // agreement to 1e-7 (measured ~1e-9) at 5 ms and 50 ms steps with large rates.
  const ImuNoise noise;
  for (int64_t dt_ns : {kImuPeriodNs, 10 * kImuPeriodNs}) {
    const EkfState x = someState();
    const ImuSample r0 = reading(x.t_ns, {0.4, -0.3, 0.9}, {0.5, 9.6, -1.2});
    const ImuSample r1 = reading(x.t_ns + dt_ns, {0.9, -0.1, 1.6}, {1.7, 8.3, -0.4});
    Matrix15d F;
    Matrix15d Q;
    const EkfState x1 = propagateEkfState(x, r0, r1, kGravity, noise, &F, &Q);
    EXPECT_EQ(x1.t_ns, r1.t_ns);
    EXPECT_LT(maxAbs(x1.P - (F * x.P * F.transpose() + Q)), 1e-12);
    Matrix15d numeric;
    const double eps = 1e-6;
    for (int i = 0; i < 15; ++i) {
      const Vector15d d = eps * Vector15d::Unit(i);
      const EkfState plus = propagateEkfState(applyErrorState(x, d), r0, r1, kGravity, noise);
      const EkfState minus = propagateEkfState(applyErrorState(x, -d), r0, r1, kGravity, noise);
      numeric.col(i) = (errorStateBetween(x1, plus) - errorStateBetween(x1, minus)) / (2.0 * eps);
    }
    const double err = maxAbs(F - numeric);
    std::printf("dt %.3f s: max |F - F_numeric| = %.2e\n", static_cast<double>(dt_ns) * 1e-9, err);
    EXPECT_LT(err, 1e-7) << "F\n" << F << "\nnumeric\n" << numeric;
    // The blocks compared are not trivially zero.
    EXPECT_GT(maxAbs(F.block<3, 3>(3, 6)), 1e-3);
    EXPECT_GT(maxAbs(F.block<3, 3>(3, 9)), 1e-6);
    EXPECT_GT(maxAbs(F.block<3, 3>(6, 6) - Matrix3d::Identity()), 1e-3);
    EXPECT_GT(maxAbs(F.block<3, 3>(0, 12)), 1e-6);
  }
}

TEST(ErrorStateEkf, MeasurementJacobianMatchesNumeric) {
  // H of the pose residual at a residual of ~0.35 rad (so Jl^-1 matters): to 1e-8.
  const EkfState x = someState();
  const Pose measured = x.T_world_body() * makePose({0.2, -0.25, 0.1}, {0.3, -0.1, 0.2});
  Matrix6x15d H;
  const Vector6d r0 = ekfPoseResidual(x, measured, &H);
  EXPECT_GT(r0.tail<3>().norm(), 0.3);
  Matrix6x15d numeric;
  const double eps = 1e-6;
  for (int i = 0; i < 15; ++i) {
    const Vector15d d = eps * Vector15d::Unit(i);
    numeric.col(i) =
        -(ekfPoseResidual(applyErrorState(x, d), measured) - ekfPoseResidual(applyErrorState(x, -d), measured)) /
        (2.0 * eps);
  }
  EXPECT_LT(maxAbs(H - numeric), 1e-8) << "H\n" << H << "\nnumeric\n" << numeric;
  EXPECT_GT(maxAbs(H.block<3, 3>(3, 6) - Matrix3d::Identity()), 1e-2);
}

TEST(ErrorStateEkf, MeasurementCovarianceMapsTheCameraPerturbation) {
  // The residual as a function of the camera's xi (T_true_camera = T_camera expSE3(xi)) has
  // Jacobian J; ekfMeasurementCovariance must equal J C J^T (to 1e-9).
  const Pose T_body_camera = bodyCamera();
  const Pose T_world_camera = makePose({0.5, 0.1, -0.7}, {3.0, -1.0, 1.5});
  const Matrix6d C = cameraCovariance();
  const Pose measured_body = T_world_camera * T_body_camera.inverse();
  Eigen::Matrix<double, 6, 6> J;
  const double eps = 1e-6;
  auto residual = [&](const Vector6d& xi) {
    const Pose T_body = T_world_camera * expSE3(xi) * T_body_camera.inverse();
    EkfState truth;
    truth.p_world_body = T_body.translation();
    truth.R_world_body = T_body.linear();
    return ekfPoseResidual(truth, measured_body);
  };
  for (int i = 0; i < 6; ++i) {
    J.col(i) = (residual(eps * Vector6d::Unit(i)) - residual(-eps * Vector6d::Unit(i))) / (2.0 * eps);
  }
  EXPECT_LT(maxAbs(ekfMeasurementCovariance(T_world_camera, C, T_body_camera) - J * C * J.transpose()), 1e-9);
}

TEST(ErrorStateEkf, PoseCovariancesMapTheErrorState) {
  // cameraPoseCovariance / bodyPoseCovariance = J P J^T with J the numeric Jacobian of
  // xi = logSE3(T_est^-1 T(x (+) dx)): to 1e-9.
  const EkfState x = someState();
  const Pose T_body_camera = bodyCamera();
  const double eps = 1e-6;
  Eigen::Matrix<double, 6, 15> Jb;
  Eigen::Matrix<double, 6, 15> Jc;
  const Pose Tc = x.T_world_body() * T_body_camera;
  for (int i = 0; i < 15; ++i) {
    const Vector15d d = eps * Vector15d::Unit(i);
    const Pose bp = applyErrorState(x, d).T_world_body();
    const Pose bm = applyErrorState(x, -d).T_world_body();
    Jb.col(i) = (logSE3(x.T_world_body().inverse() * bp) - logSE3(x.T_world_body().inverse() * bm)) / (2.0 * eps);
    Jc.col(i) = (logSE3(Tc.inverse() * bp * T_body_camera) - logSE3(Tc.inverse() * bm * T_body_camera)) / (2.0 * eps);
  }
  EXPECT_LT(maxAbs(bodyPoseCovariance(x) - Jb * x.P * Jb.transpose()), 1e-9);
  EXPECT_LT(maxAbs(cameraPoseCovariance(x, T_body_camera) - Jc * x.P * Jc.transpose()), 1e-9);
}

// ---------------------------------------------------------------------------------------------
// 2. Exact propagation.

/// Runs the filter over readings from an initial pose and velocity at readings.front().t_ns.
std::vector<EkfState> runFilter(const std::vector<ImuSample>& readings, const Pose& T0, const Vector3d& v0) {
  ErrorStateEkf ekf;
  EXPECT_TRUE(ekf.addImu(readings.front()).ok());  // Buffered: the reading at the start time.
  EXPECT_TRUE(ekf.initialize(readings.front().t_ns, T0, v0).ok());
  std::vector<EkfState> out{ekf.current()};
  for (size_t k = 1; k < readings.size(); ++k) {
    EXPECT_TRUE(ekf.addImu(readings[k]).ok());
    out.push_back(ekf.current());
  }
  return out;
}

TEST(ErrorStateEkf, AtRestTheStateDoesNotMoveFor10Seconds) {
  const Pose T0 = makePose({0.4, -0.3, 2.0}, {1.0, 2.0, 3.0});
  std::vector<ImuSample> readings;
  for (int64_t t = 0; t <= 10 * kSecondNs; t += kImuPeriodNs) {
    readings.push_back(reading(t, Vector3d::Zero(), T0.linear().transpose() * -kGravity));
  }
  const EkfState end = runFilter(readings, T0, Vector3d::Zero()).back();
  EXPECT_EQ(end.t_ns, 10 * kSecondNs);
  EXPECT_LT((end.p_world_body - T0.translation()).norm(), 1e-10);
  EXPECT_LT(end.v_world_body.norm(), 1e-11);
  EXPECT_LT(logSO3(T0.linear().transpose() * end.R_world_body).norm(), 1e-12);
}

TEST(ErrorStateEkf, ConstantVelocityAndConstantRateAreExact) {
  const Pose T0 = makePose({0.4, -0.3, 2.0}, {1.0, 2.0, 3.0});
  const Vector3d v(1.0, -2.0, 0.5);
  const Vector3d omega(0.3, -0.2, 0.5);
  std::vector<ImuSample> straight;
  std::vector<ImuSample> spinning;
  for (int64_t t = 0; t <= 10 * kSecondNs; t += kImuPeriodNs) {
    straight.push_back(reading(t, Vector3d::Zero(), T0.linear().transpose() * -kGravity));
    // Spinning in place at a constant body rate: R(t) = R0 Exp(omega t), specific force R^T (-g).
    const Matrix3d R = T0.linear() * expSO3(omega * static_cast<double>(t) * 1e-9);
    spinning.push_back(reading(t, omega, R.transpose() * -kGravity));
  }
  const EkfState a = runFilter(straight, T0, v).back();
  EXPECT_LT((a.p_world_body - (T0.translation() + 10.0 * v)).norm(), 1e-9);
  EXPECT_LT((a.v_world_body - v).norm(), 1e-11);
  const EkfState b = runFilter(spinning, T0, v).back();
  EXPECT_LT(logSO3((T0.linear() * expSO3(10.0 * omega)).transpose() * b.R_world_body).norm(), 1e-10);
  EXPECT_LT((b.p_world_body - (T0.translation() + 10.0 * v)).norm(), 1e-9);
  EXPECT_LT((b.v_world_body - v).norm(), 1e-10);
}

TEST(ErrorStateEkf, PropagationEqualsIntegrateImuAndTheTrajectory) {
  // Exact readings of a handheld walk: the filter reproduces integrateImu to 1e-9 at every
  // reading, and the trajectory to the midpoint rule's error (measured ~0.2 mm, 0.0003 deg
  // after 10 s; 2 mm / 0.005 deg allowed).
  const SplineTrajectory trajectory = makeFlight(TrajectoryKind::kHandheld, 10.0, 3);
  const SimImu sim = simulate(trajectory, ImuNoise{}, Vector3d::Zero(), Vector3d::Zero(), 1, false);
  const TrajectoryState start = trajectory.evaluate(sim.imu.front().t_ns);
  const std::vector<EkfState> ekf = runFilter(sim.imu, start.T_world_body, start.v_world_body);
  const std::vector<TrajectoryState> ref = integrateImu(start, sim.imu, kGravity);
  ASSERT_EQ(ekf.size(), ref.size());
  double worst = 0.0;
  for (size_t k = 0; k < ekf.size(); ++k) {
    worst = std::max(worst, (ekf[k].p_world_body - ref[k].T_world_body.translation()).norm());
    worst = std::max(worst, (ekf[k].v_world_body - ref[k].v_world_body).norm());
    worst = std::max(worst, logSO3(ekf[k].R_world_body.transpose() * ref[k].T_world_body.linear()).norm());
  }
  EXPECT_LT(worst, 1e-9);
  const TrajectoryState end = trajectory.evaluate(ekf.back().t_ns);
  const double dp = (ekf.back().p_world_body - end.T_world_body.translation()).norm();
  const double deg = rotationAngleDeg(ekf.back().R_world_body.transpose() * end.T_world_body.linear());
  std::printf("vs integrateImu %.1e; vs trajectory after 10 s: %.3f mm, %.5f deg\n", worst, dp * 1e3, deg);
  EXPECT_LT(dp, 2e-3);
  EXPECT_LT(deg, 5e-3);
}

// ---------------------------------------------------------------------------------------------
// 3. Consistency.

struct Nees {
  double full = 0.0;      // 15-dim
  double pose_vel = 0.0;  // 9-dim: dp, dv, dtheta
  double position_m = 0.0;
};

EkfOptions consistencyOptions() {
  EkfOptions o;
  o.T_body_camera = bodyCamera();
  o.initial_sigma_position_m = 0.05;
  o.initial_sigma_velocity_m_s = 0.1;
  o.initial_sigma_attitude_rad = 0.01;
  o.initial_sigma_gyro_bias_rad_s = 0.005;
  o.initial_sigma_accel_bias_m_s2 = 0.05;
  o.gate_probability = 1.0;  // No gate: the statistics of every draw are kept.
  return o;
}

/// One run: initial error drawn from P0, noisy IMU with biases, camera poses at 20 Hz with
/// cameraCovariance() noise, each applied 30 ms late (delayed updates); NEES at the end.
Nees consistencyRun(uint64_t seed, double duration_s) {
  const EkfOptions o = consistencyOptions();
  const SplineTrajectory trajectory = makeFlight(TrajectoryKind::kHandheld, duration_s + 1.0, seed);
  Xoshiro256 rng(subSeed(seed, 1));
  auto draw3 = [&]() { return Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()); };
  const Vector3d bg0 = o.initial_sigma_gyro_bias_rad_s * draw3();
  const Vector3d ba0 = o.initial_sigma_accel_bias_m_s2 * draw3();
  const SimImu sim = simulate(trajectory, o.imu_noise, bg0, ba0, subSeed(seed, 2), true);
  auto ekf = ErrorStateEkf::create(o);
  EXPECT_TRUE(ekf.ok());
  const size_t k0 = 200;  // Start 1 s in; readings before are buffered.
  for (size_t k = 0; k <= k0; ++k) EXPECT_TRUE(ekf->addImu(sim.imu[k]).ok());
  Vector15d sigma;
  sigma << Vector3d::Constant(o.initial_sigma_position_m), Vector3d::Constant(o.initial_sigma_velocity_m_s),
      Vector3d::Constant(o.initial_sigma_attitude_rad), Vector3d::Constant(o.initial_sigma_gyro_bias_rad_s),
      Vector3d::Constant(o.initial_sigma_accel_bias_m_s2);
  Vector15d e;
  for (int i = 0; i < 15; ++i) e(i) = sigma(i) * rng.gaussian();
  EkfState start = applyErrorState(truthAt(trajectory, sim, k0), -e);
  start.P = sigma.cwiseProduct(sigma).asDiagonal();
  EXPECT_TRUE(ekf->initialize(start).ok());
  const Matrix6d C = cameraCovariance();
  const size_t delay = 6;  // 30 ms
  for (size_t k = k0 + 1; k < sim.imu.size(); ++k) {
    EXPECT_TRUE(ekf->addImu(sim.imu[k]).ok());
    if (k >= k0 + delay && (k - delay) % kReadingsPerFrame == 0) {
      const int64_t t = sim.imu[k - delay].t_ns;
      const Pose T_true = trajectory.evaluate(t).T_world_body * o.T_body_camera;
      const Pose T_meas = T_true * expSE3(-drawGaussian(rng, C));  // T_true = T_meas expSE3(xi)
      const Result<EkfUpdate> u = ekf->updateCameraPose(t, T_meas, C);
      EXPECT_TRUE(u.ok() && u->accepted);
    }
  }
  const EkfState& x = ekf->current();
  const Vector15d err = errorStateBetween(x, truthAt(trajectory, sim, sim.imu.size() - 1));
  Nees n;
  n.full = err.dot(x.P.ldlt().solve(err));
  const Eigen::Matrix<double, 9, 9> P9 = x.P.topLeftCorner<9, 9>();
  n.pose_vel = err.head<9>().dot(P9.ldlt().solve(err.head<9>()));
  n.position_m = err.head<3>().norm();
  return n;
}

TEST(ErrorStateEkf, NeesOf50RunsIsWithinTheChiSquareBounds) {
  // 50 seeded runs of 10 s. The mean NEES of N runs times N is chi-square with N dim degrees of
  // freedom if the filter is consistent; its two-sided 95 % interval, divided by N, is
  // [13.52, 16.56] (15-dim, 750 dof) and [7.86, 10.21] (9-dim, 450 dof).
  const int runs = 50;
  double full = 0.0;
  double pose_vel = 0.0;
  double position = 0.0;
  for (int i = 0; i < runs; ++i) {
    const Nees n = consistencyRun(1000 + i, 10.0);
    full += n.full / runs;
    pose_vel += n.pose_vel / runs;
    position += n.position_m / runs;
  }
  const double lo15 = chiSquareQuantile(0.025, 15 * runs) / runs;
  const double hi15 = chiSquareQuantile(0.975, 15 * runs) / runs;
  const double lo9 = chiSquareQuantile(0.025, 9 * runs) / runs;
  const double hi9 = chiSquareQuantile(0.975, 9 * runs) / runs;
  std::printf("mean NEES 15-dim %.2f in [%.2f, %.2f]; 9-dim %.2f in [%.2f, %.2f]; mean |dp| %.2f mm\n", full, lo15,
              hi15, pose_vel, lo9, hi9, position * 1e3);
  EXPECT_NEAR(lo15, 13.52, 0.01);
  EXPECT_NEAR(hi15, 16.56, 0.01);
  EXPECT_GT(full, lo15);
  EXPECT_LT(full, hi15);
  EXPECT_GT(pose_vel, lo9);
  EXPECT_LT(pose_vel, hi9);
}

TEST(ErrorStateEkf, ChiSquareQuantilesMatchTables) {
  EXPECT_NEAR(chiSquareQuantile(0.999, 6), 22.4577, 1e-4);
  EXPECT_NEAR(chiSquareQuantile(0.95, 6), 12.5916, 1e-4);
  EXPECT_NEAR(chiSquareQuantile(0.95, 1), 3.84146, 1e-5);
  EXPECT_NEAR(chiSquareQuantile(0.99, 3), 11.3449, 1e-4);
  EXPECT_NEAR(chiSquareQuantile(0.95, 100), 124.342, 1e-3);
  EXPECT_NEAR(chiSquareQuantile(0.5, 2), 2.0 * std::log(2.0), 1e-9);
  EXPECT_TRUE(std::isnan(chiSquareQuantile(1.0, 6)));
  EXPECT_TRUE(std::isnan(chiSquareQuantile(0.5, 0)));
}

// ---------------------------------------------------------------------------------------------
// 4. Delayed updates.

struct DelayedScene {
  SplineTrajectory trajectory;
  SimImu sim;
  EkfOptions options;
  Matrix6d C;
  size_t k0 = 0;

  DelayedScene() {
    trajectory = makeFlight(TrajectoryKind::kHandheld, 4.0, 21);
    sim = simulate(trajectory, ImuNoise{}, {0.002, -0.001, 0.003}, {0.03, 0.02, -0.04}, 22, true);
    options.T_body_camera = bodyCamera();
    C = cameraCovariance();
    k0 = 100;  // 0.5 s
  }
  ErrorStateEkf start() const {
    ErrorStateEkf ekf = *ErrorStateEkf::create(options);
    const TrajectoryState s = trajectory.evaluate(sim.imu[k0].t_ns);
    EXPECT_TRUE(
        ekf.initialize(s.t_ns, s.T_world_body * makePose({0.01, 0.0, -0.01}, {0.02, -0.01, 0.0}), s.v_world_body).ok());
    return ekf;
  }
  /// Feeds readings k0 + 1 .. until t_ns (inclusive) not yet fed.
  void feed(ErrorStateEkf& ekf, int64_t until_ns) const {
    for (const ImuSample& r : sim.imu) {
      if (r.t_ns > ekf.newestNs() && r.t_ns <= until_ns) {
        EXPECT_TRUE(ekf.addImu(r).ok());
      }
    }
  }
  Pose measured(int64_t t_ns, uint64_t seed) const {
    Xoshiro256 rng(seed);
    return trajectory.evaluate(t_ns).T_world_body * options.T_body_camera * expSE3(-drawGaussian(rng, C));
  }
};

TEST(ErrorStateEkf, DelayedUpdateEqualsTheUpdateInTimeOrder) {
  const DelayedScene scene;
  const int64_t t1 = kSecondNs;
  const int64_t t2 = 1'020'000'000;
  const int64_t now = 1'060'000'000;
  // In time order: readings to 1.0 s, update, readings to 1.02 s, update, readings to 1.06 s.
  ErrorStateEkf in_order = scene.start();
  scene.feed(in_order, t1);
  const Result<EkfUpdate> a = in_order.updateCameraPose(t1, scene.measured(t1, 1), scene.C);
  scene.feed(in_order, t2);
  ASSERT_TRUE(in_order.updateCameraPose(t2, scene.measured(t2, 2), scene.C).ok());
  scene.feed(in_order, now);
  // Late: readings to 1.06 s, then the 1.0 s pose (12 readings re-propagated).
  ErrorStateEkf late = scene.start();
  scene.feed(late, now);
  const Result<EkfUpdate> b = late.updateCameraPose(t1, scene.measured(t1, 1), scene.C);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->accepted && b->accepted);
  EXPECT_EQ(a->repropagated_steps, 0);
  EXPECT_EQ(b->repropagated_steps, 12);
  EXPECT_LT(maxAbs(a->innovation - b->innovation), 1e-12);
  EXPECT_LT(maxAbs(a->innovation_covariance - b->innovation_covariance), 1e-12);
  // ... then the 1.02 s pose: same as in time order.
  ASSERT_TRUE(late.updateCameraPose(t2, scene.measured(t2, 2), scene.C).ok());
  expectStatesNear(late.current(), in_order.current(), 1e-9);
  // Out of order: the 1.02 s pose first, then the 1.0 s pose; the 1.02 s update is re-applied.
  ErrorStateEkf swapped = scene.start();
  scene.feed(swapped, now);
  ASSERT_TRUE(swapped.updateCameraPose(t2, scene.measured(t2, 2), scene.C).ok());
  ASSERT_TRUE(swapped.updateCameraPose(t1, scene.measured(t1, 1), scene.C).ok());
  expectStatesNear(swapped.current(), in_order.current(), 1e-9);
  // The updates moved the state (the comparison is not of two untouched filters).
  ErrorStateEkf none = scene.start();
  scene.feed(none, now);
  EXPECT_GT((none.current().p_world_body - in_order.current().p_world_body).norm(), 1e-3);
}

TEST(ErrorStateEkf, DelayedUpdateBetweenReadingsInterpolates) {
  // A pose at 1.0025 s (between readings): applied when the newest reading is 1.005 s or 1.06 s,
  // the results agree (1e-9), and stateAt(1.0025) moved to the measurement.
  const DelayedScene scene;
  const int64_t t = 1'002'500'000;
  const Pose m = scene.measured(t, 3);
  ErrorStateEkf soon = scene.start();
  scene.feed(soon, 1'005'000'000);
  ASSERT_TRUE(soon.stateAt(t).ok());
  const Pose before = soon.stateAt(t)->T_world_body();
  const Result<EkfUpdate> a = soon.updateCameraPose(t, m, scene.C);
  scene.feed(soon, 1'060'000'000);
  ErrorStateEkf late = scene.start();
  scene.feed(late, 1'060'000'000);
  const Result<EkfUpdate> b = late.updateCameraPose(t, m, scene.C);
  ASSERT_TRUE(a.ok() && b.ok() && a->accepted && b->accepted);
  EXPECT_EQ(a->repropagated_steps, 1);
  EXPECT_EQ(b->repropagated_steps, 12);
  expectStatesNear(late.current(), soon.current(), 1e-9);
  const Pose measured_body = m * scene.options.T_body_camera.inverse();
  const Pose after = late.stateAt(t)->T_world_body();
  EXPECT_LT((after.translation() - measured_body.translation()).norm(),
            (before.translation() - measured_body.translation()).norm());
}

// ---------------------------------------------------------------------------------------------
// 5. Gating.

TEST(ErrorStateEkf, GateRejectsTenSigmaAndAcceptsOneSigma) {
  const DelayedScene scene;
  ErrorStateEkf ekf = scene.start();
  scene.feed(ekf, kSecondNs);
  const EkfState x = ekf.current();
  // 10 sigma along the x position of S: d^2 >= 100 > 22.46.
  auto cameraAt = [&](const Vector6d& r) {
    Pose body = x.T_world_body();
    body.translation() += r.head<3>();
    body.linear() = x.R_world_body * expSO3(r.tail<3>());
    return body * scene.options.T_body_camera;
  };
  const Result<EkfUpdate> probe = ekf.updateCameraPose(kSecondNs, cameraAt(Vector6d::Zero()), scene.C);
  ASSERT_TRUE(probe.ok());
  ErrorStateEkf fresh = scene.start();
  scene.feed(fresh, kSecondNs);
  const Matrix6d S = probe->innovation_covariance;
  Vector6d outlier = Vector6d::Zero();
  outlier(0) = 10.0 * std::sqrt(S(0, 0));
  // testCameraPose decides as the update would, and changes nothing.
  const Result<EkfUpdate> tested = fresh.testCameraPose(kSecondNs, cameraAt(outlier), scene.C);
  ASSERT_TRUE(tested.ok());
  EXPECT_FALSE(tested->accepted);
  expectStatesNear(fresh.current(), x, 0.0 + 1e-15);
  const Result<EkfUpdate> rejected = fresh.updateCameraPose(kSecondNs, cameraAt(outlier), scene.C);
  EXPECT_DOUBLE_EQ(tested->mahalanobis_sq, rejected->mahalanobis_sq);
  ASSERT_TRUE(rejected.ok());
  EXPECT_FALSE(rejected->accepted);
  EXPECT_GE(rejected->mahalanobis_sq, 100.0 - 1e-6);
  EXPECT_NEAR(rejected->gate_threshold, 22.4577, 1e-3);
  expectStatesNear(fresh.current(), x, 0.0 + 1e-15);  // Unchanged.
  // One sigma: r = L u with |u| = 1 (S = L L^T) gives d^2 ~= 1.
  const Eigen::LLT<Matrix6d> llt(S);
  const Vector6d u = Vector6d::Constant(1.0 / std::sqrt(6.0));
  const Result<EkfUpdate> tested_one = fresh.testCameraPose(kSecondNs, cameraAt(llt.matrixL() * u), scene.C);
  ASSERT_TRUE(tested_one.ok());
  EXPECT_TRUE(tested_one->accepted);
  const Result<EkfUpdate> accepted = fresh.updateCameraPose(kSecondNs, cameraAt(llt.matrixL() * u), scene.C);
  EXPECT_DOUBLE_EQ(tested_one->mahalanobis_sq, accepted->mahalanobis_sq);
  ASSERT_TRUE(accepted.ok());
  EXPECT_TRUE(accepted->accepted);
  EXPECT_NEAR(accepted->mahalanobis_sq, 1.0, 0.05);
  // Force-accept applies the outlier anyway (re-anchoring after a relocalization).
  ErrorStateEkf forced = scene.start();
  scene.feed(forced, kSecondNs);
  const Result<EkfUpdate> f = forced.updateCameraPose(kSecondNs, cameraAt(outlier), scene.C, EkfGate::kForceAccept);
  ASSERT_TRUE(f.ok());
  EXPECT_TRUE(f->accepted && f->gate_skipped);
  EXPECT_GT(forced.current().p_world_body.x() - x.p_world_body.x(), 5.0 * std::sqrt(S(0, 0)));
}

// ---------------------------------------------------------------------------------------------
// 6. Bad input.

TEST(ErrorStateEkf, BadInputReturnsAClearStatusAndKeepsTheFilterFinite) {
  const DelayedScene scene;
  ErrorStateEkf ekf = *ErrorStateEkf::create(scene.options);
  const Pose T = scene.trajectory.evaluate(kSecondNs).T_world_body * scene.options.T_body_camera;
  // Update and queries before initialize.
  const Result<EkfUpdate> early = ekf.updateCameraPose(kSecondNs, T, scene.C);
  ASSERT_FALSE(early.ok());
  EXPECT_NE(early.error().message.find("not initialized"), std::string::npos);
  EXPECT_FALSE(ekf.predict(kSecondNs).ok());
  EXPECT_FALSE(ekf.initialized());
  ekf = scene.start();
  scene.feed(ekf, kSecondNs);
  const EkfState before = ekf.current();
  // NaN reading: ignored.
  ImuSample nan = reading(kSecondNs + kImuPeriodNs, Vector3d::Zero(), Vector3d::Zero());
  nan.accel_body.y() = std::numeric_limits<double>::quiet_NaN();
  Status s = ekf.addImu(nan);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("non-finite"), std::string::npos);
  // Out of order and repeated readings: ignored.
  s = ekf.addImu(reading(kSecondNs - kImuPeriodNs, Vector3d::Zero(), -kGravity));
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("not after"), std::string::npos);
  EXPECT_FALSE(ekf.addImu(reading(kSecondNs, Vector3d::Zero(), -kGravity)).ok());
  expectStatesNear(ekf.current(), before, 1e-15);
  // Bad poses and covariances.
  Pose broken = T;
  broken.linear()(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(ekf.updateCameraPose(kSecondNs, broken, scene.C).ok());
  Matrix6d asym = scene.C;
  asym(0, 1) += 1.0;
  EXPECT_FALSE(ekf.updateCameraPose(kSecondNs, T, asym).ok());
  EXPECT_FALSE(ekf.updateCameraPose(kSecondNs, T, -scene.C).ok());
  Matrix6d nan_cov = scene.C;
  nan_cov(2, 2) = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(ekf.updateCameraPose(kSecondNs, T, nan_cov).ok());
  // Update newer than the newest reading, or older than the ring buffer (2 s).
  const Result<EkfUpdate> future = ekf.updateCameraPose(kSecondNs + 1, T, scene.C);
  ASSERT_FALSE(future.ok());
  EXPECT_NE(future.error().message.find("after the newest IMU reading"), std::string::npos);
  scene.feed(ekf, 3 * kSecondNs + 500'000'000);
  const Result<EkfUpdate> old = ekf.updateCameraPose(kSecondNs, T, scene.C);
  ASSERT_FALSE(old.ok());
  EXPECT_NE(old.error().message.find("older than the ring buffer"), std::string::npos);
  EXPECT_LE(ekf.oldestNs(), ekf.newestNs() - 2 * kSecondNs);
  EXPECT_GT(ekf.oldestNs(), ekf.newestNs() - 2 * kSecondNs - kImuPeriodNs);
  EXPECT_TRUE(symmetricPositiveDefinite(ekf.current().P));
  // Bad initialization: nothing changes.
  const EkfState kept = ekf.current();
  EXPECT_FALSE(ekf.initialize(0, broken, Vector3d::Zero()).ok());
  EXPECT_FALSE(ekf.initialize(0, T, Vector3d::Constant(std::nan(""))).ok());
  EXPECT_FALSE(ekf.initialize(0, T, Vector3d::Zero(), Matrix15d(-Matrix15d::Identity())).ok());
  expectStatesNear(ekf.current(), kept, 0.0 + 1e-15);
}

TEST(ErrorStateEkf, ImuGapReanchorsWithoutPropagatingAcrossIt) {
  const DelayedScene scene;
  ErrorStateEkf ekf = scene.start();
  scene.feed(ekf, kSecondNs);
  const EkfState before = ekf.current();
  // 0.3 s without readings (max_imu_gap_s 0.1).
  const int64_t after_gap = kSecondNs + 300'000'000;
  size_t k = 0;
  while (scene.sim.imu[k].t_ns < after_gap) ++k;
  const Status s = ekf.addImu(scene.sim.imu[k]);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("gap"), std::string::npos);
  EXPECT_TRUE(ekf.awaitingFix());
  const EkfState x = ekf.current();
  EXPECT_EQ(x.t_ns, after_gap);
  EXPECT_EQ(x.p_world_body, before.p_world_body);  // Not propagated across the gap.
  EXPECT_EQ(x.v_world_body, before.v_world_body);
  EXPECT_TRUE(symmetricPositiveDefinite(x.P));
  EXPECT_GT(x.P(0, 0), before.P(0, 0));
  EXPECT_GE(x.P(4, 4), 25.0 - 1e-9);  // Velocity sigma raised to the initial 5 m/s.
  EXPECT_EQ(ekf.oldestNs(), after_gap);
  EXPECT_FALSE(ekf.updateCameraPose(kSecondNs, scene.measured(kSecondNs, 1), scene.C).ok());  // Before it.
  // Readings go on; the next pose is applied without the gate and clears awaitingFix.
  ++k;
  for (int i = 0; i < 10; ++i, ++k) EXPECT_TRUE(ekf.addImu(scene.sim.imu[k]).ok());
  const int64_t t = scene.sim.imu[k - 1].t_ns;
  const Result<EkfUpdate> u = ekf.updateCameraPose(t, scene.measured(t, 5), scene.C);
  ASSERT_TRUE(u.ok());
  EXPECT_TRUE(u->accepted && u->gate_skipped);
  EXPECT_FALSE(ekf.awaitingFix());
  EXPECT_LT((ekf.current().p_world_body - scene.trajectory.evaluate(t).T_world_body.translation()).norm(), 0.1);
}

TEST(ErrorStateEkf, OptionsAreValidatedByName) {
  EXPECT_TRUE(validateEkfOptions(EkfOptions{}).ok());
  auto message = [](const EkfOptions& o) {
    const Result<ErrorStateEkf> r = ErrorStateEkf::create(o);
    return r.ok() ? std::string() : r.error().message;
  };
  EkfOptions o;
  o.buffer_s = 0.0;
  EXPECT_NE(message(o).find("buffer_s"), std::string::npos);
  o = {};
  o.gate_probability = 1.5;
  EXPECT_NE(message(o).find("gate_probability"), std::string::npos);
  o = {};
  o.imu_noise.accel_noise_density = std::nan("");
  EXPECT_NE(message(o).find("accel_noise_density"), std::string::npos);
  o = {};
  o.measurement_covariance_scale = -1.0;
  EXPECT_NE(message(o).find("measurement_covariance_scale"), std::string::npos);
  o = {};
  o.max_imu_gap_s = 0.0;
  EXPECT_NE(message(o).find("max_imu_gap_s"), std::string::npos);
  o = {};
  o.T_body_camera.linear() *= 2.0;
  EXPECT_NE(message(o).find("T_body_camera"), std::string::npos);
  o = {};
  o.initial_sigma_velocity_m_s = 0.0;
  EXPECT_NE(message(o).find("initial_sigma_velocity_m_s"), std::string::npos);
  o = {};
  o.gate_probability = 1.0;
  ASSERT_TRUE(ErrorStateEkf::create(o).ok());
  EXPECT_TRUE(std::isinf(ErrorStateEkf::create(o)->gateThreshold()));
}

// ---------------------------------------------------------------------------------------------
// Queries and output.

TEST(ErrorStateEkf, PredictOutputsAndInitializationFromBufferedReadings) {
  const DelayedScene scene;
  ErrorStateEkf ekf = *ErrorStateEkf::create(scene.options);
  // Readings before initialize are buffered; initializing at 0.5025 s (between two readings)
  // propagates through the ones after it at once.
  for (const ImuSample& r : scene.sim.imu) {
    if (r.t_ns <= 600'000'000) {
      ASSERT_TRUE(ekf.addImu(r).ok());
    }
  }
  EXPECT_EQ(ekf.queuedOutputs(), 0u);
  const int64_t t0 = 502'500'000;
  const TrajectoryState s0 = scene.trajectory.evaluate(t0);
  ASSERT_TRUE(ekf.initializeFromCamera(t0, s0.T_world_body * scene.options.T_body_camera, s0.v_world_body).ok());
  ASSERT_TRUE(ekf.stateAt(t0).ok());
  EXPECT_LT((ekf.stateAt(t0)->p_world_body - s0.T_world_body.translation()).norm(), 1e-12);
  EXPECT_EQ(ekf.newestNs(), 600'000'000);
  EXPECT_EQ(ekf.oldestNs(), t0);
  const TrajectoryState s1 = scene.trajectory.evaluate(600'000'000);
  EXPECT_LT((ekf.current().p_world_body - s1.T_world_body.translation()).norm(), 1e-3);
  // IMU-rate output: one state per reading, with velocity and covariance.
  scene.feed(ekf, 700'000'000);
  const std::vector<EkfState> out = ekf.drainOutputs();
  ASSERT_EQ(out.size(), 20u);
  EXPECT_EQ(out.back().t_ns, 700'000'000);
  EXPECT_EQ(ekf.queuedOutputs(), 0u);
  // predict: inside the buffer equals the output there; past the newest reading up to 50 ms.
  const Result<EkfPrediction> inside = ekf.predict(out[5].t_ns);
  ASSERT_TRUE(inside.ok());
  expectStatesNear(inside->state, out[5], 1e-12);
  const Result<EkfPrediction> ahead = ekf.predict(720'000'000);
  ASSERT_TRUE(ahead.ok());
  EXPECT_NEAR(ahead->extrapolated_s, 0.02, 1e-12);
  const TrajectoryState s2 = scene.trajectory.evaluate(720'000'000);
  EXPECT_LT((ahead->T_world_body.translation() - s2.T_world_body.translation()).norm(), 5e-3);
  EXPECT_LT(
      (ahead->T_world_camera.translation() - (s2.T_world_body * scene.options.T_body_camera).translation()).norm(),
      5e-3);
  EXPECT_TRUE(ahead->covariance_camera.isApprox(ekf.cameraCovariance(ahead->state)));
  EXPECT_TRUE(ahead->T_world_camera.isApprox(ekf.cameraPose(ahead->state)));
  EXPECT_GT(ahead->covariance_body.trace(), bodyPoseCovariance(ekf.current()).trace());
  EXPECT_EQ(ekf.newestNs(), 700'000'000);  // predict changed nothing
  EXPECT_FALSE(ekf.predict(760'000'000).ok());
  EXPECT_FALSE(ekf.predict(t0 - 1).ok());
}

// ---------------------------------------------------------------------------------------------
// 7. Long run.

TEST(ErrorStateEkf, LongRunStaysFiniteAndPositiveDefinite) {
  // 120 s of an aggressive handheld motion, noisy IMU with biases, poses at 20 Hz applied 30 ms
  // late, 5 % of them 20-sigma outliers, and a 2 s stretch without poses: every IMU-rate output
  // finite with a symmetric positive definite P; outliers rejected; position error bounded
  // (measured max 43 mm with poses, 84 mm over the 2 s without; 100 / 300 mm allowed).
  EkfOptions o;
  o.T_body_camera = bodyCamera();
  const SplineTrajectory trajectory = makeFlight(TrajectoryKind::kAggressive, 121.0, 77);
  const SimImu sim = simulate(trajectory, o.imu_noise, {0.003, -0.002, 0.001}, {0.05, -0.08, 0.04}, 78, true);
  ErrorStateEkf ekf = *ErrorStateEkf::create(o);
  const TrajectoryState s0 = trajectory.evaluate(0);
  ASSERT_TRUE(ekf.initialize(0, s0.T_world_body, Vector3d::Zero()).ok());
  const Matrix6d C = cameraCovariance();
  Xoshiro256 rng(79);
  int outliers = 0;
  int rejected = 0;
  int checked = 0;
  double worst_m = 0.0;
  double worst_blackout_m = 0.0;
  for (size_t k = 1; k < sim.imu.size(); ++k) {
    ASSERT_TRUE(ekf.addImu(sim.imu[k]).ok());
    const int64_t t = k >= 6 ? sim.imu[k - 6].t_ns : 0;  // 30 ms late
    const bool blackout = t > 60 * kSecondNs && t < 62 * kSecondNs;
    if (k >= 6 && (k - 6) % kReadingsPerFrame == 0 && !blackout) {
      Vector6d xi = drawGaussian(rng, C);
      const bool outlier = k > 2000 && rng.chance(0.05);
      if (outlier) {
        xi *= 20.0 / std::sqrt(xi.dot(C.ldlt().solve(xi)));
        ++outliers;
      }
      const Pose T_true = trajectory.evaluate(t).T_world_body * o.T_body_camera;
      const Result<EkfUpdate> u = ekf.updateCameraPose(t, T_true * expSE3(-xi), C);
      ASSERT_TRUE(u.ok());
      if (!u->accepted) ++rejected;
    }
    for (const EkfState& x : ekf.drainOutputs()) {
      ASSERT_TRUE(x.p_world_body.allFinite() && x.v_world_body.allFinite() && x.R_world_body.allFinite());
      ASSERT_TRUE(symmetricPositiveDefinite(x.P)) << "t " << x.t_ns;
      ++checked;
    }
    if (k > 400) {
      const int64_t now = sim.imu[k].t_ns;
      const double e = (ekf.current().p_world_body - trajectory.evaluate(now).T_world_body.translation()).norm();
      double& worst = now > 60 * kSecondNs && now < 63 * kSecondNs ? worst_blackout_m : worst_m;
      worst = std::max(worst, e);
    }
  }
  std::printf("long run: %d outputs, %d outliers, %d rejected, max position error %.1f mm (blackout %.1f mm)\n",
              checked, outliers, rejected, worst_m * 1e3, worst_blackout_m * 1e3);
  EXPECT_EQ(checked, static_cast<int>(sim.imu.size()) - 1);
  EXPECT_GT(outliers, 50);
  EXPECT_GE(rejected, outliers);
  EXPECT_LE(rejected, outliers + 10);
  EXPECT_LT(worst_m, 0.1);
  EXPECT_LT(worst_blackout_m, 0.3);
}

}  // namespace
}  // namespace vkloc
