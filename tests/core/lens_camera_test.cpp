// Property tests of the lens camera models (core/lens_camera.hpp): round trips over the field of
// view, analytic against central-difference Jacobians, the edge of the field, the ideal pinhole,
// validation and model names.
#include "vkloc/core/lens_camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct NamedCamera {
  std::string name;
  LensCamera camera;
};

LensCamera makeCamera(LensModel model, double f, double cx, double cy, int width, int height, std::array<double, 5> k) {
  LensCamera c;
  c.model = model;
  c.intrinsics = PinholeCamera{f, f, cx, cy, width, height};
  c.k = k;
  return c;
}

/// Realistic cameras of every model, and two whose distortion folds inside the field.
std::vector<NamedCamera> testCameras() {
  std::vector<NamedCamera> out;
  LensCamera euroc = makeCamera(LensModel::kPinhole, 458.654, 367.215, 248.375, 752, 480,
                                {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0});
  euroc.intrinsics.fy = 457.296;
  out.push_back({"euroc_radtan", euroc});
  // k1 alone folds r (1 + k1 r^2) at r^2 = -1 / (3 k1): 46.5 degrees.
  out.push_back(
      {"radtan_fold", makeCamera(LensModel::kPinhole, 400, 319.5, 239.5, 640, 480, {-0.3, 0, 1e-3, -5e-4, 0})});
  LensCamera kb =
      makeCamera(LensModel::kKannalaBrandt, 190, 319.5, 319.5, 640, 640, {0.0076, -0.0031, 0.0006, -0.0001, 0});
  kb.intrinsics.fy = 190.5;
  kb.max_angle_deg = 105;  // a 210-degree lens
  out.push_back({"kb_210", kb});
  kb.max_angle_deg = 0;  // the polynomial folds near 146 degrees
  out.push_back({"kb_fold", kb});
  LensCamera mei = makeCamera(LensModel::kMei, 750, 640, 512, 1280, 1024, {-0.1, 0.02, 1e-4, -2e-4, 0});
  mei.intrinsics.fy = 748;
  mei.xi = 1.5;
  out.push_back({"mei", mei});
  // xi < 1, and k1 alone folds at |m|^2 = -1 / (3 k1).
  LensCamera mei_small = makeCamera(LensModel::kMei, 330, 320, 240, 640, 480, {-0.2, 0, 2e-4, 1e-4, 0});
  mei_small.xi = 0.8;
  out.push_back({"mei_small_xi", mei_small});
  LensCamera ds = makeCamera(LensModel::kDoubleSphere, 313, 319.5, 239.5, 640, 480, {0, 0, 0, 0, 0});
  ds.intrinsics.fy = 312.2;
  ds.xi = -0.2;
  ds.alpha = 0.59;
  out.push_back({"double_sphere", ds});
  LensCamera ds_low = ds;
  ds_low.xi = 0.3;
  ds_low.alpha = 0.4;
  out.push_back({"double_sphere_low_alpha", ds_low});
  return out;
}

Eigen::Vector3d direction(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

/// Directions on a seeded grid from the axis to `reach` times the field's edge.
std::vector<Eigen::Vector3d> fieldDirections(double max_angle, double reach, int rings, int spokes, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(0.0, 2 * kPi / spokes);
  std::vector<Eigen::Vector3d> out = {Eigen::Vector3d::UnitZ()};
  for (int i = 1; i <= rings; ++i) {
    const double theta = reach * max_angle * i / rings;
    const double phase = jitter(rng);
    for (int j = 0; j < spokes; ++j) out.push_back(direction(theta, phase + 2 * kPi * j / spokes));
  }
  return out;
}

double maxAbs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

TEST(LensCamera, RoundTripRaysOverTheField) {
  for (const auto& [name, camera] : testCameras()) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(validateLensCamera(camera).ok()) << validateLensCamera(camera).error().message;
    const double limit = lensMaxAngle(camera);
    EXPECT_GT(limit, 0.5);
    // The field ends where the radial distortion folds; the tangential terms fold the plane a
    // little before that in some directions (two rays, one pixel), so a radial-tangential camera
    // whose field ends at a fold round-trips to 0.99 of it.
    const bool radtan_fold = name == "radtan_fold" || name == "mei_small_xi";
    int checked = 0;
    for (const Eigen::Vector3d& d : fieldDirections(limit, radtan_fold ? 0.99 : 0.999, 40, 12, 11)) {
      const Eigen::Vector3d p = 2.5 * d;
      Eigen::Vector2d uv;
      ASSERT_TRUE(projectLens(camera, p, uv)) << "angle " << std::acos(d.z()) << " of " << limit;
      Eigen::Vector3d ray;
      ASSERT_TRUE(unprojectLens(camera, uv, ray)) << "angle " << std::acos(d.z()) << " uv " << uv.transpose();
      EXPECT_LT((ray - d).norm(), 1e-9) << "angle " << std::acos(d.z());
      EXPECT_NEAR(ray.norm(), 1.0, 1e-14);
      ++checked;
    }
    EXPECT_EQ(checked, 1 + 40 * 12);
  }
}

