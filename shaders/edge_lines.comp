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
// of its pixel) and skips the 5x5 scan: most pixels, so the pass costs ~a tenth on lavapipe.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_EPOINTS, rgba32f) readonly uniform image2D epoints;
layout(set = 0, binding = EDGE_BINDING_LINES, rgba32f) writeonly uniform image2D lines;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;

void main() {
  ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  if (q.x >= pc.width || q.y >= pc.height) return;
  vec4 out_line = vec4(0.0);
  if (pc.flags != 0u && imageLoad(distance_px, q).x < EDGE_LINE_RADIUS_PX + 0.7072) {
    const int r = int(ceil(EDGE_LINE_RADIUS_PX));
    precise float best = EDGE_LINE_RADIUS_PX * EDGE_LINE_RADIUS_PX;
    for (int y = max(q.y - r, 1); y <= min(q.y + r, pc.height - 2); ++y) {
      for (int x = max(q.x - r, 1); x <= min(q.x + r, pc.width - 2); ++x) {
        if (imageLoad(state, ivec2(x, y)).x != 2u) continue;
        vec4 point = imageLoad(epoints, ivec2(x, y));  // written by edge_nms.comp
        if (point.z == 0.0 && point.w == 0.0) continue;  // zero gradient: no normal
        precise vec2 o = vec2(q) - point.xy;
        precise float d2 = o.x * o.x + o.y * o.y;
        if (d2 >= best) continue;
        best = d2;
        out_line = vec4(point.z * o.x + point.w * o.y, point.z, point.w, 0.0);
      }
    }
  }
  imageStore(lines, q, out_line);
}
