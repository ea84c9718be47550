// vkloc: lens camera models (lens_camera.hpp). Eigen and the standard library only.
//
// Every model maps a direction to the normalized plane m, then u = fx mx + cx, v = fy my + cy.
// Distortions fold over where the radius they produce stops growing; the field of view ends
// there. The fold is the first positive root of the distortion's radial slope, a polynomial in
// s (the squared radius, or theta^2 for Kannala-Brandt) with value 1 at s = 0. projectLens tests
// a cheap lower bound of that slope first and looks for the root only near the fold.
#include "vkloc/core/lens_camera.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// The field of a distorted pinhole (and of Mei with xi <= 1) ends at |m| = 1e6 (0.00006 degrees
/// short of 90 for a pinhole); folds are looked for up to there.
constexpr double kMaxPlaneR2 = 1e12;

using Matrix23 = Eigen::Matrix<double, 2, 3>;

// --- polynomials in s ---------------------------------------------------------------------------

/// c[0] + c[1] s + ... + c[degree] s^degree.
struct Poly {
  std::array<double, 5> c{};
  int degree = 0;

  double operator()(double s) const {
    double v = c[degree];
    for (int i = degree - 1; i >= 0; --i) v = v * s + c[i];
    return v;
  }
  Poly derivative() const {
    Poly d;
    for (int i = 1; i <= degree; ++i) d.c[i - 1] = i * c[i];
    d.degree = std::max(0, degree - 1);
    return d;
  }
};

Poly makePoly(std::initializer_list<double> coefficients) {
  Poly p;
  int i = 0;
  for (const double v : coefficients) p.c[i++] = v;
  p.degree = 0;
  for (int j = 0; j < i; ++j) {
    if (p.c[j] != 0) p.degree = j;
  }
  return p;
}

/// The root of p in [a, b], where p is monotonic and changes sign: Newton steps kept inside the
/// bracket, bisection otherwise.
double monotoneRoot(const Poly& p, const Poly& dp, double a, double b) {
  const bool a_positive = p(a) > 0;
  double lo = a, hi = b, x = 0.5 * (a + b);
  for (int i = 0; i < 100; ++i) {
    const double f = p(x);
    if (f == 0) break;
    ((f > 0) == a_positive ? lo : hi) = x;
    double next = x - f / dp(x);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool converged = std::abs(next - x) <= 4e-16 * std::abs(x) || hi - lo <= 4e-16 * std::abs(hi);
    x = next;
    if (converged) break;
  }
  return x;
}

/// Writes the points of (lo, hi) where p changes sign, ascending, to out (room for p.degree);
/// returns their number. p is monotonic between the sign changes of p', found the same way.
int signChanges(const Poly& p, double lo, double hi, double* out) {
  if (p.degree == 0) return 0;
  const Poly dp = p.derivative();
  double knots[6];
  int n = 0;
  knots[n++] = lo;
  n += signChanges(dp, lo, hi, knots + 1);
  knots[n++] = hi;
  int count = 0;
  for (int i = 0; i + 1 < n; ++i) {
    if ((p(knots[i]) > 0) != (p(knots[i + 1]) > 0)) out[count++] = monotoneRoot(p, dp, knots[i], knots[i + 1]);
  }
  return count;
}

/// The first s in (0, s_max] where the slope p (p(0) = 1) reaches 0, or infinity.
double foldS(const Poly& slope, double s_max) {
  double roots[4];
  return signChanges(slope, 0.0, s_max, roots) > 0 ? roots[0] : kInf;
}

/// True when s <= s_max and the slope stays positive on [0, s]: first a lower bound that falls
/// with s (the negative terms only), then the root itself.
bool beforeFold(const Poly& slope, double s, double s_max) {
  if (!(s <= s_max)) return false;
  double bound = 1.0, power = 1.0;
  for (int i = 1; i <= slope.degree; ++i) {
    power *= s;
    bound += std::min(0.0, slope.c[i]) * power;
  }
  return bound > 0 || s < foldS(slope, s_max);
}

