// GPU remap (GpuRemap) against the references remapBilinear and remapBicubic (core/remap.hpp).
#include "vkloc/engine/gpu_remap.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "support/gpu_test_support.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/localize/camera_front.hpp"

namespace vkloc::test {
namespace {

/// Seeded test image: a gradient background, random rectangles of random gray levels, uniform
/// noise of +-noise gray levels.
ImageU8 randomImage(int w, int h, unsigned seed, int noise = 4) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<double> value(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) value[static_cast<size_t>(y) * w + x] = 30.0 + 150.0 * x / w + 60.0 * y / h;
  }
  for (int s = 0; s < 30; ++s) {
    const int x0 = static_cast<int>(U(rng) * w), y0 = static_cast<int>(U(rng) * h);
    const int x1 = std::min(w, x0 + 4 + static_cast<int>(U(rng) * w / 4));
    const int y1 = std::min(h, y0 + 4 + static_cast<int>(U(rng) * h / 4));
    const double g = U(rng) * 255.0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) value[static_cast<size_t>(y) * w + x] = g;
    }
  }
  std::uniform_int_distribution<int> N(-noise, noise);
  ImageU8 out(w, h, 1);
  for (size_t i = 0; i < value.size(); ++i) {
    out.data[i] = static_cast<uint8_t>(std::clamp(std::round(value[i]) + N(rng), 0.0, 255.0));
  }
  return out;
}

/// An undistortion-like table: output pixel (x, y) of a w x h pinhole view samples a source of
/// sw x sh through the radial polynomial 1 + k1 r^2 + k2 r^4 (normalised radius), with the
/// principal points off the pixel grid. The corners of the output fall outside the source.
RemapTable radialTable(int w, int h, int sw, int sh, double k1, double k2) {
  RemapTable table{w, h, sw, sh, {}};
  table.uv.resize(2 * static_cast<size_t>(w) * h);
  const double f = 0.8 * sw, cx = 0.5 * (w - 1) + 0.3, cy = 0.5 * (h - 1) - 0.2;
  const double scx = 0.5 * (sw - 1) - 0.17, scy = 0.5 * (sh - 1) + 0.41, sf = 0.8 * sw;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double xn = (x - cx) / f, yn = (y - cy) / f, r2 = xn * xn + yn * yn;
      const double s = 1.0 + k1 * r2 + k2 * r2 * r2;
      const size_t i = static_cast<size_t>(y) * w + x;
      table.uv[2 * i] = static_cast<float>(scx + sf * xn * s);
      table.uv[2 * i + 1] = static_cast<float>(scy + sf * yn * s);
    }
  }
  return table;
}

/// Random positions over the source and a margin around it, with exact integers, the last
/// row/column, NaN and infinities mixed in.
RemapTable randomTable(int w, int h, int sw, int sh, unsigned seed) {
  RemapTable table{w, h, sw, sh, {}};
  table.uv.resize(2 * static_cast<size_t>(w) * h);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-3.0f, static_cast<float>(sw) + 2.0f);
  std::uniform_real_distribution<float> V(-3.0f, static_cast<float>(sh) + 2.0f);
  std::uniform_int_distribution<int> kind(0, 99);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < table.uv.size() / 2; ++i) {
    float u = U(rng), v = V(rng);
    const int k = kind(rng);
    if (k == 0) u = nan;
    if (k == 1) v = -inf;
    if (k == 2) u = inf;
    if (k == 3) u = std::floor(std::clamp(u, 0.0f, static_cast<float>(sw - 1)));
    if (k == 4) v = static_cast<float>(sh - 1);
    if (k == 5) u = static_cast<float>(sw - 1);
    table.uv[2 * i] = u;
    table.uv[2 * i + 1] = v;
  }
  return table;
}

