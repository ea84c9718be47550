#version 450
// Model render, fragment stage: colour, linear metric depth and camera-frame face normals.
#extension GL_GOOGLE_include_directive : require
#include "render_layout.h"
#include "octahedral.glsl"

// Textures per descriptor set (engine/src/textures.hpp): the bound set holds this draw's
// texture at slot pc.texture, a dynamically uniform index.
layout(constant_id = 0) const int kTextureCount = 1;
layout(constant_id = 1) const bool kWriteNormals = true;

layout(push_constant) uniform Push { ModelPush pc; };
layout(set = 0, binding = 0) uniform sampler2D textures[kTextureCount];

layout(location = 0) in vec2 in_uv;
layout(location = 1) in vec4 in_color;

layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_depth;   // camera z, metres
// Octahedral camera-frame normal facing the camera, packSnorm2x16; bit 0 (the x half's least
// significant bit, 3e-5 of its range) holds 1 on back faces (RenderOutput::back_faces).
layout(location = 2) out uint out_normal;

void main() {
  vec4 c = pc.base_color * in_color;
  if ((pc.flags & VKLOC_FLAG_TEXTURED) != 0u) {
    // Trilinear: the sampler has mipmapMode LINEAR and every level of the texture.
    c *= texture(textures[pc.texture], in_uv);
  }
  out_color = vec4(c.rgb, 1.0);
  // gl_FragCoord.w = 1 / w_clip = 1 / z_camera: exact perspective-correct metric depth.
  float z = 1.0 / gl_FragCoord.w;
  out_depth = z;
  if (kWriteNormals) {
    // Camera-frame point of this pixel: pinhole back-projection (seed 000 eq. 3) with the
    // pixel-centre convention u = x_fb - 0.5. Its screen derivatives span the triangle plane.
    vec2 uv_px = gl_FragCoord.xy - 0.5;
    vec3 p = vec3((uv_px - pc.intrinsics.zw) / pc.intrinsics.xy * z, z);
    vec3 n = normalize(cross(dFdx(p), dFdy(p)));
    if (dot(n, p) > 0.0) n = -n;
    // gl_FrontFacing follows the pipeline's VK_FRONT_FACE_COUNTER_CLOCKWISE, the CPU reference's
    // plane-sign test (cpu_renderer.cpp, "Winding and back faces").
    out_normal = (packSnorm2x16(octEncode(n)) & ~1u) | (gl_FrontFacing ? 0u : 1u);
  }
}
