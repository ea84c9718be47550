#version 450
// Image remap through a table (GpuRemap, engine/src/remap.cpp): per output pixel, bilinear
// interpolation in float of the 8-bit source at the table's (u, v), exactly as the reference
// remapBilinear (host/src/core/remap.cpp) computes it: the same operations in the same order,
// `precise` so that no product and sum are contracted into an fma.
// Each invocation writes whole uints of the packed 8-bit output (4 consecutive pixels of the
// row-major image, which may straddle rows), so no two invocations write the same word.
// Consecutive invocations take consecutive words (coalesced on GPUs).
#extension GL_GOOGLE_include_directive : require
#include "remap_layout.h"

// Output uints per invocation: specialization constant 0 (1 on GPUs; more on CPU drivers, where
// every 8 invocations run as one coroutine whose set-up costs about as much as a light
// kernel's work, LAVAPIPE.md).
layout(constant_id = 0) const int kWords = 1;
layout(local_size_x = REMAP_LOCAL_SIZE) in;
layout(push_constant) uniform Push { RemapPush pc; };
// Two output pixels' (u, v) per vec4: one word's four pixels are 2 loads.
layout(std430, set = 0, binding = REMAP_BINDING_TABLE) readonly buffer Table { vec4 uv[]; };
layout(std430, set = 0, binding = REMAP_BINDING_SOURCE) readonly buffer Source { uint source[]; };
layout(std430, set = 0, binding = REMAP_BINDING_OUTPUT) writeonly buffer Output { uint result[]; };

float sourcePixel(int i) { return float((source[i >> 2] >> (8u * uint(i & 3))) & 0xffu); }

// The remapped value of one pixel at source position (u, v), 0..255.
uint remapPixel(float u, float v) {
  // NaN fails every comparison: NaN, +-inf and positions off the source give 0.
  bool inside = u >= 0.0 && u <= pc.max_u && v >= 0.0 && v <= pc.max_v;
  if (!inside) return 0u;
  precise float x0f = floor(u);
  precise float y0f = floor(v);
  precise float fx = u - x0f;
  precise float fy = v - y0f;
  int x0 = int(x0f);
  int y0 = int(y0f);
  int x1 = min(x0 + 1, pc.source_width - 1);
  int row0 = y0 * pc.source_width;
  int row1 = min(y0 + 1, pc.source_height - 1) * pc.source_width;
  float a = sourcePixel(row0 + x0);
  float b = sourcePixel(row0 + x1);
  float c = sourcePixel(row1 + x0);
  float d = sourcePixel(row1 + x1);
  precise float gx = 1.0 - fx;
  precise float gy = 1.0 - fy;
  precise float top = gx * a + fx * b;
  precise float bottom = gx * c + fx * d;
  precise float value = gy * top + fy * bottom;
  return uint(clamp(floor(value + 0.5), 0.0, 255.0));
}

void main() {
  uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
  for (int r = 0; r < kWords; ++r) {
    uint word = (group * uint(kWords) + uint(r)) * uint(REMAP_LOCAL_SIZE) + gl_LocalInvocationID.x;
    if (word >= pc.word_count) return;
    vec4 uv01 = uv[2u * word];
    vec4 uv23 = uv[2u * word + 1u];
    uint p = 4u * word;
    // Pixels past the image in the last word are 0 (the table's padding is never sampled).
    uint packed = remapPixel(uv01.x, uv01.y);
    if (p + 1u < pc.pixel_count) packed |= remapPixel(uv01.z, uv01.w) << 8u;
    if (p + 2u < pc.pixel_count) packed |= remapPixel(uv23.x, uv23.y) << 16u;
    if (p + 3u < pc.pixel_count) packed |= remapPixel(uv23.z, uv23.w) << 24u;
    result[word] = packed;
  }
}
