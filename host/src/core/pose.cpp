#include "vkloc/core/pose.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "vkloc/core/text.hpp"

namespace vkloc {

Result<Pose> lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up_world) {
  if (!eye.allFinite() || !target.allFinite() || !up_world.allFinite()) {
    return makeError(ErrorCode::kInvalidArgument, "lookAt: non-finite eye, target or up");
  }
  const Eigen::Vector3d forward = target - eye;
  if (forward.norm() < 1e-12) return makeError(ErrorCode::kInvalidArgument, "lookAt: eye equals target");
  const Eigen::Vector3d z = forward.normalized();
  // Right-handed camera frame: x = z cross up is the image's right, y = z cross x points down.
  Eigen::Vector3d x = z.cross(up_world);
  if (x.norm() < 1e-6 * up_world.norm()) {
    // Looking straight along `up` (e.g. a drone camera pointing down): any image "up" is as
    // good; take the world axis least aligned with the view direction.
    Eigen::Index axis = 0;
    z.cwiseAbs().minCoeff(&axis);
    x = z.cross(Eigen::Vector3d::Unit(axis));
  }
  if (x.norm() < 1e-12) {
    return makeError(ErrorCode::kInvalidArgument, "lookAt: up direction is zero");
  }
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Pose T_world_camera = Pose::Identity();
  T_world_camera.linear().col(0) = x;
  T_world_camera.linear().col(1) = y;
  T_world_camera.linear().col(2) = z;
  T_world_camera.translation() = eye;
  return T_world_camera;
}

bool isValidPose(const Pose& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 && R.determinant() > 0;
}

Result<std::vector<double>> parseNumbers(const std::string& text, const std::string& what, size_t expected) {
  std::string cleaned = text;
  for (char& ch : cleaned) {
    if (ch == ',' || ch == ';' || ch == '[' || ch == ']') ch = ' ';
  }
  std::vector<double> v;
  std::istringstream in(cleaned);
  std::string token;
  while (in >> token) {
    char* end = nullptr;
    const double d = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
      return makeError(ErrorCode::kInvalidArgument, text::cat(what, ": ", text::shown(token), " is not a number"));
    }
    if (!std::isfinite(d)) return makeError(ErrorCode::kInvalidArgument, text::cat(what, ": non-finite value"));
    v.push_back(d);
  }
  if (expected > 0 && v.size() != expected) {
    return makeError(ErrorCode::kInvalidArgument, text::cat(what, ": expected ", expected, " numbers, got ", v.size()));
  }
  return v;
}

Result<Pose> parsePose(const std::string& text) {
  auto numbers = parseNumbers(text, "pose");
  if (!numbers.ok()) return numbers.error();
  const std::vector<double>& v = *numbers;
  Pose T = Pose::Identity();
  if (v.size() == 7) {
    Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (std::abs(q.norm() - 1.0) > 1e-3) {
      return makeError(ErrorCode::kInvalidArgument,
                       text::cat("pose: quaternion norm ", q.norm(), " is not 1 (order is qx qy qz qw)"));
    }
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  } else if (v.size() == 16 || v.size() == 12) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (size_t i = 0; i < v.size(); ++i) M(static_cast<int>(i / 4), static_cast<int>(i % 4)) = v[i];
    T.matrix() = M;
    if (!isValidPose(T) || (v.size() == 16 && (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)) {
      return makeError(ErrorCode::kInvalidArgument, "pose: matrix is not a rigid transform");
    }
  } else {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("pose: expected 7 numbers (tx ty tz qx qy qz qw) or 16 (4x4), got ", v.size()));
  }
  return T;
}

std::string formatPose(const Pose& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, "%.9g %.9g %.9g %.9g %.9g %.9g %.9g", t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                q.w());
  return buffer;
}

}  // namespace vkloc
