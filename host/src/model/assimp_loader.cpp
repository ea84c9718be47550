// OBJ (+ MTL) and the other formats assimp reads, and PLY. OBJ files are checked before import,
// because assimp's parsers accept garbage (binary bytes as OBJ), size arrays from unchecked
// counts, and can trip its internal assertions on the result: the check walks the file and
// reports what is wrong with line numbers. PLY is read here, value by value, without assimp,
// whose PLY importer crashed and corrupted its heap on damaged files.
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/format.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "model/model_internal.hpp"
#include "vkloc/core/text.hpp"
#include "vkloc/model/cao.hpp"

// Debian's assimp is built with its internal assertions enabled, and their default handler
// aborts the process; the hook that replaces it (setAiAssertHandler) is not exported. The
// library calls this function through its PLT, so this definition takes its place: a failed
// assertion during an import throws, and loadWithAssimp reports the file as malformed.
namespace Assimp {
void aiAssertViolation(const char* expression, const char* file, int line) {
  throw std::runtime_error(fmt::format("assimp internal check '{}' failed ({}:{})", expression, file, line));
}
}  // namespace Assimp

namespace vkloc::model_detail {
namespace {

namespace fs = std::filesystem;

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

// `text` for quoting in a message: bytes outside printable ASCII become '?', at most
// `max_size` kept.
std::string quote(std::string_view text, size_t max_size = 60) {
  std::string out(text.substr(0, max_size));
  for (char& c : out) {
    if (c < 0x20 || c > 0x7e) c = '?';
  }
  return text.size() > max_size ? out + "..." : out;
}

// Calls fn(line_number, line) for every line of `text` (1-based numbers, no line break).
template <typename Fn>
bool forEachLine(std::string_view text, Fn&& fn) {
  size_t line_number = 0, pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    if (!fn(++line_number, text.substr(pos, end - pos))) return false;
    pos = end + 1;
  }
  return true;
}

// ---- OBJ ------------------------------------------------------------------------------------

// forEachLine for OBJ: like assimp's OBJ parser, a carriage return or form feed also ends a
// line (the pieces keep the line number of the '\n'-terminated line they are in), and a
// comment runs from a '#' that starts a token to the end of the line.
template <typename Fn>
void forEachObjLine(std::string_view text, Fn&& fn) {
  forEachLine(text, [&](size_t line_number, std::string_view line) {
    size_t start = 0;
    for (size_t i = 0; i <= line.size(); ++i) {
      if (i == line.size() || line[i] == '\r' || line[i] == '\f') {
        std::string_view piece = line.substr(start, i - start);
        for (size_t k = 0; k < piece.size(); ++k) {
          if (piece[k] == '#' && (k == 0 || isSpace(piece[k - 1]))) piece = piece.substr(0, k);
        }
        if (!fn(line_number, piece)) return false;
        start = i + 1;
      }
    }
    return true;
  });
}

// Parses a number as OBJ writes it (optional leading '+'); false if `text` is not one.
bool parseFloat(std::string_view text, float& value) {
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

// What an OBJ statement keyword declares: 0 a vertex, 1 a texture coordinate, 2 a normal, 3 a
// face, line or point, -1 something else, -2 none of these although assimp's parser would
// take it for one (it looks at the first one or two characters only).
int objStatement(std::string_view keyword) {
  if (keyword == "v") return 0;
  if (keyword == "vt") return 1;
  if (keyword == "vn") return 2;
  if (keyword == "f" || keyword == "fo" || keyword == "l" || keyword == "p") return 3;
  const bool lookalike = keyword.substr(0, 2) == "vt" || keyword.substr(0, 2) == "vn" || keyword[0] == 'f' ||
                         keyword[0] == 'l' || keyword[0] == 'p';
  return lookalike ? -2 : -1;
}

// Checks that an OBJ file is text, that vertex positions are finite numbers, that it has faces,
// and that every face, line and point references existing vertices, texture coordinates and
// normals (1-based, or negative = relative to the last one defined). Warns about missing
// material libraries.
Status checkObj(const std::string& path, const std::vector<uint8_t>& bytes, std::vector<std::string>& warnings) {
  for (size_t i = 0; i < bytes.size(); ++i) {
    const uint8_t b = bytes[i];
    if ((b < 0x20 && b != '\t' && b != '\n' && b != '\r' && b != '\v' && b != '\f' && b != 0x1a) || b == 0x7f) {
      return fileError(ErrorCode::kMalformedInput, path,
                       fmt::format("not a text OBJ file (byte 0x{:02x} at offset {})", b, i));
    }
  }
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  // Totals first: OBJ readers accept references to elements defined later in the file.
  uint64_t total[3] = {0, 0, 0};  // v, vt, vn
  forEachObjLine(text, [&](size_t, std::string_view line) {
    const auto t = text::splitFields(line);
    const int kind = t.empty() ? -1 : objStatement(t[0]);
    if (kind >= 0 && kind < 3) ++total[kind];
    return true;
  });
  if (total[0] > kMaxModelElements) {
    return fileError(ErrorCode::kUnsupported, path,
                     fmt::format("{} vertices, more than the {} allowed", total[0], kMaxModelElements));
  }
  static const char* const kKinds[3] = {"vertex", "texture coordinate", "normal"};
  static const char* const kPlurals[3] = {"vertices", "texture coordinates", "normals"};
  uint64_t seen[3] = {0, 0, 0};
  uint64_t element = 0, faces = 0, triangles = 0;
  Status status;
  const fs::path dir = fs::path(path).parent_path();
  forEachObjLine(text, [&](size_t line_number, std::string_view line) {
    const auto t = text::splitFields(line);
    const int statement = t.empty() ? -1 : objStatement(t[0]);
    if (statement == -2) {
      status = fileError(ErrorCode::kMalformedInput, path,
                         fmt::format("line {}: unknown statement '{}'", line_number, quote(t[0])));
      return false;
    }
    if (statement == 1 || statement == 2) {
      float v = 0;
      bool numbers = true;
      for (size_t k = 1; k < t.size(); ++k) numbers = numbers && parseFloat(t[k], v);
      const size_t count = t.size() - 1;
      if (!numbers || (statement == 1 ? count < 2 || count > 3 : count != 3)) {
        status = fileError(ErrorCode::kMalformedInput, path,
                           fmt::format("line {} is not '{}': '{}'", line_number,
                                       statement == 1 ? "vt u v [w]" : "vn x y z", quote(line)));
        return false;
      }
    }
    if (statement == 0) {
      float p[3];
      for (int k = 0; k < 3; ++k) {
        if (t.size() < 4 || !parseFloat(t[1 + k], p[k])) {
          status = fileError(
              ErrorCode::kMalformedInput, path,
              fmt::format("vertex {} (line {}) is not 'v x y z': '{}'", seen[0] + 1, line_number, quote(line)));
          return false;
        }
      }
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        status = fileError(ErrorCode::kMalformedInput, path,
                           fmt::format("vertex {} (line {}) has non-finite position ({}, {}, {})", seen[0] + 1,
                                       line_number, p[0], p[1], p[2]));
        return false;
      }
      ++seen[0];
    }
    if (statement == 1 || statement == 2) ++seen[statement];
    if (t.size() > 1 && t[0] == "mtllib") {
      const std::string rest(line.substr(t[1].data() - line.data()));
      std::error_code ec;
      bool found = fs::exists(dir / std::string(oneLine(rest)), ec);
      for (size_t i = 1; i < t.size() && !found; ++i) found = fs::exists(dir / std::string(t[i]), ec);
      if (!found) {
        warnings.push_back(oneLine(fmt::format(
            "{}: material library '{}' not found; its materials use the default colour", path, oneLine(rest))));
      }
    }
    if (statement != 3) return true;
    ++element;
    const char type = t[0][0];
    faces += type == 'f' ? 1 : 0;
    const char* what = type == 'f' ? "face" : type == 'l' ? "line" : "point";
    const size_t needed = type == 'f' ? 3 : type == 'l' ? 2 : 1;
    if (t.size() - 1 < needed) {
      status = fileError(ErrorCode::kMalformedInput, path,
                         fmt::format("{} {} (line {}) has {} vertices, fewer than {}", what, element, line_number,
                                     t.size() - 1, needed));
      return false;
    }
    if (type == 'f' && t.size() - 1 > kMaxPolygonVertices) {
      status = fileError(ErrorCode::kUnsupported, path,
                         fmt::format("face {} (line {}) has {} vertices, more than the {} allowed in one polygon",
                                     element, line_number, t.size() - 1, kMaxPolygonVertices));
      return false;
    }
    triangles += type == 'f' ? t.size() - 3 : 0;
    if (triangles > kMaxModelElements) {
      status = fileError(ErrorCode::kUnsupported, path,
                         fmt::format("more than {} triangles (at line {})", kMaxModelElements, line_number));
      return false;
    }
    for (size_t i = 1; i < t.size(); ++i) {
      std::string_view ref = t[i];
      for (int kind = 0; kind < 3 && !ref.empty(); ++kind) {
        const size_t slash = ref.find('/');
        const std::string_view field = ref.substr(0, slash);
        ref = slash == std::string_view::npos ? std::string_view() : ref.substr(slash + 1);
        if (field.empty() && kind > 0) continue;
        int64_t index = 0;
        const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), index);
        if (ec != std::errc() || end != field.data() + field.size() || index == 0) {
          status = fileError(ErrorCode::kMalformedInput, path,
                             fmt::format("{} {} (line {}) has a malformed vertex reference '{}'", what, element,
                                         line_number, quote(t[i])));
          return false;
        }
        const int64_t resolved = index > 0 ? index : static_cast<int64_t>(seen[kind]) + index + 1;
        const uint64_t available = index > 0 ? total[kind] : seen[kind];
        if (resolved < 1 || static_cast<uint64_t>(resolved) > available) {
          status = fileError(ErrorCode::kMalformedInput, path,
                             fmt::format("{} {} (line {}) references {} {} but there are {} {}", what, element,
                                         line_number, kKinds[kind], index, available, kPlurals[kind]));
          return false;
        }
      }
    }
    return true;
  });
  if (status.ok() && faces == 0) {
    return fileError(ErrorCode::kMalformedInput, path, "mesh has no triangles (no 'f' lines)");
  }
  return status;
}

