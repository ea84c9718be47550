// Tests of the CPU edge stages (edges.hpp): edge detector, pyramid, distance fields and
// reference edge points, against brute force and analytic scenes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>

#include "support/analytic_scenes.hpp"
#include "track/edges_internal.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {
namespace {

ImageU8 randomEdgeMap(int w, int h, double density, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ImageU8 edges(w, h, 1, 0);
  for (auto& e : edges.data) e = u(rng) < density ? 255 : 0;
  return edges;
}

TEST(EdgeDistanceField, MatchesBruteForceEuclideanDistance) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    for (double density : {0.002, 0.02, 0.2}) {
      const ImageU8 edges = randomEdgeMap(61, 47, density, seed);
      const float trunc = 12.0f;
      auto field = computeDistanceField(edges, trunc);
      ASSERT_TRUE(field.ok()) << field.error().message;
      std::vector<std::pair<int, int>> pts;
      for (int y = 0; y < edges.height; ++y) {
        for (int x = 0; x < edges.width; ++x) {
          if (edges.at(x, y)) pts.emplace_back(x, y);
        }
      }
      double max_err = 0;
      for (int y = 0; y < edges.height; ++y) {
        for (int x = 0; x < edges.width; ++x) {
          double best = 1e30;
          for (const auto& [px, py] : pts) best = std::min(best, std::hypot(x - px, y - py));
          best = std::min(best, static_cast<double>(trunc));
          max_err = std::max(max_err, std::abs(best - field->distance.at(x, y)));
        }
      }
      EXPECT_LT(max_err, 1e-3) << "seed " << seed << " density " << density;
    }
  }
}

