// Reference edge points of a rendered view on the CPU: edge flags, back-projection, budget.
#include "vkloc/track/reference_edges.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <opencv2/imgproc.hpp>

#include "track/edges_internal.hpp"

namespace vkloc {

EdgeDetectorOptions keyframeDetector() {
  EdgeDetectorOptions options;
  options.noise_sigmas = 0.0;
  options.min_high_gradient = 13.0;
  return options;
}

using namespace track_detail;

namespace {

/// A geometric edge flag and the 4-neighbour it points to (pixels).
struct EdgeDirection {
  uint8_t flag;
  int dx, dy;
};
constexpr EdgeDirection kOcclusionDirections[4] = {{kEdgePixelOcclusionRight, 1, 0},
                                                   {kEdgePixelOcclusionLeft, -1, 0},
                                                   {kEdgePixelOcclusionDown, 0, 1},
                                                   {kEdgePixelOcclusionUp, 0, -1}};
constexpr EdgeDirection kCreaseDirections[2] = {{kEdgePixelCreaseRight, 1, 0}, {kEdgePixelCreaseDown, 0, 1}};

constexpr double kPi = 3.14159265358979323846;

/// True when a rendered depth (metres) is a surface: positive and finite (background is 0).
inline bool isSurface(float z) { return z > 0 && std::isfinite(z); }

/// True when all n depths are background: +0 exactly (as renders write it).
inline bool allBackground(const float* z, int n) {
  uint32_t any = 0;
  for (int i = 0; i < n; ++i) {
    uint32_t bits = 0;
    std::memcpy(&bits, z + i, sizeof bits);
    any |= bits;
  }
  return any == 0;
}

/// True when two depths (metres, > 0) are on the same surface: no discontinuity.
bool continuous(float a, float b, double ratio) {
  return std::abs(static_cast<double>(a) - b) <= ratio * std::min(a, b);
}

}  // namespace

// --- reference edges ----------------------------------------------------------------------------

Status validateReferenceEdgeOptions(const ReferenceEdgeOptions& o) {
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(o.detector));
  if (!finiteIn(o.depth_jump_ratio, 1e-6, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "reference edges: depth_jump_ratio must be in 1e-6..1e6");
  }
  if (!finiteIn(o.crease_angle_deg, 0.0, 180.0)) {
    return makeError(ErrorCode::kInvalidArgument, "reference edges: crease_angle_deg must be in 0..180");
  }
  if (o.hole_gap_px < 0 || o.hole_gap_px > 4096) {
    return makeError(ErrorCode::kInvalidArgument, "reference edges: hole_gap_px must be in 0..4096");
  }
  if (o.cell_px < 1 || o.cell_px > 4096) {
    return makeError(ErrorCode::kInvalidArgument, "reference edges: cell_px must be in 1..4096");
  }
  if (o.max_points_per_cell < 1) {
    return makeError(ErrorCode::kInvalidArgument, "reference edges: max_points_per_cell must be >= 1");
  }
  if (o.max_points < 1) return makeError(ErrorCode::kInvalidArgument, "reference edges: max_points must be >= 1");
  if (o.levels < 1 || o.levels > 8)
    return makeError(ErrorCode::kInvalidArgument, "reference edges: levels must be in 1..8");
  return Status::success();
}

