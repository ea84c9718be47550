// GPU renderer textures: any number of them (batched descriptor sets), mip chains made by blits
// or on the host, trilinear sampling against the CPU reference.
#include <gtest/gtest.h>

#include <cmath>

#include "support/analytic_scenes.hpp"
#include "support/gpu_test_support.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc::test {
namespace {

class GpuTexture : public GpuTest {
 protected:
  RenderOutput render(const Model& model, const PinholeCamera& cam, const Pose& T_world_camera,
                      const GpuRendererOptions& options = {}) {
    auto renderer = GpuRenderer::create(context_, model, options);
    EXPECT_TRUE(renderer.ok()) << (renderer.ok() ? "" : renderer.error().message);
    if (!renderer.ok()) return {};
    auto out = (*renderer)->render(cam, T_world_camera, RenderSettings{});
    EXPECT_TRUE(out.ok()) << (out.ok() ? "" : out.error().message);
    return out.ok() ? std::move(*out) : RenderOutput{};
  }
};

/// Colour differences between two renders over the pixels both cover at the same depth.
struct ColourDiff {
  int compared = 0;
  int max_diff = 0;
  double mean_abs = 0;
  int above(int) const;
  std::vector<int> per_pixel;  ///< Largest channel difference of each compared pixel.
};

int ColourDiff::above(int threshold) const {
  int n = 0;
  for (int d : per_pixel) n += d > threshold;
  return n;
}

ColourDiff colourDiff(const RenderOutput& a, const RenderOutput& b) {
  ColourDiff r;
  double sum = 0;
  for (size_t i = 0; i < a.depth.data.size(); ++i) {
    const float za = a.depth.data[i], zb = b.depth.data[i];
    if (za <= 0 || zb <= 0 || std::abs(za - zb) > 1e-3f * zb) continue;
    int d = 0;
    for (int c = 0; c < 3; ++c) {
      const int e = std::abs(int(a.rgba.data[i * 4 + c]) - int(b.rgba.data[i * 4 + c]));
      d = std::max(d, e);
      sum += e;
    }
    r.max_diff = std::max(r.max_diff, d);
    r.per_pixel.push_back(d);
    ++r.compared;
  }
  r.mean_abs = r.compared > 0 ? sum / (3.0 * r.compared) : 0;
  return r;
}

TEST_F(GpuTexture, ThreeHundredTexturedMaterialsRenderInPlaceAndMatchTheReference) {
  // More textures than lavapipe's 32 samplers per stage: drawn in batches of descriptor sets.
  const int cols = 20, rows = 15;
  const double z = 2.0, pitch = 0.128, size = 0.112;
  const Model wall = makeTileWall(cols, rows, z, pitch, size);
  const PinholeCamera cam{500.0, 500.0, 319.5, 239.5, 640, 480};
  const RenderOutput out = render(wall, cam, Pose::Identity());
  ASSERT_FALSE(out.rgba.empty());
  for (int k = 0; k < cols * rows; ++k) {
    for (const auto& [tx, ty] : {std::pair{1, 1}, std::pair{6, 1}, std::pair{1, 6}, std::pair{6, 6}}) {
      const auto px = tileTexelPixel(cam, cols, rows, z, pitch, size, k, tx, ty);
      const auto expected = tileColor(k, (tx < 4) == (ty < 4) ? 0 : 1);
      for (int c = 0; c < 3; ++c) {
        // Bilinear weights are 8-bit fixed point on some devices: one level.
        ASSERT_NEAR(out.rgba.at(px[0], px[1], c), expected[c], 1)
            << "tile " << k << " texel " << tx << "," << ty << " channel " << c;
      }
    }
  }
  auto ref = renderReference(wall, cam, Pose::Identity());
  ASSERT_TRUE(ref.ok()) << ref.error().message;
  const ColourDiff diff = colourDiff(out, *ref);
  EXPECT_GT(diff.compared, 300 * 26 * 26);
  // Inside the tiles only quadrant borders blend two colours; measured on lavapipe: max 2.
  EXPECT_LE(diff.max_diff, 3);
  EXPECT_LT(diff.mean_abs, 0.1);

  // One texture per set (the fallback without dynamic indexing), odd batches and host-built
  // mip levels all give the same image.
  for (const auto& [per_set, host_mipmaps] : {std::pair{1, false}, std::pair{7, true}, std::pair{300, false}}) {
    GpuRendererOptions options;
    options.max_textures_per_set = per_set;
    options.host_mipmaps = host_mipmaps;
    const RenderOutput other = render(wall, cam, Pose::Identity(), options);
    EXPECT_EQ(other.rgba.data, out.rgba.data) << per_set << " textures per set";
  }
}

TEST_F(GpuTexture, FarStripedPlaneRendersItsMeanColourInBothRenderers) {
  // 1-texel stripes minified at least twofold everywhere (see mipmap_test.cpp): level-0
  // sampling would alias across the whole range, mip-mapped sampling stays at the mean.
  const PinholeCamera cam{300.0, 300.0, 159.5, 119.5, 320, 240};
  const Pose T_world_camera = cameraLookingAt({0.3, 0, 3}, {0.3, 20, 0});
  const Model ground = makeTexturedGround(60.0, makeStripeTexture(64), 240.0);
  for (bool host_mipmaps : {false, true}) {
    GpuRendererOptions options;
    options.host_mipmaps = host_mipmaps;
    const RenderOutput gpu = render(ground, cam, T_world_camera, options);
    auto cpu = renderReference(ground, cam, T_world_camera);
    ASSERT_TRUE(cpu.ok());
    const RenderOutput& reference = *cpu;
    for (const RenderOutput* out : {&gpu, &reference}) {
      double sum = 0, worst = 0;
      int covered = 0;
      for (int v = 0; v < cam.height; ++v) {
        for (int u = 0; u < cam.width; ++u) {
          if (out->depth.at(u, v) <= 0) continue;
          ++covered;
          sum += out->rgba.at(u, v, 0);
          worst = std::max(worst, std::abs(out->rgba.at(u, v, 0) - 127.5));
        }
      }
      const char* which = out == &gpu ? (host_mipmaps ? "GPU, host mip levels" : "GPU, blit mip levels") : "CPU";
      ASSERT_GT(covered, cam.width * cam.height / 3) << which;
      EXPECT_NEAR(sum / covered, 127.5, 1.0) << which;
      // Level 1 of 1-texel stripes is 127 or 128 whichever way it is rounded.
      EXPECT_LE(worst, 1.5) << which;
    }
  }
}

TEST_F(GpuTexture, MipMappedViewMatchesTheReference) {
  // A detailed texture on the ground seen at a grazing angle: levels of detail from
  // magnification near the camera to the last levels at the far end.
  const PinholeCamera cam{400.0, 400.0, 159.5, 119.5, 320, 240};
  const Pose T_world_camera = cameraLookingAt({0.2, 0, 1.5}, {0.2, 12, 0});
  const Model ground = makeTexturedGround(40.0, makeDetailTexture(256), 40.0);
  auto cpu = renderReference(ground, cam, T_world_camera);
  ASSERT_TRUE(cpu.ok());
  for (bool host_mipmaps : {false, true}) {
    GpuRendererOptions options;
    options.host_mipmaps = host_mipmaps;
    const RenderOutput gpu = render(ground, cam, T_world_camera, options);
    const ColourDiff diff = colourDiff(gpu, *cpu);
    ASSERT_GT(diff.compared, cam.width * cam.height / 3);
    EXPECT_LT(diff.above(8), diff.compared / 200);
  }
}

TEST_F(GpuTexture, ModelWithoutTexturesStillRenders) {
  const Model quad = makeQuad({-0.5, -0.5, 2.0}, {1, 0, 0}, {0, 1, 0});
  const RenderOutput out = render(quad, PinholeCamera{500, 500, 319.5, 239.5, 640, 480}, Pose::Identity());
  ASSERT_FALSE(out.rgba.empty());
  EXPECT_EQ(out.rgba.at(320, 240, 0), 255);
}

}  // namespace
}  // namespace vkloc::test
