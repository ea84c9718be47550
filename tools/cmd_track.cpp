// vkloc track: localize every image of a sequence in its model, write the trajectory and a
// per-frame log as they are made, then evaluate against the sequence's ground truth.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "common.hpp"
#include "track_overlay.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/eval/eval.hpp"
#include "vkloc/eval/report.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc::cli {
namespace {

struct TrackArgs {
  std::string sequence;
  std::string out = "trajectory.txt";
  std::string frames_csv;
  LocalizerArgs localizer;
  std::string motion = "constant-velocity";
  size_t max_frames = 0;
  size_t start_frame = 0;  ///< First image tracked; > 0 starts at its ground-truth pose, no velocity.
  std::string report_dir;
  std::string init_offset;  ///< "dx,dy,dz,rx,ry,rz": metres (world axes), degrees (camera axes).
  bool calibrate = false;
  bool no_imu = false;
  double visual_delay_ms = 0;  ///< IMU readings fed this far ahead of each frame (a late frame).
  bool quiet = false;
  DeviceArgs device;
  bool no_vulkan = false;
  OverlayArgs overlay;
  CameraArgs camera;         ///< Another calibration than the sequence's camera.yaml.
  ViewArgs view;             ///< The tracker's view of a lens image.
  std::string db;            ///< Keyframe database: relocalization after a loss, global initialization.
  bool global_init = false;  ///< Start with no pose: search the database (around the prior).
  double prior_sigma_m = 0;  ///< > 0: a simulated GPS-like prior from the ground truth with this 1-sigma.
  uint64_t prior_seed = 1;   ///< Seed of the simulated prior's error.
};

std::string seconds(int64_t t_ns) {
  const char* sign = t_ns < 0 ? "-" : "";
  const uint64_t a = t_ns < 0 ? static_cast<uint64_t>(-(t_ns + 1)) + 1 : static_cast<uint64_t>(t_ns);
  return fmt::format("{}{}.{:09d}", sign, a / 1000000000ull, a % 1000000000ull);
}

/// Errors of the filter's IMU-rate output against ground truth (interpolated: cubic Hermite in
/// position with central-difference velocities, slerp in rotation, linear in velocity).
struct FilterErrors {
  std::vector<double> position_m, rotation_deg, velocity_m_s;
  /// The same from kSettleS after the first output on (the start transient left out: an unknown
  /// start velocity takes the first fixes to pin down).
  std::vector<double> settled_position_m, settled_rotation_deg, settled_velocity_m_s;
};

constexpr double kSettleS = 1.0;

FilterErrors filterErrors(const std::vector<FilterOutput>& outputs, const std::vector<StampedPose>& gt) {
  FilterErrors e;
  if (gt.size() < 3) return e;
  std::vector<Eigen::Vector3d> v(gt.size());
  for (size_t k = 0; k < gt.size(); ++k) {
    const size_t a = k == 0 ? 0 : k - 1, b = std::min(k + 1, gt.size() - 1);
    const double dt = static_cast<double>(gt[b].t_ns - gt[a].t_ns) * 1e-9;
    v[k] = (gt[b].T_world_camera.translation() - gt[a].T_world_camera.translation()) / dt;
  }
  size_t k = 0;
  for (const FilterOutput& o : outputs) {
    while (k + 1 < gt.size() && gt[k + 1].t_ns < o.t_ns) ++k;
    if (k + 1 >= gt.size() || o.t_ns < gt[k].t_ns) continue;
    const double h = static_cast<double>(gt[k + 1].t_ns - gt[k].t_ns) * 1e-9;
    const double s = static_cast<double>(o.t_ns - gt[k].t_ns) * 1e-9 / h;
    const Eigen::Vector3d p0 = gt[k].T_world_camera.translation(), p1 = gt[k + 1].T_world_camera.translation();
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
                 h11 = s * s * s - s * s;
    const Eigen::Vector3d p = h00 * p0 + h10 * h * v[k] + h01 * p1 + h11 * h * v[k + 1];
    const Eigen::Quaterniond q = Eigen::Quaterniond(gt[k].T_world_camera.linear())
                                     .slerp(s, Eigen::Quaterniond(gt[k + 1].T_world_camera.linear()));
    const Eigen::Vector3d vel = (1 - s) * v[k] + s * v[k + 1];
    e.position_m.push_back((o.T_world_camera.translation() - p).norm());
    e.rotation_deg.push_back(rotationAngleDeg(q.toRotationMatrix().transpose() * o.T_world_camera.linear()));
    e.velocity_m_s.push_back((o.v_world_body - vel).norm());
    if (static_cast<double>(o.t_ns - outputs.front().t_ns) * 1e-9 >= kSettleS) {
      e.settled_position_m.push_back(e.position_m.back());
      e.settled_rotation_deg.push_back(e.rotation_deg.back());
      e.settled_velocity_m_s.push_back(e.velocity_m_s.back());
    }
  }
  return e;
}

double rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t n = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  return v[n];
}

