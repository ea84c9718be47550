// Internal pieces of the CPU edge stages shared by the detector, the live frame and the
// reference edges (track/edge_detector.cpp, live_frame.cpp, reference_edges.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

#include "vkloc/core/image.hpp"
#include "vkloc/core/numeric.hpp"
#include "vkloc/track/edge_detector.hpp"

namespace vkloc::track_detail {

inline cv::Mat wrap(const ImageF32& image) {
  return cv::Mat(image.height, image.width, CV_32FC(image.channels), const_cast<float*>(image.data.data()));
}

/// True when x is a multiple of 8 and row[x .. x + 7] lie before `end` and are all 0: scans of
/// sparse edge maps pass over eight pixels at a time.
inline bool eightClear(const uint8_t* row, int x, int end) {
  if ((x & 7) != 0 || x + 8 > end) return false;
  uint64_t word;
  std::memcpy(&word, row + x, sizeof word);
  return word == 0;
}

/// Sobel / 8 gradients and magnitude of the image edges were detected on, and the detector's
/// other working buffers (kept between calls so that repeated frames do not allocate).
struct EdgeGradients {
  cv::Mat gx, gy, mag;
  std::vector<float> sample;
  std::vector<float> candidates;  ///< selectTwoRanks' working buffer.
  std::vector<uint8_t> state;
  std::vector<int> strong;  ///< Pixels (y w + x) at or above the high threshold, row-major.
  std::vector<int> stack;
};

/// The values of ranks rank_low <= rank_high (0-based, ascending) among `values`, all >= 0 (or
/// NaN, which ranks above +inf; -0 counts as +0): for values without NaN, exactly the values a
/// sort would put there, in about two linear passes. `values` must not be empty and rank_high < values.size();
/// `scratch` is working memory.
void selectTwoRanks(const std::vector<float>& values, size_t rank_low, size_t rank_high, std::vector<float>& scratch,
                    float& low, float& high);

/// Gives `image` the size w x h x c with every value `fill`, reusing its memory.
template <typename T>
inline void resetImage(Image<T>& image, int w, int h, int c, T fill) {
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

/// detectEdges into `edges`, leaving the gradients in `g` (which keeps its buffers between calls).
Status detectEdgesImpl(const ImageF32& gray, const EdgeDetectorOptions& options, EdgeGradients& g, ImageU8& edges);

}  // namespace vkloc::track_detail
