// The Localizer's search depth on a far scene (the demo city seen from a drone): a frame whose
// alignment starts deeper than the tracker's own levels is also aligned from those, and the
// result with more inliers on the finest level is kept.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "localize/localize_scene.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

// Without the IMU the first frame after a start has no motion to extrapolate and starts at
// max_search_level. Here a drone 30 m up, looking 45 deg down through a 90-degree view, flies
// 0.5 m and turns 5 deg between the frames: from level 2 alone the alignment ends 0.81 m and 7 deg
// off, from the usual levels 4 mm off, and the inliers on the finest level tell which is right.
TEST(LocalizerSearch, ADeepStartIsCheckedAgainstTheUsualLevels) {
  const Model city = makeDemoCity();
  const PinholeCamera camera{160.0, 160.0, 159.5, 119.5, 320, 240};
  auto truth = [](int i) {
    const double course = 60.0 * M_PI / 180.0, heading = course + 5.0 * i * M_PI / 180.0;
    const Eigen::Vector3d p(-40.0 + 0.5 * i * std::cos(course), -30.0 + 0.5 * i * std::sin(course), 30.0);
    return test::cameraLookingAt(p, p + 30.0 * Eigen::Vector3d(std::cos(heading), std::sin(heading), -1.0));
  };
  std::vector<ImageU8> images;
  for (int i = 0; i < 2; ++i) {
    auto view = renderReference(city, camera, truth(i));
    ASSERT_TRUE(view.ok()) << view.error().message;
    images.push_back(view->gray);
  }
  for (int deepest : {0, 2}) {
    SCOPED_TRACE(deepest);
    LocalizerOptions options;
    options.keyframe_threading = KeyframeThreading::kSynchronous;
    options.max_search_level = deepest;
    auto created = Localizer::create(city, camera, options, nullptr);
    ASSERT_TRUE(created.ok()) << created.error().message;
    Localizer& localizer = **created;
    localizer.reset(truth(0));
    auto first = localizer.localize(0, images[0]);
    ASSERT_TRUE(first.ok()) << first.error().message;
    EXPECT_EQ(first->state, TrackingState::kTracking);
    auto second = localizer.localize(50'000'000, images[1]);
    ASSERT_TRUE(second.ok()) << second.error().message;
    EXPECT_EQ(second->search_level, deepest);
    EXPECT_EQ(second->state, TrackingState::kTracking);
    EXPECT_LT(test::translationError(second->T_world_camera, truth(1)), 0.1);
    EXPECT_LT(test::rotationErrorDeg(second->T_world_camera, truth(1)), 0.1);
  }
}

}  // namespace
}  // namespace vkloc
