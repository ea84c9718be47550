// The demo models' mesh builder: planar quads split on a world-aligned grid so that neighbouring
// faces stay watertight, and solids built from them.
#include <functional>
#include <limits>

#include "sim/demo_internal.hpp"

namespace vkloc::demo_detail {

int alignedAxis(const V3& d) {
  const double len = std::sqrt(dot(d, d));
  for (int a = 0; a < 3; ++a)
    if (std::abs(std::abs(d[a]) - len) <= 1e-9 * std::max(1.0, len)) return a;
  return -1;
}

/// World grid lines k * cell strictly inside (lo, hi), leaving at least `kSplitTol` at both ends.
constexpr double kSplitTol = 1e-4;
int gridLineCount(double lo, double hi, double cell) {
  if (hi < lo) std::swap(lo, hi);
  const double k0 = std::floor((lo + kSplitTol) / cell) + 1;
  const double k1 = std::ceil((hi - kSplitTol) / cell) - 1;
  return k1 >= k0 ? static_cast<int>(k1 - k0 + 1) : 0;
}

/// Split parameters in [0, 1] along edge p -> p + d for grid spacing `cell` (cell <= 0: none),
/// and the exact world coordinate of each split along the edge's axis.
void splitParams(const V3& p, const V3& d, double cell, std::vector<double>& params, std::vector<double>& coords,
                 int& axis) {
  params.assign({0.0});
  coords.assign({0.0});
  axis = cell > 0 ? alignedAxis(d) : -1;
  if (axis >= 0) {
    const double lo = p[axis], hi = p[axis] + d[axis];
    const double a = std::min(lo, hi), b = std::max(lo, hi);
    const int n = gridLineCount(a, b, cell);
    const double k0 = std::floor((a + kSplitTol) / cell) + 1;
    coords[0] = lo;
    std::vector<double> g;
    for (int i = 0; i < n; ++i) g.push_back((k0 + i) * cell);
    if (hi < lo) std::reverse(g.begin(), g.end());
    for (double x : g) {
      params.push_back((x - lo) / (hi - lo));
      coords.push_back(x);
    }
    params.push_back(1.0);
    coords.push_back(hi);
  } else {
    params.push_back(1.0);
    coords.push_back(0.0);
  }
}

Model MeshBuilder::build(const std::string& source, uint32_t target_triangles) {
  // Choose the world grid spacing that brings the triangle count closest to the target.
  auto countFor = [&](double cell) {
    uint64_t n = tris_.size();
    for (const auto& q : quads_) {
      uint64_t nu = 1, nv = 1;
      if (q.split && cell > 0) {
        const V3 du = q.p[1] - q.p[0], dv = q.p[3] - q.p[0];
        const int au = alignedAxis(du), av = alignedAxis(dv);
        if (au >= 0) nu += gridLineCount(q.p[0][au], q.p[1][au], cell);
        if (av >= 0) nv += gridLineCount(q.p[0][av], q.p[3][av], cell);
      }
      n += 2 * nu * nv;
    }
    return n;
  };
  double cell = 0;
  const uint64_t natural = countFor(0);
  if (target_triangles > natural) {
    // Bisection on log(cell) for the largest cell reaching the target, then a fine local scan.
    double lo = 1e-3, hi = 400.0;
    for (int it = 0; it < 60; ++it) {
      const double mid = std::sqrt(lo * hi);
      (countFor(mid) >= target_triangles ? lo : hi) = mid;
    }
    double best = lo;
    uint64_t best_err = std::numeric_limits<uint64_t>::max();
    for (int k = -200; k <= 200; ++k) {
      const double c = lo * std::exp(k * 2.5e-4);
      const uint64_t n = countFor(c);
      const uint64_t err = n > target_triangles ? n - target_triangles : target_triangles - n;
      if (err < best_err) best_err = err, best = c;
    }
    cell = best;
  }

  Model model;
  model.source = source;
  const uint64_t total = countFor(cell);
  std::vector<std::vector<uint32_t>> by_material(materials_.size());
  model.positions.reserve(total * 2 * 3);
  model.uvs.reserve(total * 2 * 2);
  model.colors.reserve(total * 2 * 4);

  auto addVertex = [&](const V3& p, const V2& t, const Rgba8& c) {
    const uint32_t index = static_cast<uint32_t>(model.positions.size() / 3);
    model.positions.insert(model.positions.end(), {float(p.x), float(p.y), float(p.z)});
    model.uvs.insert(model.uvs.end(), {float(t.u), float(t.v)});
    model.colors.insert(model.colors.end(), {c.r, c.g, c.b, c.a});
    return index;
  };
  std::vector<double> pu, pv, cu, cv;
  for (const auto& q : quads_) {
    const V3 du = q.p[1] - q.p[0], dv = q.p[3] - q.p[0];
    int au = -1, av = -1;
    splitParams(q.p[0], du, q.split ? cell : 0, pu, cu, au);
    splitParams(q.p[0], dv, q.split ? cell : 0, pv, cv, av);
    const uint32_t base = static_cast<uint32_t>(model.positions.size() / 3);
    const size_t nu = pu.size(), nv = pv.size();
    for (size_t j = 0; j < nv; ++j) {
      for (size_t i = 0; i < nu; ++i) {
        const double a = pu[i], b = pv[j];
        V3 p = q.p[0] + a * du + b * dv;
        // Exact grid coordinates along axis-aligned edges keep neighbours' vertices identical.
        if (au >= 0) p[au] = cu[i];
        if (av >= 0) p[av] = cv[j];
        V2 t{q.uv[0].u + a * (q.uv[1].u - q.uv[0].u) + b * (q.uv[3].u - q.uv[0].u),
             q.uv[0].v + a * (q.uv[1].v - q.uv[0].v) + b * (q.uv[3].v - q.uv[0].v)};
        const bool last_u = i == nu - 1, last_v = j == nv - 1;
        int corner = -1;
        if (i == 0 && j == 0)
          corner = 0;
        else if (last_u && j == 0)
          corner = 1;
        else if (last_u && last_v)
          corner = 2;
        else if (i == 0 && last_v)
          corner = 3;
        if (corner >= 0) p = q.p[corner], t = q.uv[corner];
        addVertex(p, t, q.color);
      }
    }
    auto& out = by_material[q.material];
    for (size_t j = 0; j + 1 < nv; ++j) {
      for (size_t i = 0; i + 1 < nu; ++i) {
        const uint32_t v00 = base + uint32_t(j * nu + i), v10 = v00 + 1;
        const uint32_t v01 = v00 + uint32_t(nu), v11 = v01 + 1;
        out.insert(out.end(), {v00, v10, v11, v00, v11, v01});
      }
    }
  }
  for (const auto& t : tris_) {
    auto& out = by_material[t.material];
    for (int k = 0; k < 3; ++k) out.push_back(addVertex(t.p[k], t.uv[k], t.color));
  }
  // Keep only materials (and their textures) that some triangle uses.
  model.materials.clear();
  model.textures.clear();
  for (size_t m = 0; m < by_material.size(); ++m) {
    if (by_material[m].empty()) continue;
    Material mat = materials_[m];
    if (mat.texture >= 0) {
      model.textures.push_back(std::move(textures_[mat.texture]));
      mat.texture = static_cast<int>(model.textures.size()) - 1;
    }
    DrawRange r;
    r.first_index = static_cast<uint32_t>(model.indices.size());
    r.index_count = static_cast<uint32_t>(by_material[m].size());
    r.material = static_cast<int>(model.materials.size());
    model.materials.push_back(std::move(mat));
    model.ranges.push_back(r);
    model.indices.insert(model.indices.end(), by_material[m].begin(), by_material[m].end());
  }
  quads_.clear();
  tris_.clear();
  buildBlocks(model, 32768);
  return model;
}

// ---- solids ------------------------------------------------------------------------------------

/// A closed axis-aligned box [lo, hi] with outward-facing faces.
void addBox(MeshBuilder& mb, V3 lo, V3 hi, const std::array<FaceLook, 6>& look, Rgba8 color, bool split) {
  const V3 X{1, 0, 0}, Y{0, 1, 0}, Z{0, 0, 1};
  const V3 nX{-1, 0, 0}, nY{0, -1, 0};
  const double dx = hi.x - lo.x, dy = hi.y - lo.y, dz = hi.z - lo.z;
  const Frame frames[6] = {
      {{hi.x, lo.y, lo.z}, Y, Z}, {{lo.x, hi.y, lo.z}, nY, Z}, {{hi.x, hi.y, lo.z}, nX, Z},
      {{lo.x, lo.y, lo.z}, X, Z}, {{lo.x, lo.y, hi.z}, X, Y},  {{lo.x, hi.y, lo.z}, X, nY},
  };
  const double ls[6] = {dy, dy, dx, dx, dx, dx};
  const double lt[6] = {dz, dz, dz, dz, dy, dy};
  for (int f = 0; f < 6; ++f) {
    const FaceLook& fl = look[f];
    if (!fl.enabled) continue;
    UvMap uv = fl.tile_m > 0 ? UvMap{1 / fl.tile_m, 0, -1 / fl.tile_m, 0}
                             : fitUv(0, 0, ls[f], lt[f], fl.uv[0], fl.uv[1], fl.uv[2], fl.uv[3]);
    mb.rect(frames[f], 0, 0, ls[f], lt[f], uv, fl.material, color, split);
  }
}

std::array<FaceLook, 6> allFaces(int material, double tile_m) {
  std::array<FaceLook, 6> a;
  for (auto& f : a) f.material = material, f.tile_m = tile_m;
  return a;
}

/// Walls around a rectilinear region (outside facing out), as maximal straight segments.

std::vector<WallSeg> regionOutline(const Region& reg) {
  std::vector<double> xs, ys;
  for (const auto* list : {&reg.include, &reg.exclude})
    for (const auto& r : *list) xs.insert(xs.end(), {r.x0, r.x1}), ys.insert(ys.end(), {r.y0, r.y1});
  sortUnique(xs);
  sortUnique(ys);
  const int nx = static_cast<int>(xs.size()) - 1, ny = static_cast<int>(ys.size()) - 1;
  auto inside = [&](int i, int j) {
    if (i < 0 || j < 0 || i >= nx || j >= ny) return false;
    return reg.contains(0.5 * (xs[i] + xs[i + 1]), 0.5 * (ys[j] + ys[j + 1]));
  };
  std::vector<WallSeg> walls;
  // Vertical walls (constant x): scan each grid line for runs of boundary cells.
  for (int i = 0; i <= nx; ++i) {
    for (int side = 0; side < 2; ++side) {  // side 0: solid at i - 1, outward +x; 1: solid at i, outward -x.
      int j = 0;
      while (j < ny) {
        auto edge = [&](int jj) {
          return side == 0 ? inside(i - 1, jj) && !inside(i, jj) : inside(i, jj) && !inside(i - 1, jj);
        };
        if (!edge(j)) {
          ++j;
          continue;
        }
        int k = j;
        while (k < ny && edge(k)) ++k;
        if (side == 0)
          walls.push_back({xs[i], ys[j], xs[i], ys[k], 1, 0});
        else
          walls.push_back({xs[i], ys[k], xs[i], ys[j], -1, 0});
        j = k;
      }
    }
  }
  for (int j = 0; j <= ny; ++j) {
    for (int side = 0; side < 2; ++side) {  // side 0: solid at j - 1, outward +y; 1: outward -y.
      int i = 0;
      while (i < nx) {
        auto edge = [&](int ii) {
          return side == 0 ? inside(ii, j - 1) && !inside(ii, j) : inside(ii, j) && !inside(ii, j - 1);
        };
        if (!edge(i)) {
          ++i;
          continue;
        }
        int k = i;
        while (k < nx && edge(k)) ++k;
        if (side == 0)
          walls.push_back({xs[k], ys[j], xs[i], ys[j], 0, 1});
        else
          walls.push_back({xs[i], ys[j], xs[k], ys[j], 0, -1});
        i = k;
      }
    }
  }
  return walls;
}

/// Vertical frame of a wall segment: s along the wall from its left end, t up from z0.
Frame wallFrame(const WallSeg& w, double z0) {
  const double len = w.length();
  return Frame{{w.ax, w.ay, z0}, {(w.bx - w.ax) / len, (w.by - w.ay) / len, 0}, {0, 0, 1}};
}

Frame horizontalFrame(double z) { return Frame{{0, 0, z}, {1, 0, 0}, {0, 1, 0}}; }

Rgba8 tint(Rng& rng, double strength) {
  const double base = 255 * (1 - strength);
  auto ch = [&] { return static_cast<uint8_t>(std::lround(base + 255 * strength * rng.uniform(0.55, 1.0))); };
  Rgba8 c;
  c.r = ch();
  c.g = ch();
  c.b = ch();
  return c;
}

int clampTextureSize(int size) { return std::clamp(size, 16, 4096); }

uint32_t textureSeed(uint32_t seed, uint32_t model, uint32_t index) { return hash4(seed, model, index, 0x7E7u); }

/// A tree: box trunk and a convex octagonal crown (cone, frustum, cone).
/// `trunk_h`: trunk height, `r`: crown radius, `tw`: half trunk width, metres.
void addTree(MeshBuilder& mb, int bark, int leaves, double x, double y, double z, double trunk_h, double r, double tw,
             Rng& rng) {
  addBox(mb, {x - tw, y - tw, z + kGap}, {x + tw, y + tw, z + trunk_h}, allFaces(bark, 1.0), kWhite);
  const double za = z + trunk_h + kGap, zb = za + 0.5 * r, zc = zb + 0.8 * r, zt = zc + 0.9 * r;
  const V3 centre{x, y, 0.5 * (za + zt)};
  const double phase = rng.uniform(0, 0.785);
  const Rgba8 tone = tint(rng, 0.35);
  constexpr int n = 8;
  V3 lower[n], upper[n];
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2 * kPi * i / n;
    lower[i] = {x + r * std::cos(a), y + r * std::sin(a), zb};
    upper[i] = {x + 0.85 * r * std::cos(a), y + 0.85 * r * std::sin(a), zc};
  }
  const V3 bottom{x, y, za}, apex{x, y, zt};
  auto out = [&](V3 a, V3 b, V3 c) { return (1.0 / 3) * (a + b + c) - centre; };
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n;
    const double u0 = double(i) / n * 2, u1 = double(i + 1) / n * 2;
    mb.tri(bottom, lower[i], lower[j], {0.5 * (u0 + u1), 1.0}, {u0, 0.7}, {u1, 0.7}, leaves, tone,
           out(bottom, lower[i], lower[j]));
    mb.tri(lower[i], lower[j], upper[j], {u0, 0.7}, {u1, 0.7}, {u1, 0.3}, leaves, tone,
           out(lower[i], lower[j], upper[j]));
    mb.tri(lower[i], upper[j], upper[i], {u0, 0.7}, {u1, 0.3}, {u0, 0.3}, leaves, tone,
           out(lower[i], upper[j], upper[i]));
    mb.tri(upper[i], upper[j], apex, {u0, 0.3}, {u1, 0.3}, {0.5 * (u0 + u1), 0.0}, leaves, tone,
           out(upper[i], upper[j], apex));
  }
}

}  // namespace vkloc::demo_detail