// ---- PLY ------------------------------------------------------------------------------------

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

// Parses a PLY header, then walks the body: every declared element must be present and
// numeric, vertex positions finite, and face indices below the vertex count.
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

// ---- assimp scene -> Model -------------------------------------------------------------------

class SceneConverter {
 public:
  SceneConverter(const std::string& path, const aiScene& scene, std::vector<std::string>& warnings)
      : path_(path), scene_(scene), warnings_(warnings), dir_(fs::path(path).parent_path()) {}

  Result<Model> convert() {
    for (unsigned i = 0; i < scene_.mNumMaterials; ++i) {
      model_.materials.push_back(convertMaterial(*scene_.mMaterials[i], i));
    }
    if (scene_.mRootNode) {
      VKLOC_TRY_STATUS(visit(*scene_.mRootNode, aiMatrix4x4(), 0));
    } else {
      for (unsigned i = 0; i < scene_.mNumMeshes; ++i) {
        VKLOC_TRY_STATUS(addMesh(i, aiMatrix4x4()));
      }
    }
    return std::move(model_);
  }

 private:
  Status visit(const aiNode& node, const aiMatrix4x4& parent, int depth) {
    if (depth > 256) {
      return fileError(ErrorCode::kMalformedInput, path_, "node hierarchy deeper than 256 levels");
    }
    const aiMatrix4x4 world = parent * node.mTransformation;
    for (unsigned i = 0; i < node.mNumMeshes; ++i) VKLOC_TRY_STATUS(addMesh(node.mMeshes[i], world));
    for (unsigned i = 0; i < node.mNumChildren; ++i) {
      if (node.mChildren[i]) VKLOC_TRY_STATUS(visit(*node.mChildren[i], world, depth + 1));
    }
    return Status::success();
  }

