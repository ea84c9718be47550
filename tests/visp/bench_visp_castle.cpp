// vkloc_visp_bench: ViSP's model-based tracker (vpMbGenericTracker, Debian libvisp-dev 3.5) on
// visp-images-data's mbt-depth/Castle-simu, timed and scored against the ground truth, as the
// reference vkloc is compared with.
//
//   vkloc_visp_bench [--castle DIR] [--out DIR] [--mode edge|edge+klt|klt] [--runs N]
//                    [--frames N] [--init-offset dx,dy,dz,rx,ry,rz]
//                    [--vkloc auto,cpu,vulkan] [--vkloc-policy when-needed|every-frame]
//
// With --vkloc, vkloc's Localizer runs on the same in-memory frames in the same process after
// ViSP (same start pose), so the time ratio is measured in one run on one machine state.
//
// What it does, per mode:
// - Loads every Images/Image_NNNN.pgm (or .png; 640x480 gray) into memory with its ground truth
//   CameraPose/Camera_NNN.txt (cMo = T_camera_object, metres).
// - Builds the tracker as ViSP's own tests do (testGenericTracker.cpp, perfGenericTracker.cpp):
//   loadConfigFile(Config/chateau.xml), loadModel(Models/chateau.cao), then
//   loadModel(Models/cube.cao, false, T_object_cube) with T_object_cube =
//   [[-1,0,0,-0.2],[0,0,1,0.12],[0,1,0,-0.15]] (metres); initFromPose(first image, cMo_init)
//   where cMo_init is the first ground-truth pose, optionally perturbed; then track() on every
//   image, the first included (as ViSP's tests do).
// - Times each track() call with std::chrono::steady_clock: one warm-up pass (not counted), then
//   --runs passes, each with a freshly built tracker; reports the median (and mean, p90) over
//   all frames of all timed passes. Loading, configuration and initFromPose are not timed.
// - Scores the poses of the first timed pass (ViSP is deterministic here; the spread between
//   passes is printed) against the ground truth with world = object frame:
//   T_world_camera = inverse(cMo). Translation error = |p_est - p_gt| of the camera centre in the
//   object frame (mm), rotation error = angle of R_est^T R_gt (deg); both without alignment, as
//   `vkloc eval` computes its unaligned ATE. ViSP's tests use |t(cMo_est) - t(cMo_gt)| instead;
//   that figure is printed too.
// - A frame is lost when track() threw or its error exceeds --lost-mm or --lost-deg (default
//   50 mm / 5 deg: over 2.5 times the worst excursion, 19 mm / 1.9 deg, of edge tracking from
//   the ground-truth start); the sequence is lost when its last frame is.
// - Writes to --out: visp_<mode>.txt (TUM "t tx ty tz qx qy qz qw" of T_world_camera, t =
//   (image number - first number) / 30 s, as `vkloc import visp` stamps the frames, so that
//   `vkloc eval --estimate visp_edge.txt --sequence <imported Castle-simu>` evaluates it) and
//   visp_<mode>_frames.csv (a `vkloc eval --frames` log: t_ns, state, total_ms = median
//   track() time over the timed passes, plus per-frame errors and feature counts).
//
// Tracker settings (Castle-simu's Config/chateau.xml, read by loadConfigFile; ViSP 3.5 defaults
// for the rest; the program prints the values read back from the tracker):
// - Moving edges (vpMe): mask size 5 px, 180 masks (1 deg orientation step), search range 8 px
//   on each side of the projected edge along its normal, sample step 5 px between sites, old
//   (non-normalised) likelihood threshold 10000, contrast bounds mu1 = mu2 = 0.5, strip 2 px,
//   minimum sample step 4 px.
// - KLT (vpKltOpencv through OpenCV): max 10000 features, window 5 px, quality 0.01, min
//   distance 5 px, Harris k 0.02, block size 3, 3 pyramid levels, mask border 5 px, threshold
//   acceptation 0.5 (ViSP default).
// - Faces: appear at 85 deg, disappear at 89 deg between the view ray and the face normal;
//   near 0.01 m, far 2 m and field-of-view clipping; no scanline visibility test.
// - Pose optimisation (ViSP defaults): Gauss-Newton with Tukey M-estimator, gain lambda 1.0,
//   at most 30 iterations per frame; camera 700/700/320/240 (px, py, u0, v0) without distortion.
//
// --init-offset dx,dy,dz,rx,ry,rz perturbs the start in the camera frame: T_world_camera_init =
// T_world_camera_gt * [R(r), d], d in metres, r a rotation vector in degrees (its norm is the
// angle), so "0.02,0,0,0,0,5" is 2 cm to the right and 5 deg about the optical axis.
//
// Exit codes: 0 done, 1 bad input or a check failed (--max-mean-mm, --max-mean-deg), 2 bad
// command line.
#include <fmt/format.h>
#include <visp3/core/vpConfig.h>
#include <visp3/core/vpException.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/io/vpImageIo.h>
#include <visp3/klt/vpKltOpencv.h>
#include <visp3/mbt/vpMbGenericTracker.h>
#include <visp3/mbt/vpMbtXmlGenericParser.h>
#include <visp3/me/vpMe.h>

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/engine/gpu.hpp"
#include "vkloc/engine/gpu_accelerator.hpp"
#include "vkloc/eval/eval.hpp"
#include "vkloc/io/import.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/localize/localizer.hpp"
#include "vkloc/model/cao.hpp"

