// vkloc bench reloc: relocalization on STAR's protocol (seed 001 sec. III-E): query frames spread
// over a sequence with ground truth, each searched in the keyframe database within a window
// around its true position. Reports retrieval (the top keyframe's distance to the query), recovery
// (a pose relocalized, verified and within the error goal; wrong poses accepted are counted
// apart), and the query and recovery times. Optionally forced-loss trials: tracking with the IMU,
// the images blacked out for a while or the camera made to jump, and the frames it takes to
// relocalize after the first usable image; or global-initialization trials (seed 000 sec. V-A):
// no pose at a seeded frame, a GPS-like prior drawn around the truth, and the frames and time to
// the first verified pose.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "common.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/keyframe_database.hpp"
#include "vkloc/localize/localizer.hpp"

namespace vkloc::cli {
namespace {

struct RelocBenchArgs {
  std::string sequence;
  std::string db;
  int queries = 100;
  double window_m = 2.0;        ///< Search window around the query's true position (STAR: 2 m).
  double goal_fraction = 0.02;  ///< Recovered: translation error <= this x scene depth ...
  double goal_deg = 2.0;        ///< ... and rotation error <= this.
  double retrieval_m = 1.0;     ///< Retrieval success: top keyframe within this ...
  double retrieval_deg = 30.0;  ///< ... and this of the query.
  int candidates = RelocalizationOptions{}.candidates;
  int refined = RelocalizationOptions{}.refined_probes;
  int realign_level = RelocalizationOptions{}.realign_level;
  int rerank = RelocalizationOptions{}.rerank_candidates;
  double rerank_bits_weight = RelocalizationOptions{}.rerank_bits_weight;
  bool top_first = RelocalizationOptions{}.top_candidate_first;
  bool feature_starts = RelocalizationOptions{}.feature_starts;
  bool inside_box = RelocalizationOptions{}.inside_database_box;
  bool confirm_start = RelocalizationOptions{}.confirm_start;
  std::string keyframes = "sync";
  int trials = 0;              ///< Forced-loss or start trials (0: none).
  std::string loss = "black";  ///< black | jump | start.
  double black_s = 1.0;        ///< Seconds of black frames.
  double jump_m = 5.0;         ///< Jump of the camera, metres.
  double prior_sigma_m = 1.0;  ///< Start trials: the prior's 1-sigma per axis, metres.
  int start_frames = 20;       ///< Start trials: frames searched before a start counts as failed.
  uint64_t seed = 1;
  bool no_vulkan = false;
  DeviceArgs device;
  std::string csv;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(std::floor(q * static_cast<double>(v.size() - 1) + 0.5)));
  return v[k];
}

struct Setup {
  Sequence seq;
  PinholeCamera camera;
  Model model;
  std::shared_ptr<const KeyframeDatabase> db;
  std::shared_ptr<Accelerator> accelerator;
  std::shared_ptr<GpuContext> context;
};

std::unique_ptr<Localizer> makeLocalizer(const Setup& s, const RelocBenchArgs& a, bool imu) {
  LocalizerOptions options;
  LocalizerArgs localizer_args;
  localizer_args.keyframes = a.keyframes;
  localizer_args.filter = "ekf";
  localizer_args.apply(options);
  setSequenceInertial(s.seq, imu, options);
  options.relocalization.candidates = a.candidates;
  options.relocalization.refined_probes = a.refined;
  options.relocalization.realign_level = a.realign_level;
  options.relocalization.rerank_candidates = a.rerank;
  options.relocalization.rerank_bits_weight = a.rerank_bits_weight;
  options.relocalization.top_candidate_first = a.top_first;
  options.relocalization.feature_starts = a.feature_starts;
  options.relocalization.inside_database_box = a.inside_box;
  options.relocalization.confirm_start = a.confirm_start;
  auto localizer = take(Localizer::create(s.model, s.camera, options, s.accelerator));
  check(localizer->setKeyframeDatabase(s.db));
  return localizer;
}

void runQueries(const Setup& s, const RelocBenchArgs& a);
void runLossTrials(const Setup& s, const RelocBenchArgs& a);
void runStartTrials(const Setup& s, const RelocBenchArgs& a);

void runRelocBench(const RelocBenchArgs& a) {
  Setup s;
  s.seq = take(loadSequence(a.sequence));
  if (s.seq.groundtruth.empty()) throw Failure{fmt::format("{}: no ground truth (groundtruth.txt)", a.sequence)};
  s.camera = sequenceCamera(s.seq);
  s.model = loadSequenceModel(s.seq);
  s.db = std::make_shared<const KeyframeDatabase>(take(KeyframeDatabase::load(a.db, modelFingerprint(s.model))));
  if (s.db->size() == 0) throw Failure{fmt::format("{}: the database holds no keyframe", a.db)};
  if (!a.no_vulkan) {
    s.context = a.device.create();
    s.accelerator = take(makeGpuAccelerator(s.context));
  }

  // Query time over the whole database: the median of repeated full scans, per 1000 keyframes.
  {
    const ImageU8 gray = take(readImageU8(s.seq.imagePath(0), 1));
    const GlobalDescriptor d = take(globalDescriptor(gray));
    std::vector<double> us;
    for (int r = 0; r < 200; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      const std::vector<KeyframeCandidate> c = s.db->query(d, static_cast<size_t>(a.candidates));
      us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
      if (c.empty()) throw Failure{"query returned nothing"};
    }
    const auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < 50; ++r) (void)globalDescriptor(gray);
    const double descriptor_ms = msSince(t0) / 50.0;
    const double median_us = percentile(us, 0.5);
    std::printf("query: %zu keyframes in %.1f us (%.4f ms per 1000 keyframes), descriptor of a %dx%d image %.3f ms\n",
                s.db->size(), median_us, median_us * 1e-3 * 1000.0 / static_cast<double>(s.db->size()), s.camera.width,
                s.camera.height, descriptor_ms);
  }

