// GPU edge stages (GpuEdgeStages) against the CPU backend (edges.hpp, edge_tracker.hpp).
#include "vkloc/engine/gpu_edges.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <optional>
#include <random>
#include <string>

#include "support/analytic_scenes.hpp"
#include "support/gpu_test_support.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::test {
namespace {

PinholeCamera qvga() { return PinholeCamera{260.0, 262.0, 159.5, 119.5, 320, 240}; }

/// Seeded test image: random rectangles and discs of random gray levels on a gradient
/// background, plus uniform noise of +-noise gray levels.
ImageU8 randomImage(int w, int h, unsigned seed, int noise = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> value(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) value[static_cast<size_t>(y) * w + x] = 60.0 + 60.0 * x / w + 20.0 * y / h;
  }
  for (int s = 0; s < 25; ++s) {
    const double cx = U(rng) * w, cy = U(rng) * h, r = 8 + U(rng) * w / 6.0, g = 20 + U(rng) * 215;
    const bool disc = U(rng) < 0.5;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double dx = x - cx, dy = y - cy;
        const bool inside = disc ? dx * dx + dy * dy < r * r : std::abs(dx) < r && std::abs(dy) < 0.6 * r;
        if (inside) value[static_cast<size_t>(y) * w + x] = g;
      }
    }
  }
  std::uniform_int_distribution<int> N(-noise, noise);
  ImageU8 out(w, h, 1);
  for (size_t i = 0; i < value.size(); ++i)
    out.data[i] = static_cast<uint8_t>(std::clamp(value[i] + N(rng), 0.0, 255.0));
  return out;
}

double maxAbsDiff(const ImageF32& a, const ImageF32& b) {
  if (a.data.size() != b.data.size()) return 1e30;
  double m = 0;
  for (size_t i = 0; i < a.data.size(); ++i) m = std::max(m, std::abs(static_cast<double>(a.data[i]) - b.data[i]));
  return m;
}

int differingPixels(const ImageU8& a, const ImageU8& b) {
  if (a.data.size() != b.data.size()) return 1 << 30;
  int n = 0;
  for (size_t i = 0; i < a.data.size(); ++i) n += (a.data[i] != 0) != (b.data[i] != 0);
  return n;
}

class GpuEdges : public GpuTest {
 protected:
  std::unique_ptr<GpuEdgeStages> makeStages(const PinholeCamera& camera, const LiveFrameOptions& options = {}) {
    auto stages = GpuEdgeStages::create(context_, camera, options, method_, shapes_);
    EXPECT_TRUE(stages.ok()) << (stages.ok() ? "" : stages.error().message);
    if (stages.ok() && method_ != GpuDistanceMethod::kAuto) {
      EXPECT_EQ((*stages)->distanceMethod(), method_);
    }
    return stages.ok() ? std::move(*stages) : nullptr;
  }

  /// Distance method of makeStages (kAuto: the device's default).
  GpuDistanceMethod method_ = GpuDistanceMethod::kAuto;
  GpuKernelShapes shapes_ = GpuKernelShapes::kAuto;
  static constexpr GpuDistanceMethod kBothMethods[2] = {GpuDistanceMethod::kJumpFlooding,
                                                        GpuDistanceMethod::kSeparable};