namespace {

/// The reference view at one pyramid level: gray (0..255), depth (m), normals (3 channels),
/// back faces (RenderOutput::back_faces; empty when the render has none).
struct ReferenceLevel {
  ImageF32 gray;
  ImageF32 depth;
  ImageF32 normals;
  ImageU8 back_faces;
};

/// The back-face mask when it matches the depth's size, else null (not known).
const ImageU8* backFacesOf(const ImageU8& back_faces, const ImageF32& depth) {
  const bool usable = back_faces.channels == 1 && back_faces.width == depth.width &&
                      back_faces.height == depth.height && !back_faces.empty();
  return usable ? &back_faces : nullptr;
}

/// Halves a reference level: gray as the live pyramid (downsampleHalf), depth, normals and
/// back-face flag of the nearest surface among the 2x2 input pixels an output pixel covers.
ReferenceLevel downsampleReference(const ReferenceLevel& in) {
  ReferenceLevel out;
  out.gray = downsampleHalf(in.gray);
  const int w = out.gray.width;
  const int h = out.gray.height;
  out.depth = ImageF32(w, h, 1, 0.0f);
  const bool normals = in.normals.channels == 3 && in.normals.width == in.depth.width;
  if (normals) out.normals = ImageF32(w, h, 3, 0.0f);
  const ImageU8* back_faces = backFacesOf(in.back_faces, in.depth);
  if (back_faces) out.back_faces = ImageU8(w, h, 1, 0);
  const int in_w = in.depth.width;
  const int in_h = in.depth.height;
  for (int y = 0; y < h; ++y) {
    // The 2x2 input pixels, clamped to the input, in the order (x0, y0), (x1, y0), (x0, y1), (x1, y1):
    // the first nearest wins.
    const int sy[2] = {std::min(2 * y, in_h - 1), std::min(2 * y + 1, in_h - 1)};
    float* depth_out = &out.depth.data[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      const int sx[2] = {std::min(2 * x, in_w - 1), std::min(2 * x + 1, in_w - 1)};
      float best = 0;
      size_t source = 0;
      bool found = false;
      for (int dy = 0; dy < 2; ++dy) {
        const size_t row = static_cast<size_t>(sy[dy]) * in_w;
        for (int dx = 0; dx < 2; ++dx) {
          const size_t i = row + static_cast<size_t>(sx[dx]);
          const float z = in.depth.data[i];
          if (isSurface(z) && (best == 0 || z < best)) {
            best = z;
            source = i;
            found = true;
          }
        }
      }
      depth_out[x] = best;
      if (back_faces && found) out.back_faces.data[static_cast<size_t>(y) * w + x] = back_faces->data[source];
      if (normals && found) {
        const float* n = &in.normals.data[source * 3];
        float* o = &out.normals.data[(static_cast<size_t>(y) * w + x) * 3];
        o[0] = n[0];
        o[1] = n[1];
        o[2] = n[2];
      }
    }
  }
  return out;
}

/// True when the surface of the near pixel (x, y) continues within `gap` pixels beyond its
/// depth jump in direction (sx, sy): some pixel x + k sx, 2 <= k <= gap, has the depth that the
/// near surface's inverse depth, extrapolated linearly along the line, predicts there (within
/// `ratio`). Inverse depth of a plane is linear in the image, so a hole in a wall is found.
bool nearSurfaceResumes(const ImageF32& D, int x, int y, int sx, int sy, int gap, double ratio) {
  const float zp = D.at(x, y);
  const double izp = 1.0 / zp;
  double diz = 0;
  const int bx = x - sx;
  const int by = y - sy;
  if (bx >= 0 && by >= 0 && bx < D.width && by < D.height) {
    const float zb = D.at(bx, by);
    if (isSurface(zb) && continuous(zp, zb, ratio)) diz = izp - 1.0 / zb;
  }
  for (int k = 2; k <= gap; ++k) {
    const int qx = x + k * sx;
    const int qy = y + k * sy;
    if (qx < 0 || qy < 0 || qx >= D.width || qy >= D.height) return false;
    const double iz = izp + k * diz;
    if (!(iz > 0)) return false;
    const float zq = D.at(qx, qy);
    if (isSurface(zq) && continuous(static_cast<float>(1.0 / iz), zq, ratio)) return true;
  }
  return false;
}

/// Geometric edge flags of a reference level (occlusion and crease flags; hole rims dropped and
/// marked in hole_rim) and its texture edges; stage 1 merges them (mergeReferenceEdges). The two
/// are independent, so buildEdgeReference runs them side by side.
struct GeometricFlags {
  ImageU8 flags;
  ImageU8 hole_rim;  ///< 1 on both sides of a dropped hole-rim flag; empty when not searched.
};
struct TextureEdges {
  EdgeGradients gradients;
  ImageU8 edges;
  Status status = Status::success();
};

/// Drops the occlusion flags of pixel (x, y) whose near surface resumes behind the jump (a hole
/// in the model, not its outline) and marks both sides in hole_rim. Out of line: the scan for
/// flagged pixels stays a tight loop.
[[gnu::noinline]] void dropHoleRimFlags(const ImageF32& D, int x, int y, int gap, double ratio, uint8_t& f,
                                        ImageU8& hole_rim) {
  for (const EdgeDirection& side : kOcclusionDirections) {
    if (!(f & side.flag)) continue;
    if (!nearSurfaceResumes(D, x, y, side.dx, side.dy, gap, ratio)) continue;
    f &= static_cast<uint8_t>(~side.flag);
    hole_rim.at(x, y) = 1;
    const int qx = x + side.dx;
    const int qy = y + side.dy;
    if (qx >= 0 && qy >= 0 && qx < D.width && qy < D.height) hole_rim.at(qx, qy) = 1;
  }
}

GeometricFlags geometricReferenceFlags(const ReferenceLevel& view, const ReferenceEdgeOptions& options) {
  const int w = view.depth.width;
  const int h = view.depth.height;
  const bool have_normals =
      !view.normals.empty() && view.normals.width == w && view.normals.height == h && view.normals.channels == 3;
  ImageU8 flags(w, h, 1, 0);
  const double ratio = options.depth_jump_ratio;
  const float cos_crease = static_cast<float>(std::cos(options.crease_angle_deg * kPi / 180.0));
  const ImageF32& D = view.depth;
  const bool creases = options.crease_edges && have_normals;
  // One pair of 4-neighbours p, q (q right of or below p), row pointers given.
  auto pair = [&](float zp, float zq, const float* np, const float* nq, uint8_t& fp, uint8_t& fq, uint8_t to_q,
                  uint8_t to_p, uint8_t crease) {
    const bool sp = isSurface(zp);
    const bool sq = isSurface(zq);
    if (!sp && !sq) return;
    if (sp != sq || !continuous(zp, zq, ratio)) {
      if (options.occlusion_edges) {
        // Background counts as infinitely far: the flag goes on the surface pixel.
        if (sp && (!sq || zp < zq)) {
          fp |= to_q;
        } else {
          fq |= to_p;
        }
      }
      return;
    }
    if (creases && np[0] * nq[0] + np[1] * nq[1] + np[2] * nq[2] < cos_crease) fp |= crease;
  };
  for (int y = 0; y < h; ++y) {
    const float* z = &D.data[static_cast<size_t>(y) * w];
    const float* z_below = y + 1 < h ? z + w : nullptr;
    const float* n = have_normals ? &view.normals.data[static_cast<size_t>(y) * w * 3] : nullptr;
    const float* n_below = have_normals && z_below ? n + static_cast<size_t>(w) * 3 : nullptr;
    uint8_t* f = &flags.data[static_cast<size_t>(y) * w];
    uint8_t* f_below = z_below ? f + w : nullptr;
    for (int x = 0; x < w; ++x) {
      // Background (depth +0) at x .. x + 7, its right neighbour and below: no pair there has
      // a surface. Skipped eight at a time: a keyframe of a small or distant model is mostly sky.
      if ((x & 7) == 0 && z_below && x + 9 <= w && allBackground(z + x, 9) && allBackground(z_below + x, 8)) {
        x += 7;
        continue;
      }
      const float* np = n ? n + 3 * x : nullptr;
      if (x + 1 < w) {
        pair(z[x], z[x + 1], np, np ? np + 3 : nullptr, f[x], f[x + 1], kEdgePixelOcclusionRight,
             kEdgePixelOcclusionLeft, kEdgePixelCreaseRight);
      }
      if (z_below) {
        pair(z[x], z_below[x], np, n_below ? n_below + 3 * x : nullptr, f[x], f_below[x], kEdgePixelOcclusionDown,
             kEdgePixelOcclusionUp, kEdgePixelCreaseDown);
      }
    }
  }
  // Rims of model holes: drop their occlusion flags and remember them for the texture edges.
  ImageU8 hole_rim;
  if (options.occlusion_edges && options.hole_gap_px > 0) {
    hole_rim = ImageU8(w, h, 1, 0);
    constexpr uint8_t kOcclusionFlags =
        kEdgePixelOcclusionRight | kEdgePixelOcclusionLeft | kEdgePixelOcclusionDown | kEdgePixelOcclusionUp;
    for (int y = 0; y < h; ++y) {
      uint8_t* f = &flags.data[static_cast<size_t>(y) * w];
      for (int x = 0; x < w; ++x) {
        if (f[x] & kOcclusionFlags) dropHoleRimFlags(D, x, y, options.hole_gap_px, ratio, f[x], hole_rim);
      }
    }
  }
  return GeometricFlags{std::move(flags), std::move(hole_rim)};
}

void textureReferenceEdges(const ReferenceLevel& view, const ReferenceEdgeOptions& options, TextureEdges& out) {
  out.status = detectEdgesImpl(view.gray, options.detector, out.gradients, out.edges);
}

/// Stage 1 (detectReferenceEdges) from its two halves. `texture` is null without texture edges.
ImageU8 mergeReferenceEdges(const ReferenceLevel& view, GeometricFlags geometric_flags, const TextureEdges* texture) {
  ImageU8 flags = std::move(geometric_flags.flags);
  if (texture == nullptr) return flags;
  const ImageU8& hole_rim = geometric_flags.hole_rim;
  const int w = view.depth.width;
  const int h = view.depth.height;
  const ImageF32& D = view.depth;
  auto nearHoleRim = [&](int x, int y) {
    if (hole_rim.empty()) return false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx;
        const int ny = y + dy;
        if (nx >= 0 && ny >= 0 && nx < w && ny < h && hole_rim.at(nx, ny)) return true;
      }
    }
    return false;
  };
  const ImageU8* edges = &texture->edges;
  // A geometric edge that shows in the gray image is represented by its texture edge pixels
  // (found by the same detector as the live image's edges, so both place it alike); the
  // geometric flags next to such pixels are dropped.
  ImageU8 geometric = flags;
  for (int y = 0; y < h; ++y) {
    const uint8_t* edge_row = &edges->data[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      if (eightClear(edge_row, x, w)) {
        x += 7;
        continue;
      }
      if (!edge_row[x]) continue;
      bool has_surface = D.at(x, y) > 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int nx = x + dx;
          const int ny = y + dy;
          if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
          has_surface = has_surface || geometric.at(nx, ny) != 0;
          flags.at(nx, ny) &= kEdgePixelTexture;
        }
      }
      if (has_surface && !nearHoleRim(x, y)) flags.at(x, y) |= kEdgePixelTexture;
    }
  }
  return flags;
}

