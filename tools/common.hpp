// Shared pieces of the vkloc command-line verbs.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/engine/gpu.hpp"
#include "vkloc/io/calibration.hpp"
#include "vkloc/localize/keyframe_database.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {
struct Sequence;
}
namespace vkloc::cli {

/// Thrown inside a verb to stop with a one-line message and exit code 1.
struct Failure {
  std::string message;
};

/// Unwraps a Result or throws Failure with its message.
template <typename T>
T take(Result<T> r) {
  if (!r.ok()) throw Failure{r.error().message};
  return std::move(r).value();
}
inline void check(const Status& s) {
  if (!s.ok()) throw Failure{s.error().message};
}

/// Model options shared by verbs that load a model.
struct ModelArgs {
  std::string model = "city";  ///< File path, or a built-in name: city, room.
  double unit_scale = 1.0;
  std::string T_world_model;  ///< "" or 7/16 numbers.
  uint32_t block_triangles = 32768;
  void add(CLI::App& app);
  /// Loads the model (or builds the demo); prints warnings to stderr.
  Model load() const;
};

/// Camera options: a calibration file (loadCalibration: vkloc, Kalibr, EuRoC, OpenCV, ROS,
/// CamOdoCal, COLMAP), or inline intrinsics, or the default 640x480.
struct CameraArgs {
  std::string file;
  std::string select;      ///< --camera-name: camera of a multi-camera file, by name or index.
  std::string intrinsics;  ///< "fx,fy,cx,cy,width,height"
  void add(CLI::App& app);
  /// A pinhole camera; a lens with distortion is refused (verbs that render take only those).
  PinholeCamera get() const;
  /// The whole calibration (lens model and mounting) from --camera, else `fallback` with
  /// --intrinsics when given.
  SequenceCamera getFull(const SequenceCamera& fallback) const;
  bool given() const { return !file.empty() || !intrinsics.empty(); }
};

/// How a lens image becomes the tracker's pinhole view (CameraFront): --view, --view-size,
/// --view-hfov, --view-pitch.
struct ViewArgs {
  std::string view = "undistorted";
  std::string size;     ///< "WxH"; empty: the lens image's.
  double hfov_deg = 0;  ///< 0: a pinhole lens keeps its intrinsics, another gets 90.
  double pitch_deg = 45;
  double dead_band_deg = ViewOptions{}.dead_band_deg;
  double flat_field_sigma_px = 0;  ///< ViewOptions::flat_field_sigma_px.
  std::string interpolation = "bicubic";
  void add(CLI::App& app);
  /// The options for a sequence (its gravity gives the world's up).
  ViewOptions options(const Sequence& seq) const;
};

/// The tracker's camera for a sequence's lens: the view's intrinsics, and the camera front that
/// makes the view (null for an ideal pinhole lens seen as it is).
struct SequenceView {
  PinholeCamera camera;
  std::unique_ptr<CameraFront> front;
};
SequenceView sequenceView(const SequenceCamera& camera, const ViewOptions& options);

/// Where and how the Localizer runs: --backend, --policy, --keyframes (vkloc track, vkloc demo).
struct LocalizerArgs {
  std::string backend = "auto";
  std::string policy = "when-needed";
  std::string keyframes = "worker";
  std::string filter = "ekf";  ///< Inertial fusion: ekf | window.
  int max_search_level = LocalizerOptions{}.max_search_level;
  double visual_covariance_scale = InertialAiding{}.ekf.measurement_covariance_scale;
  std::string frame_pose = "filter";      ///< Tracked frames' pose: filter (the EKF's posterior) | visual.
  std::string rotation_prior = "filter";  ///< Attitude prior of the alignment: filter | off.
  double rotation_prior_scale = 1.0;      ///< Factor on that prior's covariance.
  std::string local_search = "on";        ///< Without a database, search keyframes rendered after a loss.
  /// Keyframes' texture-edge floor, gray levels per pixel (ReferenceEdgeOptions::detector's min_high_gradient).
  double keyframe_edge_floor = keyframeDetector().min_high_gradient;
  void add(CLI::App& app);
  /// Sets the options' backend, policy, keyframe threading, filter, search and keyframe edge floor; throws Failure
  /// on a bad value.
  void apply(LocalizerOptions& options) const;
  /// The same as command-line arguments (to hand on to `vkloc track`).
  std::vector<std::string> arguments() const;
};

/// Device options.
struct DeviceArgs {
  std::string device;
  void add(CLI::App& app);
  std::shared_ptr<GpuContext> create() const;
};

/// True when the name is a built-in demo model.
bool isDemoModel(const std::string& name);

/// Writes rgba.png, gray.png, depth_mm.png, depth.tiff (and normals.png) for one render,
/// named with `stem` in `dir`. Returns the paths written.
std::vector<std::string> writeRender(const std::string& dir, const std::string& stem, const RenderOutput& out);

/// The sequence's model (file, or built-in demo placed by T_world_model); throws Failure.
Model loadSequenceModel(const Sequence& seq);
/// The sequence's camera when it is an ideal pinhole; throws Failure naming `vkloc track --view`
/// for another lens.
PinholeCamera sequenceCamera(const Sequence& seq);
/// The sequence's initial pose (sequence.yaml, else ground truth at the first image; with
/// start_frame > 0 the ground truth at that image), moved by `offset` = "dx,dy,dz,rx,ry,rz"
/// (metres along world axes, degrees about camera axes; "" = none); throws Failure.
Pose initialPose(const Sequence& seq, const std::string& offset, size_t start_frame = 0);
/// The pose initialPose() starts from, before any offset: sequence.yaml's, else the ground
/// truth's within 10 ms of the first image; with start_frame > 0 the ground truth's within 1 ms
/// of that image. nullopt where there is none.
std::optional<Pose> sequenceStartPose(const Sequence& seq, size_t start_frame = 0);
/// Inertial aiding from the sequence: on when it has IMU readings and `use_imu`, with its camera
/// mounting and gravity.
void setSequenceInertial(const Sequence& seq, bool use_imu, LocalizerOptions& options);
/// Gives the localizer the sequence's IMU readings from index `next` up to and including
/// t_ns; returns the index of the first reading not given. A bad reading is skipped with a
/// warning on stderr (the others are kept).
size_t feedSequenceImu(const Sequence& seq, size_t next, int64_t t_ns, Localizer& localizer);
/// The region a GPS-like prior at `center_world` with 1-sigma `sigma_m` (per axis, metres) is
/// searched in: 3.37 sigma (99 % of a 3-D Gaussian), at least `min_radius_m`.
SearchRegion priorSearchRegion(const Eigen::Vector3d& center_world, double sigma_m, double min_radius_m);
/// Runs `vkloc track` with these arguments (used by `vkloc demo`); throws Failure on errors.
void runTrackArguments(const std::vector<std::string>& arguments);

/// A verb of the command line: `add` creates its subcommand on the app. Each tools/cmd_*.cpp
/// registers its verbs with VKLOC_REGISTER_VERB; main() adds them ordered by `order`, so adding a
/// verb is adding a file.
struct Verb {
  int order = 0;  ///< Position in `vkloc --help` (lower first).
  void (*add)(CLI::App& app) = nullptr;
};
/// Every registered verb (filled by static registration before main runs).
std::vector<Verb>& verbRegistry();
struct VerbRegistration {
  VerbRegistration(int order, void (*add)(CLI::App& app)) { verbRegistry().push_back(Verb{order, add}); }
};
#define VKLOC_REGISTER_VERB(order, add_function) \
  static const ::vkloc::cli::VerbRegistration vkloc_verb_registration_##add_function { order, add_function }

/// Ground truth at t_ns: interpolated (linear position, slerp rotation) between two samples at
/// most 50 ms apart, else the nearest sample within 10 ms (the evaluation's defaults).
std::optional<Pose> groundTruthAt(const std::vector<StampedPose>& gt, int64_t t_ns);

/// Adds `vkloc bench verify` (cmd_bench_verify.cpp) to the bench verb.
void addVerifyBench(CLI::App& bench);
/// Adds `vkloc bench reloc` (cmd_bench_reloc.cpp) to the bench verb.
void addRelocBench(CLI::App& bench);
/// Adds `vkloc bench remap` (cmd_bench_remap.cpp) to the bench verb.
void addRemapBench(CLI::App& bench);

}  // namespace vkloc::cli
