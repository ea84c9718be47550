// ViSP data: the .cao parser on hand-written files, pose and camera XML readers, and the import
// of visp-images-data's mbt-depth/Castle-simu, whose ground truth must put the model's edges on
// the image's edges (and a slightly wrong pose must not).
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "support/test_support.hpp"
#include "vkloc/io/import.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/model/cao.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/render/cpu_renderer.hpp"
#include "vkloc/render/renderer.hpp"

namespace vkloc {
namespace {

using test::TempDir;
using test::writeFile;

std::string castleFolder() {
  const char* env = std::getenv("VKLOC_VISP_CASTLE");
  return env ? env : "/usr/share/visp-images-data/ViSP-images/mbt-depth/Castle-simu";
}

bool castleAvailable() { return std::filesystem::is_directory(castleFolder() + "/Images"); }

#define SKIP_WITHOUT_CASTLE()                                                         \
  if (!castleAvailable())                                                             \
  GTEST_SKIP() << castleFolder()                                                      \
               << " is missing: install the Debian package visp-images-data (or set " \
                  "VKLOC_VISP_CASTLE)"

double triangleArea(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

/// Total area of a model's triangles and their area-weighted mean normal direction.
double modelArea(const Model& m, Eigen::Vector3d* normal_sum = nullptr) {
  double area = 0.0;
  if (normal_sum) normal_sum->setZero();
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) {
      const float* v = &m.positions[3 * m.indices[3 * t + k]];
      p[k] = Eigen::Vector3d(v[0], v[1], v[2]);
    }
    area += triangleArea(p[0], p[1], p[2]);
    if (normal_sum) *normal_sum += 0.5 * (p[1] - p[0]).cross(p[2] - p[0]);
  }
  return area;
}

// ---- .cao parser ------------------------------------------------------------------------------

TEST(CaoParser, PointsLinesAndBothFaceKinds) {
  TempDir dir("visp");
  // A unit square (z = 0) as a face from lines, and a triangle (z = 1) as a face from points;
  // one stand-alone 3D line. Comments everywhere, names and useLod attributes.
  const std::string path = dir.file("shapes.cao");
  ASSERT_TRUE(writeFile(path,
                        "# header comment\n"
                        "V1\n"
                        "# points\n"
                        "8   # count\n"
                        "0 0 0\n1 0 0  # trailing\n1 1 0\n0 1 0\n"
                        "0 0 1\n2 0 1\n0 2 1\n"
                        "5 5 5\n"
                        "# lines\n"
                        "5\n"
                        "0 1 name=a\n1 2\n3 2\n3 0 useLod=true\n"
                        "6 7 name=free_line\n"
                        "# faces from lines (line 2 is reversed on purpose)\n"
                        "1\n"
                        "4 0 1 2 3 name=square\n"
                        "# faces from points\n"
                        "1\n"
                        "3 4 5 6 name=tri useLod=false\n"
                        "0\n"
                        "0\n"));
  std::vector<std::string> warnings;
  auto cao = parseCaoFile(path, &warnings);
  ASSERT_TRUE(cao.ok()) << cao.error().message;
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(cao->points.size(), 8u);
  EXPECT_EQ(cao->points[7], Eigen::Vector3d(5, 5, 5));
  ASSERT_EQ(cao->faces.size(), 2u);
  EXPECT_EQ(cao->faces[0], (std::vector<uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(cao->faces[1], (std::vector<uint32_t>{4, 5, 6}));
  EXPECT_EQ(cao->face_names, (std::vector<std::string>{"square", "tri"}));
  // 4 square edges + the free line + 3 triangle edges.
  EXPECT_EQ(cao->segments.size(), 8u);

  auto model = caoToModel(*cao, path);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_EQ(model->triangleCount(), 3u);
  Eigen::Vector3d n;
  EXPECT_NEAR(modelArea(*model, &n), 1.0 + 2.0, 1e-6);
  // Both loops are counter-clockwise seen from +z: the normals keep that.
  EXPECT_NEAR(n.z(), 3.0, 1e-6);
  ASSERT_EQ(model->materials.size(), 1u);
  EXPECT_FLOAT_EQ(model->materials[0].base_color[0], 0.5f);
  EXPECT_TRUE(validateModel(*model).ok());
}

TEST(CaoParser, LoadWithTransformRelativePathAndNoHeader) {
  TempDir dir("visp");
  std::filesystem::create_directories(dir.path() / "parts");
  // The part: a unit right triangle in z = 0, no version header, old style (no cylinder section).
  ASSERT_TRUE(writeFile(dir.file("parts/tri.cao"), "3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n1\n3 0 1 2\n"));
  ASSERT_TRUE(writeFile(dir.file("top.cao"),
                        "V1\n"
                        "load(\"parts/tri.cao\", t=[1; 2; 3], tu=[0; 0; 90deg])\n"
                        "load(\"parts/tri.cao\", t=(0.5, 0, 0))\n"
                        "0\n0\n0\n0\n0\n0\n"));
  auto cao = parseCaoFile(dir.file("top.cao"));
  ASSERT_TRUE(cao.ok()) << cao.error().message;
  ASSERT_EQ(cao->points.size(), 6u);
  // First include: rotate 90 deg about z then translate: (1,0,0) -> (0,1,0) + (1,2,3).
  EXPECT_LT((cao->points[0] - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);
  EXPECT_LT((cao->points[1] - Eigen::Vector3d(1, 3, 3)).norm(), 1e-12);
  EXPECT_LT((cao->points[2] - Eigen::Vector3d(0, 2, 3)).norm(), 1e-12);
  EXPECT_LT((cao->points[4] - Eigen::Vector3d(1.5, 0, 0)).norm(), 1e-12);
  ASSERT_EQ(cao->faces.size(), 2u);
  EXPECT_EQ(cao->faces[1], (std::vector<uint32_t>{3, 4, 5}));

  // Radian angles and a self-include (skipped with a warning).
  ASSERT_TRUE(writeFile(dir.file("self.cao"),
                        "V1\nload(\"self.cao\")\nload(\"parts/tri.cao\", tu=[3.14159265358979; 0; 0])\n"
                        "0\n0\n0\n0\n"));
  std::vector<std::string> warnings;
  auto self = parseCaoFile(dir.file("self.cao"), &warnings);
  ASSERT_TRUE(self.ok()) << self.error().message;
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("includes itself"), std::string::npos) << warnings[0];
  EXPECT_LT((self->points[2] - Eigen::Vector3d(0, -1, 0)).norm(), 1e-9);
}

TEST(CaoParser, ConcaveFaceTriangulatesWithTheRightArea) {
  // An L, a comb and a star, all concave, in a tilted plane; the oracle is the shoelace area.
  const std::vector<Eigen::Vector2d> shapes[] = {
      {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}},
      {{0, 0}, {5, 0}, {5, 3}, {4, 3}, {4, 1}, {3, 1}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}},
      // A star: strongly concave.
      {{0, 3}, {-1, 1}, {-3, 1}, {-1.5, -0.5}, {-2, -3}, {0, -1.5}, {2, -3}, {1.5, -0.5}, {3, 1}, {1, 1}},
  };
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (const auto& shape : shapes) {
    double shoelace = 0.0;
    for (size_t i = 0; i < shape.size(); ++i) {
      const auto& a = shape[i];
      const auto& b = shape[(i + 1) % shape.size()];
      shoelace += 0.5 * (a.x() * b.y() - b.x() * a.y());
    }
    ASSERT_GT(shoelace, 0.0);
    std::vector<Eigen::Vector3d> loop;
    for (const auto& p : shape) loop.push_back(R * Eigen::Vector3d(p.x(), p.y(), 0.0) + Eigen::Vector3d(1, 2, 3));
    const std::vector<uint32_t> tri = triangulatePolygon(loop);
    // n - 2 triangles, fewer when clipping leaves collinear vertices (dropped, zero area).
    ASSERT_GE(tri.size(), 3u);
    ASSERT_LE(tri.size(), 3 * (shape.size() - 2));
    ASSERT_EQ(tri.size() % 3, 0u);
    double area = 0.0;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (size_t t = 0; t < tri.size(); t += 3) {
      const Eigen::Vector3d e = (loop[tri[t + 1]] - loop[tri[t]]).cross(loop[tri[t + 2]] - loop[tri[t]]);
      // Every triangle has the polygon's orientation (+z of the shape plane, rotated).
      EXPECT_GT(e.dot(R.col(2)), 0.0);
      area += 0.5 * e.norm();
      n += 0.5 * e;
    }
    EXPECT_NEAR(area, shoelace, 1e-9);
    EXPECT_NEAR(n.dot(R.col(2)), shoelace, 1e-9);
    // Reversed loop: same area, triangles flipped.
    std::vector<Eigen::Vector3d> reversed(loop.rbegin(), loop.rend());
    const std::vector<uint32_t> rtri = triangulatePolygon(reversed);
    double rn = 0.0;
    for (size_t t = 0; t < rtri.size(); t += 3) {
      rn += 0.5 *
            (reversed[rtri[t + 1]] - reversed[rtri[t]]).cross(reversed[rtri[t + 2]] - reversed[rtri[t]]).dot(R.col(2));
    }
    EXPECT_NEAR(rn, -shoelace, 1e-9);
  }
  // Degenerate loops give nothing.
  EXPECT_TRUE(triangulatePolygon({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}).empty());
  EXPECT_TRUE(triangulatePolygon({{0, 0, 0}, {1, 0, 0}}).empty());
}

TEST(CaoParser, CylindersAndCirclesAreTessellated) {
  TempDir dir("visp");
  const std::string path = dir.file("round.cao");
  ASSERT_TRUE(writeFile(path,
                        "V1\n4\n0 0 0\n0 0 2\n1 0 0\n0 1 0\n0\n0\n0\n"
                        "1\n0 1 0.5 name=tube\n"
                        "1\n0.25 0 2 3\n"));
  std::vector<std::string> warnings;
  auto model = loadCaoModel(path, &warnings);
  ASSERT_TRUE(model.ok()) << model.error().message;
  EXPECT_EQ(warnings.size(), 2u);
  // 32-gon tube side area 2 * 32 * r sin(pi/32) * h, disc 32/2 * r^2 sin(2 pi / 32).
  const double tube = 2 * 32 * 0.5 * std::sin(M_PI / 32) * 2.0;
  const double disc = 16 * 0.25 * 0.25 * std::sin(2 * M_PI / 32);
  EXPECT_NEAR(modelArea(*model), tube + disc, 1e-5);
  // Tube normals point away from the axis.
  for (size_t t = 0; t < 64; ++t) {
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) {
      const float* v = &model->positions[3 * model->indices[3 * t + k]];
      p[k] = Eigen::Vector3d(v[0], v[1], v[2]);
    }
    const Eigen::Vector3d c = (p[0] + p[1] + p[2]) / 3.0;
    const Eigen::Vector3d radial(c.x(), c.y(), 0.0);
    if (radial.norm() < 0.3) continue;  // A disc triangle.
    EXPECT_GT((p[1] - p[0]).cross(p[2] - p[0]).dot(radial), 0.0);
  }
}

