// Gauss-Newton edge alignment on SE(3), CPU backend (see edge_tracker.hpp).
#include "vkloc/track/edge_tracker.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <optional>

#include "vkloc/core/numeric.hpp"
namespace vkloc {
namespace {

/// Lower bound of the t-distribution scale, pixels (default of estimateTDistributionScale).
constexpr double kMinSigmaPx = 0.05;

/// Robust cost (eq. 13 for one sigma): the sum of log(1 + r^2 / (nu sigma^2)), the negative
/// log-likelihood of the t-distribution up to constants, over the points inside the image at
/// both poses of a step (`in_a` and `in_b` set); an invalid residual there (a truncated
/// distance) costs as much as the truncation.
double robustCost(const std::vector<float>& residuals, const std::vector<uint8_t>& in_a,
                  const std::vector<uint8_t>& in_b, double sigma, double nu, double truncation) {
  const double inv = 1.0 / (nu * sigma * sigma);
  const double invalid_cost = std::log1p(truncation * truncation * inv);
  double cost = 0;
  for (size_t i = 0; i < residuals.size(); ++i) {
    if (!in_a[i] || !in_b[i]) continue;
    const float r = residuals[i];
    cost += r < 0 ? invalid_cost : std::log1p(static_cast<double>(r) * r * inv);
  }
  return cost;
}

/// T with its rotation re-orthonormalised (through a normalised quaternion), so that many
/// compounded increments stay a valid rigid transform (isValidPose tolerates 1e-6).
Pose orthonormalized(const Pose& T) {
  Pose out = T;
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  return out;
}

/// Points whose depth z is at least the `quantile` quantile of the depths of `points`.
std::vector<EdgePoint> farPoints(const std::vector<EdgePoint>& points, double quantile) {
  std::vector<float> z;
  z.reserve(points.size());
  for (const EdgePoint& p : points) z.push_back(p.z);
  if (z.empty()) return {};
  const size_t k = std::min(z.size() - 1, static_cast<size_t>(quantile * static_cast<double>(z.size())));
  std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(k), z.end());
  const float threshold = z[k];
  std::vector<EdgePoint> out;
  out.reserve(points.size() - k);
  for (const EdgePoint& p : points) {
    if (p.z >= threshold) out.push_back(p);
  }
  return out;
}

/// True when the 2x2 bilinear footprint of (u, v) lies inside a w x h image.
bool footprintInside(double u, double v, int w, int h) { return u >= 0 && v >= 0 && u < w - 1 && v < h - 1; }

/// Whether `point` projects in front of `camera` at T_camera_ref with its bilinear footprint
/// inside the image (as evaluateEdgePoint asks before reading the distance field).
bool projectsInImage(const EdgePoint& point, const Pose& T_camera_ref, const PinholeCamera& camera) {
  const Eigen::Vector3d p = T_camera_ref * Eigen::Vector3d(point.x, point.y, point.z);
  if (!(p.z() > 1e-6)) return false;
  return footprintInside(camera.fx * p.x() / p.z() + camera.cx, camera.fy * p.y() / p.z() + camera.cy, camera.width,
                         camera.height);
}

/// Per point: 1 where projectsInImage, else 0.
void markInImage(const std::vector<EdgePoint>& points, const Pose& T_camera_ref, const PinholeCamera& camera,
                 std::vector<uint8_t>& in_image) {
  in_image.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) in_image[i] = projectsInImage(points[i], T_camera_ref, camera);
}

}  // namespace

void unpackEdgeNormalEquations(const EdgeNormalEquations& packed, Matrix6d& H, Vector6d& g) {
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) {
      H(r, c) = packed[edgeNormalIndex(r, c)];
      H(c, r) = H(r, c);
    }
    g[r] = packed[kEdgeNormalGradientOffset + r];
  }
}

