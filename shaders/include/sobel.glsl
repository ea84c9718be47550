// Sobel / 8 (gray levels per pixel) of the 3x3 window
//   a b c
//   d . f
//   h i k
// and its magnitude, evaluated without contraction so that every shader computing them
// (edge_sobel.comp, and on CPU drivers edge_nms.comp and edge_lines.comp, which recompute
// them from GRAY) gets the same floats.
#ifndef VKLOC_SOBEL_GLSL
#define VKLOC_SOBEL_GLSL

vec2 sobel8(float a, float b, float c, float d, float f, float h, float i, float k) {
  precise float gx = ((c - a) + 2.0 * (f - d) + (k - h)) * 0.125;
  precise float gy = ((h - a) + 2.0 * (i - b) + (k - c)) * 0.125;
  return vec2(gx, gy);
}

float sobelMagnitude(vec2 g) {
  precise float m = sqrt(g.x * g.x + g.y * g.y);
  return m;
}

#endif