void run(const TrackArgs& a) {
  const auto t_start = std::chrono::steady_clock::now();
  const Sequence seq = take(loadSequence(a.sequence));
  if (seq.images.empty()) throw Failure{fmt::format("{}: images.txt lists no image", a.sequence)};
  // The lens (the sequence's camera.yaml, or --camera) and the view the tracker works in.
  Sequence lens_seq = seq;
  if (a.camera.given()) lens_seq.camera = a.camera.getFull(seq.camera);
  SequenceView view = sequenceView(lens_seq.camera, a.view.options(seq));
  const PinholeCamera camera = view.camera;
  LocalizerOptions options;
  a.localizer.apply(options);
  options.calibrate_backend = a.calibrate;
  if (a.motion == "last-pose") {
    options.motion = MotionModel::kLastPose;
  } else if (a.motion != "constant-velocity") {
    throw Failure{fmt::format("--motion '{}': expected constant-velocity or last-pose", a.motion)};
  }
  // Inertial aiding from the sequence's IMU readings (body frame) and camera mounting.
  setSequenceInertial(lens_seq, !a.no_imu, options);
  const bool use_imu = options.inertial.enabled;
  if (a.start_frame >= seq.images.size()) {
    throw Failure{fmt::format("--start-frame {}: the sequence has {} images", a.start_frame, seq.images.size())};
  }
  // A global initialization needs no start pose (the search finds it); a sequence without one
  // starts that way when a database is given.
  const bool no_start_pose = !a.global_init && !a.db.empty() && !sequenceStartPose(seq, a.start_frame);
  const bool global_init = a.global_init || no_start_pose;
  if (global_init && !a.init_offset.empty()) {
    throw Failure{no_start_pose ? "--init-offset: the sequence gives no start pose to move (the database is searched)"
                                : "--init-offset moves a start pose; --global-init starts without one"};
  }
  const Pose T_init = global_init ? Pose::Identity() : initialPose(seq, a.init_offset, a.start_frame);
  // The velocity at the start is the sequence's own only when it starts at its first image.
  const std::optional<Eigen::Vector3d> v_init =
      a.start_frame == 0 ? seq.initial_velocity_world : std::optional<Eigen::Vector3d>{};

  const Model model = loadSequenceModel(seq);
  std::shared_ptr<GpuContext> context;
  if (!a.no_vulkan) context = a.device.create();
  std::shared_ptr<Accelerator> accelerator;
  if (context) accelerator = take(makeGpuAccelerator(context));
  auto localizer = take(Localizer::create(model, camera, options, accelerator));
  std::string view_line;
  if (view.front) {
    const CameraFront& f = *view.front;
    std::string stabilised;
    if (f.options().kind == ViewKind::kStabilised) {
      stabilised = fmt::format(", axis {:.0f} deg below the horizon", f.options().pitch_deg);
      if (f.options().dead_band_deg > 0) stabilised += fmt::format(", dead band {:g} deg", f.options().dead_band_deg);
    }
    view_line = fmt::format("camera front: {} {} lens {}x{} -> {} view {}x{}, hfov {:.1f} deg{}", lens_seq.camera.model,
                            f.lens().isIdealPinhole() ? "(ideal)" : "", f.lens().intrinsics.width,
                            f.lens().intrinsics.height, viewKindName(f.options().kind), camera.width, camera.height,
                            2.0 * std::atan(0.5 * camera.width / camera.fx) * 180.0 / M_PI, stabilised);
    if (!a.overlay.dir.empty())
      throw Failure{"--overlay draws on pinhole images; it is not available with a camera front"};
    check(localizer->setCameraFront(std::move(view.front)));
  }
  localizer->reset(T_init, v_init);
  std::string search_line;
  if (!a.db.empty()) {
    auto db = std::make_shared<const KeyframeDatabase>(take(KeyframeDatabase::load(a.db, modelFingerprint(model))));
    check(localizer->setKeyframeDatabase(db));
    search_line = fmt::format("keyframe database: {} keyframes ({})", db->size(), a.db);
  }
  if (global_init) {
    if (a.db.empty()) throw Failure{"--global-init needs --db (vkloc keyframes build)"};
    // The region of a GPS-like prior at the first image (prior.csv, or simulated from the ground
    // truth with --prior-sigma); else the whole database.
    std::optional<SearchRegion> region;
    const int64_t t_first = seq.images[a.start_frame].t_ns;
    if (a.prior_sigma_m > 0) {
      const std::optional<Pose> truth = groundTruthAt(seq.groundtruth, t_first);
      if (!truth) throw Failure{"--prior-sigma: no ground truth at the first image to simulate a prior from"};
      Xoshiro256 rng(a.prior_seed);
      region = priorSearchRegion(
          truth->translation() + a.prior_sigma_m * Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()),
          a.prior_sigma_m, options.relocalization.min_radius_m);
    } else if (!seq.priors.empty()) {
      auto near = std::min_element(seq.priors.begin(), seq.priors.end(), [&](const auto& x, const auto& y) {
        return std::llabs(x.t_ns - t_first) < std::llabs(y.t_ns - t_first);
      });
      region = priorSearchRegion(near->p_world_body, near->sigma.maxCoeff(), options.relocalization.min_radius_m);
    }
    check(localizer->startSearch(region));
    search_line +=
        region ? fmt::format("; global initialization within {:.1f} m of ({:.2f}, {:.2f}, {:.2f})", region->radius_m,
                             region->center_world.x(), region->center_world.y(), region->center_world.z())
               : "; global initialization over the whole database";
    if (no_start_pose) search_line += " (the sequence gives no start pose)";
  }
  const auto overlay = TrackOverlay::create(a.overlay, model, camera, options, seq.groundtruth);
  const double setup_ms = msSince(t_start);

  const size_t first = a.start_frame;
  const size_t left = seq.images.size() - first;
  const size_t total = a.max_frames > 0 ? std::min(a.max_frames, left) : left;
  if (!a.quiet) {
    std::printf("sequence %s: %zu of %zu images, %dx%d; model %zu triangles\n", seq.name.c_str(), total,
                seq.images.size(), camera.width, camera.height, model.triangleCount());
    std::printf("%s\n", localizer->backendSummary().c_str());
    if (!view_line.empty()) std::printf("%s\n", view_line.c_str());
    if (!search_line.empty()) std::printf("%s\n", search_line.c_str());
    std::printf("inertial aiding: %s\n", use_imu ? fmt::format("on ({} IMU readings)", seq.imu.size()).c_str()
                                                 : (seq.imu.empty() ? "off (no imu.csv)" : "off (--no-imu)"));
    std::fflush(stdout);
  }

  const std::filesystem::path out_path(a.out);
  if (out_path.has_parent_path()) std::filesystem::create_directories(out_path.parent_path());
  const std::string frames_path = a.frames_csv.empty()
                                      ? (out_path.parent_path() / (out_path.stem().string() + "_frames.csv")).string()
                                      : a.frames_csv;
  // New output goes to "<file>.partial" until the run is complete: a failed run never
  // truncates the previous trajectory and log, and keeps what it tracked.
  auto traj = take(PartialFileWriter::open(a.out));
  auto frames = take(PartialFileWriter::open(frames_path));
  // The alignments' own poses of the tracked frames, beside the trajectory (which has the
  // filter's estimates where --frame-pose filter and the EKF run).
  const std::string visual_path = (out_path.parent_path() / (out_path.stem().string() + "_visual.txt")).string();
  auto visual = take(PartialFileWriter::open(visual_path));
  check(visual->appendLine(
      "# vkloc track: the alignment's T_world_camera of each tracked frame, TUM format: t tx ty tz qx qy qz qw"));
  check(traj->appendLine(
      "# vkloc track: T_world_camera, TUM format: t tx ty tz qx qy qz qw (lost frames are not listed; inertial-only "
      "ones are)"));
  check(frames->appendLine(
      "t_ns,state,render_ms,reference_ms,live_ms,align_ms,total_ms,inlier_ratio,mean_residual_px,points,iterations,"
      "rerendered,visible_ratio,spread_ratio,chance_inlier_ratio,scale_px,keyframe_id,keyframe_age_frames,"
      "keyframe_adopted,visual_rejected,ekf_nis,inertial_sigma_m,verify_score,search_level,"
      "search_probes,image_shift_px,prior_restarted,relocalization_candidates,search_radius_m,relocalization_ms,"
      "front_ms,view_tilt_deg,image_content,image_contrast,pose_filtered"));
  // The filter's output at the IMU rate (kEkf): camera pose, body velocity, 1-sigma figures.
  const std::string filter_path = (out_path.parent_path() / (out_path.stem().string() + "_filter.csv")).string();
  auto filter_out = take(PartialFileWriter::open(filter_path));
  check(filter_out->appendLine(
      "t_ns,tx,ty,tz,qx,qy,qz,qw,vx,vy,vz,sigma_position_m,sigma_rotation_deg,sigma_velocity_m_s"));
  std::vector<FilterOutput> filter_outputs;
  const bool tty = isatty(fileno(stdout)) != 0 && !a.quiet;
  size_t last_decile = 0;
  std::vector<StampedPose> estimate, visual_estimate;
  size_t filtered = 0;  // tracked frames that report the filter's estimate
  std::vector<double> total_ms, depths;
  size_t lost = 0, inertial = 0, rejected = 0, rerendered = 0, lost_after_first = 0, relocalized = 0, initializing = 0,
         no_content = 0;
  // Readings from one frame interval before the first image tracked on (the filter starts there).
  size_t next_imu = 0;
  if (first > 0) {
    const int64_t t_from = seq.images[first - 1].t_ns;
    while (next_imu < seq.imu.size() && seq.imu[next_imu].t_ns < t_from) ++next_imu;
  }
  long first_tracked = -1;
  double first_frame_ms = 0;
  // Longest run of consecutive frames posed by the IMU alone, and its length in seconds (from
  // its first frame to one frame interval past its last).
  size_t inertial_run = 0, inertial_longest = 0;
  int64_t inertial_run_start_ns = 0;
  double inertial_longest_s = 0.0;
  std::vector<double> intervals_s;
  for (size_t i = first + 1; i < first + total; ++i) {
    intervals_s.push_back(static_cast<double>(seq.images[i].t_ns - seq.images[i - 1].t_ns) * 1e-9);
  }
  const double frame_interval_s = intervals_s.empty() ? 0.0 : median(intervals_s);
  const auto t_frames = std::chrono::steady_clock::now();
  try {
    for (size_t i = first; i < first + total; ++i) {
      const ImageEntry& entry = seq.images[i];
      ImageU8 gray = take(readImageU8(seq.imagePath(i), 1));
      if (use_imu) {
        next_imu =
            feedSequenceImu(seq, next_imu, entry.t_ns + static_cast<int64_t>(a.visual_delay_ms * 1e6), *localizer);
      }
      Result<LocalizationResult> r = localizer->localize(entry.t_ns, gray);
      if (!r.ok()) throw Failure{fmt::format("{}: frame {}: {}", seq.imagePath(i), i, r.error().message)};
      const LocalizationResult& f = *r;
      const bool tracking = f.state == TrackingState::kTracking || f.state == TrackingState::kRelocalized;
      const bool has_pose = tracking || f.state == TrackingState::kInertial;
      relocalized += f.state == TrackingState::kRelocalized;
      initializing += f.state == TrackingState::kInitializing;
      if (tracking && first_tracked < 0) first_tracked = static_cast<long>(i);
      lost_after_first += !has_pose && first_tracked >= 0;
      inertial += f.state == TrackingState::kInertial;
      if (f.state == TrackingState::kInertial) {
        if (inertial_run++ == 0) inertial_run_start_ns = entry.t_ns;
        inertial_longest = std::max(inertial_longest, inertial_run);
        inertial_longest_s = std::max(
            inertial_longest_s, static_cast<double>(entry.t_ns - inertial_run_start_ns) * 1e-9 + frame_interval_s);
      } else {
        inertial_run = 0;
      }
      rejected += f.visual_rejected;
      no_content += f.image_content != ImageContent::kOk;
      if (has_pose) {
        check(traj->appendLine(fmt::format("{} {}", seconds(entry.t_ns), formatPose(f.T_world_camera))));
        estimate.push_back({entry.t_ns, f.T_world_camera});
      } else if (f.state != TrackingState::kInitializing) {  // frames before a first pose are counted apart
        ++lost;
      }
      if (tracking) {
        check(visual->appendLine(fmt::format("{} {}", seconds(entry.t_ns), formatPose(f.T_world_camera_visual))));
        visual_estimate.push_back({entry.t_ns, f.T_world_camera_visual});
        filtered += f.pose_filtered;
      }
      rerendered += f.reference_rendered;
      check(frames->appendLine(fmt::format(
          "{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.4f},{:.4f},{},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{},{},{},{},{:."
          "4g},"
          "{:.4g},{:.4f},{},{},{:.1f},{},{},{:.4g},{:.1f},{:.3f},{:.2f},{},{:.2f},{}",
          entry.t_ns, trackingStateName(f.state), f.render_ms, f.reference_ms, f.live_ms, f.align_ms, f.total_ms,
          f.quality.inlier_ratio, f.quality.mean_residual_px, f.quality.points_used, f.quality.iterations,
          f.reference_rendered ? 1 : 0, f.quality.visible_ratio, f.quality.spread_ratio, f.quality.chance_inlier_ratio,
          f.quality.scale_px, f.keyframe_id, f.keyframe_age_frames, f.keyframe_adopted ? 1 : 0,
          f.visual_rejected ? 1 : 0, f.innovation, f.inertial_sigma_m, f.verify_score, f.search_level,
          f.motion_search_probes, f.image_shift_px, f.prior_restarted ? 1 : 0, f.relocalization_candidates,
          f.search_radius_m, f.relocalization_ms, f.front_ms,
          Eigen::AngleAxisd(f.T_camera_view.linear()).angle() * 180.0 / M_PI, imageContentName(f.image_content),
          f.image_contrast, f.pose_filtered ? 1 : 0)));
      for (const FilterOutput& o : localizer->takeFilterOutputs()) {
        const Eigen::Quaterniond q(o.T_world_camera.linear());
        const Eigen::Vector3d& t = o.T_world_camera.translation();
        check(filter_out->appendLine(
            fmt::format("{},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.6g},{:.6g},{:.6g},{:.4g},{:.4g},{:.4g}",
                        o.t_ns, t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(), o.v_world_body.x(), o.v_world_body.y(),
                        o.v_world_body.z(), std::sqrt(std::max(0.0, o.covariance.topLeftCorner<3, 3>().trace())),
                        std::sqrt(std::max(0.0, o.covariance.bottomRightCorner<3, 3>().trace())) * 180.0 / M_PI,
                        o.sigma_velocity.norm())));
        filter_outputs.push_back(o);
      }
      if (overlay && overlay->wanted(i)) overlay->write(i, entry.t_ns, gray, f);
      if (i == first) {
        first_frame_ms = f.total_ms;
      } else {
        total_ms.push_back(f.total_ms);
      }
      if (f.scene_depth_m > 0) depths.push_back(f.scene_depth_m);
      if (!a.quiet) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_frames).count();
        const double fps = s > 0 ? static_cast<double>(i + 1) / s : 0.0;
        if (tty) {
          std::printf("\rframe %zu/%zu  %.1f fps  lost %zu  inertial %zu  re-rendered %zu", i + 1 - first, total, fps,
                      lost, inertial, rerendered);
          if (i + 1 == first + total) std::printf("\n");
          std::fflush(stdout);
        } else {
          const size_t decile = (i + 1 - first) * 10 / total;
          if (decile > last_decile) {
            last_decile = decile;
            std::printf("frame %zu/%zu, %.1f fps, lost %zu, inertial %zu, re-rendered %zu\n", i + 1 - first, total, fps,
                        lost, inertial, rerendered);
            std::fflush(stdout);
          }
        }
      }
    }
  } catch (const Failure& failure) {
    // Keep what was tracked, say where; the previous files at --out are untouched.
    traj->keep();
    frames->keep();
    filter_out->keep();
    visual->keep();
    throw Failure{fmt::format("{} (the {} frames tracked before are kept in {} and {})", failure.message,
                              frames->lines() - 1, traj->partialPath(), frames->partialPath())};
  }
  check(traj->commit());
  check(frames->commit());
  check(filter_out->commit());
  check(visual->commit());
  if (overlay) {
    const std::string overlay_line = overlay->finish();
    if (!a.quiet) std::printf("%s\n", overlay_line.c_str());
  }
  const double hz = total_ms.empty() ? 0.0 : 1000.0 / median(total_ms);

  // Evaluation against ground truth.
  std::string summary = fmt::format(
      "{{\n  \"sequence\": \"{}\",\n  \"frames\": {},\n  \"lost\": {},\n  \"inertial\": {},\n  \"visual_rejected\": "
      "{},\n"
      "  \"rerendered\": {},\n  \"backend\": \"{}\",\n"
      "  \"policy\": \"{}\",\n  \"startup_ms\": {:.1f},\n  \"first_frame_ms\": {:.1f},\n  \"median_frame_ms\": "
      "{:.3f},\n"
      "  \"hz_median\": {:.3f},\n  \"first_tracked_frame\": {},\n  \"lost_after_first_tracked\": {},\n  "
      "\"scene_depth_median_m\": {:.6g},\n  \"relocalized\": {},\n  \"initializing\": {},\n  "
      "\"no_image_content\": {},\n  \"inertial_longest_frames\": {},\n  \"inertial_longest_s\": {:.3f}",
      seq.name, total, lost, inertial, rejected, rerendered, localizerBackendName(options.backend), a.localizer.policy,
      setup_ms, first_frame_ms, total_ms.empty() ? 0.0 : median(total_ms), hz, first_tracked, lost_after_first,
      median(depths), relocalized, initializing, no_content, inertial_longest, inertial_longest_s);
  std::filesystem::path report_dir = a.report_dir.empty()
                                         ? out_path.parent_path() / (out_path.stem().string() + "_report")
                                         : std::filesystem::path(a.report_dir);
  std::filesystem::create_directories(report_dir);
  if (!seq.groundtruth.empty()) {
    EvalInput input;
    input.estimate = estimate;
    input.groundtruth = seq.groundtruth;
    std::vector<int64_t> times;
    for (size_t i = first; i < first + total; ++i) times.push_back(seq.images[i].t_ns);
    input.frame_times_ns = times;
    input.frame_log = take(loadFrameLog(frames_path));
    const EvalResult result = take(evaluateTrajectory(input));
    ReportInfo info;
    info.estimate_path = a.out;
    info.sequence_path = a.sequence;
    info.frames_path = frames_path;
    const std::string json_path = (report_dir / "report.json").string();
    const std::string html_path = (report_dir / "report.html").string();
    check(writeReportFile(json_path, evalReportJson(result, info)));
    Result<std::string> chartjs = loadChartJs(defaultChartJsPath());
    check(writeReportFile(html_path, evalReportHtml(result, info, chartjs.ok() ? &chartjs.value() : nullptr)));
    summary += fmt::format(
        ",\n  \"translation_median_m\": {:.9g},\n  \"translation_mean_m\": {:.9g},\n  \"translation_max_m\": {:.9g},\n"
        "  \"rotation_median_deg\": {:.9g},\n  \"rotation_mean_deg\": {:.9g},\n  \"rotation_max_deg\": {:.9g},\n"
        "  \"localized_fraction\": {:.6f},\n  \"translation_median_over_depth\": {:.9g}",
        result.translation_m.median, result.translation_m.mean, result.translation_m.max, result.rotation_deg.median,
        result.rotation_deg.mean, result.rotation_deg.max, result.localized_fraction,
        depths.empty() ? 0.0 : result.translation_m.median / median(depths));
    // The alignments' own poses on the tracked frames (the same as above where no frame reports
    // the filter's estimate).
    summary += fmt::format(",\n  \"pose_filtered_frames\": {}", filtered);
    if (!visual_estimate.empty()) {
      EvalInput visual_input;
      visual_input.estimate = visual_estimate;
      visual_input.groundtruth = seq.groundtruth;
      Result<EvalResult> v = evaluateTrajectory(visual_input);
      if (v.ok()) {
        summary += fmt::format(
            ",\n  \"visual_translation_median_m\": {:.9g},\n  \"visual_translation_max_m\": {:.9g},\n"
            "  \"visual_rotation_median_deg\": {:.9g},\n  \"visual_rotation_max_deg\": {:.9g}",
            v->translation_m.median, v->translation_m.max, v->rotation_deg.median, v->rotation_deg.max);
      }
    }
    if (!filter_outputs.empty()) {
      const FilterErrors fe = filterErrors(filter_outputs, seq.groundtruth);
      const double span_s = static_cast<double>(filter_outputs.back().t_ns - filter_outputs.front().t_ns) * 1e-9;
      summary += fmt::format(
          ",\n  \"filter_outputs\": {},\n  \"filter_rate_hz\": {:.1f},\n  \"filter_position_rms_m\": {:.6g},\n"
          "  \"filter_position_median_m\": {:.6g},\n  \"filter_rotation_rms_deg\": {:.6g},\n"
          "  \"filter_velocity_rms_m_s\": {:.6g},\n  \"filter_velocity_median_m_s\": {:.6g}",
          filter_outputs.size(), span_s > 0 ? static_cast<double>(filter_outputs.size() - 1) / span_s : 0.0,
          rms(fe.position_m), median(fe.position_m), rms(fe.rotation_deg), rms(fe.velocity_m_s),
          median(fe.velocity_m_s));
      summary += fmt::format(
          ",\n  \"filter_settled_after_s\": {:.1f},\n  \"filter_settled_position_rms_m\": {:.6g},\n"
          "  \"filter_settled_position_median_m\": {:.6g},\n  \"filter_settled_rotation_rms_deg\": {:.6g},\n"
          "  \"filter_settled_velocity_rms_m_s\": {:.6g},\n  \"filter_settled_velocity_median_m_s\": {:.6g}",
          kSettleS, rms(fe.settled_position_m), median(fe.settled_position_m), rms(fe.settled_rotation_deg),
          rms(fe.settled_velocity_m_s), median(fe.settled_velocity_m_s));
    }
    if (!a.quiet) {
      std::fputs(formatEvalTable(result).c_str(), stdout);
      std::printf("report: %s\n", std::filesystem::absolute(html_path).string().c_str());
    }
  } else if (!a.quiet) {
    std::printf("no ground truth in %s: nothing to evaluate\n", a.sequence.c_str());
  }
  summary += "\n}\n";
  check(writeReportFile((report_dir / "track.json").string(), summary));
  std::printf(
      "tracked %zu frames, %zu lost, %zu inertial only, %zu relocalized, %zu initializing, %zu references rendered: "
      "%.1f Hz (median %.1f ms per frame "
      "after the first); "
      "start-up %.0f ms, first frame %.0f ms (includes shader compilation)\n",
      total, lost, inertial, relocalized, initializing, rerendered, hz, total_ms.empty() ? 0.0 : median(total_ms),
      setup_ms, first_frame_ms);
  if (no_content > 0) {
    std::printf(
        "%zu frames had nothing to align (black, saturated or uniform; frames log column image_content): "
        "not aligned or searched, bridged by the IMU where it runs\n",
        no_content);
  }
  std::printf("wrote %s, %s and %s\n", a.out.c_str(), frames_path.c_str(), visual_path.c_str());
}