  /// GPU live frame vs CPU: pyramid within 1e-3 gray levels, edge maps equal except <= 0.1 %
  /// of the pixels (NMS ties decided by float rounding), distance field vs the exact CPU EDT of
  /// the GPU's own edge map: <= 0.01 % pixels off by > 0.05 px, max error <= 0.5 px; gradients
  /// within 1e-3 except <= 0.1 % pixels (next to a JFA miss); edge lines (s, n_u, n_v) within
  /// 1e-3 except in the 5x5 neighbourhoods of differing edge pixels and <= 0.05 % other pixels
  /// (nearest-edge ties decided by float rounding).
  void compareLiveFrame(const ImageU8& gray, const PinholeCamera& camera, const LiveFrameOptions& options) {
    auto stages = makeStages(camera, options);
    ASSERT_TRUE(stages);
    ASSERT_TRUE(stages->processLiveImage(gray).ok());
    auto gpu = stages->readLiveFrame();
    ASSERT_TRUE(gpu.ok()) << gpu.error().message;
    auto cpu = buildLiveFrame(gray, camera, options);
    ASSERT_TRUE(cpu.ok()) << cpu.error().message;
    ASSERT_EQ(gpu->levels.size(), cpu->levels.size());
    for (size_t k = 0; k < cpu->levels.size(); ++k) {
      SCOPED_TRACE(::testing::Message() << "level " << k);
      const LiveLevel& g = gpu->levels[k];
      const LiveLevel& c = cpu->levels[k];
      EXPECT_EQ(g.camera.width, c.camera.width);
      EXPECT_DOUBLE_EQ(g.camera.cx, c.camera.cx);
      EXPECT_LE(maxAbsDiff(g.gray, c.gray), 1e-3);
      const int n = c.camera.width * c.camera.height;
      int edge_pixels = 0;
      for (uint8_t e : c.edges.data) edge_pixels += e != 0;
      EXPECT_GT(edge_pixels, n / 200) << "test image has too few edges to be meaningful";
      EXPECT_LE(differingPixels(g.edges, c.edges), n / 1000) << "of " << edge_pixels << " edge pixels";

      auto exact = computeDistanceField(g.edges, options.truncation_px);
      ASSERT_TRUE(exact.ok());
      int off = 0, grad_off = 0;
      double worst = 0;
      for (int i = 0; i < n; ++i) {
        const double e = std::abs(g.field.distance.data[i] - exact->distance.data[i]);
        off += e > 0.05;
        worst = std::max(worst, e);
        const double eg = std::max(std::abs(g.field.gradient.data[2 * i] - exact->gradient.data[2 * i]),
                                   std::abs(g.field.gradient.data[2 * i + 1] - exact->gradient.data[2 * i + 1]));
        grad_off += eg > 1e-3;
      }
      EXPECT_LE(off, n / 10000) << "pixels off by > 0.05 px";
      EXPECT_LE(worst, 0.5);
      if (stages->distanceMethod() == GpuDistanceMethod::kSeparable) {
        EXPECT_LE(worst, 1e-5) << "the separable transform is exact";
        EXPECT_EQ(grad_off, 0);
      }
      EXPECT_LE(grad_off, n / 1000);

      if (!options.subpixel_edges) {
        EXPECT_TRUE(g.edge_lines.empty());
        continue;
      }
      ASSERT_EQ(g.edge_lines.channels, 3);
      ASSERT_EQ(c.edge_lines.data.size(), g.edge_lines.data.size());
      int line_pixels = 0, lines_off = 0;
      for (int i = 0; i < n; ++i) {
        const float* a = &g.edge_lines.data[3 * static_cast<size_t>(i)];
        const float* b = &c.edge_lines.data[3 * static_cast<size_t>(i)];
        line_pixels += b[1] != 0 || b[2] != 0;
        double e = 0;
        for (int ch = 0; ch < 3; ++ch) e = std::max(e, std::abs(static_cast<double>(a[ch]) - b[ch]));
        lines_off += e > 1e-3;
      }
      EXPECT_GT(line_pixels, 2 * edge_pixels) << "edge lines cover the pixels within 2 px of an edge";
      EXPECT_LE(lines_off, 25 * differingPixels(g.edges, c.edges) + n / 2000) << "of " << line_pixels;
    }
  }
};

TEST_F(GpuEdges, LiveFrameMatchesCpuOnSeededImages) {
  LiveFrameOptions options;
  options.levels = 3;
  for (GpuDistanceMethod method : kBothMethods) {
    method_ = method;
    for (unsigned seed : {1u, 2u}) {
      SCOPED_TRACE(::testing::Message() << "seed " << seed << ", " << gpuDistanceMethodName(method));
      compareLiveFrame(randomImage(320, 240, seed), qvga(), options);
    }
  }
}

// The other device type's kernel shapes on this device (on lavapipe: the GPU variants, one
// pixel and row per invocation, Sobel stored for NMS, dense edge lines with jump flooding),
// against the CPU as above; an odd size for the borders.
TEST_F(GpuEdges, OtherKernelShapesMatchCpuToo) {
  LiveFrameOptions options;
  options.levels = 2;
  for (GpuKernelShapes shapes : {GpuKernelShapes::kGpu, GpuKernelShapes::kCpu}) {
    shapes_ = shapes;
    for (GpuDistanceMethod method : kBothMethods) {
      method_ = method;
      SCOPED_TRACE(::testing::Message() << (shapes == GpuKernelShapes::kGpu ? "gpu" : "cpu") << " shapes, "
                                        << gpuDistanceMethodName(method));
      compareLiveFrame(randomImage(321, 239, 4), PinholeCamera{300.0, 300.0, 160.0, 119.0, 321, 239}, options);
    }
  }
  shapes_ = GpuKernelShapes::kAuto;
}

TEST_F(GpuEdges, LiveFrameMatchesCpuWithOddSizeAndOtherOptions) {
  // Odd sizes exercise the (w + 1) / 2 pyramid and border replication; a low percentile and a
  // small truncation exercise the radix select and a short jump-flooding schedule.
  LiveFrameOptions options;
  options.levels = 2;
  options.truncation_px = 5.0f;
  options.detector.contrast_percentile = 0.5;
  options.detector.high_factor = 3.0;
  options.detector.low_ratio = 0.5;
  const PinholeCamera camera{200.0, 200.0, 100.0, 70.0, 201, 143};
  for (GpuDistanceMethod method : kBothMethods) {
    method_ = method;
    for (bool subpixel : {true, false}) {
      SCOPED_TRACE(::testing::Message() << "subpixel_edges " << subpixel << ", " << gpuDistanceMethodName(method));
      options.subpixel_edges = subpixel;
      compareLiveFrame(randomImage(201, 143, 7, 6), camera, options);
    }
  }
}

