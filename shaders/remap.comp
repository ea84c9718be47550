#version 450
// Image remap through a table (GpuRemap, engine/src/remap.cpp): per output pixel, bilinear or
// bicubic interpolation in float of the 8-bit source at the table's (u, v), exactly as the
// references remapBilinear and remapBicubic (host/src/core/remap.cpp) compute it: the same
// operations in the same order, `precise` so that no product and sum are contracted into an fma.
// Each invocation writes whole uints of the packed 8-bit output (4 consecutive pixels of the
// row-major image, which may straddle rows), so no two invocations write the same word.
// Consecutive invocations take consecutive words (coalesced on GPUs).
#extension GL_GOOGLE_include_directive : require
#include "remap_layout.h"

// Output uints per invocation (1 on GPUs; more on CPU drivers, where every 8 invocations run as
// one coroutine whose set-up costs about as much as a light kernel's work, LAVAPIPE.md).
layout(constant_id = REMAP_SPEC_WORDS) const int kWords = 1;
// REMAP_INTERPOLATION_BILINEAR or REMAP_INTERPOLATION_BICUBIC: one pipeline per interpolation.
layout(constant_id = REMAP_SPEC_INTERPOLATION) const int kInterpolation = REMAP_INTERPOLATION_BILINEAR;
layout(local_size_x = REMAP_LOCAL_SIZE) in;
layout(push_constant) uniform Push { RemapPush pc; };
// Two output pixels' (u, v) per vec4: one word's four pixels are 2 loads.
layout(std430, set = 0, binding = REMAP_BINDING_TABLE) readonly buffer Table { vec4 uv[]; };
layout(std430, set = 0, binding = REMAP_BINDING_SOURCE) readonly buffer Source { uint source[]; };
layout(std430, set = 0, binding = REMAP_BINDING_OUTPUT) writeonly buffer Output { uint result[]; };

float sourcePixel(int i) { return float((source[i >> 2] >> (8u * uint(i & 3))) & 0xffu); }

// The bilinear value of one pixel at source position (u, v), 0..255 (remapBilinear).
uint bilinearPixel(float u, float v) {
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

// Cubic convolution kernel W(d) with a = -0.75 (core/remap.hpp), evaluated left to right as
// remapBicubic does: a + 2 = 1.25, a + 3 = 2.25, 5a = -3.75, 8a = -6, 4a = -3 (exact in float).
// W(d) for 0 <= d <= 1: ((a + 2) d - (a + 3)) d d + 1.
float cubicNear(float d) {
  precise float p = 1.25 * d;
  precise float q = p - 2.25;
  precise float r = q * d;
  precise float s = r * d;
  precise float w = s + 1.0;
  return w;
}

// W(d) for 1 <= d <= 2: ((a d - 5a) d + 8a) d - 4a.
float cubicFar(float d) {
  precise float p = -0.75 * d;
  precise float q = p - -3.75;
  precise float r = q * d;
  precise float s = r + -6.0;
  precise float t = s * d;
  precise float w = t - -3.0;
  return w;
}

// The weights of the taps at -1, 0, 1, 2 for a fraction 0 <= t < 1.
vec4 cubicWeights(float t) {
  precise float d0 = 1.0 + t;
  precise float d2 = 1.0 - t;
  precise float d3 = 2.0 - t;
  return vec4(cubicFar(d0), cubicNear(t), cubicNear(d2), cubicFar(d3));
}

// ((w.x p.x + w.y p.y) + w.z p.z) + w.w p.w.
float cubicSum(vec4 w, vec4 p) {
  precise float s = w.x * p.x + w.y * p.y + w.z * p.z + w.w * p.w;
  return s;
}

// The 4 taps of one row: the source bytes row + xs, which lie within 4 consecutive bytes (xs
// ascending, replicated at the borders), from the 2 uints that hold them (half the loads of one
// per tap). The second uint is clamped to the buffer (its bytes then go unused).
vec4 rowTaps(int row, ivec4 xs) {
  int word = (row + xs.x) >> 2;
  uint lo = source[word];
  uint hi = source[min(word + 1, pc.source_last_word)];
  uvec4 offset = uvec4(ivec4(row - 4 * word) + xs);  // 0..6: bytes from the start of `lo`
  uvec4 from_lo = uvec4(lo) >> (8u * (offset & 3u));
  uvec4 from_hi = uvec4(hi) >> (8u * (offset & 3u));
  uvec4 bytes = mix(from_hi, from_lo, lessThan(offset, uvec4(4u))) & 0xffu;
  return vec4(bytes);
}

// The bicubic value of one pixel at source position (u, v), 0..255 (remapBicubic): taps outside
// the source replicate the border.
uint bicubicPixel(float u, float v) {
  bool inside = u >= 0.0 && u <= pc.max_u && v >= 0.0 && v <= pc.max_v;
  if (!inside) return 0u;
  precise float x0f = floor(u);
  precise float y0f = floor(v);
  precise float tx = u - x0f;
  precise float ty = v - y0f;
  int x0 = int(x0f);
  int y0 = int(y0f);
  ivec4 xs = clamp(ivec4(x0 - 1, x0, x0 + 1, x0 + 2), ivec4(0), ivec4(pc.source_width - 1));
  ivec4 rows = clamp(ivec4(y0 - 1, y0, y0 + 1, y0 + 2), ivec4(0), ivec4(pc.source_height - 1)) * pc.source_width;
  vec4 wx = cubicWeights(tx);
  vec4 wy = cubicWeights(ty);
  vec4 r;
  for (int k = 0; k < 4; ++k) {
    r[k] = cubicSum(wx, rowTaps(rows[k], xs));
  }
  precise float value = cubicSum(wy, r);
  return uint(clamp(floor(value + 0.5), 0.0, 255.0));
}

uint remapPixel(float u, float v) {
  return kInterpolation == REMAP_INTERPOLATION_BICUBIC ? bicubicPixel(u, v) : bilinearPixel(u, v);
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
