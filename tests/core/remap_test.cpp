// Tests of the reference remaps (core/remap.hpp): bilinear and bicubic, bicubic against OpenCV's
// INTER_CUBIC, and the fixed-point bicubic fast path against the reference.
#include "vkloc/core/remap.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace vkloc {
namespace {

ImageU8 rampImage(int w, int h) {
  ImageU8 image(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) image.at(x, y) = static_cast<uint8_t>((x * 37 + y * 11) % 256);
  }
  return image;
}

/// Output w x h sampling a source of sw x sh at (x + du, y + dv).
RemapTable shiftTable(int w, int h, int sw, int sh, float du, float dv) {
  RemapTable table{w, h, sw, sh, {}};
  table.uv.resize(2 * static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      table.uv[2 * (static_cast<size_t>(y) * w + x)] = static_cast<float>(x) + du;
      table.uv[2 * (static_cast<size_t>(y) * w + x) + 1] = static_cast<float>(y) + dv;
    }
  }
  return table;
}

TEST(Remap, IdentityTableGivesTheSourceBack) {
  const ImageU8 source = rampImage(37, 23);
  auto out = remapBilinear(source, shiftTable(37, 23, 37, 23, 0.0f, 0.0f));
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->width, 37);
  EXPECT_EQ(out->height, 23);
  EXPECT_EQ(out->channels, 1);
  EXPECT_EQ(out->data, source.data);
}

TEST(Remap, HalfPixelShiftAveragesNeighboursRoundingHalfUp) {
  const ImageU8 source = rampImage(16, 9);
  // Half a pixel right: (a + b) / 2, rounded half up. The last column samples at w - 0.5,
  // outside the source, and is 0.
  auto right = remapBilinear(source, shiftTable(16, 9, 16, 9, 0.5f, 0.0f));
  ASSERT_TRUE(right.ok());
  for (int y = 0; y < 9; ++y) {
    for (int x = 0; x < 15; ++x) {
      const int sum = source.at(x, y) + source.at(x + 1, y);
      EXPECT_EQ(right->at(x, y), (sum + 1) / 2) << x << "," << y;
    }
    EXPECT_EQ(right->at(15, y), 0);
  }
  // Half a pixel right and down: the mean of four, rounded half up.
  auto diagonal = remapBilinear(source, shiftTable(15, 8, 16, 9, 0.5f, 0.5f));
  ASSERT_TRUE(diagonal.ok());
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 15; ++x) {
      const int sum = source.at(x, y) + source.at(x + 1, y) + source.at(x, y + 1) + source.at(x + 1, y + 1);
      EXPECT_EQ(diagonal->at(x, y), (sum + 2) / 4) << x << "," << y;
    }
  }
}

TEST(Remap, SubPixelWeightsFollowTheBilinearFormula) {
  ImageU8 source(2, 2, 1);
  source.data = {10, 200, 60, 250};  // a b / c d
  RemapTable table{1, 1, 2, 2, {0.25f, 0.75f}};
  auto out = remapBilinear(source, table);
  ASSERT_TRUE(out.ok());
  const double value = 0.25 * (0.75 * 10 + 0.25 * 200) + 0.75 * (0.75 * 60 + 0.25 * 250);  // 99.375
  EXPECT_EQ(out->data[0], static_cast<uint8_t>(std::floor(value + 0.5)));
}