// The CPU field uses a separable transform that looks only ceil(truncation) - 1 pixels each way
// (OpenCV's precise transform above 128 px): it must give OpenCV's values bit for bit wherever
// those are below the truncation, at every truncation, density and shape, borders included.
TEST(EdgeDistanceField, EqualsOpenCvPreciseTransformAtEveryTruncation) {
  struct Case {
    int w, h;
    double density;
  };
  const Case cases[] = {{640, 480, 0.01}, {640, 480, 0.0003}, {97, 13, 0.05},
                        {1, 50, 0.1},     {50, 1, 0.1},       {33, 29, 0.9}};
  int compared = 0;
  for (const Case& c : cases) {
    for (uint32_t seed : {7u, 8u}) {
      ImageU8 edges = randomEdgeMap(c.w, c.h, c.density, seed);
      edges.at(0, 0) = 255;  // an edge on the border, and one in the last pixel
      edges.at(c.w - 1, c.h - 1) = 255;
      cv::Mat inverted(c.h, c.w, CV_8U);
      for (int y = 0; y < c.h; ++y) {
        for (int x = 0; x < c.w; ++x) inverted.at<uint8_t>(y, x) = edges.at(x, y) ? 0 : 255;
      }
      cv::Mat exact;
      cv::distanceTransform(inverted, exact, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
      for (float trunc : {0.5f, 1.0f, 2.5f, 7.0f, 20.0f, 128.0f, 128.5f, 300.0f}) {
        auto field = computeDistanceField(edges, trunc);
        ASSERT_TRUE(field.ok()) << field.error().message;
        int mismatches = 0;
        for (int y = 0; y < c.h; ++y) {
          for (int x = 0; x < c.w; ++x) {
            const float want = std::min(exact.at<float>(y, x), trunc);
            mismatches += field->distance.at(x, y) != want;
          }
        }
        EXPECT_EQ(mismatches, 0) << c.w << "x" << c.h << " density " << c.density << " seed " << seed << " truncation "
                                 << trunc;
        ++compared;
      }
    }
  }
  EXPECT_EQ(compared, 6 * 2 * 8);
}

TEST(EdgeDistanceField, GradientPointsAwayFromTheNearestEdge) {
  // One edge pixel: the exact distance is |p - e| with gradient (p - e) / |p - e|; central
  // differences of the exact field differ from it by O(1 / r^2).
  ImageU8 edges(80, 60, 1, 0);
  edges.at(37, 22) = 255;
  auto field = computeDistanceField(edges, 100.0f);
  ASSERT_TRUE(field.ok());
  int checked = 0;
  for (int y = 1; y < 59; ++y) {
    for (int x = 1; x < 79; ++x) {
      const double dx = x - 37, dy = y - 22;
      const double r = std::hypot(dx, dy);
      if (r < 6) continue;
      EXPECT_NEAR(field->gradient.at(x, y, 0), dx / r, 0.02) << x << "," << y;
      EXPECT_NEAR(field->gradient.at(x, y, 1), dy / r, 0.02) << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 4000);
  // Truncation: far pixels are clamped and carry no gradient.
  auto truncated = computeDistanceField(edges, 5.0f);
  ASSERT_TRUE(truncated.ok());
  EXPECT_FLOAT_EQ(truncated->distance.at(70, 50), 5.0f);
  EXPECT_FLOAT_EQ(truncated->gradient.at(70, 50, 0), 0.0f);
  EXPECT_FLOAT_EQ(truncated->gradient.at(70, 50, 1), 0.0f);
}

TEST(EdgeDistanceField, NoEdgesAndBadInput) {
  auto field = computeDistanceField(ImageU8(10, 8, 1, 0), 7.0f);
  ASSERT_TRUE(field.ok());
  for (float d : field->distance.data) EXPECT_EQ(d, 7.0f);
  EXPECT_FALSE(computeDistanceField(ImageU8(), 7.0f).ok());
  EXPECT_FALSE(computeDistanceField(ImageU8(4, 4, 1, 0), 0.0f).ok());
  EXPECT_FALSE(computeDistanceField(ImageU8(4, 4, 3, 0), 1.0f).ok());
}

/// A synthetic scene: random rectangles of random gray on a mid-gray background, slightly
/// blurred, with mild noise. Values 0..255 as floats.
ImageF32 syntheticScene(int w, int h, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> gray(30, 225);
  std::uniform_int_distribution<int> px(0, w - 1), py(0, h - 1), size(8, 60);
  ImageF32 img(w, h, 1, 120.0f);
  for (int k = 0; k < 25; ++k) {
    const int x0 = px(rng), y0 = py(rng), sx = size(rng), sy = size(rng);
    const float g = static_cast<float>(gray(rng));
    for (int y = y0; y < std::min(h, y0 + sy); ++y) {
      for (int x = x0; x < std::min(w, x0 + sx); ++x) img.at(x, y) = g;
    }
  }
  // [1 2 1] / 4 blur in both directions, then noise of sigma 1 gray level.
  ImageF32 tmp = img;
  for (int y = 0; y < h; ++y) {
    for (int x = 1; x < w - 1; ++x)
      tmp.at(x, y) = 0.25f * img.at(x - 1, y) + 0.5f * img.at(x, y) + 0.25f * img.at(x + 1, y);
  }
  img = tmp;
  for (int y = 1; y < h - 1; ++y) {
    for (int x = 0; x < w; ++x)
      img.at(x, y) = 0.25f * tmp.at(x, y - 1) + 0.5f * tmp.at(x, y) + 0.25f * tmp.at(x, y + 1);
  }
  std::normal_distribution<float> noise(0.0f, 1.0f);
  for (float& v : img.data) v = std::clamp(v + noise(rng), 0.0f, 255.0f);
  return img;
}

ImageF32 quantised(ImageF32 img) {
  for (float& v : img.data) v = std::round(std::clamp(v, 0.0f, 255.0f));
  return img;
}

/// Fraction of edge pixels of `a` with an edge pixel of `b` within one pixel (8-neighbourhood).
double keptFraction(const ImageU8& a, const ImageU8& b) {
  int total = 0, kept = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      if (!a.at(x, y)) continue;
      ++total;
      bool found = false;
      for (int dy = -1; dy <= 1 && !found; ++dy) {
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          const int nx = x + dx, ny = y + dy;
          found = nx >= 0 && ny >= 0 && nx < a.width && ny < a.height && b.at(nx, ny);
        }
      }
      kept += found;
    }
  }
  return total ? static_cast<double>(kept) / total : 0.0;
}

// The detector's quantiles: both ranks equal a full sort's values on gradient-like samples
// (many exact zeros, ties, a long tail), at the ends, on one repeated value and beside +inf.
TEST(EdgeDetector, RankSelectionEqualsSorting) {
  std::mt19937 rng(7);
  std::vector<float> scratch;
  for (int trial = 0; trial < 40; ++trial) {
    const size_t n = 1 + static_cast<size_t>(rng() % 5000);
    std::vector<float> values(n);
    std::exponential_distribution<float> tail(0.05f);
    for (float& v : values) {
      const uint32_t pick = rng() % 10;
      v = pick < 3 ? 0.0f : pick == 3 ? static_cast<float>(rng() % 4) : tail(rng);
    }
    if (trial == 1) std::fill(values.begin(), values.end(), 2.5f);
    if (trial == 2) values.back() = std::numeric_limits<float>::infinity();
    if (trial == 3) values.front() = -0.0f;
    std::vector<float> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    const std::vector<std::pair<size_t, size_t>> ranks = {{0, 0},         {0, n - 1},     {n - 1, n - 1},
                                                          {n / 3, n / 2}, {n / 2, n / 2}, {n / 10, (9 * n) / 10}};
    for (const auto& [a, b] : ranks) {
      float low = -1.0f, high = -1.0f;
      track_detail::selectTwoRanks(values, a, b, scratch, low, high);
      ASSERT_EQ(low, sorted[a]) << "trial " << trial << " n " << n << " rank " << a;
      ASSERT_EQ(high, sorted[b]) << "trial " << trial << " n " << n << " rank " << b;
    }
  }
}

