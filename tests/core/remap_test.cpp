// Tests of the reference remap (core/remap.hpp).
#include "vkloc/core/remap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

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

}  // namespace
}  // namespace vkloc
