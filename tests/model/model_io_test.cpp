// Model loading, validation, placement and blocking: every format on small hand-made files,
// the error cases, and truncated / random / corrupted versions of each format.
#include <assimp/material.h>
#include <assimp/scene.h>
#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <draco/point_cloud/point_cloud_builder.h>
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {
namespace {

using test::TempDir;
using test::writeFile;
using Bytes = std::vector<uint8_t>;

// ---- the test quad ----------------------------------------------------------------------------
// Four vertices in the z = 0 plane, two counter-clockwise triangles seen from +z. Texture
// coordinates in the top-left-origin convention Model uses; colours RGBA8.
constexpr float kQuadPositions[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
constexpr float kQuadUvs[4][2] = {{0.1f, 0.8f}, {0.9f, 0.8f}, {0.9f, 0.3f}, {0.1f, 0.3f}};
constexpr uint8_t kQuadColors[4][4] = {{255, 0, 0, 255}, {0, 255, 0, 255}, {0, 0, 255, 255}, {10, 20, 30, 128}};
constexpr uint32_t kQuadIndices[6] = {0, 1, 2, 0, 2, 3};

void putFloat(Bytes& out, float v) {
  uint8_t b[4];
  std::memcpy(b, &v, 4);
  out.insert(out.end(), b, b + 4);
}
void putU16(Bytes& out, uint16_t v) { out.insert(out.end(), {uint8_t(v), uint8_t(v >> 8)}); }
void putU32(Bytes& out, uint32_t v) {
  out.insert(out.end(), {uint8_t(v), uint8_t(v >> 8), uint8_t(v >> 16), uint8_t(v >> 24)});
}
Bytes toBytes(const std::string& s) { return Bytes(s.begin(), s.end()); }

std::string replaceOnce(std::string s, const std::string& from, const std::string& to) {
  const size_t at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? s : s.replace(at, from.size(), to);
}

// Index of the vertex at (x, y, z), or -1.
int findVertex(const Model& model, float x, float y, float z) {
  for (size_t i = 0; i < model.vertexCount(); ++i) {
    const float* p = &model.positions[3 * i];
    if (std::abs(p[0] - x) < 1e-4f && std::abs(p[1] - y) < 1e-4f && std::abs(p[2] - z) < 1e-4f) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

// Checks the quad's geometry (shifted by `offset`), and its uvs / colours when expected.
void expectQuad(const Model& model, const std::array<float, 3>& offset, bool uvs, bool colors) {
  ASSERT_EQ(model.vertexCount(), 4u);
  ASSERT_EQ(model.triangleCount(), 2u);
  EXPECT_TRUE(validateModel(model).ok());
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(model.bounds.min[k], offset[k], 1e-4);
    EXPECT_NEAR(model.bounds.max[k], offset[k] + (k < 2 ? 1.0f : 0.0f), 1e-4);
  }
  EXPECT_EQ(model.uvs.empty(), !uvs);
  EXPECT_EQ(model.colors.empty(), !colors);
  for (int v = 0; v < 4; ++v) {
    const int i = findVertex(model, kQuadPositions[v][0] + offset[0], kQuadPositions[v][1] + offset[1],
                             kQuadPositions[v][2] + offset[2]);
    ASSERT_GE(i, 0) << "vertex " << v;
    if (uvs) {
      EXPECT_NEAR(model.uvs[2 * i], kQuadUvs[v][0], 1e-3) << "vertex " << v;
      EXPECT_NEAR(model.uvs[2 * i + 1], kQuadUvs[v][1], 1e-3) << "vertex " << v;
    }
    for (int k = 0; colors && k < 4; ++k) {
      EXPECT_NEAR(model.colors[4 * i + k], kQuadColors[v][k], 1) << "vertex " << v;
    }
  }
  // Counter-clockwise seen from +z.
  for (size_t t = 0; t < model.triangleCount(); ++t) {
    const float* a = &model.positions[3 * model.indices[3 * t]];
    const float* b = &model.positions[3 * model.indices[3 * t + 1]];
    const float* c = &model.positions[3 * model.indices[3 * t + 2]];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]), 0.0f);
  }
}

// A 2x2 PNG: top-left red, top-right green, bottom-left blue, bottom-right white.
Bytes pngBytes() {
  cv::Mat bgr(2, 2, CV_8UC3);
  bgr.at<cv::Vec3b>(0, 0) = {0, 0, 255};
  bgr.at<cv::Vec3b>(0, 1) = {0, 255, 0};
  bgr.at<cv::Vec3b>(1, 0) = {255, 0, 0};
  bgr.at<cv::Vec3b>(1, 1) = {255, 255, 255};
  Bytes out;
  cv::imencode(".png", bgr, out);
  return out;
}

void expectTestTexture(const Texture& t) {
  ASSERT_EQ(t.width, 2);
  ASSERT_EQ(t.height, 2);
  const std::vector<uint8_t> expected = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
  EXPECT_EQ(t.rgba, expected);
}

std::string base64(const Bytes& in) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t n = (uint32_t{in[i]} << 16) | (i + 1 < in.size() ? uint32_t{in[i + 1]} << 8 : 0) |
                       (i + 2 < in.size() ? in[i + 2] : 0);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += i + 1 < in.size() ? kAlphabet[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? kAlphabet[n & 63] : '=';
  }
  return out;
}

// ---- OBJ / PLY --------------------------------------------------------------------------------

// The quad as OBJ (bottom-left uv origin, so v is stored as 1 - v).
std::string quadObj(const std::string& mtllib = "quad.mtl") {
  std::string s = "# test quad\nmtllib " + mtllib + "\n";
  for (const auto& p : kQuadPositions) s += fmt::format("v {} {} {}\n", p[0], p[1], p[2]);
  for (const auto& t : kQuadUvs) s += fmt::format("vt {} {}\n", t[0], 1.0f - t[1]);
  return s + "usemtl red\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
}

std::string plyHeader(const std::string& format, bool colors) {
  return "ply\nformat " + format +
         " 1.0\ncomment test quad\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n" +
         std::string(colors ? "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n"
                            : "") +
         "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string quadPlyAscii(bool colors = true) {
  std::string s = plyHeader("ascii", colors);
  for (int v = 0; v < 4; ++v) {
    s += fmt::format("{} {} {}", kQuadPositions[v][0], kQuadPositions[v][1], kQuadPositions[v][2]);
    if (colors) {
      s += fmt::format(" {} {} {} {}", kQuadColors[v][0], kQuadColors[v][1], kQuadColors[v][2], kQuadColors[v][3]);
    }
    s += "\n";
  }
  return s + "3 0 1 2\n3 0 2 3\n";
}

