// Reference image remap through a table (remap.hpp). Standard library only.
#include "vkloc/core/remap.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define VKLOC_REMAP_AVX2 1
#include <immintrin.h>
#endif

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

namespace {

constexpr int kFractionBits = 5;  ///< Positions in 1/32 px.
constexpr int kFractions = 1 << kFractionBits;
constexpr int kWeightBits = 14;  ///< Weights in 1/16384.

/// The 16 weights (row k, tap j at k * 4 + j: the order the taps are loaded in) of each fraction
/// (fy * kFractions + fx), products of remapBicubic's cubicWeights in kWeightBits fixed point,
/// their sum made exactly 1 << kWeightBits by the largest one.
struct BicubicWeights {
  alignas(32) int16_t w[kFractions * kFractions][16];  // a row per 256-bit load
  BicubicWeights() {
    float wx[kFractions][4];
    for (int f = 0; f < kFractions; ++f) cubicWeights(static_cast<float>(f) / kFractions, wx[f]);
    for (int fy = 0; fy < kFractions; ++fy) {
      for (int fx = 0; fx < kFractions; ++fx) {
        int16_t* out = w[fy * kFractions + fx];
        int sum = 0, largest = 0;
        for (int k = 0; k < 4; ++k) {
          for (int j = 0; j < 4; ++j) {
            const double product = static_cast<double>(wx[fy][k]) * static_cast<double>(wx[fx][j]);
            out[k * 4 + j] = static_cast<int16_t>(std::lround(product * (1 << kWeightBits)));
            sum += out[k * 4 + j];
            if (out[k * 4 + j] > out[largest]) largest = k * 4 + j;
          }
        }
        out[largest] = static_cast<int16_t>(out[largest] + ((1 << kWeightBits) - sum));
      }
    }
  }
};

const BicubicWeights& bicubicWeights() {
  static const BicubicWeights weights;
  return weights;
}

uint8_t roundWeighted(int sum) {
  return static_cast<uint8_t>(std::clamp((sum + (1 << (kWeightBits - 1))) >> kWeightBits, 0, 255));
}

/// A pixel whose 4x4 taps may leave the source, or that has none: remapBicubic's rules with
/// the fast path's rounding and weights, taps clamped to the source.
uint8_t bicubicFixedAtBorder(const uint8_t* src, int sw, int sh, float u, float v) {
  if (!(u >= 0.0f && u <= static_cast<float>(sw - 1) && v >= 0.0f && v <= static_cast<float>(sh - 1))) return 0;
  const int iu = static_cast<int>(u * kFractions + 0.5f), iv = static_cast<int>(v * kFractions + 0.5f);
  const int x0 = iu >> kFractionBits, y0 = iv >> kFractionBits;
  const int16_t* w = bicubicWeights().w[(iv & (kFractions - 1)) * kFractions + (iu & (kFractions - 1))];
  int sum = 0;
  for (int k = 0; k < 4; ++k) {
    const uint8_t* row = src + static_cast<size_t>(std::clamp(y0 - 1 + k, 0, sh - 1)) * sw;
    for (int j = 0; j < 4; ++j) sum += w[k * 4 + j] * row[std::clamp(x0 - 1 + j, 0, sw - 1)];
  }
  return roundWeighted(sum);
}

/// The sum of the 16 weighted taps of the pixel whose first tap is at `p` (row k at p + k stride).
int bicubicFixedSum(const uint8_t* p, size_t stride, const int16_t* w) {
  int sum = 0;
  for (int k = 0; k < 4; ++k) {
    for (int j = 0; j < 4; ++j) sum += w[k * 4 + j] * p[k * stride + j];
  }
  return sum;
}

/// One pixel of remapBicubicFixedRows: inside the source (all 16 taps on it: round(32 u) >> 5 in
/// 1..sw - 3, likewise v) its taps and weights, else the border's rules.
uint8_t bicubicFixedPixel(const uint8_t* src, int sw, int sh, float u, float v) {
  if (!(u >= 1.0f && u < static_cast<float>(sw - 3) && v >= 1.0f && v < static_cast<float>(sh - 3))) {
    return bicubicFixedAtBorder(src, sw, sh, u, v);
  }
  const int iu = static_cast<int>(u * kFractions + 0.5f), iv = static_cast<int>(v * kFractions + 0.5f);
  const uint8_t* p = src + static_cast<size_t>((iv >> kFractionBits) - 1) * static_cast<size_t>(sw) +
                     static_cast<size_t>((iu >> kFractionBits) - 1);
  return roundWeighted(bicubicFixedSum(
      p, static_cast<size_t>(sw), bicubicWeights().w[(iv & (kFractions - 1)) * kFractions + (iu & (kFractions - 1))]));
}

#if defined(__SSE2__)
/// The 4 int32 partial sums of the pixel whose first tap is at `p` (their total: bicubicFixedSum).
inline __m128i bicubicFixedPartial(const uint8_t* p, size_t stride, const int16_t* w) {
  int32_t r[4];
  for (int k = 0; k < 4; ++k) std::memcpy(&r[k], p + k * stride, 4);
  const __m128i taps = _mm_set_epi32(r[3], r[2], r[1], r[0]);
  const __m128i zero = _mm_setzero_si128();
  return _mm_add_epi32(
      _mm_madd_epi16(_mm_unpacklo_epi8(taps, zero), _mm_load_si128(reinterpret_cast<const __m128i*>(w))),
      _mm_madd_epi16(_mm_unpackhi_epi8(taps, zero), _mm_load_si128(reinterpret_cast<const __m128i*>(w + 8))));
}
#endif

/// remapBicubicFixedRows's loop on the target's baseline: four pixels at a time with SSE2 (where
/// `sse2` and the target has it), else one at a time.
void bicubicFixedRows(const uint8_t* source, const RemapTable& table, uint8_t* out, int row_begin, int row_end,
                      bool sse2) {
  const int sw = table.source_width, sh = table.source_height;
  const auto one = [&](float u, float v) { return bicubicFixedPixel(source, sw, sh, u, v); };
#if defined(__SSE2__)
  const BicubicWeights& weights = bicubicWeights();
  // Inside these bounds all 16 taps lie on the source (bicubicFixedPixel).
  const float max_u = static_cast<float>(sw - 3), max_v = static_cast<float>(sh - 3);
  const size_t stride = static_cast<size_t>(sw);
#else
  (void)sse2;
#endif
  for (int y = row_begin; y < row_end; ++y) {
    const size_t first = static_cast<size_t>(y) * static_cast<size_t>(table.width);
    const float* uv = table.uv.data() + 2 * first;
    uint8_t* dst = out + first;
    int x = 0;
#if defined(__SSE2__)
    // Four pixels at a time where all four lie inside: positions, tap offsets and weight indices
    // in SIMD, the four sums transposed and added in one register, rounded, shifted and
    // saturated to bytes together (packs / packus clamp to 0..255 as roundWeighted does).
    const __m128 one_f = _mm_set1_ps(1.0f), max_u4 = _mm_set1_ps(max_u), max_v4 = _mm_set1_ps(max_v);
    const __m128 scale = _mm_set1_ps(static_cast<float>(kFractions)), half = _mm_set1_ps(0.5f);
    const __m128i fraction_mask = _mm_set1_epi32(kFractions - 1);
    const __m128i rounding = _mm_set1_epi32(1 << (kWeightBits - 1));
    for (; sse2 && x + 4 <= table.width; x += 4) {
      const __m128 a = _mm_loadu_ps(uv + 2 * x), b = _mm_loadu_ps(uv + 2 * x + 4);
      const __m128 u = _mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));
      const __m128 v = _mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1));
      const __m128 in = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(u, one_f), _mm_cmplt_ps(u, max_u4)),
                                   _mm_and_ps(_mm_cmpge_ps(v, one_f), _mm_cmplt_ps(v, max_v4)));
      if (_mm_movemask_ps(in) != 0xF) {
        for (int i = 0; i < 4; ++i) dst[x + i] = one(uv[2 * (x + i)], uv[2 * (x + i) + 1]);
        continue;
      }
      const __m128i iu = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(u, scale), half));
      const __m128i iv = _mm_cvttps_epi32(_mm_add_ps(_mm_mul_ps(v, scale), half));
      alignas(16) int32_t x0[4], y0[4], index[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(x0), _mm_srli_epi32(iu, kFractionBits));
      _mm_store_si128(reinterpret_cast<__m128i*>(y0), _mm_srli_epi32(iv, kFractionBits));
      _mm_store_si128(reinterpret_cast<__m128i*>(index),
                      _mm_or_si128(_mm_slli_epi32(_mm_and_si128(iv, fraction_mask), kFractionBits),
                                   _mm_and_si128(iu, fraction_mask)));
      __m128i partial[4];
      for (int i = 0; i < 4; ++i) {
        const uint8_t* p = source + static_cast<size_t>(y0[i] - 1) * stride + static_cast<size_t>(x0[i] - 1);
        partial[i] = bicubicFixedPartial(p, stride, weights.w[index[i]]);
      }
      const __m128i s01 =
          _mm_add_epi32(_mm_unpacklo_epi32(partial[0], partial[1]), _mm_unpackhi_epi32(partial[0], partial[1]));
      const __m128i s23 =
          _mm_add_epi32(_mm_unpacklo_epi32(partial[2], partial[3]), _mm_unpackhi_epi32(partial[2], partial[3]));
      const __m128i sums = _mm_add_epi32(_mm_unpacklo_epi64(s01, s23), _mm_unpackhi_epi64(s01, s23));
      const __m128i shifted = _mm_srai_epi32(_mm_add_epi32(sums, rounding), kWeightBits);
      const __m128i words = _mm_packs_epi32(shifted, shifted);
      const int32_t bytes = _mm_cvtsi128_si32(_mm_packus_epi16(words, words));
      std::memcpy(dst + x, &bytes, 4);
    }
