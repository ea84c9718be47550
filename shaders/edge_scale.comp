#version 450
// t-distribution scale of the residuals (estimateTDistributionScale, host/src/edge_tracker.cpp):
// over the valid residuals (r >= 0), var = max(mean(r^2), min^2), then `iterations` times
// var = max(mean(r^2 (nu + 1) / (nu + r^2 / var)), min^2); writes sqrt(var) (pixels) to
// CONTROL.sigma_px, or min when no residual is valid. One workgroup, grid-stride loops.
// Push: point_count, step = iterations, robust.y = nu, robust.z = min (pixels).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#include "edge_layout.h"

layout(local_size_x = 64) in;
layout(push_constant) uniform Push { EdgePush pc; };
layout(std430, set = 0, binding = EDGE_BINDING_RESIDUALS) readonly buffer Residuals { float residuals[]; };
layout(std430, set = 0, binding = EDGE_BINDING_CONTROL) buffer Control { EdgeControl control; };

shared vec2 subgroup_totals[64];

// (sum, count) over the workgroup; every invocation gets the total.
vec2 workgroupTotal(vec2 v) {
  v = subgroupAdd(v);
  if (subgroupElect()) subgroup_totals[gl_SubgroupID] = v;
  barrier();
  vec2 total = vec2(0.0);
  for (uint s = 0u; s < gl_NumSubgroups; ++s) total += subgroup_totals[s];
  barrier();
  return total;
}

void main() {
  const float nu = pc.robust.y;
  const float min_sigma = pc.robust.z;
  const float min_var = min_sigma * min_sigma;
  vec2 acc = vec2(0.0);
  for (uint i = gl_LocalInvocationIndex; i < pc.point_count; i += 64u) {
    float r = residuals[i];
    if (r >= 0.0) acc += vec2(r * r, 1.0);
  }
  const vec2 first = workgroupTotal(acc);
  float var = first.y > 0.0 ? max(first.x / first.y, min_var) : min_var;
  for (int it = 0; it < pc.step && first.y > 0.0; ++it) {
    float a = 0.0;
    for (uint i = gl_LocalInvocationIndex; i < pc.point_count; i += 64u) {
      float r = residuals[i];
      if (r >= 0.0) a += r * r * (nu + 1.0) / (nu + r * r / var);
    }
    var = max(workgroupTotal(vec2(a, 0.0)).x / first.y, min_var);
  }
  if (gl_LocalInvocationIndex == 0u) control.sigma_px = sqrt(var);
}
