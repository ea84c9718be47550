#version 450
// Sub-pixel edge lines (LiveLevel::edge_lines, computeEdgeLines in host/src/edges_cpu.cpp) as a
// gather: pixel q takes the interior edge pixel p within kEdgeLineRadiusPx whose sub-pixel edge
// point e (EPOINTS, from edge_nms.comp: parabola vertex of the Sobel magnitude along the quantised
// gradient direction, |offset| <= half a step; the normal comes from GRAD) is nearest, strictly nearer than the radius; ties
// go to the first p in row-major order, as the CPU splat (edge pixels in row-major order,
// strict <) decides them.
// Writes (s, n_u, n_v, 0): n the unit intensity-gradient normal at p, s = n . (q - e) in pixels;
// (0, 0, 0, 0) where no edge point is that near or when pc.flags is 0 (sub-pixel edges off).
// A span whose pixels are all at least EDGE_LINE_NEAR_PX from the nearest edge pixel
// (DISTANCE, written before this pass) has no candidate (an edge point lies within
// |t d| <= 0.5 sqrt(2) of its pixel) and skips the scan: most spans.
// Two ways over the image (EdgePush::flags bit EDGE_LINES_LISTED):
// - dense: every span, writing zeros where there is no candidate (jump flooding on GPUs);
// - listed: only the near-edge spans edt_rows.comp listed (separable transform, CPU drivers).
//   LINES keeps stale values at the other pixels, which are all at least EDGE_LINE_NEAR_PX from
//   an edge: readers mask LINES with DISTANCE there (reduce_edges.comp, readLiveFrame).
// Each invocation does kSpan consecutive pixels of a row (specialization constant: 8 on CPU
// drivers, 1 on GPUs). The window of 5 rows x (kSpan + 4) columns is read one row at a time,
// without branches (a position that is no edge gets a far point), and each output pixel then
// tests only its own 5 columns of that row: 25 candidates per pixel, visited in row-major order,
// where testing every window position against every output costs kSpan + 4 times more.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"
#include "sobel.glsl"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation: specialization constant 2 (1 on GPUs; 16 on CPU drivers, where every 8
// invocations run as one coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
// CPU drivers: GRAD is not written (edge_sobel.comp); the normal is recomputed from GRAY.
layout(constant_id = 3) const int kFusedSobel = 0;
const int kR = 2;  // ceil(EDGE_LINE_RADIUS_PX)
const int kCols = kSpan + 2 * kR;
const float kFar = 1.0e4;  // point of a window position that is no edge: never within the radius
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) readonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_EPOINTS, rg32f) readonly uniform image2D epoints;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) readonly uniform image2D grad;
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) readonly uniform image2D gray;

// Sobel / 8 at interior pixel p: from GRAD, or with kFusedSobel from GRAY.
vec2 gradientAt(ivec2 p) {
  if (kFusedSobel == 0) return imageLoad(grad, p).xy;
  float a = imageLoad(gray, p + ivec2(-1, -1)).x, b = imageLoad(gray, p + ivec2(0, -1)).x;
  float c = imageLoad(gray, p + ivec2(1, -1)).x, d = imageLoad(gray, p + ivec2(-1, 0)).x;
  float f = imageLoad(gray, p + ivec2(1, 0)).x, h = imageLoad(gray, p + ivec2(-1, 1)).x;
  float i = imageLoad(gray, p + ivec2(0, 1)).x, k = imageLoad(gray, p + ivec2(1, 1)).x;
  return sobel8(a, b, c, d, f, h, i, k);
}
layout(set = 0, binding = EDGE_BINDING_LINES, rgba32f) writeonly uniform image2D lines;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;

layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) readonly buffer Control { EdgeControl ctl; };
layout(std430, set = 0, binding = EDGE_BINDING_CANDIDATES) readonly buffer Spans { uint spans[]; };

