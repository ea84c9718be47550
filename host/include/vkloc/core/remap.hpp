// vkloc: image remapping through a table (undistortion, stabilised views). Standard library only.
// remapBilinear and remapBicubic are the references: the GPU stage (GpuRemap, engine/) computes
// the same float operations; the fast CPU paths (OpenCV's remap for bilinear, remapBicubicFixedRows
// for bicubic) quantise positions to 1/32 px and weights to fixed point, which moves values near
// hard edges by a few gray levels.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// How output pixels are sampled from the source.
enum class RemapInterpolation {
  kBilinear,  ///< 2x2 taps (remapBilinear).
  kBicubic,   ///< 4x4 taps, cubic convolution with a = -0.75 (remapBicubic; OpenCV's INTER_CUBIC).
};

/// "bilinear" or "bicubic".
const char* remapInterpolationName(RemapInterpolation interpolation);

/// For each pixel of an output image: where to sample the source image.
struct RemapTable {
  int width = 0;  ///< Output size, pixels.
  int height = 0;
  int source_width = 0;  ///< Source (lens image) size, pixels.
  int source_height = 0;
  /// 2 floats (u, v) per output pixel, rows top to bottom: the source position in pixels (pixel
  /// centres at integers). A pixel whose position is not finite, or lies outside
  /// [0, source_width - 1] x [0, source_height - 1], has no source and is written as 0.
  std::vector<float> uv;
};

/// Checks sizes (1..16384) and uv.size() == 2 * width * height. kInvalidArgument otherwise.
Status validateRemapTable(const RemapTable& table);

/// The reference remap: bilinear interpolation in float of the 4 source pixels around (u, v),
/// rounded to nearest (0.5 up) and clamped to 0..255; pixels without a source get 0. Exactly:
/// x0 = floor(u), fx = u - x0, x1 = min(x0 + 1, source_width - 1) (y likewise), a b / c d the
/// pixels at (x0, y0) (x1, y0) / (x0, y1) (x1, y1),
///   value = (1 - fy) ((1 - fx) a + fx b) + fy ((1 - fx) c + fx d),
/// every product and sum rounded to float in this order (no fma), output
/// clamp(floor(value + 0.5), 0, 255). GpuRemap (engine) computes the same operations.
/// kInvalidArgument when the table is invalid or `source` is not a single-channel image of the
/// table's source size.
Result<ImageU8> remapBilinear(const ImageU8& source, const RemapTable& table);

/// The reference bicubic remap: cubic convolution (Keys 1981, with a = -0.75 as OpenCV's
/// INTER_CUBIC) in float of the 4x4 source pixels around (u, v), taps outside the source
/// replaced by the nearest border pixel (OpenCV's BORDER_REPLICATE), rounded to nearest (0.5 up)
/// and clamped to 0..255; pixels without a source get 0 (the rule of RemapTable::uv). Exactly:
/// x0 = floor(u), t = u - x0, taps x_k = clamp(x0 - 1 + k, 0, source_width - 1) for k = 0..3
/// (y likewise with s = v - y0), weights
///   wx = (W(1 + t), W(t), W(1 - t), W(2 - t)),
///   W(d) = ((a + 2) d - (a + 3)) d d + 1          for d <= 1,
///   W(d) = ((a d - 5a) d + 8a) d - 4a             for 1 < d <= 2,
/// each row k: r_k = ((wx0 p_k0 + wx1 p_k1) + wx2 p_k2) + wx3 p_k3, then
/// value = ((wy0 r_0 + wy1 r_1) + wy2 r_2) + wy3 r_3, every product and sum rounded to float in
/// this order (no fma; W evaluated as written, left to right), output
/// clamp(floor(value + 0.5), 0, 255). Overshoots at edges (the negative lobes) are clamped.
/// Constants are kept; a linear ramp is sampled at t + delta(t), delta = -(2a + 1) t (1 - t) (1 - 2t)
/// (|delta| <= 0.048 px; only a = -1/2 has none).
/// GpuRemap (engine) computes the same operations. Errors as remapBilinear's.
Result<ImageU8> remapBicubic(const ImageU8& source, const RemapTable& table);

/// Which kernel remapBicubicFixedRows runs: the fastest the processor has (AVX2, eight pixels at
/// a time, chosen at run time; else SSE2, four at a time, on x86-64), SSE2 (on x86-64; elsewhere
/// scalar), or one pixel at a time. The integer operations are the same, so are the outputs.
enum class FixedRemapKernel { kFastest, kSse2, kScalar };

/// The CPU fast path of remapBicubic: each position rounded to 1/32 px (floor(32 u + 1/2), as
/// OpenCV's fixed-point maps), the 16 weights of each of the 32 x 32 fractions the products of
/// remapBicubic's W in 14-bit fixed point, made to sum to exactly 1 (a constant image stays
/// constant), integer sums, output clamp((sum + 2^13) >> 14, 0, 255); taps off the source
/// replicate the border and pixels without a source get 0 (remapBicubic's rules). Within 1 gray
/// level of remapBicubic on most pixels: the rounding moves a position by up to 1/64 px, a few
/// gray levels at a hard edge; within 1 on every pixel where positions lie on the 1/32 px grid.
/// Computes output rows [row_begin, row_end) of `out` (table.width x table.height bytes), so that
/// callers can split the rows over threads. Unchecked: the caller validated the table
/// (validateRemapTable) and `source` is a table.source_width x table.source_height image.
void remapBicubicFixedRows(const uint8_t* source, const RemapTable& table, uint8_t* out, int row_begin, int row_end,
                           FixedRemapKernel kernel = FixedRemapKernel::kFastest);

/// The kernel `kernel` is on this processor: "AVX2", "SSE2" or "scalar".
const char* remapBicubicFixedKernel(FixedRemapKernel kernel = FixedRemapKernel::kFastest);

/// remapBicubicFixedRows over the whole table, on one thread; errors as remapBicubic's.
Result<ImageU8> remapBicubicFixed(const ImageU8& source, const RemapTable& table,
                                  FixedRemapKernel kernel = FixedRemapKernel::kFastest);

/// remapBilinear or remapBicubic, as `interpolation` says.
Result<ImageU8> remapImage(const ImageU8& source, const RemapTable& table, RemapInterpolation interpolation);

/// Remaps images through a table it holds, on a device (the GPU stage, made by an Accelerator).
/// Used by one thread at a time.
class ImageRemapper {
 public:
  virtual ~ImageRemapper() = default;
  /// Replaces the table; kInvalidArgument when its sizes differ from the first table's.
  virtual Status setTable(const RemapTable& table) = 0;
  /// The image of `source` (1 channel, the table's source size) through the table, by the rule of
  /// the interpolation the remapper was made with (remapImage). kInvalidArgument for another
  /// size; device errors as they come.
  virtual Result<ImageU8> remap(const ImageU8& source) = 0;
  virtual std::string describe() const = 0;
};

}  // namespace vkloc
