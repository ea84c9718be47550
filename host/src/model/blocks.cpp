// Spatial blocks: a median-split tree over triangle centroids, flattened into contiguous
// index ranges.
#include <algorithm>
#include <cmath>

#include "model/model_internal.hpp"

namespace vkloc {
namespace {

// A triangle's centroid and its index in the original order; 16 bytes so that the split's
// partitioning moves compact records rather than chasing indices.
struct Centroid {
  float c[3];
  uint32_t triangle;
};

class BlockSplitter {
 public:
  BlockSplitter(std::vector<Centroid>& items, uint32_t max_triangles) : items_(items), max_(max_triangles) {}

  // Splits items_[begin, end) at the median centroid along the longest axis of the centroids'
  // bounds until each part holds at most max_ triangles; appends the parts in tree order.
  // Ties on the axis are broken by triangle index, so the parts do not depend on how
  // nth_element orders equal keys: the result is deterministic.
  void split(size_t begin, size_t end) {
    if (max_ == 0 || end - begin <= max_) {
      leaves_.push_back({begin, end});
      return;
    }
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = begin; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], items_[i].c[k]);
        hi[k] = std::max(hi[k], items_[i].c[k]);
      }
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k) {
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    }
    const size_t mid = begin + (end - begin) / 2;
    std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end,
                     [axis](const Centroid& a, const Centroid& b) {
                       return a.c[axis] < b.c[axis] || (a.c[axis] == b.c[axis] && a.triangle < b.triangle);
                     });
    split(begin, mid);
    split(mid, end);
  }

  const std::vector<std::pair<size_t, size_t>>& leaves() const { return leaves_; }

 private:
  std::vector<Centroid>& items_;
  uint32_t max_;
  std::vector<std::pair<size_t, size_t>> leaves_;
};

void extendByTriangle(Aabb& box, const Model& model, const uint32_t* corners) {
  const size_t n = model.vertexCount();
  for (int j = 0; j < 3; ++j) {
    if (corners[j] < n) box.extend(&model.positions[3 * size_t{corners[j]}]);
  }
}

void extendBox(Aabb& box, const Aabb& other) {
  if (other.empty()) return;
  box.extend(other.min.data());
  box.extend(other.max.data());
}

}  // namespace

namespace model_detail {

void updateBounds(Model& model) {
  model.bounds = Aabb{};
  if (model.blocks.empty()) {
    for (size_t t = 0; t + 2 < model.indices.size(); t += 3) {
      extendByTriangle(model.bounds, model, &model.indices[t]);
    }
    return;
  }
  for (Block& block : model.blocks) {
    block.bounds = Aabb{};
    const uint64_t last = std::min<uint64_t>(uint64_t{block.first_range} + block.range_count, model.ranges.size());
    for (uint64_t r = block.first_range; r < last; ++r) {
      const DrawRange& range = model.ranges[r];
      const uint64_t end = std::min<uint64_t>(uint64_t{range.first_index} + range.index_count, model.indices.size());
      for (uint64_t i = range.first_index; i + 2 < end; i += 3) {
        extendByTriangle(block.bounds, model, &model.indices[i]);
      }
    }
    extendBox(model.bounds, block.bounds);
  }
}

}  // namespace model_detail

void buildBlocks(Model& model, uint32_t max_block_triangles) {
  const size_t triangles = model.triangleCount();
  const size_t vertices = model.vertexCount();

  // Material per triangle from the current ranges (later ranges win; uncovered: material 0).
  std::vector<int> material(triangles, 0);
  for (const DrawRange& r : model.ranges) {
    const uint64_t first = r.first_index / 3;
    const uint64_t last = std::min<uint64_t>((uint64_t{r.first_index} + r.index_count) / 3, triangles);
    for (uint64_t t = first; t < last; ++t) material[t] = r.material;
  }

  // Centroids; corners out of range or non-finite coordinates count as 0 so that the split's
  // ordering stays a strict weak order whatever the input.
  std::vector<Centroid> items(triangles);
  for (size_t t = 0; t < triangles; ++t) {
    Centroid& item = items[t];
    item.triangle = static_cast<uint32_t>(t);
    for (int k = 0; k < 3; ++k) {
      float sum = 0.0f;
      for (int j = 0; j < 3; ++j) {
        const uint32_t v = model.indices[3 * t + j];
        if (v < vertices) sum += model.positions[3 * size_t{v} + k];
      }
      item.c[k] = std::isfinite(sum) ? sum / 3.0f : 0.0f;
    }
  }
  BlockSplitter splitter(items, max_block_triangles);
  if (triangles > 0) splitter.split(0, triangles);

  // Within a block, order triangles by material, then original order (sorting 64-bit keys
  // (material with its sign bit flipped, triangle) is much faster than comparing through the
  // material table), and emit one range per run of equal material.
  std::vector<uint32_t> indices(model.indices.size());
  std::vector<uint64_t> keys;
  model.ranges.clear();
  model.blocks.clear();
  for (const auto& [begin, end] : splitter.leaves()) {
    keys.clear();
    for (size_t i = begin; i < end; ++i) {
      const uint32_t t = items[i].triangle;
      keys.push_back((uint64_t{static_cast<uint32_t>(material[t]) ^ 0x80000000u} << 32) | t);
    }
    std::sort(keys.begin(), keys.end());
    Block block;
    block.first_range = static_cast<uint32_t>(model.ranges.size());
    block.triangle_count = static_cast<uint32_t>(end - begin);
    for (size_t k = 0; k < keys.size(); ++k) {
      const uint32_t t = static_cast<uint32_t>(keys[k]);
      const size_t i = begin + k;
      std::copy_n(&model.indices[3 * size_t{t}], 3, &indices[3 * i]);
      if (k == 0 || (keys[k] >> 32) != (keys[k - 1] >> 32)) {
        model.ranges.push_back(DrawRange{static_cast<uint32_t>(3 * i), 0, material[t]});
      }
      model.ranges.back().index_count += 3;
    }
    block.range_count = static_cast<uint32_t>(model.ranges.size()) - block.first_range;
    model.blocks.push_back(block);
  }
  model.indices.swap(indices);
  model_detail::updateBounds(model);
}

}  // namespace vkloc
