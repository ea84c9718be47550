// vkloc: 3D edge points of a rendered reference view (a keyframe; seed paper 000, sec. IV-C, eq.
// 3): render (gray, depth, normals) -> per-pixel edge flags -> back-projected points ->
// spatially even budget, per pyramid level as the live frame's.
#pragma once

#include <cstdint>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/edge_detector.hpp"
#include "vkloc/track/live_frame.hpp"

namespace vkloc {

// --- reference view: 3D edge points ---------------------------------------------------------

/// Per-pixel flags of the reference edge map (stage 1 output, one byte per pixel). Geometric
/// edges lie between a pixel and a 4-neighbour; the flag sits on the flagged pixel and names the
/// side where the neighbour is.
enum EdgePixelFlags : uint8_t {
  kEdgePixelTexture = 1u << 0,         ///< Intensity edge of the rendered gray image.
  kEdgePixelOcclusionRight = 1u << 1,  ///< Near side of a depth jump to the right neighbour.
  kEdgePixelOcclusionLeft = 1u << 2,   ///< Near side of a depth jump to the left neighbour.
  kEdgePixelOcclusionDown = 1u << 3,   ///< Near side of a depth jump to the neighbour below.
  kEdgePixelOcclusionUp = 1u << 4,     ///< Near side of a depth jump to the neighbour above.
  kEdgePixelCreaseRight = 1u << 5,     ///< Normal discontinuity to the right neighbour.
  kEdgePixelCreaseDown = 1u << 6,      ///< Normal discontinuity to the neighbour below.
};

/// What an edge point was made from.
enum EdgeKind : uint32_t {
  kEdgeTexture = 1u << 0,    ///< Intensity edge in the rendered gray image.
  kEdgeOcclusion = 1u << 1,  ///< Depth discontinuity (silhouette, occluding edge), near surface.
  kEdgeCrease = 1u << 2,     ///< Normal discontinuity.
  /// Modifier bit ORed onto one of the kinds above: the point's pixel lies within 2 pixels of
  /// background (no surface) in the render: a silhouette against the sky or the rim of a hole
  /// through a damaged model (which live images do not show).
  kEdgeBackground = 1u << 3,
  /// Modifier bit: the point's pixel lies within 2 pixels of a back face in the render
  /// (RenderOutput::back_faces): the inside of a closed model seen through a hole in it and that
  /// hole's rim, which live images do not show (or, in a model with inconsistent winding, a true
  /// surface; KeyframeManagerOptions::adapt_edge_kinds learns which).
  kEdgeBackFace = 1u << 4,
};

/// The kind an EdgePoint::kind counts as (TrackQuality::kind_inlier_ratio's index): 0 texture,
/// 1 occlusion, 2 crease, 3 near background, 4 near a back face (either modifier decides whatever
/// the base kind; back face first); -1 for no known kind.
inline int edgeKindIndex(uint32_t kind) {
  if (kind & kEdgeBackFace) return 4;
  if (kind & kEdgeBackground) return 3;
  return kind == kEdgeOcclusion ? 1 : kind == kEdgeCrease ? 2 : kind == kEdgeTexture ? 0 : -1;
}

/// A 3D edge point in the reference camera frame; 16 bytes, the std430 layout of a vec4.
struct EdgePoint {
  float x = 0;        ///< Reference camera frame, metres (x right).
  float y = 0;        ///< Metres (y down).
  float z = 0;        ///< Metres (z forward, > 0).
  uint32_t kind = 0;  ///< EdgeKind of the point.
};
static_assert(sizeof(EdgePoint) == 16, "EdgePoint must match a GLSL vec4");

/// The edge detector of keyframe renders: a render has no sensor noise, so no noise floor;
/// instead an absolute floor on the high threshold (13 gray levels per pixel, Sobel / 8: a step
/// of 26 gray levels) keeps the faint shading of nearly plain textures (painted walls, plaster,
/// wood grain) out of the keyframe: a camera image, under its own light, tone curve, blur and
/// noise, does not show it reliably, and a keyframe point with no edge under it in the image
/// pulls the alignment towards whatever edge lies nearest (README, "Tracker defaults").
EdgeDetectorOptions keyframeDetector();

/// How reference edges are taken from a rendered view.
struct ReferenceEdgeOptions {
  bool texture_edges = true;       ///< Use intensity edges of the rendered gray image.
  bool occlusion_edges = true;     ///< Use depth discontinuities.
  bool crease_edges = true;        ///< Use normal discontinuities.
  double depth_jump_ratio = 0.05;  ///< Depth discontinuity: |z_a - z_b| > ratio * min(z_a, z_b).
  double crease_angle_deg = 30.0;  ///< Crease: angle between neighbouring normals above this, degrees.
  /// Model holes: an occlusion edge whose near surface resumes (inverse depth extrapolated along
  /// the image line, within depth_jump_ratio) at most this many pixels beyond the far side is
  /// the rim of a hole in the model (not visible in live images); it and the texture edges
  /// within one pixel of it are dropped. 0 = keep every occlusion edge.
  int hole_gap_px = 24;
  EdgeDetectorOptions detector = keyframeDetector();  ///< Texture edge detector (keyframeDetector).
  int cell_px = 16;                                   ///< Subsampling grid cell side, pixels.
  int max_points_per_cell = 6;                        ///< At most this many points per cell.
  int max_points = 4000;                              ///< Total budget of points per level (> 0).
  int levels = 3;  ///< Pyramid levels of buildEdgeReference (1..8), as the live frame's.
  /// Run the per-level tasks of buildEdgeReference on OpenCV's thread pool; false runs them on
  /// the calling thread (a background keyframe worker, which must leave the pool to the
  /// tracking thread). The points are the same either way.
  bool parallel = true;
};

/// Checks ranges of ReferenceEdgeOptions; kInvalidArgument naming the field otherwise.
Status validateReferenceEdgeOptions(const ReferenceEdgeOptions& options);

/// Stage 1: per-pixel EdgePixelFlags of a rendered view (0 = no edge), same size as the view.
/// Geometric edges are found between 4-neighbours p and q: a depth discontinuity (or surface
/// next to background) sets the occlusion flag pointing at q on the NEAR pixel p; a crease (both
/// surfaces, no depth jump, normals more than crease_angle_deg apart) sets the crease flag on
/// the left/upper pixel of the pair.
/// Texture edges (detectEdges on the rendered gray, the live images' detector) take precedence:
/// geometric flags within one pixel of a texture edge pixel are dropped, so a geometric edge
/// that is visible in the gray image is placed exactly where the live detector places it, and
/// geometric points remain where the render shows no intensity edge (untextured or unshaded
/// models). Texture edges on background are kept only next to a geometric edge. The view needs
/// gray and depth; normals are needed for creases (skipped when absent). kInvalidArgument when
/// sizes disagree or gray/depth are missing.
Result<ImageU8> detectReferenceEdges(const RenderOutput& view, const ReferenceEdgeOptions& options = {});

/// Stage 2: back-projects flagged pixels into the reference camera frame (eq. 3,
/// P = z ((u - cx) / fx, (v - cy) / fy, 1)) and compacts them in row-major order. A texture
/// edge is placed at its pixel centre with the depth of the near surface: its own depth, or the
/// smallest depth among its 8-neighbours across a depth jump (an edge pixel on the far side of a
/// silhouette belongs to the occluding surface). A geometric edge is placed on the
/// boundary between the pixel pair, half a pixel from the flagged pixel towards its
/// neighbour, with the depth of the near surface (occlusion: the near pixel's depth, linearly
/// extrapolated by half a pixel from the near side when that side is continuous; crease: the
/// mean of the two depths). Pixels without depth are skipped. Points within 2 pixels of
/// background get kEdgeBackground; kEdgeBackFace needs the render's back-face mask, which only
/// buildEdgeReference has.
/// One point is made per flag bit. `options` gives depth_jump_ratio (continuity test).
std::vector<EdgePoint> backProjectEdges(const ImageU8& flags, const ImageF32& depth, const PinholeCamera& camera,
                                        const ReferenceEdgeOptions& options = {});

/// Stage 3: spatially even subsample. Points are bucketed by the pixel they project to in
/// `camera` into cells of cell_px; every cell keeps at most k points, k = the largest value
/// <= max_points_per_cell with a total <= max_points (evenly spaced in the cell's list order);
/// if even k = 1 exceeds the budget, evenly spaced cells are kept. Deterministic; the order of
/// the input is preserved.
std::vector<EdgePoint> subsampleEdgePoints(const std::vector<EdgePoint>& points, const PinholeCamera& camera,
                                           const ReferenceEdgeOptions& options = {});

/// A reference for tracking: 3D edge points of a view rendered from T_world_ref, extracted per
/// pyramid level so that each level's points are the edges the live pyramid shows there.
struct EdgeReference {
  PinholeCamera camera;                 ///< Camera the reference was rendered with (level 0).
  Pose T_world_ref = Pose::Identity();  ///< Pose of the reference (virtual) camera.
  /// Edge points found at full resolution (pyramid level 0), reference camera frame, metres.
  std::vector<EdgePoint> points;
  /// coarse_points[k - 1]: edge points found at pyramid level k >= 1 (same frame and units).
  std::vector<std::vector<EdgePoint>> coarse_points;
};

/// Points of pyramid level `level` (level 0: points; coarser: coarse_points, the coarsest
/// available for levels beyond it).
inline const std::vector<EdgePoint>& edgePointsForLevel(const EdgeReference& reference, int level) {
  if (level <= 0 || reference.coarse_points.empty()) return reference.points;
  const size_t k = static_cast<size_t>(level) - 1;
  return reference.coarse_points[k < reference.coarse_points.size() ? k : reference.coarse_points.size() - 1];
}

/// Runs stages 1-3 on a view rendered with `camera` at T_world_ref at `options.levels` pyramid
/// levels: level k's gray image is downsampled exactly as the live pyramid (downsampleHalf), its
/// depth, normals and back-face flag are those of the nearest surface in each 2x2 block, and its
/// points are back-projected with pyramidCamera(camera, k) (levels below 8x8 pixels are not
/// built). Points near a back face get kEdgeBackFace when the view has back_faces.
/// kInvalidArgument on bad options, sizes that differ from the camera's or an invalid pose.
Result<EdgeReference> buildEdgeReference(const RenderOutput& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options = {});
/// The same, taking the view's depth and normals over instead of copying them (~5 MB at
/// 640x480).
Result<EdgeReference> buildEdgeReference(RenderOutput&& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options = {});

}  // namespace vkloc
