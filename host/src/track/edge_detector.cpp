// The Canny-like edge detector (Sobel / 8, contrast quantile, NMS, hysteresis) on the CPU.
#include "vkloc/track/edge_detector.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "track/edges_internal.hpp"

namespace vkloc {

using namespace track_detail;

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
  if (!finiteIn(o.noise_quantile, 0.01, 0.9)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: noise_quantile must be in 0.01..0.9");
  }
  if (!finiteIn(o.noise_sigmas, 0.0, 100.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: noise_sigmas must be in 0..100");
  }
  if (!finiteIn(o.min_high_gradient, 0.0, 1e9)) {
    return makeError(ErrorCode::kInvalidArgument, "edge detector: min_high_gradient must be >= 0 and finite");
  }
  return Status::success();
}

Result<ImageU8> detectEdges(const ImageF32& gray, const EdgeDetectorOptions& options) {
  EdgeGradients scratch;
  ImageU8 edges;
  VKLOC_TRY_STATUS(detectEdgesImpl(gray, options, scratch, edges));
  return edges;
}

double rayleighQuantileFactor(double quantile) { return std::sqrt(-2.0 * std::log(1.0 - quantile)); }

namespace track_detail {

namespace {
/// selectTwoRanks' counts, kept per thread so that repeated frames do not allocate.
std::vector<uint32_t>& countScratch() {
  thread_local std::vector<uint32_t> counts;
  return counts;
}
}  // namespace

void selectTwoRanks(const std::vector<float>& values, size_t rank_low, size_t rank_high, std::vector<float>& scratch,
                    float& low, float& high) {
  // Non-negative IEEE-754 floats order as their bit patterns read as unsigned integers (the sign
  // dropped: -0 is 0), so the top bits of the pattern are a monotonic bucket index. Bucket 0 holds
  // exact zeros alone (flat image regions: often most of a frame). One pass counts the buckets, a
  // second gathers the values of the (at most two) non-zero buckets holding the ranks, and a
  // selection among those few gives the exact values (the values a sort would put there).
  constexpr int kShift = 20;
  constexpr size_t kBins = (size_t{1} << (31 - kShift)) + 1;
  auto key = [](float v) {
    uint32_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    return bits & 0x7fffffffu;
  };
  auto bucket = [&](float v) {
    const uint32_t k = key(v);
    return k == 0 ? 0u : (k >> kShift) + 1u;
  };
  // Four interleaved counts: runs of equal values would otherwise make each increment wait for
  // the previous one to the same counter.
  std::vector<uint32_t>& counts = countScratch();
  counts.assign(4 * kBins, 0);
  const size_t n = values.size();
  size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    ++counts[bucket(values[i])];
    ++counts[kBins + bucket(values[i + 1])];
    ++counts[2 * kBins + bucket(values[i + 2])];
    ++counts[3 * kBins + bucket(values[i + 3])];
  }
  for (; i < n; ++i) ++counts[bucket(values[i])];
  for (size_t b = 0; b < kBins; ++b) counts[b] += counts[kBins + b] + counts[2 * kBins + b] + counts[3 * kBins + b];
  // Bucket of each rank and the rank's offset inside it.
  auto locate = [&](size_t rank, uint32_t& bin, size_t& offset) {
    size_t below = 0;
    for (size_t b = 0; b < kBins; ++b) {
      if (rank < below + counts[b]) {
        bin = static_cast<uint32_t>(b);
        offset = rank - below;
        return;
      }
      below += counts[b];
    }
  };
  uint32_t bin_low = 0, bin_high = 0;
  size_t offset_low = 0, offset_high = 0;
  locate(rank_low, bin_low, offset_low);
  locate(rank_high, bin_high, offset_high);
  // The low bucket's values first, then the high bucket's (when they differ); zeros need none.
  const size_t n_low = bin_low == 0 ? 0 : counts[bin_low];
  const size_t n_high = bin_high == 0 || bin_high == bin_low ? 0 : counts[bin_high];
  scratch.resize(n_low + n_high);
  if (!scratch.empty()) {
    // A bucket not gathered gets an index no value has.
    const uint32_t gather_low = n_low > 0 ? bin_low : static_cast<uint32_t>(kBins);
    const uint32_t gather_high = n_high > 0 ? bin_high : static_cast<uint32_t>(kBins);
    size_t at_low = 0;
    size_t at_high = n_low;
    for (const float v : values) {
      const uint32_t b = bucket(v);
      if (b == gather_low) {
        scratch[at_low++] = v;
      } else if (b == gather_high) {
        scratch[at_high++] = v;
      }
    }
  }
  // Values of one bucket compare as their bit patterns (NaNs included), as the buckets do.
  auto less = [&](float x, float y) { return key(x) < key(y); };
  const auto first = scratch.begin();
  auto nth = [&](size_t begin, size_t at, size_t end) {
    std::nth_element(first + static_cast<std::ptrdiff_t>(begin), first + static_cast<std::ptrdiff_t>(at),
                     first + static_cast<std::ptrdiff_t>(end), less);
    return scratch[at];
  };
  low = bin_low == 0 ? 0.0f : nth(0, offset_low, n_low);
  if (bin_high == 0) {
    high = 0.0f;
  } else if (bin_high == bin_low) {
    high = nth(offset_low, offset_high, n_low);  // the low selection left the larger values above it
  } else {
    high = nth(n_low, n_low + offset_high, n_low + n_high);
  }
}

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
  // The noise quantile lies below the contrast quantile (rank kn < k when there is one).
  const bool with_noise = options.noise_sigmas > 0.0 && k > 0;
  const size_t kn = with_noise ? std::min(k - 1, static_cast<size_t>(options.noise_quantile * (sample.size() - 1))) : k;
  float contrast_value = 0.0f;
  float noise_value = 0.0f;
  selectTwoRanks(sample, kn, k, g.candidates, noise_value, contrast_value);
  const double contrast = contrast_value;
  const double noise_floor =
      with_noise ? options.noise_sigmas * noise_value / rayleighQuantileFactor(options.noise_quantile) : 0.0;
  const float high =
      static_cast<float>(std::max({options.high_factor * contrast, options.min_high_gradient, noise_floor}));
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

}  // namespace track_detail

}  // namespace vkloc
