#version 450
// 3x3 Sobel divided by 8 (gray levels per pixel), borders replicated, and its magnitude.
// Each invocation does kSpan consecutive pixels of kRows consecutive rows (specialization
// constants: 8 x 16 on CPU drivers, where a 3 x (kSpan + 2) window slid down the rows replaces
// 8 gathers per pixel; 1 x 1 on GPUs).
// With kFusedSobel (CPU drivers) only the magnitudes the contrast quantile samples (even x and
// y, edge_hist.comp) are computed and stored: edge_nms.comp and edge_lines.comp recompute the
// gradient from GRAY where they need it, because on lavapipe storing three floats per pixel
// costs more than recomputing them (stores go lane by lane).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"
#include "sobel.glsl"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation (1 on GPUs; 16 on CPU drivers, where every 8 invocations run as one
// coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
layout(constant_id = 3) const int kFusedSobel = 0;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) readonly uniform image2D gray;
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) writeonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) writeonly uniform image2D grad;

float g(int x, int y) { return imageLoad(gray, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x; }

// Columns x0 - 1 .. x0 + kSpan (clamped) of rows y - 1, y, y + 1 (clamped).
float top[kSpan + 2], mid[kSpan + 2], bot[kSpan + 2];

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  int y0 = int(gl_GlobalInvocationID.y) * kRows;
  if (x0 >= pc.width || y0 >= pc.height) return;
  if (kFusedSobel != 0) {
    // The even rows of the block; top and mid slide down two rows at a time.
    int y = y0 + (y0 & 1);
    for (int i = 0; i < kSpan + 2; ++i) {
      top[i] = g(x0 - 1 + i, y - 1);
      mid[i] = g(x0 - 1 + i, y);
    }
    for (; y < min(y0 + kRows, pc.height); y += 2) {
      for (int i = 0; i < kSpan + 2; ++i) bot[i] = g(x0 - 1 + i, y + 1);
      for (int j = 0; j < kSpan; ++j) {
        int x = x0 + j;
        if (x >= pc.width) break;
        if ((x & 1) != 0) continue;
        vec2 gxy = sobel8(top[j], top[j + 1], top[j + 2], mid[j], mid[j + 2], bot[j], bot[j + 1], bot[j + 2]);
        imageStore(mag, ivec2(x, y), vec4(sobelMagnitude(gxy)));
      }
      for (int i = 0; i < kSpan + 2; ++i) {
        top[i] = bot[i];
        mid[i] = g(x0 - 1 + i, y + 2);
      }
    }
    return;
  }
  // Slid down one row per output row: each input row is read once per invocation.
  for (int i = 0; i < kSpan + 2; ++i) {
    top[i] = g(x0 - 1 + i, y0 - 1);
    mid[i] = g(x0 - 1 + i, y0);
  }
  for (int r = 0; r < kRows; ++r) {
    int y = y0 + r;
    if (y >= pc.height) return;
    for (int i = 0; i < kSpan + 2; ++i) bot[i] = g(x0 - 1 + i, y + 1);
    for (int j = 0; j < kSpan; ++j) {
      if (x0 + j >= pc.width) break;
      vec2 gxy = sobel8(top[j], top[j + 1], top[j + 2], mid[j], mid[j + 2], bot[j], bot[j + 1], bot[j + 2]);
      ivec2 p = ivec2(x0 + j, y);
      imageStore(grad, p, vec4(gxy, 0.0, 0.0));
      imageStore(mag, p, vec4(sobelMagnitude(gxy)));
    }
    for (int i = 0; i < kSpan + 2; ++i) {
      top[i] = mid[i];
      mid[i] = bot[i];
    }
  }
}
