// Model writers: OBJ (+ MTL, PNG), PLY, glTF / GLB (optionally Draco-compressed) and Draco.
#include "vkloc/model/model_write.hpp"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/core/decoder_buffer.h>
#include <draco/core/encoder_buffer.h>
#include <draco/mesh/mesh.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <vector>

#include "model/model_internal.hpp"
#include "vkloc/core/atomic_file.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

static_assert(std::endian::native == std::endian::little, "the PLY and GLB writers assume a little-endian host");

using model_detail::fileError;
using model_detail::lowerExtension;

/// `text` with every character outside [A-Za-z0-9._-] replaced by '_' (safe in OBJ/MTL
/// statements and glTF URIs without escaping).
std::string safeName(const std::string& text) {
  std::string out = text;
  for (char& c : out) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (!std::isalnum(u) && c != '.' && c != '_' && c != '-') c = '_';
  }
  return out.empty() ? std::string("model") : out;
}

// ---- checks ------------------------------------------------------------------------------------

Status checkModel(const Model& m, const std::string& path) {
  auto bad = [&](const std::string& what) {
    return fileError(ErrorCode::kInvalidArgument, path, "cannot write model: " + what);
  };
  if (m.positions.size() % 3 != 0) return bad("positions size is not a multiple of 3");
  const size_t n = m.vertexCount();
  if (!m.uvs.empty() && m.uvs.size() != 2 * n) return bad(fmt::format("{} uv values for {} vertices", m.uvs.size(), n));
  if (!m.colors.empty() && m.colors.size() != 4 * n)
    return bad(fmt::format("{} colour bytes for {} vertices", m.colors.size(), n));
  if (m.indices.empty() || m.indices.size() % 3 != 0)
    return bad("no triangles (index count must be a positive multiple of 3)");
  for (float v : m.positions)
    if (!std::isfinite(v)) return bad("non-finite vertex position");
  for (float v : m.uvs)
    if (!std::isfinite(v)) return bad("non-finite texture coordinate");
  for (uint32_t i : m.indices)
    if (i >= n) return bad(fmt::format("index {} is not below the vertex count {}", i, n));
  const size_t nm = std::max<size_t>(1, m.materials.size());
  for (const DrawRange& r : m.ranges) {
    if (r.first_index % 3 != 0 || r.index_count % 3 != 0 || uint64_t(r.first_index) + r.index_count > m.indices.size())
      return bad("draw range outside the index array");
    if (r.material < 0 || static_cast<size_t>(r.material) >= nm)
      return bad(fmt::format("draw range material {} does not exist", r.material));
  }
  for (const Material& mat : m.materials)
    if (mat.texture >= static_cast<int>(m.textures.size()))
      return bad(fmt::format("material '{}' references missing texture {}", mat.name, mat.texture));
  for (const Texture& t : m.textures)
    if (t.width <= 0 || t.height <= 0 || t.rgba.size() != size_t(t.width) * t.height * 4)
      return bad(
          fmt::format("texture '{}' size {}x{} does not match its {} bytes", t.name, t.width, t.height, t.rgba.size()));
  return Status::success();
}

Status checkOptions(const ModelWriteOptions& o, const std::string& path) {
  // Draco's entropy coder counts symbols in a table as long as the largest one (up to
  // 2^(bits + 1) for sparse geometry): 24 bits keep it within 128 MiB, 30 asked for 4 GiB.
  if (o.draco_position_bits < 1 || o.draco_position_bits > 24 || o.draco_uv_bits < 1 || o.draco_uv_bits > 24)
    return fileError(ErrorCode::kInvalidArgument, path, "Draco quantization bits must be in 1..24");
  if (o.draco_speed < 0 || o.draco_speed > 10)
    return fileError(ErrorCode::kInvalidArgument, path, "Draco speed must be in 0..10");
  return Status::success();
}

/// The model's materials (a default one when it has none) and its triangles grouped by
/// material; without ranges, every triangle uses material 0.
struct MaterialGroups {
  std::vector<Material> materials;
  std::vector<std::vector<uint32_t>> indices;  ///< Per material, 3 per triangle.
};

