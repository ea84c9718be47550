// vkloc: the clock every timing figure (render_ms, align_ms, total_ms, ...) is read from.
#pragma once

#include <chrono>

namespace vkloc {

/// Monotonic; wall-clock jumps do not change measured durations.
using SteadyClock = std::chrono::steady_clock;

/// Milliseconds elapsed since `t0`.
inline double msSince(SteadyClock::time_point t0) {
  return std::chrono::duration<double, std::milli>(SteadyClock::now() - t0).count();
}

}  // namespace vkloc
