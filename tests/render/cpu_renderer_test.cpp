// Tests of the CPU reference renderer against analytic ground truth.
#include "vkloc/render/cpu_renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "support/analytic_scenes.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

using test::Ray;

RenderOutput renderOk(const Model& model, const PinholeCamera& camera, const Pose& T_world_camera,
                      const RenderSettings& settings = {}) {
  Result<RenderOutput> r = renderReference(model, camera, T_world_camera, settings);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().message);
  if (!r.ok()) return {};
  return std::move(r).value();
}

bool covered(const RenderOutput& out, int i, int j) { return out.depth.at(i, j) != kBackgroundDepth; }

double relativeError(double a, double b) { return std::abs(a - b) / std::abs(b); }

/// Counts pixels where the rendered coverage differs from `expected` (nullopt where the
/// pixel is ambiguous and skipped), checks depth where both see a surface, and checks that
/// every coverage mismatch lies next to a change of expected coverage (within 1 px of the
/// analytic silhouette). Returns the number of mismatches.
int compareWithAnalytic(const RenderOutput& out, const PinholeCamera& cam,
                        const std::function<std::optional<double>(int, int)>& expected_depth,
                        double depth_tolerance = 1e-6) {
  const int w = cam.width;
  const int h = cam.height;
  std::vector<int> hit(static_cast<size_t>(w) * h);
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const auto d = expected_depth(i, j);
      hit[static_cast<size_t>(j) * w + i] = d ? 1 : 0;
      if (d && covered(out, i, j)) {
        EXPECT_LT(relativeError(out.depth.at(i, j), *d), depth_tolerance)
            << "pixel " << i << "," << j << " rendered " << out.depth.at(i, j) << " analytic " << *d;
      }
    }
  }
  int mismatches = 0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const int expected = hit[static_cast<size_t>(j) * w + i];
      if (expected == (covered(out, i, j) ? 1 : 0)) continue;
      ++mismatches;
      bool near_boundary = false;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const int x = i + di;
          const int y = j + dj;
          if (x < 0 || y < 0 || x >= w || y >= h) continue;
          near_boundary = near_boundary || hit[static_cast<size_t>(y) * w + x] != expected;
        }
      }
      EXPECT_TRUE(near_boundary) << "coverage differs far from the silhouette at " << i << "," << j;
    }
  }
  return mismatches;
}

bool allFinite(const ImageF32& image) {
  for (float v : image.data) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

// --- 1. planes --------------------------------------------------------------------------------

TEST(ReferenceRender, FrontoParallelPlaneDepthIsExact) {
  const PinholeCamera cam;
  const Pose T = test::cameraLookingAt({0.25, -3.0, 0.5}, {0.1, 0.0, 0.4});
  // The plane y = 0 facing -y (towards the camera), large enough to fill the view.
  const Model plane = test::makePlane({0, 0, 0}, {0, -1, 0}, 100.0);
  const RenderOutput out = renderOk(plane, cam, T);
  const int mismatches = compareWithAnalytic(out, cam, [&](int i, int j) {
    return test::rayPlane(test::pixelRay(cam, T, i, j), {0, 0, 0}, {0, -1, 0});
  });
  EXPECT_EQ(mismatches, 0);
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < cam.width; ++i) ASSERT_TRUE(covered(out, i, j)) << i << "," << j;
  }
  EXPECT_EQ(out.blocks_drawn, 1u);
  EXPECT_EQ(out.triangles_drawn, 2u);
}

TEST(ReferenceRender, TiltedPlaneDepthClippedByNearAndFar) {
  const PinholeCamera cam;
  const Pose T = test::cameraLookingAt({0.3, -4.0, 1.2}, {0.0, 0.0, 0.5});
  // Quad on the plane 4 z = x (normal (-1, 0, 4)), corners exactly representable in float;
  // it reaches behind the camera (near clipping) and beyond the far plane.
  Model plane = test::makeQuad({-30, -30, -7.5}, {60, 0, 15}, {0, 60, 0});
  RenderSettings settings;
  settings.far_m = 20.0;
  const RenderOutput out = renderOk(plane, cam, T, settings);
  ASSERT_TRUE(allFinite(out.depth));
  int far_cut = 0;
  const int mismatches = compareWithAnalytic(out, cam, [&](int i, int j) -> std::optional<double> {
    const Ray ray = test::pixelRay(cam, T, i, j);
    const auto t = test::rayPlane(ray, {0, 0, 0}, {-1, 0, 4});
    if (!t) return std::nullopt;
    const Eigen::Vector3d p = ray.origin + *t * ray.direction;
    if (std::abs(p.x()) > 30 || std::abs(p.y()) > 30) return std::nullopt;
    if (*t > settings.far_m) {
      ++far_cut;
      return std::nullopt;
    }
    return t;
  });
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(far_cut, 1000);  // The far plane does cut the view.
}

// --- 2, 8. box: depth, silhouette, normals ---------------------------------------------------

struct BoxScene {
  PinholeCamera cam;
  Pose T = test::cameraLookingAt({2.5, -3.0, 2.0}, {0.0, 0.0, 0.5});
  Eigen::Vector3d lo{-0.5, -0.375, 0.0};
  Eigen::Vector3d hi{0.625, 0.5, 1.25};
  Model model = test::makeBox(lo, hi);
};

TEST(ReferenceRender, BoxDepthAndSilhouetteMatchRayBox) {
  const BoxScene s;
  const RenderOutput out = renderOk(s.model, s.cam, s.T);
  int surface = 0;
  const int mismatches = compareWithAnalytic(out, s.cam, [&](int i, int j) -> std::optional<double> {
    const auto hit = test::rayBox(test::pixelRay(s.cam, s.T, i, j), s.lo, s.hi);
    if (!hit) return std::nullopt;
    ++surface;
    return hit->t;
  });
  EXPECT_GT(surface, 10000);
  EXPECT_LE(mismatches, 2);  // Only exact ties of a pixel centre on the silhouette may differ.
  EXPECT_EQ(out.triangles_drawn, 12u);
}

