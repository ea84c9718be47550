// vkloc: rigid transforms.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/status.hpp"

namespace vkloc {

/// Rigid transform. `T_a_b` maps points from frame b into frame a: p_a = T_a_b * p_b, so
/// T_a_c = T_a_b * T_b_c reads left to right. Translations in metres.
using Pose = Eigen::Isometry3d;

/// Builds T_world_camera for a camera at `eye` looking at `target` (world frame, metres), with
/// image "up" as close as possible to `up_world` (any, when the view is parallel to it).
/// Camera frame: x right, y down, z forward. Returns kInvalidArgument when eye == target, up is
/// zero or any value is non-finite.
Result<Pose> lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                    const Eigen::Vector3d& up_world = Eigen::Vector3d::UnitZ());

/// Parses a list of finite numbers separated by spaces, commas or semicolons (brackets are
/// ignored), e.g. "1, 2.5 3". kInvalidArgument naming `what` and the bad token otherwise; when
/// `expected` > 0, also when the count differs.
Result<std::vector<double>> parseNumbers(const std::string& text, const std::string& what, size_t expected = 0);

/// Parses a pose from text: "tx ty tz qx qy qz qw" (TUM order, T_world_camera) or 16 numbers
/// (row-major 4x4). Commas and spaces both separate. Rejects non-finite values and a
/// quaternion whose norm is far from 1 (|1 - |q|| > 1e-3 after reading; it is then normalised).
Result<Pose> parsePose(const std::string& text);

/// Formats a pose as "tx ty tz qx qy qz qw" with 9 significant digits.
std::string formatPose(const Pose& T);

/// True when the rotation is orthonormal to 1e-6 and every entry finite.
bool isValidPose(const Pose& T);

/// A timestamped camera pose T_world_camera (a TUM trajectory line).
struct StampedPose {
  int64_t t_ns = 0;  ///< Nanoseconds.
  Pose T_world_camera = Pose::Identity();
};

}  // namespace vkloc
