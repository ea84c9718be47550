// vkloc keyframes: build and inspect the keyframe database of relocalization and global
// initialization (localize/keyframe_database.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "common.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/core/threads.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/keyframe_database.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc::cli {
namespace {

struct BuildArgs {
  std::string sequence;
  ModelArgs model;
  CameraArgs camera;
  std::string out;
  std::string volume;  ///< "x0,y0,z0,x1,y1,z1", metres; default: the ground truth's box + margin.
  double margin_m = 1.0;
  std::string spacing = "auto";  ///< Metres, or "auto" (autoSpacing).
  double corridor_m = 0;         ///< Radius of the corridor around the path, metres; 0: the whole box.
  std::string path;              ///< TUM trajectory: the corridor's path (default: the sequence's ground truth).
  int headings = 12;
  std::string tilts;  ///< Degrees below the horizon, comma-separated; default: the ground truth's.
  double tilt_step_deg = 15.0;
  std::string up;  ///< "x,y,z"; default: against the sequence's gravity, else +z.
  double clearance_m = KeyframePlacement{}.min_clearance_m;
  std::string renderer = "auto";
  int threads = 0;  ///< CPU renderers (0: one per core).
  DeviceArgs device;
  bool quiet = false;
};

/// Tilt of a camera's optical axis below the horizon, degrees.
double tiltBelowHorizonDeg(const Pose& T_world_camera, const Eigen::Vector3d& up) {
  const Eigen::Vector3d z = T_world_camera.linear().col(2);
  return std::asin(std::clamp(-z.dot(up.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

/// Views a build with "--spacing auto" may render at most: a finer spacing is made coarser to fit.
constexpr size_t kAutoMaxViews = 300'000;

/// Views of the placement at its spacing: the box's counted (placementBoxViews), a corridor's
/// positions listed (on a copy whose view limit is lifted) where the box's count is within reach
/// of a listing.
double placementViews(const KeyframePlacement& placement) {
  const double box_views = placementBoxViews(placement);
  if (placement.corridor.empty() || box_views > 1e8) return box_views;
  KeyframePlacement lifted = placement;
  lifted.max_views = std::numeric_limits<size_t>::max();
  return static_cast<double>(take(placementPositions(lifted)).size()) * static_cast<double>(placement.headings) *
         static_cast<double>(placement.tilts_deg.size());
}

/// "--spacing auto": kSpacingDepthFraction x the scene's typical depth (typicalSceneDepth, views
/// nearer a surface than the placement's clearance left out) seen from the sequence's ground
/// truth (at most 48 of its poses, evenly spread), else from the corridor's path (at most 48 of
/// its points) or a coarse grid of the box (5 positions along its longest side), at the
/// placement's tilts and 4 headings; made coarser until the views are at most kAutoMaxViews.
/// Sets placement.spacing_m; returns what the build prints about it.
std::string autoSpacing(Renderer& renderer, const PinholeCamera& camera, const std::optional<Sequence>& seq,
                        KeyframePlacement& placement) {
  std::vector<Pose> views;
  std::string from;
  auto spread = [](size_t n, size_t at_most) {
    std::vector<size_t> picked;
    const size_t m = std::min(n, at_most);
    for (size_t i = 0; i < m; ++i) picked.push_back(i * n / m);
    return picked;
  };
  auto around = [&](const Eigen::Vector3d& position) {
    for (double tilt : placement.tilts_deg) {
      for (int h = 0; h < 4; ++h) views.push_back(placementPose(position, placement.up_world, 90.0 * h, tilt));
    }
  };
  if (seq && !seq->groundtruth.empty()) {
    for (size_t i : spread(seq->groundtruth.size(), 48)) views.push_back(seq->groundtruth[i].T_world_camera);
    from = fmt::format("{} ground-truth views", views.size());
  } else if (!placement.corridor.empty()) {
    const std::vector<size_t> picked = spread(placement.corridor.size(), 48);
    for (size_t i : picked) around(placement.corridor[i]);
    from = fmt::format("{} views along the corridor's path", views.size());
  } else {
    KeyframePlacement coarse = placement;
    double longest = 0;
    for (int k = 0; k < 3; ++k) longest = std::max(longest, double{placement.volume.max[k] - placement.volume.min[k]});
    coarse.spacing_m = std::max(longest / 4.0, 1e-3);
    for (const Eigen::Vector3d& position : take(placementPositions(coarse))) around(position);
    from = fmt::format("{} views of a coarse grid", views.size());
  }
  const double depth_m =
      take(typicalSceneDepth(renderer, camera, views, placement.min_model_fraction, placement.min_clearance_m));
  if (!(depth_m > 0)) {
    throw Failure{
        fmt::format("--spacing auto: none of {} sees the model in free space; give --spacing in metres", from)};
  }
  placement.spacing_m = std::max(kSpacingDepthFraction * depth_m, 1e-3);
  bool widened = false;
  for (int k = 0; k < 60; ++k) {
    const double views_n = placementViews(placement);
    if (views_n <= static_cast<double>(kAutoMaxViews)) break;
    placement.spacing_m *= std::max(1.05, std::cbrt(views_n / static_cast<double>(kAutoMaxViews)));
    widened = true;
  }
  return fmt::format(" (auto: {:g} x the scene's typical depth {:.3g} m, from {}{})", kSpacingDepthFraction, depth_m,
                     from, widened ? fmt::format(", made coarser to keep the views within {}", kAutoMaxViews) : "");
}

void runBuild(const BuildArgs& a) {
  PinholeCamera camera;
  Model model;
  std::optional<Sequence> seq;
  if (!a.sequence.empty()) {
    seq = take(loadSequence(a.sequence));
    camera = sequenceCamera(*seq);
    model = loadSequenceModel(*seq);
  } else {
    camera = a.camera.get();
    model = a.model.load();
  }
  KeyframePlacement placement;
  const bool auto_spacing = a.spacing == "auto";  // chosen once a renderer is made
  if (!auto_spacing) {
    const std::vector<double> v = take(parseNumbers(a.spacing, "--spacing (metres, or auto)", 1));
    if (!(v[0] >= 1e-3 && v[0] <= 1e6))
      throw Failure{fmt::format("--spacing {}: expected 0.001..1e6 m or auto", a.spacing)};
    placement.spacing_m = v[0];
  }
  placement.headings = a.headings;
  placement.min_clearance_m = a.clearance_m;
  if (!a.up.empty()) {
    const std::vector<double> v = take(parseNumbers(a.up, "--up (x,y,z)", 3));
    placement.up_world = Eigen::Vector3d(v[0], v[1], v[2]);
  } else if (seq) {
    placement.up_world = -seq->gravity_world;
  }
  if (!(placement.up_world.norm() > 0)) throw Failure{"--up: need a non-zero vector"};
  placement.up_world.normalize();
  // A corridor: the positions within corridor_m of a path (a flight plan; the sequence's ground
  // truth stands in for one by default).
  if (a.corridor_m > 0) {
    if (!a.path.empty()) {
      for (const StampedPose& p : take(loadTumTrajectory(a.path)))
        placement.corridor.push_back(p.T_world_camera.translation());
    } else if (seq && !seq->groundtruth.empty()) {
      for (const StampedPose& p : seq->groundtruth) placement.corridor.push_back(p.T_world_camera.translation());
    } else {
      throw Failure{"--corridor needs a --path or a --sequence with ground truth"};
    }
    if (placement.corridor.empty()) throw Failure{fmt::format("--path {}: no pose in the file", a.path)};
    placement.corridor_radius_m = a.corridor_m;
  } else if (!a.path.empty()) {
    throw Failure{"--path is the corridor's path: give --corridor RADIUS too"};
  }
  if (!a.volume.empty()) {
    const std::vector<double> v = take(parseNumbers(a.volume, "--volume (x0,y0,z0,x1,y1,z1)", 6));
    for (int k = 0; k < 3; ++k) {
      placement.volume.min[k] = static_cast<float>(std::min(v[k], v[k + 3]));
      placement.volume.max[k] = static_cast<float>(std::max(v[k], v[k + 3]));
    }
  } else if (!placement.corridor.empty()) {
    // The corridor's box: its path's with the radius around it.
    for (const Eigen::Vector3d& c : placement.corridor) {
      const Eigen::Vector3f t = c.cast<float>();
      placement.volume.extend(t.data());
    }
    for (int k = 0; k < 3; ++k) {
      placement.volume.min[k] -= static_cast<float>(a.corridor_m);
      placement.volume.max[k] += static_cast<float>(a.corridor_m);
    }
  } else if (seq && !seq->groundtruth.empty()) {
    // The navigable volume: where the sequence's camera went, with a margin.
    for (const StampedPose& p : seq->groundtruth) {
      const Eigen::Vector3f t = p.T_world_camera.translation().cast<float>();
      placement.volume.extend(t.data());
    }
    for (int k = 0; k < 3; ++k) {
      placement.volume.min[k] -= static_cast<float>(a.margin_m);
      placement.volume.max[k] += static_cast<float>(a.margin_m);
    }
  } else {
    throw Failure{"--volume is needed without a --sequence with ground truth"};
  }
  if (!a.tilts.empty()) {
    placement.tilts_deg = take(parseNumbers(a.tilts, "--tilts (degrees below the horizon)", 0));
  } else if (seq && !seq->groundtruth.empty()) {
    // The tilts the platform uses: those of the ground truth, on a grid of tilt_step_deg.
    std::set<long> steps;
    for (const StampedPose& p : seq->groundtruth) {
      steps.insert(std::lround(tiltBelowHorizonDeg(p.T_world_camera, placement.up_world) / a.tilt_step_deg));
    }
    placement.tilts_deg.clear();
    for (long s : steps) placement.tilts_deg.push_back(static_cast<double>(s) * a.tilt_step_deg);
  }
  // Checked now (with a provisional spacing for "auto"), before any renderer is made.
  if (auto_spacing) placement.spacing_m = 1e6;
  check(validateKeyframePlacement(placement));

  // One Vulkan renderer (the device is parallel itself), or one CPU renderer per core.
  std::vector<std::unique_ptr<Renderer>> renderers;
  std::shared_ptr<GpuContext> context;
  if (a.renderer == "vulkan") {
    context = a.device.create();
    std::shared_ptr<Accelerator> accelerator = take(makeGpuAccelerator(context));
    renderers.push_back(take(accelerator->createRenderer(model)));
  } else if (a.renderer == "auto") {
    try {  // a GPU when there is one; no Vulkan device at all is not an error here
      context = a.device.create();
      std::shared_ptr<Accelerator> accelerator = take(makeGpuAccelerator(context));
      if (!accelerator->isCpuDriver()) renderers.push_back(take(accelerator->createRenderer(model)));
    } catch (const Failure&) {
      context.reset();
    }
  } else if (a.renderer != "cpu") {
    throw Failure{fmt::format("--renderer '{}': expected auto, cpu or vulkan", a.renderer)};
  }
  if (renderers.empty()) {
    const int threads = a.threads > 0 ? a.threads : availableCores();
    for (int t = 0; t < threads; ++t) renderers.push_back(take(CpuRenderer::create(model)));
  }
  std::vector<Renderer*> pointers;
  for (const auto& r : renderers) pointers.push_back(r.get());
  const Renderer* renderer = renderers.front().get();
  std::string spacing_note;
  if (auto_spacing) {
    spacing_note = autoSpacing(*renderers.front(), camera, seq, placement);
    check(validateKeyframePlacement(placement));
  }
  std::string tilts;
  for (double t : placement.tilts_deg) tilts += fmt::format("{}{:g}", tilts.empty() ? "" : ",", t);
  if (!a.quiet) {
    std::printf(
        "volume [%.1f %.1f %.1f] .. [%.1f %.1f %.1f] m%s, spacing %.3g m%s, %d headings, tilts %s deg; %zu x %s\n",
        placement.volume.min[0], placement.volume.min[1], placement.volume.min[2], placement.volume.max[0],
        placement.volume.max[1], placement.volume.max[2],
        placement.corridor.empty()
            ? ""
            : fmt::format(" within {:g} m of a path of {} poses", a.corridor_m, placement.corridor.size()).c_str(),
        placement.spacing_m, spacing_note.c_str(), placement.headings, tilts.c_str(), renderers.size(),
        renderer->describe().c_str());
    std::fflush(stdout);
  }
  const auto t0 = SteadyClock::now();
  double last_print_ms = 0;
  auto progress = [&](size_t done, size_t total) {
    const double ms = msSince(t0);
    if (a.quiet || (ms - last_print_ms < 2000 && done != total)) return;
    last_print_ms = ms;
    const double eta_s = done > 0 ? ms * 1e-3 * static_cast<double>(total - done) / static_cast<double>(done) : 0.0;
    std::fprintf(stderr, "keyframes: %zu/%zu views, %.0f s, %.0f s left\n", done, total, ms * 1e-3, eta_s);
  };
  KeyframeBuildStats stats;
  RenderSettings render;
  const KeyframeDatabase db = take(buildKeyframeDatabase(model, pointers, camera, placement, render, progress, &stats));
  if (db.size() == 0) throw Failure{"no view of the placement lies in free space and sees the model; nothing written"};
  check(db.save(a.out));
  const uint64_t bytes = std::filesystem::file_size(a.out);
  std::printf(
      "keyframes: %zu of %zu views kept (%zu positions; left out: %zu too close, %zu inside geometry, %zu empty) in "
      "%.1f s (%.2f ms per view); %s: %.1f KiB, %.1f bytes per keyframe\n",
      stats.kept, stats.views, stats.positions, stats.too_close, stats.inside, stats.empty, stats.seconds,
      stats.views > 0 ? 1e3 * stats.seconds / static_cast<double>(stats.views) : 0.0, a.out.c_str(),
      static_cast<double>(bytes) / 1024.0, static_cast<double>(bytes) / static_cast<double>(db.size()));
}

struct InfoArgs {
  std::string db;
  std::string sequence;
};

void runInfo(const InfoArgs& a) {
  std::optional<uint64_t> fingerprint;
  if (!a.sequence.empty()) fingerprint = modelFingerprint(loadSequenceModel(take(loadSequence(a.sequence))));
  const KeyframeDatabase db = take(KeyframeDatabase::load(a.db, fingerprint));
  Aabb box;
  for (const DatabaseKeyframe& k : db.keyframes()) {
    const Eigen::Vector3f t = k.T_world_camera.translation().cast<float>();
    box.extend(t.data());
  }
  const PinholeCamera& c = db.camera();
  std::printf("%s: version %u, %zu keyframes, model fingerprint %016llx%s, camera %dx%d fx %.2f fy %.2f\n",
              a.db.c_str(), KeyframeDatabase::kVersion, db.size(),
              static_cast<unsigned long long>(db.modelFingerprint()),
              fingerprint ? " (matches the sequence's model)" : "", c.width, c.height, c.fx, c.fy);
  if (db.size() > 0) {
    std::printf("positions [%.2f %.2f %.2f] .. [%.2f %.2f %.2f] m\n", box.min[0], box.min[1], box.min[2], box.max[0],
                box.max[1], box.max[2]);
  }
}

void addKeyframesVerb(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("keyframes", "Keyframe database for relocalization: build, info");
  cmd->require_subcommand(1);
  {
    auto args = std::make_shared<BuildArgs>();
    CLI::App* build = cmd->add_subcommand(
        "build", "Render virtual cameras on a grid in the model's free space and store one ORB descriptor each");
    build->add_option("--sequence,-s", args->sequence,
                      "Sequence: its model, camera, gravity, and its ground truth's box and tilts as defaults");
    args->model.add(*build);
    args->camera.add(*build);
    build->add_option("--out,-o", args->out, "Database file to write")->required();
    build->add_option("--volume", args->volume, "Box of positions 'x0,y0,z0,x1,y1,z1', metres (world frame)");
    build->add_option("--margin", args->margin_m, "Margin around the ground truth's box, metres")
        ->check(CLI::Range(0.0, 1e5))
        ->capture_default_str();
    build
        ->add_option("--corridor", args->corridor_m,
                     "Only positions within this radius of a path (--path, else the sequence's ground truth), metres")
        ->check(CLI::Range(0.0, 1e5));
    build->add_option("--path", args->path, "The corridor's path: a TUM trajectory (t tx ty tz qx qy qz qw), metres");
    build
        ->add_option("--spacing", args->spacing,
                     fmt::format("Grid spacing, metres, or auto: {:g} x the scene's typical depth seen from the "
                                 "ground truth (without one, from the corridor's path or a coarse grid of the volume), "
                                 "coarser where the views would exceed {}",
                                 kSpacingDepthFraction, kAutoMaxViews))
        ->capture_default_str();
    build->add_option("--headings", args->headings, "Headings per position")
        ->check(CLI::Range(1, 360))
        ->capture_default_str();
    build->add_option("--tilts", args->tilts,
                      "Tilts below the horizon, degrees, e.g. '0,20' (default: the ground truth's)");
    build->add_option("--tilt-step", args->tilt_step_deg, "Grid of the ground truth's tilts, degrees")
        ->check(CLI::Range(1.0, 90.0))
        ->capture_default_str();
    build->add_option("--up", args->up, "Up direction 'x,y,z' (default: against the sequence's gravity, else +z)");
    build->add_option("--clearance", args->clearance_m, "Leave out views with a surface nearer than this, metres")
        ->check(CLI::Range(0.0, 1e6))
        ->capture_default_str();
    build->add_option("--renderer", args->renderer, "auto (Vulkan on a GPU, else CPU) | cpu | vulkan")
        ->capture_default_str();
    build->add_option("--threads", args->threads, "CPU renderers in parallel (0: one per core)")
        ->check(CLI::Range(0, 256))
        ->capture_default_str();
    args->device.add(*build);
    build->add_flag("--quiet,-q", args->quiet, "Print only the final line");
    build->callback([args] {
      if (args->sequence.empty() && args->model.model.empty()) throw Failure{"give --sequence or --model"};
      runBuild(*args);
    });
  }
  {
    auto args = std::make_shared<InfoArgs>();
    CLI::App* info =
        cmd->add_subcommand("info", "Describe a keyframe database (and check it against a sequence's model)");
    info->add_option("database", args->db, "Database file")->required();
    info->add_option("--sequence,-s", args->sequence, "Check that the database was built for this sequence's model");
    info->callback([args] { runInfo(*args); });
  }
}

}  // namespace

VKLOC_REGISTER_VERB(35, addKeyframesVerb);

}  // namespace vkloc::cli