  Status addMesh(unsigned index, const aiMatrix4x4& T) {
    if (index >= scene_.mNumMeshes || !scene_.mMeshes[index]) {
      return fileError(ErrorCode::kMalformedInput, path_, fmt::format("bad mesh index {}", index));
    }
    const aiMesh& mesh = *scene_.mMeshes[index];
    Primitive prim;
    prim.material = static_cast<int>(mesh.mMaterialIndex);
    const unsigned n = mesh.mNumVertices;
    if (n > 0 && !mesh.mVertices) {
      return fileError(ErrorCode::kMalformedInput, path_, fmt::format("mesh {} has no positions", index));
    }
    prim.positions.resize(size_t{3} * n);
    for (unsigned v = 0; v < n; ++v) {
      const aiVector3D& source = mesh.mVertices[v];
      if (!std::isfinite(source.x) || !std::isfinite(source.y) || !std::isfinite(source.z)) {
        return fileError(ErrorCode::kMalformedInput, path_,
                         fmt::format("vertex {} has non-finite position ({}, {}, {})", vertex_count_ + v, source.x,
                                     source.y, source.z));
      }
      const aiVector3D p = T * source;
      prim.positions[3 * v] = p.x;
      prim.positions[3 * v + 1] = p.y;
      prim.positions[3 * v + 2] = p.z;
    }
    if (mesh.mTextureCoords[0]) {
      prim.uvs.resize(size_t{2} * n);
      for (unsigned v = 0; v < n; ++v) {
        prim.uvs[2 * v] = mesh.mTextureCoords[0][v].x;
        prim.uvs[2 * v + 1] = mesh.mTextureCoords[0][v].y;
      }
    }
    if (mesh.mColors[0]) {
      prim.colors.resize(size_t{4} * n);
      for (unsigned v = 0; v < n; ++v) {
        const aiColor4D& c = mesh.mColors[0][v];
        const float rgba[4] = {c.r, c.g, c.b, c.a};
        for (int k = 0; k < 4; ++k) {
          const float x = std::isfinite(rgba[k]) ? std::clamp(rgba[k], 0.0f, 1.0f) : 0.0f;
          prim.colors[4 * v + k] = static_cast<uint8_t>(std::lround(255.0f * x));
        }
      }
    }
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines left by triangulation
      prim.indices.insert(prim.indices.end(), face.mIndices, face.mIndices + 3);
    }
    // The scene's transform may mirror; keep triangles counter-clockwise.
    if (T.Determinant() < 0) {
      for (size_t i = 0; i + 2 < prim.indices.size(); i += 3) {
        std::swap(prim.indices[i + 1], prim.indices[i + 2]);
      }
    }
    vertex_count_ += n;
    joinIdenticalVertices(prim);
    return appendPrimitive(model_, prim, path_, fmt::format("mesh {} ('{}')", index, mesh.mName.C_Str()));
  }

  Material convertMaterial(const aiMaterial& source, unsigned index) {
    Material m;
    aiString name;
    m.name = source.Get(AI_MATKEY_NAME, name) == AI_SUCCESS ? name.C_Str() : fmt::format("material{}", index);
    aiColor4D color;
    float opacity = 1.0f;
    if (source.Get(AI_MATKEY_BASE_COLOR, color) == AI_SUCCESS) {
      m.base_color = {color.r, color.g, color.b, color.a};
    } else if (source.Get(AI_MATKEY_COLOR_DIFFUSE, color) == AI_SUCCESS) {
      if (source.Get(AI_MATKEY_OPACITY, opacity) == AI_SUCCESS) color.a = opacity;
      m.base_color = {color.r, color.g, color.b, color.a};
    }
    for (float& c : m.base_color) c = std::isfinite(c) ? std::clamp(c, 0.0f, 1.0f) : 1.0f;
    aiString file;
    for (aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
      if (source.GetTextureCount(type) > 0 && source.GetTexture(type, 0, &file) == AI_SUCCESS) {
        m.texture = texture(file.C_Str(), m.name);
        break;
      }
    }
    return m;
  }

  // Index of the texture for `reference` (an embedded "*N" name or a file path), loading it on
  // first use; -1 with a warning when it is missing or cannot be decoded.
  int texture(const std::string& reference, const std::string& material) {
    const auto cached = cache_.find(reference);
    if (cached != cache_.end()) return cached->second;
    int& slot = cache_[reference];
    slot = -1;
    Texture tex;
    std::string error;
    const std::string context = fmt::format("{}: material '{}': texture '{}'", path_, material, reference);
    if (const aiTexture* embedded = scene_.GetEmbeddedTexture(reference.c_str())) {
      tex.name = "embedded " + reference;
      if (!decodeEmbedded(*embedded, tex, error)) {
        warnings_.push_back(oneLine(context + " cannot be decoded (" + error + "); using the base colour"));
        return -1;
      }
    } else if (!reference.empty() && reference[0] == '*') {
      warnings_.push_back(oneLine(context + " names a missing embedded texture; using the base colour"));
      return -1;
    } else {
      std::string relative = reference;
      std::replace(relative.begin(), relative.end(), '\\', '/');
      std::error_code ec;
      fs::path file = dir_ / relative;
      if (!fs::is_regular_file(file, ec)) file = dir_ / fs::path(relative).filename();
      if (!fs::is_regular_file(file, ec)) {
        warnings_.push_back(oneLine(
            fmt::format("{} not found (looked for {}); using the base colour", context, (dir_ / relative).string())));
        return -1;
      }
      tex.name = file.string();
      auto bytes = readFileBytes(file.string());
      if (!bytes.ok() || !decodeTexture(bytes->data(), bytes->size(), tex, error)) {
        warnings_.push_back(oneLine(context + " cannot be read (" + (bytes.ok() ? error : bytes.error().message) +
                                    "); using the base colour"));
        return -1;
      }
    }
    model_.textures.push_back(std::move(tex));
    slot = static_cast<int>(model_.textures.size()) - 1;
    return slot;
  }

  static bool decodeEmbedded(const aiTexture& source, Texture& tex, std::string& error) {
    if (!source.pcData) {
      error = "no data";
      return false;
    }
    if (source.mHeight == 0) {  // compressed file bytes (PNG, JPEG, ...)
      return decodeTexture(reinterpret_cast<const uint8_t*>(source.pcData), source.mWidth, tex, error);
    }
    if (source.mWidth > 32768 || source.mHeight > 32768) {
      error = fmt::format("{}x{} texels", source.mWidth, source.mHeight);
      return false;
    }
    tex.width = static_cast<int>(source.mWidth);
    tex.height = static_cast<int>(source.mHeight);
    const size_t count = size_t{source.mWidth} * source.mHeight;
    tex.rgba.resize(4 * count);
    for (size_t i = 0; i < count; ++i) {
      const aiTexel& t = source.pcData[i];
      tex.rgba[4 * i] = t.r;
      tex.rgba[4 * i + 1] = t.g;
      tex.rgba[4 * i + 2] = t.b;
      tex.rgba[4 * i + 3] = t.a;
    }
    return true;
  }

  const std::string& path_;
  const aiScene& scene_;
  std::vector<std::string>& warnings_;
  fs::path dir_;
  Model model_;
  size_t vertex_count_ = 0;  // vertices converted so far, for messages
  std::map<std::string, int> cache_;
};

