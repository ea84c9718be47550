// vkloc distort: a copy of a pinhole sequence whose images a lens has distorted (radial-
// tangential, the same intrinsics), for measuring what the camera front's undistortion costs.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "common.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/io/sequence.hpp"

namespace vkloc::cli {
namespace {

struct DistortArgs {
  std::string sequence;
  std::string out;
  std::string k = "-0.28,0.074,2e-4,1.8e-5,0";  ///< k1,k2,p1,p2,k3 (a EuRoC-like barrel).
  size_t frames = 0;
};

void run(const DistortArgs& a) {
  namespace fs = std::filesystem;
  Sequence seq = take(loadSequence(a.sequence));
  const PinholeCamera K = sequenceCamera(seq);
  LensCamera lens;
  lens.intrinsics = K;
  const std::vector<double> k = take(parseNumbers(a.k, "--k (k1,k2,p1,p2,k3)", 5));
  std::copy(k.begin(), k.end(), lens.k.begin());
  check(validateLensCamera(lens));
  // Each lens pixel shows what the pinhole image shows along its ray; none where it sees beyond.
  cv::Mat map(K.height, K.width, CV_32FC2);
  size_t outside = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      Eigen::Vector3d ray;
      cv::Vec2f& m = map.at<cv::Vec2f>(v, u);
      m = cv::Vec2f(-1e5f, -1e5f);
      if (!unprojectLens(lens, Eigen::Vector2d(u, v), ray) || ray.z() <= 0) {
        ++outside;
        continue;
      }
      const double x = K.fx * ray.x() / ray.z() + K.cx, y = K.fy * ray.y() / ray.z() + K.cy;
      if (x < 0 || y < 0 || x > K.width - 1 || y > K.height - 1) ++outside;
      m = cv::Vec2f(static_cast<float>(x), static_cast<float>(y));
    }
  }
  fs::create_directories(fs::path(a.out) / "images");
  Sequence out = seq;
  out.directory = a.out;
  out.name = seq.name + "_radtan";
  if (!seq.model.empty() && seq.model != "city" && seq.model != "room") {
    out.model = fs::absolute(seq.modelPath()).string();
  }
  out.camera.model = "pinhole";
  out.camera.distortion = k;
  const size_t total = a.frames > 0 ? std::min(a.frames, seq.images.size()) : seq.images.size();
  out.images.clear();
  for (size_t i = 0; i < total; ++i) {
    const cv::Mat image = cv::imread(seq.imagePath(i), cv::IMREAD_UNCHANGED);
    if (image.empty()) throw Failure{fmt::format("{}: cannot read the image", seq.imagePath(i))};
    if (image.cols != K.width || image.rows != K.height) {
      throw Failure{fmt::format("{}: {}x{} image; the camera is {}x{}", seq.imagePath(i), image.cols, image.rows,
                                K.width, K.height)};
    }
    cv::Mat distorted;
    cv::remap(image, distorted, map, cv::Mat(), cv::INTER_LANCZOS4, cv::BORDER_CONSTANT, cv::Scalar::all(0));
    const std::string rel = fmt::format("images/{:06d}.png", i);
    if (!cv::imwrite((fs::path(a.out) / rel).string(), distorted)) {
      throw Failure{fmt::format("{}/{}: cannot write the image", a.out, rel)};
    }
    out.images.push_back(ImageEntry{seq.images[i].t_ns, rel});
    if ((i + 1) % 50 == 0 || i + 1 == total) {
      std::printf("frame %zu/%zu\n", i + 1, total);
      std::fflush(stdout);
    }
  }
  check(saveSequence(out, a.out));
  std::printf("distorted %zu images (k = %s; %.1f %% of the lens image sees beyond the original) -> %s\n", total,
              a.k.c_str(), 100.0 * static_cast<double>(outside) / (static_cast<double>(K.width) * K.height),
              a.out.c_str());
}

void addDistortVerb(CLI::App& app) {
  auto args = std::make_shared<DistortArgs>();
  CLI::App* cmd = app.add_subcommand(
      "distort", "Copy a pinhole sequence with its images distorted by a radial-tangential lens (PNG)");
  cmd->add_option("--sequence,-s", args->sequence, "Pinhole sequence folder")->required();
  cmd->add_option("--out,-o", args->out, "Output sequence folder")->required();
  cmd->add_option("--k", args->k, "Distortion 'k1,k2,p1,p2,k3'")->capture_default_str();
  cmd->add_option("--frames", args->frames, "Only the first N images (0 = all)")->capture_default_str();
  cmd->callback([args] { run(*args); });
}

}  // namespace

VKLOC_REGISTER_VERB(65, addDistortVerb);

}  // namespace vkloc::cli
