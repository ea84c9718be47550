// Model loading entry point: format dispatch, the checks every loaded model goes through,
// placement in the world, validation, and the helpers the format loaders share.
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <new>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "model/model_internal.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/model/cao.hpp"

namespace vkloc {
namespace model_detail {

Error fileError(ErrorCode code, const std::string& path, const std::string& what) {
  return makeError(code, oneLine(path + ": " + what));
}

std::string oneLine(std::string text) { return text::oneLine(text); }

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

Result<std::vector<uint8_t>> readFileBytes(const std::string& path, uint64_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return fileError(ErrorCode::kNotFound, path, "file not found");
  if (fs::is_directory(status)) {
    return fileError(ErrorCode::kIoError, path, "is a directory, not a file");
  }
  std::ifstream file(path, std::ios::binary);
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  if (!file || size < 0) return fileError(ErrorCode::kIoError, path, "cannot read file");
  if (static_cast<uint64_t>(size) > max_bytes) {
    return fileError(ErrorCode::kMalformedInput, path,
                     fmt::format("file is larger than the {} bytes allowed ({} bytes)", max_bytes, size));
  }
  file.seekg(0);
  std::vector<uint8_t> bytes(static_cast<size_t>(size));
  file.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!file) return fileError(ErrorCode::kIoError, path, "read error");
  return bytes;
}

Status appendPrimitive(Model& model, const Primitive& prim, const std::string& path, const std::string& what) {
  const size_t base = model.vertexCount();
  const size_t count = prim.positions.size() / 3;
  if (prim.uvs.size() != (prim.uvs.empty() ? 0 : 2 * count) ||
      prim.colors.size() != (prim.colors.empty() ? 0 : 4 * count)) {
    return fileError(ErrorCode::kMalformedInput, path, what + ": attribute counts differ");
  }
  if (base + count > kMaxModelElements || model.triangleCount() + prim.indices.size() / 3 > kMaxModelElements) {
    return fileError(ErrorCode::kUnsupported, path,
                     fmt::format("{}: model has more than {} vertices or triangles", what, kMaxModelElements));
  }
  for (size_t i = 0; i < prim.indices.size(); ++i) {
    if (prim.indices[i] >= count) {
      return fileError(ErrorCode::kMalformedInput, path,
                       fmt::format("{}: triangle {} references vertex {} but there are {} vertices", what, i / 3,
                                   prim.indices[i], count));
    }
  }
  model.positions.insert(model.positions.end(), prim.positions.begin(), prim.positions.end());
  if (!prim.uvs.empty() || !model.uvs.empty()) {
    model.uvs.resize(2 * base, 0.0f);
    if (prim.uvs.empty()) {
      model.uvs.resize(2 * (base + count), 0.0f);
    } else {
      model.uvs.insert(model.uvs.end(), prim.uvs.begin(), prim.uvs.end());
    }
  }
  if (!prim.colors.empty() || !model.colors.empty()) {
    model.colors.resize(4 * base, 255);
    if (prim.colors.empty()) {
      model.colors.resize(4 * (base + count), 255);
    } else {
      model.colors.insert(model.colors.end(), prim.colors.begin(), prim.colors.end());
    }
  }
  const size_t triangles = prim.indices.size() / 3;
  if (triangles == 0) return Status::success();
  DrawRange range;
  range.first_index = static_cast<uint32_t>(model.indices.size());
  range.index_count = static_cast<uint32_t>(3 * triangles);
  range.material = prim.material;
  for (size_t i = 0; i < 3 * triangles; ++i) {
    model.indices.push_back(static_cast<uint32_t>(base + prim.indices[i]));
  }
  model.ranges.push_back(range);
  return Status::success();
}

namespace {

uint32_t readBigEndian32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}

// Width and height from a PNG or JPEG header; false for other formats or when not found.
bool imageHeaderSize(const uint8_t* data, size_t size, uint64_t& width, uint64_t& height) {
  static const uint8_t kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size >= 24 && std::equal(kPng, kPng + 8, data)) {
    width = readBigEndian32(data + 16);
    height = readBigEndian32(data + 20);
    return true;
  }
  if (size < 4 || data[0] != 0xff || data[1] != 0xd8) return false;
  // JPEG: walk the marker segments up to the first start-of-frame.
  size_t pos = 2;
  while (pos + 9 <= size) {
    if (data[pos] != 0xff) return false;
    const uint8_t marker = data[pos + 1];
    const size_t length = (size_t{data[pos + 2]} << 8) | data[pos + 3];
    const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof) {
      height = (uint64_t{data[pos + 5]} << 8) | data[pos + 6];
      width = (uint64_t{data[pos + 7]} << 8) | data[pos + 8];
      return true;
    }
    if (length < 2) return false;
    pos += 2 + length;
  }
  return false;
}