TEST(CaoParser, MalformedFilesNameFileAndLine) {
  TempDir dir("visp");
  struct Case {
    std::string text;
    int line;
    std::string what;
  };
  const Case cases[] = {
      {"V1\n3\n0 0 0\n1 0\n0 1 0\n0\n0\n1\n3 0 1 2\n", 4, "three finite numbers"},
      {"V1\n3\n0 0 0\n1 0 nan\n0 1 0\n0\n0\n1\n3 0 1 2\n", 4, "three finite numbers"},
      {"V1\nthree\n", 2, "number of points"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n1\n3 0 1 3\n", 9, "point index 3"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n1\n3 0 -1 2\n", 9, "not a point index"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n1\n2 0 1\n", 9, "at least 3"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n1\n4 0 1 2\n", 9, "expected 4 point indices"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n1\n0 7\n0\n0\n", 7, "point index 7"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n1\n0 1\n1\n3 0 1 5\n0\n", 9, "line index"},
      {"V9\n", 1, "version"},
      {"V1\nload(parts.cao)\n", 2, "quoted file name"},
      {"V1\nload(\"missing.cao\")\n", 2, "not found"},
      {"V1\nload(\"x.cao\", t=[1; 2])\n", 2, "t= needs three numbers"},
      {"V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n0\n1\n0 1 -2\n", 10, "radius"},
      {"V1\n2000000\n", 2, "more than"},
  };
  for (const Case& c : cases) {
    const std::string path = dir.file("bad.cao");
    ASSERT_TRUE(writeFile(path, c.text));
    auto r = loadCaoModel(path);
    ASSERT_FALSE(r.ok()) << c.text;
    EXPECT_EQ(r.error().code, ErrorCode::kMalformedInput) << r.error().message;
    EXPECT_NE(r.error().message.find(fmt::format("{}:{}:", path, c.line)), std::string::npos)
        << r.error().message << "\nfor:\n"
        << c.text;
    EXPECT_NE(r.error().message.find(c.what), std::string::npos) << r.error().message;
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
  }
  // Truncated: names the file.
  ASSERT_TRUE(writeFile(dir.file("short.cao"), "V1\n3\n0 0 0\n"));
  auto r = loadCaoModel(dir.file("short.cao"));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("short.cao: unexpected end of file"), std::string::npos) << r.error().message;
  // Missing file.
  auto missing = loadCaoModel(dir.file("nothing.cao"));
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  // Points only: nothing to triangulate.
  ASSERT_TRUE(writeFile(dir.file("points.cao"), "V1\n3\n0 0 0\n1 0 0\n0 1 0\n0\n0\n0\n"));
  auto empty = loadCaoModel(dir.file("points.cao"));
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("no faces"), std::string::npos) << empty.error().message;
}

