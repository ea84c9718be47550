#include "vkloc/track/pose_verification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vkloc {

VerificationFeatures verificationFeatures(const TrackResult& result, double scene_depth_m) {
  const TrackQuality& q = result.quality;
  VerificationFeatures f;
  f.inlier_ratio = q.inlier_ratio;
  f.chance_inlier_ratio = q.chance_inlier_ratio;
  f.above_chance =
      q.chance_inlier_ratio < 1.0 ? (q.inlier_ratio - q.chance_inlier_ratio) / (1.0 - q.chance_inlier_ratio) : 0.0;
  f.mean_residual_px = q.mean_residual_px;
  f.scale_px = q.scale_px;
  f.spread_ratio = q.spread_ratio;
  f.visible_ratio = q.visible_ratio;
  f.points_in_image = q.points_in_image;
  const double var_t = result.covariance.topLeftCorner<3, 3>().trace();
  const double var_r = result.covariance.bottomRightCorner<3, 3>().trace();
  const bool have = result.covariance.allFinite() && var_t > 0 && var_r > 0 && scene_depth_m > 0;
  f.sigma_t_rel = have ? std::sqrt(var_t) / scene_depth_m : std::numeric_limits<double>::infinity();
  f.sigma_r_deg = have ? std::sqrt(var_r) * 180.0 / M_PI : std::numeric_limits<double>::infinity();
  return f;
}

double verificationScore(const VerificationFeatures& f, const VerificationOptions& o) {
  auto ramp = [](double x, double zero, double width) { return std::clamp((x - zero) / width, 0.0, 1.0); };
  const double above = std::clamp(f.above_chance, 0.0, 1.0);
  const double residual = f.mean_residual_px / o.inlier_threshold_px;
  const double residual_term = ramp(o.residual_zero - residual, 0.0, o.residual_ramp);
  const double spread = f.spread_ratio > 0 ? std::min(f.spread_ratio, 1.0 / f.spread_ratio) : 0.0;
  const double spread_term = ramp(spread, o.spread_zero, o.spread_ramp);
  const double score = above * residual_term * spread_term;
  return std::isfinite(score) ? score : 0.0;
}

}  // namespace vkloc
