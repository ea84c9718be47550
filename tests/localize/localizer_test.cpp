// Tests of the Localizer without Vulkan (CPU reference renderer, CPU edge backend): the data flow
// in both keyframe modes, determinism of the synchronous mode, waiting only when there is no
// keyframe to track against, and errors.
#include "vkloc/localize/localizer.hpp"

#include <gtest/gtest.h>

#include <set>

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

std::vector<LocalizationResult> run(Localizer& localizer, int frames, int first = 0) {
  std::vector<LocalizationResult> out;
  const auto& images = test::localizeFrames(first + frames);
  for (int i = first; i < first + frames; ++i) {
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

TEST(Localizer, WorkerModeWaitsOnlyForTheFirstKeyframe) {
  auto localizer = makeLocalizer(KeyframeThreading::kWorkerThread);
  ASSERT_TRUE(localizer);
  EXPECT_NE(localizer->backendSummary().find("keyframes on a worker thread"), std::string::npos);
  localizer->reset(test::localizeTruth(0));
  const auto results = run(*localizer, kFrames);
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
  EXPECT_FALSE(refused([](LocalizerOptions& o) { o.motion_search_steps = 0; }));  // off is valid
  EXPECT_FALSE(Localizer::create(Model{}, test::localizeCamera(), LocalizerOptions{}, nullptr).ok());
  EXPECT_FALSE(parseLocalizerBackend("gpu").ok());
}

}  // namespace
}  // namespace vkloc
