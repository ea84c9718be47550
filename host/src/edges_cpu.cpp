// CPU backend of the edge stages declared in edges.hpp.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "vkloc/edges.hpp"

namespace vkloc {
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

cv::Mat wrap(const ImageF32& image) {
  return cv::Mat(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.data.data()));
}

bool finiteIn(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

/// True when two depths (metres, > 0) are on the same surface: no discontinuity.
bool continuous(float a, float b, double ratio) {
  return std::abs(static_cast<double>(a) - b) <= ratio * std::min(a, b);
}

}  // namespace

// --- edge detection --------------------------------------------------------------------------

Status validateEdgeDetectorOptions(const EdgeDetectorOptions& o) {
  if (!finiteIn(o.contrast_percentile, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: contrast_percentile must be in 0..1");
  }
  if (!finiteIn(o.high_factor, 1e-6, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: high_factor must be in 1e-6..1e6");
  }
  if (!finiteIn(o.low_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: low_ratio must be in 0..1");
  }
  if (!finiteIn(o.min_high_gradient, 0.0, 1e9)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: min_high_gradient must be >= 0 and finite");
  }
  return Status::success();
}

namespace {

/// Sobel / 8 gradients and magnitude of the image edges were detected on, and the detector's
/// other working buffers (kept between calls so that repeated frames do not allocate).
struct EdgeGradients {
  cv::Mat gx, gy, mag;
  std::vector<float> sample;
  std::vector<uint8_t> state;
  std::vector<int> strong;  ///< Pixels (y w + x) at or above the high threshold, row-major.
  std::vector<int> stack;
};

/// Gives `image` the size w x h x c with every value `fill`, reusing its memory.
template <typename T>
void resetImage(Image<T>& image, int w, int h, int c, T fill) {
  image.width = w;
  image.height = h;
  image.channels = c;
  image.data.assign(static_cast<size_t>(w) * h * c, fill);
}

/// Step (dx, dy) of the non-maximum suppression direction of a gradient (gx, gy): the gradient
/// direction quantised to 4 directions.
inline void nmsDirection(float gx, float gy, int& dx, int& dy) {
  const float tan22 = 0.41421356f;  // tan(22.5 deg)
  const float ax = std::abs(gx);
  const float ay = std::abs(gy);
  if (ay <= tan22 * ax) {
    dx = 1;
    dy = 0;
  } else if (ax <= tan22 * ay) {
    dx = 0;
    dy = 1;
  } else if ((gx > 0) == (gy > 0)) {
    dx = 1;
    dy = 1;
  } else {
    dx = -1;
    dy = 1;
  }
}

/// Sub-pixel position of the edge through interior pixel (x, y), relative to its centre: the
/// vertex of the parabola through the gradient magnitudes at the pixel and its two neighbours
/// along the suppression direction (|offset| <= half a step; an ideal step's symmetric 2-pixel
/// edge gives the point between both pixels).
inline void subpixelOffset(const EdgeGradients& g, int x, int y, float& du, float& dv) {
  int dx = 0, dy = 0;
  nmsDirection(g.gx.at<float>(y, x), g.gy.at<float>(y, x), dx, dy);
  const float m0 = g.mag.at<float>(y, x);
  const float a = g.mag.at<float>(y - dy, x - dx);
  const float b = g.mag.at<float>(y + dy, x + dx);
  const float denominator = a - 2.0f * m0 + b;
  float t = denominator < 0 ? 0.5f * (a - b) / denominator : 0.0f;
  t = std::clamp(t, -0.5f, 0.5f);
  du = t * static_cast<float>(dx);
  dv = t * static_cast<float>(dy);
}

Status detectEdgesImpl(const ImageF32& gray, const EdgeDetectorOptions& options, EdgeGradients& g, ImageU8& edges);

}  // namespace

Result<ImageU8> detectEdges(const ImageF32& gray, const EdgeDetectorOptions& options) {
  EdgeGradients scratch;
  ImageU8 edges;
  VKLOC_TRY_STATUS(detectEdgesImpl(gray, options, scratch, edges));
  return edges;
}

namespace {

/// detectEdges into `edges`, leaving the gradients in `g`.
Status detectEdgesImpl(const ImageF32& gray, const EdgeDetectorOptions& options, EdgeGradients& g, ImageU8& edges) {
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(options));
  if (gray.empty() || gray.channels != 1 || gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument, "detectEdges: expected a non-empty single-channel image");
  }
  const int w = gray.width;
  const int h = gray.height;
  const cv::Mat src = wrap(gray);
  cv::Mat& gx = g.gx;
  cv::Mat& gy = g.gy;
  cv::Mat& mag = g.mag;
  cv::Sobel(src, gx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::Sobel(src, gy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0, cv::BORDER_REPLICATE);
  cv::magnitude(gx, gy, mag);

  // Contrast: quantile of the magnitude over a 2x2-strided sample of the pixels.
  std::vector<float>& sample = g.sample;
  sample.clear();
  sample.reserve(static_cast<size_t>((w + 1) / 2) * ((h + 1) / 2));
  for (int y = 0; y < h; y += 2) {
    const float* row = mag.ptr<float>(y);
    for (int x = 0; x < w; x += 2) sample.push_back(row[x]);
  }
  const size_t k = std::min(sample.size() - 1, static_cast<size_t>(options.contrast_percentile * (sample.size() - 1)));
  std::nth_element(sample.begin(), sample.begin() + static_cast<std::ptrdiff_t>(k), sample.end());
  const double contrast = sample[k];
  const float high = static_cast<float>(std::max(options.high_factor * contrast, options.min_high_gradient));
  const float low = static_cast<float>(options.low_ratio * high);

  // Non-maximum suppression: 0 = suppressed, 1 = weak candidate, 2 = strong.
  std::vector<uint8_t>& state = g.state;
  state.assign(static_cast<size_t>(w) * h, 0);
  std::vector<int>& strong = g.strong;
  strong.clear();
  const float tan22 = 0.41421356f;  // tan(22.5 deg)
  for (int y = 1; y < h - 1; ++y) {
    const float* m0 = mag.ptr<float>(y - 1);
    const float* m1 = mag.ptr<float>(y);
    const float* m2 = mag.ptr<float>(y + 1);
    const float* dx = gx.ptr<float>(y);
    const float* dy = gy.ptr<float>(y);
    for (int x = 1; x < w - 1; ++x) {
      const float m = m1[x];
      if (m < low || m <= 0.0f) continue;
      const float ax = std::abs(dx[x]);
      const float ay = std::abs(dy[x]);
      float a = 0, b = 0;
      if (ay <= tan22 * ax) {
        a = m1[x - 1];
        b = m1[x + 1];
      } else if (ax <= tan22 * ay) {
        a = m0[x];
        b = m2[x];
      } else if ((dx[x] > 0) == (dy[x] > 0)) {
        a = m0[x - 1];
        b = m2[x + 1];
      } else {
        a = m0[x + 1];
        b = m2[x - 1];
      }
      if (m >= a && m >= b && (m > a || m > b)) {
        const int i = y * w + x;
        state[static_cast<size_t>(i)] = m >= high ? 2 : 1;
        if (m >= high) strong.push_back(i);
      }
    }
  }

  // Hysteresis: grow from strong pixels through 8-connected weak ones.
  resetImage<uint8_t>(edges, w, h, 1, 0);
  std::vector<int>& stack = g.stack;
  stack.clear();
  for (const int i : strong) {
    if (edges.data[i] != 0) continue;  // reached from an earlier strong pixel
    edges.data[i] = 255;
    stack.push_back(i);
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      const int px = p % w;
      const int py = p / w;
      for (int dy2 = -1; dy2 <= 1; ++dy2) {
        for (int dx2 = -1; dx2 <= 1; ++dx2) {
          const int qx = px + dx2;
          const int qy = py + dy2;
          if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
          const int q = qy * w + qx;
          if (state[q] == 0 || edges.data[q] != 0) continue;
          edges.data[q] = 255;
          stack.push_back(q);
        }
      }
    }
  }
  return Status::success();
}

}  // namespace

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
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
// Wider vectors where the CPU has them (chosen once at load time; the baseline build is SSE2).
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

/// computeDistanceField into `field`, reusing its memory and the scratch.
Status computeDistanceFieldInto(const ImageU8& edges, float truncation_px, DistanceField& field, DistanceScratch& sc) {
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
  size(field.gradient, w, h, 2);
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
  computeDistanceGradient(field);
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

/// LiveLevel::edge_lines of an edge map: every edge pixel splats its sub-pixel line into the
/// pixels within kEdgeLineRadiusPx of its edge point; a pixel keeps the nearest edge point.
void computeEdgeLines(const ImageU8& edges, const EdgeGradients& g, ImageF32& lines, std::vector<float>& best) {
  const int w = edges.width;
  const int h = edges.height;
  resetImage(lines, w, h, 3, 0.0f);
  best.assign(static_cast<size_t>(w) * h, kEdgeLineRadiusPx * kEdgeLineRadiusPx);
  const int r = static_cast<int>(std::ceil(kEdgeLineRadiusPx));
  for (int y = 1; y < h - 1; ++y) {
    const uint8_t* row = &edges.data[static_cast<size_t>(y) * w];
    for (int x = 1; x < w - 1; ++x) {
      if (!row[x]) continue;
      const float gx = g.gx.at<float>(y, x);
      const float gy = g.gy.at<float>(y, x);
      const float m = std::sqrt(gx * gx + gy * gy);
      if (!(m > 0)) continue;
      const float nu = gx / m;
      const float nv = gy / m;
      float du = 0, dv = 0;
      subpixelOffset(g, x, y, du, dv);
      const float eu = static_cast<float>(x) + du;
      const float ev = static_cast<float>(y) + dv;
      for (int qy = std::max(y - r, 0); qy <= std::min(y + r, h - 1); ++qy) {
        for (int qx = std::max(x - r, 0); qx <= std::min(x + r, w - 1); ++qx) {
          const float ou = static_cast<float>(qx) - eu;
          const float ov = static_cast<float>(qy) - ev;
          const float d2 = ou * ou + ov * ov;
          float& b = best[static_cast<size_t>(qy) * w + qx];
          if (d2 >= b) continue;
          b = d2;
          float* out = &lines.data[(static_cast<size_t>(qy) * w + qx) * 3];
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
      resetImage(level_gray, gray.width, gray.height, 1, 0.0f);
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
  // Per level: edges (with their gradients), then the distance field and the edge lines, which
  // both read only the edges. Level 0 is about four times the work of the rest together: round 1
  // runs level 0's edges beside the coarser levels' edges and fields; round 2 level 0's distance
  // field and the coarser levels' edge lines beside level 0's edge lines.
  struct LevelScratch {
    EdgeGradients gradients;
    ImageU8 edges;
    DistanceScratch distance;
    std::vector<float> best;
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
    status[static_cast<size_t>(built + level)] = computeDistanceFieldInto(
        sc.edges, options.truncation_px, frame.levels[static_cast<size_t>(level)].field, sc.distance);
  };
  auto linesOf = [&](int level) {
    LevelScratch& sc = scratch[static_cast<size_t>(level)];
    LiveLevel& out = frame.levels[static_cast<size_t>(level)];
    if (options.subpixel_edges) {
      computeEdgeLines(sc.edges, sc.gradients, out.edge_lines, sc.best);
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
  twoWays(
      [&] {
        fieldOf(0);
        for (int level = 1; level < built; ++level) linesOf(level);
      },
      [&] { linesOf(0); });
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

/// The reference view at one pyramid level: gray (0..255), depth (m), normals (3 channels).
struct ReferenceLevel {
  ImageF32 gray;
  ImageF32 depth;
  ImageF32 normals;
};

/// Halves a reference level: gray as the live pyramid (downsampleHalf), depth and normals of
/// the nearest surface among the 2x2 input pixels an output pixel covers.
ReferenceLevel downsampleReference(const ReferenceLevel& in) {
  ReferenceLevel out;
  out.gray = downsampleHalf(in.gray);
  const int w = out.gray.width;
  const int h = out.gray.height;
  out.depth = ImageF32(w, h, 1, 0.0f);
  const bool normals = in.normals.channels == 3 && in.normals.width == in.depth.width;
  if (normals) out.normals = ImageF32(w, h, 3, 0.0f);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float best = 0;
      int bx = -1, by = -1;
      for (int dy = 0; dy < 2; ++dy) {
        for (int dx = 0; dx < 2; ++dx) {
          const int sx = std::min(2 * x + dx, in.depth.width - 1);
          const int sy = std::min(2 * y + dy, in.depth.height - 1);
          const float z = in.depth.at(sx, sy);
          if (z > 0 && std::isfinite(z) && (best == 0 || z < best)) {
            best = z;
            bx = sx;
            by = sy;
          }
        }
      }
      out.depth.at(x, y) = best;
      if (normals && bx >= 0) {
        for (int c = 0; c < 3; ++c) out.normals.at(x, y, c) = in.normals.at(bx, by, c);
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
    if (zb > 0 && std::isfinite(zb) && continuous(zp, zb, ratio)) diz = izp - 1.0 / zb;
  }
  for (int k = 2; k <= gap; ++k) {
    const int qx = x + k * sx;
    const int qy = y + k * sy;
    if (qx < 0 || qy < 0 || qx >= D.width || qy >= D.height) return false;
    const double iz = izp + k * diz;
    if (!(iz > 0)) return false;
    const float zq = D.at(qx, qy);
    if (zq > 0 && std::isfinite(zq) && continuous(static_cast<float>(1.0 / iz), zq, ratio)) return true;
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
    const bool sp = zp > 0 && std::isfinite(zp);
    const bool sq = zq > 0 && std::isfinite(zq);
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
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        uint8_t& f = flags.at(x, y);
        for (const EdgeDirection& side : kOcclusionDirections) {
          if (!(f & side.flag)) continue;
          if (!nearSurfaceResumes(D, x, y, side.dx, side.dy, options.hole_gap_px, ratio)) continue;
          f &= static_cast<uint8_t>(~side.flag);
          hole_rim.at(x, y) = 1;
          const int qx = x + side.dx;
          const int qy = y + side.dy;
          if (qx >= 0 && qy >= 0 && qx < w && qy < h) hole_rim.at(qx, qy) = 1;
        }
      }
    }
  }
  return GeometricFlags{std::move(flags), std::move(hole_rim)};
}

void textureReferenceEdges(const ReferenceLevel& view, const ReferenceEdgeOptions& options, TextureEdges& out) {
  out.status = detectEdgesImpl(view.gray, options.detector, out.gradients, out.edges);
}

/// Stage 1 (detectReferenceEdges) from its two halves; when texture_offsets is given it
/// receives, per texture edge pixel, the sub-pixel offset (du, dv) of the edge from the pixel
/// centre (2 channels, pixels). `texture` is null without texture edges.
ImageU8 mergeReferenceEdges(const ReferenceLevel& view, GeometricFlags geometric_flags, const TextureEdges* texture,
                            ImageF32* texture_offsets) {
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
  if (texture_offsets) *texture_offsets = ImageF32(w, h, 2, 0.0f);
  // A geometric edge that shows in the gray image is represented by its texture edge pixels
  // (found by the same detector as the live image's edges, so both place it alike); the
  // geometric flags next to such pixels are dropped.
  ImageU8 geometric = flags;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!edges->at(x, y)) continue;
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
      if (has_surface && !nearHoleRim(x, y)) {
        flags.at(x, y) |= kEdgePixelTexture;
        if (texture_offsets) {
          subpixelOffset(texture->gradients, x, y, texture_offsets->at(x, y, 0), texture_offsets->at(x, y, 1));
        }
      }
    }
  }
  return flags;
}

Result<ImageU8> detectReferenceEdgesImpl(const ReferenceLevel& view, const ReferenceEdgeOptions& options,
                                         ImageF32* texture_offsets = nullptr) {
  GeometricFlags geometric = geometricReferenceFlags(view, options);
  if (!options.texture_edges) return mergeReferenceEdges(view, std::move(geometric), nullptr, texture_offsets);
  TextureEdges texture;
  textureReferenceEdges(view, options, texture);
  VKLOC_TRY_STATUS(texture.status);
  return mergeReferenceEdges(view, std::move(geometric), &texture, texture_offsets);
}

}  // namespace

Result<ImageU8> detectReferenceEdges(const RenderOutput& view, const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceEdgeOptions(options));
  if (view.depth.empty() || view.depth.channels != 1 || view.gray.width != view.depth.width ||
      view.gray.height != view.depth.height || view.gray.channels != 1 || view.gray.empty()) {
    return makeError(ErrorCode::kInvalidArgument,
                     "detectReferenceEdges: view needs a gray image and a depth image of the same size");
  }
  return detectReferenceEdgesImpl(ReferenceLevel{toFloat(view.gray), view.depth, view.normals}, options);
}

namespace {

/// Stage 2 (backProjectEdges); texture edge points are moved by texture_offsets when given.
std::vector<EdgePoint> backProjectEdgesImpl(const ImageU8& flags, const ImageF32& depth, const PinholeCamera& camera,
                                            const ReferenceEdgeOptions& options, const ImageF32* texture_offsets) {
  std::vector<EdgePoint> points;
  const int w = flags.width;
  const int h = flags.height;
  if (depth.width != w || depth.height != h || depth.channels != 1 || flags.channels != 1) return points;
  const double ratio = options.depth_jump_ratio;
  auto depthAt = [&](int x, int y) -> float {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0.0f;
    const float z = depth.at(x, y);
    return std::isfinite(z) && z > 0 ? z : 0.0f;
  };
  int px = 0, py = 0;  // pixel whose flags are emitted
  auto nearBackground = [&]() {
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        const int nx = px + dx;
        const int ny = py + dy;
        if (nx >= 0 && ny >= 0 && nx < w && ny < h && depthAt(nx, ny) <= 0) return true;
      }
    }
    return false;
  };
  auto emit = [&](double u, double v, double z, uint32_t kind) {
    // Eq. 3: P = pi^-1(u, Z) with metric depth Z (camera z).
    if (nearBackground()) kind |= kEdgeBackground;
    EdgePoint p;
    p.x = static_cast<float>(z * (u - camera.cx) / camera.fx);
    p.y = static_cast<float>(z * (v - camera.cy) / camera.fy);
    p.z = static_cast<float>(z);
    p.kind = kind;
    points.push_back(p);
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const uint8_t f = flags.at(x, y);
      if (!f) continue;
      px = x;
      py = y;
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
          const bool offset = texture_offsets && texture_offsets->width == w && texture_offsets->height == h;
          emit(x + (offset ? texture_offsets->at(x, y, 0) : 0.0), y + (offset ? texture_offsets->at(x, y, 1) : 0.0), z,
               kEdgeTexture);
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
  return backProjectEdgesImpl(flags, depth, camera, options, nullptr);
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
  cv::parallel_for_(
      cv::Range(0, tasks),
      [&](const cv::Range& range) {
        for (int t = range.start; t < range.end; ++t) {
          const size_t k = static_cast<size_t>(t / (options.texture_edges ? 2 : 1));
          if (options.texture_edges && t % 2 == 1) {
            textureReferenceEdges(levels[k], options, texture[k]);
          } else {
            geometric[k] = geometricReferenceFlags(levels[k], options);
          }
        }
      },
      tasks);
  for (const TextureEdges& t : texture) VKLOC_TRY_STATUS(t.status);
  cv::parallel_for_(
      cv::Range(0, n),
      [&](const cv::Range& range) {
        for (int k = range.start; k < range.end; ++k) {
          const size_t i = static_cast<size_t>(k);
          const ReferenceLevel& level = levels[i];
          const PinholeCamera level_camera = pyramidCamera(camera, k);
          ImageF32 offsets;
          const ImageU8 flags = mergeReferenceEdges(level, std::move(geometric[i]),
                                                    options.texture_edges ? &texture[i] : nullptr, &offsets);
          points[i] = subsampleEdgePoints(backProjectEdgesImpl(flags, level.depth, level_camera, options, &offsets),
                                          level_camera, options);
        }
      },
      n);
  ref.points = std::move(points[0]);
  for (int k = 1; k < n; ++k) ref.coarse_points.push_back(std::move(points[static_cast<size_t>(k)]));
  return ref;
}

}  // namespace

Result<EdgeReference> buildEdgeReference(const RenderOutput& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceView(view, camera, T_world_ref, options));
  return buildEdgeReferenceFrom(ReferenceLevel{toFloat(view.gray), view.depth, view.normals}, camera, T_world_ref,
                                options);
}

Result<EdgeReference> buildEdgeReference(RenderOutput&& view, const PinholeCamera& camera, const Pose& T_world_ref,
                                         const ReferenceEdgeOptions& options) {
  VKLOC_TRY_STATUS(validateReferenceView(view, camera, T_world_ref, options));
  return buildEdgeReferenceFrom(ReferenceLevel{toFloat(view.gray), std::move(view.depth), std::move(view.normals)},
                                camera, T_world_ref, options);
}

}  // namespace vkloc
