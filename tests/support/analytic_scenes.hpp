// Test scenes with analytic ground truth: mesh builders (plane, box, UV sphere, textured quad)
// and exact ray intersections, for the CPU reference renderer's tests and the GPU renderer's.
//
// Every builder returns a valid vkloc::Model: triangles counter-clockwise seen from the front
// (outside), one material, one draw range and one block whose bounds enclose the mesh.
// Pixel rays use the pinhole convention of camera.hpp and are scaled so that the ray
// parameter t is the camera-frame z of the hit, i.e. directly comparable with rendered depth.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc::test {

/// Fills one draw range (material 0) over all triangles, one block and the model bounds, and
/// adds a default material when the model has none.
inline void finishSingleBlock(Model& m) {
  if (m.materials.empty()) m.materials.push_back(Material{"default", {1, 1, 1, 1}, -1});
  m.ranges = {DrawRange{0, static_cast<uint32_t>(m.indices.size()), 0}};
  Aabb bounds;
  for (size_t i = 0; i < m.vertexCount(); ++i) bounds.extend(&m.positions[3 * i]);
  Block block;
  block.bounds = bounds;
  block.first_range = 0;
  block.range_count = 1;
  block.triangle_count = static_cast<uint32_t>(m.triangleCount());
  m.blocks = {block};
  m.bounds = bounds;
}

/// Appends a vertex (position, uv, optional RGBA8 colour) and returns its index.
inline uint32_t addVertex(Model& m, const Eigen::Vector3d& p, const Eigen::Vector2d& uv = {0, 0}) {
  const auto index = static_cast<uint32_t>(m.vertexCount());
  for (int k = 0; k < 3; ++k) m.positions.push_back(static_cast<float>(p[k]));
  m.uvs.push_back(static_cast<float>(uv.x()));
  m.uvs.push_back(static_cast<float>(uv.y()));
  return index;
}

/// Appends the quad corner + s * edge_s + t * edge_t, s, t in [0, 1], as two triangles with
/// uv = (s, t). The front (counter-clockwise) side is the one `edge_t x edge_s` points to: a
/// camera looking at the front with edge_s pointing right and edge_t down in its image sees
/// uv (0, 0) at the top-left, as texture images are stored.
inline void appendQuad(Model& m, const Eigen::Vector3d& corner, const Eigen::Vector3d& edge_s,
                       const Eigen::Vector3d& edge_t) {
  const uint32_t v0 = addVertex(m, corner, {0, 0});
  const uint32_t v1 = addVertex(m, corner + edge_s, {1, 0});
  const uint32_t v2 = addVertex(m, corner + edge_s + edge_t, {1, 1});
  const uint32_t v3 = addVertex(m, corner + edge_t, {0, 1});
  // (v3 - v0) x (v2 - v0) = t x (s + t) = t x s, and (v2 - v0) x (v1 - v0) = t x s.
  m.indices.insert(m.indices.end(), {v0, v3, v2, v0, v2, v1});
}

/// A single quad (see appendQuad) with a white untextured material.
inline Model makeQuad(const Eigen::Vector3d& corner, const Eigen::Vector3d& edge_s, const Eigen::Vector3d& edge_t) {
  Model m;
  m.source = "analytic quad";
  appendQuad(m, corner, edge_s, edge_t);
  finishSingleBlock(m);
  return m;
}

/// Two orthonormal directions (s, t) spanning the plane with unit normal n, with t x s = n.
inline std::pair<Eigen::Vector3d, Eigen::Vector3d> planeAxes(const Eigen::Vector3d& n) {
  const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d s = helper.cross(n).normalized();
  const Eigen::Vector3d t = s.cross(n);  // (s x n) x s = n for unit s orthogonal to n.
  return {s, t};
}

/// A square of side 2 * half_size centred on `center` in the plane with normal `normal`
/// (world frame), front side towards `normal`, as two triangles.
inline Model makePlane(const Eigen::Vector3d& center, const Eigen::Vector3d& normal, double half_size) {
  const Eigen::Vector3d n = normal.normalized();
  const auto [s, t] = planeAxes(n);
  return makeQuad(center - half_size * (s + t), 2 * half_size * s, 2 * half_size * t);
}

