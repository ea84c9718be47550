#version 450
// Radix select step (one workgroup): finds the bucket holding the wanted rank, appends its bits
// to the prefix, clears the histogram; after the last pass derives the thresholds
// high = max(high_factor * s, min_high_gradient), low = low_ratio * high.
// Each invocation sums a run of buckets; invocation 0 finds the run holding the rank, whose
// invocation then finds the bucket (a single invocation scanning all 2048 buckets took 0.7 ms
// per frame on an H100, memory latency bound).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(std430, set = 0, binding = EDGE_BINDING_HIST) buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };

shared uint run_sums[256];
shared uint found_run;    // run holding the rank, 256 = none (rank beyond the total)
shared uint found_below;  // samples in the runs before it (all samples when none)

void main() {
  const uint t = gl_LocalInvocationIndex;
  const uint nbits = pc.step == 2 ? 9u : 11u;
  const uint nb = 1u << nbits;
  const uint per = (nb + 255u) / 256u;
  const uint first = t * per;
  const uint k = pc.step == 0 ? pc.rank : ctl.remaining;
  uint local_sum = 0u;
  for (uint i = 0u; i < per; ++i) {
    if (first + i < nb) local_sum += hist[first + i];
  }
  run_sums[t] = local_sum;
  barrier();
  if (t == 0u) {
    uint below = 0u;
    uint run = 256u;
    for (uint i = 0u; i < 256u; ++i) {
      if (below + run_sums[i] > k) {
        run = i;
        break;
      }
      below += run_sums[i];
    }
    found_run = run;
    found_below = below;
  }
  barrier();
  const bool last_bucket = found_run == 256u && t == 255u;  // the scan ran off the end
  if (t == found_run || last_bucket) {
    uint below = found_below;
    uint selected = nb - 1u;
    if (!last_bucket) {
      for (uint i = 0u; i < per; ++i) {
        uint c = hist[first + i];
        if (below + c > k) {
          selected = first + i;
          break;
        }
        below += c;
      }
    }
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
  barrier();
  for (uint i = 0u; i < per; ++i) {
    if (first + i < nb) hist[first + i] = 0u;
  }
}
