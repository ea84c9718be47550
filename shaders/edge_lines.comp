#version 450
// Sub-pixel edge lines (LiveLevel::edge_lines, computeEdgeLines in host/src/edges_cpu.cpp) as a
// gather: pixel q takes the interior edge pixel p within kEdgeLineRadiusPx whose sub-pixel edge
// point e (parabola vertex of the Sobel magnitude along the quantised gradient direction,
// |offset| <= half a step) is nearest, strictly nearer than the radius; ties go to the first p in
// row-major order, as the CPU splat (edge pixels in row-major order, strict <) decides them.
// Writes (s, n_u, n_v, 0): n the unit intensity-gradient normal at p, s = n . (q - e) in pixels;
// (0, 0, 0, 0) where no edge point is that near or when pc.flags is 0 (sub-pixel edges off).
// A pixel whose distance to the nearest edge pixel (DISTANCE, written before this pass) is at
// least the radius + 0.7072 px has no candidate (an edge point lies within |t d| <= 0.5 sqrt(2)
// of its pixel) and skips the 5x5 scan: most pixels, so the pass costs ~a tenth on lavapipe.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) readonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) readonly uniform image2D grad;
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_LINES, rgba32f) writeonly uniform image2D lines;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;

float m(ivec2 p) { return imageLoad(mag, p).x; }

void main() {
  ivec2 q = ivec2(gl_GlobalInvocationID.xy);
  if (q.x >= pc.width || q.y >= pc.height) return;
  vec4 out_line = vec4(0.0);
  if (pc.flags != 0u && imageLoad(distance_px, q).x < EDGE_LINE_RADIUS_PX + 0.7072) {
    const int r = int(ceil(EDGE_LINE_RADIUS_PX));
    precise float best = EDGE_LINE_RADIUS_PX * EDGE_LINE_RADIUS_PX;
    for (int y = max(q.y - r, 1); y <= min(q.y + r, pc.height - 2); ++y) {
      for (int x = max(q.x - r, 1); x <= min(q.x + r, pc.width - 2); ++x) {
        ivec2 p = ivec2(x, y);
        if (imageLoad(state, p).x != 2u) continue;
        vec2 g = imageLoad(grad, p).xy;
        precise float len = sqrt(g.x * g.x + g.y * g.y);
        if (!(len > 0.0)) continue;
        // Quantised direction of the non-maximum suppression (nmsDirection).
        float ax = abs(g.x), ay = abs(g.y);
        const float tan22 = 0.41421356;
        ivec2 d;
        if (ay <= tan22 * ax) {
          d = ivec2(1, 0);
        } else if (ax <= tan22 * ay) {
          d = ivec2(0, 1);
        } else if ((g.x > 0.0) == (g.y > 0.0)) {
          d = ivec2(1, 1);
        } else {
          d = ivec2(-1, 1);
        }
        float m0 = m(p);
        float a = m(p - d);
        float b = m(p + d);
        precise float denominator = a - 2.0 * m0 + b;
        precise float t = denominator < 0.0 ? 0.5 * (a - b) / denominator : 0.0;
        t = clamp(t, -0.5, 0.5);
        precise vec2 e = vec2(p) + t * vec2(d);
        precise vec2 o = vec2(q) - e;
        precise float d2 = o.x * o.x + o.y * o.y;
        if (d2 >= best) continue;
        best = d2;
        precise vec2 n = g / len;
        out_line = vec4(n.x * o.x + n.y * o.y, n.x, n.y, 0.0);
      }
    }
  }
  imageStore(lines, q, out_line);
}