EdgePointEvaluation evaluateEdgePoint(const EdgePoint& point, const Pose& T_camera_ref, const LiveLevel& level,
                                      bool with_jacobian) {
  EdgePointEvaluation e;
  const Eigen::Vector3d p = T_camera_ref * Eigen::Vector3d(point.x, point.y, point.z);
  if (!(p.z() > 1e-6)) return e;
  const PinholeCamera& cam = level.camera;
  const double iz = 1.0 / p.z();
  e.u = cam.fx * p.x() * iz + cam.cx;
  e.v = cam.fy * p.y() * iz + cam.cy;
  const ImageF32& D = level.field.distance;
  if (!footprintInside(e.u, e.v, D.width, D.height)) return e;
  const int x0 = static_cast<int>(e.u);
  const int y0 = static_cast<int>(e.v);
  const double a = e.u - x0;
  const double b = e.v - y0;
  const float trunc = level.field.truncation_px;
  const float d00 = D.at(x0, y0);
  const float d10 = D.at(x0 + 1, y0);
  const float d01 = D.at(x0, y0 + 1);
  const float d11 = D.at(x0 + 1, y0 + 1);
  if (d00 >= trunc || d10 >= trunc || d01 >= trunc || d11 >= trunc) return e;
  const double w00 = (1 - a) * (1 - b);
  const double w10 = a * (1 - b);
  const double w01 = (1 - a) * b;
  const double w11 = a * b;
  e.valid = true;
  double gu = 0, gv = 0;
  const ImageF32& L = level.edge_lines;
  bool on_line = false;
  if (L.channels == 3 && L.width == D.width && L.height == D.height) {
    // Near an edge: distance to the sub-pixel edge line, when all four pixels see one edge
    // (normals within ~37 degrees of each other and of the same sign).
    const float* l00 = &L.data[(static_cast<size_t>(y0) * L.width + x0) * 3];
    const float* l10 = l00 + 3;
    const float* l01 = l00 + static_cast<size_t>(L.width) * 3;
    const float* l11 = l01 + 3;
    auto same = [&](const float* q) { return q[1] * l00[1] + q[2] * l00[2] > 0.8f; };
    if ((l00[1] != 0 || l00[2] != 0) && same(l10) && same(l01) && same(l11)) {
      const double s = w00 * l00[0] + w10 * l10[0] + w01 * l01[0] + w11 * l11[0];
      const double sign = s < 0 ? -1.0 : 1.0;
      e.residual = std::abs(s);
      gu = sign * (w00 * l00[1] + w10 * l10[1] + w01 * l01[1] + w11 * l11[1]);
      gv = sign * (w00 * l00[2] + w10 * l10[2] + w01 * l01[2] + w11 * l11[2]);
      on_line = true;
    }
  }
  if (!on_line) e.residual = w00 * d00 + w10 * d10 + w01 * d01 + w11 * d11;
  if (!with_jacobian) return e;
  if (!on_line) {
    const ImageF32& G = level.field.gradient;
    if (G.empty()) {
      // Not built (LiveFrameOptions::distance_gradient): the same values from the distances.
      float g00[2], g10[2], g01[2], g11[2];
      distanceGradientAt(level.field, x0, y0, g00[0], g00[1]);
      distanceGradientAt(level.field, x0 + 1, y0, g10[0], g10[1]);
      distanceGradientAt(level.field, x0, y0 + 1, g01[0], g01[1]);
      distanceGradientAt(level.field, x0 + 1, y0 + 1, g11[0], g11[1]);
      gu = w00 * g00[0] + w10 * g10[0] + w01 * g01[0] + w11 * g11[0];
      gv = w00 * g00[1] + w10 * g10[1] + w01 * g01[1] + w11 * g11[1];
    } else {
      gu =
          w00 * G.at(x0, y0, 0) + w10 * G.at(x0 + 1, y0, 0) + w01 * G.at(x0, y0 + 1, 0) + w11 * G.at(x0 + 1, y0 + 1, 0);
      gv =
          w00 * G.at(x0, y0, 1) + w10 * G.at(x0 + 1, y0, 1) + w01 * G.at(x0, y0 + 1, 1) + w11 * G.at(x0 + 1, y0 + 1, 1);
    }
  }
  // dr/dp = [G_u G_v] d(u, v)/dp (eq. 15), then dp/d(delta) = [I | -hat(p)]:
  // the rotation part -dr/dp hat(p) equals (p x dr/dp)^T.
  const double ga = gu * cam.fx * iz;
  const double gb = gv * cam.fy * iz;
  const Eigen::Vector3d dr_dp(ga, gb, -(ga * p.x() + gb * p.y()) * iz);
  e.jacobian.head<3>() = dr_dp;
  e.jacobian.tail<3>() = p.cross(dr_dp);
  return e;
}

std::vector<float> evaluateEdgeResiduals(const std::vector<EdgePoint>& points, const Pose& T_camera_ref,
                                         const LiveLevel& level) {
  std::vector<float> residuals(points.size(), kInvalidResidual);
  for (size_t i = 0; i < points.size(); ++i) {
    const EdgePointEvaluation e = evaluateEdgePoint(points[i], T_camera_ref, level, false);
    if (e.valid) residuals[i] = static_cast<float>(e.residual);
  }
  return residuals;
}

