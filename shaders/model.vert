#version 450
// Model render, vertex stage: positions relative to the model origin, projected with the
// pinhole clip transform (reverse-Z).
#extension GL_GOOGLE_include_directive : require
#include "render_layout.h"

layout(push_constant) uniform Push { ModelPush pc; };

layout(location = 0) in vec3 in_position;  // metres, relative to the model origin
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec4 in_color;     // unorm8x4

layout(location = 0) out vec2 out_uv;
layout(location = 1) out vec4 out_color;

void main() {
  gl_Position = pc.clip_from_origin * vec4(in_position, 1.0);
  out_uv = in_uv;
  out_color = in_color;
}