TEST_F(GpuEdges, LiveFrameMatchesCpuOnRenderedDemoView) {
  auto model = makeDemoModel("city");
  ASSERT_TRUE(model.ok());
  auto renderer = GpuRenderer::create(context_, *model);
  ASSERT_TRUE(renderer.ok()) << renderer.error().message;
  const auto views = demoViewpoints("city");
  ASSERT_FALSE(views.empty());
  auto view = (*renderer)->render(qvga(), views.front());
  ASSERT_TRUE(view.ok()) << view.error().message;
  LiveFrameOptions options;
  options.levels = 2;
  compareLiveFrame(view->gray, qvga(), options);
}

TEST_F(GpuEdges, HysteresisFollowsLongWeakChainsToTheFixedPoint) {
  // A serpentine band (weak step edges, contrast 30: magnitude 15) of 8 rows with a short
  // strong piece (contrast 120) at one end: every weak pixel of the snake's outline is
  // 8-connected to the strong piece through thousands of weak pixels. Exact arithmetic: the
  // GPU edge map must equal the CPU's bit for bit.
  const int w = 160, h = 120;
  ImageU8 gray(w, h, 1, 100);
  for (int band = 0; band < 7; ++band) {
    const int y0 = 8 + band * 15;
    for (int y = y0; y < y0 + 8; ++y) {
      for (int x = 10; x < 150; ++x) gray.at(x, y) = 130;
    }
    if (band < 6) {  // connector to the next band, alternating sides
      const int x0 = band % 2 == 0 ? 142 : 10;
      for (int y = y0 + 8; y < y0 + 15; ++y) {
        for (int x = x0; x < x0 + 8; ++x) gray.at(x, y) = 130;
      }
    }
  }
  for (int y = 8; y < 16; ++y) {
    for (int x = 10; x < 20; ++x) gray.at(x, y) = 220;
  }
  LiveFrameOptions options;
  options.levels = 1;
  options.detector.contrast_percentile = 0.0;
  options.detector.min_high_gradient = 20.0;
  const PinholeCamera camera{150.0, 150.0, 79.5, 59.5, w, h};
  auto stages = makeStages(camera, options);
  ASSERT_TRUE(stages);
  // First a frame that reaches the fixed point at once (a strong square): on CPU drivers the next
  // frame's first submission then records only a few passes, and the snake needs more.
  ImageU8 square(w, h, 1, 100);
  for (int y = 40; y < 80; ++y) {
    for (int x = 60; x < 100; ++x) square.at(x, y) = 220;
  }
  ASSERT_TRUE(stages->processLiveImage(square).ok());
  EXPECT_LE(stages->lastHysteresisPasses()[0], 2);
  ASSERT_TRUE(stages->processLiveImage(gray).ok());
  auto gpu = stages->readLiveFrame();
  ASSERT_TRUE(gpu.ok());
  auto cpu = detectEdges(toFloat(gray), options.detector);
  ASSERT_TRUE(cpu.ok());
  int edges = 0;
  for (uint8_t e : cpu->data) edges += e != 0;
  EXPECT_GT(edges, 2000);
  EXPECT_EQ(differingPixels(gpu->levels[0].edges, *cpu), 0);
  EXPECT_LT(stages->lastHysteresisPasses()[0], 64) << "hysteresis did not reach its fixed point";
  EXPECT_GT(stages->lastHysteresisPasses()[0], 2) << "the snake should need more passes than the square";
}

/// Points near the live edges of `level` (within 4 px, projections at least 3 px inside the
/// image) back-projected at depths 2..6 m into the reference camera = the live camera at
/// T_camera_ref^-1.
std::vector<EdgePoint> pointsNearEdges(const LiveLevel& level, const Pose& T_camera_ref, int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> X(3, level.camera.width - 4), Y(3, level.camera.height - 4);
  std::uniform_real_distribution<double> Z(2.0, 6.0), J(-0.3, 0.3);
  const Pose T_ref_camera = T_camera_ref.inverse();
  std::vector<EdgePoint> points;
  while (static_cast<int>(points.size()) < count) {
    const int x = X(rng), y = Y(rng);
    if (level.field.distance.at(x, y) > 4.0f) continue;
    const double u = x + J(rng), v = y + J(rng), z = Z(rng);
    const PinholeCamera& c = level.camera;
    const Eigen::Vector3d p_ref = T_ref_camera * Eigen::Vector3d(z * (u - c.cx) / c.fx, z * (v - c.cy) / c.fy, z);
    points.push_back(EdgePoint{static_cast<float>(p_ref.x()), static_cast<float>(p_ref.y()),
                               static_cast<float>(p_ref.z()), kEdgeTexture});
  }
  return points;
}

