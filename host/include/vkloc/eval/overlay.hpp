// vkloc: edge overlays, an independent look at what the tracker did with a frame. The model is
// rendered at the estimated pose, its edge points are taken as a keyframe's are (finest level),
// projected into the live image and classified against the live image's own edges: an inlier
// lies within the tracker's inlier threshold of a live edge (bilinear distance field, as the
// tracker reads it), an outlier farther or where the distance is truncated. Where ground truth
// is known, the same 3D points are also drawn at the true pose.
//
// Images: the live gray image dimmed, as 8-bit RGB; estimated-pose points green (inlier) or red
// (outlier) as small crosses, true-pose points cyan single pixels underneath; an optional caption
// band at the top in a built-in 5x7 pixel font.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/live_frame.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// How an overlay is made. The Localizer's options give the values that match the tracker:
/// reference = LocalizerOptions::reference, live = LocalizerOptions::live, render =
/// LocalizerOptions::render, inlier_threshold_px = LocalizerOptions::tracker.inlier_threshold_px.
struct EdgeOverlayOptions {
  ReferenceEdgeOptions reference;    ///< Edge points of the render (only level 0 is built).
  LiveFrameOptions live;             ///< Live edges and distance field (only level 0 is built).
  RenderSettings render;             ///< Clip planes and culling of the render at the estimate.
  double inlier_threshold_px = 1.5;  ///< Inlier: distance to the nearest live edge <= this, pixels.
  double dim = 0.5;                  ///< Brightness factor of the live image underneath (0..1).
  bool draw_truth = true;            ///< Draw the points at the true pose when one is given.
};

/// Checks ranges (threshold > 0 and finite, dim in 0..1, the reference and live options);
/// kInvalidArgument naming the field otherwise.
Status validateEdgeOverlayOptions(const EdgeOverlayOptions& options);

/// How well a set of model edge points at one pose agrees with the live edges.
struct EdgeAgreement {
  int points = 0;             ///< Model edge points (all of level 0).
  int in_image = 0;           ///< Of these, in front of the camera and inside the image.
  int inliers = 0;            ///< Of these, within the inlier threshold of a live edge.
  double inlier_ratio = 0;    ///< inliers / in_image (0 when none is in the image).
  double mean_inlier_px = 0;  ///< Mean distance of the inliers to the live edges, pixels.
  double median_distance_px =
      0;  ///< Median distance of the points in the image (truncated ones count as the truncation), pixels.
};

/// One model edge point seen from a pose.
struct ProjectedEdgePoint {
  float u = 0;            ///< Image column, pixels (pixel centres at integers).
  float v = 0;            ///< Image row, pixels.
  float distance_px = 0;  ///< Distance to the nearest live edge (the truncation when farther), pixels.
  bool inlier = false;    ///< distance_px <= the inlier threshold (and not truncated).
};

/// Projects world-frame points with `camera` at T_world_camera and classifies those in front of
/// the camera and inside the image against `level` (level 0 of a LiveFrame, same camera);
/// points behind or outside are left out of `projected` and of in_image. `projected` may be null.
EdgeAgreement classifyEdgePoints(const std::vector<Eigen::Vector3d>& points_world, const PinholeCamera& camera,
                                 const Pose& T_world_camera, const LiveLevel& level, double inlier_threshold_px,
                                 std::vector<ProjectedEdgePoint>* projected);

/// The model's edge points seen from T_world_camera (level 0 of buildEdgeReference on a render
/// made by `renderer`), in the world frame, metres. Errors of the render and of the extraction.
Result<std::vector<Eigen::Vector3d>> modelEdgePointsWorld(Renderer& renderer, const PinholeCamera& camera,
                                                          const Pose& T_world_camera,
                                                          const EdgeOverlayOptions& options);

/// An overlay image and its figures.
struct EdgeOverlay {
  ImageU8 image;                       ///< RGB (3 channels), camera size.
  EdgeAgreement estimate;              ///< The points at the estimated pose.
  std::optional<EdgeAgreement> truth;  ///< The same points at the true pose (when given).
};

/// Makes the overlay of one live gray frame (camera size, 1 channel): renders the model with
/// `renderer` at T_world_estimate, extracts its edge points, builds the live distance field and
/// classifies and draws the points (at T_world_truth too when given and options.draw_truth).
/// No caption is drawn (drawOverlayCaption). kInvalidArgument for a gray image of another size
/// or channel count, an invalid pose or options; the renderer's errors as they come.
Result<EdgeOverlay> makeEdgeOverlay(Renderer& renderer, const ImageU8& gray, const PinholeCamera& camera,
                                    const Pose& T_world_estimate, const std::optional<Pose>& T_world_truth,
                                    const EdgeOverlayOptions& options);

/// RGB colour of overlay drawing.
using OverlayRgb = std::array<uint8_t, 3>;

/// Height in pixels of `lines` text lines at `scale` as drawOverlayCaption lays them out.
int overlayCaptionHeight(int lines, int scale);

/// Draws `text` with the built-in 5x7 font (6 x 8 pixels per character at scale 1) with its top
/// left corner at (x, y) into an RGB or gray image, clipped at the borders. Letters are drawn
/// as capitals; characters the font lacks are drawn as '?'.
void drawOverlayText(ImageU8& image, int x, int y, std::string_view text, const OverlayRgb& colour, int scale = 1);

/// Darkens a band at the top of an RGB image and writes `lines` in it (white), at scale 2 when
/// the longest line fits the width, else 1.
void drawOverlayCaption(ImageU8& image, const std::vector<std::string>& lines);

}  // namespace vkloc
