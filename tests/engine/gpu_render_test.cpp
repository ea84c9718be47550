// GPU renderer against analytic scenes and the CPU reference renderer.
#include <gtest/gtest.h>

#include <cmath>

#include "support/analytic_scenes.hpp"
#include "support/gpu_test_support.hpp"
#include "support/test_support.hpp"
#include "vkloc/model/model_write.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::test {
namespace {

PinholeCamera vga() { return PinholeCamera{520.0, 520.0, 319.5, 239.5, 640, 480}; }

class GpuRender : public GpuTest {
 protected:
  RenderOutput render(const Model& model, const PinholeCamera& cam, const Pose& T_world_camera,
                      const RenderSettings& settings = {}) {
    auto renderer = GpuRenderer::create(context_, model);
    EXPECT_TRUE(renderer.ok()) << (renderer.ok() ? "" : renderer.error().message);
    if (!renderer.ok()) return {};
    auto out = (*renderer)->render(cam, T_world_camera, settings);
    EXPECT_TRUE(out.ok()) << (out.ok() ? "" : out.error().message);
    return out.ok() ? std::move(*out) : RenderOutput{};
  }
};

// Counts pixels where coverage differs between two depth maps and which have no pixel within
// one pixel (8-neighbourhood) where the other image's coverage matches: those are silhouette
// errors larger than 1 px.
int silhouetteErrorsBeyondOnePixel(const ImageF32& a, const ImageF32& b) {
  int bad = 0;
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const bool ca = a.at(x, y) > 0, cb = b.at(x, y) > 0;
      if (ca == cb) continue;
      bool near_boundary = false;
      for (int dy = -1; dy <= 1 && !near_boundary; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= a.width || yy >= a.height) continue;
          if ((b.at(xx, yy) > 0) == ca) {
            near_boundary = true;
            break;
          }
        }
      }
      bad += !near_boundary;
    }
  }
  return bad;
}

TEST_F(GpuRender, PlaneDepthMatchesAnalyticOverNearAndFarRange) {
  // Tilted planes at 0.1 m .. 2 km: the linear depth output is exact to 1e-4 relative.
  for (double distance : {0.12, 1.5, 40.0, 600.0, 1900.0}) {
    const Eigen::Vector3d normal = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
    const Eigen::Vector3d centre(0, 0, 0);
    const Model plane = makePlane(centre, normal, 10.0 * distance);
    const Pose T_world_camera = cameraLookingAt(centre + normal * distance + Eigen::Vector3d(0.1, 0.05, 0) * distance,
                                                centre, Eigen::Vector3d::UnitY());
    RenderSettings s;
    s.near_m = 0.1;
    s.far_m = 2500.0;
    const PinholeCamera cam = vga();
    const RenderOutput out = render(plane, cam, T_world_camera, s);
    ASSERT_FALSE(out.depth.empty());
    double worst = 0;
    int compared = 0;
    for (int v = 0; v < cam.height; v += 3) {
      for (int u = 0; u < cam.width; u += 3) {
        const auto t = rayPlane(pixelRay(cam, T_world_camera, u, v), centre, normal);
        const float z = out.depth.at(u, v);
        if (!t || *t > s.far_m) continue;
        ASSERT_GT(z, 0.0f) << "no surface at " << u << "," << v << " distance " << distance;
        worst = std::max(worst, std::abs(z - *t) / *t);
        ++compared;
      }
    }
    EXPECT_GT(compared, 10000);
    // The issue asks for 1e-4; float reverse-Z with 1 / gl_FragCoord.w measures ~2e-7 at every
    // distance here, so a tenfold margin over that catches regressions early.
    EXPECT_LT(worst, 2e-6) << "distance " << distance;
  }
}