TEST(EdgeDetector, EdgesSurviveExposureAndGammaChanges) {
  const ImageF32 base = quantised(syntheticScene(320, 240, 5));
  auto edges = detectEdges(base);
  ASSERT_TRUE(edges.ok());
  int count = 0;
  for (uint8_t e : edges->data) count += e != 0;
  ASSERT_GT(count, 1000);
  ImageF32 half = base, gamma_dark = base, gamma_bright = base;
  for (size_t i = 0; i < base.data.size(); ++i) {
    half.data[i] = 0.5f * base.data[i];
    gamma_dark.data[i] = 255.0f * std::pow(base.data[i] / 255.0f, 1.5f);
    gamma_bright.data[i] = 255.0f * std::pow(base.data[i] / 255.0f, 1.0f / 1.5f);
  }
  for (const ImageF32* changed : {&half, &gamma_dark, &gamma_bright}) {
    auto other = detectEdges(quantised(*changed));
    ASSERT_TRUE(other.ok());
    EXPECT_GE(keptFraction(*edges, *other), 0.95) << (changed == &half         ? "half"
                                                      : changed == &gamma_dark ? "dark"
                                                                               : "bright");
    EXPECT_GE(keptFraction(*other, *edges), 0.95);  // and no flood of new edges
  }
  // A fixed threshold would not pass: the same detector with a fixed absolute threshold (the
  // floor dominates) loses many edges of the half-exposure image.
  EdgeDetectorOptions fixed;
  fixed.high_factor = 1e-6;
  fixed.min_high_gradient = 12.0;
  auto fixed_base = detectEdges(base, fixed);
  auto fixed_half = detectEdges(quantised(half), fixed);
  ASSERT_TRUE(fixed_base.ok() && fixed_half.ok());
  EXPECT_LT(keptFraction(*fixed_base, *fixed_half), 0.95);
}

// A plain wall under sensor noise: the contrast quantile alone lies inside the noise and turns it
// into edges; the noise floor keeps the wall empty and still finds a real step in the same noise.
TEST(EdgeDetector, NoiseFloorKeepsPlainNoisyWallsEmptyAndRealStepsFound) {
  const int w = 320, h = 240;
  Xoshiro256 rng(7);
  ImageF32 wall(w, h, 1), step(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float noise = static_cast<float>(3.0 * rng.gaussian());  // 3 gray levels, 1 sigma
      wall.at(x, y) = 128.0f + noise;
      step.at(x, y) = (x >= w / 2 ? 158.0f : 128.0f) + noise;  // a 30-level step
    }
  }
  auto edgeFraction = [&](const ImageU8& e) {
    int n = 0;
    for (uint8_t v : e.data) n += v != 0;
    return static_cast<double>(n) / (w * h);
  };
  EdgeDetectorOptions no_floor;
  no_floor.noise_sigmas = 0.0;
  auto noisy = detectEdges(wall, no_floor);
  auto floored = detectEdges(wall);
  ASSERT_TRUE(noisy.ok() && floored.ok());
  EXPECT_GT(edgeFraction(*noisy), 0.03) << "without the floor, noise becomes edges";
  EXPECT_LT(edgeFraction(*floored), 0.001) << "with it, a plain wall has (almost) none";
  auto with_step = detectEdges(step);
  ASSERT_TRUE(with_step.ok());
  int on_step = 0;
  for (int y = 2; y < h - 2; ++y) on_step += with_step->at(w / 2 - 1, y) != 0 || with_step->at(w / 2, y) != 0;
  EXPECT_GE(on_step, (h - 4) * 95 / 100) << "the step stays an edge along its whole length";
  EXPECT_LT(edgeFraction(*with_step), 3.0 * h / (w * h)) << "and little else is";
  // The floor scales with the image (a gain multiplies noise and step alike).
  ImageF32 bright = step;
  for (float& v : bright.data) v *= 1.5f;
  auto with_gain = detectEdges(bright);
  ASSERT_TRUE(with_gain.ok());
  EXPECT_NEAR(edgeFraction(*with_gain), edgeFraction(*with_step), 0.1 * edgeFraction(*with_step));
  EdgeDetectorOptions bad;
  bad.noise_quantile = 0.95;
  EXPECT_FALSE(detectEdges(wall, bad).ok());
  EXPECT_NEAR(rayleighQuantileFactor(0.5), std::sqrt(2.0 * std::log(2.0)), 1e-12);
}

