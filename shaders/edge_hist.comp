#version 450
// Contrast quantile by radix select on the magnitude's float bits (non-negative floats order
// like their bit patterns): pass 0 counts bits 30..20, pass 1 bits 19..9 of the samples whose
// higher bits equal the selected prefix, pass 2 bits 8..0. Samples: every second pixel in x
// and y (as detectEdges). Shared-memory histogram per workgroup, grid-stride loop; the sample
// index advances by the stride without a division per sample (lavapipe divides lane by lane).
// The last workgroup to finish a pass (counted in hist_done[pass]) then does the select step:
// finds the bucket holding the wanted rank, appends its bits to the prefix, clears the
// histogram. Two selects run in turn, 3 passes each (pc.step 0..5): steps 0-2 select the noise
// quantile q (rank pc.pad0, skipped when the noise floor is off: ctl.noise stays 0) and store
// ctl.noise = robust.x * q (robust.x = noise_sigmas / Rayleigh factor, EdgeDetectorOptions);
// steps 3-5 select the contrast quantile s (rank pc.rank) and derive the thresholds
// high = max(high_factor * s, min_high_gradient, ctl.noise), low = low_ratio * high. One dispatch per pass
// instead of a histogram and a one-workgroup select dispatch (which leaves all but one thread
// of a CPU driver idle).
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 256) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_MAG, r32f) readonly uniform image2D mag;
layout(std430, set = 0, binding = EDGE_BINDING_HIST) coherent buffer Hist { uint hist[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) coherent buffer Control { EdgeControl ctl; };

shared uint bins[EDGE_HIST_BINS];
shared bool last_group;   // this workgroup finished the pass last
shared uint found_run;    // run holding the rank, 256 = none (rank beyond the total)
shared uint found_below;  // samples in the runs before it (all samples when none)

// Select step over the finished histogram (bins 0 .. 2^nbits - 1) by the 256 invocations of the
// last workgroup: each sums a run of buckets; invocation 0 finds the run holding the rank, whose
// invocation then finds the bucket (a single invocation scanning all 2048 buckets took 0.7 ms
// per frame on an H100, memory latency bound).
void selectStep(uint nbits) {
  const uint t = gl_LocalInvocationIndex;
  const uint nb = 1u << nbits;
  const uint per = (nb + 255u) / 256u;
  const uint first = t * per;
  const uint sub = uint(pc.step) % 3u;
  const uint k = sub == 0u ? (pc.step < 3 ? pc.pad0 : pc.rank) : ctl.remaining;
  uint local_sum = 0u;
  for (uint i = 0u; i < per; ++i) {
    if (first + i < nb) local_sum += hist[first + i];
  }
  bins[t] = local_sum;  // the workgroup's own bins are flushed: reused for the run sums
  barrier();
  if (t == 0u) {
    uint below = 0u;
    uint run = 256u;
    for (uint i = 0u; i < 256u; ++i) {
      if (below + bins[i] > k) {
        run = i;
        break;
      }
      below += bins[i];
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
    uint prefix = sub == 0u ? selected : ((ctl.prefix << nbits) | selected);
    ctl.prefix = prefix;
    ctl.remaining = k - below;
    if (pc.step == 2) ctl.noise = pc.robust.x * uintBitsToFloat(prefix);
    if (pc.step == 5) {
      float s = uintBitsToFloat(prefix);
      float high = max(max(pc.high_factor * s, pc.min_high_gradient), ctl.noise);
      ctl.contrast = s;
      ctl.high = high;
      ctl.low = pc.low_ratio * high;
    }
  }
  for (uint i = 0u; i < per; ++i) {
    if (first + i < nb) hist[first + i] = 0u;
  }
}

void main() {
  for (uint b = gl_LocalInvocationIndex; b < EDGE_HIST_BINS; b += 256u) bins[b] = 0u;
  barrier();
  const uint sub = uint(pc.step) % 3u;
  uint shift = sub == 0u ? 20u : (sub == 1u ? 9u : 0u);
  uint nbits = sub == 2u ? 9u : 11u;
  uint mask = (1u << nbits) - 1u;
  uint high_shift = shift + nbits;
  uint prefix = sub == 0u ? 0u : ctl.prefix;  // a new select starts from no prefix
  uint sw = uint(pc.width + 1) / 2u;
  uint sh = uint(pc.height + 1) / 2u;
  uint stride = 256u * pc.group_count;
  // Sample (x, y) of index i = y * sw + x, advanced by `stride` per iteration.
  uint x = gl_GlobalInvocationID.x % sw, y = gl_GlobalInvocationID.x / sw;
  const uint step_x = stride % sw, step_y = stride / sw;
  while (y < sh) {
    uint bits = floatBitsToUint(imageLoad(mag, ivec2(2u * x, 2u * y)).x);
    if ((bits >> high_shift) == prefix) atomicAdd(bins[(bits >> shift) & mask], 1u);
    x += step_x;
    y += step_y;
    if (x >= sw) {
      x -= sw;
      ++y;
    }
  }
  barrier();
  for (uint b = gl_LocalInvocationIndex; b <= mask; b += 256u) {
    if (bins[b] != 0u) atomicAdd(hist[b], bins[b]);
  }
  // Last workgroup out does the select step: the flushes above are made visible before the
  // count, and the last group's reads of HIST come after it.
  memoryBarrierBuffer();
  barrier();
  if (gl_LocalInvocationIndex == 0u) last_group = atomicAdd(ctl.hist_done[pc.step], 1u) == pc.group_count - 1u;
  barrier();
  if (!last_group) return;
  memoryBarrierBuffer();
  selectStep(nbits);
}