/// An axis-aligned box [lo, hi] (world frame) as 12 triangles, counter-clockwise seen from
/// outside, 4 vertices per face with uv 0..1 on each face. open_top leaves out the +z face (a
/// hole: from above, the inside of the walls and of the floor is seen from behind).
inline Model makeBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, bool open_top = false) {
  Model m;
  m.source = "analytic box";
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      if (open_top && axis == 2 && side == 1) continue;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = side ? 1.0 : -1.0;
      // Face spanned by the two other axes; appendQuad's front t x s must point along n.
      const int a = (axis + 1) % 3;
      const int b = (axis + 2) % 3;
      Eigen::Vector3d corner = lo;
      corner[axis] = side ? hi[axis] : lo[axis];
      Eigen::Vector3d e_a = Eigen::Vector3d::Zero();
      Eigen::Vector3d e_b = Eigen::Vector3d::Zero();
      e_a[a] = hi[a] - lo[a];
      e_b[b] = hi[b] - lo[b];
      // unit(a) x unit(b) = unit(axis): (s, t) = (e_b, e_a) faces +axis, (e_a, e_b) -axis.
      if (side) {
        appendQuad(m, corner, e_b, e_a);
      } else {
        appendQuad(m, corner, e_a, e_b);
      }
    }
  }
  finishSingleBlock(m);
  return m;
}

/// A UV sphere: `stacks` rings from the +z pole to the -z pole, `slices` segments around z.
/// Vertices on the seam and at the poles share exact positions, so the mesh is watertight;
/// degenerate pole triangles are left out. uv = (slice / slices, stack / stacks).
inline Model makeUvSphere(const Eigen::Vector3d& center, double radius, int slices, int stacks) {
  Model m;
  m.source = "analytic uv sphere";
  const double pi = 3.14159265358979323846;
  for (int i = 0; i <= stacks; ++i) {
    const double theta = pi * i / stacks;
    for (int j = 0; j <= slices; ++j) {
      const double phi = 2 * pi * (j % slices) / slices;
      Eigen::Vector3d p(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
      if (i == 0) p = Eigen::Vector3d(0, 0, 1);
      if (i == stacks) p = Eigen::Vector3d(0, 0, -1);
      addVertex(m, center + radius * p, {static_cast<double>(j) / slices, static_cast<double>(i) / stacks});
    }
  }
  auto id = [&](int i, int j) { return static_cast<uint32_t>(i * (slices + 1) + j); };
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      // d/dtheta x d/dphi points outwards: (00, 10, 11) and (00, 11, 01).
      if (i != stacks - 1) m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      if (i != 0) m.indices.insert(m.indices.end(), {id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  finishSingleBlock(m);
  return m;
}

/// An RGBA8 checkerboard of n x n texels: texel (x, y) is `even` when x + y is even, else
/// `odd`.
inline Texture makeCheckerTexture(int n, std::array<uint8_t, 4> even, std::array<uint8_t, 4> odd) {
  Texture tex;
  tex.name = "checker";
  tex.width = n;
  tex.height = n;
  tex.rgba.resize(static_cast<size_t>(n) * n * 4);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const auto& c = (x + y) % 2 == 0 ? even : odd;
      std::copy(c.begin(), c.end(), &tex.rgba[(static_cast<size_t>(y) * n + x) * 4]);
    }
  }
  return tex;
}

/// A quad (see appendQuad) textured with a black/white n x n checkerboard (texel (0, 0)
/// black), white base colour, uv 0..1 over the quad.
inline Model makeCheckerQuad(const Eigen::Vector3d& corner, const Eigen::Vector3d& edge_s,
                             const Eigen::Vector3d& edge_t, int n = 8) {
  Model m = makeQuad(corner, edge_s, edge_t);
  m.source = "analytic checker quad";
  m.textures = {makeCheckerTexture(n, {0, 0, 0, 255}, {255, 255, 255, 255})};
  m.materials = {Material{"checker", {1, 1, 1, 1}, 0}};
  return m;
}

/// A size x size RGBA8 texture of 1-texel vertical stripes, black at even x and white at odd
/// x: mean 127.5 and all of its detail at the highest frequency, the worst case for aliasing.
inline Texture makeStripeTexture(int size) {
  Texture tex;
  tex.name = "stripes";
  tex.width = size;
  tex.height = size;
  tex.rgba.resize(static_cast<size_t>(size) * size * 4);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const uint8_t v = x % 2 == 0 ? 0 : 255;
      uint8_t* p = &tex.rgba[(static_cast<size_t>(y) * size + x) * 4];
      p[0] = p[1] = p[2] = v;
      p[3] = 255;
    }
  }
  return tex;
}