TEST(EdgeDetector, IdealStepGivesSymmetricTwoPixelEdge) {
  ImageF32 img(32, 24, 1, 50.0f);
  for (int y = 0; y < 24; ++y) {
    for (int x = 16; x < 32; ++x) img.at(x, y) = 200.0f;
  }
  auto edges = detectEdges(img);
  ASSERT_TRUE(edges.ok());
  for (int y = 1; y < 23; ++y) {
    for (int x = 0; x < 32; ++x) EXPECT_EQ(edges->at(x, y) != 0, x == 15 || x == 16) << x << "," << y;
  }
  EXPECT_FALSE(detectEdges(ImageF32()).ok());
  EdgeDetectorOptions bad;
  bad.low_ratio = 2.0;
  EXPECT_FALSE(detectEdges(img, bad).ok());
}

TEST(EdgePyramid, DownsampleIsConsistentWithPyramidCamera) {
  // A linear ramp f(u) = 3u + 2v + 1 keeps its values at the pixel centres of the level
  // camera: the output at (i, j) must equal f at the input coordinates of that centre.
  PinholeCamera cam;
  cam.width = 64;
  cam.height = 48;
  cam.cx = 31.2;
  cam.cy = 23.9;
  ImageF32 img(64, 48, 1);
  for (int y = 0; y < 48; ++y) {
    for (int x = 0; x < 64; ++x) img.at(x, y) = static_cast<float>(3 * x + 2 * y + 1);
  }
  const ImageF32 half = downsampleHalf(img);
  ASSERT_EQ(half.width, 32);
  ASSERT_EQ(half.height, 24);
  const PinholeCamera c1 = pyramidCamera(cam, 1);
  EXPECT_EQ(c1.width, 32);
  // The same 3D point seen through both cameras: level pixel (i, j) <-> input (2i + 0.5, 2j + 0.5).
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  const double u0 = cam.fx * p.x() / p.z() + cam.cx;
  const double u1 = c1.fx * p.x() / p.z() + c1.cx;
  EXPECT_NEAR(2 * u1 + 0.5, u0, 1e-12);
  for (int j = 1; j < 23; ++j) {
    for (int i = 1; i < 31; ++i) EXPECT_NEAR(half.at(i, j), 3 * (2 * i + 0.5) + 2 * (2 * j + 0.5) + 1, 1e-3);
  }
  // A constant image stays constant, borders included.
  const ImageF32 flat = downsampleHalf(ImageF32(9, 7, 1, 42.0f));
  EXPECT_EQ(flat.width, 5);
  for (float v : flat.data) EXPECT_NEAR(v, 42.0f, 1e-4);
  // Every output, borders included, equals the [1 3 3 1] / 8 filter with clamped taps, for even
  // and odd sizes (the interior loop runs without clamping).
  for (int w : {1, 2, 3, 4, 5, 6, 7, 8, 33, 640}) {
    SCOPED_TRACE(::testing::Message() << "width " << w);
    ImageF32 in(w, 5, 1);
    for (int y = 0; y < 5; ++y) {
      for (int x = 0; x < w; ++x) in.at(x, y) = static_cast<float>((x * 37 + y * 11) % 29);
    }
    const ImageF32 out = downsampleHalf(in);
    ASSERT_EQ(out.width, (w + 1) / 2);
    const double taps[4] = {1.0 / 8, 3.0 / 8, 3.0 / 8, 1.0 / 8};
    auto clampi = [](int v, int n) { return std::min(std::max(v, 0), n - 1); };
    for (int j = 0; j < out.height; ++j) {
      for (int i = 0; i < out.width; ++i) {
        double expected = 0;
        for (int ty = 0; ty < 4; ++ty) {
          for (int tx = 0; tx < 4; ++tx) {
            expected += taps[ty] * taps[tx] * in.at(clampi(2 * i - 1 + tx, w), clampi(2 * j - 1 + ty, 5));
          }
        }
        ASSERT_NEAR(out.at(i, j), expected, 1e-4) << i << "," << j;
      }
    }
  }
}

