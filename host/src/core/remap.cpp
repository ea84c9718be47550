// Reference image remap through a table (remap.hpp). Standard library only.
#include "vkloc/core/remap.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "vkloc/core/text.hpp"

namespace vkloc {

namespace {
constexpr int kMaxRemapSide = 16384;
}  // namespace

Status validateRemapTable(const RemapTable& table) {
  auto bad = [](const char* field, int v) {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("remap table: ", field, " = ", v, " is outside 1..", kMaxRemapSide));
  };
  if (table.width < 1 || table.width > kMaxRemapSide) return bad("width", table.width);
  if (table.height < 1 || table.height > kMaxRemapSide) return bad("height", table.height);
  if (table.source_width < 1 || table.source_width > kMaxRemapSide) return bad("source_width", table.source_width);
  if (table.source_height < 1 || table.source_height > kMaxRemapSide) return bad("source_height", table.source_height);
  const size_t expected = 2 * static_cast<size_t>(table.width) * static_cast<size_t>(table.height);
  if (table.uv.size() != expected) {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("remap table: uv holds ", table.uv.size(), " floats, a ", table.width, "x", table.height,
                               " table needs ", expected, " (u, v per output pixel)"));
  }
  return Status::success();
}

namespace {

/// kInvalidArgument unless `source` is a single-channel image of the table's source size.
Status checkSource(const char* who, const ImageU8& source, const RemapTable& table) {
  const int sw = table.source_width, sh = table.source_height;
  if (source.channels != 1 || source.width != sw || source.height != sh ||
      source.data.size() != static_cast<size_t>(sw) * static_cast<size_t>(sh)) {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat(who, ": source image is ", source.width, "x", source.height, "x", source.channels,
                               ", the table expects ", sw, "x", sh, " single-channel"));
  }
  return Status::success();
}

// Cubic convolution kernel W(d) (remap.hpp) with a = -0.75, one rounded operation per statement
// as shaders/remap.comp computes it. The constants are exact in float: a + 2 = 1.25, a + 3 = 2.25,
// 5a = -3.75, 8a = -6, 4a = -3.
constexpr float kCubicA = -0.75f;

/// W(d) for 0 <= d <= 1: ((a + 2) d - (a + 3)) d d + 1.
float cubicNear(float d) {
  const float p = (kCubicA + 2.0f) * d;
  const float q = p - (kCubicA + 3.0f);
  const float r = q * d;
  const float s = r * d;
  return s + 1.0f;
}

/// W(d) for 1 <= d <= 2: ((a d - 5a) d + 8a) d - 4a.
float cubicFar(float d) {
  const float p = kCubicA * d;
  const float q = p - 5.0f * kCubicA;
  const float r = q * d;
  const float s = r + 8.0f * kCubicA;
  const float t = s * d;
  return t - 4.0f * kCubicA;
}

/// The 4 weights of the taps at -1, 0, 1, 2 for a fraction 0 <= t < 1.
void cubicWeights(float t, float w[4]) {
  const float d0 = 1.0f + t, d2 = 1.0f - t, d3 = 2.0f - t;
  w[0] = cubicFar(d0);
  w[1] = cubicNear(t);
  w[2] = cubicNear(d2);
  w[3] = cubicFar(d3);
}

/// ((w0 p0 + w1 p1) + w2 p2) + w3 p3, one rounded operation per statement.
float cubicSum(const float w[4], const float p[4]) {
  const float m0 = w[0] * p[0], m1 = w[1] * p[1], m2 = w[2] * p[2], m3 = w[3] * p[3];
  const float s01 = m0 + m1;
  const float s012 = s01 + m2;
  return s012 + m3;
}

