// vkloc bench render: timing of model renders at 640x480 for ~10k, 100k and 1M triangles.
// vkloc bench track: per-frame localization time per stage and backend on one sequence.
// vkloc bench live: the live-image stages (pyramid, edges, distance fields) on one frame, per
// GPU stage and against the CPU backend in the same run.
// vkloc bench keyframe: a keyframe's render and its reference edge points at one true pose.
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "common.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/threads.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/engine/gpu_edges.hpp"
#include "vkloc/eval/eval.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/sim/demo_models.hpp"
#include "vkloc/track/reference_edges.hpp"

namespace vkloc::cli {
namespace {

struct BenchArgs {
  DeviceArgs device;
  CameraArgs camera;
  std::vector<uint32_t> triangles{10000, 100000, 1000000};
  int runs = 40;
  int warmup = 3;
  int reference_runs = 3;
  bool cull = true;
  double roughness_m = 0.03;
  double lod_pixel_error = 0.5;
  uint32_t block_triangles = 32768;
};

// Displaces every vertex by up to `amplitude` metres in a direction hashed from its position,
// so coincident vertices move together (no cracks) and the subdivided flat faces of the
// enlarged demo become rough like a photogrammetry mesh (level of detail cannot just undo the
// subdivision without error).
void roughen(Model& model, double amplitude) {
  if (amplitude <= 0) return;
  auto hash = [](float x, float y, float z, uint32_t k) {
    uint32_t h = 2166136261u ^ k;
    for (float f : {x, y, z}) {
      uint32_t bits;
      std::memcpy(&bits, &f, 4);
      h = (h ^ bits) * 16777619u;
      h ^= h >> 15;
    }
    return (h & 0xffffff) / static_cast<double>(0xffffff) * 2.0 - 1.0;
  };
  for (size_t i = 0; i < model.positions.size(); i += 3) {
    const float x = model.positions[i], y = model.positions[i + 1], z = model.positions[i + 2];
    for (uint32_t k = 0; k < 3; ++k) {
      model.positions[i + k] += static_cast<float>(amplitude * hash(x, y, z, k));
    }
  }
}

struct Stats {
  double median = 0, p10 = 0, p90 = 0;
};

Stats stats(std::vector<double> v) {
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  auto q = [&](double f) { return v[std::min(v.size() - 1, static_cast<size_t>(f * (v.size() - 1) + 0.5))]; };
  return {q(0.5), q(0.1), q(0.9)};
}

void run(const BenchArgs& a) {
  const PinholeCamera camera = a.camera.get();
  auto context = a.device.create();
  std::printf("device: %s (%s); %dx%d, %d runs after %d warm-up, median [p10 p90] ms\n", context->device().name.c_str(),
              context->device().type.c_str(), camera.width, camera.height, a.runs, a.warmup);
  std::printf(
      "columns: exact = full detail; lod = level of detail at %.2f px error; c+d+n = colour, depth and "
      "normals read back; gpu = left on the GPU\n",
      a.lod_pixel_error);
  std::printf("%-10s %-8s %9s %8s %-22s %-22s %-22s %8s %-22s %-22s %s\n", "model", "view", "triangles", "drawn",
              "exact c+d+n", "exact c+d", "exact gpu", "lod drawn", "lod c+d+n", "lod gpu", "CPU reference c+d+n");
  for (uint32_t target : a.triangles) {
    DemoModelOptions options;
    options.target_triangles = target;
    Model model = makeDemoCity(options);
    if (target > 20000) roughen(model, a.roughness_m);
    buildBlocks(model, a.block_triangles);
    auto t0 = std::chrono::steady_clock::now();
    auto renderer = take(GpuRenderer::create(context, model));
    const double create_ms = msSince(t0);
    const auto views = demoViewpoints("city");
    // "drone": the demo's first drone view (45 deg down); "overview": far away, whole model in view.
    const Pose overview = take(lookAt({-180, -180, 220}, {0, 0, 0}));
    const std::pair<const char*, Pose> cases[2] = {{"drone", views.front()}, {"overview", overview}};
    for (const auto& view_case : cases) {
      const char* const view_name = view_case.first;
      const Pose& pose = view_case.second;  // a plain reference: lambdas below capture it
      RenderSettings all;
      all.cull_back_faces = a.cull;
      RenderSettings no_normals = all;
      no_normals.outputs &= ~kRenderNormals;
      RenderSettings lod = all;
      lod.lod_pixel_error = a.lod_pixel_error;
      auto time = [&](const RenderSettings& s, bool readback, uint32_t* drawn) {
        std::vector<double> ms;
        for (int i = 0; i < a.warmup + a.runs; ++i) {
          const auto t1 = std::chrono::steady_clock::now();
          RenderOutput out =
              readback ? take(renderer->render(camera, pose, s)) : take(renderer->renderOnGpu(camera, pose, s));
          if (i >= a.warmup) ms.push_back(msSince(t1));
          *drawn = out.triangles_drawn;
        }
        return stats(ms);
      };
      uint32_t drawn = 0, lod_drawn = 0;
      const Stats full = time(all, true, &drawn);
      const Stats color_depth = time(no_normals, true, &drawn);
      const Stats gpu_only = time(all, false, &drawn);
      const Stats lod_full = time(lod, true, &lod_drawn);
      const Stats lod_gpu = time(lod, false, &lod_drawn);
      std::string ref = "-";
      if (a.reference_runs > 0 && model.triangleCount() <= 200000) {
        std::vector<double> ms;
        for (int i = 0; i < a.reference_runs; ++i) {
          const auto t1 = std::chrono::steady_clock::now();
          (void)take(renderReference(model, camera, pose, all));
          ms.push_back(msSince(t1));
        }
        const Stats r = stats(ms);
        ref = fmt::format("{:.1f} ({:.1f}x exact)", r.median, r.median / full.median);
      }
      auto fmt_stats = [](const Stats& st) { return fmt::format("{:.2f} [{:.2f} {:.2f}]", st.median, st.p10, st.p90); };
      std::printf("%-10s %-8s %9zu %8u %-22s %-22s %-22s %8u %-22s %-22s %s\n",
                  fmt::format("city{}k", target / 1000).c_str(), view_name, model.triangleCount(), drawn,
                  fmt_stats(full).c_str(), fmt_stats(color_depth).c_str(), fmt_stats(gpu_only).c_str(), lod_drawn,
                  fmt_stats(lod_full).c_str(), fmt_stats(lod_gpu).c_str(), ref.c_str());
      std::fflush(stdout);
    }
    std::printf("%-10s renderer created (upload + LOD build) in %.0f ms\n", "", create_ms);
  }
}

struct TrackBenchArgs {
  std::string sequence;
  std::vector<std::string> backends{"auto", "cpu", "vulkan"};
  std::vector<std::string> keyframes{"worker", "sync"};
  std::string policy = "when-needed";
  int runs = 5;
  size_t max_frames = 0;
  std::string pace = "none";  // "camera": each frame given at its timestamp after the pass's start
  DeviceArgs device;
};

/// One backend and keyframe mode: timings over every timed pass (ms), keyframe ages (frames),
/// throughput and errors over every timed pass.
struct TrackBenchRun {
  std::string summary;
  double create_ms = 0, first_frame_ms = 0;
  std::vector<double> total, reused, render, reference, live, align, age;
  std::vector<double> t_err_mm, r_err_deg;
  /// Wall time of the timed passes (localize and IMU feed; images preloaded; with --pace camera
  /// also the waits for each frame's time).
  double wall_s = 0;
  size_t lost = 0, waited = 0, frames = 0;
};

double median(const std::vector<double>& v) { return v.empty() ? NAN : stats(v).median; }

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? NAN : sum / static_cast<double>(v.size());
}

void runTrackBench(const TrackBenchArgs& a) {
  const Sequence seq = take(loadSequence(a.sequence));
  if (seq.images.empty()) throw Failure{fmt::format("{}: images.txt lists no image", a.sequence)};
  const PinholeCamera camera = sequenceCamera(seq);
  const Model model = loadSequenceModel(seq);
  const Pose T_init = initialPose(seq, "");
  const size_t n = a.max_frames > 0 ? std::min(a.max_frames, seq.images.size()) : seq.images.size();
  std::vector<ImageU8> images;
  images.reserve(n);
  for (size_t i = 0; i < n; ++i) images.push_back(take(readImageU8(seq.imagePath(i), 1)));
  std::map<int64_t, Pose> gt;
  for (const auto& g : seq.groundtruth) gt[g.t_ns] = g.T_world_camera;
  auto context = a.device.create();
  std::printf(
      "sequence %s: %zu frames %dx%d, model %zu triangles; device %s (%s); policy %s; %d timed passes after "
      "one warm-up pass, medians over all timed frames\n",
      seq.name.c_str(), n, camera.width, camera.height, model.triangleCount(), context->device().name.c_str(),
      context->device().type.c_str(), a.policy.c_str(), a.runs);
  std::printf("%-7s %-6s %7s %7s %7s %7s %7s %7s %7s %7s %7s %6s %6s %7s %7s %6s %8s %8s\n", "backend", "keyfr.", "fps",
              "frame", "p90", "render", "ref.pts", "live", "align", "reused", "age", "waits", "lost", "create", "1st",
              "kf", "mean mm", "mean deg");
  std::vector<std::pair<std::string, std::string>> summaries;
  const bool camera_pace = a.pace == "camera";
  if (camera_pace) {
    std::printf("frames given at the camera's pace (their timestamps); fps is then the camera's rate\n");
  }
  for (const std::string& backend : a.backends) {
    for (const std::string& mode : a.keyframes) {
      LocalizerOptions options;
      options.backend = take(parseLocalizerBackend(backend));
      options.policy = take(parseRerenderPolicy(a.policy));
      options.keyframe_threading = take(parseKeyframeThreading(mode));
      setSequenceInertial(seq, true, options);
      TrackBenchRun run;
      const auto t0 = std::chrono::steady_clock::now();
      auto localizer = take(Localizer::create(model, camera, options, take(makeGpuAccelerator(context))));
      run.create_ms = msSince(t0);
      run.summary = localizer->backendSummary();
      std::set<uint64_t> keyframes;
      for (int pass = -1; pass < a.runs; ++pass) {  // pass -1: warm-up (shader JIT, caches).
        localizer->reset(T_init);
        size_t next_imu = 0;
        const auto t_pass = std::chrono::steady_clock::now();
        for (size_t i = 0; i < n; ++i) {
          const int64_t t_ns = seq.images[i].t_ns;
          if (camera_pace) {
            // A camera delivers frame i (t_ns - t_first) after the first; the keyframe worker
            // uses the time between frames.
            std::this_thread::sleep_until(t_pass + std::chrono::nanoseconds(t_ns - seq.images[0].t_ns));
          }
          next_imu = feedSequenceImu(seq, next_imu, t_ns, *localizer);
          const LocalizationResult r = take(localizer->localize(t_ns, images[i]));
          if (pass < 0) {
            if (i == 0) run.first_frame_ms = r.total_ms;
            continue;
          }
          run.total.push_back(r.total_ms);
          run.render.push_back(r.render_ms);
          run.reference.push_back(r.reference_ms);
          run.live.push_back(r.live_ms);
          run.align.push_back(r.align_ms);
          run.age.push_back(static_cast<double>(r.keyframe_age_frames));
          keyframes.insert(r.keyframe_id);
          if (!r.reference_rendered) run.reused.push_back(r.total_ms);
          ++run.frames;
          run.lost += r.state == TrackingState::kLost;
          run.waited += r.reference_rendered;
          const auto it = gt.find(t_ns);
          if (it != gt.end() && r.state == TrackingState::kTracking) {
            run.t_err_mm.push_back((r.T_world_camera.translation() - it->second.translation()).norm() * 1e3);
            run.r_err_deg.push_back(rotationAngleDeg(it->second.linear().transpose() * r.T_world_camera.linear()));
          }
        }
        if (pass >= 0) run.wall_s += msSince(t_pass) * 1e-3;
        std::fprintf(stderr, "\r%s %s: pass %d of %d", backend.c_str(), mode.c_str(), pass + 2, a.runs + 1);
      }
      std::fprintf(stderr, "\n");
      const auto t_stats = computeErrorStats(run.t_err_mm);
      const auto r_stats = computeErrorStats(run.r_err_deg);
      const Stats latency = stats(run.total);
      const double passes = static_cast<double>(a.runs);
      std::printf(
          "%-7s %-6s %7.1f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %6.1f %6.1f %7.1f %7.1f %6.1f %8.3f "
          "%8.4f\n",
          backend.c_str(), mode.c_str(), run.wall_s > 0 ? static_cast<double>(run.frames) / run.wall_s : 0.0,
          latency.median, latency.p90, median(run.render), median(run.reference), median(run.live), median(run.align),
          median(run.reused), mean(run.age), static_cast<double>(run.waited) / passes,
          static_cast<double>(run.lost) / passes, run.create_ms, run.first_frame_ms,
          static_cast<double>(keyframes.size()) / passes, t_stats.mean, r_stats.mean);
      std::fflush(stdout);
      summaries.emplace_back(backend + " " + mode, run.summary);
    }
  }
  std::printf(
      "columns: fps = frames per second over the timed passes (throughput; images preloaded; the camera's rate "
      "with --pace camera); frame / p90 = "
      "latency of localize() (image in to pose out), median and 90th percentile, ms; render / ref.pts = keyframe "
      "render and edge points made on the caller's thread (0 when none), ms; live = pyramid, edges, distance "
      "fields; align = Gauss-Newton; reused = frames that made no keyframe; age = mean frames between a keyframe's "
      "pose and the frame tracked with it; waits = frames per pass that waited for a keyframe; lost per pass; "
      "create = Localizer::create, 1st = first frame of the warm-up pass (JIT), ms; kf = keyframes per pass; "
      "errors over every timed pass\n");
  for (const auto& [what, summary] : summaries) std::printf("%s: %s\n", what.c_str(), summary.c_str());
}

struct LiveBenchArgs {
  std::string sequence;
  int frame = -1;  // -1: the middle frame
  int levels = 2;
  int runs = 60;
  std::string distance = "auto";
  bool no_vulkan = false;
  DeviceArgs device;
};

/// Median, p10 and p90 of CPU buildLiveFrame runs (ms) after a few untimed ones.
Stats timeCpuLiveFrame(const ImageU8& gray, const PinholeCamera& camera, const LiveFrameOptions& options, int runs) {
  LiveFrame cpu_frame;
  std::vector<double> cpu;
  const int warmup = 5;  // caches, thread pool start
  for (int i = -warmup; i < runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    check(buildLiveFrame(gray, camera, options, cpu_frame));
    if (i >= 0) cpu.push_back(msSince(t0));
  }
  return stats(cpu);
}

/// The image a one-frame bench uses: `frame`, or the middle one when it is negative. Failure
/// when the sequence has no image or fewer than frame + 1.
size_t benchFrameIndex(const Sequence& seq, const std::string& folder, int frame) {
  if (seq.images.empty()) throw Failure{fmt::format("{}: images.txt lists no image", folder)};
  const size_t index = frame < 0 ? seq.images.size() / 2 : static_cast<size_t>(frame);
  if (index >= seq.images.size()) {
    throw Failure{fmt::format("--frame {}: the sequence has {} images", frame, seq.images.size())};
  }
  return index;
}

void runLiveBench(const LiveBenchArgs& a) {
  const Sequence seq = take(loadSequence(a.sequence));
  const size_t index = benchFrameIndex(seq, a.sequence, a.frame);
  const PinholeCamera camera = sequenceCamera(seq);
  const ImageU8 gray = take(readImageU8(seq.imagePath(index), 1));
  LiveFrameOptions options;
  options.levels = a.levels;
  options.keep_intermediate = false;
  options.distance_gradient = false;  // as the tracker's (the alignment computes it where it reads it)
  if (a.no_vulkan) {
    const Stats c = timeCpuLiveFrame(gray, camera, options, a.runs);
    std::printf("%s frame %zu (%dx%d), %d levels; CPU only; medians of %d runs\n", seq.name.c_str(), index,
                camera.width, camera.height, options.levels, a.runs);
    std::printf("CPU frame (buildLiveFrame): median %.3f ms (p10 %.3f, p90 %.3f)\n", c.median, c.p10, c.p90);
    return;
  }
  const GpuDistanceMethod method = a.distance == "separable" ? GpuDistanceMethod::kSeparable
                                   : a.distance == "jfa"     ? GpuDistanceMethod::kJumpFlooding
                                                             : GpuDistanceMethod::kAuto;
  auto context = a.device.create();
  auto stages = take(GpuEdgeStages::create(context, camera, options, method));
  std::printf("%s frame %zu (%dx%d), %d levels; device %s (%s), distance %s, validation %s; medians of %d runs\n",
              seq.name.c_str(), index, camera.width, camera.height, stages->levelCount(),
              context->device().name.c_str(), context->device().type.c_str(),
              gpuDistanceMethodName(stages->distanceMethod()), context->validationEnabled() ? "ON (slower)" : "off",
              a.runs);
  const int warmup = 5;  // shader JIT on lavapipe, caches
  std::vector<double> untimed;
  for (int i = -warmup; i < a.runs; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    check(stages->processLiveImage(gray));
    if (i >= 0) untimed.push_back(msSince(t0));
  }
  // Per-stage device times: timestamps between stages (each drains lavapipe's queue, so their
  // sum exceeds the untimed frame there).
  stages->setStageTimings(true);
  std::vector<std::pair<std::string, std::vector<double>>> per_stage;
  for (int i = 0; i < a.runs; ++i) {
    check(stages->processLiveImage(gray));
    for (const GpuStageTiming& t : stages->lastTimings()) {
      auto it = std::find_if(per_stage.begin(), per_stage.end(), [&](const auto& s) { return s.first == t.stage; });
      if (it == per_stage.end()) it = per_stage.insert(per_stage.end(), {t.stage, {}});
      it->second.push_back(t.ms);
    }
  }
  const Stats c = timeCpuLiveFrame(gray, camera, options, a.runs);
  double stage_sum = 0;
  std::printf("GPU stages (device time, ms):\n");
  for (const auto& [stage, ms] : per_stage) {
    stage_sum += median(ms);
    std::printf("  %-20s %8.3f\n", stage.c_str(), median(ms));
  }
  std::printf("  %-20s %8.3f (with a timestamp after every stage)\n", "sum", stage_sum);
  const Stats g = stats(untimed);
  std::printf("GPU frame, host wall (no timestamps): median %.3f ms (p10 %.3f, p90 %.3f)\n", g.median, g.p10, g.p90);
  std::printf("CPU frame (buildLiveFrame):           median %.3f ms (p10 %.3f, p90 %.3f)\n", c.median, c.p10, c.p90);
  std::printf("GPU / CPU (medians): %.2f\n", g.median / c.median);
}

struct KeyframeBenchArgs {
  std::string sequence;
  int frame = -1;  // -1: the middle frame
  int runs = 60;
  bool no_vulkan = false;
  DeviceArgs device;
};

/// A keyframe's two halves at one frame's ground-truth pose: the render (colour, depth, normals)
/// and the reference edge points built from it on the CPU, on one thread (the worker mode's
/// keyframe thread) and on the thread pool (the synchronous mode), runs interleaved.
void runKeyframeBench(const KeyframeBenchArgs& a) {
  const Sequence seq = take(loadSequence(a.sequence));
  const size_t index = benchFrameIndex(seq, a.sequence, a.frame);
  const int64_t t_ns = seq.images[index].t_ns;
  const auto gt = std::find_if(seq.groundtruth.begin(), seq.groundtruth.end(),
                               [&](const StampedPose& g) { return g.t_ns == t_ns; });
  if (gt == seq.groundtruth.end()) {
    throw Failure{fmt::format("{}: no ground-truth pose at image {} (t = {} ns)", a.sequence, index, t_ns)};
  }
  const Pose T_world_camera = gt->T_world_camera;
  const PinholeCamera camera = sequenceCamera(seq);
  const Model model = loadSequenceModel(seq);
  std::unique_ptr<Renderer> renderer;
  std::string device = "CPU reference renderer";
  if (!a.no_vulkan) {
    auto accelerator = take(makeGpuAccelerator(a.device.create()));
    renderer = take(accelerator->createRenderer(model));
    device = accelerator->describe();
  } else {
    renderer = take(CpuRenderer::create(model));
  }
  const LocalizerOptions defaults;
  RenderSettings settings = defaults.render;
  settings.outputs = kRenderAll;
  const int warmup = 3;  // shader JIT, caches, thread pool start
  // The CPU rasterizer on one thread (the worker mode's keyframe thread) and with a band of rows
  // per core (the synchronous mode); a GPU renderer ignores the count.
  const int cores = availableCores();
  std::vector<int> thread_counts{1};
  if (a.no_vulkan && cores > 1) thread_counts.push_back(cores);
  std::vector<double> render_ms, render_cores_ms, serial_ms, parallel_ms;
  RenderOutput view;
  for (int i = -warmup; i < a.runs; ++i) {
    for (const int threads : thread_counts) {
      settings.threads = threads;
      const auto t0 = std::chrono::steady_clock::now();
      view = take(renderer->render(camera, T_world_camera, settings));
      if (i >= 0) (threads == 1 ? render_ms : render_cores_ms).push_back(msSince(t0));
    }
  }
  size_t points = 0, coarse = 0;
  for (int i = -warmup; i < a.runs; ++i) {
    for (const bool parallel : {false, true}) {
      // The default options' levels (3) are what the Localizer builds with its default
      // max_search_level (Localizer::create sets reference.levels = live.levels).
      ReferenceEdgeOptions options = defaults.reference;
      options.parallel = parallel;
      RenderOutput copy = view;  // the keyframe hands its render over (moved, not copied)
      const auto t0 = std::chrono::steady_clock::now();
      const EdgeReference reference = take(buildEdgeReference(std::move(copy), camera, T_world_camera, options));
      if (i < 0) continue;
      (parallel ? parallel_ms : serial_ms).push_back(msSince(t0));
      points = reference.points.size();
      coarse = 0;
      for (const auto& level : reference.coarse_points) coarse += level.size();
    }
  }
  std::printf("%s frame %zu (%dx%d) at its true pose, model %zu triangles; %s; medians of %d runs\n", seq.name.c_str(),
              index, camera.width, camera.height, model.triangleCount(), device.c_str(), a.runs);
  auto line = [](const char* what, const std::vector<double>& ms) {
    const Stats st = stats(ms);
    std::printf("  %-34s %7.3f ms (p10 %.3f, p90 %.3f)\n", what, st.median, st.p10, st.p90);
  };
  line("render (colour, depth, normals)", render_ms);
  if (!render_cores_ms.empty()) line(fmt::format("the same, {} threads (sync)", cores).c_str(), render_cores_ms);
  line("edge points, one thread (worker)", serial_ms);
  line("edge points, thread pool (sync)", parallel_ms);
  std::printf("  %zu edge points at level 0, %zu at the coarser levels\n", points, coarse);
}

}  // namespace