TEST(EdgePyramid, LiveFrameLevelsAndErrors) {
  PinholeCamera cam;
  cam.width = 160;
  cam.height = 120;
  const ImageF32 scene = quantised(syntheticScene(160, 120, 9));
  ImageU8 gray(160, 120, 1);
  for (size_t i = 0; i < gray.data.size(); ++i) gray.data[i] = static_cast<uint8_t>(scene.data[i]);
  auto frame = buildLiveFrame(gray, cam);
  ASSERT_TRUE(frame.ok()) << frame.error().message;
  ASSERT_EQ(frame->levels.size(), 3u);
  EXPECT_EQ(frame->levels[2].field.distance.width, 40);
  EXPECT_EQ(frame->levels[2].camera.width, 40);
  EXPECT_DOUBLE_EQ(frame->levels[2].camera.fx, cam.fx / 4);
  PinholeCamera wrong = cam;
  wrong.width = 161;
  EXPECT_FALSE(buildLiveFrame(gray, wrong).ok());
  LiveFrameOptions bad;
  bad.levels = 0;
  EXPECT_FALSE(buildLiveFrame(gray, cam, bad).ok());
}

// --- reference edges ---------------------------------------------------------------------------

double distanceToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (a + t * ab - p).norm();
}

/// The 12 edges of an axis-aligned box, as segment end points.
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> boxEdges(const Eigen::Vector3d& lo,
                                                                  const Eigen::Vector3d& hi) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edges;
  for (int axis = 0; axis < 3; ++axis) {
    for (int k = 0; k < 4; ++k) {
      Eigen::Vector3d a, b;
      for (int c = 0, bit = 0; c < 3; ++c) {
        if (c == axis) {
          a[c] = lo[c];
          b[c] = hi[c];
        } else {
          a[c] = b[c] = ((k >> bit++) & 1) ? hi[c] : lo[c];
        }
      }
      edges.emplace_back(a, b);
    }
  }
  return edges;
}

double distanceToBoxEdges(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  double best = 1e30;
  for (const auto& [a, b] : boxEdges(lo, hi)) best = std::min(best, distanceToSegment(p, a, b));
  return best;
}

/// Image distance (pixels) from the projection of p_camera to the nearest projected box edge.
double imageDistanceToBoxEdges(const Eigen::Vector3d& p_camera, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                               const PinholeCamera& cam, const Pose& T_world_camera) {
  auto project = [&](const Eigen::Vector3d& q) {
    return Eigen::Vector2d(cam.fx * q.x() / q.z() + cam.cx, cam.fy * q.y() / q.z() + cam.cy);
  };
  const Pose T_camera_world = T_world_camera.inverse();
  const Eigen::Vector2d uv = project(p_camera);
  double best = 1e30;
  for (const auto& [a, b] : boxEdges(lo, hi)) {
    const Eigen::Vector2d A = project(T_camera_world * a), B = project(T_camera_world * b);
    const Eigen::Vector2d ab = B - A;
    const double t = std::clamp((uv - A).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (A + t * ab - uv).norm());
  }
  return best;
}

// The geometric flags equal the rule of ReferenceEdgeOptions, pair by pair, on seeded depth with
// runs of background (the scan skips those eight pixels at a time), jumps, ties, +inf and NaN, at
// widths that are and are not multiples of eight.
TEST(ReferenceEdges, GeometricFlagsFollowThePairRule) {
  std::mt19937 rng(11);
  for (const int w : {37, 64, 8}) {
    const int h = 23;
    RenderOutput view;
    view.depth = ImageF32(w, h, 1, 0.0f);
    view.normals = ImageF32(w, h, 3, 0.0f);
    view.gray = ImageU8(w, h, 1, 0);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const uint32_t pick = rng() % 16;
        float z = 0.0f;  // background in long runs on the left half
        if (x >= w / 3 || pick < 3) {
          z = pick < 6    ? 2.0f
              : pick < 10 ? 2.0f + 0.01f * static_cast<float>(rng() % 20)
                          : 1.0f + static_cast<float>(rng() % 5);
        }
        if (pick == 15 && y == 5) z = std::numeric_limits<float>::infinity();
        if (pick == 15 && y == 6) z = std::numeric_limits<float>::quiet_NaN();
        view.depth.at(x, y) = z;
        const float a = 0.3f * static_cast<float>(rng() % 8);
        view.normals.at(x, y, 0) = std::sin(a);
        view.normals.at(x, y, 2) = -std::cos(a);
      }
    }
    ReferenceEdgeOptions options;
    options.texture_edges = false;
    options.hole_gap_px = 0;
    auto flags = detectReferenceEdges(view, options);
    ASSERT_TRUE(flags.ok()) << flags.error().message;
    ImageU8 expected(w, h, 1, 0);
    const float cos_crease = static_cast<float>(std::cos(options.crease_angle_deg * M_PI / 180.0));
    auto surface = [](float z) { return z > 0 && std::isfinite(z); };
    auto pair = [&](int px, int py, int qx, int qy, uint8_t to_q, uint8_t to_p, uint8_t crease) {
      const float zp = view.depth.at(px, py), zq = view.depth.at(qx, qy);
      if (!surface(zp) && !surface(zq)) return;
      if (surface(zp) != surface(zq) ||
          std::abs(static_cast<double>(zp) - zq) > options.depth_jump_ratio * std::min(zp, zq)) {
        if (surface(zp) && (!surface(zq) || zp < zq)) {
          expected.at(px, py) |= to_q;
        } else {
          expected.at(qx, qy) |= to_p;
        }
        return;
      }
      float dot = 0;
      for (int c = 0; c < 3; ++c) dot += view.normals.at(px, py, c) * view.normals.at(qx, qy, c);
      if (dot < cos_crease) expected.at(px, py) |= crease;
    };
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        if (x + 1 < w) pair(x, y, x + 1, y, kEdgePixelOcclusionRight, kEdgePixelOcclusionLeft, kEdgePixelCreaseRight);
        if (y + 1 < h) pair(x, y, x, y + 1, kEdgePixelOcclusionDown, kEdgePixelOcclusionUp, kEdgePixelCreaseDown);
      }
    }
    int flagged = 0;
    for (uint8_t f : expected.data) flagged += f != 0;
    EXPECT_GT(flagged, w * h / 10) << "width " << w;
    EXPECT_EQ(flags->data, expected.data) << "width " << w;
  }
}

