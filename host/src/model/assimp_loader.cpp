// OBJ (+ MTL) and the other formats assimp reads. OBJ files are checked before import, because
// assimp's parsers accept garbage (binary bytes as OBJ), size arrays from unchecked counts, and
// can trip its internal assertions on the result: the check walks the file and reports what is
// wrong with line numbers. PLY is read by ply_loader.cpp, without assimp.
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
