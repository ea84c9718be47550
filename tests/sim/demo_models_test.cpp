// Tests of the built-in demo models: determinism, validity, triangle targets, winding, views.
#include "vkloc/sim/demo_models.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {
namespace {

using Eigen::Vector3d;

Vector3d vertex(const Model& m, uint32_t i) {
  return Vector3d(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
}

bool sameAabb(const Aabb& a, const Aabb& b) { return a.min == b.min && a.max == b.max; }

/// Field-by-field equality, bit for bit.
void expectIdentical(const Model& a, const Model& b) {
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.uvs, b.uvs);
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.indices, b.indices);
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (size_t i = 0; i < a.materials.size(); ++i) {
    EXPECT_EQ(a.materials[i].name, b.materials[i].name);
    EXPECT_EQ(a.materials[i].base_color, b.materials[i].base_color);
    EXPECT_EQ(a.materials[i].texture, b.materials[i].texture);
  }
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (size_t i = 0; i < a.textures.size(); ++i) {
    EXPECT_EQ(a.textures[i].width, b.textures[i].width);
    EXPECT_EQ(a.textures[i].rgba, b.textures[i].rgba) << a.textures[i].name;
  }
  ASSERT_EQ(a.ranges.size(), b.ranges.size());
  for (size_t i = 0; i < a.ranges.size(); ++i) {
    EXPECT_EQ(a.ranges[i].first_index, b.ranges[i].first_index);
    EXPECT_EQ(a.ranges[i].index_count, b.ranges[i].index_count);
    EXPECT_EQ(a.ranges[i].material, b.ranges[i].material);
  }
  ASSERT_EQ(a.blocks.size(), b.blocks.size());
  for (size_t i = 0; i < a.blocks.size(); ++i) EXPECT_TRUE(sameAabb(a.blocks[i].bounds, b.blocks[i].bounds));
  EXPECT_TRUE(sameAabb(a.bounds, b.bounds));
}

/// Counts crossings of the ray p + t d (t > 0) with the model's triangles. A nearly vertical
/// direction and a 2D grid over x, y keep it fast (plain arrays: it also runs in Debug builds).
/// Sets `ambiguous` when a hit lies within rounding of a triangle edge (the parity could then
/// be wrong).
class RayCounter {
 public:
  RayCounter(const Model& m, const Vector3d& dir, double cell) : cell_(cell) {
    const Vector3d d = dir.normalized();
    for (int k = 0; k < 3; ++k) dir_[k] = d[k];
    x0_ = m.bounds.min[0];
    y0_ = m.bounds.min[1];
    z1_ = m.bounds.max[2];
    nx_ = static_cast<int>((m.bounds.max[0] - x0_) / cell_) + 1;
    ny_ = static_cast<int>((m.bounds.max[1] - y0_) / cell_) + 1;
    grid_.resize(static_cast<size_t>(nx_) * ny_);
    tris_.resize(m.triangleCount());
    stamp_.assign(m.triangleCount(), 0);
    for (uint32_t t = 0; t < m.triangleCount(); ++t) {
      const Vector3d a = vertex(m, m.indices[3 * t]), b = vertex(m, m.indices[3 * t + 1]),
                     c = vertex(m, m.indices[3 * t + 2]);
      for (int k = 0; k < 3; ++k) tris_[t].a[k] = a[k], tris_[t].e1[k] = b[k] - a[k], tris_[t].e2[k] = c[k] - a[k];
      const double lo[2] = {std::min({a.x(), b.x(), c.x()}), std::min({a.y(), b.y(), c.y()})};
      const double hi[2] = {std::max({a.x(), b.x(), c.x()}), std::max({a.y(), b.y(), c.y()})};
      for (int j = cy(lo[1]); j <= cy(hi[1]); ++j)
        for (int i = cx(lo[0]); i <= cx(hi[0]); ++i) grid_[static_cast<size_t>(j) * nx_ + i].push_back(t);
    }
  }

