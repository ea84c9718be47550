// vkloc: the camera front: turns the lens image into the pinhole view the tracker works in
// (seed paper 000 sec. IV-B, eq. 8). Either an undistorted view fixed to the lens, or an
// electronically stabilised view (EIS) whose optical axis keeps a chosen angle below the horizon
// with roll and pitch compensated from the camera's attitude each frame beyond a dead band (inside
// it the view is the lens's own); its heading follows the camera's. The view shares the lens's optical centre:
// T_camera_view is a pure rotation.
//
// Frames: camera = the physical lens (x right, y down, z forward); view = the virtual pinhole
// camera; world as the model's, `up_world` against gravity.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/remap.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

enum class ViewKind {
  kUndistorted,  ///< Fixed to the lens, optical axes aligned (a pinhole lens: its own intrinsics).
  kStabilised,   ///< EIS: axis at pitch_deg below the horizon (within dead_band_deg), no roll, heading of the camera.
};
/// "undistorted", "stabilised".
const char* viewKindName(ViewKind kind);
Result<ViewKind> parseViewKind(const std::string& name);

struct ViewOptions {
  ViewKind kind = ViewKind::kUndistorted;
  /// Bicubic keeps edges sharper: measured on lenses applied to the development sequences, the
  /// tracking error grows less than with bilinear (README, "Lenses: undistorted and stabilised views").
  RemapInterpolation interpolation = RemapInterpolation::kBicubic;
  /// View size, pixels; 0: the lens image's size.
  int width = 0;
  int height = 0;
  /// Horizontal field of view of the view, degrees (1..170); 0: a pinhole lens (distorted or
  /// not) keeps its own focal lengths (an undistorted view of its size keeps its principal point
  /// too, a smaller one is the central crop of it), any other lens gets 90.
  double hfov_deg = 0;
  /// kStabilised: angle of the view's optical axis below the horizon, degrees (-89..90; 90 = down).
  double pitch_deg = 0;
  /// kStabilised: dead band, degrees (0..90; 0 = every frame fully compensated). The view stays
  /// fixed to the lens (looking along the lens's axis, principal point at the view's centre)
  /// while the compensating rotation (from the lens to the stabilised direction at pitch_deg, no
  /// roll) is at most this angle, and beyond it turns by only the excess about the same axis:
  /// the view's axis stays within the band of the stabilised direction. A lens mounted at
  /// pitch_deg on an airframe that tilts less than the band sees through its own centre.
  /// A view held still in the world holds the edge alignment's valley (a turn about the view's
  /// vertical axis traded for a shift across it) still in the world, where the filter cannot
  /// tell the two apart; a view that turns with the airframe, whose turns the gyro measures, sees
  /// that valley from changing directions (README, "Lenses: undistorted and stabilised views").
  double dead_band_deg = 25;
  /// kStabilised: world direction against gravity (normalized on use).
  Eigen::Vector3d up_world{0, 0, 1};
  /// kStabilised: the remap table is computed exactly every grid_step_px view pixels and
  /// bilinearly in between (1 = every pixel; 1..32).
  int grid_step_px = 8;
  /// Flat field: the view divided by its local mean brightness (a Gaussian of this sigma, view
  /// pixels, over the pixels that have a source) and multiplied by the image's mean, so that a
  /// smooth falloff of brightness (a lens's vignetting, seen off its axis by a stabilised view,
  /// a darker side of the scene) does not push one part's edges below the edge detector's
  /// thresholds, which are quantiles of the whole image. 0 = off (0..1e4).
  double flat_field_sigma_px = 0;
};

/// Lens image -> view image. Not thread-safe (it caches two tables: the lens's own view, a turned one).
class CameraFront {
 public:
  /// kInvalidArgument for an invalid lens (validateLensCamera) or options out of range, or a
  /// view of which less than half has a source in the lens's valid field.
  static Result<std::unique_ptr<CameraFront>> create(const LensCamera& lens, const ViewOptions& options);