/// A size x size RGBA8 texture with detail at every scale: a checkerboard of 16-texel squares
/// in red, diagonal sine waves of periods 7 and 3 texels in green and blue, and hash noise.
inline Texture makeDetailTexture(int size) {
  Texture tex;
  tex.name = "detail";
  tex.width = size;
  tex.height = size;
  tex.rgba.resize(static_cast<size_t>(size) * size * 4);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      uint32_t h = static_cast<uint32_t>(x) * 73856093u ^ static_cast<uint32_t>(y) * 19349663u;
      h = (h ^ (h >> 13)) * 0x5bd1e995u;
      const double noise = static_cast<double>((h >> 8) & 63) - 32.0;
      uint8_t* p = &tex.rgba[(static_cast<size_t>(y) * size + x) * 4];
      const double r = ((x / 16 + y / 16) % 2 == 0 ? 40.0 : 215.0) + noise;
      const double g = 127.5 + 100.0 * std::sin(2 * M_PI * (x + y) / 7.0) + noise;
      const double b = 127.5 + 100.0 * std::sin(2 * M_PI * (x - 2 * y) / 3.0) - noise;
      p[0] = static_cast<uint8_t>(std::clamp(r, 0.0, 255.0));
      p[1] = static_cast<uint8_t>(std::clamp(g, 0.0, 255.0));
      p[2] = static_cast<uint8_t>(std::clamp(b, 0.0, 255.0));
      p[3] = 255;
    }
  }
  return tex;
}

/// A square of side 2 * half_size in the plane z = 0 centred on the origin, front side up
/// (+z), textured with `tex` repeated `repeats` times along each side (uv 0..repeats), white
/// base colour.
inline Model makeTexturedGround(double half_size, const Texture& tex, double repeats) {
  Model m = makeQuad({-half_size, half_size, 0}, {2 * half_size, 0, 0}, {0, -2 * half_size, 0});
  m.source = "analytic textured ground";
  for (float& uv : m.uvs) uv = static_cast<float>(uv * repeats);
  m.textures = {tex};
  m.materials = {Material{"ground", {1, 1, 1, 1}, 0}};
  return m;
}

/// Colour `which` (0 or 1) of tile k of makeTileWall: distinct for every k < 400 and between
/// the two colours of a tile.
inline std::array<uint8_t, 4> tileColor(int k, int which) {
  const auto r = static_cast<uint8_t>(10 + (k % 20) * 12);
  const auto g = static_cast<uint8_t>(10 + (k / 20) * 12);
  const auto b = static_cast<uint8_t>((k * 37) % 256);
  if (which == 0) return {r, g, b, 255};
  return {static_cast<uint8_t>(255 - r), static_cast<uint8_t>(255 - g), static_cast<uint8_t>(255 - b), 255};
}

/// A wall of cols x rows square tiles in the plane z = `z` facing the origin (a camera at the
/// origin with identity pose sees tile (0, 0) top-left). Tile k = row * cols + col has side
/// `size`, pitch `pitch` (metres), the grid centred on the z axis, and its own material k with
/// its own 8 x 8 texture k: texels with x < 4 == y < 4 (top-left and bottom-right quadrants) in
/// tileColor(k, 0), the others tileColor(k, 1). One draw range per tile, one block.
inline Model makeTileWall(int cols, int rows, double z, double pitch, double size) {
  Model m;
  m.source = "analytic tile wall";
  for (int k = 0; k < cols * rows; ++k) {
    const int col = k % cols, row = k / cols;
    const Eigen::Vector3d corner((col - cols / 2.0) * pitch + (pitch - size) / 2,
                                 (row - rows / 2.0) * pitch + (pitch - size) / 2, z);
    const auto first = static_cast<uint32_t>(m.indices.size());
    appendQuad(m, corner, {size, 0, 0}, {0, size, 0});
    m.ranges.push_back(DrawRange{first, 6, k});
    Texture tex;
    tex.name = "tile" + std::to_string(k);
    tex.width = tex.height = 8;
    tex.rgba.resize(8 * 8 * 4);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 8; ++x) {
        const auto c = tileColor(k, (x < 4) == (y < 4) ? 0 : 1);
        std::copy(c.begin(), c.end(), &tex.rgba[(static_cast<size_t>(y) * 8 + x) * 4]);
      }
    }
    m.textures.push_back(std::move(tex));
    m.materials.push_back(Material{"tile" + std::to_string(k), {1, 1, 1, 1}, k});
  }
  Aabb bounds;
  for (size_t i = 0; i < m.vertexCount(); ++i) bounds.extend(&m.positions[3 * i]);
  Block block;
  block.bounds = bounds;
  block.first_range = 0;
  block.range_count = static_cast<uint32_t>(m.ranges.size());
  block.triangle_count = static_cast<uint32_t>(m.triangleCount());
  m.blocks = {block};
  m.bounds = bounds;
  return m;
}

