#include "vkloc/track/pose_verification.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace vkloc {
namespace {

TrackResult resultWith(double inlier_ratio, double chance, double mean_residual_px, double spread_ratio) {
  TrackResult r;
  r.quality.inlier_ratio = inlier_ratio;
  r.quality.chance_inlier_ratio = chance;
  r.quality.mean_residual_px = mean_residual_px;
  r.quality.spread_ratio = spread_ratio;
  r.covariance = Matrix6d::Identity() * 1e-6;
  return r;
}

// The features come from the quality figures and the covariance; sigma_t_rel is over the depth.
TEST(PoseVerification, FeaturesFromTheAlignment) {
  const VerificationFeatures f = verificationFeatures(resultWith(0.8, 0.2, 0.3, 1.0), 10.0);
  EXPECT_NEAR(f.above_chance, 0.75, 1e-12);
  EXPECT_NEAR(f.sigma_t_rel, std::sqrt(3e-6) / 10.0, 1e-12);
  EXPECT_NEAR(f.sigma_r_deg, std::sqrt(3e-6) * 180.0 / M_PI, 1e-9);
  // No covariance or no depth: infinitely uncertain, never NaN.
  TrackResult none = resultWith(0.8, 0.2, 0.3, 1.0);
  none.covariance.setZero();
  EXPECT_TRUE(std::isinf(verificationFeatures(none, 10.0).sigma_t_rel));
  EXPECT_TRUE(std::isinf(verificationFeatures(resultWith(0.8, 0.2, 0.3, 1.0), 0.0).sigma_t_rel));
}

// A true pose (many inliers above chance, small residuals, points spread as in the keyframe)
// passes; chance-level residuals, a collapsed point spread or inliers at the chance rate fail.
TEST(PoseVerification, ScoreSeparatesTheKindsOfWrongPose) {
  const VerificationOptions o;
  auto score = [&](double ir, double chance, double res, double spread) {
    return verificationScore(verificationFeatures(resultWith(ir, chance, res, spread), 10.0), o);
  };
  const double truth = score(0.85, 0.2, 0.25, 1.0);
  EXPECT_GE(truth, o.min_score);
  EXPECT_LE(truth, 1.0);
  EXPECT_NEAR(truth, (0.85 - 0.2) / 0.8, 1e-12);                         // both terms saturate
  EXPECT_LT(score(0.85, 0.2, 0.5 * o.inlier_threshold_px, 1.0), 1e-12);  // residuals spread evenly: chance
  EXPECT_LT(score(1.0, 0.2, 0.2, 0.05), 1e-12);                          // shrunk onto a few edges
  EXPECT_LT(score(1.0, 0.2, 0.2, 20.0), 1e-12);                          // blown up
  EXPECT_LT(score(0.2, 0.2, 0.2, 1.0), 1e-12);                           // inliers at the chance rate
  EXPECT_EQ(score(0.1, 0.2, 0.2, 1.0), 0.0);                             // below chance: clamped
  // Monotone in each term.
  EXPECT_GT(score(0.9, 0.2, 0.3, 1.0), score(0.7, 0.2, 0.3, 1.0));
  EXPECT_GT(score(0.8, 0.2, 0.35, 1.0), score(0.8, 0.2, 0.5, 1.0));
  EXPECT_GT(score(0.8, 0.2, 0.3, 0.75), score(0.8, 0.2, 0.3, 0.65));
  // Non-finite input gives 0, never NaN.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(score(nan, 0.2, 0.3, 1.0), 0.0);
  EXPECT_EQ(score(0.8, 0.2, nan, 1.0), 0.0);
}

}  // namespace
}  // namespace vkloc
