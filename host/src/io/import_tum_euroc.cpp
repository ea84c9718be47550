// Importers of public dataset layouts (TUM RGB-D, EuRoC ASL) into a vkloc Sequence.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>

#include "io/io_internal.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/io/import.hpp"

namespace vkloc {

namespace {

namespace fs = std::filesystem;
using text::lineError;
using text::shown;
using text::splitCsv;
using text::trim;

bool parseNs(std::string_view t, int64_t& out) { return text::parseInt64(t, out).empty(); }

bool parseFinite(std::string_view t, double& out) { return text::parseDouble(t, out).empty(); }

/// Reads the data lines of a CSV file ('#' comments and blank lines skipped) as
/// (line number, fields). kNotFound when the file is missing.
Result<std::vector<std::pair<size_t, std::vector<std::string_view>>>> readCsv(const std::string& path,
                                                                              std::string& storage) {
  auto read = io_detail::readTable(path, "file");
  if (!read.ok()) return read.error();
  storage = std::move(read).value();
  std::vector<std::pair<size_t, std::vector<std::string_view>>> rows;
  const std::string_view text(storage);
  size_t start = 0;
  size_t line_no = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    ++line_no;
    const std::string_view line = trim(text.substr(start, end - start));
    start = end + 1;
    if (line.empty() || line.front() == '#') continue;
    if (const std::string wrong = io_detail::tableLimits(line, rows.size()); !wrong.empty()) {
      return lineError(path, line_no, wrong);
    }
    rows.emplace_back(line_no, splitCsv(line));
  }
  return rows;
}

std::string timeOrderError(int64_t previous, int64_t current) {
  return fmt::format("timestamp {} ns is not after the previous one {} ns", current, previous);
}

/// Absolute, normalised form of a folder path.
fs::path absoluteFolder(const std::string& directory) {
  std::error_code ec;
  fs::path p = fs::absolute(directory, ec).lexically_normal();
  if (ec) p = fs::path(directory).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p;
}

/// T_world_camera at t by linear / spherical interpolation between the bracketing samples.
std::optional<Pose> interpolate(const std::vector<StampedPose>& poses, int64_t t_ns) {
  const auto it =
      std::lower_bound(poses.begin(), poses.end(), t_ns, [](const StampedPose& p, int64_t t) { return p.t_ns < t; });
  if (it == poses.end()) return std::nullopt;
  if (it->t_ns == t_ns) return it->T_world_camera;
  if (it == poses.begin()) return std::nullopt;
  const StampedPose& a = *(it - 1);
  const StampedPose& b = *it;
  const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  const Eigen::Quaterniond qa(a.T_world_camera.linear());
  const Eigen::Quaterniond qb(b.T_world_camera.linear());
  Pose T = Pose::Identity();
  T.linear() = qa.slerp(s, qb).normalized().toRotationMatrix();
  T.translation() = (1.0 - s) * a.T_world_camera.translation() + s * b.T_world_camera.translation();
  return T;
}

void setInitialPose(Sequence& seq) {
  if (!seq.images.empty() && !seq.groundtruth.empty()) {
    seq.initial_T_world_camera = interpolate(seq.groundtruth, seq.images.front().t_ns);
  }
}

// Published calibrations of the TUM RGB-D Kinects (colour camera, 640x480).
SequenceCamera tumCamera(double fx, double fy, double cx, double cy, std::vector<double> distortion) {
  SequenceCamera camera;
  camera.model = "pinhole";
  camera.intrinsics = PinholeCamera{fx, fy, cx, cy, 640, 480};
  camera.distortion = std::move(distortion);
  return camera;
}

// -----------------------------------------------------------------------------------------------
// EuRoC imu0/sensor.yaml (cam0/sensor.yaml: io_detail::loadKalibrSensorCamera)

// These throw YAML::Exception (with the line) on bad values; callers catch it.
double yamlNumber(const YAML::Node& node, const char* key) {
  const double v = node.as<double>();
  if (!std::isfinite(v)) throw YAML::Exception(node.Mark(), fmt::format("'{}' is not finite", key));
  return v;
}

Result<YAML::Node> loadYamlFile(const std::string& path) {
  Result<std::string> read = text::readFile(path, "file", io_detail::kMaxYamlBytes);
  if (!read.ok()) return read.error();
  std::string text = std::move(read).value();
  // OpenCV-style files start with "%YAML:1.0", which is not a valid YAML directive.
  if (text.rfind("%YAML:", 0) == 0) text[0] = '#';
  auto root = io_detail::parseYaml(path, text);
  if (!root.ok()) return root.error();
  if (!root->IsMap()) return lineError(path, 1, "expected a mapping of sensor keys");
  return root;
}

Result<ImuNoise> loadEurocImuNoise(const std::string& path) {
  auto loaded = loadYamlFile(path);
  if (!loaded.ok()) return loaded.error();
  const YAML::Node& root = *loaded;
  ImuNoise noise;
  try {
    struct Field {
      const char* key;
      double* out;
    };
    for (const Field& f :
         {Field{"rate_hz", &noise.rate_hz}, Field{"gyroscope_noise_density", &noise.gyro_noise_density},
          Field{"accelerometer_noise_density", &noise.accel_noise_density},
          Field{"gyroscope_random_walk", &noise.gyro_random_walk},
          Field{"accelerometer_random_walk", &noise.accel_random_walk}}) {
      const YAML::Node n = root[f.key];
      if (!n) continue;
      const double v = yamlNumber(n, f.key);
      if (v <= 0.0) return lineError(path, n.Mark().line + 1, fmt::format("'{}' must be > 0", f.key));
      *f.out = v;
    }
  } catch (const YAML::Exception& e) {
    return lineError(path, static_cast<size_t>(e.mark.line + 1), e.msg);
  }
  return noise;
}

/// mav0/cam0/data.csv: "t_ns,filename"; image paths made absolute under `image_folder`.
Result<std::vector<ImageEntry>> loadEurocImages(const std::string& path, const fs::path& image_folder) {
  std::string storage;
  auto rows = readCsv(path, storage);
  if (!rows.ok()) return rows.error();
  std::vector<ImageEntry> images;
  for (const auto& [line, fields] : *rows) {
    if (fields.size() != 2) {
      return lineError(path, line, fmt::format("expected 2 columns (timestamp_ns,filename), got {}", fields.size()));
    }
    ImageEntry e;
    if (!parseNs(fields[0], e.t_ns)) {
      return lineError(path, line,
                       fmt::format("timestamp {} is not an integer number of nanoseconds", shown(fields[0])));
    }
    if (fields[1].empty()) return lineError(path, line, "empty file name");
    if (!images.empty() && e.t_ns <= images.back().t_ns) {
      return lineError(path, line, timeOrderError(images.back().t_ns, e.t_ns));
    }
    e.path = (image_folder / std::string(fields[1])).lexically_normal().string();
    images.push_back(std::move(e));
  }
  return images;
}

/// mav0/state_groundtruth_estimate0/data.csv: t_ns, p_RS_R xyz, q_RS wxyz, ... (T_world_body).
Result<std::vector<StampedPose>> loadEurocGroundTruth(const std::string& path, const Pose& T_body_camera) {
  std::string storage;
  auto rows = readCsv(path, storage);
  if (!rows.ok()) return rows.error();
  std::vector<StampedPose> poses;
  for (const auto& [line, fields] : *rows) {
    if (fields.size() < 8) {
      return lineError(
          path, line,
          fmt::format("expected at least 8 columns (t_ns, p_x, p_y, p_z, q_w, q_x, q_y, q_z), got {}", fields.size()));
    }
    StampedPose p;
    if (!parseNs(fields[0], p.t_ns)) {
      return lineError(path, line,
                       fmt::format("timestamp {} is not an integer number of nanoseconds", shown(fields[0])));
    }
    double v[7] = {};
    for (size_t c = 0; c < 7; ++c) {
      if (!parseFinite(fields[c + 1], v[c])) {
        return lineError(path, line, fmt::format("column {}: {} is not a finite number", c + 2, shown(fields[c + 1])));
      }
    }
    const Eigen::Quaterniond q_world_body(v[3], v[4], v[5], v[6]);  // w first in EuRoC.
    if (std::abs(q_world_body.norm() - 1.0) > 1e-3) {
      return lineError(path, line,
                       fmt::format("quaternion norm {} is not 1 (order is q_w q_x q_y q_z)", q_world_body.norm()));
    }
    if (!poses.empty() && p.t_ns <= poses.back().t_ns) {
      return lineError(path, line, timeOrderError(poses.back().t_ns, p.t_ns));
    }
    Pose T_world_body = Pose::Identity();
    T_world_body.linear() = q_world_body.normalized().toRotationMatrix();
    T_world_body.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    p.T_world_camera = T_world_body * T_body_camera;
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

Result<Sequence> importTumRgbd(const std::string& tum_directory, const std::optional<SequenceCamera>& camera_override,
                               const std::string& model) {
  std::error_code ec;
  if (!fs::is_directory(tum_directory, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: TUM RGB-D folder not found", tum_directory));
  }
  const fs::path dir = absoluteFolder(tum_directory);
  Sequence seq;
  seq.name = dir.filename().string();
  seq.model = model;
  if (camera_override) {
    seq.camera = *camera_override;
    if (const Status valid = validateCamera(seq.camera.intrinsics); !valid.ok()) return valid.error();
  } else {
    const std::string folder = seq.name;
    if (folder.find("freiburg1") != std::string::npos) {
      seq.camera = tumCamera(517.3, 516.5, 318.6, 255.3, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633});
    } else if (folder.find("freiburg2") != std::string::npos) {
      seq.camera = tumCamera(520.9, 521.0, 325.1, 249.7, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172});
    } else if (folder.find("freiburg3") != std::string::npos) {
      seq.camera = tumCamera(535.4, 539.2, 320.1, 247.6, {});
    } else {
      return makeError(
          ErrorCode::kInvalidArgument,
          fmt::format("{}: folder name names no freiburg1/2/3 camera; give the camera with --camera", tum_directory));
    }
  }
  auto images = loadImageList((dir / "rgb.txt").string());
  if (!images.ok()) return images.error();
  seq.images = std::move(*images);
  for (ImageEntry& e : seq.images) {
    const fs::path p(e.path);
    if (!p.is_absolute()) e.path = (dir / p).lexically_normal().string();
  }
  const std::string gt_path = (dir / "groundtruth.txt").string();
  if (fs::exists(gt_path, ec)) {
    auto gt = loadTumTrajectory(gt_path);
    if (!gt.ok()) return gt.error();
    seq.groundtruth = std::move(*gt);
  }
  setInitialPose(seq);
  return seq;
}

Result<Sequence> importEuroc(const std::string& euroc_directory, const std::string& model) {
  std::error_code ec;
  if (!fs::is_directory(euroc_directory, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: EuRoC folder not found", euroc_directory));
  }
  const fs::path dir = absoluteFolder(euroc_directory);
  // Accept the dataset folder (containing mav0/) or mav0/ itself.
  const fs::path mav0 = fs::is_directory(dir / "mav0", ec) ? dir / "mav0" : dir;
  Sequence seq;
  seq.name = (mav0 == dir ? dir.parent_path() : dir).filename().string();
  seq.model = model;
  // Kalibr-style sensor.yaml: pinhole, omni (Mei) or ds (double sphere); radtan, or equidistant
  // (Kannala-Brandt); T_BS = T_body_camera. Shared with loadCalibration.
  auto camera = io_detail::loadKalibrSensorCamera((mav0 / "cam0" / "sensor.yaml").string());
  if (!camera.ok()) return camera.error();
  seq.camera = std::move(*camera);
  auto images = loadEurocImages((mav0 / "cam0" / "data.csv").string(), mav0 / "cam0" / "data");
  if (!images.ok()) return images.error();
  seq.images = std::move(*images);

  const std::string imu_path = (mav0 / "imu0" / "data.csv").string();
  if (fs::exists(imu_path, ec)) {
    auto imu = loadImuCsv(imu_path);
    if (!imu.ok()) return imu.error();
    seq.imu = std::move(*imu);
  }
  const std::string imu_yaml = (mav0 / "imu0" / "sensor.yaml").string();
  if (fs::exists(imu_yaml, ec)) {
    auto noise = loadEurocImuNoise(imu_yaml);
    if (!noise.ok()) return noise.error();
    seq.imu_noise = *noise;
  }
  const std::string gt_path = (mav0 / "state_groundtruth_estimate0" / "data.csv").string();
  if (fs::exists(gt_path, ec)) {
    auto gt = loadEurocGroundTruth(gt_path, seq.camera.T_body_camera);
    if (!gt.ok()) return gt.error();
    seq.groundtruth = std::move(*gt);
  }
  setInitialPose(seq);
  return seq;
}

}  // namespace vkloc
