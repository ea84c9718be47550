// Built-in demo models: a city block seen from a drone and an indoor room, generated in code.
//
// Everything is deterministic: random choices come from a splitmix64 generator seeded with
// DemoModelOptions::seed, textures are drawn with OpenCV primitives plus hash noise, and no
// standard-library distribution (whose output differs between implementations) is used.
//
// Geometry is emitted as planar quads (plus a few triangles). Solids are closed and never
// overlap or touch with coincident faces: objects standing on a surface float 2 mm above it,
// buildings stand on ground that is cut out under their footprint. Quads whose edges are
// axis-aligned are split on a world-aligned grid when a triangle target is set, so that
// neighbouring faces get the same split points and stay watertight.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "vkloc/demo.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

// ================================================================================================
// Deterministic random numbers
// ================================================================================================

uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// Integer hash of up to four values, uniform over 32 bits.
uint32_t hash4(uint32_t a, uint32_t b, uint32_t c = 0, uint32_t d = 0) {
  uint64_t s = (uint64_t(a) << 32 | b) ^ (uint64_t(c) << 32 | d) * 0xD6E8FEB86659FD93ull;
  return static_cast<uint32_t>(splitmix64(s) >> 32);
}

/// Hash to [0, 1).
double hashUnit(uint32_t a, uint32_t b, uint32_t c = 0, uint32_t d = 0) {
  return hash4(a, b, c, d) * (1.0 / 4294967296.0);
}

class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed ^ 0x5DEECE66Dull) { splitmix64(state_); }
  uint64_t next() { return splitmix64(state_); }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Integer in [lo, hi].
  int range(int lo, int hi) { return lo + static_cast<int>(next() % uint64_t(hi - lo + 1)); }
  bool chance(double p) { return uniform() < p; }

 private:
  uint64_t state_;
};

// ================================================================================================
// Texture painting
// ================================================================================================

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

/// A square RGBA canvas; coordinates are fractions of the side (0..1, y down). Rectangles,
/// lines and circles wrap around the edges so that textures tile seamlessly with repeat
/// sampling; the other shapes are meant to stay inside.
class Canvas {
 public:
  /// Draws straight into the RGBA storage of the texture that finish() returns.
  Canvas(int size, Rgb fill, uint32_t seed) : s_(size), seed_(seed) {
    texture_.width = texture_.height = size;
    texture_.rgba.resize(static_cast<size_t>(size) * size * 4);
    img_ = cv::Mat(size, size, CV_8UC4, texture_.rgba.data());
    img_.setTo(fill.scalar());
  }
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int size() const { return s_; }
  cv::Mat& mat() { return img_; }
  int px(double f) const { return static_cast<int>(std::lround(f * s_)); }
  uint32_t seed() const { return seed_; }

  void rect(double x0, double y0, double x1, double y1, Rgb c) {
    if (x1 < x0) std::swap(x0, x1);
    if (y1 < y0) std::swap(y0, y1);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const double ax = x0 + dx, bx = x1 + dx, ay = y0 + dy, by = y1 + dy;
        if (bx <= 0 || ax >= 1 || by <= 0 || ay >= 1) continue;
        int a = px(ax), b = px(bx), cy = px(ay), d = px(by);
        if (b <= a) b = a + 1;
        if (d <= cy) d = cy + 1;
        cv::rectangle(img_, cv::Point(a, cy), cv::Point(b - 1, d - 1), c.scalar(), cv::FILLED);
      }
    }
  }
  /// Rectangle outline of thickness t (fraction), inside the rectangle.
  void outline(double x0, double y0, double x1, double y1, double t, Rgb c) {
    rect(x0, y0, x1, y0 + t, c);
    rect(x0, y1 - t, x1, y1, c);
    rect(x0, y0, x0 + t, y1, c);
    rect(x1 - t, y0, x1, y1, c);
  }
  void line(double x0, double y0, double x1, double y1, double t, Rgb c) {
    const int th = std::max(1, px(t));
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        cv::line(img_, cv::Point(px(x0 + dx), px(y0 + dy)), cv::Point(px(x1 + dx), px(y1 + dy)), c.scalar(), th,
                 cv::LINE_AA);
      }
    }
  }
  void circle(double cx, double cy, double r, Rgb c, double thickness = -1) {
    const int th = thickness < 0 ? cv::FILLED : std::max(1, px(thickness));
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (cx + dx + r < 0 || cx + dx - r > 1 || cy + dy + r < 0 || cy + dy - r > 1) continue;
        cv::circle(img_, cv::Point(px(cx + dx), px(cy + dy)), std::max(1, px(r)), c.scalar(), th, cv::LINE_AA);
      }
    }
  }
  void ellipse(double cx, double cy, double rx, double ry, Rgb c) {
    cv::ellipse(img_, cv::Point(px(cx), px(cy)), cv::Size(std::max(1, px(rx)), std::max(1, px(ry))), 0, 0, 360,
                c.scalar(), cv::FILLED, cv::LINE_AA);
  }
  void poly(const std::vector<std::array<double, 2>>& pts, Rgb c) {
    std::vector<cv::Point> p;
    for (const auto& q : pts) p.emplace_back(px(q[0]), px(q[1]));
    cv::fillPoly(img_, std::vector<std::vector<cv::Point>>{p}, c.scalar(), cv::LINE_AA);
  }
  /// Vertical gradient fill of a rectangle, colour a at the top to b at the bottom.
  void gradient(double x0, double y0, double x1, double y1, Rgb a, Rgb b) {
    const int r0 = std::clamp(px(y0), 0, s_), r1 = std::clamp(px(y1), 0, s_);
    const int c0 = std::clamp(px(x0), 0, s_), c1 = std::clamp(px(x1), 0, s_);
    for (int y = r0; y < r1; ++y) {
      const double t = r1 - r0 > 1 ? double(y - r0) / (r1 - r0 - 1) : 0.0;
      const cv::Scalar c = a.mix(b, t).scalar();
      for (int x = c0; x < c1; ++x) {
        auto& p = img_.at<cv::Vec4b>(y, x);
        for (int k = 0; k < 3; ++k) p[k] = static_cast<uint8_t>(c[k]);
      }
    }
  }

  /// Multiplies brightness by 1 + fine * white noise + coarse * smooth value noise (tileable,
  /// `cells_x` x `cells_y` lattice cells).
  void noise(double fine, double coarse, int cells_x = 8, int cells_y = 8, uint32_t salt = 0) {
    const uint32_t seed = hash4(seed_, salt, 0x4E01u);
    std::vector<float> lattice(static_cast<size_t>(cells_x) * cells_y);
    for (int j = 0; j < cells_y; ++j)
      for (int i = 0; i < cells_x; ++i) lattice[j * cells_x + i] = static_cast<float>(hashUnit(seed, i, j) * 2.0 - 1.0);
    // Per-column lattice cells and smoothstep weights, computed once.
    std::vector<int> col0(s_), col1(s_);
    std::vector<float> colt(s_);
    auto cellOf = [this](int p, int cells, int& c0, int& c1, float& t) {
      const double f = (p + 0.5) * cells / s_ - 0.5;
      const int i = static_cast<int>(std::floor(f));
      const double u = f - i;
      t = static_cast<float>(u * u * (3 - 2 * u));
      c0 = (i % cells + cells) % cells;
      c1 = (c0 + 1) % cells;
    };
    for (int x = 0; x < s_; ++x) cellOf(x, cells_x, col0[x], col1[x], colt[x]);
    const float f_fine = static_cast<float>(fine) * (2.0f / 65535.0f), f_coarse = static_cast<float>(coarse);
    for (int y = 0; y < s_; ++y) {
      int j0 = 0, j1 = 0;
      float ty = 0;
      cellOf(y, cells_y, j0, j1, ty);
      const float* l0 = &lattice[j0 * cells_x];
      const float* l1 = &lattice[j1 * cells_x];
      uint32_t state = hash4(seed, static_cast<uint32_t>(y), 7);  // Row-seeded LCG for white noise.
      auto* row = img_.ptr<cv::Vec4b>(y);
      for (int x = 0; x < s_; ++x) {
        const float a = l0[col0[x]] + (l0[col1[x]] - l0[col0[x]]) * colt[x];
        const float b = l1[col0[x]] + (l1[col1[x]] - l1[col0[x]]) * colt[x];
        state = state * 1664525u + 1013904223u;
        const float white = static_cast<float>(state >> 16) * f_fine - static_cast<float>(fine);
        const float f = 1.0f + white + f_coarse * (a + (b - a) * ty);
        for (int k = 0; k < 3; ++k) row[x][k] = cv::saturate_cast<uint8_t>(row[x][k] * f + 0.5f);
      }
    }
  }

  /// The finished texture; the canvas is empty afterwards.
  Texture finish(const std::string& name) {
    img_.release();
    texture_.name = name;
    return std::move(texture_);
  }

 private:
  int s_;
  uint32_t seed_;
  Texture texture_;
  cv::Mat img_;  ///< Header over texture_.rgba.
};

