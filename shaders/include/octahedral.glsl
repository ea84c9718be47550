// Octahedral encoding of unit vectors into two values in [-1, 1] (decoder in engine/src).
#ifndef VKLOC_OCTAHEDRAL_GLSL
#define VKLOC_OCTAHEDRAL_GLSL
vec2 octEncode(vec3 n) {
  n /= abs(n.x) + abs(n.y) + abs(n.z);
  vec2 e = n.xy;
  if (n.z < 0.0) {
    e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
  }
  return e;
}
#endif
