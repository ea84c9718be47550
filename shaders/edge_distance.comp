#version 450
// Distance from each pixel centre to its jump-flooding seed, clamped to truncation_px (the
// truncation where there is no seed). flags 0: seeds in SEED_A, 1: in SEED_B.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_SEED_A, r32ui) readonly uniform uimage2D seeds_a;
layout(set = 0, binding = EDGE_BINDING_SEED_B, r32ui) readonly uniform uimage2D seeds_b;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) writeonly uniform image2D distance_px;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  uint s = pc.flags == 0u ? imageLoad(seeds_a, p).x : imageLoad(seeds_b, p).x;
  float d = pc.truncation_px;
  if (s != EDGE_NO_SEED) {
    ivec2 e = ivec2(s & 0xffffu, s >> 16) - p;
    d = min(sqrt(float(e.x * e.x + e.y * e.y)), pc.truncation_px);
  }
  imageStore(distance_px, p, vec4(d));
}
