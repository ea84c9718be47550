// vkloc: the keyframe database of relocalization and global initialization (STAR, seed paper 001
// sec. II-D): virtual cameras placed on a grid in the model's free space, each rendered once
// offline and compressed to one 256-bit ORB descriptor of the whole view downsampled to 80x64,
// with its pose. Online, the descriptor of the live image ranks the keyframes of a search region
// by Hamming distance; the Localizer aligns from the best and keeps a verified pose.
//
// Frames and units: poses are T_world_camera (camera to world, metres; camera x right, y down,
// z forward); positions and radii metres, angles degrees.
//
// File format (little-endian, version 1; the README's "Keyframe database" section):
//   magic "VKLOCKDB" (8 bytes), u32 version, u32 flags (0), u64 model fingerprint,
//   camera: u32 width, u32 height, f64 fx, fy, cx, cy (the camera the views were made for),
//   u64 keyframe count N, then N records of 76 bytes:
//     f64 position x, y, z (world, m); f32 quaternion x, y, z, w (R_world_camera);
//     f32 median scene depth (m); u64 descriptor[4],
//   then a u64 FNV-1a checksum of every byte before it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/renderer.hpp"

namespace vkloc {

/// 256-bit binary descriptor of a whole view (one ORB descriptor of the 80x64 thumbnail).
using GlobalDescriptor = std::array<uint64_t, 4>;

/// Size of the thumbnail a view is reduced to before its descriptor is computed (STAR's).
constexpr int kThumbnailWidth = 80;
constexpr int kThumbnailHeight = 64;

/// The thumbnail of an 8-bit gray image (any size >= 80x64): area-averaged to 80x64.
/// kInvalidArgument for a smaller or non-gray image.
Result<ImageU8> descriptorThumbnail(const ImageU8& gray);

/// One ORB descriptor (OpenCV, 63-pixel patch, no orientation: the views are upright) of the
/// whole view's 80x64 gradient-magnitude thumbnail, about its centre (edges survive the change
/// from a model's textures to a camera's image better than gray levels). kInvalidArgument as
/// descriptorThumbnail.
Result<GlobalDescriptor> globalDescriptor(const ImageU8& gray);

/// Standard deviation of the thumbnail's gray levels (0..127.5): a view with (almost) nothing in
/// it (black, saturated, a blank wall) has too little to be recognised or aligned.
double thumbnailContrast(const ImageU8& thumbnail);

/// Bits that differ, 0..256.
int hammingDistance(const GlobalDescriptor& a, const GlobalDescriptor& b);

/// 64-bit FNV-1a of the model's vertex positions and triangle indices: a database is used only
/// with the model (placed in the world as) it was built for.
uint64_t modelFingerprint(const Model& model);

/// One keyframe of the database.
struct DatabaseKeyframe {
  Pose T_world_camera = Pose::Identity();  ///< Pose of the virtual camera.
  float scene_depth_m = 0;                 ///< Median depth of its render, metres.
  GlobalDescriptor descriptor{};
};

/// A sphere of positions to search (world frame): relocalization's region after a loss, a
/// GPS-like prior's. An infinite radius searches everywhere.
struct SearchRegion {
  Eigen::Vector3d center_world = Eigen::Vector3d::Zero();
  double radius_m = 0;
};

/// A keyframe ranked for a query.
struct KeyframeCandidate {
  size_t index = 0;  ///< Into KeyframeDatabase::keyframes().
  int distance = 0;  ///< Hamming distance of its descriptor to the query's, bits.
};

/// The database: keyframes, the camera they were rendered with and the model's fingerprint.
/// Immutable once built or loaded; const members may be called from any thread.
class KeyframeDatabase {
 public:
  static constexpr uint32_t kVersion = 1;

  KeyframeDatabase() = default;
  KeyframeDatabase(uint64_t model_fingerprint, const PinholeCamera& camera)
      : fingerprint_(model_fingerprint), camera_(camera) {}

  void add(const DatabaseKeyframe& keyframe);
  const std::vector<DatabaseKeyframe>& keyframes() const { return keyframes_; }
  size_t size() const { return keyframes_.size(); }
  uint64_t modelFingerprint() const { return fingerprint_; }
  const PinholeCamera& camera() const { return camera_; }

