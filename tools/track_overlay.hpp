// `vkloc track --overlay DIR`: per tracked frame an edge overlay image (eval/overlay.hpp) with a
// caption, and a sidecar CSV of the figures, written beside tracking.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/image.hpp"
#include "vkloc/core/pose.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc::cli {

/// Command-line options of the overlays.
struct OverlayArgs {
  std::string dir;  ///< Folder of the overlay images; "" = no overlays.
  int every = 1;    ///< Every Nth frame (frames 0, N, 2N, ...).
  void add(CLI::App& app);
};

/// Writes overlays while a sequence is tracked: <dir>/frame_NNNNNN.png and <dir>/overlays.csv
/// (frame, t_ns, file, state, tracker and overlay inlier ratios, errors against ground truth).
/// A frame whose overlay cannot be made or written is reported on stderr (one line) and
/// tracking goes on.
class TrackOverlay {
 public:
  /// Null when args.dir is empty. Throws Failure (one line) when the folder or the CSV cannot be
  /// made or an option is out of range. `groundtruth` (T_world_camera, increasing times) may be
  /// empty.
  static std::unique_ptr<TrackOverlay> create(const OverlayArgs& args, const Model& model, const PinholeCamera& camera,
                                              const LocalizerOptions& options, std::vector<StampedPose> groundtruth);
  ~TrackOverlay();
  TrackOverlay(const TrackOverlay&) = delete;
  TrackOverlay& operator=(const TrackOverlay&) = delete;

  /// True when frame `index` gets an overlay.
  bool wanted(size_t index) const { return index % static_cast<size_t>(every_) == 0; }
  /// Makes and writes the overlay of one frame (its gray image and the Localizer's result).
  void write(size_t index, int64_t t_ns, const ImageU8& gray, const LocalizationResult& result);
  /// Completes the CSV; returns a line saying what was written (and how many failed).
  std::string finish();

  struct Impl;

 private:
  TrackOverlay() = default;
  std::unique_ptr<Impl> impl_;
  int every_ = 1;
};

}  // namespace vkloc::cli
