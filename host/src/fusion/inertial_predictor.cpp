// Inertial prediction between visual fixes (fusion/inertial_predictor.hpp).
#include "vkloc/fusion/inertial_predictor.hpp"

#include <algorithm>
#include <cmath>

#include "vkloc/core/numeric.hpp"
#include "vkloc/fusion/imu_integration.hpp"

namespace vkloc {
namespace {

double seconds(int64_t dt_ns) { return static_cast<double>(dt_ns) * 1e-9; }

}  // namespace

Status validateInertialOptions(const InertialOptions& o) {
  if (!o.gravity_world.allFinite() || o.gravity_world.norm() > 100.0) {
    return makeError(ErrorCode::kInvalidArgument, "inertial: gravity_world must be finite (|g| <= 100 m/s^2)");
  }
  if (o.window_fixes < 2 || o.window_fixes > 10000 || o.min_fixes < 2 || o.min_fixes > o.window_fixes) {
    return makeError(ErrorCode::kInvalidArgument, "inertial: need 2 <= min_fixes <= window_fixes <= 10000");
  }
  if (!finiteIn(o.window_s, 1e-3, 1e4) || !finiteIn(o.buffer_s, o.window_s, 1e5) ||
      !finiteIn(o.max_extrapolation_s, 0.0, 10.0) || !finiteIn(o.max_reading_gap_s, 1e-6, 1e3) ||
      !finiteIn(o.accel_sigma, 0.0, 1e3) || !finiteIn(o.min_fix_sigma_m, 0.0, 1e3)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "inertial: need window_s in [1e-3, 1e4], buffer_s in [window_s, 1e5], max_extrapolation_s in "
                     "[0, 10], max_reading_gap_s in [1e-6, 1e3], accel_sigma in [0, 1e3] and min_fix_sigma_m in "
                     "[0, 1e3]");
  }
  return Status::success();
}

Status InertialPredictor::addImu(const ImuSample& sample) {
  if (!sample.gyro_body.allFinite() || !sample.accel_body.allFinite()) {
    return makeError(ErrorCode::kInvalidArgument, "IMU reading: non-finite rate or acceleration");
  }
  if (!imu_.empty() && sample.t_ns <= imu_.back().t_ns) {
    return makeError(ErrorCode::kInvalidArgument, "IMU reading: time " + std::to_string(sample.t_ns) +
                                                      " ns is not after the previous reading's " +
                                                      std::to_string(imu_.back().t_ns) + " ns");
  }
  imu_.push_back(sample);
  // Readings before the oldest fix are dropped by addFix. A bound for long stretches without
  // fixes: a window older than buffer_s is dropped with the readings it would need.
  const int64_t keep_ns = static_cast<int64_t>(options_.buffer_s * 1e9);
  if (!fixes_.empty() && fixes_.front().t_ns < sample.t_ns - keep_ns) fixes_.clear();
  while (imu_.size() > 2 && imu_[1].t_ns < sample.t_ns - keep_ns) imu_.pop_front();
  return Status::success();
}

void InertialPredictor::addFix(int64_t t_ns, const Pose& T_world_body) {
  if (!isValidPose(T_world_body) || (!fixes_.empty() && t_ns <= fixes_.back().t_ns)) return;
  fixes_.push_back({t_ns, T_world_body});
  const int64_t window_ns = static_cast<int64_t>(options_.window_s * 1e9);
  while (fixes_.size() > static_cast<size_t>(options_.window_fixes) || fixes_.front().t_ns < t_ns - window_ns) {
    fixes_.pop_front();
  }
  // Readings before the oldest fix: keep the one at or just before it (interpolation).
  while (imu_.size() > 2 && imu_[1].t_ns <= fixes_.front().t_ns) imu_.pop_front();
}

void InertialPredictor::reset() {
  fixes_.clear();
  imu_.clear();
}