// ---- shared texture pieces ---------------------------------------------------------------------

/// A window: frame, glass with a vertical gradient, optional blind, mullion and transom.
void drawWindow(Canvas& c, Rng& rng, double x0, double y0, double x1, double y1, Rgb frame, Rgb glass, bool mullion,
                bool transom, double frame_t) {
  c.rect(x0, y0, x1, y1, frame);
  const double ix0 = x0 + frame_t, iy0 = y0 + frame_t, ix1 = x1 - frame_t, iy1 = y1 - frame_t;
  const double tone = rng.uniform(0.75, 1.25);
  c.gradient(ix0, iy0, ix1, iy1, glass.scaled(0.8 * tone), glass.scaled(1.15 * tone));
  if (rng.chance(0.45)) {  // Blind pulled down part of the way, with slats.
    const double by = iy0 + (iy1 - iy0) * rng.uniform(0.15, 0.75);
    const Rgb blind = Rgb{225, 215, 190}.mix(Rgb{170, 175, 180}, rng.uniform());
    c.rect(ix0, iy0, ix1, by, blind);
    for (double y = iy0 + 0.012; y < by; y += 0.018) c.rect(ix0, y, ix1, y + 0.003, blind.scaled(0.85));
  }
  if (mullion) c.rect((x0 + x1) / 2 - frame_t / 2, y0, (x0 + x1) / 2 + frame_t / 2, y1, frame);
  if (transom) c.rect(x0, y0 + (y1 - y0) * 0.3 - frame_t / 2, x1, y0 + (y1 - y0) * 0.3 + frame_t / 2, frame);
}

/// Asphalt: dark grey with coarse and fine noise, a few darker patches and cracks.
void drawAsphalt(Canvas& c, Rng& rng, int patches) {
  c.noise(0.10, 0.07, 8, 8, 1);
  for (int i = 0; i < patches; ++i) {
    const double x = rng.uniform(0, 1), y = rng.uniform(0, 1);
    const double w = rng.uniform(0.05, 0.2), h = rng.uniform(0.05, 0.2);
    c.rect(x, y, x + w, y + h, Rgb{58, 58, 60}.scaled(rng.uniform(0.85, 1.05)));
  }
  for (int i = 0; i < patches; ++i) {
    double x = rng.uniform(0, 1), y = rng.uniform(0, 1);
    for (int k = 0; k < 4; ++k) {
      const double nx = x + rng.uniform(-0.06, 0.06), ny = y + rng.uniform(-0.06, 0.06);
      c.line(x, y, nx, ny, 0.003, Rgb{40, 40, 42});
      x = nx;
      y = ny;
    }
  }
  c.noise(0.12, 0.0, 8, 8, 2);
}

const Rgb kMarkingWhite{228, 228, 222};

// ---- city textures -----------------------------------------------------------------------------
// Road textures: u across the 12 m road (0 = left kerb), v along it, 12 m per tile.

Texture roadTexture(int size, uint32_t seed, bool crossing) {
  Canvas c(size, Rgb{78, 78, 82}, seed);
  Rng rng(seed);
  drawAsphalt(c, rng, 3);
  const double m = 1.0 / 12.0;                // One metre.
  c.rect(0, 0, 0.3 * m, 1, Rgb{60, 60, 62});  // Gutters.
  c.rect(1 - 0.3 * m, 0, 1, 1, Rgb{60, 60, 62});
  c.rect(0.5 * m, 0, 0.65 * m, 1, kMarkingWhite);  // Edge lines.
  c.rect(1 - 0.65 * m, 0, 1 - 0.5 * m, 1, kMarkingWhite);
  if (!crossing) {
    for (double v = 0; v < 1; v += 0.5) c.rect(0.5 - 0.075 * m, v, 0.5 + 0.075 * m, v + 0.25, kMarkingWhite);
  } else {
    // Zebra crossing 0.5 .. 3.5 m from the junction end (v = 0), bars 0.5 m wide.
    for (double u = 1.0 * m; u + 0.5 * m <= 11.0 * m + 1e-9; u += 1.0 * m)
      c.rect(u, 0.5 * m, u + 0.5 * m, 3.5 * m, kMarkingWhite);
    c.rect(0.5, 4.5 * m, 1 - 0.65 * m, 4.9 * m, kMarkingWhite);                 // Stop line, approaching lane.
    c.rect(0.5 - 0.075 * m, 4.5 * m, 0.5 + 0.075 * m, 8.0 * m, kMarkingWhite);  // Solid centre.
    c.rect(0.5 - 0.075 * m, 9.0 * m, 0.5 + 0.075 * m, 12.0 * m, kMarkingWhite);
    // Arrow on the approaching lane.
    const double au = 0.75, av = 6.2 * m;
    c.rect(au - 0.1 * m, av, au + 0.1 * m, av + 2.5 * m, kMarkingWhite);
    c.poly({{au - 0.45 * m, av + 0.05 * m}, {au + 0.45 * m, av + 0.05 * m}, {au, av - 0.9 * m}}, kMarkingWhite);
  }
  c.noise(0.05, 0.04, 4, 4, 3);
  return c.finish(crossing ? "road_crossing" : "road");
}

Texture junctionTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{76, 76, 80}, seed);
  Rng rng(seed);
  drawAsphalt(c, rng, 5);
  c.circle(0.3, 0.62, 0.04, Rgb{50, 50, 52});
  c.circle(0.3, 0.62, 0.04, Rgb{95, 95, 98}, 0.006);
  for (int i = -2; i <= 2; ++i) c.line(0.3 + i * 0.012, 0.59, 0.3 + i * 0.012, 0.65, 0.003, Rgb{90, 90, 92});
  c.rect(0.62, 0.2, 0.7, 0.24, Rgb{40, 40, 40});  // Drain grate.
  return c.finish("junction");
}

/// Sidewalk: u along (4 m per tile), v across 3 m, v = 0 at the lot side, 1 at the kerb.
Texture sidewalkTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{172, 170, 164}, seed);
  const int nu = 8, nv = 5;  // 0.5 m slabs over 4 m x 2.6 m.
  const double kerb = 0.07;
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      const double tone = 0.9 + 0.2 * hashUnit(seed, i, j, 11);
      const double y0 = j * (1 - kerb) / nv, y1 = (j + 1) * (1 - kerb) / nv;
      c.rect(double(i) / nu, y0, double(i + 1) / nu, y1, Rgb{172, 170, 164}.scaled(tone));
      c.rect(double(i) / nu, y0, double(i + 1) / nu, y0 + 0.008, Rgb{120, 118, 112});
      c.rect(double(i) / nu, y0, double(i) / nu + 0.006, y1, Rgb{120, 118, 112});
    }
  }
  c.rect(0, 1 - kerb, 1, 1, Rgb{205, 203, 198});  // Kerb stones with joints every metre.
  c.rect(0, 1 - kerb, 1, 1 - kerb + 0.008, Rgb{100, 100, 98});
  for (int i = 0; i < 4; ++i) c.rect(i / 4.0, 1 - kerb, i / 4.0 + 0.005, 1, Rgb{130, 130, 126});
  c.noise(0.10, 0.06, 8, 8, 1);
  return c.finish("sidewalk");
}

/// Plaza paving, 8 m tile: staggered 1 x 2 m slabs with a darker inlay band.
Texture plazaTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{196, 188, 170}, seed);
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 4; ++i) {
      const double off = (j % 2) * 0.125;
      const double x0 = i * 0.25 + off, y0 = j / 8.0;
      const double tone = 0.88 + 0.22 * hashUnit(seed, i, j, 3);
      c.rect(x0, y0, x0 + 0.25, y0 + 0.125, Rgb{196, 188, 170}.scaled(tone));
      c.rect(x0, y0, x0 + 0.004, y0 + 0.125, Rgb{140, 134, 120});
      c.rect(x0, y0, x0 + 0.25, y0 + 0.004, Rgb{140, 134, 120});
    }
  }
  c.rect(0, 0.5, 1, 0.5 + 1.0 / 16, Rgb{120, 110, 100});
  c.rect(0.5, 0, 0.5 + 1.0 / 16, 1, Rgb{120, 110, 100});
  c.noise(0.09, 0.08, 8, 8, 1);
  return c.finish("plaza");
}

/// Grass, 10 m tile, with mowing stripes 2.5 m wide.
Texture grassTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{82, 128, 58}, seed);
  for (int i = 0; i < 4; i += 2) c.rect(i * 0.25, 0, i * 0.25 + 0.25, 1, Rgb{96, 146, 66});
  Rng rng(seed);
  for (int i = 0; i < 30; ++i)
    c.circle(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0.005, 0.02), Rgb{66, 104, 46});
  c.noise(0.22, 0.12, 8, 8, 1);
  return c.finish("grass");
}

