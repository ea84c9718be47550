// vkloc: the Vulkan device and the GPU model renderer (engine). No Vulkan types are exposed.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "vkloc/core/status.hpp"
#include "vkloc/render/renderer.hpp"

namespace vkloc {

/// A Vulkan physical device as seen by vkloc.
struct GpuDeviceInfo {
  int index = 0;             ///< Position in the Vulkan enumeration order.
  std::string name;          ///< e.g. "llvmpipe (LLVM 15.0.6, 256 bits)".
  std::string type;          ///< "discrete", "integrated", "virtual", "cpu" or "other".
  std::string api_version;   ///< e.g. "1.3.230".
  std::string driver;        ///< Driver name and version info.
  bool usable = false;       ///< Meets vkloc's requirements (Vulkan 1.2, features).
  std::string why_unusable;  ///< Empty when usable.
};

/// How to pick and set up a device.
struct GpuOptions {
  /// Device to use: "" picks automatically (discrete > integrated > virtual > cpu); a number
  /// selects by index; other text selects the first device whose name contains it
  /// (case-insensitive). (The command-line tools fill it from --device or VKLOC_DEVICE; the
  /// library reads no environment variable.)
  std::string device;
  /// VK_LAYER_KHRONOS_validation: 1 = on (kNoDevice when the layer is not installed), 0 = off,
  /// -1 = on in debug builds when installed (on_warning says when it is not), off in release.
  int validation = -1;
  /// Receives every validation warning and error (one message each; called on the thread that
  /// made the Vulkan call). Messages are always counted (validationMessages()); null: only counted.
  WarningHandler on_validation_message;
  /// Receives other warnings (e.g. validation asked for by default but not installed); null: dropped.
  WarningHandler on_warning;
  /// Treats device memory as not host-visible even where it is (lavapipe, integrated GPUs):
  /// uploads and readback then go through staging copies as on a discrete GPU. For testing
  /// that path on any device.
  bool force_staging = false;
  /// On a CPU device (lavapipe), sets glibc's mmap threshold to 32 MiB and trim threshold to
  /// 1 GiB for the whole process: lavapipe allocates and frees multi-megabyte buffers per draw,
  /// and with the defaults every draw faults its pages back in (README, "Performance"). This
  /// changes the allocator of the whole process, so it is off unless the program asks for it
  /// (the vkloc tool does).
  bool tune_allocator = false;
};

/// Owns the Vulkan instance and device. Create once, share between renderers and edge stages.
/// Thread-safety: the context's queue and its one-off command pool are guarded internally, so
/// objects made on one context (each used by one thread at a time) may work on different threads
/// concurrently (the Localizer's keyframe worker renders while the tracking thread runs the edge
/// stages). The accessors are safe from any thread.
class GpuContext {
 public:
  /// Lists every Vulkan device. kNoDevice (with the Debian package to install) when no Vulkan
  /// driver is present.
  static Result<std::vector<GpuDeviceInfo>> listDevices();
  /// Creates the context on the selected device. kNoDevice / kNotFound with a one-line message
  /// when nothing suitable exists.
  static Result<std::shared_ptr<GpuContext>> create(const GpuOptions& options = {});

  ~GpuContext();
  GpuContext(const GpuContext&) = delete;
  GpuContext& operator=(const GpuContext&) = delete;

  const GpuDeviceInfo& device() const;
  bool validationEnabled() const;
  /// Number of validation warnings and errors reported since creation.
  uint64_t validationMessages() const;

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  explicit GpuContext(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// How a GpuRenderer keeps its render targets.
struct GpuRendererOptions {
  /// On devices whose memory the host can read directly (lavapipe, integrated GPUs), render
  /// into linear host-visible images and read them without a copy. false always copies to a
  /// staging buffer, as on discrete GPUs.
  bool direct_readback = true;
  /// Simplified levels built per block at creation (each ~1/4 of the previous triangles; see
  /// RenderSettings::lod_pixel_error). 0 builds none.
  int lod_levels = 4;
  /// Builds texture mip levels on the host (buildMipLevels) instead of with vkCmdBlitImage, as
  /// on devices that cannot blit the texture format with linear filtering. For testing that path
  /// on any device.
  bool host_mipmaps = false;
  /// Most textures per descriptor set; 0: as many as the device allows. Models with more
  /// textures than a set holds are drawn with one set per batch of textures, bound when a draw
  /// needs another batch. For testing that path on any device.
  int max_textures_per_set = 0;
};

/// Renders one model with Vulkan. Model data is uploaded once at creation; render targets are
/// (re)allocated when the camera size changes. Any number of textures, each at its own size with
/// a mip chain, sampled trilinearly with REPEAT wrapping (as the CPU reference renderer does).
/// Used by one thread at a time.
class GpuRenderer final : public Renderer {
 public:
  /// Uploads the model (vertices, indices, textures). kInvalidArgument for an invalid model,
  /// kGpuError when the device runs out of memory.
  static Result<std::unique_ptr<GpuRenderer>> create(std::shared_ptr<GpuContext> context, const Model& model,
                                                     const GpuRendererOptions& options = {});
  ~GpuRenderer();

  /// Renders the model at T_world_camera and reads the requested outputs back to the host.
  /// kInvalidArgument for an invalid camera, pose or settings.
  Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera,
                              const RenderSettings& settings = {}) override;
  /// "Vulkan on <device> (<type>)".
  std::string describe() const override;

  /// Renders without reading back: the images stay in the renderer's GPU targets, where later
  /// GPU stages of the engine read them, until the next render. Returns the statistics part of
  /// RenderOutput with empty images.
  Result<RenderOutput> renderOnGpu(const PinholeCamera& camera, const Pose& T_world_camera,
                                   const RenderSettings& settings = {});

  /// Reads the outputs of the last render (e.g. after renderOnGpu) back to the host; the same
  /// result render() would have returned. kInvalidArgument before the first render.
  Result<RenderOutput> readback();

  struct Impl;
  Impl& impl() { return *impl_; }

 private:
  explicit GpuRenderer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// A RendererFactory making GpuRenderers on `context` (the simulator's and the tools' renderer).
RendererFactory gpuRendererFactory(std::shared_ptr<GpuContext> context, const GpuRendererOptions& options = {});

}  // namespace vkloc
