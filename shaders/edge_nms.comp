#version 450
// Non-maximum suppression along the gradient direction quantised to 4 directions (detectEdges
// in host/src/edges_cpu.cpp): keeps an interior pixel whose magnitude is >= low, > 0, >= both
// neighbours and > one of them; 2 when >= high, else 1 (weak, appended to the candidate list).
// For every kept pixel also its sub-pixel edge point for edge_lines.comp (EPOINTS): the parabola
// vertex of the magnitude along the quantised direction d, e = p + t d with |t| <= 1/2, as
// (e_u, e_v); other pixels' values are never read.
// Each invocation does kSpan consecutive pixels of kRows rows (specialization constant: 8 on CPU
// drivers, where the 3 x (kSpan + 2) magnitudes slide down the rows; 1 on GPUs).
// With kFusedSobel (CPU drivers) the magnitudes and the gradient come from GRAY here
// (sobel.glsl, the floats edge_sobel.comp computes), one new row of magnitudes per output row,
// instead of from MAG and GRAD, which edge_sobel.comp then does not write.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "edge_layout.h"
#include "sobel.glsl"

layout(constant_id = 1) const int kSpan = 1;
// Rows per invocation (1 on GPUs; 16 on CPU drivers, where every 8 invocations run as one
// coroutine whose set-up costs about as much as a light kernel's work); the 3-row window of
// magnitudes slides down them, each row read once.
layout(constant_id = 2) const int kRows = 1;
layout(constant_id = 3) const int kFusedSobel = 0;
layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_GRAY, r32f) readonly uniform image2D gray;
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) readonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) readonly uniform image2D grad;
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) writeonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_EPOINTS, rg32f) writeonly uniform image2D epoints;
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };
layout(std430, set = 0, binding = EDGE_BINDING_CANDIDATES) writeonly buffer Candidates { uint candidates[]; };