TEST(LensCamera, RoundTripPixelsOverTheImage) {
  for (const auto& [name, camera] : testCameras()) {
    SCOPED_TRACE(name);
    const PinholeCamera& K = camera.intrinsics;
    int inside = 0, total = 0;
    for (double v = 0; v <= K.height - 1; v += 7.5) {
      for (double u = 0; u <= K.width - 1; u += 7.5) {
        ++total;
        const Eigen::Vector2d uv(u, v);
        Eigen::Vector3d ray;
        if (!unprojectLens(camera, uv, ray)) continue;
        ++inside;
        EXPECT_NEAR(ray.norm(), 1.0, 1e-14);
        Eigen::Vector2d back;
        ASSERT_TRUE(projectLens(camera, ray, back)) << uv.transpose();
        EXPECT_LT((back - uv).norm(), 1e-8) << uv.transpose();
      }
    }
    // Every model sees at least the disc that fits the image; most see it all.
    EXPECT_GT(inside, 0.7 * total);
  }
}

/// Central differences of projectLens around p.
Eigen::Matrix<double, 2, 3> numericProjectJacobian(const LensCamera& camera, const Eigen::Vector3d& p) {
  Eigen::Matrix<double, 2, 3> J;
  const double h = 1e-6 * p.norm();
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();
    dp[i] = h;
    Eigen::Vector2d plus, minus;
    EXPECT_TRUE(projectLens(camera, p + dp, plus));
    EXPECT_TRUE(projectLens(camera, p - dp, minus));
    J.col(i) = (plus - minus) / (2 * h);
  }
  return J;
}

/// Central differences of unprojectLens around uv.
Eigen::Matrix<double, 3, 2> numericUnprojectJacobian(const LensCamera& camera, const Eigen::Vector2d& uv) {
  Eigen::Matrix<double, 3, 2> J;
  const double h = 1e-3;  // pixels
  for (int i = 0; i < 2; ++i) {
    Eigen::Vector2d duv = Eigen::Vector2d::Zero();
    duv[i] = h;
    Eigen::Vector3d plus, minus;
    EXPECT_TRUE(unprojectLens(camera, uv + duv, plus));
    EXPECT_TRUE(unprojectLens(camera, uv - duv, minus));
    J.col(i) = (plus - minus) / (2 * h);
  }
  return J;
}