// Walks a PNG's chunks and checks their CRCs, so that a corrupt file is refused here rather
// than by libpng, which prints its complaints to stderr.
bool pngIntact(const uint8_t* data, size_t size, std::string& error) {
  static const std::array<uint32_t, 256> kCrcTable = [] {
    std::array<uint32_t, 256> table{};
    for (uint32_t n = 0; n < 256; ++n) {
      uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      table[n] = c;
    }
    return table;
  }();
  size_t pos = 8;
  while (pos + 12 <= size) {
    const uint32_t length = readBigEndian32(data + pos);
    if (length > size - pos - 12) break;
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = pos + 4; i < pos + 8 + length; ++i) crc = kCrcTable[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
    if ((crc ^ 0xFFFFFFFFu) != readBigEndian32(data + pos + 8 + length)) {
      error = fmt::format("PNG chunk at offset {} has a bad CRC", pos);
      return false;
    }
    if (std::memcmp(data + pos + 4, "IEND", 4) == 0) return true;
    pos += 12 + size_t{length};
  }
  error = "truncated PNG";
  return false;
}

}  // namespace

bool decodeTexture(const uint8_t* data, size_t size, Texture& out, std::string& error) {
  // PNG's deflate and JPEG's entropy coding stay well under 2048 pixels per byte even for
  // flat images; a header claiming more is corrupt and would make the decoder allocate for it.
  constexpr uint64_t kMaxPixelsPerByte = 2048;
  constexpr uint64_t kMaxPixels = uint64_t{1} << 28;
  if (size == 0) {
    error = "empty image";
    return false;
  }
  uint64_t width = 0, height = 0;
  if (imageHeaderSize(data, size, width, height) &&
      (width * height > kMaxPixels || width * height > kMaxPixelsPerByte * size)) {
    error = fmt::format("image header claims {}x{} pixels in {} bytes", width, height, size);
    return false;
  }
  static const uint8_t kPng[4] = {0x89, 'P', 'N', 'G'};
  if (size >= 8 && std::equal(kPng, kPng + 4, data) && !pngIntact(data, size, error)) return false;
  cv::Mat image;
  try {
    const cv::Mat encoded(1, static_cast<int>(std::min<size_t>(size, INT32_MAX)), CV_8U, const_cast<uint8_t*>(data));
    image = cv::imdecode(encoded, cv::IMREAD_UNCHANGED);
    if (image.empty()) {
      error = "not a decodable image";
      return false;
    }
    if (image.depth() != CV_8U) {
      const double scale = image.depth() == CV_16U ? 1.0 / 257.0 : image.depth() == CV_32F ? 255.0 : 1.0;
      image.convertTo(image, CV_8U, scale);
    }
    cv::Mat rgba;
    switch (image.channels()) {
      case 1:
        cv::cvtColor(image, rgba, cv::COLOR_GRAY2RGBA);
        break;
      case 3:
        cv::cvtColor(image, rgba, cv::COLOR_BGR2RGBA);
        break;
      case 4:
        cv::cvtColor(image, rgba, cv::COLOR_BGRA2RGBA);
        break;
      default:
        error = fmt::format("image has {} channels", image.channels());
        return false;
    }
    out.width = rgba.cols;
    out.height = rgba.rows;
    out.rgba.resize(size_t{4} * rgba.cols * rgba.rows);
    for (int y = 0; y < rgba.rows; ++y) {
      std::copy_n(rgba.ptr<uint8_t>(y), size_t{4} * rgba.cols, out.rgba.data() + size_t{4} * y * rgba.cols);
    }
  } catch (const cv::Exception& e) {
    error = e.what();
    return false;
  }
  return true;
}

std::string quote(std::string_view text, size_t max_size) {
  std::string out(text.substr(0, max_size));
  for (char& c : out) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return text.size() > max_size ? out + "..." : out;
}

