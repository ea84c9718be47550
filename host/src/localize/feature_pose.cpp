// A camera pose from ORB features matched with a render of known depth (see feature_pose.hpp).
#include "vkloc/localize/feature_pose.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>

#include "vkloc/core/numeric.hpp"

namespace vkloc {
namespace {

constexpr int kDescriptorBytes = 32;

cv::Mat descriptorMat(const PointFeatures& f) {
  return cv::Mat(static_cast<int>(f.size()), kDescriptorBytes, CV_8U, const_cast<uint8_t*>(f.descriptors.data()));
}

/// Camera z (metres) at a keypoint of the render: the nearest pixel's, when its 3x3
/// neighbourhood is all surface and spans less than 3 % of it (a corner on an occluding edge has
/// the depth of either side: left out). 0 when unusable.
float keypointDepth(const ImageF32& depth, float x_px, float y_px) {
  const int x = static_cast<int>(std::lround(x_px));
  const int y = static_cast<int>(std::lround(y_px));
  if (x < 1 || y < 1 || x >= depth.width - 1 || y >= depth.height - 1) return 0.0f;
  float lo = depth.at(x, y), hi = lo;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const float d = depth.at(x + dx, y + dy);
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  if (!(lo > 0.0f) || !std::isfinite(hi) || hi - lo > 0.03f * depth.at(x, y)) return 0.0f;
  return depth.at(x, y);
}

}  // namespace

Status validateFeaturePoseOptions(const FeaturePoseOptions& o) {
  if (o.max_features < 50 || o.max_features > 20000 || !finiteIn(o.ratio, 0.01, 1.0) || o.max_distance_bits < 0 ||
      o.max_distance_bits > 256 || !finiteIn(o.reprojection_px, 0.1, 100.0) || o.iterations < 1 ||
      o.iterations > 100000 || o.min_inliers < 4 || !finiteIn(o.min_inlier_fraction, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "relocalization.features: need max_features in 50..20000, ratio in 0.01..1, "
                     "max_distance_bits in 0..256, reprojection_px in 0.1..100, iterations in 1..100000, "
                     "min_inliers >= 4 and min_inlier_fraction in 0..1");
  }
  return Status::success();
}

Result<PointFeatures> detectPointFeatures(const ImageU8& gray, int max_features) {
  if (gray.channels != 1 || gray.width < 1 || gray.height < 1 ||
      gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("feature pose: need an 8-bit gray image, got {}x{} with {} channel(s)", gray.width,
                                 gray.height, gray.channels));
  }
  const cv::Mat in(gray.height, gray.width, CV_8UC1, const_cast<uint8_t*>(gray.data.data()));
  constexpr float kScaleFactor = 1.2f;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  try {
    cv::Ptr<cv::ORB> orb = cv::ORB::create(std::max(1, max_features), kScaleFactor);
    orb->detectAndCompute(in, cv::noArray(), keypoints, descriptors);
  } catch (const cv::Exception& e) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("feature pose: ORB failed: {}", e.what()));
  }
  PointFeatures out;
  if (keypoints.empty() || descriptors.cols != kDescriptorBytes || descriptors.type() != CV_8U) return out;
  out.x_px.reserve(keypoints.size());
  out.y_px.reserve(keypoints.size());
  out.descriptors.resize(keypoints.size() * kDescriptorBytes);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    // OpenCV scales a level-l position by s = 1.2^l about the image's corner; about pixel
    // centres (core/camera.hpp) the position is (p_l + 0.5) s - 0.5 = p + (s - 1) / 2.
    const float half_growth = 0.5f * (std::pow(kScaleFactor, static_cast<float>(keypoints[i].octave)) - 1.0f);
    out.x_px.push_back(keypoints[i].pt.x + half_growth);
    out.y_px.push_back(keypoints[i].pt.y + half_growth);
    std::memcpy(out.descriptors.data() + i * kDescriptorBytes, descriptors.ptr<uint8_t>(static_cast<int>(i)),
                kDescriptorBytes);
  }
  return out;
}