Bytes quadPlyBinary(float first_x = 0.0f, uint32_t last_index = 3) {
  Bytes out = toBytes(plyHeader("binary_little_endian", true));
  for (int v = 0; v < 4; ++v) {
    for (int k = 0; k < 3; ++k) putFloat(out, v == 0 && k == 0 ? first_x : kQuadPositions[v][k]);
    out.insert(out.end(), kQuadColors[v], kQuadColors[v] + 4);
  }
  for (int t = 0; t < 2; ++t) {
    out.push_back(3);
    for (int j = 0; j < 3; ++j) putU32(out, t == 1 && j == 2 ? last_index : kQuadIndices[3 * t + j]);
  }
  return out;
}

// ---- glTF ---------------------------------------------------------------------------------------

// The quad's vertex data as one glTF buffer: positions (0, 48 bytes), uvs (48, 32), colours as
// normalized ubyte (80, 16), ushort indices (96, 12).
Bytes quadBuffer() {
  Bytes out;
  for (const auto& p : kQuadPositions) {
    for (float x : p) putFloat(out, x);
  }
  for (const auto& t : kQuadUvs) {
    for (float x : t) putFloat(out, x);
  }
  for (const auto& c : kQuadColors) out.insert(out.end(), c, c + 4);
  for (uint32_t i : kQuadIndices) putU16(out, static_cast<uint16_t>(i));
  return out;
}

// bufferViews 0-3 and accessors 0-3 of quadBuffer() in buffer 0, starting at `offset`.
std::string quadViewsJson(size_t offset) {
  return fmt::format(R"({{"buffer":0,"byteOffset":{},"byteLength":48}},{{"buffer":0,"byteOffset":{},"byteLength":32}},
{{"buffer":0,"byteOffset":{},"byteLength":16}},{{"buffer":0,"byteOffset":{},"byteLength":12}})",
                     offset, offset + 48, offset + 80, offset + 96);
}
const char* kQuadAccessorsJson =
    R"({"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5126,"count":4,"type":"VEC2"},
{"bufferView":2,"componentType":5121,"normalized":true,"count":4,"type":"VEC4"},
{"bufferView":3,"componentType":5123,"count":6,"type":"SCALAR"})";

// A glTF document drawing the quad through a node translated by (10, 0, 0) with a textured
// material. `buffer` and `image` are the JSON of buffer 0 and image 0; `extra_views` is
// appended to the bufferViews.
std::string quadGltfJson(const std::string& buffer, const std::string& image, const std::string& extra_views = "") {
  return fmt::format(R"({{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"mesh":0,"translation":[10,0,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"COLOR_0":2}},"indices":3,"material":0}}]}}],
"materials":[{{"name":"painted","pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.25,1,1],"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{}],
"buffers":[{}],"bufferViews":[{}{}],"accessors":[{}]}})",
                     image, buffer, quadViewsJson(0), extra_views, kQuadAccessorsJson);
}

Bytes packGlb(std::string json, Bytes bin) {
  while (json.size() % 4) json += ' ';
  while (bin.size() % 4) bin.push_back(0);
  Bytes out = toBytes("glTF");
  putU32(out, 2);
  putU32(out, static_cast<uint32_t>(12 + 8 + json.size() + (bin.empty() ? 0 : 8 + bin.size())));
  putU32(out, static_cast<uint32_t>(json.size()));
  putU32(out, 0x4E4F534A);
  out.insert(out.end(), json.begin(), json.end());
  if (!bin.empty()) {
    putU32(out, static_cast<uint32_t>(bin.size()));
    putU32(out, 0x004E4942);
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

// The quad as GLB: vertex data and the PNG (bufferView 4) in the BIN chunk.
Bytes quadGlb() {
  Bytes bin = quadBuffer();
  const Bytes png = pngBytes();
  const size_t png_offset = bin.size();
  bin.insert(bin.end(), png.begin(), png.end());
  const std::string json =
      quadGltfJson(fmt::format(R"({{"byteLength":{}}})", bin.size()), R"({"bufferView":4,"mimeType":"image/png"})",
                   fmt::format(R"(,{{"buffer":0,"byteOffset":{},"byteLength":{}}})", png_offset, png.size()));
  return packGlb(json, bin);
}

// ---- Draco --------------------------------------------------------------------------------------

struct DracoQuad {
  Bytes bytes;
  uint32_t position_id = 0, uv_id = 0, color_id = 0;  // attribute unique ids
};

// The quad at height z encoded with Draco; `flip_v` stores v as 1 - v (OBJ convention, as
// standalone .drc files from draco_encoder have).
DracoQuad encodeDracoQuad(float z, int method, bool flip_v) {
  draco::TriangleSoupMeshBuilder builder;
  builder.Start(2);
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  const int uv = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
  const int col = builder.AddAttribute(draco::GeometryAttribute::COLOR, 4, draco::DT_UINT8, true);
  float p[4][3], t[4][2];
  for (int v = 0; v < 4; ++v) {
    p[v][0] = kQuadPositions[v][0];
    p[v][1] = kQuadPositions[v][1];
    p[v][2] = z;
    t[v][0] = kQuadUvs[v][0];
    t[v][1] = flip_v ? 1.0f - kQuadUvs[v][1] : kQuadUvs[v][1];
  }
  for (int f = 0; f < 2; ++f) {
    const uint32_t* c = &kQuadIndices[3 * f];
    builder.SetAttributeValuesForFace(pos, draco::FaceIndex(f), p[c[0]], p[c[1]], p[c[2]]);
    builder.SetAttributeValuesForFace(uv, draco::FaceIndex(f), t[c[0]], t[c[1]], t[c[2]]);
    builder.SetAttributeValuesForFace(col, draco::FaceIndex(f), kQuadColors[c[0]], kQuadColors[c[1]],
                                      kQuadColors[c[2]]);
  }
  std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
  draco::Encoder encoder;
  encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, 16);
  encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, 16);
  encoder.SetEncodingMethod(method);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(*mesh, &buffer);
  EXPECT_TRUE(status.ok()) << status.error_msg_string();
  DracoQuad out;
  out.bytes.assign(buffer.data(), buffer.data() + buffer.size());
  out.position_id = mesh->attribute(pos)->unique_id();
  out.uv_id = mesh->attribute(uv)->unique_id();
  out.color_id = mesh->attribute(col)->unique_id();
  return out;
}

