// Trajectory evaluation: matching estimates to ground truth, absolute and relative pose errors,
// alignment, lost frames, frame times, and the frames-log parser.
#include "vkloc/eval/eval.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

std::string trim(const std::string& s) { return std::string(text::trim(s)); }

std::string lower(const std::string& s) { return text::lower(s); }

std::vector<std::string> splitCommas(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

bool parseInt64(const std::string& s, int64_t& v) { return text::parseInt64(s, v).empty(); }

bool parseDouble(const std::string& s, double& v) { return text::parseDouble(s, v).empty(); }

/// Decimal seconds to nanoseconds by vkloc's one rule (text::parseSecondsToNs).
bool parseSecondsNs(const std::string& s, int64_t& t_ns) { return text::parseSecondsToNs(s, t_ns).empty(); }

bool isNotMeasured(const std::string& s) {
  const std::string l = lower(s);
  return l.empty() || l == "nan" || l == "-";
}

// Angle of a rotation, radians, robust near 0 and pi.
double rotationAngle(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

// Index of the entry of `times` nearest to t, or -1 when farther than tol_ns or none.
long nearestIndex(const std::vector<int64_t>& times, int64_t t, int64_t tol_ns) {
  if (times.empty()) return -1;
  const auto it = std::lower_bound(times.begin(), times.end(), t);
  long best = -1;
  int64_t best_d = std::numeric_limits<int64_t>::max();
  const long hi = static_cast<long>(it - times.begin());
  for (long k : {hi - 1, hi}) {
    if (k < 0 || k >= static_cast<long>(times.size())) continue;
    const int64_t d = std::abs(times[k] - t);
    if (d < best_d) {
      best_d = d;
      best = k;
    }
  }
  return best_d <= tol_ns ? best : -1;
}

struct GtMatch {
  bool ok = false;
  Pose T_world_camera = Pose::Identity();
  bool interpolated = false;
  double dt_s = 0.0;
};

// Ground truth at time t: interpolated between the bracketing samples when both are within
// max_gap, else the nearest within max_time_diff.
GtMatch groundTruthAt(const std::vector<StampedPose>& gt, const std::vector<int64_t>& gt_t, int64_t t,
                      int64_t max_gap_ns, int64_t max_diff_ns) {
  GtMatch m;
  const auto it = std::lower_bound(gt_t.begin(), gt_t.end(), t);
  const size_t hi = static_cast<size_t>(it - gt_t.begin());
  if (hi < gt_t.size() && gt_t[hi] == t) {
    m.ok = true;
    m.T_world_camera = gt[hi].T_world_camera;
    return m;
  }
  if (hi > 0 && hi < gt_t.size() && t - gt_t[hi - 1] <= max_gap_ns && gt_t[hi] - t <= max_gap_ns) {
    const Pose& A = gt[hi - 1].T_world_camera;
    const Pose& B = gt[hi].T_world_camera;
    const double a = static_cast<double>(t - gt_t[hi - 1]) / static_cast<double>(gt_t[hi] - gt_t[hi - 1]);
    const Eigen::Quaterniond qa(A.linear()), qb(B.linear());
    m.T_world_camera.linear() = qa.slerp(a, qb).normalized().toRotationMatrix();
    m.T_world_camera.translation() = (1.0 - a) * A.translation() + a * B.translation();
    m.ok = true;
    m.interpolated = true;
    return m;
  }
  const long k = nearestIndex(gt_t, t, max_diff_ns);
  if (k >= 0) {
    m.ok = true;
    m.T_world_camera = gt[k].T_world_camera;
    m.dt_s = std::abs(gt_t[k] - t) * 1e-9;
  }
  return m;
}

// Position of the ground truth at t (linear interpolation, clamped to the ends; has_gt false
// beyond max_gap of any sample).
MarkedFrame markFrame(const std::vector<StampedPose>& gt, const std::vector<int64_t>& gt_t, int64_t t,
                      int64_t max_gap_ns, int64_t max_diff_ns) {
  MarkedFrame f;
  f.t_ns = t;
  const GtMatch m = groundTruthAt(gt, gt_t, t, max_gap_ns, max_diff_ns);
  if (m.ok) {
    f.has_gt = true;
    f.p_world_gt = m.T_world_camera.translation();
  }
  return f;
}

Status checkTrajectory(const std::vector<StampedPose>& poses, const char* what) {
  for (size_t i = 0; i < poses.size(); ++i) {
    if (!isValidPose(poses[i].T_world_camera)) {
      return makeError(ErrorCode::kInvalidArgument, fmt::format("{} pose {} is not a valid rigid transform", what, i));
    }
    if (i > 0 && poses[i].t_ns <= poses[i - 1].t_ns) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("{} times must increase: pose {} at {} ns follows {} ns", what, i, poses[i].t_ns,
                                   poses[i - 1].t_ns));
    }
  }
  return Status::success();
}

double percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return 0.0;
  const double pos = p * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double f = pos - static_cast<double>(lo);
  return sorted[lo] + f * (sorted[hi] - sorted[lo]);
}

// Relative errors over segments; `coord` is the travelled distance (m) or time (s) per frame.
RelativeError relativeError(const std::vector<Pose>& T_gt, const std::vector<Pose>& T_est,
                            const std::vector<double>& coord, double nominal, bool per_distance) {
  RelativeError r;
  r.nominal = nominal;
  std::vector<double> te, re;
  const double eps = 1e-9 * std::max(1.0, nominal);
  size_t j = 0;
  for (size_t i = 0; i < coord.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < coord.size() && coord[j] - coord[i] < nominal - eps) ++j;
    if (j >= coord.size()) break;
    const double span = coord[j] - coord[i];
    if (span > 2.0 * nominal) {
      ++r.skipped;
      continue;
    }
    const Pose d_gt = T_gt[i].inverse() * T_gt[j];
    const Pose d_est = T_est[i].inverse() * T_est[j];
    const Pose E = d_gt.inverse() * d_est;
    const double t_err = E.translation().norm() / span;
    te.push_back(per_distance ? 100.0 * t_err : t_err);
    re.push_back(rotationAngle(E.linear()) * kRadToDeg / span);
  }
  r.translation = computeErrorStats(std::move(te));
  r.rotation = computeErrorStats(std::move(re));
  return r;
}

Alignment align(const std::vector<FrameError>& frames, const std::vector<Pose>& T_gt, const std::vector<Pose>& T_est,
                bool with_scale, std::vector<double>* per_frame_t, std::vector<double>* per_frame_r) {
  Alignment a;
  const long n = static_cast<long>(frames.size());
  if (n < 3) return a;
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (long i = 0; i < n; ++i) {
    src.col(i) = frames[i].p_world_est;
    dst.col(i) = frames[i].p_world_gt;
  }
  // Positions on a line leave the rotation about it undetermined (Umeyama then returns an
  // arbitrary one): detect it from the spread of the ground-truth positions.
  const Eigen::Vector3d dst_mean = dst.rowwise().mean();
  const Eigen::Vector3d src_mean = src.rowwise().mean();
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> spread(dst.colwise() - dst_mean);
  const Eigen::Vector3d sv = spread.singularValues();
  if (!(sv(1) > 1e-3 * sv(0)) || !(sv(0) > 1e-9)) {
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (long i = 0; i < n; ++i) sum += T_gt[i].linear() * T_est[i].linear().transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
    const Eigen::Matrix3d R = svd.matrixU() * D * svd.matrixV().transpose();
    a.scale = 1.0;
    if (with_scale) {
      const double src_var = (src.colwise() - src_mean).squaredNorm();
      if (src_var > 0)
        a.scale = ((dst.colwise() - dst_mean).cwiseProduct(R * (src.colwise() - src_mean))).sum() / src_var;
    }
    if (!(a.scale > 0) || !R.allFinite()) return a;
    a.rotation_from_orientations = true;
    a.T_gt_est.linear() = R;
    a.T_gt_est.translation() = dst_mean - a.scale * (R * src_mean);
  } else {
    const Eigen::Matrix4d S = Eigen::umeyama(src, dst, with_scale);
    if (!S.allFinite()) return a;
    Eigen::Matrix3d sR = S.block<3, 3>(0, 0);
    a.scale = with_scale ? std::cbrt(sR.determinant()) : 1.0;
    if (!(a.scale > 0)) return a;
    a.T_gt_est.linear() = sR / a.scale;
    a.T_gt_est.translation() = S.block<3, 1>(0, 3);
  }
  a.valid = true;
  std::vector<double> te(n), re(n);
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3d p = a.scale * (a.T_gt_est.linear() * T_est[i].translation()) + a.T_gt_est.translation();
    te[i] = (p - T_gt[i].translation()).norm();
    re[i] = rotationAngle(T_gt[i].linear().transpose() * a.T_gt_est.linear() * T_est[i].linear()) * kRadToDeg;
  }
  if (per_frame_t) *per_frame_t = te;
  if (per_frame_r) *per_frame_r = re;
  a.translation_m = computeErrorStats(std::move(te));
  a.rotation_deg = computeErrorStats(std::move(re));
  return a;
}

}  // namespace

