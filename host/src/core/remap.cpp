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

Result<ImageU8> remapBilinear(const ImageU8& source, const RemapTable& table) {
  VKLOC_TRY_STATUS(validateRemapTable(table));
  const int sw = table.source_width, sh = table.source_height;
  if (source.channels != 1 || source.width != sw || source.height != sh ||
      source.data.size() != static_cast<size_t>(sw) * static_cast<size_t>(sh)) {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("remapBilinear: source image is ", source.width, "x", source.height, "x",
                               source.channels, ", the table expects ", sw, "x", sh, " single-channel"));
  }
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
    const float value = top_w + bottom_w;
    out.data[i] = static_cast<uint8_t>(std::clamp(std::floor(value + 0.5f), 0.0f, 255.0f));
  }
  return out;
}

}  // namespace vkloc
