#include "vkloc/core/camera.hpp"

#include <algorithm>
#include <cmath>

#include "vkloc/core/text.hpp"

namespace vkloc {

Status validateCamera(const PinholeCamera& c) {
  auto bad = [](const char* field, double v) {
    return makeError(ErrorCode::kInvalidArgument, text::cat("camera: ", field, " = ", v, " is invalid"));
  };
  // Focal lengths from 0.01 to 1e7 px and principal points within 1e6 px keep every projection
  // term representable in float on the GPU.
  if (!(c.fx >= 0.01 && c.fx <= 1e7)) return bad("fx", c.fx);
  if (!(c.fy >= 0.01 && c.fy <= 1e7)) return bad("fy", c.fy);
  if (!(std::abs(c.cx) <= 1e6)) return bad("cx", c.cx);
  if (!(std::abs(c.cy) <= 1e6)) return bad("cy", c.cy);
  if (c.width < 1 || c.width > 16384) return bad("width", c.width);
  if (c.height < 1 || c.height > 16384) return bad("height", c.height);
  return Status::success();
}

PinholeCamera scaledCamera(const PinholeCamera& camera, int width) {
  const double s = static_cast<double>(width) / camera.width;
  PinholeCamera out;
  out.width = width;
  out.height = std::max(1, static_cast<int>(std::lround(camera.height * s)));
  out.fx = camera.fx * s;
  out.fy = camera.fy * s;
  out.cx = (camera.cx + 0.5) * s - 0.5;
  out.cy = (camera.cy + 0.5) * s - 0.5;
  return out;
}

}  // namespace vkloc
