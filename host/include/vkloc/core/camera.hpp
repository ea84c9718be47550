// vkloc: camera models. Standard library only; reading calibration files is io/calibration.hpp.
#pragma once

#include "vkloc/core/status.hpp"

namespace vkloc {

/// Pinhole camera without distortion.
///
/// Pixel convention (OpenCV / Hartley-Zisserman): integer pixel coordinates are pixel centres,
/// the top-left pixel's centre is (0, 0), u grows right, v grows down. A camera-frame point
/// (x right, y down, z forward, metres) projects to u = fx x/z + cx, v = fy y/z + cy.
struct PinholeCamera {
  double fx = 525.0;  ///< Focal length along u, pixels.
  double fy = 525.0;  ///< Focal length along v, pixels (may differ from fx: non-square pixels).
  double cx = 319.5;  ///< Principal point u, pixels.
  double cy = 239.5;  ///< Principal point v, pixels.
  int width = 640;    ///< Image width, pixels.
  int height = 480;   ///< Image height, pixels.
};

/// Checks that focal lengths are within 0.01..1e7 px, the principal point within +-1e6 px and
/// the size within 1..16384. Returns kInvalidArgument naming the bad field otherwise.
Status validateCamera(const PinholeCamera& camera);

/// The same field of view at another width (pixels): focal lengths and principal point scaled
/// in pixel-centre coordinates, height rounded (at least 1).
PinholeCamera scaledCamera(const PinholeCamera& camera, int width);

}  // namespace vkloc
