#version 450
// Non-maximum suppression along the gradient direction quantised to 4 directions (detectEdges
// in host/src/edges_cpu.cpp): keeps an interior pixel whose magnitude is >= low, > 0, >= both
// neighbours and > one of them; 2 when >= high, else 1 (weak, appended to the candidate list).
// For every kept pixel also its sub-pixel edge point for edge_lines.comp (EPOINTS): the parabola
// vertex of the magnitude along the quantised direction d, e = p + t d with |t| <= 1/2, and the
// unit gradient normal n, as (e_u, e_v, n_u, n_v); other pixels' values are never read.
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "edge_layout.h"

layout(local_size_x = 16, local_size_y = 16) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) readonly uniform image2D mag;
layout(set = 0, binding = EDGE_BINDING_GRAD, rg32f) readonly uniform image2D grad;
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) writeonly uniform uimage2D state;
layout(set = 0, binding = EDGE_BINDING_EPOINTS, rgba32f) writeonly uniform image2D epoints;
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };
layout(std430, set = 0, binding = EDGE_BINDING_CANDIDATES) writeonly buffer Candidates { uint candidates[]; };

float m(int x, int y) { return imageLoad(mag, ivec2(x, y)).x; }

void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  bool inside = p.x < pc.width && p.y < pc.height;
  uint s = 0u;
  if (p.x >= 1 && p.y >= 1 && p.x < pc.width - 1 && p.y < pc.height - 1) {
    float v = m(p.x, p.y);
    float low = ctl.low;
    if (!(v < low || v <= 0.0)) {
      vec2 g = imageLoad(grad, p).xy;
      float ax = abs(g.x), ay = abs(g.y);
      const float tan22 = 0.41421356;
      ivec2 d;  // nmsDirection; a = m(p - d), b = m(p + d)
      if (ay <= tan22 * ax) {
        d = ivec2(1, 0);
      } else if (ax <= tan22 * ay) {
        d = ivec2(0, 1);
      } else if ((g.x > 0.0) == (g.y > 0.0)) {
        d = ivec2(1, 1);
      } else {
        d = ivec2(-1, 1);
      }
      float a = m(p.x - d.x, p.y - d.y);
      float b = m(p.x + d.x, p.y + d.y);
      if (v >= a && v >= b && (v > a || v > b)) {
        s = v >= ctl.high ? 2u : 1u;
        precise float len = sqrt(g.x * g.x + g.y * g.y);
        precise float denominator = a - 2.0 * v + b;
        precise float t = denominator < 0.0 ? 0.5 * (a - b) / denominator : 0.0;
        t = clamp(t, -0.5, 0.5);
        precise vec2 e = vec2(p) + t * vec2(d);
        precise vec2 n = len > 0.0 ? g / len : vec2(0.0);
        imageStore(epoints, p, vec4(e, n));
      }
    }
  }
  if (inside) imageStore(state, p, uvec4(s));
  // One atomic per subgroup for the candidate list.
  bool weak = s == 1u;
  uvec4 ballot = subgroupBallot(weak);
  uint count = subgroupBallotBitCount(ballot);
  if (count == 0u) return;
  uint base = 0u;
  if (subgroupElect()) base = atomicAdd(ctl.candidate_count, count);
  base = subgroupBroadcastFirst(base);
  if (weak) candidates[base + subgroupBallotExclusiveBitCount(ballot)] = uint(p.x) | (uint(p.y) << 16);
}
