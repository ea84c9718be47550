// Photometric side of the simulator: sRGB conversion, lighting with shadow maps, exposure,
// white balance, vignetting, sensor noise, colour jitter of the model.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "vkloc/core/random.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc {
namespace {

using Rng = Xoshiro256;

constexpr double kPi = 3.14159265358979323846;

/// sRGB decode table for 8-bit values.
const std::array<float, 256>& srgbTable() {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    for (int i = 0; i < 256; ++i) t[i] = static_cast<float>(srgbToLinear(i / 255.0));
    return t;
  }();
  return table;
}

uint8_t toByte(double encoded01) {
  const double v = std::clamp(encoded01, 0.0, 1.0) * 255.0;
  return static_cast<uint8_t>(std::lround(v));
}

}  // namespace

double srgbToLinear(double encoded) {
  return encoded <= 0.04045 ? encoded / 12.92 : std::pow((encoded + 0.055) / 1.055, 2.4);
}

double linearToSrgb(double linear) {
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

ImageF32 decodeRender(const ImageU8& rgba) {
  ImageF32 out(rgba.width, rgba.height, 3);
  const auto& table = srgbTable();
  const size_t n = static_cast<size_t>(rgba.width) * rgba.height;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) out.data[3 * i + c] = table[rgba.data[4 * i + c]];
  }
  return out;
}

ImageU8 encodeImage(const ImageF32& linear_rgb, double gamma) {
  ImageU8 out(linear_rgb.width, linear_rgb.height, 3);
  const double inv_gamma = 1.0 / gamma;
  const bool plain = gamma == 1.0;
  for (size_t i = 0; i < out.data.size(); ++i) {
    const double x = std::clamp(static_cast<double>(linear_rgb.data[i]), 0.0, 1.0);
    double s = linearToSrgb(x);
    if (!plain) s = std::pow(s, inv_gamma);
    out.data[i] = toByte(s);
  }
  return out;
}

void applyExposure(ImageF32& linear_rgb, double gain, const std::array<double, 3>& white_balance) {
  const float g[3] = {static_cast<float>(gain * white_balance[0]), static_cast<float>(gain * white_balance[1]),
                      static_cast<float>(gain * white_balance[2])};
  const size_t n = static_cast<size_t>(linear_rgb.width) * linear_rgb.height;
  for (size_t i = 0; i < n; ++i) {
    for (int c = 0; c < 3; ++c) linear_rgb.data[3 * i + c] *= g[c];
  }
}

void applyVignetting(ImageF32& linear_rgb, const PinholeCamera& camera, double strength) {
  if (strength == 0.0) return;
  for (int v = 0; v < linear_rgb.height; ++v) {
    const double y = (v - camera.cy) / camera.fy;
    for (int u = 0; u < linear_rgb.width; ++u) {
      const double x = (u - camera.cx) / camera.fx;
      // cos theta = 1 / sqrt(1 + x^2 + y^2), so cos^4 theta = 1 / (1 + x^2 + y^2)^2.
      const double q = 1.0 + x * x + y * y;
      const auto f = static_cast<float>(1.0 - strength * (1.0 - 1.0 / (q * q)));
      for (int c = 0; c < linear_rgb.channels; ++c) linear_rgb.at(u, v, c) *= f;
    }
  }
}

void addSensorNoise(ImageF32& linear_rgb, double shot, double read, uint64_t seed) {
  if (shot == 0.0 && read == 0.0) return;
  Rng rng(seed);
  const double shot2 = shot * shot;
  const double read2 = read * read;
  for (float& value : linear_rgb.data) {
    const double sigma = std::sqrt(shot2 * std::max(0.0, static_cast<double>(value)) + read2);
    value = static_cast<float>(value + sigma * rng.gaussian());
  }
}

