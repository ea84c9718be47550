// vkloc: trajectory evaluation (absolute and relative pose errors, lost frames, frame times);
// its reports (terminal table, JSON, HTML) are eval/report.hpp.
//
// Estimated and ground-truth poses are T_world_camera in the same world (model) frame; errors are
// computed without alignment (global localization), and for comparison after an SE(3) (and
// optionally Sim(3)) alignment of the estimate onto the ground truth.
//
// Frames log (CSV written by the tracker, one row per processed camera frame):
//   # lines starting with '#' and blank lines are ignored
//   t_ns,state,total_ms,render_ms,align_ms,note
//   1403636579763555584,tracking,12.5,3.1,8.0,
//   1403636579813555456,lost,30.2,3.0,,reinit
// - The first other line is the header: comma-separated column names (spaces around names are
//   trimmed). Fields are plain (no quoting); every row has exactly as many fields as the header.
// - Time, required: `t_ns` (integer nanoseconds) or `timestamp` (seconds, decimal, as in TUM
//   files; up to 9 decimals are kept exactly). Times must strictly increase.
// - `state`, optional: free text, compared in lower case. "tracking" is a localized frame,
//   "lost" a frame the tracker flags as lost, "inertial" a frame whose pose came from the IMU
//   alone (localized, marked in the report); any other value (e.g. "initializing") is counted
//   under its own name.
// - Every column whose name ends in `_ms` is a per-stage time in milliseconds; `total_ms` is the
//   whole frame. Empty, "nan" or "-" fields mean "not measured" and are left out of statistics.
// - Every other column is kept by its name as numbers (FrameLog::values), e.g. the tracker's
//   `inlier_ratio`; a field that is empty, "nan", "-" or not a number reads as NaN.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Per-frame log of the tracker (see the format at the top of this file).
struct FrameLog {
  std::vector<int64_t> t_ns;                  ///< Frame times, nanoseconds, strictly increasing.
  std::vector<std::string> state;             ///< Lower-case state per frame; empty when no column.
  std::vector<std::string> stage_names;       ///< Names of the `_ms` columns, in file order.
  std::vector<std::vector<double>> stage_ms;  ///< [stage][frame] milliseconds; NaN = not measured.
  std::vector<std::string> value_names;       ///< Names of the other columns, in file order.
  std::vector<std::vector<double>> values;    ///< [column][frame] numbers; NaN = none.

  /// values of the column named `name` (exact match), or null when the log has no such column.
  const std::vector<double>* column(const std::string& name) const;
};

/// Parses a frames log from text; `name` is used in messages ("name:line: what is wrong").
/// kMalformedInput for a missing time column, a wrong field count, a bad number or times that
/// do not increase.
Result<FrameLog> parseFrameLog(const std::string& text, const std::string& name);
/// Reads and parses a frames log file. kNotFound / kIoError when it cannot be read.
Result<FrameLog> loadFrameLog(const std::string& path);

struct EvalOptions {
  /// Interpolate ground truth (linear position, slerp rotation) when both bracketing GT poses are
  /// within this time of the estimate, seconds.
  double max_gap_s = 0.05;
  /// Otherwise match the nearest GT pose when within this time, seconds. Also the tolerance for
  /// matching reference frames to estimates and to frames-log rows.
  double max_time_diff_s = 0.01;
  double rpe_distance_m = 1.0;  ///< Segment length (travelled GT distance) of RPE per metre, metres.
  double rpe_delta_s = 1.0;     ///< Segment duration of RPE per second, seconds.
  bool sim3 = false;            ///< Also compute a Sim(3)-aligned ATE (scale estimated).
};

/// Statistics of a list of non-negative errors. std is the population standard deviation, so
/// rmse^2 = mean^2 + std^2. All zero when count == 0.
struct ErrorStats {
  size_t count = 0;     ///< Number of values.
  double mean = 0.0;    ///< Arithmetic mean.
  double median = 0.0;  ///< Middle value (mean of the two middle values for even counts).
  double rmse = 0.0;    ///< sqrt(mean of squares).
  double max = 0.0;     ///< Largest value.
  double std = 0.0;     ///< Population standard deviation.
};
/// Statistics of `values` (any order).
ErrorStats computeErrorStats(std::vector<double> values);

/// Error of one estimated pose against ground truth at the same time (world frame).
struct FrameError {
  int64_t t_ns = 0;                                       ///< Estimate time, nanoseconds.
  Eigen::Vector3d p_world_est = Eigen::Vector3d::Zero();  ///< Estimated camera position, metres.
  Eigen::Vector3d p_world_gt = Eigen::Vector3d::Zero();   ///< Ground-truth position, metres.
  Eigen::Vector3d error_world = Eigen::Vector3d::Zero();  ///< p_est - p_gt on world axes, metres.
  double translation_m = 0.0;                             ///< |p_est - p_gt|, metres.
  double rotation_deg = 0.0;                              ///< Angle of R_gt^T R_est, degrees.
  double aligned_translation_m = 0.0;                     ///< Translation error after SE(3) alignment, metres.
  double aligned_rotation_deg = 0.0;                      ///< Rotation error after SE(3) alignment, degrees.
  bool interpolated = false;                              ///< GT interpolated between two samples (else nearest/exact).
  double gt_time_diff_s = 0.0;  ///< |t_est - t_gt| of the nearest GT pose (0 if interpolated).
  std::string state;            ///< Tracker state from the frames log; "" when unknown.
};

