// vkloc bench remap: the remap stage that turns a lens image into the tracker's pinhole view
// (CameraFront), its speed and its agreement with the float references (remapBilinear,
// remapBicubic).
//  1. Undistortion of a EuRoC-like radial-tangential lens to a view of the same size and
//     intrinsics, bilinear: the CPU fast path (CameraFront::remap: OpenCV, cached fixed-point
//     maps), the reference (one thread), the exact table's build, and GpuRemap (wall and device
//     time, table upload). Then bicubic (CameraFront's default): the same CPU fast path with
//     INTER_CUBIC and replicated borders, remapBicubic, and GpuRemap's bicubic pipeline.
//  2. A stabilised view (480x360, hfov 90, pitch 45) of a 210-degree fisheye with a new attitude
//     every frame: the table on the grid plus OpenCV's remap, against the exact table; the grid
//     table's largest deviation from the exact one; bilinear and bicubic, CPU and GPU.
//  3. Agreement on a seeded test image: GPU and OpenCV against the reference of their
//     interpolation, both views.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>

#include "common.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/core/random.hpp"
#include "vkloc/core/remap.hpp"
#include "vkloc/engine/gpu_remap.hpp"
#include "vkloc/localize/camera_front.hpp"

namespace vkloc::cli {
namespace {

struct RemapBenchArgs {
  std::string size = "640x480";  ///< Undistortion: lens image and view size, "WxH".
  int runs = 200;                ///< Timed runs per stage, after kWarmup untimed ones.
  bool no_vulkan = false;        ///< Skip the GPU stages.
  DeviceArgs device;
  std::string csv;  ///< "" or a file for one row per stage.
};

constexpr int kWarmup = 5;          ///< Untimed runs first (shader JIT on lavapipe, caches).
constexpr int kTableBuildRuns = 5;  ///< Runs of the undistortion's one-off exactTable.
constexpr uint64_t kImageSeed = 1;  ///< Seed of the agreement test images.

struct Timing {
  double median = NAN, p90 = NAN;
  int runs = 0;
};

Timing timing(std::vector<double> ms) {
  Timing t;
  t.runs = static_cast<int>(ms.size());
  if (ms.empty()) return t;
  std::sort(ms.begin(), ms.end());
  auto q = [&](double f) { return ms[std::min(ms.size() - 1, static_cast<size_t>(f * (ms.size() - 1) + 0.5))]; };
  t.median = q(0.5);
  t.p90 = q(0.9);
  return t;
}

/// Runs `fn(i)` for i = -warmup .. runs - 1 and returns the durations of the runs i >= 0, ms.
template <typename F>
Timing timeRuns(int warmup, int runs, F&& fn) {
  std::vector<double> ms;
  ms.reserve(static_cast<size_t>(runs));
  for (int i = -warmup; i < runs; ++i) {
    const auto t0 = SteadyClock::now();
    fn(i);
    if (i >= 0) ms.push_back(msSince(t0));
  }
  return timing(std::move(ms));
}

/// How two images of one size differ, pixel by pixel.
struct Agreement {
  double within_1 = 0;  ///< Fraction of pixels that differ by at most 1 gray level.
  int max_diff = 0;     ///< Largest difference, gray levels.
  size_t differ = 0;    ///< Pixels that differ at all.
};

Agreement compare(const ImageU8& a, const ImageU8& b) {
  if (a.width != b.width || a.height != b.height || a.data.size() != b.data.size()) {
    throw Failure{fmt::format("agreement: images of {}x{} and {}x{}", a.width, a.height, b.width, b.height)};
  }
  Agreement r;
  size_t within = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const int d = std::abs(static_cast<int>(a.data[i]) - static_cast<int>(b.data[i]));
    within += d <= 1 ? 1 : 0;
    r.differ += d != 0 ? 1 : 0;
    r.max_diff = std::max(r.max_diff, d);
  }
  r.within_1 = a.data.empty() ? 1.0 : static_cast<double>(within) / static_cast<double>(a.data.size());
  return r;
}

std::string agreementNote(const Agreement& g) {
  return fmt::format("{:.3f} % within 1 gray level, max diff {}, {} px differ", 100.0 * g.within_1, g.max_diff,
                     g.differ);
}

/// A seeded gray image with natural-ish content: smooth gradients (a tilted ramp and two broad
/// waves) under a few dozen discs and turned rectangles whose edges ramp over 0.5..3 px (an
/// anti-aliased or defocused edge), some of them translucent.
ImageU8 testImage(int width, int height, uint64_t seed) {
  Xoshiro256 rng(seed);
  const double w = width, h = height;
  std::vector<double> v(static_cast<size_t>(width) * height);
  const double gx = rng.uniform(-60, 60), gy = rng.uniform(-60, 60);
  const double k1x = rng.uniform(0.5, 2.0), k1y = rng.uniform(0.5, 2.0), p1 = rng.uniform(0, 2 * M_PI);
  const double k2x = rng.uniform(1.0, 3.0), k2y = rng.uniform(-3.0, -1.0), p2 = rng.uniform(0, 2 * M_PI);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double sx = x / w, sy = y / h;
      v[static_cast<size_t>(y) * width + x] = 128 + gx * (sx - 0.5) + gy * (sy - 0.5) +
                                              25 * std::sin(2 * M_PI * (k1x * sx + k1y * sy) + p1) +
                                              15 * std::sin(2 * M_PI * (k2x * sx + k2y * sy) + p2);
    }
  }
  const double scale = std::min(w, h);
  for (int s = 0; s < 40; ++s) {
    const bool disc = rng.chance(0.5);
    const double cx = rng.uniform(0, w), cy = rng.uniform(0, h);
    const double rx = rng.uniform(0.02, 0.12) * scale, ry = disc ? rx : rng.uniform(0.02, 0.12) * scale;
    const double angle = rng.uniform(0, M_PI), ca = std::cos(angle), sa = std::sin(angle);
    const double value = rng.uniform(10, 245), alpha = rng.chance(0.3) ? rng.uniform(0.4, 0.8) : 1.0;
    const double ramp = rng.uniform(0.5, 3.0);  // edge width, pixels
    const double reach = std::max(rx, ry) * (disc ? 1.0 : M_SQRT2) + ramp + 1;
    const int x0 = std::max(0, static_cast<int>(std::floor(cx - reach)));
    const int x1 = std::min(width - 1, static_cast<int>(std::ceil(cx + reach)));
    const int y0 = std::max(0, static_cast<int>(std::floor(cy - reach)));
    const int y1 = std::min(height - 1, static_cast<int>(std::ceil(cy + reach)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        // Signed distance to the shape's outline, pixels (negative inside).
        double d;
        if (disc) {
          d = std::hypot(x - cx, y - cy) - rx;
        } else {
          const double lx = std::abs(ca * (x - cx) + sa * (y - cy)) - rx;
          const double ly = std::abs(-sa * (x - cx) + ca * (y - cy)) - ry;
          d = std::hypot(std::max(lx, 0.0), std::max(ly, 0.0)) + std::min(std::max(lx, ly), 0.0);
        }
        const double cover = alpha * std::clamp(0.5 - d / ramp, 0.0, 1.0);
        double& p = v[static_cast<size_t>(y) * width + x];
        p = (1 - cover) * p + cover * value;
      }
    }
  }
  ImageU8 image(width, height, 1);
  for (size_t i = 0; i < v.size(); ++i) image.data[i] = static_cast<uint8_t>(std::clamp(std::lround(v[i]), 0L, 255L));
  return image;
}