Eigen::Vector3d sunDirection(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * kPi / 180.0;
  const double el = elevation_deg * kPi / 180.0;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

Result<ShadowMap> renderShadowMap(Renderer& renderer, const Aabb& scene_bounds, const LightingOptions& lighting) {
  if (scene_bounds.empty()) return makeError(ErrorCode::kInvalidArgument, "shadow map: the scene bounds are empty");
  if (lighting.shadow_map_size < 16 || lighting.shadow_map_size > 8192) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("shadow map size {} is outside 16..8192", lighting.shadow_map_size));
  }
  const Eigen::Vector3d lo(scene_bounds.min[0], scene_bounds.min[1], scene_bounds.min[2]);
  const Eigen::Vector3d hi(scene_bounds.max[0], scene_bounds.max[1], scene_bounds.max[2]);
  const Eigen::Vector3d center = 0.5 * (lo + hi);
  const double radius = std::max(0.5 * (hi - lo).norm(), 1e-3);
  ShadowMap map;
  map.spot = lighting.spot;
  const int size = lighting.shadow_map_size;
  map.camera.width = size;
  map.camera.height = size;
  map.camera.cx = (size - 1) / 2.0;
  map.camera.cy = (size - 1) / 2.0;
  RenderSettings settings;
  settings.outputs = kRenderDepth;
  Eigen::Vector3d eye;
  Eigen::Vector3d target;
  if (lighting.spot) {
    if (!(lighting.spot_fov_deg > 1.0 && lighting.spot_fov_deg < 170.0)) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("spot lamp opening angle {} deg is outside (1, 170)", lighting.spot_fov_deg));
    }
    eye = Eigen::Vector3d(lighting.spot_position[0], lighting.spot_position[1], lighting.spot_position[2]);
    if (!eye.allFinite()) return makeError(ErrorCode::kInvalidArgument, "spot lamp position is not finite");
    target = eye - Eigen::Vector3d::UnitZ();
    const double f = (size / 2.0) / std::tan(0.5 * lighting.spot_fov_deg * kPi / 180.0);
    map.camera.fx = map.camera.fy = f;
    settings.near_m = std::max(1e-3, 1e-4 * radius);
    settings.far_m = (eye - center).norm() + 2.0 * radius + 1.0;
  } else {
    if (!(lighting.sun_elevation_deg > 0.0 && lighting.sun_elevation_deg <= 90.0) ||
        !std::isfinite(lighting.sun_azimuth_deg)) {
      return makeError(ErrorCode::kInvalidArgument,
                       fmt::format("sun elevation {} deg is outside (0, 90]", lighting.sun_elevation_deg));
    }
    map.direction_to_sun = sunDirection(lighting.sun_azimuth_deg, lighting.sun_elevation_deg);
    // Far away along the sun direction with a long focal length: the bounding sphere just
    // fills the map and rays are parallel to within radius / distance = 1 % rad.
    const double distance = 100.0 * radius;
    eye = center + distance * map.direction_to_sun;
    target = center;
    const double half_angle = std::asin(radius / distance);
    map.camera.fx = map.camera.fy = (size / 2.0) / std::tan(half_angle);
    settings.near_m = distance - 1.01 * radius - 1.0;
    settings.far_m = distance + 1.01 * radius + 1.0;
  }
  auto pose = lookAt(eye, target, Eigen::Vector3d::UnitZ());
  if (!pose.ok()) return pose.error();
  map.T_world_light = *pose;
  auto rendered = renderer.render(map.camera, map.T_world_light, settings);
  if (!rendered.ok()) return makeError(rendered.error().code, "shadow map: " + rendered.error().message);
  map.depth = std::move(rendered->depth);
  return map;
}

double shadowLitFraction(const ShadowMap& map, const LightingOptions& lighting, const Eigen::Vector3d& p_world,
                         const Eigen::Vector3d& normal_world) {
  const Eigen::Vector3d q = map.T_world_light.inverse() * p_world;
  if (!(q.z() > 0)) return map.spot ? 0.0 : 1.0;
  const PinholeCamera& cam = map.camera;
  const double u = cam.fx * q.x() / q.z() + cam.cx;
  const double v = cam.fy * q.y() / q.z() + cam.cy;
  if (map.spot) {
    const double du = u - cam.cx;
    const double dv = v - cam.cy;
    if (du * du + dv * dv > 0.25 * cam.width * cam.width) return 0.0;  // Outside the lamp's cone.
  }
  const Eigen::Vector3d l =
      map.spot ? Eigen::Vector3d(map.T_world_light.translation() - p_world).normalized() : map.direction_to_sun;
  const double cos_angle = std::clamp(std::abs(normal_world.dot(l)), 0.05, 1.0);
  const double tan_angle = std::min(std::sqrt(1.0 - cos_angle * cos_angle) / cos_angle, 10.0);
  const double texel_m = q.z() / cam.fx;  // Footprint of one shadow-map texel at this depth.
  const double bias = texel_m * (lighting.shadow_bias_texels + lighting.shadow_slope_bias * tan_angle);
  const int iu = static_cast<int>(std::lround(u));
  const int iv = static_cast<int>(std::lround(v));
  const int r = lighting.pcf ? 1 : 0;
  int lit = 0;
  int taps = 0;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      ++taps;
      const int x = iu + dx;
      const int y = iv + dy;
      if (x < 0 || y < 0 || x >= map.depth.width || y >= map.depth.height) {
        lit += map.spot ? 0 : 1;
        continue;
      }
      const float d = map.depth.at(x, y);
      if (d == kBackgroundDepth || q.z() <= d + bias) ++lit;
    }
  }
  return static_cast<double>(lit) / taps;
}