/// Pixel (rounded pinhole coordinates) of texel (tx, ty)'s centre of tile k of
/// makeTileWall(cols, rows, z, pitch, size) seen by `cam` at the origin with identity pose.
inline std::array<int, 2> tileTexelPixel(const PinholeCamera& cam, int cols, int rows, double z, double pitch,
                                         double size, int k, int tx, int ty) {
  const int col = k % cols, row = k / cols;
  const double x = (col - cols / 2.0) * pitch + (pitch - size) / 2 + (tx + 0.5) / 8.0 * size;
  const double y = (row - rows / 2.0) * pitch + (pitch - size) / 2 + (ty + 0.5) / 8.0 * size;
  return {static_cast<int>(std::lround(cam.fx * x / z + cam.cx)),
          static_cast<int>(std::lround(cam.fy * y / z + cam.cy))};
}

/// Bilinear REPEAT lookup with texel centres at (k + 0.5) / size, uv (0, 0) at the image's
/// top-left: what the renderers must sample. Returns 0..255 RGBA as doubles.
inline Eigen::Vector4d sampleTextureBilinear(const Texture& tex, double s, double t) {
  const double x = s * tex.width - 0.5;
  const double y = t * tex.height - 0.5;
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  auto wrap = [](long k, int n) { return static_cast<int>(((k % n) + n) % n); };
  auto texel = [&](long xi, long yi) {
    const uint8_t* p = &tex.rgba[(static_cast<size_t>(wrap(yi, tex.height)) * tex.width + wrap(xi, tex.width)) * 4];
    return Eigen::Vector4d(p[0], p[1], p[2], p[3]);
  };
  const long x0 = static_cast<long>(fx);
  const long y0 = static_cast<long>(fy);
  const double ax = x - fx;
  const double ay = y - fy;
  return (1 - ay) * ((1 - ax) * texel(x0, y0) + ax * texel(x0 + 1, y0)) +
         ay * ((1 - ax) * texel(x0, y0 + 1) + ax * texel(x0 + 1, y0 + 1));
}

/// A world-frame ray; the parameter t of a hit origin + t * direction is its camera z.
struct Ray {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;
};

/// The ray through pinhole coordinates (u, v) (pixel (i, j)'s centre is (u, v) = (i, j)).
inline Ray pixelRay(const PinholeCamera& cam, const Pose& T_world_camera, double u, double v) {
  const Eigen::Vector3d d_camera((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
  return {T_world_camera.translation(), T_world_camera.linear() * d_camera};
}

/// T_world_camera of a camera at `eye` looking at `target`, image up towards `up` (x right,
/// y down, z forward).
inline Pose cameraLookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                            const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ()) {
  return lookAt(eye, target, up).value();
}

/// Hit of the plane n . p = n . point, for t > 0.
inline std::optional<double> rayPlane(const Ray& ray, const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  const double denom = normal.dot(ray.direction);
  if (denom == 0) return std::nullopt;
  const double t = normal.dot(point - ray.origin) / denom;
  if (!(t > 0)) return std::nullopt;
  return t;
}

/// First hit of the box [lo, hi] from outside (slab method), with the outward normal of the
/// face hit (world frame).
struct BoxHit {
  double t = 0;
  Eigen::Vector3d normal;
};
inline std::optional<BoxHit> rayBox(const Ray& ray, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double t_enter = -std::numeric_limits<double>::infinity();
  double t_exit = std::numeric_limits<double>::infinity();
  int enter_axis = -1;
  for (int a = 0; a < 3; ++a) {
    const double d = ray.direction[a];
    if (d == 0) {
      if (ray.origin[a] < lo[a] || ray.origin[a] > hi[a]) return std::nullopt;
      continue;
    }
    double t0 = (lo[a] - ray.origin[a]) / d;
    double t1 = (hi[a] - ray.origin[a]) / d;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_enter) {
      t_enter = t0;
      enter_axis = a;
    }
    t_exit = std::min(t_exit, t1);
  }
  if (enter_axis < 0 || t_enter > t_exit || !(t_enter > 0)) return std::nullopt;
  BoxHit hit;
  hit.t = t_enter;
  hit.normal = Eigen::Vector3d::Zero();
  hit.normal[enter_axis] = ray.direction[enter_axis] > 0 ? -1.0 : 1.0;
  return hit;
}