TEST_F(GpuRender, BoxDepthSilhouetteAndNormalsMatchAnalytic) {
  const Eigen::Vector3d lo(-1, -0.5, -0.8), hi(1.2, 0.7, 0.9);
  const Model box = makeBox(lo, hi);
  // Non-square pixels and an off-centre principal point (seed 001 eqs. 7-8).
  const PinholeCamera cam{480.0, 610.0, 290.3, 260.8, 640, 480};
  const Pose T_world_camera = cameraLookingAt({3.1, -2.4, 1.9}, {0.1, 0.05, 0.0});
  const RenderOutput out = render(box, cam, T_world_camera);
  ASSERT_FALSE(out.depth.empty());
  ImageF32 analytic(cam.width, cam.height, 1, 0.0f);
  double worst = 0;
  double worst_normal_deg = 0;
  const Eigen::Matrix3d R_camera_world = T_world_camera.linear().transpose();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto hit = rayBox(pixelRay(cam, T_world_camera, u, v), lo, hi);
      if (!hit) continue;
      analytic.at(u, v) = static_cast<float>(hit->t);
      const float z = out.depth.at(u, v);
      if (z <= 0) continue;
      worst = std::max(worst, std::abs(z - hit->t) / hit->t);
      const Eigen::Vector3d n_expected = R_camera_world * hit->normal;
      const Eigen::Vector3d n(out.normals.at(u, v, 0), out.normals.at(u, v, 1), out.normals.at(u, v, 2));
      // Normals are per triangle; compare away from face edges where the hit face is unambiguous.
      const double angle = std::acos(std::clamp(n.dot(n_expected), -1.0, 1.0)) * 180.0 / M_PI;
      if (std::abs(z - hit->t) / hit->t < 1e-5) worst_normal_deg = std::max(worst_normal_deg, angle);
    }
  }
  // The requirement (1e-4 relative). Measured: lavapipe < 1e-5; NVIDIA H100 1.3e-5, where
  // vertices snap to the sub-pixel grid (subPixelPrecisionBits) and faces seen at a grazing
  // angle change depth fastest across a pixel.
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(worst_normal_deg, 0.5);
  EXPECT_EQ(silhouetteErrorsBeyondOnePixel(out.depth, analytic), 0);
  EXPECT_EQ(silhouetteErrorsBeyondOnePixel(analytic, out.depth), 0);
}

TEST_F(GpuRender, SphereMatchesRayCastAndReference) {
  const Model sphere = makeUvSphere({0.3, -0.2, 0.1}, 0.9, 48, 24);
  const PinholeCamera cam = vga();
  const Pose T_world_camera = cameraLookingAt({0.5, -3.0, 1.2}, {0.3, -0.2, 0.1});
  const RenderOutput out = render(sphere, cam, T_world_camera);
  auto ref = renderReference(sphere, cam, T_world_camera);
  ASSERT_TRUE(ref.ok()) << ref.error().message;
  double worst = 0;
  int compared = 0;
  for (int v = 0; v < cam.height; v += 5) {
    for (int u = 0; u < cam.width; u += 5) {
      const float z = out.depth.at(u, v);
      if (z <= 0) continue;
      const auto t = rayModel(pixelRay(cam, T_world_camera, u, v), sphere);
      if (!t) continue;
      worst = std::max(worst, std::abs(z - *t) / *t);
      ++compared;
    }
  }
  EXPECT_GT(compared, 1500);
  // 1e-4 relative, as above: lavapipe < 1e-5, NVIDIA H100 8.2e-5 (sub-pixel vertex snapping on
  // the sphere's grazing rim).
  EXPECT_LT(worst, 1e-4);
  EXPECT_EQ(silhouetteErrorsBeyondOnePixel(out.depth, ref->depth), 0);
  EXPECT_EQ(silhouetteErrorsBeyondOnePixel(ref->depth, out.depth), 0);
}

