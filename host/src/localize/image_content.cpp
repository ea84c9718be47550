// Whether a frame holds anything to align with (see image_content.hpp).
#include "vkloc/localize/image_content.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "vkloc/core/numeric.hpp"

namespace vkloc {
namespace {

constexpr int kWidth = 80;  // the keyframe database's thumbnail (kThumbnailWidth x kThumbnailHeight)
constexpr int kHeight = 64;

}  // namespace

const char* imageContentName(ImageContent content) {
  switch (content) {
    case ImageContent::kOk:
      return "ok";
    case ImageContent::kBlack:
      return "black";
    case ImageContent::kSaturated:
      return "saturated";
    case ImageContent::kUniform:
      return "uniform";
  }
  return "?";
}

Status validateImageContentOptions(const ImageContentOptions& o) {
  if (!finiteIn(o.min_contrast, 0.0, 255.0)) {
    return makeError(ErrorCode::kInvalidArgument, "image content: min_contrast must be in 0..255");
  }
  if (!finiteIn(o.dark_level, 0.0, 255.0) || !finiteIn(o.saturated_level, 0.0, 255.0) ||
      !(o.dark_level <= o.saturated_level)) {
    return makeError(ErrorCode::kInvalidArgument, "image content: need 0 <= dark_level <= saturated_level <= 255");
  }
  return Status::success();
}

Result<ImageContentCheck> checkImageContent(const ImageU8& gray, const ImageContentOptions& options) {
  if (gray.channels != 1 || gray.width < 1 || gray.height < 1 ||
      gray.data.size() != static_cast<size_t>(gray.width) * static_cast<size_t>(gray.height)) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("image content: need a non-empty 8-bit gray image, got {}x{} with {} channel(s)",
                                 gray.width, gray.height, gray.channels));
  }
  VKLOC_TRY_STATUS(validateImageContentOptions(options));
  const int w = gray.width, h = gray.height;
  const int tw = std::min(kWidth, w), th = std::min(kHeight, h);
  // Block sums of the thumbnail (an area average: block bx holds the columns x with
  // x * tw / w == bx, [first[bx], first[bx + 1]); rows likewise), and the histogram of
  // horizontal neighbour differences, which estimates the per-pixel noise.
  std::vector<int> first(static_cast<size_t>(tw) + 1, w);
  for (int x = w - 1; x >= 0; --x) first[static_cast<size_t>(int64_t{x} * tw / w)] = x;
  std::vector<double> sums(static_cast<size_t>(tw) * th, 0.0);
  std::vector<int64_t> rows(static_cast<size_t>(th), 0);  // image rows per block row
  std::array<int64_t, 256> differences{};
  double total = 0;
  // Column sums over the rows of one block row (a vectorised add per image row), reduced to the
  // block sums when the block row ends. A column sum of 8-bit values fits in 32 bits up to 2^24
  // rows per block row (images up to 2^30 rows at the 64 block rows); every other sum is an
  // integer below 2^53, exact in double in any order.
  std::vector<uint32_t> columns(static_cast<size_t>(w), 0);
  auto flushBlockRow = [&](size_t by) {
    for (size_t bx = 0; bx < static_cast<size_t>(tw); ++bx) {
      int64_t sum = 0;
      for (int x = first[bx]; x < first[bx + 1]; ++x) sum += columns[static_cast<size_t>(x)];
      sums[by * static_cast<size_t>(tw) + bx] += static_cast<double>(sum);
      total += static_cast<double>(sum);
    }
    std::fill(columns.begin(), columns.end(), 0u);
  };
  for (int y = 0; y < h; ++y) {
    const uint8_t* row = gray.data.data() + static_cast<size_t>(y) * w;
    if (y % 4 == 0) {  // every fourth row is enough for a median
      for (int x = 1; x < w; ++x) ++differences[static_cast<size_t>(std::abs(row[x] - row[x - 1]))];
    }
    const size_t by = static_cast<size_t>(int64_t{y} * th / h);
    ++rows[by];
    for (int x = 0; x < w; ++x) columns[static_cast<size_t>(x)] += row[x];
    if (y + 1 == h || static_cast<size_t>(int64_t{y + 1} * th / h) != by) flushBlockRow(by);
  }
  double mean_sum = 0, square_sum = 0;
  for (size_t k = 0; k < sums.size(); ++k) {
    const size_t bx = k % static_cast<size_t>(tw), by = k / static_cast<size_t>(tw);
    const double v = sums[k] / static_cast<double>((first[bx + 1] - first[bx]) * rows[by]);
    mean_sum += v;
    square_sum += v * v;
  }
  const double n = static_cast<double>(sums.size());
  const double mean = mean_sum / n;
  const double variance = std::max(0.0, square_sum / n - mean * mean);
  // Per-pixel noise from the median absolute neighbour difference (robust to the few edges):
  // for Gaussian noise of sigma s the difference has sigma s sqrt(2) and median |d| 0.6745 of that.
  // The thumbnail keeps s^2 / (pixels per block) of its variance, which is taken off.
  double noise_variance = 0;
  int64_t pairs = 0;
  for (int64_t c : differences) pairs += c;
  if (pairs > 0) {
    int64_t seen = 0;
    int median = 0;
    while (median < 255 && 2 * (seen + differences[static_cast<size_t>(median)]) < pairs) {
      seen += differences[static_cast<size_t>(median)];
      ++median;
    }
    const double sigma = (median + 0.5) / (0.6745 * std::sqrt(2.0));
    const double block_pixels = static_cast<double>(w) * h / n;
    noise_variance = sigma * sigma / block_pixels;
  }
  ImageContentCheck out;
  out.mean = total / (static_cast<double>(w) * h);
  out.contrast = std::sqrt(std::max(0.0, variance - noise_variance));
  if (out.contrast < options.min_contrast) {
    out.content = out.mean < options.dark_level        ? ImageContent::kBlack
                  : out.mean > options.saturated_level ? ImageContent::kSaturated
                                                       : ImageContent::kUniform;
  }
  return out;
}

}  // namespace vkloc
