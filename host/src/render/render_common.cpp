// Projection and frustum helpers shared by the GPU renderer and the CPU reference.
#include <fmt/format.h>

#include <cmath>

#include "vkloc/render/renderer.hpp"

namespace vkloc {

Status validateRenderSettings(const RenderSettings& s) {
  if (!(s.near_m >= 1e-6) || !std::isfinite(s.near_m)) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("render: near = {} m must be at least 1e-6 m", s.near_m));
  }
  if (!(s.far_m > s.near_m) || !std::isfinite(s.far_m) || s.far_m / s.near_m > 1e9) {
    return makeError(
        ErrorCode::kInvalidArgument,
        fmt::format("render: far = {} m must be finite, above near = {} m and at most 1e9 x near", s.far_m, s.near_m));
  }
  if (!(s.lod_pixel_error >= 0) || !std::isfinite(s.lod_pixel_error)) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("render: lod_pixel_error = {} must be finite and >= 0", s.lod_pixel_error));
  }
  if (s.threads < 1 || s.threads > 64) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("render: threads = {} must be in 1..64", s.threads));
  }
  return Status::success();
}

Eigen::Matrix4d projectionMatrix(const PinholeCamera& camera, double near_m, double far_m) {
  // Seed 001 eqs. 7-8 folded into one matrix for Vulkan clip space (x right, y down, depth
  // 0..1), with the pixel-centre convention u_fb = u + 0.5 and reverse-Z:
  //   x_clip = (2 fx / w) x + (2 (cx + 0.5) / w - 1) z,   w_clip = z
  //   y_clip = (2 fy / h) y + (2 (cy + 0.5) / h - 1) z
  //   z_clip = a z + b  with  z_ndc = z_clip / z = 1 at z = near, 0 at z = far.
  const double w = camera.width;
  const double h = camera.height;
  const double a = -near_m / (far_m - near_m);
  const double b = near_m * far_m / (far_m - near_m);
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = 2.0 * camera.fx / w;
  P(0, 2) = 2.0 * (camera.cx + 0.5) / w - 1.0;
  P(1, 1) = 2.0 * camera.fy / h;
  P(1, 2) = 2.0 * (camera.cy + 0.5) / h - 1.0;
  P(2, 2) = a;
  P(2, 3) = b;
  P(3, 2) = 1.0;
  return P;
}

bool aabbInFrustum(const Aabb& box, const PinholeCamera& camera, const Pose& T_world_camera, double near_m,
                   double far_m) {
  return aabbInFrustumFromCamera(box, camera, T_world_camera.inverse(), near_m, far_m);
}

bool aabbInFrustumFromCamera(const Aabb& box, const PinholeCamera& camera, const Pose& T_camera_world, double near_m,
                             double far_m) {
  if (box.empty()) return false;
  // Frustum planes in the camera frame as n . p >= d (inside), then tested against the box's
  // eight corners transformed into the camera frame.
  const double w = camera.width;
  const double h = camera.height;
  // Image borders at u = -0.5 and u = w - 0.5 (pixel edges), as normalised image coordinates.
  const double xl = (-0.5 - camera.cx) / camera.fx;
  const double xr = (w - 0.5 - camera.cx) / camera.fx;
  const double yt = (-0.5 - camera.cy) / camera.fy;
  const double yb = (h - 0.5 - camera.cy) / camera.fy;
  const Eigen::Vector3d normals[6] = {{1, 0, -xl}, {-1, 0, xr}, {0, 1, -yt}, {0, -1, yb}, {0, 0, 1}, {0, 0, -1}};
  const double offsets[6] = {0, 0, 0, 0, near_m, -far_m};
  Eigen::Vector3d corners[8];
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p_world((i & 1) ? box.max[0] : box.min[0], (i & 2) ? box.max[1] : box.min[1],
                                  (i & 4) ? box.max[2] : box.min[2]);
    corners[i] = T_camera_world * p_world;
  }
  for (int k = 0; k < 6; ++k) {
    bool any_inside = false;
    for (const Eigen::Vector3d& c : corners) {
      if (normals[k].dot(c) >= offsets[k]) {
        any_inside = true;
        break;
      }
    }
    if (!any_inside) return false;
  }
  return true;
}

}  // namespace vkloc