double estimateTDistributionScale(const std::vector<float>& residuals, double nu, int iterations, double min_sigma_px) {
  // The squares of the valid residuals, once, in order (the fixed-point iterations below read
  // only them; a compact array keeps the loop free of branches).
  thread_local std::vector<double> squares;
  squares.clear();
  double sum = 0;
  for (float r : residuals) {
    if (r < 0) continue;
    const double r2 = static_cast<double>(r) * r;
    squares.push_back(r2);
    sum += r2;
  }
  const size_t n = squares.size();
  const double min_var = min_sigma_px * min_sigma_px;
  if (n == 0) return min_sigma_px;
  double var = std::max(sum / n, min_var);
  // The terms first (independent: their divisions vectorise), then their sum in order (the
  // same additions as one loop).
  thread_local std::vector<double> terms;
  terms.resize(n);
  const double nu1 = nu + 1.0;
  for (int it = 0; it < iterations; ++it) {
    const double* r2 = squares.data();
    double* t = terms.data();
    for (size_t i = 0; i < n; ++i) t[i] = r2[i] * nu1 / (nu + r2[i] / var);
    double acc = 0;
    for (size_t i = 0; i < n; ++i) acc += t[i];
    var = std::max(acc / n, min_var);
  }
  return std::sqrt(var);
}

namespace {

/// Adds one valid point's weighted terms to the normal equations (eq. 14).
inline void addToNormalEquations(EdgeNormalEquations& out, double residual, const Vector6d& J, double sigma_px,
                                 double nu) {
  const double w = tDistributionWeight(residual, sigma_px, nu);
  for (int r = 0; r < 6; ++r) {
    const double wj = w * J[r];
    for (int c = r; c < 6; ++c) out[edgeNormalIndex(r, c)] += wj * J[c];
    out[kEdgeNormalGradientOffset + r] += wj * residual;
  }
  out[kEdgeNormalCostIndex] += w * residual * residual;
  out[kEdgeNormalCountIndex] += 1.0;
}

}  // namespace

EdgeNormalEquations accumulateEdgeNormalEquations(const std::vector<EdgePoint>& points, const Pose& T_camera_ref,
                                                  const LiveLevel& level, double sigma_px, double nu) {
  EdgeNormalEquations out{};
  for (const EdgePoint& point : points) {
    const EdgePointEvaluation e = evaluateEdgePoint(point, T_camera_ref, level, true);
    if (e.valid) addToNormalEquations(out, e.residual, e.jacobian, sigma_px, nu);
  }
  return out;
}

const char* trackingStateName(TrackingState state) {
  switch (state) {
    case TrackingState::kTracking:
      return "tracking";
    case TrackingState::kLost:
      return "lost";
    case TrackingState::kInertial:
      return "inertial";
    case TrackingState::kInitializing:
      return "initializing";
    case TrackingState::kRelocalized:
      return "relocalized";
  }
  return "?";
}