  /// The `k` keyframes nearest to `descriptor` in Hamming distance, nearest first (ties by
  /// index), among those whose position lies in `region` (all when nullopt).
  std::vector<KeyframeCandidate> query(const GlobalDescriptor& descriptor, size_t k,
                                       const std::optional<SearchRegion>& region = std::nullopt) const;

  /// How far a camera inside the grid of positions can be from the nearest one, metres: half the
  /// diagonal of a grid cell whose side is the median distance from a position to its nearest
  /// other one (estimated on up to 256 positions; 0 with fewer than two positions). A search
  /// region grown by it holds the keyframes nearest a camera at its border.
  double positionReach() const;
  /// The box of the keyframes' positions (world, metres): min and max corners; min > max (both
  /// infinite) for an empty database. Built over a navigable volume, it bounds where a camera
  /// can be (RelocalizationOptions::inside_database_box).
  std::pair<Eigen::Vector3d, Eigen::Vector3d> positionBounds() const;

  /// Writes the file format above atomically. I/O errors as kIoError naming the path.
  Status save(const std::string& path) const;
  /// Reads a database. kNotFound / kIoError for a file that cannot be read; kMalformedInput
  /// naming the path for a file that is not a database, a truncated or damaged one (size,
  /// checksum, non-finite poses); kUnsupported for a version this build does not read;
  /// kInvalidArgument when `expected_fingerprint` is given and the database was built for
  /// another model.
  static Result<KeyframeDatabase> load(const std::string& path,
                                       std::optional<uint64_t> expected_fingerprint = std::nullopt);
  /// Bytes one keyframe takes in the file.
  static constexpr size_t kRecordBytes = 3 * 8 + 4 * 4 + 4 + 4 * 8;