// A GLB with one mesh of two primitives: the quad at z = 1 Draco-compressed (with colours) and
// the plain quad at z = 0 without colours.
Bytes mixedDracoGlb() {
  const DracoQuad draco = encodeDracoQuad(1.0f, draco::MESH_EDGEBREAKER_ENCODING, false);
  Bytes bin = quadBuffer();
  const size_t draco_offset = bin.size();
  bin.insert(bin.end(), draco.bytes.begin(), draco.bytes.end());
  const std::string json = fmt::format(R"({{"asset":{{"version":"2.0"}},
"extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],
"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[
 {{"attributes":{{"POSITION":4,"TEXCOORD_0":5,"COLOR_0":6}},"indices":7,"material":0,
   "extensions":{{"KHR_draco_mesh_compression":{{"bufferView":4,"attributes":{{"POSITION":{},"TEXCOORD_0":{},"COLOR_0":{}}}}}}}}},
 {{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"indices":3}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.5,1]}}}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{},{{"buffer":0,"byteOffset":{},"byteLength":{}}}],
"accessors":[{},
 {{"componentType":5126,"count":4,"type":"VEC3","min":[0,0,1],"max":[1,1,1]}},
 {{"componentType":5126,"count":4,"type":"VEC2"}},
 {{"componentType":5121,"normalized":true,"count":4,"type":"VEC4"}},
 {{"componentType":5123,"count":6,"type":"SCALAR"}}]}})",
                                       draco.position_id, draco.uv_id, draco.color_id, bin.size(), quadViewsJson(0),
                                       draco_offset, draco.bytes.size(), kQuadAccessorsJson);
  return packGlb(json, bin);
}

// ---- helpers for error checks -------------------------------------------------------------------

void expectError(const Result<Model>& result, ErrorCode code, const std::string& path, const std::string& text) {
  ASSERT_FALSE(result.ok()) << path;
  EXPECT_EQ(result.error().code, code) << result.error().message;
  EXPECT_EQ(result.error().message.rfind(path + ": ", 0), 0u) << result.error().message;
  EXPECT_NE(result.error().message.find(text), std::string::npos) << result.error().message;
  EXPECT_EQ(result.error().message.find('\n'), std::string::npos) << result.error().message;
}

// ---- loading each format ------------------------------------------------------------------------

TEST(ModelIo, LoadsObjWithMtlAndTexture) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.obj"), quadObj()));
  ASSERT_TRUE(writeFile(dir.file("quad.mtl"), "newmtl red\nKd 0.5 0.25 1.0\nmap_Kd tex.png\n"));
  ASSERT_TRUE(writeFile(dir.file("tex.png"), pngBytes()));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("quad.obj"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  expectQuad(*model, {0, 0, 0}, true, false);
  const auto& m = model->materials.at(model->ranges.at(0).material);
  EXPECT_EQ(m.name, "red");
  EXPECT_NEAR(m.base_color[0], 0.5f, 1e-6);
  EXPECT_NEAR(m.base_color[1], 0.25f, 1e-6);
  EXPECT_NEAR(m.base_color[2], 1.0f, 1e-6);
  ASSERT_EQ(m.texture, 0);
  expectTestTexture(model->textures[0]);
  EXPECT_EQ(model->source, dir.file("quad.obj"));
  EXPECT_EQ(model->blocks.size(), 1u);
}

TEST(ModelIo, ExtensionIsCaseInsensitive) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("QUAD.OBJ"), quadObj("none.mtl")));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("QUAD.OBJ"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  expectQuad(*model, {0, 0, 0}, true, false);
  ASSERT_EQ(warnings.size(), 1u);  // the missing material library
  EXPECT_NE(warnings[0].find("none.mtl"), std::string::npos) << warnings[0];
  EXPECT_GE(model->materials.size(), 1u);
}

TEST(ModelIo, MissingTextureIsAWarning) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.obj"), quadObj()));
  ASSERT_TRUE(writeFile(dir.file("quad.mtl"), "newmtl red\nKd 0.5 0.25 1.0\nmap_Kd missing.png\n"));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("quad.obj"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0].rfind(dir.file("quad.obj") + ": ", 0), 0u) << warnings[0];
  EXPECT_NE(warnings[0].find("'red'"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("missing.png"), std::string::npos) << warnings[0];
  EXPECT_EQ(model->materials.at(model->ranges.at(0).material).texture, -1);
  EXPECT_NEAR(model->materials.at(model->ranges.at(0).material).base_color[1], 0.25f, 1e-6);
  EXPECT_TRUE(model->textures.empty());
}

TEST(ModelIo, LoadsPlyWithVertexColors) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("ascii.ply"), quadPlyAscii()));
  ASSERT_TRUE(writeFile(dir.file("binary.ply"), quadPlyBinary()));
  ASSERT_TRUE(writeFile(dir.file("plain.ply"), quadPlyAscii(false)));
  for (const char* name : {"ascii.ply", "binary.ply"}) {
    SCOPED_TRACE(name);
    auto model = loadModel(dir.file(name));
    ASSERT_TRUE(model.ok()) << model.error().message;
    expectQuad(*model, {0, 0, 0}, false, true);
    // Vertex colours are the appearance: the base colour that multiplies them is white.
    ASSERT_EQ(model->materials.size(), 1u);
    EXPECT_EQ(model->materials[0].base_color, (std::array<float, 4>{1, 1, 1, 1}));
  }
  auto plain = loadModel(dir.file("plain.ply"));
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  expectQuad(*plain, {0, 0, 0}, false, false);
  EXPECT_EQ(plain->materials.at(0).base_color, Material{}.base_color);
}