TEST(Remap, PositionsOffTheSourceOrNotFiniteGiveZero) {
  const ImageU8 source(8, 6, 1, 77);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  // Pairs (u, v); the source covers [0, 7] x [0, 5].
  const float positions[][2] = {{0.0f, 0.0f},   {7.0f, 5.0f},   {3.5f, 2.5f},    {-0.001f, 1.0f},
                                {7.001f, 1.0f}, {1.0f, -1e-6f}, {1.0f, 5.0001f}, {nan, 1.0f},
                                {1.0f, nan},    {inf, 1.0f},    {1.0f, -inf},    {-1e30f, 1e30f}};
  constexpr int kCount = sizeof(positions) / sizeof(positions[0]);
  RemapTable table{kCount, 1, 8, 6, {}};
  for (const auto& p : positions) {
    table.uv.push_back(p[0]);
    table.uv.push_back(p[1]);
  }
  auto out = remapBilinear(source, table);
  ASSERT_TRUE(out.ok()) << out.error().message;
  const uint8_t expected[kCount] = {77, 77, 77, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  for (int i = 0; i < kCount; ++i) {
    EXPECT_EQ(out->data[i], expected[i]) << "position " << i << " (" << positions[i][0] << ", " << positions[i][1]
                                         << ")";
  }
}

TEST(Remap, SizeMismatchesAreErrors) {
  const ImageU8 source = rampImage(8, 6);
  RemapTable table = shiftTable(4, 3, 8, 6, 0.0f, 0.0f);
  ASSERT_TRUE(validateRemapTable(table).ok());
  ASSERT_TRUE(remapBilinear(source, table).ok());

  RemapTable short_uv = table;
  short_uv.uv.pop_back();
  Status status = validateRemapTable(short_uv);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
  auto result = remapBilinear(source, short_uv);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(result.error().message.find("uv"), std::string::npos) << result.error().message;

  for (auto mutate : {+[](RemapTable& t) { t.width = 0; }, +[](RemapTable& t) { t.height = -3; },
                      +[](RemapTable& t) { t.source_width = 16385; }, +[](RemapTable& t) { t.source_height = 0; }}) {
    RemapTable bad = table;
    mutate(bad);
    EXPECT_FALSE(validateRemapTable(bad).ok());
    auto r = remapBilinear(source, bad);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
  }

  // The source must be single-channel and of the table's source size.
  for (const ImageU8& wrong : {rampImage(7, 6), rampImage(8, 5), ImageU8(8, 6, 3), ImageU8()}) {
    auto r = remapBilinear(wrong, table);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(r.error().message.find("8x6"), std::string::npos) << r.error().message;
  }
  ImageU8 truncated = rampImage(8, 6);
  truncated.data.pop_back();
  EXPECT_FALSE(remapBilinear(truncated, table).ok());
}

/// Every pixel of the output through `remap` with positions (u, v) given per pixel.
RemapTable pointsTable(int sw, int sh, const std::vector<float>& uv) {
  return RemapTable{static_cast<int>(uv.size() / 2), 1, sw, sh, uv};
}

TEST(RemapBicubic, ConstantImageStaysConstant) {
  // The weights sum to 1 (up to float rounding), border taps replicate: every position with a
  // source gives the constant, at the borders and corners too.
  for (const uint8_t level : {uint8_t{0}, uint8_t{1}, uint8_t{77}, uint8_t{254}, uint8_t{255}}) {
    const ImageU8 source(9, 7, 1, level);
    std::mt19937 rng(level + 1u);
    std::uniform_real_distribution<float> U(0.0f, 8.0f), V(0.0f, 6.0f);
    std::vector<float> uv = {0.0f, 0.0f, 8.0f, 6.0f, 0.3f, 5.9f, 7.99f, 0.01f, 0.5f, 0.5f};
    for (int i = 0; i < 500; ++i) {
      uv.push_back(U(rng));
      uv.push_back(V(rng));
    }
    auto out = remapBicubic(source, pointsTable(9, 7, uv));
    ASSERT_TRUE(out.ok()) << out.error().message;
    for (size_t i = 0; i < out->data.size(); ++i) {
      ASSERT_EQ(out->data[i], level) << "level " << int{level} << " at (" << uv[2 * i] << ", " << uv[2 * i + 1] << ")";
    }
  }
}

TEST(RemapBicubic, IntegerPositionsGiveTheSource) {
  // At t = 0 the weights are exactly (0, 1, 0, 0).
  const ImageU8 source = rampImage(37, 23);
  auto out = remapBicubic(source, shiftTable(37, 23, 37, 23, 0.0f, 0.0f));
  ASSERT_TRUE(out.ok()) << out.error().message;
  EXPECT_EQ(out->data, source.data);
  // A shift by whole pixels: the shifted source, the last column and row without a source.
  auto shifted = remapBicubic(source, shiftTable(37, 23, 37, 23, 2.0f, 1.0f));
  ASSERT_TRUE(shifted.ok());
  for (int y = 0; y < 23; ++y) {
    for (int x = 0; x < 37; ++x) {
      const uint8_t expected = x + 2 < 37 && y + 1 < 23 ? source.at(x + 2, y + 1) : 0;
      ASSERT_EQ(shifted->at(x, y), expected) << x << "," << y;
    }
  }
}

TEST(RemapBicubic, ReproducesLinearRampsUpToTheKernelsPositionBias) {
  // The weights sum to 1, so constants are kept; their first moment is not t but
  // t + delta(t), delta(t) = -(2a + 1) t (1 - t) (1 - 2t) (0 only for a = -1/2, Keys 1981; for
  // a = -0.75 |delta| <= 0.048 px, 0 at t = 0 and 1/2). So a linear ramp sampled away from the
  // borders at (u, v) is the ramp at (u + delta(tx), v + delta(ty)), up to the final rounding.
  constexpr int kW = 40, kH = 30;
  ImageU8 source(kW, kH, 1);
  auto ramp = [](double x, double y) { return 2.0 * x + 3.0 * y + 10.0; };  // 10..175
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) source.at(x, y) = static_cast<uint8_t>(ramp(x, y));
  }
  auto delta = [](double t) { return 0.5 * t * (1 - t) * (1 - 2 * t); };  // -(2a + 1) = 0.5
  std::mt19937 rng(7);
  // All 16 taps inside: x0 - 1 >= 0 and x0 + 2 <= w - 1.
  std::uniform_real_distribution<float> U(1.0f, kW - 2.001f), V(1.0f, kH - 2.001f);
  std::vector<float> uv;
  for (int i = 0; i < 2000; ++i) {
    uv.push_back(U(rng));
    uv.push_back(V(rng));
  }
  // Half-pixel positions: no bias, the exact mean of the neighbours (x.5 values round up).
  for (int i = 0; i < 20; ++i) {
    uv.push_back(1.5f + static_cast<float>(i));
    uv.push_back(1.5f + static_cast<float>(i % 25));
  }
  auto out = remapBicubic(source, pointsTable(kW, kH, uv));
  ASSERT_TRUE(out.ok()) << out.error().message;
  double worst_unbiased = 0;
  for (size_t i = 0; i < out->data.size(); ++i) {
    const double u = uv[2 * i], v = uv[2 * i + 1];
    const double expected = ramp(u + delta(u - std::floor(u)), v + delta(v - std::floor(v)));
    ASSERT_LE(std::abs(out->data[i] - expected), 0.5 + 1e-3) << "at (" << u << ", " << v << ")";
    worst_unbiased = std::max(worst_unbiased, std::abs(out->data[i] - ramp(u, v)));
  }
  // The bias is real: without it, some samples are off by more than the rounding.
  EXPECT_GT(worst_unbiased, 0.5 + 1e-3);
  for (size_t i = 2000; i < out->data.size(); ++i) {
    EXPECT_EQ(out->data[i], static_cast<uint8_t>(std::floor(ramp(uv[2 * i], uv[2 * i + 1]) + 0.5)));
  }
}

