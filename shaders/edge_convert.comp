#version 450
// Live image upload: 8-bit gray (4 pixels per uint, row-major) to the r32f level-0 image.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

// Rows per invocation: specialization constant 2 (1 on GPUs; 16 on CPU drivers, where every 8
// invocations run as one coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(std430, set = 0, binding = EDGE_BINDING_INPUT8) readonly buffer Input8 { uint pixels[]; };
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) writeonly uniform image2D gray;

void main() {
  int x = int(gl_GlobalInvocationID.x);
  for (int r = 0; r < kRows; ++r) {
    ivec2 p = ivec2(x, int(gl_GlobalInvocationID.y) * kRows + r);
    if (p.x >= pc.width || p.y >= pc.height) return;
    uint i = uint(p.y * pc.width + p.x);
    uint value = (pixels[i >> 2] >> (8u * (i & 3u))) & 0xffu;
    imageStore(gray, p, vec4(float(value)));
  }
}