/// Least-squares alignment of estimated positions onto ground truth (Umeyama 1991, eq. 40-42).
struct Alignment {
  bool valid = false;                ///< False when fewer than 3 matched poses.
  Pose T_gt_est = Pose::Identity();  ///< Rotation + translation taking estimate world into GT world.
  double scale = 1.0;                ///< Scale applied before T_gt_est (1 for SE(3)).
  /// True when the positions lie on a line (or a point), so that they leave the rotation about
  /// that line free: the rotation is then the chordal mean of R_gt R_est^T over the frames.
  bool rotation_from_orientations = false;
  ErrorStats translation_m;  ///< Position errors after alignment, metres.
  ErrorStats rotation_deg;   ///< Rotation errors after alignment, degrees.
};

/// Relative pose error over segments: for matched frames i < j (j the first frame whose segment
/// reaches the nominal length), E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j). Errors are
/// divided by the segment's actual length. Segments longer than twice the nominal one (a gap in
/// the estimate) are skipped.
struct RelativeError {
  double nominal = 0.0;    ///< Segment length: metres (per distance) or seconds (per time).
  size_t skipped = 0;      ///< Segments skipped because they spanned a gap.
  ErrorStats translation;  ///< Per distance: percent of the segment length; per time: m/s.
  ErrorStats rotation;     ///< Per distance: deg/m; per time: deg/s.
};

/// Time statistics of one `_ms` column of the frames log, milliseconds.
struct StageTimeStats {
  std::string name;  ///< Column name, e.g. "total_ms".
  size_t count = 0;  ///< Frames with a measurement.
  double mean_ms = 0.0;
  double median_ms = 0.0;
  double p90_ms = 0.0;  ///< 90th percentile, linear interpolation between order statistics.
  double max_ms = 0.0;
};

/// A reference frame that was not localized, with the GT position at its time when known.
struct MarkedFrame {
  int64_t t_ns = 0;                                      ///< Frame time, nanoseconds.
  bool has_gt = false;                                   ///< Whether GT covers this time.
  Eigen::Vector3d p_world_gt = Eigen::Vector3d::Zero();  ///< GT position, metres (if has_gt).
};

/// Everything `evaluateTrajectory` measures.
struct EvalResult {
  EvalOptions options;  ///< Options used.
  // Matching of estimates to ground truth.
  size_t estimates = 0;                 ///< Estimated poses given.
  size_t matched = 0;                   ///< Estimates with GT (interpolated or nearest).
  size_t interpolated = 0;              ///< Of these, interpolated between two GT poses.
  std::vector<int64_t> unmatched_t_ns;  ///< Times of estimates without GT, nanoseconds.
  // Reference frames (the frames that should have been localized).
  std::string reference_source;                ///< "sequence images", "frames log" or "ground truth".
  size_t reference_frames = 0;                 ///< Number of reference frames.
  std::vector<MarkedFrame> not_estimated;      ///< Reference frames with no estimate within max_time_diff.
  std::vector<MarkedFrame> lost;               ///< Reference frames flagged "lost" in the frames log.
  std::vector<MarkedFrame> inertial;           ///< Reference frames flagged "inertial" (IMU only, localized).
  double not_estimated_fraction = 0.0;         ///< not_estimated / reference_frames.
  double lost_fraction = 0.0;                  ///< lost / reference_frames.
  double localized_fraction = 0.0;             ///< Frames estimated and not flagged lost / reference_frames.
  std::map<std::string, size_t> state_counts;  ///< Frames-log rows per state.
  // Absolute errors without alignment (world frame).
  ErrorStats translation_m;                                   ///< Metres.
  ErrorStats rotation_deg;                                    ///< Degrees.
  Eigen::Vector3d axis_mean_abs_m = Eigen::Vector3d::Zero();  ///< Mean |error| per world axis, metres.
  Eigen::Vector3d axis_rmse_m = Eigen::Vector3d::Zero();      ///< RMSE per world axis, metres.
  Alignment se3;                                              ///< ATE after rigid alignment.
  std::optional<Alignment> sim3;                              ///< ATE after similarity alignment (options.sim3).
  RelativeError rpe_distance;                                 ///< RPE per metre.
  RelativeError rpe_time;                                     ///< RPE per second.
  std::vector<FrameError> frames;                             ///< One per matched estimate, in time order.
  // Frame times.
  std::vector<StageTimeStats> timing;  ///< One per `_ms` column of the frames log.
  double frame_rate_hz = 0.0;          ///< 1000 / median total_ms; 0 without total_ms.
  // Inputs kept for plots.
  std::vector<StampedPose> groundtruth;  ///< Ground truth as given.
  std::vector<StampedPose> estimate;     ///< Estimate as given.
  std::optional<FrameLog> frame_log;     ///< Frames log as given.
  int64_t t0_ns = 0;                     ///< Time origin of plots (earliest input time), nanoseconds.
  std::vector<std::string> warnings;     ///< Things a user should know (e.g. nothing matched).
};

/// Inputs of an evaluation. Times must strictly increase within each list.
struct EvalInput {
  std::vector<StampedPose> estimate;     ///< Estimated T_world_camera (may be empty: all lost).
  std::vector<StampedPose> groundtruth;  ///< Ground-truth T_world_camera (non-empty).
  /// Times of the frames that should be localized (e.g. a sequence's images), nanoseconds. When
  /// absent: the frames log's times if given, else the ground-truth times.
  std::optional<std::vector<int64_t>> frame_times_ns;
  std::optional<FrameLog> frame_log;  ///< Tracker's per-frame log.
};

/// Matches estimates to ground truth and computes every figure of EvalResult. kInvalidArgument
/// for empty ground truth, times that do not increase, invalid poses or non-positive options.
/// An estimate that matches nothing is not an error: it is reported (and warned about).
Result<EvalResult> evaluateTrajectory(const EvalInput& input, const EvalOptions& options = {});

}  // namespace vkloc
