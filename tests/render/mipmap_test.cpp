// Texture mip chains and the CPU reference renderer's trilinear sampling: level sizes and
// filter, no aliasing on a far striped plane, many textured materials in their places.
#include "vkloc/render/mipmap.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "support/analytic_scenes.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc {
namespace {

Texture makeTexture(int w, int h, uint32_t seed) {
  Texture t;
  t.name = "random";
  t.width = w;
  t.height = h;
  t.rgba.resize(static_cast<size_t>(w) * h * 4);
  for (size_t i = 0; i < t.rgba.size(); ++i) {
    seed = seed * 1664525u + 1013904223u;
    t.rgba[i] = static_cast<uint8_t>(seed >> 24);
  }
  return t;
}

uint8_t texel(const Texture& t, int x, int y, int c) { return t.rgba[(static_cast<size_t>(y) * t.width + x) * 4 + c]; }

TEST(Mipmap, LevelCountsAndSizesFollowVulkan) {
  EXPECT_EQ(textureMipLevelCount(1, 1), 1);
  EXPECT_EQ(textureMipLevelCount(2, 1), 2);
  EXPECT_EQ(textureMipLevelCount(256, 256), 9);
  EXPECT_EQ(textureMipLevelCount(1024, 256), 11);
  EXPECT_EQ(textureMipLevelCount(5, 3), 3);
  EXPECT_EQ(textureMipLevelCount(0, 3), 0);
  const std::vector<Texture> levels = buildMipLevels(makeTexture(37, 10, 1));
  // 37x10 -> 18x5 -> 9x2 -> 4x1 -> 2x1 -> 1x1.
  const int expected[][2] = {{18, 5}, {9, 2}, {4, 1}, {2, 1}, {1, 1}};
  ASSERT_EQ(levels.size(), 5u);
  for (size_t k = 0; k < levels.size(); ++k) {
    EXPECT_EQ(levels[k].width, expected[k][0]);
    EXPECT_EQ(levels[k].height, expected[k][1]);
    EXPECT_EQ(levels[k].rgba.size(), static_cast<size_t>(levels[k].width) * levels[k].height * 4);
  }
  EXPECT_TRUE(buildMipLevels(makeTexture(1, 1, 2)).empty());
}

TEST(Mipmap, EvenSizesAverageTwoByTwoBlocks) {
  const Texture base = makeTexture(16, 8, 7);
  const Texture half = downsampleTexture(base);
  ASSERT_EQ(half.width, 8);
  ASSERT_EQ(half.height, 4);
  for (int y = 0; y < half.height; ++y) {
    for (int x = 0; x < half.width; ++x) {
      for (int c = 0; c < 4; ++c) {
        const int sum = texel(base, 2 * x, 2 * y, c) + texel(base, 2 * x + 1, 2 * y, c) +
                        texel(base, 2 * x, 2 * y + 1, c) + texel(base, 2 * x + 1, 2 * y + 1, c);
        EXPECT_EQ(texel(half, x, y, c), static_cast<int>(std::lround(sum / 4.0))) << x << "," << y;
      }
    }
  }
}

TEST(Mipmap, OddSizesSampleLikeALinearBlit) {
  // 5 -> 2 texels: destination centres map to source x = (k + 0.5) * 2.5 - 0.5 = 0.75 and 3.25.
  Texture row;
  row.width = 5;
  row.height = 1;
  for (int v : {0, 40, 80, 120, 200}) row.rgba.insert(row.rgba.end(), {uint8_t(v), uint8_t(v), 0, 255});
  const Texture half = downsampleTexture(row);
  ASSERT_EQ(half.width, 2);
  ASSERT_EQ(half.height, 1);
  EXPECT_EQ(texel(half, 0, 0, 0), 30);   // 0.25 * 0 + 0.75 * 40
  EXPECT_EQ(texel(half, 1, 0, 0), 140);  // 0.75 * 120 + 0.25 * 200
  EXPECT_EQ(texel(half, 0, 0, 3), 255);
}

TEST(Mipmap, ConstantTextureStaysConstantAtEveryLevel) {
  Texture t = makeTexture(300, 77, 3);
  for (size_t i = 0; i < t.rgba.size(); i += 4) {
    t.rgba[i] = 12;
    t.rgba[i + 1] = 200;
    t.rgba[i + 2] = 99;
    t.rgba[i + 3] = 255;
  }
  for (const Texture& level : buildMipLevels(t)) {
    for (size_t i = 0; i < level.rgba.size(); i += 4) {
      ASSERT_EQ(level.rgba[i], 12);
      ASSERT_EQ(level.rgba[i + 1], 200);
      ASSERT_EQ(level.rgba[i + 2], 99);
    }
  }
}

// The striped ground of the aliasing tests: 64-texel stripes, 2 repeats per metre (128 texels
// per metre), seen from 3 m above looking 20 m ahead. The nearest visible ground is at camera
// z ~6.5 m, where a pixel covers ~2.8 texels across the stripes: every covered pixel is
// minified by at least a factor 2 (level of detail >= 1), where the stripes average out.
struct StripedGround {
  PinholeCamera cam{300.0, 300.0, 159.5, 119.5, 320, 240};
  Pose T_world_camera = test::cameraLookingAt({0.3, 0, 3}, {0.3, 20, 0});
  Model model = test::makeTexturedGround(60.0, test::makeStripeTexture(64), 240.0);
};

TEST(ReferenceRenderTexture, FarStripedPlaneRendersItsMeanColourWithoutAliasing) {
  const StripedGround scene;
  auto out = renderReference(scene.model, scene.cam, scene.T_world_camera);
  ASSERT_TRUE(out.ok()) << out.error().message;
  // The scene aliases without mip-mapping: level-0 bilinear lookups at the pixel centres
  // (what the renderers did before) spread over the whole range.
  const Eigen::Vector3d n(0, 0, 1);
  double sum = 0, worst = 0, level0_sq = 0;
  int covered = 0;
  for (int v = 0; v < scene.cam.height; ++v) {
    for (int u = 0; u < scene.cam.width; ++u) {
      if (out->depth.at(u, v) <= 0) continue;
      ++covered;
      const double value = out->rgba.at(u, v, 0);
      sum += value;
      worst = std::max(worst, std::abs(value - 127.5));
      const auto ray = test::pixelRay(scene.cam, scene.T_world_camera, u, v);
      const auto t = test::rayPlane(ray, Eigen::Vector3d::Zero(), n);
      if (!t) continue;
      const Eigen::Vector3d p = ray.origin + *t * ray.direction;
      const double s_coord = (p.x() + 60.0) * 2.0, t_coord = (60.0 - p.y()) * 2.0;
      const double level0 = test::sampleTextureBilinear(scene.model.textures[0], s_coord, t_coord)[0];
      level0_sq += (level0 - 127.5) * (level0 - 127.5);
    }
  }
  ASSERT_GT(covered, scene.cam.width * scene.cam.height / 3);
  EXPECT_GT(std::sqrt(level0_sq / covered), 40.0);  // aliasing without mip levels
  EXPECT_NEAR(sum / covered, 127.5, 1.0);
  // Level 1 of 1-texel stripes is uniform (127.5 rounded): every pixel at the mean.
  EXPECT_LE(worst, 1.0);
}

TEST(ReferenceRenderTexture, LevelOfDetailIsLog2OfTexelsPerPixel) {
  // A fronto-parallel quad showing a 64-texel texture over 16 pixels: 4 texels per pixel,
  // level of detail 2 exactly. Level 2 of a texture whose level 0 is a 4x4-periodic pattern is
  // constant, so the render equals level 2's (and 3's) single colour.
  Texture tex = test::makeCheckerTexture(64, {0, 0, 0, 255}, {255, 255, 255, 255});
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) tex.rgba[(static_cast<size_t>(y) * 64 + x) * 4 + 2] = (x % 4) * 60;
  }
  Model quad = test::makeQuad({-0.5, -0.5, 2.0}, {1, 0, 0}, {0, 1, 0});
  quad.textures = {tex};
  quad.materials = {Material{"m", {1, 1, 1, 1}, 0}};
  // 1 m at 2 m with fx = 32: 16 pixels across the quad.
  PinholeCamera cam{32.0, 32.0, 15.5, 15.5, 32, 32};
  auto out = renderReference(quad, cam, Pose::Identity());
  ASSERT_TRUE(out.ok()) << out.error().message;
  const std::vector<Texture> levels = buildMipLevels(tex);
  const uint8_t expected_g = levels[1].rgba[1], expected_b = levels[1].rgba[2];
  int checked = 0;
  for (int v = 9; v < 23; ++v) {
    for (int u = 9; u < 23; ++u) {
      ASSERT_GT(out->depth.at(u, v), 0.0f);
      EXPECT_NEAR(out->rgba.at(u, v, 1), expected_g, 1) << u << "," << v;
      EXPECT_NEAR(out->rgba.at(u, v, 2), expected_b, 1) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(ReferenceRenderTexture, ThreeHundredMaterialsEachShowTheirOwnTexture) {
  // 20 x 15 tiles of 28 px at a 32 px pitch, 8 x 8 texels each (3.5 px per texel).
  const int cols = 20, rows = 15;
  const double z = 2.0, pitch = 0.128, size = 0.112;
  const Model wall = test::makeTileWall(cols, rows, z, pitch, size);
  ASSERT_EQ(wall.textures.size(), 300u);
  ASSERT_TRUE(validateModel(wall).ok()) << validateModel(wall).error().message;
  std::set<std::array<uint8_t, 4>> colours;
  for (int k = 0; k < cols * rows; ++k) {
    colours.insert(test::tileColor(k, 0));
    colours.insert(test::tileColor(k, 1));
  }
  ASSERT_EQ(colours.size(), 600u);
  const PinholeCamera cam{500.0, 500.0, 319.5, 239.5, 640, 480};
  auto renderer = CpuRenderer::create(wall);
  ASSERT_TRUE(renderer.ok());
  auto out = (*renderer)->render(cam, Pose::Identity(), RenderSettings{});
  ASSERT_TRUE(out.ok()) << out.error().message;
  for (int k = 0; k < cols * rows; ++k) {
    // Texels 1 and 6 sit inside their quadrants (bilinear neighbours of the same colour).
    for (const auto& [tx, ty] : {std::pair{1, 1}, std::pair{6, 1}, std::pair{1, 6}, std::pair{6, 6}}) {
      const auto px = test::tileTexelPixel(cam, cols, rows, z, pitch, size, k, tx, ty);
      const auto expected = test::tileColor(k, (tx < 4) == (ty < 4) ? 0 : 1);
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(out->rgba.at(px[0], px[1], c), expected[c]) << "tile " << k << " texel " << tx << "," << ty;
      }
    }
  }
}

}  // namespace
}  // namespace vkloc
