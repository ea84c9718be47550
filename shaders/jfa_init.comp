#version 450
// Jump flooding, initialisation: every edge pixel seeds itself, other pixels have no seed.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_SEED_A, r32ui) writeonly uniform uimage2D seeds;

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  bool edge = imageLoad(state, p).x == 2u;
  imageStore(seeds, p, uvec4(edge ? (uint(p.x) | (uint(p.y) << 16)) : EDGE_NO_SEED));
}
