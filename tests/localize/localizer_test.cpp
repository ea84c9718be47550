// Tests of the Localizer without Vulkan (CPU reference renderer, CPU edge backend): the data flow
// in both keyframe modes, determinism of the synchronous mode, waiting only when there is no
// keyframe to track against, and errors.
#include "vkloc/localize/localizer.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <thread>

#include "localize/localize_scene.hpp"

namespace vkloc {
namespace {

constexpr int kFrames = 24;
constexpr int64_t kFrameNs = 50'000'000;

std::unique_ptr<Localizer> makeLocalizer(KeyframeThreading threading) {
  LocalizerOptions options;
  options.keyframe_threading = threading;
  auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
  EXPECT_TRUE(created.ok()) << created.error().message;
  return created.ok() ? std::move(created).value() : nullptr;
}

// The ideal IMU (200 Hz, body = camera) of localizeTruth's camera.
const Eigen::Vector3d kGravityWorld(0, 0, -9.81);
ImuSample circlingImuAt(int64_t t_ns) { return test::localizeImuAt(t_ns, kFrameNs); }

/// Frames first..first+frames-1 of the box scene; with_imu: each after the circling camera's IMU
/// readings from the first frame's time up to its own; pace: wall time between frames, as a
/// camera gives them (0: back to back).
std::vector<LocalizationResult> run(Localizer& localizer, int frames, int first = 0, bool with_imu = false,
                                    std::chrono::milliseconds pace = std::chrono::milliseconds(0)) {
  std::vector<LocalizationResult> out;
  const auto& images = test::localizeFrames(first + frames);
  int64_t t_imu = first * kFrameNs;
  for (int i = first; i < first + frames; ++i) {
    for (; with_imu && t_imu <= i * kFrameNs; t_imu += 5'000'000) {
      EXPECT_TRUE(localizer.addImu(circlingImuAt(t_imu)).ok());
    }
    if (pace.count() > 0 && i > first) std::this_thread::sleep_for(pace);
    auto r = localizer.localize(i * kFrameNs, images[static_cast<size_t>(i)]);
    EXPECT_TRUE(r.ok()) << r.error().message;
    if (!r.ok()) break;
    out.push_back(*r);
  }
  return out;
}

TEST(Localizer, SynchronousModeTracksAndIsDeterministic) {
  std::vector<LocalizationResult> runs[2];
  for (auto& results : runs) {
    auto localizer = makeLocalizer(KeyframeThreading::kSynchronous);
    ASSERT_TRUE(localizer);
    EXPECT_NE(localizer->backendSummary().find("keyframes made synchronously"), std::string::npos);
    localizer->reset(test::localizeTruth(0));
    results = run(*localizer, kFrames);
    ASSERT_EQ(results.size(), static_cast<size_t>(kFrames));
  }
  for (int i = 0; i < kFrames; ++i) {
    const LocalizationResult& r = runs[0][static_cast<size_t>(i)];
    EXPECT_EQ(r.state, TrackingState::kTracking) << i;
    EXPECT_LT(test::translationError(r.T_world_camera, test::localizeTruth(i)), 2e-3) << i;
    EXPECT_LT(test::rotationErrorDeg(r.T_world_camera, test::localizeTruth(i)), 0.1) << i;
    EXPECT_FALSE(r.keyframe_adopted);
    EXPECT_FALSE(r.keyframe_requested);
    // The same input gives the same output, bit for bit.
    EXPECT_TRUE(r.T_world_camera.matrix() == runs[1][static_cast<size_t>(i)].T_world_camera.matrix()) << i;
    EXPECT_EQ(r.keyframe_id, runs[1][static_cast<size_t>(i)].keyframe_id);
  }
  EXPECT_TRUE(runs[0][0].reference_rendered);
  EXPECT_EQ(runs[0][0].keyframe_age_frames, 0);
}

// With the EKF a tracked frame reports the filter's estimate after the update, and the
// alignment's pose beside it; reporting one or the other changes nothing else (synchronous mode:
// the alignments are bit for bit the same).
/// A synchronous Localizer with the EKF on the box scene, its options changed by `edit`.
std::unique_ptr<Localizer> makeEkfLocalizer(const std::function<void(LocalizerOptions&)>& edit) {
  LocalizerOptions options;
  options.keyframe_threading = KeyframeThreading::kSynchronous;
  options.inertial.filter = InertialFilter::kEkf;
  options.inertial.predictor.gravity_world = kGravityWorld;
  edit(options);
  auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
  EXPECT_TRUE(created.ok()) << created.error().message;
  return created.ok() ? std::move(created).value() : nullptr;
}

TEST(Localizer, WithTheEkfATrackedFrameReportsTheFiltersEstimate) {
  std::vector<LocalizationResult> runs[2];
  for (int report = 0; report < 2; ++report) {
    auto localizer = makeEkfLocalizer([&](LocalizerOptions& o) { o.report_filtered_pose = report == 1; });
    ASSERT_TRUE(localizer);
    localizer->reset(test::localizeTruth(0));
    runs[report] = run(*localizer, kFrames, 0, true);
    ASSERT_EQ(runs[report].size(), static_cast<size_t>(kFrames));
  }
  int filtered = 0;
  for (int i = 0; i < kFrames; ++i) {
    const LocalizationResult& visual = runs[0][static_cast<size_t>(i)];
    const LocalizationResult& fused = runs[1][static_cast<size_t>(i)];
    EXPECT_EQ(fused.state, TrackingState::kTracking) << i;
    EXPECT_FALSE(visual.pose_filtered) << i;
    EXPECT_TRUE(visual.T_world_camera.matrix() == visual.T_world_camera_visual.matrix()) << i;
    EXPECT_TRUE(fused.T_world_camera_visual.matrix() == visual.T_world_camera.matrix()) << i;
    filtered += fused.pose_filtered;
    EXPECT_LT(test::translationError(fused.T_world_camera, test::localizeTruth(i)), 2e-3) << i;
    EXPECT_LT(test::rotationErrorDeg(fused.T_world_camera, test::localizeTruth(i)), 0.1) << i;
    if (fused.pose_filtered) {
      EXPECT_GT(fused.covariance(0, 0), 0.0) << i;
      EXPECT_TRUE(fused.covariance.allFinite()) << i;
    } else {
      EXPECT_TRUE(fused.T_world_camera.matrix() == fused.T_world_camera_visual.matrix()) << i;
    }
  }
  // Every frame once the filter runs (the first starts it, after a reading at its time).
  EXPECT_GE(filtered, kFrames - 1);
}

// Each frame the filter predicts from the IMU is aligned with the filter's attitude as a prior
// (rotation_prior_from_filter): the alignments change, and tracking holds as without it. The box
// is seen near and wide, where the edges fix the rotation themselves: the prior changes little
// there (measured: mean rotation error of the alignments 0.0102 deg without it, 0.0109 with it;
// the filter's 0.0080 / 0.0091 deg). Where it pays, a narrow view far off, see
// EdgeTracker.ARotationPriorPinsTheAttitudeAndGivesTheEdgesPoseBack and the README.
TEST(Localizer, TheFiltersAttitudeIsAPriorOfTheAlignment) {
  std::vector<LocalizationResult> runs[2];
  double visual_deg[2] = {0, 0}, fused_deg[2] = {0, 0};
  for (int prior = 0; prior < 2; ++prior) {
    SCOPED_TRACE(prior);
    auto localizer = makeEkfLocalizer([&](LocalizerOptions& o) { o.rotation_prior_from_filter = prior == 1; });
    ASSERT_TRUE(localizer);
    localizer->reset(test::localizeTruth(0));
    runs[prior] = run(*localizer, kFrames, 0, true);
    ASSERT_EQ(runs[prior].size(), static_cast<size_t>(kFrames));
    for (int i = 0; i < kFrames; ++i) {
      const LocalizationResult& r = runs[prior][static_cast<size_t>(i)];
      EXPECT_EQ(r.state, TrackingState::kTracking) << i;
      EXPECT_LT(test::translationError(r.T_world_camera, test::localizeTruth(i)), 2e-3) << i;
      EXPECT_LT(test::rotationErrorDeg(r.T_world_camera, test::localizeTruth(i)), 0.1) << i;
      visual_deg[prior] += test::rotationErrorDeg(r.T_world_camera_visual, test::localizeTruth(i)) / kFrames;
      fused_deg[prior] += test::rotationErrorDeg(r.T_world_camera, test::localizeTruth(i)) / kFrames;
    }
  }
  // The first frame starts the filter (no prediction, the same alignment); the later ones differ.
  EXPECT_TRUE(runs[0][0].T_world_camera_visual.matrix() == runs[1][0].T_world_camera_visual.matrix());
  int changed = 0;
  for (int i = 1; i < kFrames; ++i) {
    changed += !(runs[0][static_cast<size_t>(i)].T_world_camera_visual.matrix() ==
                 runs[1][static_cast<size_t>(i)].T_world_camera_visual.matrix());
  }
  EXPECT_GE(changed, kFrames / 2);
  std::printf("mean rotation error, alignment / filter: without the prior %.4f / %.4f deg, with it %.4f / %.4f deg\n",
              visual_deg[0], fused_deg[0], visual_deg[1], fused_deg[1]);
  EXPECT_LT(fused_deg[1], 1.25 * fused_deg[0] + 0.002);
}

// The restart tests' start: the filter given 1 m/s across the view as its known velocity (it
// predicts 5 cm off a frame, and tightly), 12 frames; the frame of the first restart.
struct WrongVelocityRun {
  std::vector<LocalizationResult> results;
  std::optional<int> restarted_at;
  int refused = 0;
};

// Started at the first frame's true pose moving at speed_m_s along the camera's x axis (the
// camera circles at a few centimetres per second).
WrongVelocityRun runFromAWrongVelocity(const std::function<void(LocalizerOptions&)>& edit, double speed_m_s = 1.0) {
  WrongVelocityRun out;
  auto localizer = makeEkfLocalizer(edit);
  if (!localizer) return out;
  const Pose T0 = test::localizeTruth(0);
  localizer->reset(T0, Eigen::Vector3d(T0.linear() * Eigen::Vector3d(speed_m_s, 0, 0)));
  out.results = run(*localizer, 12, 0, true);
  for (size_t i = 0; i < out.results.size(); ++i) {
    out.refused += out.results[i].visual_rejected;
    if (out.results[i].prior_restarted && !out.restarted_at) out.restarted_at = static_cast<int>(i);
  }
  return out;
}

// Every frame after the restart is tracked within 3 mm of the truth.
void expectTrackedAfterTheRestart(const WrongVelocityRun& r) {
  ASSERT_EQ(r.results.size(), 12u);
  ASSERT_TRUE(r.restarted_at.has_value());
  for (int i = *r.restarted_at + 1; i < 12; ++i) {
    const LocalizationResult& f = r.results[static_cast<size_t>(i)];
    EXPECT_GT(f.inertial_sigma_m, 0.0) << i;  // an inertial prediction
    EXPECT_EQ(f.state, TrackingState::kTracking) << i;
    EXPECT_LT(test::translationError(f.T_world_camera, test::localizeTruth(i)), 3e-3) << i;
  }
}

// A filter started at a wrong velocity refuses the true poses; after restart_after_refusals of
// them, confidently verified, it restarts at the last, and it runs on the IMU from there at once:
// the next frame's prediction is inertial (before, the restart forgot the readings, and the
// frames after it were predicted by constant velocity, lost ones neither bridged nor searched).
// It keeps its velocity with restart_sigma_velocity_m_s as the sigma, so the next frame is
// predicted within a few centimetres; with 0 it restarts at an unknown velocity, at rest with a
// sigma of scene depths per second (a drone so restarted drifts off at its speed).
TEST(Localizer, ARestartedFilterPredictsFromTheImuAtOnceAndKeepsItsVelocityLoosened) {
  double next_sigma_m[2] = {0, 0};
  for (int keep = 0; keep < 2; ++keep) {
    SCOPED_TRACE(keep);
    const WrongVelocityRun r =
        runFromAWrongVelocity([&](LocalizerOptions& o) { o.restart_sigma_velocity_m_s = keep ? 1.0 : 0.0; });
    expectTrackedAfterTheRestart(r);
    ASSERT_TRUE(r.restarted_at.has_value());
    EXPECT_LE(*r.restarted_at, 4);
    next_sigma_m[keep] = r.results[static_cast<size_t>(*r.restarted_at + 1)].inertial_sigma_m;
  }
  // 1 m/s over 50 ms on each axis (sigma_m bounds the three: sqrt(3) x 5 cm), against 2 scene
  // depths per second.
  EXPECT_LT(next_sigma_m[1], 0.1);
  EXPECT_GT(next_sigma_m[0], 2.0 * next_sigma_m[1]) << next_sigma_m[0];
}

// A restart keeps the filter's velocity with restart_sigma_velocity_m_s as its sigma; where that
// velocity is itself wrong (2 m/s with a sigma of 0.2 here) the next true pose is refused too:
// the prior then restarts at that pose at an unknown velocity, and every frame after is tracked.
// (Before, it restarted with the same velocity every other frame, the frames between bridged 8 cm
// off.)
TEST(Localizer, ARestartWhoseVelocityTheNextPoseRefusesRestartsAtAnUnknownVelocity) {
  const WrongVelocityRun r =
      runFromAWrongVelocity([](LocalizerOptions& o) { o.restart_sigma_velocity_m_s = 0.2; }, 2.0);
  ASSERT_EQ(r.results.size(), 12u);
  ASSERT_TRUE(r.restarted_at.has_value());
  const size_t first = static_cast<size_t>(*r.restarted_at);
  ASSERT_LT(first + 2, r.results.size());
  EXPECT_TRUE(r.results[first + 1].prior_restarted);  // refused by the velocity kept: restarted again
  int restarts = 0;
  for (size_t i = first; i < r.results.size(); ++i) {
    const LocalizationResult& f = r.results[i];
    restarts += f.prior_restarted;
    EXPECT_EQ(f.state, TrackingState::kTracking) << i;
    EXPECT_FALSE(f.visual_rejected) << i;
    EXPECT_LT(test::translationError(f.T_world_camera, test::localizeTruth(static_cast<int>(i))), 3e-3) << i;
  }
  EXPECT_EQ(restarts, 2);
}

// The same wrong-velocity start with the score rule off: a filter that refuses every tracked pose
// for restart_after_refused_s restarts at the last one whatever its score, and tracks from there;
// with that rule off too it refuses on, the frames bridged by the IMU alone.
TEST(Localizer, AFilterThatRefusesEveryPoseForLongRestartsWhateverTheScores) {
  for (const double after_s : {0.15, 0.0}) {
    SCOPED_TRACE(after_s);
    const WrongVelocityRun r = runFromAWrongVelocity([&](LocalizerOptions& o) {
      o.restart_after_refusals = 0;
      o.restart_after_refused_s = after_s;
    });
    ASSERT_EQ(r.results.size(), 12u);
    if (after_s > 0) {
      // Refused at 1, 2, 3 (0.1 s after the first refusal) and 4: restarted there.
      expectTrackedAfterTheRestart(r);
      ASSERT_TRUE(r.restarted_at.has_value());
      EXPECT_LE(*r.restarted_at, 5);
      EXPECT_GE(r.refused, 3);
    } else {
      EXPECT_FALSE(r.restarted_at.has_value());
      EXPECT_GE(r.refused, 6);
    }
  }
}

// Started at an unknown velocity, the first frame's plain alignment goes to the motion search
// unless it is verified with motion_search_start_score (that pose sets the velocity); a searched
// pose replaces it only when verified higher. A start score the box's true poses cannot reach
// makes frame 1 search and keep a pose verified at least as well as the plain one; the default
// takes the plain pose without a search.
TEST(Localizer, AnUnknownVelocityStartSearchesUnlessTheFirstPoseIsConfident) {
  double plain_score = 0;
  for (double start_score : {LocalizerOptions{}.motion_search_start_score, 0.999}) {
    SCOPED_TRACE(start_score);
    auto localizer = makeEkfLocalizer([&](LocalizerOptions& o) { o.motion_search_start_score = start_score; });
    ASSERT_TRUE(localizer);
    localizer->reset(test::localizeTruth(0));  // no velocity
    const auto results = run(*localizer, 3, 0, true);
    ASSERT_EQ(results.size(), 3u);
    EXPECT_EQ(results[0].state, TrackingState::kTracking);  // the start pose starts the filter
    // A searched pose within 0.2 % of the ~2.3 m depth (it was aligned against a keyframe rendered
    // at its start, whose edges differ from the plain alignment's by a few pixels' sampling).
    const double tolerance_m = start_score < 0.99 ? 3e-3 : 5e-3;
    for (int i = 1; i < 3; ++i) {
      EXPECT_EQ(results[i].state, TrackingState::kTracking) << i;
      EXPECT_LT(test::translationError(results[i].T_world_camera, test::localizeTruth(i)), tolerance_m) << i;
    }
    if (start_score < 0.99) {
      EXPECT_GE(results[1].verify_score, start_score);
      EXPECT_EQ(results[1].motion_search_probes, 0);
      plain_score = results[1].verify_score;
    } else {
      EXPECT_LT(results[1].verify_score, start_score);
      EXPECT_GT(results[1].motion_search_probes, 0);           // the search ran for a confident pose
      EXPECT_GE(results[1].verify_score, plain_score - 1e-9);  // and kept the best of it and the plain one
      EXPECT_EQ(results[2].motion_search_probes, 0);           // the second pose has pinned the velocity down
    }
  }
}

// The same search when its grid cannot reach as far as the prediction's uncertainty (a stream so
// slow that the camera moves farther between two frames than the grid's steps: here a grid of one
// step each way) has not seen every place the camera may be: a pose it keeps below
// motion_search_start_score waits for the next frame, tracked from it, to confirm it
// (initializing, then relocalized, then tracked). The control: the default grid reaches the
// prediction's 3 sigma at this frame rate and its pose is taken at once; so is, with the short
// grid, a feature start the edges agreed with (point features matched with the frame before do
// not match a look-alike place), the search's first start.
TEST(Localizer, AnUnknownVelocityStartWhoseSearchFellShortWaitsForTheNextFrame) {
  struct Case {
    int steps;
    bool feature_start;
  };
  for (const Case c : {Case{1, false}, Case{LocalizerOptions{}.motion_search_steps, false}, Case{1, true}}) {
    SCOPED_TRACE(::testing::Message() << "steps " << c.steps << " feature start " << c.feature_start);
    const int steps = c.steps;
    auto localizer = makeEkfLocalizer([&](LocalizerOptions& o) {
      o.motion_search_start_score = 0.999;
      o.motion_search_steps = steps;
      o.motion_search_feature_start = c.feature_start;
    });
    ASSERT_TRUE(localizer);
    localizer->reset(test::localizeTruth(0));  // no velocity
    const auto results = run(*localizer, 4, 0, true);
    ASSERT_EQ(results.size(), 4u);
    EXPECT_EQ(results[0].state, TrackingState::kTracking);
    EXPECT_GT(results[1].motion_search_probes, 0);
    EXPECT_LT(results[1].verify_score, 0.999);
    for (int i = 1; i < 4; ++i) {
      EXPECT_LT(test::translationError(results[i].T_world_camera, test::localizeTruth(i)), 5e-3) << i;
    }
    if (c.feature_start) {
      EXPECT_EQ(results[1].motion_search_probes, 1);  // the feature start, agreed with
      EXPECT_EQ(results[1].state, TrackingState::kTracking);
      EXPECT_EQ(results[2].state, TrackingState::kTracking);
    } else if (steps == 1) {
      EXPECT_EQ(results[1].state, TrackingState::kInitializing);
      EXPECT_TRUE(results[1].confirming);
      EXPECT_EQ(results[2].state, TrackingState::kRelocalized);
    } else {
      EXPECT_EQ(results[1].state, TrackingState::kTracking);
      EXPECT_FALSE(results[1].confirming);
      EXPECT_EQ(results[2].state, TrackingState::kTracking);
    }
    EXPECT_EQ(results[3].state, TrackingState::kTracking);
  }
}

TEST(Localizer, AFarFrameAfterAnUnknownVelocityStartIsFoundFromPointFeatures) {
  // A start at frame 0 with no velocity, then frame 40 (the frames between not given, as at a
  // low frame rate; 0.70 m and a turn away): the point features matched with frame 0, lifted by
  // a depth render at its pose, give the search's first start, taken at once. (Without it the
  // image shift's starts and the grid end 0.30 m off here.)
  constexpr int kSkip = 40;
  const auto& images = test::localizeFrames(kSkip + 1);
  auto localizer = makeEkfLocalizer([&](LocalizerOptions& o) { o.motion_search_max_gap_s = 2.5; });
  ASSERT_TRUE(localizer);
  localizer->reset(test::localizeTruth(0));
  std::vector<LocalizationResult> results;
  for (int i : {0, kSkip}) {
    for (int64_t t = (i == 0 ? 0 : kFrameNs); t <= i * kFrameNs; t += 5'000'000) {
      ASSERT_TRUE(localizer->addImu(circlingImuAt(t)).ok());
    }
    auto r = localizer->localize(i * kFrameNs, images[static_cast<size_t>(i)]);
    ASSERT_TRUE(r.ok()) << r.error().message;
    results.push_back(*r);
  }
  ASSERT_GT(test::translationError(test::localizeTruth(0), test::localizeTruth(kSkip)), 0.6);
  EXPECT_EQ(results[1].state, TrackingState::kTracking);
  EXPECT_LT(test::translationError(results[1].T_world_camera, test::localizeTruth(kSkip)), 3e-3);
  EXPECT_EQ(results[1].motion_search_probes, 1);  // the feature start, first of the search
}

TEST(Localizer, InASlowStreamTheFrameBeforeIsRecentToTheMotionSearch) {
  // A stream of one image every kSkip frames (0.95 s, slower than motion_search_max_gap_s) and
  // the defaults: the second frame after a start at an unknown velocity gets the point features
  // matched with the first as its first start, as at any frame rate (before, the frame before
  // was too old for it, and the image shift's starts and the grid ended off).
  constexpr int kSkip = 19;
  const auto& images = test::localizeFrames(2 * kSkip + 1);
  auto localizer = makeEkfLocalizer([](LocalizerOptions&) {});
  ASSERT_TRUE(localizer);
  localizer->reset(test::localizeTruth(0));
  std::vector<LocalizationResult> results;
  int64_t t_imu = 0;
  for (int i : {0, kSkip, 2 * kSkip}) {
    for (; t_imu <= i * kFrameNs; t_imu += 5'000'000) ASSERT_TRUE(localizer->addImu(circlingImuAt(t_imu)).ok());
    auto r = localizer->localize(i * kFrameNs, images[static_cast<size_t>(i)]);
    ASSERT_TRUE(r.ok()) << r.error().message;
    results.push_back(*r);
  }
  EXPECT_EQ(results[1].state, TrackingState::kTracking);
  EXPECT_LT(test::translationError(results[1].T_world_camera, test::localizeTruth(kSkip)), 3e-3);
  EXPECT_EQ(results[1].motion_search_probes, 1);  // the feature start, first of the search
  EXPECT_EQ(results[2].state, TrackingState::kTracking);
  EXPECT_LT(test::translationError(results[2].T_world_camera, test::localizeTruth(2 * kSkip)), 3e-3);
}

TEST(Localizer, MotionSearchFeatureAgreementOutOfRangeIsRefused) {
  for (int k = 0; k < 6; ++k) {
    LocalizerOptions options;
    if (k == 5) options.motion_search_feature_attitude_sigmas = std::numeric_limits<double>::quiet_NaN();
    if (k == 3) options.motion_search_feature_attitude_sigmas = -1.0;
    if (k == 4) options.motion_search_feature_attitude_sigmas = std::numeric_limits<double>::infinity();
    if (k == 0) options.motion_search_feature_min_inliers = 3;
    if (k == 1) options.motion_search_feature_min_inlier_fraction = 1.5;
    if (k == 2) options.motion_search_feature_min_inlier_fraction = std::numeric_limits<double>::quiet_NaN();
    auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
    ASSERT_FALSE(created.ok()) << k;
    EXPECT_NE(created.error().message.find(k < 3 ? "motion_search_feature_min_inlier"
                                                 : "motion_search_feature_attitude_sigmas"),
              std::string::npos);
  }
}

TEST(Localizer, AMotionSearchStartScoreOutsideZeroToOneIsRefused) {
  for (double bad : {-0.1, 1.5, std::numeric_limits<double>::quiet_NaN()}) {
    LocalizerOptions options;
    options.motion_search_start_score = bad;
    auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
    ASSERT_FALSE(created.ok()) << bad;
    EXPECT_NE(created.error().message.find("motion_search_start_score"), std::string::npos);
  }
}

TEST(Localizer, KeyframeRenderThreadsOutsideZeroTo64AreRefused) {
  for (int bad : {-1, 65}) {
    LocalizerOptions options;
    options.keyframe_render_threads = bad;
    auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
    ASSERT_FALSE(created.ok()) << bad;
    EXPECT_NE(created.error().message.find("keyframe_render_threads"), std::string::npos);
  }
}

TEST(Localizer, SynchronousPosesDoNotDependOnTheKeyframeRenderThreads) {
  // The CPU rasterizer's bands give the one-thread render byte for byte, so the synchronous
  // mode's poses are the same bits with any number of render threads.
  std::vector<std::vector<LocalizationResult>> runs;
  for (int threads : {1, 3}) {
    LocalizerOptions options;
    options.keyframe_threading = KeyframeThreading::kSynchronous;
    options.keyframe_render_threads = threads;
    auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
    ASSERT_TRUE(created.ok()) << created.error().message;
    const std::string summary = (*created)->backendSummary();
    EXPECT_NE(summary.find(threads == 1 ? "rasterizer, 1 thread;" : "rasterizer, 3 threads;"), std::string::npos)
        << summary;
    (*created)->reset(test::localizeTruth(0));
    runs.push_back(run(**created, 8));
  }
  ASSERT_EQ(runs[0].size(), runs[1].size());
  for (size_t i = 0; i < runs[0].size(); ++i) {
    EXPECT_EQ(runs[0][i].state, runs[1][i].state) << "frame " << i;
    EXPECT_TRUE(runs[0][i].T_world_camera.matrix() == runs[1][i].T_world_camera.matrix()) << "frame " << i;
  }
}

TEST(Localizer, WorkerModeWaitsOnlyForTheFirstKeyframe) {
  auto localizer = makeLocalizer(KeyframeThreading::kWorkerThread);
  ASSERT_TRUE(localizer);
  EXPECT_NE(localizer->backendSummary().find("keyframes on a worker thread"), std::string::npos);
  localizer->reset(test::localizeTruth(0));
  // At a camera's pace (20 ms apart) the worker has time to finish what it was asked for even
  // when other processes keep both cores busy; back to back, 23 frames of 320x240 can all be
  // tracked before a loaded machine gives the worker a keyframe's worth of time.
  const auto results = run(*localizer, kFrames, 0, false, std::chrono::milliseconds(20));
  ASSERT_EQ(results.size(), static_cast<size_t>(kFrames));
  std::set<uint64_t> keyframes;
  int adopted = 0, requested = 0;
  for (int i = 0; i < kFrames; ++i) {
    const LocalizationResult& r = results[static_cast<size_t>(i)];
    EXPECT_EQ(r.state, TrackingState::kTracking) << i;
    EXPECT_LT(test::translationError(r.T_world_camera, test::localizeTruth(i)), 3e-3) << i;
    EXPECT_LT(test::rotationErrorDeg(r.T_world_camera, test::localizeTruth(i)), 0.15) << i;
    // Only the first frame waits for a keyframe; later ones track against the newest finished.
    EXPECT_EQ(r.reference_rendered, i == 0) << i;
    if (i > 0) {
      EXPECT_EQ(r.render_ms, 0.0) << i;
    }
    keyframes.insert(r.keyframe_id);
    adopted += r.keyframe_adopted;
    requested += r.keyframe_requested;
    if (!r.keyframe_adopted && !r.reference_rendered && i > 0) {
      EXPECT_GE(r.keyframe_age_frames, results[static_cast<size_t>(i) - 1].keyframe_age_frames) << i;
    }
  }
  // The camera turns 0.5 deg a frame: the 3 deg / 10-frame limits ask for new keyframes.
  EXPECT_GE(requested, 1);
  EXPECT_GE(adopted, 1);
  EXPECT_GE(keyframes.size(), 2u);
}

TEST(Localizer, WorkerModeWaitsAfterALossAndAfterReset) {
  auto localizer = makeLocalizer(KeyframeThreading::kWorkerThread);
  ASSERT_TRUE(localizer);
  localizer->reset(test::localizeTruth(0));
  run(*localizer, 6);
  // A black frame: nothing to align (lost, no IMU); the next image waits for a fresh keyframe.
  const ImageU8 black(320, 240, 1, 0);
  auto lost = localizer->localize(6 * kFrameNs, black);
  ASSERT_TRUE(lost.ok());
  EXPECT_EQ(lost->state, TrackingState::kLost);
  const auto after = run(*localizer, 4, 7);
  ASSERT_EQ(after.size(), 4u);
  EXPECT_TRUE(after[0].reference_rendered);
  for (const auto& r : after) EXPECT_EQ(r.state, TrackingState::kTracking);
  // After reset the first frame waits again, and timestamps may start over.
  localizer->reset(test::localizeTruth(12));
  auto again = localizer->localize(0, test::localizeFrames(13)[12]);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->reference_rendered);
  EXPECT_EQ(again->state, TrackingState::kTracking);
}

TEST(Localizer, BadInputIsAnErrorNotACrash) {
  auto localizer = makeLocalizer(KeyframeThreading::kWorkerThread);
  ASSERT_TRUE(localizer);
  const ImageU8& image = test::localizeFrames(1)[0];
  // No pose yet.
  auto none = localizer->localize(0, image);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("reset()"), std::string::npos);
  localizer->reset(test::localizeTruth(0));
  // Wrong size and channels.
  EXPECT_FALSE(localizer->localize(0, ImageU8(321, 240, 1)).ok());
  EXPECT_FALSE(localizer->localize(0, ImageU8(320, 240, 3)).ok());
  // A guess that is not a rigid transform.
  Pose bad = test::localizeTruth(0);
  bad.linear() *= 1.5;
  EXPECT_FALSE(localizer->localize(0, image, bad).ok());
  bad.translation().x() = NAN;
  EXPECT_FALSE(localizer->localize(0, image, bad).ok());
  // Time must increase.
  ASSERT_TRUE(localizer->localize(100, image).ok());
  EXPECT_FALSE(localizer->localize(100, image).ok());
  EXPECT_FALSE(localizer->localize(50, image).ok());
  // Bad IMU readings are refused, tracking goes on.
  ImuSample sample;
  sample.t_ns = 10;
  EXPECT_TRUE(localizer->addImu(sample).ok());
  EXPECT_FALSE(localizer->addImu(sample).ok());
  // Options and devices.
  LocalizerOptions options;
  options.backend = LocalizerBackend::kVulkan;
  auto no_device = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr);
  ASSERT_FALSE(no_device.ok());
  EXPECT_EQ(no_device.error().code, ErrorCode::kNoDevice);
  options = LocalizerOptions{};
  options.max_keyframe_lead_frames = -1;
  EXPECT_FALSE(Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr).ok());
  options = LocalizerOptions{};
  options.init_search_steps = 11;
  EXPECT_FALSE(Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), options, nullptr).ok());
  // Motion search and prior restart out of range.
  auto refused = [](void (*set)(LocalizerOptions&)) {
    LocalizerOptions o;
    set(o);
    auto created = Localizer::create(test::makeBoxOnGround(), test::localizeCamera(), o, nullptr);
    return !created.ok() && created.error().code == ErrorCode::kInvalidArgument;
  };
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.motion_search_steps = -1; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.motion_search_candidates = 0; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.motion_search_max_gap_s = NAN; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.motion_search_min_response = 2.0; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.motion_search_confident_score = 1.5; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_after_refusals = -1; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_min_score = -0.5; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_after_refused_s = -1.0; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_after_refused_s = INFINITY; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_sigma_velocity_m_s = -1.0; }));
  EXPECT_TRUE(refused([](LocalizerOptions& o) { o.restart_sigma_velocity_m_s = NAN; }));
  EXPECT_FALSE(refused([](LocalizerOptions& o) { o.motion_search_steps = 0; }));  // off is valid
  EXPECT_FALSE(Localizer::create(Model{}, test::localizeCamera(), LocalizerOptions{}, nullptr).ok());
  EXPECT_FALSE(parseLocalizerBackend("gpu").ok());
}

}  // namespace
}  // namespace vkloc