Result<ImageU8> detectReferenceEdgesImpl(const ReferenceLevel& view, const ReferenceEdgeOptions& options) {
  GeometricFlags geometric = geometricReferenceFlags(view, options);
  if (!options.texture_edges) return mergeReferenceEdges(view, std::move(geometric), nullptr);
  TextureEdges texture;
  textureReferenceEdges(view, options, texture);
  VKLOC_TRY_STATUS(texture.status);
  return mergeReferenceEdges(view, std::move(geometric), &texture);
}

}  // namespace

Result<ImageU8> detectReferenceEdges(const RenderOutput& view, const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceEdgeOptions(options));
  if (view.depth.empty() || view.depth.channels != 1 || view.gray.width != view.depth.width ||
      view.gray.height != view.depth.height || view.gray.channels != 1 || view.gray.empty()) {
    return makeError(ErrorCode::kInvalidArgument,
                     "detectReferenceEdges: view needs a gray image and a depth image of the same size");
  }
  return detectReferenceEdgesImpl(ReferenceLevel{toFloat(view.gray), view.depth, view.normals, view.back_faces},
                                  options);
}

namespace {

/// Stage 2 (backProjectEdges); with the gradients the texture edges were found on, texture
/// edge points are moved to their sub-pixel edge (subpixelOffset).
std::vector<EdgePoint> backProjectEdgesImpl(const ImageU8& flags, const ImageF32& depth, const PinholeCamera& camera,
                                            const ReferenceEdgeOptions& options, const EdgeGradients* texture_gradients,
                                            const ImageU8* back_faces) {
  std::vector<EdgePoint> points;
  const int w = flags.width;
  const int h = flags.height;
  if (depth.width != w || depth.height != h || depth.channels != 1 || flags.channels != 1) return points;
  const double ratio = options.depth_jump_ratio;
  auto depthAt = [&](int x, int y) -> float {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0.0f;
    const float z = depth.at(x, y);
    return isSurface(z) ? z : 0.0f;
  };
  const uint8_t* back = back_faces ? back_faces->data.data() : nullptr;
  // kEdgeBackground / kEdgeBackFace of pixel i: no surface there, or a back face.
  auto modifiersOf = [&](size_t i) -> uint32_t {
    return (isSurface(depth.data[i]) ? 0u : kEdgeBackground) | (back && back[i] ? kEdgeBackFace : 0u);
  };
  int px = 0, py = 0;  // pixel whose flags are emitted
  // Modifier bits of the pixels within 2 pixels of (px, py); -1: not known yet.
  int64_t near_modifiers = -1;
  auto nearModifiers = [&]() -> uint32_t {
    if (near_modifiers >= 0) return static_cast<uint32_t>(near_modifiers);
    uint32_t m = 0;
    if (px >= 2 && py >= 2 && px + 2 < w && py + 2 < h) {
      for (int dy = -2; dy <= 2; ++dy) {
        const size_t row = static_cast<size_t>(py + dy) * w + px - 2;
        for (size_t dx = 0; dx < 5; ++dx) m |= modifiersOf(row + dx);
      }
    } else {
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const int nx = px + dx;
          const int ny = py + dy;
          if (nx >= 0 && ny >= 0 && nx < w && ny < h) m |= modifiersOf(static_cast<size_t>(ny) * w + nx);
        }
      }
    }
    near_modifiers = m;
    return m;
  };
  auto emit = [&](double u, double v, double z, uint32_t kind) {
    // Eq. 3: P = pi^-1(u, Z) with metric depth Z (camera z).
    kind |= nearModifiers();
    EdgePoint p;
    p.x = static_cast<float>(z * (u - camera.cx) / camera.fx);
    p.y = static_cast<float>(z * (v - camera.cy) / camera.fy);
    p.z = static_cast<float>(z);
    p.kind = kind;
    points.push_back(p);
  };
  for (int y = 0; y < h; ++y) {
    const uint8_t* flag_row = &flags.data[static_cast<size_t>(y) * w];
    for (int x = 0; x < w; ++x) {
      if (eightClear(flag_row, x, w)) {
        x += 7;
        continue;
      }
      const uint8_t f = flag_row[x];
      if (!f) continue;
      px = x;
      py = y;
      near_modifiers = -1;
      const float zp = depthAt(x, y);
      if (f & kEdgePixelTexture) {
        // On or next to a depth jump the edge belongs to the near surface: take the smallest
        // depth of the pixel and its 8-neighbours that are on the near side of a jump.
        float z = zp;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const float zn = depthAt(x + dx, y + dy);
            if (zn <= 0 || (zp > 0 && continuous(zp, zn, ratio))) continue;
            if (zp > 0 && zn > zp) continue;
            if (z <= 0 || zn < z) z = zn;
          }
        }
        if (z > 0) {
          float du = 0, dv = 0;
          if (texture_gradients) subpixelOffset(*texture_gradients, x, y, du, dv);
          emit(x + static_cast<double>(du), y + static_cast<double>(dv), z, kEdgeTexture);
        }
      }
      if (zp <= 0) continue;
      for (const EdgeDirection& d : kOcclusionDirections) {
        if (!(f & d.flag)) continue;
        // Near surface extrapolated half a pixel towards the jump when the pixel behind is
        // on the same surface.
        const float zb = depthAt(x - d.dx, y - d.dy);
        double z = zp;
        if (zb > 0 && continuous(zp, zb, ratio)) z = zp + 0.5 * (static_cast<double>(zp) - zb);
        if (!(z > 0)) z = zp;
        emit(x + 0.5 * d.dx, y + 0.5 * d.dy, z, kEdgeOcclusion);
      }
      for (const EdgeDirection& d : kCreaseDirections) {
        if (!(f & d.flag)) continue;
        const float zq = depthAt(x + d.dx, y + d.dy);
        if (zq <= 0) continue;
        emit(x + 0.5 * d.dx, y + 0.5 * d.dy, 0.5 * (static_cast<double>(zp) + zq), kEdgeCrease);
      }
    }
  }
  return points;
}

}  // namespace

