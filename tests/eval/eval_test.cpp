// Trajectory evaluation on hand-made trajectories whose errors are known analytically: constant
// offsets, fixed rotation errors, rigid and similarity transforms, scale and rotation drift,
// interpolation, missing and lost frames, the frames log, and the JSON / HTML reports.
#include "vkloc/eval/eval.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/eval/report.hpp"

namespace vkloc {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int64_t kSec = 1'000'000'000;

Pose makePose(const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = p;
  return T;
}

Eigen::Matrix3d rot(double angle_rad, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix();
}

// A helix with turning, pitching camera: positions not collinear, rotations all different.
std::vector<StampedPose> helix(int n, int64_t dt_ns = kSec / 10) {
  std::vector<StampedPose> out;
  for (int i = 0; i < n; ++i) {
    const double t = i * dt_ns * 1e-9;
    const Eigen::Vector3d p(3.0 * std::cos(0.5 * t), 3.0 * std::sin(0.5 * t), 0.2 * t + 0.3 * std::sin(t));
    const Eigen::Matrix3d R = rot(0.5 * t, Eigen::Vector3d::UnitZ()) * rot(0.3 * std::sin(0.7 * t), {1, 0, 0});
    out.push_back({1000 * kSec + i * dt_ns, makePose(p, R)});
  }
  return out;
}

EvalResult evaluate(const EvalInput& in, const EvalOptions& o = {}) {
  Result<EvalResult> r = evaluateTrajectory(in, o);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  return r.ok() ? std::move(r).value() : EvalResult{};
}

TEST(Eval, ConstantOffsetGivesExactStatistics) {
  EvalInput in;
  in.groundtruth = helix(60);
  const Eigen::Vector3d offset(0.1, -0.2, 0.3);
  for (const auto& g : in.groundtruth) {
    StampedPose e = g;
    e.T_world_camera.translation() += offset;
    in.estimate.push_back(e);
  }
  const EvalResult r = evaluate(in);
  const double norm = std::sqrt(0.01 + 0.04 + 0.09);
  EXPECT_EQ(r.matched, 60u);
  EXPECT_EQ(r.translation_m.count, 60u);
  EXPECT_NEAR(r.translation_m.mean, norm, 1e-12);
  EXPECT_NEAR(r.translation_m.median, norm, 1e-12);
  EXPECT_NEAR(r.translation_m.rmse, norm, 1e-12);
  EXPECT_NEAR(r.translation_m.max, norm, 1e-12);
  EXPECT_NEAR(r.translation_m.std, 0.0, 1e-9);
  EXPECT_NEAR(r.axis_mean_abs_m.x(), 0.1, 1e-12);
  EXPECT_NEAR(r.axis_mean_abs_m.y(), 0.2, 1e-12);
  EXPECT_NEAR(r.axis_mean_abs_m.z(), 0.3, 1e-12);
  EXPECT_NEAR(r.axis_rmse_m.x(), 0.1, 1e-12);
  EXPECT_NEAR(r.axis_rmse_m.y(), 0.2, 1e-12);
  EXPECT_NEAR(r.axis_rmse_m.z(), 0.3, 1e-12);
  EXPECT_NEAR(r.frames[7].error_world.y(), -0.2, 1e-12);
  EXPECT_NEAR(r.rotation_deg.max, 0.0, 1e-6);
  // A pure translation is removed by the rigid alignment.
  ASSERT_TRUE(r.se3.valid);
  EXPECT_NEAR(r.se3.translation_m.max, 0.0, 1e-9);
  EXPECT_NEAR((r.se3.T_gt_est.translation() + offset).norm(), 0.0, 1e-9);
  // Every GT frame has an estimate.
  EXPECT_EQ(r.reference_source, "ground truth");
  EXPECT_EQ(r.not_estimated.size(), 0u);
  EXPECT_DOUBLE_EQ(r.localized_fraction, 1.0);
}

TEST(Eval, ErrorStatisticsOfHandValues) {
  const ErrorStats s = computeErrorStats({3.0, 1.0, 4.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_NEAR(s.rmse, std::sqrt(30.0 / 4.0), 1e-15);
  EXPECT_NEAR(s.std, std::sqrt(1.25), 1e-15);
  EXPECT_EQ(computeErrorStats({}).count, 0u);
}

TEST(Eval, KnownRotationErrorInCameraAndWorldFrame) {
  const Eigen::Vector3d axis(0.3, -0.5, 0.8);
  for (bool world_side : {false, true}) {
    EvalInput in;
    in.groundtruth = helix(40);
    for (const auto& g : in.groundtruth) {
      StampedPose e = g;
      const Eigen::Matrix3d E = rot(2.0 * kDeg, axis);
      e.T_world_camera.linear() =
          world_side ? Eigen::Matrix3d(E * g.T_world_camera.linear()) : Eigen::Matrix3d(g.T_world_camera.linear() * E);
      in.estimate.push_back(e);
    }
    const EvalResult r = evaluate(in);
    EXPECT_NEAR(r.rotation_deg.mean, 2.0, 1e-9) << world_side;
    EXPECT_NEAR(r.rotation_deg.median, 2.0, 1e-9);
    EXPECT_NEAR(r.rotation_deg.rmse, 2.0, 1e-9);
    EXPECT_NEAR(r.rotation_deg.max, 2.0, 1e-9);
    EXPECT_NEAR(r.translation_m.max, 0.0, 1e-12);
  }
}

TEST(Eval, RigidTransformIsRemovedByAlignmentOnly) {
  EvalInput in;
  in.groundtruth = helix(80);
  // The estimate lives in another world: T_est_world = X * T_gt_world.
  const Pose X = makePose({5.0, -3.0, 2.0}, rot(30.0 * kDeg, {0.2, 0.4, 1.0}));
  std::vector<double> expected;
  for (const auto& g : in.groundtruth) {
    in.estimate.push_back({g.t_ns, X * g.T_world_camera});
    expected.push_back((X * g.T_world_camera.translation() - g.T_world_camera.translation()).norm());
  }
  EvalOptions o;
  o.sim3 = true;
  const EvalResult r = evaluate(in, o);
  ASSERT_EQ(r.frames.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR(r.frames[i].translation_m, expected[i], 1e-9);
    // R_gt^T X_R R_gt is a rotation by the same angle.
    EXPECT_NEAR(r.frames[i].rotation_deg, 30.0, 1e-8);
    EXPECT_NEAR(r.frames[i].aligned_translation_m, 0.0, 1e-8);
    EXPECT_NEAR(r.frames[i].aligned_rotation_deg, 0.0, 1e-5);
  }
  EXPECT_GT(r.translation_m.mean, 1.0);
  ASSERT_TRUE(r.se3.valid);
  EXPECT_NEAR(r.se3.translation_m.rmse, 0.0, 1e-8);
  EXPECT_TRUE((r.se3.T_gt_est.matrix() - X.inverse().matrix()).cwiseAbs().maxCoeff() < 1e-8);
  ASSERT_TRUE(r.sim3.has_value());
  EXPECT_NEAR(r.sim3->scale, 1.0, 1e-9);
  // Relative errors do not see a rigid change of world.
  EXPECT_NEAR(r.rpe_distance.translation.max, 0.0, 1e-8);
  EXPECT_NEAR(r.rpe_time.rotation.max, 0.0, 1e-5);
}

TEST(Eval, AlignmentOfCollinearPositionsUsesOrientations) {
  // Camera centres on one straight line (as in ViSP's Castle-simu): positions alone leave the
  // rotation about the line free; the orientations fix it.
  EvalInput in;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Matrix3d R = rot(0.02 * i, {0.3, 1.0, 0.2}) * rot(0.5, {1.0, 0.0, 0.0});
    in.groundtruth.push_back({i * kSec / 30, makePose({0.05 + 0.001 * i, 0.1 - 0.002 * i, 0.6}, R)});
  }
  const Pose X = makePose({0.2, -0.1, 0.05}, rot(25.0 * kDeg, {0.5, -1.0, 0.0}));
  for (const auto& g : in.groundtruth) in.estimate.push_back({g.t_ns, X * g.T_world_camera});
  const EvalResult r = evaluate(in);
  ASSERT_TRUE(r.se3.valid);
  EXPECT_TRUE(r.se3.rotation_from_orientations);
  EXPECT_LT(r.se3.rotation_deg.max, 1e-6);
  EXPECT_LT(r.se3.translation_m.max, 1e-9);
  EXPECT_TRUE((r.se3.T_gt_est.matrix() - X.inverse().matrix()).cwiseAbs().maxCoeff() < 1e-9);
  EXPECT_FALSE(r.warnings.empty());
}

TEST(Eval, ScaledEstimateNeedsSim3) {
  EvalInput in;
  in.groundtruth = helix(80);
  const Pose X = makePose({1.0, 2.0, -1.0}, rot(10.0 * kDeg, {1, 1, 0}));
  for (const auto& g : in.groundtruth) {
    Pose T = g.T_world_camera;
    T.translation() *= 0.5;  // estimate at half scale, then moved rigidly
    in.estimate.push_back({g.t_ns, X * T});
  }
  EvalOptions o;
  o.sim3 = true;
  const EvalResult r = evaluate(in, o);
  ASSERT_TRUE(r.sim3 && r.sim3->valid);
  EXPECT_NEAR(r.sim3->scale, 2.0, 1e-9);
  EXPECT_NEAR(r.sim3->translation_m.max, 0.0, 1e-8);
  EXPECT_GT(r.se3.translation_m.rmse, 0.1);
}

TEST(Eval, RpeOnStraightLineWithScaleDrift) {
  // GT: 1 m/s along x for 10 s, sampled at 10 Hz; estimate 2 % too long everywhere.
  EvalInput in;
  for (int i = 0; i <= 100; ++i) {
    const double x = 0.1 * i;
    in.groundtruth.push_back({i * kSec / 10, makePose({x, 0, 0}, Eigen::Matrix3d::Identity())});
    in.estimate.push_back({i * kSec / 10, makePose({1.02 * x, 0, 0}, Eigen::Matrix3d::Identity())});
  }
  const EvalResult r = evaluate(in);
  EXPECT_EQ(r.rpe_distance.translation.count, 91u);  // segments starting at 0..9 m
  EXPECT_NEAR(r.rpe_distance.translation.mean, 2.0, 1e-6);
  EXPECT_NEAR(r.rpe_distance.translation.max, 2.0, 1e-6);
  EXPECT_NEAR(r.rpe_distance.rotation.max, 0.0, 1e-9);
  EXPECT_NEAR(r.rpe_time.translation.mean, 0.02, 1e-8);
  EXPECT_NEAR(r.rpe_time.translation.max, 0.02, 1e-8);
  // Absolute error grows linearly: 0.02 x, so the largest is 0.2 m at the end.
  EXPECT_NEAR(r.translation_m.max, 0.2, 1e-12);
  EXPECT_NEAR(r.translation_m.mean, 0.1, 1e-12);

  // Segments of 2 m: still 2 %.
  EvalOptions o;
  o.rpe_distance_m = 2.0;
  const EvalResult r2 = evaluate(in, o);
  EXPECT_EQ(r2.rpe_distance.translation.count, 81u);
  EXPECT_NEAR(r2.rpe_distance.translation.mean, 2.0, 1e-6);
}

TEST(Eval, RpeRotationDriftPerMetreAndSecond) {
  // Heading of the estimate drifts by 1 deg per metre travelled at 2 m/s.
  EvalInput in;
  for (int i = 0; i <= 100; ++i) {
    const double x = 0.2 * i;
    in.groundtruth.push_back({i * kSec / 10, makePose({x, 0, 0}, Eigen::Matrix3d::Identity())});
    in.estimate.push_back({i * kSec / 10, makePose({x, 0, 0}, rot(x * kDeg, Eigen::Vector3d::UnitZ()))});
  }
  const EvalResult r = evaluate(in);
  EXPECT_NEAR(r.rpe_distance.rotation.mean, 1.0, 1e-9);
  EXPECT_NEAR(r.rpe_distance.rotation.max, 1.0, 1e-9);
  EXPECT_NEAR(r.rpe_time.rotation.mean, 2.0, 1e-9);
  EXPECT_NEAR(r.rotation_deg.max, 20.0, 1e-9);
}

TEST(Eval, InterpolatesBetweenGroundTruthSamples) {
  // GT at 20 Hz moving 1 m/s along y and turning 10 deg/s; every estimate inside it has both
  // neighbours within max_gap (0.05 s).
  EvalInput in;
  auto truth = [](double t) {
    return makePose({0.0, t, 1.0}, rot(10.0 * t * kDeg, Eigen::Vector3d::UnitZ()) * rot(0.5, {1, 0, 0}));
  };
  for (int i = 0; i <= 20; ++i) in.groundtruth.push_back({i * kSec / 20, truth(0.05 * i)});
  in.estimate.push_back({25 * kSec / 1000, truth(0.025)});  // between samples: exact
  in.estimate.push_back({165 * kSec / 1000, truth(0.165)});
  Pose off = truth(0.43);
  off.linear() = off.linear() * rot(1.0 * kDeg, {0, 1, 0});
  in.estimate.push_back({430 * kSec / 1000, off});  // 1 deg away from the interpolated rotation
  in.estimate.push_back({2 * kSec, truth(2.0)});    // beyond GT: no match
  const EvalResult r = evaluate(in);
  EXPECT_EQ(r.estimates, 4u);
  EXPECT_EQ(r.matched, 3u);
  EXPECT_EQ(r.interpolated, 3u);
  ASSERT_EQ(r.unmatched_t_ns.size(), 1u);
  EXPECT_EQ(r.unmatched_t_ns[0], 2 * kSec);
  EXPECT_NEAR(r.frames[0].translation_m, 0.0, 1e-12);
  EXPECT_NEAR(r.frames[0].rotation_deg, 0.0, 1e-6);
  EXPECT_NEAR(r.frames[1].translation_m, 0.0, 1e-12);
  EXPECT_NEAR(r.frames[2].rotation_deg, 1.0, 1e-6);
  EXPECT_FALSE(r.warnings.empty());

  // With a gap larger than max_gap only the nearest sample within max_time_diff counts.
  EvalInput sparse;
  sparse.groundtruth = {{0, truth(0.0)}, {kSec, truth(1.0)}};
  sparse.estimate = {{5 * kSec / 1000, truth(0.0)}, {kSec / 2, truth(0.5)}};
  const EvalResult rs = evaluate(sparse);
  EXPECT_EQ(rs.matched, 1u);
  EXPECT_EQ(rs.interpolated, 0u);
  EXPECT_NEAR(rs.frames[0].gt_time_diff_s, 0.005, 1e-12);
  EXPECT_EQ(rs.unmatched_t_ns.size(), 1u);
  EvalOptions wide;
  wide.max_gap_s = 1.0;
  EXPECT_EQ(evaluate(sparse, wide).interpolated, 2u);
}

TEST(Eval, CountsMissingAndLostFrames) {
  // 20 images at 20 Hz; estimates for all but 5; the tracker flags 3 frames lost, one of which
  // also has no estimate.
  EvalInput in;
  in.groundtruth = helix(21, kSec / 20);
  std::vector<int64_t> images;
  for (int i = 0; i < 20; ++i) images.push_back(in.groundtruth[i].t_ns);
  in.frame_times_ns = images;
  const std::vector<int> missing = {3, 4, 10, 11, 17};
  const std::vector<int> lost = {2, 10, 15};
  const std::vector<int> inertial = {6, 7};  // IMU only: localized, marked
  FrameLog log;
  log.stage_names = {"total_ms"};
  log.stage_ms.resize(1);
  for (int i = 0; i < 20; ++i) {
    if (std::find(missing.begin(), missing.end(), i) == missing.end()) in.estimate.push_back(in.groundtruth[i]);
    log.t_ns.push_back(images[i]);
    const bool is_lost = std::find(lost.begin(), lost.end(), i) != lost.end();
    const bool is_inertial = std::find(inertial.begin(), inertial.end(), i) != inertial.end();
    log.state.push_back(is_lost ? "lost" : (is_inertial ? "inertial" : "tracking"));
    log.stage_ms[0].push_back(10.0);
  }
  in.frame_log = log;
  const EvalResult r = evaluate(in);
  ASSERT_EQ(r.inertial.size(), 2u);
  EXPECT_EQ(r.inertial[1].t_ns, images[7]);
  EXPECT_EQ(r.state_counts.at("inertial"), 2u);
  EXPECT_EQ(r.reference_source, "sequence images");
  EXPECT_EQ(r.reference_frames, 20u);
  ASSERT_EQ(r.not_estimated.size(), 5u);
  EXPECT_EQ(r.not_estimated[2].t_ns, images[10]);
  EXPECT_TRUE(r.not_estimated[2].has_gt);
  EXPECT_NEAR((r.not_estimated[2].p_world_gt - in.groundtruth[10].T_world_camera.translation()).norm(), 0.0, 1e-12);
  ASSERT_EQ(r.lost.size(), 3u);
  EXPECT_EQ(r.lost[1].t_ns, images[10]);
  EXPECT_DOUBLE_EQ(r.not_estimated_fraction, 0.25);
  EXPECT_DOUBLE_EQ(r.lost_fraction, 0.15);
  EXPECT_DOUBLE_EQ(r.localized_fraction, 13.0 / 20.0);  // 15 estimated, 2 of them lost
  EXPECT_EQ(r.state_counts.at("lost"), 3u);
  EXPECT_EQ(r.state_counts.at("tracking"), 15u);
  EXPECT_EQ(r.frames[2].state, "lost");  // estimate of image 2
  EXPECT_EQ(r.frames[3].state, "tracking");

  // Without images the frames log is the reference.
  in.frame_times_ns.reset();
  const EvalResult r2 = evaluate(in);
  EXPECT_EQ(r2.reference_source, "frames log");
  EXPECT_EQ(r2.not_estimated.size(), 5u);

  // No estimates at all: every frame is not estimated, nothing fails.
  in.estimate.clear();
  const EvalResult r3 = evaluate(in);
  EXPECT_EQ(r3.not_estimated.size(), 20u);
  EXPECT_EQ(r3.translation_m.count, 0u);
  EXPECT_DOUBLE_EQ(r3.localized_fraction, 0.0);
}

TEST(Eval, ParsesFramesLogAndTimeStatistics) {
  const std::string text =
      "# tracker log\n"
      "t_ns, state, total_ms, render_ms, note\n"
      "\n"
      "100,Tracking,10,2.5,a\n"
      "200,tracking,20,,b\n"
      "300,lost,30,nan,\r\n"
      "400,initializing,40,3.5,c\n"
      "500,tracking,50,4.5,d\n";
  Result<FrameLog> log = parseFrameLog(text, "frames.csv");
  ASSERT_TRUE(log.ok()) << log.error().message;
  EXPECT_EQ(log->t_ns, (std::vector<int64_t>{100, 200, 300, 400, 500}));
  EXPECT_EQ(log->state[0], "tracking");
  EXPECT_EQ(log->stage_names, (std::vector<std::string>{"total_ms", "render_ms"}));
  EXPECT_TRUE(std::isnan(log->stage_ms[1][1]));

  EvalInput in;
  in.groundtruth = {{100, Pose::Identity()}, {500, Pose::Identity()}};
  in.frame_log = *log;
  const EvalResult r = evaluate(in);
  ASSERT_EQ(r.timing.size(), 2u);
  EXPECT_EQ(r.timing[0].count, 5u);
  EXPECT_DOUBLE_EQ(r.timing[0].mean_ms, 30.0);
  EXPECT_DOUBLE_EQ(r.timing[0].median_ms, 30.0);
  EXPECT_DOUBLE_EQ(r.timing[0].p90_ms, 46.0);  // 40 + 0.6 * (50 - 40)
  EXPECT_DOUBLE_EQ(r.timing[0].max_ms, 50.0);
  EXPECT_DOUBLE_EQ(r.frame_rate_hz, 1000.0 / 30.0);
  EXPECT_EQ(r.timing[1].count, 3u);
  EXPECT_DOUBLE_EQ(r.timing[1].median_ms, 3.5);
  EXPECT_DOUBLE_EQ(r.timing[1].mean_ms, 3.5);
  EXPECT_EQ(r.state_counts.at("initializing"), 1u);
  EXPECT_EQ(r.lost.size(), 1u);

  // Seconds keep nine decimals exactly.
  Result<FrameLog> secs = parseFrameLog("timestamp,total_ms\n1403636579.763555527,5\n1403636579.8,6\n", "s.csv");
  ASSERT_TRUE(secs.ok()) << secs.error().message;
  EXPECT_EQ(secs->t_ns[0], 1403636579763555527LL);
  EXPECT_EQ(secs->t_ns[1], 1403636579800000000LL);

  struct Bad {
    const char* text;
    const char* expect;
  };
  for (const Bad& bad :
       {Bad{"state,total_ms\ntracking,1\n", "frames.csv:1:"}, Bad{"t_ns,total_ms\n1,2\n2,3,4\n", "frames.csv:3:"},
        Bad{"t_ns,total_ms\n5,2\n5,3\n", "frames.csv:3:"}, Bad{"t_ns,total_ms\n1,abc\n", "frames.csv:2:"},
        Bad{"t_ns,total_ms\n1.5,2\n", "frames.csv:2:"}, Bad{"# only a comment\n", "frames.csv"}}) {
    Result<FrameLog> b = parseFrameLog(bad.text, "frames.csv");
    ASSERT_FALSE(b.ok()) << bad.text;
    EXPECT_EQ(b.error().code, ErrorCode::kMalformedInput);
    EXPECT_EQ(b.error().message.rfind(bad.expect, 0), 0u) << b.error().message;
    EXPECT_EQ(b.error().message.find('\n'), std::string::npos);
  }
  EXPECT_EQ(loadFrameLog("/nonexistent/frames.csv").error().code, ErrorCode::kNotFound);
}

TEST(Eval, RejectsBadInput) {
  EvalInput in;
  EXPECT_FALSE(evaluateTrajectory(in).ok());  // no ground truth
  in.groundtruth = helix(5);
  in.estimate = {in.groundtruth[2], in.groundtruth[1]};
  EXPECT_FALSE(evaluateTrajectory(in).ok());  // times decrease
  in.estimate = {in.groundtruth[1]};
  in.estimate[0].T_world_camera.translation().x() = NAN;
  EXPECT_FALSE(evaluateTrajectory(in).ok());
  in.estimate.clear();
  EvalOptions o;
  o.rpe_distance_m = 0.0;
  EXPECT_FALSE(evaluateTrajectory(in, o).ok());
  o = EvalOptions{};
  o.max_time_diff_s = NAN;
  EXPECT_FALSE(evaluateTrajectory(in, o).ok());
}

EvalResult reportFixture() {
  EvalInput in;
  in.groundtruth = helix(30);
  for (size_t i = 0; i < in.groundtruth.size(); ++i) {
    if (i == 5) continue;
    StampedPose e = in.groundtruth[i];
    e.T_world_camera.translation() += Eigen::Vector3d(0.1, -0.2, 0.3);
    in.estimate.push_back(e);
  }
  FrameLog log;
  log.stage_names = {"total_ms", "align_ms"};
  log.stage_ms.resize(2);
  for (size_t i = 0; i < in.groundtruth.size(); ++i) {
    log.t_ns.push_back(in.groundtruth[i].t_ns);
    log.state.push_back(i == 7 ? "</script><b>x" : (i == 5 ? "lost" : "tracking"));
    log.stage_ms[0].push_back(20.0 + static_cast<double>(i));
    log.stage_ms[1].push_back(5.0);
  }
  in.frame_log = log;
  EvalOptions o;
  o.sim3 = true;
  return evaluate(in, o);
}

TEST(EvalReport, JsonHoldsTheFigures) {
  const EvalResult r = reportFixture();
  ReportInfo info;
  info.estimate_path = "est \"quoted\".txt";
  info.written_at = "2024-01-02T03:04:05";
  const nlohmann::json j = nlohmann::json::parse(evalReportJson(r, info));
  EXPECT_NEAR(j["ate"]["translation_m"]["rmse"].get<double>(), std::sqrt(0.14), 1e-12);
  EXPECT_NEAR(j["ate"]["per_axis_m"]["mean_abs"][2].get<double>(), 0.3, 1e-12);
  EXPECT_EQ(j["matching"]["matched"].get<int>(), 29);
  EXPECT_EQ(j["frames"]["not_estimated"].get<int>(), 1);
  EXPECT_EQ(j["frames"]["lost"].get<int>(), 1);
  EXPECT_EQ(j["per_frame"].size(), 29u);
  EXPECT_NEAR(j["per_frame"][3]["error_m"][1].get<double>(), -0.2, 1e-12);
  EXPECT_EQ(j["per_frame"][3]["t_ns"].get<int64_t>(), r.frames[3].t_ns);
  EXPECT_TRUE(j["ate_sim3"]["valid"].get<bool>());
  EXPECT_DOUBLE_EQ(j["timing"]["stages"][0]["median_ms"].get<double>(), 34.5);
  EXPECT_EQ(j["inputs"]["estimate"].get<std::string>(), info.estimate_path);
  EXPECT_EQ(j["written_at"].get<std::string>(), info.written_at);
  EXPECT_TRUE(j["rpe_distance"].contains("translation_percent"));

  const std::string table = formatEvalTable(r);
  EXPECT_NE(table.find("0.3742"), std::string::npos) << table;  // sqrt(0.14)
  EXPECT_NE(table.find("total_ms"), std::string::npos);
}

TEST(EvalReport, HtmlInlinesChartJsAndEscapesInput) {
  const EvalResult r = reportFixture();
  ReportInfo info;
  info.estimate_path = "<script>alert(1)</script>&\"'.txt";
  info.groundtruth_path = "gt.txt";
  const std::string fake = "/* Chart fake */ var Chart = function(){}; var s = '</script><!--';";
  const std::string html = evalReportHtml(r, info, &fake);
  EXPECT_NE(html.find("var Chart = function(){}"), std::string::npos);
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;&amp;&quot;&#39;.txt"), std::string::npos);
  EXPECT_EQ(html.find("<b>x"), std::string::npos);
  EXPECT_EQ(html.find("<!--"), std::string::npos);
  // Exactly the three script elements close: library, plots and the frames log's quality plots.
  size_t closes = 0;
  for (size_t at = html.find("</script"); at != std::string::npos; at = html.find("</script", at + 1)) ++closes;
  EXPECT_EQ(closes, 3u);
  EXPECT_NE(html.find("const D={"), std::string::npos);
  EXPECT_NE(html.find("\"gt_xy\":[["), std::string::npos);
  EXPECT_NE(html.find("id=\"topview\""), std::string::npos);
  EXPECT_NE(html.find("id=\"timing\""), std::string::npos);
  EXPECT_NE(html.find("0.3742"), std::string::npos);  // summary table

  const std::string bare = evalReportHtml(r, info, nullptr);
  EXPECT_NE(bare.find("Plots unavailable"), std::string::npos);
  EXPECT_EQ(bare.find("<canvas"), std::string::npos);
  EXPECT_EQ(bare.find("<script"), std::string::npos);

  Result<std::string> chartjs = loadChartJs(defaultChartJsPath());
  if (chartjs.ok()) {
    const std::string full = evalReportHtml(r, info, &chartjs.value());
    EXPECT_NE(full.find("Chart.js v3"), std::string::npos);
    EXPECT_GT(full.size(), chartjs->size());
  }
  EXPECT_EQ(loadChartJs("/nonexistent/chart.js").error().code, ErrorCode::kNotFound);
}

TEST(EvalReport, WritesAtomicallyAndKeepsOldFileOnFailure) {
  test::TempDir dir("vkloc_eval");
  const std::string path = dir.file("report.json");
  ASSERT_TRUE(writeReportFile(path, "first").ok());
  ASSERT_TRUE(writeReportFile(path, "second").ok());
  const auto bytes = test::readFile(path);
  EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "second");
  const Status s = writeReportFile(dir.file("missing/report.json"), "x");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("missing/report.json"), std::string::npos);
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file() ? 1 : 0;
  EXPECT_EQ(files, 1u);  // no temporary left behind
}

}  // namespace
}  // namespace vkloc
