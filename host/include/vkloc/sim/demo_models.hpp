// vkloc: built-in demo models, generated in code, for examples, tests and benchmarks.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {

/// How a demo model is generated.
struct DemoModelOptions {
  /// Same seed -> bit-identical model (for a given build); another seed varies the layout,
  /// sizes, colours and texture details.
  uint32_t seed = 1;
  /// 0 = natural size; otherwise axis-aligned walls, roofs and ground are split on a world grid
  /// (so neighbouring faces stay crack-free) whose spacing is chosen to bring the total triangle
  /// count within +-10% of this. Targets below the natural size give the natural model.
  uint32_t target_triangles = 0;
  int texture_size = 256;  ///< Side of each generated square texture, pixels (16..4096).
};

/// A textured urban block in the world frame (z up, metres, ground at z = 0 over about
/// [-100, 100] x [-100, 100]): streets with lane markings, zebra crossings and raised kerbs,
/// 15 to 30 buildings (boxes, L shapes, set-back upper storeys, flat or gable roofs) 6 to 60 m
/// tall with window-grid facades, parking lots with cars, parks with trees. Triangles are
/// counter-clockwise seen from outside, so back-face culling is valid; every solid is closed
/// (standing on the ground, which is cut under buildings). Vertex colours tint buildings and cars.
/// An invalid texture_size is clamped to 16..4096.
Model makeDemoCity(const DemoModelOptions& options = {});

/// A textured room, about 6 x 5 x 3 m (x in [-3, 3], y in [-2.5, 2.5], floor at z = 0), seen
/// from inside: wood floor, painted walls with a door, a window, posters and a whiteboard, a
/// tiled ceiling with lights, a table with chairs, a bookcase with books, a couch, a rug and
/// boxes. Triangles are counter-clockwise seen from the room. texture_size is clamped as above.
Model makeDemoRoom(const DemoModelOptions& options = {});

/// Names accepted by makeDemoModel and demoViewpoints.
std::vector<std::string> demoModelNames();

/// Builds the demo called `name` ("city" or "room"). Returns kNotFound for another name and
/// kInvalidArgument for a texture_size outside 16..4096.
Result<Model> makeDemoModel(const std::string& name, const DemoModelOptions& options = {});

/// A few camera poses T_world_camera (camera x right, y down, z forward) that look at the demo
/// `name`: drone views tilted 45 degrees down from 10 to 60 m altitude for "city", handheld
/// views at 1.5 m height for "room". Empty for an unknown name. The poses do not depend on the
/// seed.
std::vector<Pose> demoViewpoints(const std::string& name);

}  // namespace vkloc
