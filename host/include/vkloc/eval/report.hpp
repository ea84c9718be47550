// vkloc: reports of a trajectory evaluation: terminal table, JSON, self-contained HTML with plots.
#pragma once

#include <string>

#include "vkloc/core/status.hpp"
#include "vkloc/eval/eval.hpp"

namespace vkloc {

/// Where the report's inputs came from (shown in reports; any may be empty).
struct ReportInfo {
  std::string estimate_path;     ///< Estimated trajectory file.
  std::string groundtruth_path;  ///< Ground-truth file.
  std::string sequence_path;     ///< Sequence folder.
  std::string frames_path;       ///< Frames log file.
  std::string written_at;        ///< Time of writing; "" = now (local time, ISO 8601).
};

/// Aligned plain-text table of the figures, for a terminal.
std::string formatEvalTable(const EvalResult& result);

/// JSON document with every figure, the inputs and per-frame errors (times in seconds and ns).
std::string evalReportJson(const EvalResult& result, const ReportInfo& info);

/// Path of the Chart.js UMD build inlined into HTML reports by default.
const char* defaultChartJsPath();

/// Self-contained HTML report: summary table, inputs, plots drawn by `chartjs_source` (the text
/// of Chart.js 3.x, inlined). When `chartjs_source` is null the plots are replaced by a notice
/// and the tables stay. Everything from the inputs is escaped for HTML / JavaScript.
std::string evalReportHtml(const EvalResult& result, const ReportInfo& info, const std::string* chartjs_source);

/// Reads the Chart.js text for evalReportHtml. kNotFound / kIoError naming the file;
/// kMalformedInput when it is empty or does not mention Chart.js.
Result<std::string> loadChartJs(const std::string& path);

/// Writes a report to `path` through a temporary file in the same folder and a rename, so that
/// an existing file is replaced only by a complete one. kIoError naming the file.
Status writeReportFile(const std::string& path, const std::string& text);

}  // namespace vkloc