/// GPU residuals vs the CPU's for the same points: same validity, values equal to float
/// projection accuracy (2e-4 px: (u, v) in float carry ~5e-5 px, times |grad d| <= ~1.5), more
/// than min_valid of them valid.
void expectResidualsMatch(const std::vector<float>& gpu, const std::vector<float>& cpu, int min_valid) {
  ASSERT_EQ(gpu.size(), cpu.size());
  int valid = 0, mismatched = 0;
  double worst = 0;
  for (size_t i = 0; i < cpu.size(); ++i) {
    const bool a = gpu[i] >= 0, b = cpu[i] >= 0;
    mismatched += a != b;
    if (a && b) {
      ++valid;
      worst = std::max(worst, std::abs(static_cast<double>(gpu[i]) - cpu[i]));
    }
  }
  EXPECT_GT(valid, min_valid);
  EXPECT_EQ(mismatched, 0);
  EXPECT_LE(worst, 2e-4);
}

TEST_F(GpuEdges, ResidualsAndNormalEquationsMatchCpuOnTheSameField) {
  LiveFrameOptions options;
  options.levels = 2;
  auto stages = makeStages(qvga(), options);
  ASSERT_TRUE(stages);
  ASSERT_TRUE(stages->processLiveImage(randomImage(320, 240, 3)).ok());
  auto live = stages->readLiveFrame();
  ASSERT_TRUE(live.ok());
  // The read-back frame carries the GPU's edge lines, so the CPU evaluation below takes the same
  // sub-pixel-line / distance-field branch per point as the GPU kernels.
  ASSERT_EQ(live->levels[0].edge_lines.channels, 3);
  const Pose T_camera_ref = expSE3((Vector6d() << 0.05, -0.03, 0.1, 0.01, -0.02, 0.015).finished());
  // The pose the points were made with differs from the evaluated pose by a small motion, so
  // residuals are spread over 0..truncation and the gradient g is far from zero.
  const Pose T_eval =
      applyLeftIncrement(T_camera_ref, (Vector6d() << 0.01, 0.004, -0.01, 0.002, 0.001, -0.003).finished());
  for (int level = 0; level < 2; ++level) {
    SCOPED_TRACE(::testing::Message() << "level " << level);
    const LiveLevel& L = live->levels[level];
    const std::vector<EdgePoint> points = pointsNearEdges(L, T_camera_ref, 3000, 11 + level);
    ASSERT_TRUE(stages->setReference(points).ok());

    auto gpu_r = stages->residuals(T_eval, level);
    ASSERT_TRUE(gpu_r.ok()) << gpu_r.error().message;
    const std::vector<float> cpu_r = evaluateEdgeResiduals(points, T_eval, L);
    expectResidualsMatch(*gpu_r, cpu_r, 2500);

    // Normal equations: every value within 1e-4 of the sum of the absolute per-point
    // contributions (the scale float accumulation errors are relative to), count exact.
    const double sigma = 1.3, nu = 5.0;
    auto gpu_eq = stages->accumulate(T_eval, level, sigma, nu);
    ASSERT_TRUE(gpu_eq.ok()) << gpu_eq.error().message;
    const EdgeNormalEquations cpu_eq = accumulateEdgeNormalEquations(points, T_eval, L, sigma, nu);
    EdgeNormalEquations scale{};
    for (const EdgePoint& p : points) {
      const EdgePointEvaluation e = evaluateEdgePoint(p, T_eval, L, true);
      if (!e.valid) continue;
      const double w = tDistributionWeight(e.residual, sigma, nu);
      for (int r = 0; r < 6; ++r) {
        for (int c = r; c < 6; ++c) scale[edgeNormalIndex(r, c)] += std::abs(w * e.jacobian[r] * e.jacobian[c]);
        scale[kEdgeNormalGradientOffset + r] += std::abs(w * e.jacobian[r] * e.residual);
      }
      scale[kEdgeNormalCostIndex] += w * e.residual * e.residual;
    }
    EXPECT_EQ((*gpu_eq)[kEdgeNormalCountIndex], cpu_eq[kEdgeNormalCountIndex]);
    for (int i = 0; i < kEdgeNormalCountIndex; ++i) {
      EXPECT_NEAR((*gpu_eq)[i], cpu_eq[i], 1e-4 * scale[i] + 1e-12) << "value " << i;
    }

    // Fused evaluation (residuals -> scale on the device -> normal equations, one submission):
    // the scale within 1e-5 relative of the host's double-precision estimate from the same
    // residuals, the residuals as above, the normal equations as accumulate() with that scale.
    auto fused = stages->evaluate(T_eval, level, nu, 5, 0.05);
    ASSERT_TRUE(fused.ok()) << fused.error().message;
    ASSERT_EQ(fused->residuals.size(), cpu_r.size());
    for (size_t i = 0; i < cpu_r.size(); ++i) ASSERT_EQ(fused->residuals[i], (*gpu_r)[i]) << "point " << i;
    const double host_sigma = estimateTDistributionScale(fused->residuals, nu, 5, 0.05);
    EXPECT_NEAR(fused->sigma_px, host_sigma, 1e-5 * host_sigma);
    ASSERT_TRUE(fused->eq.has_value());
    const EdgeNormalEquations cpu_fused = accumulateEdgeNormalEquations(points, T_eval, L, fused->sigma_px, nu);
    EXPECT_EQ((*fused->eq)[kEdgeNormalCountIndex], cpu_fused[kEdgeNormalCountIndex]);
    for (int i = 0; i < kEdgeNormalCountIndex; ++i) {
      EXPECT_NEAR((*fused->eq)[i], cpu_fused[i], 2e-4 * scale[i] + 1e-12) << "fused value " << i;
    }
  }
}

