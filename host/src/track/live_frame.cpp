// Live-image stages on the CPU: pyramid, edges, truncated distance fields, sub-pixel edge lines.
#include "vkloc/track/live_frame.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "track/edges_internal.hpp"

namespace vkloc {

using namespace track_detail;

// --- pyramid and distance fields ---------------------------------------------------------------

PinholeCamera pyramidCamera(const PinholeCamera& camera, int level) {
  PinholeCamera c = camera;
  for (int k = 0; k < level; ++k) {
    c.fx *= 0.5;
    c.fy *= 0.5;
    c.cx = (c.cx + 0.5) * 0.5 - 0.5;
    c.cy = (c.cy + 0.5) * 0.5 - 0.5;
    c.width = (c.width + 1) / 2;
    c.height = (c.height + 1) / 2;
  }
  return c;
}

ImageF32 toFloat(const ImageU8& gray) {
  ImageF32 out(gray.width, gray.height, gray.channels);
  for (size_t i = 0; i < gray.data.size(); ++i) out.data[i] = gray.data[i];
  return out;
}

ImageF32 downsampleHalf(const ImageF32& image) {
  const int w = image.width;
  const int h = image.height;
  const int ow = (w + 1) / 2;
  const int oh = (h + 1) / 2;
  if (w <= 0 || h <= 0 || image.channels != 1) return {};
  auto clampi = [](int v, int n) { return std::min(std::max(v, 0), n - 1); };
  constexpr float kTaps[4] = {1.0f / 8, 3.0f / 8, 3.0f / 8, 1.0f / 8};
  // Horizontal pass into an ow x h buffer, then vertical.
  ImageF32 tmp(ow, h, 1);
  // Interior outputs (taps 2x-1 .. 2x+2 inside the row) without clamping, so the loop vectorises.
  const int x_end = w >= 3 ? std::max(1, std::min(ow, (w - 3) / 2 + 1)) : 1;  // 2x + 2 <= w - 1
  for (int y = 0; y < h; ++y) {
    const float* row = &image.data[static_cast<size_t>(y) * w];
    float* out = &tmp.data[static_cast<size_t>(y) * ow];
    auto clamped = [&](int x) {
      float s = 0;
      for (int t = 0; t < 4; ++t) s += kTaps[t] * row[clampi(2 * x - 1 + t, w)];
      return s;
    };
    out[0] = clamped(0);
    for (int x = 1; x < x_end; ++x) {
      const float* r = row + 2 * x - 1;
      out[x] = kTaps[0] * r[0] + kTaps[1] * r[1] + kTaps[2] * r[2] + kTaps[3] * r[3];
    }
    for (int x = x_end; x < ow; ++x) out[x] = clamped(x);
  }
  ImageF32 out(ow, oh, 1);
  for (int y = 0; y < oh; ++y) {
    const float* r[4];
    for (int t = 0; t < 4; ++t) r[t] = &tmp.data[static_cast<size_t>(clampi(2 * y - 1 + t, h)) * ow];
    for (int x = 0; x < ow; ++x) {
      out.at(x, y) = kTaps[0] * r[0][x] + kTaps[1] * r[1][x] + kTaps[2] * r[2][x] + kTaps[3] * r[3][x];
    }
  }
  return out;
}

void distanceGradientAt(const DistanceField& field, int x, int y, float& g_u, float& g_v) {
  const int w = field.distance.width;
  const int h = field.distance.height;
  const float t = field.truncation_px;
  const float* D = field.distance.data.data();
  const float* row = D + static_cast<size_t>(y) * w;
  const int ylo = std::max(y - 1, 0);
  const int yhi = std::min(y + 1, h - 1);
  const float up = D[static_cast<size_t>(ylo) * w + x];
  const float down = D[static_cast<size_t>(yhi) * w + x];
  const float inv_dy = yhi > ylo ? 1.0f / static_cast<float>(yhi - ylo) : 0.0f;
  const float c = row[x];
  if (x == 0 || x == w - 1) {
    // The border columns of computeDistanceGradient.
    auto diff = [t](float centre, float a, float b, float scale) {
      const bool known = (centre < t) & (a < t) & (b < t);
      return (b - a) * scale * static_cast<float>(known);
    };
    const int xlo = std::max(x - 1, 0);
    const int xhi = std::min(x + 1, w - 1);
    g_u = xhi > xlo ? diff(c, row[xlo], row[xhi], 1.0f / static_cast<float>(xhi - xlo)) : 0.0f;
    g_v = diff(c, up, down, inv_dy);
    return;
  }
  const float l = row[x - 1], r = row[x + 1];
  const float ku = (c < t && l < t && r < t) ? 0.5f : 0.0f;
  const float kv = (c < t && up < t && down < t) ? inv_dy : 0.0f;
  g_u = (r - l) * ku;
  g_v = (down - up) * kv;
}

void computeDistanceGradient(DistanceField& field) {
  const int w = field.distance.width;
  const int h = field.distance.height;
  if (field.gradient.width != w || field.gradient.height != h || field.gradient.channels != 2) {
    field.gradient = ImageF32(w, h, 2);
  }
  const float t = field.truncation_px;
  const float* D = field.distance.data.data();
  float* G = field.gradient.data.data();
  // Difference (b - a) * scale of two samples, zero when the centre c or either is truncated.
  // (Distances are finite, so multiplying by the 0/1 mask is a branch-free select.)
  auto diff = [t](float c, float a, float b, float scale) {
    const bool known = (c < t) & (a < t) & (b < t);
    return (b - a) * scale * static_cast<float>(known);
  };
  for (int y = 0; y < h; ++y) {
    const float* row = D + static_cast<size_t>(y) * w;
    const int ylo = std::max(y - 1, 0);
    const int yhi = std::min(y + 1, h - 1);
    const float* up = D + static_cast<size_t>(ylo) * w;
    const float* down = D + static_cast<size_t>(yhi) * w;
    const float inv_dy = yhi > ylo ? 1.0f / static_cast<float>(yhi - ylo) : 0.0f;
    float* out = G + static_cast<size_t>(y) * w * 2;
    // Border columns one-sided (a single column has no u difference), the interior branch-free.
    for (int x : {0, w - 1}) {
      const int xlo = std::max(x - 1, 0);
      const int xhi = std::min(x + 1, w - 1);
      out[2 * x] = xhi > xlo ? diff(row[x], row[xlo], row[xhi], 1.0f / static_cast<float>(xhi - xlo)) : 0.0f;
      out[2 * x + 1] = diff(row[x], up[x], down[x], inv_dy);
    }
    for (int x = 1; x < w - 1; ++x) {
      const float c = row[x], l = row[x - 1], r = row[x + 1], u = up[x], d = down[x];
      const float ku = (c < t && l < t && r < t) ? 0.5f : 0.0f;
      const float kv = (c < t && u < t && d < t) ? inv_dy : 0.0f;
      out[2 * x] = (r - l) * ku;
      out[2 * x + 1] = (d - u) * kv;
    }
  }
}

namespace {

/// Largest truncation (pixels) the separable transform below handles: squared distances up to
/// R^2 + (R + 1)^2 with R = ceil(truncation) - 1 must fit int16. Larger truncations use OpenCV's
/// precise transform.
constexpr int kSeparableMaxTruncationPx = 128;

/// Scratch of the distance transforms, kept between frames.
struct DistanceScratch {
  cv::Mat inverted;            ///< Edges as zeros, for OpenCV's transform (large truncations).
  std::vector<int16_t> up;     ///< w x h: vertical distance to the nearest edge above, capped.
  std::vector<int16_t> down;   ///< w: the same from below, for the row being finished.
  std::vector<int16_t> g2pad;  ///< w + 2R: squared vertical distances of one row, padded.
  std::vector<int16_t> best;   ///< w: squared distance of the row, running minimum.
};

/// Exact Euclidean distance transform truncated at `truncation_px` (distances >= it become it):
/// separable, as OpenCV's precise transform, but every pixel only looks R = ceil(truncation) - 1
/// pixels up, down and along its row. Why exact: a pixel closer than the truncation to its
/// nearest edge pixel e has integer |dx|, |dy| < truncation, so <= R, to e: e's column is within
/// the row window and the vertical distance found in that column is at most |dy| <= R (not
/// capped); candidates from columns with no edge within R rows are >= (R + 1)^2 >= truncation^2. Both passes are
/// plain min/add loops over rows of int16 that compilers vectorise: on a 640x480 frame with
/// R = 20 this is 3-4x faster than cv::distanceTransform on the same core count.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(__SANITIZE_THREAD__)
// Wider vectors where the CPU has them (chosen once at load time; the baseline build is SSE2).
// Not under ThreadSanitizer, whose instrumented ifunc resolver runs before its runtime is up.
__attribute__((target_clones("avx2", "default")))
#endif
void truncatedDistanceTransform(const ImageU8& edges, float truncation_px, float* distance, DistanceScratch& sc) {
  const int w = edges.width;
  const int h = edges.height;
  const int R = static_cast<int>(std::ceil(truncation_px)) - 1;  // |dx|, |dy| < truncation
  const int16_t cap = static_cast<int16_t>(R + 1);
  const int16_t far2 = static_cast<int16_t>(cap * cap);
  sc.up.resize(static_cast<size_t>(w) * h);
  sc.down.assign(static_cast<size_t>(w), cap);
  sc.g2pad.assign(static_cast<size_t>(w + 2 * R), far2);
  sc.best.resize(static_cast<size_t>(w));
  // Column pass, downwards: distance to the nearest edge at or above, capped at R + 1.
  for (int y = 0; y < h; ++y) {
    const uint8_t* e = &edges.data[static_cast<size_t>(y) * w];
    int16_t* up = &sc.up[static_cast<size_t>(y) * w];
    const int16_t* prev = y > 0 ? up - w : nullptr;
    for (int x = 0; x < w; ++x) {
      const int16_t above = prev ? static_cast<int16_t>(std::min<int>(prev[x] + 1, cap)) : cap;
      up[x] = e[x] ? int16_t{0} : above;
    }
  }
  // Column pass upwards, fused with the row pass of each finished row (still in cache).
  int16_t* down = sc.down.data();
  int16_t* g2 = sc.g2pad.data() + R;
  int16_t* best = sc.best.data();
  for (int y = h - 1; y >= 0; --y) {
    const uint8_t* e = &edges.data[static_cast<size_t>(y) * w];
    const int16_t* up = &sc.up[static_cast<size_t>(y) * w];
    int16_t nearest = cap;
    for (int x = 0; x < w; ++x) {
      const int16_t below = static_cast<int16_t>(std::min<int>(down[x] + 1, cap));
      down[x] = e[x] ? int16_t{0} : below;
      const int16_t g = std::min(up[x], down[x]);
      g2[x] = static_cast<int16_t>(g * g);
      nearest = std::min(nearest, g);
    }
    float* out = distance + static_cast<size_t>(y) * w;
    if (nearest == cap) {  // no edge within R rows: the whole row is truncated
      std::fill(out, out + w, truncation_px);
      continue;
    }
    // eq. 12's V(u) = min over edge pixels of the distance, as min over dx of dx^2 + g2(x + dx).
    std::copy(g2, g2 + w, best);
    for (int dx = 1; dx <= R; ++dx) {
      const int16_t dx2 = static_cast<int16_t>(dx * dx);
      const int16_t* left = g2 - dx;
      const int16_t* right = g2 + dx;
      for (int x = 0; x < w; ++x) {
        const int16_t m = std::min(left[x], right[x]);
        best[x] = std::min(best[x], static_cast<int16_t>(m + dx2));
      }
    }
    for (int x = 0; x < w; ++x) out[x] = std::min(std::sqrt(static_cast<float>(best[x])), truncation_px);
  }
}

/// computeDistanceField into `field`, reusing its memory and the scratch; the gradient only when
/// `with_gradient` (else it is left empty).
Status computeDistanceFieldInto(const ImageU8& edges, float truncation_px, DistanceField& field, DistanceScratch& sc,
                                bool with_gradient = true) {
  if (edges.empty() || edges.channels != 1 || edges.data.size() != static_cast<size_t>(edges.width) * edges.height) {
    return makeError(ErrorCode::kInvalidArgument, "computeDistanceField: expected a non-empty single-channel edge map");
  }
  if (!(truncation_px > 0) || !std::isfinite(truncation_px)) {
    return makeError(ErrorCode::kInvalidArgument, "computeDistanceField: truncation_px must be > 0 and finite");
  }
  const int w = edges.width;
  const int h = edges.height;
  field.truncation_px = truncation_px;
  // Sized only: the transform writes every distance, computeDistanceGradient every gradient.
  auto size = [](ImageF32& image, int width, int height, int channels) {
    image.width = width;
    image.height = height;
    image.channels = channels;
    image.data.resize(static_cast<size_t>(width) * height * channels);
  };
  size(field.distance, w, h, 1);
  if (with_gradient) {
    size(field.gradient, w, h, 2);
  } else {
    field.gradient = ImageF32{};
  }
  if (truncation_px <= static_cast<float>(kSeparableMaxTruncationPx)) {
    truncatedDistanceTransform(edges, truncation_px, field.distance.data.data(), sc);
  } else {
    // distanceTransform measures the distance to the nearest zero pixel: edges become zeros.
    sc.inverted.create(h, w, CV_8U);
    bool any_edge = false;
    for (int y = 0; y < h; ++y) {
      uint8_t* dst = sc.inverted.ptr<uint8_t>(y);
      const uint8_t* src = &edges.data[static_cast<size_t>(y) * w];
      for (int x = 0; x < w; ++x) {
        dst[x] = src[x] ? 0 : 255;
        any_edge = any_edge || src[x];
      }
    }
    if (!any_edge) {
      std::fill(field.distance.data.begin(), field.distance.data.end(), truncation_px);
    } else {
      cv::Mat dist(h, w, CV_32F, field.distance.data.data());
      cv::distanceTransform(sc.inverted, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
      const float t = truncation_px;
      for (float& d : field.distance.data) d = std::min(d, t);
    }
  }
  if (with_gradient) computeDistanceGradient(field);
  return Status::success();
}

}  // namespace

Result<DistanceField> computeDistanceField(const ImageU8& edges, float truncation_px) {
  DistanceField field;
  DistanceScratch scratch;
  VKLOC_TRY_STATUS(computeDistanceFieldInto(edges, truncation_px, field, scratch));
  return field;
}

namespace {

/// Working buffers of computeEdgeLines kept between frames of one level.
struct EdgeLineScratch {
  std::vector<float> best;       ///< Squared distance of the nearest edge point so far, per pixel.
  std::vector<int> written;      ///< Pixels the last call wrote (the only ones not in the cleared state).
  const float* lines = nullptr;  ///< The lines buffer the last call wrote into.
};

/// LiveLevel::edge_lines of an edge map: every edge pixel splats its sub-pixel line into the
/// pixels within kEdgeLineRadiusPx of its edge point; a pixel keeps the nearest edge point.
/// Only the pixels the previous frame wrote are cleared (most of a frame is far from edges),
/// which leaves the same state as clearing everything.
void computeEdgeLines(const ImageU8& edges, const EdgeGradients& g, ImageF32& lines, EdgeLineScratch& sc) {
  const int w = edges.width;
  const int h = edges.height;
  const size_t n = static_cast<size_t>(w) * h;
  const float far2 = kEdgeLineRadiusPx * kEdgeLineRadiusPx;
  if (lines.width == w && lines.height == h && lines.channels == 3 && lines.data.size() == 3 * n &&
      sc.lines == lines.data.data() && sc.best.size() == n) {
    for (const int i : sc.written) {
      float* out = &lines.data[static_cast<size_t>(i) * 3];
      out[0] = out[1] = out[2] = 0.0f;
      sc.best[static_cast<size_t>(i)] = far2;
    }
  } else {
    resetImage(lines, w, h, 3, 0.0f);
    sc.best.assign(n, far2);
  }
  sc.written.clear();
  sc.lines = lines.data.data();
  // Raw pointers, not reloaded from the vectors after each sc.written.push_back.
  float* best = sc.best.data();
  float* out_lines = lines.data.data();
  const int r = static_cast<int>(std::ceil(kEdgeLineRadiusPx));
  for (int y = 1; y < h - 1; ++y) {
    const uint8_t* row = &edges.data[static_cast<size_t>(y) * w];
    const float* gx_row = g.gx.ptr<float>(y);
    const float* gy_row = g.gy.ptr<float>(y);
    for (int x = 1; x < w - 1; ++x) {
      if (eightClear(row, x, w - 1)) {
        x += 7;
        continue;
      }
      if (!row[x]) continue;
      const float gx = gx_row[x];
      const float gy = gy_row[x];
      const float m = std::sqrt(gx * gx + gy * gy);
      if (!(m > 0)) continue;
      const float nu = gx / m;
      const float nv = gy / m;
      float du = 0, dv = 0;
      subpixelOffset(g, x, y, du, dv);
      const float eu = static_cast<float>(x) + du;
      const float ev = static_cast<float>(y) + dv;
      const int x0 = std::max(x - r, 0);
      const int x1 = std::min(x + r, w - 1);
      for (int qy = std::max(y - r, 0); qy <= std::min(y + r, h - 1); ++qy) {
        const float ov = static_cast<float>(qy) - ev;
        const float ov2 = ov * ov;
        float* best_row = best + static_cast<size_t>(qy) * w;
        for (int qx = x0; qx <= x1; ++qx) {
          const float ou = static_cast<float>(qx) - eu;
          const float d2 = ou * ou + ov2;
          float& b = best_row[qx];
          if (d2 >= b) continue;
          const int i = qy * w + qx;
          if (b == far2) sc.written.push_back(i);  // first write since the clear
          b = d2;
          float* out = out_lines + static_cast<size_t>(i) * 3;
          out[0] = nu * ou + nv * ov;
          out[1] = nu;
          out[2] = nv;
        }
      }
    }
  }
}

}  // namespace

Result<LiveFrame> buildLiveFrame(const ImageU8& gray, const PinholeCamera& camera, const LiveFrameOptions& options) {
  LiveFrame frame;
  VKLOC_TRY_STATUS(buildLiveFrame(gray, camera, options, frame));
  return frame;
}

Status buildLiveFrame(const ImageU8& gray, const PinholeCamera& camera, const LiveFrameOptions& options,
                      LiveFrame& frame) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(options.detector));
  if (options.levels < 1 || options.levels > 8) {
    return makeError(ErrorCode::kInvalidArgument, "buildLiveFrame: levels must be in 1..8");
  }
  if (!(options.truncation_px > 0) || !std::isfinite(options.truncation_px)) {
    return makeError(ErrorCode::kInvalidArgument, "buildLiveFrame: truncation_px must be > 0 and finite");
  }
  if (gray.channels != 1 || gray.width != camera.width || gray.height != camera.height ||
      gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("buildLiveFrame: image is {}x{}x{}, camera expects {}x{} single-channel", gray.width,
                                 gray.height, gray.channels, camera.width, camera.height));
  }
  // The gray pyramid first (cheap), then the levels in parallel (level 0 on one core, the
  // coarser ones on another): each level's edges, distance field and edge lines depend only on
  // its own gray image. Working buffers are kept per thread: once warm nothing is allocated.
  thread_local std::vector<ImageF32> pyramid;
  int built = 0;
  for (int level = 0; level < options.levels; ++level) {
    if (static_cast<int>(pyramid.size()) <= level) pyramid.resize(static_cast<size_t>(level) + 1);
    ImageF32& level_gray = pyramid[static_cast<size_t>(level)];
    if (level == 0) {
      // Sized only: every value is written below.
      level_gray.width = gray.width;
      level_gray.height = gray.height;
      level_gray.channels = 1;
      level_gray.data.resize(gray.data.size());
      for (size_t i = 0; i < gray.data.size(); ++i) level_gray.data[i] = gray.data[i];
    } else {
      const ImageF32& finer = pyramid[static_cast<size_t>(level) - 1];
      if (finer.width < 16 || finer.height < 16) break;
      level_gray = downsampleHalf(finer);
    }
    built = level + 1;
  }
  frame.levels.resize(static_cast<size_t>(built));
  // Named by reference: inside the lambda below `pyramid` would be the worker thread's own.
  const std::vector<ImageF32>& grays = pyramid;
  // Per level: edges (with their gradients), then the distance field (reads the edges) and the
  // edge lines (the edges and gradients). Level 0 is about four times the work of the rest
  // together: round 1 runs level 0's edges beside the coarser levels' edges and fields; round 2
  // level 0's edge lines beside level 0's distance field and the coarser levels' edge lines. With
  // OpenCV's TBB backend the calling thread runs the first task of each round (not a promise of
  // cv::parallel_for_; only speed depends on it), so level 0's edge lines read level 0's
  // gradients from the cache of the core that made them.
  struct LevelScratch {
    EdgeGradients gradients;
    ImageU8 edges;
    DistanceScratch distance;
    EdgeLineScratch lines;
  };
  thread_local std::vector<LevelScratch> level_scratch;
  if (level_scratch.size() < static_cast<size_t>(built)) level_scratch.resize(static_cast<size_t>(built));
  std::vector<LevelScratch>& scratch = level_scratch;  // the calling thread's, shared with the workers
  std::vector<Status> status(static_cast<size_t>(2 * built), Status::success());
  auto edgesOf = [&](int level) {
    LiveLevel& out = frame.levels[static_cast<size_t>(level)];
    out.camera = pyramidCamera(camera, level);
    LevelScratch& sc = scratch[static_cast<size_t>(level)];
    status[static_cast<size_t>(level)] =
        detectEdgesImpl(grays[static_cast<size_t>(level)], options.detector, sc.gradients, sc.edges);
  };
  auto fieldOf = [&](int level) {
    LevelScratch& sc = scratch[static_cast<size_t>(level)];
    status[static_cast<size_t>(built + level)] =
        computeDistanceFieldInto(sc.edges, options.truncation_px, frame.levels[static_cast<size_t>(level)].field,
                                 sc.distance, options.distance_gradient);
  };
  auto linesOf = [&](int level) {
    LevelScratch& sc = scratch[static_cast<size_t>(level)];
    LiveLevel& out = frame.levels[static_cast<size_t>(level)];
    if (options.subpixel_edges) {
      computeEdgeLines(sc.edges, sc.gradients, out.edge_lines, sc.lines);
    } else {
      out.edge_lines = ImageF32{};
    }
  };
  auto twoWays = [&](const std::function<void()>& a, const std::function<void()>& b) {
    cv::parallel_for_(
        cv::Range(0, 2),
        [&](const cv::Range& r) {
          for (int i = r.start; i < r.end; ++i) (i == 0 ? a : b)();
        },
        2);
  };
  twoWays([&] { edgesOf(0); },
          [&] {
            for (int level = 1; level < built; ++level) {
              edgesOf(level);
              if (!status[static_cast<size_t>(level)].ok()) continue;
              fieldOf(level);
            }
          });
  for (const Status& st : status) VKLOC_TRY_STATUS(st);
  twoWays([&] { linesOf(0); },
          [&] {
            fieldOf(0);
            for (int level = 1; level < built; ++level) linesOf(level);
          });
  for (int level = 0; level < built; ++level) {
    LiveLevel& out = frame.levels[static_cast<size_t>(level)];
    if (options.keep_intermediate) {
      const ImageF32& g = grays[static_cast<size_t>(level)];
      out.gray.width = g.width;
      out.gray.height = g.height;
      out.gray.channels = 1;
      out.gray.data.assign(g.data.begin(), g.data.end());
      out.edges = scratch[static_cast<size_t>(level)].edges;
    } else {
      out.gray = ImageF32{};
      out.edges = ImageU8{};
    }
  }
  for (const Status& st : status) VKLOC_TRY_STATUS(st);
  return Status::success();
}

}  // namespace vkloc