TEST(ModelIo, PlyPolygonsTexcoordsAndColourTypes) {
  TempDir dir("modelio");
  // A quad (one face of 4 corners), a line and a point (dropped: no area), an unused vertex,
  // texture coordinates named u/v, 16-bit colours.
  const std::string header =
      "element vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty float u\n"
      "property float v\nproperty ushort red\nproperty ushort green\nproperty ushort blue\n"
      "element face 3\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string ascii = dir.file("quad.ply");
  ASSERT_TRUE(writeFile(ascii, "ply\nformat ascii 1.0\n" + header +
                                   "0 0 0 0 0 65535 0 0\n1 0 0 1 0 0 65535 0\n1 1 0 1 1 0 0 65535\n"
                                   "0 1 0 0 1 32768 32768 32768\n5 5 5 0 0 0 0 0\n4 0 1 2 3\n2 0 1\n1 2\n"));
  auto model = loadModel(ascii);
  ASSERT_TRUE(model.ok()) << model.error().message;
  ASSERT_EQ(model->triangleCount(), 2u);
  ASSERT_EQ(model->vertexCount(), 4u);
  ASSERT_EQ(model->colors.size(), 16u);
  ASSERT_EQ(model->uvs.size(), 8u);
  for (size_t v = 0; v < 4; ++v) {
    const float* p = &model->positions[3 * v];
    SCOPED_TRACE(fmt::format("vertex {} at ({}, {})", v, p[0], p[1]));
    // u = x, v = y in the file; vkloc's v grows downwards.
    EXPECT_FLOAT_EQ(model->uvs[2 * v], p[0]);
    EXPECT_FLOAT_EQ(model->uvs[2 * v + 1], 1.0f - p[1]);
    EXPECT_EQ(model->colors[4 * v + 3], 255);  // no alpha: opaque
  }
  EXPECT_EQ(model->colors[0], 255);   // 65535 of 65535
  EXPECT_EQ(model->colors[12], 128);  // 32768 of 65535
  // Both triangles face +z (the quad's orientation kept).
  for (size_t t = 0; t < 2; ++t) {
    const uint32_t* i = &model->indices[3 * t];
    const Eigen::Vector3f a(&model->positions[3 * i[0]]), b(&model->positions[3 * i[1]]),
        c(&model->positions[3 * i[2]]);
    EXPECT_GT((b - a).cross(c - a).z(), 0.0f);
  }
  EXPECT_EQ(model->materials.at(0).base_color, (std::array<float, 4>{1, 1, 1, 1}));
}

TEST(ModelIo, LoadsGltfWithEmbeddedData) {
  TempDir dir("modelio");
  const Bytes buffer = quadBuffer();
  const std::string json =
      quadGltfJson(fmt::format(R"({{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}})", buffer.size(),
                               base64(buffer)),
                   fmt::format(R"({{"uri":"data:image/png;base64,{}"}})", base64(pngBytes())));
  ASSERT_TRUE(writeFile(dir.file("quad.gltf"), json));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("quad.gltf"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_TRUE(warnings.empty());
  expectQuad(*model, {10, 0, 0}, true, true);
  const Material& m = model->materials.at(model->ranges.at(0).material);
  EXPECT_EQ(m.name, "painted");
  EXPECT_EQ(m.base_color, (std::array<float, 4>{0.5f, 0.25f, 1, 1}));
  ASSERT_EQ(m.texture, 0);
  expectTestTexture(model->textures[0]);
}

TEST(ModelIo, LoadsGltfWithExternalFiles) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.bin"), quadBuffer()));
  ASSERT_TRUE(writeFile(dir.file("my tex.png"), pngBytes()));
  const std::string json = quadGltfJson(fmt::format(R"({{"byteLength":{},"uri":"quad.bin"}})", quadBuffer().size()),
                                        R"({"uri":"my%20tex.png"})");
  ASSERT_TRUE(writeFile(dir.file("quad.gltf"), json));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("quad.gltf"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_TRUE(warnings.empty());
  expectQuad(*model, {10, 0, 0}, true, true);
  ASSERT_EQ(model->textures.size(), 1u);
  expectTestTexture(model->textures[0]);

  // A missing image is a warning naming the material and the file; a missing buffer an error.
  std::filesystem::remove(dir.file("my tex.png"));
  warnings.clear();
  model = loadModel(dir.file("quad.gltf"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("'painted'"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("my tex.png"), std::string::npos) << warnings[0];
  EXPECT_EQ(model->materials[0].texture, -1);
  std::filesystem::remove(dir.file("quad.bin"));
  expectError(loadModel(dir.file("quad.gltf")), ErrorCode::kNotFound, dir.file("quad.gltf"), "quad.bin");
}

TEST(ModelIo, LoadsGlb) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.glb"), quadGlb()));
  auto model = loadModel(dir.file("quad.glb"));
  ASSERT_TRUE(model.ok()) << model.error().message;
  expectQuad(*model, {10, 0, 0}, true, true);
  ASSERT_EQ(model->textures.size(), 1u);
  expectTestTexture(model->textures[0]);
}

TEST(ModelIo, LoadsOtherAssimpFormatsWithEmbeddedTextures) {
  // The quad GLB converted by assimp to its own binary format, once with the PNG embedded as
  // is and once as raw texels: both reach loadModel as embedded texture "*0".
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.glb"), quadGlb()));
  for (bool raw : {false, true}) {
    SCOPED_TRACE(raw ? "raw texels" : "embedded PNG");
    Assimp::Importer importer;
    ASSERT_NE(importer.ReadFile(dir.file("quad.glb"), 0), nullptr) << importer.GetErrorString();
    std::unique_ptr<aiScene> scene(importer.GetOrphanedScene());
    ASSERT_EQ(scene->mNumTextures, 1u);
    if (raw) {
      aiTexture& texture = *scene->mTextures[0];
      delete[] texture.pcData;
      texture.mWidth = texture.mHeight = 2;
      texture.pcData = new aiTexel[4]{{0, 0, 255, 255}, {0, 255, 0, 255}, {255, 0, 0, 255}, {255, 255, 255, 255}};
    }
    Assimp::Exporter exporter;
    ASSERT_EQ(exporter.Export(scene.get(), "assbin", dir.file("quad.assbin")), AI_SUCCESS);
    auto model = loadModel(dir.file("quad.assbin"));
    ASSERT_TRUE(model.ok()) << model.error().message;
    expectQuad(*model, {10, 0, 0}, true, true);
    const Material& m = model->materials.at(model->ranges.at(0).material);
    EXPECT_EQ(m.base_color, (std::array<float, 4>{0.5f, 0.25f, 1, 1}));
    ASSERT_EQ(m.texture, 0);
    expectTestTexture(model->textures[0]);
  }
}

TEST(ModelIo, LoadsDrc) {
  TempDir dir("modelio");
  for (int method : {draco::MESH_EDGEBREAKER_ENCODING, draco::MESH_SEQUENTIAL_ENCODING}) {
    SCOPED_TRACE(method);
    ASSERT_TRUE(writeFile(dir.file("quad.drc"), encodeDracoQuad(0.0f, method, true).bytes));
    auto model = loadModel(dir.file("quad.drc"));
    ASSERT_TRUE(model.ok()) << model.error().message;
    expectQuad(*model, {0, 0, 0}, true, true);
    EXPECT_EQ(model->materials.at(0).base_color, (std::array<float, 4>{1, 1, 1, 1}));
  }
}

TEST(ModelIo, DrcPointCloudIsUnsupported) {
  TempDir dir("modelio");
  draco::PointCloudBuilder builder;
  builder.Start(3);
  const int pos = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
  for (int v = 0; v < 3; ++v) builder.SetAttributeValueForPoint(pos, draco::PointIndex(v), kQuadPositions[v]);
  auto cloud = builder.Finalize(false);
  draco::Encoder encoder;
  draco::EncoderBuffer buffer;
  ASSERT_TRUE(encoder.EncodePointCloudToBuffer(*cloud, &buffer).ok());
  ASSERT_TRUE(writeFile(dir.file("cloud.drc"), Bytes(buffer.data(), buffer.data() + buffer.size())));
  expectError(loadModel(dir.file("cloud.drc")), ErrorCode::kUnsupported, dir.file("cloud.drc"), "point cloud");
}

TEST(ModelIo, LoadsGlbMixingDracoAndPlainPrimitives) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("mixed.glb"), mixedDracoGlb()));
  auto model = loadModel(dir.file("mixed.glb"));
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_EQ(model->vertexCount(), 8u);
  EXPECT_EQ(model->triangleCount(), 4u);
  EXPECT_TRUE(validateModel(*model).ok());
  EXPECT_NEAR(model->bounds.min[2], 0.0f, 1e-4);
  EXPECT_NEAR(model->bounds.max[2], 1.0f, 1e-4);
  ASSERT_EQ(model->colors.size(), 4 * model->vertexCount());
  for (int v = 0; v < 4; ++v) {
    const int draco_vertex = findVertex(*model, kQuadPositions[v][0], kQuadPositions[v][1], 1.0f);
    const int plain_vertex = findVertex(*model, kQuadPositions[v][0], kQuadPositions[v][1], 0.0f);
    ASSERT_GE(draco_vertex, 0);
    ASSERT_GE(plain_vertex, 0);
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(model->uvs[2 * draco_vertex + k], kQuadUvs[v][k], 1e-3);
      EXPECT_NEAR(model->uvs[2 * plain_vertex + k], kQuadUvs[v][k], 1e-6);
    }
    for (int k = 0; k < 4; ++k) {
      EXPECT_EQ(model->colors[4 * draco_vertex + k], kQuadColors[v][k]);
      EXPECT_EQ(model->colors[4 * plain_vertex + k], 255);  // no COLOR_0: white
    }
  }
  // The Draco primitive uses material 0, the plain one the default material.
  ASSERT_EQ(model->materials.size(), 2u);
  EXPECT_EQ(model->materials[0].base_color, (std::array<float, 4>{1, 0.5f, 0.5f, 1}));
}