TEST(RemapBicubic, WeightsFollowTheCubicConvolutionFormula) {
  // One row of 4 pixels sampled at u = 1.25 (t = 0.25), v = 0: the value is
  // W(1.25) p0 + W(0.25) p1 + W(0.75) p2 + W(1.75) p3 with a = -0.75.
  ImageU8 source(4, 1, 1);
  source.data = {20, 100, 180, 40};
  auto W = [](double d) {
    const double a = -0.75;
    d = std::abs(d);
    return d <= 1 ? ((a + 2) * d - (a + 3)) * d * d + 1 : ((a * d - 5 * a) * d + 8 * a) * d - 4 * a;
  };
  auto out = remapBicubic(source, pointsTable(4, 1, {1.25f, 0.0f, 0.5f, 0.0f}));
  ASSERT_TRUE(out.ok()) << out.error().message;
  const double at_125 = W(1.25) * 20 + W(0.25) * 100 + W(0.75) * 180 + W(1.75) * 40;
  EXPECT_EQ(out->data[0], static_cast<uint8_t>(std::floor(at_125 + 0.5))) << at_125;
  // u = 0.5: the tap at -1 replicates pixel 0.
  const double at_05 = W(1.5) * 20 + W(0.5) * 20 + W(0.5) * 100 + W(1.5) * 180;
  EXPECT_EQ(out->data[1], static_cast<uint8_t>(std::floor(at_05 + 0.5))) << at_05;
  // Overshoot past 0..255 is clamped: a step sampled next to its edge.
  ImageU8 step(4, 1, 1);
  step.data = {0, 0, 255, 255};
  auto clamped = remapBicubic(step, pointsTable(4, 1, {0.5f, 0.0f, 2.5f, 0.0f}));
  ASSERT_TRUE(clamped.ok());
  EXPECT_EQ(clamped->data[0], 0);    // W(1.5) * 255 < 0 before clamping
  EXPECT_EQ(clamped->data[1], 255);  // 255 - W(1.5) * 255 > 255 before clamping
}

