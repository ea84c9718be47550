// vkloc: keyframes (STAR, seed paper 001 sec. II-B): a model render at a chosen pose reduced to
// the 3D edge points the tracker aligns (track/reference_edges.hpp), made by a KeyframeMaker on
// the caller's thread or by a KeyframeWorker on a thread of its own, in parallel with tracking
// (STAR's two processes, eqs. 1-2).
#pragma once

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc {

/// Which edge kinds a keyframe leaves out: [occlusion, crease, near background, near a back
/// face] (texture edges are always kept; a point near a back face is of that kind whatever else
/// it is). See KeyframeManager's edge-kind learning.
using EdgeKindMask = std::array<bool, 4>;

/// What to make a keyframe of.
struct KeyframeRequest {
  Pose T_world_ref = Pose::Identity();  ///< Pose of the keyframe (virtual) camera.
  int64_t t_ns = 0;                     ///< Frame time this pose was predicted for, nanoseconds.
  int64_t frame_index = 0;              ///< Index of that frame (the Localizer's count; may lie ahead).
  EdgeKindMask dropped_kinds{};         ///< Edge kinds left out.
  bool keep_gray = false;               ///< Keep the render's gray image in Keyframe::gray.
  bool keep_depth = false;              ///< Keep the render's depth in Keyframe::depth.
};

/// A finished keyframe. Immutable once made; shared between the worker and the tracker.
struct Keyframe {
  uint64_t id = 0;           ///< 1, 2, ... in the order made.
  KeyframeRequest request;   ///< What it was made of.
  EdgeReference reference;   ///< Edge points per pyramid level, keyframe camera frame (T_world_ref).
  double scene_depth_m = 0;  ///< Median depth of the render's surfaces, metres (0: nothing seen).
  ImageU8 gray;              ///< The render's gray image when request.keep_gray (else empty).
  ImageF32 depth;            ///< The render's depth (camera z, metres) when request.keep_depth.
  double render_ms = 0;      ///< Wall time of the render, ms.
  double reference_ms = 0;   ///< Wall time of the edge-point extraction, ms.
};

/// Renders keyframes and extracts their edge points. Not thread-safe (one thread at a time).
class KeyframeMaker {
 public:
  /// Takes the renderer over. `reference` levels are those of the live frame.
  KeyframeMaker(std::unique_ptr<Renderer> renderer, const PinholeCamera& camera, const RenderSettings& render,
                const ReferenceEdgeOptions& reference);
  /// The render threads and edge-point parallelism of the calls made while the caller waits
  /// (`waiting` below: a keyframe worker's makeNow and renderNow, when nothing else runs); by
  /// default those of the constructor.
  void setWaitingThreads(int render_threads, bool parallel_reference);
  /// Renders colour, depth and normals at request.T_world_ref and builds the edge reference
  /// without the dropped kinds, with the waiting threads when `waiting`. Renderer and
  /// extraction errors are returned as they are.
  Result<std::shared_ptr<const Keyframe>> make(const KeyframeRequest& request, bool waiting = false);
  /// The renderer's describe().
  std::string describe() const { return renderer_->describe(); }
  /// A plain render (colour and depth) at any camera and pose, e.g. a small view to compare with
  /// the live image, with the waiting threads when `waiting`. Renderer errors as they are.
  Result<RenderOutput> renderView(const PinholeCamera& camera, const Pose& T_world_camera, bool waiting = false);

 private:
  std::unique_ptr<Renderer> renderer_;
  PinholeCamera camera_;
  RenderSettings render_;
  ReferenceEdgeOptions reference_;
  int waiting_render_threads_;
  bool waiting_parallel_reference_;
  uint64_t next_id_ = 1;
};

/// A KeyframeMaker on a thread of its own. The tracking thread requests keyframes and picks up
/// finished ones without waiting; only makeNow() waits. At most one keyframe is being made and
/// one request waits; a new request replaces the waiting one. The worker thread runs at the
/// lowest scheduling priority when asked (Linux SCHED_IDLE: it takes only CPU time the rest of
/// the process leaves), while makeNow() makes its keyframe on the calling thread, so a caller
/// that must wait is not slowed by that priority. Thread-safety: all members may be called from
/// any thread (typically the one tracking thread); the maker is used by one thread at a time.
class KeyframeWorker {
 public:
  /// `background`: run the worker thread at the lowest priority (see above).
  explicit KeyframeWorker(std::unique_ptr<KeyframeMaker> maker, bool background = false);
  /// Stops the thread after the keyframe in progress (a waiting request is dropped).
  ~KeyframeWorker();
  KeyframeWorker(const KeyframeWorker&) = delete;
  KeyframeWorker& operator=(const KeyframeWorker&) = delete;

  /// Queues a request (replacing one that has not started). Returns at once.
  void request(const KeyframeRequest& request);
  /// True while a request waits or a keyframe is being made.
  bool busy() const;
  /// The newest keyframe finished since the last call (older unclaimed ones are dropped), null
  /// when none; the error of a failed request.
  Result<std::shared_ptr<const Keyframe>> takeFinished();
  /// Drops the waiting request, the keyframe in progress and unclaimed results, then makes
  /// `request` on the calling thread (after the keyframe in progress is done with the maker).
  Result<std::shared_ptr<const Keyframe>> makeNow(const KeyframeRequest& request);
  /// KeyframeMaker::renderView on the calling thread (after the keyframe in progress is done with
  /// the maker); drops the waiting request as makeNow does.
  Result<RenderOutput> renderNow(const PinholeCamera& camera, const Pose& T_world_camera);
  /// Drops the waiting request and unclaimed results (reset, loss).
  void discard();
  std::string describe() const { return description_; }
  /// True when the worker thread runs at the lowest priority (asked for, and the system allowed it).
  bool background() const { return background_applied_; }

 private:
  void run();
  std::unique_ptr<KeyframeMaker> maker_;
  std::string description_;
  std::mutex maker_mutex_;  ///< Held while the maker makes a keyframe.
  mutable std::mutex mutex_;
  std::condition_variable wake_;  ///< The worker waits on it for requests.
  std::optional<KeyframeRequest> pending_;
  uint64_t pending_ticket_ = 0;  ///< Ticket of pending_.
  uint64_t next_ticket_ = 1;
  uint64_t running_ticket_ = 0;  ///< Ticket being made (0: idle).
  uint64_t discard_below_ = 0;   ///< Results of tickets below this are dropped.
  std::optional<Result<std::shared_ptr<const Keyframe>>> finished_result_;  ///< Unclaimed, for takeFinished.
  bool stop_ = false;
  bool background_ = false;
  std::atomic<bool> background_applied_{false};
  std::thread thread_;
};

}  // namespace vkloc