// ---- options --------------------------------------------------------------------------------------

TEST(ModelIo, AppliesUnitScaleTransformAndBlockSize) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.ply"), quadPlyAscii()));
  ModelLoadOptions options;
  options.unit_scale = 0.001;  // millimetres
  // 90 degrees about z, then a translation.
  options.T_world_model = {0, -1, 0, 5, 1, 0, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1};
  options.max_block_triangles = 1;
  auto model = loadModel(dir.file("quad.ply"), options);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_EQ(model->blocks.size(), 2u);
  EXPECT_NEAR(model->bounds.min[0], 5 - 0.001, 1e-6);
  EXPECT_NEAR(model->bounds.max[0], 5, 1e-6);
  EXPECT_NEAR(model->bounds.min[1], 6, 1e-6);
  EXPECT_NEAR(model->bounds.max[1], 6.001, 1e-6);
  EXPECT_NEAR(model->bounds.min[2], 7, 1e-6);
  EXPECT_GE(findVertex(*model, 5.0f, 6.001f, 7.0f), 0);  // (1, 0, 0) mm rotated to +y

  // A mirroring transform keeps triangles counter-clockwise seen from outside (+z).
  options = {};
  options.T_world_model = {-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  model = loadModel(dir.file("quad.ply"), options);
  ASSERT_TRUE(model.ok()) << model.error().message;
  for (size_t t = 0; t < model->triangleCount(); ++t) {
    const float* a = &model->positions[3 * model->indices[3 * t]];
    const float* b = &model->positions[3 * model->indices[3 * t + 1]];
    const float* c = &model->positions[3 * model->indices[3 * t + 2]];
    EXPECT_GT((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]), 0.0f);
  }
}

TEST(ModelIo, RejectsInvalidOptions) {
  TempDir dir("modelio");
  const std::string path = dir.file("quad.ply");
  ASSERT_TRUE(writeFile(path, quadPlyAscii()));
  ModelLoadOptions options;
  options.unit_scale = 0.0;
  expectError(loadModel(path, options), ErrorCode::kInvalidArgument, path, "unit_scale");
  options = {};
  options.T_world_model[3] = NAN;
  expectError(loadModel(path, options), ErrorCode::kInvalidArgument, path, "T_world_model");
  options = {};
  options.T_world_model[14] = 1.0;
  expectError(loadModel(path, options), ErrorCode::kInvalidArgument, path, "last row");
  options = {};
  options.unit_scale = 1e38;
  options.T_world_model[0] = 1e10;
  expectError(loadModel(path, options), ErrorCode::kInvalidArgument, path, "not finite");
}

// ---- bad input ------------------------------------------------------------------------------------

TEST(ModelIo, ReportsMissingEmptyDirectoryAndUnknown) {
  TempDir dir("modelio");
  const std::string missing = dir.file("model.obj");
  auto result = loadModel(missing);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kNotFound);
  EXPECT_EQ(result.error().message, missing + ": file not found");

  std::filesystem::create_directories(dir.file("folder.obj"));
  expectError(loadModel(dir.file("folder.obj")), ErrorCode::kIoError, dir.file("folder.obj"), "directory");

  for (const char* name : {"e.obj", "e.ply", "e.gltf", "e.glb", "e.drc", "e.stl"}) {
    ASSERT_TRUE(writeFile(dir.file(name), std::string()));
    expectError(loadModel(dir.file(name)), ErrorCode::kMalformedInput, dir.file(name), "empty");
  }
  ASSERT_TRUE(writeFile(dir.file("model.xyz"), quadObj()));
  expectError(loadModel(dir.file("model.xyz")), ErrorCode::kUnsupported, dir.file("model.xyz"), "'.xyz'");
  ASSERT_TRUE(writeFile(dir.file("model"), quadObj()));
  expectError(loadModel(dir.file("model")), ErrorCode::kUnsupported, dir.file("model"), "no file extension");
}