Result<std::optional<FeaturePose>> featurePose(const PointFeatures& live, const PointFeatures& render,
                                               const ImageF32& render_depth, const PinholeCamera& camera,
                                               const Pose& T_world_render, const FeaturePoseOptions& options) {
  if (render_depth.channels != 1 || render_depth.width != camera.width || render_depth.height != camera.height ||
      render_depth.data.size() != static_cast<size_t>(camera.width) * camera.height) {
    return makeError(
        ErrorCode::kInvalidArgument,
        fmt::format("feature pose: the render's depth is {}x{} with {} channel(s), the camera {}x{}",
                    render_depth.width, render_depth.height, render_depth.channels, camera.width, camera.height));
  }
  for (const PointFeatures* f : {&live, &render}) {
    if (f->y_px.size() != f->x_px.size() || f->descriptors.size() != f->size() * kDescriptorBytes) {
      return makeError(ErrorCode::kInvalidArgument,
                       "feature pose: point features need a y and 32 descriptor bytes per x");
    }
  }
  if (!(camera.fx > 0) || !(camera.fy > 0)) {
    return makeError(ErrorCode::kInvalidArgument, "feature pose: the camera's focal lengths must be positive");
  }
  if (live.size() < 4 || render.size() < 4) return std::optional<FeaturePose>{};
  // Nearest render feature of each live one, kept when clearly better than the second nearest.
  std::vector<std::vector<cv::DMatch>> knn;
  try {
    cv::BFMatcher(cv::NORM_HAMMING).knnMatch(descriptorMat(live), descriptorMat(render), knn, 2);
  } catch (const cv::Exception&) {
    return std::optional<FeaturePose>{};  // nothing matched
  }
  std::vector<cv::Point3d> points_world;
  std::vector<cv::Point2d> pixels_live;
  std::vector<char> used(render.size(), 0);  // one live feature per render feature
  for (const std::vector<cv::DMatch>& m : knn) {
    if (m.size() < 2 || m[0].distance > options.max_distance_bits || m[0].distance >= options.ratio * m[1].distance) {
      continue;
    }
    const auto r = static_cast<size_t>(m[0].trainIdx);
    if (used[r]) continue;
    const float z = keypointDepth(render_depth, render.x_px[r], render.y_px[r]);
    if (z <= 0.0f) continue;
    used[r] = 1;
    const Eigen::Vector3d p_render((render.x_px[r] - camera.cx) / camera.fx * z,
                                   (render.y_px[r] - camera.cy) / camera.fy * z, z);
    const Eigen::Vector3d p_world = T_world_render * p_render;
    points_world.emplace_back(p_world.x(), p_world.y(), p_world.z());
    const auto l = static_cast<size_t>(m[0].queryIdx);
    pixels_live.emplace_back(live.x_px[l], live.y_px[l]);
  }
  FeaturePose out;
  out.matches = static_cast<int>(points_world.size());
  if (out.matches < std::max(options.min_inliers, 6)) return std::optional<FeaturePose>{};
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat rvec, tvec, R_cv;
  try {
    std::vector<int> inliers;
    // The solver's random samples come from OpenCV's fixed-seed generator: deterministic.
    const bool solved =
        cv::solvePnPRansac(points_world, pixels_live, K, cv::noArray(), rvec, tvec, false, options.iterations,
                           static_cast<float>(options.reprojection_px), 0.999, inliers, cv::SOLVEPNP_EPNP);
    out.inliers = static_cast<int>(inliers.size());
    if (!solved || out.inliers < options.min_inliers ||
        out.inliers < options.min_inlier_fraction * static_cast<double>(out.matches)) {
      return std::optional<FeaturePose>{};
    }
    // Levenberg-Marquardt on the inliers from the RANSAC pose.
    std::vector<cv::Point3d> in_world;
    std::vector<cv::Point2d> in_live;
    for (int i : inliers) {
      in_world.push_back(points_world[static_cast<size_t>(i)]);
      in_live.push_back(pixels_live[static_cast<size_t>(i)]);
    }
    cv::solvePnPRefineLM(in_world, in_live, K, cv::noArray(), rvec, tvec);
    cv::Rodrigues(rvec, R_cv);
  } catch (const cv::Exception&) {
    return std::optional<FeaturePose>{};  // a degenerate set of points: no pose
  }
  Eigen::Matrix3d R_camera_world;
  Eigen::Vector3d t_camera_world;
  cv::cv2eigen(R_cv, R_camera_world);
  cv::cv2eigen(tvec, t_camera_world);
  Pose T_camera_world = Pose::Identity();
  T_camera_world.linear() = R_camera_world;
  T_camera_world.translation() = t_camera_world;
  out.T_world_camera = T_camera_world.inverse();
  if (!isValidPose(out.T_world_camera)) return std::optional<FeaturePose>{};
  return std::optional<FeaturePose>{out};
}

}  // namespace vkloc
