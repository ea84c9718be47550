#version 450
// Exact truncated distance transform, column pass (separable, as the CPU's; see
// truncatedDistanceTransform in host/src/edges_cpu.cpp): one invocation per column sweeps down
// and up, writing g^2 into SEED_A, g = vertical distance (pixels) to the nearest edge pixel of
// the column, capped at R + 1 with R = ceil(truncation) - 1. Used on CPU drivers, where one
// sequential loop per column beats jump flooding's 9 gathers per pixel and pass.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_SEED_A, r32ui) uniform uimage2D g2;

void main() {
  int x = int(gl_GlobalInvocationID.x);
  if (x >= pc.width) return;
  uint cap = uint(ceil(pc.truncation_px));  // R + 1
  // Downwards: distance to the nearest edge at or above.
  uint d = cap;
  for (int y = 0; y < pc.height; ++y) {
    d = imageLoad(state, ivec2(x, y)).x == 2u ? 0u : min(d + 1u, cap);
    imageStore(g2, ivec2(x, y), uvec4(d));
  }
  // Upwards: the nearer of both directions, squared.
  d = cap;
  for (int y = pc.height - 1; y >= 0; --y) {
    uint up = imageLoad(g2, ivec2(x, y)).x;
    d = up == 0u ? 0u : min(d + 1u, cap);
    uint g = min(up, d);
    imageStore(g2, ivec2(x, y), uvec4(g * g));
  }
}