  if (a.queries > 0) runQueries(s, a);
  if (a.trials <= 0) return;
  if (a.loss == "start") {
    runStartTrials(s, a);
  } else {
    runLossTrials(s, a);
  }
}

/// STAR's protocol: queries spread over the frames with ground truth.
void runQueries(const Setup& s, const RelocBenchArgs& a) {
  std::vector<size_t> frames;
  for (size_t i = 0; i < s.seq.images.size(); ++i) {
    if (groundTruthAt(s.seq.groundtruth, s.seq.images[i].t_ns)) frames.push_back(i);
  }
  std::vector<size_t> queries;
  const size_t n = std::min(frames.size(), static_cast<size_t>(a.queries));
  for (size_t q = 0; q < n; ++q) queries.push_back(frames[q * frames.size() / n]);
  auto localizer = makeLocalizer(s, a, false);
  const double reach_m = s.db->positionReach();
  std::unique_ptr<PartialFileWriter> csv;
  if (!a.csv.empty()) {
    csv = take(PartialFileWriter::open(a.csv));
    check(csv->appendLine(
        "frame,top_distance_bits,top_m,top_deg,state,t_err_m,r_err_deg,depth_m,verify_score,candidates,ms,ranked_m,"
        "ranked_deg,feature_starts"));
  }
  size_t retrieved = 0, retrieved_ranked = 0, recovered = 0, wrong = 0, in_window = 0;
  std::vector<double> top_m, top_deg, ranked_m, ranked_deg, recover_ms;
  const auto t_start = std::chrono::steady_clock::now();
  for (size_t q = 0; q < queries.size(); ++q) {
    const size_t i = queries[q];
    const Pose truth = *groundTruthAt(s.seq.groundtruth, s.seq.images[i].t_ns);
    const ImageU8 gray = take(readImageU8(s.seq.imagePath(i), 1));
    SearchRegion region;
    region.center_world = truth.translation();
    region.radius_m = a.window_m;
    const GlobalDescriptor d = take(globalDescriptor(gray));
    // Retrieval as the search does it: the window grown by the grid's reach (Localizer).
    SearchRegion grown = region;
    grown.radius_m += reach_m;
    const std::vector<KeyframeCandidate> top = s.db->query(d, 1, grown);
    double dm = NAN, ddeg = NAN;
    int bits = -1;
    if (!top.empty()) {
      ++in_window;
      const Pose& T = s.db->keyframes()[top[0].index].T_world_camera;
      dm = (T.translation() - truth.translation()).norm();
      ddeg = rotationAngleDeg(T.linear().transpose() * truth.linear());
      bits = top[0].distance;
      top_m.push_back(dm);
      top_deg.push_back(ddeg);
      retrieved += dm <= a.retrieval_m && ddeg <= a.retrieval_deg;
    }
    check(localizer->startSearch(region));
    // One image, no IMU (STAR's protocol): the search's pose is reported on its frame
    // (RelocalizationOptions::confirm_start needs the IMU).
    const LocalizationResult r = take(localizer->localize(s.seq.images[i].t_ns, gray));
    // The search's own retrieval: its first candidate after the re-ranking.
    double rm = NAN, rdeg = NAN;
    if (r.relocalization_top_keyframe >= 0) {
      const Pose& T = s.db->keyframes()[static_cast<size_t>(r.relocalization_top_keyframe)].T_world_camera;
      rm = (T.translation() - truth.translation()).norm();
      rdeg = rotationAngleDeg(T.linear().transpose() * truth.linear());
      ranked_m.push_back(rm);
      ranked_deg.push_back(rdeg);
      retrieved_ranked += rm <= a.retrieval_m && rdeg <= a.retrieval_deg;
    }
    const double t_err = (r.T_world_camera.translation() - truth.translation()).norm();
    const double r_err = rotationAngleDeg(r.T_world_camera.linear().transpose() * truth.linear());
    const bool relocalized = r.state == TrackingState::kRelocalized;
    const double depth = r.scene_depth_m > 0 ? r.scene_depth_m : 1.0;
    const bool good = relocalized && t_err <= a.goal_fraction * depth && r_err <= a.goal_deg;
    recovered += good;
    wrong += relocalized && !good;
    recover_ms.push_back(r.total_ms);
    if (csv) {
      check(csv->appendLine(fmt::format(
          "{},{},{:.4f},{:.3f},{},{:.5f},{:.4f},{:.3f},{:.4f},{},{:.1f},{:.4f},{:.3f},{}", i, bits, dm, ddeg,
          trackingStateName(r.state), relocalized ? t_err : NAN, relocalized ? r_err : NAN, r.scene_depth_m,
          r.verify_score, r.relocalization_candidates, r.total_ms, rm, rdeg, r.relocalization_feature_starts)));
    }
    if ((q + 1) % 10 == 0 || q + 1 == queries.size()) {
      std::fprintf(stderr, "bench reloc: %zu/%zu queries, %zu recovered, %.0f s\n", q + 1, queries.size(), recovered,
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count());
    }
  }
  if (csv) check(csv->commit());
  const double nq = static_cast<double>(queries.size());
  std::printf(
      "%s: %zu queries, window %.1f m (+ the grid's reach %.2f m): retrieval (top keyframe within %.1f m and %.0f "
      "deg) %.1f %% (median %.2f m, %.1f deg; %zu with no keyframe in the window)\n",
      s.seq.name.c_str(), queries.size(), a.window_m, reach_m, a.retrieval_m, a.retrieval_deg, 100.0 * retrieved / nq,
      percentile(top_m, 0.5), percentile(top_deg, 0.5), queries.size() - in_window);
  if (a.rerank > a.candidates) {
    std::printf(
        "%s: retrieval after the re-ranking (the search's first of the %d nearest, ranked by phase correlation%s): "
        "%.1f %% (median %.2f m, %.1f deg)\n",
        s.seq.name.c_str(), a.rerank, a.rerank_bits_weight > 0 ? " and descriptor distance" : "",
        100.0 * retrieved_ranked / nq, percentile(ranked_m, 0.5), percentile(ranked_deg, 0.5));
  }
  std::printf(
      "%s: recovered (verified, within %.1f %% of depth and %.1f deg) %.1f %%, wrong poses accepted %zu; recovery "
      "time median %.0f ms, p90 %.0f ms (%d candidates)\n",
      s.seq.name.c_str(), 100 * a.goal_fraction, a.goal_deg, 100.0 * recovered / nq, wrong, percentile(recover_ms, 0.5),
      percentile(recover_ms, 0.9), a.candidates);
}

