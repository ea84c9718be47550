// vkloc: importers that turn other datasets into vkloc sequences: TUM RGB-D, EuRoC ASL and ViSP
// model-based tracking folders (e.g. visp-images-data's mbt-depth/Castle-simu). Part of the
// bench (vkloc::bench), not of the library an integrator links.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/io/sequence.hpp"

namespace vkloc {

/// Converts a TUM RGB-D folder (rgb.txt, groundtruth.txt, accelerometer.txt ignored) into a
/// Sequence referencing the original images by absolute path. The camera is taken from
/// `camera_override` when given, else from the folder name (freiburg1/2/3 calibrations).
/// `model` is stored as given; `directory` is left empty (image paths are absolute).
/// initial_T_world_camera is the ground truth interpolated at the first image when it brackets
/// it. kNotFound when the folder or rgb.txt is missing. Does not write anything.
Result<Sequence> importTumRgbd(const std::string& tum_directory, const std::optional<SequenceCamera>& camera_override,
                               const std::string& model = "");

/// Converts a EuRoC ASL folder (mav0/cam0 sensor.yaml + data.csv, mav0/imu0/data.csv,
/// mav0/state_groundtruth_estimate0/data.csv when present) into a Sequence. Ground truth is
/// converted from T_world_body to T_world_camera with the camera's T_body_camera (T_BS);
/// mav0/imu0/sensor.yaml, when present, gives imu_noise. `euroc_directory` may also be the mav0
/// folder itself. The camera keeps its calibration: Kalibr camera_model pinhole (radtan:
/// pinhole; equidistant: kannala_brandt), omni (mei) or ds (double_sphere), as loadCalibration.
/// kNotFound when cam0/sensor.yaml or cam0/data.csv is missing; kUnsupported for other camera or
/// distortion models.
Result<Sequence> importEuroc(const std::string& euroc_directory, const std::string& model = "");

/// Reads a ViSP pose file: a 4x4 homogeneous matrix as 16 numbers (row-major, e.g. the
/// Camera_NNN.txt files holding cMo = T_camera_object, metres). The rotation must be orthonormal
/// to 1e-4 (it is then re-orthonormalised) and the last row 0 0 0 1. kNotFound / kMalformedInput
/// with the file name otherwise.
Result<Pose> loadVispPose(const std::string& path);

/// Reads pinhole intrinsics px, py, u0, v0 from a ViSP camera XML (vpXmlParserCamera, preferring
/// the model of type perspectiveProjWithoutDistortion) or a model-based tracker config XML
/// (<camera><px>..). u = u0 + px x/z, v = v0 + py y/z. `width` / `height` (pixels) give the
/// image size; when <= 0 they are read from <image_width> / <image_height>. Errors name the file
/// and the missing or bad tag.
Result<PinholeCamera> loadVispCameraXml(const std::string& path, int width = 0, int height = 0);

/// How a ViSP image folder is converted.
struct VispImportOptions {
  /// Add Models/cube.cao to the model, placed with T_object_cube (visp-images-data's
  /// Castle-simu scene contains this cube; ViSP's depth-tracker test loads it with this pose).
  bool include_cube = true;
  /// Cube frame into the object (world) frame, metres.
  Pose T_object_cube = defaultCastleCubePose();
  /// Timestamp of image number n (Image_NNNN): (n - first) / frame_rate_hz seconds.
  double frame_rate_hz = 30.0;
  /// Name of the written model file inside the output folder (.obj keeps the gray material).
  std::string model_file = "model.obj";

  /// [[-1,0,0,-0.2],[0,0,1,0.12],[0,1,0,-0.15]]: the cube's pose in the castle scene.
  static Pose defaultCastleCubePose();
};

/// What importVispSequence wrote.
struct VispImportReport {
  size_t frames = 0;          ///< Images written.
  size_t poses = 0;           ///< Ground-truth poses written.
  size_t triangles = 0;       ///< Model triangles.
  size_t cube_triangles = 0;  ///< Of which from the cube.
  std::string model_path;     ///< Model file written.
  std::vector<std::string> warnings;
};

/// Converts a ViSP mbt folder laid out as Castle-simu (Images/Image_NNNN.pgm or .png,
/// CameraPose/Camera_NNN.txt, Config/<one>.xml with the intrinsics, Models/<one>.cao other than
/// cube.cao, optional Models/cube.cao) into a vkloc sequence in `out_dir`: the images are
/// converted to PNG under images/, the model (castle plus cube) is written as
/// options.model_file, and ground truth T_world_camera = inverse(cMo) with world = the model's
/// object frame. Gravity is -y in that frame (the castle's up axis is +y). Errors (one line,
/// naming the file): kNotFound for a missing folder/file, kMalformedInput for bad content.
Result<Sequence> importVispSequence(const std::string& folder, const std::string& out_dir,
                                    const VispImportOptions& options = {}, VispImportReport* report = nullptr);

}  // namespace vkloc
