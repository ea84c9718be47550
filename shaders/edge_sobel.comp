#version 450
// 3x3 Sobel divided by 8 (gray levels per pixel), borders replicated, and its magnitude.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) readonly uniform image2D gray;
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) writeonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) writeonly uniform image2D grad;

float g(int x, int y) { return imageLoad(gray, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x; }

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  float a = g(p.x - 1, p.y - 1), b = g(p.x, p.y - 1), c = g(p.x + 1, p.y - 1);
  float d = g(p.x - 1, p.y), f = g(p.x + 1, p.y);
  float h = g(p.x - 1, p.y + 1), i = g(p.x, p.y + 1), j = g(p.x + 1, p.y + 1);
  float gx = ((c - a) + 2.0 * (f - d) + (j - h)) * 0.125;
  float gy = ((h - a) + 2.0 * (i - b) + (j - c)) * 0.125;
  imageStore(grad, p, vec4(gx, gy, 0.0, 0.0));
  imageStore(mag, p, vec4(sqrt(gx * gx + gy * gy)));
}
