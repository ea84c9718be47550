// vkloc: the sensor readings the fusion consumes besides the camera: IMU samples with their
// noise model, and GPS-like position priors.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace vkloc {

/// One IMU reading in the body frame.
struct ImuSample {
  int64_t t_ns = 0;
  Eigen::Vector3d gyro_body = Eigen::Vector3d::Zero();   ///< Angular rate, rad/s.
  Eigen::Vector3d accel_body = Eigen::Vector3d::Zero();  ///< Specific force R_body_world (a - g), m/s^2.
};

/// Continuous-time IMU noise model (Kalibr / EuRoC convention).
struct ImuNoise {
  double rate_hz = 200.0;               ///< Sample rate, Hz.
  double gyro_noise_density = 1.7e-4;   ///< White noise, rad/s/sqrt(Hz).
  double accel_noise_density = 2.0e-3;  ///< White noise, m/s^2/sqrt(Hz).
  double gyro_random_walk = 1.9e-5;     ///< Bias random walk, rad/s^2/sqrt(Hz).
  double accel_random_walk = 3.0e-3;    ///< Bias random walk, m/s^3/sqrt(Hz).
};

/// A GPS-like position prior of the body in the world frame.
struct PositionPrior {
  int64_t t_ns = 0;
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();  ///< Metres.
  Eigen::Vector3d sigma = Eigen::Vector3d::Ones();         ///< 1-sigma per axis, metres (> 0).
};

}  // namespace vkloc
