// vkloc: the triangle-mesh model that vkloc renders and localizes against.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/status.hpp"

namespace vkloc {

/// An axis-aligned box in the world frame, metres. Empty when min > max.
struct Aabb {
  std::array<float, 3> min{1e30f, 1e30f, 1e30f};
  std::array<float, 3> max{-1e30f, -1e30f, -1e30f};
  bool empty() const { return min[0] > max[0]; }
  void extend(const float p[3]) {
    for (int i = 0; i < 3; ++i) {
      min[i] = p[i] < min[i] ? p[i] : min[i];
      max[i] = p[i] > max[i] ? p[i] : max[i];
    }
  }
};

/// An RGBA8 texture, rows top to bottom, 4 bytes per pixel.
struct Texture {
  std::string name;           ///< Source file or embedded name, for messages.
  int width = 0;              ///< Pixels.
  int height = 0;             ///< Pixels.
  std::vector<uint8_t> rgba;  ///< width * height * 4 bytes.
};

/// Surface appearance of a group of triangles.
struct Material {
  std::string name;
  /// Base colour, linear 0..1 RGBA; multiplies the texture and the vertex colour.
  std::array<float, 4> base_color{0.8f, 0.8f, 0.8f, 1.0f};
  int texture = -1;  ///< Index into Model::textures, or -1 for none.
};

/// A contiguous range of Model::indices (whole triangles) drawn with one material.
struct DrawRange {
  uint32_t first_index = 0;  ///< Offset into Model::indices (multiple of 3).
  uint32_t index_count = 0;  ///< Multiple of 3.
  int material = 0;          ///< Index into Model::materials.
};

/// A spatial block of the model: a set of draw ranges and their world bounds. Triangles belong
/// to exactly one block (by centroid); bounds enclose whole triangles, so neighbouring blocks'
/// bounds overlap, as the overlapping blocks of seed 000 §III do.
struct Block {
  Aabb bounds;               ///< World frame, metres.
  uint32_t first_range = 0;  ///< Offset into Model::ranges.
  uint32_t range_count = 0;
  uint32_t triangle_count = 0;
};

/// A triangle mesh in the world frame (model transform and unit scale already applied).
///
/// Vertex attributes are stored as separate arrays of equal length (positions.size() / 3).
/// `uvs` and `colors` may be empty when the source has none. Texture coordinates follow the
/// Vulkan/glTF convention: (0, 0) is the top-left of the texture image.
struct Model {
  std::string source;               ///< File the model came from, for messages.
  std::vector<float> positions;     ///< x, y, z per vertex, world frame, metres.
  std::vector<float> uvs;           ///< u, v per vertex, or empty.
  std::vector<uint8_t> colors;      ///< RGBA8 per vertex (sRGB-encoded as stored), or empty.
  std::vector<uint32_t> indices;    ///< 3 per triangle, counter-clockwise seen from outside.
  std::vector<Material> materials;  ///< At least one after loading.
  std::vector<Texture> textures;
  std::vector<DrawRange> ranges;  ///< Sorted by block, then material.
  std::vector<Block> blocks;      ///< At least one after loading (may be the whole model).
  Aabb bounds;                    ///< World frame, metres.

  size_t vertexCount() const { return positions.size() / 3; }
  size_t triangleCount() const { return indices.size() / 3; }
};

/// How a model file is placed in the world and split into blocks.
struct ModelLoadOptions {
  /// Model-to-world transform, row-major 4x4 rigid (or similarity) matrix applied after
  /// `unit_scale`: p_world = T_world_model * (unit_scale * p_model).
  std::array<double, 16> T_world_model{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  /// Metres per model unit (e.g. 0.001 for a model in millimetres).
  double unit_scale = 1.0;
  /// Target maximum triangles per spatial block; blocks are split along their longest axis at
  /// the median centroid until at or below this. 0 keeps one block.
  uint32_t max_block_triangles = 32768;
};

/// Loads a mesh model. Formats, chosen by extension (case-insensitive) and checked by content:
///  - .obj (+ .mtl, textures), .ply (vertex colours), .gltf / .glb (embedded or external
///    textures), and what else assimp reads;
///  - .drc (Draco) and glTF/GLB primitives using KHR_draco_mesh_compression;
///  - .cao (ViSP CAD models, untextured; see visp.hpp).
/// Returns kNotFound for a missing file, kMalformedInput for truncated or garbage bytes, empty
/// meshes, NaN/inf vertices or out-of-range indices, kUnsupported for unknown formats; every
/// message names the file. A missing texture is a warning (see `warnings`), not an error: the
/// material renders with its base colour.
Result<Model> loadModel(const std::string& path, const ModelLoadOptions& options = {},
                        std::vector<std::string>* warnings = nullptr);

/// Checks a model's invariants: finite positions, indices in range, attribute sizes, ranges
/// and blocks covering every triangle once, materials and textures referenced exist.
Status validateModel(const Model& model);

/// Reorders triangles into spatial blocks (median split on the longest axis) and rebuilds
/// `ranges`, `blocks` and `bounds`. Per-triangle materials are taken from the current ranges.
void buildBlocks(Model& model, uint32_t max_block_triangles);

/// Applies p_world = T_world_model * (unit_scale * p) to every vertex position.
void transformModel(Model& model, const std::array<double, 16>& T_world_model, double unit_scale);

}  // namespace vkloc
