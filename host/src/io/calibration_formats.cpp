// Calibration files of other tools, told apart by their keys: Kalibr camchain.yaml and EuRoC /
// Kalibr sensor.yaml, OpenCV FileStorage and ROS camera_info YAML, CamOdoCal YAML, COLMAP
// cameras.txt; plus vkloc's own camera.yaml. Every reader ends in lensCamera(), so a camera
// that loads is one vkloc can project with.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <optional>
#include <tuple>
#include <utility>

#include "io/io_internal.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/io/calibration.hpp"

namespace vkloc {

using namespace io_detail;

namespace {

/// Line of a node in its file (1-based); 0 when unknown.
size_t lineOf(const YAML::Node& node) { return node && node.Mark().line >= 0 ? yamlLine(node) : 0; }

/// Where an error is: the file, the line when known and, in a file of several cameras, the
/// camera ("cam1").
struct Where {
  std::string path;
  std::string camera;
  size_t line = 0;

  /// The same place at a node's line.
  Where at(const YAML::Node& node) const { return Where{path, camera, lineOf(node)}; }
  Where at(size_t at_line) const { return Where{path, camera, at_line}; }
  /// "path[:line]: [camera: ]what", one line.
  Error error(ErrorCode code, const std::string& what) const {
    std::string message = line > 0 ? fmt::format("{}:{}: ", path, line) : path + ": ";
    if (!camera.empty()) message += camera + ": ";
    return makeError(code, text::oneLine(message + what));
  }
  /// "path[:line]: [camera: ]field 'key': what".
  Error field(const std::string& key, const std::string& what, ErrorCode code = ErrorCode::kMalformedInput) const {
    return error(code, fmt::format("field '{}': {}", key, what));
  }
};

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

bool allDigits(std::string_view s) {
  return !s.empty() &&
         std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

bool allZero(const std::vector<double>& v, size_t from = 0) {
  return std::all_of(v.begin() + static_cast<std::ptrdiff_t>(std::min(from, v.size())), v.end(),
                     [](double d) { return d == 0.0; });
}

// ---------------------------------------------------------------------------------------------
// Field readers: "field 'key': what" errors, no exceptions.

/// The first of `keys` present in the mapping (its name and node), if any.
std::optional<std::pair<std::string, YAML::Node>> firstKey(const YAML::Node& map,
                                                           std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (const YAML::Node n = map[key]; n) return std::make_pair(std::string(key), n);
  }
  return std::nullopt;
}

Result<double> readNumber(const Where& w, const YAML::Node& node, const std::string& key) {
  if (!node) return w.field(key, "missing");
  if (!node.IsScalar()) return w.at(node).field(key, "expected a number");
  double v = 0.0;
  const std::string_view token = text::trim(node.Scalar());
  std::string wrong = text::parseDouble(token, v);
  // YAML's and OpenCV's spellings of NaN and infinity (.nan, .NaN, .Nan, -.inf).
  const std::string spelled = text::lower(token);
  if (!wrong.empty() && (spelled == ".nan" || spelled == ".inf" || spelled == "+.inf" || spelled == "-.inf")) {
    wrong = "non-finite value " + shown(token);
  }
  if (!wrong.empty()) return w.at(node).field(key, wrong);
  return v;
}

Result<int> readInt(const Where& w, const YAML::Node& node, const std::string& key) {
  if (!node) return w.field(key, "missing");
  if (!node.IsScalar()) return w.at(node).field(key, "expected a whole number of pixels");
  int64_t v = 0;
  const std::string wrong = text::parseInt64(text::trim(node.Scalar()), v);
  if (!wrong.empty()) return w.at(node).field(key, wrong);
  if (v < 1 || v > 16384) return w.at(node).field(key, fmt::format("{} is outside 1..16384 pixels", v));
  return static_cast<int>(v);
}

/// A number in a sub-mapping: parent.key (CamOdoCal's projection_parameters.gamma1).
Result<double> readNested(const Where& w, const YAML::Node& root, const char* parent, const char* key) {
  const YAML::Node p = root[parent];
  if (!p) return w.field(parent, "missing");
  if (!p.IsMap()) return w.at(p).field(parent, "expected a mapping");
  return readNumber(w, p[key], fmt::format("{}.{}", parent, key));
}

/// A list of numbers: a YAML sequence (nested sequences flattened row by row, as Kalibr writes a
/// 4x4 matrix) or an OpenCV / ROS matrix mapping {rows, cols, [dt,] data}.
Result<std::vector<double>> readNumbers(const Where& w, const YAML::Node& node, const std::string& key) {
  if (!node) return w.field(key, "missing");
  std::vector<double> out;
  if (node.IsNull()) return out;
  if (node.IsMap()) {
    const YAML::Node data = node["data"];
    if (!data) return w.at(node).field(key, "missing 'data' of the matrix");
    auto numbers = readNumbers(w, data, key);
    if (!numbers.ok()) return numbers.error();
    const YAML::Node rows = node["rows"];
    const YAML::Node cols = node["cols"];
    if (rows && cols) {
      int64_t r = 0, c = 0;
      if (!rows.IsScalar() || !cols.IsScalar() || !text::parseInt64(text::trim(rows.Scalar()), r).empty() ||
          !text::parseInt64(text::trim(cols.Scalar()), c).empty() || r < 0 || c < 0) {
        return w.at(node).field(key, "'rows' and 'cols' must be whole numbers");
      }
      // Each of r and c is at most the count before they are multiplied (no overflow).
      const auto count = static_cast<int64_t>(numbers->size());
      if (r > count || c > count || r * c != count) {
        return w.at(data).field(key, fmt::format("{}x{} matrix but 'data' holds {} numbers", r, c, numbers->size()));
      }
    }
    return numbers;
  }
  if (!node.IsSequence()) return w.at(node).field(key, "expected a list of numbers");
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node e = node[i];
    if (e.IsSequence()) {
      for (size_t j = 0; j < e.size(); ++j) {
        auto v = readNumber(w, e[j], key);
        if (!v.ok()) return v.error();
        out.push_back(*v);
      }
      continue;
    }
    auto v = readNumber(w, e, key);
    if (!v.ok()) return v.error();
    out.push_back(*v);
  }
  return out;
}

/// [width, height].
Result<std::pair<int, int>> readSize(const Where& w, const YAML::Node& node, const std::string& key) {
  if (!node) return w.field(key, "missing");
  if (!node.IsSequence() || node.size() != 2) return w.at(node).field(key, "expected [width, height]");
  auto width = readInt(w, node[0], key);
  if (!width.ok()) return width.error();
  auto height = readInt(w, node[1], key);
  if (!height.ok()) return height.error();
  return std::make_pair(*width, *height);
}

/// A rigid 4x4 transform (16 numbers, row-major). The rotation must be orthonormal to 1e-3 (it
/// is then projected onto SO(3): printed matrices carry rounding) and the last row 0 0 0 1.
Result<Pose> readRigid(const Where& w, const YAML::Node& node, const std::string& key) {
  auto m = readNumbers(w, node, key);
  if (!m.ok()) return m.error();
  const Where here = w.at(node.IsMap() && node["data"] ? node["data"] : node);
  if (m->size() != 16) return here.field(key, fmt::format("expected a 4x4 matrix (16 numbers), got {}", m->size()));
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i) M(i / 4, i % 4) = (*m)[static_cast<size_t>(i)];
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 || R.determinant() <= 0 ||
      (M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    return here.field(key, "not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Pose T = Pose::Identity();
  T.linear() = svd.matrixU() * svd.matrixV().transpose();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

Result<std::string> readName(const Where& w, const YAML::Node& node, const std::string& key) {
  if (!node) return w.field(key, "missing");
  if (!node.IsScalar()) return w.at(node).field(key, "expected a name");
  return std::string(text::trim(node.Scalar()));
}

// ---------------------------------------------------------------------------------------------
// Final check: lensCamera() (validateLensCamera), its message pointed at the file's field.

/// The parameter a lensCamera() message starts with: "camera: fx = 0 is invalid" -> "fx",
/// "camera: k1 = nan: not finite" -> "k1", "distortion: ..." and "camera: the pinhole distortion
/// folds over ..." -> "distortion".
std::string parameterOf(std::string_view message) {
  if (message.rfind("camera: ", 0) == 0) message.remove_prefix(8);
  if (message.find("distortion folds") != std::string_view::npos) return "distortion";
  size_t n = 0;
  while (n < message.size() && (std::isalnum(static_cast<unsigned char>(message[n])) || message[n] == '_')) ++n;
  return std::string(message.substr(0, n));
}

/// A field of the file and its line (0: unknown).
struct FieldRef {
  std::string key;
  size_t line = 0;
};
/// Parameter name (fx fy cx cy width height k1..k4 p1 p2 xi alpha distortion) -> file field.
using FieldOf = std::map<std::string, FieldRef>;

/// The field of every distortion parameter.
void distortionField(FieldOf& fields, const FieldRef& field) {
  for (const char* p : {"k1", "k2", "k3", "k4", "p1", "p2", "distortion"}) fields[p] = field;
}

Result<SequenceCamera> finish(const Where& w, const SequenceCamera& camera, const FieldOf& fields) {
  auto lens = lensCamera(camera);
  if (!lens.ok()) {
    std::string_view message = lens.error().message;
    if (message.rfind("camera: ", 0) == 0) message.remove_prefix(8);
    const auto it = fields.find(parameterOf(message));
    return it == fields.end() ? w.error(ErrorCode::kMalformedInput, std::string(message))
                              : w.at(it->second.line).field(it->second.key, std::string(message));
  }
  return sequenceCamera(*lens, camera.T_body_camera);
}

/// Selection in a file of one camera: empty, "0", "cam0" or its name.
Status selectSingle(const Where& w, const std::string& select, const std::string& name = "") {
  if (select.empty() || select == "0" || select == "cam0" || (!name.empty() && select == name)) {
    return Status::success();
  }
  return w.error(ErrorCode::kNotFound,
                 fmt::format("no camera {} (the file holds one camera{}; select it with '0'{})", shown(select),
                             name.empty() ? "" : " named " + shown(name), name.empty() ? "" : " or its name"));
}

// ---------------------------------------------------------------------------------------------
// Kalibr: camchain.yaml entries and single-camera sensor.yaml (EuRoC).

/// One Kalibr camera. Kalibr models: pinhole [fu fv pu pv], omni [xi fu fv pu pv] (Mei),
/// ds [xi alpha fu fv pu pv] (double sphere), eucm [alpha beta fu fv pu pv] (not supported);
/// distortion radtan [k1 k2 r1 r2] (EuRoC writes "radial-tangential"; a 5th k3 is accepted for
/// pinhole), equidistant [k1 k2 k3 k4] (pinhole only: Kannala-Brandt), none, fov (unsupported).
/// Mounting: T_BS (EuRoC: body from sensor) or T_cam_imu (inverted); identity without either.
Result<SequenceCamera> readKalibrCamera(const Where& w, const YAML::Node& node) {
  if (!node.IsMap()) return w.error(ErrorCode::kMalformedInput, "expected a mapping of camera fields");
  std::string camera_model = "pinhole";
  const YAML::Node camera_model_node = node["camera_model"];
  if (const YAML::Node n = camera_model_node; n) {
    auto name = readName(w, n, "camera_model");
    if (!name.ok()) return name.error();
    camera_model = text::lower(*name);
  }
  size_t n_intrinsics = 0;
  const char* intrinsics_order = "";
  if (camera_model == "pinhole") {
    n_intrinsics = 4;
    intrinsics_order = "fu, fv, pu, pv";
  } else if (camera_model == "omni") {
    n_intrinsics = 5;
    intrinsics_order = "xi, fu, fv, pu, pv";
  } else if (camera_model == "ds") {
    n_intrinsics = 6;
    intrinsics_order = "xi, alpha, fu, fv, pu, pv";
  } else if (camera_model == "eucm") {
    return w.at(camera_model_node)
        .field("camera_model", "'eucm' (extended unified camera model) is not supported (supported: pinhole, omni, ds)",
               ErrorCode::kUnsupported);
  } else {
    return w.at(camera_model_node)
        .field("camera_model",
               fmt::format("unknown model {} (known: pinhole, omni, ds; eucm is not supported)", shown(camera_model)),
               ErrorCode::kUnsupported);
  }

  const auto distortion_node = firstKey(node, {"distortion_coeffs", "distortion_coefficients"});
  const std::string distortion_key = distortion_node ? distortion_node->first : "distortion_coeffs";
  const Where at_distortion = distortion_node ? w.at(distortion_node->second) : w;
  std::vector<double> coefficients;
  if (distortion_node) {
    auto d = readNumbers(w, distortion_node->second, distortion_key);
    if (!d.ok()) return d.error();
    coefficients = std::move(*d);
  }
  std::string distortion_model = coefficients.empty() ? "none" : "radtan";
  const YAML::Node distortion_model_node = node["distortion_model"];
  const Where at_distortion_model = w.at(distortion_model_node);
  if (const YAML::Node n = distortion_model_node; n) {
    auto name = readName(w, n, "distortion_model");
    if (!name.ok()) return name.error();
    distortion_model = text::lower(*name);
  }
  if (distortion_model == "radial-tangential" || distortion_model == "radial_tangential") distortion_model = "radtan";
  if (distortion_model == "equi") distortion_model = "equidistant";
  if (distortion_model == "fov") {
    return at_distortion_model.field(
        "distortion_model", "'fov' is not supported (supported: radtan, equidistant, none)", ErrorCode::kUnsupported);
  }
  if (distortion_model != "radtan" && distortion_model != "equidistant" && distortion_model != "none") {
    return at_distortion_model.field(
        "distortion_model",
        fmt::format("unknown model {} (known: radtan, equidistant, none; fov is not supported)",
                    shown(distortion_model)),
        ErrorCode::kUnsupported);
  }

  const YAML::Node intrinsics_node = node["intrinsics"];
  auto intrinsics = readNumbers(w, intrinsics_node, "intrinsics");
  if (!intrinsics.ok()) return intrinsics.error();
  if (intrinsics->size() != n_intrinsics) {
    return w.at(intrinsics_node)
        .field("intrinsics", fmt::format("expected {} numbers for {}, got {} ({})", n_intrinsics, camera_model,
                                         intrinsics->size(), intrinsics_order));
  }
  auto size = readSize(w, node["resolution"], "resolution");
  if (!size.ok()) return size.error();

  SequenceCamera camera;
  const std::vector<double>& k = *intrinsics;
  const size_t f = n_intrinsics - 4;  // Index of fu.
  camera.intrinsics = PinholeCamera{k[f], k[f + 1], k[f + 2], k[f + 3], size->first, size->second};
  const FieldRef intrinsics_field{"intrinsics", lineOf(intrinsics_node)};
  const FieldRef resolution_field{"resolution", lineOf(node["resolution"])};
  FieldOf fields{{"fx", intrinsics_field},    {"fy", intrinsics_field},    {"cx", intrinsics_field},
                 {"cy", intrinsics_field},    {"xi", intrinsics_field},    {"alpha", intrinsics_field},
                 {"width", resolution_field}, {"height", resolution_field}};
  distortionField(fields, FieldRef{distortion_key, at_distortion.line});

  // Model and distortion together.
  auto unsupportedPair = [&](const char* supported) {
    return at_distortion_model.field("distortion_model",
                                     fmt::format("{} with camera_model {} is not supported ({})",
                                                 shown(distortion_model), shown(camera_model), supported),
                                     ErrorCode::kUnsupported);
  };
  auto countError = [&](const char* expected) {
    return at_distortion.field(distortion_key, fmt::format("expected {} coefficients for {}, got {}", expected,
                                                           distortion_model, coefficients.size()));
  };
  if (distortion_model == "none") {
    if (!allZero(coefficients))
      return at_distortion.field(distortion_key, "non-zero coefficients with distortion_model none");
    coefficients.clear();
  }
  if (camera_model == "pinhole") {
    if (distortion_model == "equidistant") {
      if (coefficients.size() != 4) return countError("4 (k1, k2, k3, k4)");
      camera.model = "kannala_brandt";
    } else {
      if (distortion_model == "radtan" && coefficients.size() != 4 && coefficients.size() != 5) {
        return countError("4 (k1, k2, r1, r2) or 5 (k1, k2, r1, r2, k3)");
      }
      camera.model = "pinhole";
    }
  } else if (camera_model == "omni") {
    if (distortion_model == "equidistant") return unsupportedPair("omni: radtan or none");
    if (distortion_model == "radtan" && coefficients.size() != 4) return countError("4 (k1, k2, r1, r2)");
    camera.model = "mei";
    camera.xi = k[0];
  } else {  // ds
    if (distortion_model != "none") return unsupportedPair("ds: none");
    camera.model = "double_sphere";
    camera.xi = k[0];
    camera.alpha = k[1];
  }
  camera.distortion = std::move(coefficients);

  if (const YAML::Node n = node["T_BS"]; n) {
    auto T = readRigid(w, n, "T_BS");
    if (!T.ok()) return T.error();
    camera.T_body_camera = *T;
  } else if (const YAML::Node t = node["T_cam_imu"]; t) {
    auto T = readRigid(w, t, "T_cam_imu");
    if (!T.ok()) return T.error();
    camera.T_body_camera = T->inverse();
  }
  return finish(w, camera, fields);
}

/// "cam<digits>" -> the index; -1 otherwise.
int kalibrIndex(const std::string& key) {
  if (key.size() < 4 || key.compare(0, 3, "cam") != 0 || !allDigits(std::string_view(key).substr(3)) ||
      key.size() > 9) {
    return -1;
  }
  return std::stoi(key.substr(3));
}

std::vector<std::pair<int, std::string>> kalibrCameras(const YAML::Node& root) {
  std::vector<std::pair<int, std::string>> cameras;
  for (const auto& entry : root) {
    if (!entry.first.IsScalar() || !entry.second.IsMap()) continue;
    const int index = kalibrIndex(entry.first.Scalar());
    if (index >= 0) cameras.emplace_back(index, entry.first.Scalar());
  }
  std::sort(cameras.begin(), cameras.end());
  return cameras;
}

Result<SequenceCamera> readKalibrChain(const std::string& path, const YAML::Node& root, const std::string& select) {
  const std::vector<std::pair<int, std::string>> cameras = kalibrCameras(root);
  std::string name = cameras.front().second;
  int index = cameras.front().first;
  if (!select.empty()) {
    const std::string wanted = allDigits(select) ? "cam" + select : select;
    const auto it = std::find_if(cameras.begin(), cameras.end(), [&](const auto& c) { return c.second == wanted; });
    if (it == cameras.end()) {
      std::vector<std::string> names;
      for (const auto& c : cameras) names.push_back(c.second);
      return makeError(ErrorCode::kNotFound, text::oneLine(fmt::format("{}: no camera {} (available: {})", path,
                                                                       shown(select), joined(names))));
    }
    name = it->second;
    index = it->first;
  }
  const Where w{path, name};
  const YAML::Node node = root[name];
  auto camera = readKalibrCamera(w, node);
  if (!camera.ok()) return camera.error();
  // Without T_cam_imu (a camera-only calibration), cam0 is the body and camN follows the chain
  // T_cN_c0 = T_cN_cN-1 * ... * T_c1_c0 of T_cn_cnm1 (camera n from camera n-1).
  if (!node["T_cam_imu"] && index > 0) {
    Pose T_cn_c0 = Pose::Identity();
    bool chained = true;
    for (int i = 1; i <= index && chained; ++i) {
      const YAML::Node link = root[fmt::format("cam{}", i)];
      if (!link || !link.IsMap() || !link["T_cn_cnm1"]) {
        chained = false;
        break;
      }
      auto T = readRigid(Where{path, fmt::format("cam{}", i)}, link["T_cn_cnm1"], "T_cn_cnm1");
      if (!T.ok()) return T.error();
      T_cn_c0 = *T * T_cn_c0;
    }
    if (chained) {
      Pose T_body_c0 = Pose::Identity();
      if (const YAML::Node cam0 = root["cam0"]; cam0 && cam0.IsMap() && cam0["T_cam_imu"]) {
        auto T = readRigid(Where{path, "cam0"}, cam0["T_cam_imu"], "T_cam_imu");
        if (!T.ok()) return T.error();
        T_body_c0 = T->inverse();
      }
      camera->T_body_camera = T_body_c0 * T_cn_c0.inverse();
    }
  }
  return camera;
}

// ---------------------------------------------------------------------------------------------
// OpenCV FileStorage YAML and ROS camera_info YAML: a 3x3 camera matrix and a list of
// distortion coefficients in OpenCV's order k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tx ty]]]],
// or k1..k4 of OpenCV's fisheye module (Kannala-Brandt).

Result<SequenceCamera> readOpenCv(const std::string& path, const YAML::Node& root, const std::string& select) {
  const Where w{path, ""};
  std::string name;
  if (const YAML::Node n = root["camera_name"]; n && n.IsScalar()) name = std::string(text::trim(n.Scalar()));
  VKLOC_TRY_STATUS(selectSingle(w, select, name));

  const auto K_node = firstKey(root, {"camera_matrix", "K", "cameraMatrix"});
  auto K = readNumbers(w, K_node->second, K_node->first);
  if (!K.ok()) return K.error();
  const Where at_K = w.at(K_node->second);
  if (K->size() != 9)
    return at_K.field(K_node->first, fmt::format("expected a 3x3 matrix (9 numbers), got {}", K->size()));
  const std::vector<double>& m = *K;
  if (m[1] != 0.0) {
    return at_K.field(K_node->first, fmt::format("skew {} is not supported (must be 0)", num(m[1])),
                      ErrorCode::kUnsupported);
  }
  if (m[3] != 0.0 || m[6] != 0.0 || m[7] != 0.0 || m[8] != 1.0) {
    return at_K.field(K_node->first, "expected [fx, 0, cx, 0, fy, cy, 0, 0, 1]");
  }

  SequenceCamera camera;
  std::string width_key = "image_width";
  std::string height_key = "image_height";
  if (const auto wh = firstKey(root, {"image_size", "imageSize", "cameraResolution", "resolution"});
      wh && !root["image_width"]) {
    width_key = height_key = wh->first;
    auto size = readSize(w, wh->second, wh->first);
    if (!size.ok()) return size.error();
    std::tie(camera.intrinsics.width, camera.intrinsics.height) = *size;
  } else {
    if (!root["image_width"] && root["width"]) {
      width_key = "width";
      height_key = "height";
    }
    auto width = readInt(w, root[width_key], width_key);
    if (!width.ok()) return width.error();
    auto height = readInt(w, root[height_key], height_key);
    if (!height.ok()) return height.error();
    camera.intrinsics.width = *width;
    camera.intrinsics.height = *height;
  }
  camera.intrinsics.fx = m[0];
  camera.intrinsics.cx = m[2];
  camera.intrinsics.fy = m[4];
  camera.intrinsics.cy = m[5];

  const auto D_node =
      firstKey(root, {"distortion_coefficients", "D", "dist_coeffs", "distCoeffs", "distortion_coeffs"});
  const std::string D_key = D_node ? D_node->first : "distortion_coefficients";
  const Where at_D = D_node ? w.at(D_node->second) : w;
  std::vector<double> d;
  if (D_node) {
    auto read = readNumbers(w, D_node->second, D_key);
    if (!read.ok()) return read.error();
    d = std::move(*read);
  }
  std::string model_key = "distortion_model";
  std::string model;
  Where at_model = w;
  if (const auto n = firstKey(root, {"distortion_model", "model"}); n) {
    model_key = n->first;
    at_model = w.at(n->second);
    auto read = readName(w, n->second, n->first);
    if (!read.ok()) return read.error();
    model = text::lower(*read);
  }
  const FieldRef K_field{K_node->first, at_K.line};
  FieldOf fields{{"fx", K_field},
                 {"fy", K_field},
                 {"cx", K_field},
                 {"cy", K_field},
                 {"width", FieldRef{width_key, lineOf(root[width_key])}},
                 {"height", FieldRef{height_key, lineOf(root[height_key])}}};
  distortionField(fields, FieldRef{D_key, at_D.line});
  if (model == "fisheye" || model == "equidistant" || model == "kannala_brandt" || model == "equi") {
    if (d.size() != 4) {
      return at_D.field(D_key, fmt::format("expected 4 coefficients (k1, k2, k3, k4) for {}, got {}", model, d.size()));
    }
    camera.model = "kannala_brandt";
  } else if (model.empty() || model == "plumb_bob" || model == "radtan" || model == "radial-tangential" ||
             model == "rational_polynomial" || model == "pinhole" || model == "none") {
    camera.model = "pinhole";
    if (model == "none" && !allZero(d)) return at_D.field(D_key, "non-zero coefficients with distortion model none");
    const size_t n = d.size();
    if (n != 0 && n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
      return at_D.field(D_key, fmt::format("expected 0, 4, 5, 8, 12 or 14 coefficients, got {}", n));
    }
    if (n > 5) {
      // Rational (k4 k5 k6), thin prism (s1..s4) and tilt (tx ty) terms: only when zero.
      if (!allZero(d, 5)) {
        return at_D.field(D_key,
                          "rational / thin-prism / tilted coefficients beyond k1 k2 p1 p2 k3 are not supported (they "
                          "must be 0)",
                          ErrorCode::kUnsupported);
      }
      d.resize(5);
    }
  } else {
    return at_model.field(
        model_key,
        fmt::format("unknown distortion model {} (known: plumb_bob, rational_polynomial, equidistant, "
                    "fisheye, none)",
                    shown(model)),
        ErrorCode::kUnsupported);
  }
  camera.distortion = std::move(d);
  return finish(w, camera, fields);
}

// ---------------------------------------------------------------------------------------------
// CamOdoCal (also VINS-Mono / VINS-Fusion configs): model_type MEI, KANNALA_BRANDT, PINHOLE.

Result<SequenceCamera> readCamOdoCal(const std::string& path, const YAML::Node& root, const std::string& select) {
  const Where w{path, ""};
  std::string name;
  if (const YAML::Node n = root["camera_name"]; n && n.IsScalar()) name = std::string(text::trim(n.Scalar()));
  VKLOC_TRY_STATUS(selectSingle(w, select, name));
  auto type = readName(w, root["model_type"], "model_type");
  if (!type.ok()) return type.error();
  std::string model_type = *type;
  std::transform(model_type.begin(), model_type.end(), model_type.begin(),
                 [](char c) { return static_cast<char>(std::toupper(static_cast<unsigned char>(c))); });

  SequenceCamera camera;
  struct Param {
    const char* parent;
    const char* key;
    double* out;
    const char* parameter;  ///< LensCamera's name of it.
  };
  std::vector<Param> params;
  PinholeCamera& k = camera.intrinsics;
  std::array<double, 4> dist{};
  if (model_type == "MEI") {
    camera.model = "mei";
    params = {{"mirror_parameters", "xi", &camera.xi, "xi"},    {"distortion_parameters", "k1", &dist[0], "k1"},
              {"distortion_parameters", "k2", &dist[1], "k2"},  {"distortion_parameters", "p1", &dist[2], "p1"},
              {"distortion_parameters", "p2", &dist[3], "p2"},  {"projection_parameters", "gamma1", &k.fx, "fx"},
              {"projection_parameters", "gamma2", &k.fy, "fy"}, {"projection_parameters", "u0", &k.cx, "cx"},
              {"projection_parameters", "v0", &k.cy, "cy"}};
  } else if (model_type == "KANNALA_BRANDT") {
    // theta_d = theta + k2 theta^3 + k3 theta^5 + k4 theta^7 + k5 theta^9: OpenCV fisheye's k1..k4.
    camera.model = "kannala_brandt";
    params = {{"projection_parameters", "k2", &dist[0], "k1"}, {"projection_parameters", "k3", &dist[1], "k2"},
              {"projection_parameters", "k4", &dist[2], "k3"}, {"projection_parameters", "k5", &dist[3], "k4"},
              {"projection_parameters", "mu", &k.fx, "fx"},    {"projection_parameters", "mv", &k.fy, "fy"},
              {"projection_parameters", "u0", &k.cx, "cx"},    {"projection_parameters", "v0", &k.cy, "cy"}};
  } else if (model_type == "PINHOLE") {
    camera.model = "pinhole";
    params = {{"distortion_parameters", "k1", &dist[0], "k1"}, {"distortion_parameters", "k2", &dist[1], "k2"},
              {"distortion_parameters", "p1", &dist[2], "p1"}, {"distortion_parameters", "p2", &dist[3], "p2"},
              {"projection_parameters", "fx", &k.fx, "fx"},    {"projection_parameters", "fy", &k.fy, "fy"},
              {"projection_parameters", "cx", &k.cx, "cx"},    {"projection_parameters", "cy", &k.cy, "cy"}};
  } else if (model_type == "SCARAMUZZA" || model_type == "PINHOLE_FULL") {
    return w.at(root["model_type"])
        .field("model_type", fmt::format("{} is not supported (supported: MEI, KANNALA_BRANDT, PINHOLE)", shown(*type)),
               ErrorCode::kUnsupported);
  } else {
    return w.at(root["model_type"])
        .field("model_type",
               fmt::format("unknown model {} (known: MEI, KANNALA_BRANDT, PINHOLE; SCARAMUZZA is not supported)",
                           shown(*type)),
               ErrorCode::kUnsupported);
  }
  auto width = readInt(w, root["image_width"], "image_width");
  if (!width.ok()) return width.error();
  auto height = readInt(w, root["image_height"], "image_height");
  if (!height.ok()) return height.error();
  camera.intrinsics.width = *width;
  camera.intrinsics.height = *height;
  FieldOf fields{{"width", FieldRef{"image_width", lineOf(root["image_width"])}},
                 {"height", FieldRef{"image_height", lineOf(root["image_height"])}}};

  for (const Param& p : params) {
    auto v = readNested(w, root, p.parent, p.key);
    if (!v.ok()) return v.error();
    *p.out = *v;
    fields[p.parameter] = FieldRef{fmt::format("{}.{}", p.parent, p.key), lineOf(root[p.parent][p.key])};
  }
  camera.distortion.assign(dist.begin(), dist.end());
  return finish(w, camera, fields);
}

// ---------------------------------------------------------------------------------------------
// COLMAP cameras.txt: "CAMERA_ID MODEL WIDTH HEIGHT PARAMS..." per line, '#' comments.
//
// Pixel convention: COLMAP puts the image's upper-left corner at (0, 0), so the centre of the
// upper-left pixel is at (0.5, 0.5) (COLMAP documentation, "Cameras"; a centred principal point
// is width / 2). vkloc (as OpenCV) puts that pixel's centre at (0, 0): cx = cx_colmap - 0.5,
// cy = cy_colmap - 0.5. Focal lengths and distortion are the same in both conventions.

struct ColmapLine {
  size_t line = 0;
  uint64_t id = 0;
  std::string model;
  int width = 0;
  int height = 0;
  std::vector<double> params;
};

/// True when the first data line reads "<id> <MODEL> <width> <height> ...".
bool looksLikeColmap(std::string_view content) {
  text::LineCursor lines(content);
  for (std::string_view line; lines.next(line);) {
    if (text::isBlankOrComment(line)) continue;
    const std::vector<std::string_view> f = text::splitFields(line);
    if (f.size() < 4 || !allDigits(f[0]) || !allDigits(f[2]) || !allDigits(f[3])) return false;
    return std::all_of(f[1].begin(), f[1].end(), [](char c) {
      return std::isupper(static_cast<unsigned char>(c)) || std::isdigit(c) || c == '_';
    });
  }
  return false;
}

Result<SequenceCamera> colmapCamera(const Where& w, const ColmapLine& c) {
  struct Model {
    const char* name;
    const char* lens;      ///< SequenceCamera model.
    const char* order;     ///< Parameter names, for messages.
    size_t count;          ///< Number of parameters.
    bool single_focal;     ///< f instead of fx fy.
    size_t n_distortion;   ///< Parameters after the principal point.
    size_t zero_from = 0;  ///< Distortion parameters from this index on must be zero (FULL_OPENCV).
  };
  static const Model models[] = {
      {"SIMPLE_PINHOLE", "pinhole", "f, cx, cy", 3, true, 0},
      {"PINHOLE", "pinhole", "fx, fy, cx, cy", 4, false, 0},
      {"SIMPLE_RADIAL", "pinhole", "f, cx, cy, k", 4, true, 1},
      {"RADIAL", "pinhole", "f, cx, cy, k1, k2", 5, true, 2},
      {"OPENCV", "pinhole", "fx, fy, cx, cy, k1, k2, p1, p2", 8, false, 4},
      {"FULL_OPENCV", "pinhole", "fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6", 12, false, 8, 5},
      {"OPENCV_FISHEYE", "kannala_brandt", "fx, fy, cx, cy, k1, k2, k3, k4", 8, false, 4},
      {"SIMPLE_RADIAL_FISHEYE", "kannala_brandt", "f, cx, cy, k", 4, true, 1},
      {"RADIAL_FISHEYE", "kannala_brandt", "f, cx, cy, k1, k2", 5, true, 2},
  };
  const Model* m = nullptr;
  for (const Model& candidate : models) {
    if (c.model == candidate.name) m = &candidate;
  }
  if (!m) {
    std::vector<std::string> names;
    for (const Model& candidate : models) names.emplace_back(candidate.name);
    return w.field("MODEL", fmt::format("{} is not supported (supported: {})", shown(c.model), joined(names)),
                   ErrorCode::kUnsupported);
  }
  if (c.params.size() != m->count) {
    return w.field(
        "PARAMS", fmt::format("expected {} numbers for {}, got {} ({})", m->count, m->name, c.params.size(), m->order));
  }
  SequenceCamera camera;
  camera.model = m->lens;
  const std::vector<double>& p = c.params;
  const size_t pp = m->single_focal ? 1 : 2;  // Index of cx.
  camera.intrinsics = PinholeCamera{p[0], p[m->single_focal ? 0 : 1], p[pp] - 0.5, p[pp + 1] - 0.5, c.width, c.height};
  std::vector<double> d(p.begin() + static_cast<std::ptrdiff_t>(pp + 2), p.end());
  if (m->zero_from > 0) {
    if (!allZero(d, m->zero_from)) {
      return w.field("PARAMS", fmt::format("{} with non-zero k4, k5, k6 (rational model) is not supported", m->name),
                     ErrorCode::kUnsupported);
    }
    d.resize(m->zero_from);
  }
  const size_t n_lens = camera.model == "kannala_brandt" ? 4 : (d.size() > 4 ? 5 : 4);
  if (!d.empty()) d.resize(n_lens, 0.0);  // SIMPLE_RADIAL k -> k1 k2 p1 p2 = k 0 0 0.
  camera.distortion = std::move(d);
  const FieldRef params{"PARAMS", w.line};
  FieldOf fields{{"fx", params},
                 {"fy", params},
                 {"cx", params},
                 {"cy", params},
                 {"width", FieldRef{"WIDTH", w.line}},
                 {"height", FieldRef{"HEIGHT", w.line}}};
  distortionField(fields, params);
  return finish(w, camera, fields);
}

Result<SequenceCamera> readColmap(const std::string& path, const std::string& content, const std::string& select) {
  std::vector<ColmapLine> cameras;
  std::map<uint64_t, size_t> line_of_id;
  text::LineCursor lines(content);
  for (std::string_view line; lines.next(line);) {
    if (text::isBlankOrComment(line)) continue;
    const Where w{path, "", lines.number()};
    if (const std::string wrong = tableLimits(line, cameras.size()); !wrong.empty()) {
      return w.error(ErrorCode::kMalformedInput, wrong);
    }
    const std::vector<std::string_view> f = text::splitFields(line);
    ColmapLine c;
    c.line = lines.number();
    if (f.size() < 4) {
      return w.error(ErrorCode::kMalformedInput,
                     fmt::format("expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..., got {} fields", f.size()));
    }
    if (const std::string wrong = text::parseUint64(f[0], c.id); !wrong.empty()) return w.field("CAMERA_ID", wrong);
    c.model = std::string(f[1]);
    for (const auto& [index, key, out] :
         {std::tuple{size_t{2}, "WIDTH", &c.width}, std::tuple{size_t{3}, "HEIGHT", &c.height}}) {
      uint64_t v = 0;
      if (const std::string wrong = text::parseUint64(f[index], v); !wrong.empty()) return w.field(key, wrong);
      if (v < 1 || v > 16384) return w.field(key, fmt::format("{} is outside 1..16384 pixels", v));
      *out = static_cast<int>(v);
    }
    for (size_t j = 4; j < f.size(); ++j) {
      double v = 0.0;
      if (const std::string wrong = text::parseDouble(f[j], v); !wrong.empty()) return w.field("PARAMS", wrong);
      c.params.push_back(v);
    }
    if (const auto [other, added] = line_of_id.emplace(c.id, c.line); !added) {
      return w.field("CAMERA_ID", fmt::format("camera {} is listed twice (also line {})", c.id, other->second));
    }
    cameras.push_back(std::move(c));
  }
  if (cameras.empty()) return makeError(ErrorCode::kMalformedInput, fmt::format("{}: no camera lines", path));
  const ColmapLine* chosen = &cameras.front();
  if (!select.empty()) {
    uint64_t id = 0;
    const bool numeric = text::parseUint64(select, id).empty();
    const auto it =
        std::find_if(cameras.begin(), cameras.end(), [&](const ColmapLine& c) { return numeric && c.id == id; });
    if (it == cameras.end()) {
      std::vector<std::string> ids;
      for (const ColmapLine& c : cameras) ids.push_back(std::to_string(c.id));
      return makeError(ErrorCode::kNotFound, text::oneLine(fmt::format("{}: no camera {} (available camera ids: {})",
                                                                       path, shown(select), joined(ids))));
    }
    chosen = &*it;
  }
  return colmapCamera(Where{path, fmt::format("camera {}", chosen->id), chosen->line}, *chosen);
}

// ---------------------------------------------------------------------------------------------
// Reading and telling formats apart.

/// OpenCV FileStorage writes "%YAML:1.0", which is not a valid YAML directive, and tags matrices
/// "!!opencv-matrix": both are blanked (lines and columns stay where they were).
std::string withoutOpenCvMarks(std::string content) {
  if (content.rfind("%YAML", 0) == 0 && content.rfind("%YAML 1.", 0) != 0) content[0] = '#';
  for (size_t at = content.find("!!opencv-"); at != std::string::npos; at = content.find("!!opencv-", at)) {
    while (at < content.size() && !std::isspace(static_cast<unsigned char>(content[at]))) content[at++] = ' ';
  }
  return content;
}

Result<SequenceCamera> loadCalibrationUnguarded(const std::string& path, const std::string& select) {
  auto read = text::readFile(path, "calibration file", kMaxTableBytes);
  if (!read.ok()) return read.error();
  const std::string& content = *read;
  if (looksLikeColmap(content)) return readColmap(path, content, select);
  if (content.size() > kMaxYamlBytes) {
    return makeError(ErrorCode::kMalformedInput,
                     fmt::format("{}: calibration file is larger than {} bytes (the YAML limit)", path, kMaxYamlBytes));
  }
  auto parsed = parseYaml(path, withoutOpenCvMarks(content));
  if (!parsed.ok()) return parsed.error();
  const YAML::Node& root = *parsed;  // const: looking a key up must not add it.
  constexpr const char* kFormats =
      "expected vkloc camera.yaml, Kalibr camchain.yaml or sensor.yaml, OpenCV or ROS camera YAML, CamOdoCal YAML or "
      "COLMAP cameras.txt";
  if (!root.IsMap())
    return makeError(ErrorCode::kUnsupported, fmt::format("{}: not a calibration file ({})", path, kFormats));

  const Where w{path, ""};
  if (root["model_type"]) return readCamOdoCal(path, root, select);
  if (!kalibrCameras(root).empty()) return readKalibrChain(path, root, select);
  if (firstKey(root, {"camera_matrix", "K", "cameraMatrix"})) return readOpenCv(path, root, select);
  if (root["camera_model"] || root["T_BS"] || (root["intrinsics"] && root["intrinsics"].IsSequence())) {
    VKLOC_TRY_STATUS(selectSingle(w, select));
    return readKalibrCamera(w, root);
  }
  if (root["fx"]) {
    VKLOC_TRY_STATUS(selectSingle(w, select));
    return readSequenceCamera(path, root);
  }
  for (const char* key : {"camera", "intrinsics"}) {
    if (const YAML::Node n = root[key]; n && n.IsMap() && n["fx"]) {
      VKLOC_TRY_STATUS(selectSingle(w, select));
      return readSequenceCamera(path, n);
    }
  }
  return makeError(ErrorCode::kUnsupported, fmt::format("{}: no known calibration keys ({})", path, kFormats));
}

}  // namespace

Result<SequenceCamera> io_detail::loadKalibrSensorCamera(const std::string& path) {
  try {
    auto read = text::readFile(path, "camera file", kMaxYamlBytes);
    if (!read.ok()) return read.error();
    auto parsed = parseYaml(path, withoutOpenCvMarks(*read));
    if (!parsed.ok()) return parsed.error();
    const YAML::Node loaded = *parsed;
    if (!loaded.IsMap()) return lineError(path, 1, "expected a mapping of sensor keys");
    return readKalibrCamera(Where{path, ""}, loaded);
  } catch (const std::exception& e) {
    return makeError(ErrorCode::kMalformedInput, text::oneLine(fmt::format("{}: {}", path, e.what())));
  }
}

Result<SequenceCamera> loadCalibration(const std::string& path, const std::string& select) {
  try {
    return loadCalibrationUnguarded(path, select);
  } catch (const YAML::Exception& e) {
    return lineError(path, static_cast<size_t>(e.mark.line + 1), text::oneLine(e.msg));
  } catch (const std::exception& e) {
    return makeError(ErrorCode::kMalformedInput, text::oneLine(fmt::format("{}: {}", path, e.what())));
  }
}

}  // namespace vkloc