/// A w x h view of the source, scaled by `scale` and rotated by `angle` about the centre.
RemapTable similarityTable(int w, int h, int sw, int sh, double scale, double angle) {
  RemapTable table{w, h, sw, sh, {}};
  table.uv.resize(2 * static_cast<size_t>(w) * h);
  const double c = std::cos(angle) * scale, s = std::sin(angle) * scale;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double dx = x - 0.5 * (w - 1), dy = y - 0.5 * (h - 1);
      const size_t i = static_cast<size_t>(y) * w + x;
      table.uv[2 * i] = static_cast<float>(0.5 * (sw - 1) + c * dx - s * dy + 0.123);
      table.uv[2 * i + 1] = static_cast<float>(0.5 * (sh - 1) + s * dx + c * dy - 0.377);
    }
  }
  return table;
}

struct Agreement {
  int max_diff = 0;
  double exact = 0;      ///< Fraction of pixels equal.
  double within1 = 0;    ///< Fraction of pixels within 1 gray level.
  double no_source = 0;  ///< Fraction of pixels without a source (0 in the reference's sense).
};

Agreement compare(const ImageU8& gpu, const ImageU8& cpu, const RemapTable& table) {
  Agreement a;
  if (gpu.width != cpu.width || gpu.height != cpu.height || gpu.data.size() != cpu.data.size()) {
    a.max_diff = 256;
    return a;
  }
  size_t exact = 0, within1 = 0, no_source = 0;
  const float max_u = static_cast<float>(table.source_width - 1), max_v = static_cast<float>(table.source_height - 1);
  for (size_t i = 0; i < cpu.data.size(); ++i) {
    const int d = std::abs(static_cast<int>(gpu.data[i]) - static_cast<int>(cpu.data[i]));
    a.max_diff = std::max(a.max_diff, d);
    exact += d == 0;
    within1 += d <= 1;
    const float u = table.uv[2 * i], v = table.uv[2 * i + 1];
    no_source += !(u >= 0.0f && u <= max_u && v >= 0.0f && v <= max_v);
  }
  const double n = static_cast<double>(cpu.data.size());
  a.exact = exact / n;
  a.within1 = within1 / n;
  a.no_source = no_source / n;
  return a;
}

// Tolerance: |GPU - reference| <= 1 gray level on at least 99.9 % of the pixels. (The shader
// does the reference's float operations in its order without contraction, so a conforming
// device - correctly rounded add and multiply - matches exactly; lavapipe does. The tolerance
// leaves room for devices that flush denormals or round the final floor differently.)
constexpr int kToleranceLevels = 1;
constexpr double kMinFractionWithinTolerance = 0.999;

class GpuRemapTest : public GpuTest {
 protected:
  /// Remaps `source` through `table` on the GPU and with the reference of `interpolation`;
  /// checks the tolerance and prints the agreement.
  void expectMatchesReference(const char* what, const ImageU8& source, const RemapTable& table,
                              RemapInterpolation interpolation = RemapInterpolation::kBilinear) {
    auto remap = GpuRemap::create(context_, table, interpolation);
    ASSERT_TRUE(remap.ok()) << remap.error().message;
    expectMatchesReference(what, **remap, source, table, interpolation);
  }

  /// The same with `remap`, made for `interpolation`.
  void expectMatchesReference(const char* what, GpuRemap& remap, const ImageU8& source, const RemapTable& table,
                              RemapInterpolation interpolation = RemapInterpolation::kBilinear) {
    auto gpu = remap.remap(source);
    ASSERT_TRUE(gpu.ok()) << gpu.error().message;
    auto cpu = remapImage(source, table, interpolation);
    ASSERT_TRUE(cpu.ok()) << cpu.error().message;
    ASSERT_EQ(gpu->width, table.width);
    ASSERT_EQ(gpu->height, table.height);
    ASSERT_EQ(gpu->channels, 1);
    const Agreement a = compare(*gpu, *cpu, table);
    std::printf(
        "[ remap ] %-8s %-28s %dx%d from %dx%d: max |diff| %d, equal %.6f %%, within %d %.6f %%, "
        "no source %.2f %%\n",
        remapInterpolationName(interpolation), what, table.width, table.height, table.source_width, table.source_height,
        a.max_diff, 100.0 * a.exact, kToleranceLevels, 100.0 * a.within1, 100.0 * a.no_source);
    EXPECT_GE(a.within1, kMinFractionWithinTolerance) << what << ": max |diff| " << a.max_diff;
    // Pixels without a source are 0 on both: the GPU must not invent values there.
    for (size_t i = 0; i < cpu->data.size(); ++i) {
      if (cpu->data[i] == 0 && gpu->data[i] > kToleranceLevels) {
        ADD_FAILURE() << what << ": pixel " << i << " is " << int{gpu->data[i]} << " on the GPU, 0 in the reference";
        break;
      }
    }
  }
};