TEST(LensCamera, AnalyticJacobiansMatchCentralDifferences) {
  for (const auto& [name, camera] : testCameras()) {
    SCOPED_TRACE(name);
    const double limit = lensMaxAngle(camera);
    std::vector<Eigen::Vector3d> points = {
        Eigen::Vector3d(0, 0, 1.7),         // exactly on the axis: r = 0
        Eigen::Vector3d(1e-9, -2e-9, 1.0),  // r tiny
        Eigen::Vector3d(-3e-5, 1e-5, 0.8),  // r small
    };
    for (const double fraction : {0.05, 0.3, 0.6, 0.9}) {
      for (const double phi : {0.3, 2.0, 4.1}) points.push_back(3.0 * direction(fraction * limit, phi));
    }
    for (const Eigen::Vector3d& p : points) {
      SCOPED_TRACE(testing::Message() << "p = " << p.transpose());
      Eigen::Vector2d uv;
      Eigen::Matrix<double, 2, 3> J;
      ASSERT_TRUE(projectLens(camera, p, uv, &J));
      const Eigen::Matrix<double, 2, 3> Jn = numericProjectJacobian(camera, p);
      EXPECT_LT(maxAbs(J - Jn), 1e-6 * maxAbs(J)) << "\n" << J << "\n" << Jn;
      // The projection ignores the length of p.
      EXPECT_LT(maxAbs(J * p), 1e-9 * maxAbs(J) * p.norm());

      Eigen::Vector3d ray;
      Eigen::Matrix<double, 3, 2> Ju;
      ASSERT_TRUE(unprojectLens(camera, uv, ray, &Ju));
      const Eigen::Matrix<double, 3, 2> Jun = numericUnprojectJacobian(camera, uv);
      EXPECT_LT(maxAbs(Ju - Jun), 1e-6 * maxAbs(Ju)) << "\n" << Ju << "\n" << Jun;
      // Unprojection then projection is the identity on pixels.
      Eigen::Vector2d back;
      Eigen::Matrix<double, 2, 3> Jr;
      ASSERT_TRUE(projectLens(camera, ray, back, &Jr));
      EXPECT_LT(maxAbs(Jr * Ju - Eigen::Matrix2d::Identity()), 1e-9);
      EXPECT_LT(std::abs(ray.dot(Ju.col(0))) + std::abs(ray.dot(Ju.col(1))), 1e-12 * maxAbs(Ju));
    }
  }
}

TEST(LensCamera, BeyondTheFieldReturnsFalseAndLeavesOutputs) {
  const Eigen::Vector2d uv_sentinel(-7.0, 7.0);
  Eigen::Matrix<double, 2, 3> J_sentinel;
  J_sentinel.setConstant(3.0);
  auto expectRejected = [&](const LensCamera& camera, const Eigen::Vector3d& p) {
    Eigen::Vector2d uv = uv_sentinel;
    Eigen::Matrix<double, 2, 3> J = J_sentinel;
    EXPECT_FALSE(projectLens(camera, p, uv, &J)) << p.transpose();
    EXPECT_EQ(uv, uv_sentinel);
    EXPECT_EQ(J, J_sentinel);
  };
  for (const auto& [name, camera] : testCameras()) {
    SCOPED_TRACE(name);
    const double limit = lensMaxAngle(camera);
    for (const double phi : {0.0, 1.0, 2.5, 4.0}) {
      // Just inside projects; just beyond and further out do not.
      Eigen::Vector2d uv;
      EXPECT_TRUE(projectLens(camera, direction(limit - 1e-6, phi), uv));
      EXPECT_TRUE(uv.allFinite());
      for (const double past : {1e-9, 1e-4, 0.1, 1.0}) {
        if (limit + past < kPi) expectRejected(camera, 4.0 * direction(limit + past, phi));
      }
      // Exactly at the limit: either rejected or a finite pixel, never NaN.
      Eigen::Vector2d at = uv_sentinel;
      Eigen::Matrix<double, 2, 3> J_at;
      if (projectLens(camera, direction(limit, phi), at, &J_at)) {
        EXPECT_TRUE(at.allFinite());
        EXPECT_TRUE(J_at.allFinite());
      }
    }
    expectRejected(camera, Eigen::Vector3d(0, 0, -1));  // straight behind
    expectRejected(camera, Eigen::Vector3d::Zero());
    expectRejected(camera, Eigen::Vector3d(kNaN, 0, 1));
    expectRejected(camera, Eigen::Vector3d(0, 0, std::numeric_limits<double>::infinity()));

    // Pixels far outside the image circle (or NaN) have no ray; outputs stay.
    const PinholeCamera& K = camera.intrinsics;
    const Eigen::Vector3d ray_sentinel(5, 6, 7);
    Eigen::Matrix<double, 3, 2> Ju_sentinel;
    Ju_sentinel.setConstant(-2.0);
    for (const Eigen::Vector2d& uv : {Eigen::Vector2d(kNaN, 10), Eigen::Vector2d(K.cx + 1e3 * K.fx, K.cy),
                                      Eigen::Vector2d(K.cx - 30 * K.fx, K.cy + 40 * K.fy)}) {
      if (name == "euroc_radtan" && uv.allFinite()) continue;  // monotonic to |m| = 1e6: no circle
      Eigen::Vector3d ray = ray_sentinel;
      Eigen::Matrix<double, 3, 2> Ju = Ju_sentinel;
      EXPECT_FALSE(unprojectLens(camera, uv, ray, &Ju)) << uv.transpose();
      EXPECT_EQ(ray, ray_sentinel);
      EXPECT_EQ(Ju, Ju_sentinel);
    }
  }
}

