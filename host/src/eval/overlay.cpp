// Edge overlays: model edge points at the estimated (and true) pose over the live image,
// classified against the live distance field; a 5x7 pixel font for captions.
#include "vkloc/eval/overlay.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "vkloc/track/edge_tracker.hpp"

namespace vkloc {
namespace {

constexpr OverlayRgb kInlierRgb{40, 230, 40};
constexpr OverlayRgb kOutlierRgb{255, 40, 40};
constexpr OverlayRgb kTruthRgb{0, 200, 255};

// 5x7 glyphs (the HD44780 character set): 7 rows, bit 4 = leftmost column.
struct Glyph {
  char c;
  uint8_t rows[7];
};
constexpr Glyph kGlyphs[] = {
    {' ', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}}, {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}}, {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}}, {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}}, {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}}, {'A', {0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}}, {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}}, {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}}, {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}}, {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}}, {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}}, {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}}, {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}}, {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}}, {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}}, {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}}, {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}}, {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}}, {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}}, {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}}, {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}}, {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}}, {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
};
constexpr int kGlyphAdvance = 6;  // 5 columns and a space
constexpr int kLineAdvance = 8;   // 7 rows and a space

const Glyph& glyphFor(char c) {
  const char upper = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kGlyphs) {
    if (g.c == upper) return g;
  }
  for (const Glyph& g : kGlyphs) {
    if (g.c == '?') return g;
  }
  return kGlyphs[0];
}

void putPixel(ImageU8& image, int x, int y, const OverlayRgb& rgb) {
  if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
  if (image.channels >= 3) {
    for (int c = 0; c < 3; ++c) image.at(x, y, c) = rgb[static_cast<size_t>(c)];
  } else {
    image.at(x, y) = static_cast<uint8_t>((299 * rgb[0] + 587 * rgb[1] + 114 * rgb[2]) / 1000);
  }
}

void drawCross(ImageU8& image, float u, float v, const OverlayRgb& rgb) {
  const int x = static_cast<int>(std::lround(u)), y = static_cast<int>(std::lround(v));
  putPixel(image, x, y, rgb);
  putPixel(image, x - 1, y, rgb);
  putPixel(image, x + 1, y, rgb);
  putPixel(image, x, y - 1, rgb);
  putPixel(image, x, y + 1, rgb);
}

}  // namespace

Status validateEdgeOverlayOptions(const EdgeOverlayOptions& options) {
  if (!(options.inlier_threshold_px > 0) || !std::isfinite(options.inlier_threshold_px)) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("overlay inlier_threshold_px must be > 0, got {}", options.inlier_threshold_px));
  }
  if (!(options.dim >= 0 && options.dim <= 1)) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("overlay dim must be in 0..1, got {}", options.dim));
  }
  ReferenceEdgeOptions reference = options.reference;
  reference.levels = 1;
  if (Status s = validateReferenceEdgeOptions(reference); !s.ok()) return s;
  return validateRenderSettings(options.render);
}

EdgeAgreement classifyEdgePoints(const std::vector<Eigen::Vector3d>& points_world, const PinholeCamera& camera,
                                 const Pose& T_world_camera, const LiveLevel& level, double inlier_threshold_px,
                                 std::vector<ProjectedEdgePoint>* projected) {
  EdgeAgreement a;
  a.points = static_cast<int>(points_world.size());
  if (projected != nullptr) projected->clear();
  const Pose T_camera_world = T_world_camera.inverse();
  const float truncation = level.field.truncation_px;
  std::vector<float> distances;
  double inlier_sum = 0;
  for (const Eigen::Vector3d& p_world : points_world) {
    const Eigen::Vector3d p = T_camera_world * p_world;
    if (!(p.z() > 1e-6)) continue;
    const double u = camera.fx * p.x() / p.z() + camera.cx;
    const double v = camera.fy * p.y() / p.z() + camera.cy;
    if (!(u >= 0 && v >= 0 && u <= camera.width - 1 && v <= camera.height - 1)) continue;
    ++a.in_image;
    // The tracker's own reading of the distance field (bilinear; invalid where truncated).
    EdgePoint point;
    point.x = static_cast<float>(p.x());
    point.y = static_cast<float>(p.y());
    point.z = static_cast<float>(p.z());
    const EdgePointEvaluation e = evaluateEdgePoint(point, Pose::Identity(), level, false);
    ProjectedEdgePoint q;
    q.u = static_cast<float>(u);
    q.v = static_cast<float>(v);
    q.distance_px = e.valid ? static_cast<float>(e.residual) : truncation;
    q.inlier = e.valid && e.residual <= inlier_threshold_px;
    if (q.inlier) {
      ++a.inliers;
      inlier_sum += e.residual;
    }
    distances.push_back(q.distance_px);
    if (projected != nullptr) projected->push_back(q);
  }
  if (a.in_image > 0) a.inlier_ratio = static_cast<double>(a.inliers) / a.in_image;
  if (a.inliers > 0) a.mean_inlier_px = inlier_sum / a.inliers;
  if (!distances.empty()) {
    const auto mid = distances.begin() + static_cast<std::ptrdiff_t>(distances.size() / 2);
    std::nth_element(distances.begin(), mid, distances.end());
    a.median_distance_px = *mid;
  }
  return a;
}