TEST_F(GpuRemapTest, UndistortionTableMatchesReference) {
  const ImageU8 source = randomImage(640, 480, 11);
  const RemapTable table = radialTable(640, 480, 640, 480, 0.28, 0.09);
  expectMatchesReference("radial (undistortion)", source, table);
  // Some of the table lies off the source, most of it on it.
  const Agreement off = compare(ImageU8(640, 480, 1), ImageU8(640, 480, 1), table);
  EXPECT_GT(off.no_source, 0.001);
  EXPECT_LT(off.no_source, 0.5);
}

TEST_F(GpuRemapTest, CameraFrontOnTheDeviceFollowsItsTables) {
  // A stabilised fisheye view whose table changes every frame: the front on the device gives the
  // reference remap of each frame's table (the accelerator's remapper, as the Localizer uses it).
  LensCamera lens;
  lens.model = LensModel::kKannalaBrandt;
  lens.intrinsics = PinholeCamera{200.0, 200.0, 399.5, 399.5, 800, 800};
  lens.k = {0.02, -0.005, 0.001, -0.0001, 0.0};
  lens.max_angle_deg = 105;
  ViewOptions view;
  view.kind = ViewKind::kStabilised;
  view.width = 240;
  view.height = 180;
  view.hfov_deg = 90;
  view.pitch_deg = 45;
  view.dead_band_deg = 0;  // a new table every frame
  view.interpolation = RemapInterpolation::kBilinear;
  auto front = CameraFront::create(lens, view);
  ASSERT_TRUE(front.ok()) << front.error().message;
  auto accelerator = makeGpuAccelerator(context_);
  ASSERT_TRUE(accelerator.ok());
  auto remapper =
      (*accelerator)->createRemapper((*front)->table(Eigen::Matrix3d::Identity()), RemapInterpolation::kBilinear);
  ASSERT_TRUE(remapper.ok()) << remapper.error().message;
  (*front)->setRemapper(std::move(remapper).value());
  EXPECT_NE((*front)->remapDescription().find("GPU remap"), std::string::npos);
  const ImageU8 source = randomImage(800, 800, 21);
  for (int i = 0; i < 3; ++i) {
    const Eigen::Matrix3d R_world_camera =
        (Eigen::AngleAxisd(0.2 * i, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(-2.0, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Eigen::Matrix3d R = (*front)->viewRotation(R_world_camera);
    ImageU8 out;
    ASSERT_TRUE((*front)->remap(source, R, out).ok());
    auto reference = remapBilinear(source, (*front)->table(R));
    ASSERT_TRUE(reference.ok());
    const Agreement a = compare(out, *reference, (*front)->table(R));
    EXPECT_GE(a.within1, kMinFractionWithinTolerance) << "frame " << i;
  }
  // The lens's own view (the kept exact table, as inside a dead band) and a turned one in turn:
  // the device gets each frame's table back.
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 1, 0).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d* R : {&I, &turned, &I, &turned}) {
    ImageU8 view_image;
    ASSERT_TRUE((*front)->remap(source, *R, view_image).ok());
    auto reference = remapBilinear(source, (*front)->table(*R));
    ASSERT_TRUE(reference.ok());
    const Agreement a = compare(view_image, *reference, (*front)->table(*R));
    EXPECT_GE(a.within1, kMinFractionWithinTolerance) << (R == &I ? "the lens's view" : "turned");
  }
  ImageU8 out;
  EXPECT_FALSE((*front)->remap(ImageU8(640, 480, 1), Eigen::Matrix3d::Identity(), out).ok());
}

TEST_F(GpuRemapTest, RandomSubPixelTableMatchesReference) {
  const ImageU8 source = randomImage(640, 480, 12);
  expectMatchesReference("random sub-pixel + NaN/inf", source, randomTable(640, 480, 640, 480, 13));
}

TEST_F(GpuRemapTest, OddSizesMatchReference) {
  const ImageU8 source = randomImage(640, 480, 14);
  // 333 wide: rows straddle the output's uints; 251 * 333 is odd, so the last uint is partial.
  expectMatchesReference("odd output 333x251", source, similarityTable(333, 251, 640, 480, 1.7, 0.3));
  expectMatchesReference("odd random 333x251", source, randomTable(333, 251, 640, 480, 15));
  // Odd source sizes too, and tiny images: 1 or 2 source pixels along an axis, 5 output pixels.
  const ImageU8 odd_source = randomImage(641, 479, 16);
  expectMatchesReference("odd source 641x479", odd_source, radialTable(333, 251, 641, 479, -0.2, 0.05));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  expectMatchesReference("1x1 source", randomImage(1, 1, 17),
                         RemapTable{5, 1, 1, 1, {0.0f, 0.0f, 1e-7f, 0.0f, -0.0f, 0.0f, 0.0f, nan, 0.0f, -1e-7f}});
  ImageU8 two(2, 1, 1);
  two.data = {17, 200};
  expectMatchesReference("2x1 source", two,
                         RemapTable{3,
                                    3,
                                    2,
                                    1,
                                    {0.0f, 0.0f, 0.25f, 0.0f, 0.5f, 0.0f, 0.75f, 0.0f, 1.0f, 0.0f, 1.0001f, 0.0f, 0.3f,
                                     0.1f, 0.999999f, 0.0f, 0.5f, -0.0f}});
}

TEST_F(GpuRemapTest, SetTableReplacesTheTableOfTheSameSizes) {
  const ImageU8 source = randomImage(640, 480, 21);
  const RemapTable first = radialTable(320, 240, 640, 480, 0.1, 0.0);
  auto remap = GpuRemap::create(context_, first);
  ASSERT_TRUE(remap.ok()) << remap.error().message;
  GpuRemap& r = **remap;
  expectMatchesReference("setTable: first", r, source, first);
  // A stabilised view: a new table every frame, same sizes.
  for (int frame = 0; frame < 3; ++frame) {
    const RemapTable next = similarityTable(320, 240, 640, 480, 1.0 + 0.1 * frame, 0.05 * frame);
    ASSERT_TRUE(r.setTable(next).ok());
    expectMatchesReference("setTable: next", r, source, next);
  }
  const RemapTable last = similarityTable(320, 240, 640, 480, 1.2, 0.1);
  // Other sizes, or an invalid table: kInvalidArgument, and the previous table stays.
  for (const RemapTable& other :
       {similarityTable(321, 240, 640, 480, 1.0, 0.0), similarityTable(320, 241, 640, 480, 1.0, 0.0),
        similarityTable(320, 240, 639, 480, 1.0, 0.0), similarityTable(320, 240, 640, 481, 1.0, 0.0),
        RemapTable{320, 240, 640, 480, {}}}) {
    const Status status = r.setTable(other);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
  }
  expectMatchesReference("setTable: after refusals", r, source, last);
}

TEST_F(GpuRemapTest, StagingPathMatchesReference) {
  // The discrete-GPU path: the table in device-local memory filled through staging copies
  // (odd size: the padded copy of the last word), at creation and by setTable.
  GpuOptions options;
  options.validation = 1;
  options.force_staging = true;
  options.on_validation_message = [](const std::string& m) {
    std::fprintf(stderr, "Vulkan validation: %s\n", m.c_str());
  };
  auto staging_context = GpuContext::create(options);
  ASSERT_TRUE(staging_context.ok()) << staging_context.error().message;
  const ImageU8 source = randomImage(640, 480, 41);
  const RemapTable first = radialTable(333, 251, 640, 480, 0.2, 0.0);
  auto remap = GpuRemap::create(*staging_context, first);
  ASSERT_TRUE(remap.ok()) << remap.error().message;
  expectMatchesReference("staging: first", **remap, source, first);
  const RemapTable next = randomTable(333, 251, 640, 480, 42);
  ASSERT_TRUE((*remap)->setTable(next).ok());
  expectMatchesReference("staging: setTable", **remap, source, next);
  EXPECT_EQ((*staging_context)->validationMessages(), 0u);
}

TEST_F(GpuRemapTest, RejectsBadInput) {
  const RemapTable table = similarityTable(64, 48, 80, 60, 1.0, 0.0);
  auto null_context = GpuRemap::create(nullptr, table);
  ASSERT_FALSE(null_context.ok());
  EXPECT_EQ(null_context.error().code, ErrorCode::kInvalidArgument);
  RemapTable invalid = table;
  invalid.uv.resize(10);
  auto bad_table = GpuRemap::create(context_, invalid);
  ASSERT_FALSE(bad_table.ok());
  EXPECT_EQ(bad_table.error().code, ErrorCode::kInvalidArgument);
  auto bad_interpolation = GpuRemap::create(context_, table, static_cast<RemapInterpolation>(7));
  ASSERT_FALSE(bad_interpolation.ok());
  EXPECT_EQ(bad_interpolation.error().code, ErrorCode::kInvalidArgument);

  auto remap = GpuRemap::create(context_, table);
  ASSERT_TRUE(remap.ok()) << remap.error().message;
  for (const ImageU8& wrong : {randomImage(64, 48, 1), randomImage(81, 60, 1), ImageU8(80, 60, 3), ImageU8()}) {
    auto out = (*remap)->remap(wrong);
    ASSERT_FALSE(out.ok());
    EXPECT_EQ(out.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(out.error().message.find("80x60"), std::string::npos) << out.error().message;
  }
  // Still usable after the refusals.
  expectMatchesReference("after bad input", **remap, randomImage(80, 60, 2), table);
}

// Bicubic: the table cases above through the bicubic pipeline against remapBicubic.
TEST_F(GpuRemapTest, BicubicMatchesReferenceOnTheTableCases) {
  constexpr RemapInterpolation kCubic = RemapInterpolation::kBicubic;
  const ImageU8 source = randomImage(640, 480, 11);
  expectMatchesReference("radial (undistortion)", source, radialTable(640, 480, 640, 480, 0.28, 0.09), kCubic);
  expectMatchesReference("random sub-pixel + NaN/inf", randomImage(640, 480, 12), randomTable(640, 480, 640, 480, 13),
                         kCubic);
  const ImageU8 source14 = randomImage(640, 480, 14);
  expectMatchesReference("odd output 333x251", source14, similarityTable(333, 251, 640, 480, 1.7, 0.3), kCubic);
  expectMatchesReference("odd random 333x251", source14, randomTable(333, 251, 640, 480, 15), kCubic);
  expectMatchesReference("odd source 641x479", randomImage(641, 479, 16), radialTable(333, 251, 641, 479, -0.2, 0.05),
                         kCubic);
  // Tiny sources: every tap clamped (replicated) along an axis of 1, 2 or 3 pixels.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  expectMatchesReference("1x1 source", randomImage(1, 1, 17),
                         RemapTable{5, 1, 1, 1, {0.0f, 0.0f, 1e-7f, 0.0f, -0.0f, 0.0f, 0.0f, nan, 0.0f, -1e-7f}},
                         kCubic);
  ImageU8 two(2, 1, 1);
  two.data = {17, 200};
  expectMatchesReference("2x1 source", two,
                         RemapTable{3,
                                    3,
                                    2,
                                    1,
                                    {0.0f, 0.0f, 0.25f, 0.0f, 0.5f, 0.0f, 0.75f, 0.0f, 1.0f, 0.0f, 1.0001f, 0.0f, 0.3f,
                                     0.1f, 0.999999f, 0.0f, 0.5f, -0.0f}},
                         kCubic);
  RemapTable over_3x2{7, 5, 3, 2, {}};  // a 7x5 grid over the whole 3x2 source, edges included
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 7; ++x) {
      over_3x2.uv.push_back(static_cast<float>(x) / 3.0f);
      over_3x2.uv.push_back(static_cast<float>(y) / 4.0f);
    }
  }
  expectMatchesReference("3x2 source", randomImage(3, 2, 18), over_3x2, kCubic);
}

