#version 450
// Jump flooding, one pass of step k: each pixel keeps the nearest of the seeds held by itself
// and its 8 neighbours at offsets of k pixels. kFromB 0: SEED_A -> SEED_B, 1: SEED_B -> SEED_A
// (a specialization constant, not a push constant: lavapipe's SIMD code otherwise loads from
// both images and selects).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(constant_id = 0) const int kFromB = 0;
layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_SEED_A, r32ui) uniform uimage2D seeds_a;
layout(set = 0, binding = EDGE_BINDING_SEED_B, r32ui) uniform uimage2D seeds_b;

uint load(ivec2 q) { return kFromB == 0 ? imageLoad(seeds_a, q).x : imageLoad(seeds_b, q).x; }

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  uint best = EDGE_NO_SEED;
  int best_d2 = 0x7fffffff;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      ivec2 q = p + pc.step * ivec2(dx, dy);
      if (q.x < 0 || q.y < 0 || q.x >= pc.width || q.y >= pc.height) continue;
      uint s = load(q);
      if (s == EDGE_NO_SEED) continue;
      ivec2 d = ivec2(s & 0xffffu, s >> 16) - p;
      int d2 = d.x * d.x + d.y * d.y;
      if (d2 < best_d2) {
        best_d2 = d2;
        best = s;
      }
    }
  }
  if (kFromB == 0) {
    imageStore(seeds_b, p, uvec4(best));
  } else {
    imageStore(seeds_a, p, uvec4(best));
  }
}