TEST(ReferenceRender, BoxNormalsAreCameraFrameFaceNormals) {
  const BoxScene s;
  const RenderOutput out = renderOk(s.model, s.cam, s.T);
  ASSERT_EQ(out.normals.channels, 3);
  const Eigen::Matrix3d R_camera_world = s.T.linear().transpose();
  int checked = 0;
  int faces_seen[6] = {};
  for (int j = 0; j < s.cam.height; ++j) {
    for (int i = 0; i < s.cam.width; ++i) {
      const Ray ray = test::pixelRay(s.cam, s.T, i, j);
      const auto hit = test::rayBox(ray, s.lo, s.hi);
      const Eigen::Vector3f n(out.normals.at(i, j, 0), out.normals.at(i, j, 1), out.normals.at(i, j, 2));
      if (!covered(out, i, j)) {
        EXPECT_EQ(n, Eigen::Vector3f::Zero());
        continue;
      }
      EXPECT_NEAR(n.norm(), 1.0, 1e-6);
      if (!hit) continue;
      // Skip centres within 1e-7 m of a box edge, where either face is right.
      const Eigen::Vector3d p = ray.origin + hit->t * ray.direction;
      int on_bounds = 0;
      for (int a = 0; a < 3; ++a) {
        on_bounds += std::abs(p[a] - s.lo[a]) < 1e-7 || std::abs(p[a] - s.hi[a]) < 1e-7;
      }
      if (on_bounds > 1) continue;
      const Eigen::Vector3d expected = R_camera_world * hit->normal;
      EXPECT_LT((n.cast<double>() - expected).norm(), 1e-6) << "pixel " << i << "," << j;
      // Facing the camera: n . p_camera < 0.
      EXPECT_LT(n.cast<double>().dot(R_camera_world * (p - s.T.translation())), 0.0);
      int face = 0;
      for (int a = 0; a < 3; ++a) {
        if (hit->normal[a] != 0) face = 2 * a + (hit->normal[a] > 0);
      }
      ++faces_seen[face];
      ++checked;
    }
  }
  EXPECT_GT(checked, 10000);
  // The camera at (+x, -y, +z) of the box sees the +x, -y and +z faces.
  EXPECT_GT(faces_seen[1], 1000);
  EXPECT_GT(faces_seen[2], 1000);
  EXPECT_GT(faces_seen[5], 1000);
}

TEST(ReferenceRender, NormalsOfBackFacesPointTowardsTheCamera) {
  // From inside the box every visible face is seen from behind; its normal must still face
  // the camera, i.e. be the inward face normal.
  const BoxScene s;
  const Pose T = test::cameraLookingAt({0.1, 0.05, 0.6}, {0.6, 0.5, 0.7});
  const RenderOutput out = renderOk(s.model, s.cam, T);
  const Eigen::Matrix3d R_camera_world = T.linear().transpose();
  int checked = 0;
  for (int j = 0; j < s.cam.height; j += 4) {
    for (int i = 0; i < s.cam.width; i += 4) {
      ASSERT_TRUE(covered(out, i, j));
      const Ray ray = test::pixelRay(s.cam, T, i, j);
      // Exit face of the box along the ray: the smallest positive slab exit.
      double t_exit = std::numeric_limits<double>::infinity();
      Eigen::Vector3d inward = Eigen::Vector3d::Zero();
      for (int a = 0; a < 3; ++a) {
        if (ray.direction[a] == 0) continue;
        const double bound = ray.direction[a] > 0 ? s.hi[a] : s.lo[a];
        const double t = (bound - ray.origin[a]) / ray.direction[a];
        if (t < t_exit) {
          t_exit = t;
          inward = Eigen::Vector3d::Zero();
          inward[a] = ray.direction[a] > 0 ? -1.0 : 1.0;
        }
      }
      EXPECT_LT(relativeError(out.depth.at(i, j), t_exit), 1e-6);
      const Eigen::Vector3d n(out.normals.at(i, j, 0), out.normals.at(i, j, 1), out.normals.at(i, j, 2));
      const Eigen::Vector3d p = ray.origin + t_exit * ray.direction;
      int on_bounds = 0;
      for (int a = 0; a < 3; ++a) {
        on_bounds += std::abs(p[a] - s.lo[a]) < 1e-7 || std::abs(p[a] - s.hi[a]) < 1e-7;
      }
      if (on_bounds > 1) continue;
      EXPECT_LT((n - R_camera_world * inward).norm(), 1e-6) << i << "," << j;
      ++checked;
    }
  }
  EXPECT_GT(checked, 15000);
}

// --- 3. sphere -----------------------------------------------------------------------------------

TEST(ReferenceRender, SphereMatchesRayTriangleAndTrueSphere) {
  PinholeCamera cam;
  cam.width = 128;
  cam.height = 96;
  cam.fx = 150;
  cam.fy = 150;
  cam.cx = 63.5;
  cam.cy = 47.5;
  const Pose T = test::cameraLookingAt({0.2, -4.0, 0.7}, {0.0, 0.0, 0.0});
  const Eigen::Vector3d center(0, 0, 0);
  const double radius = 1.0;
  const Model sphere = test::makeUvSphere(center, radius, 64, 32);
  ASSERT_EQ(sphere.triangleCount(), 64u * 62u);
  const RenderOutput out = renderOk(sphere, cam, T);

  const auto ray_cast = test::rayCastDepth(sphere, cam, T);
  const int mismatches =
      compareWithAnalytic(out, cam, [&](int i, int j) { return ray_cast[static_cast<size_t>(j) * cam.width + i]; });
  EXPECT_LE(mismatches, 2);

  // Every surface point lies between the true sphere and the tessellation's inner bound: a
  // point of a triangle with vertices on the sphere has |p - c|^2 >= r^2 - e_max^2 / 3, e_max
  // the longest edge (|sum l_i v_i - c|^2 = r^2 - 1/2 sum_ij l_i l_j |v_i - v_j|^2).
  double e_max = 0;
  for (size_t k = 0; k < sphere.indices.size(); k += 3) {
    for (int e = 0; e < 3; ++e) {
      e_max = std::max(e_max, (test::modelVertex(sphere, sphere.indices[k + e]) -
                               test::modelVertex(sphere, sphere.indices[k + (e + 1) % 3]))
                                  .norm());
    }
  }
  const double r_min = std::sqrt(radius * radius - e_max * e_max / 3.0) - 1e-6;
  int surface = 0;
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < cam.width; ++i) {
      if (!covered(out, i, j)) continue;
      ++surface;
      const Ray ray = test::pixelRay(cam, T, i, j);
      const double r = (ray.origin + out.depth.at(i, j) * ray.direction - center).norm();
      EXPECT_GE(r, r_min);
      EXPECT_LE(r, radius + 1e-6);
    }
  }
  EXPECT_GT(surface, 3000);
}

