// Property tests of the SO(3)/SE(3) maps in se3.hpp.
#include "vkloc/core/se3.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "vkloc/core/pose.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v(n(rng), n(rng), n(rng));
  return v.normalized();
}

/// Rotation vectors covering identity, tiny, ordinary, near-pi and exactly-pi angles.
std::vector<Eigen::Vector3d> testRotations() {
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3d> out = {Eigen::Vector3d::Zero()};
  for (double angle : {1e-12, 1e-9, 1e-6, 1e-4, 1e-3, 0.1, 1.0, 2.0, 3.0, kPi - 1e-3, kPi - 1e-6, kPi - 1e-9, kPi}) {
    for (int k = 0; k < 4; ++k) out.push_back(angle * randomUnit(rng));
  }
  out.push_back(kPi * Eigen::Vector3d::UnitX());
  out.push_back(kPi * Eigen::Vector3d(0, 1, 1).normalized());
  return out;
}

Eigen::Matrix3d angleAxis(const Eigen::Vector3d& phi) {
  const double angle = phi.norm();
  if (angle == 0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, phi / angle).toRotationMatrix();
}

TEST(Se3, HatVeeAndCrossProduct) {
  const Eigen::Vector3d a(0.3, -1.2, 2.5);
  const Eigen::Vector3d b(-0.7, 0.4, 1.1);
  EXPECT_LT((hat(a) * b - a.cross(b)).norm(), 1e-15);
  EXPECT_LT((vee(hat(a)) - a).norm(), 1e-15);
  Vector6d xi;
  xi << 1, 2, 3, 0.1, 0.2, 0.3;
  EXPECT_LT((veeSE3(hatSE3(xi)) - xi).norm(), 1e-15);
}

TEST(Se3, ExpSO3MatchesAngleAxisAndIsOrthonormal) {
  for (const Eigen::Vector3d& phi : testRotations()) {
    const Eigen::Matrix3d R = expSO3(phi);
    EXPECT_LT((R - angleAxis(phi)).cwiseAbs().maxCoeff(), 1e-14) << phi.transpose();
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-14);
  }
}

TEST(Se3, LogSO3InvertsExpIncludingNearPi) {
  for (const Eigen::Vector3d& phi : testRotations()) {
    const Eigen::Matrix3d R = angleAxis(phi);  // independent construction
    const Eigen::Vector3d back = logSO3(R);
    EXPECT_LE(back.norm(), kPi + 1e-12);
    // Rotation vectors of angle pi are ambiguous in sign: compare the rotations, and the
    // vectors themselves below pi.
    EXPECT_LT((expSO3(back) - R).cwiseAbs().maxCoeff(), 1e-14) << phi.transpose();
    if (phi.norm() < kPi - 1e-5) {
      EXPECT_LT((back - phi).norm(), 1e-12 * std::max(1.0, phi.norm())) << phi.transpose();
    }
  }
}

TEST(Se3, RotationAngleDegIsTheAngleOfTheAxisAngle) {
  for (const Eigen::Vector3d& phi : testRotations()) {
    const double expected = phi.norm() * 180.0 / kPi;  // testRotations are within [0, pi]
    EXPECT_NEAR(rotationAngleDeg(angleAxis(phi)), expected, 1e-9) << phi.transpose();
  }
  EXPECT_EQ(rotationAngleDeg(Eigen::Matrix3d::Identity()), 0.0);
}

TEST(Se3, ExpLogRoundTripSE3) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> t(-5.0, 5.0);
  for (const Eigen::Vector3d& phi : testRotations()) {
    Pose T = Pose::Identity();
    T.linear() = angleAxis(phi);
    T.translation() = Eigen::Vector3d(t(rng), t(rng), t(rng));
    const Pose back = expSE3(logSE3(T));
    EXPECT_LT((back.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-12) << phi.transpose();
  }
  // Near identity: a micrometre translation with a nano-radian rotation.
  Vector6d tiny;
  tiny << 1e-6, -2e-6, 3e-6, 1e-9, -1e-9, 2e-9;
  EXPECT_LT((logSE3(expSE3(tiny)) - tiny).norm(), 1e-20);
}

