// Round trips through saveModel and loadModel for every writable format.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/model/model_write.hpp"
#include "vkloc/sim/demo_models.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// A cube with a different RGBA colour at every vertex (alpha not 255), no uvs, no textures.
Model colouredCube() {
  Model m;
  m.source = "cube";
  for (int i = 0; i < 8; ++i) {
    m.positions.insert(m.positions.end(),
                       {float(i & 1) * 2 - 1, float((i >> 1) & 1) * 3 - 1.5f, float(i >> 2) + 0.25f});
    m.colors.insert(m.colors.end(), {uint8_t(30 * i), uint8_t(255 - 20 * i), uint8_t(7 * i + 3), uint8_t(100 + i)});
  }
  // Counter-clockwise seen from outside.
  const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
  m.materials.push_back(Material{"paint", {1, 1, 1, 1}, -1});
  m.ranges.push_back(DrawRange{0, static_cast<uint32_t>(m.indices.size()), 0});
  buildBlocks(m, 32768);
  return m;
}

struct Format {
  const char* name;
  const char* ext;
  bool draco = false;      ///< Draco-compressed glTF.
  bool quantized = false;  ///< Positions and uvs lose precision (Draco).
  bool textures = false;   ///< Materials with textures survive.
  bool alpha = true;       ///< Vertex colour alpha survives.
};

void PrintTo(const Format& f, std::ostream* os) { *os << f.name; }

const Format kFormats[] = {
    {"obj", ".obj", false, false, true, false},      {"ply", ".ply", false, false, false, true},
    {"gltf", ".gltf", false, false, true, true},     {"glb", ".glb", false, false, true, true},
    {"gltf_draco", ".gltf", true, true, true, true}, {"glb_draco", ".glb", true, true, true, true},
    {"drc", ".drc", false, true, false, true},
};

/// Per-corner attributes as sorted value lists: invariant under vertex merging and reordering
/// of vertices, triangles and corners.
struct CornerStats {
  std::vector<float> coord[5];    ///< x, y, z, u, v of every triangle corner, each sorted.
  std::vector<uint32_t> colours;  ///< RGBA of every corner, sorted.
  std::map<int, int> facing;      ///< Triangles whose normal is within 25 deg of +-x/y/z.
};

CornerStats cornerStats(const Model& m, bool keep_alpha) {
  CornerStats s;
  for (uint32_t t = 0; t < m.triangleCount(); ++t) {
    float p[3][3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + k];
      for (int a = 0; a < 3; ++a) p[k][a] = m.positions[3 * v + a], s.coord[a].push_back(p[k][a]);
      if (!m.uvs.empty()) s.coord[3].push_back(m.uvs[2 * v]), s.coord[4].push_back(m.uvs[2 * v + 1]);
      if (!m.colors.empty()) {
        uint32_t c;
        std::memcpy(&c, &m.colors[4 * v], 4);
        if (!keep_alpha) c &= 0x00FFFFFFu;
        s.colours.push_back(c);
      }
    }
    double e1[3], e2[3], n[3];
    for (int a = 0; a < 3; ++a) e1[a] = p[1][a] - p[0][a], e2[a] = p[2][a] - p[0][a];
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int a = 0; a < 3 && len > 0; ++a)
      if (std::abs(n[a]) > 0.9 * len) ++s.facing[n[a] > 0 ? a + 1 : -(a + 1)];
  }
  for (auto& c : s.coord) std::sort(c.begin(), c.end());
  std::sort(s.colours.begin(), s.colours.end());
  return s;
}

/// Largest distance between two equally long sorted lists (infinite when lengths differ).
double maxDifference(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) return INFINITY;
  double d = 0;
  for (size_t i = 0; i < a.size(); ++i) d = std::max(d, std::abs(double(a[i]) - b[i]));
  return d;
}

/// Draco quantization step for `bits` over the model's largest extent.
double dracoStep(const Aabb& box, int bits) {
  double extent = 0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, double(box.max[a]) - box.min[a]);
  return extent / std::ldexp(1.0, bits);
}

