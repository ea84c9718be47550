#version 450
// Edge alignment per reference point (evaluateEdgePoint in host/src/edge_tracker.cpp):
// p = T_camera_ref P, (u, v) = (fx x / z + cx, fy y / z + cy); valid when z > 1e-6 m, the 2x2
// bilinear footprint lies inside the image and none of its four distances is truncated.
// When the four pixels of the footprint carry one sub-pixel edge line (LINES: normals non-zero at
// (x0, y0), each within dot > 0.8 of it), r = |bilinear s| and (G_u, G_v) = sign(s) * bilinear n;
// otherwise r = bilinear distance and (G_u, G_v) = bilinear distance gradient, the gradient at
// each of the four pixels computed here from DISTANCE as computeDistanceField does (no image of
// it is built per frame: on lavapipe storing it cost ~10 % of the live frame, while the 12
// distances a point needs replace the 4 two-channel gradient loads it made).
// J = [G_u G_v] [fx/z 0 -fx x/z^2; 0 fy/z -fy y/z^2] [I | -hat(p)].
// kMode 0: writes r per point (-1 when invalid). kMode 1: accumulates the 29 normal-equation
// values (edge_tracker.hpp layout) with t-distribution weights w = (nu + 1) / (nu + (r/sigma)^2)
// in vec4 accumulators, reduced by subgroupAdd and per workgroup into PARTIALS[group * 8 + k];
// sigma is pushed (robust.x) or, with robust.w = 1, read from CONTROL.sigma_px (edge_scale.comp).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "edge_layout.h"