/// The radial slope of the model's distortion as a polynomial in s, and the range of s searched.
struct Slope {
  Poly poly;
  double s_max = 0.0;
};

Slope distortionSlope(const LensCamera& c) {
  const auto& k = c.k;
  switch (c.model) {
    case LensModel::kPinhole:  // d(r radial(r^2))/dr in s = r^2
      return {makePoly({1.0, 3 * k[0], 5 * k[1], 7 * k[4]}), kMaxPlaneR2};
    case LensModel::kKannalaBrandt:  // d theta_d / d theta in s = theta^2, theta <= pi
      return {makePoly({1.0, 3 * k[0], 5 * k[1], 7 * k[2], 9 * k[3]}), kPi * kPi};
    case LensModel::kMei:  // the unified plane radius is at most 1 / sqrt(xi^2 - 1) for xi > 1
      return {makePoly({1.0, 3 * k[0], 5 * k[1]}), c.xi > 1 ? 1.0 / (c.xi * c.xi - 1) : kMaxPlaneR2};
    case LensModel::kDoubleSphere:
      break;
  }
  return {makePoly({1.0}), 0.0};
}

// --- radial-tangential distortion ---------------------------------------------------------------

struct RadTan {
  double k1, k2, p1, p2, k3;
};

RadTan radTan(const LensCamera& c) {
  const double k3 = c.model == LensModel::kPinhole ? c.k[4] : 0.0;
  return {c.k[0], c.k[1], c.k[2], c.k[3], k3};
}

/// md = m radial + tangential (Brown-Conrady, OpenCV's order); D = d(md)/d(m).
Eigen::Vector2d distort(const RadTan& d, const Eigen::Vector2d& m, Eigen::Matrix2d* D) {
  const double mx = m.x(), my = m.y(), mxy = mx * my;
  const double r2 = mx * mx + my * my;
  const double radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  if (D) {
    const double dradial = d.k1 + r2 * (2 * d.k2 + 3 * d.k3 * r2);  // d radial / d r2
    const double cross = 2 * mxy * dradial + 2 * d.p1 * mx + 2 * d.p2 * my;
    *D << radial + 2 * mx * mx * dradial + 2 * d.p1 * my + 6 * d.p2 * mx, cross, cross,
        radial + 2 * my * my * dradial + 6 * d.p1 * my + 2 * d.p2 * mx;
  }
  return {mx * radial + 2 * d.p1 * mxy + d.p2 * (r2 + 2 * mx * mx),
          my * radial + d.p1 * (r2 + 2 * my * my) + 2 * d.p2 * mxy};
}

/// Newton on distort(m) = md from m, halving steps that do not reduce the residual. True when
/// the residual ends at most tolerance.
bool newtonUndistort(const RadTan& d, const Eigen::Vector2d& md, double tolerance, Eigen::Vector2d& m) {
  Eigen::Matrix2d D;
  Eigen::Vector2d e = distort(d, m, &D) - md;
  double error = e.norm();
  for (int i = 0; i < 50 && error > 0; ++i) {
    const double det = D(0, 0) * D(1, 1) - D(0, 1) * D(1, 0);
    if (!(std::abs(det) > 0)) break;
    const Eigen::Vector2d step(-(D(1, 1) * e.x() - D(0, 1) * e.y()) / det, -(D(0, 0) * e.y() - D(1, 0) * e.x()) / det);
    if (step.norm() <= 1e-15 * std::max(1.0, m.norm())) {  // converged to rounding
      m += step;
      break;
    }
    bool improved = false;
    double t = 1.0;
    for (int h = 0; h < 30 && !improved; ++h, t *= 0.5) {
      const Eigen::Vector2d mt = m + t * step;
      Eigen::Matrix2d Dt;
      const Eigen::Vector2d et = distort(d, mt, &Dt) - md;
      if (et.norm() < error) {
        m = mt, D = Dt, e = et, error = et.norm();
        improved = true;
      }
    }
    if (!improved) break;
  }
  return error <= tolerance;
}