// Merges the vertices of `prim` whose position, uv and colour are equal (0 and -0 alike) and
// drops the ones no triangle uses. assimp's JoinIdenticalVertices is not used: its float
// tolerance merges distinct corners of tiny coordinates, so a model saved and loaded again could
// lose every triangle's area (a fuzz finding, tests/fuzz/findings/model_ply).
void joinIdenticalVertices(Primitive& prim) {
  struct Key {
    float value[5] = {0, 0, 0, 0, 0};
    uint32_t rgba = 0;
    bool operator==(const Key& o) const { return std::equal(value, value + 5, o.value) && rgba == o.rgba; }
  };
  struct KeyHash {
    size_t operator()(const Key& k) const {
      uint64_t h = 1469598103934665603ull;  // FNV-1a over the normalised bits
      for (const float v : k.value) {
        uint32_t bits = 0;
        const float normalised = v + 0.0f;  // -0 -> +0, so that equal values hash alike
        std::memcpy(&bits, &normalised, sizeof bits);
        h = (h ^ bits) * 1099511628211ull;
      }
      return static_cast<size_t>((h ^ k.rgba) * 1099511628211ull);
    }
  };
  const size_t n = prim.positions.size() / 3;
  for (const uint32_t i : prim.indices) {
    if (i >= n) return;  // appendPrimitive reports the bad index
  }
  const bool has_uv = !prim.uvs.empty(), has_color = !prim.colors.empty();
  std::vector<uint8_t> used(n, 0);
  for (const uint32_t i : prim.indices) used[i] = 1;
  std::unordered_map<Key, uint32_t, KeyHash> first;
  first.reserve(n);
  std::vector<uint32_t> remap(n, 0);
  Primitive out;
  out.material = prim.material;
  for (size_t v = 0; v < n; ++v) {
    if (!used[v]) continue;
    Key key;
    std::copy_n(&prim.positions[3 * v], 3, key.value);
    if (has_uv) std::copy_n(&prim.uvs[2 * v], 2, key.value + 3);
    if (has_color) std::memcpy(&key.rgba, &prim.colors[4 * v], 4);
    const auto [it, inserted] = first.emplace(key, static_cast<uint32_t>(out.positions.size() / 3));
    remap[v] = it->second;
    if (!inserted) continue;
    out.positions.insert(out.positions.end(), &prim.positions[3 * v], &prim.positions[3 * v] + 3);
    if (has_uv) out.uvs.insert(out.uvs.end(), &prim.uvs[2 * v], &prim.uvs[2 * v] + 2);
    if (has_color) out.colors.insert(out.colors.end(), &prim.colors[4 * v], &prim.colors[4 * v] + 4);
  }
  out.indices.reserve(prim.indices.size());
  for (const uint32_t i : prim.indices) out.indices.push_back(remap[i]);
  prim = std::move(out);
}

bool hasTriangleWithArea(const std::vector<float>& positions, const std::vector<uint32_t>& indices) {
  constexpr double kEps = 1.1920928955078125e-07;  // float epsilon, 2^-23
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    const float* a = &positions[3 * size_t{indices[t]}];
    const float* b = &positions[3 * size_t{indices[t + 1]}];
    const float* c = &positions[3 * size_t{indices[t + 2]}];
    const Eigen::Vector3d pa(a[0], a[1], a[2]), pb(b[0], b[1], b[2]), pc(c[0], c[1], c[2]);
    const Eigen::Vector3d u = pb - pa, v = pc - pa;
    const double magnitude = std::max({pa.cwiseAbs().maxCoeff(), pb.cwiseAbs().maxCoeff(), pc.cwiseAbs().maxCoeff()});
    const double noise = 8.0 * kEps * magnitude * (u.norm() + v.norm() + (pc - pb).norm());
    const double twice_area = u.cross(v).norm();
    if (twice_area > noise && twice_area > 0.0) return true;
  }
  return false;
}

}  // namespace model_detail

