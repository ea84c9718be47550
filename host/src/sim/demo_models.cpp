// Built-in demo models: a city block seen from a drone and an indoor room, generated in code.
//
// Everything is deterministic: random choices come from a splitmix64 generator seeded with
// DemoModelOptions::seed, textures are drawn with OpenCV primitives plus hash noise, and no
// standard-library distribution (whose output differs between implementations) is used.
//
// Geometry is emitted as planar quads (plus a few triangles). Solids are closed and never
// overlap or touch with coincident faces: objects standing on a surface float 2 mm above it,
// buildings stand on ground that is cut out under their footprint. Quads whose edges are
// axis-aligned are split on a world-aligned grid when a triangle target is set, so that
// neighbouring faces get the same split points and stay watertight.
#include "vkloc/sim/demo_models.hpp"

#include "sim/demo_internal.hpp"
#include "vkloc/core/pose.hpp"

namespace vkloc {

using demo_detail::kPi;

Result<Model> makeDemoModel(const std::string& name, const DemoModelOptions& options) {
  if (options.texture_size < 16 || options.texture_size > 4096)
    return makeError(ErrorCode::kInvalidArgument,
                     "demo model texture_size " + std::to_string(options.texture_size) + " is outside 16..4096");
  if (name == "city") return makeDemoCity(options);
  if (name == "room") return makeDemoRoom(options);
  return makeError(ErrorCode::kNotFound, "unknown demo model '" + name + "'; available: city, room");
}

std::vector<Pose> demoViewpoints(const std::string& name) {
  struct View {
    double ex, ey, ez, tx, ty, tz;
  };
  std::vector<View> views;
  if (name == "city") {
    // Drone views tilted 45 degrees down; eyes below the roof-tops stay over the streets.
    auto drone = [&](double x, double y, double altitude, double yaw_deg) {
      const double yaw = yaw_deg * kPi / 180;
      views.push_back({x, y, altitude, x + altitude * std::cos(yaw), y + altitude * std::sin(yaw), 0});
    };
    drone(1.0, -45.0, 10, 90);
    drone(-66.0, -25.0, 20, 0);
    drone(25.0, 0.5, 30, 180);
    drone(66.0, 40.0, 45, 225);
    drone(-60.0, -60.0, 60, 45);
    drone(0.0, 70.0, 60, -90);
  } else if (name == "room") {
    views = {{2.3, 1.6, 1.5, -2.0, -1.0, 1.0},
             {2.4, -1.0, 1.5, -3.0, 0.0, 1.2},
             {-0.5, -1.8, 1.5, -0.8, 2.5, 1.3},
             {-2.0, 1.8, 1.5, -0.2, -2.5, 1.2},
             {0.3, 1.9, 1.5, 2.6, -2.2, 0.6}};
  }
  std::vector<Pose> poses;
  for (const View& v : views) {
    Result<Pose> T = lookAt(Eigen::Vector3d(v.ex, v.ey, v.ez), Eigen::Vector3d(v.tx, v.ty, v.tz));
    if (T.ok()) poses.push_back(*T);
  }
  return poses;
}

}  // namespace vkloc
