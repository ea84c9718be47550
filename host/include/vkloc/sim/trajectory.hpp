// vkloc: smooth continuous-time trajectories, synthetic IMU and position priors (the simulator's).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/imu_integration.hpp"
#include "vkloc/fusion/sensors.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {

/// A C2-smooth trajectory of T_world_body: a uniform cubic B-spline on positions and a cumulative
/// cubic B-spline on SO(3) (rotation R(t) = R_0 prod_j exp(B~_j(t) log(R_{j-1}^T R_j))), so that
/// position, velocity, acceleration, orientation and angular velocity are analytic at any t.
/// omega_body is the body rate ([omega]x = R^T dR/dt), i.e. what a gyroscope measures.
/// A default-constructed trajectory is empty: evaluate() returns the identity state.
class SplineTrajectory {
 public:
  /// Control poses at knot spacing `dt_ns` from `t0_ns`. The spline is defined on
  /// [t0 + dt, t0 + (n-2) dt] (n >= 4 control poses). kInvalidArgument for fewer than 4 poses,
  /// dt <= 0 or invalid poses.
  static Result<SplineTrajectory> fromControlPoses(std::vector<Pose> T_world_body_control, int64_t t0_ns,
                                                   int64_t dt_ns);
  int64_t startNs() const;
  int64_t endNs() const;
  /// State at t (clamped to [startNs(), endNs()]).
  TrajectoryState evaluate(int64_t t_ns) const;
  const std::vector<Pose>& controlPoses() const { return control_; }

 private:
  std::vector<Pose> control_;
  int64_t t0_ns_ = 0;
  int64_t dt_ns_ = 1;
};

/// Kinds of built-in trajectories.
enum class TrajectoryKind {
  kDroneFlight,  ///< 23-47 m above the box floor and clear of buildings, camera tilted 45 deg down (city).
  kDroneAgile,   ///< The drone's path with fast roll and pitch of the airframe (+-25 deg, ~1 Hz).
  kHandheld,     ///< Walking pace, 1.2-1.8 m high, gentle head motion (room).
  kAggressive,   ///< Fast rotations (up to ~3 rad/s) and accelerations, handheld scale.
  kOrbit,        ///< Circle around the scene centre looking at it.
  kDroneAcro,    ///< The agile drone's path and swings, twice as far and fast (up to ~45 deg, ~4.5 rad/s).
};
/// Parses "drone", "drone_agile", "drone_acro", "handheld", "aggressive", "orbit".
Result<TrajectoryKind> parseTrajectoryKind(const std::string& name);
const char* trajectoryKindName(TrajectoryKind kind);
/// The drone kinds: flight, agile, acro (a camera mounted 45 deg down, flying over buildings).
bool isDroneKind(TrajectoryKind kind);

/// The scene's highest geometry seen from above, for drones to fly over: a grid over the model's
/// xy extent (world frame, z up) whose cells hold the largest z (metres) of any triangle whose xy
/// bounding box comes within `radius_m` of the cell. Conservative: a sloped triangle counts with
/// its highest corner over its whole bounding box. A default-constructed field is empty.
class HeightField {
 public:
  /// Cells of `cell_m` metres, coarser when the extent would need more than 2048 per side.
  /// kInvalidArgument for a model without triangles or a non-finite, non-positive cell or
  /// negative radius.
  static Result<HeightField> fromModel(const Model& model, double radius_m, double cell_m = 1.0);
  /// Highest z (metres) near (x, y); -infinity outside the grid or where no triangle is near.
  double top(double x, double y) const;
  bool empty() const { return tops_.empty(); }

 private:
  double x0_ = 0.0, y0_ = 0.0, cell_ = 1.0;
  int width_ = 0, height_ = 0;
  std::vector<float> tops_;
};

struct TrajectoryOptions {
  TrajectoryKind kind = TrajectoryKind::kDroneFlight;
  double duration_s = 10.0;  ///< Length of the usable part of the spline, seconds.
  uint64_t seed = 1;         ///< Random variation of the path; same seed, same path.
  /// Camera mounting on the body; the generators place the *camera* so that it sees the scene
  /// (e.g. 45 deg down for the drone) and derive T_world_body = T_world_camera T_body_camera^-1.
  Pose T_body_camera = Pose::Identity();
  /// Drone kinds: what to fly over. The drone keeps `drone_clearance_m` above it, climbing
  /// (and descending) at most `drone_climb_rate` metres per second of flight so that it is
  /// already high enough when it reaches a tall building. Empty: only the box floor counts.
  HeightField obstacles;
  double drone_clearance_m = 10.0;  ///< Metres above `obstacles`.
  double drone_climb_rate = 2.0;    ///< Metres per second.
};

/// Builds a trajectory that keeps the camera viewing the model inside `scene_bounds` (world
/// frame, z up), defined on [0, duration] (startNs() == 0). kInvalidArgument for an empty or
/// non-finite box, a duration outside (0, 10^4] s, an invalid T_body_camera, a negative or
/// non-finite drone_clearance_m or a non-positive or non-finite drone_climb_rate.
Result<SplineTrajectory> makeTrajectory(const TrajectoryOptions& options, const Aabb& scene_bounds);

/// Samples the IMU along the trajectory at noise.rate_hz from startNs(): gyro = omega_body + b_g
/// + n_g, accel = R_world_body^T (a_world - gravity_world) + b_a + n_a, with discrete white noise
/// sigma = density * sqrt(rate) and biases doing a random walk sigma = rw / sqrt(rate) per
/// sample, starting at zero. `noise == nullopt` gives exact readings at the default 200 Hz.
/// Deterministic in `seed`. Empty for a non-positive rate or negative/non-finite parameters.
std::vector<ImuSample> simulateImu(const SplineTrajectory& trajectory, const std::optional<ImuNoise>& noise,
                                   const Eigen::Vector3d& gravity_world, uint64_t seed);

struct PriorOptions {
  double rate_hz = 5.0;                  ///< GPS rate, Hz.
  Eigen::Vector3d sigma{1.5, 1.5, 3.0};  ///< 1-sigma noise per world axis, metres.
  double dropout_probability = 0.05;     ///< Chance that a fix starts a dropout.
  double dropout_mean_s = 2.0;           ///< Mean dropout length, seconds.
};
/// Position priors of the body at rate_hz from startNs() with Gaussian noise. Each fix that is
/// not inside a dropout starts one with dropout_probability: it and every fix during an
/// exponentially distributed time (mean dropout_mean_s) are lost. Deterministic in `seed`.
/// Empty for a non-positive rate or sigma, or a probability outside [0, 1].
std::vector<PositionPrior> simulatePriors(const SplineTrajectory& trajectory, const PriorOptions& options,
                                          uint64_t seed);

}  // namespace vkloc
