// Level-of-detail index buffers per model block, chosen per view by screen-space error.
#pragma once

#include <cstdint>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc::engine {

/// One indexed draw: a run of triangles with one material.
struct LodDraw {
  uint32_t first_index = 0;
  uint32_t index_count = 0;
  int material = 0;
};

/// One detail level of a block: its draws and the largest distance (metres) between the
/// simplified surface and the full-detail one.
struct LodLevel {
  uint32_t first_draw = 0;
  uint32_t draw_count = 0;
  uint32_t triangles = 0;
  double error_m = 0.0;
};

struct LodBlock {
  Aabb bounds;                   ///< World frame, metres.
  std::vector<LodLevel> levels;  ///< levels[0] is full detail; error grows with the index.
};

/// All blocks' levels. `indices` holds the full-detail triangles (vertex-cache ordered) first,
/// then every simplified level.
struct LodModel {
  std::vector<uint32_t> indices;
  std::vector<LodDraw> draws;
  std::vector<LodBlock> blocks;
};

/// Builds full-detail draws for every block and, when `max_levels` > 0, up to that many
/// simplified levels per block (each about a quarter of the previous one's triangles, with
/// the borders of every draw range locked so neighbouring blocks and materials never crack).
LodModel buildLodModel(const Model& model, int max_levels);

/// Index of the coarsest level of `block` whose geometric error, seen at camera depth
/// `depth_m` (the block's nearest), stays within `max_error_px` pixels; 0 when max_error_px
/// <= 0 or depth_m <= 0 (the block reaches the camera plane).
int selectLodLevel(const LodBlock& block, double depth_m, double pixels_per_metre_at_1m, double max_error_px);

/// Smallest camera-frame z (metres) of the box's corners: a lower bound of its points' depth.
double minDepthOfBox(const Aabb& box, const Pose& T_camera_world);

/// Upper bound of the pixels that one metre perpendicular to a ray at 1 m depth spans anywhere
/// in the image (focal length, enlarged for off-axis rays).
double lodPixelsPerMetre(const PinholeCamera& camera);

}  // namespace vkloc::engine