void addTrackOptions(CLI::App* cmd, const std::shared_ptr<TrackArgs>& args) {
  cmd->add_option("--sequence,-s", args->sequence, "Sequence folder (sequence.yaml, camera.yaml, images.txt)")
      ->required();
  cmd->add_option("--out,-o", args->out, "Estimated trajectory, TUM format (lost frames left out)")
      ->capture_default_str();
  cmd->add_option("--frames-csv", args->frames_csv,
                  "Per-frame log (t_ns, state, stage *_ms, quality); default <out stem>_frames.csv");
  args->localizer.add(*cmd);
  args->camera.add(*cmd);
  args->view.add(*cmd);
  cmd->add_option("--motion", args->motion, "Pose prediction: constant-velocity | last-pose")->capture_default_str();
  cmd->add_option("--max-frames", args->max_frames, "Track only the first N images (0 = all)")
      ->check(CLI::Range(0, 1000000000))
      ->capture_default_str();
  cmd->add_option("--start-frame", args->start_frame,
                  "Start at this image, at its ground-truth pose with no velocity (0 = the sequence's start)")
      ->capture_default_str();
  cmd->add_option("--report", args->report_dir,
                  "Report folder (report.html, report.json, track.json); default "
                  "<out stem>_report next to --out");
  cmd->add_option("--init-offset", args->init_offset,
                  "Perturb the initial pose: 'dx,dy,dz,rx,ry,rz' (metres on world axes, degrees about camera axes)");
  cmd->add_flag("--calibrate", args->calibrate, "With --backend auto: time CPU and Vulkan on the first frame");
  cmd->add_flag("--no-imu", args->no_imu, "Ignore the sequence's imu.csv (no inertial aiding)");
  cmd->add_option("--visual-delay-ms", args->visual_delay_ms,
                  "Deliver each frame this late: the IMU readings up to the frame's time + this are given first "
                  "(the filter then applies the visual pose as a delayed update; its output lags by as much)")
      ->check(CLI::Range(0.0, 2000.0))
      ->capture_default_str();
  cmd->add_flag("--no-vulkan", args->no_vulkan, "Render with the CPU reference rasterizer (slow)");
  cmd->add_flag("--quiet,-q", args->quiet, "Print only the final line");
  cmd->add_option("--db", args->db,
                  "Keyframe database (vkloc keyframes build): relocalize after a loss, and --global-init");
  cmd->add_flag(
      "--global-init", args->global_init,
      "Start with no pose: search the database around the prior (prior.csv or --prior-sigma), else all of it");
  cmd->add_option("--prior-sigma", args->prior_sigma_m,
                  "With --global-init: a GPS-like prior simulated from the ground truth with this 1-sigma, metres")
      ->check(CLI::Range(0.0, 1e6));
  cmd->add_option("--prior-seed", args->prior_seed, "Seed of the simulated prior's error")->capture_default_str();
  args->device.add(*cmd);
  args->overlay.add(*cmd);
}

}  // namespace

static void addTrackVerb(CLI::App& app) {
  auto args = std::make_shared<TrackArgs>();
  CLI::App* cmd = app.add_subcommand(
      "track", "Localize every image of a sequence in its model; write the trajectory, a frames log and a report");
  addTrackOptions(cmd, args);
  cmd->callback([args] { run(*args); });
}

/// Runs `vkloc track` with the given arguments (without the verb), as other verbs' building
/// block (vkloc demo). Throws Failure like the verb.
void runTrackArguments(const std::vector<std::string>& arguments) {
  CLI::App app{"vkloc track"};
  auto args = std::make_shared<TrackArgs>();
  addTrackOptions(&app, args);
  std::vector<std::string> reversed(arguments.rbegin(), arguments.rend());
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    throw Failure{fmt::format("track: {}", e.what())};
  }
  run(*args);
}

VKLOC_REGISTER_VERB(30, addTrackVerb);

}  // namespace vkloc::cli
