#version 450
// Pyramid: halves the finer level with the separable binomial [1 3 3 1] / 8 on input pixels
// 2i - 1 .. 2i + 2, borders replicated (downsampleHalf in host/src/edges_cpu.cpp, same order of
// operations: four horizontal sums, then the vertical combination).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY_PREV, r32f) readonly uniform image2D finer;
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) writeonly uniform image2D gray;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  ivec2 n = imageSize(finer);
  const float k[4] = float[4](0.125, 0.375, 0.375, 0.125);
  int x[4];
  for (int t = 0; t < 4; ++t) x[t] = clamp(2 * p.x - 1 + t, 0, n.x - 1);
  precise float result = 0.0;
  precise float rows[4];
  for (int t = 0; t < 4; ++t) {
    int y = clamp(2 * p.y - 1 + t, 0, n.y - 1);
    precise float s = 0.0;
    for (int j = 0; j < 4; ++j) s += k[j] * imageLoad(finer, ivec2(x[j], y)).x;
    rows[t] = s;
  }
  result = k[0] * rows[0] + k[1] * rows[1] + k[2] * rows[2] + k[3] * rows[3];
  imageStore(gray, p, vec4(result));
}
