#version 450
// Distance gradient (G_u, G_v) as computeDistanceField: central differences inside, one-sided
// on the border, 0 where the pixel or a neighbour used is truncated.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;
layout(set = 0, binding = EDGE_BINDING_DGRAD, rg32f) writeonly uniform image2D dgrad;

float axisGradient(ivec2 p, ivec2 axis, int c, int n, float centre) {
  if (n < 2) return 0.0;
  int lo = max(c - 1, 0);
  int hi = min(c + 1, n - 1);
  float a = imageLoad(distance_px, p + (lo - c) * axis).x;
  float b = imageLoad(distance_px, p + (hi - c) * axis).x;
  float t = pc.truncation_px;
  if (a >= t || b >= t || centre >= t) return 0.0;
  return (b - a) / float(hi - lo);
}

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (p.x >= pc.width || p.y >= pc.height) return;
  float centre = imageLoad(distance_px, p).x;
  float gu = axisGradient(p, ivec2(1, 0), p.x, pc.width, centre);
  float gv = axisGradient(p, ivec2(0, 1), p.y, pc.height, centre);
  imageStore(dgrad, p, vec4(gu, gv, 0.0, 0.0));
}