/// Solves f(t) = y for t in [0, hi], f increasing there with f(0) = 0 <= y <= f(hi): Newton kept
/// inside the bracket, bisection otherwise. fdf(t, df) returns f(t) and sets df = f'(t).
template <typename F>
double solveIncreasing(const F& fdf, double y, double hi) {
  double lo = 0.0, t = std::min(y, hi);
  for (int i = 0; i < 100; ++i) {
    double df = 0.0;
    const double f = fdf(t, df) - y;
    if (f == 0) break;
    (f < 0 ? lo : hi) = t;
    double next = t - f / df;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool converged = std::abs(next - t) <= 1e-16 * t || hi - lo <= 1e-16 * hi;
    t = next;
    if (converged) break;
  }
  return t;
}

/// The undistorted plane point of md (k3 only for the pinhole model): Newton from md, and when
/// that fails or lands past the fold, Newton from the radial-only inverse inside the fold.
bool undistort(const LensCamera& c, const Eigen::Vector2d& md, Eigen::Vector2d& m_out) {
  const RadTan d = radTan(c);
  const Slope slope = distortionSlope(c);
  const double tolerance = 1e-12 * std::max(1.0, md.norm());
  Eigen::Vector2d m = md;
  if (newtonUndistort(d, md, tolerance, m) && beforeFold(slope.poly, m.squaredNorm(), slope.s_max)) {
    m_out = m;
    return true;
  }
  const double rd = md.norm();
  if (rd == 0) return false;
  const double r_hi = std::sqrt(std::min(foldS(slope.poly, slope.s_max), slope.s_max));
  auto radial = [&d](double r, double& df) {
    const double s = r * r;
    df = 1 + s * (3 * d.k1 + s * (5 * d.k2 + s * 7 * d.k3));
    return r * (1 + s * (d.k1 + s * (d.k2 + s * d.k3)));
  };
  double unused = 0.0;
  if (!(rd < radial(r_hi, unused))) return false;  // beyond the image circle (radially)
  m = md * (solveIncreasing(radial, rd, r_hi) / rd);
  if (!newtonUndistort(d, md, tolerance, m)) return false;
  m_out = m;
  return true;
}

// --- Kannala-Brandt -----------------------------------------------------------------------------

/// theta_d(theta) and its derivative.
double thetaD(const std::array<double, 5>& k, double theta, double& dtheta_d) {
  const double s = theta * theta;
  dtheta_d = 1 + s * (3 * k[0] + s * (5 * k[1] + s * (7 * k[2] + s * 9 * k[3])));
  return theta * (1 + s * (k[0] + s * (k[1] + s * (k[2] + s * k[3]))));
}

/// Largest theta before the fold (or pi).
double kbThetaMax(const LensCamera& c) {
  const Slope slope = distortionSlope(c);
  if (beforeFold(slope.poly, slope.s_max, slope.s_max)) return kPi;
  return std::min(kPi, std::sqrt(foldS(slope.poly, slope.s_max)));
}

// --- unified model / double sphere --------------------------------------------------------------

/// Mei: angle from the axis of the ray whose unified-plane radius^2 is r2 (Mei 2007, the inverse
/// of the unified projection: lambda = (xi + sqrt(1 + (1 - xi^2) r2)) / (1 + r2)).
double meiAngle(double xi, double r2) {
  const double lambda = (xi + std::sqrt(std::max(0.0, 1 + (1 - xi * xi) * r2))) / (1 + r2);
  return std::atan2(lambda * std::sqrt(r2), lambda - xi);
}

/// Double sphere (Usenko, Demmel, Cremers 2018, sec. III-F): valid where z > -w2 d1, with
/// w1 = alpha / (1 - alpha) for alpha <= 0.5, (1 - alpha) / alpha otherwise.
double dsW2(double xi, double alpha) {
  const double w1 = alpha <= 0.5 ? alpha / (1 - alpha) : (1 - alpha) / alpha;
  return (w1 + xi) / std::sqrt(2 * w1 * xi + xi * xi + 1);
}

// --- projection ---------------------------------------------------------------------------------