namespace {

using model_detail::fileError;

std::string modelName(const Model& model) { return model.source.empty() ? "model" : model.source; }

Error modelError(const Model& model, const std::string& what) {
  return fileError(ErrorCode::kMalformedInput, modelName(model), what);
}

bool finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// A model whose triangles all have no area (corners on one point or one line) has no edges to
// render or track. Precondition: finite positions, indices in range.
Status checkArea(const Model& model) {
  if (model_detail::hasTriangleWithArea(model.positions, model.indices)) return Status::success();
  return modelError(model, fmt::format("none of the model's {} triangles has an area (the corners of each lie on one "
                                       "point or line): there is nothing to render or track",
                                       model.triangleCount()));
}

// Attribute sizes, finite values, index range, material and texture references.
Status validateGeometry(const Model& model) {
  const size_t n = model.vertexCount();
  if (model.positions.size() % 3 != 0) {
    return modelError(model, fmt::format("{} position floats is not a multiple of 3", model.positions.size()));
  }
  if (!model.uvs.empty() && model.uvs.size() != 2 * n) {
    return modelError(model, fmt::format("{} uv floats for {} vertices", model.uvs.size(), n));
  }
  if (!model.colors.empty() && model.colors.size() != 4 * n) {
    return modelError(model, fmt::format("{} colour bytes for {} vertices", model.colors.size(), n));
  }
  if (model.indices.size() % 3 != 0) {
    return modelError(model, fmt::format("{} indices is not a multiple of 3", model.indices.size()));
  }
  if (model.indices.empty()) return modelError(model, "mesh has no triangles");
  for (size_t i = 0; i < n; ++i) {
    const float* p = &model.positions[3 * i];
    if (!finite3(p)) {
      return modelError(model, fmt::format("vertex {} has non-finite position ({}, {}, {})", i, p[0], p[1], p[2]));
    }
  }
  for (size_t i = 0; i < model.uvs.size(); i += 2) {
    if (!std::isfinite(model.uvs[i]) || !std::isfinite(model.uvs[i + 1])) {
      return modelError(model, fmt::format("vertex {} has non-finite texture coordinate ({}, {})", i / 2, model.uvs[i],
                                           model.uvs[i + 1]));
    }
  }
  for (size_t i = 0; i < model.indices.size(); ++i) {
    if (model.indices[i] >= n) {
      return modelError(
          model, fmt::format("triangle {} references vertex {} but there are {} vertices", i / 3, model.indices[i], n));
    }
  }
  VKLOC_TRY_STATUS(checkArea(model));
  if (model.materials.empty()) return modelError(model, "model has no materials");
  for (size_t i = 0; i < model.materials.size(); ++i) {
    const Material& m = model.materials[i];
    if (m.texture < -1 || m.texture >= static_cast<int>(model.textures.size())) {
      return modelError(model, fmt::format("material {} ('{}') references texture {} but there are {} textures", i,
                                           m.name, m.texture, model.textures.size()));
    }
    for (float c : m.base_color) {
      if (!std::isfinite(c)) {
        return modelError(model, fmt::format("material {} ('{}') has a non-finite base colour", i, m.name));
      }
    }
  }
  for (size_t i = 0; i < model.textures.size(); ++i) {
    const Texture& t = model.textures[i];
    if (t.width <= 0 || t.height <= 0 ||
        t.rgba.size() != size_t{4} * static_cast<size_t>(t.width) * static_cast<size_t>(t.height)) {
      return modelError(model, fmt::format("texture {} ('{}') is {}x{} but has {} bytes", i, t.name, t.width, t.height,
                                           t.rgba.size()));
    }
  }
  return Status::success();
}

bool contains(const Aabb& box, const float* p) {
  for (int k = 0; k < 3; ++k) {
    if (!(p[k] >= box.min[k] && p[k] <= box.max[k])) return false;
  }
  return true;
}

// Ranges cover every triangle once; blocks cover the ranges in order; bounds enclose them.
// Precondition: validateGeometry passed.
Status validateLayout(const Model& model) {
  const uint64_t index_count = model.indices.size();
  std::vector<uint32_t> order(model.ranges.size());
  for (size_t i = 0; i < model.ranges.size(); ++i) {
    const DrawRange& r = model.ranges[i];
    if (r.first_index % 3 != 0 || r.index_count % 3 != 0 || uint64_t{r.first_index} + r.index_count > index_count) {
      return modelError(model, fmt::format("range {} (first {}, count {}) is not whole triangles within the {} indices",
                                           i, r.first_index, r.index_count, index_count));
    }
    if (r.material < 0 || r.material >= static_cast<int>(model.materials.size())) {
      return modelError(model, fmt::format("range {} references material {} but there are {} materials", i, r.material,
                                           model.materials.size()));
    }
    order[i] = static_cast<uint32_t>(i);
  }
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return model.ranges[a].first_index < model.ranges[b].first_index; });
  uint64_t covered = 0;
  for (uint32_t i : order) {
    const DrawRange& r = model.ranges[i];
    if (r.index_count == 0) continue;
    if (r.first_index != covered) {
      return modelError(model,
                        fmt::format("ranges {} triangles from index {}", r.first_index > covered ? "miss" : "repeat",
                                    std::min<uint64_t>(r.first_index, covered)));
    }
    covered += r.index_count;
  }
  if (covered != index_count) {
    return modelError(model, fmt::format("ranges cover {} of {} indices", covered, index_count));
  }
  if (model.blocks.empty()) return modelError(model, "model has no blocks");
  uint64_t next_range = 0;
  for (size_t b = 0; b < model.blocks.size(); ++b) {
    const Block& block = model.blocks[b];
    if (block.first_range != next_range || uint64_t{block.first_range} + block.range_count > model.ranges.size()) {
      return modelError(model,
                        fmt::format("block {} has ranges {}..{} but the next range is {} of {}", b, block.first_range,
                                    uint64_t{block.first_range} + block.range_count, next_range, model.ranges.size()));
    }
    next_range += block.range_count;
    uint64_t triangles = 0;
    for (uint32_t r = block.first_range; r < block.first_range + block.range_count; ++r) {
      const DrawRange& range = model.ranges[r];
      triangles += range.index_count / 3;
      for (uint32_t i = range.first_index; i < range.first_index + range.index_count; ++i) {
        const float* p = &model.positions[3 * size_t{model.indices[i]}];
        if (!contains(block.bounds, p) || !contains(model.bounds, p)) {
          return modelError(
              model, fmt::format("vertex {} lies outside the bounds of block {} or of the model", model.indices[i], b));
        }
      }
    }
    if (triangles != block.triangle_count) {
      return modelError(
          model, fmt::format("block {} says {} triangles but its ranges have {}", b, block.triangle_count, triangles));
    }
  }
  if (next_range != model.ranges.size()) {
    return modelError(model, fmt::format("blocks cover {} of {} ranges", next_range, model.ranges.size()));
  }
  return Status::success();
}

