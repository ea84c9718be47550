// Internal pieces of the demo models shared by the texture painter (demo_textures.cpp), the mesh
// builder (mesh_builder.cpp) and the two scenes (demo_city.cpp, demo_room.cpp).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vkloc/core/random.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::demo_detail {

inline constexpr double kPi = 3.14159265358979323846;

// ================================================================================================
// Deterministic random numbers
// ================================================================================================

/// Integer hash of up to four values, uniform over 32 bits.
inline uint32_t hash4(uint32_t a, uint32_t b, uint32_t c = 0, uint32_t d = 0) {
  uint64_t s = (uint64_t(a) << 32 | b) ^ (uint64_t(c) << 32 | d) * 0xD6E8FEB86659FD93ull;
  return static_cast<uint32_t>(splitMix64(s) >> 32);
}

/// Hash to [0, 1).
inline double hashUnit(uint32_t a, uint32_t b, uint32_t c = 0, uint32_t d = 0) {
  return hash4(a, b, c, d) * (1.0 / 4294967296.0);
}

/// The demo models' generator: SplitMix64 from a seed-derived state.
class Rng : public SplitMix64 {
 public:
  explicit Rng(uint64_t seed) : SplitMix64(seed ^ 0x5DEECE66Dull) { next(); }
};

// ---- texture painting (demo_textures.cpp) -----------------------------------------------------

/// An RGB colour, 0..255 per channel.
struct Rgb {
  double r = 0, g = 0, b = 0;
  Rgb scaled(double f) const { return {r * f, g * f, b * f}; }
  Rgb mix(const Rgb& o, double t) const { return {r + (o.r - r) * t, g + (o.g - g) * t, b + (o.b - b) * t}; }
  cv::Scalar scalar() const {
    auto c = [](double v) { return std::clamp(v, 0.0, 255.0); };
    return cv::Scalar(c(r), c(g), c(b), 255);  // Channel order R, G, B, A as stored.
  }
};

enum class FacadeKind { kPunched, kBrick, kRibbon, kCurtain, kBalcony, kPanels, kClassic, kIndustrial };

struct FacadeStyle {
  const char* name;
  FacadeKind kind;
  Rgb wall, frame, glass;
  double bay_m;    ///< Nominal bay width, metres.
  double floor_m;  ///< Floor height, metres.
};

inline const std::array<FacadeStyle, 8> kFacadeStyles{{
    {"facade_plaster", FacadeKind::kPunched, {226, 214, 188}, {245, 245, 240}, {70, 90, 110}, 3.2, 3.1},
    {"facade_brick", FacadeKind::kBrick, {150, 72, 52}, {235, 232, 224}, {52, 62, 74}, 3.0, 3.0},
    {"facade_office", FacadeKind::kRibbon, {178, 178, 174}, {60, 64, 70}, {80, 104, 124}, 3.6, 3.5},
    {"facade_glass", FacadeKind::kCurtain, {70, 90, 100}, {190, 196, 200}, {76, 112, 136}, 3.0, 3.6},
    {"facade_balcony", FacadeKind::kBalcony, {238, 236, 230}, {90, 90, 94}, {66, 80, 96}, 3.4, 3.0},
    {"facade_panels", FacadeKind::kPanels, {200, 202, 206}, {50, 52, 56}, {60, 76, 92}, 3.0, 3.2},
    {"facade_classic", FacadeKind::kClassic, {210, 168, 104}, {240, 236, 226}, {56, 64, 76}, 3.0, 3.4},
    {"facade_metal", FacadeKind::kIndustrial, {150, 160, 168}, {70, 74, 80}, {90, 110, 126}, 3.6, 3.6},
}};

