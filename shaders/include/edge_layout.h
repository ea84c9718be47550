// Layouts of the edge-stage compute shaders (engine/src/edge_stages.cpp), shared by C++ and GLSL.
// Sizes and offsets are checked by static_asserts in engine/src/edge_stages.cpp.
#ifndef VKLOC_EDGE_LAYOUT_H
#define VKLOC_EDGE_LAYOUT_H

#ifdef __cplusplus
#include <cstdint>
#define VKLOC_VEC4(name) float name[4]
#define VKLOC_FLOAT(name) float name
#define VKLOC_INT(name) int32_t name
#define VKLOC_UINT(name) uint32_t name
namespace vkloc::engine {
#else
#define VKLOC_VEC4(name) vec4 name
#define VKLOC_FLOAT(name) float name
#define VKLOC_INT(name) int name
#define VKLOC_UINT(name) uint name
#endif

// Descriptor bindings of set 0 (one set per pyramid level; every edge shader uses this layout).
#define EDGE_BINDING_INPUT8 0     // SSBO: 8-bit gray input, 4 pixels per uint, row-major
#define EDGE_BINDING_GRAY_PREV 1  // r32f: gray of the next finer level (pyramid input)
#define EDGE_BINDING_GRAY 2       // r32f: gray of this level, 0..255
#define EDGE_BINDING_MAG 3        // r32f: Sobel/8 gradient magnitude
#define EDGE_BINDING_GRAD 4       // rg32f: Sobel/8 gradient (gx, gy)
#define EDGE_BINDING_STATE 5      // r32ui: 0 none, 1 weak candidate, 2 edge
#define EDGE_BINDING_SEED_A 6     // r32ui: JFA seeds x | y << 16 (~0u none), or edt_columns' g^2
#define EDGE_BINDING_SEED_B 7     // r32ui: ping-pong partner of SEED_A
#define EDGE_BINDING_DISTANCE 8   // r32f: truncated distance to the nearest edge, pixels
#define EDGE_BINDING_HIST 9       // SSBO: uint[EDGE_HIST_BINS] radix-select histogram
#define EDGE_BINDING_CONTROL 10   // SSBO: EdgeControl
// CANDIDATES holds the weak candidates (NMS -> hysteresis), then the near-edge row spans
// (edt_rows -> edge_lines).
#define EDGE_BINDING_CANDIDATES 11  // SSBO: uint[] pixels or spans, x | y << 16
#define EDGE_BINDING_POINTS 12      // SSBO: EdgePoint[] (vec4: x, y, z metres, kind bits)
#define EDGE_BINDING_RESIDUALS 13   // SSBO: float[] residual per point (pixels), -1 = invalid
#define EDGE_BINDING_PARTIALS 14    // SSBO: vec4[group * 8 + k] per-workgroup normal equations
#define EDGE_BINDING_LINES 15       // rgba32f: sub-pixel edge line (s, n_u, n_v, 0), LiveLevel::edge_lines
#define EDGE_BINDING_EPOINTS 16     // rg32f: sub-pixel edge point (e_u, e_v) of an NMS-kept pixel
#define EDGE_BINDING_COUNT 17

#define EDGE_HIST_BINS 2048u
#define EDGE_MAX_HYSTERESIS_PASSES 64
#define EDGE_NO_SEED 0xffffffffu
#define EDGE_EDT_MAX_RADIUS 64   // edt_rows.comp: R = ceil(truncation) - 1 <= this
#define EDGE_LINE_RADIUS_PX 2.0  // kEdgeLineRadiusPx of edges.hpp, pixels of a level
// A pixel at least this far from every edge pixel (pixels of a level) has no edge point within
// EDGE_LINE_RADIUS_PX (an edge point lies within sqrt(2) / 2 of its pixel), so its edge line is
// (0, 0, 0). On the listed path (edt_rows.comp -> edge_lines.comp) LINES is written only at
// pixels nearer than this and holds stale values elsewhere: readers mask it with DISTANCE.
#define EDGE_LINE_NEAR_PX 2.7072
#define EDGE_LINE_SPAN 8      // pixels per near-edge span of edt_rows.comp's list
#define EDGE_LINES_LISTED 2u  // EdgePush::flags bit of edge_lines.comp: listed spans only
#define EDGE_REDUCE_VEC4S 8   // 29 values of the normal equations in 8 vec4s (3 unused)

// Push constants shared by all edge shaders (fields unused by a shader are ignored). 128 bytes.
struct EdgePush {
  VKLOC_INT(width);                // Size of this level, pixels.
  VKLOC_INT(height);               // Pixels.
  VKLOC_INT(step);                 // JFA step (pixels); histogram / select pass; hysteresis pass slot.
  VKLOC_UINT(flags);               // JFA / distance: 1 = read SEED_B (write SEED_A), 0 = the reverse;
                                   // edge lines: bit 0 = build them (else write zeros), bit 1 = only
                                   // the spans listed by edt_rows (EDGE_LINES_LISTED).
  VKLOC_FLOAT(high_factor);        // EdgeDetectorOptions::high_factor.
  VKLOC_FLOAT(min_high_gradient);  // EdgeDetectorOptions::min_high_gradient, gray levels per pixel.
  VKLOC_FLOAT(low_ratio);          // EdgeDetectorOptions::low_ratio.
  VKLOC_FLOAT(truncation_px);      // Distance truncation, pixels of this level.
  VKLOC_UINT(rank);                // Rank of the contrast quantile among the magnitude samples.
  VKLOC_UINT(point_count);         // Number of reference points.
  VKLOC_UINT(group_count);         // Workgroups of a grid-stride dispatch.
  VKLOC_UINT(pad0);                // edge_hist: rank of the noise quantile among the magnitude samples.
  VKLOC_VEC4(pose_row0);           // T_camera_ref as rows [R | t], t in metres.
  VKLOC_VEC4(pose_row1);
  VKLOC_VEC4(pose_row2);
  VKLOC_VEC4(intrinsics);  // fx, fy, cx, cy of this level, pixels.
  VKLOC_VEC4(robust);      // sigma (pixels), nu, minimum sigma (pixels), 1 = sigma from CONTROL.sigma_px;
                           // edge_hist: x = noise floor per unit of the noise quantile.
};

// Per-level control block written by the shaders.
struct EdgeControl {
  VKLOC_UINT(prefix);           // Radix select: magnitude bits selected so far.
  VKLOC_UINT(remaining);        // Radix select: rank left within the selected bucket.
  VKLOC_FLOAT(contrast);        // Selected quantile s of the magnitude.
  VKLOC_FLOAT(high);            // High threshold.
  VKLOC_FLOAT(low);             // Low threshold.
  VKLOC_UINT(candidate_count);  // Weak candidates appended by NMS.
  VKLOC_FLOAT(sigma_px);        // t-distribution scale of the last residuals (edge_scale.comp), pixels.
  VKLOC_UINT(line_span_count);  // Near-edge row spans appended by edt_rows.comp (EDGE_LINE_SPAN px each).
  VKLOC_FLOAT(noise);           // Noise floor of the high threshold (edge_hist steps 0-2), gray levels per pixel.
  VKLOC_UINT(hist_done[7]);     // Radix select: workgroups finished per histogram pass (6 used).
  VKLOC_UINT(changes[EDGE_MAX_HYSTERESIS_PASSES]);  // Pixels promoted per hysteresis pass slot.
};

#ifdef __cplusplus
}  // namespace vkloc::engine
#endif
#undef VKLOC_VEC4
#undef VKLOC_FLOAT
#undef VKLOC_INT
#undef VKLOC_UINT
#endif