namespace {

namespace fs = std::filesystem;
using vkloc::Pose;

constexpr double kFrameRateHz = 30.0;  // `vkloc import visp` default, Hz.

struct BenchOptions {
  std::string castle_dir = "/usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu";  ///< Data folder.
  std::string out_dir;        ///< Where trajectories and frame logs go; nothing written when empty.
  std::string mode = "edge";  ///< "edge", "edge+klt" or "klt".
  int runs = 5;               ///< Timed passes over the sequence (after one warm-up pass).
  int frames = 0;             ///< Use only the first N images; 0 = all.
  std::string init_offset;    ///< "dx,dy,dz,rx,ry,rz": metres and degrees, camera frame.
  double lost_mm = 50.0;      ///< Translation error above which a frame is lost, mm.
  double lost_deg = 5.0;      ///< Rotation error above which a frame is lost, degrees.
  double max_mean_mm = 0.0;   ///< Fail when the mean translation error exceeds this, mm (0 = off).
  double max_mean_deg = 0.0;  ///< Fail when the mean rotation error exceeds this, deg (0 = off).
  /// vkloc backends run on the same frames in the same process after ViSP ("auto,cpu,vulkan";
  /// empty = ViSP only).
  std::string vkloc_backends;
  std::string vkloc_policy = "when-needed";  ///< Re-render policy of vkloc: when-needed | every-frame.
};

/// One image of the sequence with its ground truth.
struct Frame {
  int number = 0;                ///< NNNN of Image_NNNN.
  int64_t t_ns = 0;              ///< (number - first) / 30 Hz, nanoseconds.
  vpImage<unsigned char> image;  ///< Gray image.
  Pose T_camera_object_gt;       ///< Ground-truth cMo, metres.
};

/// Poses and timings of one pass over the sequence.
struct Pass {
  std::vector<Pose> T_camera_object;    ///< Estimated cMo per frame.
  std::vector<double> track_ms;         ///< Wall time of track(), ms.
  std::vector<bool> threw;              ///< track() threw a vpException.
  std::vector<unsigned> edge_features;  ///< Moving-edge sites used.
  std::vector<unsigned> klt_features;   ///< KLT points used.
  std::string first_exception;          ///< Message of the first exception, if any.
};

vpHomogeneousMatrix toVisp(const Pose& T) {
  vpHomogeneousMatrix M;
  for (unsigned r = 0; r < 4; ++r) {
    for (unsigned c = 0; c < 4; ++c) M[r][c] = T.matrix()(r, c);
  }
  return M;
}

Pose fromVisp(const vpHomogeneousMatrix& M) {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = M[r][c];
    t(r) = M[r][3];
  }
  // Re-orthonormalise against rounding in ViSP's exponential map.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = svd.matrixU() * svd.matrixV().transpose();
  Pose T = Pose::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

/// Reads the images and ground-truth poses of a Castle-simu-like folder.
vkloc::Result<std::vector<Frame>> loadCastle(const std::string& dir, int max_frames) {
  const fs::path images_dir = fs::path(dir) / "Images";
  std::error_code ec;
  if (!fs::is_directory(images_dir, ec)) {
    return vkloc::makeError(vkloc::ErrorCode::kNotFound, images_dir.string() + ": no such folder");
  }
  const std::regex name_re(R"(Image_(\d+)\.(pgm|png))");
  std::map<int, fs::path> images;
  for (const auto& entry : fs::directory_iterator(images_dir, ec)) {
    std::smatch m;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, m, name_re)) images.emplace(std::stoi(m[1].str()), entry.path());
  }
  if (images.empty()) {
    return vkloc::makeError(vkloc::ErrorCode::kNotFound, images_dir.string() + ": no Image_NNNN.pgm/png files");
  }
  std::vector<Frame> frames;
  const int first = images.begin()->first;
  for (const auto& [number, path] : images) {
    if (max_frames > 0 && static_cast<int>(frames.size()) >= max_frames) break;
    Frame frame;
    frame.number = number;
    frame.t_ns = std::llround(static_cast<double>(number - first) * 1e9 / kFrameRateHz);
    try {
      vpImageIo::read(frame.image, path.string());
    } catch (const vpException& e) {
      return vkloc::makeError(vkloc::ErrorCode::kMalformedInput, path.string() + ": " + e.getStringMessage());
    }
    if (frame.image.getWidth() == 0 || frame.image.getHeight() == 0) {
      return vkloc::makeError(vkloc::ErrorCode::kMalformedInput, path.string() + ": empty image");
    }
    const std::string pose_path = (fs::path(dir) / "CameraPose" / fmt::format("Camera_{:03d}.txt", number)).string();
    auto cMo = vkloc::loadVispPose(pose_path);
    if (!cMo) return cMo.error();
    frame.T_camera_object_gt = *cMo;
    frames.push_back(std::move(frame));
  }
  return frames;
}

