// Conversion of a ViSP model-based tracking folder (images, cMo poses, camera XML, .cao models)
// into a vkloc sequence.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>

#include "vkloc/core/text.hpp"
#include "vkloc/io/image_io.hpp"
#include "vkloc/io/import.hpp"
#include "vkloc/model/cao.hpp"
#include "vkloc/model/model_write.hpp"

namespace vkloc {

namespace fs = std::filesystem;

namespace {

/// Largest pose / XML text read, bytes.
constexpr uint64_t kMaxTextBytes = uint64_t{256} << 20;

Error fileError(ErrorCode code, const std::string& path, const std::string& what) {
  return makeError(code, path + ": " + text::oneLine(what));
}

std::string lowerExtension(const std::string& path) { return text::lower(fs::path(path).extension().string()); }

Result<std::string> readText(const std::string& path) { return text::readFile(path, "file", kMaxTextBytes); }

/// The text between <tag> and </tag> in [from, to), or nullopt. `pos` receives the end.
std::optional<std::string> xmlTag(const std::string& text, const std::string& tag, size_t from, size_t to,
                                  size_t* end_pos = nullptr) {
  const std::string open = "<" + tag + ">", close = "</" + tag + ">";
  const size_t b = text.find(open, from);
  if (b == std::string::npos || b >= to) return std::nullopt;
  const size_t e = text.find(close, b + open.size());
  if (e == std::string::npos || e > to) return std::nullopt;
  if (end_pos) *end_pos = e + close.size();
  return std::string(text::trim(std::string_view(text).substr(b + open.size(), e - b - open.size())));
}

/// Number n in a file name "<prefix>n.<ext>", or nullopt.
std::optional<uint64_t> numberedFile(const std::string& name, const std::string& prefix) {
  if (name.rfind(prefix, 0) != 0) return std::nullopt;
  const size_t dot = name.find('.', prefix.size());
  if (dot == std::string::npos || dot == prefix.size()) return std::nullopt;
  uint64_t n = 0;
  if (!text::parseUint64(std::string_view(name).substr(prefix.size(), dot - prefix.size()), n).empty()) {
    return std::nullopt;
  }
  return n;
}

}  // namespace

Pose VispImportOptions::defaultCastleCubePose() {
  Pose T = Pose::Identity();
  T.matrix().topRows<3>() << -1, 0, 0, -0.2, 0, 0, 1, 0.12, 0, 1, 0, -0.15;
  return T;
}

Result<Pose> loadVispPose(const std::string& path) {
  auto text = readText(path);
  if (!text.ok()) return text.error();
  std::string s = *text;
  std::replace(s.begin(), s.end(), ',', ' ');
  std::replace(s.begin(), s.end(), ';', ' ');
  std::replace(s.begin(), s.end(), '[', ' ');
  std::replace(s.begin(), s.end(), ']', ' ');
  const std::vector<std::string_view> tokens = text::splitFields(s);
  if (tokens.size() != 16) {
    return fileError(ErrorCode::kMalformedInput, path,
                     fmt::format("expected a 4x4 matrix (16 numbers), found {} values", tokens.size()));
  }
  Eigen::Matrix4d M;
  for (int i = 0; i < 16; ++i) {
    double v = 0.0;
    if (!text::parseDouble(tokens[static_cast<size_t>(i)], v).empty()) {
      return fileError(ErrorCode::kMalformedInput, path,
                       fmt::format("value {} '{}' is not a finite number", i + 1, tokens[static_cast<size_t>(i)]));
    }
    M(i / 4, i % 4) = v;
  }
  if ((M.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    return fileError(ErrorCode::kMalformedInput, path, "last row of the pose matrix is not 0 0 0 1");
  }
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>();
  const double error = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > 1e-4 || R.determinant() < 0.0) {
    return fileError(
        ErrorCode::kMalformedInput, path,
        fmt::format("rotation is not orthonormal (|R R^T - I| = {:.2g}, det {:.3g})", error, R.determinant()));
  }
  Pose T = Pose::Identity();
  T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  T.translation() = M.topRightCorner<3, 1>();
  return T;
}

Result<PinholeCamera> loadVispCameraXml(const std::string& path, int width, int height) {
  auto read = readText(path);
  if (!read.ok()) return read.error();
  std::string text = std::move(read).value();
  // Drop XML comments.
  for (size_t b = text.find("<!--"); b != std::string::npos; b = text.find("<!--", b)) {
    const size_t e = text.find("-->", b + 4);
    text.erase(b, e == std::string::npos ? std::string::npos : e + 3 - b);
  }
  // Search range: the perspectiveProjWithoutDistortion <model> when there is one, else all.
  size_t from = 0, to = text.size();
  for (size_t pos = 0;;) {
    size_t end = 0;
    const size_t b = text.find("<model>", pos);
    auto model = xmlTag(text, "model", pos, text.size(), &end);
    if (!model || b == std::string::npos) break;
    if (model->find("perspectiveProjWithoutDistortion") != std::string::npos) {
      from = b;
      to = end;
      break;
    }
    pos = end;
  }
  PinholeCamera camera;
  const std::pair<const char*, double*> fields[] = {
      {"px", &camera.fx}, {"py", &camera.fy}, {"u0", &camera.cx}, {"v0", &camera.cy}};
  for (const auto& [tag, value] : fields) {
    auto content = xmlTag(text, tag, from, to);
    if (!content) return fileError(ErrorCode::kMalformedInput, path, fmt::format("no <{}> element", tag));
    if (!text::parseDouble(*content, *value).empty()) {
      return fileError(ErrorCode::kMalformedInput, path,
                       fmt::format("<{}> '{}' is not a finite number", tag, *content));
    }
  }
  const std::pair<const char*, int*> sizes[] = {{"image_width", &width}, {"image_height", &height}};
  for (const auto& [tag, value] : sizes) {
    if (*value > 0) continue;
    auto content = xmlTag(text, tag, 0, text.size());
    uint64_t v = 0;
    if (!content) {
      return fileError(ErrorCode::kMalformedInput, path, fmt::format("no <{}> element and no image size given", tag));
    }
    if (!text::parseUint64(*content, v).empty() || v == 0 || v > 16384) {
      return fileError(ErrorCode::kMalformedInput, path, fmt::format("<{}> '{}' is not a valid size", tag, *content));
    }
    *value = static_cast<int>(v);
  }
  camera.width = width;
  camera.height = height;
  if (Status s = validateCamera(camera); !s.ok()) return fileError(ErrorCode::kMalformedInput, path, s.error().message);
  return camera;
}

Result<Sequence> importVispSequence(const std::string& folder, const std::string& out_dir,
                                    const VispImportOptions& options, VispImportReport* report) {
  VispImportReport local_report;
  VispImportReport& rep = report ? *report : local_report;
  rep = VispImportReport{};
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return fileError(ErrorCode::kNotFound, folder, "ViSP folder not found");
  if (!(options.frame_rate_hz > 0.0) || !std::isfinite(options.frame_rate_hz)) {
    return makeError(ErrorCode::kInvalidArgument, "frame_rate_hz must be a positive number");
  }
  const fs::path root(folder);
  auto listDir = [&](const char* name) -> Result<std::vector<fs::path>> {
    const fs::path dir = root / name;
    if (!fs::is_directory(dir, ec)) return fileError(ErrorCode::kNotFound, dir.string(), "folder not found");
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      if (entry.is_regular_file(ec)) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    return files;
  };

  // Images: Image_NNNN.<pgm|png|ppm|jpg>, ordered by number.
  auto image_files = listDir("Images");
  if (!image_files.ok()) return image_files.error();
  std::map<uint64_t, fs::path> images;
  for (const auto& p : *image_files) {
    const std::string ext = lowerExtension(p.string());
    if (ext != ".pgm" && ext != ".png" && ext != ".ppm" && ext != ".jpg" && ext != ".jpeg") continue;
    if (auto n = numberedFile(p.filename().string(), "Image_")) images.emplace(*n, p);
  }
  if (images.empty()) return fileError(ErrorCode::kNotFound, (root / "Images").string(), "no Image_NNNN images");

  // Poses: Camera_NNN.txt (cMo).
  auto pose_files = listDir("CameraPose");
  if (!pose_files.ok()) return pose_files.error();
  std::map<uint64_t, fs::path> poses;
  for (const auto& p : *pose_files) {
    if (auto n = numberedFile(p.filename().string(), "Camera_")) poses.emplace(*n, p);
  }

  // Intrinsics: the first Config/*.xml with a camera.
  auto config_files = listDir("Config");
  if (!config_files.ok()) return config_files.error();
  auto first_image = readImageU8(images.begin()->second.string(), 1);
  if (!first_image.ok()) return first_image.error();
  std::optional<PinholeCamera> camera;
  std::string camera_error = "no .xml file";
  for (const auto& p : *config_files) {
    if (lowerExtension(p.string()) != ".xml") continue;
    auto c = loadVispCameraXml(p.string(), first_image->width, first_image->height);
    if (c.ok()) {
      camera = *c;
      break;
    }
    camera_error = c.error().message;
  }
  if (!camera) {
    return fileError(ErrorCode::kNotFound, (root / "Config").string(), "no camera intrinsics: " + camera_error);
  }

  // Model: the .cao in Models/ other than cube.cao, plus the cube.
  auto model_files = listDir("Models");
  if (!model_files.ok()) return model_files.error();
  std::vector<fs::path> caos;
  std::optional<fs::path> cube;
  for (const auto& p : *model_files) {
    if (lowerExtension(p.string()) != ".cao") continue;
    if (p.filename() == "cube.cao") {
      cube = p;
    } else {
      caos.push_back(p);
    }
  }
  if (caos.empty()) return fileError(ErrorCode::kNotFound, (root / "Models").string(), "no .cao model");
  if (caos.size() > 1) {
    rep.warnings.push_back(
        fmt::format("{}: several .cao models; using {}", (root / "Models").string(), caos.front().filename().string()));
  }
  auto cao = parseCaoFile(caos.front().string(), &rep.warnings);
  if (!cao.ok()) return cao.error();
  CaoModel scene = std::move(cao).value();
  auto castle = caoToModel(scene, caos.front().string());
  if (!castle.ok()) return castle.error();
  const size_t castle_triangles = castle->triangleCount();
  if (options.include_cube) {
    if (!cube) return fileError(ErrorCode::kNotFound, (root / "Models" / "cube.cao").string(), "file not found");
    auto cube_cao = parseCaoFile(cube->string(), &rep.warnings);
    if (!cube_cao.ok()) return cube_cao.error();
    if (!isValidPose(options.T_object_cube)) {
      return makeError(ErrorCode::kInvalidArgument, "T_object_cube is not a valid rigid transform");
    }
    appendCaoModel(scene, *cube_cao, options.T_object_cube);
  }
  auto model = caoToModel(scene, caos.front().string());
  if (!model.ok()) return model.error();
  rep.triangles = model->triangleCount();
  rep.cube_triangles = rep.triangles - castle_triangles;

  // Output folder, images, model.
  const fs::path out(out_dir);
  fs::create_directories(out / "images", ec);
  if (ec) return fileError(ErrorCode::kIoError, (out / "images").string(), "cannot create folder: " + ec.message());
  const std::string model_path = (out / options.model_file).string();
  VKLOC_TRY_STATUS(saveModel(*model, model_path));
  rep.model_path = model_path;

  Sequence seq;
  seq.directory = out_dir;
  seq.name = root.filename().empty() ? root.parent_path().filename().string() : root.filename().string();
  seq.model = options.model_file;
  seq.gravity_world = Eigen::Vector3d(0.0, -9.81, 0.0);
  seq.camera.model = "pinhole";
  seq.camera.intrinsics = *camera;
  const uint64_t first_number = images.begin()->first;
  for (const auto& [number, path] : images) {
    auto image = readImageU8(path.string(), 1);
    if (!image.ok()) return image.error();
    if (image->width != camera->width || image->height != camera->height) {
      return fileError(ErrorCode::kMalformedInput, path.string(),
                       fmt::format("image is {}x{} but the first image is {}x{}", image->width, image->height,
                                   camera->width, camera->height));
    }
    const std::string stem = path.stem().string();
    const std::string rel = "images/" + stem + ".png";
    VKLOC_TRY_STATUS(writePng((out / rel).string(), *image));
    const int64_t t_ns =
        static_cast<int64_t>(std::llround(static_cast<double>(number - first_number) * 1e9 / options.frame_rate_hz));
    seq.images.push_back(ImageEntry{t_ns, rel});
    auto pose_it = poses.find(number);
    if (pose_it == poses.end()) {
      rep.warnings.push_back(
          fmt::format("{}: no CameraPose/Camera_{:03d}.txt; frame has no ground truth", path.string(), number));
      continue;
    }
    auto T_camera_object = loadVispPose(pose_it->second.string());
    if (!T_camera_object.ok()) return T_camera_object.error();
    seq.groundtruth.push_back(StampedPose{t_ns, T_camera_object->inverse()});
  }
  if (!seq.groundtruth.empty() && seq.groundtruth.front().t_ns == seq.images.front().t_ns) {
    seq.initial_T_world_camera = seq.groundtruth.front().T_world_camera;
  }
  VKLOC_TRY_STATUS(saveSequence(seq, out_dir));
  rep.frames = seq.images.size();
  rep.poses = seq.groundtruth.size();
  return seq;
}

}  // namespace vkloc
