#version 450
// Distance gradient (G_u, G_v) as computeDistanceField: central differences inside, one-sided
// on the border, 0 where the pixel or a neighbour used is truncated. Each invocation does kSpan
// consecutive pixels of kRows rows (specialization constants: 8 and 16 on CPU drivers, 1 on GPUs).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation (1 on GPUs; 16 on CPU drivers, where every 8 invocations run as one
// coroutine whose set-up costs about as much as a light kernel's work); the 3-row window slides
// down them, each input row read once.
layout(constant_id = 2) const int kRows = 1;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;
layout(set = 0, binding = EDGE_BINDING_DGRAD, rg32f) writeonly uniform image2D dgrad;

float d(int x, int y) { return imageLoad(distance_px, ivec2(x, y)).x; }

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  int y0 = int(gl_GlobalInvocationID.y) * kRows;
  if (x0 >= pc.width || y0 >= pc.height) return;
  float t = pc.truncation_px;
  // Columns x0 - 1 .. x0 + kSpan (clamped to the image) of rows y - 1, y, y + 1 (clamped), slid
  // down one row per output row.
  float up[kSpan + 2], row[kSpan + 2], down[kSpan + 2];
  for (int i = 0; i < kSpan + 2; ++i) {
    int x = clamp(x0 - 1 + i, 0, pc.width - 1);
    up[i] = d(x, max(y0 - 1, 0));
    row[i] = d(x, y0);
  }
  for (int r = 0; r < kRows; ++r) {
    int y = y0 + r;
    if (y >= pc.height) return;
    for (int i = 0; i < kSpan + 2; ++i) down[i] = d(clamp(x0 - 1 + i, 0, pc.width - 1), min(y + 1, pc.height - 1));
    int ylo = max(y - 1, 0), yhi = min(y + 1, pc.height - 1);
    float inv_dy = yhi > ylo ? 1.0 / float(yhi - ylo) : 0.0;
    for (int j = 0; j < kSpan; ++j) {
      int x = x0 + j;
      if (x >= pc.width) break;
      float centre = row[j + 1];
      float gu = 0.0;
      if (pc.width >= 2) {
        // Neighbours clamped to the image: row[j] / row[j + 2], or the centre on a border.
        bool left_in = x > 0, right_in = x < pc.width - 1;
        float a = left_in ? row[j] : centre, b = right_in ? row[j + 2] : centre;
        float span = float(int(left_in) + int(right_in));
        if (a < t && b < t && centre < t) gu = (b - a) / span;
      }
      float gv = 0.0;
      if (pc.height >= 2) {
        float a = up[j + 1], b = down[j + 1];  // rows ylo and yhi
        if (a < t && b < t && centre < t) gv = (b - a) * inv_dy;
      }
      imageStore(dgrad, ivec2(x, y), vec4(gu, gv, 0.0, 0.0));
    }
    for (int i = 0; i < kSpan + 2; ++i) {
      up[i] = row[i];
      row[i] = down[i];
    }
  }
}
