// Procedural textures of the demo models, drawn with OpenCV primitives plus hash noise.
#include <opencv2/imgproc.hpp>

#include "sim/demo_internal.hpp"

namespace vkloc::demo_detail {
namespace {

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

}  // namespace

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

}  // namespace vkloc::demo_detail
