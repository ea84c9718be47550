// glTF 2.0 (.gltf / .glb) loading. glTF is parsed here rather than by assimp: Debian's assimp
// cannot decode KHR_draco_mesh_compression (decoded by draco_loader.cpp's helpers), one parser
// keeps Draco and plain primitives consistent in mixed files, and every offset and count read from the file is
// checked against the bytes that back it before anything is allocated or read.
#include <draco/compression/decode.h>
#include <draco/mesh/mesh.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>

#include "model/model_internal.hpp"

namespace vkloc::model_detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---- glTF -----------------------------------------------------------------------------------

// A failure while reading a glTF file; thrown inside GltfReader and turned into an Error at
// its entry point.
struct GltfFailure {
  ErrorCode code;
  std::string message;  ///< Without the file path, unless `has_path`.
  bool has_path = false;
};

[[noreturn]] void fail(const std::string& message, ErrorCode code = ErrorCode::kMalformedInput) {
  throw GltfFailure{code, message};
}

struct Span {
  const uint8_t* data = nullptr;
  size_t size = 0;
};

// Column-major 4x4, as glTF stores node matrices.
using Mat4 = std::array<double, 16>;
constexpr Mat4 kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

Mat4 multiply(const Mat4& a, const Mat4& b) {
  Mat4 c{};
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[col * 4 + k];
      c[col * 4 + row] = s;
    }
  }
  return c;
}

double determinant3(const Mat4& m) {
  return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) + m[8] * (m[1] * m[6] - m[5] * m[2]);
}

std::string percentDecode(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// Decodes the payload of a base64 data URI (standard or URL-safe alphabet); false on other
// characters.
bool decodeBase64(std::string_view text, std::vector<uint8_t>& out) {
  const auto sextet = [](char ch) {
    if (ch >= 'A' && ch <= 'Z') return ch - 'A';
    if (ch >= 'a' && ch <= 'z') return ch - 'a' + 26;
    if (ch >= '0' && ch <= '9') return ch - '0' + 52;
    if (ch == '+' || ch == '-') return 62;
    if (ch == '/' || ch == '_') return 63;
    return -1;
  };
  out.clear();
  out.reserve(text.size() / 4 * 3);
  uint32_t acc = 0;
  int bits = 0;
  for (char ch : text) {
    if (ch == '=') break;
    const int v = sextet(ch);
    if (v < 0) return false;
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<uint8_t>((acc >> bits) & 0xff));
    }
  }
  return true;
}

uint32_t readLe32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}

class GltfReader {
 public:
  GltfReader(const std::string& path, const std::vector<uint8_t>& file, std::vector<std::string>& warnings)
      : path_(path), dir_(fs::path(path).parent_path()), warnings_(warnings), file_(file) {}

  Model read() {
    parseContainer();
    checkAsset();
    loadBuffers();
    const json& materials = array(root_, "materials");
    for (size_t i = 0; i < materials.size(); ++i) model_.materials.push_back(material(materials[i], i));
    mesh_cache_.resize(array(root_, "meshes").size());
    visitScene();
    return std::move(model_);
  }

 private:
  // ---- container and JSON helpers ----