int trackerType(const std::string& mode) {
  if (mode == "edge") return vpMbGenericTracker::EDGE_TRACKER;
  if (mode == "klt") return vpMbGenericTracker::KLT_TRACKER;
  return vpMbGenericTracker::EDGE_TRACKER | vpMbGenericTracker::KLT_TRACKER;
}

/// T_object_cube of ViSP's Castle-simu tests, metres.
vpHomogeneousMatrix castleCubePose() {
  vpHomogeneousMatrix T;
  T[0][0] = -1;
  T[0][3] = -0.2;
  T[1][1] = 0;
  T[1][2] = 1;
  T[1][3] = 0.12;
  T[2][1] = 1;
  T[2][2] = 0;
  T[2][3] = -0.15;
  return T;
}

/// Configures `tracker` as ViSP's Castle-simu tests do. Throws vpException on bad files. ViSP
/// 3.5's .cao loader prints its counts to std::cout even with verbose off; they are dropped.
void configureTracker(vpMbGenericTracker& tracker, const std::string& dir) {
  const fs::path base(dir);
  tracker.loadConfigFile((base / "Config" / "chateau.xml").string(), false);
  std::ostringstream sink;
  std::streambuf* const cout_buffer = std::cout.rdbuf(sink.rdbuf());
  try {
    tracker.loadModel((base / "Models" / "chateau.cao").string(), false);
    tracker.loadModel((base / "Models" / "cube.cao").string(), false, castleCubePose());
  } catch (...) {
    std::cout.rdbuf(cout_buffer);
    throw;
  }
  std::cout.rdbuf(cout_buffer);
}

void printSettings(const vpMbGenericTracker& tracker, const std::string& mode, const std::string& dir) {
  vpCameraParameters cam;
  tracker.getCameraParameters(cam);
  std::printf("camera: px %.1f py %.1f u0 %.1f v0 %.1f (no distortion)\n", cam.get_px(), cam.get_py(), cam.get_u0(),
              cam.get_v0());
  if (mode != "klt") {
    const vpMe me = tracker.getMovingEdge();
    std::printf(
        "moving edges: range %u px, sample step %.1f px, mask size %u, masks %u, threshold %.0f, mu1 %.2f, mu2 %.2f, "
        "strip %d, min sample step %.1f\n",
        me.getRange(), me.getSampleStep(), me.getMaskSize(), me.getMaskNumber(), me.getThreshold(), me.getMu1(),
        me.getMu2(), me.getStrip(), me.getMinSampleStep());
  }
  if (mode != "edge") {
    const vpKltOpencv klt = tracker.getKltOpencv();
    std::printf(
        "klt: max features %d, window %d px, quality %.3f, min distance %.1f px, harris %.3f, block %d, pyramid "
        "levels %d, mask border %u px, threshold acceptation %.2f\n",
        klt.getMaxFeatures(), klt.getWindowSize(), klt.getQuality(), klt.getMinDistance(), klt.getHarrisFreeParameter(),
        klt.getBlockSize(), klt.getPyramidLevels(), tracker.getKltMaskBorder(), tracker.getKltThresholdAcceptation());
  }
  // vpMbGenericTracker does not forward the clipping distances to its getters: read them from
  // the file the sub-tracker was configured with.
  vpMbtXmlGenericParser parser(vpMbtXmlGenericParser::EDGE_PARSER | vpMbtXmlGenericParser::KLT_PARSER);
  {
    std::ostringstream sink;  // The parser echoes every setting to std::cout.
    std::streambuf* const cout_buffer = std::cout.rdbuf(sink.rdbuf());
    try {
      parser.parse((fs::path(dir) / "Config" / "chateau.xml").string());
    } catch (...) {
      std::cout.rdbuf(cout_buffer);
      throw;
    }
    std::cout.rdbuf(cout_buffer);
  }
  std::printf(
      "faces: appear %.0f deg, disappear %.0f deg, near %.3f m, far %.3f m (chateau.xml), clipping flags %u; "
      "scanline visibility off; optimisation: lambda %.2f, max iterations %u\n",
      vpMath::deg(tracker.getAngleAppear()), vpMath::deg(tracker.getAngleDisappear()), parser.getNearClippingDistance(),
      parser.getFarClippingDistance(), tracker.getClipping(), tracker.getLambda(), tracker.getMaxIter());
}

