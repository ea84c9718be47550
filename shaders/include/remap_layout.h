// Layout of the remap compute shader (shaders/remap.comp, engine/src/remap.cpp), shared by C++
// and GLSL. Sizes and offsets are checked by static_asserts in engine/src/remap.cpp.
#ifndef VKLOC_REMAP_LAYOUT_H
#define VKLOC_REMAP_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#define VKLOC_FLOAT(name) float name
#define VKLOC_INT(name) int32_t name
#define VKLOC_UINT(name) uint32_t name
namespace vkloc::engine {
#else
#define VKLOC_FLOAT(name) float name
#define VKLOC_INT(name) int name
#define VKLOC_UINT(name) uint name
#endif

// Descriptor bindings of set 0.
#define REMAP_BINDING_TABLE 0   // SSBO: vec4[] (u, v) of 2 output pixels per vec4, row-major, padded to 4 pixels
#define REMAP_BINDING_SOURCE 1  // SSBO: uint[] 8-bit source, 4 pixels per uint, row-major
#define REMAP_BINDING_OUTPUT 2  // SSBO: uint[] 8-bit output, 4 pixels per uint, row-major
#define REMAP_BINDING_COUNT 3

#define REMAP_LOCAL_SIZE 64  // invocations per workgroup (x)

// Specialization constants of remap.comp.
#define REMAP_SPEC_WORDS 0          // int: output uints per invocation
#define REMAP_SPEC_INTERPOLATION 1  // int: one of REMAP_INTERPOLATION_*
#define REMAP_INTERPOLATION_BILINEAR 0
#define REMAP_INTERPOLATION_BICUBIC 1

// Push constants. 32 bytes.
struct RemapPush {
  VKLOC_INT(source_width);      // Source size, pixels.
  VKLOC_INT(source_height);     // Pixels.
  VKLOC_UINT(pixel_count);      // Output pixels, width * height.
  VKLOC_UINT(word_count);       // Output uints, (pixel_count + 3) / 4.
  VKLOC_FLOAT(max_u);           // source_width - 1: the largest u with a source.
  VKLOC_FLOAT(max_v);           // source_height - 1.
  VKLOC_INT(source_last_word);  // Index of the source's last uint: (source pixels + 3) / 4 - 1.
  VKLOC_UINT(pad0);
};

#ifdef __cplusplus
}  // namespace vkloc::engine
#endif
#undef VKLOC_FLOAT
#undef VKLOC_INT
#undef VKLOC_UINT

#endif  // VKLOC_REMAP_LAYOUT_H