TEST(RemapBicubic, PositionsOffTheSourceOrNotFiniteGiveZero) {
  const ImageU8 source(8, 6, 1, 77);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<float> uv = {0.0f, 0.0f,    7.0f, 5.0f, 3.5f, 2.5f, -0.001f, 1.0f, 7.001f, 1.0f, 1.0f,   -1e-6f,
                                 1.0f, 5.0001f, nan,  1.0f, 1.0f, nan,  inf,     1.0f, 1.0f,   -inf, -1e30f, 1e30f};
  auto out = remapBicubic(source, pointsTable(8, 6, uv));
  ASSERT_TRUE(out.ok()) << out.error().message;
  const std::vector<uint8_t> expected = {77, 77, 77, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(out->data, expected);
}

TEST(RemapBicubic, SizeMismatchesAreErrors) {
  const ImageU8 source = rampImage(8, 6);
  const RemapTable table = shiftTable(4, 3, 8, 6, 0.0f, 0.0f);
  ASSERT_TRUE(remapBicubic(source, table).ok());
  RemapTable short_uv = table;
  short_uv.uv.pop_back();
  auto result = remapBicubic(source, short_uv);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kInvalidArgument);
  RemapTable no_width = table;
  no_width.width = 0;
  EXPECT_FALSE(remapBicubic(source, no_width).ok());
  for (const ImageU8& wrong : {rampImage(7, 6), rampImage(8, 5), ImageU8(8, 6, 3), ImageU8()}) {
    auto r = remapBicubic(wrong, table);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(r.error().message.find("remapBicubic"), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("8x6"), std::string::npos) << r.error().message;
  }
}

TEST(RemapBicubic, RemapImageDispatchesOnTheInterpolation) {
  const ImageU8 source = rampImage(32, 24);
  const RemapTable table = shiftTable(30, 22, 32, 24, 0.37f, 0.61f);
  auto bilinear = remapImage(source, table, RemapInterpolation::kBilinear);
  auto bicubic = remapImage(source, table, RemapInterpolation::kBicubic);
  ASSERT_TRUE(bilinear.ok() && bicubic.ok());
  EXPECT_EQ(bilinear->data, remapBilinear(source, table)->data);
  EXPECT_EQ(bicubic->data, remapBicubic(source, table)->data);
  EXPECT_NE(bilinear->data, bicubic->data);
  EXPECT_STREQ(remapInterpolationName(RemapInterpolation::kBilinear), "bilinear");
  EXPECT_STREQ(remapInterpolationName(RemapInterpolation::kBicubic), "bicubic");
  EXPECT_FALSE(remapImage(ImageU8(), table, RemapInterpolation::kBicubic).ok());
}

/// A seeded smooth-ish image: two broad waves over a tilted ramp under soft discs whose edges
/// ramp over 2..5 px (a defocused edge), 8-bit.
ImageU8 smoothImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double p1 = 6.3 * U(rng), p2 = 6.3 * U(rng);
  std::vector<double> value(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double sx = static_cast<double>(x) / w, sy = static_cast<double>(y) / h;
      value[static_cast<size_t>(y) * w + x] = 120 + 40 * (sx - sy) + 30 * std::sin(6.3 * (1.3 * sx + 0.7 * sy) + p1) +
                                              20 * std::sin(6.3 * (2.1 * sx - 1.7 * sy) + p2);
    }
  }
  for (int s = 0; s < 25; ++s) {
    const double cx = U(rng) * w, cy = U(rng) * h, r = 5 + U(rng) * 0.1 * w, g = 20 + 215 * U(rng);
    const double ramp = 2 + 3 * U(rng);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double cover = std::clamp(0.5 - (std::hypot(x - cx, y - cy) - r) / ramp, 0.0, 1.0);
        double& v = value[static_cast<size_t>(y) * w + x];
        v = (1 - cover) * v + cover * g;
      }
    }
  }
  ImageU8 out(w, h, 1);
  for (size_t i = 0; i < value.size(); ++i) {
    out.data[i] = static_cast<uint8_t>(std::clamp(std::round(value[i]), 0.0, 255.0));
  }
  return out;
}