Result<std::vector<Eigen::Vector3d>> modelEdgePointsWorld(Renderer& renderer, const PinholeCamera& camera,
                                                          const Pose& T_world_camera,
                                                          const EdgeOverlayOptions& options) {
  RenderSettings settings = options.render;
  settings.outputs = kRenderAll;
  Result<RenderOutput> view = renderer.render(camera, T_world_camera, settings);
  if (!view.ok()) return view.error();
  ReferenceEdgeOptions reference = options.reference;
  reference.levels = 1;
  Result<EdgeReference> edges = buildEdgeReference(std::move(view).value(), camera, T_world_camera, reference);
  if (!edges.ok()) return edges.error();
  std::vector<Eigen::Vector3d> points;
  points.reserve(edges->points.size());
  for (const EdgePoint& p : edges->points) points.push_back(T_world_camera * Eigen::Vector3d(p.x, p.y, p.z));
  return points;
}

Result<EdgeOverlay> makeEdgeOverlay(Renderer& renderer, const ImageU8& gray, const PinholeCamera& camera,
                                    const Pose& T_world_estimate, const std::optional<Pose>& T_world_truth,
                                    const EdgeOverlayOptions& options) {
  if (Status s = validateEdgeOverlayOptions(options); !s.ok()) return s.error();
  if (gray.channels != 1 || gray.width != camera.width || gray.height != camera.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("overlay: the image is {}x{} with {} channels, the camera {}x{} gray", gray.width,
                                 gray.height, gray.channels, camera.width, camera.height));
  }
  if (!isValidPose(T_world_estimate) || (T_world_truth && !isValidPose(*T_world_truth))) {
    return makeError(ErrorCode::kInvalidArgument, "overlay: invalid pose");
  }
  LiveFrameOptions live = options.live;
  live.levels = 1;
  live.keep_intermediate = false;
  live.subpixel_edges = false;
  live.distance_gradient = false;
  Result<LiveFrame> frame = buildLiveFrame(gray, camera, live);
  if (!frame.ok()) return frame.error();
  Result<std::vector<Eigen::Vector3d>> points = modelEdgePointsWorld(renderer, camera, T_world_estimate, options);
  if (!points.ok()) return points.error();

  EdgeOverlay out;
  out.image = ImageU8(gray.width, gray.height, 3);
  for (size_t i = 0; i < gray.data.size(); ++i) {
    const auto g = static_cast<uint8_t>(std::lround(gray.data[i] * options.dim));
    for (size_t c = 0; c < 3; ++c) out.image.data[3 * i + c] = g;
  }
  const LiveLevel& level = frame->levels.front();
  std::vector<ProjectedEdgePoint> projected;
  if (T_world_truth) {
    out.truth = classifyEdgePoints(*points, camera, *T_world_truth, level, options.inlier_threshold_px, &projected);
    if (options.draw_truth) {
      for (const ProjectedEdgePoint& q : projected) {
        putPixel(out.image, static_cast<int>(std::lround(q.u)), static_cast<int>(std::lround(q.v)), kTruthRgb);
      }
    }
  }
  out.estimate = classifyEdgePoints(*points, camera, T_world_estimate, level, options.inlier_threshold_px, &projected);
  for (const ProjectedEdgePoint& q : projected) {
    if (q.inlier) drawCross(out.image, q.u, q.v, kInlierRgb);
  }
  for (const ProjectedEdgePoint& q : projected) {
    if (!q.inlier) drawCross(out.image, q.u, q.v, kOutlierRgb);
  }
  return out;
}

int overlayCaptionHeight(int lines, int scale) { return (lines * kLineAdvance + 2) * scale; }

void drawOverlayText(ImageU8& image, int x, int y, std::string_view text, const OverlayRgb& colour, int scale) {
  scale = std::max(1, scale);
  int pen = x;
  for (char c : text) {
    const Glyph& g = glyphFor(c);
    for (int row = 0; row < 7; ++row) {
      for (int col = 0; col < 5; ++col) {
        if ((g.rows[row] >> (4 - col) & 1) == 0) continue;
        for (int dy = 0; dy < scale; ++dy) {
          for (int dx = 0; dx < scale; ++dx) putPixel(image, pen + col * scale + dx, y + row * scale + dy, colour);
        }
      }
    }
    pen += kGlyphAdvance * scale;
  }
}

void drawOverlayCaption(ImageU8& image, const std::vector<std::string>& lines) {
  if (lines.empty() || image.empty()) return;
  size_t longest = 0;
  for (const std::string& line : lines) longest = std::max(longest, line.size());
  const int scale = static_cast<int>(longest) * kGlyphAdvance * 2 + 4 <= image.width ? 2 : 1;
  const int band = std::min(image.height, overlayCaptionHeight(static_cast<int>(lines.size()), scale));
  for (int y = 0; y < band; ++y) {
    for (int x = 0; x < image.width; ++x) {
      for (int c = 0; c < image.channels; ++c) image.at(x, y, c) = static_cast<uint8_t>(image.at(x, y, c) / 4);
    }
  }
  for (size_t i = 0; i < lines.size(); ++i) {
    drawOverlayText(image, 2 * scale, scale + static_cast<int>(i) * kLineAdvance * scale, lines[i], {255, 255, 255},
                    scale);
  }
}

}  // namespace vkloc