/// Parking lot, tile 10 m (u, x) by 16 m (v, y): two rows of 2.5 x 5 m bays and an aisle.
Texture parkingTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{84, 84, 88}, seed);
  Rng rng(seed);
  drawAsphalt(c, rng, 2);
  const double lw = 0.012;
  for (int i = 0; i < 4; ++i) {
    c.rect(i * 0.25 - lw / 2, 0, i * 0.25 + lw / 2, 5.0 / 16, kMarkingWhite);
    c.rect(i * 0.25 - lw / 2, 11.0 / 16, i * 0.25 + lw / 2, 1, kMarkingWhite);
  }
  c.rect(0, 5.0 / 16 - 0.006, 1, 5.0 / 16 + 0.004, kMarkingWhite);
  c.rect(0, 11.0 / 16 - 0.004, 1, 11.0 / 16 + 0.006, kMarkingWhite);
  // Aisle arrow.
  c.rect(0.35, 0.5 - 0.01, 0.6, 0.5 + 0.01, kMarkingWhite);
  c.poly({{0.6, 0.47}, {0.6, 0.53}, {0.66, 0.5}}, kMarkingWhite);
  c.noise(0.05, 0.03, 4, 4, 3);
  return c.finish("parking");
}

/// Flat roofs, 10 m tile: membrane with 1 m seams, or gravel.
Texture roofTexture(int size, uint32_t seed, bool gravel) {
  Rng rng(seed);
  if (gravel) {
    Canvas c(size, Rgb{150, 146, 138}, seed);
    for (int i = 0; i < 6; ++i)
      c.ellipse(rng.uniform(0.1, 0.9), rng.uniform(0.1, 0.9), rng.uniform(0.04, 0.1), rng.uniform(0.04, 0.1),
                Rgb{128, 125, 118});
    c.noise(0.45, 0.1, 8, 8, 1);
    return c.finish("roof_gravel");
  }
  Canvas c(size, Rgb{112, 114, 118}, seed);
  for (int i = 0; i < 10; ++i) c.rect(i / 10.0, 0, i / 10.0 + 0.005, 1, Rgb{90, 92, 96});
  for (int i = 0; i < 5; ++i)
    c.ellipse(rng.uniform(0.1, 0.9), rng.uniform(0.1, 0.9), rng.uniform(0.03, 0.12), rng.uniform(0.02, 0.06),
              Rgb{96, 98, 100});
  c.noise(0.12, 0.1, 8, 8, 1);
  return c.finish("roof_membrane");
}

/// Roof tiles, 4 m tile: u along the ridge, v down the slope.
Texture roofTilesTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{150, 70, 48}, seed);
  const int rows = 12, cols = 14;
  for (int j = 0; j < rows; ++j) {
    for (int i = 0; i < cols; ++i) {
      const double x0 = (i + 0.5 * (j % 2)) / cols, y0 = double(j) / rows;
      const double tone = 0.85 + 0.25 * hashUnit(seed, i, j);
      c.rect(x0, y0, x0 + 1.0 / cols, y0 + 1.0 / rows, Rgb{150, 70, 48}.scaled(tone));
      c.rect(x0, y0, x0 + 0.006, y0 + 1.0 / rows, Rgb{90, 40, 30});
    }
    c.rect(0, double(j + 1) / rows - 0.012, 1, double(j + 1) / rows, Rgb{80, 36, 26});
  }
  c.noise(0.08, 0.08, 4, 4, 1);
  return c.finish("roof_tiles");
}

/// Roof-top plant unit: panel frame, louvres and a fan; mapped 0..1 on every face.
Texture roofUnitTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{176, 180, 182}, seed);
  c.outline(0, 0, 1, 1, 0.04, Rgb{120, 124, 128});
  for (double y = 0.12; y < 0.5; y += 0.05) c.rect(0.1, y, 0.9, y + 0.02, Rgb{100, 104, 108});
  c.circle(0.5, 0.73, 0.17, Rgb{70, 72, 76});
  c.circle(0.5, 0.73, 0.17, Rgb{140, 144, 148}, 0.015);
  c.line(0.33, 0.73, 0.67, 0.73, 0.012, Rgb{140, 144, 148});
  c.line(0.5, 0.56, 0.5, 0.9, 0.012, Rgb{140, 144, 148});
  c.noise(0.06, 0.05, 4, 4, 1);
  return c.finish("roof_unit");
}

/// Parapet: concrete with a metal coping band at the top (v < 0.15); u 4 m per tile.
Texture parapetTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{196, 194, 188}, seed);
  c.rect(0, 0, 1, 0.14, Rgb{150, 154, 158});
  c.rect(0, 0.14, 1, 0.17, Rgb{110, 110, 108});
  for (int i = 0; i < 4; ++i) c.rect(i / 4.0, 0.17, i / 4.0 + 0.008, 1, Rgb{160, 158, 152});
  c.noise(0.05, 0.12, 4, 4, 1);
  return c.finish("roof_parapet");
}

/// Car atlas (paint areas near white, tinted by vertex colour): [0, .5]x[0, .5] body side,
/// [.5, 1]x[0, .5] body front/back, [0, .5]x[.5, 1] cabin sides, [.5, 1]x[.5, 1] tops.
Texture carTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{235, 235, 235}, seed);
  const Rgb dark{30, 30, 34}, glass{60, 72, 86}, trim{120, 120, 124};
  // Body side: wheels, door seams, sill.
  c.rect(0, 0.42, 0.5, 0.5, dark);
  c.circle(0.1, 0.44, 0.06, dark);
  c.circle(0.4, 0.44, 0.06, dark);
  c.circle(0.1, 0.44, 0.03, trim);
  c.circle(0.4, 0.44, 0.03, trim);
  c.rect(0.2, 0.05, 0.203, 0.38, trim);
  c.rect(0.3, 0.05, 0.303, 0.38, trim);
  c.rect(0.22, 0.18, 0.24, 0.19, dark);
  c.rect(0.32, 0.18, 0.34, 0.19, dark);
  // Front/back: grille and lights.
  c.rect(0.58, 0.25, 0.92, 0.33, dark);
  c.rect(0.53, 0.12, 0.6, 0.2, Rgb{240, 220, 160});
  c.rect(0.9, 0.12, 0.97, 0.2, Rgb{240, 220, 160});
  c.rect(0.66, 0.38, 0.84, 0.44, Rgb{225, 225, 215});  // Number plate.
  // Cabin sides/front: windows.
  c.rect(0.03, 0.56, 0.47, 0.96, glass);
  c.rect(0.24, 0.56, 0.26, 0.96, Rgb{230, 230, 230});
  // Tops: hood lines, sunroof.
  c.rect(0.55, 0.55, 0.95, 0.95, Rgb{228, 228, 228});
  c.outline(0.62, 0.64, 0.88, 0.86, 0.006, trim);
  c.noise(0.03, 0.03, 4, 4, 1);
  return c.finish("car");
}

Texture leavesTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{60, 104, 46}, seed);
  Rng rng(seed);
  for (int i = 0; i < 120; ++i)
    c.circle(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0.01, 0.05),
             Rgb{60, 104, 46}.scaled(rng.uniform(0.6, 1.4)));
  c.noise(0.25, 0.15, 8, 8, 1);
  return c.finish("leaves");
}

Texture barkTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{96, 74, 56}, seed);
  for (int i = 0; i < 16; ++i) c.rect(i / 16.0, 0, i / 16.0 + 0.02, 1, Rgb{70, 54, 40});
  c.noise(0.2, 0.2, 16, 2, 1);
  return c.finish("bark");
}

// ---- facades -----------------------------------------------------------------------------------

enum class FacadeKind { kPunched, kBrick, kRibbon, kCurtain, kBalcony, kPanels, kClassic, kIndustrial };

struct FacadeStyle {
  const char* name;
  FacadeKind kind;
  Rgb wall, frame, glass;
  double bay_m;    ///< Nominal bay width, metres.
  double floor_m;  ///< Floor height, metres.
};

const std::array<FacadeStyle, 8> kFacadeStyles{{
    {"facade_plaster", FacadeKind::kPunched, {226, 214, 188}, {245, 245, 240}, {70, 90, 110}, 3.2, 3.1},
    {"facade_brick", FacadeKind::kBrick, {150, 72, 52}, {235, 232, 224}, {52, 62, 74}, 3.0, 3.0},
    {"facade_office", FacadeKind::kRibbon, {178, 178, 174}, {60, 64, 70}, {80, 104, 124}, 3.6, 3.5},
    {"facade_glass", FacadeKind::kCurtain, {70, 90, 100}, {190, 196, 200}, {76, 112, 136}, 3.0, 3.6},
    {"facade_balcony", FacadeKind::kBalcony, {238, 236, 230}, {90, 90, 94}, {66, 80, 96}, 3.4, 3.0},
    {"facade_panels", FacadeKind::kPanels, {200, 202, 206}, {50, 52, 56}, {60, 76, 92}, 3.0, 3.2},
    {"facade_classic", FacadeKind::kClassic, {210, 168, 104}, {240, 236, 226}, {56, 64, 76}, 3.0, 3.4},
    {"facade_metal", FacadeKind::kIndustrial, {150, 160, 168}, {70, 74, 80}, {90, 110, 126}, 3.6, 3.6},
}};