TEST(Se3, ExpSE3MatchesMatrixExponential) {
  // Independent oracle: the series sum_k X^k / k! of the 4x4 twist matrix.
  Vector6d xi;
  xi << 0.4, -0.3, 1.2, 0.5, -0.8, 0.3;
  const Eigen::Matrix4d X = hatSE3(xi);
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d term = Eigen::Matrix4d::Identity();
  for (int k = 1; k < 40; ++k) {
    term = term * X / k;
    sum += term;
  }
  EXPECT_LT((expSE3(xi).matrix() - sum).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(Se3, AdjointIdentity) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vector6d a, xi;
    for (int k = 0; k < 6; ++k) {
      a[k] = n(rng);
      xi[k] = 0.5 * n(rng);
    }
    const Pose T = expSE3(a);
    const Pose lhs = expSE3(adjointSE3(T) * xi);
    const Pose rhs = T * expSE3(xi) * T.inverse();
    EXPECT_LT((lhs.matrix() - rhs.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(Se3, LeftAndRightJacobiansMatchNumericDerivatives) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& phi :
       {Eigen::Vector3d(0.3, -0.2, 0.9), Eigen::Vector3d(1e-7, 2e-7, -1e-7), Eigen::Vector3d(0, 2.9, 0.3)}) {
    const Eigen::Matrix3d R = expSO3(phi);
    Eigen::Matrix3d Jl_num, Jr_num;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = h * Eigen::Vector3d::Unit(k);
      // expSO3(phi + d) = expSO3(Jl d) R  =>  Jl d = log(expSO3(phi + d) R^T); central differences.
      Jl_num.col(k) = (logSO3(expSO3(phi + d) * R.transpose()) - logSO3(expSO3(phi - d) * R.transpose())) / (2 * h);
      Jr_num.col(k) = (logSO3(R.transpose() * expSO3(phi + d)) - logSO3(R.transpose() * expSO3(phi - d))) / (2 * h);
    }
    EXPECT_LT((leftJacobianSO3(phi) - Jl_num).cwiseAbs().maxCoeff(), 1e-8) << phi.transpose();
    EXPECT_LT((rightJacobianSO3(phi) - Jr_num).cwiseAbs().maxCoeff(), 1e-8) << phi.transpose();
    EXPECT_LT((leftJacobianInverseSO3(phi) * leftJacobianSO3(phi) - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
              1e-12);
  }
}

TEST(Se3, PointJacobianOfLeftPerturbationMatchesNumeric) {
  Vector6d a;
  a << 0.2, -1.0, 3.0, 0.4, 0.1, -0.6;
  const Pose T = expSE3(a);
  const Eigen::Vector3d p_ref(0.5, -0.25, 2.0);
  const Eigen::Vector3d p = T * p_ref;
  Eigen::Matrix<double, 3, 6> numeric;
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    const Vector6d d = h * Vector6d::Unit(k);
    numeric.col(k) = (applyLeftIncrement(T, d) * p_ref - applyLeftIncrement(T, -d) * p_ref) / (2 * h);
  }
  EXPECT_LT((pointJacobian(p) - numeric).cwiseAbs().maxCoeff(), 1e-8);
  // Left increments compose in the left frame: exp(d) T moves T's points by exp(d).
  const Vector6d d = 0.1 * a;
  EXPECT_LT(((applyLeftIncrement(T, d) * p_ref) - (expSE3(d) * p)).norm(), 1e-14);
}

}  // namespace
}  // namespace vkloc

namespace vkloc {
namespace {

TEST(PoseText, BadTokenIsQuotedPrintably) {
  const auto parsed = parseNumbers(std::string("1 2\x1b[2J\x01 3", 10), "--init-offset", 3);
  ASSERT_FALSE(parsed.ok());
  const std::string& message = parsed.error().message;
  EXPECT_NE(message.find("is not a number"), std::string::npos) << message;
  for (const char c : message) EXPECT_FALSE(static_cast<unsigned char>(c) < 0x20 || c == 0x7f) << message;
}

}  // namespace
}  // namespace vkloc