/// One pass: a fresh tracker, initialised at `T_camera_object_init` on the first image, tracks
/// every frame. Throws vpException only from configuration (track() exceptions are recorded).
Pass runPass(const std::vector<Frame>& frames, const BenchOptions& options, const Pose& T_camera_object_init,
             bool print_settings) {
  vpMbGenericTracker tracker(1, trackerType(options.mode));
  configureTracker(tracker, options.castle_dir);
  if (print_settings) printSettings(tracker, options.mode, options.castle_dir);
  tracker.initFromPose(frames.front().image, toVisp(T_camera_object_init));
  Pass pass;
  for (const Frame& frame : frames) {
    bool threw = false;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      tracker.track(frame.image);
    } catch (const vpException& e) {
      threw = true;
      if (pass.first_exception.empty()) {
        pass.first_exception = fmt::format("frame {}: {}", frame.number, e.getStringMessage());
      }
    }
    const auto t1 = std::chrono::steady_clock::now();
    vpHomogeneousMatrix cMo;
    tracker.getPose(cMo);
    pass.T_camera_object.push_back(fromVisp(cMo));
    pass.track_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    pass.threw.push_back(threw);
    pass.edge_features.push_back(tracker.getNbFeaturesEdge());
    pass.klt_features.push_back(tracker.getNbFeaturesKlt());
  }
  return pass;
}