std::vector<EdgePoint> backProjectEdges(const ImageU8& flags, const ImageF32& depth, const PinholeCamera& camera,
                                        const ReferenceEdgeOptions& options) {
  return backProjectEdgesImpl(flags, depth, camera, options, nullptr, nullptr);
}

std::vector<EdgePoint> subsampleEdgePoints(const std::vector<EdgePoint>& points, const PinholeCamera& camera,
                                           const ReferenceEdgeOptions& options) {
  const int cell = std::max(options.cell_px, 1);
  const int cells_x = std::max(1, (camera.width + cell - 1) / cell);
  const int cells_y = std::max(1, (camera.height + cell - 1) / cell);
  const size_t budget = static_cast<size_t>(std::max(options.max_points, 1));
  if (points.size() <= budget && options.max_points_per_cell >= static_cast<int>(points.size())) return points;
  // Bucket the point indices by cell, keeping input order inside a cell.
  std::vector<std::vector<uint32_t>> buckets(static_cast<size_t>(cells_x) * cells_y);
  for (size_t i = 0; i < points.size(); ++i) {
    const EdgePoint& p = points[i];
    if (!(p.z > 0)) continue;
    const double u = camera.fx * p.x / p.z + camera.cx;
    const double v = camera.fy * p.y / p.z + camera.cy;
    const int cx = std::clamp(static_cast<int>(std::floor((u + 0.5) / cell)), 0, cells_x - 1);
    const int cy = std::clamp(static_cast<int>(std::floor((v + 0.5) / cell)), 0, cells_y - 1);
    buckets[static_cast<size_t>(cy) * cells_x + cx].push_back(static_cast<uint32_t>(i));
  }
  auto totalFor = [&](size_t k) {
    size_t total = 0;
    for (const auto& b : buckets) total += std::min(b.size(), k);
    return total;
  };
  size_t k = static_cast<size_t>(std::max(options.max_points_per_cell, 1));
  while (k > 1 && totalFor(k) > budget) --k;
  std::vector<uint8_t> keep(points.size(), 0);
  for (const auto& b : buckets) {
    const size_t n = b.size();
    const size_t take = std::min(n, k);
    for (size_t j = 0; j < take; ++j) keep[b[(j * n + n / 2) / take]] = 1;
  }
  std::vector<EdgePoint> out;
  for (size_t i = 0; i < points.size(); ++i) {
    if (keep[i]) out.push_back(points[i]);
  }
  if (out.size() > budget) {
    // Even one point per cell is too many: keep evenly spaced points of the list.
    std::vector<EdgePoint> thinned;
    thinned.reserve(budget);
    for (size_t j = 0; j < budget; ++j) thinned.push_back(out[(j * out.size() + out.size() / 2) / budget]);
    out = std::move(thinned);
  }
  return out;
}

