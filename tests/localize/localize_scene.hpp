// A small scene for the Localizer's tests: the checker box on the ground seen by a 320x240 camera
// circling it at about 2 m, images rendered by the CPU reference renderer (no Vulkan).
#pragma once

#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "support/analytic_scenes.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/fusion/sensors.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc::test {

inline PinholeCamera localizeCamera() { return PinholeCamera{260.0, 260.0, 159.5, 119.5, 320, 240}; }

/// Camera pose of frame i: on a circle of radius 2 m around the box, 1.2 m up, 0.5 deg per frame.
inline Pose localizeTruth(int i) {
  const double a = -0.9 + 0.5 * M_PI / 180.0 * i;
  return cameraLookingAt({2.0 * std::cos(a), 2.0 * std::sin(a), 1.2}, {0.0, 0.0, 0.15});
}

/// The ideal IMU reading (body = camera) at t_ns of the camera of localizeTruth at one frame per
/// frame_ns: it circles the box at 0.5 deg per frame looking at a point on the world z axis, so
/// it turns about z at that rate and accelerates towards the axis. World z up, gravity -9.81 m/s^2.
inline ImuSample localizeImuAt(int64_t t_ns, int64_t frame_ns = 50'000'000) {
  const double w = 0.5 * M_PI / 180.0 / (static_cast<double>(frame_ns) * 1e-9);  // rad/s about world z
  const double a = -0.9 + w * static_cast<double>(t_ns) * 1e-9;
  const Eigen::Matrix3d R_world_camera =
      cameraLookingAt({2.0 * std::cos(a), 2.0 * std::sin(a), 1.2}, {0.0, 0.0, 0.15}).linear();
  const Eigen::Vector3d accel_world = -w * w * Eigen::Vector3d(2.0 * std::cos(a), 2.0 * std::sin(a), 0.0);
  ImuSample s;
  s.t_ns = t_ns;
  s.gyro_body = R_world_camera.transpose() * Eigen::Vector3d(0, 0, w);
  s.accel_body = R_world_camera.transpose() * (accel_world - Eigen::Vector3d(0, 0, -9.81));
  return s;
}

/// Gray images of frames 0..n-1 (cached per process: the CPU renderer takes a while).
inline const std::vector<ImageU8>& localizeFrames(int n) {
  static std::vector<ImageU8> frames;
  if (static_cast<int>(frames.size()) < n) {
    const Model model = makeBoxOnGround();
    for (int i = static_cast<int>(frames.size()); i < n; ++i) {
      auto view = renderReference(model, localizeCamera(), localizeTruth(i));
      frames.push_back(view.ok() ? view->gray : ImageU8(320, 240, 1));
    }
  }
  return frames;
}

/// Three boxes of different sizes on the checker ground: unlike the single box, no turn of the
/// scene maps it onto itself, so a view has one true place.
inline Model makeAsymmetricScene() {
  Model m = makeBoxOnGround();
  for (const auto& [lo, hi] : {std::pair<Eigen::Vector3d, Eigen::Vector3d>{{0.5, 0.4, 0.0}, {0.8, 0.6, 0.7}},
                               std::pair<Eigen::Vector3d, Eigen::Vector3d>{{-0.9, -0.6, 0.0}, {-0.6, -0.2, 0.2}}}) {
    const Model box = makeBox(lo, hi);
    const uint32_t base = static_cast<uint32_t>(m.vertexCount());
    m.positions.insert(m.positions.end(), box.positions.begin(), box.positions.end());
    m.uvs.insert(m.uvs.end(), box.uvs.begin(), box.uvs.end());
    for (uint32_t i : box.indices) m.indices.push_back(base + i);
  }
  finishSingleBlock(m);
  return m;
}

inline double translationError(const Pose& a, const Pose& b) { return (a.translation() - b.translation()).norm(); }

inline double rotationErrorDeg(const Pose& a, const Pose& b) {
  return logSO3(a.linear().transpose() * b.linear()).norm() * 180.0 / M_PI;
}

}  // namespace vkloc::test
