// vkloc: camera calibration files: vkloc's camera.yaml (model, intrinsics, distortion, mounting
// on the body) and plain pinhole intrinsics in YAML or JSON.
#pragma once

#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Camera of a sequence: projection model, intrinsics, distortion and mounting on the body (IMU).
struct SequenceCamera {
  /// "pinhole" (supported); "mei" and "kannala_brandt" are reserved for fisheye lenses: they are
  /// read and written with their parameters but loaders of images reject them for now.
  std::string model = "pinhole";
  PinholeCamera intrinsics;  ///< fx, fy, cx, cy (pixels), width, height.
  /// Distortion coefficients: pinhole: radial-tangential k1 k2 p1 p2 [k3] (empty = none);
  /// kannala_brandt: k1..k4; mei: k1 k2 p1 p2.
  std::vector<double> distortion;
  double xi = 0.0;                        ///< Mei unified model's mirror parameter (mei only).
  Pose T_body_camera = Pose::Identity();  ///< Camera frame into body (IMU) frame, metres.
};

/// Reads a sequence's camera.yaml. kNotFound for a missing file; kMalformedInput naming the file
/// and field for bad content.
Result<SequenceCamera> loadSequenceCamera(const std::string& path);
Status saveSequenceCamera(const SequenceCamera& camera, const std::string& path);

/// Loads a camera from a YAML or JSON file with keys fx, fy, cx, cy, width, height (a
/// `camera.yaml` as written by vkloc, or a flat JSON object). Errors name the file and field.
Result<PinholeCamera> loadCamera(const std::string& path);

}  // namespace vkloc
