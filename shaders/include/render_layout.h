// Push-constant layout of the model render pipeline, shared by C++ (engine/src) and GLSL.
// Sizes and offsets are checked by static_asserts in engine/src/renderer.cpp.
#ifndef VKLOC_RENDER_LAYOUT_H
#define VKLOC_RENDER_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#define VKLOC_MAT4(name) float name[16]
#define VKLOC_VEC4(name) float name[4]
#define VKLOC_INT(name) int32_t name
#define VKLOC_UINT(name) uint32_t name
namespace vkloc::engine {
#else
#define VKLOC_MAT4(name) mat4 name
#define VKLOC_VEC4(name) vec4 name
#define VKLOC_INT(name) int name
#define VKLOC_UINT(name) uint name
#endif

// Flags of ModelPush::flags.
#define VKLOC_FLAG_TEXTURED 1u

struct ModelPush {
  // Column-major clip transform of positions stored relative to the model origin:
  // P * T_camera_world * T_world_origin (see projectionMatrix in host/src/render_common.cpp).
  VKLOC_MAT4(clip_from_origin);
  // fx, fy, cx, cy in pixels: lets the fragment shader rebuild camera-frame points.
  VKLOC_VEC4(intrinsics);
  // Material base colour, 0..1 RGBA.
  VKLOC_VEC4(base_color);
  VKLOC_INT(texture);  // Slot in the texture array of the bound descriptor set (textures.hpp).
  VKLOC_UINT(flags);
  VKLOC_INT(pad0);
  VKLOC_INT(pad1);
};

#ifdef __cplusplus
}  // namespace vkloc::engine
#endif
#undef VKLOC_MAT4
#undef VKLOC_VEC4
#undef VKLOC_INT
#undef VKLOC_UINT
#endif