Status checkOptions(const std::string& path, const ModelLoadOptions& options) {
  const auto& T = options.T_world_model;
  if (!std::isfinite(options.unit_scale) || options.unit_scale <= 0.0) {
    return fileError(ErrorCode::kInvalidArgument, path,
                     fmt::format("unit_scale must be positive and finite, got {}", options.unit_scale));
  }
  for (double v : T) {
    if (!std::isfinite(v)) {
      return fileError(ErrorCode::kInvalidArgument, path, "T_world_model has non-finite entries");
    }
  }
  if (T[12] != 0.0 || T[13] != 0.0 || T[14] != 0.0 || T[15] != 1.0) {
    return fileError(ErrorCode::kInvalidArgument, path,
                     fmt::format("T_world_model's last row must be 0 0 0 1 (row-major), got {} {} {} {}", T[12], T[13],
                                 T[14], T[15]));
  }
  const double det =
      T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) + T[2] * (T[4] * T[9] - T[5] * T[8]);
  if (std::abs(det) < 1e-12) {
    return fileError(ErrorCode::kInvalidArgument, path, "T_world_model is singular");
  }
  return Status::success();
}

Result<Model> loadChecked(const std::string& path, const ModelLoadOptions& options,
                          std::vector<std::string>& warnings) {
  namespace fs = std::filesystem;
  VKLOC_TRY_STATUS(checkOptions(path, options));
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return fileError(ErrorCode::kNotFound, path, "file not found");
  if (fs::is_directory(status)) {
    return fileError(ErrorCode::kIoError, path, "is a directory, not a model file");
  }
  const uintmax_t size = fs::file_size(path, ec);
  if (ec) return fileError(ErrorCode::kIoError, path, "cannot read file: " + ec.message());
  if (size == 0) return fileError(ErrorCode::kMalformedInput, path, "file is empty");
  if (size > model_detail::kMaxModelFileBytes) {
    return fileError(
        ErrorCode::kMalformedInput, path,
        fmt::format("file is larger than the {} bytes allowed ({} bytes)", model_detail::kMaxModelFileBytes, size));
  }

  const std::string ext = model_detail::lowerExtension(path);
  Result<Model> loaded = [&]() -> Result<Model> {
    if (ext == ".obj") return model_detail::loadWithAssimp(path, ext, warnings);
    if (ext == ".ply") {
      auto bytes = model_detail::readFileBytes(path);
      if (!bytes.ok()) return bytes.error();
      return model_detail::loadPly(path, *bytes);
    }
    if (ext == ".gltf" || ext == ".glb") return model_detail::loadGltf(path, warnings);
    if (ext == ".drc") return model_detail::loadDrc(path);
    if (ext == ".cao") return loadCaoModel(path, &warnings);
    if (!ext.empty() && model_detail::assimpReadsExtension(ext)) {
      return model_detail::loadWithAssimp(path, ext, warnings);
    }
    return fileError(
        ErrorCode::kUnsupported, path,
        ext.empty()
            ? std::string("unknown model format (no file extension)")
            : fmt::format(
                  "unknown model format '{}' (use .obj, .ply, .gltf, .glb, .drc, .cao or another format assimp reads)",
                  ext));
  }();
  if (!loaded.ok()) return loaded.error();

  Model model = std::move(loaded).value();
  model.source = path;
  if (model.materials.empty()) {
    model.materials.push_back(Material{});
    model.materials.back().name = "default";
  }
  VKLOC_TRY_STATUS(validateGeometry(model));
  for (const DrawRange& r : model.ranges) {
    if (r.material < 0 || r.material >= static_cast<int>(model.materials.size())) {
      return modelError(model, fmt::format("a mesh references material {} but there are {} materials", r.material,
                                           model.materials.size()));
    }
  }
  transformModel(model, options.T_world_model, options.unit_scale);
  for (size_t i = 0; i < model.vertexCount(); ++i) {
    if (!finite3(&model.positions[3 * i])) {
      return fileError(ErrorCode::kInvalidArgument, path,
                       fmt::format("vertex {} is not finite after applying unit_scale and T_world_model", i));
    }
  }
  buildBlocks(model, options.max_block_triangles);
  VKLOC_TRY_STATUS(validateLayout(model));
  // Positions are stored as float in the world frame: far from the world origin they are
  // rounded (2^-24 of the coordinate). Say so when that exceeds 0.1 mm.
  float reach = 0.0f;
  for (int k = 0; k < 3; ++k) reach = std::max({reach, std::abs(model.bounds.min[k]), std::abs(model.bounds.max[k])});
  if (reach > 1600.0f) {
    warnings.push_back(
        fmt::format("{}: coordinates reach {:.0f} m from the world origin, where positions are rounded to "
                    "{:.2f} mm; place the world origin near the model (T_world_model)",
                    path, reach, reach * 1000.0 / (1 << 24)));
  }
  return model;
}

}  // namespace