// --- 4. texture -------------------------------------------------------------------------------

// Camera with integer principal point: world x = (u - 320) / 256 at z = 2, so quad corners on
// pixel centres are exactly representable.
PinholeCamera textureCamera() {
  PinholeCamera cam;
  cam.fx = 512;
  cam.fy = 512;
  cam.cx = 320;
  cam.cy = 240;
  return cam;
}

TEST(ReferenceRender, CheckerTextureTexelCentresBilinearAndRepeat) {
  const PinholeCamera cam = textureCamera();
  // Quad spanning pixels u in [160, 480], v in [80, 400] at z = 2: 40 px per texel, texel
  // (kx, ky)'s centre on pixel (180 + 40 kx, 100 + 40 ky).
  Model quad = test::makeCheckerQuad({-0.625, -0.625, 2.0}, {1.25, 0, 0}, {0, 1.25, 0}, 8);
  Texture& tex = quad.textures[0];
  auto setTexel = [&](int x, int y, std::array<uint8_t, 4> c) {
    std::copy(c.begin(), c.end(), &tex.rgba[(static_cast<size_t>(y) * 8 + x) * 4]);
  };
  setTexel(1, 0, {255, 0, 0, 255});  // Markers that catch flipped or transposed uv.
  setTexel(0, 2, {0, 0, 255, 255});
  RenderSettings settings;
  settings.background_rgba = {10, 20, 30, 40};
  const RenderOutput out = renderOk(quad, cam, Pose::Identity(), settings);

  for (int ky = 0; ky < 8; ++ky) {
    for (int kx = 0; kx < 8; ++kx) {
      const int i = 180 + 40 * kx;
      const int j = 100 + 40 * ky;
      for (int ch = 0; ch < 4; ++ch) {
        ASSERT_EQ(out.rgba.at(i, j, ch), tex.rgba[(static_cast<size_t>(ky) * 8 + kx) * 4 + ch])
            << "texel " << kx << "," << ky << " channel " << ch;
      }
      EXPECT_DOUBLE_EQ(out.depth.at(i, j), 2.0);
    }
  }
  // Everywhere inside: bilinear between texel centres, uv = ((i - 160) / 320, (j - 80) / 320).
  int exact = 0;
  int total = 0;
  for (int j = 81; j < 400; ++j) {
    for (int i = 161; i < 480; ++i) {
      const Eigen::Vector4d expected = test::sampleTextureBilinear(tex, (i - 160) / 320.0, (j - 80) / 320.0);
      bool same = true;
      for (int ch = 0; ch < 3; ++ch) {
        const int diff = std::abs(out.rgba.at(i, j, ch) - static_cast<int>(std::lround(expected[ch])));
        ASSERT_LE(diff, 1) << i << "," << j;
        same = same && diff == 0;
      }
      exact += same;
      ++total;
    }
  }
  EXPECT_GT(exact, total * 999 / 1000);
  // REPEAT at the border: pixel 161 has x = 1/320 * 8 - 0.5 = -0.475, i.e. 0.475 of texel 7
  // and 0.525 of texel 0. Row of texel centres ky = 0: texel 7 white, texel 0 black.
  EXPECT_EQ(out.rgba.at(161, 100, 1), 121);
  EXPECT_EQ(out.rgba.at(161, 140, 1), 134);  // ky = 1: texel 7 black, texel 0 white.
  // Quad edges through pixel centres: the top and left edges are in, bottom and right out.
  EXPECT_TRUE(covered(out, 160, 200));
  EXPECT_FALSE(covered(out, 480, 200));
  EXPECT_TRUE(covered(out, 200, 80));
  EXPECT_FALSE(covered(out, 200, 400));
  for (int ch = 0; ch < 4; ++ch) EXPECT_EQ(out.rgba.at(5, 5, ch), settings.background_rgba[ch]);
  EXPECT_EQ(out.rgba.at(200, 200, 3), 255);
  // Gray is the BT.601 luma of the colour.
  const ImageU8 gray = rgbaToGray(out.rgba);
  EXPECT_EQ(out.gray.data, gray.data);
}

TEST(ReferenceRender, TiltedTextureIsPerspectiveCorrect) {
  PinholeCamera cam;
  cam.width = 320;
  cam.height = 240;
  cam.fx = cam.fy = 256;
  cam.cx = 160;
  cam.cy = 120;
  const Eigen::Vector3d corner(-1, -0.75, 1.5);
  const Eigen::Vector3d es(2, 0, 1);  // Recedes to the right.
  const Eigen::Vector3d et(0, 1.5, 0);
  const Model quad = test::makeCheckerQuad(corner, es, et, 8);
  const RenderOutput out = renderOk(quad, cam, Pose::Identity());
  const Eigen::Vector3d n = et.cross(es);
  int total = 0;
  int exact = 0;
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < cam.width; ++i) {
      const Ray ray = test::pixelRay(cam, Pose::Identity(), i, j);
      const auto t = test::rayPlane(ray, corner, n);
      if (!t) continue;
      const Eigen::Vector3d p = ray.origin + *t * ray.direction - corner;
      const double s_coord = p.dot(es) / es.squaredNorm();
      const double t_coord = p.dot(et) / et.squaredNorm();
      if (s_coord < 0.002 || s_coord > 0.998 || t_coord < 0.002 || t_coord > 0.998) continue;
      ASSERT_TRUE(covered(out, i, j));
      EXPECT_LT(relativeError(out.depth.at(i, j), *t), 1e-6);
      const Eigen::Vector4d expected = test::sampleTextureBilinear(quad.textures[0], s_coord, t_coord);
      bool same = true;
      for (int ch = 0; ch < 3; ++ch) {
        const int diff = std::abs(out.rgba.at(i, j, ch) - static_cast<int>(std::lround(expected[ch])));
        ASSERT_LE(diff, 1) << i << "," << j;
        same = same && diff == 0;
      }
      exact += same;
      ++total;
    }
  }
  EXPECT_GT(total, 15000);
  EXPECT_GT(exact, total * 99 / 100);
}