TEST(ModelIo, RejectsBadIndicesAndNonFiniteVertices) {
  TempDir dir("modelio");
  std::string obj = replaceOnce(quadObj("none.mtl"), "f 1/1 3/3 4/4", "f 1/1 3/3 900/4");
  const std::string obj_path = dir.file("bad.obj");
  ASSERT_TRUE(writeFile(obj_path, obj));
  expectError(loadModel(obj_path), ErrorCode::kMalformedInput, obj_path,
              "face 2 (line 13) references vertex 900 but there are 4 vertices");

  obj = replaceOnce(quadObj("none.mtl"), "v 0 0 0", "v nan 0 1");
  ASSERT_TRUE(writeFile(obj_path, obj));
  expectError(loadModel(obj_path), ErrorCode::kMalformedInput, obj_path,
              "vertex 1 (line 3) has non-finite position (nan, 0, 1)");

  const std::string ply_path = dir.file("bad.ply");
  ASSERT_TRUE(writeFile(ply_path, quadPlyBinary(INFINITY)));
  expectError(loadModel(ply_path), ErrorCode::kMalformedInput, ply_path,
              "vertex 0 has non-finite position (inf, 0, 0)");
  ASSERT_TRUE(writeFile(ply_path, quadPlyBinary(0.0f, 12)));
  expectError(loadModel(ply_path), ErrorCode::kMalformedInput, ply_path,
              "face 1 references vertex 12 but there are 4 vertices");

  // glTF: an index past the vertices, and a NaN position.
  Bytes buffer = quadBuffer();
  buffer[96 + 10] = 7;
  std::string json = quadGltfJson(fmt::format(R"({{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}})",
                                              buffer.size(), base64(buffer)),
                                  R"({"uri":"tex.png"})");
  const std::string gltf_path = dir.file("bad.gltf");
  ASSERT_TRUE(writeFile(gltf_path, json));
  expectError(loadModel(gltf_path), ErrorCode::kMalformedInput, gltf_path,
              "references vertex 7 but there are 4 vertices");
  buffer = quadBuffer();
  const float nan = NAN;
  std::memcpy(&buffer[4], &nan, 4);
  json = quadGltfJson(fmt::format(R"({{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}})",
                                  buffer.size(), base64(buffer)),
                      R"({"uri":"tex.png"})");
  ASSERT_TRUE(writeFile(gltf_path, json));
  expectError(loadModel(gltf_path), ErrorCode::kMalformedInput, gltf_path, "non-finite position");
}