TEST_F(GpuRemapTest, BicubicSetTableReplacesTheTable) {
  const ImageU8 source = randomImage(640, 480, 21);
  const RemapTable first = radialTable(320, 240, 640, 480, 0.1, 0.0);
  auto remap = GpuRemap::create(context_, first, RemapInterpolation::kBicubic);
  ASSERT_TRUE(remap.ok()) << remap.error().message;
  GpuRemap& r = **remap;
  EXPECT_NE(r.describe().find("bicubic"), std::string::npos) << r.describe();
  expectMatchesReference("setTable: first", r, source, first, RemapInterpolation::kBicubic);
  for (int frame = 0; frame < 3; ++frame) {
    const RemapTable next = similarityTable(320, 240, 640, 480, 1.0 + 0.1 * frame, 0.05 * frame);
    ASSERT_TRUE(r.setTable(next).ok());
    expectMatchesReference("setTable: next", r, source, next, RemapInterpolation::kBicubic);
  }
  const RemapTable last = similarityTable(320, 240, 640, 480, 1.2, 0.1);
  const Status refused = r.setTable(similarityTable(321, 240, 640, 480, 1.0, 0.0));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, ErrorCode::kInvalidArgument);
  expectMatchesReference("setTable: after refusal", r, source, last, RemapInterpolation::kBicubic);
  // The two pipelines differ where the positions are off the grid.
  auto bilinear = GpuRemap::create(context_, last);
  ASSERT_TRUE(bilinear.ok());
  EXPECT_NE((*bilinear)->describe().find("bilinear"), std::string::npos) << (*bilinear)->describe();
  auto bilinear_out = (*bilinear)->remap(source);
  auto bicubic_out = r.remap(source);
  ASSERT_TRUE(bilinear_out.ok() && bicubic_out.ok());
  EXPECT_NE(bilinear_out->data, bicubic_out->data);
}

