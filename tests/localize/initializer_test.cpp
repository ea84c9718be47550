// Tests of the start-up refinements (localize/initializer.hpp) with scripted tracking steps.
#include "vkloc/localize/initializer.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "vkloc/core/se3.hpp"

namespace vkloc {
namespace {

TrackResult result(TrackingState state, double inliers, const Pose& T = Pose::Identity()) {
  TrackResult r;
  r.state = state;
  r.quality.inlier_ratio = inliers;
  r.T_world_camera = T;
  return r;
}

TEST(Initializer, AConfidentFirstAlignmentIsKept) {
  Initializer init(InitializerOptions{});
  int aligns = 0, rekeys = 0;
  InitializerSteps steps;
  steps.align = [&](const Pose&) -> Result<TrackResult> {
    ++aligns;
    return result(TrackingState::kLost, 0);
  };
  steps.rekey = [&](const Pose&) {
    ++rekeys;
    return Status::success();
  };
  auto r = init.refine(Pose::Identity(), result(TrackingState::kTracking, 0.9), steps);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kTracking);
  EXPECT_EQ(aligns, 0);
  EXPECT_EQ(rekeys, 0);
}

TEST(Initializer, SearchesTheRotationGridAndKeepsTheBest) {
  InitializerOptions o;
  o.search_steps = 1;
  o.search_deg = 4.0;
  Initializer init(o);
  std::vector<Eigen::Vector3d> starts;
  InitializerSteps steps;
  steps.align = [&](const Pose& start) -> Result<TrackResult> {
    const Eigen::Vector3d phi = logSO3(start.linear());
    starts.push_back(phi);
    // The start turned +4 deg about x and -4 deg about y tracks best.
    const bool best = phi.x() > 0.06 && phi.y() < -0.06;
    return result(best ? TrackingState::kTracking : TrackingState::kLost, best ? 0.8 : 0.3, start);
  };
  steps.rekey = [&](const Pose&) { return Status::success(); };
  auto r = init.refine(Pose::Identity(), result(TrackingState::kTracking, 0.5), steps);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(starts.size(), 8u);  // the 3 x 3 grid without its centre
  EXPECT_EQ(r->state, TrackingState::kTracking);
  EXPECT_NEAR(r->quality.inlier_ratio, 0.8, 1e-12);
  EXPECT_NEAR(logSO3(r->T_world_camera.linear()).x(), 4.0 * M_PI / 180.0, 1e-9);
}

// A grid start replaces the first alignment in the same state only by min_inlier_gain: a first
// alignment from the start pose at 0.548 was replaced by a grid start 2.29 m off at 0.554 (the
// fisheye's crop over the hard city), and every frame after was lost.
TEST(Initializer, AGridStartReplacesTheFirstAlignmentOnlyByAMargin) {
  for (const double grid_inliers : {0.554, 0.62}) {
    SCOPED_TRACE(grid_inliers);
    Initializer init(InitializerOptions{});
    InitializerSteps steps;
    steps.align = [&](const Pose& start) -> Result<TrackResult> {
      Pose far = start;
      far.translation().x() = 2.29;
      return result(TrackingState::kTracking, grid_inliers, far);
    };
    steps.rekey = [&](const Pose&) { return Status::success(); };
    auto r = init.refine(Pose::Identity(), result(TrackingState::kTracking, 0.548), steps);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->state, TrackingState::kTracking);
    if (grid_inliers < 0.548 + InitializerOptions{}.min_inlier_gain) {
      EXPECT_NEAR(r->quality.inlier_ratio, 0.548, 1e-12);
      EXPECT_EQ(r->T_world_camera.translation().x(), 0.0);
    } else {
      EXPECT_NEAR(r->quality.inlier_ratio, grid_inliers, 1e-12);
    }
  }
  // A lost first alignment gives way to any tracking start.
  Initializer init(InitializerOptions{});
  InitializerSteps steps;
  steps.align = [&](const Pose&) -> Result<TrackResult> { return result(TrackingState::kTracking, 0.3); };
  steps.rekey = [&](const Pose&) { return Status::success(); };
  auto r = init.refine(Pose::Identity(), result(TrackingState::kLost, 0.5), steps);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kTracking);
}

TEST(Initializer, RefinesFromFreshKeyframesWhileLost) {
  InitializerOptions o;
  o.search_steps = 0;
  o.refinements = 4;
  Initializer init(o);
  int aligns = 0;
  std::vector<double> rekeyed;
  InitializerSteps steps;
  steps.align = [&](const Pose& start) -> Result<TrackResult> {
    ++aligns;
    Pose next = start;
    next.translation().x() += 1.0;  // each alignment converges one step further
    return result(aligns >= 3 ? TrackingState::kTracking : TrackingState::kLost, 0.6, next);
  };
  steps.rekey = [&](const Pose& at) {
    rekeyed.push_back(at.translation().x());
    return Status::success();
  };
  Pose first = Pose::Identity();
  first.translation().x() = 1.0;
  auto r = init.refine(Pose::Identity(), result(TrackingState::kLost, 0.1, first), steps);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->state, TrackingState::kTracking);
  EXPECT_EQ(rekeyed, (std::vector<double>{1.0, 2.0, 3.0}));  // keyframes at each estimate
  EXPECT_EQ(aligns, 3);
}

TEST(Initializer, StepErrorsAreReturned) {
  Initializer init(InitializerOptions{});
  InitializerSteps steps;
  steps.align = [&](const Pose&) -> Result<TrackResult> { return makeError(ErrorCode::kGpuError, "device lost"); };
  steps.rekey = [&](const Pose&) { return Status::success(); };
  auto r = init.refine(Pose::Identity(), result(TrackingState::kLost, 0.0), steps);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kGpuError);
  InitializerOptions bad;
  bad.search_steps = 11;
  EXPECT_FALSE(validateInitializerOptions(bad).ok());
  bad = InitializerOptions{};
  bad.refinements = -1;
  EXPECT_FALSE(validateInitializerOptions(bad).ok());
}

}  // namespace
}  // namespace vkloc