// The listed edge-lines path (separable transform) writes LINES only near this frame's edges and
// leaves the rest as the last frame wrote it; the reads must never see that. A sparse frame (one
// square) after a dense one (noise: edge lines almost everywhere) must give the CPU's edge lines
// on read-back and the CPU's residuals on the CPU's own live frame, points up to 4 px from an
// edge (where the dense frame's lines were).
TEST_F(GpuEdges, SparseFrameAfterADenseOneSeesNoEarlierEdgeLines) {
  ImageU8 sparse(320, 240, 1, 20);
  for (int y = 80; y < 160; ++y) {
    for (int x = 110; x < 210; ++x) sparse.at(x, y) = 200;
  }
  LiveFrameOptions options;
  options.levels = 2;
  auto cpu = buildLiveFrame(sparse, qvga(), options);
  ASSERT_TRUE(cpu.ok());
  const Pose T_camera_ref = expSE3((Vector6d() << 0.02, -0.01, 0.05, 0.01, -0.02, 0.01).finished());
  const Pose T_eval =
      applyLeftIncrement(T_camera_ref, (Vector6d() << 0.004, 0.002, -0.005, 0.001, 0.001, -0.002).finished());
  for (GpuDistanceMethod method : kBothMethods) {
    SCOPED_TRACE(gpuDistanceMethodName(method));
    method_ = method;
    auto stages = makeStages(qvga(), options);
    ASSERT_TRUE(stages);
    ASSERT_TRUE(stages->processLiveImage(randomImage(320, 240, 9)).ok());
    ASSERT_TRUE(stages->processLiveImage(sparse).ok());
    auto gpu = stages->readLiveFrame();
    ASSERT_TRUE(gpu.ok());
    for (int level = 0; level < 2; ++level) {
      SCOPED_TRACE(::testing::Message() << "level " << level);
      const LiveLevel& g = gpu->levels[level];
      const LiveLevel& c = cpu->levels[level];
      ASSERT_EQ(differingPixels(g.edges, c.edges), 0);
      ASSERT_EQ(g.edge_lines.data.size(), c.edge_lines.data.size());
      double worst_line = 0;
      for (size_t i = 0; i < c.edge_lines.data.size(); ++i) {
        worst_line = std::max(worst_line, std::abs(static_cast<double>(g.edge_lines.data[i]) - c.edge_lines.data[i]));
      }
      EXPECT_LE(worst_line, 1e-3);
      const std::vector<EdgePoint> points = pointsNearEdges(c, T_camera_ref, 2000, 21 + level);
      ASSERT_TRUE(stages->setReference(points).ok());
      auto gpu_r = stages->residuals(T_eval, level);
      ASSERT_TRUE(gpu_r.ok()) << gpu_r.error().message;
      expectResidualsMatch(*gpu_r, evaluateEdgeResiduals(points, T_eval, c), 1500);
    }
  }
}

TEST_F(GpuEdges, SubpixelEdgeLinesGiveTheDistanceToATiltedStep) {
  // A step edge along the line n . (u, v) = c, n at 20 degrees, c off the pixel grid; pixel
  // values are the area fraction of the pixel on the bright side (box-filtered step). Oracle:
  // the residual of a point at signed offset o from the line is |o|.
  const int w = 160, h = 120;
  const double angle = 20.0 * M_PI / 180.0;
  const Eigen::Vector2d n(std::cos(angle), std::sin(angle));
  const double c = n.dot(Eigen::Vector2d(80.3, 60.0));
  const ImageU8 gray = test::makeTiltedStepImage(w, h, n, c);
  const PinholeCamera cam{200.0, 200.0, 79.5, 59.5, w, h};
  LiveFrameOptions options;
  options.levels = 1;
  auto stages = makeStages(cam, options);
  ASSERT_TRUE(stages);
  ASSERT_TRUE(stages->processLiveImage(gray).ok());
  const Eigen::Vector2d tangent(-n.y(), n.x());
  std::vector<EdgePoint> points;
  std::vector<double> offsets;
  for (int k = -20; k <= 20; ++k) {
    for (double offset : {0.0, 0.7, -0.7}) {
      const Eigen::Vector2d uv = n * c + tangent * (1.7 * k) + n * offset;
      points.push_back(EdgePoint{static_cast<float>((uv.x() - cam.cx) / cam.fx),
                                 static_cast<float>((uv.y() - cam.cy) / cam.fy), 1.0f, kEdgeTexture});
      offsets.push_back(offset);
    }
  }
  ASSERT_TRUE(stages->setReference(points).ok());
  auto r = stages->residuals(Pose::Identity(), 0);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->size(), points.size());
  double worst = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    ASSERT_GE((*r)[i], 0.0f) << "point " << i;
    worst = std::max(worst, std::abs((*r)[i] - std::abs(offsets[i])));
  }
  // As the CPU (host_edge_tracker): ~0.03 px; pixel-centre distances alone are off by up to 0.5 px.
  EXPECT_LT(worst, 0.08);
  // With the lines off the same points see the pixel-centre distance field only.
  options.subpixel_edges = false;
  auto coarse = makeStages(cam, options);
  ASSERT_TRUE(coarse);
  ASSERT_TRUE(coarse->processLiveImage(gray).ok());
  ASSERT_TRUE(coarse->setReference(points).ok());
  auto r_coarse = coarse->residuals(Pose::Identity(), 0);
  ASSERT_TRUE(r_coarse.ok());
  double worst_coarse = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if ((*r_coarse)[i] >= 0) worst_coarse = std::max(worst_coarse, std::abs((*r_coarse)[i] - std::abs(offsets[i])));
  }
  EXPECT_GT(worst_coarse, 0.2);
}