TEST_F(GpuRender, CheckerboardTextureSamplesLikeReference) {
  // Fronto-parallel textured quad: 8x8 checker texels spanning many pixels each.
  const Model quad = makeCheckerQuad({-1, -0.75, 2.0}, {2.0, 0, 0}, {0, 1.5, 0}, 8);
  const PinholeCamera cam = vga();
  const Pose T_world_camera = Pose::Identity();
  const RenderOutput out = render(quad, cam, T_world_camera);
  auto ref = renderReference(quad, cam, T_world_camera);
  ASSERT_TRUE(ref.ok()) << ref.error().message;
  int exact_checked = 0, max_diff = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (ref->depth.at(u, v) <= 0 || out.depth.at(u, v) <= 0) continue;
      for (int c = 0; c < 3; ++c) {
        max_diff = std::max(max_diff, std::abs(int(out.rgba.at(u, v, c)) - int(ref->rgba.at(u, v, c))));
      }
      // Expected colour: bilinear REPEAT lookup with texel centres at (k + 0.5) / 8.
      const double s = (u - cam.cx) / cam.fx + 0.5;  // x = (u - cx) / fx * z, z = 2, quad 2 m wide
      const double t = (v - cam.cy) / cam.fy * 2.0 / 1.5 + 0.5;
      if (s < 0.01 || s > 0.99 || t < 0.01 || t > 0.99) continue;
      const double expected = sampleTextureBilinear(quad.textures[0], s, t)[0];
      EXPECT_NEAR(out.rgba.at(u, v, 0), expected, 2.0) << u << "," << v;
      if (std::abs(out.rgba.at(u, v, 0) - expected) > 2.0) return;  // one report is enough
      ++exact_checked;
    }
  }
  EXPECT_GT(exact_checked, 100000);
  // Bilinear weights are 8-bit fixed point on some devices: allow a few levels at texel edges.
  EXPECT_LE(max_diff, 3);
}

TEST_F(GpuRender, DemoModelsMatchReference) {
  for (const std::string name : {"room", "city"}) {
    auto model = makeDemoModel(name);
    ASSERT_TRUE(model.ok());
    const PinholeCamera cam{400.0, 410.0, 161.2, 118.7, 320, 240};
    const Pose T_world_camera = demoViewpoints(name).front();
    const RenderOutput out = render(*model, cam, T_world_camera);
    auto ref = renderReference(*model, cam, T_world_camera);
    ASSERT_TRUE(ref.ok());
    double worst = 0;
    int covered_mismatch = 0, colour_far = 0, surface = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const float zg = out.depth.at(u, v), zr = ref->depth.at(u, v);
        if ((zg > 0) != (zr > 0)) ++covered_mismatch;
        if (zg <= 0 || zr <= 0) continue;
        ++surface;
        const double rel = std::abs(zg - zr) / zr;
        // Pixels on a depth discontinuity may see a different triangle; skip the few of them.
        if (rel > 1e-3) continue;
        worst = std::max(worst, rel);
        int diff = 0;
        for (int c = 0; c < 3; ++c)
          diff = std::max(diff, std::abs(int(out.rgba.at(u, v, c)) - int(ref->rgba.at(u, v, c))));
        colour_far += diff > 8;
      }
    }
    EXPECT_GT(surface, cam.width * cam.height / 4) << name;
    EXPECT_LT(worst, 1e-4) << name;
    EXPECT_EQ(silhouetteErrorsBeyondOnePixel(out.depth, ref->depth), 0) << name;
    EXPECT_LT(covered_mismatch, cam.width * cam.height / 500) << name;
    EXPECT_LT(colour_far, surface / 200) << name;
  }
}

TEST_F(GpuRender, FrustumCullingSkipsBlocksWithoutChangingTheImage) {
  DemoModelOptions options;
  auto city = makeDemoCity(options);
  Model one_block = city;
  buildBlocks(one_block, 0);
  buildBlocks(city, 300);
  ASSERT_GT(city.blocks.size(), 4u);
  const PinholeCamera cam{300, 300, 159.5, 119.5, 320, 240};
  const Pose T_world_camera = demoViewpoints("city").front();
  const RenderOutput culled = render(city, cam, T_world_camera);
  const RenderOutput all = render(one_block, cam, T_world_camera);
  EXPECT_LT(culled.blocks_drawn, city.blocks.size());
  EXPECT_LT(culled.triangles_drawn, city.triangleCount());
  EXPECT_EQ(all.triangles_drawn, one_block.triangleCount());
  EXPECT_EQ(culled.depth.data, all.depth.data);
  EXPECT_EQ(culled.rgba.data, all.rgba.data);
}