TEST_F(GpuRemapTest, CameraFrontBicubicOnTheDeviceFollowsItsTables) {
  // The accelerator's bicubic remapper in a stabilised camera front: each frame's view is
  // remapBicubic of that frame's table.
  LensCamera lens;
  lens.model = LensModel::kKannalaBrandt;
  lens.intrinsics = PinholeCamera{200.0, 200.0, 399.5, 399.5, 800, 800};
  lens.k = {0.02, -0.005, 0.001, -0.0001, 0.0};
  lens.max_angle_deg = 105;
  ViewOptions view;
  view.kind = ViewKind::kStabilised;
  view.width = 240;
  view.height = 180;
  view.hfov_deg = 90;
  view.pitch_deg = 45;
  view.dead_band_deg = 0;  // a new table every frame
  view.interpolation = RemapInterpolation::kBicubic;
  auto front = CameraFront::create(lens, view);
  ASSERT_TRUE(front.ok()) << front.error().message;
  auto accelerator = makeGpuAccelerator(context_);
  ASSERT_TRUE(accelerator.ok());
  auto remapper =
      (*accelerator)->createRemapper((*front)->table(Eigen::Matrix3d::Identity()), RemapInterpolation::kBicubic);
  ASSERT_TRUE(remapper.ok()) << remapper.error().message;
  (*front)->setRemapper(std::move(remapper).value());
  EXPECT_NE((*front)->remapDescription().find("bicubic"), std::string::npos) << (*front)->remapDescription();
  const ImageU8 source = randomImage(800, 800, 22);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Matrix3d R_world_camera =
        (Eigen::AngleAxisd(0.2 * i, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(-2.0, Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    const Eigen::Matrix3d R = (*front)->viewRotation(R_world_camera);
    ImageU8 out;
    ASSERT_TRUE((*front)->remap(source, R, out).ok());
    auto reference = remapBicubic(source, (*front)->table(R));
    ASSERT_TRUE(reference.ok());
    const Agreement a = compare(out, *reference, (*front)->table(R));
    EXPECT_GE(a.within1, kMinFractionWithinTolerance) << "frame " << i << ": max |diff| " << a.max_diff;
  }
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double minimum(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }

/// Process CPU time (all threads, lavapipe's included), milliseconds: less disturbed than wall
/// time by other processes on a shared machine.
double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// Speed report (prints, never fails on time; timings are noisy on shared CPUs).
TEST_F(GpuRemapTest, TimingReport640x480) {
  const ImageU8 source = randomImage(640, 480, 31);
  const RemapTable table = radialTable(640, 480, 640, 480, 0.28, 0.09);
  auto remap = GpuRemap::create(context_, table);
  ASSERT_TRUE(remap.ok()) << remap.error().message;
  GpuRemap& r = **remap;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(r.remap(source).ok());  // JIT compilation at first use
  constexpr int kRuns = 60;
  std::vector<double> device_ms, wall_ms, process_ms, set_table_ms, cpu_ms, opencv_ms;
  for (int i = 0; i < kRuns; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    const double c0 = processCpuMs();
    auto out = r.remap(source);
    process_ms.push_back(processCpuMs() - c0);
    wall_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    ASSERT_TRUE(out.ok());
    device_ms.push_back(r.lastGpuMs());
    t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(r.setTable(table).ok());
    set_table_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    t0 = std::chrono::steady_clock::now();
    auto cpu = remapBilinear(source, table);
    cpu_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    ASSERT_TRUE(cpu.ok());
  }
  // OpenCV's fast path for comparison (fixed-point weights: not bit-exact with the reference).
  const cv::Mat src(source.height, source.width, CV_8UC1, const_cast<uint8_t*>(source.data.data()));
  const cv::Mat map(table.height, table.width, CV_32FC2, const_cast<float*>(table.uv.data()));
  cv::Mat map1, map2, dst;
  cv::convertMaps(map, cv::Mat(), map1, map2, CV_16SC2);
  for (int i = 0; i < kRuns + 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    cv::remap(src, dst, map1, map2, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    if (i >= 3) {
      opencv_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
  }
  std::printf("[ remap ] 640x480 on %s, median (min) of %d:\n", context_->device().name.c_str(), kRuns);
  std::printf("[ remap ]   GpuRemap::remap device   %8.3f ms (%.3f) lastGpuMs\n", median(device_ms),
              minimum(device_ms));
  std::printf("[ remap ]   GpuRemap::remap host     %8.3f ms (%.3f) upload + submit + wait + readback\n",
              median(wall_ms), minimum(wall_ms));
  std::printf("[ remap ]   GpuRemap::remap CPU time %8.3f ms (%.3f) process, all threads\n", median(process_ms),
              minimum(process_ms));
  std::printf("[ remap ]   GpuRemap::setTable       %8.3f ms (%.3f)\n", median(set_table_ms), minimum(set_table_ms));
  std::printf("[ remap ]   remapBilinear (CPU)      %8.3f ms (%.3f)\n", median(cpu_ms), minimum(cpu_ms));
  std::printf("[ remap ]   cv::remap 16SC2 maps     %8.3f ms (%.3f)\n", median(opencv_ms), minimum(opencv_ms));
  RecordProperty("gpu_device_ms", std::to_string(median(device_ms)));
  RecordProperty("gpu_host_ms", std::to_string(median(wall_ms)));
  RecordProperty("cpu_reference_ms", std::to_string(median(cpu_ms)));
}

}  // namespace
}  // namespace vkloc::test
