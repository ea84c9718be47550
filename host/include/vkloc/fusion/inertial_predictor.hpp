// vkloc: inertial prediction of the body pose between visual fixes (the propagation half of
// seed paper 000's loosely coupled IMU filter, sec. IV-D). Visual fixes (accepted edge
// alignments) give T_world_body at frame times; IMU samples are integrated from the oldest fix
// of a sliding window with the midpoint rule (integrateImu). The velocity at the window start
// comes from a least-squares line through the fixes' positions minus the integrated
// accelerations, so one noisy fix barely moves it:
//   p_i - dP(t_i) = p_0 + v_0 (t_i - t_0)        (dP: double integral of R a + g from t_0, v = 0)
//   p(t) = p_0 + v_0 (t - t_0) + dP(t),  R(t) = R_last (R_int(t_last)^T R_int(t))
// where R_int is the gyro-integrated rotation from the first fix's R_world_body.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/sensors.hpp"

namespace vkloc {

/// Options of InertialPredictor. Plain data; checked by validateInertialOptions.
struct InertialOptions {
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};  ///< m/s^2.
  int window_fixes = 20;                           ///< Most recent fixes in the velocity fit (>= 2).
  double window_s = 1.5;                           ///< Fixes older than this before the newest are dropped, seconds.
  int min_fixes = 4;                               ///< No prediction from fewer fixes (>= 2).
  /// Readings older than this before the newest are dropped, and so are fixes (a window that old
  /// predicts nothing useful); readings before the oldest fix always are. Seconds, >= window_s.
  double buffer_s = 30.0;
  /// Prediction up to this long after the newest IMU sample is allowed (readings held), seconds.
  double max_extrapolation_s = 0.02;
  /// No prediction across a gap between consecutive readings longer than this (dropped IMU
  /// data is not bridged by interpolation), seconds.
  double max_reading_gap_s = 0.1;
  /// 1-sigma of an acceleration error (bias, orientation) growing the position uncertainty as
  /// 0.5 sigma dt^2 after the newest fix, m/s^2.
  double accel_sigma = 0.05;
  double min_fix_sigma_m = 1e-3;  ///< Floor of the fixes' position noise estimated from the fit, metres.
};

/// kInvalidArgument for non-finite gravity or values out of range.
Status validateInertialOptions(const InertialOptions& options);

/// A predicted body pose with its uncertainty.
struct InertialPrediction {
  Pose T_world_body = Pose::Identity();
  double sigma_m = 0;      ///< 1-sigma position error of the prediction, metres.
  double fit_rms_m = 0;    ///< RMS residual of the fixes about the fitted motion, metres.
  double since_fix_s = 0;  ///< Time from the newest fix to the prediction, seconds.
  int fixes = 0;           ///< Fixes used.
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();  ///< Predicted velocity, m/s.
};

/// Sliding window of visual fixes plus the IMU samples since its oldest fix. Not thread-safe.
class InertialPredictor {
 public:
  explicit InertialPredictor(const InertialOptions& options = {}) : options_(options) {}

  /// Appends a reading. kInvalidArgument for a non-finite value or a time not after the last
  /// reading's (the reading is then ignored).
  Status addImu(const ImuSample& sample);
  /// Appends an accepted visual pose of the body at t_ns (after the last fix; earlier or
  /// invalid ones are ignored) and drops fixes and readings the window no longer needs.
  void addFix(int64_t t_ns, const Pose& T_world_body);
  /// The body pose at t_ns (after the newest fix), or nullopt when there are fewer than
  /// min_fixes fixes or the readings do not cover the oldest fix to t_ns.
  std::optional<InertialPrediction> predict(int64_t t_ns) const;
  /// Forgets fixes (readings are kept: they stay valid across a relocalization).
  void clearFixes() { fixes_.clear(); }
  /// Forgets fixes and readings.
  void reset();

  size_t fixCount() const { return fixes_.size(); }
  bool hasImu() const { return !imu_.empty(); }

 private:
  struct Fix {
    int64_t t_ns;
    Pose T_world_body;
  };
  InertialOptions options_;
  std::deque<Fix> fixes_;
  std::deque<ImuSample> imu_;
};

}  // namespace vkloc