#endif
    for (; x < table.width; ++x) dst[x] = one(uv[2 * x], uv[2 * x + 1]);
  }
}

#if defined(VKLOC_REMAP_AVX2)
/// bicubicFixedRows with AVX2 (chosen at run time where the processor has it): eight pixels at a
/// time, each pixel's 16 taps widened and weighted in one 256-bit register; the same integer
/// operations, so the same outputs.
__attribute__((target("avx2"))) void bicubicFixedRowsAvx2(const uint8_t* source, const RemapTable& table, uint8_t* out,
                                                          int row_begin, int row_end) {
  const BicubicWeights& weights = bicubicWeights();
  const int sw = table.source_width, sh = table.source_height;
  const float max_u = static_cast<float>(sw - 3), max_v = static_cast<float>(sh - 3);
  const size_t stride = static_cast<size_t>(sw);
  const auto one = [&](float u, float v) { return bicubicFixedPixel(source, sw, sh, u, v); };
  const __m256 one_f = _mm256_set1_ps(1.0f), max_u8 = _mm256_set1_ps(max_u), max_v8 = _mm256_set1_ps(max_v);
  const __m256 scale = _mm256_set1_ps(static_cast<float>(kFractions)), half = _mm256_set1_ps(0.5f);
  const __m256i fraction_mask = _mm256_set1_epi32(kFractions - 1);
  const __m256i rounding = _mm256_set1_epi32(1 << (kWeightBits - 1));
  const __m256i ones = _mm256_set1_epi32(1);
  const __m256i stride8 = _mm256_set1_epi32(sw);
  for (int y = row_begin; y < row_end; ++y) {
    const size_t first = static_cast<size_t>(y) * static_cast<size_t>(table.width);
    const float* uv = table.uv.data() + 2 * first;
    uint8_t* dst = out + first;
    int x = 0;
    for (; x + 8 <= table.width; x += 8) {
      const __m256 a = _mm256_loadu_ps(uv + 2 * x), b = _mm256_loadu_ps(uv + 2 * x + 8);
      // Lanes hold pixels 0 1 4 5 | 2 3 6 7 after the shuffle; the permute puts them in order.
      const __m256 u = _mm256_castpd_ps(
          _mm256_permute4x64_pd(_mm256_castps_pd(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0))), 0xD8));
      const __m256 v = _mm256_castpd_ps(
          _mm256_permute4x64_pd(_mm256_castps_pd(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1))), 0xD8));
      const __m256 in =
          _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(u, one_f, _CMP_GE_OQ), _mm256_cmp_ps(u, max_u8, _CMP_LT_OQ)),
                        _mm256_and_ps(_mm256_cmp_ps(v, one_f, _CMP_GE_OQ), _mm256_cmp_ps(v, max_v8, _CMP_LT_OQ)));
      if (_mm256_movemask_ps(in) != 0xFF) {
        for (int i = 0; i < 8; ++i) dst[x + i] = one(uv[2 * (x + i)], uv[2 * (x + i) + 1]);
        continue;
      }
      const __m256i iu = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(u, scale), half));
      const __m256i iv = _mm256_cvttps_epi32(_mm256_add_ps(_mm256_mul_ps(v, scale), half));
      const __m256i x0 = _mm256_sub_epi32(_mm256_srli_epi32(iu, kFractionBits), ones);
      const __m256i y0 = _mm256_sub_epi32(_mm256_srli_epi32(iv, kFractionBits), ones);
      alignas(32) int32_t offset[8], index[8];
      _mm256_store_si256(reinterpret_cast<__m256i*>(offset), _mm256_add_epi32(_mm256_mullo_epi32(y0, stride8), x0));
      _mm256_store_si256(reinterpret_cast<__m256i*>(index),
                         _mm256_or_si256(_mm256_slli_epi32(_mm256_and_si256(iv, fraction_mask), kFractionBits),
                                         _mm256_and_si256(iu, fraction_mask)));
      __m256i partial[8];
      for (int i = 0; i < 8; ++i) {
        const uint8_t* p = source + offset[i];
        int32_t r[4];
        for (int k = 0; k < 4; ++k) std::memcpy(&r[k], p + k * stride, 4);
        const __m256i taps = _mm256_cvtepu8_epi16(_mm_set_epi32(r[3], r[2], r[1], r[0]));
        partial[i] = _mm256_madd_epi16(taps, _mm256_load_si256(reinterpret_cast<const __m256i*>(weights.w[index[i]])));
      }
      // Pixel i's 8 partial sums to one: lanes [0..3 of pixels 0-3 | 4..7 of pixels 0-3] (and 4-7).
      const __m256i low =
          _mm256_hadd_epi32(_mm256_hadd_epi32(partial[0], partial[1]), _mm256_hadd_epi32(partial[2], partial[3]));
      const __m256i high =
          _mm256_hadd_epi32(_mm256_hadd_epi32(partial[4], partial[5]), _mm256_hadd_epi32(partial[6], partial[7]));
      const __m256i sums =
          _mm256_add_epi32(_mm256_permute2x128_si256(low, high, 0x20), _mm256_permute2x128_si256(low, high, 0x31));
      const __m256i shifted = _mm256_srai_epi32(_mm256_add_epi32(sums, rounding), kWeightBits);
      const __m256i words = _mm256_packs_epi32(shifted, shifted);
      const __m256i bytes = _mm256_packus_epi16(words, words);
      const int32_t first4 = _mm_cvtsi128_si32(_mm256_castsi256_si128(bytes));
      const int32_t last4 = _mm_cvtsi128_si32(_mm256_extracti128_si256(bytes, 1));
      std::memcpy(dst + x, &first4, 4);
      std::memcpy(dst + x + 4, &last4, 4);
    }
    for (; x < table.width; ++x) dst[x] = one(uv[2 * x], uv[2 * x + 1]);
  }
}
#endif