/// A rotation and zoom about the centre with a radial term, w x h from a source of the same size:
/// positions off the pixel grid, some of them off the source.
RemapTable turnedTable(int w, int h) {
  RemapTable table{w, h, w, h, {}};
  table.uv.resize(2 * static_cast<size_t>(w) * h);
  const double angle = 0.21, scale = 0.93;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double dx = x - 0.5 * (w - 1), dy = y - 0.5 * (h - 1);
      const double r2 = (dx * dx + dy * dy) / (w * w), k = scale * (1 + 0.15 * r2);
      const size_t i = static_cast<size_t>(y) * w + x;
      table.uv[2 * i] = static_cast<float>(0.5 * (w - 1) + k * (std::cos(angle) * dx - std::sin(angle) * dy) + 0.3);
      table.uv[2 * i + 1] =
          static_cast<float>(0.5 * (h - 1) + k * (std::sin(angle) * dx + std::cos(angle) * dy) - 0.45);
    }
  }
  return table;
}

TEST(RemapBicubic, AgreesWithOpenCvInterCubicReplicate) {
  // OpenCV's INTER_CUBIC (same kernel, a = -0.75) with BORDER_REPLICATE and a float map:
  // positions quantised to 1/32 px and fixed-point weights, so not bit-exact; the pixels without
  // a source (0 in the reference, replicated border in OpenCV) are left out.
  constexpr int kW = 320, kH = 240;
  const ImageU8 source = smoothImage(kW, kH, 3);
  RemapTable table = turnedTable(kW, kH);
  auto reference = remapBicubic(source, table);
  ASSERT_TRUE(reference.ok()) << reference.error().message;
  const cv::Mat src(kH, kW, CV_8UC1, const_cast<uint8_t*>(source.data.data()));
  const cv::Mat map(kH, kW, CV_32FC2, table.uv.data());
  cv::Mat dst;
  cv::remap(src, dst, map, cv::Mat(), cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  ASSERT_EQ(dst.type(), CV_8UC1);
  size_t compared = 0, within1 = 0, exact = 0, no_source = 0;
  int max_diff = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const size_t i = static_cast<size_t>(y) * kW + x;
      const float u = table.uv[2 * i], v = table.uv[2 * i + 1];
      if (!(u >= 0.0f && u <= kW - 1 && v >= 0.0f && v <= kH - 1)) {
        ++no_source;
        EXPECT_EQ(reference->data[i], 0);
        continue;
      }
      const int d = std::abs(static_cast<int>(dst.at<uint8_t>(y, x)) - static_cast<int>(reference->data[i]));
      ++compared;
      within1 += d <= 1;
      exact += d == 0;
      max_diff = std::max(max_diff, d);
    }
  }
  const double n = static_cast<double>(compared);
  std::printf(
      "[ remap ] bicubic vs cv::INTER_CUBIC + BORDER_REPLICATE, %zu px with a source (%zu without): "
      "equal %.3f %%, within 1 %.3f %%, max |diff| %d\n",
      compared, no_source, 100.0 * exact / n, 100.0 * within1 / n, max_diff);
  EXPECT_GT(no_source, 0u);
  EXPECT_GE(within1 / n, 0.99);
  EXPECT_LE(max_diff, 6);
}

/// Counts of the pixels of `a` against `b`: equal, within 1 gray level, and the largest difference.
struct Difference {
  size_t equal = 0, within1 = 0, count = 0;
  int max_diff = 0;
};
Difference difference(const ImageU8& a, const ImageU8& b) {
  Difference d;
  d.count = a.data.size();
  for (size_t i = 0; i < a.data.size(); ++i) {
    const int diff = std::abs(static_cast<int>(a.data[i]) - static_cast<int>(b.data[i]));
    d.equal += diff == 0;
    d.within1 += diff <= 1;
    d.max_diff = std::max(d.max_diff, diff);
  }
  return d;
}

/// Hard edges: a checkerboard of 7-pixel cells at gray levels 20 and 235 with seeded noise.
ImageU8 edgeImage(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-6, 6);
  ImageU8 image(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int cell = ((x / 7) + (y / 7)) % 2 == 0 ? 20 : 235;
      image.at(x, y) = static_cast<uint8_t>(std::clamp(cell + noise(rng), 0, 255));
    }
  }
  return image;
}