TEST_F(GpuEdges, SparseEdgesGiveExactDistancesUpToTheTruncation) {
  // One bright square and one bright dot on black: most pixels lie 5-20 px from the nearest
  // edge, so the jump-flooding schedule (steps 16, 8, 4, 2, 1, 2, 1 for 20 px) must carry seeds
  // the whole truncation distance; the edge lines pass skips pixels beyond its radius.
  ImageU8 gray(320, 240, 1, 0);
  for (int y = 100; y < 140; ++y) {
    for (int x = 140; x < 180; ++x) gray.at(x, y) = 200;
  }
  for (int y = 30; y < 33; ++y) {
    for (int x = 40; x < 43; ++x) gray.at(x, y) = 200;
  }
  LiveFrameOptions options;
  options.levels = 1;
  for (GpuDistanceMethod method : kBothMethods) {
    SCOPED_TRACE(gpuDistanceMethodName(method));
    method_ = method;
    auto stages = makeStages(qvga(), options);
    ASSERT_TRUE(stages);
    ASSERT_TRUE(stages->processLiveImage(gray).ok());
    auto gpu = stages->readLiveFrame();
    ASSERT_TRUE(gpu.ok());
    const LiveLevel& g = gpu->levels[0];
    auto exact = computeDistanceField(g.edges, options.truncation_px);
    ASSERT_TRUE(exact.ok());
    int far = 0, off = 0;
    for (size_t i = 0; i < exact->distance.data.size(); ++i) {
      const float e = exact->distance.data[i];
      far += e > 10.0f && e < options.truncation_px;
      off += std::abs(g.field.distance.data[i] - e) > 1e-4f;
    }
    EXPECT_GT(far, 3000);
    EXPECT_EQ(off, 0);
    auto cpu = buildLiveFrame(gray, qvga(), options);
    ASSERT_TRUE(cpu.ok());
    ASSERT_EQ(cpu->levels[0].edge_lines.data.size(), g.edge_lines.data.size());
    double worst_line = 0;
    for (size_t i = 0; i < g.edge_lines.data.size(); ++i) {
      worst_line =
          std::max(worst_line, std::abs(static_cast<double>(g.edge_lines.data[i]) - cpu->levels[0].edge_lines.data[i]));
    }
    EXPECT_LE(worst_line, 1e-3);
  }
}

TEST_F(GpuEdges, StageTimingsOnlyWhenAskedFor) {
  auto stages = makeStages(qvga());
  ASSERT_TRUE(stages);
  const ImageU8 gray = randomImage(320, 240, 3);
  ASSERT_TRUE(stages->processLiveImage(gray).ok());
  auto names = [&] {
    std::vector<std::string> out;
    for (const GpuStageTiming& t : stages->lastTimings()) out.push_back(t.stage);
    return out;
  };
  EXPECT_EQ(names(), std::vector<std::string>{"submission (host)"});
  stages->setStageTimings(true);
  ASSERT_TRUE(stages->processLiveImage(gray).ok());
  const std::vector<std::string> stages_named = names();
  if (stages_named != std::vector<std::string>{"submission (host)"}) {  // the device has timestamps
    EXPECT_NE(std::find(stages_named.begin(), stages_named.end(), "sobel"), stages_named.end());
    EXPECT_NE(std::find(stages_named.begin(), stages_named.end(), "edge lines"), stages_named.end());
  }
  for (const GpuStageTiming& t : stages->lastTimings()) EXPECT_GE(t.ms, 0.0) << t.stage;
}

