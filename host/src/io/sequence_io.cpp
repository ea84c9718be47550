// Sequence folder: reading and writing of sequence.yaml, camera.yaml, images.txt,
// groundtruth.txt, imu.csv and prior.csv.
#include <fmt/format.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cassert>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

#include "io/io_internal.hpp"
#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/io/sequence.hpp"

namespace vkloc {

namespace {

namespace fs = std::filesystem;
using namespace io_detail;
using text::formatSeconds;
using text::isBlankOrComment;
using text::parseDouble;
using text::parseSecondsToNs;
using text::splitCsv;

// ---------------------------------------------------------------------------------------------
// Text helpers.

Status checkIncreasingForSave(const std::string& what, size_t i, bool have_previous, int64_t previous,
                              int64_t current) {
  if (!have_previous || current > previous) return Status::success();
  return makeError(
      ErrorCode::kInvalidArgument,
      fmt::format("{}: entry {}: timestamp {} ns is not after the previous one {} ns", what, i, current, previous));
}

/// Quaternion (x, y, z, w) to a rotation; empty string or what is wrong.
std::string quaternionRotation(double qx, double qy, double qz, double qw, Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(qw, qx, qy, qz);
  const double norm = q.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    return fmt::format("quaternion norm {} is not 1 (order is qx qy qz qw)", norm);
  }
  R = q.normalized().toRotationMatrix();
  return {};
}

/// Parses an integer number of nanoseconds.
std::string parseNs(std::string_view token, int64_t& out) {
  if (!text::parseInt64(token, out).empty()) {
    return "timestamp " + shown(token) + " is not an integer number of nanoseconds";
  }
  return {};
}

/// Checks that a timestamp increases; `unit_seconds` picks how it is printed.
std::string checkIncreasing(bool have_previous, int64_t previous, int64_t current, bool unit_seconds) {
  if (!have_previous || current > previous) return {};
  if (unit_seconds) {
    return fmt::format("timestamp {} s is not after the previous one {} s", formatSeconds(current),
                       formatSeconds(previous));
  }
  return fmt::format("timestamp {} ns is not after the previous one {} ns", current, previous);
}

// ---------------------------------------------------------------------------------------------
// Numeric CSV tables with an integer nanosecond timestamp in the first column.

struct CsvRow {
  size_t line = 0;
  int64_t t_ns = 0;
  std::vector<double> values;
};

Result<std::vector<CsvRow>> loadNsCsv(const std::string& path, const char* what, size_t value_columns) {
  auto text = readTable(path, what);
  if (!text.ok()) return text.error();
  text::LineCursor lines(*text);
  std::vector<CsvRow> rows;
  bool seen_data = false;
  for (std::string_view line; lines.next(line);) {
    const size_t line_no = lines.number();
    if (isBlankOrComment(line)) continue;
    if (const std::string wrong = tableLimits(line, rows.size()); !wrong.empty())
      return lineError(path, line_no, wrong);
    const std::vector<std::string_view> fields = splitCsv(line);
    if (!seen_data) {
      seen_data = true;
      // An optional header line: column names, none of which is a number.
      bool any_number = false;
      for (std::string_view f : fields) {
        double ignored = 0.0;
        const auto [end, ec] = std::from_chars(f.data(), f.data() + f.size(), ignored);
        any_number = any_number || (!f.empty() && ec == std::errc()) || f.empty();
      }
      if (!any_number) continue;
    }
    if (fields.size() != value_columns + 1) {
      return lineError(path, line_no,
                       fmt::format("expected {} comma-separated columns, got {}", value_columns + 1, fields.size()));
    }
    CsvRow row;
    row.line = line_no;
    std::string wrong = parseNs(fields[0], row.t_ns);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    row.values.resize(value_columns);
    for (size_t c = 0; c < value_columns; ++c) {
      wrong = parseDouble(fields[c + 1], row.values[c]);
      if (!wrong.empty()) return lineError(path, line_no, fmt::format("column {}: {}", c + 2, wrong));
    }
    wrong = checkIncreasing(!rows.empty(), rows.empty() ? 0 : rows.back().t_ns, row.t_ns, false);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::string trajectoryText(const std::vector<StampedPose>& poses) {
  std::string out = "# timestamp tx ty tz qx qy qz qw (T_world_camera; seconds, metres)\n";
  for (const StampedPose& p : poses) {
    const Eigen::Quaterniond q(p.T_world_camera.linear());
    const Eigen::Vector3d t = p.T_world_camera.translation();
    out += fmt::format("{} {} {} {} {} {} {} {}\n", formatSeconds(p.t_ns), num(t.x()), num(t.y()), num(t.z()),
                       num(q.x()), num(q.y()), num(q.z()), num(q.w()));
  }
  return out;
}

std::string imageListText(const std::vector<ImageEntry>& images) {
  std::string out = "# timestamp path (seconds; path relative to this folder or absolute)\n";
  for (const ImageEntry& e : images) out += fmt::format("{} {}\n", formatSeconds(e.t_ns), e.path);
  return out;
}

std::string imuText(const std::vector<ImuSample>& samples) {
  std::string out =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
      "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (const ImuSample& s : samples) {
    out += fmt::format("{},{},{},{},{},{},{}\n", s.t_ns, num(s.gyro_body.x()), num(s.gyro_body.y()),
                       num(s.gyro_body.z()), num(s.accel_body.x()), num(s.accel_body.y()), num(s.accel_body.z()));
  }
  return out;
}

std::string priorText(const std::vector<PositionPrior>& priors) {
  std::string out = "#timestamp [ns],x [m],y [m],z [m],sigma_x [m],sigma_y [m],sigma_z [m]\n";
  for (const PositionPrior& p : priors) {
    out += fmt::format("{},{},{},{},{},{},{}\n", p.t_ns, num(p.p_world_body.x()), num(p.p_world_body.y()),
                       num(p.p_world_body.z()), num(p.sigma.x()), num(p.sigma.y()), num(p.sigma.z()));
  }
  return out;
}

// Validation before writing.

/// What makes an images.txt path unusable (empty when nothing): one rule for load and save.
std::string imagePathProblem(const std::string& p) {
  if (p.empty() || trim(p) != std::string_view(p) || p.find_first_of("\n\r") != std::string::npos || p.front() == '#') {
    return fmt::format("image path {} is empty, starts with '#' or has surrounding or line-break whitespace", shown(p));
  }
  return {};
}

/// A name or path written into sequence.yaml: YAML is UTF-8, and the emitter would replace
/// other bytes, so they are refused rather than changed.
Status checkUtf8(const std::string& value, const char* key, const std::string& what) {
  const size_t bad = text::invalidUtf8Offset(value);
  if (bad == std::string::npos) return Status::success();
  return invalid(fmt::format("{}: {} {} is not valid UTF-8 (byte 0x{:02x} at offset {}); YAML cannot hold it", what,
                             key, shown(value), static_cast<unsigned char>(value[bad]), bad));
}

Status validateTrajectory(const std::vector<StampedPose>& poses, const std::string& what) {
  for (size_t i = 0; i < poses.size(); ++i) {
    VKLOC_TRY_STATUS(checkIncreasingForSave(what, i, i > 0, i > 0 ? poses[i - 1].t_ns : 0, poses[i].t_ns));
    if (!finitePose(poses[i].T_world_camera)) {
      return invalid(fmt::format("{}: entry {}: pose is non-finite or not a rigid transform", what, i));
    }
  }
  return Status::success();
}

Status validateImages(const std::vector<ImageEntry>& images, const std::string& what) {
  for (size_t i = 0; i < images.size(); ++i) {
    VKLOC_TRY_STATUS(checkIncreasingForSave(what, i, i > 0, i > 0 ? images[i - 1].t_ns : 0, images[i].t_ns));
    if (const std::string bad = imagePathProblem(images[i].path); !bad.empty()) {
      return invalid(fmt::format("{}: entry {}: {}", what, i, bad));
    }
  }
  return Status::success();
}

Status validateImu(const std::vector<ImuSample>& samples, const std::string& what) {
  for (size_t i = 0; i < samples.size(); ++i) {
    VKLOC_TRY_STATUS(checkIncreasingForSave(what, i, i > 0, i > 0 ? samples[i - 1].t_ns : 0, samples[i].t_ns));
    if (!samples[i].gyro_body.allFinite() || !samples[i].accel_body.allFinite()) {
      return invalid(fmt::format("{}: entry {}: non-finite IMU value", what, i));
    }
  }
  return Status::success();
}

Status validatePriors(const std::vector<PositionPrior>& priors, const std::string& what) {
  for (size_t i = 0; i < priors.size(); ++i) {
    VKLOC_TRY_STATUS(checkIncreasingForSave(what, i, i > 0, i > 0 ? priors[i - 1].t_ns : 0, priors[i].t_ns));
    if (!priors[i].p_world_body.allFinite() || !priors[i].sigma.allFinite()) {
      return invalid(fmt::format("{}: entry {}: non-finite prior value", what, i));
    }
    if (!(priors[i].sigma.minCoeff() > 0.0)) return invalid(fmt::format("{}: entry {}: sigma must be > 0", what, i));
  }
  return Status::success();
}

Status validateNoise(const ImuNoise& n, const std::string& what) {
  for (double v : {n.rate_hz, n.gyro_noise_density, n.accel_noise_density, n.gyro_random_walk, n.accel_random_walk}) {
    if (!std::isfinite(v) || v <= 0.0) return invalid(fmt::format("{}: IMU noise values must be finite and > 0", what));
  }
  return Status::success();
}

}  // namespace

// -----------------------------------------------------------------------------------------------
// Sequence paths.

std::string Sequence::imagePath(size_t i) const {
  assert(i < images.size());
  const fs::path p(images[i].path);
  if (p.is_absolute() || directory.empty()) return p.string();
  return (fs::path(directory) / p).string();
}

std::string Sequence::modelPath() const {
  if (model.empty() || model == "city" || model == "room") return model;
  const fs::path p(model);
  if (p.is_absolute() || directory.empty()) return model;
  return (fs::path(directory) / p).string();
}

// -----------------------------------------------------------------------------------------------
// groundtruth.txt

Result<std::vector<StampedPose>> loadTumTrajectory(const std::string& path) {
  auto text = readTable(path, "trajectory file");
  if (!text.ok()) return text.error();
  text::LineCursor lines(*text);
  std::vector<StampedPose> poses;
  for (std::string_view line; lines.next(line);) {
    const size_t line_no = lines.number();
    if (isBlankOrComment(line)) continue;
    if (const std::string wrong = tableLimits(line, poses.size()); !wrong.empty())
      return lineError(path, line_no, wrong);
    const std::vector<std::string_view> f = text::splitFields(line, true);
    if (f.size() != 8) {
      return lineError(path, line_no, fmt::format("expected 8 columns (t tx ty tz qx qy qz qw), got {}", f.size()));
    }
    StampedPose p;
    std::string wrong = parseSecondsToNs(f[0], p.t_ns);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    double v[7] = {};
    for (size_t c = 0; c < 7; ++c) {
      wrong = parseDouble(f[c + 1], v[c]);
      if (!wrong.empty()) return lineError(path, line_no, fmt::format("column {}: {}", c + 2, wrong));
    }
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    wrong = quaternionRotation(v[3], v[4], v[5], v[6], R);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    p.T_world_camera.linear() = R;
    p.T_world_camera.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    wrong = checkIncreasing(!poses.empty(), poses.empty() ? 0 : poses.back().t_ns, p.t_ns, true);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    poses.push_back(p);
  }
  return poses;
}

Status saveTumTrajectory(const std::vector<StampedPose>& poses, const std::string& path) {
  VKLOC_TRY_STATUS(validateTrajectory(poses, path));
  return writeFileAtomically(path, trajectoryText(poses));
}

// -----------------------------------------------------------------------------------------------
// images.txt

Result<std::vector<ImageEntry>> loadImageList(const std::string& path) {
  auto text = readTable(path, "image list");
  if (!text.ok()) return text.error();
  text::LineCursor lines(*text);
  std::vector<ImageEntry> images;
  for (std::string_view raw; lines.next(raw);) {
    const size_t line_no = lines.number();
    if (isBlankOrComment(raw)) continue;
    if (const std::string wrong = tableLimits(raw, images.size()); !wrong.empty())
      return lineError(path, line_no, wrong);
    const std::string_view line = trim(raw);
    const size_t split = line.find_first_of(" \t");
    if (split == std::string_view::npos) {
      return lineError(path, line_no, "expected 2 columns (timestamp_s path), got 1");
    }
    ImageEntry e;
    std::string wrong = parseSecondsToNs(line.substr(0, split), e.t_ns);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    e.path = std::string(trim(line.substr(split)));
    // The paths saveImageList refuses are refused here too, so that load and save agree.
    if (const std::string bad = imagePathProblem(e.path); !bad.empty()) return lineError(path, line_no, bad);
    wrong = checkIncreasing(!images.empty(), images.empty() ? 0 : images.back().t_ns, e.t_ns, true);
    if (!wrong.empty()) return lineError(path, line_no, wrong);
    images.push_back(std::move(e));
  }
  return images;
}

Status saveImageList(const std::vector<ImageEntry>& images, const std::string& path) {
  VKLOC_TRY_STATUS(validateImages(images, path));
  return writeFileAtomically(path, imageListText(images));
}

// -----------------------------------------------------------------------------------------------
// imu.csv and prior.csv

Result<std::vector<ImuSample>> loadImuCsv(const std::string& path) {
  auto rows = loadNsCsv(path, "IMU file", 6);
  if (!rows.ok()) return rows.error();
  std::vector<ImuSample> samples;
  samples.reserve(rows->size());
  for (const CsvRow& r : *rows) {
    ImuSample s;
    s.t_ns = r.t_ns;
    s.gyro_body = Eigen::Vector3d(r.values[0], r.values[1], r.values[2]);
    s.accel_body = Eigen::Vector3d(r.values[3], r.values[4], r.values[5]);
    samples.push_back(s);
  }
  return samples;
}

Status saveImuCsv(const std::vector<ImuSample>& samples, const std::string& path) {
  VKLOC_TRY_STATUS(validateImu(samples, path));
  return writeFileAtomically(path, imuText(samples));
}

Result<std::vector<PositionPrior>> loadPriorCsv(const std::string& path) {
  auto rows = loadNsCsv(path, "prior file", 6);
  if (!rows.ok()) return rows.error();
  std::vector<PositionPrior> priors;
  priors.reserve(rows->size());
  for (const CsvRow& r : *rows) {
    PositionPrior p;
    p.t_ns = r.t_ns;
    p.p_world_body = Eigen::Vector3d(r.values[0], r.values[1], r.values[2]);
    p.sigma = Eigen::Vector3d(r.values[3], r.values[4], r.values[5]);
    if (!(p.sigma.minCoeff() > 0.0)) return lineError(path, r.line, "sigma_x, sigma_y and sigma_z must be > 0");
    priors.push_back(p);
  }
  return priors;
}

Status savePriorCsv(const std::vector<PositionPrior>& priors, const std::string& path) {
  VKLOC_TRY_STATUS(validatePriors(priors, path));
  return writeFileAtomically(path, priorText(priors));
}

// -----------------------------------------------------------------------------------------------
// Whole sequence.

Result<Sequence> loadSequence(const std::string& directory) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: sequence folder not found", directory));
  }
  const fs::path dir(directory);
  const std::string yaml_path = (dir / "sequence.yaml").string();
  auto loaded = loadYaml(yaml_path, "sequence file");
  if (!loaded.ok()) return loaded.error();
  Sequence seq;
  seq.directory = directory;
  try {
    const YAML::Node& root = *loaded;
    if (const YAML::Node n = root["name"]; n) {
      auto s = yamlString(yaml_path, n, "name");
      if (!s.ok()) return s.error();
      seq.name = *s;
    }
    if (const YAML::Node n = root["model"]; n) {
      auto s = yamlString(yaml_path, n, "model");
      if (!s.ok()) return s.error();
      seq.model = *s;
    }
    // What save refuses, load refuses: the name and model path are UTF-8.
    VKLOC_TRY_STATUS(checkUtf8(seq.name, "name", yaml_path));
    VKLOC_TRY_STATUS(checkUtf8(seq.model, "model", yaml_path));
    if (const YAML::Node n = root["T_world_model"]; n) {
      auto T = yamlPose(yaml_path, n, "T_world_model");
      if (!T.ok()) return T.error();
      seq.T_world_model = *T;
    }
    if (const YAML::Node n = root["unit_scale"]; n) {
      auto s = yamlDouble(yaml_path, n, "unit_scale");
      if (!s.ok()) return s.error();
      if (!(*s > 0.0)) return lineError(yaml_path, yamlLine(n), "'unit_scale' must be > 0");
      seq.unit_scale = *s;
    }
    if (const YAML::Node n = root["initial_T_world_camera"]; n && !n.IsNull()) {
      auto T = yamlPose(yaml_path, n, "initial_T_world_camera");
      if (!T.ok()) return T.error();
      seq.initial_T_world_camera = *T;
    }
    if (const YAML::Node n = root["initial_velocity_world"]; n && !n.IsNull()) {
      auto v = yamlNumbers(yaml_path, n, "initial_velocity_world");
      if (!v.ok()) return v.error();
      if (v->size() != 3) {
        return lineError(yaml_path, yamlLine(n),
                         fmt::format("'initial_velocity_world' needs 3 numbers (m/s), got {}", v->size()));
      }
      seq.initial_velocity_world = Eigen::Vector3d((*v)[0], (*v)[1], (*v)[2]);
    }
    if (const YAML::Node n = root["gravity_world"]; n) {
      auto g = yamlNumbers(yaml_path, n, "gravity_world");
      if (!g.ok()) return g.error();
      if (g->size() != 3) {
        return lineError(yaml_path, yamlLine(n), fmt::format("'gravity_world' needs 3 numbers, got {}", g->size()));
      }
      seq.gravity_world = Eigen::Vector3d((*g)[0], (*g)[1], (*g)[2]);
    }
    if (const YAML::Node n = root["imu_noise"]; n && !n.IsNull()) {
      if (!n.IsMap()) return lineError(yaml_path, yamlLine(n), "'imu_noise' must be a mapping");
      ImuNoise noise;
      struct Field {
        const char* key;
        double* out;
      };
      for (const Field& f :
           {Field{"rate_hz", &noise.rate_hz}, Field{"gyro_noise_density", &noise.gyro_noise_density},
            Field{"accel_noise_density", &noise.accel_noise_density},
            Field{"gyro_random_walk", &noise.gyro_random_walk}, Field{"accel_random_walk", &noise.accel_random_walk}}) {
        const YAML::Node v = n[f.key];
        if (!v) continue;  // Default value.
        auto d = yamlDouble(yaml_path, v, f.key);
        if (!d.ok()) return d.error();
        if (!(*d > 0.0)) return lineError(yaml_path, yamlLine(v), fmt::format("'{}' must be > 0", f.key));
        *f.out = *d;
      }
      seq.imu_noise = noise;
    }
  } catch (const YAML::Exception& e) {
    return lineError(yaml_path, static_cast<size_t>(e.mark.line + 1), "invalid sequence file: " + text::oneLine(e.msg));
  }

  auto camera = loadSequenceCamera((dir / "camera.yaml").string());
  if (!camera.ok()) return camera.error();
  seq.camera = std::move(*camera);
  auto images = loadImageList((dir / "images.txt").string());
  if (!images.ok()) return images.error();
  seq.images = std::move(*images);

  // Optional files: absent is fine, present must be valid.
  const std::string gt_path = (dir / "groundtruth.txt").string();
  if (fs::exists(gt_path, ec)) {
    auto gt = loadTumTrajectory(gt_path);
    if (!gt.ok()) return gt.error();
    seq.groundtruth = std::move(*gt);
  }
  const std::string imu_path = (dir / "imu.csv").string();
  if (fs::exists(imu_path, ec)) {
    auto imu = loadImuCsv(imu_path);
    if (!imu.ok()) return imu.error();
    seq.imu = std::move(*imu);
  }
  const std::string prior_path = (dir / "prior.csv").string();
  if (fs::exists(prior_path, ec)) {
    auto priors = loadPriorCsv(prior_path);
    if (!priors.ok()) return priors.error();
    seq.priors = std::move(*priors);
  }
  return seq;
}

