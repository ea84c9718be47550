#version 450
// Sub-pixel edge lines (LiveLevel::edge_lines, computeEdgeLines in host/src/edges_cpu.cpp) as a
// gather: pixel q takes the interior edge pixel p within kEdgeLineRadiusPx whose sub-pixel edge
// point e (EPOINTS, from edge_nms.comp: parabola vertex of the Sobel magnitude along the quantised
// gradient direction, |offset| <= half a step) is nearest, strictly nearer than the radius; ties
// go to the first p in row-major order, as the CPU splat (edge pixels in row-major order,
// strict <) decides them.
// Writes (s, n_u, n_v, 0): n the unit intensity-gradient normal at p, s = n . (q - e) in pixels;
// (0, 0, 0, 0) where no edge point is that near or when pc.flags is 0 (sub-pixel edges off).
// A pixel whose distance to the nearest edge pixel (DISTANCE, written before this pass) is at
// least the radius + 0.7072 px has no candidate (an edge point lies within |t d| <= 0.5 sqrt(2)
// of its pixel) and skips the scan: most pixels, so the pass costs ~a tenth on lavapipe.
// Each invocation does kSpan consecutive pixels of a row (specialization constant: 8 on CPU
// drivers, where the 5 x (kSpan + 4) window is read once for all of them; 1 on GPUs); the
// window is scanned in row-major order, so every pixel sees its candidates in the same order.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(constant_id = 1) const int kSpan = 1;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_EPOINTS, rgba32f) readonly uniform image2D epoints;
layout(set = 0, binding = EDGE_BINDING_LINES, rgba32f) writeonly uniform image2D lines;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  int qy = int(gl_GlobalInvocationID.y);
  if (x0 >= pc.width || qy >= pc.height) return;
  const int r = int(ceil(EDGE_LINE_RADIUS_PX));
  vec4 out_line[kSpan];
  float best[kSpan];
  bool wanted[kSpan];
  bool any = false;
  for (int j = 0; j < kSpan; ++j) {
    out_line[j] = vec4(0.0);
    best[j] = EDGE_LINE_RADIUS_PX * EDGE_LINE_RADIUS_PX;
    wanted[j] = pc.flags != 0u && x0 + j < pc.width &&
                imageLoad(distance_px, ivec2(x0 + j, qy)).x < EDGE_LINE_RADIUS_PX + 0.7072;
    any = any || wanted[j];
  }
  if (any) {
    for (int y = max(qy - r, 1); y <= min(qy + r, pc.height - 2); ++y) {
      for (int x = max(x0 - r, 1); x <= min(x0 + kSpan - 1 + r, pc.width - 2); ++x) {
        if (imageLoad(state, ivec2(x, y)).x != 2u) continue;
        vec4 point = imageLoad(epoints, ivec2(x, y));  // written by edge_nms.comp
        if (point.z == 0.0 && point.w == 0.0) continue;  // zero gradient: no normal
        for (int j = 0; j < kSpan; ++j) {
          int qx = x0 + j;
          if (!wanted[j] || abs(x - qx) > r) continue;
          precise vec2 o = vec2(qx, qy) - point.xy;
          precise float d2 = o.x * o.x + o.y * o.y;
          if (d2 >= best[j]) continue;
          best[j] = d2;
          out_line[j] = vec4(point.z * o.x + point.w * o.y, point.z, point.w, 0.0);
        }
      }
    }
  }
  for (int j = 0; j < kSpan; ++j) {
    if (x0 + j < pc.width) imageStore(lines, ivec2(x0 + j, qy), out_line[j]);
  }
}