namespace {

Status validateReferenceView(const RenderOutput& view, const PinholeCamera& camera, const Pose& T_world_ref,
                             const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  if (!isValidPose(T_world_ref)) {
    return makeError(ErrorCode::kInvalidArgument, "buildEdgeReference: T_world_ref is not a valid rigid transform");
  }
  if (view.depth.width != camera.width || view.depth.height != camera.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("buildEdgeReference: view is {}x{}, camera expects {}x{}", view.depth.width,
                                 view.depth.height, camera.width, camera.height));
  }
  VKLOC_TRY_STATUS(validateReferenceEdgeOptions(options));
  if (options.levels < 1 || options.levels > 8) {
    return makeError(ErrorCode::kInvalidArgument, "buildEdgeReference: levels must be in 1..8");
  }
  if (view.gray.width != camera.width || view.gray.height != camera.height || view.gray.channels != 1 ||
      view.depth.channels != 1) {
    return makeError(ErrorCode::kInvalidArgument, "buildEdgeReference: view needs gray and depth of the camera's size");
  }
  return Status::success();
}

/// buildEdgeReference from its level 0 (a checked view's gray as floats, depth, normals).
Result<EdgeReference> buildEdgeReferenceFrom(ReferenceLevel level0, const PinholeCamera& camera,
                                             const Pose& T_world_ref, const ReferenceEdgeOptions& options) {
  EdgeReference ref;
  ref.camera = camera;
  ref.T_world_ref = T_world_ref;
  // The pyramid of render targets first, then the levels in parallel (each reads only its own).
  std::vector<ReferenceLevel> levels;
  levels.push_back(std::move(level0));
  while (static_cast<int>(levels.size()) < options.levels) {
    const ReferenceLevel& finer = levels.back();
    if (finer.depth.width < 16 || finer.depth.height < 16) break;
    levels.push_back(downsampleReference(finer));
  }
  const int n = static_cast<int>(levels.size());
  std::vector<std::vector<EdgePoint>> points(static_cast<size_t>(n));
  // Round 1: per level the geometric flags and the texture edges, 2n independent tasks (level 0's
  // two halves are the largest; they run side by side). Round 2: per level the merge,
  // back-projection and subsampling.
  std::vector<GeometricFlags> geometric(static_cast<size_t>(n));
  std::vector<TextureEdges> texture(static_cast<size_t>(n));
  const int tasks = options.texture_edges ? 2 * n : n;
  auto forRange = [&](int count, const std::function<void(const cv::Range&)>& body) {
    if (options.parallel) {
      cv::parallel_for_(cv::Range(0, count), body, count);
    } else {
      body(cv::Range(0, count));
    }
  };
  forRange(tasks, [&](const cv::Range& range) {
    for (int t = range.start; t < range.end; ++t) {
      const size_t k = static_cast<size_t>(t / (options.texture_edges ? 2 : 1));
      if (options.texture_edges && t % 2 == 1) {
        textureReferenceEdges(levels[k], options, texture[k]);
      } else {
        geometric[k] = geometricReferenceFlags(levels[k], options);
      }
    }
  });
  for (const TextureEdges& t : texture) VKLOC_TRY_STATUS(t.status);
  forRange(n, [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k) {
      const size_t i = static_cast<size_t>(k);
      const ReferenceLevel& level = levels[i];
      const PinholeCamera level_camera = pyramidCamera(camera, k);
      const TextureEdges* level_texture = options.texture_edges ? &texture[i] : nullptr;
      const ImageU8 flags = mergeReferenceEdges(level, std::move(geometric[i]), level_texture);
      points[i] = subsampleEdgePoints(backProjectEdgesImpl(flags, level.depth, level_camera, options,
                                                           level_texture ? &level_texture->gradients : nullptr,
                                                           backFacesOf(level.back_faces, level.depth)),
                                      level_camera, options);
    }
  });
  ref.points = std::move(points[0]);
  for (int k = 1; k < n; ++k) ref.coarse_points.push_back(std::move(points[static_cast<size_t>(k)]));
  return ref;
}

}  // namespace

Result<EdgeReference> buildEdgeReference(const RenderOutput& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceView(view, camera, T_world_ref, options));
  return buildEdgeReferenceFrom(ReferenceLevel{toFloat(view.gray), view.depth, view.normals, view.back_faces}, camera,
                                T_world_ref, options);
}

Result<EdgeReference> buildEdgeReference(RenderOutput&& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceView(view, camera, T_world_ref, options));
  return buildEdgeReferenceFrom(
      ReferenceLevel{toFloat(view.gray), std::move(view.depth), std::move(view.normals), std::move(view.back_faces)},
      camera, T_world_ref, options);
}

}  // namespace vkloc
