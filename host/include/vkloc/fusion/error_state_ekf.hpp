// vkloc: loosely coupled IMU / visual-pose fusion by an error-state extended Kalman filter with
// delayed (out-of-sequence) updates, seed paper 000 sec. IV-D; the ring-buffer design follows its
// ref. [22] (ethz-asl MSF): states are kept per IMU reading, a late pose measurement is applied
// to the state at its own time and the readings after it are propagated again.
//
// Frames and units: world (gravity_world, z up by default), body = IMU frame, camera frame of
// the edge alignment (x right, y down, z forward). Metres, seconds (t_ns: nanoseconds), radians.
//
// Nominal state x = (p_world_body, v_world_body, R_world_body, b_g, b_a); the true state is
// x (+) dx with the 15-dim error state, in this order and with these indices:
//   dx = [dp (0..2), dv (3..5), dtheta (6..8), db_g (9..11), db_a (12..14)]
//   p = p_hat + dp, v = v_hat + dv          (world frame)
//   R = R_hat Exp(dtheta)                   (right perturbation: dtheta in the body frame)
//   b_g = b_g_hat + db_g, b_a = b_a_hat + db_a
// P is the 15x15 covariance of dx. Readings: gyro = omega_body + b_g + n_g,
// accel = R^T (a_world - g) + b_a + n_a (ImuSample), biases random walks.
//
// Pose covariances in and out (alignment input, predictions) use the tracker's SE(3) convention
// with RIGHT perturbation: T_true = T_est expSE3(xi), xi = [rho; phi] in the frame of T_est's
// child (camera or body), see core/se3.hpp.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/sensors.hpp"

namespace vkloc {

using Vector15d = Eigen::Matrix<double, 15, 1>;
using Matrix15d = Eigen::Matrix<double, 15, 15>;
using Matrix6x15d = Eigen::Matrix<double, 6, 15>;

/// Options of ErrorStateEkf. Plain data; checked by validateEkfOptions.
struct EkfOptions {
  /// Continuous-time densities (Kalibr convention) of the readings' white noise and bias random
  /// walks; a step of dt seconds adds density^2 dt to the discrete covariance (rate_hz unused).
  ImuNoise imu_noise;
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};  ///< m/s^2, world frame.
  Pose T_body_camera = Pose::Identity();           ///< Camera in the body (IMU) frame, metres.
  double initial_sigma_position_m = 0.05;          ///< 1-sigma of p at initialize(), metres (> 0).
  /// 1-sigma of v at initialize(), m/s (> 0); a large value (the default) means "unknown".
  double initial_sigma_velocity_m_s = 5.0;
  double initial_sigma_attitude_rad = 0.035;    ///< 1-sigma per axis of dtheta, radians (> 0).
  double initial_sigma_gyro_bias_rad_s = 0.01;  ///< 1-sigma of b_g, rad/s (> 0).
  double initial_sigma_accel_bias_m_s2 = 0.1;   ///< 1-sigma of b_a, m/s^2 (> 0).
  /// Multiplies the alignment's covariance before use (> 0). The edge alignment's Gauss-Newton
  /// covariance is rarely calibrated: set this from data (e.g. so that the filter's normalised
  /// innovations average 6); 1 trusts the alignment as is.
  double measurement_covariance_scale = 1.0;
  /// Floors of the measurement's 1-sigma (position in metres, rotation in radians; >= 0): the
  /// eigenvalues of the position and rotation blocks are raised to at least floor^2, so that an
  /// overoptimistic alignment covariance cannot make the filter overconfident.
  double min_measurement_sigma_m = 1e-3;
  double min_measurement_sigma_rad = 0.05 * 3.14159265358979323846 / 180.0;
  /// Chi-square gate on the 6-DOF innovation: an update whose squared Mahalanobis distance
  /// exceeds chiSquareQuantile(gate_probability, 6) is rejected (0.999 -> 22.46; 0.99 -> 16.81).
  /// In (0, 1]; 1 disables the gate.
  double gate_probability = 0.999;
  /// Length of the state ring buffer, seconds (> 0): a pose update may be this much older than
  /// the newest IMU reading.
  double buffer_s = 2.0;
  /// Longest interval between consecutive readings the filter propagates across, seconds (> 0);
  /// a longer gap re-anchors (see ErrorStateEkf::addImu).
  double max_imu_gap_s = 0.1;
  /// predict() may extrapolate this far past the newest reading (holding it), seconds (>= 0).
  double max_extrapolation_s = 0.05;
  /// Most IMU-rate outputs kept until drainOutputs() (the oldest are dropped beyond it).
  size_t max_queued_outputs = 4096;
};

