#version 450
// Radix select step (one invocation): finds the bucket holding the wanted rank, appends its
// bits to the prefix, clears the histogram; after the last pass derives the thresholds
// high = max(high_factor * s, min_high_gradient), low = low_ratio * high.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 1) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(std430, set = 0, binding = EDGE_BINDING_HIST) buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };

void main() {
  uint nbits = pc.step == 2 ? 9u : 11u;
  uint nb = 1u << nbits;
  uint k = pc.step == 0 ? pc.rank : ctl.remaining;
  uint below = 0u;
  uint selected = nb - 1u;
  for (uint b = 0u; b < nb; ++b) {
    uint c = hist[b];
    if (below + c > k) {
      selected = b;
      break;
    }
    below += c;
  }
  for (uint b = 0u; b < nb; ++b) hist[b] = 0u;
  uint prefix = pc.step == 0 ? selected : ((ctl.prefix << nbits) | selected);
  ctl.prefix = prefix;
  ctl.remaining = k - below;
  if (pc.step == 2) {
    float s = uintBitsToFloat(prefix);
    float high = max(pc.high_factor * s, pc.min_high_gradient);
    ctl.contrast = s;
    ctl.high = high;
    ctl.low = pc.low_ratio * high;
  }
}
