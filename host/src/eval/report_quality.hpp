// Per-frame quality plots of the HTML report, drawn from the frames log's columns by name:
// tracking state as a step plot, `inlier_ratio` (with `chance_inlier_ratio`) and `verify_score`,
// `ekf_nis` and `inertial_sigma_m`. A column the log lacks is left out; a plot without any of its
// columns is left out.
#pragma once

#include <cstdint>
#include <string>

#include "vkloc/eval/eval.hpp"

namespace vkloc {

/// The plots' boxes (<div class="plot"> with a canvas each) for the report's plot grid; "" when
/// `log` is null or has none of the columns.
std::string qualityPlotDivs(const FrameLog* log);

/// A <script> element drawing them with Chart.js (loaded before it), times in seconds from
/// t0_ns; "" when there is nothing to draw. Numbers and state names only (state names are
/// reduced to [a-z0-9_-]), so the script is safe to inline.
std::string qualityPlotScript(const FrameLog* log, int64_t t0_ns);

}  // namespace vkloc
