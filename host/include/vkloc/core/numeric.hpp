// vkloc: small numeric checks shared by the option validators.
#pragma once

#include <cmath>

namespace vkloc {

/// True when `v` is finite and lo <= v <= hi (a NaN is never in range).
inline bool finiteIn(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

}  // namespace vkloc
