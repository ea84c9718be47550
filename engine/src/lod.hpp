// Level-of-detail index buffers per model block, chosen per view by screen-space error.
#pragma once

#include <cstdint>
#include <vector>

#include "vkloc/model.hpp"

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

/// Index of the coarsest level of `block` whose geometric error, seen from `distance_m` with
/// focal length `focal_px`, stays within `max_error_px` pixels; 0 when max_error_px <= 0.
int selectLodLevel(const LodBlock& block, double distance_m, double focal_px, double max_error_px);

/// Distance (metres) from a point to an axis-aligned box; 0 inside.
double distanceToBox(const Aabb& box, const double p[3]);

}  // namespace vkloc::engine
