// vkloc: a camera pose from point features matched between the live image and a model render
// whose depth is known: ORB keypoints of both (OpenCV), nearest-neighbour matches in Hamming
// distance with the ratio test, the render's keypoints lifted to 3D world points by its depth,
// and a RANSAC PnP (OpenCV's solvePnPRansac, EPnP minimal sets, then Levenberg-Marquardt on the
// inliers). Relocalization uses it as one more start of the edge alignment: a start from the
// geometry of many matched points, not from a database keyframe's pose (which may be a metre and
// tens of degrees off: outside the alignment's basin near walls).
//
// Frames and units: poses are T_world_camera (camera to world, metres; camera x right, y down,
// z forward); pixels as core/camera.hpp (integer coordinates at pixel centres).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Options of the feature pose. Plain data; validateFeaturePoseOptions checks them.
struct FeaturePoseOptions {
  int max_features = 1000;       ///< ORB keypoints per image, best Harris score first (50..20000).
  double ratio = 0.8;            ///< Lowe's ratio test: best / second-best Hamming distance below it.
  int max_distance_bits = 80;    ///< Matches farther than this (of 256 bits) are dropped.
  double reprojection_px = 4.0;  ///< RANSAC inlier threshold, pixels of the live image.
  int iterations = 300;          ///< RANSAC iterations.
  int min_inliers = 15;          ///< Fewer RANSAC inliers than this: no pose.
  /// Fewer inliers than this fraction of the matches: no pose (a chance consensus among many
  /// wrong matches).
  double min_inlier_fraction = 0.15;
};

/// kInvalidArgument listing the fields' ranges for values out of range.
Status validateFeaturePoseOptions(const FeaturePoseOptions& options);

/// ORB keypoints (pixel positions) and their 256-bit descriptors, 32 bytes each, row by row.
struct PointFeatures {
  std::vector<float> x_px, y_px;
  std::vector<uint8_t> descriptors;  ///< 32 x size() bytes.
  size_t size() const { return x_px.size(); }
};

/// The ORB features of an 8-bit gray image (8 pyramid levels, scale 1.2). Deterministic.
/// kInvalidArgument for an empty or non-gray image.
Result<PointFeatures> detectPointFeatures(const ImageU8& gray, int max_features);

/// What a feature pose found.
struct FeaturePose {
  Pose T_world_camera = Pose::Identity();  ///< Of the live camera.
  int matches = 0;                         ///< Matches with a depth, given to RANSAC.
  int inliers = 0;                         ///< RANSAC inliers.
};

/// The live camera's pose from `live` features matched with those of a render made at
/// T_world_render with `camera` (the same intrinsics as the live image) whose depth (camera z,
/// metres, 0 = nothing) is `render_depth`. nullopt when too few matches or inliers agree
/// (options) or OpenCV finds the points degenerate. kInvalidArgument when the depth image is not
/// camera-sized, the features are inconsistent (a y and 32 descriptor bytes per x) or the
/// camera's focal lengths are not positive.
Result<std::optional<FeaturePose>> featurePose(const PointFeatures& live, const PointFeatures& render,
                                               const ImageF32& render_depth, const PinholeCamera& camera,
                                               const Pose& T_world_render, const FeaturePoseOptions& options);

}  // namespace vkloc