/// Upper-floor facade tile: 4 bays wide (u) by 2 floors high (v); v = 0 and 0.5 are floor
/// boundaries, each floor occupies [f / 2, (f + 1) / 2] with its floor level at the bottom.
Texture facadeTexture(int size, uint32_t seed, const FacadeStyle& st) {
  Canvas c(size, st.wall, seed);
  Rng rng(seed);
  const double ft = 0.012;                                                // Window frame thickness.
  auto floorY = [](int f, double h) { return (f + 1) * 0.5 - h * 0.5; };  // h: fraction of floor.
  switch (st.kind) {
    case FacadeKind::kBrick: {
      const int courses = std::max(8, size / 6);
      for (int j = 0; j < courses; ++j) {
        const int bricks = courses / 3;
        for (int i = 0; i < bricks; ++i) {
          const double x0 = (i + 0.5 * (j % 2)) / bricks, y0 = double(j) / courses;
          c.rect(x0, y0, x0 + 1.0 / bricks, y0 + 1.0 / courses, st.wall.scaled(0.85 + 0.3 * hashUnit(seed, i, j)));
          c.rect(x0, y0, x0 + 0.004, y0 + 1.0 / courses, Rgb{190, 180, 165});
        }
        c.rect(0, double(j) / courses, 1, double(j) / courses + 0.004, Rgb{190, 180, 165});
      }
      break;
    }
    case FacadeKind::kPanels: {
      for (int f = 0; f < 2; ++f)
        for (int i = 0; i < 8; ++i) {
          const double t = hashUnit(seed, i, f, 5);
          const Rgb col = t < 0.2 ? Rgb{190, 90, 60} : st.wall.scaled(0.85 + 0.3 * t);
          c.rect(i / 8.0, f * 0.5, (i + 1) / 8.0, f * 0.5 + 0.5, col);
          c.rect(i / 8.0, f * 0.5, i / 8.0 + 0.005, f * 0.5 + 0.5, Rgb{110, 112, 116});
        }
      break;
    }
    case FacadeKind::kIndustrial: {
      for (int i = 0; i < 32; ++i) c.rect(i / 32.0, 0, i / 32.0 + 1.0 / 64, 1, st.wall.scaled(0.8));
      break;
    }
    default:
      break;
  }
  for (int f = 0; f < 2; ++f) {
    const double top = f * 0.5;
    // Floor slab / spandrel line at the floor level.
    if (st.kind == FacadeKind::kPunched || st.kind == FacadeKind::kBalcony)
      c.rect(0, top + 0.5 - 0.02, 1, top + 0.5, st.wall.scaled(0.85));
    if (st.kind == FacadeKind::kClassic) {
      c.rect(0, top + 0.5 - 0.035, 1, top + 0.5, st.wall.mix(Rgb{245, 240, 230}, 0.6));
      c.rect(0, top + 0.5 - 0.04, 1, top + 0.5 - 0.035, st.wall.scaled(0.6));
    }
    if (st.kind == FacadeKind::kRibbon) {
      c.gradient(0, floorY(f, 0.85), 1, floorY(f, 0.3), st.glass.scaled(0.8), st.glass.scaled(1.2));
      for (int i = 0; i < 8; ++i) {
        const double x = i / 8.0;
        c.rect(x - ft / 2, floorY(f, 0.85), x + ft / 2, floorY(f, 0.3), st.frame);
        if (rng.chance(0.4))
          c.rect(x + ft / 2, floorY(f, 0.85), x + 1.0 / 8 - ft / 2, floorY(f, 0.85) + rng.uniform(0.05, 0.2),
                 Rgb{210, 205, 190});
      }
      c.rect(0, floorY(f, 0.85) - ft, 1, floorY(f, 0.85), st.frame);
      c.rect(0, floorY(f, 0.3), 1, floorY(f, 0.3) + ft, st.frame);
      continue;
    }
    if (st.kind == FacadeKind::kCurtain) {
      for (int i = 0; i < 8; ++i) {
        const double x0 = i / 8.0;
        const double tone = 0.8 + 0.4 * hashUnit(seed, i, f, 9);
        c.gradient(x0, top, x0 + 1.0 / 8, floorY(f, 0.25), st.glass.scaled(tone * 1.15), st.glass.scaled(tone * 0.85));
        c.rect(x0, floorY(f, 0.25), x0 + 1.0 / 8, top + 0.5, st.wall);  // Spandrel.
        c.rect(x0, top, x0 + 0.008, top + 0.5, st.frame);
      }
      c.rect(0, floorY(f, 0.25), 1, floorY(f, 0.25) + 0.008, st.frame);
      c.rect(0, top, 1, top + 0.01, st.frame);
      continue;
    }
    for (int b = 0; b < 4; ++b) {
      const double cx = (b + 0.5) / 4;
      double w = 0.55 / 4, sill = 0.3, head = 0.8;
      if (st.kind == FacadeKind::kClassic) w = 0.42 / 4, sill = 0.22, head = 0.82;
      if (st.kind == FacadeKind::kPanels) w = 0.5 / 4, sill = 0.35, head = 0.8;
      if (st.kind == FacadeKind::kIndustrial) {
        if (b % 2 == 1) continue;
        w = 0.8 / 4, sill = 0.6, head = 0.85;
      }
      if (st.kind == FacadeKind::kBalcony && (b == 1 || b == 2)) sill = 0.02;  // Balcony doors.
      const double x0 = cx - w / 2, x1 = cx + w / 2, y0 = floorY(f, head), y1 = floorY(f, sill);
      if (st.kind == FacadeKind::kClassic) {
        c.rect(x0 - 0.03, y0, x0 - 0.005, y1, Rgb{70, 110, 80});  // Shutters.
        c.rect(x1 + 0.005, y0, x1 + 0.03, y1, Rgb{70, 110, 80});
        c.poly({{x0 - 0.01, y0 - 0.01}, {x1 + 0.01, y0 - 0.01}, {cx, y0 - 0.05}}, st.frame);
      }
      if (st.kind == FacadeKind::kBrick) c.rect(x0 - 0.01, y0 - 0.025, x1 + 0.01, y0, Rgb{200, 190, 170});
      drawWindow(c, rng, x0, y0, x1, y1, st.frame, st.glass, st.kind != FacadeKind::kIndustrial,
                 st.kind == FacadeKind::kClassic || st.kind == FacadeKind::kBrick, ft);
      if (sill > 0.1) c.rect(x0 - 0.008, y1, x1 + 0.008, y1 + 0.01, st.frame.scaled(0.9));  // Sill.
      if (st.kind == FacadeKind::kBalcony && (b == 1 || b == 2)) {
        // Balcony slab and railing in front of the doors.
        const double bx0 = (b == 1 ? 0.25 : 0.5) + 0.02, bx1 = bx0 + 0.21;
        const double ry = floorY(f, 0.35);
        for (double x = bx0; x < bx1; x += 0.012) c.rect(x, ry, x + 0.003, floorY(f, 0.0), Rgb{60, 60, 64});
        c.rect(bx0, ry - 0.006, bx1, ry, Rgb{60, 60, 64});
        c.rect(bx0, floorY(f, 0.0) - 0.03, bx1, floorY(f, 0.0), Rgb{160, 160, 160});
      }
    }
  }
  c.noise(0.05, 0.06, 4, 4, 1);
  return c.finish(st.name);
}

enum class GroundKind { kShop, kResidential, kLobby, kGarage };
struct GroundStyle {
  const char* name;
  GroundKind kind;
  Rgb wall, accent;
};
const std::array<GroundStyle, 4> kGroundStyles{{
    {"ground_shop", GroundKind::kShop, {90, 90, 96}, {180, 40, 40}},
    {"ground_residential", GroundKind::kResidential, {200, 190, 170}, {110, 70, 50}},
    {"ground_lobby", GroundKind::kLobby, {60, 66, 72}, {200, 200, 205}},
    {"ground_garage", GroundKind::kGarage, {150, 150, 150}, {120, 124, 130}},
}};