TEST(LensCamera, FieldLimitsOfEachModel) {
  const auto cameras = testCameras();
  auto limitOf = [&](const std::string& name) {
    for (const auto& nc : cameras) {
      if (nc.name == name) return lensMaxAngle(nc.camera);
    }
    ADD_FAILURE() << name;
    return 0.0;
  };
  // No fold for EuRoC (3 k1 s + 5 k2 s^2 + 1 has no real root): the field ends at |m| = 1e6.
  EXPECT_NEAR(limitOf("euroc_radtan"), std::atan(1e6), 1e-12);
  EXPECT_NEAR(limitOf("radtan_fold"), std::atan(std::sqrt(1 / 0.9)), 1e-12);
  EXPECT_NEAR(limitOf("kb_210"), 105 * kPi / 180, 1e-15);
  const double kb_fold = limitOf("kb_fold");
  EXPECT_GT(kb_fold, 2.4);
  EXPECT_LT(kb_fold, 2.7);
  const std::array<double, 4> k = {0.0076, -0.0031, 0.0006, -0.0001};
  const double s = kb_fold * kb_fold;
  EXPECT_NEAR(1 + s * (3 * k[0] + s * (5 * k[1] + s * (7 * k[2] + s * 9 * k[3]))), 0.0, 1e-12);
  EXPECT_NEAR(limitOf("mei"), std::acos(-1 / 1.5), 1e-12);
  const double w1 = (1 - 0.59) / 0.59, w2 = (w1 - 0.2) / std::sqrt(2 * w1 * -0.2 + 0.04 + 1);
  EXPECT_NEAR(limitOf("double_sphere"), std::acos(-w2), 1e-12);
}

TEST(LensCamera, HugeAndTinyPointsProjectLikeUnitOnes) {
  for (const auto& [name, camera] : testCameras()) {
    SCOPED_TRACE(name);
    const Eigen::Vector3d d = direction(0.5 * lensMaxAngle(camera), 0.7);
    Eigen::Vector2d uv, uv_big, uv_small;
    Eigen::Matrix<double, 2, 3> J, J_big;
    ASSERT_TRUE(projectLens(camera, d, uv, &J));
    ASSERT_TRUE(projectLens(camera, 1e250 * d, uv_big, &J_big));
    ASSERT_TRUE(projectLens(camera, 1e-250 * d, uv_small));
    EXPECT_LT((uv_big - uv).norm(), 1e-9);
    EXPECT_LT((uv_small - uv).norm(), 1e-9);
    EXPECT_LT(maxAbs(J_big * 1e250 - J), 1e-9 * maxAbs(J));
  }
}

TEST(LensCamera, IdealPinholeEqualsPinholeCamera) {
  LensCamera camera;
  camera.intrinsics = PinholeCamera{525.5, 524.0, 319.7, 241.2, 640, 480};
  ASSERT_TRUE(camera.isIdealPinhole());
  ASSERT_TRUE(validateLensCamera(camera).ok());
  EXPECT_EQ(lensMaxAngle(camera), kPi / 2);
  const PinholeCamera& K = camera.intrinsics;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), depth(0.05, 10.0);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d p(xy(rng), xy(rng), depth(rng));
    Eigen::Vector2d uv;
    Eigen::Matrix<double, 2, 3> J;
    ASSERT_TRUE(projectLens(camera, p, uv, &J));
    EXPECT_EQ(uv.x(), K.fx * p.x() / p.z() + K.cx);
    EXPECT_EQ(uv.y(), K.fy * p.y() / p.z() + K.cy);
    Eigen::Vector3d ray;
    ASSERT_TRUE(unprojectLens(camera, uv, ray));
    const Eigen::Vector3d expected = Eigen::Vector3d((uv.x() - K.cx) / K.fx, (uv.y() - K.cy) / K.fy, 1.0).normalized();
    EXPECT_LT((ray - expected).norm(), 1e-15);
  }
  Eigen::Vector2d uv;
  EXPECT_FALSE(projectLens(camera, Eigen::Vector3d(1, 0, 0), uv));  // z = 0
  camera.k[1] = 1e-3;
  EXPECT_FALSE(camera.isIdealPinhole());
}

