// Model damage for simulated sequences: clustered holes and simplification, as the models that
// reconstructions produce differ from the world.
#include <fmt/format.h>
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "vkloc/core/random.hpp"
#include "vkloc/sim/simulate.hpp"

namespace vkloc {
namespace {

using Rng = Xoshiro256;

constexpr uint32_t kBlockTriangles = 32768;

/// Material of every triangle, from the draw ranges.
std::vector<int> triangleMaterials(const Model& model) {
  std::vector<int> material(model.triangleCount(), 0);
  for (const DrawRange& r : model.ranges) {
    for (uint32_t k = 0; k < r.index_count / 3; ++k) {
      const size_t tri = r.first_index / 3 + k;
      if (tri < material.size()) material[tri] = r.material;
    }
  }
  return material;
}

/// A model with the given triangles (old vertex indices grouped by material), unused vertices
/// dropped, blocks rebuilt.
Model rebuildFromGroups(const Model& model, const std::vector<std::vector<uint32_t>>& by_material) {
  Model out;
  out.source = model.source;
  out.materials = model.materials;
  out.textures = model.textures;
  std::vector<uint32_t> remap(model.vertexCount(), UINT32_MAX);
  const bool has_uv = !model.uvs.empty();
  const bool has_color = !model.colors.empty();
  for (size_t m = 0; m < by_material.size(); ++m) {
    if (by_material[m].empty()) continue;
    DrawRange range;
    range.first_index = static_cast<uint32_t>(out.indices.size());
    range.index_count = static_cast<uint32_t>(by_material[m].size());
    range.material = static_cast<int>(m);
    for (uint32_t old : by_material[m]) {
      if (remap[old] == UINT32_MAX) {
        remap[old] = static_cast<uint32_t>(out.positions.size() / 3);
        out.positions.insert(out.positions.end(), &model.positions[3 * old], &model.positions[3 * old] + 3);
        if (has_uv) out.uvs.insert(out.uvs.end(), &model.uvs[2 * old], &model.uvs[2 * old] + 2);
        if (has_color) out.colors.insert(out.colors.end(), &model.colors[4 * old], &model.colors[4 * old] + 4);
      }
      out.indices.push_back(remap[old]);
    }
    out.ranges.push_back(range);
  }
  if (out.materials.empty()) out.materials.push_back(Material{});
  buildBlocks(out, kBlockTriangles);
  return out;
}

std::vector<std::vector<uint32_t>> groupByMaterial(const Model& model, const std::vector<uint32_t>& triangles) {
  const std::vector<int> materials = triangleMaterials(model);
  std::vector<std::vector<uint32_t>> by_material(std::max<size_t>(model.materials.size(), 1));
  for (uint32_t tri : triangles) {
    const size_t m = std::min(static_cast<size_t>(std::max(materials[tri], 0)), by_material.size() - 1);
    const uint32_t* c = &model.indices[3 * static_cast<size_t>(tri)];
    by_material[m].insert(by_material[m].end(), c, c + 3);
  }
  return by_material;
}

}  // namespace

Result<Model> punchHoles(const Model& model, double fraction, double radius_m, uint64_t seed, DamageReport* report,
                         std::vector<uint32_t>* removed_out) {
  if (!(fraction >= 0.0 && fraction <= 0.9)) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("hole fraction {} is outside 0..0.9", fraction));
  }
  if (!(radius_m >= 0.0) || !std::isfinite(radius_m)) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("hole radius {} m must be finite and >= 0", radius_m));
  }
  VKLOC_TRY_STATUS(validateModel(model));
  const size_t n = model.triangleCount();
  std::vector<double> area(n);
  std::vector<Eigen::Vector3d> centroid(n);
  double total = 0.0;
  for (size_t t = 0; t < n; ++t) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) {
      const float* q = &model.positions[3 * static_cast<size_t>(model.indices[3 * t + k])];
      p[k] = Eigen::Vector3d(q[0], q[1], q[2]);
    }
    area[t] = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm();
    centroid[t] = (p[0] + p[1] + p[2]) / 3.0;
    total += area[t];
  }
  if (radius_m == 0.0) {
    const Eigen::Vector3d lo(model.bounds.min[0], model.bounds.min[1], model.bounds.min[2]);
    const Eigen::Vector3d hi(model.bounds.max[0], model.bounds.max[1], model.bounds.max[2]);
    radius_m = model.bounds.empty() ? 1.0 : std::max(0.02 * (hi - lo).norm(), 1e-6);
  }
  const double target = fraction * total;
  std::vector<char> removed(n, 0);
  double removed_area = 0.0;
  size_t patches = 0;
  Rng rng(subSeed(seed, 0x686f6c6573ull));
  // Cumulative area for area-weighted seeds.
  std::vector<double> cumulative(n);
  std::partial_sum(area.begin(), area.end(), cumulative.begin());
  std::vector<std::pair<double, uint32_t>> candidates;
  size_t failed_seeds = 0;
  while (target > 0.0 && removed_area < target && total > 0.0 && failed_seeds < 1000) {
    const double pick = rng.uniform() * total;
    const size_t seed_tri = std::min(
        static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin()), n - 1);
    const double r = radius_m * rng.uniform(0.5, 1.5);
    if (removed[seed_tri]) {
      ++failed_seeds;
      continue;
    }
    // The patch: remaining triangles whose centroid lies within r of the seed's, nearest first.
    candidates.clear();
    const Eigen::Vector3d c0 = centroid[seed_tri];
    for (size_t t = 0; t < n; ++t) {
      if (removed[t]) continue;
      const double d2 = (centroid[t] - c0).squaredNorm();
      if (d2 <= r * r || t == seed_tri) candidates.emplace_back(d2, static_cast<uint32_t>(t));
    }
    std::sort(candidates.begin(), candidates.end());
    bool took = false;
    for (const auto& [d2, t] : candidates) {
      const double missing = target - removed_area;
      if (missing <= 0.0) break;
      // Take a triangle when it fits, or when it overshoots by less than leaving it out would
      // miss and by less than 0.5 % of the total area.
      if (area[t] <= missing || area[t] - missing < std::min(missing, 0.005 * total)) {
        removed[t] = 1;
        removed_area += area[t];
        took = true;
      }
    }
    if (took) {
      ++patches;
      failed_seeds = 0;
    } else {
      ++failed_seeds;
    }
  }
  std::vector<uint32_t> kept;
  kept.reserve(n);
  if (removed_out) removed_out->clear();
  for (size_t t = 0; t < n; ++t) {
    if (!removed[t]) {
      kept.push_back(static_cast<uint32_t>(t));
    } else if (removed_out) {
      removed_out->push_back(static_cast<uint32_t>(t));
    }
  }
  if (kept.empty()) return makeError(ErrorCode::kInvalidArgument, "punching holes removed every triangle");
  Model out = rebuildFromGroups(model, groupByMaterial(model, kept));
  if (report) {
    report->triangles_before = n;
    report->triangles_after = out.triangleCount();
    report->removed_area_fraction = total > 0.0 ? removed_area / total : 0.0;
    report->hole_patches = patches;
  }
  return out;
}

