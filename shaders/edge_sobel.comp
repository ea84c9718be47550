#version 450
// 3x3 Sobel divided by 8 (gray levels per pixel), borders replicated, and its magnitude.
// Each invocation does kSpan consecutive pixels of kRows consecutive rows (specialization
// constants: 8 x 16 on CPU drivers, where a 3 x (kSpan + 2) window slid down the rows replaces
// 8 gathers per pixel; 1 x 1 on GPUs).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation (1 on GPUs; 16 on CPU drivers, where every 8 invocations run as one
// coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) readonly uniform image2D gray;
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) writeonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) writeonly uniform image2D grad;

float g(int x, int y) { return imageLoad(gray, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x; }

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  int y0 = int(gl_GlobalInvocationID.y) * kRows;
  if (x0 >= pc.width || y0 >= pc.height) return;
  // Columns x0 - 1 .. x0 + kSpan of rows y - 1, y, y + 1 (clamped), slid down one row per output
  // row: each input row is read once per invocation.
  float top[kSpan + 2], mid[kSpan + 2], bot[kSpan + 2];
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
      float a = top[j], b = top[j + 1], c = top[j + 2];
      float d = mid[j], f = mid[j + 2];
      float h = bot[j], i = bot[j + 1], k = bot[j + 2];
      float gx = ((c - a) + 2.0 * (f - d) + (k - h)) * 0.125;
      float gy = ((h - a) + 2.0 * (i - b) + (k - c)) * 0.125;
      ivec2 p = ivec2(x0 + j, y);
      imageStore(grad, p, vec4(gx, gy, 0.0, 0.0));
      imageStore(mag, p, vec4(sqrt(gx * gx + gy * gy)));
    }
    for (int i = 0; i < kSpan + 2; ++i) {
      top[i] = mid[i];
      mid[i] = bot[i];
    }
  }
}