/// The EuRoC-like lens: fx = fy = 0.8203 width (525 at 640), centred, radial-tangential.
LensCamera eurocLikeLens(int width, int height) {
  LensCamera lens;
  lens.model = LensModel::kPinhole;
  const double f = 0.8203 * width;
  lens.intrinsics = PinholeCamera{f, f, 0.5 * (width - 1), 0.5 * (height - 1), width, height};
  lens.k = {-0.28, 0.074, 2e-4, 1.8e-5, 0};
  return lens;
}

/// A 210-degree equidistant fisheye on an 800x800 sensor.
LensCamera fisheyeLens() {
  LensCamera lens;
  lens.model = LensModel::kKannalaBrandt;
  lens.intrinsics = PinholeCamera{200, 200, 399.5, 399.5, 800, 800};
  lens.k = {0.02, -0.005, 0.001, -0.0001, 0};
  lens.max_angle_deg = 105;
  return lens;
}

/// Frame i's attitude of a drone camera: heading along world +y, looking 45 deg down (up_world
/// = +z), rolled about its optical axis by 0.2 sin(i) rad, so that every frame has a new one.
Eigen::Matrix3d droneAttitude(int i) {
  const Eigen::Vector3d up(0, 0, 1), heading(0, 1, 0);
  const double pitch = M_PI / 4;
  Eigen::Matrix3d R_world_camera;
  const Eigen::Vector3d z = std::cos(pitch) * heading - std::sin(pitch) * up;
  const Eigen::Vector3d x = heading.cross(up).normalized();
  R_world_camera.col(0) = x;
  R_world_camera.col(1) = z.cross(x);
  R_world_camera.col(2) = z;
  return R_world_camera * Eigen::AngleAxisd(0.2 * std::sin(i), Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

bool hasSource(const float* uv, const RemapTable& t) {
  return std::isfinite(uv[0]) && std::isfinite(uv[1]) && uv[0] >= 0 && uv[1] >= 0 && uv[0] <= t.source_width - 1 &&
         uv[1] <= t.source_height - 1;
}

/// Largest distance between the two tables' source positions where both have one, pixels; counts
/// the pixels where only one has a source in `mismatched`.
double maxDeviation(const RemapTable& a, const RemapTable& b, size_t& mismatched) {
  double worst = 0;
  for (size_t i = 0; i + 1 < a.uv.size() && i + 1 < b.uv.size(); i += 2) {
    const bool in_a = hasSource(&a.uv[i], a), in_b = hasSource(&b.uv[i], b);
    if (in_a != in_b) {
      ++mismatched;
    } else if (in_a) {
      worst = std::max(
          worst, std::hypot(static_cast<double>(a.uv[i]) - b.uv[i], static_cast<double>(a.uv[i + 1]) - b.uv[i + 1]));
    }
  }
  return worst;
}

/// Prints the table row by row (and the CSV) as the stages finish.
class Report {
 public:
  explicit Report(const std::string& csv_path) {
    if (!csv_path.empty()) {
      csv_ = take(PartialFileWriter::open(csv_path));
      check(csv_->appendLine("stage,median_ms,p90_ms,runs,notes"));
    }
    std::printf("%-50s %9s %9s  %s\n", "stage", "median ms", "p90 ms", "notes");
  }
  void row(const std::string& stage, const Timing& t, const std::string& notes) {
    const bool timed = t.runs > 0;
    std::printf("%-50s %9s %9s  %s\n", stage.c_str(), timed ? fmt::format("{:.3f}", t.median).c_str() : "-",
                timed ? fmt::format("{:.3f}", t.p90).c_str() : "-", notes.c_str());
    std::fflush(stdout);
    if (csv_) {
      std::string quoted = notes;
      for (size_t p = quoted.find('"'); p != std::string::npos; p = quoted.find('"', p + 2)) quoted.insert(p, "\"");
      check(csv_->appendLine(timed ? fmt::format("{},{:.4f},{:.4f},{},\"{}\"", stage, t.median, t.p90, t.runs, quoted)
                                   : fmt::format("{},,,0,\"{}\"", stage, quoted)));
    }
  }
  void commit() {
    if (csv_) check(csv_->commit());
  }

 private:
  std::unique_ptr<PartialFileWriter> csv_;
};

/// The GpuRemap for `table`, or null with the reason in `skip` when the device cannot hold it.
std::unique_ptr<GpuRemap> makeGpuRemap(const std::shared_ptr<GpuContext>& context, const RemapTable& table,
                                       RemapInterpolation interpolation, std::string& skip) {
  if (!context) return nullptr;
  auto gpu = GpuRemap::create(context, table, interpolation);
  if (!gpu.ok() && gpu.error().code == ErrorCode::kUnsupported) {
    skip = "skipped: " + gpu.error().message;
    return nullptr;
  }
  return take(std::move(gpu));
}

void runRemapBench(const RemapBenchArgs& a) {
  int width = 0, height = 0;
  char x = 0, extra = 0;
  if (std::sscanf(a.size.c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 || (x != 'x' && x != 'X') ||
      width < 16 || height < 16 || width > 16384 || height > 16384) {
    throw Failure{fmt::format("--size '{}': expected WxH, each 16..16384, e.g. 640x480", a.size)};
  }
  std::shared_ptr<GpuContext> context;
  std::string gpu_skip = "skipped (--no-vulkan)";
  if (!a.no_vulkan) {
    try {
      context = a.device.create();
    } catch (const Failure& f) {
      // A device asked for by name must exist; without one asked for, the GPU rows are skipped.
      if (!a.device.device.empty() || std::getenv("VKLOC_DEVICE") != nullptr) throw;
      gpu_skip = "skipped: " + f.message;
    }
  }
  const int runs = a.runs;
  std::printf("bench remap: %s; %d timed runs after %d warm-up, ms per frame\n",
              context       ? fmt::format("device {} ({})", context->device().name, context->device().type).c_str()
              : a.no_vulkan ? "GPU stages skipped (--no-vulkan)"
                            : "no Vulkan device, GPU stages skipped",
              runs, kWarmup);
  Report report(a.csv);

  // 1. Undistortion.
  const LensCamera lens = eurocLikeLens(width, height);
  ViewOptions undistorted_bilinear;
  undistorted_bilinear.interpolation = RemapInterpolation::kBilinear;
  auto undistort = take(CameraFront::create(lens, undistorted_bilinear));
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const ImageU8 lens_image = testImage(width, height, kImageSeed);
  ImageU8 view_image;
  const std::string what = fmt::format("{}x{}", width, height);
  const Timing t_fast = timeRuns(kWarmup, runs, [&](int) { check(undistort->remap(lens_image, I, view_image)); });
  report.row("undistort: CameraFront::remap (OpenCV)", t_fast,
             fmt::format("{} -> {}, cached fixed-point maps (1/32 px), bilinear", what, what));
  const RemapTable& table = undistort->table(I);
  ImageU8 reference;
  const Timing t_ref =
      timeRuns(std::min(kWarmup, 2), runs, [&](int) { reference = take(remapBilinear(lens_image, table)); });
  report.row("undistort: remapBilinear (reference)", t_ref,
             fmt::format("float, one thread; {:.1f}x the fast path", t_ref.median / t_fast.median));
  RemapTable exact;
  const Timing t_build = timeRuns(1, kTableBuildRuns, [&](int) { exact = undistort->exactTable(I); });
  report.row("undistort: exactTable", t_build,
             fmt::format("once per lens (every pixel projected); {} runs", kTableBuildRuns));

  std::string undistort_skip = gpu_skip;
  auto gpu = makeGpuRemap(context, table, RemapInterpolation::kBilinear, undistort_skip);
  Timing t_gpu, t_gpu_device, t_set;
  ImageU8 gpu_image;
  if (gpu) {
    std::vector<double> device_ms;
    t_gpu = timeRuns(kWarmup, runs, [&](int i) {
      gpu_image = take(gpu->remap(lens_image));
      if (i >= 0) device_ms.push_back(gpu->lastGpuMs());
    });
    t_gpu_device = timing(std::move(device_ms));
    t_set = timeRuns(kWarmup, runs, [&](int) { check(gpu->setTable(table)); });
    report.row("undistort: GpuRemap::remap, wall", t_gpu,
               fmt::format("upload {:.2f} MiB, dispatch, read back", lens_image.data.size() / 1048576.0));
    report.row("undistort: GpuRemap::remap, device", t_gpu_device, "lastGpuMs (timestamps around the dispatch)");
    report.row("undistort: GpuRemap::setTable", t_set,
               fmt::format("{:.2f} MiB table upload, once per lens", table.uv.size() * sizeof(float) / 1048576.0));
  } else {
    report.row("undistort: GpuRemap", Timing{}, undistort_skip);
  }

  // 1b. Undistortion, bicubic: CameraFront's default (remapBicubicFixedRows on OpenCV's threads:
  // positions in 1/32 px, 14-bit weights, replicated borders, pixels without a source 0), the
  // reference and the GPU's bicubic pipeline.
  ViewOptions undistorted_bicubic;
  undistorted_bicubic.interpolation = RemapInterpolation::kBicubic;
  auto undistort_cubic = take(CameraFront::create(lens, undistorted_bicubic));
  ImageU8 view_cubic;
  const Timing t_fast_cubic =
      timeRuns(kWarmup, runs, [&](int) { check(undistort_cubic->remap(lens_image, I, view_cubic)); });
  report.row("undistort bicubic: CameraFront::remap (fixed point)", t_fast_cubic,
             fmt::format("positions in 1/32 px, 14-bit weights, {}, OpenCV's {} threads; {:.1f}x bilinear",
                         remapBicubicFixedKernel(), cv::getNumThreads(), t_fast_cubic.median / t_fast.median));
  ImageU8 reference_cubic;
  const Timing t_ref_cubic =
      timeRuns(std::min(kWarmup, 2), runs, [&](int) { reference_cubic = take(remapBicubic(lens_image, table)); });
  report.row("undistort bicubic: remapBicubic (reference)", t_ref_cubic,
             fmt::format("float, one thread; {:.1f}x the fast path", t_ref_cubic.median / t_fast_cubic.median));
  std::string cubic_skip = gpu_skip;
  auto gpu_cubic = makeGpuRemap(context, table, RemapInterpolation::kBicubic, cubic_skip);
  Timing t_gpu_cubic, t_gpu_cubic_device;
  ImageU8 gpu_cubic_image;
  if (gpu_cubic) {
    std::vector<double> device_ms;
    t_gpu_cubic = timeRuns(kWarmup, runs, [&](int i) {
      gpu_cubic_image = take(gpu_cubic->remap(lens_image));
      if (i >= 0) device_ms.push_back(gpu_cubic->lastGpuMs());
    });
    t_gpu_cubic_device = timing(std::move(device_ms));
    report.row("undistort bicubic: GpuRemap::remap, wall", t_gpu_cubic,
               fmt::format("16 taps per pixel; {:.1f}x bilinear", t_gpu_cubic.median / t_gpu.median));
    report.row("undistort bicubic: GpuRemap::remap, device", t_gpu_cubic_device,
               fmt::format("lastGpuMs; {:.1f}x bilinear", t_gpu_cubic_device.median / t_gpu_device.median));
  } else {
    report.row("undistort bicubic: GpuRemap", Timing{}, cubic_skip);
  }

  // 2. Stabilised view of a fisheye, a new attitude every frame.
  ViewOptions stabilised;
  stabilised.kind = ViewKind::kStabilised;
  stabilised.width = 480;
  stabilised.height = 360;
  stabilised.hfov_deg = 90;
  stabilised.pitch_deg = 45;
  stabilised.dead_band_deg = 0;  // every frame turned: a new table each time
  stabilised.up_world = Eigen::Vector3d(0, 0, 1);
  stabilised.interpolation = RemapInterpolation::kBilinear;
  const LensCamera fisheye = fisheyeLens();
  auto front = take(CameraFront::create(fisheye, stabilised));
  const ImageU8 fisheye_image = testImage(fisheye.intrinsics.width, fisheye.intrinsics.height, kImageSeed + 1);
  ImageU8 stab_view;
  std::vector<double> grid_ms, cv_ms, frame_ms, exact_ms;
  double worst_px = 0;
  size_t mismatched = 0;
  for (int i = -kWarmup; i < runs; ++i) {
    const Eigen::Matrix3d R_camera_view = front->viewRotation(droneAttitude(i));
    const auto t0 = SteadyClock::now();
    const RemapTable& grid_table = front->table(R_camera_view);
    const double grid = msSince(t0);
    const auto t1 = SteadyClock::now();
    check(front->remap(fisheye_image, R_camera_view, stab_view));  // the table above, cached
    const double remap = msSince(t1);
    const auto t2 = SteadyClock::now();
    const RemapTable exact_table = front->exactTable(R_camera_view);
    const double exact_build = msSince(t2);
    worst_px = std::max(worst_px, maxDeviation(grid_table, exact_table, mismatched));
    if (i < 0) continue;
    grid_ms.push_back(grid);
    cv_ms.push_back(remap);
    frame_ms.push_back(grid + remap);
    exact_ms.push_back(exact_build);
  }
  const std::string stab_what =
      fmt::format("800x800 fisheye (210 deg) -> 480x360, hfov 90, pitch 45, grid {} px", stabilised.grid_step_px);
  report.row("stabilised: CameraFront::table (grid)", timing(grid_ms), stab_what);
  report.row("stabilised: OpenCV remap (float table)", timing(cv_ms), "CameraFront::remap with the table built");
  const Timing t_frame = timing(frame_ms);
  report.row("stabilised: grid table + OpenCV remap", t_frame, "per frame, new attitude each frame");
  const Timing t_exact = timing(exact_ms);
  report.row("stabilised: exactTable", t_exact,
             fmt::format("every pixel projected; grid table deviates up to {:.4f} px{}", worst_px,
                         mismatched > 0 ? fmt::format(", {} px with a source in one only", mismatched) : ""));
  std::string stab_skip = gpu_skip;
  auto stab_gpu = makeGpuRemap(context, front->table(front->viewRotation(droneAttitude(0))),
                               RemapInterpolation::kBilinear, stab_skip);
  Timing t_stab_gpu;
  if (stab_gpu) {
    t_stab_gpu = timeRuns(kWarmup, runs, [&](int i) {
      check(stab_gpu->setTable(front->table(front->viewRotation(droneAttitude(i)))));
      (void)take(stab_gpu->remap(fisheye_image));
    });
    report.row("stabilised: grid table + GPU setTable + remap", t_stab_gpu, "per frame, wall");
  } else {
    report.row("stabilised: GpuRemap", Timing{}, stab_skip);
  }
  // Bicubic: a front of its own (its table on the grid, the fixed-point path reading the float
  // table), and the GPU's bicubic pipeline fed the same tables.
  ViewOptions stabilised_bicubic = stabilised;
  stabilised_bicubic.interpolation = RemapInterpolation::kBicubic;
  auto front_cubic = take(CameraFront::create(fisheye, stabilised_bicubic));
  ImageU8 stab_view_cubic;
  const Timing t_frame_cubic = timeRuns(kWarmup, runs, [&](int i) {
    check(front_cubic->remap(fisheye_image, front_cubic->viewRotation(droneAttitude(i)), stab_view_cubic));
  });
  report.row("stabilised bicubic: grid table + fixed-point remap", t_frame_cubic,
             fmt::format("per frame; {:.1f}x bilinear", t_frame_cubic.median / t_frame.median));
  std::string stab_cubic_skip = gpu_skip;
  auto stab_gpu_cubic = makeGpuRemap(context, front_cubic->table(front_cubic->viewRotation(droneAttitude(0))),
                                     RemapInterpolation::kBicubic, stab_cubic_skip);
  if (stab_gpu_cubic) {
    const Timing t = timeRuns(kWarmup, runs, [&](int i) {
      check(stab_gpu_cubic->setTable(front_cubic->table(front_cubic->viewRotation(droneAttitude(i)))));
      (void)take(stab_gpu_cubic->remap(fisheye_image));
    });
    report.row("stabilised bicubic: grid + GPU setTable + remap", t, "per frame, wall");
  } else {
    report.row("stabilised bicubic: GpuRemap", Timing{}, stab_cubic_skip);
  }

  // 3. Agreement with the reference on the seeded test images.
  const Agreement cv_undistort = compare(view_image, reference);
  const Eigen::Matrix3d R_last = front->viewRotation(droneAttitude(runs));
  check(front->remap(fisheye_image, R_last, stab_view));
  const RemapTable& stab_table = front->table(R_last);
  const ImageU8 stab_reference = take(remapBilinear(fisheye_image, stab_table));
  const Agreement cv_stab = compare(stab_view, stab_reference);
  std::optional<Agreement> gpu_undistort, gpu_stab;
  if (gpu) {
    gpu_undistort = compare(gpu_image, reference);
    report.row("agreement undistort: GPU vs reference", Timing{}, agreementNote(*gpu_undistort));
  }
  report.row("agreement undistort: OpenCV vs reference", Timing{}, agreementNote(cv_undistort));
  if (stab_gpu) {
    check(stab_gpu->setTable(stab_table));
    gpu_stab = compare(take(stab_gpu->remap(fisheye_image)), stab_reference);
    report.row("agreement stabilised: GPU vs reference", Timing{}, agreementNote(*gpu_stab));
  }
  report.row("agreement stabilised: OpenCV vs reference", Timing{}, agreementNote(cv_stab));
  // Bicubic against remapBicubic: the GPU's pipeline and the CPU's fixed-point path (pixels
  // without a source are 0 in all three).
  std::optional<Agreement> gpu_cubic_undistort;
  if (gpu_cubic) {
    gpu_cubic_undistort = compare(gpu_cubic_image, reference_cubic);
    report.row("agreement undistort bicubic: GPU vs reference", Timing{}, agreementNote(*gpu_cubic_undistort));
  }
  const Agreement cv_cubic_undistort = compare(view_cubic, reference_cubic);
  report.row("agreement undistort bicubic: fixed vs reference", Timing{}, agreementNote(cv_cubic_undistort));
  check(front_cubic->remap(fisheye_image, R_last, stab_view_cubic));
  const RemapTable& stab_table_cubic = front_cubic->table(R_last);
  const ImageU8 stab_reference_cubic = take(remapBicubic(fisheye_image, stab_table_cubic));
  if (stab_gpu_cubic) {
    check(stab_gpu_cubic->setTable(stab_table_cubic));
    report.row("agreement stabilised bicubic: GPU vs reference", Timing{},
               agreementNote(compare(take(stab_gpu_cubic->remap(fisheye_image)), stab_reference_cubic)));
  }
  report.row("agreement stabilised bicubic: fixed vs reference", Timing{},
             agreementNote(compare(stab_view_cubic, stab_reference_cubic)));
  report.commit();

  std::string gpu_summary = "GPU skipped";
  if (gpu) {
    gpu_summary = fmt::format("GPU {:.3f} ms wall ({:.3f} ms device), {}", t_gpu.median, t_gpu_device.median,
                              gpu_undistort->max_diff == 0
                                  ? "equal to the reference"
                                  : fmt::format("max diff {} from the reference", gpu_undistort->max_diff));
  }
  std::printf(
      "summary: undistort %s: CPU fast path %.3f ms (reference %.3f ms, %.1fx), %s; stabilised per frame %.3f ms "
      "(grid) vs %.3f ms (exact table), grid error <= %.4f px; OpenCV within 1 gray level of the reference on "
      "%.2f %% of pixels (max diff %d)\n",
      what.c_str(), t_fast.median, t_ref.median, t_ref.median / t_fast.median, gpu_summary.c_str(), t_frame.median,
      t_exact.median, worst_px, 100.0 * cv_undistort.within_1, cv_undistort.max_diff);
  std::string gpu_cubic_summary = "GPU skipped";
  if (gpu_cubic) {
    gpu_cubic_summary =
        fmt::format("GPU {:.3f} ms wall ({:.3f} ms device), {}", t_gpu_cubic.median, t_gpu_cubic_device.median,
                    gpu_cubic_undistort->max_diff == 0
                        ? "equal to the reference"
                        : fmt::format("max diff {} from the reference", gpu_cubic_undistort->max_diff));
  }
  std::printf(
      "summary bicubic: undistort %s: CPU fast path %.3f ms (reference %.3f ms), %s; stabilised per frame %.3f ms; "
      "fixed point within 1 gray level of the reference on %.2f %% of pixels (max diff %d)\n",
      what.c_str(), t_fast_cubic.median, t_ref_cubic.median, gpu_cubic_summary.c_str(), t_frame_cubic.median,
      100.0 * cv_cubic_undistort.within_1, cv_cubic_undistort.max_diff);
}

}  // namespace

void addRemapBench(CLI::App& bench) {
  auto args = std::make_shared<RemapBenchArgs>();
  CLI::App* remap = bench.add_subcommand(
      "remap", "Remap stage (lens image -> pinhole view): CPU, reference and GPU speed, and their agreement");
  remap->add_option("--size", args->size, "Undistortion: lens image and view size, WxH")->capture_default_str();
  remap->add_option("--runs", args->runs, "Timed runs per stage")->check(CLI::Range(1, 100000))->capture_default_str();
  remap->add_flag("--no-vulkan", args->no_vulkan, "Skip the GPU stages");
  args->device.add(*remap);
  remap->add_option("--csv", args->csv, "Write one row per stage");
  remap->callback([args] { runRemapBench(*args); });
}

}  // namespace vkloc::cli
