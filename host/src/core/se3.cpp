#include "vkloc/core/se3.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace vkloc {
namespace {

// Below this angle (radians) the closed forms lose precision to cancellation and Taylor series
// with terms up to theta^6 take over; their truncation error is then below 1e-17.
constexpr double kSmallAngle = 1e-2;

}  // namespace

Eigen::Matrix3d hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d W;
  W << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return W;
}

Eigen::Vector3d vee(const Eigen::Matrix3d& W) {
  return 0.5 * Eigen::Vector3d(W(2, 1) - W(1, 2), W(0, 2) - W(2, 0), W(1, 0) - W(0, 1));
}

Eigen::Matrix4d hatSE3(const Vector6d& xi) {
  Eigen::Matrix4d X = Eigen::Matrix4d::Zero();
  X.topLeftCorner<3, 3>() = hat(xi.tail<3>());
  X.topRightCorner<3, 1>() = xi.head<3>();
  return X;
}

Vector6d veeSE3(const Eigen::Matrix4d& X) {
  Vector6d xi;
  xi.head<3>() = X.topRightCorner<3, 1>();
  xi.tail<3>() = vee(X.topLeftCorner<3, 3>());
  return xi;
}

Eigen::Matrix3d expSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d W = hat(phi);
  double a = 0;  // sin(theta) / theta
  double b = 0;  // (1 - cos(theta)) / theta^2
  if (theta < kSmallAngle) {
    a = 1.0 - theta2 / 6.0 * (1.0 - theta2 / 20.0 * (1.0 - theta2 / 42.0));
    b = 0.5 - theta2 / 24.0 * (1.0 - theta2 / 30.0 * (1.0 - theta2 / 56.0));
  } else {
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  return Eigen::Matrix3d::Identity() + a * W + b * W * W;
}

Eigen::Vector3d logSO3(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();  // sin(theta / 2)
  const double w = q.w();     // cos(theta / 2) >= 0
  if (s < 1e-10) {
    // theta = 2 atan(s / w) ~= 2 s / w (1 - s^2 / (3 w^2)); w ~= 1 here.
    return (2.0 / w) * (1.0 - s * s / (3.0 * w * w)) * v;
  }
  const double theta = 2.0 * std::atan2(s, w);
  return (theta / s) * v;
}

double rotationAngleDeg(const Eigen::Matrix3d& R) { return logSO3(R).norm() * 180.0 / M_PI; }

Eigen::Matrix3d leftJacobianSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d W = hat(phi);
  double b = 0;  // (1 - cos) / theta^2
  double c = 0;  // (theta - sin) / theta^3
  if (theta < kSmallAngle) {
    b = 0.5 - theta2 / 24.0 * (1.0 - theta2 / 30.0 * (1.0 - theta2 / 56.0));
    c = 1.0 / 6.0 - theta2 / 120.0 * (1.0 - theta2 / 42.0 * (1.0 - theta2 / 72.0));
  } else {
    b = (1.0 - std::cos(theta)) / theta2;
    c = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Eigen::Matrix3d::Identity() + b * W + c * W * W;
}

Eigen::Matrix3d leftJacobianInverseSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d W = hat(phi);
  double d = 0;  // (1 - theta sin / (2 (1 - cos))) / theta^2
  if (theta < kSmallAngle) {
    d = 1.0 / 12.0 + theta2 / 720.0 + theta2 * theta2 / 30240.0 + theta2 * theta2 * theta2 / 1209600.0;
  } else {
    d = (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / theta2;
  }
  return Eigen::Matrix3d::Identity() - 0.5 * W + d * W * W;
}

Eigen::Matrix3d rightJacobianSO3(const Eigen::Vector3d& phi) { return leftJacobianSO3(-phi); }

Pose expSE3(const Vector6d& xi) {
  const Eigen::Vector3d phi = xi.tail<3>();
  Pose T = Pose::Identity();
  T.linear() = expSO3(phi);
  T.translation() = leftJacobianSO3(phi) * xi.head<3>();
  return T;
}

Vector6d logSE3(const Pose& T) {
  Vector6d xi;
  const Eigen::Vector3d phi = logSO3(T.linear());
  xi.tail<3>() = phi;
  xi.head<3>() = leftJacobianInverseSO3(phi) * T.translation();
  return xi;
}

Matrix6d adjointSE3(const Pose& T) {
  Matrix6d A = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  A.topLeftCorner<3, 3>() = R;
  A.topRightCorner<3, 3>() = hat(T.translation()) * R;
  A.bottomRightCorner<3, 3>() = R;
  return A;
}

Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& p) {
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -hat(p);
  return J;
}

Pose applyLeftIncrement(const Pose& T, const Vector6d& delta) { return expSE3(delta) * T; }

}  // namespace vkloc