/// Ground floor: 4 bays wide (u), the whole ground floor high (v = 0 at its top, 1 at ground).
Texture groundFloorTexture(int size, uint32_t seed, const GroundStyle& st) {
  Canvas c(size, st.wall, seed);
  Rng rng(seed);
  const Rgb glass{50, 62, 74}, frame{40, 40, 44};
  c.rect(0, 0.92, 1, 1, st.wall.scaled(0.6));  // Plinth.
  for (int b = 0; b < 4; ++b) {
    const double x0 = b / 4.0, x1 = (b + 1) / 4.0;
    switch (st.kind) {
      case GroundKind::kShop: {
        c.rect(x0, 0.0, x1, 0.16, st.accent.scaled(b % 2 ? 0.8 : 1.0));  // Sign band.
        for (int k = 0; k < 5; ++k) c.rect(x0 + 0.03 + k * 0.04, 0.05, x0 + 0.055 + k * 0.04, 0.11, Rgb{240, 240, 230});
        if (b == 2) {
          drawWindow(c, rng, x0 + 0.07, 0.3, x1 - 0.07, 0.92, frame, glass, true, false, 0.012);
        } else {
          drawWindow(c, rng, x0 + 0.02, 0.24, x1 - 0.02, 0.85, frame, glass.scaled(1.3), true, false, 0.012);
        }
        break;
      }
      case GroundKind::kResidential: {
        if (b == 1) {
          c.rect(x0 + 0.05, 0.32, x1 - 0.05, 0.92, st.accent);  // Wooden door with panels.
          c.outline(x0 + 0.07, 0.36, x1 - 0.07, 0.6, 0.008, st.accent.scaled(0.7));
          c.outline(x0 + 0.07, 0.64, x1 - 0.07, 0.88, 0.008, st.accent.scaled(0.7));
          c.rect(x0 + 0.03, 0.28, x1 - 0.03, 0.32, Rgb{80, 80, 84});  // Canopy.
        } else {
          drawWindow(c, rng, x0 + 0.06, 0.3, x1 - 0.06, 0.7, Rgb{240, 240, 236}, glass, true, false, 0.012);
          c.rect(x0 + 0.05, 0.7, x1 - 0.05, 0.72, Rgb{220, 220, 216});
        }
        break;
      }
      case GroundKind::kLobby: {
        drawWindow(c, rng, x0, 0.12, x1, 0.92, st.accent, glass, b != 1, true, 0.01);
        if (b == 1) c.rect(x0 + 0.08, 0.45, x1 - 0.08, 0.92, Rgb{70, 80, 90});
        break;
      }
      case GroundKind::kGarage: {
        if (b % 2 == 0) {
          c.rect(x0 + 0.02, 0.2, x1 - 0.02, 0.92, st.accent);
          for (double y = 0.22; y < 0.92; y += 0.03) c.rect(x0 + 0.02, y, x1 - 0.02, y + 0.006, st.accent.scaled(0.7));
        } else {
          c.rect(x0 + 0.08, 0.3, x1 - 0.08, 0.92, Rgb{90, 60, 45});
          drawWindow(c, rng, x0 + 0.09, 0.12, x1 - 0.09, 0.24, frame, glass, false, false, 0.008);
        }
        break;
      }
    }
  }
  c.noise(0.05, 0.06, 4, 4, 1);
  return c.finish(st.name);
}

// ---- room textures -----------------------------------------------------------------------------

/// Wooden floor, 2 m tile: planks 0.2 m wide along u, staggered butt joints, grain.
Texture woodFloorTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{168, 120, 76}, seed);
  const int planks = 10;
  for (int i = 0; i < planks; ++i) {
    const double y0 = double(i) / planks, y1 = double(i + 1) / planks;
    const double joint = hashUnit(seed, i, 1);
    for (int k = -1; k < 2; ++k) {
      const double xa = joint + k * 0.5;
      const double tone = 0.8 + 0.35 * hashUnit(seed, i, k + 5);
      c.rect(xa, y0, xa + 0.5, y1, Rgb{168, 120, 76}.scaled(tone));
      c.rect(xa, y0, xa + 0.004, y1, Rgb{90, 60, 36});
    }
    c.rect(0, y0, 1, y0 + 0.004, Rgb{90, 60, 36});
  }
  c.noise(0.06, 0.18, 2, 64, 1);  // Grain: stretched along the planks.
  c.noise(0.05, 0.0, 4, 4, 2);
  return c.finish("wood_floor");
}

/// Wall paint, u 3 m per tile, v the full 3 m height (v = 1 at the floor): skirting board,
/// two-tone paint split by a rail at 1 m.
Texture wallTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{232, 228, 216}, seed);
  c.rect(0, 2.0 / 3.0, 1, 1, Rgb{150, 170, 178});
  c.rect(0, 2.0 / 3.0 - 0.012, 1, 2.0 / 3.0, Rgb{250, 250, 246});
  c.rect(0, 2.0 / 3.0, 1, 2.0 / 3.0 + 0.004, Rgb{120, 130, 136});
  c.rect(0, 1 - 0.03, 1, 1, Rgb{250, 250, 246});  // Skirting.
  c.rect(0, 1 - 0.03, 1, 1 - 0.026, Rgb{150, 150, 146});
  c.rect(0.6, 0.8, 0.64, 0.83, Rgb{245, 245, 240});  // Socket.
  c.outline(0.6, 0.8, 0.64, 0.83, 0.004, Rgb{160, 160, 160});
  c.noise(0.03, 0.03, 4, 4, 1);
  return c.finish("wall_paint");
}

/// Suspended ceiling, 2.4 m tile: 4 x 4 tiles of 0.6 m with metal grid.
Texture ceilingTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{236, 236, 232}, seed);
  for (int i = 0; i < 4; ++i) {
    c.rect(i / 4.0, 0, i / 4.0 + 0.012, 1, Rgb{180, 182, 184});
    c.rect(0, i / 4.0, 1, i / 4.0 + 0.012, Rgb{180, 182, 184});
  }
  c.noise(0.12, 0.03, 4, 4, 1);
  return c.finish("ceiling_tiles");
}

Texture doorTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{140, 96, 60}, seed);
  c.outline(0, 0, 1, 1, 0.06, Rgb{236, 234, 228});  // Frame.
  c.outline(0.18, 0.1, 0.82, 0.45, 0.02, Rgb{110, 74, 46});
  c.outline(0.18, 0.52, 0.82, 0.92, 0.02, Rgb{110, 74, 46});
  c.rect(0.78, 0.5, 0.9, 0.52, Rgb{200, 200, 205});  // Handle.
  c.circle(0.8, 0.55, 0.012, Rgb{80, 80, 84});
  c.noise(0.05, 0.15, 2, 32, 1);
  return c.finish("door");
}

Texture windowTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{245, 245, 242}, seed);
  c.gradient(0.06, 0.06, 0.94, 0.94, Rgb{150, 190, 230}, Rgb{220, 232, 240});
  // Skyline outside.
  Rng rng(seed);
  for (double x = 0.06; x < 0.94; x += rng.uniform(0.05, 0.12)) {
    const double h = rng.uniform(0.5, 0.8);
    c.rect(x, h, std::min(0.94, x + rng.uniform(0.04, 0.1)), 0.94, Rgb{120, 128, 140}.scaled(rng.uniform(0.8, 1.2)));
  }
  c.outline(0, 0, 1, 1, 0.06, Rgb{245, 245, 242});
  c.rect(0.485, 0, 0.515, 1, Rgb{245, 245, 242});
  c.rect(0, 0.36, 1, 0.39, Rgb{245, 245, 242});
  c.noise(0.02, 0.02, 4, 4, 1);
  return c.finish("window");
}

Texture whiteboardTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{246, 247, 248}, seed);
  Rng rng(seed);
  c.outline(0, 0, 1, 1, 0.025, Rgb{170, 174, 178});
  const Rgb ink[3] = {{30, 40, 130}, {20, 20, 24}, {170, 30, 30}};
  for (int i = 0; i < 6; ++i) {  // "Text" lines.
    const double y = 0.12 + i * 0.07;
    double x = 0.06;
    while (x < rng.uniform(0.3, 0.5)) {
      const double w = rng.uniform(0.02, 0.06);
      c.line(x, y, x + w, y + rng.uniform(-0.01, 0.01), 0.006, ink[i % 3]);
      x += w + 0.015;
    }
  }
  c.outline(0.58, 0.12, 0.78, 0.3, 0.006, ink[0]);  // Boxes and arrows of a diagram.
  c.outline(0.62, 0.55, 0.9, 0.72, 0.006, ink[1]);
  c.line(0.68, 0.3, 0.74, 0.55, 0.006, ink[2]);
  c.circle(0.3, 0.75, 0.1, ink[1], 0.006);
  c.line(0.2, 0.75, 0.4, 0.75, 0.005, ink[2]);
  c.rect(0.05, 0.955, 0.95, 0.975, Rgb{150, 154, 158});  // Pen tray.
  return c.finish("whiteboard");
}