TEST_F(GpuRender, BackFaceCullingKeepsClosedModelsIdentical) {
  const Model box = makeBox({-1, -1, -1}, {1, 1, 1});
  const PinholeCamera cam = vga();
  const Pose T = cameraLookingAt({3, 2, 1.5}, {0, 0, 0});
  RenderSettings culled;
  culled.cull_back_faces = true;
  EXPECT_EQ(render(box, cam, T, culled).depth.data, render(box, cam, T).depth.data);
  // Inside the box every face is seen from behind: nothing left.
  const RenderOutput inside = render(box, cam, cameraLookingAt({0.1, 0.2, 0}, {1, 0, 0}), culled);
  for (float z : inside.depth.data) ASSERT_EQ(z, kBackgroundDepth);
}

TEST_F(GpuRender, BackFacesMatchReference) {
  // The box without its top from above (back faces through the hole, front faces around it)
  // and the closed box from inside (back faces only): the flag (gl_FrontFacing) equals the CPU
  // reference's plane-sign test on every pixel both see at the same depth, and the normal
  // stays the camera-facing one beside it.
  const Eigen::Vector3d lo(-1, -0.5, -0.8), hi(1.2, 0.7, 0.9);
  const PinholeCamera cam = vga();
  struct Case {
    Model model;
    Pose T_world_camera;
    bool expect_front;
  };
  const Case cases[] = {
      {makeBox(lo, hi, true), cameraLookingAt({2.0, -2.5, 3.5}, {0.1, 0.05, 0.2}), true},
      {makeBox(lo, hi), cameraLookingAt({0.1, 0.05, 0.2}, {1.0, 0.4, 0.5}), false},
  };
  for (const Case& c : cases) {
    const RenderOutput out = render(c.model, cam, c.T_world_camera);
    auto ref = renderReference(c.model, cam, c.T_world_camera);
    ASSERT_TRUE(ref.ok());
    ASSERT_EQ(out.back_faces.width, cam.width);
    ASSERT_EQ(out.back_faces.height, cam.height);
    int back = 0, front = 0, compared = 0, mismatched = 0;
    double worst_normal = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const float zg = out.depth.at(u, v), zr = ref->depth.at(u, v);
        if (zg <= 0) {
          EXPECT_EQ(out.back_faces.at(u, v), 0);
          continue;
        }
        if (zr <= 0 || std::abs(zg - zr) > 1e-4 * zr) continue;  // another triangle at a discontinuity
        ++compared;
        mismatched += out.back_faces.at(u, v) != ref->back_faces.at(u, v);
        (out.back_faces.at(u, v) ? back : front) += 1;
        for (int ch = 0; ch < 3; ++ch) {
          worst_normal = std::max(worst_normal, double(std::abs(out.normals.at(u, v, ch) - ref->normals.at(u, v, ch))));
        }
      }
    }
    EXPECT_GT(compared, cam.width * cam.height / 8);
    EXPECT_EQ(mismatched, 0);
    EXPECT_GT(back, 5000);
    if (c.expect_front) {
      EXPECT_GT(front, 5000);
    } else {
      EXPECT_EQ(front, 0);
    }
    EXPECT_LT(worst_normal, 1e-3);
  }
}

TEST_F(GpuRender, RejectsInvalidInputWithoutCrashing) {
  const Model box = makeBox({-1, -1, -1}, {1, 1, 1});
  auto renderer = GpuRenderer::create(context_, box);
  ASSERT_TRUE(renderer.ok());
  Pose nan_pose = Pose::Identity();
  nan_pose.translation().x() = NAN;
  EXPECT_FALSE((*renderer)->render(vga(), nan_pose).ok());
  PinholeCamera bad = vga();
  bad.width = 0;
  EXPECT_FALSE((*renderer)->render(bad, Pose::Identity()).ok());
  bad = vga();
  bad.fx = NAN;
  EXPECT_FALSE((*renderer)->render(bad, Pose::Identity()).ok());
  RenderSettings s;
  s.near_m = 0;
  EXPECT_FALSE((*renderer)->render(vga(), Pose::Identity(), s).ok());
  Model broken = box;
  broken.indices.push_back(999);
  EXPECT_FALSE(GpuRenderer::create(context_, broken).ok());
  // Still renders afterwards, at a new size too.
  PinholeCamera small{100, 100, 49.5, 39.5, 100, 80};
  auto out = (*renderer)->render(small, cameraLookingAt({3, 0, 0}, {0, 0, 0}));
  ASSERT_TRUE(out.ok());
  EXPECT_EQ(out->depth.width, 100);
  EXPECT_GT(out->depth.at(50, 40), 0.0f);
}