// Pixels x0 .. x0 + kSpan - 1 of row qy; `listed`: the caller knows a pixel nearby is near an
// edge (its span is listed), so the distance test is skipped.
void pixelRow(int x0, int qy, bool listed) {
  float best[kSpan];  // squared distance of the nearest edge point so far, pixels^2
  int best_x[kSpan];  // its edge pixel, -1 = none
  int best_y[kSpan];
  // Loads are unconditional (clamped), the tests branch-free: lavapipe turns a load under a
  // divergent condition into a slow masked one.
  bool any = listed;
  for (int j = 0; j < kSpan; ++j) {
    best[j] = EDGE_LINE_RADIUS_PX * EDGE_LINE_RADIUS_PX;
    best_x[j] = -1;
    best_y[j] = 0;
    if (!listed) {
      float distance = imageLoad(distance_px, ivec2(min(x0 + j, pc.width - 1), qy)).x;
      any = any || (x0 + j < pc.width) && (distance < EDGE_LINE_NEAR_PX);
    }
  }
  any = any && (pc.flags & 1u) != 0u;
  if (any) {
    for (int i = 0; i <= 2 * kR; ++i) {
      int y = qy - kR + i;
      bool row_inside = y >= 1 && y <= pc.height - 2;  // edge pixels are interior
      int yc = clamp(y, 0, pc.height - 1);
      vec2 e[kCols];
      for (int c = 0; c < kCols; ++c) {
        int x = x0 - kR + c;
        ivec2 p = ivec2(clamp(x, 0, pc.width - 1), yc);
        vec2 point = imageLoad(epoints, p).xy;  // only meaningful at an edge pixel
        uint pixel_state = imageLoad(state, p).x;
        // An edge pixel's magnitude is > 0 (edge_nms.comp keeps no other), so it has a normal
        // (the CPU skips pixels without one).
        bool edge = row_inside && x >= 1 && x <= pc.width - 2 && pixel_state == 2u;
        e[c] = edge ? point : vec2(kFar);
      }
      for (int j = 0; j < kSpan; ++j) {
        for (int k = 0; k <= 2 * kR; ++k) {
          precise vec2 o = vec2(x0 + j, qy) - e[j + k];
          precise float d2 = o.x * o.x + o.y * o.y;
          bool nearer = d2 < best[j];
          best[j] = nearer ? d2 : best[j];
          best_x[j] = nearer ? x0 - kR + j + k : best_x[j];
          best_y[j] = nearer ? y : best_y[j];
        }
      }
    }
  }
  for (int j = 0; j < kSpan; ++j) {
    if (x0 + j >= pc.width) break;
    vec4 line = vec4(0.0);
    if (best_x[j] >= 0) {
      ivec2 p = ivec2(best_x[j], best_y[j]);
      vec2 point = imageLoad(epoints, p).xy;
      vec2 g = gradientAt(p);
      precise float len = sqrt(g.x * g.x + g.y * g.y);
      precise vec2 n = len > 0.0 ? g / len : vec2(0.0);
      precise vec2 o = vec2(x0 + j, qy) - point;
      line = vec4(n.x * o.x + n.y * o.y, n, 0.0);
    }
    imageStore(lines, ivec2(x0 + j, qy), line);
  }
}

void main() {
  if ((pc.flags & EDGE_LINES_LISTED) != 0u) {
    // Only the near-edge spans of edt_rows.comp's list, grid-stride over pc.group_count groups;
    // the rest of LINES is stale (masked by its readers). Where edges are sparse this keeps
    // every lane of a CPU driver's 8-wide coroutine busy, where the dense pass below runs the
    // scan for a whole 8-invocation row as soon as one of them is near an edge.
    uint count = ctl.line_span_count;
    uint stride = 64u * pc.group_count;
    for (uint i = gl_WorkGroupID.x * 64u + gl_LocalInvocationIndex; i < count; i += stride) {
      uint s = spans[i];
      int y = int(s >> 16);
      for (int x = int(s & 0xffffu); x < min(int(s & 0xffffu) + EDGE_LINE_SPAN, pc.width); x += kSpan) {
        pixelRow(x, y, true);
      }
    }
    return;
  }
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  for (int r = 0; r < kRows; ++r) {
    int qy = int(gl_GlobalInvocationID.y) * kRows + r;
    if (x0 >= pc.width || qy >= pc.height) return;
    pixelRow(x0, qy, false);
  }
}
