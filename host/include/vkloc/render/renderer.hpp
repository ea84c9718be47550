// vkloc: what a model render produces and the Renderer interface every renderer implements.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {

/// Which outputs a render fills. Depth is always produced. Without kRenderColor the colour and
/// gray images may hold only the background (the CPU renderer then skips shading; a device
/// renderer fills them anyway).
enum RenderOutputFlags : uint32_t {
  kRenderColor = 1u << 0,    ///< RGBA8 and 8-bit gray.
  kRenderDepth = 1u << 1,    ///< Linear metric depth.
  kRenderNormals = 1u << 2,  ///< Camera-frame face normals and the back-face mask.
  kRenderAll = kRenderColor | kRenderDepth | kRenderNormals,
};

/// Depth range and appearance settings of a render.
struct RenderSettings {
  double near_m = 0.05;   ///< Near clip plane, metres (camera z). Surfaces closer are clipped.
  double far_m = 5000.0;  ///< Far clip plane, metres. Surfaces farther are background.
  /// RGBA8 written where no surface is seen.
  std::array<uint8_t, 4> background_rgba{0, 0, 0, 0};
  bool cull_back_faces = false;   ///< Skip triangles seen from behind (needs consistent winding).
  uint32_t outputs = kRenderAll;  ///< RenderOutputFlags to fill.
  /// Level of detail: blocks far enough away are drawn simplified when the simplification's
  /// geometric error projects to at most this many pixels (errors measured at block creation,
  /// projected from the nearest point of the block's bounds). 0 always draws full detail. The
  /// CPU reference ignores it.
  double lod_pixel_error = 0.0;
  /// CPU reference: threads that each draw a band of rows (1..64; at most one band per 32 rows).
  /// The output is the same for any count. GPU renderers ignore it.
  int threads = 1;
};

/// Depth value of pixels where no surface is seen (metres).
constexpr float kBackgroundDepth = 0.0f;

/// A rendered view. Images are camera.width x camera.height, rows top to bottom.
struct RenderOutput {
  ImageU8 rgba;  ///< 4 channels, sRGB-encoded colour as stored in textures; alpha 255 on surfaces.
  ImageU8 gray;  ///< 1 channel, BT.601 luma of rgba.
  /// 1 channel, metres: camera-frame z of the visible surface (not the distance along the ray);
  /// kBackgroundDepth (0) where no surface is seen.
  ImageF32 depth;
  /// 3 channels, unit face normal in the camera frame pointing towards the camera; (0, 0, 0)
  /// on background.
  ImageF32 normals;
  /// 1 channel, filled with the normals: 255 where the visible surface is seen from behind (a
  /// back face: its winding is clockwise on the screen, the camera lies on the inner side of a
  /// closed model's surface), 0 on front faces and background. Through a hole in a closed model
  /// the inside of the far walls is seen from behind; the world shows neither it nor the hole's
  /// rim. Models whose winding is inconsistent or inward mark true surfaces too.
  ImageU8 back_faces;
  uint32_t blocks_drawn = 0;     ///< Blocks that passed frustum culling.
  uint32_t triangles_drawn = 0;  ///< Triangles submitted after culling.
};

/// Checks 1e-6 <= near < far, far finite, far / near <= 1e9 (float reverse-Z precision) and
/// lod_pixel_error finite and >= 0, threads in 1..64. kInvalidArgument naming the field otherwise.
Status validateRenderSettings(const RenderSettings& settings);

/// Column-major 4x4 clip transform for a pinhole camera in Vulkan's conventions, reverse-Z:
/// camera z = near maps to depth 1, z = far to 0; x_ndc = 2 (u + 0.5) / width - 1 with
/// u = fx x / z + cx (seed 001 eqs. 7-8 without the OpenGL y flip). Multiply with
/// T_camera_world for the model-view-projection.
Eigen::Matrix4d projectionMatrix(const PinholeCamera& camera, double near_m, double far_m);

/// Returns true when the box may intersect the camera's view frustum (near..far), false when
/// it lies entirely outside one of the six planes.
bool aabbInFrustum(const Aabb& box, const PinholeCamera& camera, const Pose& T_world_camera, double near_m,
                   double far_m);

/// The same test with the inverse pose already computed (per-block loops invert once).
bool aabbInFrustumFromCamera(const Aabb& box, const PinholeCamera& camera, const Pose& T_camera_world, double near_m,
                             double far_m);

/// Renders one model (the one it was made for) at camera poses: the keyframe renders of the
/// Localizer and the simulator's images. Implemented by the CPU reference rasterizer
/// (render/cpu_renderer.hpp) and the Vulkan renderer (engine: GpuRenderer); both follow the
/// conventions above. Errors: kInvalidArgument for an invalid camera, pose or settings,
/// kGpuError when a device fails. An instance is used by one thread at a time; different
/// instances may render concurrently.
class Renderer {
 public:
  virtual ~Renderer() = default;
  /// Renders the model at T_world_camera and returns the outputs `settings.outputs` asks for
  /// (colour and depth always).
  virtual Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera,
                                      const RenderSettings& settings) = 0;
  /// One line naming the renderer and where it runs, for logs.
  virtual std::string describe() const = 0;
};

/// Makes a Renderer for a model (copying or uploading what it needs: the model may be destroyed
/// afterwards). kInvalidArgument for an invalid model; device errors as the renderer's.
using RendererFactory = std::function<Result<std::unique_ptr<Renderer>>(const Model& model)>;

}  // namespace vkloc
