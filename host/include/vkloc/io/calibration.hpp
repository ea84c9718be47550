// vkloc: camera calibration files: vkloc's camera.yaml (model, intrinsics, distortion, mounting
// on the body), plain pinhole intrinsics in YAML or JSON, and the calibration files of other
// tools (Kalibr, EuRoC, OpenCV, ROS, CamOdoCal, COLMAP) read by loadCalibration.
#pragma once

#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Camera of a sequence: projection model, intrinsics, distortion and mounting on the body (IMU).
/// The file form of a LensCamera (lensCamera() / sequenceCamera() convert).
struct SequenceCamera {
  /// "pinhole", "kannala_brandt", "mei" or "double_sphere" (LensModel, lensModelName()).
  std::string model = "pinhole";
  PinholeCamera intrinsics;  ///< fx, fy, cx, cy (pixels), width, height.
  /// Distortion coefficients: pinhole: radial-tangential k1 k2 p1 p2 [k3] (empty = none);
  /// kannala_brandt: k1..k4; mei: k1 k2 p1 p2 (empty = none); double_sphere: none (empty).
  std::vector<double> distortion;
  double xi = 0.0;     ///< mei: mirror parameter (>= 0); double_sphere: xi (-1..1); else 0.
  double alpha = 0.0;  ///< double_sphere: alpha (0..1); else 0.
  /// Half field of view the lens really images, degrees from the optical axis; 0 = the model's
  /// own limit (LensCamera::max_angle_deg).
  double max_angle_deg = 0.0;
  Pose T_body_camera = Pose::Identity();  ///< Camera frame into body (IMU) frame, metres.
};

/// The LensCamera of a SequenceCamera, checked with validateLensCamera. kInvalidArgument naming
/// the field at fault ("model", "distortion", or the parameter as validateLensCamera names it)
/// for an unknown model, a distortion count that does not fit the model, or bad values.
Result<LensCamera> lensCamera(const SequenceCamera& camera);

/// The SequenceCamera of a LensCamera mounted at T_body_camera. Distortion: empty when every
/// coefficient is zero; pinhole: 4 coefficients when k3 is zero, else 5; kannala_brandt, mei: 4.
SequenceCamera sequenceCamera(const LensCamera& camera, const Pose& T_body_camera);

/// Reads a sequence's camera.yaml. kNotFound for a missing file; kMalformedInput naming the file
/// and field for bad content (including parameters validateLensCamera refuses); kUnsupported for
/// an unknown model. Keys: model, fx, fy, cx, cy, width, height, distortion, xi, alpha,
/// max_angle_deg, T_body_camera (only fx..height are required).
Result<SequenceCamera> loadSequenceCamera(const std::string& path);
/// Writes camera.yaml atomically (alpha only for double_sphere, max_angle_deg only when non-zero).
/// kInvalidArgument naming the path and field when the camera does not pass lensCamera().
Status saveSequenceCamera(const SequenceCamera& camera, const std::string& path);

/// Loads a camera from a YAML or JSON file with keys fx, fy, cx, cy, width, height (a
/// `camera.yaml` as written by vkloc, or a flat JSON object). Errors name the file and field.
/// Distortion in the file is ignored; loadCalibration() reads it.
Result<PinholeCamera> loadCamera(const std::string& path);

/// Reads one camera from a calibration file, whichever of these it is (told by its keys and
/// content, never by its name):
///  - vkloc camera.yaml, or flat fx/fy/cx/cy/width/height YAML/JSON (also under `camera:` or
///    `intrinsics:`);
///  - Kalibr camchain.yaml / camchain-imucam.yaml (cam0, cam1, ...: camera_model pinhole, omni
///    (Mei) or ds (double sphere); distortion_model radtan, equidistant or none;
///    T_body_camera = T_cam_imu^-1, or without it cam0 is the body and camN follows the
///    T_cn_cnm1 chain); a Kalibr / EuRoC single-camera sensor.yaml (T_BS = T_body_camera);
///  - OpenCV FileStorage YAML (`%YAML:1.0`, camera_matrix or K, distortion_coefficients or D as
///    !!opencv-matrix; distortion_model / model `fisheye` = Kannala-Brandt) and ROS camera_info
///    YAML (plumb_bob, rational_polynomial with k4..k6 zero, equidistant);
///  - CamOdoCal YAML (model_type MEI, KANNALA_BRANDT, PINHOLE);
///  - COLMAP cameras.txt (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV,
///    OPENCV_FISHEYE, SIMPLE_RADIAL_FISHEYE, RADIAL_FISHEYE, FULL_OPENCV with k4..k6 zero).
///    COLMAP puts the centre of the top-left pixel at (0.5, 0.5), vkloc at (0, 0): cx and cy
///    are read minus 0.5.
/// Pixel conventions of the other formats are OpenCV's, as vkloc's. Formats without a mounting
/// give T_body_camera = identity. `select` picks a camera in files that hold several: a Kalibr
/// name ("cam1") or index ("1"), a COLMAP camera id; empty = the first. In single-camera files
/// it may be empty, "0", "cam0" or the file's camera_name.
/// Errors, one line starting with the path: kNotFound (no file, or no camera `select`, listing
/// the available ones), kMalformedInput ("path: [cam1: ]field 'k': what is wrong": missing or
/// wrong field, wrong number count, non-finite or out-of-range value as validateLensCamera finds
/// it), kUnsupported (unknown format; unknown or unsupported model, naming the supported ones).
/// Never throws.
Result<SequenceCamera> loadCalibration(const std::string& path, const std::string& select = "");

}  // namespace vkloc