Status validateEdgeTrackerOptions(const EdgeTrackerOptions& o) {
  if (!finiteIn(o.nu, 1e-3, 1e6))
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: nu must be in 1e-3..1e6");
  if (o.scale_iterations < 0 || o.scale_iterations > 100) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: scale_iterations must be in 0..100");
  }
  if (o.max_iterations < 1 || o.max_iterations > 1000) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: max_iterations must be in 1..1000");
  }
  if (o.finest_level < 0) return makeError(ErrorCode::kInvalidArgument, "edge tracker: finest_level must be >= 0");
  if (o.coarsest_level >= 0 && o.coarsest_level < o.finest_level) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: coarsest_level must be -1 or >= finest_level");
  }
  if (!finiteIn(o.far_first_depth_quantile, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: far_first_depth_quantile must be in 0..1");
  }
  if (o.far_first_coarsest_level < -1) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: far_first_coarsest_level must be >= -1");
  }
  if (!(o.far_first_skip_inlier_ratio >= 0) || std::isnan(o.far_first_skip_inlier_ratio)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: far_first_skip_inlier_ratio must be >= 0");
  }
  if (!finiteIn(o.min_step, 0.0, 1.0))
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_step must be in 0..1");
  if (!finiteIn(o.min_cost_decrease, 0.0, 1.0))
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_cost_decrease must be in 0..1");
  if (!finiteIn(o.initial_damping, 1e-12, 1e6) || !finiteIn(o.max_damping, o.initial_damping, 1e12)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: need 1e-12 <= initial_damping <= max_damping <= 1e12");
  }
  if (!finiteIn(o.inlier_threshold_px, 1e-6, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: inlier_threshold_px must be > 0");
  }
  if (!finiteIn(o.min_inlier_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_inlier_ratio must be in 0..1");
  }
  if (!finiteIn(o.min_inlier_ratio_above_chance, -1.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_inlier_ratio_above_chance must be in -1..1");
  }
  if (!finiteIn(o.max_spread_change, 1.0, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: max_spread_change must be >= 1");
  }
  if (!finiteIn(o.min_visible_ratio, 0.0, 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_visible_ratio must be in 0..1");
  }
  if (!finiteIn(o.max_mean_residual_px, 0.0, 1e6)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: max_mean_residual_px must be >= 0");
  }
  if (o.min_points < 6) return makeError(ErrorCode::kInvalidArgument, "edge tracker: min_points must be >= 6");
  if (!(o.max_translation_m > 0)) {
    return makeError(ErrorCode::kInvalidArgument, "edge tracker: max_translation_m must be > 0");
  }
  if (o.rotation_prior) {
    Pose R = Pose::Identity();
    R.linear() = o.rotation_prior->R_world_camera;
    if (!isValidPose(R)) {
      return makeError(ErrorCode::kInvalidArgument, "edge tracker: rotation_prior's R_world_camera is not a rotation");
    }
    const Eigen::Matrix3d& C = o.rotation_prior->covariance;
    if (!C.allFinite() || (C - C.transpose()).cwiseAbs().maxCoeff() > 1e-9 * C.cwiseAbs().maxCoeff() ||
        Eigen::LLT<Eigen::Matrix3d>(C).info() != Eigen::Success) {
      return makeError(ErrorCode::kInvalidArgument,
                       "edge tracker: rotation_prior's covariance must be finite, symmetric and positive definite");
    }
  }
  return Status::success();
}

Status CpuEdgeAlignment::checkLevel(int level) const {
  if (level < 0 || level >= levelCount()) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("CpuEdgeAlignment: level {} outside 0..{}", level, levelCount() - 1));
  }
  return Status::success();
}

int CpuEdgeAlignment::levelCount() const { return static_cast<int>(live_->levels.size()); }

PinholeCamera CpuEdgeAlignment::levelCamera(int level) const { return live_->levels[level].camera; }

float CpuEdgeAlignment::truncationPx(int level) const { return live_->levels[level].field.truncation_px; }

Result<EdgeEvaluation> EdgeAlignmentBackend::evaluate(int level, const Pose& T_camera_ref, double nu,
                                                      int scale_iterations, double min_sigma_px) {
  auto r = residuals(level, T_camera_ref);
  if (!r.ok()) return r.error();
  EdgeEvaluation out;
  out.residuals = std::move(r).value();
  out.sigma_px = estimateTDistributionScale(out.residuals, nu, scale_iterations, min_sigma_px);
  return out;
}

Status CpuEdgeAlignment::setPoints(const std::vector<EdgePoint>& points) {
  points_ = points;
  evaluated_.valid = false;
  return Status::success();
}

Result<EdgeEvaluation> CpuEdgeAlignment::evaluate(int level, const Pose& T_camera_ref, double nu, int scale_iterations,
                                                  double min_sigma_px) {
  VKLOC_TRY_STATUS(checkLevel(level));
  const LiveLevel& live = live_->levels[level];
  const size_t n = points_.size();
  Evaluated& c = evaluated_;
  c.valid = false;
  c.point_valid.assign(n, 0);
  c.residual.resize(n);
  c.jacobian.resize(n);
  EdgeEvaluation out;
  out.residuals.assign(n, kInvalidResidual);
  for (size_t i = 0; i < n; ++i) {
    const EdgePointEvaluation e = evaluateEdgePoint(points_[i], T_camera_ref, live, true);
    if (!e.valid) continue;
    c.point_valid[i] = 1;
    c.residual[i] = e.residual;
    c.jacobian[i] = e.jacobian;
    out.residuals[i] = static_cast<float>(e.residual);
  }
  c.level = level;
  c.T_camera_ref = T_camera_ref;
  c.valid = true;
  out.sigma_px = estimateTDistributionScale(out.residuals, nu, scale_iterations, min_sigma_px);
  return out;
}

Result<std::vector<float>> CpuEdgeAlignment::residuals(int level, const Pose& T_camera_ref) {
  VKLOC_TRY_STATUS(checkLevel(level));
  return evaluateEdgeResiduals(points_, T_camera_ref, live_->levels[level]);
}

Result<EdgeNormalEquations> CpuEdgeAlignment::accumulate(int level, const Pose& T_camera_ref, double sigma_px,
                                                         double nu) {
  VKLOC_TRY_STATUS(checkLevel(level));
  if (!(sigma_px > 0) || !(nu > 0) || !std::isfinite(sigma_px) || !std::isfinite(nu)) {
    return makeError(ErrorCode::kInvalidArgument, "CpuEdgeAlignment::accumulate: sigma_px and nu must be > 0");
  }
  const Evaluated& c = evaluated_;
  if (c.valid && c.level == level && c.T_camera_ref.matrix() == T_camera_ref.matrix()) {
    EdgeNormalEquations out{};
    for (size_t i = 0; i < points_.size(); ++i) {
      if (c.point_valid[i]) addToNormalEquations(out, c.residual[i], c.jacobian[i], sigma_px, nu);
    }
    return out;
  }
  return accumulateEdgeNormalEquations(points_, T_camera_ref, live_->levels[level], sigma_px, nu);
}

Result<double> CpuEdgeAlignment::nearEdgeFraction(int level, double threshold_px) {
  VKLOC_TRY_STATUS(checkLevel(level));
  const std::vector<float>& d = live_->levels[level].field.distance.data;
  if (d.empty()) return 0.0;
  size_t near_edge = 0;
  const auto threshold_f = static_cast<float>(threshold_px);
  if (static_cast<double>(threshold_f) == threshold_px) {
    // The threshold is a float: the same comparisons in float, which vectorise.
    for (float v : d) near_edge += v < threshold_f;
  } else {
    for (float v : d) near_edge += v < threshold_px;
  }
  return static_cast<double>(near_edge) / static_cast<double>(d.size());
}

Result<TrackResult> trackFrame(const EdgeReference& reference, const LiveFrame& live, const Pose& T_world_camera_guess,
                               const EdgeTrackerOptions& options) {
  if (live.levels.empty()) return makeError(ErrorCode::kInvalidArgument, "trackFrame: live frame has no levels");
  for (const LiveLevel& level : live.levels) {
    const DistanceField& f = level.field;
    if (f.distance.width != level.camera.width || f.distance.height != level.camera.height ||
        f.distance.channels != 1 ||
        (!f.gradient.empty() && (f.gradient.width != f.distance.width || f.gradient.height != f.distance.height ||
                                 f.gradient.channels != 2 || f.gradient.data.size() != 2 * f.distance.data.size())) ||
        f.distance.data.size() != static_cast<size_t>(f.distance.width) * f.distance.height || !(f.truncation_px > 0)) {
      return makeError(ErrorCode::kInvalidArgument,
                       "trackFrame: a live level's distance field does not match its camera");
    }
  }
  CpuEdgeAlignment backend(live);
  return trackFrame(reference, backend, T_world_camera_guess, options);
}

Result<TrackResult> trackFrame(const EdgeReference& reference, EdgeAlignmentBackend& backend,
                               const Pose& T_world_camera_guess, const EdgeTrackerOptions& options) {
  VKLOC_TRY_STATUS(validateEdgeTrackerOptions(options));
  if (!isValidPose(T_world_camera_guess)) {
    return makeError(ErrorCode::kInvalidArgument, "trackFrame: T_world_camera_guess is not a valid rigid transform");
  }
  if (!isValidPose(reference.T_world_ref)) {
    return makeError(ErrorCode::kInvalidArgument, "trackFrame: reference T_world_ref is not a valid rigid transform");
  }
  if (reference.points.empty()) {
    return makeError(ErrorCode::kInvalidArgument, "trackFrame: reference has no edge points");
  }
  const int levels = backend.levelCount();
  if (levels <= 0) return makeError(ErrorCode::kInvalidArgument, "trackFrame: live frame has no levels");
  if (options.finest_level >= levels) {
    return makeError(
        ErrorCode::kInvalidArgument,
        fmt::format("trackFrame: finest_level {} but the live frame has {} levels", options.finest_level, levels));
  }
  const int coarsest = options.coarsest_level < 0 ? levels - 1 : std::min(options.coarsest_level, levels - 1);
  auto pointsFor = [&](int level) -> const std::vector<EdgePoint>& { return edgePointsForLevel(reference, level); };

  const Pose T_camera_ref_guess = orthonormalized(T_world_camera_guess.inverse() * reference.T_world_ref);
  Pose T = T_camera_ref_guess;
  // The rotation prior on T_camera_ref: R_camera_ref = expSO3(r) R_camera_ref_prior, r ~ N(0,
  // covariance) (a camera-frame phi of the prior is -r, with the same covariance), and
  // r(delta) = logSO3(expSO3(delta_phi) R_camera_ref) ~= r + Jl^-1(r) delta_phi for the tracker's
  // left increment. The data's normal equations are sigma^2 times their information (H = sum w
  // J J^T, eq. 14), so the prior enters as sigma^2 J^T Sigma^-1 J and sigma^2 J^T Sigma^-1 r, and
  // its negative log-likelihood in robustCost's units (2 / (nu + 1) of the data's) as
  // r^T Sigma^-1 r / (nu + 1).
  Eigen::Matrix3d R_camera_ref_prior = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d prior_information = Eigen::Matrix3d::Zero();
  if (options.rotation_prior) {
    R_camera_ref_prior = options.rotation_prior->R_world_camera.transpose() * reference.T_world_ref.linear();
    prior_information = options.rotation_prior->covariance.ldlt().solve(Eigen::Matrix3d::Identity());
    prior_information = 0.5 * (prior_information + prior_information.transpose());
  }
  auto priorResidual = [&](const Pose& T_cr) -> Eigen::Vector3d {
    return logSO3(T_cr.linear() * R_camera_ref_prior.transpose());
  };
  auto priorCost = [&](const Pose& T_cr) {
    if (!options.rotation_prior) return 0.0;
    const Eigen::Vector3d r = priorResidual(T_cr);
    return r.dot(prior_information * r) / (options.nu + 1.0);
  };
  int iterations = 0;
  const std::vector<EdgePoint>* uploaded = nullptr;
  auto usePoints = [&](const std::vector<EdgePoint>& points) -> Status {
    if (uploaded == &points) return Status::success();
    VKLOC_TRY_STATUS(backend.setPoints(points));
    uploaded = &points;
    return Status::success();
  };
  std::vector<std::vector<EdgePoint>> far_lists;
  // Coarse-to-fine Gauss-Newton from T (updated in place); with far_first, pass 0 runs on the
  // far points only before pass 1 on all points.
  auto align = [&](bool far_first, int start_level) -> Status {
    for (int pass = far_first ? 0 : 1; pass < 2; ++pass) {
      for (int level_index = start_level; level_index >= options.finest_level; --level_index) {
        const std::vector<EdgePoint>& points =
            pass == 0 ? far_lists[static_cast<size_t>(level_index)] : pointsFor(level_index);
        if (points.size() < 6) continue;
        VKLOC_TRY_STATUS(usePoints(points));
        const double trunc = backend.truncationPx(level_index);
        // Residuals, scale and (GPU) normal equations at T; kept through rejected steps (T, the
        // residuals and so the scale do not change then: only the damping does).
        auto first = backend.evaluate(level_index, T, options.nu, options.scale_iterations, kMinSigmaPx);
        if (!first.ok()) return first.error();
        EdgeEvaluation at_T = std::move(first).value();
        const PinholeCamera level_camera = backend.levelCamera(level_index);
        std::vector<uint8_t> in_image_at_T;     // points inside the image at T (markInImage)
        std::vector<uint8_t> in_image_at_step;  // ... at the step's pose
        markInImage(points, T, level_camera, in_image_at_T);
        double lambda = 0;
        for (int it = 0; it < options.max_iterations; ++it) {
          if (!at_T.eq) {
            auto accumulated = backend.accumulate(level_index, T, at_T.sigma_px, options.nu);
            if (!accumulated.ok()) return accumulated.error();
            at_T.eq = *accumulated;
          }
          const EdgeNormalEquations& eq = *at_T.eq;
          if (eq[kEdgeNormalCountIndex] < 6) break;
          Matrix6d H;
          Vector6d g;
          unpackEdgeNormalEquations(eq, H, g);
          if (options.rotation_prior) {
            const Eigen::Vector3d r = priorResidual(T);
            const Eigen::Matrix3d J = leftJacobianInverseSO3(r);
            const double sigma2 = at_T.sigma_px * at_T.sigma_px;
            H.bottomRightCorner<3, 3>() += sigma2 * J.transpose() * prior_information * J;
            g.tail<3>() += sigma2 * J.transpose() * prior_information * r;
          }
          // Solve (H + lambda diag(H)) delta = -g (eq. 14); damping only after a failed solve or a
          // rejected step.
          Vector6d delta = Vector6d::Zero();
          bool solved = false;
          while (lambda <= options.max_damping) {
            Matrix6d A = H;
            A.diagonal() += lambda * H.diagonal() + Vector6d::Constant(1e-12 * (1.0 + H.diagonal().maxCoeff()));
            Eigen::LDLT<Matrix6d> ldlt(A);
            if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
              delta = ldlt.solve(-g);
              if (delta.allFinite()) {
                solved = true;
                break;
              }
            }
            lambda = lambda > 0 ? lambda * 10 : options.initial_damping;
          }
          if (!solved) break;
          ++iterations;
          const Pose T_new = orthonormalized(applyLeftIncrement(T, delta));
          auto evaluated = backend.evaluate(level_index, T_new, options.nu, options.scale_iterations, kMinSigmaPx);
          if (!evaluated.ok()) return evaluated.error();
          // Both costs with the scale at T (the robust cost of eq. 13 for one sigma), over the
          // points inside the image at both poses: a point that leaves the image (a zoom in from
          // a keyframe made farther back moves the outer points out) says nothing against the
          // step, while a truncated distance inside the image does.
          // A step that takes more than half of the points in the image out of it is refused: that
          // is a step gone astray, not a zoom (which moves out the outer ring of points).
          markInImage(points, T_new, level_camera, in_image_at_step);
          size_t in_image = 0, in_image_both = 0;
          for (size_t i = 0; i < in_image_at_T.size(); ++i) {
            in_image += in_image_at_T[i];
            in_image_both += in_image_at_T[i] & in_image_at_step[i];
          }
          const double cost_old =
              robustCost(at_T.residuals, in_image_at_T, in_image_at_step, at_T.sigma_px, options.nu, trunc) +
              priorCost(T);
          const double cost_new =
              robustCost(evaluated->residuals, in_image_at_T, in_image_at_step, at_T.sigma_px, options.nu, trunc) +
              priorCost(T_new);
          if (2 * in_image_both >= in_image && cost_new <= cost_old) {
            T = T_new;
            at_T = std::move(evaluated).value();
            std::swap(in_image_at_T, in_image_at_step);
            lambda = lambda > options.initial_damping ? lambda * 0.1 : 0.0;
            // Converged: a step below min_step, or a cost that no longer falls by min_cost_decrease.
            if (delta.norm() < options.min_step || cost_old - cost_new <= options.min_cost_decrease * cost_old) break;
          } else {
            lambda = lambda > 0 ? lambda * 10 : options.initial_damping;
            if (lambda > options.max_damping || delta.norm() < options.min_step) break;
          }
        }
      }
    }
    return Status::success();
  };
  VKLOC_TRY_STATUS(align(false, coarsest));
  const std::vector<EdgePoint>& finest_points = pointsFor(options.finest_level);
  auto inlierCount = [&](const Pose& T_cr) -> Result<int> {
    VKLOC_TRY_STATUS(usePoints(finest_points));
    auto r = backend.residuals(options.finest_level, T_cr);
    if (!r.ok()) return r.error();
    int n = 0;
    for (float v : *r) n += v >= 0 && v < options.inlier_threshold_px;
    return n;
  };
  std::optional<int> plain_inliers;
  if (options.far_first_depth_quantile > 0 && options.far_first_skip_inlier_ratio <= 1.0) {
    auto n = inlierCount(T);
    if (!n.ok()) return n.error();
    plain_inliers = *n;
  }
  const bool plain_confident = plain_inliers && *plain_inliers >= options.far_first_skip_inlier_ratio *
                                                                      static_cast<double>(finest_points.size());
  if (options.far_first_depth_quantile > 0 && !plain_confident) {
    // Second hypothesis from the same guess, far points first; the pose whose finest-level
    // inlier count is higher wins.
    for (int level_index = 0; level_index < levels; ++level_index) {
      far_lists.push_back(farPoints(pointsFor(level_index), options.far_first_depth_quantile));
    }
    const Pose T_plain = T;
    T = T_camera_ref_guess;
    const int far_coarsest =
        options.far_first_coarsest_level < 0
            ? coarsest
            : std::max(options.finest_level, std::min(options.far_first_coarsest_level, levels - 1));
    VKLOC_TRY_STATUS(align(true, far_coarsest));
    if (!plain_inliers) {
      auto n = inlierCount(T_plain);
      if (!n.ok()) return n.error();
      plain_inliers = *n;
    }
    auto far_inliers = inlierCount(T);
    if (!far_inliers.ok()) return far_inliers.error();
    if (*far_inliers <= *plain_inliers) T = T_plain;
  }

  // Quality and covariance on the finest level used.
  const int finest_index = options.finest_level;
  const PinholeCamera finest = backend.levelCamera(finest_index);
  const std::vector<EdgePoint>& points = pointsFor(finest_index);
  VKLOC_TRY_STATUS(usePoints(points));
  TrackResult result;
  result.T_camera_ref = T;
  result.T_world_camera = orthonormalized(reference.T_world_ref * T.inverse());
  TrackQuality& q = result.quality;
  q.iterations = iterations;
  auto final_residuals = backend.residuals(finest_index, T);
  if (!final_residuals.ok()) return final_residuals.error();
  const std::vector<float>& residuals = *final_residuals;
  int inliers = 0;
  double inlier_sum = 0;
  std::array<int, 5> kind_inliers{};
  for (size_t i = 0; i < points.size(); ++i) {
    const int kind = edgeKindIndex(points[i].kind);
    if (projectsInImage(points[i], T, finest)) {
      ++q.points_in_image;
      if (kind >= 0) ++q.kind_points_in_image[static_cast<size_t>(kind)];
    }
    const float r = i < residuals.size() ? residuals[i] : kInvalidResidual;
    if (r < 0) continue;
    ++q.points_used;
    if (r < options.inlier_threshold_px) {
      ++inliers;
      inlier_sum += r;
      if (kind >= 0) ++kind_inliers[static_cast<size_t>(kind)];
    }
  }
  q.inlier_ratio = q.points_in_image > 0 ? static_cast<double>(inliers) / q.points_in_image : 0.0;
  for (size_t k = 0; k < q.kind_inlier_ratio.size(); ++k) {
    q.kind_inlier_ratio[k] =
        q.kind_points_in_image[k] > 0 ? static_cast<double>(kind_inliers[k]) / q.kind_points_in_image[k] : 0.0;
  }
  auto spread = [&](const Pose& T_cr) {
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Vector2d sum2 = Eigen::Vector2d::Zero();
    int n = 0;
    for (const EdgePoint& point : points) {
      const Eigen::Vector3d p = T_cr * Eigen::Vector3d(point.x, point.y, point.z);
      if (!(p.z() > 1e-6)) continue;
      const Eigen::Vector2d uv(finest.fx * p.x() / p.z(), finest.fy * p.y() / p.z());
      sum += uv;
      sum2 += uv.cwiseProduct(uv);
      ++n;
    }
    if (n == 0) return 0.0;
    const Eigen::Vector2d mean = sum / n;
    return std::sqrt(std::max(0.0, (sum2 / n - mean.cwiseProduct(mean)).sum()));
  };
  const double spread_ref = spread(Pose::Identity());
  q.spread_ratio = spread_ref > 0 ? spread(T) / spread_ref : 0.0;
  auto chance = backend.nearEdgeFraction(finest_index, options.inlier_threshold_px);
  if (!chance.ok()) return chance.error();
  q.chance_inlier_ratio = *chance;
  const double above_chance =
      q.chance_inlier_ratio < 1.0 ? (q.inlier_ratio - q.chance_inlier_ratio) / (1.0 - q.chance_inlier_ratio) : 0.0;
  q.visible_ratio = static_cast<double>(q.points_in_image) / static_cast<double>(points.size());
  q.mean_residual_px = inliers > 0 ? inlier_sum / inliers : 0.0;
  q.scale_px = estimateTDistributionScale(residuals, options.nu, options.scale_iterations, kMinSigmaPx);
  auto final_eq = backend.accumulate(finest_index, T, q.scale_px, options.nu);
  if (!final_eq.ok()) return final_eq.error();
  const EdgeNormalEquations& eq = *final_eq;
  Matrix6d H;
  Vector6d g;
  unpackEdgeNormalEquations(eq, H, g);
  Eigen::LDLT<Matrix6d> ldlt(H);
  bool covariance_ok = false;
  if (eq[kEdgeNormalCountIndex] >= 6 && ldlt.info() == Eigen::Success && ldlt.isPositive()) {
    result.covariance = q.scale_px * q.scale_px * ldlt.solve(Matrix6d::Identity());
    covariance_ok = result.covariance.allFinite();
  }
  if (covariance_ok && options.rotation_prior) {
    // The edges' pose to first order: with information A (the edges', sigma^-2 H) and B (the
    // prior's) the MAP pose x solves (A + B) x = A x_edges + B x_prior, so x_edges = x + A^-1 B
    // (x - x_prior); about T, x - x_prior is Jl^-1(r)^-1 r on the rotation, and B (x - x_prior)
    // = [0; J^T Sigma^-1 r].
    const Eigen::Vector3d r = priorResidual(T);
    const Eigen::Matrix3d J = leftJacobianInverseSO3(r);
    Vector6d b = Vector6d::Zero();
    b.tail<3>() = J.transpose() * prior_information * r;
    const Pose T_camera_ref_edges = orthonormalized(applyLeftIncrement(T, result.covariance * b));
    result.T_world_camera_edges = orthonormalized(reference.T_world_ref * T_camera_ref_edges.inverse());
  }
  const double correction = (T_camera_ref_guess.inverse() * T).translation().norm();
  const bool ok = covariance_ok && isValidPose(result.T_world_camera) && q.points_in_image >= options.min_points &&
                  inliers >= options.min_points && q.inlier_ratio >= options.min_inlier_ratio &&
                  q.visible_ratio >= options.min_visible_ratio && q.spread_ratio * options.max_spread_change >= 1.0 &&
                  q.spread_ratio <= options.max_spread_change &&
                  above_chance >= options.min_inlier_ratio_above_chance &&
                  q.mean_residual_px <= options.max_mean_residual_px && correction <= options.max_translation_m;
  result.state = ok ? TrackingState::kTracking : TrackingState::kLost;
  return result;
}

}  // namespace vkloc
