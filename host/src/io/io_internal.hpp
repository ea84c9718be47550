// Internal helpers of the io readers and writers: yaml-cpp access with "file:line: what" errors,
// number lists that read back exactly, and the camera.yaml pieces sequence_io.cpp shares with
// calibration.cpp.
#pragma once

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <charconv>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/io/calibration.hpp"

namespace vkloc::io_detail {

using text::lineError;
using text::shown;
using text::trim;

/// Formats a double so that reading it back gives the same value (17 significant digits).
inline std::string num(double v) { return fmt::format("{:.17g}", v); }

inline Status invalid(const std::string& message) { return makeError(ErrorCode::kInvalidArgument, message); }
inline bool finitePose(const Pose& T) { return isValidPose(T); }

// ---------------------------------------------------------------------------------------------
// YAML helpers. yaml-cpp lines are 0-based.

inline size_t yamlLine(const YAML::Node& node) { return static_cast<size_t>(node.Mark().line + 1); }

// ---------------------------------------------------------------------------------------------
// Limits that keep reading time and memory linear in the input (README, "Sequences").

/// Largest YAML file (sequence.yaml, camera.yaml, calibration and sensor YAML), bytes. Real
/// ones are a few KiB (an OpenCV calibration with every view's corners ~100 KiB); yaml-cpp
/// spends ~15 us and ~500 bytes per node, so 1 MiB of "[0,0,...]" takes ~7 s and ~250 MB.
constexpr uint64_t kMaxYamlBytes = uint64_t{1} << 20;
/// Largest table file (images.txt, groundtruth.txt and other TUM trajectories, imu.csv,
/// prior.csv, import CSVs, COLMAP cameras.txt), bytes: 2.6 h of 200 Hz IMU at ~140 bytes a line.
constexpr uint64_t kMaxTableBytes = uint64_t{1} << 28;
/// Longest line of a table, bytes (a path is at most 4096 bytes on Linux).
constexpr size_t kMaxLineBytes = size_t{1} << 16;
/// Most entries (images, poses, samples, cameras) in one table: 9.7 days of 20 Hz images.
constexpr size_t kMaxTableEntries = size_t{1} << 24;

/// Reads a table file within kMaxTableBytes.
inline Result<std::string> readTable(const std::string& path, const char* what) {
  return text::readFile(path, what, kMaxTableBytes);
}

/// Line and entry limits of a table; empty string or what is wrong (for lineError).
inline std::string tableLimits(std::string_view line, size_t entries) {
  if (line.size() > kMaxLineBytes) return fmt::format("line is longer than {} bytes", kMaxLineBytes);
  if (entries >= kMaxTableEntries) return fmt::format("more than {} entries", kMaxTableEntries);
  return {};
}

/// Quoted scalars that run to the end of the text: yaml-cpp accepts `fx: "500` followed by a
/// line break as the string "500 ". Returns the 1-based line of the first one, or 0.
size_t unterminatedYamlQuote(const std::string& text);

/// Parses YAML text (path for messages): kMalformedInput "path:line: not valid YAML: ..." with
/// yaml-cpp's message made printable, an unterminated quoted string refused.
Result<YAML::Node> parseYaml(const std::string& path, const std::string& text);

/// Reads (within kMaxYamlBytes) and parses a YAML file whose root must be a mapping.
Result<YAML::Node> loadYaml(const std::string& path, const char* what);

inline Result<double> yamlDouble(const std::string& path, const YAML::Node& node, const char* key) {
  if (!node.IsScalar()) return lineError(path, yamlLine(node), fmt::format("'{}' must be a number", key));
  double v = 0.0;
  const std::string wrong = text::parseDouble(trim(node.Scalar()), v);
  if (!wrong.empty()) return lineError(path, yamlLine(node), fmt::format("'{}': {}", key, wrong));
  return v;
}

inline Result<int> yamlInt(const std::string& path, const YAML::Node& node, const char* key) {
  if (!node.IsScalar()) return lineError(path, yamlLine(node), fmt::format("'{}' must be an integer", key));
  const std::string_view s = trim(node.Scalar());
  int v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) {
    return lineError(path, yamlLine(node), fmt::format("'{}': {} is not an integer", key, shown(s)));
  }
  return v;
}

inline Result<std::string> yamlString(const std::string& path, const YAML::Node& node, const char* key) {
  if (node.IsNull()) return std::string();
  if (!node.IsScalar()) return lineError(path, yamlLine(node), fmt::format("'{}' must be a string", key));
  return node.Scalar();
}

inline Result<std::vector<double>> yamlNumbers(const std::string& path, const YAML::Node& node, const char* key) {
  std::vector<double> v;
  if (node.IsNull()) return v;
  if (!node.IsSequence()) return lineError(path, yamlLine(node), fmt::format("'{}' must be a list of numbers", key));
  for (size_t i = 0; i < node.size(); ++i) {
    auto d = yamlDouble(path, node[i], key);
    if (!d.ok()) return d.error();
    v.push_back(*d);
  }
  return v;
}

/// A pose given as a list (7 numbers "tx ty tz qx qy qz qw" or 16 row-major) or as a string.
inline Result<Pose> yamlPose(const std::string& path, const YAML::Node& node, const char* key) {
  std::string text;
  if (node.IsScalar()) {
    text = node.Scalar();
  } else {
    auto numbers = yamlNumbers(path, node, key);
    if (!numbers.ok()) return numbers.error();
    for (double d : *numbers) text += num(d) + " ";
  }
  auto pose = parsePose(text);
  if (!pose.ok()) return lineError(path, yamlLine(node), fmt::format("'{}': {}", key, pose.error().message));
  return *pose;
}

inline std::string yamlQuoted(const std::string& s) {
  YAML::Emitter e;
  e << YAML::DoubleQuoted << s;
  return e.good() ? std::string(e.c_str()) : std::string();
}

inline std::string poseList16(const Pose& T) {
  std::string out = "[";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out += num(T.matrix()(r, c)) + (r == 3 && c == 3 ? "]" : ", ");
  }
  return out;
}

inline std::string poseList7(const Pose& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  return fmt::format("[{}, {}, {}, {}, {}, {}, {}]", num(t.x()), num(t.y()), num(t.z()), num(q.x()), num(q.y()),
                     num(q.z()), num(q.w()));
}

inline std::string numberList(const double* v, size_t n) {
  std::string out = "[";
  for (size_t i = 0; i < n; ++i) out += (i ? ", " : "") + num(v[i]);
  return out + "]";
}

/// Checks a camera before it is written; kInvalidArgument "what: ..." otherwise.
Status validateSequenceCamera(const SequenceCamera& camera, const std::string& what);
/// camera.yaml text of a validated camera.
std::string cameraYaml(const SequenceCamera& camera);
/// Reads camera.yaml keys from a parsed mapping (errors "path:line: ..."); loadSequenceCamera
/// and loadCalibration share it.
Result<SequenceCamera> readSequenceCamera(const std::string& path, const YAML::Node& root);
/// Reads a Kalibr / EuRoC single-camera sensor.yaml (camera_model, intrinsics, distortion_model,
/// distortion_coefficients, resolution, T_BS); the EuRoC importer and loadCalibration share it.
Result<SequenceCamera> loadKalibrSensorCamera(const std::string& path);

}  // namespace vkloc::io_detail
