#include "lod.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vkloc::engine {
namespace {

// Scratch for compacting one draw range's vertices before simplification.
struct Compactor {
  std::vector<uint32_t> global_to_local;
  std::vector<uint32_t> local_to_global;
  std::vector<float> positions;
  std::vector<uint32_t> local_indices;
  std::vector<uint32_t> simplified;
};

// Simplifies one range to about `target` indices with locked borders; appends the result (global
// vertex indices) to `out` and returns the geometric error in metres.
double simplifyRange(const uint32_t* idx, size_t count, const Model& model, size_t target, Compactor& c,
                     std::vector<uint32_t>& out) {
  c.local_to_global.clear();
  c.positions.clear();
  c.local_indices.resize(count);
  for (size_t i = 0; i < count; ++i) {
    uint32_t& slot = c.global_to_local[idx[i]];
    if (slot == UINT32_MAX) {
      slot = static_cast<uint32_t>(c.local_to_global.size());
      c.local_to_global.push_back(idx[i]);
      c.positions.insert(c.positions.end(), &model.positions[3 * size_t(idx[i])],
                         &model.positions[3 * size_t(idx[i])] + 3);
    }
    c.local_indices[i] = slot;
  }
  const size_t nv = c.local_to_global.size();
  c.simplified.resize(count);
  float rel_error = 0.0f;
  const size_t n = meshopt_simplify(c.simplified.data(), c.local_indices.data(), count, c.positions.data(), nv,
                                    3 * sizeof(float), target, 1.0f, meshopt_SimplifyLockBorder, &rel_error);
  const float scale = meshopt_simplifyScale(c.positions.data(), nv, 3 * sizeof(float));
  meshopt_optimizeVertexCache(c.simplified.data(), c.simplified.data(), n, nv);
  for (size_t i = 0; i < n; ++i) out.push_back(c.local_to_global[c.simplified[i]]);
  for (uint32_t g : c.local_to_global) c.global_to_local[g] = UINT32_MAX;
  return static_cast<double>(rel_error) * scale;
}

}  // namespace

LodModel buildLodModel(const Model& model, int max_levels) {
  LodModel lod;
  const size_t nv = model.vertexCount();
  lod.indices.resize(model.indices.size());
  for (const DrawRange& r : model.ranges) {
    meshopt_optimizeVertexCache(lod.indices.data() + r.first_index, model.indices.data() + r.first_index, r.index_count,
                                nv);
  }
  Compactor c;
  c.global_to_local.assign(nv, UINT32_MAX);
  for (const Block& b : model.blocks) {
    LodBlock block;
    block.bounds = b.bounds;
    LodLevel full;
    full.first_draw = static_cast<uint32_t>(lod.draws.size());
    for (uint32_t r = b.first_range; r < b.first_range + b.range_count; ++r) {
      const DrawRange& range = model.ranges[r];
      lod.draws.push_back({range.first_index, range.index_count, range.material});
      full.triangles += range.index_count / 3;
    }
    full.draw_count = static_cast<uint32_t>(lod.draws.size()) - full.first_draw;
    block.levels.push_back(full);
    for (int level = 1; level <= max_levels; ++level) {
      const LodLevel prev = block.levels.back();
      if (prev.triangles < 64) break;
      LodLevel next;
      next.first_draw = static_cast<uint32_t>(lod.draws.size());
      next.error_m = 0.0;
      const size_t indices_before = lod.indices.size();
      for (uint32_t d = prev.first_draw; d < prev.first_draw + prev.draw_count; ++d) {
        const LodDraw src = lod.draws[d];
        const size_t target = (src.index_count / 4) / 3 * 3;
        const auto first = static_cast<uint32_t>(lod.indices.size());
        const double err = simplifyRange(&lod.indices[src.first_index], src.index_count, model, target, c, lod.indices);
        const auto count = static_cast<uint32_t>(lod.indices.size()) - first;
        // Errors against full detail accumulate over successive simplifications.
        next.error_m = std::max(next.error_m, prev.error_m + err);
        next.triangles += count / 3;
        if (count > 0) lod.draws.push_back({first, count, src.material});
      }
      next.draw_count = static_cast<uint32_t>(lod.draws.size()) - next.first_draw;
      if (next.triangles * 10 > prev.triangles * 7) {
        // Less than 30 % fewer triangles: not worth a level; drop what was appended.
        lod.draws.resize(next.first_draw);
        lod.indices.resize(indices_before);
        break;
      }
      block.levels.push_back(next);
    }
    lod.blocks.push_back(std::move(block));
  }
  return lod;
}

int selectLodLevel(const LodBlock& block, double depth_m, double pixels_per_metre_at_1m, double max_error_px) {
  if (max_error_px <= 0.0 || depth_m <= 0.0) return 0;
  // A surface deviation of e metres at camera depth z projects to at most
  // e * pixels_per_metre_at_1m / z pixels.
  const double max_error_m = max_error_px * depth_m / pixels_per_metre_at_1m;
  int chosen = 0;
  for (size_t i = 1; i < block.levels.size(); ++i) {
    if (block.levels[i].error_m <= max_error_m) chosen = static_cast<int>(i);
  }
  return chosen;
}

double minDepthOfBox(const Aabb& box, const Pose& T_camera_world) {
  double z_min = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d p((i & 1) ? box.max[0] : box.min[0], (i & 2) ? box.max[1] : box.min[1],
                            (i & 4) ? box.max[2] : box.min[2]);
    z_min = std::min(z_min, (T_camera_world * p).z());
  }
  return z_min;
}

double lodPixelsPerMetre(const PinholeCamera& camera) {
  // f / z is the magnification on the optical axis; towards the image corners a displacement
  // perpendicular to the ray is magnified by up to 1 + r^2 / f^2 more (r: corner radius).
  const double f = std::max(camera.fx, camera.fy);
  const double du = std::max(camera.cx + 0.5, camera.width - 0.5 - camera.cx) / camera.fx;
  const double dv = std::max(camera.cy + 0.5, camera.height - 0.5 - camera.cy) / camera.fy;
  return f * (1.0 + du * du + dv * dv);
}

}  // namespace vkloc::engine
