// camera.yaml and plain intrinsics files.
#include "vkloc/io/calibration.hpp"

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <sstream>

#include "io/io_internal.hpp"
#include "vkloc/core/atomic_file.hpp"

namespace vkloc {

using namespace io_detail;

namespace {

/// Finds the first quoted scalar of a YAML text that is never closed (yaml-cpp's scanner takes
/// the end of the text as the closing quote when a line break precedes it).
class QuoteChecker : public YAML::EventHandler {
 public:
  explicit QuoteChecker(const std::string& text) : text_(text) {}
  size_t line = 0;  ///< 1-based line of the opening quote, 0 when every quote is closed.

  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string&) override {
    if (line != 0 || mark.pos < 0) return;
    size_t i = static_cast<size_t>(mark.pos);
    // Skip node properties (a tag "!..." and an anchor "&..."), which the mark includes.
    while (i < text_.size() && (text_[i] == '!' || text_[i] == '&')) {
      while (i < text_.size() && !std::isspace(static_cast<unsigned char>(text_[i]))) ++i;
      while (i < text_.size() && std::isspace(static_cast<unsigned char>(text_[i]))) ++i;
    }
    if (i >= text_.size() || (text_[i] != '"' && text_[i] != '\'')) return;
    const char quote = text_[i];
    for (size_t k = i + 1; k < text_.size(); ++k) {
      if (quote == '"' && text_[k] == '\\') {
        ++k;  // An escape: the next byte is not the closing quote.
      } else if (text_[k] == quote) {
        if (quote == '\'' && k + 1 < text_.size() && text_[k + 1] == '\'') {
          ++k;  // '' inside single quotes is one quote.
        } else {
          return;
        }
      }
    }
    line = static_cast<size_t>(mark.line + 1);
  }
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}

 private:
  const std::string& text_;
};

/// Number of distortion coefficients a model accepts.
bool distortionCountOk(const std::string& model, size_t n) {
  if (model == "pinhole") return n == 0 || n == 4 || n == 5;
  if (model == "kannala_brandt") return n == 0 || n == 4;
  if (model == "mei") return n == 0 || n == 4;
  if (model == "double_sphere") return n == 0;
  return false;
}

constexpr const char* kDistortionCounts = "pinhole: 0, 4 or 5; kannala_brandt and mei: 0 or 4; double_sphere: 0";

bool knownModel(const std::string& model) {
  return model == "pinhole" || model == "mei" || model == "kannala_brandt" || model == "double_sphere";
}

/// The camera.yaml key that holds the parameter a validateCamera / validateLensCamera message
/// starts with ("camera: fx = ...", "k1 = nan: ...").
std::string keyOfParameter(std::string_view message) {
  if (message.rfind("camera: ", 0) == 0) message.remove_prefix(8);
  if (message.find("distortion folds") != std::string_view::npos) return "distortion";
  size_t n = 0;
  while (n < message.size() && (std::isalnum(static_cast<unsigned char>(message[n])) || message[n] == '_')) ++n;
  const std::string name(message.substr(0, n));
  for (const char* key : {"fx", "fy", "cx", "cy", "width", "height", "xi", "alpha", "max_angle_deg", "model"}) {
    if (name == key) return name;
  }
  if (name == "k1" || name == "k2" || name == "k3" || name == "k4" || name == "p1" || name == "p2" ||
      name == "distortion") {
    return "distortion";
  }
  return {};
}

}  // namespace

Result<LensCamera> lensCamera(const SequenceCamera& camera) {
  auto model = parseLensModel(camera.model);
  if (!model.ok()) return makeError(ErrorCode::kInvalidArgument, fmt::format("model: {}", model.error().message));
  LensCamera lens;
  lens.model = *model;
  lens.intrinsics = camera.intrinsics;
  if (!distortionCountOk(camera.model, camera.distortion.size())) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("distortion: {} coefficients do not fit model '{}' ({})", camera.distortion.size(),
                                 camera.model, kDistortionCounts));
  }
  std::copy(camera.distortion.begin(), camera.distortion.end(), lens.k.begin());
  lens.xi = camera.xi;
  lens.alpha = camera.alpha;
  lens.max_angle_deg = camera.max_angle_deg;
  if (const Status valid = validateLensCamera(lens); !valid.ok())
    return makeError(ErrorCode::kInvalidArgument, valid.error().message);
  return lens;
}

SequenceCamera sequenceCamera(const LensCamera& camera, const Pose& T_body_camera) {
  SequenceCamera out;
  out.model = lensModelName(camera.model);
  out.intrinsics = camera.intrinsics;
  size_t n = 0;
  switch (camera.model) {
    case LensModel::kPinhole:
      n = camera.k[4] != 0.0 ? 5 : 4;
      break;
    case LensModel::kKannalaBrandt:
    case LensModel::kMei:
      n = 4;
      break;
    case LensModel::kDoubleSphere:
      n = 0;
      break;
  }
  if (std::any_of(camera.k.begin(), camera.k.begin() + static_cast<std::ptrdiff_t>(n),
                  [](double k) { return k != 0.0; })) {
    out.distortion.assign(camera.k.begin(), camera.k.begin() + static_cast<std::ptrdiff_t>(n));
  }
  out.xi = camera.model == LensModel::kMei || camera.model == LensModel::kDoubleSphere ? camera.xi : 0.0;
  out.alpha = camera.model == LensModel::kDoubleSphere ? camera.alpha : 0.0;
  out.max_angle_deg = camera.max_angle_deg;
  out.T_body_camera = T_body_camera;
  return out;
}

