// vkloc eval: compare an estimated trajectory with ground truth; terminal table, JSON, HTML.
#include <cstdio>

#include "common.hpp"
#include "vkloc/eval/eval.hpp"
#include "vkloc/eval/report.hpp"
#include "vkloc/io/sequence.hpp"

namespace vkloc::cli {

static void addEvalVerb(CLI::App& app) {
  struct Args {
    std::string estimate;
    std::string groundtruth;
    std::string sequence;
    std::string frames;
    std::string json;
    std::string html;
    std::string chartjs = defaultChartJsPath();
    EvalOptions options;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "eval", "Evaluate an estimated trajectory against ground truth (table, JSON, HTML report with plots)");
  cmd->add_option("--estimate,-e", args->estimate, "Estimated trajectory, TUM format (T_world_camera)")->required();
  auto* gt = cmd->add_option("--groundtruth,-g", args->groundtruth, "Ground truth, TUM format (T_world_camera)");
  auto* seq = cmd->add_option("--sequence,-s", args->sequence,
                              "Sequence folder: ground truth and image times (frames not estimated are counted "
                              "against its images)");
  gt->excludes(seq);
  seq->excludes(gt);
  cmd->add_option("--frames,-f", args->frames,
                  "Tracker's frames log CSV (t_ns or timestamp, state, *_ms stage times; see vkloc/eval.hpp)");
  cmd->add_option("--json", args->json, "Write every figure and per-frame errors as JSON");
  cmd->add_option("--html", args->html, "Write a self-contained HTML report with plots");
  cmd->add_option("--chartjs", args->chartjs, "Chart.js 3 UMD build to inline into the HTML report")
      ->capture_default_str();
  cmd->add_option("--rpe-distance", args->options.rpe_distance_m, "RPE segment length, metres")->capture_default_str();
  cmd->add_option("--rpe-delta", args->options.rpe_delta_s, "RPE segment duration, seconds")->capture_default_str();
  cmd->add_option("--max-time-diff", args->options.max_time_diff_s,
                  "Largest time difference to the nearest ground-truth pose, seconds")
      ->capture_default_str();
  cmd->add_option("--max-gap", args->options.max_gap_s,
                  "Interpolate ground truth when both neighbours are within this time, seconds")
      ->capture_default_str();
  cmd->add_flag("--sim3", args->options.sim3, "Also report a Sim(3)-aligned ATE (scale estimated)");
  cmd->add_flag("--quiet,-q", args->quiet, "Do not print the table");
  cmd->callback([args] {
    if (args->groundtruth.empty() && args->sequence.empty()) throw Failure{"give --groundtruth or --sequence"};
    EvalInput input;
    ReportInfo info;
    info.estimate_path = args->estimate;
    input.estimate = take(loadTumTrajectory(args->estimate));
    if (!args->sequence.empty()) {
      const Sequence s = take(loadSequence(args->sequence));
      if (s.groundtruth.empty()) throw Failure{args->sequence + ": sequence has no groundtruth.txt"};
      input.groundtruth = s.groundtruth;
      std::vector<int64_t> times;
      for (const auto& im : s.images) times.push_back(im.t_ns);
      input.frame_times_ns = std::move(times);
      info.sequence_path = args->sequence;
    } else {
      input.groundtruth = take(loadTumTrajectory(args->groundtruth));
      if (input.groundtruth.empty()) throw Failure{args->groundtruth + ": no poses"};
      info.groundtruth_path = args->groundtruth;
    }
    if (!args->frames.empty()) {
      input.frame_log = take(loadFrameLog(args->frames));
      info.frames_path = args->frames;
    }
    const EvalResult result = take(evaluateTrajectory(input, args->options));
    if (!args->quiet) {
      std::fputs(formatEvalTable(result).c_str(), stdout);
    } else {
      for (const auto& w : result.warnings) std::fprintf(stderr, "vkloc: warning: %s\n", w.c_str());
    }
    if (!args->json.empty()) {
      check(writeReportFile(args->json, evalReportJson(result, info)));
      std::printf("wrote %s\n", args->json.c_str());
    }
    if (!args->html.empty()) {
      Result<std::string> chartjs = loadChartJs(args->chartjs);
      if (!chartjs.ok()) {
        std::fprintf(stderr, "vkloc: warning: %s; the HTML report has no plots\n", chartjs.error().message.c_str());
      }
      check(writeReportFile(args->html, evalReportHtml(result, info, chartjs.ok() ? &chartjs.value() : nullptr)));
      std::printf("wrote %s\n", args->html.c_str());
    }
  });
}

VKLOC_REGISTER_VERB(50, addEvalVerb);

}  // namespace vkloc::cli