/// 320x240, focal length 300 px, principal point at the centre.
PinholeCamera qvga300() { return PinholeCamera{300.0, 300.0, 159.5, 119.5, 320, 240}; }

TEST(ReferenceEdges, BoxSilhouetteAndCreasePointsLieOnTheBoxEdges) {
  const Eigen::Vector3d lo(-0.3, -0.2, 0.0), hi(0.3, 0.25, 0.4);
  const Model box = test::makeBox(lo, hi);
  const PinholeCamera cam = qvga300();
  const Pose T_world_ref = test::cameraLookingAt({0.8, -0.9, 0.8}, {0.0, 0.02, 0.18});
  auto view = renderReference(box, cam, T_world_ref);
  ASSERT_TRUE(view.ok()) << view.error().message;
  ReferenceEdgeOptions options;
  options.texture_edges = false;
  options.max_points = 100000;
  options.max_points_per_cell = 1000;
  auto flags = detectReferenceEdges(*view, options);
  ASSERT_TRUE(flags.ok());
  const std::vector<EdgePoint> points = backProjectEdges(*flags, view->depth, cam, options);
  int occlusion = 0, crease = 0;
  double max_err_px = 0, max_err_m = 0, sum_image_px = 0;
  for (const EdgePoint& p : points) {
    const Eigen::Vector3d world = T_world_ref * Eigen::Vector3d(p.x, p.y, p.z);
    const double err = distanceToBoxEdges(world, lo, hi);
    const double footprint = p.z / cam.fx;  // metres per pixel at the point's depth
    max_err_px = std::max(max_err_px, err / footprint);
    max_err_m = std::max(max_err_m, err);
    const double image_err = imageDistanceToBoxEdges(Eigen::Vector3d(p.x, p.y, p.z), lo, hi, cam, T_world_ref);
    sum_image_px += image_err;
    // In the image the edge lies within half a pixel diagonal of the point (pixel pair
    // midpoint or a stair step of a slanted edge).
    EXPECT_LT(image_err, 0.75) << "kind " << p.kind;
    // The boundary lies anywhere between the two pixel centres (+-0.5 px in the image), and a
    // pixel on a face seen at an angle covers more than one footprint on it.
    EXPECT_LT(err, 1.5 * footprint) << "kind " << p.kind << " error " << err << " m";
    occlusion += (p.kind & ~kEdgeBackground) == kEdgeOcclusion;
    crease += (p.kind & ~kEdgeBackground) == kEdgeCrease;
  }
  EXPECT_GT(occlusion, 400);
  EXPECT_GT(crease, 150);
  // Uniform +-0.5 px placement error averages 0.25 px: a systematic offset would show here.
  const double mean_image_px = sum_image_px / static_cast<double>(points.size());
  EXPECT_LT(mean_image_px, 0.3);
  EXPECT_LT(max_err_m, 0.009);  // metres; the camera is ~1.4 m away, 1 px ~ 4.7 mm
  RecordProperty("max_error_px", std::to_string(max_err_px));
  RecordProperty("max_error_m", std::to_string(max_err_m));
  RecordProperty("mean_image_error_px", std::to_string(mean_image_px));
  // With texture edges on, the silhouette (white box on black) is taken from the gray image's
  // edge pixels, which may be the background pixel next to the box (given the box's depth):
  // still within a pixel of the projected box edges.
  ReferenceEdgeOptions with_texture = options;
  with_texture.texture_edges = true;
  auto flags2 = detectReferenceEdges(*view, with_texture);
  ASSERT_TRUE(flags2.ok());
  int texture_points = 0;
  for (const EdgePoint& p : backProjectEdges(*flags2, view->depth, cam, with_texture)) {
    const Eigen::Vector3d pc(p.x, p.y, p.z);
    EXPECT_LT(imageDistanceToBoxEdges(pc, lo, hi, cam, T_world_ref), 1.25);
    texture_points += (p.kind & ~kEdgeBackground) == kEdgeTexture;
  }
  EXPECT_GT(texture_points, 400);
}