 private:
  uint64_t fingerprint_ = 0;
  PinholeCamera camera_;
  std::vector<DatabaseKeyframe> keyframes_;
  std::vector<double> positions_;  ///< x, y, z per keyframe (the region test of query()).
};

/// Where the virtual cameras go: positions on a grid in a box of navigable space, several
/// headings and tilts at each.
struct KeyframePlacement {
  Aabb volume;                        ///< World frame, metres: the box the positions fill.
  double spacing_m = 1.0;             ///< Grid spacing, metres (> 0); the grid is centred in the box.
  Eigen::Vector3d up_world{0, 0, 1};  ///< Against gravity.
  int headings = 12;                  ///< Headings per position, 360 / headings apart (1..360).
  /// Tilts of the optical axis below the horizon, degrees (positive looks down), each at every
  /// heading: a drone's downward views, a person's near-level ones.
  std::vector<double> tilts_deg{0.0};
  /// Views whose nearest surface is closer than this (metres) are left out: a camera inside a
  /// wall or against it.
  double min_clearance_m = 0.3;
  /// Views of which more than this fraction of pixels see the back of a face are left out: a
  /// camera inside closed geometry (needs consistently wound faces; 1 = no test).
  double max_back_face_fraction = 0.05;
  /// Views with less than this fraction of pixels on the model are left out (sky, the void).
  double min_model_fraction = 0.2;
  /// Views whose thumbnail's contrast (thumbnailContrast) is below this are left out.
  double min_contrast = 3.0;
  size_t max_views = 5'000'000;  ///< More views than this is an error (a spacing too fine).
  /// A flight corridor: when not empty, only the grid positions within corridor_radius_m of this
  /// polyline (world frame, metres; a planned path) are used, not the whole box: a path's tube
  /// takes a grid a few times finer for the same number of views.
  std::vector<Eigen::Vector3d> corridor;
  double corridor_radius_m = 0;  ///< Metres (> 0 with a corridor).
};

/// The camera a keyframe database's views are rendered with: `camera` scaled to 160 pixels wide
/// (twice the descriptor's thumbnail, which averages the render's aliasing away as optics do),
/// wider for a camera wider than 2.5:1 so that the view is at least 128 rows high.
PinholeCamera keyframeViewCamera(const PinholeCamera& camera);

/// Checks the placement: a non-empty finite volume, spacing > 0, a unit-able up vector, headings
/// in 1..360, tilts in -90..90, fractions in 0..1, a finite corridor with a radius > 0 and the
/// view count at most max_views.
Status validateKeyframePlacement(const KeyframePlacement& placement);

/// Views of the placement's whole box at its spacing (grid positions x headings x tilts; a
/// corridor's are fewer), as a double: a spacing far too fine counts beyond any integer. No checks.
double placementBoxViews(const KeyframePlacement& placement);

/// The placement's camera positions (world frame, metres): the grid points of the box, centred in
/// it, spacing_m apart; with a corridor, only those within its radius of the polyline (followed
/// through its points a quarter spacing apart, so a position within a quarter spacing of the
/// radius may go either way). The order is fixed (x slowest, z fastest). Errors:
/// kInvalidArgument for a placement validateKeyframePlacement refuses.
Result<std::vector<Eigen::Vector3d>> placementPositions(const KeyframePlacement& placement);

/// The depths of a render's pixels that see the model (> 0, metres) into `depths` (cleared first);
/// returns the nearest of them (infinity when none).
float surfaceDepths(const ImageF32& depth, std::vector<float>& depths);

/// Typical depth of the scene seen from `views` (world-frame camera poses), metres: the median,
/// over the views that see the model on at least `min_model_fraction` of their pixels and whose
/// nearest surface is at least `min_clearance_m` away (a view inside a wall does not count), of
/// each view's median depth, rendered at keyframeViewCamera(camera) (as a database's views are).
/// 0 when no view counts. Errors: kInvalidArgument for a bad camera, fraction or clearance, the
/// renderer's as they come.
Result<double> typicalSceneDepth(Renderer& renderer, const PinholeCamera& camera, const std::vector<Pose>& views,
                                 double min_model_fraction = KeyframePlacement{}.min_model_fraction,
                                 double min_clearance_m = 0.0);

/// Grid spacing of a database for a scene of typical depth `depth_m` (typicalSceneDepth): this
/// fraction of it. Relocalization aligns from the nearest keyframes, and how far a keyframe may
/// be from the camera scales with the depth (the development room, 1.66 m deep: 95 % of STAR's
/// queries recovered at 0.2 m, 75 % at 1 m; the city, 27 m deep: 99 % at 4 m and at 3.24 m).
inline constexpr double kSpacingDepthFraction = 0.12;

/// What a build did.
struct KeyframeBuildStats {
  size_t positions = 0;  ///< Grid positions.
  size_t views = 0;      ///< Views rendered (positions x headings x tilts).
  size_t kept = 0;       ///< Keyframes in the database.
  size_t too_close = 0;  ///< Left out: a surface nearer than min_clearance_m.
  size_t inside = 0;     ///< Left out: back faces seen (inside geometry).
  size_t empty = 0;      ///< Left out: too little of the model or no contrast.
  double seconds = 0;    ///< Wall time of the build.
};

/// Renders every view of the placement at a reduced copy of `camera` (same field of view, 160
/// pixels wide), keeps those in free space and returns the database. One thread per renderer
/// (each made for `model`, used by its thread alone); the result does not depend on their
/// number. `progress(done, total)` is called now and then from the calling thread (may be
/// empty). Errors: kInvalidArgument for a bad camera or placement or no renderer; the first
/// renderer error as it comes.
Result<KeyframeDatabase> buildKeyframeDatabase(const Model& model, const std::vector<Renderer*>& renderers,
                                               const PinholeCamera& camera, const KeyframePlacement& placement,
                                               const RenderSettings& render,
                                               const std::function<void(size_t, size_t)>& progress = {},
                                               KeyframeBuildStats* stats = nullptr);

/// T_world_camera of a camera at `position` looking along `heading_deg` (about up, from the
/// world's first horizontal axis) tilted `tilt_deg` below the horizon, with no roll.
Pose placementPose(const Eigen::Vector3d& position, const Eigen::Vector3d& up_world, double heading_deg,
                   double tilt_deg);

}  // namespace vkloc
