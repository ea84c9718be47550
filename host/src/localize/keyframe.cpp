#include "vkloc/localize/keyframe.hpp"

#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>

#include "vkloc/core/clock.hpp"

namespace vkloc {
namespace {

/// Median of the positive depths of a render (metres); 0 when nothing is seen.
double medianDepth(const ImageF32& depth) {
  std::vector<float> values;
  values.reserve(depth.data.size() / 4 + 1);
  for (size_t i = 0; i < depth.data.size(); i += 4) {
    if (depth.data[i] > 0.0f) values.push_back(depth.data[i]);
  }
  if (values.empty()) return 0.0;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

KeyframeMaker::KeyframeMaker(std::unique_ptr<Renderer> renderer, const PinholeCamera& camera,
                             const RenderSettings& render, const ReferenceEdgeOptions& reference)
    : renderer_(std::move(renderer)),
      camera_(camera),
      render_(render),
      reference_(reference),
      waiting_render_threads_(render.threads),
      waiting_parallel_reference_(reference.parallel) {
  render_.outputs = kRenderAll;
}

void KeyframeMaker::setWaitingThreads(int render_threads, bool parallel_reference) {
  waiting_render_threads_ = render_threads;
  waiting_parallel_reference_ = parallel_reference;
}

Result<std::shared_ptr<const Keyframe>> KeyframeMaker::make(const KeyframeRequest& request, bool waiting) {
  auto keyframe = std::make_shared<Keyframe>();
  keyframe->request = request;
  RenderSettings render = render_;
  ReferenceEdgeOptions reference_options = reference_;
  if (waiting) {
    render.threads = waiting_render_threads_;
    reference_options.parallel = waiting_parallel_reference_;
  }
  auto t0 = SteadyClock::now();
  Result<RenderOutput> view = renderer_->render(camera_, request.T_world_ref, render);
  if (!view.ok()) return view.error();
  keyframe->render_ms = msSince(t0);
  t0 = SteadyClock::now();
  keyframe->scene_depth_m = medianDepth(view->depth);
  if (request.keep_gray) keyframe->gray = view->gray;
  if (request.keep_depth) keyframe->depth = view->depth;
  // The render's depth and normals are handed to the reference stage (no 5 MB copy unless
  // keep_depth asked for the depth).
  Result<EdgeReference> reference =
      buildEdgeReference(std::move(*view), camera_, request.T_world_ref, reference_options);
  if (!reference.ok()) return reference.error();
  const EdgeKindMask& drop = request.dropped_kinds;
  if (drop[0] || drop[1] || drop[2] || drop[3]) {
    auto dropped = [&](uint32_t kind) {
      const int k = edgeKindIndex(kind);  // texture (0) is always kept
      return k >= 1 && drop[static_cast<size_t>(k - 1)];
    };
    auto keep = [&](std::vector<EdgePoint>& points) {
      points.erase(std::remove_if(points.begin(), points.end(), [&](const EdgePoint& p) { return dropped(p.kind); }),
                   points.end());
    };
    keep(reference->points);
    for (std::vector<EdgePoint>& level : reference->coarse_points) keep(level);
  }
  keyframe->reference = std::move(*reference);
  keyframe->reference_ms = msSince(t0);
  keyframe->id = next_id_++;
  return std::shared_ptr<const Keyframe>(std::move(keyframe));
}

Result<RenderOutput> KeyframeMaker::renderView(const PinholeCamera& camera, const Pose& T_world_camera, bool waiting) {
  RenderSettings settings = render_;
  settings.outputs = kRenderColor | kRenderDepth;
  if (waiting) settings.threads = waiting_render_threads_;
  return renderer_->render(camera, T_world_camera, settings);
}

KeyframeWorker::KeyframeWorker(std::unique_ptr<KeyframeMaker> maker, bool background)
    : maker_(std::move(maker)), description_(maker_->describe()), background_(background) {
  thread_ = std::thread([this] { run(); });
}

KeyframeWorker::~KeyframeWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    pending_.reset();
  }
  wake_.notify_all();
  thread_.join();
}

void KeyframeWorker::run() {
#ifdef __linux__
  if (background_) {
    // Linux schedules threads one by one: SCHED_IDLE on this thread alone lets the tracking
    // thread and the thread pool it uses run first (a wake-up of theirs preempts it at once).
    sched_param param{};
    if (sched_setscheduler(static_cast<pid_t>(gettid()), SCHED_IDLE, &param) == 0) {
      background_applied_ = true;
    } else if (setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 19) == 0) {
      background_applied_ = true;
    }
  }
#endif
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] { return stop_ || pending_.has_value(); });
    if (stop_) return;
    const KeyframeRequest request = *pending_;
    const uint64_t ticket = pending_ticket_;
    pending_.reset();
    running_ticket_ = ticket;
    lock.unlock();
    std::optional<Result<std::shared_ptr<const Keyframe>>> result;
    {
      std::lock_guard<std::mutex> maker_lock(maker_mutex_);
      result = maker_->make(request);
    }
    lock.lock();
    running_ticket_ = 0;
    if (ticket >= discard_below_) finished_result_ = std::move(result);
  }
}

void KeyframeWorker::request(const KeyframeRequest& request) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_ = request;
    pending_ticket_ = next_ticket_++;
  }
  wake_.notify_one();
}

bool KeyframeWorker::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pending_.has_value() || running_ticket_ != 0;
}

Result<std::shared_ptr<const Keyframe>> KeyframeWorker::takeFinished() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!finished_result_) return std::shared_ptr<const Keyframe>();
  Result<std::shared_ptr<const Keyframe>> out = std::move(*finished_result_);
  finished_result_.reset();
  return out;
}

Result<std::shared_ptr<const Keyframe>> KeyframeWorker::makeNow(const KeyframeRequest& request) {
  discard();
  std::lock_guard<std::mutex> maker_lock(maker_mutex_);
  return maker_->make(request, true);
}

Result<RenderOutput> KeyframeWorker::renderNow(const PinholeCamera& camera, const Pose& T_world_camera) {
  discard();
  std::lock_guard<std::mutex> maker_lock(maker_mutex_);
  return maker_->renderView(camera, T_world_camera, true);
}

void KeyframeWorker::discard() {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_.reset();
  discard_below_ = next_ticket_;
  finished_result_.reset();
}

}  // namespace vkloc