TEST(ReferenceEdges, SubsampleRespectsBudgetAndCellsDeterministically) {
  PinholeCamera cam;
  cam.width = 320;
  cam.height = 240;
  std::vector<EdgePoint> points;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0, 319), v(0, 239), z(1, 5);
  for (int i = 0; i < 20000; ++i) {
    // Denser in the left third, to see the cap per cell even things out.
    const double uu = i % 2 ? u(rng) / 3 : u(rng);
    const double vv = v(rng), zz = z(rng);
    EdgePoint p;
    p.x = static_cast<float>(zz * (uu - cam.cx) / cam.fx);
    p.y = static_cast<float>(zz * (vv - cam.cy) / cam.fy);
    p.z = static_cast<float>(zz);
    p.kind = static_cast<uint32_t>(i);  // identifies the input point
    points.push_back(p);
  }
  ReferenceEdgeOptions options;
  options.cell_px = 16;
  options.max_points_per_cell = 5;
  options.max_points = 1500;
  const auto a = subsampleEdgePoints(points, cam, options);
  const auto b = subsampleEdgePoints(points, cam, options);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LE(a.size(), 1500u);
  EXPECT_GT(a.size(), 1000u);
  std::vector<int> per_cell(20 * 15, 0);
  uint32_t last = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].kind, b[i].kind);
    if (i > 0) {
      EXPECT_GT(a[i].kind, last);  // input order kept, no duplicates
    }
    last = a[i].kind;
    const EdgePoint& src = points[a[i].kind];
    EXPECT_EQ(src.x, a[i].x);
    const double uu = cam.fx * a[i].x / a[i].z + cam.cx;
    const double vv = cam.fy * a[i].y / a[i].z + cam.cy;
    ++per_cell[std::clamp(static_cast<int>((vv + 0.5) / 16), 0, 14) * 20 +
               std::clamp(static_cast<int>((uu + 0.5) / 16), 0, 19)];
  }
  for (int c : per_cell) EXPECT_LE(c, 5);
  // Every cell is represented (the sparse right part too).
  for (int c : per_cell) EXPECT_GE(c, 1);
  // A tiny budget is still honoured.
  options.max_points = 50;
  EXPECT_EQ(subsampleEdgePoints(points, cam, options).size(), 50u);
}