enum class GroundKind { kShop, kResidential, kLobby, kGarage };
struct GroundStyle {
  const char* name;
  GroundKind kind;
  Rgb wall, accent;
};
inline const std::array<GroundStyle, 4> kGroundStyles{{
    {"ground_shop", GroundKind::kShop, {90, 90, 96}, {180, 40, 40}},
    {"ground_residential", GroundKind::kResidential, {200, 190, 170}, {110, 70, 50}},
    {"ground_lobby", GroundKind::kLobby, {60, 66, 72}, {200, 200, 205}},
    {"ground_garage", GroundKind::kGarage, {150, 150, 150}, {120, 124, 130}},
}};

Texture roadTexture(int size, uint32_t seed, bool crossing);
Texture junctionTexture(int size, uint32_t seed);
Texture sidewalkTexture(int size, uint32_t seed);
Texture plazaTexture(int size, uint32_t seed);
Texture grassTexture(int size, uint32_t seed);
Texture parkingTexture(int size, uint32_t seed);
Texture roofTexture(int size, uint32_t seed, bool gravel);
Texture roofTilesTexture(int size, uint32_t seed);
Texture roofUnitTexture(int size, uint32_t seed);
Texture parapetTexture(int size, uint32_t seed);
Texture carTexture(int size, uint32_t seed);
Texture leavesTexture(int size, uint32_t seed);
Texture barkTexture(int size, uint32_t seed);
Texture facadeTexture(int size, uint32_t seed, const FacadeStyle& st);
Texture groundFloorTexture(int size, uint32_t seed, const GroundStyle& st);
Texture woodFloorTexture(int size, uint32_t seed);
Texture wallTexture(int size, uint32_t seed);
Texture ceilingTexture(int size, uint32_t seed);
Texture doorTexture(int size, uint32_t seed);
Texture windowTexture(int size, uint32_t seed);
Texture whiteboardTexture(int size, uint32_t seed);
Texture posterTexture(int size, uint32_t seed, int variant);
Texture plainTexture(int size, uint32_t seed, const char* name, Rgb base, double fine, double coarse, int cx, int cy);
Texture cardboardTexture(int size, uint32_t seed);
Texture bookTexture(int size, uint32_t seed);
Texture lightPanelTexture(int size, uint32_t seed);
Texture rugTexture(int size, uint32_t seed);
Texture screenTexture(int size, uint32_t seed);

// ---- meshes (mesh_builder.cpp) ----------------------------------------------------------------

struct V3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
  double& operator[](int i) { return i == 0 ? x : i == 1 ? y : z; }
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

struct V2 {
  double u = 0, v = 0;
};

struct Rgba8 {
  uint8_t r = 255, g = 255, b = 255, a = 255;
};
constexpr Rgba8 kWhite{};

/// A planar parallelogram p0, p1 = p0 + U, p2 = p0 + U + V, p3 = p0 + V, counter-clockwise seen
/// from the side its normal U x V points to, with affine texture coordinates.
struct Quad {
  V3 p[4];
  V2 uv[4];
  Rgba8 color;
  int material = 0;
  bool split = true;  ///< May be split for a triangle target.
};

struct Tri {
  V3 p[3];
  V2 uv[3];
  Rgba8 color;
  int material = 0;
};

/// A plane frame: point(s, t) = o + s eu + t ev, front side towards eu x ev.
struct Frame {
  V3 o, eu, ev;
  V3 at(double s, double t) const { return o + s * eu + t * ev; }
};

/// Texture coordinates as an affine function of plane coordinates: u = su s + ou, v = sv t + ov.
struct UvMap {
  double su = 1, ou = 0, sv = -1, ov = 0;
  V2 at(double s, double t) const { return {su * s + ou, sv * t + ov}; }
};

/// Maps [s0, s1] x [t0, t1] onto the texture rectangle [u0, u1] x [v0, v1] with t up.
inline UvMap fitUv(double s0, double t0, double s1, double t1, double u0, double v0, double u1, double v1) {
  UvMap m;
  m.su = (u1 - u0) / (s1 - s0);
  m.ou = u0 - m.su * s0;
  m.sv = -(v1 - v0) / (t1 - t0);
  m.ov = v1 - m.sv * t0;
  return m;
}

