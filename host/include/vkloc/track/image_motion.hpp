// vkloc: image motion between two consecutive frames, for a start in motion: with the rotation
// from the gyro, what is left of the motion between two frames is mostly a shift of the image
// (translation across the view at the scene depth). Phase correlation (Kuglin, Hines 1975) of the
// previous image, turned into the current view by the infinite homography K R K^-1, and the
// current one gives that shift without knowing the velocity.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Shift of the current image against the previous one, full-resolution pixels: a scene point
/// seen at p in the previous image (after the rotation) is seen near p + (dx, dy) in the current.
struct ImageShift {
  double dx_px = 0;
  double dy_px = 0;
  /// Phase correlation peak (0..1): near 1 for a clean shift, near 0 when the images do not
  /// agree (no texture, mostly new content, motion along the view).
  double response = 0;
};

/// Estimates the shifts between `previous` and `current` (8-bit gray, the camera's size), both
/// taken with `camera`, after turning the previous view by R_current_previous (rotation from the
/// previous camera frame to the current one; only rotation, so exact for distant points): up to
/// max_peaks peaks of the phase correlation, highest response first (parts of the view at other
/// depths shift differently: each gives a peak). Runs at 1/2^level of the resolution, high-passed
/// and with a Hann window. kInvalidArgument for wrong sizes, a non-finite rotation or a level that
/// leaves fewer than 16x16 pixels. Images without texture give peaks of low response (never NaN).
Result<std::vector<ImageShift>> estimateImageShifts(const ImageU8& previous, const ImageU8& current,
                                                    const PinholeCamera& camera,
                                                    const Eigen::Matrix3d& R_current_previous, int level = 2,
                                                    int max_peaks = 3);

}  // namespace vkloc
