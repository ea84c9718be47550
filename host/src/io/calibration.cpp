// camera.yaml and plain intrinsics files.
#include "vkloc/io/calibration.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

#include "io/io_internal.hpp"
#include "vkloc/core/atomic_file.hpp"

namespace vkloc {

using namespace io_detail;

namespace {

/// Number of distortion coefficients a model accepts.
bool distortionCountOk(const std::string& model, size_t n) {
  if (model == "pinhole") return n == 0 || n == 4 || n == 5;
  if (model == "kannala_brandt") return n == 0 || n == 4;
  if (model == "mei") return n == 0 || n == 4;
  return false;
}

bool knownModel(const std::string& model) { return model == "pinhole" || model == "mei" || model == "kannala_brandt"; }

}  // namespace

Status io_detail::validateSequenceCamera(const SequenceCamera& camera, const std::string& what) {
  if (!knownModel(camera.model)) {
    return invalid(fmt::format("{}: unknown camera model '{}' (pinhole, mei, kannala_brandt)", what, camera.model));
  }
  const Status valid = validateCamera(camera.intrinsics);
  if (!valid.ok()) return invalid(fmt::format("{}: {}", what, valid.error().message));
  if (!distortionCountOk(camera.model, camera.distortion.size())) {
    return invalid(fmt::format("{}: {} distortion coefficients do not fit model '{}'", what, camera.distortion.size(),
                               camera.model));
  }
  for (double d : camera.distortion) {
    if (!std::isfinite(d)) return invalid(fmt::format("{}: non-finite distortion coefficient", what));
  }
  if (!std::isfinite(camera.xi)) return invalid(fmt::format("{}: non-finite xi", what));
  if (!finitePose(camera.T_body_camera))
    return invalid(fmt::format("{}: T_body_camera is not a rigid transform", what));
  return Status::success();
}

// Content builders (validation happens before).

std::string io_detail::cameraYaml(const SequenceCamera& camera) {
  const PinholeCamera& k = camera.intrinsics;
  std::string out = "# vkloc sequence camera (pixels; T_body_camera row-major 4x4, metres)\n";
  out += fmt::format("model: {}\n", camera.model);
  out += fmt::format("fx: {}\nfy: {}\ncx: {}\ncy: {}\n", num(k.fx), num(k.fy), num(k.cx), num(k.cy));
  out += fmt::format("width: {}\nheight: {}\n", k.width, k.height);
  out += fmt::format("distortion: {}\n", numberList(camera.distortion.data(), camera.distortion.size()));
  out += fmt::format("xi: {}\n", num(camera.xi));
  out += fmt::format("T_body_camera: {}\n", poseList16(camera.T_body_camera));
  return out;
}

// -----------------------------------------------------------------------------------------------
// camera.yaml

Result<SequenceCamera> loadSequenceCamera(const std::string& path) {
  auto loaded = loadYaml(path, "camera file");
  if (!loaded.ok()) return loaded.error();
  try {
    const YAML::Node& root = *loaded;
    SequenceCamera camera;
    if (const YAML::Node m = root["model"]; m) {
      auto model = yamlString(path, m, "model");
      if (!model.ok()) return model.error();
      camera.model = *model;
      if (!knownModel(camera.model)) {
        return makeError(ErrorCode::kUnsupported,
                         fmt::format("{}:{}: camera model {} is not supported (pinhole, mei, kannala_brandt)", path,
                                     yamlLine(m), shown(camera.model)));
      }
    }
    PinholeCamera& k = camera.intrinsics;
    struct DoubleField {
      const char* key;
      double* out;
    };
    for (const DoubleField& f :
         {DoubleField{"fx", &k.fx}, DoubleField{"fy", &k.fy}, DoubleField{"cx", &k.cx}, DoubleField{"cy", &k.cy}}) {
      const YAML::Node n = root[f.key];
      if (!n) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: missing key '{}'", path, f.key));
      auto v = yamlDouble(path, n, f.key);
      if (!v.ok()) return v.error();
      *f.out = *v;
    }
    for (const char* key : {"width", "height"}) {
      const YAML::Node n = root[key];
      if (!n) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: missing key '{}'", path, key));
      auto v = yamlInt(path, n, key);
      if (!v.ok()) return v.error();
      (std::string_view(key) == "width" ? k.width : k.height) = *v;
    }
    if (const Status valid = validateCamera(k); !valid.ok()) {
      // Find the offending key (validateCamera names it) to point at its line: check each field
      // alone on an otherwise valid camera.
      size_t line = 1;
      const PinholeCamera good;
      const std::pair<const char*, PinholeCamera> probes[] = {
          {"fx", PinholeCamera{k.fx, good.fy, good.cx, good.cy, good.width, good.height}},
          {"fy", PinholeCamera{good.fx, k.fy, good.cx, good.cy, good.width, good.height}},
          {"cx", PinholeCamera{good.fx, good.fy, k.cx, good.cy, good.width, good.height}},
          {"cy", PinholeCamera{good.fx, good.fy, good.cx, k.cy, good.width, good.height}},
          {"width", PinholeCamera{good.fx, good.fy, good.cx, good.cy, k.width, good.height}},
          {"height", PinholeCamera{good.fx, good.fy, good.cx, good.cy, good.width, k.height}}};
      for (const auto& [key, probe] : probes) {
        if (!validateCamera(probe).ok()) {
          line = yamlLine(root[key]);
          break;
        }
      }
      return lineError(path, line, valid.error().message);
    }
    if (const YAML::Node n = root["distortion"]; n) {
      auto d = yamlNumbers(path, n, "distortion");
      if (!d.ok()) return d.error();
      camera.distortion = *d;
      if (!distortionCountOk(camera.model, camera.distortion.size())) {
        return lineError(path, yamlLine(n),
                         fmt::format("{} distortion coefficients do not fit model '{}' (pinhole: 0, 4 or 5; mei and "
                                     "kannala_brandt: 4)",
                                     camera.distortion.size(), camera.model));
      }
    }
    if (const YAML::Node n = root["xi"]; n) {
      auto xi = yamlDouble(path, n, "xi");
      if (!xi.ok()) return xi.error();
      camera.xi = *xi;
    }
    if (const YAML::Node n = root["T_body_camera"]; n) {
      auto T = yamlPose(path, n, "T_body_camera");
      if (!T.ok()) return T.error();
      camera.T_body_camera = *T;
    }
    return camera;
  } catch (const YAML::Exception& e) {
    return lineError(path, static_cast<size_t>(e.mark.line + 1), fmt::format("invalid camera file: {}", e.msg));
  }
}

Status saveSequenceCamera(const SequenceCamera& camera, const std::string& path) {
  VKLOC_TRY_STATUS(validateSequenceCamera(camera, path));
  return writeFileAtomically(path, cameraYaml(camera));
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