  int crossings(const Vector3d& start, bool& ambiguous) {
    const double p[3] = {start.x(), start.y(), start.z()};
    const double len = std::max(0.0, (z1_ + 1 - p[2]) / dir_[2]);
    const double qx = p[0] + len * dir_[0], qy = p[1] + len * dir_[1];
    ++tick_;
    int count = 0;
    for (int j = cy(std::min(p[1], qy)); j <= cy(std::max(p[1], qy)); ++j) {
      for (int i = cx(std::min(p[0], qx)); i <= cx(std::max(p[0], qx)); ++i) {
        for (uint32_t t : grid_[static_cast<size_t>(j) * nx_ + i]) {
          if (stamp_[t] == tick_) continue;
          stamp_[t] = tick_;
          // Moller-Trumbore.
          const Tri& tri = tris_[t];
          double pv[3], tv[3], qv[3];
          cross3(dir_, tri.e2, pv);
          const double det = dot3(tri.e1, pv);
          if (std::abs(det) < 1e-14) continue;
          for (int k = 0; k < 3; ++k) tv[k] = p[k] - tri.a[k];
          const double u = dot3(tv, pv) / det;
          if (u < -1e-9 || u > 1 + 1e-9) continue;
          cross3(tv, tri.e1, qv);
          const double v = dot3(dir_, qv) / det;
          const double s = dot3(tri.e2, qv) / det;
          if (s <= 0 || v < -1e-9 || u + v > 1 + 1e-9) continue;
          if (u < 1e-9 || v < 1e-9 || u + v > 1 - 1e-9) ambiguous = true;
          ++count;
        }
      }
    }
    return count;
  }