  void parseContainer() {
    size_t start = 0;
    std::string_view text;
    if (file_.size() >= 4 && std::memcmp(file_.data(), "glTF", 4) == 0) {
      if (file_.size() < 12) fail(fmt::format("truncated GLB: {} bytes", file_.size()));
      const uint32_t version = readLe32(&file_[4]), length = readLe32(&file_[8]);
      if (version != 2) fail(fmt::format("GLB version {} is not supported (need 2)", version), ErrorCode::kUnsupported);
      if (length > file_.size()) {
        fail(fmt::format("truncated GLB: header says {} bytes, file has {}", length, file_.size()));
      }
      if (length < 20) fail(fmt::format("GLB header says {} bytes, too short for a JSON chunk", length));
      const uint32_t json_length = readLe32(&file_[12]);
      if (readLe32(&file_[16]) != 0x4E4F534Au) fail("GLB's first chunk is not JSON");
      if (json_length > length - 20) {
        fail(fmt::format("truncated GLB: JSON chunk of {} bytes runs past the {}-byte file", json_length, length));
      }
      text = std::string_view(reinterpret_cast<const char*>(&file_[20]), json_length);
      const size_t bin = 20 + size_t{json_length};
      if (length - bin >= 8 && readLe32(&file_[bin + 4]) == 0x004E4942u) {
        const uint32_t bin_length = readLe32(&file_[bin]);
        if (bin_length > length - bin - 8) {
          fail(fmt::format("truncated GLB: BIN chunk of {} bytes runs past the {}-byte file", bin_length, length));
        }
        bin_ = Span{&file_[bin + 8], bin_length};
        has_bin_ = true;
      }
    } else {
      if (file_.size() >= 3 && file_[0] == 0xEF && file_[1] == 0xBB && file_[2] == 0xBF) start = 3;
      while (start < file_.size() && std::isspace(file_[start])) ++start;
      if (start >= file_.size() || file_[start] != '{') {
        fail("not a glTF file (neither JSON nor the binary 'glTF' magic)");
      }
      text = std::string_view(reinterpret_cast<const char*>(&file_[start]), file_.size() - start);
    }
    try {
      root_ = json::parse(text.begin(), text.end());
    } catch (const json::parse_error& e) {
      fail(fmt::format("invalid glTF JSON at byte {}", e.byte));
    }
    if (!root_.is_object()) fail("glTF JSON is not an object");
  }

  void checkAsset() {
    const json* asset = find(root_, "asset");
    const json* version = asset ? find(*asset, "version") : nullptr;
    if (!version || !version->is_string()) fail("glTF has no asset.version");
    const std::string v = version->get<std::string>();
    if (v.rfind("2.", 0) != 0) fail("glTF version '" + v + "' is not supported (need 2.x)", ErrorCode::kUnsupported);
    static const char* const kHandled[] = {"KHR_draco_mesh_compression", "KHR_mesh_quantization", "KHR_materials_unlit",
                                           "KHR_texture_transform"};
    for (const json& name : array(root_, "extensionsUsed")) {
      if (name == "KHR_texture_transform") {
        warnings_.push_back(path_ + ": KHR_texture_transform is ignored; textures may be misplaced");
      }
    }
    for (const json& name : array(root_, "extensionsRequired")) {
      if (!name.is_string()) fail("extensionsRequired holds a non-string");
      if (std::find(std::begin(kHandled), std::end(kHandled), name.get<std::string>()) == std::end(kHandled)) {
        fail("requires glTF extension " + name.get<std::string>() + ", which vkloc does not support",
             ErrorCode::kUnsupported);
      }
    }
  }

  static const json* find(const json& object, const char* key) {
    if (!object.is_object()) return nullptr;
    const auto it = object.find(key);
    return it == object.end() ? nullptr : &*it;
  }

  // The array member `key` of `object`, or an empty array when absent.
  static const json& array(const json& object, const char* key) {
    static const json kEmpty = json::array();
    const json* value = find(object, key);
    if (!value) return kEmpty;
    if (!value->is_array()) fail(fmt::format("'{}' is not an array", key));
    return *value;
  }

  // A non-negative integer member; `fallback` when absent (or an error if no fallback).
  static uint64_t number(const json& object, const char* key, std::optional<uint64_t> fallback,
                         const std::string& context) {
    const json* value = find(object, key);
    if (!value) {
      if (!fallback) fail(fmt::format("{} has no '{}'", context, key));
      return *fallback;
    }
    if (!value->is_number_unsigned()) fail(fmt::format("{}: '{}' is not a non-negative integer", context, key));
    return value->get<uint64_t>();
  }

  static size_t index(const json& object, const char* key, size_t count, const std::string& context) {
    const uint64_t i = number(object, key, std::nullopt, context);
    if (i >= count) fail(fmt::format("{}: {} {} is out of range (there are {})", context, key, i, count));
    return static_cast<size_t>(i);
  }