TEST(ReferenceRender, ColourIsTextureTimesVertexColourTimesBaseColour) {
  const PinholeCamera cam = textureCamera();
  Model quad = test::makeQuad({-0.5, -0.5, 2.0}, {1, 0, 0}, {0, 1, 0});
  Texture tex;
  tex.width = 2;
  tex.height = 2;
  for (int k = 0; k < 4; ++k) {
    for (int c : {200, 100, 50, 255}) tex.rgba.push_back(static_cast<uint8_t>(c));
  }
  quad.textures = {tex};
  quad.materials = {Material{"m", {0.5f, 1.0f, 0.25f, 1.0f}, 0}};
  for (size_t v = 0; v < quad.vertexCount(); ++v) {
    for (int c : {255, 128, 64, 255}) quad.colors.push_back(static_cast<uint8_t>(c));
  }
  const RenderOutput out = renderOk(quad, cam, Pose::Identity());
  // round(255 * tex * vertex * base): 200 * 0.5, 100 * 128 / 255, 50 * 64 / 255 * 0.25.
  EXPECT_EQ(out.rgba.at(320, 240, 0), 100);
  EXPECT_EQ(out.rgba.at(320, 240, 1), 50);
  EXPECT_EQ(out.rgba.at(320, 240, 2), 3);
  EXPECT_EQ(out.rgba.at(320, 240, 3), 255);
}

// --- 5. camera model ----------------------------------------------------------------------------

TEST(ReferenceRender, NonSquarePixelsAndOffCentrePrincipalPoint) {
  PinholeCamera cam;
  cam.fx = 500;
  cam.fy = 650;
  cam.cx = 100.3;
  cam.cy = 400.7;
  // Right-angled corner at P: its edges run along +u and +v from (u_P, v_P) = (125.3, 335.7).
  const Eigen::Vector3d P(0.1, -0.2, 2.0);
  Model tri;
  test::addVertex(tri, P);
  test::addVertex(tri, P + Eigen::Vector3d(1, 0, 0));
  test::addVertex(tri, P + Eigen::Vector3d(0, 1, 0));
  tri.indices = {0, 1, 2};
  test::finishSingleBlock(tri);
  const RenderOutput out = renderOk(tri, cam, Pose::Identity());
  const Eigen::Vector3d Pf(static_cast<float>(P.x()), static_cast<float>(P.y()), static_cast<float>(P.z()));
  const double u_p = cam.fx * Pf.x() / Pf.z() + cam.cx;
  const double v_p = cam.fy * Pf.y() / Pf.z() + cam.cy;
  ASSERT_NEAR(u_p, 125.3, 1e-5);
  ASSERT_NEAR(v_p, 335.7, 1e-5);
  EXPECT_TRUE(covered(out, 126, 336));
  EXPECT_FALSE(covered(out, 125, 336));
  EXPECT_FALSE(covered(out, 126, 335));
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < 300; ++i) {
      // Inside the corner's quadrant and below the hypotenuse from (375.3, v_p) to
      // (u_p, 660.7): (u - u_p) / 250 + (v - v_p) / 325 <= 1.
      const bool expected = i > u_p && j > v_p && (i - u_p) / 250.0 + (j - v_p) / 325.0 < 1.0;
      ASSERT_EQ(covered(out, i, j), expected) << i << "," << j;
      if (expected) {
        EXPECT_FLOAT_EQ(out.depth.at(i, j), 2.0f);
      }
    }
  }
}

// --- 6. near plane ----------------------------------------------------------------------------

TEST(ReferenceRender, NearPlaneClipsTriangleCrossingIt) {
  const PinholeCamera cam;
  RenderSettings settings;
  settings.near_m = 0.5;
  // A floor triangle at y = 0.125 (below the camera) from behind the camera (z = -0.5) to
  // z = 3. Its part with z < 0.5 (rows j >= 371 near the bottom) must be clipped away.
  // Vertex colours red, green, blue: colour is linear in 3D over the triangle, so the clipped
  // part must show the 3D barycentric mix.
  const Eigen::Vector3d corners[3] = {{-1, 0.125, -0.5}, {1, 0.125, -0.5}, {0, 0.125, 3}};
  Model tri;
  for (int k = 0; k < 3; ++k) {
    test::addVertex(tri, corners[k]);
    tri.colors.insert(tri.colors.end(),
                      {uint8_t(k == 0 ? 255 : 0), uint8_t(k == 1 ? 255 : 0), uint8_t(k == 2 ? 255 : 0), 255});
  }
  tri.indices = {0, 1, 2};
  test::finishSingleBlock(tri);
  const RenderOutput out = renderOk(tri, cam, Pose::Identity(), settings);
  int coloured = 0;
  for (int j = 0; j < cam.height; j += 3) {
    for (int i = 0; i < cam.width; i += 3) {
      if (!covered(out, i, j)) continue;
      const Ray ray = test::pixelRay(cam, Pose::Identity(), i, j);
      const Eigen::Vector3d p = out.depth.at(i, j) * ray.direction;
      // Barycentrics in the plane y = 0.125 from areas in (x, z).
      auto area = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
        return (b.x() - a.x()) * (c.z() - a.z()) - (c.x() - a.x()) * (b.z() - a.z());
      };
      const double total = area(corners[0], corners[1], corners[2]);
      const double l0 = area(p, corners[1], corners[2]) / total;
      const double l1 = area(corners[0], p, corners[2]) / total;
      const double l2 = 1.0 - l0 - l1;
      const double expected[3] = {255 * l0, 255 * l1, 255 * l2};
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(out.rgba.at(i, j, ch), expected[ch], 0.51) << i << "," << j;
      ++coloured;
    }
  }
  EXPECT_GT(coloured, 5000);
  ASSERT_TRUE(allFinite(out.depth));
  ASSERT_TRUE(allFinite(out.normals));
  const auto ray_cast = test::rayCastDepth(tri, cam, Pose::Identity());
  const int mismatches = compareWithAnalytic(out, cam, [&](int i, int j) -> std::optional<double> {
    const auto hit = ray_cast[static_cast<size_t>(j) * cam.width + i];
    if (!hit || *hit < settings.near_m) return std::nullopt;
    return hit;
  });
  EXPECT_EQ(mismatches, 0);
  EXPECT_TRUE(covered(out, 320, 370));
  for (int i = 0; i < cam.width; ++i) EXPECT_FALSE(covered(out, i, 371)) << i;
  for (float z : out.depth.data) {
    if (z != kBackgroundDepth) {
      EXPECT_GE(z, settings.near_m * (1 - 1e-6));
    }
  }
}