Status io_detail::validateSequenceCamera(const SequenceCamera& camera, const std::string& what) {
  if (!knownModel(camera.model)) {
    return invalid(
        fmt::format("{}: unknown camera model '{}' (pinhole, mei, kannala_brandt, double_sphere)", what, camera.model));
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
  if (!std::isfinite(camera.alpha)) return invalid(fmt::format("{}: non-finite alpha", what));
  if (!std::isfinite(camera.max_angle_deg)) return invalid(fmt::format("{}: non-finite max_angle_deg", what));
  if (auto lens = lensCamera(camera); !lens.ok()) return invalid(fmt::format("{}: {}", what, lens.error().message));
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
  if (camera.model == "double_sphere") out += fmt::format("alpha: {}\n", num(camera.alpha));
  if (camera.max_angle_deg != 0.0) out += fmt::format("max_angle_deg: {}\n", num(camera.max_angle_deg));
  out += fmt::format("T_body_camera: {}\n", poseList16(camera.T_body_camera));
  return out;
}

// -----------------------------------------------------------------------------------------------
// camera.yaml

Result<SequenceCamera> io_detail::readSequenceCamera(const std::string& path, const YAML::Node& root) {
  try {
    SequenceCamera camera;
    if (const YAML::Node m = root["model"]; m) {
      auto model = yamlString(path, m, "model");
      if (!model.ok()) return model.error();
      camera.model = *model;
      if (!knownModel(camera.model)) {
        return makeError(ErrorCode::kUnsupported,
                         fmt::format("{}:{}: camera model {} is not supported (pinhole, mei, kannala_brandt, "
                                     "double_sphere)",
                                     path, yamlLine(m), shown(camera.model)));
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
      if (!n) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: field '{}': missing", path, f.key));
      auto v = yamlDouble(path, n, f.key);
      if (!v.ok()) return v.error();
      *f.out = *v;
    }
    for (const char* key : {"width", "height"}) {
      const YAML::Node n = root[key];
      if (!n) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: field '{}': missing", path, key));
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
                         fmt::format("{} distortion coefficients do not fit model '{}' ({})", camera.distortion.size(),
                                     camera.model, kDistortionCounts));
      }
    }
    struct OptionalField {
      const char* key;
      double* out;
    };
    for (const OptionalField& f : {OptionalField{"xi", &camera.xi}, OptionalField{"alpha", &camera.alpha},
                                   OptionalField{"max_angle_deg", &camera.max_angle_deg}}) {
      if (const YAML::Node n = root[f.key]; n) {
        auto v = yamlDouble(path, n, f.key);
        if (!v.ok()) return v.error();
        *f.out = *v;
      }
    }
    if (const YAML::Node n = root["T_body_camera"]; n) {
      auto T = yamlPose(path, n, "T_body_camera");
      if (!T.ok()) return T.error();
      camera.T_body_camera = *T;
    }
    if (auto lens = lensCamera(camera); !lens.ok()) {
      std::string_view message = lens.error().message;
      if (message.rfind("camera: ", 0) == 0) message.remove_prefix(8);
      const std::string key = keyOfParameter(message);
      const YAML::Node n = key.empty() ? YAML::Node() : root[key];
      return lineError(path, n ? yamlLine(n) : 1,
                       key.empty() ? std::string(message) : fmt::format("field '{}': {}", key, message));
    }
    return camera;
  } catch (const YAML::Exception& e) {
    return lineError(path, static_cast<size_t>(e.mark.line + 1), "invalid camera file: " + text::oneLine(e.msg));
  }
}

size_t io_detail::unterminatedYamlQuote(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  QuoteChecker checker(text);
  parser.HandleNextDocument(checker);  // The first document, the one YAML::Load reads.
  return checker.line;
}

Result<YAML::Node> io_detail::parseYaml(const std::string& path, const std::string& text) {
  try {
    if (const size_t line = unterminatedYamlQuote(text); line != 0) {
      return lineError(path, line, "not valid YAML: a quoted string opened here is never closed");
    }
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    return lineError(path, static_cast<size_t>(e.mark.line + 1), "not valid YAML: " + text::oneLine(e.msg));
  } catch (const std::exception& e) {
    return makeError(ErrorCode::kMalformedInput, text::oneLine(fmt::format("{}: not valid YAML: {}", path, e.what())));
  }
}

Result<YAML::Node> io_detail::loadYaml(const std::string& path, const char* what) {
  auto text = text::readFile(path, what, kMaxYamlBytes);
  if (!text.ok()) return text.error();
  auto root = parseYaml(path, *text);
  if (!root.ok()) return root.error();
  if (!root->IsMap()) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}:1: expected a mapping of {} keys", path, what));
  }
  return root;
}

Result<SequenceCamera> loadSequenceCamera(const std::string& path) {
  auto loaded = loadYaml(path, "camera file");
  if (!loaded.ok()) return loaded.error();
  return readSequenceCamera(path, *loaded);
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
  auto text = text::readFile(path, "camera file", kMaxYamlBytes);
  if (!text.ok()) return text.error();
  auto parsed = parseYaml(path, *text);  // JSON is a subset of YAML.
  if (!parsed.ok()) return parsed.error();
  const YAML::Node root = *parsed;
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
                       fmt::format("{}: camera model {} is not supported here (use pinhole)", path, shown(model)));
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
