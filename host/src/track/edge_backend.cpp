#include "vkloc/track/edge_backend.hpp"

#include <algorithm>

namespace vkloc {

Result<std::unique_ptr<CpuEdgeTrackingBackend>> CpuEdgeTrackingBackend::create(const PinholeCamera& camera,
                                                                               const LiveFrameOptions& options) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateEdgeDetectorOptions(options.detector));
  LiveFrameOptions live = options;
  live.keep_intermediate = false;  // the tracker reads only the distance fields and edge lines
  live.distance_gradient = false;  // evaluateEdgePoint computes it where it reads it
  return std::unique_ptr<CpuEdgeTrackingBackend>(new CpuEdgeTrackingBackend(camera, live));
}

Result<int> CpuEdgeTrackingBackend::setLiveImage(const ImageU8& gray, int levels) {
  ready_ = false;
  LiveFrameOptions options = options_;
  if (levels > 0) options.levels = std::min(levels, options_.levels);
  // Built into the previous frame's buffers: a fresh LiveFrame per frame costs ~8 MB of new
  // pages at 640x480 (distance, gradient and edge lines of every level).
  VKLOC_TRY_STATUS(buildLiveFrame(gray, camera_, options, live_));
  ready_ = true;
  return static_cast<int>(live_.levels.size());
}

Status CpuEdgeTrackingBackend::setKeyframe(const EdgeReference&) { return Status::success(); }

Result<TrackResult> CpuEdgeTrackingBackend::align(const EdgeReference& points, const Pose& T_world_camera_guess,
                                                  const EdgeTrackerOptions& options) {
  if (!ready_) return makeError(ErrorCode::kInvalidArgument, "CpuEdgeTrackingBackend: align before setLiveImage");
  return trackFrame(points, live_, T_world_camera_guess, options);
}

std::string CpuEdgeTrackingBackend::describe() const { return "CPU"; }

}  // namespace vkloc
