#include "vkloc/camera.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace vkloc {

Status validateCamera(const PinholeCamera& c) {
  auto bad = [](const char* field, double v) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("camera: {} = {} is invalid", field, v));
  };
  // Focal lengths from 0.01 to 1e7 px and principal points within 1e6 px keep every projection
  // term representable in float on the GPU.
  if (!(c.fx >= 0.01 && c.fx <= 1e7)) return bad("fx", c.fx);
  if (!(c.fy >= 0.01 && c.fy <= 1e7)) return bad("fy", c.fy);
  if (!(std::abs(c.cx) <= 1e6)) return bad("cx", c.cx);
  if (!(std::abs(c.cy) <= 1e6)) return bad("cy", c.cy);
  if (c.width < 1 || c.width > 16384) return bad("width", c.width);
  if (c.height < 1 || c.height > 16384) return bad("height", c.height);
  return Status::success();
}

Result<PinholeCamera> loadCamera(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return makeError(ErrorCode::kNotFound, fmt::format("{}: camera file not found", path));
  }
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);  // JSON is a subset of YAML.
  } catch (const std::exception& e) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: not valid YAML/JSON: {}", path, e.what()));
  }
  if (!root.IsMap()) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: expected a mapping of camera fields", path));
  }
  // Accept both a flat file and one with an `intrinsics:` / `camera:` sub-map.
  YAML::Node node = root;
  for (const char* key : {"camera", "intrinsics"}) {
    if (root[key] && root[key].IsMap()) node = root[key];
  }
  if (node["model"] && node["model"].IsScalar()) {
    const std::string model = node["model"].as<std::string>();
    if (model != "pinhole") {
      return makeError(ErrorCode::kUnsupported,
                       fmt::format("{}: camera model '{}' is not supported here (use pinhole)", path, model));
    }
  }
  PinholeCamera cam;
  auto read = [&](const char* key, auto& out) -> Status {
    const YAML::Node v = node[key];
    if (!v) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: missing field '{}'", path, key));
    try {
      out = v.as<std::remove_reference_t<decltype(out)>>();
    } catch (const std::exception&) {
      return makeError(ErrorCode::kMalformedInput,
                       fmt::format("{}: field '{}' (line {}) is not a number", path, key, v.Mark().line + 1));
    }
    return Status::success();
  };
  VKLOC_TRY_STATUS(read("fx", cam.fx));
  VKLOC_TRY_STATUS(read("fy", cam.fy));
  VKLOC_TRY_STATUS(read("cx", cam.cx));
  VKLOC_TRY_STATUS(read("cy", cam.cy));
  VKLOC_TRY_STATUS(read("width", cam.width));
  VKLOC_TRY_STATUS(read("height", cam.height));
  Status valid = validateCamera(cam);
  if (!valid.ok()) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: {}", path, valid.error().message));
  }
  return cam;
}

}  // namespace vkloc
