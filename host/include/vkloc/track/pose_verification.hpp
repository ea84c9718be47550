// vkloc: pose verification: one score per aligned frame that tells a pose at the truth from one
// the alignment converged to elsewhere (a repetitive street one lane dash off, a plain wall
// matched to sensor noise). The score is built from the alignment's own quality figures and
// covariance; its threshold is chosen from the distributions `vkloc bench verify` measures (score at
// true poses vs at wrong converged poses, README "Pose verification").
#pragma once

#include "vkloc/track/edge_tracker.hpp"

namespace vkloc {

/// What the score is made of (from TrackResult and the keyframe's scene depth).
struct VerificationFeatures {
  double inlier_ratio = 0;         ///< TrackQuality::inlier_ratio.
  double chance_inlier_ratio = 0;  ///< TrackQuality::chance_inlier_ratio.
  /// (inlier_ratio - chance) / (1 - chance): inliers beyond what a random projection gets.
  double above_chance = 0;
  double mean_residual_px = 0;  ///< TrackQuality::mean_residual_px.
  double scale_px = 0;          ///< TrackQuality::scale_px.
  double spread_ratio = 0;      ///< TrackQuality::spread_ratio.
  double visible_ratio = 0;     ///< TrackQuality::visible_ratio.
  int points_in_image = 0;      ///< TrackQuality::points_in_image.
  /// 1-sigma translation of the alignment's covariance over the scene depth (sqrt of the trace
  /// of the translation block / depth; infinite without a covariance or depth).
  double sigma_t_rel = 0;
  double sigma_r_deg = 0;  ///< 1-sigma rotation (sqrt of the trace of the rotation block), degrees.
};

/// The features of an alignment result; scene_depth_m is the keyframe's median depth (metres).
VerificationFeatures verificationFeatures(const TrackResult& result, double scene_depth_m);

/// Constants of the score and its acceptance threshold, chosen from the distributions of
/// `vkloc bench verify` on the development sequences, the simulator's hard scenarios and
/// Castle-simu (README "Pose verification").
struct VerificationOptions {
  double inlier_threshold_px = 1.5;  ///< EdgeTrackerOptions::inlier_threshold_px of the alignment.
  /// Residual term: the inliers' mean residual over the inlier threshold is about 0.5 for chance
  /// matches (residuals spread evenly below the threshold) and 0.1-0.3 at true poses. The term
  /// is 0 at or above residual_zero and 1 at or below residual_zero - residual_ramp.
  double residual_zero = 0.45;
  double residual_ramp = 0.25;
  /// Spread term: min(spread, 1 / spread) of the projected points (TrackQuality::spread_ratio)
  /// below spread_zero gives 0, above spread_zero + spread_ramp 1 (a pose that shrinks the
  /// points onto a few edges).
  double spread_zero = 0.6;
  double spread_ramp = 0.2;
  double min_score = 0.15;  ///< A pose is verified at or above this score.
};

/// Verification score in 0..1 (higher: more likely the true pose): the inliers above chance
/// (max(0, above_chance)) times the residual term times the spread term (VerificationOptions).
double verificationScore(const VerificationFeatures& features, const VerificationOptions& options = {});

}  // namespace vkloc
