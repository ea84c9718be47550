#version 450
// Live image upload: 8-bit gray (4 pixels per uint, row-major) to the r32f level-0 image.
// Each invocation does 4 consecutive pixels of a row: one uint load when the width is a
// multiple of 4 (a row then starts on a uint), per pixel otherwise (lavapipe loads a storage
// buffer lane by lane, so a load per pixel cost a third of this pass).
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
  int x0 = int(gl_GlobalInvocationID.x) * 4;
  for (int r = 0; r < kRows; ++r) {
    int y = int(gl_GlobalInvocationID.y) * kRows + r;
    if (x0 >= pc.width || y >= pc.height) return;
    uint i0 = uint(y * pc.width + x0);
    uint word = pixels[i0 >> 2];  // all 4 pixels when the width is a multiple of 4
    for (int j = 0; j < 4; ++j) {
      if (x0 + j >= pc.width) break;
      uint i = i0 + uint(j);
      uint w = (pc.width & 3) == 0 ? word : pixels[i >> 2];
      imageStore(gray, ivec2(x0 + j, y), vec4(float((w >> (8u * (i & 3u))) & 0xffu)));
    }
  }
}
