#version 450
// Contrast quantile by radix select on the magnitude's float bits (non-negative floats order
// like their bit patterns): pass 0 counts bits 30..20, pass 1 bits 19..9 of the samples whose
// higher bits equal the selected prefix, pass 2 bits 8..0. Samples: every second pixel in x
// and y (as detectEdges). Shared-memory histogram per workgroup, grid-stride loop.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) readonly uniform image2D mag;
layout(std430, set = 0, binding = EDGE_BINDING_HIST) buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) readonly buffer Control { EdgeControl ctl; };

shared uint bins[EDGE_HIST_BINS];

void main() {
  for (uint b = gl_LocalInvocationIndex; b < EDGE_HIST_BINS; b += 256u) bins[b] = 0u;
  barrier();
  uint shift = pc.step == 0 ? 20u : (pc.step == 1 ? 9u : 0u);
  uint nbits = pc.step == 2 ? 9u : 11u;
  uint mask = (1u << nbits) - 1u;
  uint high_shift = shift + nbits;
  uint prefix = ctl.prefix;
  uint sw = uint(pc.width + 1) / 2u;
  uint n = sw * (uint(pc.height + 1) / 2u);
  uint stride = 256u * pc.group_count;
  for (uint i = gl_GlobalInvocationID.x; i < n; i += stride) {
    ivec2 p = ivec2(2u * (i % sw), 2u * (i / sw));
    uint bits = floatBitsToUint(imageLoad(mag, p).x);
    if ((bits >> high_shift) != prefix) continue;
    atomicAdd(bins[(bits >> shift) & mask], 1u);
  }
  barrier();
  for (uint b = gl_LocalInvocationIndex; b <= mask; b += 256u) {
    if (bins[b] != 0u) atomicAdd(hist[b], bins[b]);
  }
}