TEST(ReferenceRender, TriangleBehindCameraRendersNothing) {
  const PinholeCamera cam;
  Model model;
  // A visible triangle, then one entirely behind the camera in the same block.
  test::addVertex(model, {-0.5, -0.5, 2});
  test::addVertex(model, {0.5, -0.5, 2});
  test::addVertex(model, {0, 0.5, 2});
  test::addVertex(model, {-5, -5, -1});
  test::addVertex(model, {5, -5, -1});
  test::addVertex(model, {0, 5, -2});
  model.indices = {0, 1, 2};
  test::finishSingleBlock(model);
  const RenderOutput visible_only = renderOk(model, cam, Pose::Identity());
  model.indices = {0, 1, 2, 3, 4, 5};
  test::finishSingleBlock(model);
  const RenderOutput both = renderOk(model, cam, Pose::Identity());
  EXPECT_EQ(both.depth.data, visible_only.depth.data);
  EXPECT_EQ(both.rgba.data, visible_only.rgba.data);
  EXPECT_EQ(both.triangles_drawn, 2u);

  Model behind_only;
  test::addVertex(behind_only, {-5, -5, -1});
  test::addVertex(behind_only, {5, -5, -1});
  test::addVertex(behind_only, {0, 5, -2});
  behind_only.indices = {0, 1, 2};
  test::finishSingleBlock(behind_only);
  const RenderOutput behind = renderOk(behind_only, cam, Pose::Identity());
  for (float z : behind.depth.data) ASSERT_EQ(z, kBackgroundDepth);
  EXPECT_EQ(behind.blocks_drawn, 0u);  // Frustum-culled as a whole.
  behind_only.blocks.clear();          // Without blocks it is rasterized and clipped away.
  const RenderOutput unculled = renderOk(behind_only, cam, Pose::Identity());
  for (float z : unculled.depth.data) ASSERT_EQ(z, kBackgroundDepth);
}

// --- 7. fill rule --------------------------------------------------------------------------------

/// Per-pixel coverage counts of a fan of triangles rendered one by one, the index of the last
/// triangle covering each pixel, and the render of the whole fan with colour 10 k + 5 for
/// triangle k.
struct FanCoverage {
  std::vector<int> count;
  std::vector<int> owner;
  RenderOutput combined;
};

/// A fan of 16 triangles around the pixel centre `centre` to 16 pixel centres on the square
/// [8, 56]^2: shared edges through pixel centres (slopes 0, 1/2, 1, 2 and vertical for the
/// centre (32, 32)). `point(pu, pv)` is the camera-frame point that projects to (pu, pv).
FanCoverage renderFan(const PinholeCamera& cam, const std::function<Eigen::Vector3d(int, int)>& point, bool reversed,
                      std::pair<int, int> centre = {32, 32}) {
  std::vector<std::pair<int, int>> ring;
  for (int k = 0; k < 4; ++k) ring.push_back({8 + 12 * k, 8});
  for (int k = 0; k < 4; ++k) ring.push_back({56, 8 + 12 * k});
  for (int k = 0; k < 4; ++k) ring.push_back({56 - 12 * k, 56});
  for (int k = 0; k < 4; ++k) ring.push_back({8, 56 - 12 * k});
  const int n = static_cast<int>(ring.size());
  FanCoverage fan;
  fan.count.assign(static_cast<size_t>(cam.width) * cam.height, 0);
  fan.owner.assign(fan.count.size(), -1);
  Model all;
  for (int k = 0; k < n; ++k) {
    Model tri;
    Eigen::Vector3d v[3] = {point(centre.first, centre.second), point(ring[k].first, ring[k].second),
                            point(ring[(k + 1) % n].first, ring[(k + 1) % n].second)};
    if (reversed) std::swap(v[1], v[2]);
    for (const auto& p : v) {
      test::addVertex(tri, p);
      all.indices.push_back(test::addVertex(all, p));
      all.colors.insert(all.colors.end(), {static_cast<uint8_t>(10 * k + 5), 0, 0, 255});
    }
    tri.indices = {0, 1, 2};
    test::finishSingleBlock(tri);
    const RenderOutput out = renderOk(tri, cam, Pose::Identity());
    for (int j = 0; j < cam.height; ++j) {
      for (int i = 0; i < cam.width; ++i) {
        if (!covered(out, i, j)) continue;
        ++fan.count[static_cast<size_t>(j) * cam.width + i];
        fan.owner[static_cast<size_t>(j) * cam.width + i] = k;
      }
    }
  }
  test::finishSingleBlock(all);
  fan.combined = renderOk(all, cam, Pose::Identity());
  return fan;
}

PinholeCamera fanCamera(double f) {
  PinholeCamera cam;
  cam.width = 64;
  cam.height = 64;
  cam.fx = f;
  cam.fy = f;
  cam.cx = 32;
  cam.cy = 32;
  return cam;
}