MaterialGroups groupByMaterial(const Model& m) {
  MaterialGroups g;
  g.materials = m.materials;
  if (g.materials.empty()) g.materials.push_back(Material{"default"});
  g.indices.resize(g.materials.size());
  if (m.ranges.empty()) {
    g.indices[0] = m.indices;
  } else {
    for (const DrawRange& r : m.ranges) {
      auto& out = g.indices[static_cast<size_t>(r.material)];
      out.insert(out.end(), m.indices.begin() + r.first_index, m.indices.begin() + r.first_index + r.index_count);
    }
  }
  return g;
}

/// Unique names made of safe characters, "material_<i>" for empty ones.
std::vector<std::string> materialNames(const std::vector<Material>& materials) {
  std::vector<std::string> names;
  std::set<std::string> seen;
  for (size_t i = 0; i < materials.size(); ++i) {
    std::string name = materials[i].name.empty() ? fmt::format("material_{}", i) : safeName(materials[i].name);
    if (seen.count(name)) name += fmt::format("_{}", i);
    seen.insert(name);
    names.push_back(name);
  }
  return names;
}

// ---- files -------------------------------------------------------------------------------------

/// Companion file next to `path`: `<dir>/<safe stem><suffix>`.
std::string companion(const std::string& path, const std::string& suffix) {
  const fs::path p(path);
  return (p.parent_path() / (safeName(p.stem().string()) + suffix)).string();
}

std::string fileName(const std::string& path) { return fs::path(path).filename().string(); }

Result<std::vector<uint8_t>> encodePng(const Texture& t, const std::string& path) {
  cv::Mat rgba(t.height, t.width, CV_8UC4, const_cast<uint8_t*>(t.rgba.data()));
  bool opaque = true;
  for (size_t i = 3; i < t.rgba.size() && opaque; i += 4) opaque = t.rgba[i] == 255;
  std::vector<uint8_t> png;
  try {
    cv::Mat bgr;
    cv::cvtColor(rgba, bgr, opaque ? cv::COLOR_RGBA2BGR : cv::COLOR_RGBA2BGRA);
    if (!cv::imencode(".png", bgr, png)) return fileError(ErrorCode::kIoError, path, "PNG encoding failed");
  } catch (const cv::Exception& e) {
    return fileError(ErrorCode::kIoError, path, std::string("PNG encoding failed: ") + e.what());
  }
  return png;
}

/// Appends the shortest text that reads back as exactly `v`.
void appendFloat(std::string& out, float v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out.append(buf, r.ptr);
}

void appendUint(std::string& out, uint64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out.append(buf, r.ptr);
}

// ---- OBJ ---------------------------------------------------------------------------------------

Status writeObj(const Model& m, const std::string& path, AtomicFileSet& files) {
  const MaterialGroups groups = groupByMaterial(m);
  const std::vector<std::string> names = materialNames(groups.materials);
  const bool textured = !m.uvs.empty();
  const std::string mtl_path = companion(path, ".mtl");
  std::vector<std::string> texture_files(m.textures.size());
  if (textured) {
    for (size_t i = 0; i < m.textures.size(); ++i) {
      const std::string png_path = companion(path, fmt::format("_tex{}.png", i));
      auto png = encodePng(m.textures[i], png_path);
      if (!png.ok()) return png.error();
      VKLOC_TRY_STATUS(files.write(png_path, png->data(), png->size()));
      texture_files[i] = fileName(png_path);
    }
  }
  std::string mtl = "# vkloc materials\n";
  for (size_t i = 0; i < groups.materials.size(); ++i) {
    const Material& mat = groups.materials[i];
    mtl += fmt::format("\nnewmtl {}\nKa 0 0 0\nKd {} {} {}\nKs 0 0 0\nd {}\nillum 1\n", names[i], mat.base_color[0],
                       mat.base_color[1], mat.base_color[2], mat.base_color[3]);
    if (textured && mat.texture >= 0) mtl += "map_Kd " + texture_files[static_cast<size_t>(mat.texture)] + "\n";
  }
  VKLOC_TRY_STATUS(files.write(mtl_path, mtl));

  return files.write(path, [&](std::ostream& out) {
    std::string text;
    text.reserve(1 << 20);
    auto flush = [&](bool force) {
      if (force || text.size() > (1u << 20)) {
        out.write(text.data(), static_cast<std::streamsize>(text.size()));
        text.clear();
      }
    };
    text += fmt::format("# vkloc model: {} vertices, {} triangles\nmtllib {}\n", m.vertexCount(), m.triangleCount(),
                        fileName(mtl_path));
    for (size_t v = 0; v < m.vertexCount(); ++v) {
      text += "v ";
      for (int k = 0; k < 3; ++k) {
        if (k) text += ' ';
        appendFloat(text, m.positions[3 * v + k]);
      }
      if (!m.colors.empty()) {
        for (int k = 0; k < 3; ++k) {
          text += ' ';
          appendFloat(text, m.colors[4 * v + k] / 255.0f);
        }
      }
      text += '\n';
      flush(false);
    }
    if (textured) {
      for (size_t v = 0; v < m.vertexCount(); ++v) {
        text += "vt ";
        appendFloat(text, m.uvs[2 * v]);
        text += ' ';
        appendFloat(text, 1.0f - m.uvs[2 * v + 1]);
        text += '\n';
        flush(false);
      }
    }
    for (size_t g = 0; g < groups.indices.size(); ++g) {
      if (groups.indices[g].empty()) continue;
      text += "usemtl " + names[g] + "\n";
      const auto& idx = groups.indices[g];
      for (size_t t = 0; t < idx.size(); t += 3) {
        text += 'f';
        for (int k = 0; k < 3; ++k) {
          text += ' ';
          appendUint(text, idx[t + k] + uint64_t{1});
          if (textured) {
            text += '/';
            appendUint(text, idx[t + k] + uint64_t{1});
          }
        }
        text += '\n';
        flush(false);
      }
    }
    flush(true);
    return static_cast<bool>(out);
  });
}