/// projectLens without the promise to leave outputs alone: false when outside the field.
bool projectImpl(const LensCamera& c, const Eigen::Vector3d& p_in, Eigen::Vector2d& uv, Matrix23* J) {
  // Every model is invariant to the length of p; far from 1 it is rescaled so that no square
  // overflows or underflows.
  const double size = p_in.cwiseAbs().maxCoeff();
  if (!(size > 0) || !std::isfinite(size)) return false;  // zero, NaN or infinite
  const bool rescale = size > 1e100 || size < 1e-100;
  const Eigen::Vector3d p = rescale ? Eigen::Vector3d(p_in / size) : p_in;
  const double x = p.x(), y = p.y(), z = p.z();
  const double r2 = x * x + y * y, d2 = r2 + z * z;
  if (c.max_angle_deg > 0 && !(std::atan2(std::sqrt(r2), z) <= c.max_angle_deg * (kPi / 180))) return false;
  const PinholeCamera& K = c.intrinsics;

  Eigen::Vector2d m;  // normalized plane (after distortion)
  Matrix23 dm;        // d(m) / d(p)
  switch (c.model) {
    case LensModel::kPinhole: {
      if (!(z > 0)) return false;
      if (c.isIdealPinhole()) {  // the formula used across vkloc, bit for bit
        uv = Eigen::Vector2d(K.fx * x / z + K.cx, K.fy * y / z + K.cy);
        if (J) *J << K.fx / z, 0, -K.fx * x / (z * z), 0, K.fy / z, -K.fy * y / (z * z);
        if (J && rescale) *J /= size;
        return uv.allFinite() && (!J || J->allFinite());
      }
      const double iz = 1 / z;
      const Eigen::Vector2d mu(x * iz, y * iz);
      const Slope slope = distortionSlope(c);
      if (!beforeFold(slope.poly, mu.squaredNorm(), slope.s_max)) return false;
      Eigen::Matrix2d D;
      m = distort(radTan(c), mu, &D);
      Matrix23 dmu;
      dmu << iz, 0, -mu.x() * iz, 0, iz, -mu.y() * iz;
      dm = D * dmu;
      break;
    }
    case LensModel::kKannalaBrandt: {
      // theta = atan2(r, z); m = a (x, y) with a = theta_d / r, whose gradient is
      // ((x, y) / r (theta_d' z / d2 - a) / r, -theta_d' / d2).
      if (r2 == 0 && !(z > 0)) return false;  // straight back: theta = pi is a circle, not a point
      const double r = std::sqrt(r2), theta = std::atan2(r, z);
      const Slope slope = distortionSlope(c);
      if (!beforeFold(slope.poly, theta * theta, slope.s_max)) return false;
      if (z > 0 && r2 <= 1e-30 * z * z) {  // on the axis: the pinhole limit, exact in double
        m = Eigen::Vector2d(x / z, y / z);
        dm << 1 / z, 0, -x / (z * z), 0, 1 / z, -y / (z * z);
        break;
      }
      double dtheta_d = 0.0;
      const double a = thetaD(c.k, theta, dtheta_d) / r;
      const double q = dtheta_d * z / d2 - a, ux = x / r, uy = y / r;
      m = Eigen::Vector2d(a * x, a * y);
      dm << a + ux * ux * q, ux * uy * q, -x * dtheta_d / d2, ux * uy * q, a + uy * uy * q, -y * dtheta_d / d2;
      break;
    }
    case LensModel::kMei: {
      // den = zs + xi on the unit sphere, scaled: den = z + xi d; valid for zs > -1/xi (xi > 1)
      // or zs > -xi (xi <= 1).
      const double d = std::sqrt(d2), zs = z / d;
      if (!(c.xi > 1 ? zs > -1 / c.xi : zs > -c.xi)) return false;
      const double den = z + c.xi * d;
      if (!(den > 0)) return false;
      const Eigen::Vector2d mu(x / den, y / den);
      const Slope slope = distortionSlope(c);
      if (!beforeFold(slope.poly, mu.squaredNorm(), slope.s_max)) return false;
      const Eigen::RowVector3d g(c.xi * x / d, c.xi * y / d, 1 + c.xi * z / d);  // d den / d p
      Matrix23 dmu;
      dmu << 1, 0, 0, 0, 1, 0;
      dmu = (dmu - mu * g) / den;
      Eigen::Matrix2d D;
      m = distort(radTan(c), mu, &D);
      dm = D * dmu;
      break;
    }
    case LensModel::kDoubleSphere: {
      // Usenko 2018, sec. III-F: projection and its valid set.
      const double d1 = std::sqrt(d2);
      if (!(z > -dsW2(c.xi, c.alpha) * d1)) return false;
      const double k = c.xi * d1 + z, dd2 = std::sqrt(r2 + k * k);
      const double den = c.alpha * dd2 + (1 - c.alpha) * k;
      if (!(den > 0)) return false;
      m = Eigen::Vector2d(x / den, y / den);
      const Eigen::RowVector3d gk(c.xi * x / d1, c.xi * y / d1, c.xi * z / d1 + 1);  // d k / d p
      const Eigen::RowVector3d gd2 = (Eigen::RowVector3d(x, y, 0) + k * gk) / dd2;
      const Eigen::RowVector3d g = c.alpha * gd2 + (1 - c.alpha) * gk;  // d den / d p
      dm << 1, 0, 0, 0, 1, 0;
      dm = (dm - m * g) / den;
      break;
    }
    default:
      return false;
  }
  uv = Eigen::Vector2d(K.fx * m.x() + K.cx, K.fy * m.y() + K.cy);
  if (J) {
    J->row(0) = K.fx * dm.row(0);
    J->row(1) = K.fy * dm.row(1);
    if (rescale) *J /= size;
  }
  return uv.allFinite() && (!J || J->allFinite());
}

