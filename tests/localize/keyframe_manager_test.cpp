// Tests of the keyframe policy and edge-kind learning (localize/keyframe_manager.hpp), with
// keyframes rendered by the CPU reference renderer.
#include "vkloc/localize/keyframe_manager.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "localize/localize_scene.hpp"

namespace vkloc {
namespace {

std::unique_ptr<KeyframeManager> manager(KeyframeManagerOptions options) {
  ReferenceEdgeOptions reference;
  reference.levels = 2;
  auto maker = std::make_unique<KeyframeMaker>(std::move(CpuRenderer::create(test::makeBoxOnGround())).value(),
                                               test::localizeCamera(), RenderSettings{}, reference);
  return std::make_unique<KeyframeManager>(std::move(maker), options);
}

KeyframeManagerOptions synchronous() {
  KeyframeManagerOptions o;
  o.threading = KeyframeThreading::kSynchronous;
  return o;
}

TrackQuality quality(double inliers) {
  TrackQuality q;
  q.inlier_ratio = inliers;
  return q;
}

Status makeAt(KeyframeManager& m, const Pose& T) {
  KeyframeRequest r;
  r.T_world_ref = T;
  double render_ms = 0, reference_ms = 0;
  Status s = m.makeNow(r, render_ms, reference_ms);
  EXPECT_GT(render_ms, 0.0);
  return s;
}

TEST(KeyframeManager, WhenNeededFollowsTheThresholds) {
  auto m = manager(synchronous());
  const Pose T = test::localizeTruth(0);
  EXPECT_TRUE(m->needsKeyframe(T));
  EXPECT_TRUE(m->mustWait());
  ASSERT_TRUE(makeAt(*m, T).ok());
  ASSERT_TRUE(m->current());
  EXPECT_FALSE(m->needsKeyframe(T));
  EXPECT_FALSE(m->mustWait());
  const double depth = m->current()->scene_depth_m;
  const RerenderThresholds& r = m->options().thresholds;
  // Translation: beyond max_translation_depth_ratio x the keyframe's depth.
  Pose moved = T;
  moved.translation() += T.linear() * Eigen::Vector3d(0.9 * r.max_translation_depth_ratio * depth, 0, 0);
  EXPECT_FALSE(m->needsKeyframe(moved));
  moved.translation() =
      T.translation() + T.linear() * Eigen::Vector3d(1.1 * r.max_translation_depth_ratio * depth, 0, 0);
  EXPECT_TRUE(m->needsKeyframe(moved));
  // Rotation beyond max_rotation_deg.
  Pose turned = T;
  turned.linear() = T.linear() * expSO3(Eigen::Vector3d(0, (r.max_rotation_deg + 0.5) * M_PI / 180.0, 0));
  EXPECT_TRUE(m->needsKeyframe(turned));
  // The last frame's inlier ratio.
  m->frameTracked(quality(r.min_inlier_ratio - 0.01));
  EXPECT_TRUE(m->needsKeyframe(T));
  m->frameTracked(quality(0.99));
  EXPECT_FALSE(m->needsKeyframe(T));
  // Frames on the keyframe: max_frames in all.
  for (int i = m->framesOnKeyframe(); i < r.max_frames; ++i) {
    EXPECT_FALSE(m->needsKeyframe(T)) << i;
    m->frameTracked(quality(0.99));
  }
  EXPECT_TRUE(m->needsKeyframe(T));
  // A frame that was not tracked: a new keyframe, and the worker mode would wait for it.
  ASSERT_TRUE(makeAt(*m, T).ok());
  EXPECT_EQ(m->framesOnKeyframe(), 0);
  m->frameNotTracked();
  EXPECT_TRUE(m->needsKeyframe(T));
  EXPECT_TRUE(m->mustWait());
  m->reset();
  EXPECT_FALSE(m->current());
  EXPECT_TRUE(m->needsKeyframe(T));
}

TEST(KeyframeManager, EveryFramePolicyAlwaysAsks) {
  KeyframeManagerOptions o = synchronous();
  o.policy = RerenderPolicy::kEveryFrame;
  auto m = manager(o);
  ASSERT_TRUE(makeAt(*m, test::localizeTruth(0)).ok());
  m->frameTracked(quality(1.0));
  EXPECT_TRUE(m->needsKeyframe(test::localizeTruth(0)));
  EXPECT_FALSE(m->request(KeyframeRequest{}));  // synchronous: nothing to ask a worker for
}

TEST(KeyframeManager, EdgeKindsTheImagesDoNotShowAreLeftOut) {
  auto m = manager(synchronous());
  TrackQuality q = quality(0.9);
  q.kind_points_in_image = {500, 100, 100, 100, 100};
  // Occlusion and near-background edges are not seen; creases and edges near back faces are.
  q.kind_inlier_ratio = {0.9, 0.2, 0.85, 0.1, 0.85};
  for (int i = 0; i < 3; ++i) m->frameTracked(q);
  const EdgeKindMask dropped = m->droppedKinds();
  EXPECT_EQ(dropped, (EdgeKindMask{true, false, true, false}));
  // New keyframes leave them out; a reset keeps what was learnt.
  m->reset();
  ASSERT_TRUE(makeAt(*m, test::localizeTruth(0)).ok());
  EXPECT_EQ(m->current()->request.dropped_kinds, dropped);
  for (const EdgePoint& p : m->current()->reference.points) {
    EXPECT_NE(p.kind, kEdgeOcclusion);
    // A point near a back face is of that kind (kept) whatever else it is.
    if (!(p.kind & kEdgeBackFace)) {
      EXPECT_EQ(p.kind & kEdgeBackground, 0u);
    }
  }
  // Each kind is learnt on its own: only the edges near back faces unseen.
  auto m3 = manager(synchronous());
  q.kind_inlier_ratio = {0.9, 0.85, 0.85, 0.85, 0.2};
  for (int i = 0; i < 3; ++i) m3->frameTracked(q);
  EXPECT_EQ(m3->droppedKinds(), (EdgeKindMask{false, false, false, true}));
  // Too few points of a kind teach nothing; learning can be turned off.
  KeyframeManagerOptions off = synchronous();
  off.adapt_edge_kinds = false;
  auto m2 = manager(off);
  for (int i = 0; i < 3; ++i) m2->frameTracked(q);
  EXPECT_EQ(m2->droppedKinds(), (EdgeKindMask{false, false, false, false}));
}

TEST(KeyframeManager, WorkerModeAdoptsRequestedKeyframes) {
  auto m = manager(KeyframeManagerOptions{});
  ASSERT_TRUE(makeAt(*m, test::localizeTruth(0)).ok());
  const uint64_t first = m->current()->id;
  KeyframeRequest r;
  r.T_world_ref = test::localizeTruth(5);
  r.frame_index = 5;
  EXPECT_TRUE(m->request(r));
  bool adopted = false;
  for (int i = 0; i < 1000 && !adopted; ++i) {
    auto a = m->adoptFinished();
    ASSERT_TRUE(a.ok());
    adopted = *a;
    if (!adopted) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(adopted);
  EXPECT_GT(m->current()->id, first);
  EXPECT_EQ(m->current()->request.frame_index, 5);
  EXPECT_EQ(m->framesOnKeyframe(), 0);
}

TEST(KeyframeThreading, ParsesItsNames) {
  EXPECT_EQ(*parseKeyframeThreading("worker"), KeyframeThreading::kWorkerThread);
  EXPECT_EQ(*parseKeyframeThreading("sync"), KeyframeThreading::kSynchronous);
  EXPECT_FALSE(parseKeyframeThreading("async").ok());
  EXPECT_STREQ(keyframeThreadingName(KeyframeThreading::kSynchronous), "sync");
  EXPECT_FALSE(parseRerenderPolicy("sometimes").ok());
}

}  // namespace
}  // namespace vkloc