TEST_F(GpuRender, RenderOnGpuThenReadbackEqualsRender) {
  auto room = makeDemoModel("room");
  ASSERT_TRUE(room.ok());
  auto renderer = GpuRenderer::create(context_, *room);
  ASSERT_TRUE(renderer.ok());
  const Pose T = demoViewpoints("room").front();
  EXPECT_FALSE((*renderer)->readback().ok());  // nothing rendered yet
  auto a = (*renderer)->render(vga(), T);
  auto b = (*renderer)->renderOnGpu(vga(), T);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->triangles_drawn, b->triangles_drawn);
  EXPECT_TRUE(b->depth.empty());
  auto c = (*renderer)->readback();
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->depth.data, a->depth.data);
  EXPECT_EQ(c->rgba.data, a->rgba.data);
  EXPECT_EQ(c->normals.data, a->normals.data);
  EXPECT_EQ(c->back_faces.data, a->back_faces.data);
}

TEST_F(GpuRender, LevelOfDetailStaysWithinItsPixelErrorBound) {
  // An enlarged city whose subdivided faces are made rough, seen from far away: level of
  // detail draws fewer triangles and the depth map stays close to the full-detail one.
  DemoModelOptions options;
  options.target_triangles = 60000;
  Model city = makeDemoCity(options);
  for (size_t i = 0; i < city.positions.size(); ++i) {
    city.positions[i] += 0.02f * static_cast<float>(std::sin(1.7 * city.positions[(i / 3) * 3] + 3.1 * (i % 3)));
  }
  buildBlocks(city, 4096);
  auto renderer = GpuRenderer::create(context_, city);
  GpuRendererOptions no_lod_options;
  no_lod_options.lod_levels = 0;
  auto no_lod = GpuRenderer::create(context_, city, no_lod_options);
  ASSERT_TRUE(renderer.ok() && no_lod.ok());
  const PinholeCamera cam = vga();
  auto T = lookAt({-200, -200, 230}, {0, 0, 0});
  ASSERT_TRUE(T.ok());
  RenderSettings exact;
  RenderSettings lod;
  lod.lod_pixel_error = 0.5;
  auto full = (*renderer)->render(cam, *T, exact);
  auto full_no_levels = (*no_lod)->render(cam, *T, exact);
  auto reduced = (*renderer)->render(cam, *T, lod);
  ASSERT_TRUE(full.ok() && full_no_levels.ok() && reduced.ok());
  EXPECT_EQ(full->depth.data, full_no_levels->depth.data);  // lod_pixel_error 0: full detail
  EXPECT_LT(reduced->triangles_drawn, full->triangles_drawn * 3 / 4);
  int both = 0, close = 0, coverage_diff = 0;
  for (size_t i = 0; i < full->depth.data.size(); ++i) {
    const float a = full->depth.data[i], b = reduced->depth.data[i];
    coverage_diff += (a > 0) != (b > 0);
    if (a <= 0 || b <= 0) continue;
    ++both;
    // 0.5 px at ~350 m is ~0.35 m of surface error along the view ray at most.
    close += std::abs(a - b) < 0.5f;
  }
  EXPECT_GT(close, both * 97 / 100);
  EXPECT_LT(coverage_diff, static_cast<int>(full->depth.data.size() / 200));
}