TEST(ModelIo, RejectsMeshesWithoutTriangles) {
  TempDir dir("modelio");
  const std::string obj_path = dir.file("points.obj");
  ASSERT_TRUE(writeFile(obj_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  expectError(loadModel(obj_path), ErrorCode::kMalformedInput, obj_path, "no triangles");
  ASSERT_TRUE(writeFile(obj_path, "# nothing\n"));
  expectError(loadModel(obj_path), ErrorCode::kMalformedInput, obj_path, "no triangles");
  ASSERT_TRUE(writeFile(obj_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n"));
  expectError(loadModel(obj_path), ErrorCode::kMalformedInput, obj_path, "no triangles");
  const std::string ply_path = dir.file("points.ply");
  ASSERT_TRUE(writeFile(ply_path,
                        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float "
                        "z\nend_header\n0 0 0\n1 1 1\n"));
  expectError(loadModel(ply_path), ErrorCode::kMalformedInput, ply_path, "no triangles");
  const std::string gltf_path = dir.file("empty.gltf");
  ASSERT_TRUE(writeFile(gltf_path, R"({"asset":{"version":"2.0"}})"));
  expectError(loadModel(gltf_path), ErrorCode::kMalformedInput, gltf_path, "no triangles");
}

TEST(ModelIo, RejectsHeadersClaimingHugeSizes) {
  TempDir dir("modelio");
  // GLB header longer than the file.
  Bytes glb = quadGlb();
  const std::string glb_path = dir.file("x.glb");
  ASSERT_TRUE(writeFile(glb_path, Bytes(glb.begin(), glb.begin() + 100)));
  expectError(loadModel(glb_path), ErrorCode::kMalformedInput, glb_path,
              fmt::format("truncated GLB: header says {} bytes, file has 100", glb.size()));
  // Accessor count and buffer length far beyond the data.
  std::string json = quadGltfJson(fmt::format(R"({{"byteLength":{}}})", 108), R"({"uri":"t.png"})");
  const std::string huge_count = replaceOnce(json, R"("count":4,"type":"VEC3")", R"("count":4000000000,"type":"VEC3")");
  ASSERT_TRUE(writeFile(glb_path, packGlb(huge_count, quadBuffer())));
  expectError(loadModel(glb_path), ErrorCode::kMalformedInput, glb_path, "does not fit");
  const std::string huge_buffer = replaceOnce(json, R"("byteLength":108)", R"("byteLength":100000000000)");
  ASSERT_TRUE(writeFile(glb_path, packGlb(huge_buffer, quadBuffer())));
  expectError(loadModel(glb_path), ErrorCode::kMalformedInput, glb_path, "BIN chunk");
  // A texture whose PNG header claims 50000 x 50000 pixels: a warning, not an allocation.
  Bytes png = pngBytes();
  png[18] = png[22] = 0xc3;
  png[19] = png[23] = 0x50;
  std::string lying_png = quadGltfJson(
      fmt::format(R"({{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}})", 108, base64(quadBuffer())),
      fmt::format(R"({{"uri":"data:image/png;base64,{}"}})", base64(png)));
  ASSERT_TRUE(writeFile(dir.file("png.gltf"), lying_png));
  std::vector<std::string> warnings;
  auto model = loadModel(dir.file("png.gltf"), {}, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("50000x50000"), std::string::npos) << warnings[0];

  // PLY element counts beyond the data.
  const std::string ply = replaceOnce(quadPlyAscii(), "element vertex 4", "element vertex 4000000000");
  const std::string ply_path = dir.file("x.ply");
  ASSERT_TRUE(writeFile(ply_path, ply));
  expectError(loadModel(ply_path), ErrorCode::kMalformedInput, ply_path, "4000000000 vertex");

  // Draco connectivity counts of 2^32 - 1 (sequential: points; edgebreaker: vertices). The
  // counts follow the 11-byte header (edgebreaker: after a traversal-type byte).
  const std::string drc_path = dir.file("x.drc");
  for (int method : {draco::MESH_SEQUENTIAL_ENCODING, draco::MESH_EDGEBREAKER_ENCODING}) {
    SCOPED_TRACE(method);
    Bytes drc = encodeDracoQuad(0.0f, method, true).bytes;
    ASSERT_EQ(drc[8], method);
    const size_t at = 12;      // sequential: after the face count; edgebreaker: after the traversal type
    ASSERT_LT(drc[at], 0x80);  // a one-byte varint
    drc.erase(drc.begin() + at);
    drc.insert(drc.begin() + at, {0xff, 0xff, 0xff, 0xff, 0x0f});
    ASSERT_TRUE(writeFile(drc_path, drc));
    expectError(loadModel(drc_path), ErrorCode::kMalformedInput, drc_path, "claims 4294967295 elements");
  }
}

TEST(ModelIo, AssimpAssertionsThrowInsteadOfAborting) {
  // Debian's assimp is built with its internal assertions on; one that fails must throw (so
  // loadModel can return an Error), not abort. With assertions compiled out this call simply
  // fails: the material has no properties.
  aiMaterial material;
  const aiMaterialProperty* property = nullptr;
  try {
    EXPECT_NE(aiGetMaterialProperty(&material, nullptr, 0, 0, &property), AI_SUCCESS);
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("assimp internal check"), std::string::npos) << e.what();
  }
}

// ---- fuzzing --------------------------------------------------------------------------------------

// Loads truncated, random and corrupted versions of `valid` (written as `name` in `dir`, next
// to any side files already there). Each must fail with a one-line message naming the file,
// or load a model that passes validateModel; truncations of binary formats and random bytes
// must fail.
void fuzzFormat(const TempDir& dir, const std::string& name, const Bytes& valid, bool text, size_t header_size) {
  const std::string path = dir.file(name);
  ASSERT_TRUE(writeFile(path, valid));
  auto model = loadModel(path);
  ASSERT_TRUE(model.ok()) << model.error().message;

  std::mt19937 rng(20240607);
  int loaded = 0, failed = 0;
  const auto check = [&](const Bytes& bytes, const std::string& what, bool may_load) {
    ASSERT_TRUE(writeFile(path, bytes));
    auto result = loadModel(path);
    if (result.ok()) {
      ++loaded;
      EXPECT_TRUE(may_load) << name << " " << what << " loaded";
      const Status status = validateModel(*result);
      EXPECT_TRUE(status.ok()) << name << " " << what << ": " << status.error().message;
    } else {
      ++failed;
      const std::string& message = result.error().message;
      EXPECT_NE(message.find(name), std::string::npos) << what << ": " << message;
      EXPECT_GT(message.size(), path.size() + 2) << what;
      EXPECT_EQ(message.find('\n'), std::string::npos) << what << ": " << message;
    }
  };
  std::vector<size_t> lengths = {0, 1, header_size - 1};
  for (size_t i = 0; i < 40; ++i) lengths.push_back(i * valid.size() / 40);
  for (size_t length : lengths) {
    check(Bytes(valid.begin(), valid.begin() + std::min(length, valid.size() - 1)),
          fmt::format("truncated to {}", length), text);
  }
  for (int i = 0; i < 40; ++i) {
    Bytes bytes(1 + rng() % (2 * valid.size()));
    for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng());
    check(bytes, fmt::format("random bytes #{}", i), false);
  }
  for (int i = 0; i < 40; ++i) {
    Bytes bytes = valid;
    const int flips = 1 + static_cast<int>(rng() % 4);
    for (int f = 0; f < flips; ++f) bytes[rng() % bytes.size()] = static_cast<uint8_t>(rng());
    check(bytes, fmt::format("corrupted copy #{}", i), true);
  }
  EXPECT_GT(failed, 0);
  ::testing::Test::RecordProperty(name + "_loaded", loaded);
}

TEST(ModelIoFuzz, Obj) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.mtl"), "newmtl red\nKd 0.5 0.25 1.0\nmap_Kd tex.png\n"));
  ASSERT_TRUE(writeFile(dir.file("tex.png"), pngBytes()));
  fuzzFormat(dir, "fuzz.obj", toBytes(quadObj()), true, 12);
}

TEST(ModelIoFuzz, PlyAscii) {
  TempDir dir("modelio");
  fuzzFormat(dir, "fuzz.ply", toBytes(quadPlyAscii()), true, plyHeader("ascii", true).size());
}

TEST(ModelIoFuzz, PlyBinary) {
  TempDir dir("modelio");
  fuzzFormat(dir, "fuzz.ply", quadPlyBinary(), false, plyHeader("binary_little_endian", true).size());
}

TEST(ModelIoFuzz, Gltf) {
  TempDir dir("modelio");
  ASSERT_TRUE(writeFile(dir.file("quad.bin"), quadBuffer()));
  ASSERT_TRUE(writeFile(dir.file("tex.png"), pngBytes()));
  const std::string json =
      quadGltfJson(fmt::format(R"({{"byteLength":{},"uri":"quad.bin"}})", quadBuffer().size()), R"({"uri":"tex.png"})");
  fuzzFormat(dir, "fuzz.gltf", toBytes(json), true, 1);
}

TEST(ModelIoFuzz, Glb) {
  TempDir dir("modelio");
  fuzzFormat(dir, "fuzz.glb", quadGlb(), false, 12);
}

TEST(ModelIoFuzz, Drc) {
  TempDir dir("modelio");
  fuzzFormat(dir, "fuzz.drc", encodeDracoQuad(0.0f, draco::MESH_EDGEBREAKER_ENCODING, true).bytes, false, 11);
  fuzzFormat(dir, "fuzz_seq.drc", encodeDracoQuad(0.0f, draco::MESH_SEQUENTIAL_ENCODING, true).bytes, false, 11);
}

TEST(ModelIoFuzz, GlbWithDraco) {
  TempDir dir("modelio");
  fuzzFormat(dir, "fuzz.glb", mixedDracoGlb(), false, 12);
}

// ---- blocks and validation --------------------------------------------------------------------

// An n x n grid of unit quads in the z = 0 plane, with one range per triangle and a
// pseudo-random material per triangle out of `materials`.
Model gridModel(int n, int materials, uint32_t seed) {
  Model model;
  for (int y = 0; y <= n; ++y) {
    for (int x = 0; x <= n; ++x) model.positions.insert(model.positions.end(), {float(x), float(y), 0.0f});
  }
  std::mt19937 rng(seed);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 2, d = a + n + 1;
      for (const auto& t : {std::array<uint32_t, 3>{a, b, c}, std::array<uint32_t, 3>{a, c, d}}) {
        model.ranges.push_back({static_cast<uint32_t>(model.indices.size()), 3, static_cast<int>(rng() % materials)});
        model.indices.insert(model.indices.end(), t.begin(), t.end());
      }
    }
  }
  model.materials.resize(materials);
  return model;
}