/// Draco quantization step for texture coordinates: their largest extent over 2^bits.
double uvStep(const Model& m, int bits) {
  float lo[2] = {1e30f, 1e30f}, hi[2] = {-1e30f, -1e30f};
  for (size_t i = 0; i < m.uvs.size(); ++i)
    lo[i % 2] = std::min(lo[i % 2], m.uvs[i]), hi[i % 2] = std::max(hi[i % 2], m.uvs[i]);
  return std::max(double(hi[0]) - lo[0], double(hi[1]) - lo[1]) / std::ldexp(1.0, bits);
}

void expectRoundTrip(const Model& original, const Format& f, const std::string& path, int draco_speed = 5) {
  SCOPED_TRACE(std::string(f.name) + " " + path);
  ModelWriteOptions options;
  options.draco = f.draco;
  options.draco_speed = draco_speed;
  const Status saved = saveModel(original, path, options);
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  std::vector<std::string> warnings;
  const Result<Model> loaded = loadModel(path, {}, &warnings);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  const Model& m = *loaded;
  EXPECT_TRUE(validateModel(m).ok());
  ASSERT_EQ(m.triangleCount(), original.triangleCount());

  // Positions and texture coordinates: exact for float formats (1e-6 for the 1 - v flips),
  // within one quantization step for Draco.
  const double pos_tol = f.quantized ? dracoStep(original.bounds, options.draco_position_bits) : 1e-6;
  const double uv_tol = f.quantized ? uvStep(original, options.draco_uv_bits) : 1e-6;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(m.bounds.min[a], original.bounds.min[a], pos_tol) << "axis " << a;
    EXPECT_NEAR(m.bounds.max[a], original.bounds.max[a], pos_tol) << "axis " << a;
  }
  const CornerStats a = cornerStats(original, f.alpha), b = cornerStats(m, f.alpha);
  for (int k = 0; k < 3; ++k) EXPECT_LE(maxDifference(a.coord[k], b.coord[k]), pos_tol) << "coordinate " << k;
  if (!original.uvs.empty()) {
    ASSERT_FALSE(m.uvs.empty());
    for (int k = 3; k < 5; ++k) EXPECT_LE(maxDifference(a.coord[k], b.coord[k]), uv_tol) << "uv " << k - 3;
  }
  // Vertex colours are never quantized.
  EXPECT_TRUE(a.colours == b.colours);
  // Winding: as many triangles face each axis direction as before.
  EXPECT_EQ(a.facing, b.facing);

  if (f.textures) {
    // Same texture pixels for every material, found by name.
    std::map<std::string, const Material*> by_name;
    for (const Material& mat : m.materials) by_name[mat.name] = &mat;
    for (const Material& mat : original.materials) {
      if (mat.texture < 0) continue;
      ASSERT_TRUE(by_name.count(mat.name)) << mat.name;
      const Material& got = *by_name[mat.name];
      ASSERT_GE(got.texture, 0) << mat.name;
      const Texture& want = original.textures[mat.texture];
      const Texture& have = m.textures[got.texture];
      EXPECT_EQ(have.width, want.width) << mat.name;
      EXPECT_EQ(have.height, want.height) << mat.name;
      EXPECT_TRUE(have.rgba == want.rgba) << mat.name;
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(got.base_color[k], mat.base_color[k], 1e-6) << mat.name;
    }
  }
}

class ModelRoundTrip : public ::testing::TestWithParam<Format> {};

TEST_P(ModelRoundTrip, DemoRoom) {
  static const Model room = makeDemoRoom();
  test::TempDir dir("vkloc_roundtrip");
  expectRoundTrip(room, GetParam(), dir.file(std::string("room") + GetParam().ext));
}

TEST_P(ModelRoundTrip, ColouredCube) {
  test::TempDir dir("vkloc_roundtrip");
  expectRoundTrip(colouredCube(), GetParam(), dir.file(std::string("cube") + GetParam().ext));
}

INSTANTIATE_TEST_SUITE_P(, ModelRoundTrip, ::testing::ValuesIn(kFormats),
                         [](const ::testing::TestParamInfo<Format>& param_info) {
                           return std::string(param_info.param.name);
                         });