TEST(ReferenceRender, SharedEdgesThroughPixelCentresAreCoveredOnce) {
  // z = 1, f = 64: pixel (pu, pv) is the point ((pu - 32) / 64, (pv - 32) / 64, 1), and every
  // projected vertex is exact, so pixel centres lie exactly on the shared edges.
  const PinholeCamera cam = fanCamera(64);
  auto point = [](int pu, int pv) { return Eigen::Vector3d((pu - 32) / 64.0, (pv - 32) / 64.0, 1.0); };
  for (bool reversed : {false, true}) {
    const FanCoverage fan = renderFan(cam, point, reversed);
    for (int j = 0; j < 64; ++j) {
      for (int i = 0; i < 64; ++i) {
        // Top and left borders of the square are in, bottom and right out.
        const bool inside = i >= 8 && i < 56 && j >= 8 && j < 56;
        ASSERT_EQ(fan.count[j * 64 + i], inside ? 1 : 0) << i << "," << j << " reversed " << reversed;
        ASSERT_EQ(covered(fan.combined, i, j), inside);
        if (inside) {
          EXPECT_EQ(fan.combined.rgba.at(i, j, 0), 10 * fan.owner[j * 64 + i] + 5);
        }
      }
    }
  }
}

TEST(ReferenceRender, SharedEdgesWithRoundedVerticesAreCoveredOnce) {
  // Vertices rounded to float, projections rounded in double: pixel centres lie a rounding
  // error away from the shared edges, on either side, yet exactly one triangle may cover each.
  // (Configurations where evaluating an edge function from either endpoint disagrees.)
  const std::pair<double, double> configs[] = {{3, 61}, {3, 77.7}, {7, 96}, {0.3, 100}, {2.9, 96}};
  for (const auto& [z, f] : configs) {
    const PinholeCamera cam = fanCamera(f);
    auto point = [z = z, f = f](int pu, int pv) { return Eigen::Vector3d((pu - 32) * z / f, (pv - 32) * z / f, z); };
    for (bool reversed : {false, true}) {
      const FanCoverage fan = renderFan(cam, point, reversed, {31, 33});
      for (int j = 0; j < 64; ++j) {
        for (int i = 0; i < 64; ++i) {
          const int count = fan.count[j * 64 + i];
          ASSERT_LE(count, 1) << i << "," << j << " z " << z << " f " << f;
          if (i > 8 && i < 56 && j > 8 && j < 56) {
            ASSERT_EQ(count, 1) << i << "," << j << " z " << z << " f " << f;
          }
          ASSERT_EQ(covered(fan.combined, i, j), count == 1);
          if (count == 1) {
            EXPECT_EQ(fan.combined.rgba.at(i, j, 0), 10 * fan.owner[j * 64 + i] + 5);
          }
        }
      }
    }
  }
}

TEST(ReferenceRender, EqualDepthKeepsFirstDrawn) {
  const PinholeCamera cam;
  Model model;
  for (int copy = 0; copy < 2; ++copy) {
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(-1, -1, 3), Eigen::Vector3d(1, -1, 3), Eigen::Vector3d(0, 1, 3)}) {
      model.indices.push_back(test::addVertex(model, p));
      model.colors.insert(model.colors.end(), {static_cast<uint8_t>(copy ? 200 : 100), 0, 0, 255});
    }
  }
  test::finishSingleBlock(model);
  const RenderOutput out = renderOk(model, cam, Pose::Identity());
  ASSERT_TRUE(covered(out, 320, 240));
  EXPECT_EQ(out.rgba.at(320, 240, 0), 100);
}

TEST(ReferenceRender, TheNearestSurfaceGivesTheColourInEitherDrawingOrderAndDepthOnlyRendersAreNotShaded) {
  // Pixels are shaded after every triangle's depth test: the colour is the nearest surface's,
  // whether it was drawn first or last.
  const PinholeCamera cam;
  for (bool near_first : {true, false}) {
    Model model;
    for (int k = 0; k < 2; ++k) {
      const bool near = (k == 0) == near_first;
      const double z = near ? 2.0 : 4.0;
      for (const Eigen::Vector3d& p :
           {Eigen::Vector3d(-z, -z, z), Eigen::Vector3d(z, -z, z), Eigen::Vector3d(0, z, z)}) {
        model.indices.push_back(test::addVertex(model, p));
        const uint8_t rgba[4] = {static_cast<uint8_t>(near ? 40 : 220), 0, 0, 255};
        for (uint8_t c : rgba) model.colors.push_back(c);
      }
    }
    test::finishSingleBlock(model);
    const RenderOutput out = renderOk(model, cam, Pose::Identity());
    ASSERT_TRUE(covered(out, 320, 240));
    EXPECT_NEAR(out.depth.at(320, 240), 2.0f, 1e-5f);
    EXPECT_EQ(out.rgba.at(320, 240, 0), 40) << (near_first ? "near drawn first" : "near drawn last");
  }
  // Depth alone: the same depths and normals as a full render, colour left as the background.
  const Model scene = test::makeBoxOnGround();  // textured
  const Pose T_world_camera = test::cameraLookingAt({1.5, -1.0, 1.2}, {0.0, 0.0, 0.1});
  RenderSettings depth_only;
  depth_only.outputs = kRenderDepth | kRenderNormals;
  depth_only.background_rgba = {7, 8, 9, 10};
  const RenderOutput full = renderOk(scene, cam, T_world_camera);
  const RenderOutput bare = renderOk(scene, cam, T_world_camera, depth_only);
  EXPECT_EQ(full.depth.data, bare.depth.data);
  EXPECT_EQ(full.normals.data, bare.normals.data);
  size_t shaded = 0;
  for (int j = 0; j < cam.height; ++j) {
    for (int i = 0; i < cam.width; ++i) {
      shaded += covered(full, i, j);
      for (int ch = 0; ch < 4; ++ch) ASSERT_EQ(bare.rgba.at(i, j, ch), depth_only.background_rgba[ch]);
    }
  }
  EXPECT_GT(shaded, static_cast<size_t>(cam.width) * cam.height / 4) << "the scene fills the view";
}

// --- 9. back-face culling ----------------------------------------------------------------------

