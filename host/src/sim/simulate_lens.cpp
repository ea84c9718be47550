// Lens images for the simulator: pinhole renders (one, or a cube map's faces) resampled through
// a lens model.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vkloc/sim/simulate.hpp"

namespace vkloc {

namespace {

/// Rotation of a cube face from the lens: columns are the face's x, y, z in the lens frame.
Pose cubeFace(int face) {
  static const double kAxes[6][2][3] = {
      {{1, 0, 0}, {0, 1, 0}},   // +z: x, y
      {{0, 0, -1}, {0, 1, 0}},  // +x
      {{0, 0, 1}, {0, 1, 0}},   // -x
      {{1, 0, 0}, {0, 0, -1}},  // +y
      {{1, 0, 0}, {0, 0, 1}},   // -y
      {{-1, 0, 0}, {0, 1, 0}},  // -z
  };
  Pose T = Pose::Identity();
  const Eigen::Vector3d x(kAxes[face][0][0], kAxes[face][0][1], kAxes[face][0][2]);
  const Eigen::Vector3d y(kAxes[face][1][0], kAxes[face][1][1], kAxes[face][1][2]);
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = x.cross(y);
  return T;
}

}  // namespace

Result<LensRig> makeLensRig(const LensCamera& lens) {
  VKLOC_TRY_STATUS(validateLensCamera(lens));
  LensRig rig;
  rig.lens = lens;
  const PinholeCamera& k = lens.intrinsics;
  const size_t n = static_cast<size_t>(k.width) * k.height;
  std::vector<Eigen::Vector3f> rays(n, Eigen::Vector3f::Zero());
  std::vector<uint8_t> valid(n, 0);
  double max_tan_x = 0, max_tan_y = 0;
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      Eigen::Vector3d ray;
      if (!unprojectLens(lens, Eigen::Vector2d(u, v), ray)) continue;
      const size_t i = static_cast<size_t>(v) * k.width + u;
      rays[i] = ray.cast<float>();
      valid[i] = 1;
      if (ray.z() > 1e-6) {
        max_tan_x = std::max(max_tan_x, std::abs(ray.x() / ray.z()));
        max_tan_y = std::max(max_tan_y, std::abs(ray.y() / ray.z()));
      }
    }
  }
  const double f = 1.25 * std::max(k.fx, k.fy);
  // One render when every pixel's ray is within 60 deg of the axis, else a cube map.
  double max_angle = 0;
  for (size_t i = 0; i < n; ++i) {
    if (valid[i])
      max_angle =
          std::max(max_angle, std::acos(std::clamp(static_cast<double>(rays[i].z() / rays[i].norm()), -1.0, 1.0)));
  }
  const bool single = max_angle <= 60.0 * M_PI / 180.0;
  if (single) {
    const int w = 2 * static_cast<int>(std::ceil(f * max_tan_x)) + 4;
    const int h = 2 * static_cast<int>(std::ceil(f * max_tan_y)) + 4;
    if (w > 8192 || h > 8192) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("simulate: the lens needs a {}x{} render (over 8192 px)", w, h));
    }
    rig.faces.push_back(PinholeCamera{f, f, 0.5 * (w - 1), 0.5 * (h - 1), w, h});
    rig.T_camera_face.push_back(Pose::Identity());
  } else {
    // 90-degree faces with 2 px to spare at each border.
    const int side = 2 * static_cast<int>(std::ceil(f)) + 4;
    std::array<bool, 6> used{};
    for (size_t i = 0; i < n; ++i) {
      if (!valid[i]) continue;
      const Eigen::Vector3f& r = rays[i];
      int axis = 0;
      r.cwiseAbs().maxCoeff(&axis);
      const bool positive = r[axis] >= 0;
      used[axis == 2 ? (positive ? 0 : 5) : axis == 0 ? (positive ? 1 : 2) : (positive ? 3 : 4)] = true;
    }
    for (int face = 0; face < 6; ++face) {
      if (!used[static_cast<size_t>(face)]) continue;
      rig.faces.push_back(PinholeCamera{f, f, 0.5 * (side - 1), 0.5 * (side - 1), side, side});
      rig.T_camera_face.push_back(cubeFace(face));
    }
  }
  rig.face_of_pixel.assign(n, -1);
  rig.uv.assign(2 * n, 0.0f);
  rig.cos_angle.assign(n, 0.0f);
  for (size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const Eigen::Vector3d r = rays[i].cast<double>();
    rig.cos_angle[i] = static_cast<float>(r.z() / r.norm());
    // The face whose axis is closest to the ray (largest z in its frame).
    int best = -1;
    double best_z = 0;
    for (size_t f_i = 0; f_i < rig.faces.size(); ++f_i) {
      const double z = rig.T_camera_face[f_i].linear().col(2).dot(r);
      if (z > best_z) {
        best_z = z;
        best = static_cast<int>(f_i);
      }
    }
    if (best < 0) continue;
    const Eigen::Vector3d p = rig.T_camera_face[static_cast<size_t>(best)].linear().transpose() * r;
    const PinholeCamera& c = rig.faces[static_cast<size_t>(best)];
    const double u = c.fx * p.x() / p.z() + c.cx, v = c.fy * p.y() / p.z() + c.cy;
    if (!(u >= 0 && v >= 0 && u <= c.width - 1 && v <= c.height - 1)) continue;
    rig.face_of_pixel[i] = static_cast<int16_t>(best);
    rig.uv[2 * i] = static_cast<float>(u);
    rig.uv[2 * i + 1] = static_cast<float>(v);
  }
  return rig;
}

ImageF32 resampleLens(const LensRig& rig, const std::vector<ImageF32>& faces) {
  const PinholeCamera& k = rig.lens.intrinsics;
  ImageF32 out(k.width, k.height, 3, 0.0f);
  const size_t n = static_cast<size_t>(k.width) * k.height;
  for (size_t i = 0; i < n; ++i) {
    const int f = rig.face_of_pixel[i];
    if (f < 0 || static_cast<size_t>(f) >= faces.size()) continue;
    const ImageF32& img = faces[static_cast<size_t>(f)];
    const float u = rig.uv[2 * i], v = rig.uv[2 * i + 1];
    const int x0 = std::min(static_cast<int>(u), img.width - 1), y0 = std::min(static_cast<int>(v), img.height - 1);
    const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
    const float fx = u - static_cast<float>(x0), fy = v - static_cast<float>(y0);
    for (int c = 0; c < 3; ++c) {
      const float a = img.at(x0, y0, c), b = img.at(x1, y0, c), d = img.at(x0, y1, c), e = img.at(x1, y1, c);
      out.data[3 * i + static_cast<size_t>(c)] = (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * d + fx * e);
    }
  }
  return out;
}

}  // namespace vkloc