void runLossTrials(const Setup& s, const RelocBenchArgs& a) {
  // Forced loss: track from a seeded start frame with the IMU; after 1 s the images go black for
  // black_s (or, for a jump, the frames skip to where the camera is jump_m away); count
  // the frames from the first usable image to a verified pose again.
  const int64_t frame_ns = s.seq.images.size() > 1 ? s.seq.images[1].t_ns - s.seq.images[0].t_ns : 50'000'000;
  const size_t lead = static_cast<size_t>(std::llround(1e9 / static_cast<double>(frame_ns)));
  const size_t black = static_cast<size_t>(std::llround(a.black_s * 1e9 / static_cast<double>(frame_ns)));
  // Frames without an image to use after the loss starts: the black ones (none for a jump).
  const size_t gap = a.loss == "black" ? black : 0;
  Xoshiro256 rng(a.seed);
  size_t ok = 0, wrong_trials = 0, skipped = 0, redrawn = 0;
  std::vector<double> frames_to_recover;
  for (int trial = 0; trial < a.trials; ++trial) {
    auto tracker = makeLocalizer(s, a, true);
    const size_t span = lead + black + 6;
    if (s.seq.images.size() <= span + 1) throw Failure{"the sequence is too short for forced-loss trials"};
    // A start with ground truth at it and at the loss and, for a jump, a frame jump_m from the
    // camera at the loss: the first after it or, where the sequence has none ahead, the last
    // before it (a jump back along the path). Starts without one are drawn again.
    size_t start = 0, resume = 0;
    std::optional<Pose> T0;
    for (int draw = 0; draw < 1000 && !T0; ++draw) {
      start = static_cast<size_t>(rng.uniform(0.0, static_cast<double>(s.seq.images.size() - span - 1)));
      resume = start + lead + (a.loss == "black" ? black : 1);
      const std::optional<Pose> at_start = groundTruthAt(s.seq.groundtruth, s.seq.images[start].t_ns);
      const std::optional<Pose> at_loss = groundTruthAt(s.seq.groundtruth, s.seq.images[start + lead].t_ns);
      if (!at_start || !at_loss) {
        ++redrawn;
        continue;
      }
      if (a.loss == "jump") {
        auto far_enough = [&](size_t k) {
          const std::optional<Pose> p = groundTruthAt(s.seq.groundtruth, s.seq.images[k].t_ns);
          return p && (p->translation() - at_loss->translation()).norm() >= a.jump_m;
        };
        std::optional<size_t> to;
        for (size_t k = resume; k + 6 < s.seq.images.size() && !to; ++k) {
          if (far_enough(k)) to = k;
        }
        for (size_t k = start + lead; k-- > 0 && !to;) {
          if (far_enough(k)) to = k;
        }
        if (!to) {
          ++redrawn;
          continue;
        }
        resume = *to;
      }
      T0 = at_start;
    }
    if (!T0) {
      ++skipped;
      continue;
    }
    tracker->reset(*T0);
    size_t next_imu = 0;
    int recovered_after = -1;
    bool accepted_wrong = false;
    std::string wrong_what;
    // Frame times run on without a gap (a jump is a jump in space, not in time).
    for (size_t f = 0; f < lead + black + 6; ++f) {
      size_t i = start + f;
      bool blacked = false;
      if (f >= lead) {
        if (a.loss == "black" && f < lead + black) {
          blacked = true;
        } else {
          i = resume + (f - lead - gap);
        }
      }
      if (i >= s.seq.images.size()) break;
      const int64_t t_ns = s.seq.images[start].t_ns + static_cast<int64_t>(f) * frame_ns;
      if (a.loss == "black") next_imu = feedSequenceImu(s.seq, next_imu, t_ns, *tracker);
      ImageU8 gray = take(readImageU8(s.seq.imagePath(i), 1));
      if (blacked) std::fill(gray.data.begin(), gray.data.end(), uint8_t{0});
      const LocalizationResult r = take(tracker->localize(t_ns, gray));
      if (f < lead + gap || blacked) continue;
      const std::optional<Pose> truth = groundTruthAt(s.seq.groundtruth, s.seq.images[i].t_ns);
      const bool trusted = r.state == TrackingState::kTracking || r.state == TrackingState::kRelocalized;
      if (!trusted || !truth) continue;
      const double t_err = (r.T_world_camera.translation() - truth->translation()).norm();
      const double r_err = rotationAngleDeg(r.T_world_camera.linear().transpose() * truth->linear());
      const double depth = r.scene_depth_m > 0 ? r.scene_depth_m : 1.0;
      if (t_err <= a.goal_fraction * depth && r_err <= a.goal_deg) {
        if (recovered_after < 0) recovered_after = static_cast<int>(f - lead - gap);
      } else if (!accepted_wrong) {
        accepted_wrong = true;
        wrong_what = fmt::format(" ({:.3f} m, {:.2f} deg off at usable frame {} (image {}), {})", t_err, r_err,
                                 f - lead - gap + 1, i, trackingStateName(r.state));
      }
    }
    if (recovered_after >= 0 && recovered_after < 3 && !accepted_wrong) ++ok;
    wrong_trials += accepted_wrong;
    frames_to_recover.push_back(recovered_after < 0 ? INFINITY : recovered_after + 1);
    std::fprintf(stderr, "bench reloc: trial %d/%d: start frame %zu, verified again at usable frame %d%s\n", trial + 1,
                 a.trials, start, recovered_after < 0 ? -1 : recovered_after + 1,
                 accepted_wrong ? (", WRONG pose" + wrong_what).c_str() : "");
  }
  const size_t done = frames_to_recover.size();
  std::printf(
      "%s: forced loss (%s): verified again within 3 frames of the first usable image in %zu of %zu trials (%.1f %%), "
      "trials with a wrong pose accepted %zu, median frames to recover %.0f%s%s\n",
      s.seq.name.c_str(),
      a.loss == "black" ? fmt::format("{:.1f} s of black frames", a.black_s).c_str()
                        : fmt::format("jump of {:.1f} m", a.jump_m).c_str(),
      ok, done, done > 0 ? 100.0 * static_cast<double>(ok) / static_cast<double>(done) : 0.0, wrong_trials,
      percentile(frames_to_recover, 0.5),
      skipped > 0 ? fmt::format(" ({} trials skipped: no such jump or no ground truth)", skipped).c_str() : "",
      redrawn > 0 ? fmt::format(" ({} starts drawn again: no such jump or no ground truth)", redrawn).c_str() : "");
}

