#version 450
// Pyramid: halves the finer level with the separable binomial [1 3 3 1] / 8 on input pixels
// 2i - 1 .. 2i + 2, borders replicated (downsampleHalf in host/src/edges_cpu.cpp, same order of
// operations: four horizontal sums, then the vertical combination). Each invocation does kSpan
// consecutive output pixels of a row (specialization constant: 8 on CPU drivers, where the
// 4 x (2 kSpan + 2) input window is read once; 1 on GPUs).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation: specialization constant 2 (1 on GPUs; 16 on CPU drivers, where every 8
// invocations run as one coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY_PREV, r32f) readonly uniform image2D finer;
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) writeonly uniform image2D gray;

void pixelRow(int x0, int py) {
  ivec2 n = imageSize(finer);
  const float k[4] = float[4](0.125, 0.375, 0.375, 0.125);
  // Input columns 2 x0 - 1 .. 2 (x0 + kSpan - 1) + 2 of the four input rows, clamped.
  float window[4][2 * kSpan + 2];
  for (int t = 0; t < 4; ++t) {
    int y = clamp(2 * py - 1 + t, 0, n.y - 1);
    for (int i = 0; i < 2 * kSpan + 2; ++i)
      window[t][i] = imageLoad(finer, ivec2(clamp(2 * x0 - 1 + i, 0, n.x - 1), y)).x;
  }
  for (int j = 0; j < kSpan; ++j) {
    if (x0 + j >= pc.width) break;
    precise float rows[4];
    for (int t = 0; t < 4; ++t) {
      precise float s = 0.0;
      for (int i = 0; i < 4; ++i) s += k[i] * window[t][2 * j + i];
      rows[t] = s;
    }
    precise float result = k[0] * rows[0] + k[1] * rows[1] + k[2] * rows[2] + k[3] * rows[3];
    imageStore(gray, ivec2(x0 + j, py), vec4(result));
  }
}

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  for (int r = 0; r < kRows; ++r) {
    int py = int(gl_GlobalInvocationID.y) * kRows + r;
    if (x0 >= pc.width || py >= pc.height) return;
    pixelRow(x0, py);
  }
}