TEST(LensCamera, ValidationNamesTheParameter) {
  for (const auto& [name, camera] : testCameras()) EXPECT_TRUE(validateLensCamera(camera).ok()) << name;
  const auto cameras = testCameras();
  const LensCamera radtan = cameras[0].camera, kb = cameras[2].camera, mei = cameras[4].camera, ds = cameras[6].camera;
  auto expectError = [](const LensCamera& c, const std::string& needle) {
    const Status s = validateLensCamera(c);
    ASSERT_FALSE(s.ok()) << needle;
    EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(s.error().message.find(needle), std::string::npos) << s.error().message;
  };
  LensCamera c = radtan;
  c.k[0] = kNaN;
  expectError(c, "k1 = nan: not finite");
  c = radtan;
  c.k[3] = std::numeric_limits<double>::infinity();
  expectError(c, "p2 = inf");
  c = radtan;
  c.k[4] = -kNaN;
  expectError(c, "k3");
  c = radtan;
  c.intrinsics.fx = kNaN;
  expectError(c, "fx");
  c = radtan;
  c.xi = 0.5;
  expectError(c, "xi = 0.5");
  c = radtan;
  c.max_angle_deg = 181;
  expectError(c, "max_angle_deg = 181");
  c = radtan;
  c.max_angle_deg = kNaN;
  expectError(c, "max_angle_deg");
  c = radtan;
  c.k[0] = -1e7;  // folds within a pixel of the axis
  expectError(c, "folds over");
  c = kb;
  c.k[3] = kNaN;
  expectError(c, "k4 = nan");
  c = kb;
  c.k[4] = 0.1;
  expectError(c, "k[4] = 0.1");
  c = mei;
  c.xi = -0.1;
  expectError(c, "xi = -0.1");
  c = mei;
  c.xi = kNaN;
  expectError(c, "xi = nan");
  c = mei;
  c.k[4] = 1e-3;
  expectError(c, "k[4]");
  c = ds;
  c.xi = 1.0;
  expectError(c, "xi = 1");
  c = ds;
  c.alpha = 1.5;
  expectError(c, "alpha = 1.5");
  c = ds;
  c.alpha = kNaN;
  expectError(c, "alpha = nan");
  c = ds;
  c.k[0] = 0.01;
  expectError(c, "k[0] = 0.01");
  c = ds;
  c.model = static_cast<LensModel>(9);
  expectError(c, "model");
}

TEST(LensCamera, ModelNamesRoundTrip) {
  for (const LensModel m :
       {LensModel::kPinhole, LensModel::kKannalaBrandt, LensModel::kMei, LensModel::kDoubleSphere}) {
    const Result<LensModel> parsed = parseLensModel(lensModelName(m));
    ASSERT_TRUE(parsed.ok()) << lensModelName(m);
    EXPECT_EQ(*parsed, m);
  }
  EXPECT_STREQ(lensModelName(LensModel::kKannalaBrandt), "kannala_brandt");
  for (const std::string bad : {"fisheye", "Pinhole", "", "mei "}) {
    const Result<LensModel> parsed = parseLensModel(bad);
    ASSERT_FALSE(parsed.ok()) << bad;
    EXPECT_EQ(parsed.error().code, ErrorCode::kUnsupported);
    EXPECT_EQ(parsed.error().message,
              "unknown camera model '" + bad + "' (pinhole, kannala_brandt, mei, double_sphere)");
  }
}

}  // namespace
}  // namespace vkloc
