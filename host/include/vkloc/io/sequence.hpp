// vkloc: image sequences with ground truth, IMU and position priors (the bench's data format;
// importers of other datasets: io/import.hpp).
//
// A sequence is a folder:
//   sequence.yaml     name, model file, T_world_model, unit_scale, initial pose, IMU noise, gravity
//   camera.yaml       camera model, intrinsics, distortion, resolution, T_body_camera
//   images.txt        TUM rgb.txt style: "timestamp_s path" per line, '#' comments
//   groundtruth.txt   TUM trajectory "t tx ty tz qx qy qz qw" of T_world_camera (optional)
//   imu.csv           EuRoC style "t_ns,wx,wy,wz,ax,ay,az", body frame (optional)
//   prior.csv         "t_ns,x,y,z,sigma_x,sigma_y,sigma_z": p_world_body with 1-sigma (optional)
// Timestamps are int64 nanoseconds in memory; text files with seconds keep 9 decimals so that a
// write/read round trip is exact. Every loader rejects malformed lines with a one-line error
// "file:line: what is wrong", non-finite numbers and timestamps that do not increase.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/sensors.hpp"
#include "vkloc/io/calibration.hpp"

namespace vkloc {

/// One camera image: time and file path (relative to the sequence folder, or absolute).
struct ImageEntry {
  int64_t t_ns = 0;
  std::string path;
};

/// A whole sequence in memory. Image pixels are not loaded; see imagePath().
struct Sequence {
  std::string directory;  ///< Folder the sequence was loaded from (relative paths resolve here).
  std::string name;
  /// Model file (relative to `directory` or absolute), or a built-in model name ("city",
  /// "room"); empty when the sequence has no model (e.g. an imported EuRoC folder).
  std::string model;
  Pose T_world_model = Pose::Identity();       ///< Applied to the model when loading it.
  double unit_scale = 1.0;                     ///< Model units to metres.
  std::optional<Pose> initial_T_world_camera;  ///< Pose at the first image when known.
  /// Velocity of the camera at the first image (world frame, m/s) when known: a sequence that
  /// starts in motion is then tracked from its first frame without waiting for the filter.
  std::optional<Eigen::Vector3d> initial_velocity_world;
  Eigen::Vector3d gravity_world{0.0, 0.0, -9.81};  ///< m/s^2.
  SequenceCamera camera;
  std::vector<ImageEntry> images;
  std::vector<StampedPose> groundtruth;  ///< Empty when not known.
  std::vector<ImuSample> imu;            ///< Empty when no IMU.
  std::optional<ImuNoise> imu_noise;     ///< Noise parameters of `imu` when known.
  std::vector<PositionPrior> priors;     ///< Empty when no priors.

  /// Path of image i resolved against `directory`. Precondition: i < images.size().
  std::string imagePath(size_t i) const;
  /// Model path resolved against `directory` (built-in names and "" are returned unchanged).
  std::string modelPath() const;
};

/// Loads a sequence folder. kNotFound when the folder, sequence.yaml, camera.yaml or images.txt
/// is missing; kMalformedInput ("file:line: ...") for bad content. Optional files may be absent.
Result<Sequence> loadSequence(const std::string& directory);

/// Writes sequence.yaml, camera.yaml, images.txt and, when non-empty, groundtruth.txt, imu.csv
/// and prior.csv into `directory` (created if needed). Each file is written atomically
/// (temporary + rename); an optional file left from an earlier save is removed when its data is
/// now empty, so that loading gives back `sequence`. sequence.yaml is removed first and written
/// last: a save that stops part way leaves a folder that does not load, never a mix of old and
/// new files. Image files are the caller's.
/// kInvalidArgument (before anything is written) for non-finite values, invalid poses or camera,
/// sigma <= 0, image paths with line breaks or surrounding spaces, or timestamps that do not
/// increase.
Status saveSequence(const Sequence& sequence, const std::string& directory);

/// TUM trajectory: "t tx ty tz qx qy qz qw" per line (t in seconds), '#' comments, blank lines
/// ignored. Quaternions are normalised; |1 - |q|| > 1e-3 is rejected. Times must increase.
Result<std::vector<StampedPose>> loadTumTrajectory(const std::string& path);
Status saveTumTrajectory(const std::vector<StampedPose>& poses, const std::string& path);

/// images.txt: "t_s path" per line (TUM rgb.txt).
Result<std::vector<ImageEntry>> loadImageList(const std::string& path);
Status saveImageList(const std::vector<ImageEntry>& images, const std::string& path);

/// imu.csv (EuRoC: t_ns, w_RS_S_x/y/z rad/s, a_RS_S_x/y/z m/s^2; header line optional).
Result<std::vector<ImuSample>> loadImuCsv(const std::string& path);
Status saveImuCsv(const std::vector<ImuSample>& samples, const std::string& path);

/// prior.csv: t_ns,x,y,z,sigma_x,sigma_y,sigma_z (metres; header line optional).
Result<std::vector<PositionPrior>> loadPriorCsv(const std::string& path);
Status savePriorCsv(const std::vector<PositionPrior>& priors, const std::string& path);

}  // namespace vkloc