// Triangles with their materials, in a canonical order.
std::vector<std::array<int64_t, 4>> triangleSet(const Model& model) {
  std::vector<std::array<int64_t, 4>> out;
  for (const DrawRange& r : model.ranges) {
    for (uint32_t i = r.first_index; i < r.first_index + r.index_count; i += 3) {
      out.push_back({model.indices[i], model.indices[i + 1], model.indices[i + 2], r.material});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(ModelIo, BuildBlocksSplitsSpatiallyAndSortsByMaterial) {
  const Model original = gridModel(100, 4, 7);
  Model model = original;
  buildBlocks(model, 100);
  ASSERT_TRUE(validateModel(model).ok()) << validateModel(model).error().message;
  EXPECT_EQ(triangleSet(model), triangleSet(original));
  EXPECT_GE(model.blocks.size(), 200u);
  double area = 0;
  for (const Block& block : model.blocks) {
    EXPECT_GE(block.triangle_count, 1u);
    EXPECT_LE(block.triangle_count, 100u);
    for (uint32_t r = block.first_range + 1; r < block.first_range + block.range_count; ++r) {
      EXPECT_LT(model.ranges[r - 1].material, model.ranges[r].material);
    }
    area += (block.bounds.max[0] - block.bounds.min[0]) * (block.bounds.max[1] - block.bounds.min[1]);
  }
  // Compact blocks: together their bounds cover little more than the 100 x 100 grid.
  EXPECT_LT(area, 2.0 * 100 * 100);
  EXPECT_EQ(model.bounds.min, (std::array<float, 3>{0, 0, 0}));
  EXPECT_EQ(model.bounds.max, (std::array<float, 3>{100, 100, 0}));

  // Deterministic.
  Model again = original;
  buildBlocks(again, 100);
  EXPECT_EQ(again.indices, model.indices);
  ASSERT_EQ(again.ranges.size(), model.ranges.size());
  for (size_t i = 0; i < model.ranges.size(); ++i) {
    EXPECT_EQ(again.ranges[i].first_index, model.ranges[i].first_index);
    EXPECT_EQ(again.ranges[i].material, model.ranges[i].material);
  }

  // 0 keeps one block, with one range per material.
  Model whole = original;
  buildBlocks(whole, 0);
  ASSERT_TRUE(validateModel(whole).ok());
  ASSERT_EQ(whole.blocks.size(), 1u);
  EXPECT_EQ(whole.ranges.size(), 4u);
  EXPECT_EQ(whole.blocks[0].triangle_count, 20000u);
}

TEST(ModelIo, BuildBlocksHandlesManyTriangles) {
  // 500k triangles, all with identical centroids in one corner to exercise ties, plus a grid.
  Model model = gridModel(400, 3, 11);
  const size_t base = model.vertexCount();
  model.positions.insert(model.positions.end(), {0, 0, 0, 1, 0, 0, 0, 1, 0});
  for (int i = 0; i < 180000; ++i) {
    model.ranges.push_back({static_cast<uint32_t>(model.indices.size()), 3, i % 3});
    model.indices.insert(model.indices.end(), {uint32_t(base), uint32_t(base + 1), uint32_t(base + 2)});
  }
  buildBlocks(model, 32768);
  ASSERT_TRUE(validateModel(model).ok()) << validateModel(model).error().message;
  for (const Block& block : model.blocks) EXPECT_LE(block.triangle_count, 32768u);
  EXPECT_EQ(model.triangleCount(), 500000u);
}

TEST(ModelIo, ValidateModelCatchesBrokenInvariants) {
  Model valid = gridModel(4, 2, 3);
  valid.textures.push_back(Texture{"t", 1, 1, {1, 2, 3, 4}});
  valid.materials[1].texture = 0;
  valid.uvs.assign(2 * valid.vertexCount(), 0.5f);
  buildBlocks(valid, 8);
  ASSERT_TRUE(validateModel(valid).ok()) << validateModel(valid).error().message;

  const std::vector<std::pair<std::string, std::function<void(Model&)>>> breakages = {
      {"non-finite position", [](Model& m) { m.positions[4] = NAN; }},
      {"references vertex", [](Model& m) { m.indices[5] = 1000; }},
      {"uv floats", [](Model& m) { m.uvs.pop_back(); }},
      {"colour bytes", [](Model& m) { m.colors.assign(3, 0); }},
      {"references texture", [](Model& m) { m.materials[0].texture = 3; }},
      {"texture 0", [](Model& m) { m.textures[0].rgba.pop_back(); }},
      {"references material", [](Model& m) { m.ranges[0].material = 9; }},
      {"ranges", [](Model& m) { m.ranges[1].first_index = m.ranges[0].first_index; }},
      {"ranges cover", [](Model& m) { m.ranges.back().index_count -= 3; }},
      {"block", [](Model& m) { m.blocks[0].triangle_count += 1; }},
      {"blocks cover", [](Model& m) { m.blocks.pop_back(); }},
      {"outside the bounds", [](Model& m) { m.positions[0] = -5; }},
      {"no triangles", [](Model& m) { m.indices.clear(); }},
      {"no materials", [](Model& m) { m.materials.clear(); }},
  };
  for (const auto& [expected, breakModel] : breakages) {
    Model broken = valid;
    broken.source = "broken.obj";
    breakModel(broken);
    const Status status = validateModel(broken);
    ASSERT_FALSE(status.ok()) << expected;
    EXPECT_EQ(status.error().code, ErrorCode::kMalformedInput);
    EXPECT_EQ(status.error().message.rfind("broken.obj: ", 0), 0u) << status.error().message;
    EXPECT_NE(status.error().message.find(expected), std::string::npos) << status.error().message;
  }

  // transformModel keeps blocks' bounds valid.
  transformModel(valid, {0, 0, 1, 3, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1}, 2.0);
  EXPECT_TRUE(validateModel(valid).ok());
  EXPECT_EQ(valid.bounds.min[0], 3.0f);
  EXPECT_EQ(valid.bounds.max[1], 8.0f);
}

}  // namespace
}  // namespace vkloc
