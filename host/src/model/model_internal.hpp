// Private helpers shared by the model loaders (model_io.cpp, assimp_loader.cpp, ply_loader.cpp,
// gltf_loader.cpp, draco_loader.cpp, cao.cpp) and the block builder (blocks.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "vkloc/model/model.hpp"

namespace draco {
class Mesh;
class PointAttribute;
}  // namespace draco

namespace vkloc::model_detail {

/// Most vertices, and most triangles, a loaded model may have (positions alone would take 3 GiB).
constexpr size_t kMaxModelElements = size_t{1} << 28;
/// Largest model, buffer or texture file, bytes: an OBJ of ~80 million triangles.
constexpr uint64_t kMaxModelFileBytes = uint64_t{1} << 32;
/// Most corners in one polygon of a file assimp triangulates (OBJ 'f' lines, PLY face lists,
/// other formats' polygons): assimp's ear clipping is quadratic (a 20,000-gon takes 13 s).
constexpr uint64_t kMaxPolygonVertices = 1024;

/// One mesh part as a loader produces it, before it is merged into a Model: attributes of
/// equal length (`uvs` / `colors` empty when absent), indices local to this primitive.
struct Primitive {
  std::vector<float> positions;   ///< x, y, z per vertex, model frame.
  std::vector<float> uvs;         ///< u, v per vertex, (0, 0) at the image's top-left, or empty.
  std::vector<uint8_t> colors;    ///< RGBA8 per vertex, or empty.
  std::vector<uint32_t> indices;  ///< 3 per triangle, counter-clockwise seen from outside.
  int material = 0;               ///< Index into the model's materials.
};

/// "<path>: <what>" as an Error, forced onto one line.
Error fileError(ErrorCode code, const std::string& path, const std::string& what);

/// Whether one triangle of `indices` (3 per triangle, in range of `positions`, x y z per vertex,
/// finite) has an area: twice its area, |u x v|, exceeds what rounding the corners to float can
/// make of a degenerate one, 8 eps M (|u| + |v| + |w|), M the largest coordinate magnitude of its
/// corners.
bool hasTriangleWithArea(const std::vector<float>& positions, const std::vector<uint32_t>& indices);

/// `text` with line breaks and other control characters replaced by spaces.
std::string oneLine(std::string text);

/// White space inside a line of a text model format (not the line break).
inline bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/// `text` for quoting in a message: bytes outside printable ASCII become '?', at most
/// `max_size` kept ("..." marks a cut).
std::string quote(std::string_view text, size_t max_size = 60);

/// Calls fn(line_number, line) for every line of `text` (1-based numbers, no '\n'); stops and
/// returns false when fn does.
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

/// Merges the vertices of `prim` whose position, uv and colour are equal (0 and -0 alike) and
/// drops the ones no triangle uses; leaves `prim` as it is when an index is out of range
/// (appendPrimitive reports it).
void joinIdenticalVertices(Primitive& prim);

/// Lower-case extension of `path` including the dot (".obj"), or "" when there is none.
std::string lowerExtension(const std::string& path);

/// Reads a whole file. Errors name the path: kNotFound when it does not exist, kIoError when it
/// is a directory or cannot be read, kMalformedInput when it is larger than `max_bytes`.
Result<std::vector<uint8_t>> readFileBytes(const std::string& path, uint64_t max_bytes = kMaxModelFileBytes);

/// Appends `prim` to `model` as one draw range, padding `uvs` (zeros) and `colors` (white) so
/// they stay parallel to `positions`. Fails (kMalformedInput, message "<path>: <what>: ...")
/// when an index is not below the primitive's vertex count, or kUnsupported when the model
/// would exceed kMaxModelElements.
Status appendPrimitive(Model& model, const Primitive& prim, const std::string& path, const std::string& what);

/// Decodes an encoded image (PNG, JPEG, ...) into an RGBA8 texture (rows top to bottom).
/// Refuses PNG/JPEG headers that claim far more pixels than `size` bytes can encode. Returns
/// false with `error` set when the bytes are not a decodable image.
bool decodeTexture(const uint8_t* data, size_t size, Texture& out, std::string& error);

/// Recomputes every block's bounds from its triangles and `model.bounds` from the blocks (from
/// all indexed vertices when there are no blocks).
void updateBounds(Model& model);

/// A colour channel 0..255 as a byte (rounded, clamped; NaN gives 0).
inline uint8_t toByte(float v) {
  return static_cast<uint8_t>(std::lround(std::isfinite(v) ? std::clamp(v, 0.0f, 255.0f) : 0.0f));
}

/// Format loaders. Each returns the geometry in the model frame with its materials and
/// textures; loadModel then checks, places and blocks it. Warnings are one line each and start
/// with the path.
Result<Model> loadWithAssimp(const std::string& path, const std::string& ext, std::vector<std::string>& warnings);
bool assimpReadsExtension(const std::string& ext);
Result<Model> loadDrc(const std::string& path);
/// PLY, ASCII or binary, read by vkloc itself (ply_loader.cpp).
Result<Model> loadPly(const std::string& path, const std::vector<uint8_t>& bytes);
Result<Model> loadGltf(const std::string& path, std::vector<std::string>& warnings);

/// Decodes a Draco mesh after checking the stream's counts against its size. nullptr with
/// `error` set (and `unsupported` for valid streams vkloc cannot use) otherwise.
std::unique_ptr<draco::Mesh> decodeDracoMesh(const uint8_t* data, size_t size, std::string& error, bool& unsupported);

/// Converts a decoded Draco mesh to a primitive. `flip_v` turns a bottom-left uv origin into the
/// top-left one. Returns false with `error` set when an attribute cannot be read.
bool dracoPrimitive(const draco::Mesh& mesh, const draco::PointAttribute* position, const draco::PointAttribute* uv,
                    const draco::PointAttribute* color, bool flip_v, Primitive& prim, std::string& error);

}  // namespace vkloc::model_detail
