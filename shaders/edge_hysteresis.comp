#version 450
// Hysteresis pass over the weak candidates (grid-stride): a weak pixel with an 8-connected edge
// neighbour becomes an edge, and the invocation then follows the chain of weak pixels from it
// (one neighbour at a time, claimed with an atomic compare-and-swap 1 -> 2). Promotions are
// counted in changes[step]; the host repeats passes until one promotes nothing, which is the
// fixed point of the CPU's 8-connected growth; passes after one that promoted nothing return
// at once. Candidates are interior pixels, so every
// neighbour is inside the image.
#extension GL_GOOGLE_include_directive : require
#include "edge_layout.h"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(set = 0, binding = EDGE_BINDING_STATE, r32ui) coherent uniform uimage2D state;
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl ctl; };
layout(std430, set = 0, binding = EDGE_BINDING_CANDIDATES) readonly buffer Candidates { uint candidates[]; };

const ivec2 kOffsets[8] =
    ivec2[8](ivec2(-1, -1), ivec2(0, -1), ivec2(1, -1), ivec2(-1, 0), ivec2(1, 0), ivec2(-1, 1), ivec2(0, 1), ivec2(1, 1));

void main() {
  // A pass after one that promoted nothing has nothing to do (the fixed point is reached).
  if (pc.step > 0 && ctl.changes[pc.step - 1] == 0u) return;
  uint count = ctl.candidate_count;
  uint stride = 64u * pc.group_count;
  uint promoted = 0u;
  for (uint i = gl_GlobalInvocationID.x; i < count; i += stride) {
    uint c = candidates[i];
    ivec2 p = ivec2(c & 0xffffu, c >> 16);
    if (imageLoad(state, p).x != 1u) continue;
    bool strong_neighbour = false;
    for (int k = 0; k < 8; ++k) strong_neighbour = strong_neighbour || imageLoad(state, p + kOffsets[k]).x == 2u;
    if (!strong_neighbour || imageAtomicCompSwap(state, p, 1u, 2u) != 1u) continue;
    ++promoted;
    for (int walk = 0; walk < 4096; ++walk) {
      bool moved = false;
      for (int k = 0; k < 8 && !moved; ++k) {
        ivec2 q = p + kOffsets[k];
        if (imageLoad(state, q).x == 1u && imageAtomicCompSwap(state, q, 1u, 2u) == 1u) {
          p = q;
          moved = true;
        }
      }
      if (!moved) break;
      ++promoted;
    }
  }
  if (promoted != 0u) atomicAdd(ctl.changes[pc.step], promoted);
}