layout(constant_id = 0) const int kMode = 0;
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_DISTANCE, r32f) readonly uniform image2D distance_px;
layout(set = 0, binding = EDGE_BINDING_LINES, rgba32f) readonly uniform image2D lines;
layout(std430, set = 0, binding = EDGE_BINDING_POINTS) readonly buffer Points { vec4 points[]; };
layout(std430, set = 0, binding = EDGE_BINDING_RESIDUALS) writeonly buffer Residuals { float residuals[]; };
layout(std430, set = 0, binding = EDGE_BINDING_PARTIALS) writeonly buffer Partials { vec4 partials[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) readonly buffer Control { EdgeControl control; };

shared vec4 subgroup_sums[64][EDGE_REDUCE_VEC4S];

float distanceAt(int x, int y) {
  return imageLoad(distance_px, ivec2(clamp(x, 0, pc.width - 1), clamp(y, 0, pc.height - 1))).x;
}

// Distance gradient (G_u, G_v) at pixel c (computeDistanceGradient in host/src/edges_cpu.cpp):
// central differences inside, one-sided on the border, 0 where the centre d or a neighbour used
// (left, right, up, down: clamped to the image) is truncated.
vec2 distanceGradient(ivec2 c, float d, float left, float right, float up, float down) {
  float t = pc.truncation_px;
  // Steps of 2 or 1 pixels: scales 0.5 or 1, multiplied as the CPU does (no division, whose
  // rounding Vulkan does not pin down).
  int span = int(c.x > 0) + int(c.x < pc.width - 1);  // 0 for a one-column image
  float inv_dx = span == 2 ? 0.5 : 1.0;
  float gu = span > 0 && d < t && left < t && right < t ? (right - left) * inv_dx : 0.0;
  int ylo = max(c.y - 1, 0), yhi = min(c.y + 1, pc.height - 1);
  float inv_dy = yhi - ylo == 2 ? 0.5 : (yhi > ylo ? 1.0 : 0.0);
  float gv = d < t && up < t && down < t ? (down - up) * inv_dy : 0.0;
  return vec2(gu, gv);
}

void main() {
  uint stride = 64u * pc.group_count;
  vec4 a0 = vec4(0), a1 = vec4(0), a2 = vec4(0), a3 = vec4(0);
  vec4 a4 = vec4(0), a5 = vec4(0), a6 = vec4(0), a7 = vec4(0);
  float fx = pc.intrinsics.x, fy = pc.intrinsics.y, cx = pc.intrinsics.z, cy = pc.intrinsics.w;
  float trunc = pc.truncation_px;
  // Scale of the weights: pushed, or estimated by edge_scale.comp in the same submission.
  float sigma = pc.robust.w > 0.5 ? control.sigma_px : pc.robust.x;
  for (uint i = gl_GlobalInvocationID.x; i < pc.point_count; i += stride) {
    vec4 P = vec4(points[i].xyz, 1.0);
    vec3 p = vec3(dot(pc.pose_row0, P), dot(pc.pose_row1, P), dot(pc.pose_row2, P));
    bool valid = p.z > 1e-6;
    float r = -1.0;
    float iz = 0.0, u = 0.0, v = 0.0;
    if (valid) {
      iz = 1.0 / p.z;
      u = fx * p.x * iz + cx;
      v = fy * p.y * iz + cy;
      valid = u >= 0.0 && v >= 0.0 && u < float(pc.width - 1) && v < float(pc.height - 1);
    }
    ivec2 q = ivec2(0);
    float w00 = 0.0, w10 = 0.0, w01 = 0.0, w11 = 0.0;
    float r_distance = 0.0;
    float d00 = 0.0, d10 = 0.0, d01 = 0.0, d11 = 0.0;  // distances of the footprint, pixels
    float d_max = 0.0;                                 // the largest of them
    if (valid) {
      q = ivec2(int(u), int(v));
      float a = u - float(q.x), b = v - float(q.y);
      d00 = imageLoad(distance_px, q).x;
      d10 = imageLoad(distance_px, q + ivec2(1, 0)).x;
      d01 = imageLoad(distance_px, q + ivec2(0, 1)).x;
      d11 = imageLoad(distance_px, q + ivec2(1, 1)).x;
      valid = !(d00 >= trunc || d10 >= trunc || d01 >= trunc || d11 >= trunc);
      d_max = max(max(d00, d10), max(d01, d11));
      w00 = (1.0 - a) * (1.0 - b);
      w10 = a * (1.0 - b);
      w01 = (1.0 - a) * b;
      w11 = a * b;
      r_distance = w00 * d00 + w10 * d10 + w01 * d01 + w11 * d11;
    }
    bool on_line = false;
    vec2 g = vec2(0.0);
    if (valid) {
      vec3 l00 = imageLoad(lines, q).xyz;
      vec3 l10 = imageLoad(lines, q + ivec2(1, 0)).xyz;
      vec3 l01 = imageLoad(lines, q + ivec2(0, 1)).xyz;
      vec3 l11 = imageLoad(lines, q + ivec2(1, 1)).xyz;
      // LINES is stale where DISTANCE >= EDGE_LINE_NEAR_PX (edge_lines.comp's listed path);
      // a pixel with a normal there is impossible, so the test changes nothing elsewhere.
      on_line = d_max < EDGE_LINE_NEAR_PX && (l00.y != 0.0 || l00.z != 0.0) && dot(l10.yz, l00.yz) > 0.8 && dot(l01.yz, l00.yz) > 0.8 &&
                dot(l11.yz, l00.yz) > 0.8;
      if (on_line) {
        float s_line = w00 * l00.x + w10 * l10.x + w01 * l01.x + w11 * l11.x;
        float sign_line = s_line < 0.0 ? -1.0 : 1.0;
        r = abs(s_line);
        g = sign_line * (w00 * l00.yz + w10 * l10.yz + w01 * l01.yz + w11 * l11.yz);
      } else {
        r = r_distance;
      }
    }
    if (kMode == 0) {
      residuals[i] = r;
      continue;
    }
    if (!valid) continue;
    if (!on_line) {
      // The 4 x 4 block around the footprint less its corners: 8 distances beyond its own 4.
      float n0 = distanceAt(q.x, q.y - 1), n1 = distanceAt(q.x + 1, q.y - 1);  // above
      float w0 = distanceAt(q.x - 1, q.y), w1 = distanceAt(q.x - 1, q.y + 1);  // left
      float e0 = distanceAt(q.x + 2, q.y), e1 = distanceAt(q.x + 2, q.y + 1);  // right
      float s0 = distanceAt(q.x, q.y + 2), s1 = distanceAt(q.x + 1, q.y + 2);  // below
      g = w00 * distanceGradient(q, d00, w0, d10, n0, d01) +
          w10 * distanceGradient(q + ivec2(1, 0), d10, d00, e0, n1, d11) +
          w01 * distanceGradient(q + ivec2(0, 1), d01, w1, d11, d00, s0) +
          w11 * distanceGradient(q + ivec2(1, 1), d11, d01, e1, d10, s1);
    }
    float ga = g.x * fx * iz;
    float gb = g.y * fy * iz;
    vec3 jt = vec3(ga, gb, -(ga * p.x + gb * p.y) * iz);
    vec3 jr = cross(p, jt);
    float s = r / sigma;
    float w = (pc.robust.y + 1.0) / (pc.robust.y + s * s);
    vec3 wt = w * jt;
    vec3 wr = w * jr;
    a0 += wt.x * vec4(jt, jr.x);
    a1 += vec4(wt.x * jr.y, wt.x * jr.z, wt.y * jt.y, wt.y * jt.z);
    a2 += vec4(wt.y * jr.x, wt.y * jr.y, wt.y * jr.z, wt.z * jt.z);
    a3 += vec4(wt.z * jr.x, wt.z * jr.y, wt.z * jr.z, wr.x * jr.x);
    a4 += vec4(wr.x * jr.y, wr.x * jr.z, wr.y * jr.y, wr.y * jr.z);
    a5 += vec4(wr.z * jr.z, wt.x * r, wt.y * r, wt.z * r);
    a6 += vec4(wr.x * r, wr.y * r, wr.z * r, w * r * r);
    a7.x += 1.0;
  }
  if (kMode == 0) return;
  a0 = subgroupAdd(a0);
  a1 = subgroupAdd(a1);
  a2 = subgroupAdd(a2);
  a3 = subgroupAdd(a3);
  a4 = subgroupAdd(a4);
  a5 = subgroupAdd(a5);
  a6 = subgroupAdd(a6);
  a7 = subgroupAdd(a7);
  if (subgroupElect()) {
    subgroup_sums[gl_SubgroupID][0] = a0;
    subgroup_sums[gl_SubgroupID][1] = a1;
    subgroup_sums[gl_SubgroupID][2] = a2;
    subgroup_sums[gl_SubgroupID][3] = a3;
    subgroup_sums[gl_SubgroupID][4] = a4;
    subgroup_sums[gl_SubgroupID][5] = a5;
    subgroup_sums[gl_SubgroupID][6] = a6;
    subgroup_sums[gl_SubgroupID][7] = a7;
  }
  barrier();
  if (gl_LocalInvocationIndex < EDGE_REDUCE_VEC4S) {
    uint k = gl_LocalInvocationIndex;
    vec4 sum = vec4(0);
    for (uint s = 0u; s < gl_NumSubgroups; ++s) sum += subgroup_sums[s][k];
    partials[gl_WorkGroupID.x * EDGE_REDUCE_VEC4S + k] = sum;
  }
}