/// kInvalidArgument naming the first field out of range (non-finite, negative, ...).
Status validateEkfOptions(const EkfOptions& options);

/// Quantile x of the chi-square distribution with `dof` degrees of freedom: P(X <= x) =
/// probability. For probability in (0, 1) and 1 <= dof <= 100000; NaN otherwise. Exact to about
/// 1e-10 relative (regularised gamma function in closed form for integer and half-integer
/// shapes, then bisection). E.g. (0.999, 6) -> 22.458, (0.95, 6) -> 12.592.
double chiSquareQuantile(double probability, int dof);

/// Filter state at one instant: the nominal state and the covariance of the error state.
struct EkfState {
  int64_t t_ns = 0;                                            ///< Time, ns.
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();      ///< Body position, metres.
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();      ///< Body velocity in world, m/s.
  Eigen::Matrix3d R_world_body = Eigen::Matrix3d::Identity();  ///< Body attitude.
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();         ///< b_g, rad/s.
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();        ///< b_a, m/s^2.
  Matrix15d P = Matrix15d::Identity();                         ///< Covariance of dx (order above).

  Pose T_world_body() const;
};

/// x (+) dx: the state whose error relative to `state` is dx (order above); P is copied.
EkfState applyErrorState(const EkfState& state, const Vector15d& dx);

/// truth (-) estimate: the dx with truth = estimate (+) dx (dtheta = Log(R_est^T R_truth)).
Vector15d errorStateBetween(const EkfState& estimate, const EkfState& truth);

/// One propagation step from `state` (at state.t_ns, where the reading was `reading`; its own
/// t_ns is ignored) to next.t_ns > state.t_ns, same scheme as integrateImu with the biases
/// subtracted: w_i = gyro_i - b_g, f_i = accel_i - b_a,
///   R' = R Exp(dt (w_0 + w_1) / 2),  a_0 = R f_0 + g,  a_1 = R' f_1 + g,
///   v' = v + dt (a_0 + a_1) / 2,     p' = p + dt v + dt^2 (2 a_0 + a_1) / 6,  biases constant,
/// and P' = F P F^T + Q with F the exact first-order transition of dx over the step (15x15) and
/// Q the white-noise and random-walk covariance over dt (accelerometer: dt^3/3, dt^2/2, dt for
/// dp, dp-dv, dv). F and Q are returned through the optional pointers. Precondition:
/// next.t_ns > state.t_ns (otherwise the state is returned unchanged with F = I, Q = 0).
EkfState propagateEkfState(const EkfState& state, const ImuSample& reading, const ImuSample& next,
                           const Eigen::Vector3d& gravity_world, const ImuNoise& noise, Matrix15d* F = nullptr,
                           Matrix15d* Q = nullptr);

/// Residual of a body-pose measurement: r = [p_meas - p; Log(R^T R_meas)] (world metres; body
/// radians). r(x (+) dx) ~= r(x) - H dx with H = [I 0 0 0 0; 0 0 Jl^-1(r_phi) 0 0] (6x15),
/// returned through `H`.
Vector6d ekfPoseResidual(const EkfState& state, const Pose& T_world_body_measured, Matrix6x15d* H = nullptr);

/// Covariance of the residual's noise (order [position world; rotation body]) for a camera
/// pose T_world_camera whose xi (T_true = T_est expSE3(xi), camera frame) has covariance
/// `covariance_camera`: the body pose T_world_body = T_world_camera T_body_camera^-1 (seed eqs.
/// 6-7) has xi_body = Ad(T_body_camera) xi, then rho is rotated into the world frame:
///   C = J Ad C_cam Ad^T J^T,  J = diag(R_world_body, I).   (No scale or floor applied.)
Matrix6d ekfMeasurementCovariance(const Pose& T_world_camera, const Matrix6d& covariance_camera,
                                  const Pose& T_body_camera);

/// 6x6 covariance of xi_body = [rho; phi] with T_true = T_world_body expSE3(xi_body), from P:
/// rho = R^T dp, phi = dtheta (to first order).
Matrix6d bodyPoseCovariance(const EkfState& state);

/// As bodyPoseCovariance for the camera: xi_camera = Ad(T_body_camera^-1) xi_body.
Matrix6d cameraPoseCovariance(const EkfState& state, const Pose& T_body_camera);