/// An axis-aligned rectangle in a plane.
struct Rect {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool contains(double x, double y) const { return x > x0 && x < x1 && y > y0 && y < y1; }
  bool overlaps(const Rect& o, double margin = 0) const {
    return x0 < o.x1 + margin && o.x0 < x1 + margin && y0 < o.y1 + margin && o.y0 < y1 + margin;
  }
  double w() const { return x1 - x0; }
  double h() const { return y1 - y0; }
};

/// Sorts coordinates and drops duplicates (closer than 1 nm).
inline void sortUnique(std::vector<double>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(), [](double a, double c) { return std::abs(a - c) < 1e-9; }), v.end());
}

/// A region of the plane: union of `include` rectangles minus the union of `exclude` ones.
struct Region {
  std::vector<Rect> include, exclude;
  bool contains(double x, double y) const {
    bool in = false;
    for (const auto& r : include) in = in || r.contains(x, y);
    if (!in) return false;
    for (const auto& r : exclude)
      if (r.contains(x, y)) return false;
    return true;
  }
  Rect bounds() const {
    Rect b{1e30, 1e30, -1e30, -1e30};
    for (const auto& r : include)
      b = {std::min(b.x0, r.x0), std::min(b.y0, r.y0), std::max(b.x1, r.x1), std::max(b.y1, r.y1)};
    return b;
  }
};

/// Collects quads and triangles, then tessellates them into a Model.
class MeshBuilder {
 public:
  int addTexturedMaterial(Texture texture, std::array<float, 4> base = {1, 1, 1, 1}) {
    Material m;
    m.name = texture.name;
    m.base_color = base;
    m.texture = static_cast<int>(textures_.size());
    textures_.push_back(std::move(texture));
    materials_.push_back(m);
    return static_cast<int>(materials_.size()) - 1;
  }

  /// Adds a quad; reorders the corners if needed so that its front faces `facing`.
  void quad(V3 p0, V3 p1, V3 p2, V3 p3, V2 t0, V2 t1, V2 t2, V2 t3, int material, Rgba8 color, V3 facing,
            bool split = true) {
    Quad q{{p0, p1, p2, p3}, {t0, t1, t2, t3}, color, material, split};
    if (dot(cross(p1 - p0, p3 - p0), facing) < 0) {
      std::swap(q.p[1], q.p[3]);
      std::swap(q.uv[1], q.uv[3]);
    }
    quads_.push_back(q);
  }

  /// Rectangle [s0, s1] x [t0, t1] of a frame, front towards eu x ev.
  void rect(const Frame& f, double s0, double t0, double s1, double t1, const UvMap& uv, int material,
            Rgba8 color = kWhite, bool split = true) {
    if (s1 - s0 < 1e-9 || t1 - t0 < 1e-9) return;
    quads_.push_back(Quad{{f.at(s0, t0), f.at(s1, t0), f.at(s1, t1), f.at(s0, t1)},
                          {uv.at(s0, t0), uv.at(s1, t0), uv.at(s1, t1), uv.at(s0, t1)},
                          color,
                          material,
                          split});
  }