// ---- PLY ---------------------------------------------------------------------------------------

template <typename T>
void put(std::vector<uint8_t>& out, T v) {
  const size_t at = out.size();
  out.resize(at + sizeof(T));
  std::memcpy(out.data() + at, &v, sizeof(T));
}

Status writePly(const Model& m, const std::string& path, AtomicFileSet& files) {
  const size_t n = m.vertexCount(), nt = m.triangleCount();
  const bool uv = !m.uvs.empty(), col = !m.colors.empty();
  std::string header = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment vkloc model\nelement vertex {}\n"
      "property float x\nproperty float y\nproperty float z\n",
      n);
  if (uv) header += "property float s\nproperty float t\n";
  if (col) header += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  header += fmt::format("element face {}\nproperty list uchar int vertex_indices\nend_header\n", nt);
  std::vector<uint8_t> body;
  body.reserve(n * (12 + (uv ? 8 : 0) + (col ? 4 : 0)) + nt * 13);
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) put(body, m.positions[3 * v + k]);
    if (uv) {
      put(body, m.uvs[2 * v]);
      put(body, 1.0f - m.uvs[2 * v + 1]);
    }
    if (col)
      for (int k = 0; k < 4; ++k) put(body, m.colors[4 * v + k]);
  }
  for (size_t t = 0; t < nt; ++t) {
    put(body, uint8_t{3});
    for (int k = 0; k < 3; ++k) put(body, static_cast<int32_t>(m.indices[3 * t + k]));
  }
  return files.write(path, [&](std::ostream& out) {
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    out.write(reinterpret_cast<const char*>(body.data()), static_cast<std::streamsize>(body.size()));
    return static_cast<bool>(out);
  });
}

// ---- Draco -------------------------------------------------------------------------------------

/// One Draco-encoded mesh and what a decoder gets back from it.
struct DracoBlob {
  std::vector<uint8_t> bytes;
  int position_id = -1, uv_id = -1, color_id = -1;  ///< Attribute unique ids, -1 when absent.
  uint32_t decoded_points = 0, decoded_faces = 0;
  std::array<float, 3> min{}, max{};  ///< Bounds of the decoded (dequantized) positions.
  bool has_area = false;              ///< Whether a decoded triangle has an area.
};

Error collapsedError(const std::string& path, const ModelWriteOptions& o) {
  return fileError(ErrorCode::kInvalidArgument, path,
                   fmt::format("Draco's {}-bit position quantization collapses every triangle; save with more "
                               "position bits or as .ply/.obj",
                               o.draco_position_bits));
}

