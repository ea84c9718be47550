// The built-in demo city (vkloc::makeDemoCity).
#include <functional>

#include "sim/demo_internal.hpp"

namespace vkloc {

using namespace demo_detail;

// ================================================================================================
// City
// ================================================================================================
namespace {

constexpr double kHalfMap = 100.0;  ///< The map spans [-kHalfMap, kHalfMap] in x and y.
constexpr double kRoadHalf = 6.0;   ///< Half road width.
constexpr double kWalk = 3.0;       ///< Sidewalk width.
constexpr double kKerbH = 0.15;     ///< Sidewalk and lot height above the road.
constexpr double kSkirt = 0.05;     ///< Walls and kerbs reach this far below the surface around them.
constexpr int kMaxBuildings = 30;

struct CityMaterials {
  int road, crossing, junction, sidewalk, plaza, grass, parking;
  int roof_membrane, roof_gravel, roof_tiles, roof_unit, parapet, car, leaves, bark;
  std::array<int, kFacadeStyles.size()> facade;
  std::array<int, kGroundStyles.size()> ground;
};

CityMaterials addCityMaterials(MeshBuilder& mb, uint32_t seed, int size) {
  uint32_t k = 0;
  auto ts = [&] { return textureSeed(seed, 1, k++); };
  CityMaterials m{};
  m.road = mb.addTexturedMaterial(roadTexture(size, ts(), false));
  m.crossing = mb.addTexturedMaterial(roadTexture(size, ts(), true));
  m.junction = mb.addTexturedMaterial(junctionTexture(size, ts()));
  m.sidewalk = mb.addTexturedMaterial(sidewalkTexture(size, ts()));
  m.plaza = mb.addTexturedMaterial(plazaTexture(size, ts()));
  m.grass = mb.addTexturedMaterial(grassTexture(size, ts()));
  m.parking = mb.addTexturedMaterial(parkingTexture(size, ts()));
  m.roof_membrane = mb.addTexturedMaterial(roofTexture(size, ts(), false));
  m.roof_gravel = mb.addTexturedMaterial(roofTexture(size, ts(), true));
  m.roof_tiles = mb.addTexturedMaterial(roofTilesTexture(size, ts()));
  m.roof_unit = mb.addTexturedMaterial(roofUnitTexture(size, ts()));
  m.parapet = mb.addTexturedMaterial(parapetTexture(size, ts()));
  m.car = mb.addTexturedMaterial(carTexture(size, ts()));
  m.leaves = mb.addTexturedMaterial(leavesTexture(size, ts()));
  m.bark = mb.addTexturedMaterial(barkTexture(size, ts()));
  for (size_t i = 0; i < kFacadeStyles.size(); ++i)
    m.facade[i] = mb.addTexturedMaterial(facadeTexture(size, ts(), kFacadeStyles[i]));
  for (size_t i = 0; i < kGroundStyles.size(); ++i)
    m.ground[i] = mb.addTexturedMaterial(groundFloorTexture(size, ts(), kGroundStyles[i]));
  return m;
}

/// Junction squares and road segments (zebra-crossing tiles next to every junction).
void addRoads(MeshBuilder& mb, const CityMaterials& cm, const std::array<double, 3>& cx,
              const std::array<double, 3>& cy) {
  const double w = 2 * kRoadHalf;
  for (double x : cx)
    for (double y : cy)
      mb.rect(Frame{{x - kRoadHalf, y - kRoadHalf, 0}, kX, kY}, 0, 0, w, w, UvMap{1 / w, 0, 1 / w, 0}, cm.junction);
  auto roads = [&](const std::array<double, 3>& centres, const std::array<double, 3>& crossings, bool along_y) {
    for (double c : centres) {
      std::vector<double> stops{-kHalfMap};
      for (double q : crossings) stops.insert(stops.end(), {q - kRoadHalf, q + kRoadHalf});
      stops.push_back(kHalfMap);
      for (size_t i = 0; i + 1 < stops.size(); i += 2) {
        const double a = stops[i], len = stops[i + 1] - a;
        // s across the road (0 at its left side looking along +t), t along it.
        const Frame f = along_y ? Frame{{c - kRoadHalf, a, 0}, kX, kY} : Frame{{a, c + kRoadHalf, 0}, kNegY, kX};
        double t0 = 0, t1 = len;
        if (i > 0) {  // Junction at t = 0: v = 0 there, lanes mirrored.
          mb.rect(f, 0, 0, w, w, UvMap{-1 / w, 1, 1 / w, 0}, cm.crossing);
          t0 = w;
        }
        if (i + 2 < stops.size()) {  // Junction at t = len.
          mb.rect(f, 0, len - w, w, len, UvMap{1 / w, 0, -1 / w, len / w}, cm.crossing);
          t1 = len - w;
        }
        mb.rect(f, 0, t0, w, t1, UvMap{1 / w, 0, 1 / w, 0}, cm.road);
      }
    }
  };
  roads(cx, cy, true);
  roads(cy, cx, false);
}

/// Raised sidewalk ring with kerb faces, and the lot surface inside it minus `holes`.
void addBlockGround(MeshBuilder& mb, const CityMaterials& cm, const Rect& blk, int lot_material, double tile_u,
                    double tile_v, const std::vector<Rect>& holes) {
  const double z = kKerbH, w = blk.w(), h = blk.h();
  mb.rect(Frame{{blk.x0, blk.y0, z}, kX, kY}, 0, 0, w, kWalk, UvMap{0.25, blk.x0 / 4, -1 / kWalk, 1}, cm.sidewalk);
  mb.rect(Frame{{blk.x0, blk.y1 - kWalk, z}, kX, kY}, 0, 0, w, kWalk, UvMap{0.25, blk.x0 / 4, 1 / kWalk, 0},
          cm.sidewalk);
  mb.rect(Frame{{blk.x0 + kWalk, blk.y0 + kWalk, z}, kY, kNegX}, 0, 0, h - 2 * kWalk, kWalk,
          UvMap{0.25, (blk.y0 + kWalk) / 4, 1 / kWalk, 0}, cm.sidewalk);
  mb.rect(Frame{{blk.x1 - kWalk, blk.y1 - kWalk, z}, kNegY, kX}, 0, 0, h - 2 * kWalk, kWalk,
          UvMap{0.25, -(blk.y1 - kWalk) / 4, 1 / kWalk, 0}, cm.sidewalk);
  for (const WallSeg& wall : regionOutline(Region{{blk}, {}})) {
    const double len = wall.length();
    mb.rect(wallFrame(wall, -kSkirt), 0, 0, len, kKerbH + kSkirt,
            fitUv(0, 0, len, kKerbH + kSkirt, 0, 0.935, len / 4, 0.995), cm.sidewalk);
  }
  const Rect lot{blk.x0 + kWalk, blk.y0 + kWalk, blk.x1 - kWalk, blk.y1 - kWalk};
  mb.region(horizontalFrame(z), Region{{lot}, holes}, UvMap{1 / tile_u, 0, 1 / tile_v, 0}, lot_material);
}

struct Building {
  std::vector<Region> parts;  ///< Footprints (unions of rectangles), each inside the previous.
  std::vector<double> tops;   ///< Top z of each part; part k starts at the top of part k - 1.
  double base = kKerbH;       ///< Ground level.
  double gf_top = 0;          ///< Top of the ground floor.
  int style = 0, ground = 0;
  bool gable = false, gravel = false;
  Rgba8 tint;
};

double snapHalf(double v) { return std::round(v * 2) / 2; }

/// Gable roof on a rectangle: two slopes and two gable-end triangles.
void addGableRoof(MeshBuilder& mb, const CityMaterials& cm, const Building& b, const Rect& r, double ze) {
  const FacadeStyle& st = kFacadeStyles[b.style];
  const bool along_x = r.w() >= r.h();
  // Work in (a, c) = coordinates along / across the ridge.
  const double a0 = along_x ? r.x0 : r.y0, a1 = along_x ? r.x1 : r.y1;
  const double c0 = along_x ? r.y0 : r.x0, c1 = along_x ? r.y1 : r.x1;
  const double cm_ = 0.5 * (c0 + c1), rise = 0.35 * (c1 - c0), zr = ze + rise;
  auto P = [&](double a, double c, double z) { return along_x ? V3{a, c, z} : V3{c, a, z}; };
  auto D = [&](double a, double c, double z) { return along_x ? V3{a, c, z} : V3{c, a, z}; };
  const double slope = std::hypot(cm_ - c0, rise);
  for (int side = 0; side < 2; ++side) {
    const double ce = side == 0 ? c0 : c1;
    const V3 facing = D(0, side == 0 ? -1 : 1, 1);
    mb.quad(P(a0, ce, ze), P(a1, ce, ze), P(a1, cm_, zr), P(a0, cm_, zr), {a0 / 4, slope / 4}, {a1 / 4, slope / 4},
            {a1 / 4, 0}, {a0 / 4, 0}, cm.roof_tiles, kWhite, facing, false);
  }
  const double fh = st.floor_m, len = c1 - c0;
  const double bay = len / std::max(1.0, std::round(len / st.bay_m));
  for (int end = 0; end < 2; ++end) {
    const double ae = end == 0 ? a0 : a1;
    const V3 facing = D(end == 0 ? -1 : 1, 0, 0);
    auto uv = [&](double c, double z) { return V2{(c - c0) / (4 * bay), (b.gf_top - z) / (2 * fh)}; };
    mb.tri(P(ae, c0, ze), P(ae, c1, ze), P(ae, cm_, zr), uv(c0, ze), uv(c1, ze), uv(cm_, zr), cm.facade[b.style],
           b.tint, facing);
  }
}

/// The same wall seen from the other side.
WallSeg reversed(const WallSeg& w) { return {w.bx, w.by, w.ax, w.ay, -w.nx, -w.ny}; }

void addBuilding(MeshBuilder& mb, const CityMaterials& cm, const Building& b, Rng& rng) {
  const FacadeStyle& st = kFacadeStyles[b.style];
  const double fh = st.floor_m;
  const double gf_h = b.gf_top - b.base;
  constexpr double kParapetH = 0.9, kParapetW = 0.3;
  for (size_t k = 0; k < b.parts.size(); ++k) {
    const Region& fp = b.parts[k];
    const bool top = k + 1 == b.parts.size();
    const bool parapet = top && !b.gable;
    const double z0 = k == 0 ? b.base - kSkirt : b.tops[k - 1];
    const double z1 = b.tops[k];
    for (const WallSeg& w : regionOutline(fp)) {
      const double len = w.length();
      const double bay = len / std::max(1.0, std::round(len / st.bay_m));
      const Frame f = wallFrame(w, z0);
      const double su = 1 / (4 * bay);
      if (k == 0) {
        mb.rect(f, 0, 0, len, std::min(b.gf_top, z1) - z0, UvMap{su, 0, -1 / gf_h, (b.gf_top - z0) / gf_h},
                cm.ground[b.ground]);
      }
      const double zs = k == 0 ? b.gf_top : z0;
      if (z1 > zs)
        mb.rect(f, 0, zs - z0, len, z1 - z0, UvMap{su, 0, -1 / (2 * fh), (b.gf_top - z0) / (2 * fh)},
                cm.facade[b.style], b.tint);
      if (parapet)
        mb.rect(f, 0, z1 - z0, len, z1 + kParapetH - z0, fitUv(0, z1 - z0, len, z1 + kParapetH - z0, 0, 0, len / 4, 1),
                cm.parapet, b.tint);
    }
    const Rgba8 roof_tint{b.tint.r, b.tint.r, b.tint.r, 255};
    const int roof_mat = b.gravel ? cm.roof_gravel : cm.roof_membrane;
    if (!top) {
      Region ring = fp;
      ring.exclude.insert(ring.exclude.end(), b.parts[k + 1].include.begin(), b.parts[k + 1].include.end());
      mb.region(horizontalFrame(z1), ring, UvMap{0.1, 0, 0.1, 0}, roof_mat, roof_tint);
      continue;
    }
    if (b.gable) {
      addGableRoof(mb, cm, b, fp.include[0], z1);
      continue;
    }
    // Flat roof inside a parapet: coping ring on top, inner faces towards the roof.
    Region roof;
    for (const Rect& r : fp.include)
      roof.include.push_back({r.x0 + kParapetW, r.y0 + kParapetW, r.x1 - kParapetW, r.y1 - kParapetW});
    mb.region(horizontalFrame(z1 + kParapetH), Region{fp.include, roof.include}, UvMap{0.25, 0, 0, 0.06}, cm.parapet,
              b.tint);
    for (const WallSeg& w : regionOutline(roof)) {
      const WallSeg in = reversed(w);
      const double len = in.length();
      mb.rect(wallFrame(in, z1), 0, 0, len, kParapetH, fitUv(0, 0, len, kParapetH, 0, 0, len / 4, 1), cm.parapet,
              b.tint);
    }
    mb.region(horizontalFrame(z1), roof, UvMap{0.1, 0, 0.1, 0}, roof_mat, roof_tint);
    // Roof-top plant units.
    const Rect bb = roof.bounds();
    std::vector<Rect> placed;
    const int units = rng.range(1, 3);
    for (int attempt = 0; attempt < 12 && static_cast<int>(placed.size()) < units; ++attempt) {
      const double w = snapHalf(rng.uniform(2, 4.5)), d = snapHalf(rng.uniform(2, 4.5));
      if (bb.w() < w + 3 || bb.h() < d + 3) continue;
      const double x0 = snapHalf(rng.uniform(bb.x0 + 1.5, bb.x1 - 1.5 - w));
      const double y0 = snapHalf(rng.uniform(bb.y0 + 1.5, bb.y1 - 1.5 - d));
      const Rect r{x0, y0, x0 + w, y0 + d};
      bool ok = true;
      for (double x : {r.x0 - 1.0, r.x1 + 1.0})
        for (double y : {r.y0 - 1.0, r.y1 + 1.0}) ok = ok && roof.contains(x, y);
      for (const auto& p : placed) ok = ok && !p.overlaps(r, 0.8);
      if (!ok) continue;
      placed.push_back(r);
      const double h = rng.uniform(1.2, 3.0);
      addBox(mb, {r.x0, r.y0, z1 + kGap}, {r.x1, r.y1, z1 + kGap + h}, allFaces(cm.roof_unit), kWhite);
    }
  }
}

/// Splits a lot into n (1..4) sub-lots.
std::vector<Rect> splitLot(const Rect& lot, int n, Rng& rng) {
  auto split = [&](const Rect& r) -> std::pair<Rect, Rect> {
    const bool along_x = r.w() >= r.h();
    if (along_x) {
      const double x = snapHalf(r.x0 + r.w() * rng.uniform(0.4, 0.6));
      return {{r.x0, r.y0, x, r.y1}, {x, r.y0, r.x1, r.y1}};
    }
    const double y = snapHalf(r.y0 + r.h() * rng.uniform(0.4, 0.6));
    return {{r.x0, r.y0, r.x1, y}, {r.x0, y, r.x1, r.y1}};
  };
  if (n <= 1) return {lot};
  auto [a, b] = split(lot);
  if (n == 2) return {a, b};
  auto [a1, a2] = split(a);
  if (n == 3) return {a1, a2, b};
  auto [b1, b2] = split(b);
  return {a1, a2, b1, b2};
}

enum class BlockRole { kInner, kEdge, kCorner };

Building makeBuilding(const Rect& sub, BlockRole role, bool tower, Rng& rng) {
  Building b;
  double m[4];
  for (double& v : m) v = snapHalf(rng.uniform(1.5, 4.0));
  Rect fp{sub.x0 + m[0], sub.y0 + m[1], sub.x1 - m[2], sub.y1 - m[3]};
  if (fp.w() < 8) fp.x0 = sub.x0 + 1.5, fp.x1 = sub.x1 - 1.5;
  if (fp.h() < 8) fp.y0 = sub.y0 + 1.5, fp.y1 = sub.y1 - 1.5;
  static constexpr int kTowerStyles[] = {2, 3, 5, 7};
  b.style = tower ? kTowerStyles[rng.range(0, 3)] : rng.range(0, static_cast<int>(kFacadeStyles.size()) - 1);
  const double fh = kFacadeStyles[b.style].floor_m;
  int floors = 0;
  switch (role) {
    case BlockRole::kInner:
      floors = rng.range(3, 10);
      break;
    case BlockRole::kEdge:
      floors = rng.range(1, 6);
      break;
    case BlockRole::kCorner:
      floors = rng.range(1, 3);
      break;
  }
  if (tower) floors = static_cast<int>(std::floor(53.0 / fh)) - rng.range(0, 3);
  const bool small = !tower && floors <= 3 && std::min(fp.w(), fp.h()) <= 20;
  if (tower)
    b.ground = 2;
  else if (small)
    b.ground = rng.chance(0.7) ? 1 : 3;
  else
    b.ground = rng.chance(0.6) ? 0 : rng.range(1, 3);
  const double gf_h = b.ground == 1 ? 3.2 : 4.2;
  b.gf_top = b.base + gf_h;
  const double top = b.gf_top + floors * fh;
  b.tint = tint(rng, 0.3);
  b.gravel = rng.chance(0.5);

  const bool can_setback = floors >= 8 && fp.w() >= 16 && fp.h() >= 16;
  if (can_setback && rng.chance(tower ? 0.7 : 0.4)) {
    Rect up = fp;
    int inset_sides = 0;
    double* sides[4] = {&up.x0, &up.y0, &up.x1, &up.y1};
    for (int s = 0; s < 4; ++s) {
      if (rng.chance(0.6)) {
        const double d = rng.range(2, 4);
        *sides[s] += s < 2 ? d : -d;
        ++inset_sides;
      }
    }
    if (inset_sides >= 1 && up.w() >= 8 && up.h() >= 8) {
      const int lower = rng.range(2, std::max(2, floors / 2));
      b.parts = {Region{{fp}, {}}, Region{{up}, {}}};
      b.tops = {b.gf_top + lower * fh, top};
      return b;
    }
  }
  if (!tower && fp.w() >= 14 && fp.h() >= 14 && rng.chance(0.4)) {
    const double cw = snapHalf(fp.w() * rng.uniform(0.35, 0.55)), ch = snapHalf(fp.h() * rng.uniform(0.35, 0.55));
    const int corner = rng.range(0, 3);
    const bool left = corner == 0 || corner == 3, bottom = corner == 0 || corner == 1;
    const Rect ra = left ? Rect{fp.x0 + cw, fp.y0, fp.x1, fp.y1} : Rect{fp.x0, fp.y0, fp.x1 - cw, fp.y1};
    const Rect rb = bottom ? Rect{fp.x0, fp.y0 + ch, fp.x1, fp.y1} : Rect{fp.x0, fp.y0, fp.x1, fp.y1 - ch};
    b.parts = {Region{{ra, rb}, {}}};
    b.tops = {top};
    return b;
  }
  b.parts = {Region{{fp}, {}}};
  b.tops = {top};
  b.gable = small && rng.chance(0.7);
  return b;
}

void addCar(MeshBuilder& mb, const CityMaterials& cm, double x, double y0, double z, bool front_north, Rgba8 paint) {
  // Body: sides [0, .5]x[0, .5], front/back [.5, 1]x[0, .5], top [.5, 1]x[.5, 1]; cabin sides [0, .5]x[.5, 1].
  std::array<FaceLook, 6> body = allFaces(cm.car);
  body[kFacePosX].uv = body[kFaceNegX].uv = {0, 0, 0.5, 0.5};
  body[kFacePosY].uv = body[kFaceNegY].uv = {0.5, 0, 1, 0.5};
  body[kFacePosZ].uv = body[kFaceNegZ].uv = {0.5, 0.5, 1, 1};
  std::array<FaceLook, 6> cabin = allFaces(cm.car);
  for (int f : {kFacePosX, kFaceNegX, kFacePosY, kFaceNegY}) cabin[f].uv = {0, 0.5, 0.5, 1};
  cabin[kFacePosZ].uv = cabin[kFaceNegZ].uv = {0.5, 0.5, 1, 1};
  const double zb = z + kGap, zt = zb + 0.85;
  addBox(mb, {x - 0.9, y0, zb}, {x + 0.9, y0 + 4.4, zt}, body, paint);
  const double c0 = front_north ? y0 + 0.9 : y0 + 1.4;
  addBox(mb, {x - 0.8, c0, zt + kGap}, {x + 0.8, c0 + 2.1, zt + kGap + 0.55}, cabin, paint);
}

const Rgba8 kCarPaints[] = {{245, 245, 245, 255}, {190, 192, 196, 255}, {50, 52, 56, 255},   {180, 30, 30, 255},
                            {40, 70, 150, 255},   {30, 90, 60, 255},    {220, 190, 60, 255}, {120, 124, 130, 255}};

}  // namespace

Model makeDemoCity(const DemoModelOptions& options) {
  const int size = clampTextureSize(options.texture_size);
  Rng rng(hash4(options.seed, 0xC1u));
  MeshBuilder mb;
  const CityMaterials cm = addCityMaterials(mb, options.seed, size);

  std::array<double, 3> cx{}, cy{};
  for (int i = 0; i < 3; ++i) cx[i] = (i - 1) * 66.0 + snapHalf(rng.uniform(-2, 2));
  for (int i = 0; i < 3; ++i) cy[i] = (i - 1) * 66.0 + snapHalf(rng.uniform(-2, 2));
  addRoads(mb, cm, cx, cy);

  const double xe[5] = {-kHalfMap, cx[0], cx[1], cx[2], kHalfMap};
  const double ye[5] = {-kHalfMap, cy[0], cy[1], cy[2], kHalfMap};
  const int park_edge = rng.range(0, 7);
  int edge_index = 0, tower_budget = 2;
  std::vector<Building> buildings;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) {
      const Rect blk{i == 0 ? xe[0] : xe[i] + kRoadHalf, j == 0 ? ye[0] : ye[j] + kRoadHalf,
                     i == 3 ? xe[4] : xe[i + 1] - kRoadHalf, j == 3 ? ye[4] : ye[j + 1] - kRoadHalf};
      const Rect lot{blk.x0 + kWalk, blk.y0 + kWalk, blk.x1 - kWalk, blk.y1 - kWalk};
      const bool inner_i = i == 1 || i == 2, inner_j = j == 1 || j == 2;
      const BlockRole role = inner_i && inner_j   ? BlockRole::kInner
                             : inner_i || inner_j ? BlockRole::kEdge
                                                  : BlockRole::kCorner;
      bool park = false;
      int n = 0;
      switch (role) {
        case BlockRole::kInner:
          n = rng.range(2, 4);
          break;
        case BlockRole::kEdge:
          park = edge_index++ == park_edge;
          n = park ? 0 : rng.range(1, 2);
          break;
        case BlockRole::kCorner:
          park = rng.chance(0.5);
          n = park ? 0 : 1;
          break;
      }
      std::vector<Rect> footprints;
      for (const Rect& sub : splitLot(lot, n, rng)) {
        if (n == 0 || static_cast<int>(buildings.size()) >= kMaxBuildings) break;
        const bool tower = role == BlockRole::kInner && tower_budget > 0 && rng.chance(0.5);
        tower_budget -= tower ? 1 : 0;
        buildings.push_back(makeBuilding(sub, role, tower, rng));
        const auto& inc = buildings.back().parts[0].include;
        footprints.insert(footprints.end(), inc.begin(), inc.end());
      }
      // Lot surface: parks are grass with trees; others plaza, parking or grass.
      int lot_mat = cm.grass;
      double tile_u = 10, tile_v = 10;
      if (!park) {
        const double r = rng.uniform();
        if (r < 0.4 || (i == 1 && j == 1))
          lot_mat = cm.parking, tile_u = 10, tile_v = 16;
        else if (r < 0.8 || role == BlockRole::kInner)
          lot_mat = cm.plaza, tile_u = tile_v = 8;
      }
      addBlockGround(mb, cm, blk, lot_mat, tile_u, tile_v, footprints);
      auto clear = [&](const Rect& r, double margin) {
        for (const Rect& f : footprints)
          if (f.overlaps(r, margin)) return false;
        return r.x0 >= lot.x0 + 0.3 && r.x1 <= lot.x1 - 0.3 && r.y0 >= lot.y0 + 0.3 && r.y1 <= lot.y1 - 0.3;
      };
      if (lot_mat == cm.parking) {
        // Cars in the painted bays: 2.5 m wide along x from x = 0, rows 5 m deep at y = 16k and 16k + 11.
        for (double by = std::floor(lot.y0 / 16) * 16; by < lot.y1; by += 16) {
          for (double row : {by, by + 11}) {
            for (double bx = std::floor(lot.x0 / 2.5) * 2.5; bx < lot.x1; bx += 2.5) {
              const Rect bay{bx, row, bx + 2.5, row + 5};
              if (!clear(bay, 1.0) || !rng.chance(0.55)) continue;
              addCar(mb, cm, bx + 1.25, row + 0.3, kKerbH, rng.chance(0.5), kCarPaints[rng.range(0, 7)]);
            }
          }
        }
      } else if (lot_mat == cm.grass) {
        std::vector<std::array<double, 2>> trees;
        const int want = park ? rng.range(8, 14) : rng.range(2, 5);
        for (int attempt = 0; attempt < 60 && static_cast<int>(trees.size()) < want; ++attempt) {
          const double x = rng.uniform(lot.x0 + 3.5, lot.x1 - 3.5), y = rng.uniform(lot.y0 + 3.5, lot.y1 - 3.5);
          bool ok = clear(Rect{x - 3, y - 3, x + 3, y + 3}, 0.5);
          for (const auto& t : trees) ok = ok && std::hypot(t[0] - x, t[1] - y) > 6.5;
          if (!ok) continue;
          trees.push_back({x, y});
          const double trunk_h = rng.uniform(1.8, 2.8), r = rng.uniform(1.6, 2.8);
          addTree(mb, cm.bark, cm.leaves, x, y, kKerbH, trunk_h, r, 0.15, rng);
        }
      }
      // Street trees on the sidewalks along inner roads, 1 m from the kerb; crowns stay clear
      // of the buildings (>= 1.5 m into the lot) and above the cars.
      const bool faces_road[4] = {j > 0, j<3, i> 0, i < 3};  // South, north, west, east sides.
      for (int side = 0; side < 4; ++side) {
        if (!faces_road[side] || !rng.chance(0.6)) continue;
        const bool along_x = side < 2;
        const double lo = (along_x ? blk.x0 : blk.y0) + 8, hi = (along_x ? blk.x1 : blk.y1) - 8;
        const double across = side == 0 ? blk.y0 + 1 : side == 1 ? blk.y1 - 1 : side == 2 ? blk.x0 + 1 : blk.x1 - 1;
        for (double a = lo; a <= hi; a += rng.uniform(12, 16)) {
          if (!rng.chance(0.8)) continue;
          const double trunk_h = rng.uniform(2.4, 3.2), r = rng.uniform(1.4, 2.2);
          addTree(mb, cm.bark, cm.leaves, along_x ? a : across, along_x ? across : a, kKerbH, trunk_h, r, 0.12, rng);
        }
      }
    }
  }
  for (const Building& b : buildings) addBuilding(mb, cm, b, rng);
  return mb.build("demo:city", options.target_triangles);
}

}  // namespace vkloc