ErrorStats computeErrorStats(std::vector<double> values) {
  ErrorStats s;
  s.count = values.size();
  if (values.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  const double n = static_cast<double>(values.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0.0;
  for (double v : values) var += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(var / n);
  std::sort(values.begin(), values.end());
  s.max = values.back();
  s.median = percentile(values, 0.5);
  return s;
}

Result<FrameLog> parseFrameLog(const std::string& text, const std::string& name) {
  FrameLog log;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  std::vector<std::string> header;
  int time_col = -1;
  bool time_in_seconds = false;
  int state_col = -1;
  std::vector<int> stage_cols;
  std::vector<int> value_cols;
  auto fail = [&](const std::string& what) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}:{}: {}", name, line_no, what));
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const std::vector<std::string> fields = splitCommas(t);
    if (header.empty()) {
      header = fields;
      for (size_t c = 0; c < header.size(); ++c) {
        const std::string h = lower(header[c]);
        if (h == "t_ns" || (h == "timestamp" && time_col < 0)) {
          time_col = static_cast<int>(c);
          time_in_seconds = h == "timestamp";
        } else if (h == "state") {
          state_col = static_cast<int>(c);
        } else if (h.size() > 3 && h.compare(h.size() - 3, 3, "_ms") == 0) {
          stage_cols.push_back(static_cast<int>(c));
          log.stage_names.push_back(header[c]);
        } else {
          value_cols.push_back(static_cast<int>(c));
          log.value_names.push_back(header[c]);
        }
      }
      if (time_col < 0) return fail("header has no 't_ns' (or 'timestamp') column");
      log.stage_ms.resize(stage_cols.size());
      log.values.resize(value_cols.size());
      continue;
    }
    if (fields.size() != header.size()) {
      return fail(fmt::format("{} fields, the header has {}", fields.size(), header.size()));
    }
    int64_t t_ns = 0;
    const std::string& ts = fields[time_col];
    if (!(time_in_seconds ? parseSecondsNs(ts, t_ns) : parseInt64(ts, t_ns))) {
      return fail(fmt::format("bad time '{}' ({})", ts.substr(0, 40),
                              time_in_seconds ? "seconds expected" : "integer nanoseconds expected"));
    }
    if (!log.t_ns.empty() && t_ns <= log.t_ns.back()) return fail("frame times must increase");
    log.t_ns.push_back(t_ns);
    if (state_col >= 0) log.state.push_back(lower(fields[state_col]));
    for (size_t k = 0; k < stage_cols.size(); ++k) {
      const std::string& f = fields[stage_cols[k]];
      double v = std::numeric_limits<double>::quiet_NaN();
      if (!isNotMeasured(f) && !parseDouble(f, v)) {
        return fail(fmt::format("bad number '{}' in column '{}'", f.substr(0, 40), log.stage_names[k]));
      }
      log.stage_ms[k].push_back(v);
    }
    for (size_t k = 0; k < value_cols.size(); ++k) {
      double v = std::numeric_limits<double>::quiet_NaN();
      if (!parseDouble(fields[value_cols[k]], v) || !std::isfinite(v)) v = std::numeric_limits<double>::quiet_NaN();
      log.values[k].push_back(v);
    }
  }
  if (header.empty()) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: no header line", name));
  return log;
}