/// First hit of the sphere |p - center| = radius from outside, t > 0.
inline std::optional<double> raySphere(const Ray& ray, const Eigen::Vector3d& center, double radius) {
  const Eigen::Vector3d oc = ray.origin - center;
  const double a = ray.direction.squaredNorm();
  const double b = oc.dot(ray.direction);
  const double c = oc.squaredNorm() - radius * radius;
  const double disc = b * b - a * c;
  if (disc < 0) return std::nullopt;
  const double t = (-b - std::sqrt(disc)) / a;
  if (!(t > 0)) return std::nullopt;
  return t;
}

/// Moller-Trumbore ray-triangle intersection in double, t > 0, either winding. Plain scalar
/// arithmetic so that it stays fast in unoptimised builds.
inline std::optional<double> rayTriangle(const Ray& ray, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                         const Eigen::Vector3d& c) {
  const double* o = ray.origin.data();
  const double* d = ray.direction.data();
  const double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double pv[3] = {d[1] * e2[2] - d[2] * e2[1], d[2] * e2[0] - d[0] * e2[2], d[0] * e2[1] - d[1] * e2[0]};
  const double det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
  if (det == 0) return std::nullopt;
  const double inv_det = 1.0 / det;
  const double tv[3] = {o[0] - a[0], o[1] - a[1], o[2] - a[2]};
  const double u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv_det;
  if (u < 0 || u > 1) return std::nullopt;
  const double qv[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
  const double v = (d[0] * qv[0] + d[1] * qv[1] + d[2] * qv[2]) * inv_det;
  if (v < 0 || u + v > 1) return std::nullopt;
  const double t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv_det;
  if (!(t > 0)) return std::nullopt;
  return t;
}

inline Eigen::Vector3d modelVertex(const Model& m, uint32_t i) {
  return Eigen::Vector3d(m.positions[3 * i], m.positions[3 * i + 1], m.positions[3 * i + 2]);
}

/// Nearest hit of any triangle of the model (brute force over all triangles).
inline std::optional<double> rayModel(const Ray& ray, const Model& m) {
  std::optional<double> best;
  for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
    const auto t = rayTriangle(ray, modelVertex(m, m.indices[k]), modelVertex(m, m.indices[k + 1]),
                               modelVertex(m, m.indices[k + 2]));
    if (t && (!best || *t < *best)) best = t;
  }
  return best;
}