/// Global initialization: at a seeded frame the localizer has no pose, only a prior position drawn
/// from N(truth, prior_sigma^2 I), searched as `vkloc track --global-init --prior-sigma` does; the
/// frames run on with the IMU until a verified pose, then 5 more to catch a wrong one.
void runStartTrials(const Setup& s, const RelocBenchArgs& a) {
  const size_t tail = 5;  // frames after the first pose (as far as the sequence goes)
  const size_t window = static_cast<size_t>(a.start_frames);
  if (s.seq.images.size() < window) {
    throw Failure{
        fmt::format("the sequence ({} images) is shorter than --start-frames {}", s.seq.images.size(), a.start_frames)};
  }
  auto region_of = [&](const Eigen::Vector3d& center_world) {
    return priorSearchRegion(center_world, a.prior_sigma_m, RelocalizationOptions{}.min_radius_m);
  };
  Xoshiro256 rng(a.seed);
  size_t started = 0, within3 = 0, wrong_trials = 0, skipped = 0;
  std::vector<double> frames_to_start, ms_to_start;
  for (int trial = 0; trial < a.trials; ++trial) {
    const size_t start =
        std::min(s.seq.images.size() - window,
                 static_cast<size_t>(rng.uniform(0.0, static_cast<double>(s.seq.images.size() - window + 1))));
    const Eigen::Vector3d noise(rng.gaussian(), rng.gaussian(), rng.gaussian());
    const std::optional<Pose> truth0 = groundTruthAt(s.seq.groundtruth, s.seq.images[start].t_ns);
    if (!truth0) {
      ++skipped;
      continue;
    }
    auto tracker = makeLocalizer(s, a, true);
    check(tracker->startSearch(region_of(truth0->translation() + a.prior_sigma_m * noise)));
    // The IMU from one frame before the start (a filter that starts with the first pose).
    size_t next_imu = static_cast<size_t>(std::lower_bound(s.seq.imu.begin(), s.seq.imu.end(),
                                                           s.seq.images[start > 0 ? start - 1 : 0].t_ns,
                                                           [](const ImuSample& m, int64_t t) { return m.t_ns < t; }) -
                                          s.seq.imu.begin());
    int first = -1;
    bool accepted_wrong = false;
    std::string wrong_what;
    double ms = 0;
    for (size_t f = 0; start + f < s.seq.images.size(); ++f) {
      if (first < 0 && f >= window) break;
      if (first >= 0 && f > static_cast<size_t>(first) + tail) break;
      const size_t i = start + f;
      const int64_t t_ns = s.seq.images[i].t_ns;
      next_imu = feedSequenceImu(s.seq, next_imu, t_ns, *tracker);
      const ImageU8 gray = take(readImageU8(s.seq.imagePath(i), 1));
      const LocalizationResult r = take(tracker->localize(t_ns, gray));
      if (first < 0) ms += r.total_ms;
      const bool trusted = r.state == TrackingState::kTracking || r.state == TrackingState::kRelocalized;
      const std::optional<Pose> truth = groundTruthAt(s.seq.groundtruth, t_ns);
      if (!trusted || !truth) continue;
      const double t_err = (r.T_world_camera.translation() - truth->translation()).norm();
      const double r_err = rotationAngleDeg(r.T_world_camera.linear().transpose() * truth->linear());
      const double depth = r.scene_depth_m > 0 ? r.scene_depth_m : 1.0;
      if (!accepted_wrong && (t_err > a.goal_fraction * depth || r_err > a.goal_deg)) {
        accepted_wrong = true;
        wrong_what =
            fmt::format(" ({:.3f} m, {:.2f} deg off at frame {}, {})", t_err, r_err, f + 1, trackingStateName(r.state));
      }
      if (first < 0) first = static_cast<int>(f);
    }
    const bool ok = first >= 0 && !accepted_wrong;
    started += ok;
    within3 += ok && first < 3;
    wrong_trials += accepted_wrong;
    frames_to_start.push_back(ok ? first + 1 : INFINITY);
    if (ok) ms_to_start.push_back(ms);
    std::fprintf(stderr,
                 "bench reloc: start %d/%d: frame %zu, prior %.2f m off, first verified pose at frame %d%s (%.0f ms)\n",
                 trial + 1, a.trials, start, a.prior_sigma_m * noise.norm(), first < 0 ? -1 : first + 1,
                 accepted_wrong ? (", WRONG pose" + wrong_what).c_str() : "", ms);
  }
  const size_t done = frames_to_start.size();
  const double pct = done > 0 ? 100.0 / static_cast<double>(done) : 0.0;
  std::printf(
      "%s: global initialization from a prior of sigma %.1f m (searched within %.2f m): a verified pose within %d "
      "frames in %zu of %zu starts (%.1f %%; within 3 frames %.1f %%), starts with a wrong pose accepted %zu; frames "
      "to the first pose median %.0f; search time to it median %.0f ms, p90 %.0f ms%s\n",
      s.seq.name.c_str(), a.prior_sigma_m, region_of(Eigen::Vector3d::Zero()).radius_m, a.start_frames, started, done,
      pct * static_cast<double>(started), pct * static_cast<double>(within3), wrong_trials,
      percentile(frames_to_start, 0.5), percentile(ms_to_start, 0.5), percentile(ms_to_start, 0.9),
      skipped > 0 ? fmt::format(" ({} starts skipped: no ground truth)", skipped).c_str() : "");
}

}  // namespace