static void addBenchVerb(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Benchmarks (median of many runs)");
  bench->require_subcommand(1);
  auto args = std::make_shared<BenchArgs>();
  CLI::App* render = bench->add_subcommand("render", "Render the demo city at ~10k, 100k and 1M triangles");
  args->device.add(*render);
  args->camera.add(*render);
  render->add_option("--triangles", args->triangles, "Model sizes (triangles)")->delimiter(',')->capture_default_str();
  render->add_option("--runs", args->runs, "Timed runs per case")->check(CLI::Range(1, 100000))->capture_default_str();
  render->add_option("--warmup", args->warmup, "Untimed runs first (JIT, caches)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  render->add_option("--reference-runs", args->reference_runs, "CPU reference runs (models up to 200k triangles)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  render->add_flag("!--no-cull", args->cull, "Disable back-face culling");
  render
      ->add_option("--roughness", args->roughness_m,
                   "Random vertex displacement of the enlarged models, metres (photogrammetry-like)")
      ->capture_default_str();
  render->add_option("--block-triangles", args->block_triangles, "Triangles per spatial block (culling granularity)")
      ->check(CLI::Range(0u, 1u << 30))
      ->capture_default_str();
  render->add_option("--lod-pixel-error", args->lod_pixel_error, "Level-of-detail error bound, pixels")
      ->capture_default_str();
  render->callback([args] { run(*args); });

  auto targs = std::make_shared<TrackBenchArgs>();
  CLI::App* track = bench->add_subcommand("track", "Per-frame localization time per stage and backend on a sequence");
  targs->device.add(*track);
  track->add_option("--sequence", targs->sequence, "Sequence folder (vkloc simulate / import)")->required();
  track->add_option("--backends", targs->backends, "Backends to compare, in one process")
      ->delimiter(',')
      ->check(CLI::IsMember({"auto", "cpu", "vulkan"}))
      ->capture_default_str();
  track->add_option("--keyframes", targs->keyframes, "Keyframe modes to compare: worker, sync")
      ->delimiter(',')
      ->check(CLI::IsMember({"worker", "sync"}))
      ->capture_default_str();
  track->add_option("--policy", targs->policy, "Re-render policy: every-frame | when-needed")
      ->check(CLI::IsMember({"every-frame", "when-needed"}))
      ->capture_default_str();
  track->add_option("--runs", targs->runs, "Timed passes over the frames")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  track->add_option("--frames", targs->max_frames, "Use only the first N frames (0 = all)")->capture_default_str();
  track
      ->add_option("--pace", targs->pace,
                   "none: each frame as soon as the last is done (throughput); camera: at its timestamp (a live "
                   "camera's latency)")
      ->check(CLI::IsMember({"none", "camera"}))
      ->capture_default_str();
  track->callback([targs] { runTrackBench(*targs); });

  auto largs = std::make_shared<LiveBenchArgs>();
  CLI::App* live = bench->add_subcommand(
      "live", "Live-image stages (pyramid, edges, distance fields) on one frame: per GPU stage, and GPU vs CPU");
  largs->device.add(*live);
  live->add_option("--sequence", largs->sequence, "Sequence folder (its camera and one of its images)")->required();
  live->add_option("--frame", largs->frame, "Image index (default: the middle one)");
  live->add_option("--levels", largs->levels, "Pyramid levels (the tracker's default options build 2)")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  live->add_option("--distance", largs->distance, "GPU distance transform: auto | separable | jfa")
      ->check(CLI::IsMember({"auto", "separable", "jfa"}))
      ->capture_default_str();
  live->add_option("--runs", largs->runs, "Timed runs")->check(CLI::Range(1, 100000))->capture_default_str();
  live->add_flag("--no-vulkan", largs->no_vulkan, "Time the CPU backend only (no device needed)");
  live->callback([largs] { runLiveBench(*largs); });

  auto kargs = std::make_shared<KeyframeBenchArgs>();
  CLI::App* keyframe = bench->add_subcommand(
      "keyframe", "A keyframe at one frame's true pose: render, and its edge points on one thread and on the pool");
  kargs->device.add(*keyframe);
  keyframe->add_option("--sequence", kargs->sequence, "Sequence folder with ground truth")->required();
  keyframe->add_option("--frame", kargs->frame, "Image index (default: the middle one)");
  keyframe->add_option("--runs", kargs->runs, "Timed runs")->check(CLI::Range(1, 100000))->capture_default_str();
  keyframe->add_flag("--no-vulkan", kargs->no_vulkan, "Render with the CPU reference rasterizer");
  keyframe->callback([kargs] { runKeyframeBench(*kargs); });

  addVerifyBench(*bench);
  addRelocBench(*bench);
  addRemapBench(*bench);
}

VKLOC_REGISTER_VERB(90, addBenchVerb);

}  // namespace vkloc::cli
