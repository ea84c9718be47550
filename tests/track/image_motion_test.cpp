#include "vkloc/track/image_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"

namespace vkloc {
namespace {

// A textured plane at depth 4 m seen by two cameras: the second turned by a few degrees and
// moved across the view. Rendered by ray casting (bilinear texture lookup), seeded.
struct PlaneScene {
  std::vector<float> texture;  // 256 x 256, 2 cm texels
  int n = 256;
  explicit PlaneScene(uint64_t seed) : texture(256 * 256) {
    Xoshiro256 rng(seed);
    // Blobs of random size and brightness: texture at many scales.
    for (float& t : texture) t = 128.0f;
    for (int b = 0; b < 600; ++b) {
      const double cx = rng.uniform(0, n), cy = rng.uniform(0, n), r = rng.uniform(1.5, 12), a = rng.uniform(-60, 60);
      for (int y = std::max(0, static_cast<int>(cy - r)); y < std::min(n, static_cast<int>(cy + r) + 1); ++y) {
        for (int x = std::max(0, static_cast<int>(cx - r)); x < std::min(n, static_cast<int>(cx + r) + 1); ++x) {
          if ((x - cx) * (x - cx) + (y - cy) * (y - cy) <= r * r) texture[y * n + x] += static_cast<float>(a);
        }
      }
    }
  }
  ImageU8 render(const PinholeCamera& camera, const Pose& T_world_camera) const {
    ImageU8 image(camera.width, camera.height, 1);
    for (int v = 0; v < camera.height; ++v) {
      for (int u = 0; u < camera.width; ++u) {
        const Eigen::Vector3d ray_c((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        const Eigen::Vector3d ray_w = T_world_camera.linear() * ray_c;
        const Eigen::Vector3d o = T_world_camera.translation();
        const double s = (4.0 - o.z()) / ray_w.z();  // plane z = 4 m
        const Eigen::Vector3d p = o + s * ray_w;
        const double tx = p.x() / 0.02 + n / 2.0, ty = p.y() / 0.02 + n / 2.0;
        const int x0 = static_cast<int>(std::floor(tx)), y0 = static_cast<int>(std::floor(ty));
        const double fx = tx - x0, fy = ty - y0;
        auto at = [&](int x, int y) { return texture[((y % n + n) % n) * n + ((x % n + n) % n)]; };
        const double value = (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
                             fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
        image.at(u, v) = static_cast<uint8_t>(std::clamp(value, 0.0, 255.0));
      }
    }
    return image;
  }
};

// The gyro's rotation is taken out and the shift left is the translation across the view:
// -f t / depth, to within a pixel, at each level.
TEST(ImageMotion, ShiftIsTheTranslationAcrossTheViewAfterTheRotation) {
  PinholeCamera camera;
  camera.width = 320;
  camera.height = 240;
  camera.fx = camera.fy = 260;
  camera.cx = 159.5;
  camera.cy = 119.5;
  const PlaneScene scene(7);
  const Pose first = Pose::Identity();
  Pose second = Pose::Identity();
  second.linear() = expSO3(Eigen::Vector3d(0.02, -0.05, 0.03));
  second.translation() = Eigen::Vector3d(0.12, -0.06, 0.0);  // metres, plane 4 m ahead
  const ImageU8 a = scene.render(camera, first), b = scene.render(camera, second);
  const Eigen::Matrix3d R_current_previous = second.linear().transpose() * first.linear();
  for (int level : {0, 1, 2}) {
    SCOPED_TRACE(level);
    auto shifts = estimateImageShifts(a, b, camera, R_current_previous, level);
    ASSERT_TRUE(shifts.ok()) << shifts.error().message;
    ASSERT_FALSE(shifts->empty());
    const ImageShift* shift = &shifts->front();
    // The translation in the second camera's frame, at the plane's depth along the view.
    const Eigen::Vector3d t_camera = second.linear().transpose() * second.translation();
    EXPECT_NEAR(shift->dx_px, -camera.fx * t_camera.x() / 4.0, 1.0 + level);
    EXPECT_NEAR(shift->dy_px, -camera.fy * t_camera.y() / 4.0, 1.0 + level);
    EXPECT_GT(shift->response, 0.1);
  }
  // Without the rotation taken out the estimate is the rotation's shift as well: far off.
  auto unturned = estimateImageShifts(a, b, camera, Eigen::Matrix3d::Identity(), 1);
  ASSERT_TRUE(unturned.ok() && !unturned->empty());
  EXPECT_GT(std::abs(unturned->front().dx_px - (-camera.fx * 0.12 / 4.0)), 5.0);
}

TEST(ImageMotion, BadInputIsAnError) {
  PinholeCamera camera;
  camera.width = 64;
  camera.height = 48;
  const ImageU8 a(64, 48, 1, 100), wrong(32, 48, 1, 100), rgb(64, 48, 3, 100);
  EXPECT_FALSE(estimateImageShifts(a, wrong, camera, Eigen::Matrix3d::Identity()).ok());
  EXPECT_FALSE(estimateImageShifts(rgb, a, camera, Eigen::Matrix3d::Identity()).ok());
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(0, 0) = std::nan("");
  EXPECT_FALSE(estimateImageShifts(a, a, camera, nan).ok());
  EXPECT_FALSE(estimateImageShifts(a, a, camera, Eigen::Matrix3d::Identity(), 3).ok());  // 8x6 pixels
  // Flat images: no shift to find, and never a NaN.
  auto flat = estimateImageShifts(a, a, camera, Eigen::Matrix3d::Identity(), 1);
  ASSERT_TRUE(flat.ok());
  for (const ImageShift& s : *flat) {
    EXPECT_TRUE(std::isfinite(s.dx_px) && std::isfinite(s.dy_px) && std::isfinite(s.response));
  }
}

}  // namespace
}  // namespace vkloc
