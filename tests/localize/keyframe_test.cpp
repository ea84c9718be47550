// Tests of keyframe making and the keyframe worker thread (localize/keyframe.hpp), with the CPU
// reference renderer behind a renderer whose calls the tests can hold, count and fail.
#include "vkloc/localize/keyframe.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "localize/localize_scene.hpp"

namespace vkloc {
namespace {

using namespace std::chrono_literals;

/// A Renderer over CpuRenderer whose renders wait while `held`, count themselves and fail on
/// request. Thread-safe for the tests' purpose.
class GatedRenderer final : public Renderer {
 public:
  struct Control {
    std::mutex mutex;
    std::condition_variable changed;
    bool held = false;
    int started = 0;
    int finished = 0;
    bool fail = false;
    std::vector<int> threads;  ///< RenderSettings::threads of every render, in order.
    void hold(bool h) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        held = h;
      }
      changed.notify_all();
    }
    /// Waits until `n` renders have started (or 5 s).
    bool waitStarted(int n) {
      std::unique_lock<std::mutex> lock(mutex);
      return changed.wait_for(lock, 5s, [&] { return started >= n; });
    }
  };
  explicit GatedRenderer(std::shared_ptr<Control> control)
      : control_(std::move(control)), inner_(std::move(CpuRenderer::create(test::makeBoxOnGround())).value()) {}
  Result<RenderOutput> render(const PinholeCamera& camera, const Pose& T_world_camera,
                              const RenderSettings& settings) override {
    {
      std::unique_lock<std::mutex> lock(control_->mutex);
      ++control_->started;
      control_->threads.push_back(settings.threads);
      control_->changed.notify_all();
      control_->changed.wait(lock, [&] { return !control_->held; });
      if (control_->fail) {
        ++control_->finished;
        return makeError(ErrorCode::kGpuError, "gated renderer: failing on purpose");
      }
    }
    Result<RenderOutput> out = inner_->render(camera, T_world_camera, settings);
    std::lock_guard<std::mutex> lock(control_->mutex);
    ++control_->finished;
    control_->changed.notify_all();
    return out;
  }
  std::string describe() const override { return "gated CPU renderer"; }

 private:
  std::shared_ptr<Control> control_;
  std::unique_ptr<CpuRenderer> inner_;
};

std::unique_ptr<KeyframeMaker> gatedMaker(const std::shared_ptr<GatedRenderer::Control>& control) {
  ReferenceEdgeOptions reference;
  reference.levels = 2;
  return std::make_unique<KeyframeMaker>(std::make_unique<GatedRenderer>(control), test::localizeCamera(),
                                         RenderSettings{}, reference);
}

KeyframeRequest requestAt(int frame) {
  KeyframeRequest r;
  r.T_world_ref = test::localizeTruth(frame);
  r.frame_index = frame;
  r.t_ns = int64_t{frame} * 50'000'000;
  return r;
}

/// Polls takeFinished() until a keyframe comes (or `seconds`).
std::shared_ptr<const Keyframe> waitFinished(KeyframeWorker& worker, int seconds = 10) {
  for (int i = 0; i < 100 * seconds; ++i) {
    Result<std::shared_ptr<const Keyframe>> r = worker.takeFinished();
    EXPECT_TRUE(r.ok());
    if (r.ok() && *r) return *r;
    std::this_thread::sleep_for(10ms);
  }
  return nullptr;
}

TEST(KeyframeMaker, MakesEdgePointsAndLeavesOutDroppedKinds) {
  auto control = std::make_shared<GatedRenderer::Control>();
  auto maker = gatedMaker(control);
  EXPECT_EQ(maker->describe(), "gated CPU renderer");
  auto all = maker->make(requestAt(0));
  ASSERT_TRUE(all.ok()) << all.error().message;
  const Keyframe& k = **all;
  EXPECT_EQ(k.id, 1u);
  EXPECT_GT(k.reference.points.size(), 200u);
  ASSERT_EQ(k.reference.coarse_points.size(), 1u);
  EXPECT_GT(k.scene_depth_m, 1.5);
  EXPECT_LT(k.scene_depth_m, 3.5);
  EXPECT_GT(k.render_ms, 0.0);
  EXPECT_TRUE(k.reference.T_world_ref.isApprox(test::localizeTruth(0)));
  auto count = [](const std::vector<EdgePoint>& points, uint32_t kind) {
    size_t n = 0;
    for (const EdgePoint& p : points) n += (p.kind & ~kEdgeBackground) == kind;
    return n;
  };
  EXPECT_GT(count(k.reference.points, kEdgeOcclusion) + count(k.reference.points, kEdgeCrease), 0u);
  KeyframeRequest drop = requestAt(0);
  drop.dropped_kinds = {true, true, true, true};
  auto textured = maker->make(drop);
  ASSERT_TRUE(textured.ok());
  EXPECT_EQ((*textured)->id, 2u);
  for (const EdgePoint& p : (*textured)->reference.points) EXPECT_EQ(p.kind, kEdgeTexture);
  for (const EdgePoint& p : (*textured)->reference.coarse_points[0]) EXPECT_EQ(p.kind, kEdgeTexture);
  control->fail = true;
  auto failed = maker->make(requestAt(0));
  ASSERT_FALSE(failed.ok());
  EXPECT_EQ(failed.error().code, ErrorCode::kGpuError);
}