TEST(RemapBicubicFixed, IsTheReferenceAtPositionsRoundedTo1Over32Pixel) {
  // At positions on the 1/32 px grid the fast path differs from the reference only by its
  // 14-bit weights (16 taps x 1/32768 x 255: about 0.12 gray level), so by at most 1 on every
  // pixel, hard edges too. Off the grid it rounds a position by up to 1/64 px: on a smooth image
  // within 1 gray level nearly everywhere; at a hard edge (215 gray levels over a pixel, a slope
  // of about 270 per pixel after the kernel's overshoot) that is up to 4-5 gray levels.
  constexpr int kW = 320, kH = 240;
  const RemapTable table = turnedTable(kW, kH);
  RemapTable rounded = table;
  for (float& p : rounded.uv) p = std::floor(p * 32.0f + 0.5f) / 32.0f;
  for (const bool hard : {false, true}) {
    const ImageU8 source = hard ? edgeImage(kW, kH, 5) : smoothImage(kW, kH, 3);
    for (const bool on_grid : {true, false}) {
      const RemapTable& t = on_grid ? rounded : table;
      auto reference = remapBicubic(source, t);
      auto fast = remapBicubicFixed(source, t);
      ASSERT_TRUE(reference.ok() && fast.ok());
      for (const FixedRemapKernel kernel : {FixedRemapKernel::kSse2, FixedRemapKernel::kScalar}) {
        auto other = remapBicubicFixed(source, t, kernel);
        ASSERT_TRUE(other.ok());
        EXPECT_EQ(other->data, fast->data) << remapBicubicFixedKernel(kernel);
      }
      const Difference d = difference(*fast, *reference);
      const double n = static_cast<double>(d.count);
      std::printf(
          "[ remap ] fixed-point bicubic vs the reference, %s image, positions %s: equal %.3f %%, within 1 "
          "%.3f %%, max %d\n",
          hard ? "hard-edged" : "smooth", on_grid ? "on the 1/32 px grid" : "as they are", 100.0 * d.equal / n,
          100.0 * d.within1 / n, d.max_diff);
      if (on_grid) {
        EXPECT_LE(d.max_diff, 1);
        EXPECT_GE(d.equal / n, 0.99);
      } else if (!hard) {
        EXPECT_GE(d.within1 / n, 0.999);
        EXPECT_LE(d.max_diff, 2);
      } else {
        EXPECT_LE(d.max_diff, 6);
      }
    }
  }
}

constexpr FixedRemapKernel kKernels[] = {FixedRemapKernel::kFastest, FixedRemapKernel::kSse2,
                                         FixedRemapKernel::kScalar};

TEST(RemapBicubicFixed, EveryKernelGivesTheSameImageAndRowsMayBeSplit) {
  // The fastest kernel (AVX2 where the processor has it), SSE2 and one pixel at a time, over odd
  // sizes whose rows end in a partial block, with positions on, near and off the border.
  for (const auto& [w, h] : {std::pair{37, 23}, std::pair{64, 48}, std::pair{13, 5}, std::pair{5, 4}}) {
    const ImageU8 source = edgeImage(w, h, 11);
    RemapTable table = turnedTable(w, h);
    table.uv[0] = std::numeric_limits<float>::quiet_NaN();
    table.uv[3] = std::numeric_limits<float>::infinity();
    auto scalar = remapBicubicFixed(source, table, FixedRemapKernel::kScalar);
    ASSERT_TRUE(scalar.ok());
    for (const FixedRemapKernel kernel : kKernels) {
      auto out = remapBicubicFixed(source, table, kernel);
      ASSERT_TRUE(out.ok());
      EXPECT_EQ(out->data, scalar->data) << w << "x" << h << " " << remapBicubicFixedKernel(kernel);
    }
    ImageU8 split(w, h, 1);
    for (int row = 0; row < h; row += 3) {
      remapBicubicFixedRows(source.data.data(), table, split.data.data(), row, std::min(h, row + 3));
    }
    EXPECT_EQ(split.data, scalar->data) << w << "x" << h;
  }
}