/// The ray of the normalized-plane point md (distorted), before the check that it is valid.
bool unprojectPlane(const LensCamera& c, const Eigen::Vector2d& md, Eigen::Vector3d& ray) {
  switch (c.model) {
    case LensModel::kPinhole: {
      Eigen::Vector2d m = md;
      if (!c.isIdealPinhole() && !undistort(c, md, m)) return false;
      ray = Eigen::Vector3d(m.x(), m.y(), 1.0).normalized();
      return true;
    }
    case LensModel::kKannalaBrandt: {
      const double td = md.norm();
      if (td == 0) {
        ray = Eigen::Vector3d::UnitZ();
        return true;
      }
      const double theta_max = kbThetaMax(c);
      auto f = [&c](double theta, double& df) { return thetaD(c.k, theta, df); };
      double unused = 0.0;
      if (!(td < f(theta_max, unused))) return false;  // beyond the image circle
      const double theta = solveIncreasing(f, td, theta_max);
      if (!(std::abs(f(theta, unused) - td) <= 1e-12 * std::max(1.0, td))) return false;
      const double s = std::sin(theta) / td;
      ray = Eigen::Vector3d(s * md.x(), s * md.y(), std::cos(theta));
      return true;
    }
    case LensModel::kMei: {
      Eigen::Vector2d m;
      if (!undistort(c, md, m)) return false;
      const double r2 = m.squaredNorm(), root = 1 + (1 - c.xi * c.xi) * r2;
      if (!(root >= 0)) return false;  // beyond the image circle (xi > 1)
      const double lambda = (c.xi + std::sqrt(root)) / (1 + r2);
      ray = Eigen::Vector3d(lambda * m.x(), lambda * m.y(), lambda - c.xi).normalized();
      return true;
    }
    case LensModel::kDoubleSphere: {
      // Usenko 2018, sec. III-F: mz = (1 - alpha^2 r2) / (alpha sqrt(1 - (2 alpha - 1) r2) + 1 - alpha),
      // ray = s (mx, my, mz) - (0, 0, xi), s = (mz xi + sqrt(mz^2 + (1 - xi^2) r2)) / (mz^2 + r2).
      const double a = c.alpha, r2 = md.squaredNorm();
      const double root2 = 1 - (2 * a - 1) * r2;
      if (!(root2 >= 0)) return false;  // r2 > 1 / (2 alpha - 1): beyond the image circle
      const double mz = (1 - a * a * r2) / (a * std::sqrt(root2) + 1 - a);
      const double root1 = mz * mz + (1 - c.xi * c.xi) * r2;
      if (!(root1 >= 0)) return false;
      const double s = (mz * c.xi + std::sqrt(root1)) / (mz * mz + r2);
      ray = Eigen::Vector3d(s * md.x(), s * md.y(), s * mz - c.xi).normalized();
      return true;
    }
  }
  return false;
}

}  // namespace