 private:
  struct Tri {
    double a[3], e1[3], e2[3];
  };
  static void cross3(const double* a, const double* b, double* out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
  }
  static double dot3(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  int cx(double x) const { return std::clamp(static_cast<int>((x - x0_) / cell_), 0, nx_ - 1); }
  int cy(double y) const { return std::clamp(static_cast<int>((y - y0_) / cell_), 0, ny_ - 1); }

  double dir_[3] = {0, 0, 1};
  double cell_, x0_ = 0, y0_ = 0, z1_ = 0;
  int nx_ = 1, ny_ = 1;
  std::vector<Tri> tris_;
  std::vector<std::vector<uint32_t>> grid_;
  std::vector<uint32_t> stamp_;
  uint32_t tick_ = 0;
};

/// Checks every triangle's winding by ray parity: the point just in front of its centroid must
/// be in free space and the point just behind it inside a solid. `free_parity` is the parity
/// of crossings above a free-space point (0 in the open city, 1 inside the closed room).
/// Returns the number of triangles that fail.
int countWrongWinding(const Model& m, double cell, int free_parity, std::string* first_bad) {
  RayCounter rays_a(m, Vector3d(0.0123, 0.0371, 1), cell);
  RayCounter rays_b(m, Vector3d(-0.0291, 0.0173, 1), cell);
  const double eps = 5e-4;  // Loose objects float 2 mm above what they stand on.
  int bad = 0;
  for (uint32_t t = 0; t < m.triangleCount(); ++t) {
    const Vector3d a = vertex(m, m.indices[3 * t]), b = vertex(m, m.indices[3 * t + 1]),
                   c = vertex(m, m.indices[3 * t + 2]);
    const Vector3d n = (b - a).cross(c - a).normalized();
    const Vector3d centre = (a + b + c) / 3;
    for (int side = 0; side < 2; ++side) {
      const Vector3d p = centre + (side == 0 ? eps : -eps) * n;
      bool ambiguous = false;
      int k = rays_a.crossings(p, ambiguous);
      if (ambiguous) {
        ambiguous = false;
        k = rays_b.crossings(p, ambiguous);
      }
      const bool free = (k % 2) == free_parity;
      if (free != (side == 0)) {
        if (bad++ == 0 && first_bad) {
          *first_bad = "triangle " + std::to_string(t) + " centre (" + std::to_string(centre.x()) + ", " +
                       std::to_string(centre.y()) + ", " + std::to_string(centre.z()) + ") normal (" +
                       std::to_string(n.x()) + ", " + std::to_string(n.y()) + ", " + std::to_string(n.z()) + ") side " +
                       std::to_string(side);
        }
        break;
      }
    }
  }
  return bad;
}

/// Seeds 1..kExtraSeeds are checked by the property tests.
constexpr uint32_t kExtraSeeds = 3;

const Model& naturalCity() {
  static const Model m = makeDemoCity();
  return m;
}
const Model& naturalRoom() {
  static const Model m = makeDemoRoom();
  return m;
}

TEST(DemoModels, SameSeedGivesBitIdenticalModels) {
  expectIdentical(naturalCity(), makeDemoCity());
  expectIdentical(naturalRoom(), makeDemoRoom());
}

TEST(DemoModels, DifferentSeedGivesDifferentModels) {
  DemoModelOptions o;
  o.seed = 2;
  const Model city = makeDemoCity(o);
  const Model room = makeDemoRoom(o);
  EXPECT_NE(city.positions, naturalCity().positions);
  EXPECT_NE(room.positions, naturalRoom().positions);
  EXPECT_NE(city.textures[0].rgba, naturalCity().textures[0].rgba);
  EXPECT_TRUE(validateModel(city).ok());
  EXPECT_TRUE(validateModel(room).ok());
}

TEST(DemoModels, NaturalModelsAreValidAndTextured) {
  for (const Model* m : {&naturalCity(), &naturalRoom()}) {
    SCOPED_TRACE(m->source);
    const Status s = validateModel(*m);
    EXPECT_TRUE(s.ok()) << (s.ok() ? "" : s.error().message);
    EXPECT_EQ(m->uvs.size(), m->vertexCount() * 2);
    EXPECT_EQ(m->colors.size(), m->vertexCount() * 4);
    EXPECT_GE(m->blocks.size(), 1u);
    ASSERT_FALSE(m->materials.empty());
    for (const Material& mat : m->materials) {
      ASSERT_GE(mat.texture, 0) << mat.name;
      ASSERT_LT(mat.texture, static_cast<int>(m->textures.size())) << mat.name;
    }
    for (const Texture& t : m->textures) {
      EXPECT_EQ(t.width, 256) << t.name;
      EXPECT_EQ(t.height, 256) << t.name;
      EXPECT_EQ(t.rgba.size(), 256u * 256u * 4u) << t.name;
    }
    // Every material is used (no dead textures).
    std::set<int> used;
    for (const DrawRange& r : m->ranges) used.insert(r.material);
    EXPECT_EQ(used.size(), m->materials.size());
  }
  EXPECT_GE(naturalCity().triangleCount(), 2000u);
  EXPECT_LE(naturalCity().triangleCount(), 20000u);
  EXPECT_GE(naturalRoom().triangleCount(), 1000u);
  EXPECT_LE(naturalRoom().triangleCount(), 10000u);
}

TEST(DemoModels, BoundsArePlausible) {
  const Aabb& c = naturalCity().bounds;
  EXPECT_NEAR(c.min[0], -100, 1e-3);
  EXPECT_NEAR(c.min[1], -100, 1e-3);
  EXPECT_NEAR(c.max[0], 100, 1e-3);
  EXPECT_NEAR(c.max[1], 100, 1e-3);
  EXPECT_NEAR(c.min[2], -0.05, 1e-3);  // Kerb faces reach 5 cm below the road.
  EXPECT_GE(c.max[2], 40.0);           // At least one tower ...
  EXPECT_LE(c.max[2], 60.0);           // ... and nothing above 60 m.
  const Aabb& r = naturalRoom().bounds;
  EXPECT_NEAR(r.min[0], -3, 1e-3);
  EXPECT_NEAR(r.max[0], 3.12, 1e-3);  // The door recess.
  EXPECT_NEAR(r.min[1], -2.7, 1e-3);  // The window recess.
  EXPECT_NEAR(r.max[1], 2.5, 1e-3);
  EXPECT_NEAR(r.min[2], 0, 1e-6);
  EXPECT_NEAR(r.max[2], 3, 1e-6);
}

TEST(DemoModels, CityIsMostlyBuildingsAndStreets) {
  // Triangles per material family: facades, roofs and street surfaces are all present.
  const Model& m = naturalCity();
  std::set<std::string> families;
  for (const DrawRange& r : m.ranges) {
    const std::string& name = m.materials[r.material].name;
    families.insert(name.substr(0, name.find('_')));
  }
  for (const char* f : {"road", "junction", "sidewalk", "facade", "ground", "roof", "car"})
    EXPECT_TRUE(families.count(f)) << f;
}

TEST(DemoModels, TriangleTargetsAreMetWithinTenPercent) {
  for (uint32_t target : {10000u, 100000u}) {
    for (const char* name : {"city", "room"}) {
      DemoModelOptions o;
      o.target_triangles = target;
      o.texture_size = 16;  // Textures do not matter here; small ones keep the test fast.
      const Result<Model> m = makeDemoModel(name, o);
      ASSERT_TRUE(m.ok());
      SCOPED_TRACE(std::string(name) + " " + std::to_string(target));
      EXPECT_NEAR(static_cast<double>(m->triangleCount()), target, 0.1 * target);
      EXPECT_TRUE(validateModel(*m).ok());
    }
  }
  // Below the natural size the natural model comes back.
  DemoModelOptions small;
  small.target_triangles = 100;
  EXPECT_EQ(makeDemoRoom(small).triangleCount(), naturalRoom().triangleCount());
}

TEST(DemoModels, MillionTriangleCitySharesTextures) {
  DemoModelOptions o;
  o.target_triangles = 1000000;
  const Model m = makeDemoCity(o);
  EXPECT_NEAR(static_cast<double>(m.triangleCount()), 1e6, 1e5);
  EXPECT_EQ(m.textures.size(), naturalCity().textures.size());
  EXPECT_GE(m.blocks.size(), 30u);  // Split into blocks of at most 32768 triangles.
  for (const Block& b : m.blocks) EXPECT_LE(b.triangle_count, 32768u);
  for (int a = 0; a < 3; ++a) {
    EXPECT_FLOAT_EQ(m.bounds.min[a], naturalCity().bounds.min[a]);
    EXPECT_FLOAT_EQ(m.bounds.max[a], naturalCity().bounds.max[a]);
  }
}

TEST(DemoModels, CityTrianglesFaceOutwardAndUp) {
  for (uint32_t seed = 2; seed <= kExtraSeeds; ++seed) {
    DemoModelOptions o;
    o.seed = seed;
    o.texture_size = 16;
    std::string first;
    EXPECT_EQ(countWrongWinding(makeDemoCity(o), 2.0, 0, &first), 0) << "seed " << seed << ": " << first;
  }
  const Model& m = naturalCity();
  std::string first;
  EXPECT_EQ(countWrongWinding(m, 2.0, 0, &first), 0) << first;
  // By area, ground and roofs face up; only the undersides of tree crowns, cars and roof-top
  // units face down.
  double up = 0, down = 0;
  for (uint32_t t = 0; t < m.triangleCount(); ++t) {
    const Vector3d a = vertex(m, m.indices[3 * t]), b = vertex(m, m.indices[3 * t + 1]),
                   c = vertex(m, m.indices[3 * t + 2]);
    const Vector3d n = (b - a).cross(c - a);  // Twice the area.
    up += std::max(0.0, n.z());
    down += std::max(0.0, -n.z());
  }
  EXPECT_GT(up, 20 * down);
  EXPECT_NEAR(up / 2, 200.0 * 200.0, 0.05 * 200 * 200);  // The ground's area, seen from above.
}

TEST(DemoModels, RoomTrianglesFaceIntoTheRoom) {
  for (uint32_t seed = 1; seed <= kExtraSeeds; ++seed) {
    DemoModelOptions o;
    o.seed = seed;
    o.texture_size = 16;
    std::string first;
    EXPECT_EQ(countWrongWinding(makeDemoRoom(o), 0.1, 1, &first), 0) << "seed " << seed << ": " << first;
  }
}

/// Number of buildings: connected groups of ground-floor wall triangles (buildings stand at
/// least 3 m apart), joined through shared vertex positions.
size_t countBuildings(const Model& m) {
  std::vector<uint32_t> parent(m.vertexCount());
  for (uint32_t v = 0; v < parent.size(); ++v) parent[v] = v;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::map<std::array<long, 3>, uint32_t> by_position;
  std::set<uint32_t> walls;
  for (const DrawRange& r : m.ranges) {
    if (m.materials[r.material].name.rfind("ground_", 0) != 0) continue;
    for (uint32_t i = r.first_index; i < r.first_index + r.index_count; ++i) {
      const uint32_t v = m.indices[i];
      walls.insert(v);
      parent[find(v)] = find(m.indices[i - i % 3]);  // Join the triangle's corners.
      const std::array<long, 3> key{std::lround(m.positions[3 * v] * 100.0),
                                    std::lround(m.positions[3 * v + 1] * 100.0),
                                    std::lround(m.positions[3 * v + 2] * 100.0)};
      const auto [it, inserted] = by_position.emplace(key, v);
      if (!inserted) parent[find(v)] = find(it->second);
    }
  }
  std::set<uint32_t> roots;
  for (uint32_t v : walls) roots.insert(find(v));
  return roots.size();
}

TEST(DemoModels, CityHas15To30BuildingsUpTo60Metres) {
  for (uint32_t seed = 1; seed <= kExtraSeeds; ++seed) {
    DemoModelOptions o;
    o.seed = seed;
    o.texture_size = 16;
    const Model m = seed == 1 ? naturalCity() : makeDemoCity(o);
    const size_t n = countBuildings(m);
    EXPECT_GE(n, 15u) << "seed " << seed;
    EXPECT_LE(n, 30u) << "seed " << seed;
    EXPECT_LE(m.bounds.max[2], 60.0f) << "seed " << seed;
    EXPECT_GE(m.bounds.max[2], 40.0f) << "seed " << seed;
  }
}

TEST(DemoModels, WindingCheckCatchesFlippedTriangles) {
  for (const Model* original : {&naturalRoom(), &naturalCity()}) {
    Model m = *original;
    for (uint32_t t : {10u, 777u}) std::swap(m.indices[3 * t + 1], m.indices[3 * t + 2]);
    EXPECT_EQ(countWrongWinding(m, m.source == "demo:city" ? 2.0 : 0.1, m.source == "demo:city" ? 0 : 1, nullptr), 2)
        << m.source;
  }
}

TEST(DemoModels, ViewpointsLookAtTheModel) {
  for (const char* name : {"city", "room"}) {
    SCOPED_TRACE(name);
    const Model& m = std::string(name) == "city" ? naturalCity() : naturalRoom();
    const std::vector<Pose> poses = demoViewpoints(name);
    ASSERT_GE(poses.size(), 4u);
    const Vector3d centre(0.5 * (m.bounds.min[0] + m.bounds.max[0]), 0.5 * (m.bounds.min[1] + m.bounds.max[1]),
                          0.5 * (m.bounds.min[2] + m.bounds.max[2]));
    for (const Pose& T_world_camera : poses) {
      EXPECT_TRUE(isValidPose(T_world_camera));
      const Pose T_camera_world = T_world_camera.inverse();
      EXPECT_GT((T_camera_world * centre).z(), 0.0);
      // Camera y (down) points down in the world: the horizon is level, image upright.
      EXPECT_LT(T_world_camera.linear().col(1).z(), 0.0);
      // A 90-degree pinhole sees many vertices in front of it.
      int seen = 0;
      for (size_t i = 0; i < m.vertexCount(); ++i) {
        const Vector3d p = T_camera_world * vertex(m, static_cast<uint32_t>(i));
        seen += p.z() > 0.1 && std::abs(p.x()) < p.z() && std::abs(p.y()) < 0.75 * p.z();
      }
      EXPECT_GT(seen, 200);
      const Vector3d eye = T_world_camera.translation();
      if (std::string(name) == "city") {
        EXPECT_GE(eye.z(), 10.0 - 1e-9);
        EXPECT_LE(eye.z(), 60.0 + 1e-9);
        // 45 degrees down.
        EXPECT_NEAR(std::asin(-T_world_camera.linear().col(2).z()) * 180 / 3.14159265358979323846, 45.0, 1e-6);
      } else {
        EXPECT_NEAR(eye.z(), 1.5, 1e-9);
        EXPECT_LT(std::abs(eye.x()), 3.0);
        EXPECT_LT(std::abs(eye.y()), 2.5);
      }
    }
  }
  EXPECT_TRUE(demoViewpoints("castle").empty());
}

TEST(DemoModels, ByNameAndOptions) {
  const Result<Model> room = makeDemoModel("room");
  ASSERT_TRUE(room.ok());
  EXPECT_EQ(room->triangleCount(), naturalRoom().triangleCount());
  const Result<Model> unknown = makeDemoModel("castle");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kNotFound);
  EXPECT_NE(unknown.error().message.find("castle"), std::string::npos);
  DemoModelOptions bad;
  bad.texture_size = 0;
  const Result<Model> invalid = makeDemoModel("city", bad);
  ASSERT_FALSE(invalid.ok());
  EXPECT_EQ(invalid.error().code, ErrorCode::kInvalidArgument);
  DemoModelOptions small;
  small.texture_size = 64;
  const Model m = makeDemoRoom(small);
  for (const Texture& t : m.textures) EXPECT_EQ(t.width, 64);
  EXPECT_EQ(demoModelNames(), (std::vector<std::string>{"city", "room"}));
}

}  // namespace
}  // namespace vkloc