TEST(CaoParser, RandomBytesAndMutationsNeverCrash) {
  TempDir dir("visp");
  const std::string good =
      "V1\n6\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n4\n0 1\n1 2\n2 3\n3 0\n1\n4 0 1 2 3\n2\n3 0 1 4\n"
      "3 1 5 4 name=x\n1\n0 4 0.1\n1\n0.2 0 1 3\n";
  ASSERT_TRUE(loadCaoModel([&] {
                const std::string p = dir.file("good.cao");
                writeFile(p, good);
                return p;
              }())
                  .ok());
  std::mt19937 rng(1234);
  const std::string alphabet = "0123456789 \n#.-eVload(\"=[];,x";
  for (int iter = 0; iter < 150; ++iter) {
    std::string text;
    if (iter % 3 == 0) {
      const size_t n = rng() % 400;
      for (size_t i = 0; i < n; ++i) text.push_back(static_cast<char>(rng() & 0xff));
    } else if (iter % 3 == 1) {
      const size_t n = rng() % 300;
      for (size_t i = 0; i < n; ++i) text.push_back(alphabet[rng() % alphabet.size()]);
    } else {
      text = good;
      for (int m = 0; m < 4; ++m) text[rng() % text.size()] = alphabet[rng() % alphabet.size()];
      text.resize(rng() % (text.size() + 1));
    }
    const std::string path = dir.file("fuzz.cao");
    ASSERT_TRUE(writeFile(path, text));
    auto r = loadCaoModel(path);
    if (r.ok()) {
      EXPECT_TRUE(validateModel(*r).ok());
    } else {
      EXPECT_EQ(r.error().message.find('\n'), std::string::npos);
    }
  }
}