float m(int x, int y) { return imageLoad(mag, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x; }

// Magnitudes of columns x0 - 1 .. x0 + kSpan (clamped) of rows y - 1, y, y + 1, slid down one
// row per output row.
float top[kSpan + 2], mid[kSpan + 2], bot[kSpan + 2];
// kFusedSobel: the gradient of pixels x0 .. x0 + kSpan - 1 of rows y and y + 1.
vec2 grad_mid[kSpan], grad_bot[kSpan];

float g(int x, int y) { return imageLoad(gray, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x; }

// kFusedSobel: magnitudes of row r (clamped to the image) into bot, as m(x0 - 1 + i, r), and
// the gradient of its pixels x0 .. x0 + kSpan - 1 into grad_bot.
void sobelRow(int x0, int r) {
  int y = clamp(r, 0, pc.height - 1);
  float up[kSpan + 4], row[kSpan + 4], down[kSpan + 4];  // gray of columns x0 - 2 .. x0 + kSpan + 1
  for (int c = 0; c < kSpan + 4; ++c) {
    up[c] = g(x0 - 2 + c, y - 1);
    row[c] = g(x0 - 2 + c, y);
    down[c] = g(x0 - 2 + c, y + 1);
  }
  for (int i = 0; i < kSpan + 2; ++i) {
    vec2 gxy = sobel8(up[i], up[i + 1], up[i + 2], row[i], row[i + 2], down[i], down[i + 1], down[i + 2]);
    bot[i] = sobelMagnitude(gxy);
    if (i >= 1 && i <= kSpan) grad_bot[i - 1] = gxy;
  }
  // Columns outside the image take their clamped neighbour's magnitude, as m() reads it.
  if (x0 == 0) bot[0] = bot[1];
  for (int i = 1; i < kSpan + 2; ++i) bot[i] = x0 - 1 + i >= pc.width ? bot[i - 1] : bot[i];
}

// Classifies pixels x0 .. x0 + kSpan - 1 of row y (top/mid/bot hold rows y - 1 .. y + 1);
// returns the weak candidates (bit j: x0 + j).
uint pixelRow(int x0, int y) {
  bool row_inside = y < pc.height && x0 < pc.width;
  uint weak_bits = 0u;  // bit j: pixel x0 + j is a weak candidate
  if (row_inside) {
    float low = ctl.low, high = ctl.high;
    for (int j = 0; j < kSpan; ++j) {
      ivec2 p = ivec2(x0 + j, y);
      if (p.x >= pc.width) break;
      uint s = 0u;
      float v = mid[j + 1];
      if (p.x >= 1 && p.y >= 1 && p.x < pc.width - 1 && p.y < pc.height - 1 && !(v < low || v <= 0.0)) {
        vec2 g = kFusedSobel != 0 ? grad_mid[j] : imageLoad(grad, p).xy;
        float ax = abs(g.x), ay = abs(g.y);
        const float tan22 = 0.41421356;
        ivec2 d;  // nmsDirection; a = m(p - d), b = m(p + d)
        float a, b;
        if (ay <= tan22 * ax) {
          d = ivec2(1, 0);
          a = mid[j];
          b = mid[j + 2];
        } else if (ax <= tan22 * ay) {
          d = ivec2(0, 1);
          a = top[j + 1];
          b = bot[j + 1];
        } else if ((g.x > 0.0) == (g.y > 0.0)) {
          d = ivec2(1, 1);
          a = top[j];
          b = bot[j + 2];
        } else {
          d = ivec2(-1, 1);
          a = top[j + 2];
          b = bot[j];
        }
        if (v >= a && v >= b && (v > a || v > b)) {
          s = v >= high ? 2u : 1u;
          precise float denominator = a - 2.0 * v + b;
          precise float t = denominator < 0.0 ? 0.5 * (a - b) / denominator : 0.0;
          t = clamp(t, -0.5, 0.5);
          precise vec2 e = vec2(p) + t * vec2(d);
          // Only the point: every 4 bytes of a conditional store cost (lavapipe stores lane by
          // lane); edge_lines.comp takes the normal from GRAD.
          imageStore(epoints, p, vec4(e, 0.0, 0.0));
        }
      }
      if (s != 0u) imageStore(state, p, uvec4(s));  // STATE is cleared to 0 before this pass
      if (s == 1u) weak_bits |= 1u << uint(j);
    }
  }
  return weak_bits;
}

void main() {
  int x0 = int(gl_GlobalInvocationID.x) * kSpan;
  int y0 = int(gl_GlobalInvocationID.y) * kRows;
  if (kFusedSobel != 0) {
    sobelRow(x0, y0 - 1);
    for (int i = 0; i < kSpan + 2; ++i) top[i] = bot[i];
    sobelRow(x0, y0);
    for (int i = 0; i < kSpan + 2; ++i) mid[i] = bot[i];
    for (int j = 0; j < kSpan; ++j) grad_mid[j] = grad_bot[j];
  } else {
    for (int i = 0; i < kSpan + 2; ++i) {
      top[i] = m(x0 - 1 + i, y0 - 1);
      mid[i] = m(x0 - 1 + i, y0);
    }
  }
  for (int r = 0; r < kRows; ++r) {
    int y = y0 + r;
    if (kFusedSobel != 0) {
      sobelRow(x0, y + 1);
    } else {
      for (int i = 0; i < kSpan + 2; ++i) bot[i] = m(x0 - 1 + i, y + 1);
    }
    uint weak_bits = pixelRow(x0, y);
    for (int i = 0; i < kSpan + 2; ++i) {
      top[i] = mid[i];
      mid[i] = bot[i];
    }
    for (int j = 0; j < kSpan; ++j) grad_mid[j] = grad_bot[j];
    // The weak candidates into the list: one atomic per subgroup (its invocations share y).
    uint count = bitCount(weak_bits);
    uint total = subgroupAdd(count);
    if (total == 0u) continue;
    uint offset = subgroupExclusiveAdd(count);
    uint base = 0u;
    if (subgroupElect()) base = atomicAdd(ctl.candidate_count, total);
    base = subgroupBroadcastFirst(base) + offset;
    for (int j = 0; j < kSpan; ++j) {
      if ((weak_bits & (1u << uint(j))) != 0u) candidates[base++] = uint(x0 + j) | (uint(y) << 16);
    }
  }
}