  const LensCamera& lens() const { return lens_; }
  const PinholeCamera& view() const { return view_; }
  const ViewOptions& options() const { return options_; }
  /// True when the view needs no remap at all (an ideal pinhole lens, kUndistorted, own size,
  /// no flat field).
  bool identity() const { return same_pixels_ && options_.flat_field_sigma_px == 0; }
  /// True when the view's pixels are resampled from the lens image (false: they are its own,
  /// perhaps flat-fielded): a device remapper is worth making only then.
  bool needsRemap() const { return !same_pixels_; }

  /// R_camera_view for a camera at attitude R_world_camera: identity for kUndistorted.
  Eigen::Matrix3d viewRotation(const Eigen::Matrix3d& R_world_camera) const;
  /// T_camera_view (rotation only) for a camera at T_world_camera.
  Pose viewExtrinsic(const Pose& T_world_camera) const;

  /// Exact remap table of the view turned by R_camera_view (every pixel projected).
  RemapTable exactTable(const Eigen::Matrix3d& R_camera_view) const;
  /// The table in use for R_camera_view: the view fixed to the lens (kUndistorted, or a
  /// stabilised view's identity rotation, which its dead band gives) exact, built once and kept;
  /// any other rotation built on the grid (grid_step_px) and interpolated, kept until the next.
  const RemapTable& table(const Eigen::Matrix3d& R_camera_view);

  /// The view image seen by the lens image `lens_image` (1 channel, the lens's size) through
  /// table(R_camera_view) with the options' interpolation on the CPU (bilinear: OpenCV's remap;
  /// bicubic: remapBicubicFixedRows on OpenCV's threads; both with positions in 1/32 px, and
  /// remapBilinear / remapBicubic their references), or on the device remapper when given.
  /// kInvalidArgument for an image of another size or channel count.
  Status remap(const ImageU8& lens_image, const Eigen::Matrix3d& R_camera_view, ImageU8& view_image);

  /// Remaps on a device from now on (null: on the CPU again), e.g. Accelerator::createRemapper
  /// of the first table. The device's errors come back from remap().
  void setRemapper(std::unique_ptr<ImageRemapper> remapper);
  /// "OpenCV remap (CPU)", "fixed-point bicubic remap (CPU)" or the device remapper's description.
  std::string remapDescription() const;

  /// Fraction of the last table's pixels that have a source (0..1).
  double validFraction() const { return current().valid_fraction; }

  ~CameraFront();

 private:
  CameraFront() = default;
  void fillGrid(const Eigen::Matrix3d& R_camera_view, int step, RemapTable& table) const;
  bool sourceOf(const Eigen::Matrix3d& R_camera_view, double u, double v, float& su, float& sv) const;
  void flatten(ImageU8& view_image) const;  ///< ViewOptions::flat_field_sigma_px, in place.
  /// remap() without the size check and the flat field.
  Status resample(const ImageU8& lens_image, const Eigen::Matrix3d& R_camera_view, ImageU8& view_image);

  struct Maps;
  /// One remap table with what is derived from it (none built yet while the table is empty).
  struct Slot {
    RemapTable table;
    Eigen::Matrix3d R_camera_view = Eigen::Matrix3d::Zero();
    double valid_fraction = 0;
    std::vector<uint32_t> no_source;  ///< View pixels without a source.
    std::unique_ptr<Maps> maps;       ///< OpenCV's fixed-point form of a cached table (bilinear).
  };
  void buildMaps(Slot& slot);  ///< slot.maps from slot.table (a cached table OpenCV remaps bilinearly).
  const Slot& current() const { return slots_[current_]; }

  LensCamera lens_;
  PinholeCamera view_;
  ViewOptions options_;
  Eigen::Vector3d up_world_{0, 0, 1};
  bool same_pixels_ = false;  ///< The view's pixels are the lens image's (a flat field may follow).
  /// kFixedSlot: the view fixed to the lens (kUndistorted, or a stabilised view inside its dead
  /// band), exact and kept; kTurnedSlot: a stabilised view turned from it, on the grid.
  static constexpr int kFixedSlot = 0;
  static constexpr int kTurnedSlot = 1;
  Slot slots_[2];
  int current_ = kFixedSlot;
  std::unique_ptr<ImageRemapper> remapper_;
  bool remapper_stale_ = true;  ///< The device holds another table than the current one.
};

}  // namespace vkloc
