// Soak test of the Localizer (label "soak", not in the normal run): one Localizer (worker-thread
// keyframes, IMU filter, keyframe database) tracks a camera circling the three-box scene for
// VKLOC_SOAK_SECONDS (default 3600) of wall time, with forced losses and resets drawn from a
// seeded generator: black-outs (the IMU bridges them), jumps of the camera (relocalization
// finds it), resets with timestamps starting over, and global initializations. It checks that
// memory stays flat and frames do not get slower:
// - resident memory (/proc/self/statm): the median of the last 10 % of the samples is at most
//   kMaxRssGrowthMiB above the median of the first 10 %;
// - time of a tracked frame: the median of the last 10 % of the tracked frames is at most
//   kMaxTimeRatio times the median of the first 10 %, in process CPU time (all threads: the
//   caller's, the keyframe worker's, OpenCV's), which the load of other programs on the machine
//   changes much less than the wall time (also printed);
// and that the losses were recovered from (most frames tracked, relocalizations happened).
// A line of figures is printed every minute; VKLOC_SOAK_LOG names a CSV file for the samples.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "localize/localize_scene.hpp"
#include "vkloc/localize/keyframe_database.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/render/cpu_renderer.hpp"

namespace vkloc {
namespace {

constexpr double kMaxRssGrowthMiB = 16.0;  // end vs start, medians of 10 % of the samples
constexpr double kMaxTimeRatio = 1.5;      // median tracked-frame time, last 10 % / first 10 %
constexpr int kFramesPerTurn = 360;        // 1 degree per frame
constexpr int64_t kFrameNs = 50'000'000;   // 20 Hz
constexpr int64_t kImuNs = 5'000'000;      // 200 Hz

double soakSeconds() {
  const char* s = std::getenv("VKLOC_SOAK_SECONDS");
  if (s == nullptr || *s == '\0') return 3600.0;
  const double v = std::atof(s);
  return v > 0 ? v : 3600.0;
}

/// Resident set size, MiB (/proc/self/statm, second field, pages).
double rssMiB() {
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

/// CPU time of the whole process, ms.
double processCpuMs() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

/// Median of the first (or last) tenth of `v`, at least one value.
double tenthMedian(const std::vector<double>& v, bool last) {
  const size_t n = std::max<size_t>(1, v.size() / 10);
  if (v.size() < n) return 0;
  return last ? median({v.end() - static_cast<std::ptrdiff_t>(n), v.end()})
              : median({v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n)});
}

/// The camera at angle step k (any integer; 1 degree a step) round the scene, as localizeTruth.
double angleAt(double k) { return -0.9 + M_PI / 180.0 * k; }
Pose truthAt(double k) {
  const double a = angleAt(k);
  return test::cameraLookingAt({2.0 * std::cos(a), 2.0 * std::sin(a), 1.2}, {0.0, 0.0, 0.15});
}

TEST(LocalizerSoak, FlatMemoryAndFrameTimeOverLossesAndResets) {
  const double seconds = soakSeconds();
  const Model model = test::makeAsymmetricScene();
  const PinholeCamera camera = test::localizeCamera();
  // The frames of one turn and the keyframe database, made before anything is measured.
  std::vector<ImageU8> frames;
  for (int k = 0; k < kFramesPerTurn; ++k) {
    Result<RenderOutput> view = renderReference(model, camera, truthAt(k));
    ASSERT_TRUE(view.ok()) << view.error().message;
    frames.push_back(view->gray);
  }
  std::shared_ptr<const KeyframeDatabase> database;
  {
    auto r0 = CpuRenderer::create(model);
    auto r1 = CpuRenderer::create(model);
    ASSERT_TRUE(r0.ok() && r1.ok());
    KeyframePlacement p;
    p.volume.min = {-2.2f, -2.2f, 1.0f};
    p.volume.max = {2.2f, 2.2f, 1.4f};
    p.spacing_m = 0.4;
    p.headings = 16;
    p.tilts_deg = {25.0, 40.0};
    p.max_back_face_fraction = 1.0;  // the analytic scenes' quads are not wound for culling
    std::vector<Renderer*> renderers{r0->get(), r1->get()};
    auto built = buildKeyframeDatabase(model, renderers, camera, p, RenderSettings{});
    ASSERT_TRUE(built.ok()) << built.error().message;
    database = std::make_shared<const KeyframeDatabase>(std::move(built).value());
  }
  LocalizerOptions options;
  options.keyframe_threading = KeyframeThreading::kWorkerThread;
  options.backend = LocalizerBackend::kCpu;
  auto created = Localizer::create(model, camera, options, nullptr);
  ASSERT_TRUE(created.ok()) << created.error().message;
  Localizer& localizer = **created;
  ASSERT_TRUE(localizer.setKeyframeDatabase(database).ok());

  // IMU of the circle at 1 degree per frame (rigid rotation about world z, gravity -z).
  const double w = M_PI / 180.0 / (kFrameNs * 1e-9);  // rad/s
  auto imuAt = [&](double k, int64_t t_ns) {
    const double a = angleAt(k);
    const Pose T = truthAt(k);
    ImuSample s;
    s.t_ns = t_ns;
    s.gyro_body = T.linear().transpose() * Eigen::Vector3d(0, 0, w);
    s.accel_body =
        T.linear().transpose() *
        (Eigen::Vector3d(-w * w * 2.0 * std::cos(a), -w * w * 2.0 * std::sin(a), 0.0) + Eigen::Vector3d(0, 0, 9.81));
    return s;
  };

  std::mt19937 rng(2026);
  const ImageU8 black(camera.width, camera.height, 1, 0);
  std::FILE* log = nullptr;
  if (const char* path = std::getenv("VKLOC_SOAK_LOG")) {
    log = std::fopen(path, "w");
    if (log) {
      std::fprintf(log,
                   "elapsed_s,frames,rss_mib,tracked_ms_median_recent,tracked_cpu_ms_median_recent,resets,losses,"
                   "relocalized\n");
    }
  }

  // State of the run: step index k of the camera (frame k % 360), time t, next IMU time.
  int64_t k = 0, t_ns = 0, imu_t_ns = 0;
  long frames_run = 0, tracked = 0, resets = 0, losses = 0, relocalized = 0, inertial = 0, no_content = 0;
  long searches = 0;
  std::vector<double> rss, tracked_ms, tracked_cpu_ms, recent_ms, recent_cpu_ms;
  localizer.reset(truthAt(0));
  const auto t_start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count(); };
  double next_report = 60.0;
  // Frames since the last event; tracked frames right after one are left out of the timing
  // (keyframe waits and searches are not the steady state compared here).
  int since_event = 0;