/// Whether a triangle keeps an area once the positions are quantized to `bits` as Draco does
/// (x, y, z per vertex); true for a range that overflows a float (refused elsewhere).
bool quantizedTriangleWithArea(const std::vector<float>& positions, const std::vector<uint32_t>& indices, int bits) {
  float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                 std::numeric_limits<float>::max()};
  float hi[3] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(),
                 std::numeric_limits<float>::lowest()};
  for (size_t i = 0; i < positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], positions[i]);
    hi[i % 3] = std::max(hi[i % 3], positions[i]);
  }
  float range = 0.0f;
  for (int k = 0; k < 3; ++k) range = std::max(range, hi[k] - lo[k]);
  if (!std::isfinite(range)) return true;  // refused by encodeDraco's range check, with its reason
  if (range == 0.0f) range = 1.0f;
  const float scale = static_cast<float>((int64_t{1} << bits) - 1) / range;
  const int64_t top = (int64_t{1} << bits) - 1;
  const auto quantized = [&](uint32_t vertex, int k) -> int64_t {
    const float v = std::floor((positions[3 * size_t{vertex} + static_cast<size_t>(k)] - lo[k]) * scale + 0.5f);
    if (!(v > 0.0f)) return 0;  // also NaN, from an infinite scale over a zero offset
    return v >= static_cast<float>(top) ? top : static_cast<int64_t>(v);
  };
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    int64_t e1[3], e2[3];  // coordinates below 2^24 (the most bits): every product fits
    for (int k = 0; k < 3; ++k) {
      const int64_t a = quantized(indices[t], k);
      e1[k] = quantized(indices[t + 1], k) - a;
      e2[k] = quantized(indices[t + 2], k) - a;
    }
    if (e1[1] * e2[2] != e1[2] * e2[1] || e1[2] * e2[0] != e1[0] * e2[2] || e1[0] * e2[1] != e1[1] * e2[0]) {
      return true;
    }
  }
  return false;
}

/// Encodes vertices (positions, optional uvs and RGBA colours) and triangles; `flip_v` stores
/// v' = 1 - v.
Result<DracoBlob> encodeDraco(const std::vector<float>& positions, const std::vector<float>& uvs,
                              const std::vector<uint8_t>& colors, const std::vector<uint32_t>& indices, bool flip_v,
                              const ModelWriteOptions& o, const std::string& path) {
  const uint32_t n = static_cast<uint32_t>(positions.size() / 3);
  // Draco quantizes each attribute over its range, max - min in float: a range that overflows
  // makes its encoder crash (a fuzz finding), so such a model is refused.
  const auto checkRange = [&](const std::vector<float>& values, const std::string& names, const char* what) -> Status {
    const int components = static_cast<int>(names.size());
    for (int k = 0; k < components; ++k) {
      float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
      for (size_t i = static_cast<size_t>(k); i < values.size(); i += static_cast<size_t>(components)) {
        lo = std::min(lo, values[i]);
        hi = std::max(hi, values[i]);
      }
      if (!values.empty() && !std::isfinite(hi - lo)) {
        return fileError(ErrorCode::kInvalidArgument, path,
                         fmt::format("{} {} spans {:g} to {:g}, more than a float holds: Draco cannot quantize it; "
                                     "save as .ply, .obj or .gltf",
                                     what, names[static_cast<size_t>(k)], lo, hi));
      }
    }
    return Status::success();
  };
  VKLOC_TRY_STATUS(checkRange(positions, "xyz", "position"));
  VKLOC_TRY_STATUS(checkRange(uvs, "uv", "texture coordinate"));
  draco::Mesh mesh;
  mesh.set_num_points(n);
  auto add = [&](draco::GeometryAttribute::Type type, int components, draco::DataType dt, bool normalized,
                 const void* data, size_t bytes_per_value) {
    draco::GeometryAttribute ga;
    ga.Init(type, nullptr, static_cast<uint8_t>(components), dt, normalized, static_cast<int64_t>(bytes_per_value), 0);
    const int id = mesh.AddAttribute(ga, true, n);
    mesh.attribute(id)->buffer()->Write(0, data, bytes_per_value * n);
    return id;
  };
  DracoBlob blob;
  const int pos = add(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, false, positions.data(), 12);
  int uv = -1, col = -1;
  if (!uvs.empty()) {
    std::vector<float> stored = uvs;
    if (flip_v)
      for (size_t i = 1; i < stored.size(); i += 2) stored[i] = 1.0f - stored[i];
    uv = add(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32, false, stored.data(), 8);
  }
  if (!colors.empty()) col = add(draco::GeometryAttribute::COLOR, 4, draco::DT_UINT8, true, colors.data(), 4);
  const size_t nf = indices.size() / 3;
  mesh.SetNumFaces(nf);
  for (size_t f = 0; f < nf; ++f) {
    mesh.SetFace(draco::FaceIndex(static_cast<uint32_t>(f)),
                 {draco::PointIndex(indices[3 * f]), draco::PointIndex(indices[3 * f + 1]),
                  draco::PointIndex(indices[3 * f + 2])});
  }
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, o.draco_position_bits);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, o.draco_uv_bits);
  encoder.SetSpeedOptions(o.draco_speed, o.draco_speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  if (!status.ok()) return fileError(ErrorCode::kIoError, path, "Draco encoding failed: " + status.error_msg_string());
  blob.bytes.assign(buffer.data(), buffer.data() + buffer.size());
  blob.position_id = static_cast<int>(mesh.attribute(pos)->unique_id());
  if (uv >= 0) blob.uv_id = static_cast<int>(mesh.attribute(uv)->unique_id());
  if (col >= 0) blob.color_id = static_cast<int>(mesh.attribute(col)->unique_id());

  // Decode once: the glTF accessors must describe the decoded mesh (counts, position bounds).
  draco::DecoderBuffer in;
  in.Init(reinterpret_cast<const char*>(blob.bytes.data()), blob.bytes.size());
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&in);
  if (!decoded.ok())
    return fileError(ErrorCode::kIoError, path, "Draco round trip failed: " + decoded.status().error_msg_string());
  const std::unique_ptr<draco::Mesh> back = std::move(decoded).value();
  blob.decoded_points = back->num_points();
  blob.decoded_faces = back->num_faces();
  const draco::PointAttribute* p = back->GetAttributeByUniqueId(static_cast<uint32_t>(blob.position_id));
  if (!p) return fileError(ErrorCode::kIoError, path, "Draco round trip lost the positions");
  blob.min = {1e30f, 1e30f, 1e30f};
  blob.max = {-1e30f, -1e30f, -1e30f};
  std::vector<float> decoded_positions;
  decoded_positions.reserve(3 * size_t{blob.decoded_points});
  for (uint32_t i = 0; i < blob.decoded_points; ++i) {
    float v[3];
    p->GetMappedValue(draco::PointIndex(i), v);
    for (int k = 0; k < 3; ++k) blob.min[k] = std::min(blob.min[k], v[k]), blob.max[k] = std::max(blob.max[k], v[k]);
    decoded_positions.insert(decoded_positions.end(), v, v + 3);
  }
  std::vector<uint32_t> decoded_indices;
  decoded_indices.reserve(3 * size_t{blob.decoded_faces});
  for (uint32_t f = 0; f < blob.decoded_faces; ++f) {
    for (const draco::PointIndex& i : back->face(draco::FaceIndex(f))) decoded_indices.push_back(i.value());
  }
  blob.has_area = model_detail::hasTriangleWithArea(decoded_positions, decoded_indices);
  return blob;
}