  static const json& element(const json& root, const char* key, size_t i) {
    const json& a = array(root, key);
    if (i >= a.size()) fail(fmt::format("{} {} does not exist (there are {})", key, i, a.size()));
    if (!a[i].is_object()) fail(fmt::format("{} {} is not an object", key, i));
    return a[i];
  }

  // ---- buffers and accessors ----

  // Loads the bytes of a data URI or of a file relative to the model (its path goes to
  // `file_name`); nullopt if the file is missing.
  std::optional<std::vector<uint8_t>> loadUri(const std::string& uri, const std::string& context,
                                              std::string* file_name) {
    if (uri.rfind("data:", 0) == 0) {
      const size_t comma = uri.find(',');
      if (comma == std::string::npos || uri.substr(0, comma).find(";base64") == std::string::npos) {
        fail(context + " has a data URI that is not base64");
      }
      std::vector<uint8_t> out;
      if (!decodeBase64(std::string_view(uri).substr(comma + 1), out)) fail(context + " has invalid base64 data");
      return out;
    }
    const fs::path file = dir_ / percentDecode(uri);
    if (file_name) *file_name = file.string();
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) return std::nullopt;
    auto bytes = readFileBytes(file.string());
    if (!bytes.ok()) fail(context + ": " + bytes.error().message, bytes.error().code);
    return std::move(bytes).value();
  }

  void loadBuffers() {
    const json& buffers = array(root_, "buffers");
    for (size_t i = 0; i < buffers.size(); ++i) {
      const std::string context = fmt::format("buffer {}", i);
      const uint64_t length = number(buffers[i], "byteLength", std::nullopt, context);
      const json* uri = find(buffers[i], "uri");
      if (!uri) {
        if (i != 0 || !has_bin_) fail(context + " has no uri and there is no GLB BIN chunk");
        if (length > bin_.size) {
          fail(fmt::format("{} says {} bytes but the GLB BIN chunk has {}", context, length, bin_.size));
        }
        buffers_.push_back(Span{bin_.data, static_cast<size_t>(length)});
        continue;
      }
      if (!uri->is_string()) fail(context + ": uri is not a string");
      std::string file_name;
      auto bytes = loadUri(uri->get<std::string>(), context, &file_name);
      if (!bytes) fail(fmt::format("{} file '{}' not found", context, file_name), ErrorCode::kNotFound);
      if (bytes->size() < length) {
        fail(fmt::format("{} says {} bytes but its data has {}", context, length, bytes->size()));
      }
      owned_.push_back(std::move(*bytes));
      buffers_.push_back(Span{owned_.back().data(), static_cast<size_t>(length)});
    }
  }

  struct View {
    Span bytes;
    uint64_t stride = 0;  // 0: tightly packed
  };

  View bufferView(size_t i) {
    const json& v = element(root_, "bufferViews", i);
    const std::string context = fmt::format("bufferView {}", i);
    const size_t buffer = index(v, "buffer", buffers_.size(), context);
    const uint64_t offset = number(v, "byteOffset", 0, context);
    const uint64_t length = number(v, "byteLength", std::nullopt, context);
    if (offset > buffers_[buffer].size || length > buffers_[buffer].size - offset) {
      fail(fmt::format("{} (offset {}, {} bytes) runs past the end of buffer {} ({} bytes)", context, offset, length,
                       buffer, buffers_[buffer].size));
    }
    return View{Span{buffers_[buffer].data + offset, static_cast<size_t>(length)}, number(v, "byteStride", 0, context)};
  }

  struct Accessor {
    const uint8_t* data = nullptr;
    size_t count = 0;
    size_t stride = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
  };

  static int componentSize(int type) {
    switch (type) {
      case 5120:
      case 5121:
        return 1;
      case 5122:
      case 5123:
        return 2;
      case 5125:
      case 5126:
        return 4;
      default:
        return 0;
    }
  }

  Accessor accessor(size_t i) {
    const json& a = element(root_, "accessors", i);
    const std::string context = fmt::format("accessor {}", i);
    Accessor out;
    out.count = static_cast<size_t>(std::min<uint64_t>(number(a, "count", std::nullopt, context), SIZE_MAX / 64));
    out.component_type =
        static_cast<int>(std::min<uint64_t>(number(a, "componentType", std::nullopt, context), 1 << 16));
    const json* normalized = find(a, "normalized");
    out.normalized = normalized && normalized->is_boolean() && normalized->get<bool>();
    const json* type = find(a, "type");
    const std::string t = type && type->is_string() ? type->get<std::string>() : "";
    out.components = t == "SCALAR" ? 1 : t == "VEC2" ? 2 : t == "VEC3" ? 3 : t == "VEC4" ? 4 : 0;
    const int size = componentSize(out.component_type);
    if (out.components == 0 || size == 0) {
      fail(fmt::format("{} has unsupported type '{}' / componentType {}", context, t, out.component_type));
    }
    if (find(a, "sparse")) fail(context + " is sparse, which vkloc does not support", ErrorCode::kUnsupported);
    if (!find(a, "bufferView")) fail(context + " has no bufferView", ErrorCode::kUnsupported);
    const View view = bufferView(index(a, "bufferView", array(root_, "bufferViews").size(), context));
    const uint64_t offset = number(a, "byteOffset", 0, context);
    const uint64_t element_size = uint64_t(size) * out.components;
    out.stride = static_cast<size_t>(view.stride ? view.stride : element_size);
    if (out.stride < element_size || out.stride > 255) fail(fmt::format("{} has byteStride {}", context, out.stride));
    if (out.count == 0 || offset > view.bytes.size || (out.count - 1) > (view.bytes.size - offset) / out.stride ||
        offset + (out.count - 1) * out.stride + element_size > view.bytes.size) {
      fail(fmt::format("{} ({} elements of {} bytes from offset {}) does not fit its {}-byte bufferView", context,
                       out.count, element_size, offset, view.bytes.size));
    }
    out.data = view.bytes.data + offset;
    return out;
  }

  // Values as floats (normalized integers mapped to 0..1 or -1..1 as glTF specifies).
  std::vector<float> floats(size_t i, int min_components, int max_components, const char* what) {
    const Accessor a = accessor(i);
    if (a.components < min_components || a.components > max_components) {
      fail(fmt::format("{} accessor {} has {} components", what, i, a.components));
    }
    std::vector<float> out(a.count * a.components);
    for (size_t e = 0; e < a.count; ++e) {
      const uint8_t* p = a.data + e * a.stride;
      for (int c = 0; c < a.components; ++c) {
        float v = 0;
        switch (a.component_type) {
          case 5126:
            std::memcpy(&v, p + 4 * c, 4);
            break;
          case 5120: {
            int8_t x;
            std::memcpy(&x, p + c, 1);
            v = a.normalized ? std::max(x / 127.0f, -1.0f) : x;
            break;
          }
          case 5121:
            v = a.normalized ? p[c] / 255.0f : p[c];
            break;
          case 5122: {
            int16_t x;
            std::memcpy(&x, p + 2 * c, 2);
            v = a.normalized ? std::max(x / 32767.0f, -1.0f) : x;
            break;
          }
          case 5123: {
            uint16_t x;
            std::memcpy(&x, p + 2 * c, 2);
            v = a.normalized ? x / 65535.0f : x;
            break;
          }
          case 5125: {
            uint32_t x;
            std::memcpy(&x, p + 4 * c, 4);
            v = static_cast<float>(x);
            break;
          }
        }
        out[e * a.components + c] = v;
      }
    }
    return out;
  }

  std::vector<uint32_t> indices(size_t i) {
    const Accessor a = accessor(i);
    if (a.components != 1 || (a.component_type != 5121 && a.component_type != 5123 && a.component_type != 5125)) {
      fail(fmt::format("index accessor {} is not scalar unsigned byte, short or int", i));
    }
    std::vector<uint32_t> out(a.count);
    for (size_t e = 0; e < a.count; ++e) {
      const uint8_t* p = a.data + e * a.stride;
      if (a.component_type == 5121) {
        out[e] = *p;
      } else if (a.component_type == 5123) {
        uint16_t x;
        std::memcpy(&x, p, 2);
        out[e] = x;
      } else {
        std::memcpy(&out[e], p, 4);
      }
    }
    return out;
  }

  // ---- materials and textures ----

  Material material(const json& m, size_t i) {
    Material out;
    const json* name = find(m, "name");
    out.name = name && name->is_string() ? name->get<std::string>() : fmt::format("material{}", i);
    out.base_color = {1.0f, 1.0f, 1.0f, 1.0f};
    const json* pbr = find(m, "pbrMetallicRoughness");
    if (!pbr) return out;
    if (const json* factor = find(*pbr, "baseColorFactor")) {
      if (!factor->is_array() || factor->size() != 4) {
        fail(fmt::format("material {}: baseColorFactor is not 4 numbers", i));
      }
      for (int k = 0; k < 4; ++k) {
        if (!(*factor)[k].is_number()) fail(fmt::format("material {}: baseColorFactor is not 4 numbers", i));
        const float c = (*factor)[k].get<float>();
        out.base_color[k] = std::isfinite(c) ? std::clamp(c, 0.0f, 1.0f) : 1.0f;
      }
    }
    if (const json* info = find(*pbr, "baseColorTexture")) {
      const std::string context = fmt::format("material {} ('{}')", i, out.name);
      out.texture = texture(index(*info, "index", array(root_, "textures").size(), context), out.name);
      texcoord_sets_.resize(i + 1, 0);
      texcoord_sets_[i] = static_cast<int>(std::min<uint64_t>(number(*info, "texCoord", 0, context), 8));
    }
    return out;
  }

  // Texture index for glTF texture `t`, loading its image once; -1 with a warning when the
  // image is missing or cannot be decoded.
  int texture(size_t t, const std::string& material) {
    const json& tex = element(root_, "textures", t);
    if (!find(tex, "source")) {
      warnings_.push_back(oneLine(fmt::format(
          "{}: material '{}': texture {} has no PNG/JPEG source; using the base colour", path_, material, t)));
      return -1;
    }
    const size_t image = index(tex, "source", array(root_, "images").size(), fmt::format("texture {}", t));
    const auto cached = image_cache_.find(image);
    if (cached != image_cache_.end()) return cached->second;
    int& slot = image_cache_[image];
    slot = -1;
    const json& img = element(root_, "images", image);
    const std::string context = fmt::format("{}: material '{}': image {}", path_, material, image);
    Texture out;
    std::vector<uint8_t> owned;
    Span bytes;
    if (const json* uri = find(img, "uri")) {
      if (!uri->is_string()) fail(fmt::format("image {}: uri is not a string", image));
      std::string file_name;
      auto loaded = loadUri(uri->get<std::string>(), fmt::format("image {}", image), &file_name);
      out.name = file_name.empty() ? fmt::format("image {} (data URI)", image) : file_name;
      if (!loaded) {
        warnings_.push_back(
            oneLine(fmt::format("{}: texture file '{}' not found; using the base colour", context, file_name)));
        return -1;
      }
      owned = std::move(*loaded);
      bytes = Span{owned.data(), owned.size()};
    } else if (find(img, "bufferView")) {
      bytes = bufferView(index(img, "bufferView", array(root_, "bufferViews").size(), fmt::format("image {}", image)))
                  .bytes;
      out.name = fmt::format("image {} (embedded)", image);
    } else {
      fail(fmt::format("image {} has neither uri nor bufferView", image));
    }
    std::string error;
    if (!decodeTexture(bytes.data, bytes.size, out, error)) {
      warnings_.push_back(
          oneLine(fmt::format("{}: '{}' cannot be decoded ({}); using the base colour", context, out.name, error)));
      return -1;
    }
    model_.textures.push_back(std::move(out));
    slot = static_cast<int>(model_.textures.size()) - 1;
    return slot;
  }

  // glTF's default material for primitives that name none: white, untextured.
  int defaultMaterial() {
    if (default_material_ < 0) {
      default_material_ = static_cast<int>(model_.materials.size());
      model_.materials.push_back(Material{"default", {1.0f, 1.0f, 1.0f, 1.0f}, -1});
    }
    return default_material_;
  }

  // ---- meshes and nodes ----

  Primitive primitive(const json& p, const std::string& context) {
    Primitive prim;
    const size_t materials = array(root_, "materials").size();
    prim.material =
        find(p, "material") ? static_cast<int>(index(p, "material", materials, context)) : defaultMaterial();
    const int set = prim.material < static_cast<int>(texcoord_sets_.size()) ? texcoord_sets_[prim.material] : 0;
    const std::string uv_name = fmt::format("TEXCOORD_{}", set);
    const json* attributes = find(p, "attributes");
    if (!attributes || !attributes->is_object()) fail(context + " has no attributes");
    const json* extensions = find(p, "extensions");
    const json* draco = extensions ? find(*extensions, "KHR_draco_mesh_compression") : nullptr;
    if (draco) {
      dracoPrimitive(*draco, uv_name, context, prim);
      return prim;
    }
    const size_t accessors = array(root_, "accessors").size();
    prim.positions = floats(index(*attributes, "POSITION", accessors, context), 3, 3, "POSITION");
    const size_t n = prim.positions.size() / 3;
    if (find(*attributes, uv_name.c_str())) {
      prim.uvs = floats(index(*attributes, uv_name.c_str(), accessors, context), 2, 2, "TEXCOORD");
      if (prim.uvs.size() != 2 * n) fail(context + ": TEXCOORD count differs from POSITION count");
    }
    if (find(*attributes, "COLOR_0")) {
      const size_t acc = index(*attributes, "COLOR_0", accessors, context);
      const std::vector<float> c = floats(acc, 3, 4, "COLOR_0");
      const size_t comps = c.size() / std::max<size_t>(n, 1);
      if (c.size() != comps * n) fail(context + ": COLOR_0 count differs from POSITION count");
      prim.colors.resize(4 * n, 255);
      for (size_t v = 0; v < n; ++v) {
        for (size_t k = 0; k < comps; ++k) prim.colors[4 * v + k] = toByte(255.0f * c[comps * v + k]);
      }
    }
    if (find(p, "indices")) {
      prim.indices = indices(index(p, "indices", accessors, context));
    } else {
      prim.indices.resize(n);
      for (size_t v = 0; v < n; ++v) prim.indices[v] = static_cast<uint32_t>(v);
    }
    return prim;
  }

  void dracoPrimitive(const json& ext, const std::string& uv_name, const std::string& context, Primitive& prim) {
    const View view =
        bufferView(index(ext, "bufferView", array(root_, "bufferViews").size(), context + " Draco extension"));
    std::string error;
    bool unsupported = false;
    const auto mesh = decodeDracoMesh(view.bytes.data, view.bytes.size, error, unsupported);
    if (!mesh) fail(context + ": " + error, unsupported ? ErrorCode::kUnsupported : ErrorCode::kMalformedInput);
    const json* ids = find(ext, "attributes");
    if (!ids || !ids->is_object()) fail(context + ": Draco extension has no attributes");
    const auto attribute = [&](const char* name) -> const draco::PointAttribute* {
      if (!find(*ids, name)) return nullptr;
      const uint64_t id = number(*ids, name, std::nullopt, context + " Draco attributes");
      const draco::PointAttribute* att =
          id <= UINT32_MAX ? mesh->GetAttributeByUniqueId(static_cast<uint32_t>(id)) : nullptr;
      if (!att) fail(fmt::format("{}: Draco attribute {} (id {}) is not in the stream", context, name, id));
      return att;
    };
    const draco::PointAttribute* position = attribute("POSITION");
    if (!position) fail(context + ": Draco extension has no POSITION");
    if (!model_detail::dracoPrimitive(*mesh, position, attribute(uv_name.c_str()), attribute("COLOR_0"), false, prim,
                                      error)) {
      fail(context + ": " + error);
    }
  }

  // The mesh's triangle primitives in the mesh frame, converted once and reused per instance.
  const std::vector<Primitive>& mesh(size_t m) {
    std::optional<std::vector<Primitive>>& cached = mesh_cache_[m];
    if (cached) return *cached;
    cached.emplace();
    const json& primitives = array(element(root_, "meshes", m), "primitives");
    for (size_t i = 0; i < primitives.size(); ++i) {
      const std::string context = fmt::format("mesh {} primitive {}", m, i);
      const uint64_t mode = number(primitives[i], "mode", 4, context);
      if (mode < 4 || mode > 6) {
        if (mode > 6) fail(fmt::format("{} has unknown mode {}", context, mode));
        warnings_.push_back(fmt::format("{}: {} draws points or lines; skipped", path_, context));
        continue;
      }
      Primitive prim = primitive(primitives[i], context);
      std::vector<uint32_t> list;
      const std::vector<uint32_t>& idx = prim.indices;
      const json* extensions = find(primitives[i], "extensions");
      if (mode == 4 || (extensions && find(*extensions, "KHR_draco_mesh_compression"))) {  // Draco decodes to a list
        prim.indices.resize(idx.size() / 3 * 3);
      } else {
        for (size_t k = 2; k < idx.size(); ++k) {
          const bool strip = mode == 5;
          const uint32_t a = strip ? idx[k - 2] : idx[0], b = idx[k - 1], c = idx[k];
          list.insert(list.end(), {strip && k % 2 ? b : a, strip && k % 2 ? a : b, c});  // keep strips' winding
        }
        prim.indices = std::move(list);
      }
      cached->push_back(std::move(prim));
    }
    return *cached;
  }

  static Mat4 localMatrix(const json& node, size_t i) {
    const auto numbers = [&](const char* key, size_t count, std::vector<double> fallback) {
      const json* value = find(node, key);
      if (!value) return fallback;
      if (!value->is_array() || value->size() != count) {
        fail(fmt::format("node {}: '{}' is not {} numbers", i, key, count));
      }
      std::vector<double> out;
      for (const json& x : *value) {
        if (!x.is_number()) fail(fmt::format("node {}: '{}' is not {} numbers", i, key, count));
        out.push_back(x.get<double>());
      }
      return out;
    };
    Mat4 m = kIdentity;
    if (find(node, "matrix")) {
      const std::vector<double> v = numbers("matrix", 16, {});
      std::copy(v.begin(), v.end(), m.begin());
      return m;
    }
    const std::vector<double> t = numbers("translation", 3, {0, 0, 0});
    const std::vector<double> q = numbers("rotation", 4, {0, 0, 0, 1});
    const std::vector<double> s = numbers("scale", 3, {1, 1, 1});
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const double x = norm > 0 ? q[0] / norm : 0, y = norm > 0 ? q[1] / norm : 0, z = norm > 0 ? q[2] / norm : 0,
                 w = norm > 0 ? q[3] / norm : 1;
    const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                         2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                         2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int col = 0; col < 3; ++col) {
      for (int row = 0; row < 3; ++row) m[col * 4 + row] = r[col * 3 + row] * s[col];
    }
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    return m;
  }

  void addInstance(size_t m, const Mat4& T) {
    const bool mirror = determinant3(T) < 0;
    const std::vector<Primitive>& prims = mesh(m);
    for (size_t i = 0; i < prims.size(); ++i) {
      Primitive prim = prims[i];
      for (size_t v = 0; v + 2 < prim.positions.size(); v += 3) {
        const float* p = &prim.positions[v];
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
          fail(fmt::format("mesh {} primitive {}: vertex {} has non-finite position ({}, {}, {})", m, i, v / 3, p[0],
                           p[1], p[2]));
        }
      }
      for (size_t v = 0; v + 2 < prim.positions.size(); v += 3) {
        const double x = prim.positions[v], y = prim.positions[v + 1], z = prim.positions[v + 2];
        for (int k = 0; k < 3; ++k) {
          prim.positions[v + k] = static_cast<float>(T[k] * x + T[4 + k] * y + T[8 + k] * z + T[12 + k]);
        }
      }
      if (mirror) {
        for (size_t k = 0; k + 2 < prim.indices.size(); k += 3) std::swap(prim.indices[k + 1], prim.indices[k + 2]);
      }
      const Status status = appendPrimitive(model_, prim, path_, fmt::format("mesh {} primitive {}", m, i));
      if (!status.ok()) throw GltfFailure{status.error().code, status.error().message, true};
    }
  }

  void visit(size_t n, const Mat4& parent, int depth) {
    if (depth > 256 || ++visited_nodes_ > 1000000) fail("node hierarchy is cyclic or too deep");
    const json& node = element(root_, "nodes", n);
    const Mat4 world = multiply(parent, localMatrix(node, n));
    if (find(node, "mesh")) addInstance(index(node, "mesh", mesh_cache_.size(), fmt::format("node {}", n)), world);
    for (const json& child : array(node, "children")) {
      if (!child.is_number_unsigned()) fail(fmt::format("node {} has a non-index child", n));
      visit(child.get<size_t>(), world, depth + 1);
    }
  }

  // Draws the default scene (or scene 0, or every root node when there are no scenes, or
  // every mesh when there are no nodes).
  void visitScene() {
    const json& scenes = array(root_, "scenes");
    const json& nodes = array(root_, "nodes");
    if (!scenes.empty()) {
      const size_t s = find(root_, "scene") ? index(root_, "scene", scenes.size(), "glTF") : 0;
      for (const json& n : array(element(root_, "scenes", s), "nodes")) {
        if (!n.is_number_unsigned()) fail(fmt::format("scene {} has a non-index node", s));
        visit(n.get<size_t>(), kIdentity, 0);
      }
    } else if (!nodes.empty()) {
      std::vector<bool> is_child(nodes.size(), false);
      for (const json& node : nodes) {
        for (const json& c : array(node, "children")) {
          if (c.is_number_unsigned() && c.get<size_t>() < nodes.size()) is_child[c.get<size_t>()] = true;
        }
      }
      for (size_t n = 0; n < nodes.size(); ++n) {
        if (!is_child[n]) visit(n, kIdentity, 0);
      }
    } else {
      for (size_t m = 0; m < mesh_cache_.size(); ++m) addInstance(m, kIdentity);
    }
  }

  const std::string& path_;
  fs::path dir_;
  std::vector<std::string>& warnings_;
  const std::vector<uint8_t>& file_;
  json root_;
  Span bin_;
  bool has_bin_ = false;
  std::vector<Span> buffers_;
  std::vector<std::vector<uint8_t>> owned_;
  std::vector<int> texcoord_sets_;
  std::map<size_t, int> image_cache_;
  std::vector<std::optional<std::vector<Primitive>>> mesh_cache_;
  int default_material_ = -1;
  size_t visited_nodes_ = 0;
  Model model_;
};

}  // namespace

Result<Model> loadGltf(const std::string& path, std::vector<std::string>& warnings) {
  auto bytes = readFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  try {
    return GltfReader(path, *bytes, warnings).read();
  } catch (const GltfFailure& failure) {
    if (failure.has_path) return makeError(failure.code, failure.message);
    return fileError(failure.code, path, failure.message);
  } catch (const json::exception& e) {
    return fileError(ErrorCode::kMalformedInput, path, std::string("malformed glTF: ") + e.what());
  }
}

}  // namespace vkloc::model_detail
