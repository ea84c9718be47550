// vkloc: image remapping through a table (undistortion, stabilised views). Standard library only.
// remapBilinear is the reference: the GPU stage (GpuRemap, engine/) computes the same float
// operations; the fast CPU path (OpenCV's remap) quantises positions to 1/32 px, which moves
// values near hard edges by a few gray levels.
#pragma once

#include <string>
#include <vector>

#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

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

/// Remaps images through a table it holds, on a device (the GPU stage, made by an Accelerator).
/// Used by one thread at a time.
class ImageRemapper {
 public:
  virtual ~ImageRemapper() = default;
  /// Replaces the table; kInvalidArgument when its sizes differ from the first table's.
  virtual Status setTable(const RemapTable& table) = 0;
  /// The image of `source` (1 channel, the table's source size) through the table, by
  /// remapBilinear's rule. kInvalidArgument for another size; device errors as they come.
  virtual Result<ImageU8> remap(const ImageU8& source) = 0;
  virtual std::string describe() const = 0;
};

}  // namespace vkloc