  /// A rectilinear region of a frame, cut into rectangles along the rectangles' edges; cells of
  /// a row that are contiguous are merged.
  void region(const Frame& f, const Region& reg, const UvMap& uv, int material, Rgba8 color = kWhite) {
    std::vector<double> xs, ys;
    const Rect b = reg.bounds();
    auto addCoords = [&](const Rect& r) {
      for (double x : {r.x0, r.x1})
        if (x >= b.x0 && x <= b.x1) xs.push_back(x);
      for (double y : {r.y0, r.y1})
        if (y >= b.y0 && y <= b.y1) ys.push_back(y);
    };
    for (const auto& r : reg.include) addCoords(r);
    for (const auto& r : reg.exclude) addCoords(r);
    sortUnique(xs);
    sortUnique(ys);
    for (size_t j = 0; j + 1 < ys.size(); ++j) {
      const double yc = 0.5 * (ys[j] + ys[j + 1]);
      size_t i = 0;
      while (i + 1 < xs.size()) {
        if (!reg.contains(0.5 * (xs[i] + xs[i + 1]), yc)) {
          ++i;
          continue;
        }
        size_t k = i + 1;
        while (k + 1 < xs.size() && reg.contains(0.5 * (xs[k] + xs[k + 1]), yc)) ++k;
        rect(f, xs[i], ys[j], xs[k], ys[j + 1], uv, material, color);
        i = k;
      }
    }
  }

  /// Triangle with its front towards `facing`.
  void tri(V3 p0, V3 p1, V3 p2, V2 t0, V2 t1, V2 t2, int material, Rgba8 color, V3 facing) {
    Tri t{{p0, p1, p2}, {t0, t1, t2}, color, material};
    if (dot(cross(p1 - p0, p2 - p0), facing) < 0) {
      std::swap(t.p[1], t.p[2]);
      std::swap(t.uv[1], t.uv[2]);
    }
    tris_.push_back(t);
  }

  Model build(const std::string& source, uint32_t target_triangles);

 private:
  std::vector<Quad> quads_;
  std::vector<Tri> tris_;
  std::vector<Material> materials_;
  std::vector<Texture> textures_;
};

/// Axis (0, 1, 2) along which `d` points, or -1 when it is not axis-aligned.

/// Face of a box: material, texture rectangle (u0, v0, u1, v1) or metric tiling, colour.
struct FaceLook {
  int material = 0;
  std::array<double, 4> uv{0, 0, 1, 1};
  double tile_m = 0;  ///< > 0: texture repeats every tile_m metres instead of fitting uv.
  bool enabled = true;
};

/// Index of box faces: +x, -x, +y, -y, +z, -z.
enum BoxFace { kFacePosX, kFaceNegX, kFacePosY, kFaceNegY, kFacePosZ, kFaceNegZ };

struct WallSeg {
  double ax, ay, bx, by;  ///< From the left end to the right end seen from outside.
  double nx, ny;          ///< Outward normal.
  double length() const { return std::abs(bx - ax) + std::abs(by - ay); }
};

inline constexpr double kGap = 0.002;  ///< Loose objects float this far above what they stand on.
inline const V3 kX{1, 0, 0}, kY{0, 1, 0}, kZ{0, 0, 1}, kNegX{-1, 0, 0}, kNegY{0, -1, 0};

/// A closed axis-aligned box [lo, hi] with outward-facing faces.
void addBox(MeshBuilder& mb, V3 lo, V3 hi, const std::array<FaceLook, 6>& look, Rgba8 color, bool split = false);
std::array<FaceLook, 6> allFaces(int material, double tile_m = 0);
/// Walls around a rectilinear region (outside facing out), as maximal straight segments.
std::vector<WallSeg> regionOutline(const Region& reg);
/// Vertical frame of a wall segment: s along the wall from its left end, t up from z0.
Frame wallFrame(const WallSeg& w, double z0);
inline const Frame kGroundFrame{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
Frame horizontalFrame(double z);
Rgba8 tint(Rng& rng, double strength);
int clampTextureSize(int size);
/// A tree: box trunk and a convex octagonal crown (cone, frustum, cone).
/// `trunk_h`: trunk height, `r`: crown radius, `tw`: half trunk width, metres.
void addTree(MeshBuilder& mb, int bark, int leaves, double x, double y, double z, double trunk_h, double r, double tw,
             Rng& rng);
uint32_t textureSeed(uint32_t seed, uint32_t model, uint32_t index);

}  // namespace vkloc::demo_detail