// Every Draco speed: the slow ones predict texture coordinates from the mesh (the predictor
// whose orientation count the loader checks before Draco decodes it), the fast ones by delta.
TEST(ModelRoundTripFiles, DracoDemoRoomAtEverySpeed) {
  static const Model room = makeDemoRoom();
  test::TempDir dir("vkloc_roundtrip");
  for (const Format& f : kFormats) {
    if (!f.quantized) continue;
    for (int speed = 0; speed <= 10; ++speed) {
      SCOPED_TRACE(speed);
      expectRoundTrip(room, f, dir.file(std::string("room") + f.ext), speed);
    }
  }
}

/// The JSON chunk of a GLB file.
json glbJson(const std::vector<uint8_t>& glb) {
  uint32_t header[5];
  if (glb.size() < sizeof(header)) return {};
  std::memcpy(header, glb.data(), sizeof(header));
  if (header[0] != 0x46546C67u || header[1] != 2 || header[2] != glb.size() || header[4] != 0x4E4F534Au) return {};
  return json::parse(glb.begin() + 20, glb.begin() + 20 + header[3]);
}

TEST(ModelRoundTripFiles, GltfFollowsTheSpecLayout) {
  const Model room = makeDemoRoom();
  test::TempDir dir("vkloc_write");
  for (bool draco : {false, true}) {
    SCOPED_TRACE(draco ? "draco" : "plain");
    ModelWriteOptions o;
    o.draco = draco;
    const std::string path = dir.file(draco ? "room_draco.glb" : "room.glb");
    ASSERT_TRUE(saveModel(room, path, o).ok());
    json j = glbJson(test::readFile(path));  // Not const: a missing key reads as null and fails.
    ASSERT_TRUE(j.is_object());
    EXPECT_EQ(j["asset"]["version"], "2.0");
    ASSERT_EQ(j["meshes"].size(), 1u);
    EXPECT_EQ(j["meshes"][0]["primitives"].size(), room.materials.size());  // All used.
    EXPECT_EQ(j["materials"].size(), room.materials.size());
    EXPECT_EQ(j["images"].size(), room.textures.size());
    for (json& sampler : j["samplers"]) {
      EXPECT_EQ(sampler["wrapS"], 10497);
      EXPECT_EQ(sampler["wrapT"], 10497);
    }
    for (json& image : j["images"]) EXPECT_EQ(image["mimeType"], "image/png");
    for (json& p : j["meshes"][0]["primitives"]) {
      json& pos = j["accessors"][p["attributes"]["POSITION"].get<size_t>()];
      EXPECT_EQ(pos["min"].size(), 3u);
      EXPECT_EQ(pos["max"].size(), 3u);
      EXPECT_EQ(j["accessors"][p["indices"].get<size_t>()]["componentType"], 5125);
      json& col = j["accessors"][p["attributes"]["COLOR_0"].get<size_t>()];
      EXPECT_EQ(col["componentType"], 5121);
      EXPECT_EQ(col["normalized"], true);
      EXPECT_TRUE(p["attributes"].contains("TEXCOORD_0"));
      EXPECT_EQ(p["extensions"].contains("KHR_draco_mesh_compression"), draco);
      json& mat = j["materials"][p["material"].get<size_t>()]["pbrMetallicRoughness"];
      EXPECT_EQ(mat["baseColorFactor"].size(), 4u);
      EXPECT_TRUE(mat.contains("baseColorTexture"));
    }
    const bool required =
        j.contains("extensionsRequired") && j["extensionsRequired"] == json::array({"KHR_draco_mesh_compression"});
    EXPECT_EQ(required, draco);
    EXPECT_EQ(j.contains("extensionsUsed"), draco);
  }
  // A .gltf comes with its .bin and one PNG per texture, named after the file.
  ASSERT_TRUE(saveModel(room, dir.file("room.gltf")).ok());
  EXPECT_TRUE(fs::exists(dir.file("room.bin")));
  for (size_t i = 0; i < room.textures.size(); ++i)
    EXPECT_TRUE(fs::exists(dir.file("room_tex" + std::to_string(i) + ".png")));
  // Draco is much smaller.
  EXPECT_LT(fs::file_size(dir.file("room_draco.glb")), fs::file_size(dir.file("room.glb")));
}

