// IMU integration (midpoint rotation, trapezoidal world acceleration). Gyro readings are body
// rates ([w]x = R^T dR/dt); rotations update on the right.
#include "vkloc/fusion/imu_integration.hpp"

#include <Eigen/Geometry>
#include <algorithm>

#include "vkloc/core/se3.hpp"

namespace vkloc {

std::vector<TrajectoryState> integrateImu(const TrajectoryState& initial, const std::vector<ImuSample>& samples,
                                          const Eigen::Vector3d& gravity_world, const Eigen::Vector3d& gyro_bias,
                                          const Eigen::Vector3d& accel_bias) {
  std::vector<TrajectoryState> states;
  states.reserve(std::max<size_t>(samples.size(), 1));
  TrajectoryState state = initial;
  if (!samples.empty()) {
    state.t_ns = samples.front().t_ns;
    state.omega_body = samples.front().gyro_body - gyro_bias;
    state.a_world_body = state.T_world_body.linear() * (samples.front().accel_body - accel_bias) + gravity_world;
  }
  states.push_back(state);
  for (size_t k = 1; k < samples.size(); ++k) {
    const ImuSample& s = samples[k];
    const double dt = static_cast<double>(s.t_ns - state.t_ns) * 1e-9;
    TrajectoryState next = state;
    next.t_ns = s.t_ns;
    next.omega_body = s.gyro_body - gyro_bias;
    if (dt > 0.0) {
      // Rotation: R_{k+1} = R_k exp(dt (w_k + w_{k+1}) / 2) (midpoint rate).
      const Eigen::Matrix3d R = state.T_world_body.linear() * expSO3(0.5 * dt * (state.omega_body + next.omega_body));
      const Eigen::Quaterniond q(R);
      next.T_world_body.linear() = q.normalized().toRotationMatrix();
      // World acceleration a = R (f - b_a) + g at both ends, taken as linear in between and
      // integrated exactly: v += dt (a_k + a_{k+1}) / 2, p += dt v_k + dt^2 (2 a_k + a_{k+1}) / 6.
      next.a_world_body = next.T_world_body.linear() * (s.accel_body - accel_bias) + gravity_world;
      next.v_world_body = state.v_world_body + 0.5 * dt * (state.a_world_body + next.a_world_body);
      next.T_world_body.translation() = state.T_world_body.translation() + dt * state.v_world_body +
                                        (dt * dt / 6.0) * (2.0 * state.a_world_body + next.a_world_body);
    } else {
      next.a_world_body = state.T_world_body.linear() * (s.accel_body - accel_bias) + gravity_world;
    }
    states.push_back(next);
    state = next;
  }
  return states;
}

}  // namespace vkloc