/// Whether updateCameraPose applies the chi-square gate.
enum class EkfGate {
  kGated,        ///< Reject when the squared Mahalanobis distance exceeds the gate.
  kForceAccept,  ///< Apply whatever the distance (re-anchoring after a relocalization).
};

/// What an update did. innovation and S are evaluated at the measurement's time, before it.
struct EkfUpdate {
  int64_t t_ns = 0;                                   ///< Measurement time, ns.
  bool accepted = false;                              ///< Applied to the filter (false: rejected by the gate).
  bool gate_skipped = false;                          ///< Applied without the gate (kForceAccept or awaitingFix()).
  double mahalanobis_sq = 0.0;                        ///< r^T S^-1 r.
  double gate_threshold = 0.0;                        ///< The threshold it was compared with (inf: no gate).
  Vector6d innovation = Vector6d::Zero();             ///< r = [p_meas - p; Log(R^T R_meas)].
  Matrix6d innovation_covariance = Matrix6d::Zero();  ///< S = H P H^T + C_meas.
  int repropagated_steps = 0;                         ///< IMU steps propagated again after it (0: in time order).
};

/// A pose prediction at one instant.
struct EkfPrediction {
  EkfState state;                                          ///< Full state at t_ns (P included).
  Pose T_world_body = Pose::Identity();                    ///< Body pose, metres.
  Pose T_world_camera = Pose::Identity();                  ///< T_world_body T_body_camera.
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< m/s.
  Matrix6d covariance_body = Matrix6d::Zero();             ///< bodyPoseCovariance.
  Matrix6d covariance_camera = Matrix6d::Zero();           ///< cameraPoseCovariance.
  double extrapolated_s = 0.0;                             ///< Time past the newest reading (readings held), seconds.
};

/// Error-state EKF fusing IMU readings (propagation, at the IMU rate) with camera poses from the
/// edge alignment (updates, possibly late). Not thread-safe: one thread calls everything.
///
/// Typical use: addImu() for every reading (also before initialize(): readings are kept for
/// buffer_s); initializeFromCamera() at the first accepted alignment; then updateCameraPose() for
/// each alignment with its image time, and predict(t_image) as the motion prior of a frame.
class ErrorStateEkf {
 public:
  /// A filter with the default options.
  ErrorStateEkf();
  /// kInvalidArgument (validateEkfOptions) for bad options.
  static Result<ErrorStateEkf> create(const EkfOptions& options);

  /// Starts (or restarts) the filter at t_ns with the body pose and velocity; the biases start at
  /// zero. `covariance` (15x15, order above, symmetric positive definite) defaults to the
  /// initial sigmas of the options. Buffered readings after t_ns are propagated at once (the
  /// state at t_ns takes the reading interpolated there). Queued outputs are kept. Returns
  /// kInvalidArgument (filter unchanged) for a non-finite or non-rigid pose, non-finite velocity,
  /// or a covariance that is not finite, symmetric and positive definite.
  Status initialize(int64_t t_ns, const Pose& T_world_body, const Eigen::Vector3d& v_world_body,
                    const std::optional<Matrix15d>& covariance = std::nullopt);
  /// As above from a full state (biases and P given; state.t_ns is the start time).
  Status initialize(const EkfState& state);
  /// As above from a camera pose: T_world_body = T_world_camera T_body_camera^-1 (eqs. 6-7).
  Status initializeFromCamera(int64_t t_ns, const Pose& T_world_camera, const Eigen::Vector3d& v_world_body,
                              const std::optional<Matrix15d>& covariance = std::nullopt);
  /// Forgets the state, buffers and queued outputs (options kept).
  void reset();

  /// Propagates the state to the reading's time (propagateEkfState), stores the state in the
  /// ring buffer and queues it as an output. Before initialize() the reading is only stored.
  /// Errors (kInvalidArgument):
  ///  - a non-finite reading, or a time not after the previous reading (or the filter's time):
  ///    the reading is ignored, nothing changes;
  ///  - a gap longer than max_imu_gap_s since the previous reading: no propagation across it.
  ///    The filter re-anchors at this reading: the nominal state is kept, the position, velocity
  ///    and attitude variances are raised to at least the initial sigmas (position also by
  ///    (gap (|v| + initial_sigma_velocity))^2) with their correlations cleared, the ring buffer
  ///    restarts here (older updates fail) and awaitingFix() is true: the next pose update is
  ///    applied without the gate. The reading is used and its state queued.
  Status addImu(const ImuSample& sample);