const std::vector<double>* FrameLog::column(const std::string& name) const {
  for (size_t k = 0; k < value_names.size() && k < values.size(); ++k) {
    if (value_names[k] == name) return &values[k];
  }
  return nullptr;
}

Result<FrameLog> loadFrameLog(const std::string& path) {
  auto content = text::readFile(path, "frames log");
  if (!content.ok()) return content.error();
  return parseFrameLog(*content, path);
}

Result<EvalResult> evaluateTrajectory(const EvalInput& input, const EvalOptions& options) {
  if (!(options.max_gap_s >= 0) || !(options.max_time_diff_s >= 0) || !(options.rpe_distance_m > 0) ||
      !(options.rpe_delta_s > 0) ||
      !std::isfinite(options.max_gap_s + options.max_time_diff_s + options.rpe_distance_m + options.rpe_delta_s)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "evaluation options: max gap and max time difference must be >= 0, RPE distance and delta > 0");
  }
  if (input.groundtruth.empty()) return makeError(ErrorCode::kInvalidArgument, "ground truth is empty");
  VKLOC_TRY_STATUS(checkTrajectory(input.groundtruth, "ground truth"));
  VKLOC_TRY_STATUS(checkTrajectory(input.estimate, "estimate"));
  if (input.frame_times_ns) {
    for (size_t i = 1; i < input.frame_times_ns->size(); ++i) {
      if ((*input.frame_times_ns)[i] <= (*input.frame_times_ns)[i - 1]) {
        return makeError(ErrorCode::kInvalidArgument, fmt::format("frame times must increase (frame {})", i));
      }
    }
  }
  if (input.frame_log) {
    const FrameLog& fl = *input.frame_log;
    bool ok = fl.state.empty() || fl.state.size() == fl.t_ns.size();
    ok = ok && fl.stage_ms.size() == fl.stage_names.size();
    for (const auto& col : fl.stage_ms) ok = ok && col.size() == fl.t_ns.size();
    for (size_t i = 1; ok && i < fl.t_ns.size(); ++i) ok = fl.t_ns[i] > fl.t_ns[i - 1];
    if (!ok) return makeError(ErrorCode::kInvalidArgument, "frames log: inconsistent column sizes or times");
  }

  EvalResult r;
  r.options = options;
  r.groundtruth = input.groundtruth;
  r.estimate = input.estimate;
  r.frame_log = input.frame_log;
  const int64_t max_gap_ns = std::llround(options.max_gap_s * 1e9);
  const int64_t max_diff_ns = std::llround(options.max_time_diff_s * 1e9);

  std::vector<int64_t> gt_t, est_t;
  for (const auto& p : input.groundtruth) gt_t.push_back(p.t_ns);
  for (const auto& p : input.estimate) est_t.push_back(p.t_ns);
  r.t0_ns = gt_t.front();
  if (!est_t.empty()) r.t0_ns = std::min(r.t0_ns, est_t.front());
  if (input.frame_log && !input.frame_log->t_ns.empty()) r.t0_ns = std::min(r.t0_ns, input.frame_log->t_ns.front());
  if (input.frame_times_ns && !input.frame_times_ns->empty()) {
    r.t0_ns = std::min(r.t0_ns, input.frame_times_ns->front());
  }

  // --- estimates against ground truth
  r.estimates = input.estimate.size();
  std::vector<Pose> T_gt, T_est;
  for (const auto& e : input.estimate) {
    const GtMatch m = groundTruthAt(input.groundtruth, gt_t, e.t_ns, max_gap_ns, max_diff_ns);
    if (!m.ok) {
      r.unmatched_t_ns.push_back(e.t_ns);
      continue;
    }
    FrameError f;
    f.t_ns = e.t_ns;
    f.p_world_est = e.T_world_camera.translation();
    f.p_world_gt = m.T_world_camera.translation();
    f.error_world = f.p_world_est - f.p_world_gt;
    f.translation_m = f.error_world.norm();
    f.rotation_deg = rotationAngle(m.T_world_camera.linear().transpose() * e.T_world_camera.linear()) * kRadToDeg;
    f.interpolated = m.interpolated;
    f.gt_time_diff_s = m.dt_s;
    if (input.frame_log && !input.frame_log->state.empty()) {
      const long k = nearestIndex(input.frame_log->t_ns, e.t_ns, max_diff_ns);
      if (k >= 0) f.state = input.frame_log->state[k];
    }
    r.interpolated += m.interpolated ? 1 : 0;
    r.frames.push_back(f);
    T_gt.push_back(m.T_world_camera);
    T_est.push_back(e.T_world_camera);
  }
  r.matched = r.frames.size();
  if (r.matched == 0 && r.estimates > 0) {
    r.warnings.push_back(
        fmt::format("no estimate has ground truth within {} s; are both trajectories in seconds of the same clock?",
                    options.max_time_diff_s));
  } else if (!r.unmatched_t_ns.empty()) {
    r.warnings.push_back(fmt::format("{} of {} estimates have no ground truth within {} s", r.unmatched_t_ns.size(),
                                     r.estimates, options.max_time_diff_s));
  }

  std::vector<double> te, re;
  Eigen::Vector3d abs_sum = Eigen::Vector3d::Zero(), sq_sum = Eigen::Vector3d::Zero();
  for (const auto& f : r.frames) {
    te.push_back(f.translation_m);
    re.push_back(f.rotation_deg);
    abs_sum += f.error_world.cwiseAbs();
    sq_sum += f.error_world.cwiseAbs2();
  }
  r.translation_m = computeErrorStats(te);
  r.rotation_deg = computeErrorStats(re);
  if (r.matched > 0) {
    r.axis_mean_abs_m = abs_sum / static_cast<double>(r.matched);
    r.axis_rmse_m = (sq_sum / static_cast<double>(r.matched)).cwiseSqrt();
  }

  // --- alignment
  std::vector<double> aligned_t, aligned_r;
  r.se3 = align(r.frames, T_gt, T_est, false, &aligned_t, &aligned_r);
  if (r.se3.valid) {
    for (size_t i = 0; i < r.frames.size(); ++i) {
      r.frames[i].aligned_translation_m = aligned_t[i];
      r.frames[i].aligned_rotation_deg = aligned_r[i];
    }
    if (r.se3.rotation_from_orientations) {
      r.warnings.push_back("ground-truth positions lie on a line: the aligned rotation is taken from the orientations");
    }
  } else if (r.matched > 0) {
    r.warnings.push_back("fewer than 3 matched poses: no aligned ATE");
  }
  if (options.sim3) r.sim3 = align(r.frames, T_gt, T_est, true, nullptr, nullptr);

  // --- relative errors: distance travelled along the whole ground truth, at each matched time
  std::vector<double> gt_arc(gt_t.size(), 0.0);
  for (size_t k = 1; k < gt_t.size(); ++k) {
    gt_arc[k] = gt_arc[k - 1] + (input.groundtruth[k].T_world_camera.translation() -
                                 input.groundtruth[k - 1].T_world_camera.translation())
                                    .norm();
  }
  std::vector<double> dist, secs;
  for (const auto& f : r.frames) {
    const auto it = std::lower_bound(gt_t.begin(), gt_t.end(), f.t_ns);
    const size_t hi = static_cast<size_t>(it - gt_t.begin());
    double s;
    if (hi == 0) {
      s = gt_arc.front();
    } else if (hi >= gt_t.size()) {
      s = gt_arc.back();
    } else {
      const double a = static_cast<double>(f.t_ns - gt_t[hi - 1]) / static_cast<double>(gt_t[hi] - gt_t[hi - 1]);
      s = gt_arc[hi - 1] + a * (gt_arc[hi] - gt_arc[hi - 1]);
    }
    dist.push_back(s);
    secs.push_back(static_cast<double>(f.t_ns - r.t0_ns) * 1e-9);
  }
  r.rpe_distance = relativeError(T_gt, T_est, dist, options.rpe_distance_m, true);
  r.rpe_time = relativeError(T_gt, T_est, secs, options.rpe_delta_s, false);

  // --- reference frames: estimated? lost?
  std::vector<int64_t> ref;
  if (input.frame_times_ns) {
    ref = *input.frame_times_ns;
    r.reference_source = "sequence images";
  } else if (input.frame_log) {
    ref = input.frame_log->t_ns;
    r.reference_source = "frames log";
  } else {
    ref = gt_t;
    r.reference_source = "ground truth";
  }
  r.reference_frames = ref.size();
  size_t localized = 0;
  for (int64_t t : ref) {
    const bool estimated = nearestIndex(est_t, t, max_diff_ns) >= 0;
    bool is_lost = false, is_inertial = false;
    if (input.frame_log && !input.frame_log->state.empty()) {
      const long k = nearestIndex(input.frame_log->t_ns, t, max_diff_ns);
      is_lost = k >= 0 && input.frame_log->state[k] == "lost";
      is_inertial = k >= 0 && input.frame_log->state[k] == "inertial";
    }
    if (is_inertial) r.inertial.push_back(markFrame(input.groundtruth, gt_t, t, max_gap_ns, max_diff_ns));
    if (!estimated) r.not_estimated.push_back(markFrame(input.groundtruth, gt_t, t, max_gap_ns, max_diff_ns));
    if (is_lost) r.lost.push_back(markFrame(input.groundtruth, gt_t, t, max_gap_ns, max_diff_ns));
    if (estimated && !is_lost) ++localized;
  }
  if (!ref.empty()) {
    const double n = static_cast<double>(ref.size());
    r.not_estimated_fraction = static_cast<double>(r.not_estimated.size()) / n;
    r.lost_fraction = static_cast<double>(r.lost.size()) / n;
    r.localized_fraction = static_cast<double>(localized) / n;
  }

  // --- frame times
  if (input.frame_log) {
    const FrameLog& fl = *input.frame_log;
    for (const auto& s : fl.state) ++r.state_counts[s.empty() ? std::string("(empty)") : s];
    for (size_t k = 0; k < fl.stage_names.size(); ++k) {
      std::vector<double> v;
      for (double x : fl.stage_ms[k]) {
        if (std::isfinite(x)) v.push_back(x);
      }
      std::sort(v.begin(), v.end());
      StageTimeStats st;
      st.name = fl.stage_names[k];
      st.count = v.size();
      if (!v.empty()) {
        double sum = 0.0;
        for (double x : v) sum += x;
        st.mean_ms = sum / static_cast<double>(v.size());
        st.median_ms = percentile(v, 0.5);
        st.p90_ms = percentile(v, 0.9);
        st.max_ms = v.back();
      }
      if (lower(st.name) == "total_ms" && st.median_ms > 0) r.frame_rate_hz = 1000.0 / st.median_ms;
      r.timing.push_back(st);
    }
  }
  return r;
}

}  // namespace vkloc
