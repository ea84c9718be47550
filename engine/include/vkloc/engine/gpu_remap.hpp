// vkloc: image remapping through a table on the GPU (Vulkan compute): undistortion and
// stabilised views. The results are those of remapBilinear or remapBicubic (core/remap.hpp); no
// Vulkan types are exposed.
#pragma once

#include <memory>

#include "vkloc/core/image.hpp"
#include "vkloc/core/remap.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/engine/gpu.hpp"

namespace vkloc {

/// Remaps 8-bit gray images through a RemapTable on the GPU. The table stays resident in
/// device-local memory (8 bytes per output pixel) until the next setTable; each remap uploads
/// the source (1 byte per pixel), runs one compute dispatch and reads the output back.
/// Each output pixel equals the reference's (remapBilinear or remapBicubic, chosen at creation)
/// on devices whose float add and multiply are correctly rounded (Vulkan requires it; lavapipe
/// matches bit for bit); in general within 1 gray level. Bicubic reads 16 source pixels per
/// output pixel where bilinear reads 4. Not thread-safe: one thread at a time per object
/// (several objects may share a context, as GpuContext describes).
class GpuRemap final : public ImageRemapper {
 public:
  /// Allocates the buffers for `table`'s sizes, builds the pipeline of `interpolation` and uploads
  /// the table. kInvalidArgument for a null context, an invalid table (validateRemapTable) or an
  /// interpolation that is not one of the enum's; kUnsupported when the table is larger than the
  /// device's largest storage buffer (128 MiB on lavapipe: 16.7 M output pixels); kGpuError when
  /// the device runs out of memory.
  static Result<std::unique_ptr<GpuRemap>> create(std::shared_ptr<GpuContext> context, const RemapTable& table,
                                                  RemapInterpolation interpolation = RemapInterpolation::kBilinear);
  ~GpuRemap() override;
  GpuRemap(const GpuRemap&) = delete;
  GpuRemap& operator=(const GpuRemap&) = delete;

  /// Replaces the table (e.g. a stabilised view's, every frame): uploads it, nothing else.
  /// kInvalidArgument for an invalid table or one whose output or source size differs from the
  /// table given at creation (create another GpuRemap for other sizes); the old table stays.
  Status setTable(const RemapTable& table) override;

  /// Remaps `source`, an 8-bit single-channel image of the table's source size, into an image of
  /// the table's output size (remapBilinear's or remapBicubic's result). kInvalidArgument for another size or
  /// channel count; kGpuError when a Vulkan call fails.
  Result<ImageU8> remap(const ImageU8& source) override;
  /// "GPU remap (<bilinear|bicubic>) on <device>".
  std::string describe() const override;

  /// Device time of the last remap's dispatch, milliseconds (GPU timestamps; where the queue has
  /// none, the host wall time of the submission). 0 before the first remap.
  double lastGpuMs() const;

  struct Impl;

 private:
  explicit GpuRemap(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vkloc