const char* lensModelName(LensModel model) {
  switch (model) {
    case LensModel::kPinhole:
      return "pinhole";
    case LensModel::kKannalaBrandt:
      return "kannala_brandt";
    case LensModel::kMei:
      return "mei";
    case LensModel::kDoubleSphere:
      return "double_sphere";
  }
  return "unknown";
}

Result<LensModel> parseLensModel(const std::string& name) {
  for (const LensModel m :
       {LensModel::kPinhole, LensModel::kKannalaBrandt, LensModel::kMei, LensModel::kDoubleSphere}) {
    if (name == lensModelName(m)) return m;
  }
  return makeError(ErrorCode::kUnsupported, text::cat("unknown camera model ", text::shown(name),
                                                      " (pinhole, kannala_brandt, mei, double_sphere)"));
}

bool LensCamera::isIdealPinhole() const {
  return model == LensModel::kPinhole && std::all_of(k.begin(), k.end(), [](double v) { return v == 0; });
}

Status validateLensCamera(const LensCamera& camera) {
  VKLOC_TRY_STATUS(validateCamera(camera.intrinsics));
  const LensModel model = camera.model;
  const char* model_name = lensModelName(model);
  if (std::string(model_name) == "unknown") {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("camera: model ", static_cast<int>(model), " is not a lens model"));
  }
  auto bad = [](const std::string& name, double v, const std::string& what) {
    return makeError(ErrorCode::kInvalidArgument, text::cat("camera: ", name, " = ", v, ": ", what));
  };
  static const char* const kNames[4][5] = {{"k1", "k2", "p1", "p2", "k3"},
                                           {"k1", "k2", "k3", "k4", nullptr},
                                           {"k1", "k2", "p1", "p2", nullptr},
                                           {nullptr, nullptr, nullptr, nullptr, nullptr}};
  const int row = static_cast<int>(model);
  for (int i = 0; i < 5; ++i) {
    const char* name = kNames[row][i];
    const std::string shown = name ? std::string(name) : text::cat("k[", i, "]");
    if (!std::isfinite(camera.k[i])) return bad(shown, camera.k[i], "not finite");
    if (!name && camera.k[i] != 0) return bad(shown, camera.k[i], text::cat("unused by ", model_name, ", must be 0"));
  }
  if (!std::isfinite(camera.xi)) return bad("xi", camera.xi, "not finite");
  if (!std::isfinite(camera.alpha)) return bad("alpha", camera.alpha, "not finite");
  if (model == LensModel::kMei) {
    if (!(camera.xi >= 0)) return bad("xi", camera.xi, "must be >= 0 for mei");
  } else if (model == LensModel::kDoubleSphere) {
    if (!(camera.xi > -1 && camera.xi < 1)) return bad("xi", camera.xi, "must be in (-1, 1) for double_sphere");
  } else if (camera.xi != 0) {
    return bad("xi", camera.xi, text::cat("unused by ", model_name, ", must be 0"));
  }
  if (model == LensModel::kDoubleSphere) {
    if (!(camera.alpha >= 0 && camera.alpha <= 1)) return bad("alpha", camera.alpha, "must be in [0, 1]");
  } else if (camera.alpha != 0) {
    return bad("alpha", camera.alpha, text::cat("unused by ", model_name, ", must be 0"));
  }
  if (!(camera.max_angle_deg >= 0 && camera.max_angle_deg <= 180)) {
    return bad("max_angle_deg", camera.max_angle_deg, "must be in [0, 180] (0: no limit)");
  }
  // Invertible somewhere: the distortion must not fold over within one pixel of the axis.
  LensCamera uncapped = camera;
  uncapped.max_angle_deg = 0;
  const double limit = lensMaxAngle(uncapped);
  const double one_pixel = std::atan(1.0 / std::max(camera.intrinsics.fx, camera.intrinsics.fy));
  if (!(limit > one_pixel)) {
    return makeError(ErrorCode::kInvalidArgument,
                     text::cat("camera: the ", model_name, " distortion folds over ", limit * 180 / kPi,
                               " degrees from the optical axis, within one pixel: check k1..k4"));
  }
  return Status::success();
}