void addRelocBench(CLI::App& bench) {
  auto args = std::make_shared<RelocBenchArgs>();
  CLI::App* reloc = bench.add_subcommand(
      "reloc",
      "Relocalization from a keyframe database on STAR's protocol, forced-loss and global-initialization trials");
  reloc->add_option("--sequence", args->sequence, "Sequence folder with ground truth")->required();
  reloc->add_option("--db", args->db, "Keyframe database (vkloc keyframes build)")->required();
  reloc->add_option("--queries", args->queries, "Query frames, spread over the sequence (0: none)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  reloc->add_option("--window", args->window_m, "Search window around the query's true position, metres")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  reloc->add_option("--candidates", args->candidates, "Keyframes aligned per search")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  reloc->add_option("--rerank", args->rerank, "Nearest keyframes rendered small and re-ranked (0: none)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  reloc
      ->add_option("--rerank-bits-weight", args->rerank_bits_weight,
                   "Re-ranking: phase-correlation peak lost per bit of descriptor distance (0: the peak alone)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  reloc
      ->add_option("--confirm-start", args->confirm_start,
                   "Start trials: a global search's pose is reported once the next frame confirms it (with the IMU; "
                   "true | false)")
      ->capture_default_str();
  reloc->add_option("--top-first", args->top_first, "Align the best-ranked candidate's best probe first (true | false)")
      ->capture_default_str();
  reloc
      ->add_option("--feature-starts", args->feature_starts,
                   "Also start the alignment from ORB point features matched with each candidate's render (a RANSAC "
                   "PnP on its depth; true | false)")
      ->capture_default_str();
  reloc
      ->add_option("--inside-box", args->inside_box,
                   "Take a found pose only inside the box of the database's positions grown by the grid's reach (true "
                   "| false)")
      ->capture_default_str();
  reloc->add_option("--refined", args->refined, "Probed starts aligned fully per search")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  reloc
      ->add_option("--realign-level", args->realign_level,
                   "A refined pose verified below the search's score is aligned again from itself from this pyramid "
                   "level; the better verified is kept (-1: never)")
      ->check(CLI::Range(-1, 7))
      ->capture_default_str();
  reloc->add_option("--keyframes", args->keyframes, "Keyframe threading: sync | worker")->capture_default_str();
  reloc->add_option("--trials", args->trials, "Forced-loss or start trials (0: none)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  reloc
      ->add_option("--loss", args->loss,
                   "Trials: black (frames) | jump (of the camera) | start (global initialization from a prior)")
      ->check(CLI::IsMember({"black", "jump", "start"}))
      ->capture_default_str();
  reloc->add_option("--black", args->black_s, "Seconds of black frames")
      ->check(CLI::Range(0.0, 1e3))
      ->capture_default_str();
  reloc->add_option("--jump", args->jump_m, "Jump of the camera, metres")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  reloc->add_option("--prior-sigma", args->prior_sigma_m, "Start trials: the prior's 1-sigma per axis, metres")
      ->check(CLI::Range(0.0, 1e4))
      ->capture_default_str();
  reloc->add_option("--start-frames", args->start_frames, "Start trials: frames searched before a start fails")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  reloc->add_option("--seed", args->seed, "Seed of the trials' start frames")->capture_default_str();
  reloc->add_flag("--no-vulkan", args->no_vulkan, "Render keyframes with the CPU reference rasterizer");
  args->device.add(*reloc);
  reloc->add_option("--csv", args->csv, "Write one row per query");
  reloc->callback([args] { runRelocBench(*args); });
}

}  // namespace vkloc::cli