// ---- pose and camera files ---------------------------------------------------------------------

TEST(VispFiles, PoseReader) {
  TempDir dir("visp");
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, -1, 0.5).normalized()).toRotationMatrix();
  std::string text;
  for (int r = 0; r < 3; ++r) {
    text += fmt::format("{:.9f} {:.9f} {:.9f} {}\n", R(r, 0), R(r, 1), R(r, 2), 0.1 * (r + 1));
  }
  text += "0 0 0 1\n";
  ASSERT_TRUE(writeFile(dir.file("pose.txt"), text));
  auto T = loadVispPose(dir.file("pose.txt"));
  ASSERT_TRUE(T.ok()) << T.error().message;
  EXPECT_LT((T->linear() - R).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((T->translation() - Eigen::Vector3d(0.1, 0.2, 0.3)).norm(), 1e-15);
  EXPECT_TRUE(isValidPose(*T));

  const std::pair<std::string, std::string> bad[] = {
      {"1 0 0 0\n0 1 0 0\n0 0 1 0\n", "16 numbers"},
      {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n", "last row"},
      {"2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "orthonormal"},
      {"-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "orthonormal"},
      {"1 0 0 0\n0 1 0 x\n0 0 1 0\n0 0 0 1\n", "not a finite number"},
      {"1 0 0 0\n0 1 0 inf\n0 0 1 0\n0 0 0 1\n", "not a finite number"},
  };
  for (const auto& [content, what] : bad) {
    ASSERT_TRUE(writeFile(dir.file("bad.txt"), content));
    auto r = loadVispPose(dir.file("bad.txt"));
    ASSERT_FALSE(r.ok()) << content;
    EXPECT_NE(r.error().message.find("bad.txt"), std::string::npos);
    EXPECT_NE(r.error().message.find(what), std::string::npos) << r.error().message;
  }
  EXPECT_EQ(loadVispPose(dir.file("none.txt")).error().code, ErrorCode::kNotFound);
}

TEST(VispFiles, CameraXmlReader) {
  TempDir dir("visp");
  // Model-based tracker configuration style.
  ASSERT_TRUE(writeFile(dir.file("mbt.xml"),
                        "<?xml version=\"1.0\"?>\n<conf>\n <!-- <px>1</px> -->\n <camera>\n  <px>700.5</px>\n"
                        "  <py>701</py>\n  <u0>320</u0>\n  <v0> 240.25 </v0>\n </camera>\n</conf>\n"));
  auto c = loadVispCameraXml(dir.file("mbt.xml"), 640, 480);
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->fx, 700.5);
  EXPECT_EQ(c->fy, 701.0);
  EXPECT_EQ(c->cx, 320.0);
  EXPECT_EQ(c->cy, 240.25);
  EXPECT_EQ(c->width, 640);
  EXPECT_EQ(c->height, 480);
  // vpXmlParserCamera style: the model without distortion is preferred; size from the file.
  ASSERT_TRUE(writeFile(dir.file("cam.xml"),
                        "<root><camera><name>Camera</name><image_width>800</image_width>"
                        "<image_height>600</image_height>"
                        "<model><type>perspectiveProjWithDistortion</type><px>1</px><py>2</py><u0>3</u0>"
                        "<v0>4</v0><kud>0.1</kud><kdu>-0.1</kdu></model>"
                        "<model><type>perspectiveProjWithoutDistortion</type><px>600</px><py>610</py>"
                        "<u0>400</u0><v0>300</v0></model></camera></root>"));
  auto v = loadVispCameraXml(dir.file("cam.xml"));
  ASSERT_TRUE(v.ok()) << v.error().message;
  EXPECT_EQ(v->fx, 600.0);
  EXPECT_EQ(v->fy, 610.0);
  EXPECT_EQ(v->cx, 400.0);
  EXPECT_EQ(v->cy, 300.0);
  EXPECT_EQ(v->width, 800);
  EXPECT_EQ(v->height, 600);

  ASSERT_TRUE(writeFile(dir.file("nopy.xml"), "<conf><camera><px>700</px><u0>1</u0><v0>1</v0></camera></conf>"));
  auto r = loadVispCameraXml(dir.file("nopy.xml"), 640, 480);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("nopy.xml: no <py>"), std::string::npos) << r.error().message;
  ASSERT_TRUE(writeFile(dir.file("badpx.xml"), "<camera><px>7e</px><py>1</py><u0>1</u0><v0>1</v0></camera>"));
  EXPECT_NE(loadVispCameraXml(dir.file("badpx.xml"), 640, 480).error().message.find("<px> '7e'"), std::string::npos);
  EXPECT_NE(loadVispCameraXml(dir.file("mbt.xml")).error().message.find("image_width"), std::string::npos);
}

// ---- Castle-simu ------------------------------------------------------------------------------

/// The imported Castle-simu sequence, shared by the tests below (importing takes ~1 s).
class CastleSimu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!castleAvailable()) return;
    dir_ = new TempDir("visp_castle");
    VispImportReport report;
    auto seq = importVispSequence(castleFolder(), (dir_->path() / "seq").string(), {}, &report);
    ASSERT_TRUE(seq.ok()) << seq.error().message;
    report_ = new VispImportReport(report);
    auto loaded = loadSequence((dir_->path() / "seq").string());
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    sequence_ = new Sequence(std::move(loaded).value());
    auto model = loadModel(sequence_->modelPath());
    ASSERT_TRUE(model.ok()) << model.error().message;
    model_ = new Model(std::move(model).value());
    // Edges to check, from the .cao files directly (independent of the written model).
    auto castle = parseCaoFile(castleFolder() + "/Models/chateau.cao");
    ASSERT_TRUE(castle.ok()) << castle.error().message;
    castle_edges_ = new CaoModel(std::move(castle).value());
    auto cube = parseCaoFile(castleFolder() + "/Models/cube.cao");
    ASSERT_TRUE(cube.ok()) << cube.error().message;
    cube_edges_ = new CaoModel(std::move(cube).value());
  }
  static void TearDownTestSuite() {
    delete castle_edges_;
    delete cube_edges_;
    delete model_;
    delete sequence_;
    delete report_;
    delete dir_;
  }
  void SetUp() override {
    SKIP_WITHOUT_CASTLE();
    ASSERT_NE(model_, nullptr);
  }

  /// Distance (pixels) from every pixel to the nearest Canny edge of image `index`.
  static cv::Mat edgeDistance(size_t index) {
    const cv::Mat gray = cv::imread(sequence_->imagePath(index), cv::IMREAD_GRAYSCALE);
    EXPECT_FALSE(gray.empty()) << sequence_->imagePath(index);
    cv::Mat edges, not_edges, distance;
    cv::Canny(gray, edges, 30, 90);
    cv::bitwise_not(edges, not_edges);
    cv::distanceTransform(not_edges, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    return distance;
  }

  struct Score {
    size_t samples = 0;  ///< Visible samples inside the image.
    size_t near = 0;     ///< Of which within kTolerancePx of an image edge.
    double fraction() const { return samples ? static_cast<double>(near) / samples : 0.0; }
  };
  static constexpr double kTolerancePx = 1.5;

  /// Projects points every ~1 px along the segments of `edges` (mapped by T_world_edges) with
  /// T_world_camera; counts those that are visible (depth test against `depth`, rendered at the
  /// true pose) and how many lie within kTolerancePx of an image edge.
  static Score score(const CaoModel& edges, const Pose& T_world_edges, const Pose& T_world_camera,
                     const ImageF32& depth, const cv::Mat& distance) {
    const PinholeCamera& cam = sequence_->camera.intrinsics;
    const Pose T_camera_world = T_world_camera.inverse();
    auto project = [&](const Eigen::Vector3d& p_c) {
      return Eigen::Vector2d(cam.fx * p_c.x() / p_c.z() + cam.cx, cam.fy * p_c.y() / p_c.z() + cam.cy);
    };
    Score s;
    for (const auto& seg : edges.segments) {
      const Eigen::Vector3d a = T_camera_world * (T_world_edges * edges.points[seg[0]]);
      const Eigen::Vector3d b = T_camera_world * (T_world_edges * edges.points[seg[1]]);
      if (a.z() < 0.02 || b.z() < 0.02) continue;
      const int steps = std::max(2, static_cast<int>((project(a) - project(b)).norm()));
      for (int k = 1; k < steps; ++k) {  // Endpoints skipped: corners are ambiguous.
        const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / steps);
        const Eigen::Vector2d uv = project(p);
        const int x = static_cast<int>(std::lround(uv.x())), y = static_cast<int>(std::lround(uv.y()));
        if (x < 3 || y < 3 || x >= cam.width - 3 || y >= cam.height - 3) continue;
        // Visible when a neighbouring pixel is background or shows a surface at least as far.
        bool visible = false;
        for (int dy = -1; dy <= 1 && !visible; ++dy) {
          for (int dx = -1; dx <= 1 && !visible; ++dx) {
            const float d = depth.at(x + dx, y + dy);
            visible = d == kBackgroundDepth || d >= p.z() - (0.002 + 0.01 * p.z());
          }
        }
        if (!visible) continue;
        ++s.samples;
        if (distance.at<float>(y, x) <= kTolerancePx) ++s.near;
      }
    }
    return s;
  }

  static TempDir* dir_;
  static VispImportReport* report_;
  static Sequence* sequence_;
  static Model* model_;
  static CaoModel* castle_edges_;
  static CaoModel* cube_edges_;
};
TempDir* CastleSimu::dir_ = nullptr;
VispImportReport* CastleSimu::report_ = nullptr;
Sequence* CastleSimu::sequence_ = nullptr;
Model* CastleSimu::model_ = nullptr;
CaoModel* CastleSimu::castle_edges_ = nullptr;
CaoModel* CastleSimu::cube_edges_ = nullptr;