TEST(RemapBicubicFixed, NearTheBorderEveryKernelReplicatesItAsTheReferenceDoes) {
  // Positions on the 1/32 px grid around the last whole pixels (the fast blocks take a pixel only
  // while all 16 taps lie on the source: below sw - 3) on a hard-edged image, eight at a time so
  // that the SIMD kernels see them in full blocks: within 1 gray level of the reference.
  constexpr int kW = 29, kH = 17;
  const ImageU8 source = edgeImage(kW, kH, 7);
  std::vector<float> uv;
  const float near[] = {0.0f, 1.0f / 32, 31.0f / 32, 1.0f, 33.0f / 32};
  for (int k = 0; k < 8; ++k) {
    for (const float base :
         {0.0f, static_cast<float>(kW - 4), static_cast<float>(kW - 3), static_cast<float>(kW - 2)}) {
      for (const float d : near) {
        const float u = std::min(base + d, static_cast<float>(kW - 1));
        const float v =
            std::min(static_cast<float>(kH - 4) + d + static_cast<float>(k % 3), static_cast<float>(kH - 1));
        uv.insert(uv.end(), {u, v, v, u * (kH - 1) / (kW - 1)});
      }
    }
  }
  const RemapTable table = pointsTable(kW, kH, uv);
  auto reference = remapBicubic(source, table);
  ASSERT_TRUE(reference.ok());
  for (const FixedRemapKernel kernel : kKernels) {
    auto fast = remapBicubicFixed(source, table, kernel);
    ASSERT_TRUE(fast.ok());
    EXPECT_LE(difference(*fast, *reference).max_diff, 1) << remapBicubicFixedKernel(kernel);
  }
}

TEST(RemapBicubicFixed, ConstantsWholePixelsAndPixelsWithoutASourceAreExact) {
  // Weights that sum to exactly 1 keep a constant image constant; at whole pixels the kernel is
  // (0, 1, 0, 0) and the fast path equals the reference; positions off the source, NaN and
  // infinities give 0; taps off the source replicate the border as the reference's do.
  ImageU8 flat(20, 16, 1);
  std::fill(flat.data.begin(), flat.data.end(), uint8_t{201});
  auto flat_out = remapBicubicFixed(flat, turnedTable(20, 16));
  ASSERT_TRUE(flat_out.ok());
  const RemapTable turned = turnedTable(20, 16);
  for (size_t i = 0; i < flat_out->data.size(); ++i) {
    const float u = turned.uv[2 * i], v = turned.uv[2 * i + 1];
    const bool on_source = u >= 0.0f && u <= 19.0f && v >= 0.0f && v <= 15.0f;
    EXPECT_EQ(flat_out->data[i], on_source ? 201 : 0) << i;
  }
  const ImageU8 source = edgeImage(37, 23, 2);
  for (const float du : {0.0f, 2.0f, -1.0f}) {
    const RemapTable shifted = shiftTable(37, 23, 37, 23, du, du > 0 ? 1.0f : 0.0f);
    auto reference = remapBicubic(source, shifted);
    for (const FixedRemapKernel kernel : kKernels) {
      auto fast = remapBicubicFixed(source, shifted, kernel);
      ASSERT_TRUE(reference.ok() && fast.ok());
      EXPECT_EQ(fast->data, reference->data) << du << " " << remapBicubicFixedKernel(kernel);
    }
  }
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> uv = {-0.01f, 3.0f, 7.01f, 2.0f, nan, 1.0f, inf, 1.0f, 3.0f, -inf, 0.0f, 0.0f, 7.0f, 5.0f};
  const ImageU8 ramp = rampImage(8, 6);
  auto reference = remapBicubic(ramp, pointsTable(8, 6, uv));
  auto fast = remapBicubicFixed(ramp, pointsTable(8, 6, uv));
  ASSERT_TRUE(reference.ok() && fast.ok());
  EXPECT_EQ(fast->data, reference->data);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(fast->data[static_cast<size_t>(i)], 0) << i;
}

TEST(RemapBicubicFixed, SizeMismatchesAreErrors) {
  const ImageU8 source = rampImage(8, 6);
  RemapTable table = shiftTable(4, 3, 8, 6, 0.0f, 0.0f);
  table.uv.pop_back();
  EXPECT_FALSE(remapBicubicFixed(source, table).ok());
  auto wrong = remapBicubicFixed(rampImage(7, 6), shiftTable(4, 3, 8, 6, 0.0f, 0.0f));
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().message.find("remapBicubicFixed"), std::string::npos) << wrong.error().message;
}

}  // namespace
}  // namespace vkloc
