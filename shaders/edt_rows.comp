#version 450
// Exact truncated distance transform, row pass (eq. 12's V(u) as min over dx of dx^2 + g^2):
// each invocation finishes kSpan consecutive pixels of one row from the squared column
// distances g^2 of edt_columns.comp (SEED_A): it reads the kSpan + 2R values around them once
// ((R + 1)^2 outside the image) and keeps the kSpan running minima in registers (the radius
// R = ceil(truncation) - 1 is a specialization constant, so the inner loop unrolls). Terms
// with |dx| > R are >= (R + 1)^2 >= truncation^2 and can only give the clamped value, so every
// window position is added to every pixel without a range test. Writes the distance, clamped
// to the truncation. Appends every span with a pixel nearer than EDGE_LINE_NEAR_PX to
// an edge pixel (a pixel whose edge line edge_lines.comp may fill) to the span list
// (CANDIDATES, counted in line_span_count), so that edge_lines.comp need not visit the rest.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "edge_layout.h"

layout(constant_id = 0) const int kRadius = 19;
const int kSpan = EDGE_LINE_SPAN;
// Rows per invocation: specialization constant 2 (1 on GPUs; 16 on CPU drivers, where every 8
// invocations run as one coroutine whose set-up costs about as much as a light kernel's work).
layout(constant_id = 2) const int kRows = 1;
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_SEED_A, r32ui) readonly uniform uimage2D g2;
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) writeonly uniform image2D distance_px;
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };
layout(std430, set = 0, binding = EDGE_BINDING_CANDIDATES) writeonly buffer Spans { uint spans[]; };

void pixelRow(int x0, int y) {
  uint far2 = uint((kRadius + 1) * (kRadius + 1));
  uint best[kSpan];
  for (int j = 0; j < kSpan; ++j) best[j] = 0xffffffffu;
  for (int i = 0; i < kSpan + 2 * kRadius; ++i) {
    int x = x0 - kRadius + i;
    uint loaded = imageLoad(g2, ivec2(clamp(x, 0, pc.width - 1), y)).x;  // unconditional: see edge_lines.comp
    uint v = (x >= 0 && x < pc.width) ? loaded : far2;
    for (int j = 0; j < kSpan; ++j) {
      int dx = i - kRadius - j;
      best[j] = min(best[j], v + uint(dx * dx));
    }
  }
  bool near = false;
  for (int j = 0; j < kSpan; ++j) {
    if (x0 + j < pc.width) {
      float distance = min(sqrt(float(best[j])), pc.truncation_px);
      imageStore(distance_px, ivec2(x0 + j, y), vec4(distance));
      near = near || distance < EDGE_LINE_NEAR_PX;  // the test of edge_lines.comp
    }
  }
  // Into the span list: one atomic per subgroup.
  uint count = near ? 1u : 0u;
  uint total = subgroupAdd(count);
  if (total == 0u) return;
  uint offset = subgroupExclusiveAdd(count);
  uint base = 0u;
  if (subgroupElect()) base = atomicAdd(ctl.line_span_count, total);
  base = subgroupBroadcastFirst(base) + offset;
  if (near) spans[base] = uint(x0) | (uint(y) << 16);
}

void main() {
  // Invocations numbered along the spans of a row, then by block of kRows rows; the grid may be
  // 2D when a 1D one would exceed 65535 groups.
  int row_spans = (pc.width + kSpan - 1) / kSpan;
  int id = int(gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x);
  int block = id / row_spans;
  int x0 = (id - block * row_spans) * kSpan;
  for (int r = 0; r < kRows; ++r) {
    int y = block * kRows + r;
    if (y >= pc.height) return;
    pixelRow(x0, y);
  }
}