Texture posterTexture(int size, uint32_t seed, int variant) {
  Rng rng(seed);
  if (variant == 0) {  // Graphic poster with title bars.
    Canvas c(size, Rgb{240, 200, 60}, seed);
    c.circle(0.4, 0.35, 0.22, Rgb{220, 60, 40});
    c.poly({{0.5, 0.2}, {0.95, 0.65}, {0.4, 0.65}}, Rgb{30, 60, 120});
    c.rect(0.08, 0.75, 0.92, 0.8, Rgb{20, 20, 20});
    for (int i = 0; i < 3; ++i) c.rect(0.08, 0.84 + i * 0.04, rng.uniform(0.4, 0.9), 0.86 + i * 0.04, Rgb{40, 40, 40});
    c.outline(0, 0, 1, 1, 0.02, Rgb{250, 250, 250});
    c.noise(0.03, 0.02, 4, 4, 1);
    return c.finish("poster_graphic");
  }
  if (variant == 1) {  // Map-like poster.
    Canvas c(size, Rgb{226, 232, 220}, seed);
    for (int i = 0; i < 14; ++i)
      c.line(rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1), 0.01, Rgb{200, 120, 60});
    for (int i = 0; i < 6; ++i)
      c.rect(rng.uniform(0.05, 0.8), rng.uniform(0.05, 0.8), rng.uniform(0.1, 0.95), rng.uniform(0.1, 0.95),
             Rgb{150, 190, 140});
    c.outline(0, 0, 1, 1, 0.04, Rgb{40, 40, 44});
    c.noise(0.03, 0.02, 4, 4, 1);
    return c.finish("poster_map");
  }
  // Framed painting: landscape in a dark wooden frame.
  Canvas c(size, Rgb{90, 60, 40}, seed);
  c.gradient(0.08, 0.08, 0.92, 0.6, Rgb{110, 150, 210}, Rgb{230, 210, 170});
  c.poly({{0.08, 0.6}, {0.3, 0.3}, {0.5, 0.5}, {0.7, 0.25}, {0.92, 0.6}}, Rgb{90, 100, 120});
  c.rect(0.08, 0.6, 0.92, 0.92, Rgb{80, 130, 60});
  c.circle(0.75, 0.2, 0.05, Rgb{250, 230, 150});
  c.rect(0.3, 0.7, 0.6, 0.74, Rgb{70, 110, 170});
  c.outline(0.08, 0.08, 0.92, 0.92, 0.015, Rgb{200, 170, 100});
  c.noise(0.05, 0.03, 4, 4, 1);
  return c.finish("painting");
}

Texture plainTexture(int size, uint32_t seed, const char* name, Rgb base, double fine, double coarse, int cx, int cy) {
  Canvas c(size, base, seed);
  c.noise(fine, coarse, cx, cy, 1);
  return c.finish(name);
}

/// Cardboard: mapped 0..1 on every face, tape along the middle, a label.
Texture cardboardTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{190, 150, 100}, seed);
  c.rect(0.44, 0, 0.56, 1, Rgb{205, 175, 120});
  c.rect(0.1, 0.6, 0.35, 0.8, Rgb{240, 240, 235});
  for (int i = 0; i < 3; ++i) c.rect(0.12, 0.63 + i * 0.05, 0.3, 0.645 + i * 0.05, Rgb{50, 50, 50});
  c.outline(0, 0, 1, 1, 0.01, Rgb{150, 115, 75});
  c.noise(0.06, 0.06, 4, 4, 1);
  return c.finish("cardboard");
}

/// Book: the spine maps u 0..1, with bands and a title block; covers are plain.
Texture bookTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{225, 225, 225}, seed);
  c.rect(0, 0.1, 1, 0.14, Rgb{200, 180, 90});
  c.rect(0, 0.86, 1, 0.9, Rgb{200, 180, 90});
  c.rect(0.2, 0.25, 0.8, 0.6, Rgb{245, 245, 240});
  for (int i = 0; i < 4; ++i) c.rect(0.3, 0.3 + i * 0.07, 0.7, 0.33 + i * 0.07, Rgb{60, 60, 60});
  c.noise(0.04, 0.05, 4, 4, 1);
  return c.finish("book");
}

Texture lightPanelTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{252, 252, 250}, seed);
  c.outline(0, 0, 1, 1, 0.05, Rgb{200, 200, 204});
  for (int i = 1; i < 4; ++i) c.rect(i / 4.0 - 0.006, 0, i / 4.0 + 0.006, 1, Rgb{230, 230, 232});
  return c.finish("light_panel");
}

Texture rugTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{150, 40, 40}, seed);
  c.outline(0.04, 0.04, 0.96, 0.96, 0.06, Rgb{220, 200, 150});
  c.outline(0.14, 0.14, 0.86, 0.86, 0.02, Rgb{30, 40, 90});
  c.poly({{0.5, 0.25}, {0.75, 0.5}, {0.5, 0.75}, {0.25, 0.5}}, Rgb{220, 200, 150});
  c.poly({{0.5, 0.35}, {0.65, 0.5}, {0.5, 0.65}, {0.35, 0.5}}, Rgb{30, 40, 90});
  c.noise(0.15, 0.05, 4, 4, 1);
  return c.finish("rug");
}

Texture screenTexture(int size, uint32_t seed) {
  Canvas c(size, Rgb{30, 30, 34}, seed);
  c.gradient(0.05, 0.06, 0.95, 0.94, Rgb{40, 90, 160}, Rgb{20, 40, 90});
  c.rect(0.1, 0.12, 0.55, 0.7, Rgb{240, 240, 240});
  for (int i = 0; i < 8; ++i) c.rect(0.13, 0.16 + i * 0.06, 0.5, 0.18 + i * 0.06, Rgb{90, 90, 100});
  c.rect(0.05, 0.88, 0.95, 0.94, Rgb{200, 200, 210});
  return c.finish("screen");
}

// ================================================================================================
// Geometry
// ================================================================================================