  /// Fuses an alignment result: the camera pose at t_ns with the covariance of xi in the camera
  /// frame (T_true = T_world_camera expSE3(xi), [rho; phi], 6x6 symmetric positive
  /// semi-definite), scaled by measurement_covariance_scale and floored (options). The body
  /// pose T_world_camera T_body_camera^-1 is compared with the state at t_ns (ekfPoseResidual).
  /// t_ns may be older than the newest reading (down to oldestNs()): the update is applied to
  /// the buffered state at t_ns (one interpolated reading inserted when t_ns falls between two)
  /// and the readings after it are propagated again, re-applying the updates stored there, so
  /// the result equals the updates in time order. Rejected by the gate: accepted = false and
  /// nothing changes. Errors (kInvalidArgument, filter unchanged): not initialized; invalid pose
  /// or covariance; t_ns after the newest reading (feed the IMU up to t_ns first) or before
  /// oldestNs(); a numerically failed update (S not positive definite, non-finite result).
  Result<EkfUpdate> updateCameraPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance_camera,
                                     EkfGate gate = EkfGate::kGated);
  /// What updateCameraPose(t_ns, ..., kGated) would decide, without changing the filter: the
  /// same residual, covariance and gate (accepted = it passes; repropagated_steps = 0). Same errors.
  Result<EkfUpdate> testCameraPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance_camera) const;

  /// The state at the newest reading (or the initialization time). Default state before
  /// initialize().
  const EkfState& current() const;
  /// The state at t_ns without changing the filter: from the buffered state before t_ns with an
  /// interpolated reading, or up to max_extrapolation_s past the newest reading holding it
  /// (before any reading: constant velocity, no rotation). kInvalidArgument when not initialized
  /// or t_ns is outside [oldestNs(), newestNs() + max_extrapolation_s].
  Result<EkfState> stateAt(int64_t t_ns) const;
  /// stateAt(t_ns) as body and camera poses with their 6x6 covariances (right perturbation).
  Result<EkfPrediction> predict(int64_t t_ns) const;

  /// Camera pose of a state: T_world_body T_body_camera.
  Pose cameraPose(const EkfState& state) const;
  /// cameraPoseCovariance(state, T_body_camera).
  Matrix6d cameraCovariance(const EkfState& state) const;

  /// The states after each addImu since the last call, oldest first (IMU-rate output with
  /// velocity and covariance). They are what the filter knew then: a later delayed update does
  /// not revise states already queued.
  std::vector<EkfState> drainOutputs();
  size_t queuedOutputs() const { return outputs_.size(); }

  bool initialized() const { return !nodes_.empty(); }
  /// True after an IMU gap re-anchored the filter, until the next accepted update.
  bool awaitingFix() const { return awaiting_fix_; }
  /// Oldest time an update or stateAt accepts, ns (0 before initialize()).
  int64_t oldestNs() const;
  /// Time of current(), ns (0 before initialize()).
  int64_t newestNs() const;
  /// The gate threshold in use (infinity when gate_probability == 1).
  double gateThreshold() const { return gate_threshold_; }
  const EkfOptions& options() const { return options_; }

 private:
  struct Measurement {
    Pose T_world_body;
    Matrix6d covariance;  // Of the residual noise, scaled and floored.
  };
  struct Node {
    EkfState state;
    ImuSample reading;                      // Reading at state.t_ns (measured, interpolated or held).
    bool has_reading = false;               // False only at an initialization before any reading.
    std::vector<Measurement> measurements;  // Updates applied at this node, in arrival order.
  };

  struct PreparedUpdate;  // The measurement, its node and innovation (error_state_ekf.cpp).
  /// The checks and the innovation shared by updateCameraPose and testCameraPose.
  Result<PreparedUpdate> prepareUpdate(int64_t t_ns, const Pose& T_world_camera,
                                       const Matrix6d& covariance_camera) const;

  explicit ErrorStateEkf(const EkfOptions& options, double gate_threshold);
  Status startAt(const EkfState& state);
  Status step(const ImuSample& sample);
  void trim();
  EkfState propagate(const Node& from, const ImuSample& next) const;

  EkfOptions options_;
  double gate_threshold_ = 0.0;
  std::deque<Node> nodes_;          // Ring buffer, oldest first; empty before initialize().
  std::deque<ImuSample> readings_;  // Measured readings of the last buffer_s (for initialize()).
  std::deque<EkfState> outputs_;
  bool awaiting_fix_ = false;
  EkfState empty_state_;
};

}  // namespace vkloc