TEST_F(CastleSimu, ImportWritesTheSequence) {
  EXPECT_EQ(report_->frames, 40u);
  EXPECT_EQ(report_->poses, 40u);
  // Castle: the 6-point floor (4 triangles) and 4 tower quads; cube: 4 quads.
  EXPECT_EQ(report_->triangles, 20u);
  EXPECT_EQ(report_->cube_triangles, 8u);
  EXPECT_EQ(model_->triangleCount(), 20u);
  ASSERT_EQ(sequence_->images.size(), 40u);
  ASSERT_EQ(sequence_->groundtruth.size(), 40u);
  EXPECT_EQ(sequence_->images[0].t_ns, 0);
  EXPECT_EQ(sequence_->images[30].t_ns, 1000000000);  // 30 Hz.
  const PinholeCamera& c = sequence_->camera.intrinsics;
  EXPECT_EQ(c.fx, 700.0);
  EXPECT_EQ(c.fy, 700.0);
  EXPECT_EQ(c.cx, 320.0);
  EXPECT_EQ(c.cy, 240.0);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  // Ground truth is the inverse of the ViSP file: T_world_camera * cMo = identity.
  auto cMo = loadVispPose(castleFolder() + "/CameraPose/Camera_020.txt");
  ASSERT_TRUE(cMo.ok());
  const Pose product = sequence_->groundtruth[19].T_world_camera * *cMo;
  EXPECT_LT((product.matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-7);
  // Images are the source pixels.
  const cv::Mat src = cv::imread(castleFolder() + "/Images/Image_0020.pgm", cv::IMREAD_GRAYSCALE);
  const cv::Mat out = cv::imread(sequence_->imagePath(19), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(src.empty());
  ASSERT_EQ(out.size(), src.size());
  EXPECT_EQ(cv::norm(src, out, cv::NORM_INF), 0.0);
  // Errors: missing folder, one line naming it.
  auto missing = importVispSequence(castleFolder() + "/nothing", (dir_->path() / "x").string());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kNotFound);
  EXPECT_NE(missing.error().message.find("nothing"), std::string::npos);
}

TEST_F(CastleSimu, GroundTruthPutsModelEdgesOnImageEdges) {
  const Pose T_object_cube = VispImportOptions::defaultCastleCubePose();
  for (const size_t frame : {0u, 19u, 39u}) {
    const Pose& T_world_camera = sequence_->groundtruth[frame].T_world_camera;
    RenderSettings settings;
    settings.near_m = 0.01;
    settings.outputs = kRenderDepth;
    auto view = renderReference(*model_, sequence_->camera.intrinsics, T_world_camera, settings);
    ASSERT_TRUE(view.ok()) << view.error().message;
    const cv::Mat distance = edgeDistance(frame);

    Score truth = score(*castle_edges_, Pose::Identity(), T_world_camera, view->depth, distance);
    const Score cube = score(*cube_edges_, T_object_cube, T_world_camera, view->depth, distance);
    truth.samples += cube.samples;
    truth.near += cube.near;
    // Perturbed: 1 cm along the camera's x axis; 1 degree about its y axis.
    Pose shifted = T_world_camera;
    shifted.translate(Eigen::Vector3d(0.01, 0, 0));
    Pose turned = T_world_camera;
    turned.rotate(Eigen::AngleAxisd(M_PI / 180.0, Eigen::Vector3d::UnitY()));
    const Score s1 = score(*castle_edges_, Pose::Identity(), shifted, view->depth, distance);
    const Score s2 = score(*castle_edges_, Pose::Identity(), turned, view->depth, distance);
    // The other reading of the cube's transform (cube-from-object).
    const Score cube_inverse = score(*cube_edges_, T_object_cube.inverse(), T_world_camera, view->depth, distance);
    std::printf(
        "frame %zu: %zu visible edge samples, %.1f %% within %.1f px (cube %.1f %% of %zu; cube placed with the "
        "inverse transform %.1f %%); pose +1 cm: %.1f %%, +1 deg: %.1f %%\n",
        frame + 1, truth.samples, 100 * truth.fraction(), kTolerancePx, 100 * cube.fraction(), cube.samples,
        100 * cube_inverse.fraction(), 100 * s1.fraction(), 100 * s2.fraction());
    EXPECT_GT(truth.samples, 300u);
    EXPECT_GE(truth.fraction(), 0.8) << "frame " << frame + 1;
    EXPECT_GE(cube.fraction(), 0.8) << "frame " << frame + 1;
    EXPECT_LT(cube_inverse.fraction(), cube.fraction() - 0.3) << "frame " << frame + 1;
    EXPECT_LT(s1.fraction(), truth.fraction() - 0.3) << "frame " << frame + 1;
    EXPECT_LT(s2.fraction(), truth.fraction() - 0.3) << "frame " << frame + 1;
  }
}

}  // namespace
}  // namespace vkloc