Result<Model> simplifyModel(const Model& model, double ratio, uint32_t max_block_triangles) {
  if (!(ratio > 0.0 && ratio <= 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("simplify ratio {} is outside (0, 1]", ratio));
  }
  VKLOC_TRY_STATUS(validateModel(model));
  std::vector<uint32_t> all(model.triangleCount());
  std::iota(all.begin(), all.end(), 0u);
  std::vector<std::vector<uint32_t>> groups = groupByMaterial(model, all);
  if (ratio < 1.0) {
    const size_t nv = model.vertexCount();
    for (auto& indices : groups) {
      if (indices.size() < 3) continue;
      const size_t target = std::max<size_t>(3, static_cast<size_t>(std::llround(indices.size() / 3 * ratio)) * 3);
      std::vector<uint32_t> out(indices.size());
      float error = 0.0f;
      size_t count = meshopt_simplify(out.data(), indices.data(), indices.size(), model.positions.data(), nv,
                                      3 * sizeof(float), target, 0.05f, 0, &error);
      if (count > target + target / 10) {
        count = meshopt_simplifySloppy(out.data(), indices.data(), indices.size(), model.positions.data(), nv,
                                       3 * sizeof(float), target, 1.0f, &error);
      }
      out.resize(count);
      indices = std::move(out);
    }
  }
  Model out = rebuildFromGroups(model, groups);
  if (out.indices.empty()) return makeError(ErrorCode::kInvalidArgument, "simplification removed every triangle");
  if (max_block_triangles != kBlockTriangles) buildBlocks(out, max_block_triangles);
  return out;
}

Result<Model> damageModel(const Model& model, const DamageOptions& options, uint64_t seed, DamageReport* report) {
  DamageReport local;
  local.triangles_before = model.triangleCount();
  Model current = model;
  if (options.hole_fraction > 0.0) {
    auto holed = punchHoles(model, options.hole_fraction, options.hole_radius_m, seed, &local);
    if (!holed.ok()) return holed.error();
    current = std::move(holed).value();
  }
  if (options.simplify_ratio != 1.0) {
    auto simple = simplifyModel(current, options.simplify_ratio);
    if (!simple.ok()) return simple.error();
    current = std::move(simple).value();
  }
  local.triangles_after = current.triangleCount();
  if (report) *report = local;
  return current;
}

}  // namespace vkloc