TEST(ReferenceRender, BackFaceCullingKeepsClosedMeshesAndDropsBackFaces) {
  const BoxScene s;
  RenderSettings cull;
  cull.cull_back_faces = true;
  const RenderOutput plain = renderOk(s.model, s.cam, s.T);
  const RenderOutput culled = renderOk(s.model, s.cam, s.T, cull);
  EXPECT_EQ(plain.depth.data, culled.depth.data);
  EXPECT_EQ(plain.rgba.data, culled.rgba.data);
  EXPECT_EQ(plain.normals.data, culled.normals.data);

  PinholeCamera small;
  small.width = 128;
  small.height = 96;
  small.cx = 63.5;
  small.cy = 47.5;
  small.fx = small.fy = 150;
  const Pose T = test::cameraLookingAt({0.2, -4.0, 0.7}, {0, 0, 0});
  const Model sphere = test::makeUvSphere({0, 0, 0}, 1.0, 32, 16);
  EXPECT_EQ(renderOk(sphere, small, T).depth.data, renderOk(sphere, small, T, cull).depth.data);

  // A triangle counter-clockwise as the camera sees it (top, lower left, lower right on the
  // screen) is a front face; the same triangle wound the other way is a back face.
  const PinholeCamera cam;
  Model tri;
  test::addVertex(tri, {0, -1, 3});
  test::addVertex(tri, {-1, 1, 3});
  test::addVertex(tri, {1, 1, 3});
  tri.indices = {0, 1, 2};
  test::finishSingleBlock(tri);
  EXPECT_TRUE(covered(renderOk(tri, cam, Pose::Identity(), cull), 320, 240));
  tri.indices = {0, 2, 1};
  EXPECT_FALSE(covered(renderOk(tri, cam, Pose::Identity(), cull), 320, 240));
  EXPECT_TRUE(covered(renderOk(tri, cam, Pose::Identity()), 320, 240));
  // The box seen from inside shows only back faces.
  const Pose inside = test::cameraLookingAt({0.1, 0.05, 0.6}, {0.6, 0.5, 0.6});
  const RenderOutput from_inside = renderOk(s.model, s.cam, inside, cull);
  for (float z : from_inside.depth.data) ASSERT_EQ(z, kBackgroundDepth);
}

TEST(ReferenceRender, BackFacesAreFlaggedWhereTheSurfaceIsSeenFromBehind) {
  const BoxScene s;
  // Outside the closed box: front faces only; the flag comes with the normals.
  const RenderOutput outside = renderOk(s.model, s.cam, s.T);
  ASSERT_EQ(outside.back_faces.width, s.cam.width);
  ASSERT_EQ(outside.back_faces.channels, 1);
  for (uint8_t b : outside.back_faces.data) ASSERT_EQ(b, 0);
  RenderSettings no_normals;
  no_normals.outputs = kRenderColor | kRenderDepth;
  EXPECT_TRUE(renderOk(s.model, s.cam, s.T, no_normals).back_faces.empty());
  // Inside it: every surface pixel is a back face.
  const RenderOutput inside = renderOk(s.model, s.cam, test::cameraLookingAt({0.1, 0.05, 0.6}, {0.6, 0.5, 0.7}));
  for (size_t i = 0; i < inside.depth.data.size(); ++i) {
    ASSERT_GT(inside.depth.data[i], 0.0f);
    ASSERT_EQ(inside.back_faces.data[i], 255);
  }
  // The box without its top seen from above: through the hole the inside of the far walls and
  // of the floor (back faces), around it the outer walls (front faces).
  const Model open = test::makeBox(s.lo, s.hi, true);
  const Pose above = test::cameraLookingAt({1.6, -2.0, 3.2}, {0.0, 0.0, 0.4});
  const RenderOutput out = renderOk(open, s.cam, above);
  int back = 0, front = 0;
  for (int j = 0; j < s.cam.height; ++j) {
    for (int i = 0; i < s.cam.width; ++i) {
      const Ray ray = test::pixelRay(s.cam, above, i, j);
      const auto hit = test::rayBox(ray, s.lo, s.hi);
      if (!hit) {
        EXPECT_EQ(out.back_faces.at(i, j), 0);
        continue;
      }
      // Skip pixels within 1e-6 m of an edge of the entry face, where either side is right.
      const Eigen::Vector3d p = ray.origin + hit->t * ray.direction;
      int on_bounds = 0;
      for (int a = 0; a < 3; ++a) {
        on_bounds += std::abs(p[a] - s.lo[a]) < 1e-6 || std::abs(p[a] - s.hi[a]) < 1e-6;
      }
      if (on_bounds > 1) continue;
      const bool through_hole = hit->normal.z() > 0;
      EXPECT_EQ(out.back_faces.at(i, j), through_hole ? 255 : 0) << i << "," << j;
      (through_hole ? back : front) += 1;
    }
  }
  EXPECT_GT(back, 5000);
  EXPECT_GT(front, 5000);
}

// --- 10. inputs and bookkeeping ---------------------------------------------------------------

TEST(ReferenceRender, InvalidInputsReturnErrors) {
  const BoxScene s;
  auto expectInvalid = [&](const Model& m, const PinholeCamera& cam, const Pose& T, const RenderSettings& settings) {
    Result<RenderOutput> r = renderReference(m, cam, T, settings);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
    EXPECT_FALSE(r.error().message.empty());
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  };
  Pose nan_pose = s.T;
  nan_pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  expectInvalid(s.model, s.cam, nan_pose, {});
  Pose scaled = s.T;
  scaled.linear() *= 2.0;
  expectInvalid(s.model, s.cam, scaled, {});
  RenderSettings settings;
  settings.near_m = 0;
  expectInvalid(s.model, s.cam, s.T, settings);
  settings.near_m = -1;
  expectInvalid(s.model, s.cam, s.T, settings);
  settings.near_m = 1;
  settings.far_m = 1;
  expectInvalid(s.model, s.cam, s.T, settings);
  PinholeCamera cam = s.cam;
  cam.width = 0;
  expectInvalid(s.model, cam, s.T, {});
  cam = s.cam;
  cam.fx = std::numeric_limits<double>::quiet_NaN();
  expectInvalid(s.model, cam, s.T, {});
  Model bad = s.model;
  bad.indices[4] = 1000;
  expectInvalid(bad, s.cam, s.T, {});
  for (int threads : {0, 65}) {
    settings = RenderSettings{};
    settings.threads = threads;
    expectInvalid(s.model, s.cam, s.T, settings);
  }
}

