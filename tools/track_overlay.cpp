#include "track_overlay.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <system_error>

#include "common.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/eval/overlay.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc::cli {
namespace {

// Failures reported one by one; after that only counted (and summed up by finish()).
constexpr int kFailuresShown = 3;

std::string ratio(double v) { return fmt::format("{:.3f}", v); }

}  // namespace

void OverlayArgs::add(CLI::App& app) {
  app.add_option(
      "--overlay", dir,
      "Folder for per-frame edge overlays (frame_NNNNNN.png, overlays.csv): model edges at the estimate, "
      "green = within the inlier threshold of a live edge, red = not; cyan = at the ground truth. Each overlay "
      "renders the model on the CPU between frames: wall time grows, and with --keyframes worker the "
      "worker gets more time per frame");
  app.add_option("--overlay-every", every, "With --overlay: every Nth frame")->capture_default_str();
}

struct TrackOverlay::Impl {
  std::string dir;
  PinholeCamera camera;
  EdgeOverlayOptions options;
  std::vector<StampedPose> groundtruth;
  std::unique_ptr<CpuRenderer> renderer;
  std::unique_ptr<PartialFileWriter> csv;
  int64_t t0_ns = 0;
  bool have_t0 = false;
  size_t written = 0;
  size_t failed = 0;

  void fail(size_t index, const std::string& message) {
    ++failed;
    if (failed <= kFailuresShown) {
      std::fprintf(stderr, "vkloc: warning: overlay of frame %zu not written: %s%s\n", index, message.c_str(),
                   failed == kFailuresShown ? " (further overlay failures are only counted)" : "");
    }
  }
};

std::unique_ptr<TrackOverlay> TrackOverlay::create(const OverlayArgs& args, const Model& model,
                                                   const PinholeCamera& camera, const LocalizerOptions& options,
                                                   std::vector<StampedPose> groundtruth) {
  if (args.dir.empty()) return nullptr;
  if (args.every < 1) throw Failure{fmt::format("--overlay-every {}: expected 1 or more", args.every)};
  auto impl = std::make_unique<Impl>();
  impl->dir = args.dir;
  impl->camera = camera;
  impl->options.reference = options.reference;
  impl->options.live = options.live;
  impl->options.render = options.render;
  impl->options.inlier_threshold_px = options.tracker.inlier_threshold_px;
  check(validateEdgeOverlayOptions(impl->options));
  impl->groundtruth = std::move(groundtruth);
  std::error_code ec;
  std::filesystem::create_directories(args.dir, ec);
  if (ec) throw Failure{fmt::format("--overlay {}: cannot create the folder: {}", args.dir, ec.message())};
  impl->renderer = take(CpuRenderer::create(model));
  impl->csv = take(PartialFileWriter::open((std::filesystem::path(args.dir) / "overlays.csv").string()));
  check(impl->csv->appendLine(
      "frame,t_ns,file,state,tracker_inlier_ratio,points_in_image,inliers,inlier_ratio,median_distance_px,"
      "truth_inlier_ratio,translation_error_m,rotation_error_deg"));
  std::unique_ptr<TrackOverlay> overlay(new TrackOverlay());
  overlay->impl_ = std::move(impl);
  overlay->every_ = args.every;
  return overlay;
}

TrackOverlay::~TrackOverlay() {
  if (impl_ && impl_->csv) impl_->csv->keep();
}

void TrackOverlay::write(size_t index, int64_t t_ns, const ImageU8& gray, const LocalizationResult& result) {
  Impl& m = *impl_;
  if (!m.have_t0) {
    m.t0_ns = t_ns;
    m.have_t0 = true;
  }
  if (!isValidPose(result.T_world_camera)) {
    m.fail(index, "the frame has no valid pose");
    return;
  }
  const std::optional<Pose> truth = groundTruthAt(m.groundtruth, t_ns);
  Result<EdgeOverlay> overlay = makeEdgeOverlay(*m.renderer, gray, m.camera, result.T_world_camera, truth, m.options);
  if (!overlay.ok()) {
    m.fail(index, overlay.error().message);
    return;
  }
  const EdgeAgreement& e = overlay->estimate;
  double t_err_m = -1, r_err_deg = -1;
  if (truth) {
    t_err_m = (result.T_world_camera.translation() - truth->translation()).norm();
    r_err_deg = rotationAngleDeg(result.T_world_camera.linear().transpose() * truth->linear());
  }
  std::vector<std::string> caption;
  caption.push_back(fmt::format("frame {}  t {:.3f} s  {}  keyframe {}", index,
                                static_cast<double>(t_ns - m.t0_ns) * 1e-9, trackingStateName(result.state),
                                result.keyframe_id));
  caption.push_back(fmt::format("inliers: tracker {}  here {} of {}", ratio(result.quality.inlier_ratio),
                                ratio(e.inlier_ratio), e.in_image));
  if (truth) {
    caption.push_back(
        fmt::format("error {} {:.2f} deg  inliers at gt {}",
                    t_err_m < 1.0 ? fmt::format("{:.1f} mm", 1000.0 * t_err_m) : fmt::format("{:.3f} m", t_err_m),
                    r_err_deg, ratio(overlay->truth->inlier_ratio)));
  } else {
    caption.push_back("no ground truth");
  }
  drawOverlayCaption(overlay->image, caption);
  const std::string name = fmt::format("frame_{:06d}.png", index);
  const Status written = writePng((std::filesystem::path(m.dir) / name).string(), overlay->image);
  if (!written.ok()) {
    m.fail(index, written.error().message);
    return;
  }
  ++m.written;
  const Status row = m.csv->appendLine(
      fmt::format("{},{},{},{},{:.4f},{},{},{:.4f},{:.3f},{},{},{}", index, t_ns, name, trackingStateName(result.state),
                  result.quality.inlier_ratio, e.in_image, e.inliers, e.inlier_ratio, e.median_distance_px,
                  truth ? fmt::format("{:.4f}", overlay->truth->inlier_ratio) : "",
                  truth ? fmt::format("{:.6f}", t_err_m) : "", truth ? fmt::format("{:.4f}", r_err_deg) : ""));
  if (!row.ok()) m.fail(index, row.error().message);
}

std::string TrackOverlay::finish() {
  Impl& m = *impl_;
  const Status committed = m.csv->commit();
  m.csv.reset();
  std::string line = fmt::format("overlays: {} written to {}", m.written, m.dir);
  if (m.failed > 0) line += fmt::format(", {} failed", m.failed);
  if (!committed.ok()) line += fmt::format("; {}", committed.error().message);
  return line;
}

}  // namespace vkloc::cli