// Refuses polygons of more than kMaxPolygonVertices corners in an imported, untriangulated scene.
Status checkPolygonSizes(const std::string& path, const aiScene& scene) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    for (unsigned f = 0; mesh && mesh->mFaces && f < mesh->mNumFaces; ++f) {
      if (mesh->mFaces[f].mNumIndices > kMaxPolygonVertices) {
        return fileError(ErrorCode::kUnsupported, path,
                         fmt::format("mesh {} face {} has {} vertices, more than the {} allowed in one polygon", m, f,
                                     mesh->mFaces[f].mNumIndices, kMaxPolygonVertices));
      }
    }
  }
  return Status::success();
}

}  // namespace

bool assimpReadsExtension(const std::string& ext) {
  Assimp::Importer importer;
  return importer.IsExtensionSupported(ext);
}

Result<Model> loadWithAssimp(const std::string& path, const std::string& ext, std::vector<std::string>& warnings) {
  if (ext == ".obj") {
    auto bytes = readFileBytes(path);
    if (!bytes.ok()) return bytes.error();
    VKLOC_TRY_STATUS(checkObj(path, *bytes, warnings));
  } else if (ext == ".ply") {
    auto bytes = readFileBytes(path);
    if (!bytes.ok()) return bytes.error();
    return loadPly(path, *bytes);
  }
  // No logger is created, so assimp logs to its silent default logger. Triangulate polygons,
  // drop points and lines (addMesh merges duplicate vertices exactly), and flip v so that (0, 0)
  // is the top-left of the image (assimp keeps OBJ's bottom-left origin and converts glTF's to it).
  // ValidateDataStructure runs first and rejects out-of-range indices before the other steps.
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Polygons are counted before triangulation, whose ear clipping is quadratic in their size.
  const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_FlipUVs;
  const aiScene* scene = nullptr;
  std::string error;
  try {
    scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
    if (scene) VKLOC_TRY_STATUS(checkPolygonSizes(path, *scene));
    if (scene) scene = importer.ApplyPostProcessing(flags);
    if (!scene) error = importer.GetErrorString();
  } catch (const std::exception& e) {
    error = e.what();
  } catch (...) {
    error = "unknown error";
  }
  if (!scene) {
    if (error.find("o meshes") != std::string::npos || error.find("no faces") != std::string::npos) {
      return fileError(ErrorCode::kMalformedInput, path, "mesh has no triangles");
    }
    return fileError(ErrorCode::kMalformedInput, path,
                     "cannot import: " + (error.empty() ? std::string("unknown error") : quote(error, 300)));
  }
  return SceneConverter(path, *scene, warnings).convert();
}

}  // namespace vkloc::model_detail
