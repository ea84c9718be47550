// vkloc import: convert ViSP, TUM RGB-D and EuRoC folders into vkloc sequences.
#include <cstdio>
#include <optional>

#include "common.hpp"
#include "vkloc/io/import.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/model/cao.hpp"

namespace vkloc::cli {

namespace {

void printSequence(const Sequence& seq, const std::string& out) {
  std::printf("sequence:     %s (%s)\n", out.c_str(), seq.name.c_str());
  std::printf("frames:       %zu\n", seq.images.size());
  std::printf("ground truth: %zu poses\n", seq.groundtruth.size());
  if (!seq.imu.empty()) std::printf("imu:          %zu samples\n", seq.imu.size());
  const PinholeCamera& c = seq.camera.intrinsics;
  std::printf("camera:       %s %dx%d fx %.3f fy %.3f cx %.3f cy %.3f\n", seq.camera.model.c_str(), c.width, c.height,
              c.fx, c.fy, c.cx, c.cy);
  if (!seq.model.empty()) std::printf("model:        %s\n", seq.model.c_str());
}

}  // namespace

static void addImportVerb(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("import", "Convert a ViSP, TUM RGB-D or EuRoC folder into a vkloc sequence");
  cmd->require_subcommand(1);

  struct VispArgs {
    std::string folder;
    std::string out;
    bool no_cube = false;
    double rate_hz = 30.0;
  };
  auto visp = std::make_shared<VispArgs>();
  CLI::App* visp_cmd =
      cmd->add_subcommand("visp",
                          "ViSP mbt folder (Images/, CameraPose/, Config/*.xml, Models/*.cao), e.g. visp-images-data's "
                          "mbt-depth/Castle-simu");
  visp_cmd->add_option("folder", visp->folder, "ViSP folder")->required();
  visp_cmd->add_option("--out,-o", visp->out, "Output sequence folder")->required();
  visp_cmd->add_flag("--no-cube", visp->no_cube, "Leave Models/cube.cao out of the model");
  visp_cmd->add_option("--rate", visp->rate_hz, "Frame rate for timestamps, Hz")->capture_default_str();
  visp_cmd->callback([visp] {
    VispImportOptions options;
    options.include_cube = !visp->no_cube;
    options.frame_rate_hz = visp->rate_hz;
    VispImportReport report;
    const Sequence seq = take(importVispSequence(visp->folder, visp->out, options, &report));
    for (const auto& w : report.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
    printSequence(seq, visp->out);
    std::printf("model file:   %s (%zu triangles, of which cube %zu)\n", report.model_path.c_str(), report.triangles,
                report.cube_triangles);
    std::printf("timestamps:   image number / %.3f Hz; ground truth T_world_camera = inverse(cMo), world = object\n",
                visp->rate_hz);
  });

  struct TumArgs {
    std::string folder;
    std::string out;
    std::string camera;
    std::string model;
  };
  auto tum = std::make_shared<TumArgs>();
  CLI::App* tum_cmd = cmd->add_subcommand("tum", "TUM RGB-D folder (rgb.txt, groundtruth.txt)");
  tum_cmd->add_option("folder", tum->folder, "TUM RGB-D folder")->required();
  tum_cmd->add_option("--out,-o", tum->out, "Output sequence folder")->required();
  tum_cmd->add_option("--camera", tum->camera, "camera.yaml overriding the freiburg calibration");
  tum_cmd->add_option("--model", tum->model, "Model file stored in the sequence");
  tum_cmd->callback([tum] {
    std::optional<SequenceCamera> camera;
    if (!tum->camera.empty()) camera = take(loadSequenceCamera(tum->camera));
    const Sequence seq = take(importTumRgbd(tum->folder, camera, tum->model));
    check(saveSequence(seq, tum->out));
    printSequence(seq, tum->out);
  });

  struct EurocArgs {
    std::string folder;
    std::string out;
    std::string model;
  };
  auto euroc = std::make_shared<EurocArgs>();
  CLI::App* euroc_cmd = cmd->add_subcommand("euroc", "EuRoC ASL folder (mav0/cam0, mav0/imu0, ground truth)");
  euroc_cmd->add_option("folder", euroc->folder, "EuRoC folder")->required();
  euroc_cmd->add_option("--out,-o", euroc->out, "Output sequence folder")->required();
  euroc_cmd->add_option("--model", euroc->model, "Model file stored in the sequence");
  euroc_cmd->callback([euroc] {
    const Sequence seq = take(importEuroc(euroc->folder, euroc->model));
    check(saveSequence(seq, euroc->out));
    printSequence(seq, euroc->out);
  });
}

VKLOC_REGISTER_VERB(60, addImportVerb);

}  // namespace vkloc::cli
