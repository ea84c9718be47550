// PLY models (ASCII and binary), read value by value without assimp, whose PLY importer crashed
// and corrupted its heap on damaged files (fuzz findings). Every count, index and value is
// checked before it is used; polygons are triangulated by triangulatePolygon (cao.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include "model/model_internal.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/model/cao.hpp"

namespace vkloc::model_detail {
namespace {

enum class PlyType { kInvalid, kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

PlyType plyType(std::string_view t) {
  if (t == "char" || t == "int8") return PlyType::kInt8;
  if (t == "uchar" || t == "uint8") return PlyType::kUint8;
  if (t == "short" || t == "int16") return PlyType::kInt16;
  if (t == "ushort" || t == "uint16") return PlyType::kUint16;
  if (t == "int" || t == "int32") return PlyType::kInt32;
  if (t == "uint" || t == "uint32") return PlyType::kUint32;
  if (t == "float" || t == "float32") return PlyType::kFloat32;
  if (t == "double" || t == "float64") return PlyType::kFloat64;
  return PlyType::kInvalid;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kInvalid;        // of the value, or of a list's entries
  PlyType count_type = PlyType::kInvalid;  // of a list's length; kInvalid for scalars
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

// Reads the values of a PLY body: binary of either byte order, or ASCII with one element
// instance per line.
class PlyReader {
 public:
  PlyReader(std::string_view data, const std::string& format)
      : data_(data), ascii_(format == "ascii"), big_endian_(format == "binary_big_endian") {}

  // Starts the next element instance: in ASCII files, the next line. False at the end of the
  // data or at a blank line.
  bool beginInstance() {
    if (!ascii_) return true;
    pos_ = line_end_ == std::string_view::npos ? 0 : line_end_ + 1;
    if (pos_ >= data_.size()) return false;
    line_end_ = std::min(data_.find('\n', pos_), data_.size());
    return data_.substr(pos_, line_end_ - pos_).find_first_not_of(" \t\r") != std::string_view::npos;
  }

  // The next value of the current instance; false at its end or at a token that is not a number.
  bool next(PlyType type, double& value) {
    if (ascii_) {
      while (pos_ < line_end_ && isSpace(data_[pos_])) ++pos_;
      size_t end = pos_;
      while (end < line_end_ && !isSpace(data_[end])) ++end;
      std::string_view token = data_.substr(pos_, end - pos_);
      pos_ = end;
      if (!token.empty() && token[0] == '+') token.remove_prefix(1);
      const auto [stop, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
      return !token.empty() && ec == std::errc() && stop == token.data() + token.size();
    }
    static const int kSizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    const size_t size = kSizes[static_cast<int>(type)];
    if (size == 0 || data_.size() - pos_ < size) return false;
    uint8_t b[8];
    std::memcpy(b, data_.data() + pos_, size);
    pos_ += size;
    if (big_endian_) std::reverse(b, b + size);
    const auto as = [&b](auto v) {
      std::memcpy(&v, b, sizeof(v));
      return static_cast<double>(v);
    };
    switch (type) {
      case PlyType::kInt8:
        value = as(int8_t{});
        break;
      case PlyType::kUint8:
        value = as(uint8_t{});
        break;
      case PlyType::kInt16:
        value = as(int16_t{});
        break;
      case PlyType::kUint16:
        value = as(uint16_t{});
        break;
      case PlyType::kInt32:
        value = as(int32_t{});
        break;
      case PlyType::kUint32:
        value = as(uint32_t{});
        break;
      case PlyType::kFloat32:
        value = as(float{});
        break;
      default:
        value = as(double{});
        break;
    }
    return true;
  }

 private:
  std::string_view data_;
  size_t pos_ = 0;
  size_t line_end_ = std::string_view::npos;  // of the current ASCII line
  bool ascii_, big_endian_;
};

// True if `text` has only printable ASCII, tabs and line breaks ("\n" or "\r\n"); otherwise
// `offset` is the first other byte. Assimp's PLY reader treats other control bytes
// inconsistently, so they are refused.
bool plainText(std::string_view text, size_t& offset) {
  for (offset = 0; offset < text.size(); ++offset) {
    const unsigned char c = static_cast<unsigned char>(text[offset]);
    const bool crlf = c == '\r' && offset + 1 < text.size() && text[offset + 1] == '\n';
    if ((c < 0x20 && c != '\t' && c != '\n' && !crlf) || c >= 0x7f) return false;
  }
  return true;
}

// The value of a colour channel of `type` as 0..1: integers over their type's largest value.
double plyColorScale(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
      return 127.0;
    case PlyType::kUint8:
      return 255.0;
    case PlyType::kInt16:
      return 32767.0;
    case PlyType::kUint16:
      return 65535.0;
    case PlyType::kInt32:
      return 2147483647.0;
    case PlyType::kUint32:
      return 4294967295.0;
    default:
      return 1.0;
  }
}

// Reads a PLY model (ASCII or binary; positions, texture coordinates s/t, u/v, texture_u/v,
// vertex colours, polygon faces), checking every value first: assimp's PLY importer crashes or
// corrupts its heap on damaged files (fuzz findings), so it is not used for PLY.
}  // namespace

Result<Model> loadPly(const std::string& path, const std::vector<uint8_t>& bytes) {
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  if (text.substr(0, 4) != "ply\n" && text.substr(0, 5) != "ply\r\n") {
    return fileError(ErrorCode::kMalformedInput, path, "not a PLY file (no 'ply' magic line)");
  }
  const size_t header_end = text.find("end_header");
  size_t bad_byte = 0;
  if (header_end != std::string_view::npos && !plainText(text.substr(0, header_end), bad_byte)) {
    return fileError(ErrorCode::kMalformedInput, path,
                     fmt::format("PLY header has a non-text byte at offset {}", bad_byte));
  }
  std::vector<PlyElement> elements;
  std::string format;
  size_t data_offset = 0;
  Status status;
  forEachLine(text, [&](size_t line_number, std::string_view line) {
    const auto t = text::splitFields(line);
    const auto bad = [&](const std::string& what) {
      status = fileError(ErrorCode::kMalformedInput, path, fmt::format("PLY header line {}: {}", line_number, what));
      return false;
    };
    if (line_number == 1 || t.empty() || t[0] == "comment" || t[0] == "obj_info") return true;
    if (t[0] == "end_header") {
      data_offset = static_cast<size_t>(line.data() + line.size() - text.data()) + 1;
      return false;
    }
    if (t[0] == "format") {
      if (t.size() < 2 || (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian")) {
        return bad("unknown format '" + quote(line) + "'");
      }
      format = std::string(t[1]);
      return true;
    }
    if (t[0] == "element") {
      PlyElement e;
      if (t.size() != 3) return bad("expected 'element <name> <count>'");
      e.name = std::string(t[1]);
      // Element names are words (assimp, which read PLY before, took "element 4294967295face 4"
      // for a count and allocated 96 GiB: a fuzz finding).
      if (!(std::isalpha(static_cast<unsigned char>(e.name[0])) || e.name[0] == '_')) {
        return bad("element name '" + quote(t[1]) + "' does not start with a letter");
      }
      const auto [end, ec] = std::from_chars(t[2].data(), t[2].data() + t[2].size(), e.count);
      if (ec != std::errc() || end != t[2].data() + t[2].size()) {
        return bad("element count '" + quote(t[2]) + "' is not a number");
      }
      elements.push_back(e);
      return true;
    }
    if (t[0] == "property") {
      if (elements.empty()) return bad("property before any element");
      PlyProperty p;
      if (t.size() == 5 && t[1] == "list") {
        p.count_type = plyType(t[2]);
        p.type = plyType(t[3]);
        if (p.count_type == PlyType::kInvalid || p.type == PlyType::kInvalid) {
          return bad("unknown list type");
        }
      } else if (t.size() == 3) {
        p.type = plyType(t[1]);
        if (p.type == PlyType::kInvalid) return bad("unknown type '" + quote(t[1]) + "'");
      } else {
        return bad("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      p.name = std::string(t.back());
      elements.back().properties.push_back(p);
      return true;
    }
    return bad("unexpected '" + quote(line) + "'");
  });
  VKLOC_TRY_STATUS(status);
  if (data_offset == 0) {
    return fileError(ErrorCode::kMalformedInput, path, "truncated PLY header (no end_header)");
  }
  if (format.empty()) return fileError(ErrorCode::kMalformedInput, path, "PLY header has no format");
  const auto vertex =
      std::find_if(elements.begin(), elements.end(), [](const PlyElement& e) { return e.name == "vertex"; });
  int position[3] = {-1, -1, -1};
  for (size_t i = 0; vertex != elements.end() && i < vertex->properties.size(); ++i) {
    const PlyProperty& p = vertex->properties[i];
    for (int k = 0; k < 3; ++k) {
      if (p.name == std::string(1, static_cast<char>('x' + k)) && p.count_type == PlyType::kInvalid) {
        position[k] = static_cast<int>(i);
      }
    }
  }
  if (position[0] < 0 || position[1] < 0 || position[2] < 0) {
    return fileError(ErrorCode::kMalformedInput, path, "PLY has no 'vertex' element with x, y and z properties");
  }
  // Texture coordinates (first of the usual names) and colour channels of the vertex element.
  const auto scalarNamed = [&](std::initializer_list<std::string_view> names) {
    for (const std::string_view name : names) {
      for (size_t i = 0; i < vertex->properties.size(); ++i) {
        const PlyProperty& p = vertex->properties[i];
        if (p.name == name && p.count_type == PlyType::kInvalid) return static_cast<int>(i);
      }
    }
    return -1;
  };
  const int uv_index[2] = {scalarNamed({"s", "u", "texture_u", "tx"}), scalarNamed({"t", "v", "texture_v", "ty"})};
  const bool has_uv = uv_index[0] >= 0 && uv_index[1] >= 0;
  const int color_index[4] = {scalarNamed({"red", "diffuse_red", "r"}), scalarNamed({"green", "diffuse_green", "g"}),
                              scalarNamed({"blue", "diffuse_blue", "b"}), scalarNamed({"alpha", "diffuse_alpha", "a"})};
  const bool has_color = color_index[0] >= 0 || color_index[1] >= 0 || color_index[2] >= 0;
  Primitive prim;
  std::vector<uint32_t> corners;  // of the polygons, each preceded by its corner count
  std::string counts;
  for (const PlyElement& e : elements) {
    counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", e.count, e.name);
  }
  const std::string_view body = text.substr(std::min(data_offset, text.size()));
  if (format == "ascii" && !plainText(body, bad_byte)) {
    return fileError(ErrorCode::kMalformedInput, path,
                     fmt::format("ASCII PLY has a non-text byte at offset {}", data_offset + bad_byte));
  }
  PlyReader reader(body, format);
  for (const PlyElement& e : elements) {
    const bool is_vertex = &e == &*vertex;
    const bool is_face = e.name == "face";
    // A binary element without properties holds no bytes, whatever its count claims (2^64 such
    // instances would be read from nothing): skipped. ASCII instances take a line each.
    if (format != "ascii" && e.properties.empty()) continue;
    for (uint64_t i = 0; i < e.count; ++i) {
      if (!reader.beginInstance()) {
        return fileError(
            ErrorCode::kMalformedInput, path,
            fmt::format("truncated {} PLY: header declares {} but {} {} is missing (end of data or blank line)", format,
                        counts, e.name, i));
      }
      if ((is_vertex || is_face) && i >= model_detail::kMaxModelElements) {
        return fileError(
            ErrorCode::kUnsupported, path,
            fmt::format("{} {} elements, more than the {} allowed", e.count, e.name, model_detail::kMaxModelElements));
      }
      double xyz[3] = {0, 0, 0};
      double uv[2] = {0, 0};
      double rgba[4] = {0, 0, 0, 1};
      for (size_t j = 0; j < e.properties.size(); ++j) {
        const PlyProperty& p = e.properties[j];
        const auto truncated_property = [&]() {
          return fileError(
              ErrorCode::kMalformedInput, path,
              fmt::format(
                  "truncated or malformed {} PLY: {} {} property '{}' is missing or not a number (header declares {})",
                  format, e.name, i, p.name, counts));
        };
        double value = 0;
        if (p.count_type == PlyType::kInvalid) {
          if (!reader.next(p.type, value)) return truncated_property();
          if (is_vertex) {
            for (int k = 0; k < 3; ++k) {
              if (static_cast<int>(j) == position[k]) xyz[k] = value;
            }
            for (int k = 0; k < 2; ++k) {
              if (static_cast<int>(j) == uv_index[k]) uv[k] = value;
            }
            for (int k = 0; k < 4; ++k) {
              if (static_cast<int>(j) == color_index[k]) rgba[k] = value / plyColorScale(p.type);
            }
          }
          continue;
        }
        double length = 0;
        if (!reader.next(p.count_type, length)) return truncated_property();
        if (length < 0 || length != std::floor(length)) {
          return fileError(ErrorCode::kMalformedInput, path,
                           fmt::format("{} {} has a list of {} values", e.name, i, length));
        }
        const bool indices = is_face && (p.name == "vertex_indices" || p.name == "vertex_index");
        // A face without corners is malformed (assimp, which read PLY before, crashed on it).
        if (indices && length == 0) {
          return fileError(ErrorCode::kMalformedInput, path, fmt::format("face {} has no vertices", i));
        }
        if (indices && length > static_cast<double>(kMaxPolygonVertices)) {
          return fileError(ErrorCode::kUnsupported, path,
                           fmt::format("face {} has {} vertices, more than the {} allowed in one polygon", i, length,
                                       kMaxPolygonVertices));
        }
        if (indices) corners.push_back(static_cast<uint32_t>(length));
        for (double k = 0; k < length; ++k) {
          if (!reader.next(p.type, value)) return truncated_property();
          if (indices && !(value >= 0 && value < static_cast<double>(vertex->count) && value == std::floor(value))) {
            return fileError(
                ErrorCode::kMalformedInput, path,
                fmt::format("face {} references vertex {} but there are {} vertices", i, value, vertex->count));
          }
          if (indices) corners.push_back(static_cast<uint32_t>(value));
        }
      }
      if (is_vertex && !(std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2]))) {
        return fileError(ErrorCode::kMalformedInput, path,
                         fmt::format("vertex {} has non-finite position ({}, {}, {})", i, static_cast<float>(xyz[0]),
                                     static_cast<float>(xyz[1]), static_cast<float>(xyz[2])));
      }
      if (is_vertex) {
        for (int k = 0; k < 3; ++k) prim.positions.push_back(static_cast<float>(xyz[k]));
        if (has_uv) {
          // PLY's v grows upwards; vkloc's (0, 0) is the image's top-left.
          prim.uvs.push_back(static_cast<float>(uv[0]));
          prim.uvs.push_back(static_cast<float>(1.0 - uv[1]));
        }
        if (has_color) {
          for (int k = 0; k < 4; ++k) {
            const double x = std::isfinite(rgba[k]) ? std::clamp(rgba[k], 0.0, 1.0) : 0.0;
            prim.colors.push_back(static_cast<uint8_t>(std::lround(255.0 * x)));
          }
        }
      }
    }
  }
  // Polygons become triangles (ear clipping keeps their orientation); points and lines are
  // dropped, as they have no area to render.
  std::vector<Eigen::Vector3d> loop;
  for (size_t at = 0; at < corners.size(); at += 1 + corners[at]) {
    const uint32_t n = corners[at];
    const uint32_t* face = &corners[at + 1];
    if (n == 3) {
      prim.indices.insert(prim.indices.end(), face, face + 3);
    } else if (n > 3) {
      loop.clear();
      for (uint32_t k = 0; k < n; ++k) {
        const float* q = &prim.positions[3 * size_t{face[k]}];
        loop.emplace_back(q[0], q[1], q[2]);
      }
      for (const uint32_t local : triangulatePolygon(loop)) prim.indices.push_back(face[local]);
    }
  }
  if (prim.indices.empty()) return fileError(ErrorCode::kMalformedInput, path, "mesh has no triangles");
  joinIdenticalVertices(prim);
  Model model;
  // Vertex colours are the appearance: the base colour that multiplies them is white; without
  // them, the default grey.
  model.materials.push_back(Material{"default"});
  if (has_color) model.materials.back().base_color = {1.0f, 1.0f, 1.0f, 1.0f};
  VKLOC_TRY_STATUS(appendPrimitive(model, prim, path, "faces"));
  return model;
}

}  // namespace vkloc::model_detail