TEST(ReferenceRender, BandsOfRowsOnSeveralThreadsGiveTheOneThreadOutput) {
  // The textured demos (mip-mapped textures, vertex colours, blocks), an odd height so that the
  // last band is short, bands that split 2 x 2 quads' rows nowhere.
  for (const std::string name : {"room", "city"}) {
    DemoModelOptions options;
    options.texture_size = 128;
    const Model model = makeDemoModel(name, options).value();
    PinholeCamera cam;
    cam.width = 161;
    cam.height = 205;
    cam.fx = cam.fy = 120;
    cam.cx = 80;
    cam.cy = 102;
    const std::vector<Pose> views = demoViewpoints(name);
    ASSERT_FALSE(views.empty());
    for (const Pose& T : views) {
      RenderSettings one;
      const RenderOutput expected = renderOk(model, cam, T, one);
      ASSERT_GT(expected.triangles_drawn, 0u);
      for (int threads : {2, 3, 64}) {
        RenderSettings several;
        several.threads = threads;
        const RenderOutput out = renderOk(model, cam, T, several);
        EXPECT_EQ(out.rgba.data, expected.rgba.data) << name << ", " << threads << " threads";
        EXPECT_EQ(out.depth.data, expected.depth.data) << name << ", " << threads << " threads";
        EXPECT_EQ(out.normals.data, expected.normals.data) << name << ", " << threads << " threads";
        EXPECT_EQ(out.back_faces.data, expected.back_faces.data) << name << ", " << threads << " threads";
        EXPECT_EQ(out.gray.data, expected.gray.data) << name << ", " << threads << " threads";
        EXPECT_EQ(out.blocks_drawn, expected.blocks_drawn);
        EXPECT_EQ(out.triangles_drawn, expected.triangles_drawn);
      }
    }
  }
}

TEST(ReferenceRender, BandsOfRowsHandleShortImagesAndDepthOnlyRenders) {
  // Heights below one band's 32 rows, a last band shorter than the others, and a render without
  // colour (no shading) with back faces culled, on up to 64 threads.
  const Model model = makeDemoModel("room").value();
  const Pose T = demoViewpoints("room").front();
  for (int height : {1, 31, 63, 65, 66, 97}) {
    PinholeCamera cam;
    cam.width = 48;
    cam.height = height;
    cam.fx = cam.fy = 40;
    cam.cx = 23.5;
    cam.cy = 0.5 * (height - 1);
    for (uint32_t outputs : {static_cast<uint32_t>(kRenderAll), static_cast<uint32_t>(kRenderDepth)}) {
      RenderSettings one;
      one.outputs = outputs;
      one.cull_back_faces = outputs == kRenderDepth;
      const RenderOutput expected = renderOk(model, cam, T, one);
      for (int threads : {2, 64}) {
        RenderSettings several = one;
        several.threads = threads;
        const RenderOutput out = renderOk(model, cam, T, several);
        EXPECT_EQ(out.rgba.data, expected.rgba.data) << height << " rows, " << threads << " threads";
        EXPECT_EQ(out.depth.data, expected.depth.data) << height << " rows, " << threads << " threads";
        EXPECT_EQ(out.normals.data, expected.normals.data) << height << " rows, " << threads << " threads";
        EXPECT_EQ(out.back_faces.data, expected.back_faces.data) << height << " rows, " << threads << " threads";
        EXPECT_EQ(out.triangles_drawn, expected.triangles_drawn);
      }
    }
  }
}

TEST(ReferenceRender, EmptyModelRendersBackground) {
  const PinholeCamera cam;
  RenderSettings settings;
  settings.background_rgba = {1, 2, 3, 4};
  const RenderOutput out = renderOk(Model{}, cam, Pose::Identity(), settings);
  ASSERT_EQ(out.rgba.width, cam.width);
  ASSERT_EQ(out.rgba.height, cam.height);
  ASSERT_EQ(out.gray.channels, 1);
  for (float z : out.depth.data) ASSERT_EQ(z, kBackgroundDepth);
  for (size_t i = 0; i < out.rgba.data.size(); ++i) ASSERT_EQ(out.rgba.data[i], settings.background_rgba[i % 4]);
  for (float v : out.normals.data) ASSERT_EQ(v, 0.0f);
  EXPECT_EQ(out.blocks_drawn, 0u);
  EXPECT_EQ(out.triangles_drawn, 0u);
}

TEST(ReferenceRender, CountsBlocksAndTrianglesInFrustum) {
  const PinholeCamera cam;
  // Block 0 in front of the camera (2 triangles), block 1 behind it (12 triangles).
  Model front = test::makeQuad({-0.5, -0.5, 2}, {1, 0, 0}, {0, 1, 0});
  const Model back = test::makeBox({-1, -1, -3}, {1, 1, -2});
  Model m = front;
  const auto offset = static_cast<uint32_t>(m.vertexCount());
  m.positions.insert(m.positions.end(), back.positions.begin(), back.positions.end());
  m.uvs.insert(m.uvs.end(), back.uvs.begin(), back.uvs.end());
  for (uint32_t idx : back.indices) m.indices.push_back(idx + offset);
  m.ranges.push_back(DrawRange{6, 36, 0});
  Block b = back.blocks[0];
  b.first_range = 1;
  m.blocks.push_back(b);
  RenderSettings settings;
  settings.outputs = kRenderColor | kRenderDepth;
  const RenderOutput out = renderOk(m, cam, Pose::Identity(), settings);
  EXPECT_EQ(out.blocks_drawn, 1u);
  EXPECT_EQ(out.triangles_drawn, 2u);
  EXPECT_TRUE(out.normals.empty());
  EXPECT_TRUE(covered(out, 320, 240));
}

}  // namespace
}  // namespace vkloc