void applyLighting(ImageF32& linear_rgb, const RenderOutput& render, const PinholeCamera& camera,
                   const Pose& T_world_camera, const ShadowMap& map, const LightingOptions& lighting) {
  if (render.depth.empty()) return;
  const bool have_normals = !render.normals.empty();
  const Eigen::Matrix3d R = T_world_camera.linear();
  const Eigen::Vector3d t = T_world_camera.translation();
  const Eigen::Vector3d lamp = map.T_world_light.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const float z = render.depth.at(u, v);
      if (z == kBackgroundDepth || !std::isfinite(z)) continue;
      const Eigen::Vector3d p_camera((u - camera.cx) / camera.fx * z, (v - camera.cy) / camera.fy * z, z);
      const Eigen::Vector3d p_world = R * p_camera + t;
      // Without normals the surface is taken to face the camera.
      const Eigen::Vector3d n_camera =
          have_normals
              ? Eigen::Vector3d(render.normals.at(u, v, 0), render.normals.at(u, v, 1), render.normals.at(u, v, 2))
              : Eigen::Vector3d(-p_camera.normalized());
      const Eigen::Vector3d n_world = R * n_camera;
      const Eigen::Vector3d l = map.spot ? Eigen::Vector3d((lamp - p_world).normalized()) : map.direction_to_sun;
      const double n_dot_l = n_world.dot(l);
      double lit = 0.0;
      if (n_dot_l > 0.0) lit = shadowLitFraction(map, lighting, p_world, n_world);
      const auto shade = static_cast<float>(lighting.ambient + lighting.direct * std::max(0.0, n_dot_l) * lit);
      for (int c = 0; c < 3; ++c) linear_rgb.at(u, v, c) *= shade;
    }
  }
}

Model jitterModelColors(const Model& model, double gain_range, double offset_range, uint64_t seed) {
  Model out = model;
  if (gain_range == 0.0 && offset_range == 0.0) return out;
  Rng rng(subSeed(seed, 0x636f6c6f72ull));
  for (Texture& tex : out.textures) {
    double gain[3];
    double offset[3];
    for (int c = 0; c < 3; ++c) {
      gain[c] = 1.0 + rng.uniform(-gain_range, gain_range);
      offset[c] = 255.0 * rng.uniform(-offset_range, offset_range);
    }
    // One lookup table per channel: the texture bytes are sRGB-encoded, jittered as stored.
    std::array<std::array<uint8_t, 256>, 3> lut{};
    for (int c = 0; c < 3; ++c) {
      for (int i = 0; i < 256; ++i) {
        lut[c][i] = static_cast<uint8_t>(std::clamp(std::lround(gain[c] * i + offset[c]), 0L, 255L));
      }
    }
    for (size_t i = 0; i + 3 < tex.rgba.size(); i += 4) {
      for (int c = 0; c < 3; ++c) tex.rgba[i + c] = lut[c][tex.rgba[i + c]];
    }
  }
  for (Material& m : out.materials) {
    for (int c = 0; c < 3; ++c) {
      m.base_color[c] =
          static_cast<float>(std::clamp(m.base_color[c] * (1.0 + rng.uniform(-gain_range, gain_range)), 0.0, 1.0));
    }
  }
  return out;
}

AppearanceOptions hardAppearance(uint64_t seed, bool indoor, const Aabb& scene_bounds) {
  Rng rng(subSeed(seed, 0x68617264ull));
  AppearanceOptions a;
  LightingOptions& l = a.lighting;
  l.enabled = true;
  l.sun_azimuth_deg = rng.uniform(0.0, 360.0);
  l.sun_elevation_deg = rng.uniform(25.0, 65.0);
  if (indoor) {
    // A ceiling lamp 0.3 m below the top of the scene, off-centre by up to 1 m.
    l.spot = true;
    const double cx = 0.5 * (scene_bounds.min[0] + scene_bounds.max[0]);
    const double cy = 0.5 * (scene_bounds.min[1] + scene_bounds.max[1]);
    l.spot_position = {cx + rng.uniform(-1.0, 1.0), cy + rng.uniform(-1.0, 1.0), scene_bounds.max[2] - 0.3};
    l.spot_fov_deg = 150.0;
    l.ambient = 0.5;
    l.direct = 0.7;
  }
  a.exposure_ev = rng.uniform(-0.7, 0.7);
  a.exposure_drift_ev = 0.3;
  a.exposure_drift_period_s = rng.uniform(8.0, 16.0);
  a.white_balance = {rng.uniform(0.85, 1.15), 1.0, rng.uniform(0.85, 1.15)};
  a.white_balance_drift = 0.03;
  a.gamma = rng.uniform(0.85, 1.2);
  a.color_jitter_gain = 0.12;
  a.color_jitter_offset = 0.03;
  a.vignetting = 0.5;
  a.shot_noise = 0.02;
  a.read_noise = 0.004;
  a.motion_blur_subframes = 3;
  a.exposure_time_s = indoor ? 0.015 : 0.008;
  if (!indoor) a.sky = std::array<double, 3>{0.45, 0.6, 0.85};
  return a;
}

}  // namespace vkloc