double rotationAngleDeg(const Eigen::Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

std::string modeTag(const std::string& mode) { return mode == "edge+klt" ? "edge_klt" : mode; }

vkloc::Status writeOutputs(const BenchOptions& options, const std::vector<Frame>& frames, const Pass& pass,
                           const std::vector<double>& median_ms, const std::vector<double>& t_err_mm,
                           const std::vector<double>& r_err_deg, const std::vector<bool>& tracked) {
  std::error_code ec;
  fs::create_directories(options.out_dir, ec);
  if (ec) return vkloc::makeError(vkloc::ErrorCode::kIoError, options.out_dir + ": cannot create: " + ec.message());
  const std::string tag = modeTag(options.mode);
  std::vector<vkloc::StampedPose> trajectory;
  for (size_t i = 0; i < frames.size(); ++i) {
    trajectory.push_back(vkloc::StampedPose{frames[i].t_ns, pass.T_camera_object[i].inverse()});
  }
  const std::string tum_path = (fs::path(options.out_dir) / ("visp_" + tag + ".txt")).string();
  if (auto status = vkloc::saveTumTrajectory(trajectory, tum_path); !status) return status;
  const std::string csv_path = (fs::path(options.out_dir) / ("visp_" + tag + "_frames.csv")).string();
  std::ofstream csv(csv_path);
  if (!csv) return vkloc::makeError(vkloc::ErrorCode::kIoError, csv_path + ": cannot open for writing");
  csv << "# ViSP vpMbGenericTracker " << options.mode << " on " << options.castle_dir << "\n";
  csv << "t_ns,state,total_ms,t_err_mm,r_err_deg,edge_features,klt_features,image\n";
  for (size_t i = 0; i < frames.size(); ++i) {
    csv << fmt::format("{},{},{:.4f},{:.4f},{:.4f},{},{},{}\n", frames[i].t_ns, tracked[i] ? "tracking" : "lost",
                       median_ms[i], t_err_mm[i], r_err_deg[i], pass.edge_features[i], pass.klt_features[i],
                       frames[i].number);
  }
  csv.close();
  if (!csv) return vkloc::makeError(vkloc::ErrorCode::kIoError, csv_path + ": write failed");
  std::printf("wrote %s and %s\n", tum_path.c_str(), csv_path.c_str());
  return vkloc::Status{};
}

/// One vkloc backend over the same frames: per-frame stage times of every timed pass, poses of
/// the first timed pass.
struct VklocRun {
  std::string backend;            ///< "auto", "cpu" or "vulkan".
  std::string summary;            ///< Localizer::backendSummary().
  double create_ms = 0;           ///< Localizer::create (renderer upload, pipelines), ms.
  double first_frame_ms = 0;      ///< First localize() of the warm-up pass (shader JIT), ms.
  std::vector<double> total_ms;   ///< localize() wall time, every frame of every timed pass.
  std::vector<double> reused_ms;  ///< live + align of frames that kept the reference, ms.
  std::vector<double> render_ms, reference_ms, live_ms, align_ms;  ///< Stage times, ms.
  std::vector<double> t_err_mm, r_err_deg;                         ///< Errors of the first timed pass.
  size_t lost = 0;                                                 ///< Frames flagged lost in the first timed pass.
  size_t rerendered = 0;                                           ///< References rendered in the first timed pass.
};

vkloc::Result<VklocRun> runVkloc(const std::vector<Frame>& frames, const BenchOptions& options,
                                 const std::string& backend, const Pose& T_world_camera_init,
                                 const std::shared_ptr<vkloc::GpuContext>& context) {
  using namespace vkloc;
  const fs::path models = fs::path(options.castle_dir) / "Models";
  auto castle = parseCaoFile((models / "chateau.cao").string());
  if (!castle) return castle.error();
  auto cube = parseCaoFile((models / "cube.cao").string());
  if (!cube) return cube.error();
  appendCaoModel(*castle, *cube, fromVisp(castleCubePose()));
  auto model = caoToModel(*castle, (models / "chateau.cao").string());
  if (!model) return model.error();
  PinholeCamera camera;
  camera.fx = camera.fy = 700.0;
  camera.cx = 320.0;
  camera.cy = 240.0;
  camera.width = static_cast<int>(frames.front().image.getWidth());
  camera.height = static_cast<int>(frames.front().image.getHeight());

  LocalizerOptions lo;
  auto parsed_backend = parseLocalizerBackend(backend);
  if (!parsed_backend) return parsed_backend.error();
  lo.backend = *parsed_backend;
  auto policy = parseRerenderPolicy(options.vkloc_policy);
  if (!policy) return policy.error();
  lo.policy = *policy;

  VklocRun out;
  out.backend = backend;
  const auto t0 = std::chrono::steady_clock::now();
  auto accelerator = makeGpuAccelerator(context);
  if (!accelerator) return accelerator.error();
  auto localizer = Localizer::create(*model, camera, lo, *accelerator);
  if (!localizer) return localizer.error();
  out.create_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  out.summary = (*localizer)->backendSummary();

  std::vector<ImageU8> images;
  for (const Frame& f : frames) {
    ImageU8 g(static_cast<int>(f.image.getWidth()), static_cast<int>(f.image.getHeight()), 1);
    std::copy(f.image.bitmap, f.image.bitmap + g.data.size(), g.data.begin());
    images.push_back(std::move(g));
  }
  const int passes = std::max(options.runs, 1);
  for (int pass = -1; pass < passes; ++pass) {  // pass -1: warm-up.
    (*localizer)->reset(T_world_camera_init);
    for (size_t i = 0; i < frames.size(); ++i) {
      auto r = (*localizer)->localize(frames[i].t_ns, images[i]);
      if (!r) return r.error();
      if (pass < 0) {
        if (i == 0) out.first_frame_ms = r->total_ms;
        continue;
      }
      out.total_ms.push_back(r->total_ms);
      out.render_ms.push_back(r->render_ms);
      out.reference_ms.push_back(r->reference_ms);
      out.live_ms.push_back(r->live_ms);
      out.align_ms.push_back(r->align_ms);
      if (!r->reference_rendered) out.reused_ms.push_back(r->live_ms + r->align_ms);
      if (pass == 0) {
        const Pose T_wc_gt = frames[i].T_camera_object_gt.inverse();
        out.t_err_mm.push_back((r->T_world_camera.translation() - T_wc_gt.translation()).norm() * 1e3);
        out.r_err_deg.push_back(rotationAngleDeg(r->T_world_camera.linear().transpose() * T_wc_gt.linear()));
        out.lost += r->state == TrackingState::kLost ? 1 : 0;
        out.rerendered += r->reference_rendered ? 1 : 0;
      }
    }
  }
  return out;
}

/// Runs the requested vkloc backends and prints them beside ViSP's median track() time.
int compareWithVkloc(const std::vector<Frame>& frames, const BenchOptions& options, const Pose& T_camera_object_init,
                     double visp_median_ms, double visp_mean_mm, double visp_mean_deg) {
  std::vector<std::string> backends;
  std::stringstream list(options.vkloc_backends);
  for (std::string b; std::getline(list, b, ',');) {
    if (!b.empty()) backends.push_back(b);
  }
  auto context = vkloc::GpuContext::create();
  std::shared_ptr<vkloc::GpuContext> device = context ? *context : nullptr;
  if (!context) std::printf("vkloc: no Vulkan device (%s): CPU only\n", context.error().message.c_str());
  std::printf("\nvkloc on the same %zu frames (policy %s), %d timed passes after 1 warm-up pass:\n", frames.size(),
              options.vkloc_policy.c_str(), std::max(options.runs, 1));
  std::printf("%-8s %9s %9s %9s %9s %9s %10s %9s %9s %9s %5s %6s\n", "backend", "frame ms", "render", "refpts", "live",
              "align", "reused ms", "x ViSP", "mean mm", "mean deg", "lost", "rerend");
  int rc = 0;
  for (const std::string& b : backends) {
    auto run = runVkloc(frames, options, b, T_camera_object_init.inverse(), device);
    if (!run) {
      std::fprintf(stderr, "vkloc_visp_bench: vkloc backend %s: %s\n", b.c_str(), run.error().message.c_str());
      rc = 1;
      continue;
    }
    const VklocRun& v = *run;
    const double median = percentile(v.total_ms, 0.5);
    const double reused = v.reused_ms.empty() ? NAN : percentile(v.reused_ms, 0.5);
    std::printf("%-8s %9.3f %9.3f %9.3f %9.3f %9.3f %10.3f %9.2f %9.3f %9.4f %5zu %6zu\n", b.c_str(), median,
                percentile(v.render_ms, 0.5), percentile(v.reference_ms, 0.5), percentile(v.live_ms, 0.5),
                percentile(v.align_ms, 0.5), reused, median / visp_median_ms, vkloc::computeErrorStats(v.t_err_mm).mean,
                vkloc::computeErrorStats(v.r_err_deg).mean, v.lost, v.rerendered);
    std::printf("         %s; create %.0f ms, first frame %.0f ms (shader JIT on lavapipe)\n", v.summary.c_str(),
                v.create_ms, v.first_frame_ms);
  }
  std::printf(
      "ViSP (%s): %.3f ms median per frame, %.2f mm / %.3f deg mean; 'x ViSP' = vkloc median / ViSP median;"
      " 'reused ms' = live + align of frames that kept the reference (median)\n",
      options.mode.c_str(), visp_median_ms, visp_mean_mm, visp_mean_deg);
  return rc;
}

int run(const BenchOptions& options) {
  if (options.mode != "edge" && options.mode != "edge+klt" && options.mode != "klt") {
    std::fprintf(stderr, "vkloc_visp_bench: --mode must be edge, edge+klt or klt, not '%s'\n", options.mode.c_str());
    return 2;
  }
  auto frames_or = loadCastle(options.castle_dir, options.frames);
  if (!frames_or) {
    std::fprintf(stderr, "vkloc_visp_bench: %s\n", frames_or.error().message.c_str());
    return 1;
  }
  const std::vector<Frame>& frames = *frames_or;

  // Start pose: ground truth, optionally moved in the camera frame.
  Pose T_camera_object_init = frames.front().T_camera_object_gt;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset_deg = Eigen::Vector3d::Zero();
  if (!options.init_offset.empty()) {
    auto numbers = vkloc::parseNumbers(options.init_offset, "--init-offset", 6);
    if (!numbers) {
      std::fprintf(stderr, "vkloc_visp_bench: %s\n", numbers.error().message.c_str());
      return 2;
    }
    offset_m = Eigen::Vector3d((*numbers)[0], (*numbers)[1], (*numbers)[2]);
    offset_deg = Eigen::Vector3d((*numbers)[3], (*numbers)[4], (*numbers)[5]);
    const Eigen::Vector3d rotvec = offset_deg * M_PI / 180.0;
    Pose delta = Pose::Identity();
    if (rotvec.norm() > 0.0) delta.linear() = Eigen::AngleAxisd(rotvec.norm(), rotvec.normalized()).toRotationMatrix();
    delta.translation() = offset_m;
    // T_world_camera_init = T_world_camera_gt * delta  <=>  cMo_init = delta^-1 * cMo_gt.
    T_camera_object_init = delta.inverse() * T_camera_object_init;
  }

  std::printf("ViSP %d.%d.%d vpMbGenericTracker, mode %s, %zu frames of %s\n", VISP_VERSION_MAJOR, VISP_VERSION_MINOR,
              VISP_VERSION_PATCH, options.mode.c_str(), frames.size(), options.castle_dir.c_str());
  const Pose T_wc_gt0 = frames.front().T_camera_object_gt.inverse();
  const Pose T_wc_init = T_camera_object_init.inverse();
  std::printf("start: %s (%.1f mm, %.2f deg from the first ground-truth pose)\n",
              options.init_offset.empty() ? "ground truth" : ("offset " + options.init_offset).c_str(),
              (T_wc_init.translation() - T_wc_gt0.translation()).norm() * 1e3,
              rotationAngleDeg(T_wc_init.linear().transpose() * T_wc_gt0.linear()));

  // Warm-up pass (also prints the settings read back), then the timed passes.
  const Pass warmup = runPass(frames, options, T_camera_object_init, true);
  std::vector<Pass> passes;
  for (int r = 0; r < options.runs; ++r) passes.push_back(runPass(frames, options, T_camera_object_init, false));
  if (passes.empty()) passes.push_back(warmup);
  const Pass& pass = passes.front();

  // Timings over all frames of all timed passes, and the per-frame median for the frames log.
  std::vector<double> all_ms;
  std::vector<double> median_ms(frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    std::vector<double> per_frame;
    for (const Pass& p : passes) per_frame.push_back(p.track_ms[i]);
    median_ms[i] = percentile(per_frame, 0.5);
    all_ms.insert(all_ms.end(), per_frame.begin(), per_frame.end());
  }
  double run_spread_mm = 0.0;  // Largest camera-centre difference between passes, mm.
  for (const Pass& p : passes) {
    for (size_t i = 0; i < frames.size(); ++i) {
      const double d =
          (p.T_camera_object[i].inverse().translation() - pass.T_camera_object[i].inverse().translation()).norm();
      run_spread_mm = std::max(run_spread_mm, d * 1e3);
    }
  }

  // Errors against the ground truth, world = object frame.
  std::vector<double> t_err_mm;
  std::vector<double> r_err_deg;
  std::vector<double> cmo_t_err_mm;
  std::vector<bool> tracked;
  size_t exceptions = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const Pose T_wc_est = pass.T_camera_object[i].inverse();
    const Pose T_wc_gt = frames[i].T_camera_object_gt.inverse();
    t_err_mm.push_back((T_wc_est.translation() - T_wc_gt.translation()).norm() * 1e3);
    r_err_deg.push_back(rotationAngleDeg(T_wc_est.linear().transpose() * T_wc_gt.linear()));
    cmo_t_err_mm.push_back((pass.T_camera_object[i].translation() - frames[i].T_camera_object_gt.translation()).norm() *
                           1e3);
    exceptions += pass.threw[i] ? 1 : 0;
    tracked.push_back(!pass.threw[i] && t_err_mm.back() <= options.lost_mm && r_err_deg.back() <= options.lost_deg);
  }
  const auto t_stats = vkloc::computeErrorStats(t_err_mm);
  const auto r_stats = vkloc::computeErrorStats(r_err_deg);
  const auto c_stats = vkloc::computeErrorStats(cmo_t_err_mm);
  const size_t n_tracked = static_cast<size_t>(std::count(tracked.begin(), tracked.end(), true));
  double mean_edges = 0.0;
  double mean_klt = 0.0;
  for (size_t i = 0; i < frames.size(); ++i) {
    mean_edges += pass.edge_features[i];
    mean_klt += pass.klt_features[i];
  }
  mean_edges /= static_cast<double>(frames.size());
  mean_klt /= static_cast<double>(frames.size());

  std::printf("\n%-34s %10s %10s %10s %10s\n", "", "mean", "median", "p90", "max");
  std::printf("%-34s %10.3f %10.3f %10.3f %10.3f\n", "track() time (ms/frame)", vkloc::computeErrorStats(all_ms).mean,
              percentile(all_ms, 0.5), percentile(all_ms, 0.9), percentile(all_ms, 1.0));
  std::printf("%-34s %10.2f %10.2f %10.2f %10.2f\n", "camera position error (mm)", t_stats.mean, t_stats.median,
              percentile(t_err_mm, 0.9), t_stats.max);
  std::printf("%-34s %10.3f %10.3f %10.3f %10.3f\n", "rotation error (deg)", r_stats.mean, r_stats.median,
              percentile(r_err_deg, 0.9), r_stats.max);
  std::printf("%-34s %10.2f %10.2f %10.2f %10.2f\n", "cMo translation error (mm, ViSP)", c_stats.mean, c_stats.median,
              percentile(cmo_t_err_mm, 0.9), c_stats.max);
  std::printf("timing: %zu frames x %zu timed passes after 1 warm-up pass; passes agree to %.3g mm\n", frames.size(),
              passes.size(), run_spread_mm);
  std::printf("features per frame (mean): %.0f moving edges, %.0f KLT points\n", mean_edges, mean_klt);
  std::printf(
      "tracked (<= %.1f mm and <= %.2f deg, no exception): %zu/%zu frames, %zu exceptions; last frame: %s"
      " (%.1f mm, %.2f deg)\n",
      options.lost_mm, options.lost_deg, n_tracked, frames.size(), exceptions, tracked.back() ? "tracked" : "LOST",
      t_err_mm.back(), r_err_deg.back());
  const auto first_lost = std::find(tracked.begin(), tracked.end(), false);
  if (first_lost != tracked.end()) {
    std::printf("first lost frame: image %d\n", frames[static_cast<size_t>(first_lost - tracked.begin())].number);
  }
  if (!pass.first_exception.empty()) std::printf("first exception: %s\n", pass.first_exception.c_str());
  std::printf("sequence: %s\n", tracked.back() ? "tracked to the end" : "LOST");

  if (!options.vkloc_backends.empty()) {
    if (compareWithVkloc(frames, options, T_camera_object_init, percentile(all_ms, 0.5), t_stats.mean, r_stats.mean) !=
        0) {
      return 1;
    }
  }
  if (!options.out_dir.empty()) {
    if (auto status = writeOutputs(options, frames, pass, median_ms, t_err_mm, r_err_deg, tracked); !status) {
      std::fprintf(stderr, "vkloc_visp_bench: %s\n", status.error().message.c_str());
      return 1;
    }
  }
  if (options.max_mean_mm > 0.0 && !(t_stats.mean <= options.max_mean_mm)) {
    std::fprintf(stderr, "vkloc_visp_bench: mean camera position error %.2f mm exceeds --max-mean-mm %.2f\n",
                 t_stats.mean, options.max_mean_mm);
    return 1;
  }
  if (options.max_mean_deg > 0.0 && !(r_stats.mean <= options.max_mean_deg)) {
    std::fprintf(stderr, "vkloc_visp_bench: mean rotation error %.3f deg exceeds --max-mean-deg %.3f\n", r_stats.mean,
                 options.max_mean_deg);
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchOptions options;
  CLI::App app{"ViSP's model-based tracker on Castle-simu: time per frame and pose error against ground truth"};
  app.add_option("--castle", options.castle_dir, "Castle-simu folder (Images/, CameraPose/, Config/, Models/)")
      ->capture_default_str();
  app.add_option("--out", options.out_dir, "Write visp_<mode>.txt (TUM T_world_camera) and visp_<mode>_frames.csv");
  app.add_option("--mode", options.mode, "edge, edge+klt or klt")->capture_default_str();
  app.add_option("--runs", options.runs, "Timed passes after one warm-up pass (0: report the warm-up pass)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  app.add_option("--frames", options.frames, "Use only the first N images (0 = all)")->check(CLI::NonNegativeNumber);
  app.add_option("--init-offset", options.init_offset,
                 "Start pose offset in the camera frame: dx,dy,dz (m),rx,ry,rz (deg, rotation vector)");
  app.add_option("--lost-mm", options.lost_mm, "A frame is lost above this translation error, mm")
      ->capture_default_str();
  app.add_option("--lost-deg", options.lost_deg, "A frame is lost above this rotation error, deg")
      ->capture_default_str();
  app.add_option("--max-mean-mm", options.max_mean_mm, "Exit 1 when the mean translation error exceeds this, mm");
  app.add_option("--max-mean-deg", options.max_mean_deg, "Exit 1 when the mean rotation error exceeds this, deg");
  app.add_option("--vkloc", options.vkloc_backends,
                 "Also run vkloc on the same frames in this process with these backends, e.g. auto,cpu,vulkan");
  app.add_option("--vkloc-policy", options.vkloc_policy, "vkloc re-render policy: when-needed or every-frame")
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return run(options);
  } catch (const vpException& e) {
    std::fprintf(stderr, "vkloc_visp_bench: ViSP: %s\n", e.getStringMessage().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "vkloc_visp_bench: %s\n", e.what());
  }
  return 1;
}
