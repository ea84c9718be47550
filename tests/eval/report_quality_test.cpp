// The frames log's extra columns by name and the HTML report's quality plots: drawn for the
// columns a log has, left out silently for those it lacks, absent without a log.
#include "eval/report_quality.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "vkloc/eval/eval.hpp"
#include "vkloc/eval/report.hpp"

namespace vkloc {
namespace {

constexpr int64_t kT0 = 1'000'000'000'000;
constexpr int64_t kStep = 100'000'000;

std::string framesCsv(const std::string& header, const std::string& extra_fields, int frames) {
  std::string text = "t_ns,state,total_ms" + (header.empty() ? "" : "," + header) + "\n";
  for (int i = 0; i < frames; ++i) {
    const char* state = i == 3 ? "lost" : (i == 4 ? "inertial" : "tracking");
    text += std::to_string(kT0 + i * kStep) + "," + state + ",12.5" + (header.empty() ? "" : "," + extra_fields) + "\n";
  }
  return text;
}

EvalResult evaluateWith(const FrameLog& log) {
  EvalInput in;
  for (int i = 0; i < 10; ++i) {
    Pose T = Pose::Identity();
    T.translation() = Eigen::Vector3d(0.1 * i, 0.0, 1.0);
    in.groundtruth.push_back({kT0 + i * kStep, T});
    if (i != 3) in.estimate.push_back({kT0 + i * kStep, T});
  }
  in.frame_log = log;
  return evaluateTrajectory(in).value();
}

TEST(FrameLogColumns, KeepsOtherColumnsByName) {
  Result<FrameLog> log = parseFrameLog(
      "t_ns,state,verify_score,total_ms,note,ekf_nis\n1,tracking,0.9,3,hello,2.5\n2,lost,,4,x,nan\n", "f.csv");
  ASSERT_TRUE(log.ok()) << log.error().message;
  ASSERT_EQ(log->value_names.size(), 3u);
  EXPECT_EQ(log->value_names[0], "verify_score");
  const std::vector<double>* verify = log->column("verify_score");
  ASSERT_NE(verify, nullptr);
  ASSERT_EQ(verify->size(), 2u);
  EXPECT_DOUBLE_EQ((*verify)[0], 0.9);
  EXPECT_TRUE(std::isnan((*verify)[1]));
  EXPECT_TRUE(std::isnan(log->column("note")->at(0)));  // text reads as "no number"
  EXPECT_DOUBLE_EQ(log->column("ekf_nis")->at(0), 2.5);
  EXPECT_TRUE(std::isnan(log->column("ekf_nis")->at(1)));
  EXPECT_EQ(log->column("inertial_sigma_m"), nullptr);
  EXPECT_EQ(log->stage_names.size(), 1u);  // total_ms stays a stage
}

TEST(ReportQuality, PlotsTheColumnsTheLogHas) {
  // Columns in another order than the tracker writes them: read by name.
  const std::string text =
      framesCsv("ekf_nis,inertial_sigma_m,verify_score,inlier_ratio,chance_inlier_ratio", "3.5,0.02,0.8,0.9,0.1", 10);
  const FrameLog log = parseFrameLog(text, "frames.csv").value();
  const EvalResult r = evaluateWith(log);
  const std::string fake = "/* Chart fake */ var Chart = function(){};";
  const std::string html = evalReportHtml(r, {}, &fake);
  for (const char* id : {"q_state", "q_inliers", "q_nis", "q_isigma"}) {
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  }
  EXPECT_NE(html.find("const Q={"), std::string::npos);
  EXPECT_NE(html.find("\"verification score\""), std::string::npos);
  EXPECT_NE(html.find("\"EKF NIS\""), std::string::npos);
  EXPECT_NE(html.find("\"names\":[\"lost\",\"inertial\",\"tracking\"]"), std::string::npos);
  // The state runs: tracking from 0, lost at 0.3 s, inertial at 0.4 s, tracking again, the end.
  EXPECT_NE(html.find("\"y\":[2,0,1,2,2]"), std::string::npos) << html.substr(html.find("const Q="), 600);
}

TEST(ReportQuality, LeavesOutWhatIsMissing) {
  // Only the tracker's inlier ratio: no NIS or inertial plots, no error.
  const FrameLog some = parseFrameLog(framesCsv("inlier_ratio", "0.7", 10), "frames.csv").value();
  const std::string fake = "/* Chart fake */ var Chart = function(){};";
  const std::string html = evalReportHtml(evaluateWith(some), {}, &fake);
  EXPECT_NE(html.find("id=\"q_inliers\""), std::string::npos);
  EXPECT_NE(html.find("\"inlier ratio\""), std::string::npos);
  EXPECT_EQ(html.find("\"verification score\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"q_nis\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"q_isigma\""), std::string::npos);

  // No quality column at all: the state plot only; the report still renders its other plots.
  const FrameLog none = parseFrameLog(framesCsv("", "", 10), "frames.csv").value();
  const std::string plain = evalReportHtml(evaluateWith(none), {}, &fake);
  EXPECT_NE(plain.find("id=\"q_state\""), std::string::npos);
  EXPECT_EQ(plain.find("id=\"q_inliers\""), std::string::npos);
  EXPECT_NE(plain.find("id=\"terr\""), std::string::npos);
  EXPECT_NE(plain.find("</html>"), std::string::npos);

  // No frames log: no quality plots, no script for them.
  EXPECT_EQ(qualityPlotDivs(nullptr), "");
  EXPECT_EQ(qualityPlotScript(nullptr, 0), "");
  FrameLog empty;
  EXPECT_EQ(qualityPlotScript(&empty, 0), "");
}

}  // namespace
}  // namespace vkloc