Result<Model> loadModel(const std::string& path, const ModelLoadOptions& options, std::vector<std::string>* warnings) {
  std::vector<std::string> ignored;
  try {
    return loadChecked(path, options, warnings ? *warnings : ignored);
  } catch (const std::bad_alloc&) {
    return fileError(ErrorCode::kMalformedInput, path, "out of memory while loading");
  } catch (const std::exception& e) {
    return fileError(ErrorCode::kMalformedInput, path, std::string("cannot load: ") + e.what());
  } catch (...) {
    return fileError(ErrorCode::kMalformedInput, path, "cannot load: unknown error");
  }
}

Status validateModel(const Model& model) {
  VKLOC_TRY_STATUS(validateGeometry(model));
  return validateLayout(model);
}

void transformModel(Model& model, const std::array<double, 16>& T, double unit_scale) {
  float* p = model.positions.data();
  for (size_t i = 0; i < model.vertexCount(); ++i, p += 3) {
    const double x = unit_scale * p[0], y = unit_scale * p[1], z = unit_scale * p[2];
    p[0] = static_cast<float>(T[0] * x + T[1] * y + T[2] * z + T[3]);
    p[1] = static_cast<float>(T[4] * x + T[5] * y + T[6] * z + T[7]);
    p[2] = static_cast<float>(T[8] * x + T[9] * y + T[10] * z + T[11]);
  }
  // A mirroring transform turns counter-clockwise triangles clockwise; swap two corners of
  // each so they stay counter-clockwise seen from outside.
  const double det =
      unit_scale * unit_scale * unit_scale *
      (T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) + T[2] * (T[4] * T[9] - T[5] * T[8]));
  if (det < 0.0) {
    for (size_t t = 0; t + 2 < model.indices.size(); t += 3) {
      std::swap(model.indices[t + 1], model.indices[t + 2]);
    }
  }
  model_detail::updateBounds(model);
}

}  // namespace vkloc