TEST(KeyframeMaker, PointsNearABackFaceAreOfThatKindWhateverElseTheyAre) {
  // The box without its top from above: points near the inside seen through the opening (back
  // faces), near the sky around the box (background), and near both at the far rim.
  const Eigen::Vector3d lo(-0.5, -0.375, 0.0), hi(0.625, 0.5, 1.25);
  ReferenceEdgeOptions reference;
  reference.levels = 1;
  KeyframeMaker maker(std::move(CpuRenderer::create(test::makeBox(lo, hi, true))).value(), test::localizeCamera(),
                      RenderSettings{}, reference);
  KeyframeRequest request;
  request.T_world_ref = test::cameraLookingAt({1.3, -1.5, 3.6}, {0.06, 0.06, 0.4});
  auto counts = [&](const EdgeKindMask& drop) {
    request.dropped_kinds = drop;
    auto k = maker.make(request);
    EXPECT_TRUE(k.ok());
    std::array<int, 3> n{};  // near a back face, near background only, neither
    for (const EdgePoint& p : (*k)->reference.points) {
      ++n[(p.kind & kEdgeBackFace) ? 0 : (p.kind & kEdgeBackground) ? 1 : 2];
    }
    return n;
  };
  const std::array<int, 3> all = counts({});
  EXPECT_GT(all[0], 20);
  EXPECT_GT(all[1], 20);
  EXPECT_GT(all[2], 5);
  const std::array<int, 3> no_back_face = counts({false, false, false, true});
  EXPECT_EQ(no_back_face[0], 0);
  EXPECT_EQ(no_back_face[1], all[1]);
  EXPECT_EQ(no_back_face[2], all[2]);
  const std::array<int, 3> no_background = counts({false, false, true, false});
  EXPECT_EQ(no_background[0], all[0]);  // those near both stay with the back faces
  EXPECT_EQ(no_background[1], 0);
  EXPECT_EQ(no_background[2], all[2]);
}

TEST(KeyframeMaker, WaitingCallsUseTheWaitingThreadsAndMakeTheSameKeyframe) {
  auto control = std::make_shared<GatedRenderer::Control>();
  auto maker = gatedMaker(control);
  maker->setWaitingThreads(3, true);
  auto plain = maker->make(requestAt(2));
  auto waiting = maker->make(requestAt(2), true);
  ASSERT_TRUE(plain.ok() && waiting.ok());
  ASSERT_EQ((*plain)->reference.points.size(), (*waiting)->reference.points.size());
  for (size_t i = 0; i < (*plain)->reference.points.size(); ++i) {
    EXPECT_EQ((*plain)->reference.points[i].x, (*waiting)->reference.points[i].x);
    EXPECT_EQ((*plain)->reference.points[i].y, (*waiting)->reference.points[i].y);
    EXPECT_EQ((*plain)->reference.points[i].z, (*waiting)->reference.points[i].z);
  }
  ASSERT_TRUE(maker->renderView(test::localizeCamera(), test::localizeTruth(2), true).ok());
  ASSERT_TRUE(maker->renderView(test::localizeCamera(), test::localizeTruth(2)).ok());
  std::lock_guard<std::mutex> lock(control->mutex);
  EXPECT_EQ(control->threads, (std::vector<int>{1, 3, 3, 1}));
}

TEST(KeyframeWorker, MakesRequestsBesideTheCaller) {
  auto control = std::make_shared<GatedRenderer::Control>();
  KeyframeWorker worker(gatedMaker(control), true);
  EXPECT_FALSE(worker.busy());
  EXPECT_FALSE(*worker.takeFinished());
  worker.request(requestAt(3));
  // The worker runs at the lowest priority (SCHED_IDLE): while other tests keep every core busy
  // (ctest -j under ThreadSanitizer) it gets no time at all, by design; it runs once they finish.
  const auto k = waitFinished(worker, 300);
  ASSERT_TRUE(k);
  EXPECT_EQ(k->request.frame_index, 3);
  EXPECT_FALSE(worker.busy());
  // Taken once only.
  EXPECT_FALSE(*worker.takeFinished());
}