Status writeDrc(const Model& m, const std::string& path, const ModelWriteOptions& o, AtomicFileSet& files) {
  // What load would refuse is not written, and Draco's encoder is not given it: quantization can
  // collapse every triangle of a model that is small against its bounds. Positions are quantized
  // here as Draco does: per-axis minimum, one step for all axes from the largest range, rounded
  // in float. (A glTF primitive may collapse alone; the model keeps area through the others.)
  if (!quantizedTriangleWithArea(m.positions, m.indices, o.draco_position_bits)) return collapsedError(path, o);
  auto blob = encodeDraco(m.positions, m.uvs, m.colors, m.indices, true, o, path);
  if (!blob.ok()) return blob.error();
  // Checked before encoding as well; this catches what Draco's own rounding collapses.
  if (!blob->has_area) {
    return collapsedError(path, o);
  }
  return files.write(path, blob->bytes.data(), blob->bytes.size());
}

// ---- glTF / GLB --------------------------------------------------------------------------------

constexpr int kFloat = 5126, kUnsignedByte = 5121, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

class GltfWriter {
 public:
  GltfWriter(const Model& m, const std::string& path, bool binary, const ModelWriteOptions& o)
      : m_(m), path_(path), binary_(binary), o_(o) {}

  Status write(AtomicFileSet& files) {
    const MaterialGroups groups = groupByMaterial(m_);
    const bool textured = !m_.uvs.empty() && !m_.textures.empty();
    json prims = json::array();
    std::vector<int32_t> remap(m_.vertexCount(), -1);
    for (size_t g = 0; g < groups.indices.size(); ++g) {
      if (groups.indices[g].empty()) continue;
      // Compact vertex set of this primitive.
      std::vector<uint32_t> used, local;
      local.reserve(groups.indices[g].size());
      for (uint32_t i : groups.indices[g]) {
        if (remap[i] < 0) {
          remap[i] = static_cast<int32_t>(used.size());
          used.push_back(i);
        }
        local.push_back(static_cast<uint32_t>(remap[i]));
      }
      for (uint32_t i : used) remap[i] = -1;
      std::vector<float> pos, uv;
      std::vector<uint8_t> col;
      pos.reserve(used.size() * 3);
      for (uint32_t i : used) pos.insert(pos.end(), &m_.positions[3 * i], &m_.positions[3 * i] + 3);
      if (!m_.uvs.empty())
        for (uint32_t i : used) uv.insert(uv.end(), &m_.uvs[2 * i], &m_.uvs[2 * i] + 2);
      if (!m_.colors.empty())
        for (uint32_t i : used) col.insert(col.end(), &m_.colors[4 * i], &m_.colors[4 * i] + 4);
      json prim = {{"material", g}, {"mode", 4}};
      if (o_.draco) {
        auto blob = encodeDraco(pos, uv, col, local, false, o_, path_);
        if (!blob.ok()) return blob.error();
        const size_t view = addView(blob->bytes.data(), blob->bytes.size(), 0);
        json attributes, ids;
        attributes["POSITION"] = addAccessor(-1, kFloat, blob->decoded_points, "VEC3", false, &blob->min, &blob->max);
        ids["POSITION"] = blob->position_id;
        if (!uv.empty()) {
          attributes["TEXCOORD_0"] = addAccessor(-1, kFloat, blob->decoded_points, "VEC2");
          ids["TEXCOORD_0"] = blob->uv_id;
        }
        if (!col.empty()) {
          attributes["COLOR_0"] = addAccessor(-1, kUnsignedByte, blob->decoded_points, "VEC4", true);
          ids["COLOR_0"] = blob->color_id;
        }
        prim["attributes"] = attributes;
        prim["indices"] = addAccessor(-1, kUnsignedInt, size_t{3} * blob->decoded_faces, "SCALAR");
        prim["extensions"] = {{"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", ids}}}};
      } else {
        std::array<float, 3> lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
        for (size_t i = 0; i < pos.size(); ++i)
          lo[i % 3] = std::min(lo[i % 3], pos[i]), hi[i % 3] = std::max(hi[i % 3], pos[i]);
        json attributes;
        attributes["POSITION"] = addAccessor(static_cast<int>(addView(pos.data(), pos.size() * 4, kArrayBuffer)),
                                             kFloat, used.size(), "VEC3", false, &lo, &hi);
        if (!uv.empty())
          attributes["TEXCOORD_0"] = addAccessor(static_cast<int>(addView(uv.data(), uv.size() * 4, kArrayBuffer)),
                                                 kFloat, used.size(), "VEC2");
        if (!col.empty())
          attributes["COLOR_0"] = addAccessor(static_cast<int>(addView(col.data(), col.size(), kArrayBuffer)),
                                              kUnsignedByte, used.size(), "VEC4", true);
        prim["attributes"] = attributes;
        prim["indices"] = addAccessor(static_cast<int>(addView(local.data(), local.size() * 4, kElementArrayBuffer)),
                                      kUnsignedInt, local.size(), "SCALAR");
      }
      prims.push_back(prim);
    }

    json root;
    root["asset"] = {{"version", "2.0"}, {"generator", "vkloc"}};
    if (o_.draco) {
      root["extensionsUsed"] = {"KHR_draco_mesh_compression"};
      root["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    }
    root["scene"] = 0;
    root["scenes"] = {{{"nodes", {0}}}};
    root["nodes"] = {{{"mesh", 0}, {"name", "vkloc"}}};
    root["meshes"] = {{{"name", "vkloc"}, {"primitives", prims}}};
    json materials = json::array();
    const std::vector<std::string> names = materialNames(groups.materials);
    for (size_t i = 0; i < groups.materials.size(); ++i) {
      const Material& mat = groups.materials[i];
      json pbr = {{"baseColorFactor", mat.base_color}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}};
      if (textured && mat.texture >= 0) pbr["baseColorTexture"] = {{"index", mat.texture}};
      materials.push_back({{"name", mat.name.empty() ? names[i] : mat.name}, {"pbrMetallicRoughness", pbr}});
    }
    root["materials"] = materials;
    if (textured) {
      root["samplers"] = {{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}}};
      json images = json::array(), textures = json::array();
      for (size_t i = 0; i < m_.textures.size(); ++i) {
        const std::string png_path = companion(path_, fmt::format("_tex{}.png", i));
        auto png = encodePng(m_.textures[i], png_path);
        if (!png.ok()) return png.error();
        json image = {{"name", m_.textures[i].name}};
        if (binary_) {
          image["bufferView"] = addView(png->data(), png->size(), 0);
          image["mimeType"] = "image/png";
        } else {
          VKLOC_TRY_STATUS(files.write(png_path, png->data(), png->size()));
          image["uri"] = fileName(png_path);
        }
        images.push_back(image);
        textures.push_back({{"sampler", 0}, {"source", i}});
      }
      root["images"] = images;
      root["textures"] = textures;
    }
    root["bufferViews"] = views_;
    root["accessors"] = accessors_;
    json buffer = {{"byteLength", bin_.size()}};
    if (!binary_) {
      const std::string bin_path = companion(path_, ".bin");
      VKLOC_TRY_STATUS(files.write(bin_path, bin_.data(), bin_.size()));
      buffer["uri"] = fileName(bin_path);
    }
    root["buffers"] = {buffer};

    std::string text = root.dump();
    if (!binary_) return files.write(path_, text.data(), text.size());
    // GLB: 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros.
    while (text.size() % 4) text += ' ';
    while (bin_.size() % 4) bin_.push_back(0);
    std::vector<uint8_t> glb;
    const uint32_t total = static_cast<uint32_t>(12 + 8 + text.size() + 8 + bin_.size());
    put(glb, uint32_t{0x46546C67});
    put(glb, uint32_t{2});
    put(glb, total);
    put(glb, static_cast<uint32_t>(text.size()));
    put(glb, uint32_t{0x4E4F534A});
    glb.insert(glb.end(), text.begin(), text.end());
    put(glb, static_cast<uint32_t>(bin_.size()));
    put(glb, uint32_t{0x004E4942});
    glb.insert(glb.end(), bin_.begin(), bin_.end());
    return files.write(path_, glb.data(), glb.size());
  }

 private:
  size_t addView(const void* data, size_t bytes, int target) {
    while (bin_.size() % 4) bin_.push_back(0);
    const size_t offset = bin_.size();
    bin_.insert(bin_.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + bytes);
    json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    views_.push_back(view);
    return views_.size() - 1;
  }

  /// An accessor; view < 0 leaves out the bufferView (Draco-compressed data).
  size_t addAccessor(int view, int component, size_t count, const char* type, bool normalized = false,
                     const std::array<float, 3>* min = nullptr, const std::array<float, 3>* max = nullptr) {
    json a = {{"componentType", component}, {"count", count}, {"type", type}};
    if (view >= 0) a["bufferView"] = view;
    if (normalized) a["normalized"] = true;
    if (min) a["min"] = *min;
    if (max) a["max"] = *max;
    accessors_.push_back(a);
    return accessors_.size() - 1;
  }

  const Model& m_;
  const std::string& path_;
  bool binary_;
  const ModelWriteOptions& o_;
  std::vector<uint8_t> bin_;
  json views_ = json::array();
  json accessors_ = json::array();
};

}  // namespace

Status saveModel(const Model& model, const std::string& path, const ModelWriteOptions& options) {
  const std::string ext = lowerExtension(path);
  if (ext != ".obj" && ext != ".ply" && ext != ".gltf" && ext != ".glb" && ext != ".drc")
    return fileError(ErrorCode::kUnsupported, path,
                     "unknown model format '" + ext + "' for writing (use .obj, .ply, .gltf, .glb or .drc)");
  VKLOC_TRY_STATUS(checkModel(model, path));
  VKLOC_TRY_STATUS(checkOptions(options, path));
  AtomicFileSet files;
  if (ext == ".obj") VKLOC_TRY_STATUS(writeObj(model, path, files));
  if (ext == ".ply") VKLOC_TRY_STATUS(writePly(model, path, files));
  if (ext == ".drc") VKLOC_TRY_STATUS(writeDrc(model, path, options, files));
  if (ext == ".gltf" || ext == ".glb") VKLOC_TRY_STATUS(GltfWriter(model, path, ext == ".glb", options).write(files));
  return files.commit();
}

}  // namespace vkloc
