// vkloc: integration of IMU readings into body poses and velocities (strapdown mechanisation).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/fusion/sensors.hpp"

namespace vkloc {

/// State of the body at one instant, with exact derivatives of the trajectory.
struct TrajectoryState {
  int64_t t_ns = 0;                                        ///< Time, ns.
  Pose T_world_body = Pose::Identity();                    ///< Body (IMU) pose, metres.
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< Velocity in world, m/s.
  Eigen::Vector3d a_world_body = Eigen::Vector3d::Zero();  ///< Acceleration in world, m/s^2.
  Eigen::Vector3d omega_body = Eigen::Vector3d::Zero();    ///< Angular velocity in body, rad/s.
};

/// Integrates IMU samples from an initial state (pose, velocity) with biases subtracted, using
/// the midpoint rule on rotation (exp of mean rate) and trapezoidal acceleration in the world
/// frame (taken as linear between samples and integrated exactly). `initial` is the state at
/// samples.front().t_ns; its omega and acceleration are replaced by the first reading's. Returns
/// the state at every sample time (first = initial; just `initial` when there are no samples).
/// Samples whose time does not increase leave the state unchanged. Used by tests and the EKF.
std::vector<TrajectoryState> integrateImu(const TrajectoryState& initial, const std::vector<ImuSample>& samples,
                                          const Eigen::Vector3d& gravity_world,
                                          const Eigen::Vector3d& gyro_bias = Eigen::Vector3d::Zero(),
                                          const Eigen::Vector3d& accel_bias = Eigen::Vector3d::Zero());

}  // namespace vkloc