TEST(KeyframeWorker, ANewRequestReplacesTheWaitingOne) {
  auto control = std::make_shared<GatedRenderer::Control>();
  KeyframeWorker worker(gatedMaker(control));
  control->hold(true);
  worker.request(requestAt(1));
  ASSERT_TRUE(control->waitStarted(1));  // request 1 is being made (held in the render)
  EXPECT_TRUE(worker.busy());
  worker.request(requestAt(2));  // waits
  worker.request(requestAt(3));  // replaces 2
  control->hold(false);
  // 1 finishes, then 3 is made; 2 never is. The newest finished one is handed out.
  std::shared_ptr<const Keyframe> last;
  for (int i = 0; i < 4000 && (!last || last->request.frame_index != 3); ++i) {
    auto r = worker.takeFinished();
    ASSERT_TRUE(r.ok());
    if (*r) last = *r;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(last);
  EXPECT_EQ(last->request.frame_index, 3);
  std::lock_guard<std::mutex> lock(control->mutex);
  EXPECT_EQ(control->started, 2);
}

TEST(KeyframeWorker, MakeNowDropsOlderWorkAndRunsOnTheCaller) {
  auto control = std::make_shared<GatedRenderer::Control>();
  auto maker = gatedMaker(control);
  maker->setWaitingThreads(3, false);
  KeyframeWorker worker(std::move(maker), true);
  control->hold(true);
  worker.request(requestAt(1));
  ASSERT_TRUE(control->waitStarted(1));
  worker.request(requestAt(2));
  std::thread release([&] {
    std::this_thread::sleep_for(50ms);
    control->hold(false);
  });
  // Waits for request 1 to let go of the maker, then makes 9 here; 1 and 2 are dropped.
  auto now = worker.makeNow(requestAt(9));
  release.join();
  ASSERT_TRUE(now.ok()) << now.error().message;
  EXPECT_EQ((*now)->request.frame_index, 9);
  // The worker lets go of the dropped request 1 in its own time (a loaded machine, a sanitizer):
  // wait until it is idle, then nothing it made may be handed out.
  for (int i = 0; i < 2000 && worker.busy(); ++i) std::this_thread::sleep_for(5ms);
  EXPECT_FALSE(worker.busy());
  EXPECT_FALSE(*worker.takeFinished());
  std::lock_guard<std::mutex> lock(control->mutex);
  EXPECT_EQ(control->started, 2);  // 1 and 9
  // The worker's own render on its one thread, the caller's (it waits) on the waiting threads.
  EXPECT_EQ(control->threads, (std::vector<int>{1, 3}));
}

TEST(KeyframeWorker, ErrorsReachTheCallerAndDiscardDropsResults) {
  auto control = std::make_shared<GatedRenderer::Control>();
  KeyframeWorker worker(gatedMaker(control));
  control->fail = true;
  worker.request(requestAt(1));
  Result<std::shared_ptr<const Keyframe>> r = std::shared_ptr<const Keyframe>();
  for (int i = 0; i < 4000; ++i) {
    r = worker.takeFinished();
    if (!r.ok() || *r) break;
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("failing on purpose"), std::string::npos);
  control->fail = false;
  worker.request(requestAt(2));
  ASSERT_TRUE(control->waitStarted(2));
  while (worker.busy()) std::this_thread::sleep_for(5ms);
  worker.discard();
  EXPECT_FALSE(*worker.takeFinished());
}

TEST(KeyframeWorker, StopsWithARequestPendingAndOneRunning) {
  auto control = std::make_shared<GatedRenderer::Control>();
  auto worker = std::make_unique<KeyframeWorker>(gatedMaker(control));
  control->hold(true);
  worker->request(requestAt(1));
  ASSERT_TRUE(control->waitStarted(1));
  worker->request(requestAt(2));
  std::thread release([&] {
    std::this_thread::sleep_for(30ms);
    control->hold(false);
  });
  worker.reset();  // joins after the render in progress; request 2 is dropped
  release.join();
  std::lock_guard<std::mutex> lock(control->mutex);
  EXPECT_EQ(control->started, 1);
}

}  // namespace
}  // namespace vkloc