TEST(ModelRoundTripFiles, ReplacesFilesWholeAndLeavesNoTemporaries) {
  test::TempDir dir("vkloc_write");
  const std::string path = dir.file("cube.ply");
  ASSERT_TRUE(test::writeFile(path, std::string("old content")));
  ASSERT_TRUE(saveModel(colouredCube(), path).ok());
  EXPECT_NE(test::readFile(path).size(), std::string("old content").size());
  // A failing save leaves the existing file as it was, and no temporary files behind.
  const std::vector<uint8_t> before = test::readFile(path);
  Model broken = colouredCube();
  broken.indices[4] = 1000;
  const Status s = saveModel(broken, path);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(s.error().message.find(path), std::string::npos);
  EXPECT_EQ(test::readFile(path), before);
  size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) entries += e.is_regular_file();
  EXPECT_EQ(entries, 1u);
}

TEST(ModelRoundTripFiles, ReportsBadPathsOptionsAndFormats) {
  test::TempDir dir("vkloc_write");
  const Model cube = colouredCube();
  const std::string missing_dir = dir.file("no/such/dir/cube.glb");
  Status s = saveModel(cube, missing_dir);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kIoError);
  EXPECT_NE(s.error().message.find(missing_dir), std::string::npos);

  s = saveModel(cube, dir.file("cube.xyz"));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kUnsupported);

  ModelWriteOptions bad;
  bad.draco_position_bits = 0;
  s = saveModel(cube, dir.file("cube.drc"), bad);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  // Past 24 bits Draco's entropy coder asks for up to 4 GiB (a fuzz finding).
  bad.draco_position_bits = 25;
  s = saveModel(cube, dir.file("cube.drc"), bad);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("1..24"), std::string::npos) << s.error().message;

  s = saveModel(Model{}, dir.file("empty.obj"));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(ModelRoundTripFiles, DracoRefusesCoordinatesWhoseRangeOverflowsAFloat) {
  test::TempDir dir("vkloc_write_range");
  // x from -2e38 to 2e38: max - min overflows float, which crashed Draco's encoder (a fuzz
  // finding); the other formats store it.
  Model wide;
  wide.source = "wide";
  wide.positions = {-2e38f, 0, 0, 2e38f, 0, 0, 0, 1e38f, 0};
  wide.indices = {0, 1, 2};
  wide.materials.push_back(Material{"paint", {1, 1, 1, 1}, -1});
  wide.ranges.push_back(DrawRange{0, 3, 0});
  buildBlocks(wide, 32768);
  const std::string path = dir.file("wide.drc");
  const Status s = saveModel(wide, path);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(s.error().message.find("position x spans -2e+38 to 2e+38, more than a float holds"), std::string::npos)
      << s.error().message;
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(saveModel(wide, dir.file("wide.ply")).ok());
}

TEST(ModelRoundTripFiles, DracoRefusesToWriteWhatItsQuantizationCollapses) {
  test::TempDir dir("vkloc_write_collapse");
  // One sliver 1e-5 high on a base 1 long: it has an area (load accepts it), but 14-bit
  // quantization of its bounds (steps of 1/16383) puts all three corners on one line.
  Model sliver;
  sliver.source = "sliver";
  sliver.positions = {0, 0, 0, 1, 0, 0, 0.5f, 1e-5f, 0};
  sliver.indices = {0, 1, 2};
  sliver.materials.push_back(Material{"paint", {1, 1, 1, 1}, -1});
  sliver.ranges.push_back(DrawRange{0, 3, 0});
  buildBlocks(sliver, 32768);
  ASSERT_TRUE(saveModel(sliver, dir.file("sliver.ply")).ok());
  const std::string path = dir.file("sliver.drc");
  const Status s = saveModel(sliver, path);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(s.error().message.find("collapses every triangle"), std::string::npos) << s.error().message;
  EXPECT_FALSE(fs::exists(path));
  ModelWriteOptions fine;
  fine.draco_position_bits = 24;
  ASSERT_TRUE(saveModel(sliver, path, fine).ok());
  EXPECT_TRUE(loadModel(path).ok());
}

}  // namespace
}  // namespace vkloc