/// The loop shared by the reference remaps: validates `table` and `source` (errors name `who`),
/// then for each output pixel whose (u, v) lies on the source rounds
/// sample(src, sw, sh, x0, y0, fx, fy) to uint8, where (x0, y0) = floor(u, v) and (fx, fy) the
/// fractions in [0, 1). Other pixels (NaN, +-inf, off the source) stay 0.
template <typename Sample>
Result<ImageU8> remapEach(const char* who, const ImageU8& source, const RemapTable& table, Sample&& sample) {
  VKLOC_TRY_STATUS(validateRemapTable(table));
  VKLOC_TRY_STATUS(checkSource(who, source, table));
  const int sw = table.source_width, sh = table.source_height;
  ImageU8 out(table.width, table.height, 1);
  const float max_u = static_cast<float>(sw - 1), max_v = static_cast<float>(sh - 1);
  const uint8_t* src = source.data.data();
  const size_t n = out.data.size();
  for (size_t i = 0; i < n; ++i) {
    const float u = table.uv[2 * i], v = table.uv[2 * i + 1];
    // Written so that NaN fails every comparison: NaN, +-inf and positions off the source give 0.
    if (!(u >= 0.0f && u <= max_u && v >= 0.0f && v <= max_v)) continue;
    const float x0f = std::floor(u), y0f = std::floor(v);
    const float fx = u - x0f, fy = v - y0f;  // exact
    const int x0 = static_cast<int>(x0f), y0 = static_cast<int>(y0f);
    const float value = sample(src, sw, sh, x0, y0, fx, fy);
    out.data[i] = static_cast<uint8_t>(std::clamp(std::floor(value + 0.5f), 0.0f, 255.0f));
  }
  return out;
}

}  // namespace

const char* remapInterpolationName(RemapInterpolation interpolation) {
  return interpolation == RemapInterpolation::kBicubic ? "bicubic" : "bilinear";
}

Result<ImageU8> remapBilinear(const ImageU8& source, const RemapTable& table) {
  const auto sample = [](const uint8_t* src, int sw, int sh, int x0, int y0, float fx, float fy) {
    const int x1 = std::min(x0 + 1, sw - 1), y1 = std::min(y0 + 1, sh - 1);
    const uint8_t* row0 = src + static_cast<size_t>(y0) * sw;
    const uint8_t* row1 = src + static_cast<size_t>(y1) * sw;
    const float a = row0[x0], b = row0[x1], c = row1[x0], d = row1[x1];
    // value = (1 - fy) ((1 - fx) a + fx b) + fy ((1 - fx) c + fx d), every product and sum
    // rounded to float in this order, as shaders/remap.comp does (`precise` there). One operation
    // per statement: compilers that contract a * b + c into an fma within an expression (clang's
    // default where the target has fma) cannot change the rounding.
    const float gx = 1.0f - fx, gy = 1.0f - fy;
    const float a_w = gx * a, b_w = fx * b, c_w = gx * c, d_w = fx * d;
    const float top = a_w + b_w, bottom = c_w + d_w;
    const float top_w = gy * top, bottom_w = fy * bottom;
    return top_w + bottom_w;
  };
  return remapEach("remapBilinear", source, table, sample);
}

Result<ImageU8> remapBicubic(const ImageU8& source, const RemapTable& table) {
  const auto sample = [](const uint8_t* src, int sw, int sh, int x0, int y0, float tx, float ty) {
    int xs[4];
    for (int k = 0; k < 4; ++k) xs[k] = std::clamp(x0 - 1 + k, 0, sw - 1);  // BORDER_REPLICATE
    float wx[4], wy[4];
    cubicWeights(tx, wx);
    cubicWeights(ty, wy);
    float rows[4];
    for (int k = 0; k < 4; ++k) {
      const uint8_t* row = src + static_cast<size_t>(std::clamp(y0 - 1 + k, 0, sh - 1)) * sw;
      float p[4];
      for (int j = 0; j < 4; ++j) p[j] = row[xs[j]];
      rows[k] = cubicSum(wx, p);
    }
    return cubicSum(wy, rows);
  };
  return remapEach("remapBicubic", source, table, sample);
}

Result<ImageU8> remapImage(const ImageU8& source, const RemapTable& table, RemapInterpolation interpolation) {
  return interpolation == RemapInterpolation::kBicubic ? remapBicubic(source, table) : remapBilinear(source, table);
}

}  // namespace vkloc