TEST_F(GpuRender, DracoEncodedModelRendersLikeItsSource) {
  // The demo room written as Draco (standalone .drc and glTF with KHR_draco_mesh_compression),
  // loaded back and rendered: depth within the quantization step, same colours.
  auto room = makeDemoModel("room");
  ASSERT_TRUE(room.ok());
  TempDir dir("vkloc_draco");
  const PinholeCamera cam{450, 450, 159.5, 119.5, 320, 240};
  const Pose T = demoViewpoints("room").front();
  auto source = GpuRenderer::create(context_, *room);
  ASSERT_TRUE(source.ok());
  auto expected = (*source)->render(cam, T);
  ASSERT_TRUE(expected.ok());
  ModelWriteOptions options;
  options.draco = true;
  options.draco_position_bits = 16;
  for (const char* name : {"room.glb", "room.drc"}) {
    ASSERT_TRUE(saveModel(*room, dir.file(name), options).ok()) << name;
    auto loaded = loadModel(dir.file(name));
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    auto renderer = GpuRenderer::create(context_, *loaded);
    ASSERT_TRUE(renderer.ok());
    auto out = (*renderer)->render(cam, T);
    ASSERT_TRUE(out.ok());
    // Quantization step: largest bounds extent / 2^bits (about 0.1 mm here).
    double extent = 0;
    for (int k = 0; k < 3; ++k) extent = std::max<double>(extent, room->bounds.max[k] - room->bounds.min[k]);
    const double step = extent / (1 << options.draco_position_bits);
    int both = 0, within = 0, colour_close = 0;
    for (size_t i = 0; i < out->depth.data.size(); ++i) {
      const float a = expected->depth.data[i], b = out->depth.data[i];
      if (a <= 0 || b <= 0) continue;
      ++both;
      within += std::abs(a - b) <= 4 * step + 1e-5 * a;
      int diff = 0;
      for (int c = 0; c < 3; ++c)
        diff = std::max(diff, std::abs(int(expected->rgba.data[i * 4 + c]) - int(out->rgba.data[i * 4 + c])));
      colour_close += diff <= 12;
    }
    EXPECT_GT(both, static_cast<int>(out->depth.data.size() * 9 / 10)) << name;
    // Pixels on depth edges may see another surface after quantization: a few are allowed.
    EXPECT_GT(within, both * 99 / 100) << name;
    if (std::string(name) == "room.glb") {  // .drc carries no materials or textures
      EXPECT_GT(colour_close, both * 98 / 100) << name;
    }
    EXPECT_EQ(silhouetteErrorsBeyondOnePixel(out->depth, expected->depth), 0) << name;
  }
}

TEST_F(GpuRender, StagingAndDirectMemoryPathsAgree) {
  // The discrete-GPU path (device-local buffers filled through staging copies, targets copied
  // to a readback buffer) and the unified-memory path (mapped buffers, linear targets read
  // directly) produce identical outputs, with normals and without.
  auto room = makeDemoModel("room");
  ASSERT_TRUE(room.ok());
  GpuOptions staging_options;
  staging_options.validation = 1;
  staging_options.force_staging = true;
  auto staging_context = GpuContext::create(staging_options);
  ASSERT_TRUE(staging_context.ok());
  auto a = GpuRenderer::create(*staging_context, *room);
  auto b = GpuRenderer::create(context_, *room);
  ASSERT_TRUE(a.ok() && b.ok());
  const Pose T = demoViewpoints("room").back();
  auto ra = (*a)->render(vga(), T);
  auto rb = (*b)->render(vga(), T);
  ASSERT_TRUE(ra.ok() && rb.ok());
  EXPECT_EQ(ra->rgba.data, rb->rgba.data);
  EXPECT_EQ(ra->gray.data, rb->gray.data);
  EXPECT_EQ(ra->depth.data, rb->depth.data);
  EXPECT_EQ(ra->normals.data, rb->normals.data);
  EXPECT_EQ(ra->back_faces.data, rb->back_faces.data);
  RenderSettings no_normals;
  no_normals.outputs = kRenderColor | kRenderDepth;
  auto na = (*a)->render(vga(), T, no_normals);
  auto nb = (*b)->render(vga(), T, no_normals);
  ASSERT_TRUE(na.ok() && nb.ok());
  EXPECT_TRUE(na->normals.empty());
  EXPECT_TRUE(na->back_faces.empty());
  EXPECT_EQ(na->depth.data, ra->depth.data);
  EXPECT_EQ(na->rgba.data, nb->rgba.data);
  EXPECT_EQ((*staging_context)->validationMessages(), 0u);
}

}  // namespace
}  // namespace vkloc::test
