// vkloc: the live image prepared for edge alignment (seed paper 000, sec. IV-C, eqs. 12-15):
// gray -> pyramid -> per level: edges -> truncated distance field (+ gradient, sub-pixel edge
// lines). Every stage takes and returns plain images (rows top to bottom, no padding), so a GPU
// backend (engine/, GpuEdgeStages) can replace any stage with a kernel on the same layouts.
#pragma once

#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/track/edge_detector.hpp"

namespace vkloc {

// --- live image: pyramid and distance fields ------------------------------------------------

/// Intrinsics of pyramid level `level` (0 = full resolution) made by the 2x downsampling of
/// downsampleHalf: size (w + 1) / 2 per level, fx' = fx / 2, cx' = (cx + 0.5) / 2 - 0.5 (the
/// output pixel i covers input pixels 2i and 2i + 1, its centre lies at input u = 2i + 0.5).
PinholeCamera pyramidCamera(const PinholeCamera& camera, int level);

/// Halves a single-channel float image: separable binomial low-pass [1 3 3 1] / 8 on input
/// pixels 2i - 1 .. 2i + 2 (borders replicated), output size ((w + 1) / 2, (h + 1) / 2).
ImageF32 downsampleHalf(const ImageF32& image);

/// Converts an 8-bit gray image to float (same values 0..255).
ImageF32 toFloat(const ImageU8& gray);

/// Euclidean distance field of an edge map with its gradient (the V and G_u, G_v of eqs. 12-15).
struct DistanceField {
  /// 1 channel, pixels: exact Euclidean distance from each pixel centre to the nearest edge
  /// pixel centre (the values of OpenCV DIST_L2 with DIST_MASK_PRECISE), clamped to truncation_px.
  ImageF32 distance;
  /// 2 channels (G_u, G_v), pixels per pixel: central differences (d(i+1) - d(i-1)) / 2 of
  /// `distance` along u and v; one-sided differences on the image border; (0, 0) where the
  /// distance or a neighbour used is truncated (no direction to an edge is known there).
  /// Empty when not built (LiveFrameOptions::distance_gradient).
  ImageF32 gradient;
  float truncation_px = 0;  ///< Distances >= this are "far from any edge" (outliers).
};

/// The gradient of a distance field from its distances: field.gradient (resized when needed)
/// from field.distance and field.truncation_px, by the rule of DistanceField::gradient.
void computeDistanceGradient(DistanceField& field);

/// DistanceField::gradient at pixel (x, y), computed from the distances by the rule of
/// computeDistanceGradient (the same floats). Precondition: (x, y) inside the field.
void distanceGradientAt(const DistanceField& field, int x, int y, float& g_u, float& g_v);

/// Distance field of an edge map (non-zero = edge). With no edge at all every distance is
/// truncation_px. kInvalidArgument for an empty or multi-channel map or truncation_px <= 0.
Result<DistanceField> computeDistanceField(const ImageU8& edges, float truncation_px);

/// Options of the live-image stages.
struct LiveFrameOptions {
  int levels = 3;                 ///< Pyramid levels (1..8); level k has size / 2^k.
  float truncation_px = 20.0f;    ///< Distance truncation at every level, in that level's pixels.
  EdgeDetectorOptions detector;   ///< Edge detector used at every level.
  bool keep_intermediate = true;  ///< Keep gray and edge images per level (for display/tests).
  bool subpixel_edges = true;     ///< Also build LiveLevel::edge_lines (sub-pixel edge lines).
  /// Build DistanceField::gradient. false leaves it empty: the tracker (evaluateEdgePoint)
  /// then computes the gradient at the pixels it reads from the distances, by the same rule
  /// (distanceGradientAt), and the results are the same.
  bool distance_gradient = true;
};

/// Radius (pixels of a level) around live edge pixels within which LiveLevel::edge_lines is
/// filled; beyond it only the distance field is used.
constexpr float kEdgeLineRadiusPx = 2.0f;

/// One pyramid level of a live frame.
struct LiveLevel {
  PinholeCamera camera;  ///< Intrinsics of this level (pyramidCamera).
  ImageF32 gray;         ///< Low-passed gray image (empty unless keep_intermediate).
  ImageU8 edges;         ///< Edge map, 255 = edge (empty unless keep_intermediate).
  DistanceField field;   ///< Distance to the nearest edge and its gradient.
  /// Sub-pixel edge lines near the edges, 3 channels (s, n_u, n_v) per pixel, or empty (not
  /// built, e.g. a frame read back from a GPU backend): n is the unit intensity-gradient normal
  /// of the nearest live edge pixel within kEdgeLineRadiusPx (distance to its sub-pixel edge
  /// point e, the parabola vertex of the gradient magnitude across the edge) and
  /// s = n . ((u, v) - e) the signed distance (pixels) from the pixel centre to the straight edge
  /// line through e. (0, 0, 0) where no edge pixel is that near.
  ImageF32 edge_lines;
};

/// The live image prepared for tracking: distance fields per level, finest (0) first.
struct LiveFrame {
  std::vector<LiveLevel> levels;
};

/// Builds the pyramid, edges and distance fields of a gray live image taken with `camera`
/// (pixels 0..255). kInvalidArgument when the image size differs from the camera's, the image
/// is empty or multi-channel, or an option is out of range; a level smaller than 8x8 pixels is
/// not built (fewer levels are returned).
Result<LiveFrame> buildLiveFrame(const ImageU8& gray, const PinholeCamera& camera,
                                 const LiveFrameOptions& options = {});

/// buildLiveFrame into an existing frame, reusing its images' memory (and per-thread working
/// buffers), so that a stream of frames of one size allocates nothing once warm. Same results
/// and errors; on error `frame` is left in an unspecified but valid state.
Status buildLiveFrame(const ImageU8& gray, const PinholeCamera& camera, const LiveFrameOptions& options,
                      LiveFrame& frame);

}  // namespace vkloc