struct V3 {
  double x = 0, y = 0, z = 0;
  double operator[](int i) const { return i == 0 ? x : i == 1 ? y : z; }
  double& operator[](int i) { return i == 0 ? x : i == 1 ? y : z; }
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(double s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

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
UvMap fitUv(double s0, double t0, double s1, double t1, double u0, double v0, double u1, double v1) {
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
void sortUnique(std::vector<double>& v) {
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

/// Face of a box: material, texture rectangle (u0, v0, u1, v1) or metric tiling, colour.
struct FaceLook {
  int material = 0;
  std::array<double, 4> uv{0, 0, 1, 1};
  double tile_m = 0;  ///< > 0: texture repeats every tile_m metres instead of fitting uv.
  bool enabled = true;
};

/// Index of box faces: +x, -x, +y, -y, +z, -z.
enum BoxFace { kFacePosX, kFaceNegX, kFacePosY, kFaceNegY, kFacePosZ, kFaceNegZ };

/// A closed axis-aligned box [lo, hi] with outward-facing faces.
void addBox(MeshBuilder& mb, V3 lo, V3 hi, const std::array<FaceLook, 6>& look, Rgba8 color, bool split = false) {
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

std::array<FaceLook, 6> allFaces(int material, double tile_m = 0) {
  std::array<FaceLook, 6> a;
  for (auto& f : a) f.material = material, f.tile_m = tile_m;
  return a;
}

/// Walls around a rectilinear region (outside facing out), as maximal straight segments.
struct WallSeg {
  double ax, ay, bx, by;  ///< From the left end to the right end seen from outside.
  double nx, ny;          ///< Outward normal.
  double length() const { return std::abs(bx - ax) + std::abs(by - ay); }
};

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

const Frame kGroundFrame{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
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

}  // namespace

// ================================================================================================
// City
// ================================================================================================
namespace {

constexpr double kHalfMap = 100.0;  ///< The map spans [-kHalfMap, kHalfMap] in x and y.
constexpr double kRoadHalf = 6.0;   ///< Half road width.
constexpr double kWalk = 3.0;       ///< Sidewalk width.
constexpr double kKerbH = 0.15;     ///< Sidewalk and lot height above the road.
constexpr double kGap = 0.002;      ///< Loose objects float this far above what they stand on.
constexpr double kSkirt = 0.05;     ///< Walls and kerbs reach this far below the surface around them.
constexpr int kMaxBuildings = 30;

const V3 kX{1, 0, 0}, kY{0, 1, 0}, kZ{0, 0, 1}, kNegX{-1, 0, 0}, kNegY{0, -1, 0};

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

// ================================================================================================
// Room
// ================================================================================================
namespace {

struct RoomMaterials {
  int floor, wall, ceiling, door, window, whiteboard, poster_graphic, poster_map, painting;
  int frame, wood, metal, fabric, cardboard, book, light, rug, screen, pot, leaves;
};

RoomMaterials addRoomMaterials(MeshBuilder& mb, uint32_t seed, int size) {
  uint32_t k = 0;
  auto ts = [&] { return textureSeed(seed, 2, k++); };
  RoomMaterials m{};
  m.floor = mb.addTexturedMaterial(woodFloorTexture(size, ts()));
  m.wall = mb.addTexturedMaterial(wallTexture(size, ts()));
  m.ceiling = mb.addTexturedMaterial(ceilingTexture(size, ts()));
  m.door = mb.addTexturedMaterial(doorTexture(size, ts()));
  m.window = mb.addTexturedMaterial(windowTexture(size, ts()));
  m.whiteboard = mb.addTexturedMaterial(whiteboardTexture(size, ts()));
  m.poster_graphic = mb.addTexturedMaterial(posterTexture(size, ts(), 0));
  m.poster_map = mb.addTexturedMaterial(posterTexture(size, ts(), 1));
  m.painting = mb.addTexturedMaterial(posterTexture(size, ts(), 2));
  m.frame = mb.addTexturedMaterial(plainTexture(size, ts(), "frame_wood", {92, 62, 40}, 0.05, 0.2, 2, 32));
  m.wood = mb.addTexturedMaterial(plainTexture(size, ts(), "wood", {196, 160, 112}, 0.05, 0.2, 2, 48));
  m.metal = mb.addTexturedMaterial(plainTexture(size, ts(), "metal", {150, 154, 160}, 0.04, 0.06, 4, 4));
  m.fabric = mb.addTexturedMaterial(plainTexture(size, ts(), "fabric", {200, 200, 200}, 0.08, 0.1, 8, 8));
  m.cardboard = mb.addTexturedMaterial(cardboardTexture(size, ts()));
  m.book = mb.addTexturedMaterial(bookTexture(size, ts()));
  m.light = mb.addTexturedMaterial(lightPanelTexture(size, ts()));
  m.rug = mb.addTexturedMaterial(rugTexture(size, ts()));
  m.screen = mb.addTexturedMaterial(screenTexture(size, ts()));
  m.pot = mb.addTexturedMaterial(plainTexture(size, ts(), "terracotta", {176, 96, 64}, 0.08, 0.1, 4, 4));
  m.leaves = mb.addTexturedMaterial(leavesTexture(size, ts()));
  return m;
}

constexpr double kRoomX = 3.0, kRoomY = 2.5, kRoomH = 3.0;

/// An opening [s0, s1] x [t0, t1] in a wall frame, recessed `depth` behind the wall: reveal
/// faces (jambs, head, and a sill when t0 > 0) and a back panel, all facing into the room.
void addRecess(MeshBuilder& mb, const Frame& f, double s0, double t0, double s1, double t1, double depth,
               int reveal_material, int panel_material) {
  const V3 n = cross(f.eu, f.ev);
  const V3 back = -depth * n;
  const double w = s1 - s0, h = t1 - t0;
  mb.rect(Frame{f.at(s0, t0) + back, f.eu, f.ev}, 0, 0, w, h, fitUv(0, 0, w, h, 0, 0, 1, 1), panel_material);
  auto reveal = [&](V3 a, V3 b, V3 facing, double len) {
    // Quad a, b, b + back, a + back; texture from the plain upper part of the wall paint.
    mb.quad(a, b, b + back, a + back, {0, 0.1}, {len / 3, 0.1}, {len / 3, 0.1 + depth / 3}, {0, 0.1 + depth / 3},
            reveal_material, kWhite, facing);
  };
  reveal(f.at(s0, t0), f.at(s0, t1), f.eu, h);
  reveal(f.at(s1, t0), f.at(s1, t1), -1.0 * f.eu, h);
  reveal(f.at(s0, t1), f.at(s1, t1), -1.0 * f.ev, w);
  if (t0 > 0) reveal(f.at(s0, t0), f.at(s1, t0), f.ev, w);
}

/// A thin wall-mounted panel (poster, whiteboard, painting): `front` faces the room.
void addWallPanel(MeshBuilder& mb, V3 lo, V3 hi, BoxFace front, int front_material, int edge_material) {
  std::array<FaceLook, 6> look = allFaces(edge_material, 0.5);
  look[front] = FaceLook{front_material, {0, 0, 1, 1}, 0, true};
  addBox(mb, lo, hi, look, kWhite);
}

}  // namespace

Model makeDemoRoom(const DemoModelOptions& options) {
  const int size = clampTextureSize(options.texture_size);
  Rng rng(hash4(options.seed, 0x800Au));
  MeshBuilder mb;
  const RoomMaterials rm = addRoomMaterials(mb, options.seed, size);
  const double X = kRoomX, Y = kRoomY, H = kRoomH;

  // ---- shell: walls (seen from inside), floor, ceiling ----------------------------------------
  const Frame south{{X, -Y, 0}, kNegX, kZ}, north{{-X, Y, 0}, kX, kZ};
  const Frame west{{-X, -Y, 0}, kY, kZ}, east{{X, Y, 0}, kNegY, kZ};
  const UvMap wall_uv{1 / 3.0, 0, -1 / H, 1};
  const double win_x0 = -0.9, win_x1 = 0.5, win_z0 = 0.9, win_z1 = 2.1, win_depth = 0.2;
  const double door_y0 = 1.2, door_y1 = 2.1, door_h = 2.1, door_depth = 0.12;
  const Rect window_st{X - win_x1, win_z0, X - win_x0, win_z1};  // In the south wall's (s, t).
  const Rect door_st{Y - door_y1, 0, Y - door_y0, door_h};       // In the east wall's (s, t).
  mb.region(south, Region{{{0, 0, 2 * X, H}}, {window_st}}, wall_uv, rm.wall);
  mb.region(north, Region{{{0, 0, 2 * X, H}}, {}}, wall_uv, rm.wall);
  mb.region(west, Region{{{0, 0, 2 * Y, H}}, {}}, wall_uv, rm.wall);
  mb.region(east, Region{{{0, 0, 2 * Y, H}}, {door_st}}, wall_uv, rm.wall);
  addRecess(mb, south, window_st.x0, window_st.y0, window_st.x1, window_st.y1, win_depth, rm.wall, rm.window);
  addRecess(mb, east, door_st.x0, door_st.y0, door_st.x1, door_st.y1, door_depth, rm.wall, rm.door);
  mb.region(horizontalFrame(0), Region{{{-X, -Y, X, Y}, {X, door_y0, X + door_depth, door_y1}}, {}},
            UvMap{0.5, 0, 0.5, 0}, rm.floor);
  mb.region(Frame{{0, 0, H}, kX, kNegY}, Region{{{-X, -Y, X, Y}}, {}}, UvMap{1 / 2.4, 0, 1 / 2.4, 0}, rm.ceiling);

  // ---- wall-mounted items ---------------------------------------------------------------------
  const double g = kGap;
  addWallPanel(mb, {-1.8, Y - g - 0.025, 0.9}, {0.2, Y - g, 2.0}, kFaceNegY, rm.whiteboard, rm.metal);
  addWallPanel(mb, {0.8, Y - g - 0.004, 1.2}, {1.6, Y - g, 2.2}, kFaceNegY, rm.poster_graphic, rm.poster_graphic);
  addWallPanel(mb, {X - g - 0.03, -1.6, 1.2}, {X - g, -0.6, 1.9}, kFaceNegX, rm.painting, rm.frame);
  addWallPanel(mb, {1.2, -Y + g, 1.2}, {2.2, -Y + g + 0.004, 1.9}, kFacePosY, rm.poster_map, rm.poster_map);
  for (double lx : {-1.5, 0.9}) {
    std::array<FaceLook, 6> look = allFaces(rm.metal, 0.5);
    look[kFaceNegZ] = FaceLook{rm.light, {0, 0, 1, 1}, 0, true};
    addBox(mb, {lx, -0.6, H - g - 0.04}, {lx + 0.6, 0.6, H - g}, look, kWhite);
  }

  // ---- bookcase against the west wall ---------------------------------------------------------
  const double bx0 = -X + g, bx1 = -X + 0.35, by0 = -0.8, by1 = 0.8, bh = 2.0, board = 0.02;
  const Rgba8 shelf_tint = tint(rng, 0.2);
  addBox(mb, {bx0, by0, g}, {bx1, by0 + board, bh}, allFaces(rm.wood, 1.0), shelf_tint);
  addBox(mb, {bx0, by1 - board, g}, {bx1, by1, bh}, allFaces(rm.wood, 1.0), shelf_tint);
  addBox(mb, {bx0, by0 + board + g, g}, {bx0 + 0.01, by1 - board - g, bh - g}, allFaces(rm.wood, 1.0), shelf_tint);
  const double shelf_z[] = {0.06, 0.5, 0.95, 1.45, bh - board - g};
  for (double z : shelf_z)
    addBox(mb, {bx0 + 0.01 + g, by0 + board + g, z}, {bx1, by1 - board - g, z + board}, allFaces(rm.wood, 1.0),
           shelf_tint);
  static const Rgba8 kBookColors[] = {{170, 40, 40, 255},  {40, 60, 140, 255}, {40, 110, 60, 255},
                                      {220, 190, 70, 255}, {40, 40, 44, 255},  {230, 230, 225, 255},
                                      {120, 70, 130, 255}, {200, 110, 40, 255}};
  for (size_t k = 0; k + 1 < std::size(shelf_z); ++k) {
    const double z0 = shelf_z[k] + board + g, space = shelf_z[k + 1] - z0 - 0.02;
    double y = by0 + board + g + g;
    const double y_end = by1 - board - g - g;
    while (true) {
      const double w = rng.uniform(0.02, 0.055);
      if (y + w > y_end) break;
      if (rng.chance(0.08)) {  // A gap in the row.
        y += rng.uniform(0.04, 0.12);
        continue;
      }
      const double h = std::min(space, rng.uniform(0.17, 0.3)), d = rng.uniform(0.15, 0.24);
      std::array<FaceLook, 6> look = allFaces(rm.book);
      look[kFacePosX].uv = {0, 0, 1, 1};                                                     // Spine faces the room.
      look[kFacePosZ].uv = look[kFaceNegZ].uv = look[kFaceNegX].uv = {0.3, 0.3, 0.7, 0.55};  // Pages.
      look[kFacePosY].uv = look[kFaceNegY].uv = {0.02, 0.16, 0.1, 0.24};                     // Covers.
      addBox(mb, {bx1 - 0.005 - d, y, z0}, {bx1 - 0.005, y + w, z0 + h}, look, kBookColors[rng.range(0, 7)]);
      y += w + g;
    }
  }

  // ---- rug, table, chairs, things on the table -----------------------------------------------
  const double rug_top = g + 0.01;
  addBox(mb, {-1.0, -0.9, g}, {1.4, 1.5, rug_top},
         std::array<FaceLook, 6>{FaceLook{rm.rug, {0, 0, 0.05, 0.05}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}},
                                 FaceLook{rm.rug, {0, 0, 0.05, 0.05}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}},
                                 FaceLook{rm.rug, {0, 0, 1, 1}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}}},
         kWhite);
  const double tx0 = -0.6, tx1 = 1.0, ty0 = -0.15, ty1 = 0.75, tz = 0.74;
  addBox(mb, {tx0, ty0, tz - 0.04}, {tx1, ty1, tz}, allFaces(rm.wood, 1.0), kWhite);
  for (double lx : {tx0 + 0.05, tx1 - 0.1})
    for (double ly : {ty0 + 0.05, ty1 - 0.1})
      addBox(mb, {lx, ly, rug_top + g}, {lx + 0.05, ly + 0.05, tz - 0.04 - g}, allFaces(rm.metal, 0.5), kWhite);
  // Laptop: base and screen (screen texture towards -y).
  addBox(mb, {0.0, 0.1, tz + g}, {0.33, 0.33, tz + g + 0.018}, allFaces(rm.metal, 0.5), kWhite);
  {
    std::array<FaceLook, 6> look = allFaces(rm.metal, 0.5);
    look[kFaceNegY] = FaceLook{rm.screen, {0, 0, 1, 1}, 0, true};
    addBox(mb, {0.0, 0.335, tz + g}, {0.33, 0.345, tz + g + 0.22}, look, kWhite);
  }
  {
    std::array<FaceLook, 6> look = allFaces(rm.book);
    look[kFacePosZ].uv = {0, 0, 1, 1};
    addBox(mb, {0.55, 0.35, tz + g}, {0.8, 0.52, tz + g + 0.035}, look, kBookColors[1]);
    addBox(mb, {0.57, 0.36, tz + 2 * g + 0.035}, {0.78, 0.5, tz + 2 * g + 0.065}, look, kBookColors[3]);
  }
  addBox(mb, {0.42, -0.02, tz + g}, {0.5, 0.06, tz + g + 0.1}, allFaces(rm.metal, 0.2), Rgba8{240, 240, 240, 255});
  // Chairs: seat, four legs, back on the side away from the table.
  auto chair = [&](double cx, double cy, bool back_south) {
    const double s = 0.21, seat_z = 0.45;
    const Rgba8 c = tint(rng, 0.3);
    addBox(mb, {cx - s, cy - s, seat_z}, {cx + s, cy + s, seat_z + 0.04}, allFaces(rm.fabric, 0.5), c);
    for (double lx : {cx - s + 0.01, cx + s - 0.04})
      for (double ly : {cy - s + 0.01, cy + s - 0.04})
        addBox(mb, {lx, ly, rug_top + g}, {lx + 0.03, ly + 0.03, seat_z - g}, allFaces(rm.metal, 0.5), kWhite);
    const double y0 = back_south ? cy - s - g - 0.03 : cy + s + g, y1 = y0 + 0.03;
    addBox(mb, {cx - s, y0, seat_z + 0.05}, {cx + s, y1, 0.95}, allFaces(rm.fabric, 0.5), c);
  };
  chair(-0.15, -0.5, true);
  chair(0.65, -0.5, true);
  chair(0.2, 1.1, false);

  // ---- couch in the south-west corner ----------------------------------------------------------
  {
    const Rgba8 c = tint(rng, 0.5), cushion = tint(rng, 0.4);
    const double y0 = -Y + g, y1 = -1.6;
    const std::array<FaceLook, 6> fab = allFaces(rm.fabric, 0.5);
    addBox(mb, {-2.9, y0, g}, {-2.752, y1, 0.62}, fab, c);
    addBox(mb, {-1.248, y0, g}, {-1.1, y1, 0.62}, fab, c);
    addBox(mb, {-2.75, y0, g}, {-1.25, y1, 0.25}, fab, c);
    addBox(mb, {-2.75, y0, 0.25 + g}, {-1.25, -2.3, 0.85}, fab, c);
    for (double x0 : {-2.75, -1.998}) {
      addBox(mb, {x0, -2.3 + g, 0.25 + g}, {x0 + 0.748, y1, 0.42}, fab, cushion);
      addBox(mb, {x0, -2.3 + g, 0.42 + g}, {x0 + 0.748, -2.14, 0.8}, fab, cushion);
    }
  }

  // ---- cardboard boxes in the south-east corner, plant in the north-west corner ------------------
  {
    std::array<FaceLook, 6> look = allFaces(rm.cardboard);
    addBox(mb, {2.3, -Y + 0.05, g}, {2.95, -1.9, 0.45}, look, kWhite);
    addBox(mb, {2.35, -Y + 0.1, 0.45 + g}, {2.85, -1.95, 0.8}, look, Rgba8{235, 225, 215, 255});
    addBox(mb, {1.7, -Y + 0.05, g}, {2.2, -2.0, 0.35}, look, Rgba8{225, 220, 210, 255});
  }
  addBox(mb, {-2.9, 2.05, g}, {-2.5, 2.45, 0.4}, allFaces(rm.pot, 0.5), kWhite);
  addTree(mb, rm.wood, rm.leaves, -2.7, 2.25, 0.4, 0.35, 0.22, 0.02, rng);

  return mb.build("demo:room", options.target_triangles);
}

std::vector<std::string> demoModelNames() { return {"city", "room"}; }

Result<Model> makeDemoModel(const std::string& name, const DemoModelOptions& options) {
  if (options.texture_size < 16 || options.texture_size > 4096)
    return makeError(ErrorCode::kInvalidArgument,
                     "demo model texture_size " + std::to_string(options.texture_size) + " is outside 16..4096");
  if (name == "city") return makeDemoCity(options);
  if (name == "room") return makeDemoRoom(options);
  return makeError(ErrorCode::kNotFound, "unknown demo model '" + name + "'; available: city, room");
}

std::vector<Pose> demoViewpoints(const std::string& name) {
  struct View {
    double ex, ey, ez, tx, ty, tz;
  };
  std::vector<View> views;
  if (name == "city") {
    // Drone views tilted 45 degrees down; eyes below the roof-tops stay over the streets.
    auto drone = [&](double x, double y, double altitude, double yaw_deg) {
      const double yaw = yaw_deg * kPi / 180;
      views.push_back({x, y, altitude, x + altitude * std::cos(yaw), y + altitude * std::sin(yaw), 0});
    };
    drone(1.0, -45.0, 10, 90);
    drone(-66.0, -25.0, 20, 0);
    drone(25.0, 0.5, 30, 180);
    drone(66.0, 40.0, 45, 225);
    drone(-60.0, -60.0, 60, 45);
    drone(0.0, 70.0, 60, -90);
  } else if (name == "room") {
    views = {{2.3, 1.6, 1.5, -2.0, -1.0, 1.0},
             {2.4, -1.0, 1.5, -3.0, 0.0, 1.2},
             {-0.5, -1.8, 1.5, -0.8, 2.5, 1.3},
             {-2.0, 1.8, 1.5, -0.2, -2.5, 1.2},
             {0.3, 1.9, 1.5, 2.6, -2.2, 0.6}};
  }
  std::vector<Pose> poses;
  for (const View& v : views) {
    Result<Pose> T = lookAt(Eigen::Vector3d(v.ex, v.ey, v.ez), Eigen::Vector3d(v.tx, v.ty, v.tz));
    if (T.ok()) poses.push_back(*T);
  }
  return poses;
}

}  // namespace vkloc
