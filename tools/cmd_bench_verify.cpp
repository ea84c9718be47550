// vkloc bench verify: how well the per-frame verification score tells true poses from wrong ones.
// On frames with ground truth, alignments start at the true pose and at seeded offsets of growing
// size (keyframe rendered at the start guess, as the Localizer renders it at its prediction);
// those that converge near the truth are true samples, those that converge elsewhere are wrong
// samples. The verb prints the ROC of the score (accepted true poses against accepted wrong
// ones), the operating point of the tracker's thresholds, and writes one CSV row per alignment.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "common.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/keyframe.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/track/edge_tracker.hpp"
#include "vkloc/track/live_frame.hpp"
#include "vkloc/track/pose_verification.hpp"

namespace vkloc::cli {
namespace {

struct VerifyBenchArgs {
  std::vector<std::string> sequences;
  int every = 5;
  int offsets = 6;
  uint64_t seed = 1;
  double true_fraction = 0.005;       ///< True sample: translation error <= this x scene depth ...
  double true_deg = 0.5;              ///< ... and rotation error <= this, degrees.
  double wrong_fraction = 0.02;       ///< Wrong sample: translation error > this x scene depth ...
  double wrong_deg = 2.0;             ///< ... or rotation error > this, degrees.
  double max_offset_fraction = 0.15;  ///< Largest start offset, x scene depth.
  double max_offset_deg = 8.0;        ///< Largest start rotation offset, degrees.
  int search_level = 2;               ///< Coarsest pyramid level of the alignments.
  std::string csv;
};

struct Sample {
  std::string sequence;
  size_t frame = 0;
  int trial = 0;
  double offset_m = 0, offset_deg = 0;
  double depth_m = 0, t_err_m = 0, r_err_deg = 0;
  bool tracked = false;
  int label = 0;  ///< 1 true, -1 wrong, 0 in between (not counted).
  VerificationFeatures features;
  double score = 0;
};

// Fraction of `values` at or above `threshold`.
double acceptedFraction(const std::vector<double>& values, double threshold) {
  if (values.empty()) return NAN;
  size_t n = 0;
  for (double v : values) n += v >= threshold ? 1 : 0;
  return static_cast<double>(n) / static_cast<double>(values.size());
}

void runVerifyBench(const VerifyBenchArgs& a) {
  std::vector<Sample> samples;
  size_t unaligned = 0;
  LocalizerOptions defaults;
  VerificationOptions verification;
  verification.inlier_threshold_px = defaults.tracker.inlier_threshold_px;
  const auto t_start = std::chrono::steady_clock::now();
  for (const std::string& dir : a.sequences) {
    const Sequence seq = take(loadSequence(dir));
    if (seq.groundtruth.empty()) throw Failure{fmt::format("{}: no ground truth (groundtruth.txt)", dir)};
    const PinholeCamera camera = sequenceCamera(seq);
    const Model model = loadSequenceModel(seq);
    LiveFrameOptions live_options = defaults.live;
    live_options.levels = std::max(live_options.levels, a.search_level + 1);
    live_options.keep_intermediate = false;
    ReferenceEdgeOptions reference_options = defaults.reference;
    reference_options.levels = live_options.levels;
    EdgeTrackerOptions tracker = defaults.tracker;
    tracker.coarsest_level = std::max(tracker.coarsest_level, a.search_level);
    if (tracker.far_first_coarsest_level >= 0) {
      tracker.far_first_coarsest_level = std::max(tracker.far_first_coarsest_level, a.search_level);
    }
    KeyframeMaker maker(take(CpuRenderer::create(model)), camera, defaults.render, reference_options);
    Xoshiro256 rng(subSeed(a.seed, samples.size()));
    std::vector<size_t> frames;
    for (size_t i = 0; i < seq.images.size(); i += static_cast<size_t>(a.every)) {
      if (groundTruthAt(seq.groundtruth, seq.images[i].t_ns)) frames.push_back(i);
    }
    std::fprintf(stderr, "bench verify: %s: %zu frames x %d alignments\n", seq.name.c_str(), frames.size(),
                 a.offsets + 1);
    size_t done = 0;
    for (size_t i : frames) {
      const Pose truth = *groundTruthAt(seq.groundtruth, seq.images[i].t_ns);
      const ImageU8 gray = take(readImageU8(seq.imagePath(i), 1));
      const LiveFrame live = take(buildLiveFrame(gray, camera, live_options));
      // Scene depth from a keyframe at the truth.
      KeyframeRequest at_truth;
      at_truth.T_world_ref = truth;
      const auto truth_keyframe = take(maker.make(at_truth));
      const double depth = truth_keyframe->scene_depth_m;
      if (!(depth > 0)) continue;
      for (int k = 0; k <= a.offsets; ++k) {
        // Offsets grow geometrically from 1 % of the largest to the largest; trial 0 starts at the truth.
        Vector6d xi = Vector6d::Zero();
        double offset_m = 0, offset_deg = 0;
        if (k > 0) {
          const double f = a.offsets > 1 ? std::pow(100.0, static_cast<double>(k - 1) / (a.offsets - 1) - 1.0) : 1.0;
          offset_m = f * a.max_offset_fraction * depth * rng.uniform(0.5, 1.0);
          offset_deg = f * a.max_offset_deg * rng.uniform(0.5, 1.0);
          Eigen::Vector3d dt(rng.gaussian(), rng.gaussian(), rng.gaussian());
          Eigen::Vector3d dr(rng.gaussian(), rng.gaussian(), rng.gaussian());
          xi.head<3>() = dt.normalized() * offset_m;
          xi.tail<3>() = dr.normalized() * offset_deg * M_PI / 180.0;
        }
        const Pose guess = truth * expSE3(xi);
        std::shared_ptr<const Keyframe> keyframe = truth_keyframe;
        if (k > 0) {
          KeyframeRequest request;
          request.T_world_ref = guess;
          keyframe = take(maker.make(request));
        }
        // A start that sees no model edges (looking past the model) gives no alignment to score.
        Result<TrackResult> tracked = trackFrame(keyframe->reference, live, guess, tracker);
        if (!tracked.ok()) {
          ++unaligned;
          continue;
        }
        const TrackResult& r = *tracked;
        Sample s;
        s.sequence = seq.name;
        s.frame = i;
        s.trial = k;
        s.offset_m = offset_m;
        s.offset_deg = offset_deg;
        s.depth_m = depth;
        s.t_err_m = (r.T_world_camera.translation() - truth.translation()).norm();
        s.r_err_deg = rotationAngleDeg(r.T_world_camera.linear().transpose() * truth.linear());
        s.tracked = r.state == TrackingState::kTracking;
        if (s.t_err_m <= a.true_fraction * depth && s.r_err_deg <= a.true_deg) {
          s.label = 1;
        } else if (s.t_err_m > a.wrong_fraction * depth || s.r_err_deg > a.wrong_deg) {
          s.label = -1;
        }
        s.features = verificationFeatures(r, keyframe->scene_depth_m);
        s.score = verificationScore(s.features, verification);
        samples.push_back(s);
      }
      ++done;
      if (done % 10 == 0 || done == frames.size()) {
        std::fprintf(stderr, "bench verify: %s: %zu/%zu frames, %.0f s\n", seq.name.c_str(), done, frames.size(),
                     msSince(t_start) / 1000.0);
      }
    }
  }
  if (!a.csv.empty()) {
    auto out = take(PartialFileWriter::open(a.csv));
    check(out->appendLine(
        "sequence,frame,trial,offset_m,offset_deg,depth_m,t_err_m,r_err_deg,label,tracked,score,inlier_ratio,"
        "chance,above_chance,mean_residual_px,scale_px,spread_ratio,visible_ratio,"
        "points_in_image,sigma_t_rel,sigma_r_deg"));
    for (const Sample& s : samples) {
      const VerificationFeatures& f = s.features;
      check(out->appendLine(fmt::format(
          "{},{},{},{:.4f},{:.3f},{:.3f},{:.5f},{:.4f},{},{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},"
          "{:.4f},{},{:.6f},{:.5f}",
          s.sequence, s.frame, s.trial, s.offset_m, s.offset_deg, s.depth_m, s.t_err_m, s.r_err_deg, s.label,
          s.tracked ? 1 : 0, s.score, f.inlier_ratio, f.chance_inlier_ratio, f.above_chance, f.mean_residual_px,
          f.scale_px, f.spread_ratio, f.visible_ratio, f.points_in_image, f.sigma_t_rel, f.sigma_r_deg)));
    }
    check(out->commit());
  }
  // ROC per sequence and over all: accepted fractions of true and wrong samples at thresholds.
  std::vector<std::string> groups{"all"};
  for (const Sample& s : samples) {
    if (std::find(groups.begin(), groups.end(), s.sequence) == groups.end()) groups.push_back(s.sequence);
  }
  const double threshold = verification.min_score;
  std::printf(
      "true sample: converged within %.1f %% of the scene depth and %.2f deg; wrong: beyond %.1f %% or %.1f deg\n",
      100 * a.true_fraction, a.true_deg, 100 * a.wrong_fraction, a.wrong_deg);
  std::printf("%-22s %6s %6s %8s | %-20s | %-20s | %-26s\n", "sequence", "true", "wrong", "between",
              "tracker rule TPR FPR", "score>=thr TPR FPR", "TPR at FPR<=1%  (thr)");
  for (const std::string& g : groups) {
    std::vector<double> pos, neg;
    size_t rule_pos = 0, rule_neg = 0, between = 0;
    for (const Sample& s : samples) {
      if (g != "all" && s.sequence != g) continue;
      if (s.label == 1) {
        pos.push_back(s.score);
        rule_pos += s.tracked ? 1 : 0;
      } else if (s.label == -1) {
        neg.push_back(s.score);
        rule_neg += s.tracked ? 1 : 0;
      } else {
        ++between;
      }
    }
    // The lowest threshold that accepts at most 1 % of the wrong samples.
    std::vector<double> sorted = neg;
    std::sort(sorted.begin(), sorted.end(), std::greater<>());
    const size_t allowed = static_cast<size_t>(std::floor(0.01 * static_cast<double>(sorted.size())));
    double thr_1 = sorted.empty() ? -INFINITY : std::nextafter(sorted[std::min(allowed, sorted.size() - 1)], INFINITY);
    if (!sorted.empty() && allowed >= sorted.size()) thr_1 = -INFINITY;
    auto pct = [](double x) { return std::isnan(x) ? std::string("-") : fmt::format("{:.1f}%", 100 * x); };
    std::printf("%-22s %6zu %6zu %8zu | %9s %9s | %9s %9s | %9s %9s (%.3f)\n", g.c_str(), pos.size(), neg.size(),
                between, pct(pos.empty() ? NAN : static_cast<double>(rule_pos) / pos.size()).c_str(),
                pct(neg.empty() ? NAN : static_cast<double>(rule_neg) / neg.size()).c_str(),
                pct(acceptedFraction(pos, threshold)).c_str(), pct(acceptedFraction(neg, threshold)).c_str(),
                pct(acceptedFraction(pos, thr_1)).c_str(), pct(acceptedFraction(neg, thr_1)).c_str(), thr_1);
  }
  std::printf(
      "score threshold (VerificationOptions::min_score): %.3f; %zu alignments (%zu starts without model edges "
      "in view left out) in %.0f s\n",
      threshold, samples.size(), unaligned, msSince(t_start) / 1000.0);
}

}  // namespace

void addVerifyBench(CLI::App& bench) {
  auto args = std::make_shared<VerifyBenchArgs>();
  CLI::App* verify = bench.add_subcommand(
      "verify",
      "ROC of the pose verification score: true poses vs wrong converged ones on sequences with ground truth");
  verify->add_option("--sequence", args->sequences, "Sequence folders (repeat or comma-separate)")
      ->required()
      ->delimiter(',');
  verify->add_option("--every", args->every, "Use every Nth frame")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  verify->add_option("--offsets", args->offsets, "Offset starts per frame besides the one at the truth")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  verify->add_option("--seed", args->seed, "Seed of the offsets")->capture_default_str();
  verify->add_option("--max-offset", args->max_offset_fraction, "Largest start translation, fraction of scene depth")
      ->check(CLI::Range(0.0, 10.0))
      ->capture_default_str();
  verify->add_option("--max-offset-deg", args->max_offset_deg, "Largest start rotation, degrees")
      ->check(CLI::Range(0.0, 90.0))
      ->capture_default_str();
  verify->add_option("--search-level", args->search_level, "Coarsest pyramid level of the alignments")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  verify->add_option("--csv", args->csv, "Write one row per alignment (features, score, errors, label)");
  verify->callback([args] { runVerifyBench(*args); });
}

}  // namespace vkloc::cli