  auto frame = [&](const ImageU8& image, bool with_imu) {
    t_ns += kFrameNs;
    if (with_imu) {
      for (; imu_t_ns <= t_ns; imu_t_ns += kImuNs) {
        const double k_imu = static_cast<double>(k) - static_cast<double>(t_ns - imu_t_ns) / kFrameNs;
        (void)localizer.addImu(imuAt(k_imu, imu_t_ns));
      }
    } else {
      imu_t_ns = t_ns + kImuNs;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = processCpuMs();
    Result<LocalizationResult> r = localizer.localize(t_ns, image);
    const double cpu_ms = processCpuMs() - cpu0;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(r.ok()) << r.error().message;
    ++frames_run;
    ++since_event;
    tracked += r->state == TrackingState::kTracking;
    relocalized += r->state == TrackingState::kRelocalized;
    inertial += r->state == TrackingState::kInertial;
    no_content += r->image_content != ImageContent::kOk;
    if (r->state == TrackingState::kTracking && since_event > 10) {
      tracked_ms.push_back(ms);
      tracked_cpu_ms.push_back(cpu_ms);
      recent_ms.push_back(ms);
      recent_cpu_ms.push_back(cpu_ms);
    }
    if (frames_run % 50 == 0) rss.push_back(rssMiB());
  };

  while (elapsed() < seconds) {
    // An episode: 60-140 frames tracked on round the circle, then one event.
    const int run = std::uniform_int_distribution<int>(60, 140)(rng);
    for (int i = 0; i < run; ++i) {
      ++k;
      frame(frames[static_cast<size_t>(k % kFramesPerTurn)], true);
      if (::testing::Test::HasFatalFailure()) return;
    }
    since_event = 0;
    switch (std::uniform_int_distribution<int>(0, 3)(rng)) {
      case 0: {  // black-out: the camera moves on, the IMU bridges
        const int n = std::uniform_int_distribution<int>(2, 8)(rng);
        for (int i = 0; i < n; ++i) {
          ++k;
          frame(black, true);
        }
        ++losses;
        break;
      }
      case 1: {  // jump: frames skip 30-90 degrees ahead, no IMU across the gap
        k += std::uniform_int_distribution<int>(30, 90)(rng);
        frame(frames[static_cast<size_t>(k % kFramesPerTurn)], false);
        ++losses;
        break;
      }
      case 2: {  // reset at the true pose, timestamps start over
        localizer.reset(truthAt(static_cast<double>(k)));
        t_ns = 0;
        imu_t_ns = kImuNs;
        ++resets;
        break;
      }
      default: {  // global initialization over the whole database
        ASSERT_TRUE(localizer.startSearch(std::nullopt).ok());
        ++searches;
        break;
      }
    }
    if (::testing::Test::HasFatalFailure()) return;
    if (elapsed() >= next_report || elapsed() >= seconds) {
      const double m = median(recent_ms), cpu = median(recent_cpu_ms);
      std::printf(
          "soak %.0f s: %ld frames, RSS %.1f MiB, tracked frame median %.2f ms wall, %.2f ms CPU, %ld resets, %ld "
          "losses, %ld searches, %ld relocalized\n",
          elapsed(), frames_run, rssMiB(), m, cpu, resets, losses, searches, relocalized);
      std::fflush(stdout);
      if (log) {
        std::fprintf(log, "%.0f,%ld,%.2f,%.3f,%.3f,%ld,%ld,%ld\n", elapsed(), frames_run, rssMiB(), m, cpu, resets,
                     losses, relocalized);
        std::fflush(log);
      }
      recent_ms.clear();
      recent_cpu_ms.clear();
      next_report += 60.0;
    }
  }
  if (log) std::fclose(log);

  const double rss_first = tenthMedian(rss, false), rss_last = tenthMedian(rss, true);
  const double ms_first = tenthMedian(tracked_ms, false), ms_last = tenthMedian(tracked_ms, true);
  const double cpu_first = tenthMedian(tracked_cpu_ms, false), cpu_last = tenthMedian(tracked_cpu_ms, true);
  std::printf(
      "soak result: %.0f s, %ld frames (%ld tracked, %ld relocalized, %ld inertial, %ld with nothing to align), "
      "%ld resets, %ld losses (black-outs and jumps), %ld global searches;\n"
      "  RSS first 10 %% %.1f MiB, last 10 %% %.1f MiB (growth %.2f MiB, bound %.0f);\n"
      "  tracked frame median first 10 %% %.2f ms, last 10 %% %.2f ms of CPU time (ratio %.3f, bound %.2f);\n"
      "  wall time %.2f ms, %.2f ms (ratio %.3f)\n",
      elapsed(), frames_run, tracked, relocalized, inertial, no_content, resets, losses, searches, rss_first, rss_last,
      rss_last - rss_first, kMaxRssGrowthMiB, cpu_first, cpu_last, cpu_first > 0 ? cpu_last / cpu_first : 0.0,
      kMaxTimeRatio, ms_first, ms_last, ms_first > 0 ? ms_last / ms_first : 0.0);
  ASSERT_GE(rss.size(), 10u) << "too short a run to compare";
  ASSERT_GE(tracked_ms.size(), 100u) << "too few tracked frames to compare";
  EXPECT_LE(rss_last - rss_first, kMaxRssGrowthMiB);
  EXPECT_LE(cpu_last, kMaxTimeRatio * cpu_first);
  // The losses were recovered from: most frames tracked, relocalizations happened.
  EXPECT_GT(static_cast<double>(tracked + relocalized), 0.7 * static_cast<double>(frames_run));
  if (losses + searches > 5) {
    EXPECT_GT(relocalized, 0);
  }
}

}  // namespace
}  // namespace vkloc