/// Ray-cast depth image: per pixel (row-major) the camera z of the nearest triangle hit by the
/// ray through the pixel centre (Moller-Trumbore), nullopt where none. A triangle entirely in
/// front of the camera is tested only against the pixels in its projected bounding box grown
/// by 2 px (a pruning that cannot miss a hit), any other triangle against every pixel.
inline std::vector<std::optional<double>> rayCastDepth(const Model& m, const PinholeCamera& cam,
                                                       const Pose& T_world_camera) {
  const int w = cam.width;
  const int h = cam.height;
  std::vector<Ray> rays;
  rays.reserve(static_cast<size_t>(w) * h);
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) rays.push_back(pixelRay(cam, T_world_camera, i, j));
  }
  const Pose T_camera_world = T_world_camera.inverse();
  std::vector<std::optional<double>> depth(rays.size());
  for (size_t k = 0; k + 2 < m.indices.size(); k += 3) {
    const Eigen::Vector3d v[3] = {modelVertex(m, m.indices[k]), modelVertex(m, m.indices[k + 1]),
                                  modelVertex(m, m.indices[k + 2])};
    int i0 = 0, i1 = w - 1, j0 = 0, j1 = h - 1;
    double u_lo = 1e300, u_hi = -1e300, v_lo = 1e300, v_hi = -1e300;
    bool in_front = true;
    for (const Eigen::Vector3d& p : v) {
      const Eigen::Vector3d q = T_camera_world * p;
      in_front = in_front && q.z() > 1e-9;
      const double u = cam.fx * q.x() / q.z() + cam.cx;
      const double vv = cam.fy * q.y() / q.z() + cam.cy;
      u_lo = std::min(u_lo, u);
      u_hi = std::max(u_hi, u);
      v_lo = std::min(v_lo, vv);
      v_hi = std::max(v_hi, vv);
    }
    if (in_front) {
      if (u_hi < -2 || v_hi < -2 || u_lo > w + 1 || v_lo > h + 1) continue;
      i0 = std::max(i0, static_cast<int>(std::floor(u_lo)) - 2);
      i1 = std::min(i1, static_cast<int>(std::ceil(u_hi)) + 2);
      j0 = std::max(j0, static_cast<int>(std::floor(v_lo)) - 2);
      j1 = std::min(j1, static_cast<int>(std::ceil(v_hi)) + 2);
    }
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const size_t idx = static_cast<size_t>(j) * w + i;
        const auto t = rayTriangle(rays[idx], v[0], v[1], v[2]);
        if (t && (!depth[idx] || *t < *depth[idx])) depth[idx] = t;
      }
    }
  }
  return depth;
}

/// Gray image of a box-filtered step edge along the line n . (u, v) = c (n unit, pixels): each
/// pixel is 60 + 120 x the fraction of its area (8x8 samples) on the bright side n . x > c.
inline ImageU8 makeTiltedStepImage(int width, int height, const Eigen::Vector2d& n, double c) {
  ImageU8 gray(width, height, 1, 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      double covered = 0;
      for (int sy = 0; sy < 8; ++sy) {
        for (int sx = 0; sx < 8; ++sx) {
          covered += n.dot(Eigen::Vector2d(x - 0.4375 + sx / 8.0, y - 0.4375 + sy / 8.0)) > c;
        }
      }
      gray.at(x, y) = static_cast<uint8_t>(std::lround(60 + 120 * covered / 64));
    }
  }
  return gray;
}

/// An RGBA checkerboard of squares x squares squares of texels x texels texels each, so that
/// bilinear sampling keeps the square boundaries crisp.
inline Texture makeBlockChecker(int squares, int texels, uint8_t dark, uint8_t bright) {
  const Texture small = makeCheckerTexture(squares, {dark, dark, dark, 255}, {bright, bright, bright, 255});
  Texture tex = small;
  tex.width = tex.height = squares * texels;
  tex.rgba.assign(static_cast<size_t>(tex.width) * tex.height * 4, 0);
  for (int y = 0; y < tex.height; ++y) {
    for (int x = 0; x < tex.width; ++x) {
      for (int c = 0; c < 4; ++c) {
        tex.rgba[(static_cast<size_t>(y) * tex.width + x) * 4 + c] =
            small.rgba[(static_cast<size_t>(y / texels) * squares + x / texels) * 4 + c];
      }
    }
  }
  return tex;
}

/// A checker-textured box (0.6 x 0.45 x 0.4 m) on a checker-textured ground square (2.4 m),
/// z up: a small scene the edge tracker converges on from a few centimetres off.
inline Model makeBoxOnGround() {
  Model m = makeBox({-0.3, -0.2, 0.0}, {0.3, 0.25, 0.4});
  appendQuad(m, {-1.2, -1.2, 0.0}, {2.4, 0.0, 0.0}, {0.0, 2.4, 0.0});  // faces +z
  finishSingleBlock(m);
  m.textures = {makeBlockChecker(8, 8, 40, 220)};
  m.materials = {Material{"checker", {1, 1, 1, 1}, 0}};
  return m;
}

}  // namespace vkloc::test