TEST(ReferenceEdges, PointsSeenThroughAHoleAreMarkedNearABackFace) {
  // A closed box without its top, seen from above: through the opening the inside of the walls
  // and of the floor (back faces) with their creases, and the opening's rim against them; the
  // outer walls are front faces. Untextured: geometric edges only.
  const Eigen::Vector3d lo(-0.5, -0.375, 0.0), hi(0.625, 0.5, 1.25);
  const PinholeCamera cam = qvga300();
  const Pose T_world_ref = test::cameraLookingAt({1.3, -1.5, 3.6}, {0.06, 0.06, 0.4});
  ReferenceEdgeOptions options;
  options.levels = 2;  // level 1's mask is level 0's, halved with the depth
  // Points of every level, level 0 first.
  auto levels = [&](const Model& model, bool with_back_faces) {
    auto view = renderReference(model, cam, T_world_ref);
    EXPECT_TRUE(view.ok());
    if (!with_back_faces) view->back_faces = ImageU8{};
    auto ref = buildEdgeReference(*view, cam, T_world_ref, options);
    EXPECT_TRUE(ref.ok());
    std::vector<std::vector<EdgePoint>> out;
    if (!ref.ok()) return out;
    out.push_back(ref->points);
    for (const std::vector<EdgePoint>& level : ref->coarse_points) out.push_back(level);
    return out;
  };
  // Where the line of sight to a point crosses the plane of the opening (z = hi.z): inside the
  // opening (by more than 1 cm at level 0) for the points seen through it, outside it (by more
  // than 5 cm) for points on the outer walls well below the rim; margins double per level.
  const Eigen::Vector3d eye = T_world_ref.translation();
  const std::vector<std::vector<EdgePoint>> open_box = levels(test::makeBox(lo, hi, true), true);
  ASSERT_EQ(open_box.size(), 2u);
  for (size_t k = 0; k < open_box.size(); ++k) {
    const double scale = k == 0 ? 1.0 : 2.0;
    int inside = 0, outside = 0;
    for (const EdgePoint& p : open_box[k]) {
      const Eigen::Vector3d w = T_world_ref * Eigen::Vector3d(p.x, p.y, p.z);
      const Eigen::Vector3d crossing = eye + (eye.z() - hi.z()) / (eye.z() - w.z()) * (w - eye);
      const double margin = std::min({crossing.x() - lo.x(), hi.x() - crossing.x(), crossing.y() - lo.y(),
                                      hi.y() - crossing.y()});  // > 0 inside the opening
      if (w.z() < hi.z() - 0.03 * scale && margin > 0.01 * scale) {
        ++inside;
        EXPECT_TRUE(p.kind & kEdgeBackFace) << "level " << k << ": " << w.transpose();
      } else if (w.z() < hi.z() - 0.15 * scale && margin < -0.05 * scale) {
        ++outside;
        EXPECT_EQ(p.kind & kEdgeBackFace, 0u) << "level " << k << ": " << w.transpose();
      }
    }
    EXPECT_GT(inside, 20 / (1 + static_cast<int>(k))) << "level " << k;
    EXPECT_GT(outside, 20 / (1 + static_cast<int>(k))) << "level " << k;
  }
  // The closed box shows no back face; a render without the mask marks none.
  for (const auto& level : levels(test::makeBox(lo, hi), true)) {
    for (const EdgePoint& p : level) EXPECT_EQ(p.kind & kEdgeBackFace, 0u);
  }
  for (const auto& level : levels(test::makeBox(lo, hi, true), false)) {
    for (const EdgePoint& p : level) EXPECT_EQ(p.kind & kEdgeBackFace, 0u);
  }
}

TEST(ReferenceEdges, HoleRimsAreDroppedAndSilhouettesKept) {
  // A 1 m square wall in the plane z = 0 with an 8 cm square hole in its centre, seen head-on
  // from 1.5 m (200 px per metre): the hole is 16 px wide, the wall's outline 200 px.
  Model wall;
  wall.source = "wall with a hole";
  const double a = 0.5, b = 0.04;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY();
  test::appendQuad(wall, {-a, -a, 0}, (2 * a) * ex, (a - b) * ey);  // below the hole
  test::appendQuad(wall, {-a, b, 0}, (2 * a) * ex, (a - b) * ey);   // above
  test::appendQuad(wall, {-a, -b, 0}, (a - b) * ex, (2 * b) * ey);  // left
  test::appendQuad(wall, {b, -b, 0}, (a - b) * ex, (2 * b) * ey);   // right
  test::finishSingleBlock(wall);
  const PinholeCamera cam = qvga300();
  const Pose T_world_ref = test::cameraLookingAt({0.0, 0.0, 1.5}, {0.0, 0.0, 0.0});
  auto view = renderReference(wall, cam, T_world_ref);
  ASSERT_TRUE(view.ok()) << view.error().message;
  auto count = [&](int hole_gap_px, int& rim, int& outline) {
    ReferenceEdgeOptions options;
    options.texture_edges = false;
    options.hole_gap_px = hole_gap_px;
    auto flags = detectReferenceEdges(*view, options);
    ASSERT_TRUE(flags.ok());
    rim = outline = 0;
    for (const EdgePoint& p : backProjectEdges(*flags, view->depth, cam, options)) {
      if ((p.kind & ~kEdgeBackground) != kEdgeOcclusion) continue;
      EXPECT_TRUE(p.kind & kEdgeBackground);  // every depth jump here is against background
      const Eigen::Vector3d w = T_world_ref * Eigen::Vector3d(p.x, p.y, p.z);
      const double r = std::max(std::abs(w.x()), std::abs(w.y()));
      rim += r < 0.1;
      outline += r > 0.4;
    }
  };
  int rim = 0, outline = 0;
  count(0, rim, outline);
  EXPECT_GT(rim, 40);  // 4 x 16 px of hole rim
  EXPECT_GT(outline, 600);
  count(24, rim, outline);
  EXPECT_EQ(rim, 0);
  EXPECT_GT(outline, 600);  // the wall's outline does not resume: kept
}

}  // namespace
}  // namespace vkloc