double lensMaxAngle(const LensCamera& camera) {
  const LensCamera& c = camera;
  double limit = 0.0;
  switch (c.model) {
    case LensModel::kPinhole: {
      const Slope slope = distortionSlope(c);
      limit =
          c.isIdealPinhole() ? kPi / 2 : std::atan(std::sqrt(std::min(foldS(slope.poly, slope.s_max), slope.s_max)));
      break;
    }
    case LensModel::kKannalaBrandt:
      limit = kbThetaMax(c);
      break;
    case LensModel::kMei: {
      limit = std::acos(c.xi > 1 ? -1 / c.xi : -std::min(c.xi, 1.0));
      const Slope slope = distortionSlope(c);
      limit = std::min(limit, meiAngle(c.xi, std::min(foldS(slope.poly, slope.s_max), slope.s_max)));
      break;
    }
    case LensModel::kDoubleSphere:
      limit = std::acos(std::clamp(-dsW2(c.xi, c.alpha), -1.0, 1.0));
      break;
  }
  if (c.max_angle_deg > 0) limit = std::min(limit, c.max_angle_deg * (kPi / 180));
  return limit;
}

bool projectLens(const LensCamera& camera, const Eigen::Vector3d& p_camera, Eigen::Vector2d& uv, Matrix23* J) {
  Eigen::Vector2d uv_out;
  Matrix23 J_out;
  if (!projectImpl(camera, p_camera, uv_out, J ? &J_out : nullptr)) return false;
  uv = uv_out;
  if (J) *J = J_out;
  return true;
}

bool unprojectLens(const LensCamera& camera, const Eigen::Vector2d& uv, Eigen::Vector3d& ray,
                   Eigen::Matrix<double, 3, 2>* J) {
  const PinholeCamera& K = camera.intrinsics;
  const Eigen::Vector2d md((uv.x() - K.cx) / K.fx, (uv.y() - K.cy) / K.fy);
  Eigen::Vector3d r;
  if (!md.allFinite() || !unprojectPlane(camera, md, r) || !r.allFinite()) return false;
  // The ray must lie in the field projectLens accepts and project back onto uv.
  Eigen::Vector2d uv_back;
  Matrix23 P;
  if (!projectImpl(camera, r, uv_back, &P)) return false;
  const Eigen::Vector2d md_back((uv_back.x() - K.cx) / K.fx, (uv_back.y() - K.cy) / K.fy);
  if (!((md_back - md).norm() <= 1e-9 * std::max(1.0, md.norm()))) return false;
  if (J) {
    // The ray moves on the unit sphere: with T an orthonormal basis of its tangent plane,
    // d(uv) = P T a and d(ray) = T a, so d(ray)/d(uv) = T (P T)^-1.
    const Eigen::Vector3d axis = std::abs(r.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    Eigen::Matrix<double, 3, 2> T;
    T.col(0) = r.cross(axis).normalized();
    T.col(1) = r.cross(T.col(0));
    const Eigen::Matrix2d PT = P * T;
    const double det = PT(0, 0) * PT(1, 1) - PT(0, 1) * PT(1, 0);
    if (!(std::abs(det) > 0)) return false;
    Eigen::Matrix2d inverse;
    inverse << PT(1, 1), -PT(0, 1), -PT(1, 0), PT(0, 0);
    const Eigen::Matrix<double, 3, 2> J_out = T * (inverse / det);
    if (!J_out.allFinite()) return false;
    *J = J_out;
  }
  ray = r;
  return true;
}

}  // namespace vkloc