std::optional<InertialPrediction> InertialPredictor::predict(int64_t t_ns) const {
  if (fixes_.size() < static_cast<size_t>(options_.min_fixes) || imu_.empty()) return std::nullopt;
  const int64_t t0 = fixes_.front().t_ns;
  const int64_t t_last = fixes_.back().t_ns;
  if (t_ns <= t_last || imu_.front().t_ns > t0) return std::nullopt;
  if (seconds(t_ns - imu_.back().t_ns) > options_.max_extrapolation_s) return std::nullopt;
  // Readings must cover t0 .. t_ns without a gap (the one at or before t0 included).
  {
    size_t i = 0;
    while (i + 1 < imu_.size() && imu_[i + 1].t_ns <= t0) ++i;
    for (; i + 1 < imu_.size() && imu_[i].t_ns < t_ns; ++i) {
      if (seconds(imu_[i + 1].t_ns - imu_[i].t_ns) > options_.max_reading_gap_s) return std::nullopt;
    }
  }

  // Readings at arbitrary times: linear between samples, held after the last one.
  size_t k = 0;  // first sample with time > the last query
  auto readingAt = [&](int64_t t) {
    while (k < imu_.size() && imu_[k].t_ns <= t) ++k;
    ImuSample s;
    s.t_ns = t;
    if (k == 0) {
      s.gyro_body = imu_.front().gyro_body;
      s.accel_body = imu_.front().accel_body;
    } else if (k == imu_.size()) {
      s.gyro_body = imu_.back().gyro_body;
      s.accel_body = imu_.back().accel_body;
    } else {
      const ImuSample& a = imu_[k - 1];
      const ImuSample& b = imu_[k];
      const double w = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
      s.gyro_body = (1 - w) * a.gyro_body + w * b.gyro_body;
      s.accel_body = (1 - w) * a.accel_body + w * b.accel_body;
    }
    return s;
  };
  // The readings from t0 to t_ns with samples inserted at every fix time and at t_ns; index of
  // each query among them.
  std::vector<ImuSample> samples;
  samples.reserve(imu_.size() + fixes_.size() + 2);
  samples.push_back(readingAt(t0));
  std::vector<size_t> at_fix(fixes_.size(), 0);
  size_t next = k;  // first sample after t0
  auto appendUntil = [&](int64_t q) {
    while (next < imu_.size() && imu_[next].t_ns < q) samples.push_back(imu_[next++]);
    samples.push_back(readingAt(q));
    if (next < imu_.size() && imu_[next].t_ns == q) ++next;
    return samples.size() - 1;
  };
  for (size_t i = 1; i < fixes_.size(); ++i) at_fix[i] = appendUntil(fixes_[i].t_ns);
  const size_t at_t = appendUntil(t_ns);

  TrajectoryState initial;
  initial.t_ns = t0;
  initial.T_world_body = Pose::Identity();
  initial.T_world_body.linear() = fixes_.front().T_world_body.linear();
  const std::vector<TrajectoryState> states = integrateImu(initial, samples, options_.gravity_world);
  if (states.size() != samples.size()) return std::nullopt;

  // Least-squares line through p_i - dP(t_i) over tau_i = t_i - t0 (seconds).
  const size_t n = fixes_.size();
  std::vector<double> tau(n);
  std::vector<Eigen::Vector3d> y(n);
  double tau_mean = 0;
  Eigen::Vector3d y_mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    tau[i] = seconds(fixes_[i].t_ns - t0);
    y[i] = fixes_[i].T_world_body.translation() - states[at_fix[i]].T_world_body.translation();
    tau_mean += tau[i];
    y_mean += y[i];
  }
  tau_mean /= static_cast<double>(n);
  y_mean /= static_cast<double>(n);
  double s_tt = 0;
  Eigen::Vector3d s_ty = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    s_tt += (tau[i] - tau_mean) * (tau[i] - tau_mean);
    s_ty += (tau[i] - tau_mean) * (y[i] - y_mean);
  }
  if (!(s_tt > 0)) return std::nullopt;
  const Eigen::Vector3d v0 = s_ty / s_tt;
  const Eigen::Vector3d p0 = y_mean - v0 * tau_mean;
  double sse = 0;
  for (size_t i = 0; i < n; ++i) sse += (y[i] - p0 - v0 * tau[i]).squaredNorm();
  const double fit_rms = std::sqrt(sse / static_cast<double>(n > 2 ? n - 2 : 1));

  InertialPrediction out;
  const TrajectoryState& s_t = states[at_t];
  const TrajectoryState& s_last = states[at_fix[n - 1]];
  const double tau_t = seconds(t_ns - t0);
  out.T_world_body.linear() =
      fixes_.back().T_world_body.linear() * (s_last.T_world_body.linear().transpose() * s_t.T_world_body.linear());
  out.T_world_body.translation() = p0 + v0 * tau_t + s_t.T_world_body.translation();
  out.v_world_body = v0 + s_t.v_world_body;
  out.fit_rms_m = fit_rms;
  out.since_fix_s = seconds(t_ns - t_last);
  out.fixes = static_cast<int>(n);
  const double sigma_fix = std::max(fit_rms, options_.min_fix_sigma_m);
  out.sigma_m = sigma_fix * std::sqrt(1.0 / static_cast<double>(n) + (tau_t - tau_mean) * (tau_t - tau_mean) / s_tt) +
                0.5 * options_.accel_sigma * out.since_fix_s * out.since_fix_s;
  if (!isValidPose(out.T_world_body) || !std::isfinite(out.sigma_m)) return std::nullopt;
  return out;
}

}  // namespace vkloc