bool hasAvx2() {
#if defined(VKLOC_REMAP_AVX2)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  return avx2;
#else
  return false;
#endif
}

}  // namespace

void remapBicubicFixedRows(const uint8_t* source, const RemapTable& table, uint8_t* out, int row_begin, int row_end,
                           FixedRemapKernel kernel) {
#if defined(VKLOC_REMAP_AVX2)
  if (kernel == FixedRemapKernel::kFastest && hasAvx2()) {
    bicubicFixedRowsAvx2(source, table, out, row_begin, row_end);
    return;
  }
#endif
  bicubicFixedRows(source, table, out, row_begin, row_end, kernel != FixedRemapKernel::kScalar);
}

const char* remapBicubicFixedKernel(FixedRemapKernel kernel) {
  if (kernel == FixedRemapKernel::kScalar) return "scalar";
  if (kernel == FixedRemapKernel::kFastest && hasAvx2()) return "AVX2";
#if defined(__SSE2__)
  return "SSE2";
#else
  return "scalar";
#endif
}

Result<ImageU8> remapBicubicFixed(const ImageU8& source, const RemapTable& table, FixedRemapKernel kernel) {
  VKLOC_TRY_STATUS(validateRemapTable(table));
  VKLOC_TRY_STATUS(checkSource("remapBicubicFixed", source, table));
  ImageU8 out(table.width, table.height, 1);
  remapBicubicFixedRows(source.data.data(), table, out.data.data(), 0, table.height, kernel);
  return out;
}

Result<ImageU8> remapImage(const ImageU8& source, const RemapTable& table, RemapInterpolation interpolation) {
  return interpolation == RemapInterpolation::kBicubic ? remapBicubic(source, table) : remapBilinear(source, table);
}

}  // namespace vkloc