TEST_F(GpuEdges, RejectsBadInput) {
  auto stages = makeStages(qvga());
  ASSERT_TRUE(stages);
  EXPECT_FALSE(stages->readLiveFrame().ok());
  EXPECT_FALSE(stages->residuals(Pose::Identity(), 0).ok());
  EXPECT_EQ(stages->processLiveImage(ImageU8(100, 100, 1)).error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(stages->processLiveImage(ImageU8(320, 240, 3)).error().code, ErrorCode::kInvalidArgument);
  ASSERT_TRUE(stages->processLiveImage(ImageU8(320, 240, 1, 128)).ok());
  auto flat = stages->readLiveFrame();
  ASSERT_TRUE(flat.ok());
  for (float d : flat->levels[0].field.distance.data) ASSERT_EQ(d, 20.0f);  // no edge at all
  EXPECT_FALSE(stages->residuals(Pose::Identity(), 7).ok());
  EXPECT_FALSE(stages->accumulate(Pose::Identity(), 0, 0.0, 5.0).ok());
  auto empty = stages->accumulate(Pose::Identity(), 0, 1.0, 5.0);  // no reference: zeros
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ((*empty)[kEdgeNormalCountIndex], 0.0);
  LiveFrameOptions bad;
  bad.levels = 0;
  EXPECT_FALSE(GpuEdgeStages::create(context_, qvga(), bad).ok());
  LiveFrameOptions wide;
  wide.truncation_px = 66.0f;  // beyond the separable transform's radius
  EXPECT_EQ(GpuEdgeStages::create(context_, qvga(), wide, GpuDistanceMethod::kSeparable).error().code,
            ErrorCode::kInvalidArgument);
  auto fallback = GpuEdgeStages::create(context_, qvga(), wide);
  ASSERT_TRUE(fallback.ok());
  EXPECT_EQ((*fallback)->distanceMethod(), GpuDistanceMethod::kJumpFlooding);
}

// The backend over the stages builds every level whatever it is asked for and says so: the
// Localizer then does not run the live stages again for a deeper search on the same image.
TEST_F(GpuEdges, BackendBuildsEveryLevelAndSaysSo) {
  LiveFrameOptions options;
  options.levels = 3;
  auto backend = GpuEdgeTrackingBackend::create(context_, qvga(), options);
  ASSERT_TRUE(backend.ok()) << backend.error().message;
  for (int asked : {1, 2, 0, 8}) {
    auto built = (*backend)->setLiveImage(randomImage(320, 240, 3), asked);
    ASSERT_TRUE(built.ok()) << built.error().message;
    EXPECT_EQ(*built, 3) << asked;
  }
  EXPECT_FALSE((*backend)->setLiveImage(ImageU8(100, 100, 1), 1).ok());
}

double medianMs(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Benchmark, not a check: per-stage GPU times at 640x480 vs the CPU functions in the same run.
// Run: vkloc_gpu_tests --gtest_also_run_disabled_tests --gtest_filter=GpuEdges.DISABLED_Benchmark640x480
// On a noise image (dense edges), or on the 640x480 image named by VKLOC_BENCH_IMAGE.
TEST_F(GpuEdges, DISABLED_Benchmark640x480) {
  const PinholeCamera camera{520.0, 520.0, 319.5, 239.5, 640, 480};
  LiveFrameOptions options;
  options.levels = 3;
  ImageU8 gray = randomImage(640, 480, 5);
  if (const char* path = std::getenv("VKLOC_BENCH_IMAGE"); path && *path) {
    auto loaded = readImageU8(path, 1);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    ASSERT_EQ(loaded->width, 640);
    ASSERT_EQ(loaded->height, 480);
    gray = std::move(*loaded);
    std::printf("image %s\n", path);
  }
  auto stages = makeStages(camera, options);
  ASSERT_TRUE(stages);
  stages->setStageTimings(true);
  const int runs = 15;
  std::vector<std::pair<std::string, std::vector<double>>> gpu_stages;
  std::vector<double> gpu_total;
  for (int i = 0; i < runs + 2; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(stages->processLiveImage(gray).ok());
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (i < 2) continue;  // JIT warm-up
    gpu_total.push_back(ms);
    for (const auto& t : stages->lastTimings()) {
      auto it = std::find_if(gpu_stages.begin(), gpu_stages.end(), [&](const auto& s) { return s.first == t.stage; });
      if (it == gpu_stages.end()) it = gpu_stages.insert(gpu_stages.end(), {t.stage, {}});
      it->second.push_back(t.ms);
    }
  }
  std::printf("GPU (%s) live frame 640x480, 3 levels, median of %d:\n", context_->device().name.c_str(), runs);
  for (const auto& [name, v] : gpu_stages) std::printf("  %-20s %8.3f ms\n", name.c_str(), medianMs(v));
  std::printf("  %-20s %8.3f ms (host wall, incl. upload and submissions)\n", "total", medianMs(gpu_total));
  // Without timestamps (each drains lavapipe's queue): the figure the tracker sees.
  stages->setStageTimings(false);
  std::vector<double> untimed, cpu_ms;
  auto cpuNow = [] {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
  };
  for (int i = 0; i < 3 * runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = cpuNow();
    ASSERT_TRUE(stages->processLiveImage(gray).ok());
    cpu_ms.push_back(cpuNow() - c0);
    untimed.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::printf("  %-20s %8.3f ms (process CPU time per frame, all threads)\n", "cpu time", medianMs(cpu_ms));
  std::printf("  %-20s %8.3f ms (host wall, stage timestamps off; median of %d, min %.3f ms)\n", "total untimed",
              medianMs(untimed), 3 * runs, *std::min_element(untimed.begin(), untimed.end()));

  std::vector<double> t_pyr, t_edges, t_dt, t_total;
  for (int i = 0; i < runs; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    auto frame = buildLiveFrame(gray, camera, options);
    t_total.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    ASSERT_TRUE(frame.ok());
    double pyr = 0, edg = 0, dt = 0;
    ImageF32 g = toFloat(gray);
    for (int k = 0; k < 3; ++k) {
      t0 = std::chrono::steady_clock::now();
      if (k > 0) g = downsampleHalf(g);
      auto t1 = std::chrono::steady_clock::now();
      auto e = detectEdges(g, options.detector);
      auto t2 = std::chrono::steady_clock::now();
      auto f = computeDistanceField(*e, options.truncation_px);
      auto t3 = std::chrono::steady_clock::now();
      pyr += std::chrono::duration<double, std::milli>(t1 - t0).count();
      edg += std::chrono::duration<double, std::milli>(t2 - t1).count();
      dt += std::chrono::duration<double, std::milli>(t3 - t2).count();
    }
    t_pyr.push_back(pyr);
    t_edges.push_back(edg);
    t_dt.push_back(dt);
  }
  std::printf("CPU live frame 640x480, 3 levels, median of %d:\n", runs);
  std::printf("  %-20s %8.3f ms\n  %-20s %8.3f ms\n  %-20s %8.3f ms\n  %-20s %8.3f ms\n", "toFloat+pyramid",
              medianMs(t_pyr), "detectEdges", medianMs(t_edges), "distance field", medianMs(t_dt), "buildLiveFrame",
              medianMs(t_total));

  auto live = stages->readLiveFrame();
  ASSERT_TRUE(live.ok());
  const Pose T = Pose::Identity();
  const std::vector<EdgePoint> points = pointsNearEdges(live->levels[0], T, 20000, 3);
  ASSERT_TRUE(stages->setReference(points).ok());
  std::vector<double> g_res, g_acc, g_res_dev, g_acc_dev, c_res, c_acc;
  for (int i = 0; i < runs + 2; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(stages->residuals(T, 0).ok());
    const double dev_r = stages->lastTimings().empty() ? 0 : stages->lastTimings()[0].ms;
    auto t1 = std::chrono::steady_clock::now();
    ASSERT_TRUE(stages->accumulate(T, 0, 1.0, 5.0).ok());
    const double dev_a = stages->lastTimings().empty() ? 0 : stages->lastTimings()[0].ms;
    auto t2 = std::chrono::steady_clock::now();
    auto r = evaluateEdgeResiduals(points, T, live->levels[0]);
    auto t3 = std::chrono::steady_clock::now();
    auto eq = accumulateEdgeNormalEquations(points, T, live->levels[0], 1.0, 5.0);
    auto t4 = std::chrono::steady_clock::now();
    if (i < 2) continue;
    g_res.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    g_acc.push_back(std::chrono::duration<double, std::milli>(t2 - t1).count());
    g_res_dev.push_back(dev_r);
    g_acc_dev.push_back(dev_a);
    c_res.push_back(std::chrono::duration<double, std::milli>(t3 - t2).count());
    c_acc.push_back(std::chrono::duration<double, std::milli>(t4 - t3).count());
    EXPECT_GT(eq[kEdgeNormalCountIndex] + r.size(), 0.0);
  }
  std::printf("20000 points, level 0, median of %d (device / host wall):\n", runs);
  std::printf("  GPU residuals        %8.3f / %8.3f ms\n", medianMs(g_res_dev), medianMs(g_res));
  std::printf("  GPU normal equations %8.3f / %8.3f ms\n", medianMs(g_acc_dev), medianMs(g_acc));
  std::printf("  CPU residuals        %8.3f ms\n  CPU normal equations %8.3f ms\n", medianMs(c_res), medianMs(c_acc));

  // One Gauss-Newton evaluation (residuals, scale, normal equations in one submission) at the
  // reference budget of 4000 points: what the tracker pays per iteration.
  const std::vector<EdgePoint> budget(points.begin(), points.begin() + std::min<size_t>(4000, points.size()));
  ASSERT_TRUE(stages->setReference(budget).ok());
  std::vector<double> e_wall;
  std::map<std::string, std::vector<double>> e_stage;
  for (int i = 0; i < runs + 2; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(stages->evaluate(T, 0, 5.0, 5, 0.1).ok());
    auto t1 = std::chrono::steady_clock::now();
    if (i < 2) continue;
    e_wall.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    for (const GpuStageTiming& st : stages->lastTimings()) e_stage[st.stage].push_back(st.ms);
  }
  std::printf("%zu points, one evaluate() (device per stage; host wall):\n", budget.size());
  for (auto& [stage, ms] : e_stage) std::printf("  %-20s %8.3f ms\n", stage.c_str(), medianMs(ms));
  std::printf("  %-20s %8.3f ms\n", "host wall", medianMs(e_wall));
}

}  // namespace
}  // namespace vkloc::test