Status saveSequence(const Sequence& seq, const std::string& directory) {
  const fs::path dir(directory);
  const std::string yaml_path = (dir / "sequence.yaml").string();
  // Validate everything before touching the folder.
  if (!finitePose(seq.T_world_model))
    return invalid(fmt::format("{}: T_world_model is not a rigid transform", yaml_path));
  if (!std::isfinite(seq.unit_scale) || seq.unit_scale <= 0.0) {
    return invalid(fmt::format("{}: unit_scale must be finite and > 0", yaml_path));
  }
  if (seq.initial_T_world_camera && !finitePose(*seq.initial_T_world_camera)) {
    return invalid(fmt::format("{}: initial_T_world_camera is not a rigid transform", yaml_path));
  }
  if (!seq.gravity_world.allFinite()) return invalid(fmt::format("{}: non-finite gravity_world", yaml_path));
  if (seq.initial_velocity_world && !seq.initial_velocity_world->allFinite()) {
    return invalid(fmt::format("{}: non-finite initial_velocity_world", yaml_path));
  }
  if (seq.imu_noise) VKLOC_TRY_STATUS(validateNoise(*seq.imu_noise, yaml_path));
  VKLOC_TRY_STATUS(checkUtf8(seq.name, "name", yaml_path));
  VKLOC_TRY_STATUS(checkUtf8(seq.model, "model", yaml_path));
  const std::string name = yamlQuoted(seq.name);
  const std::string model = yamlQuoted(seq.model);
  if (name.empty() || model.empty()) return invalid(fmt::format("{}: name or model is not valid text", yaml_path));
  const std::string camera_path = (dir / "camera.yaml").string();
  const std::string images_path = (dir / "images.txt").string();
  const std::string gt_path = (dir / "groundtruth.txt").string();
  const std::string imu_path = (dir / "imu.csv").string();
  const std::string prior_path = (dir / "prior.csv").string();
  VKLOC_TRY_STATUS(validateSequenceCamera(seq.camera, camera_path));
  VKLOC_TRY_STATUS(validateImages(seq.images, images_path));
  VKLOC_TRY_STATUS(validateTrajectory(seq.groundtruth, gt_path));
  VKLOC_TRY_STATUS(validateImu(seq.imu, imu_path));
  VKLOC_TRY_STATUS(validatePriors(seq.priors, prior_path));

  std::string yaml = "# vkloc sequence (metres, seconds; poses T_a_b map frame b into frame a)\n";
  yaml += fmt::format("name: {}\n", name);
  yaml += fmt::format("model: {}\n", model);
  yaml += fmt::format("T_world_model: {}\n", poseList16(seq.T_world_model));
  yaml += fmt::format("unit_scale: {}\n", num(seq.unit_scale));
  if (seq.initial_T_world_camera) {
    yaml += fmt::format("initial_T_world_camera: {}  # tx ty tz qx qy qz qw\n", poseList7(*seq.initial_T_world_camera));
  }
  if (seq.initial_velocity_world) {
    const Eigen::Vector3d& v = *seq.initial_velocity_world;
    yaml += fmt::format("initial_velocity_world: [{:.9g}, {:.9g}, {:.9g}]  # m/s, of the camera at the first image\n",
                        v.x(), v.y(), v.z());
  }
  yaml += fmt::format("gravity_world: {}  # m/s^2\n", numberList(seq.gravity_world.data(), 3));
  if (seq.imu_noise) {
    const ImuNoise& n = *seq.imu_noise;
    yaml += "imu_noise:\n";
    yaml += fmt::format("  rate_hz: {}\n", num(n.rate_hz));
    yaml += fmt::format("  gyro_noise_density: {}  # rad/s/sqrt(Hz)\n", num(n.gyro_noise_density));
    yaml += fmt::format("  accel_noise_density: {}  # m/s^2/sqrt(Hz)\n", num(n.accel_noise_density));
    yaml += fmt::format("  gyro_random_walk: {}  # rad/s^2/sqrt(Hz)\n", num(n.gyro_random_walk));
    yaml += fmt::format("  accel_random_walk: {}  # m/s^3/sqrt(Hz)\n", num(n.accel_random_walk));
  }

  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir, ec)) {
    return makeError(ErrorCode::kIoError, fmt::format("{}: cannot create sequence folder", directory));
  }
  // sequence.yaml is what makes a folder a sequence: an old one goes first and the new one is
  // written last, so a save stopped part way (killed, disk full) leaves a folder that does not
  // load rather than a sequence that mixes old and new files.
  if (fs::exists(yaml_path, ec) && !fs::remove(yaml_path, ec)) {
    return makeError(ErrorCode::kIoError, fmt::format("{}: cannot replace the old sequence file", yaml_path));
  }
  VKLOC_TRY_STATUS(writeFileAtomically(camera_path, cameraYaml(seq.camera)));
  VKLOC_TRY_STATUS(writeFileAtomically(images_path, imageListText(seq.images)));
  // Optional files: written when there is data, removed when stale so that a reload matches.
  struct Optional {
    const std::string& path;
    bool present;
    std::string (*content)(const Sequence&);
  };
  const Optional optionals[] = {
      {gt_path, !seq.groundtruth.empty(), [](const Sequence& s) { return trajectoryText(s.groundtruth); }},
      {imu_path, !seq.imu.empty(), [](const Sequence& s) { return imuText(s.imu); }},
      {prior_path, !seq.priors.empty(), [](const Sequence& s) { return priorText(s.priors); }}};
  for (const Optional& o : optionals) {
    if (o.present) {
      VKLOC_TRY_STATUS(writeFileAtomically(o.path, o.content(seq)));
    } else if (fs::exists(o.path, ec)) {
      if (!fs::remove(o.path, ec)) {
        return makeError(ErrorCode::kIoError, fmt::format("{}: cannot remove stale file", o.path));
      }
    }
  }
  return writeFileAtomically(yaml_path, yaml);
}

}  // namespace vkloc
