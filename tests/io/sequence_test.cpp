// Sequence folder format: round trips, malformed input, importers of TUM RGB-D and EuRoC folders.
#include "vkloc/io/sequence.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <string>

#include "support/test_support.hpp"
#include "vkloc/core/camera.hpp"
#include "vkloc/io/import.hpp"

namespace vkloc {
namespace {

namespace fs = std::filesystem;
using test::TempDir;
using test::writeFile;

Pose randomPose(std::mt19937& rng, double translation_range = 100.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-translation_range, translation_range);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  Pose T = Pose::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return T;
}

/// Checks code and that the message starts with "file:line:".
template <typename R>
void expectLineError(const R& result, const std::string& path, int line, const std::string& contains = "") {
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.error().code, ErrorCode::kMalformedInput) << result.error().message;
  const std::string prefix = path + ":" + std::to_string(line) + ":";
  EXPECT_EQ(result.error().message.rfind(prefix, 0), 0u) << result.error().message << " (expected " << prefix << ")";
  EXPECT_EQ(result.error().message.find('\n'), std::string::npos);
  if (!contains.empty()) {
    EXPECT_NE(result.error().message.find(contains), std::string::npos) << result.error().message;
  }
}

Sequence makeSequence(std::mt19937& rng) {
  Sequence s;
  s.name = "test: \"quoted\" # not a comment";
  s.model = "models/city block.glb";
  s.T_world_model = randomPose(rng);
  s.unit_scale = 0.01;
  s.initial_T_world_camera = randomPose(rng);
  s.gravity_world = Eigen::Vector3d(0.1, -0.2, -9.80665);
  s.camera.model = "pinhole";
  s.camera.intrinsics = PinholeCamera{458.654, 457.296, 367.215, 248.375, 752, 480};
  s.camera.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  s.camera.T_body_camera = randomPose(rng, 0.5);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  int64_t t = 1403636579763555584;
  for (int i = 0; i < 20; ++i) {
    t += 50000000 + i;  // Not multiples of 1 us: all 9 decimals matter.
    s.images.push_back({t, "cam0/" + std::to_string(t) + ".png"});
    s.groundtruth.push_back({t + 3, randomPose(rng)});
  }
  s.images.push_back({t + 1, "/absolute/path with space.png"});
  for (int i = 0; i < 100; ++i) {
    ImuSample m;
    m.t_ns = 1403636579758555392 + i * 5000001LL;
    m.gyro_body = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 1e-3;
    m.accel_body = Eigen::Vector3d(u(rng), 1e-300 * u(rng), u(rng) * 1e200);
    s.imu.push_back(m);
  }
  ImuNoise noise;
  noise.rate_hz = 200.0;
  noise.gyro_noise_density = 1.6968e-04;
  s.imu_noise = noise;
  for (int i = 0; i < 10; ++i) {
    PositionPrior p;
    p.t_ns = 1403636579000000000 + i * 1000000000LL;
    p.p_world_body = Eigen::Vector3d(u(rng), u(rng), u(rng));
    p.sigma = Eigen::Vector3d(0.5, 0.25 + i, 3.0);
    s.priors.push_back(p);
  }
  return s;
}

void expectPoseNear(const Pose& a, const Pose& b, double tol) {
  EXPECT_LE((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), tol) << a.matrix() << "\nvs\n" << b.matrix();
}

// ---------------------------------------------------------------------------------------------
// Timestamps.

TEST(SequenceTimestamps, DecimalSecondsParseExactlyToNanoseconds) {
  TempDir dir("seq_ts");
  const std::string path = dir.file("images.txt");
  ASSERT_TRUE(writeFile(path,
                        "# comment\n"
                        "-1.5 a.png\n"
                        "0 b.png\n"
                        "0.000000001 c.png\n"
                        "1305031102.175304 rgb/1305031102.175304.png\n"
                        "1305031102.1753045 d.png\n"                    // ...175304500 exactly.
                        "1305031102.1753045005 e.png\n"                 // Rounds half up to ...175304501.
                        "1.30503110218e9 f.png\n"                       // Exponent form.
                        "9223372036.854775807 g with space.png\r\n"));  // INT64_MAX ns, CRLF.
  auto images = loadImageList(path);
  ASSERT_TRUE(images.ok()) << images.error().message;
  ASSERT_EQ(images->size(), 8u);
  const std::vector<int64_t> expected = {-1500000000,
                                         0,
                                         1,
                                         1305031102175304000,
                                         1305031102175304500,
                                         1305031102175304501,
                                         1305031102180000000,
                                         std::numeric_limits<int64_t>::max()};
  for (size_t i = 0; i < expected.size(); ++i) EXPECT_EQ((*images)[i].t_ns, expected[i]) << i;
  EXPECT_EQ((*images)[3].path, "rgb/1305031102.175304.png");
  EXPECT_EQ((*images)[7].path, "g with space.png");
}

TEST(SequenceTimestamps, RandomNanosecondsRoundTripThroughSeconds) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int64_t> step(1, 3000000000LL);
  std::vector<ImageEntry> images;
  int64_t t = -5000000000LL;
  for (int i = 0; i < 500; ++i) {
    t += step(rng);
    images.push_back({t, "x.png"});
  }
  images.push_back({std::numeric_limits<int64_t>::max(), "last.png"});
  TempDir dir("seq_ts2");
  ASSERT_TRUE(saveImageList(images, dir.file("images.txt")).ok());
  auto loaded = loadImageList(dir.file("images.txt"));
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->size(), images.size());
  for (size_t i = 0; i < images.size(); ++i) EXPECT_EQ((*loaded)[i].t_ns, images[i].t_ns);
}

// ---------------------------------------------------------------------------------------------
// Round trips of each file.

TEST(SequenceFiles, TrajectoryRoundTrip) {
  std::mt19937 rng(1);
  std::vector<StampedPose> poses;
  for (int i = 0; i < 200; ++i) poses.push_back({1305031102175304000 + i * 33333333LL + i % 7, randomPose(rng, 1e3)});
  TempDir dir("seq_traj");
  ASSERT_TRUE(saveTumTrajectory(poses, dir.file("gt.txt")).ok());
  auto loaded = loadTumTrajectory(dir.file("gt.txt"));
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ((*loaded)[i].t_ns, poses[i].t_ns);
    expectPoseNear((*loaded)[i].T_world_camera, poses[i].T_world_camera, 1e-12);
  }
}

TEST(SequenceFiles, TrajectoryReadsTumOrder) {
  // Hand-made line: 90 deg about z, q = (0, 0, sin 45, cos 45) in TUM order qx qy qz qw.
  TempDir dir("seq_tum");
  ASSERT_TRUE(
      writeFile(dir.file("gt.txt"), "# ground truth\n\n1.5 1 2 3 0 0 0.70710678118654757 0.70710678118654757\n"));
  auto loaded = loadTumTrajectory(dir.file("gt.txt"));
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->size(), 1u);
  EXPECT_EQ((*loaded)[0].t_ns, 1500000000);
  Pose expected = Pose::Identity();
  expected.linear() << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  expected.translation() = Eigen::Vector3d(1, 2, 3);
  expectPoseNear((*loaded)[0].T_world_camera, expected, 1e-15);
}

TEST(SequenceFiles, ImuAndPriorRoundTripExactly) {
  std::mt19937 rng(2);
  const Sequence s = makeSequence(rng);
  TempDir dir("seq_imu");
  ASSERT_TRUE(saveImuCsv(s.imu, dir.file("imu.csv")).ok());
  ASSERT_TRUE(savePriorCsv(s.priors, dir.file("prior.csv")).ok());
  auto imu = loadImuCsv(dir.file("imu.csv"));
  auto priors = loadPriorCsv(dir.file("prior.csv"));
  ASSERT_TRUE(imu.ok()) << imu.error().message;
  ASSERT_TRUE(priors.ok()) << priors.error().message;
  ASSERT_EQ(imu->size(), s.imu.size());
  for (size_t i = 0; i < s.imu.size(); ++i) {
    EXPECT_EQ((*imu)[i].t_ns, s.imu[i].t_ns);
    EXPECT_EQ((*imu)[i].gyro_body, s.imu[i].gyro_body);
    EXPECT_EQ((*imu)[i].accel_body, s.imu[i].accel_body);
  }
  ASSERT_EQ(priors->size(), s.priors.size());
  for (size_t i = 0; i < s.priors.size(); ++i) {
    EXPECT_EQ((*priors)[i].t_ns, s.priors[i].t_ns);
    EXPECT_EQ((*priors)[i].p_world_body, s.priors[i].p_world_body);
    EXPECT_EQ((*priors)[i].sigma, s.priors[i].sigma);
  }
}

TEST(SequenceFiles, ImuReadsEurocLinesWithAndWithoutHeader) {
  TempDir dir("seq_euroc_imu");
  const std::string body =
      "1403636579758555392,-0.099134701513277898,0.14730578886832138,0.02722713633111154,"
      "8.1476917083333333,-0.37592158333333331,-2.4026292499999999\n"
      "1403636579763555584, 1, 2, 3, 4, 5, 6\n";
  ASSERT_TRUE(writeFile(dir.file("a.csv"), "#timestamp [ns],w_RS_S_x [rad s^-1],...\n" + body));
  ASSERT_TRUE(writeFile(dir.file("b.csv"), "timestamp,wx,wy,wz,ax,ay,az\n" + body));
  for (const char* name : {"a.csv", "b.csv"}) {
    auto imu = loadImuCsv(dir.file(name));
    ASSERT_TRUE(imu.ok()) << imu.error().message;
    ASSERT_EQ(imu->size(), 2u);
    EXPECT_EQ((*imu)[0].t_ns, 1403636579758555392);
    EXPECT_EQ((*imu)[0].gyro_body.x(), -0.099134701513277898);
    EXPECT_EQ((*imu)[0].accel_body.z(), -2.4026292499999999);
    EXPECT_EQ((*imu)[1].accel_body, Eigen::Vector3d(4, 5, 6));
  }
}

TEST(SequenceFiles, CameraRoundTripAllModels) {
  std::mt19937 rng(3);
  TempDir dir("seq_cam");
  SequenceCamera pinhole;
  pinhole.intrinsics = PinholeCamera{517.3, 516.5, 318.6, 255.3, 640, 480};
  pinhole.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  pinhole.T_body_camera = randomPose(rng, 0.3);
  SequenceCamera mei = pinhole;
  mei.model = "mei";
  mei.distortion = {-0.1, 0.01, 1e-4, -2e-4};
  mei.xi = 1.7;
  SequenceCamera kb = pinhole;
  kb.model = "kannala_brandt";
  kb.distortion = {0.01, -0.002, 3e-4, -4e-5};
  for (const SequenceCamera& c : {pinhole, mei, kb}) {
    const std::string path = dir.file(c.model + ".yaml");
    ASSERT_TRUE(saveSequenceCamera(c, path).ok());
    auto loaded = loadSequenceCamera(path);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->model, c.model);
    EXPECT_EQ(loaded->intrinsics.fx, c.intrinsics.fx);
    EXPECT_EQ(loaded->intrinsics.fy, c.intrinsics.fy);
    EXPECT_EQ(loaded->intrinsics.cx, c.intrinsics.cx);
    EXPECT_EQ(loaded->intrinsics.cy, c.intrinsics.cy);
    EXPECT_EQ(loaded->intrinsics.width, c.intrinsics.width);
    EXPECT_EQ(loaded->intrinsics.height, c.intrinsics.height);
    EXPECT_EQ(loaded->distortion, c.distortion);
    EXPECT_EQ(loaded->xi, c.xi);
    expectPoseNear(loaded->T_body_camera, c.T_body_camera, 1e-12);
  }
  // A sequence camera.yaml is also a valid --camera file.
  auto flat = loadCamera(dir.file("pinhole.yaml"));
  ASSERT_TRUE(flat.ok()) << flat.error().message;
  EXPECT_EQ(flat->fx, 517.3);
  EXPECT_EQ(flat->cy, 255.3);
  EXPECT_EQ(flat->width, 640);
}

TEST(SequenceFiles, CameraAcceptsSevenNumberPoseAndRejectsBadContent) {
  TempDir dir("seq_cam2");
  const std::string base = "fx: 500\nfy: 500\ncx: 320\ncy: 240\nwidth: 640\nheight: 480\n";
  ASSERT_TRUE(writeFile(dir.file("tum.yaml"), base + "T_body_camera: [1, 2, 3, 0, 0, 0.70710678118654757, "
                                                     "0.70710678118654757]\n"));
  auto cam = loadSequenceCamera(dir.file("tum.yaml"));
  ASSERT_TRUE(cam.ok()) << cam.error().message;
  EXPECT_EQ(cam->model, "pinhole");
  EXPECT_TRUE(cam->distortion.empty());
  EXPECT_NEAR(cam->T_body_camera.linear()(1, 0), 1.0, 1e-15);
  EXPECT_EQ(cam->T_body_camera.translation(), Eigen::Vector3d(1, 2, 3));

  ASSERT_TRUE(writeFile(dir.file("unknown.yaml"), "model: omni_radtan\n" + base));
  auto unknown = loadSequenceCamera(dir.file("unknown.yaml"));
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(unknown.error().message.find(dir.file("unknown.yaml")), std::string::npos);

  ASSERT_TRUE(
      writeFile(dir.file("fx.yaml"), "model: pinhole\nfx: 500\nfy: -3\ncx: 320\ncy: 240\nwidth: 640\nheight: 480\n"));
  expectLineError(loadSequenceCamera(dir.file("fx.yaml")), dir.file("fx.yaml"), 3, "fy");
  ASSERT_TRUE(writeFile(dir.file("nan.yaml"), "fx: 500\nfy: 500\ncx: .nan\ncy: 240\nwidth: 640\nheight: 480\n"));
  expectLineError(loadSequenceCamera(dir.file("nan.yaml")), dir.file("nan.yaml"), 3);
  ASSERT_TRUE(writeFile(dir.file("dist.yaml"), base + "distortion: [1, 2, 3]\n"));
  expectLineError(loadSequenceCamera(dir.file("dist.yaml")), dir.file("dist.yaml"), 7, "distortion");
  ASSERT_TRUE(writeFile(dir.file("width.yaml"), "fx: 500\nfy: 500\ncx: 320\ncy: 240\nwidth: 64o\nheight: 480\n"));
  expectLineError(loadSequenceCamera(dir.file("width.yaml")), dir.file("width.yaml"), 5, "width");
  ASSERT_TRUE(writeFile(dir.file("syntax.yaml"), "fx: 500\nfy: [500\ncx: 320\n"));
  auto syntax = loadSequenceCamera(dir.file("syntax.yaml"));
  ASSERT_FALSE(syntax.ok());
  EXPECT_EQ(syntax.error().code, ErrorCode::kMalformedInput);
  EXPECT_EQ(syntax.error().message.rfind(dir.file("syntax.yaml") + ":", 0), 0u) << syntax.error().message;
  ASSERT_TRUE(writeFile(dir.file("missing.yaml"), "fx: 500\nfy: 500\ncx: 320\ncy: 240\nwidth: 640\n"));
  auto missing = loadSequenceCamera(dir.file("missing.yaml"));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("height"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Whole sequence.

TEST(SequenceFolder, RoundTrip) {
  std::mt19937 rng(4);
  const Sequence s = makeSequence(rng);
  TempDir dir("seq_all");
  const std::string folder = dir.file("nested/seq");
  const Status saved = saveSequence(s, folder);
  ASSERT_TRUE(saved.ok()) << saved.error().message;
  for (const char* f : {"sequence.yaml", "camera.yaml", "images.txt", "groundtruth.txt", "imu.csv", "prior.csv"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(folder) / f)) << f;
  }
  // No temporaries left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 6);
  auto loaded = loadSequence(folder);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const Sequence& l = *loaded;
  EXPECT_EQ(l.directory, folder);
  EXPECT_EQ(l.name, s.name);
  EXPECT_EQ(l.model, s.model);
  expectPoseNear(l.T_world_model, s.T_world_model, 1e-12);
  EXPECT_EQ(l.unit_scale, s.unit_scale);
  ASSERT_TRUE(l.initial_T_world_camera.has_value());
  expectPoseNear(*l.initial_T_world_camera, *s.initial_T_world_camera, 1e-12);
  EXPECT_EQ(l.gravity_world, s.gravity_world);
  EXPECT_EQ(l.camera.distortion, s.camera.distortion);
  EXPECT_EQ(l.camera.intrinsics.fx, s.camera.intrinsics.fx);
  expectPoseNear(l.camera.T_body_camera, s.camera.T_body_camera, 1e-12);
  ASSERT_EQ(l.images.size(), s.images.size());
  for (size_t i = 0; i < s.images.size(); ++i) {
    EXPECT_EQ(l.images[i].t_ns, s.images[i].t_ns);
    EXPECT_EQ(l.images[i].path, s.images[i].path);
  }
  ASSERT_EQ(l.groundtruth.size(), s.groundtruth.size());
  for (size_t i = 0; i < s.groundtruth.size(); ++i) {
    EXPECT_EQ(l.groundtruth[i].t_ns, s.groundtruth[i].t_ns);
    expectPoseNear(l.groundtruth[i].T_world_camera, s.groundtruth[i].T_world_camera, 1e-12);
  }
  ASSERT_EQ(l.imu.size(), s.imu.size());
  for (size_t i = 0; i < s.imu.size(); ++i) {
    EXPECT_EQ(l.imu[i].t_ns, s.imu[i].t_ns);
    EXPECT_EQ(l.imu[i].accel_body, s.imu[i].accel_body);
  }
  ASSERT_TRUE(l.imu_noise.has_value());
  EXPECT_EQ(l.imu_noise->gyro_noise_density, s.imu_noise->gyro_noise_density);
  EXPECT_EQ(l.imu_noise->accel_random_walk, s.imu_noise->accel_random_walk);
  ASSERT_EQ(l.priors.size(), s.priors.size());
  EXPECT_EQ(l.priors.back().sigma, s.priors.back().sigma);

  // Paths resolve against the folder; absolute paths and built-in models stay as they are.
  EXPECT_EQ(l.imagePath(0), (fs::path(folder) / s.images[0].path).string());
  EXPECT_EQ(l.imagePath(s.images.size() - 1), "/absolute/path with space.png");
  EXPECT_EQ(l.modelPath(), (fs::path(folder) / "models/city block.glb").string());
  Sequence builtin = l;
  builtin.model = "city";
  EXPECT_EQ(builtin.modelPath(), "city");
  builtin.model = "";
  EXPECT_EQ(builtin.modelPath(), "");

  // Saving a sequence without the optional parts removes the stale files.
  Sequence minimal = l;
  minimal.groundtruth.clear();
  minimal.imu.clear();
  minimal.priors.clear();
  minimal.imu_noise.reset();
  minimal.initial_T_world_camera.reset();
  ASSERT_TRUE(saveSequence(minimal, folder).ok());
  auto reloaded = loadSequence(folder);
  ASSERT_TRUE(reloaded.ok()) << reloaded.error().message;
  EXPECT_TRUE(reloaded->groundtruth.empty());
  EXPECT_TRUE(reloaded->imu.empty());
  EXPECT_TRUE(reloaded->priors.empty());
  EXPECT_FALSE(reloaded->imu_noise.has_value());
  EXPECT_FALSE(reloaded->initial_T_world_camera.has_value());
}

TEST(SequenceFolder, SaveRefusesBadDataBeforeWriting) {
  std::mt19937 rng(5);
  const Sequence good = makeSequence(rng);
  TempDir dir("seq_bad");
  auto expectRefused = [&](const Sequence& s, const char* what) {
    const std::string folder = dir.file(what);
    const Status st = saveSequence(s, folder);
    ASSERT_FALSE(st.ok()) << what;
    EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument) << what;
    EXPECT_FALSE(fs::exists(folder)) << what;
  };
  Sequence s = good;
  s.imu[50].accel_body.y() = std::nan("");
  expectRefused(s, "nan_imu");
  s = good;
  s.images[3].t_ns = s.images[2].t_ns;
  expectRefused(s, "equal_times");
  s = good;
  std::swap(s.groundtruth[4], s.groundtruth[5]);
  expectRefused(s, "swapped_gt");
  s = good;
  s.groundtruth[1].T_world_camera.translation().x() = std::numeric_limits<double>::infinity();
  expectRefused(s, "inf_pose");
  s = good;
  s.priors[0].sigma.z() = 0.0;
  expectRefused(s, "zero_sigma");
  s = good;
  s.camera.intrinsics.fx = std::nan("");
  expectRefused(s, "nan_fx");
  s = good;
  s.unit_scale = -1.0;
  expectRefused(s, "negative_scale");
  s = good;
  s.images[0].path = "two\nlines.png";
  expectRefused(s, "newline_path");
  // The single-file writers refuse the same way.
  std::vector<ImuSample> imu = good.imu;
  imu[3].t_ns = imu[2].t_ns - 1;
  const Status st = saveImuCsv(imu, dir.file("imu.csv"));
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code, ErrorCode::kInvalidArgument);
  EXPECT_FALSE(fs::exists(dir.file("imu.csv")));
}

TEST(SequenceFolder, MissingFilesAreNotFound) {
  TempDir dir("seq_missing");
  auto none = loadSequence(dir.file("nope"));
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::kNotFound);
  EXPECT_EQ(loadTumTrajectory(dir.file("x.txt")).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(loadImageList(dir.file("x.txt")).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(loadImuCsv(dir.file("x.csv")).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(loadPriorCsv(dir.file("x.csv")).error().code, ErrorCode::kNotFound);
  EXPECT_EQ(loadSequenceCamera(dir.file("x.yaml")).error().code, ErrorCode::kNotFound);

  std::mt19937 rng(6);
  Sequence s = makeSequence(rng);
  const std::string folder = dir.file("seq");
  ASSERT_TRUE(saveSequence(s, folder).ok());
  for (const char* required : {"camera.yaml", "images.txt", "sequence.yaml"}) {
    ASSERT_TRUE(saveSequence(s, folder).ok());
    fs::remove(fs::path(folder) / required);
    auto r = loadSequence(folder);
    ASSERT_FALSE(r.ok()) << required;
    EXPECT_EQ(r.error().code, ErrorCode::kNotFound) << required;
    EXPECT_NE(r.error().message.find(required), std::string::npos) << r.error().message;
  }
}

TEST(SequenceFolder, MalformedSequenceYamlNamesFileAndLine) {
  std::mt19937 rng(8);
  Sequence s = makeSequence(rng);
  TempDir dir("seq_yaml");
  ASSERT_TRUE(saveSequence(s, dir.path().string()).ok());
  const std::string path = dir.file("sequence.yaml");
  ASSERT_TRUE(writeFile(path, "name: a\nmodel: b\nunit_scale: abc\n"));
  expectLineError(loadSequence(dir.path().string()), path, 3, "unit_scale");
  ASSERT_TRUE(writeFile(path, "name: a\n\nunit_scale: 0\n"));
  expectLineError(loadSequence(dir.path().string()), path, 3, "unit_scale");
  ASSERT_TRUE(writeFile(path, "name: a\ngravity_world: [0, 0]\n"));
  expectLineError(loadSequence(dir.path().string()), path, 2, "gravity_world");
  ASSERT_TRUE(writeFile(path, "name: a\ninitial_T_world_camera: [0, 0, 0, 0, 0, 0, 2]\n"));
  expectLineError(loadSequence(dir.path().string()), path, 2, "quaternion");
  ASSERT_TRUE(writeFile(path, "name: a\nimu_noise:\n  rate_hz: 200\n  gyro_random_walk: .inf\n"));
  expectLineError(loadSequence(dir.path().string()), path, 4, "gyro_random_walk");
  ASSERT_TRUE(writeFile(path, "name: a\nmodel: [unclosed\n"));
  auto bad = loadSequence(dir.path().string());
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kMalformedInput);
  EXPECT_EQ(bad.error().message.rfind(path + ":", 0), 0u) << bad.error().message;
  ASSERT_TRUE(writeFile(path, "- just\n- a list\n"));
  expectLineError(loadSequence(dir.path().string()), path, 1);
  // Errors in the optional files propagate with their own name.
  ASSERT_TRUE(writeFile(path, "name: a\n"));
  ASSERT_TRUE(writeFile(dir.file("prior.csv"), "1,0,0,0,1,1,1\n2,0,0,0,1,1\n"));
  expectLineError(loadSequence(dir.path().string()), dir.file("prior.csv"), 2, "columns");
}

// ---------------------------------------------------------------------------------------------
// Malformed lines.

struct BadCase {
  const char* name;
  int kind;  // 0 trajectory, 1 image list, 2 imu, 3 prior
  std::string content;
  int line;
  const char* contains;
};

TEST(SequenceFiles, MalformedLinesGiveFileAndLine) {
  const std::string gt_ok = "# t tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n";
  const std::string imu_ok = "#timestamp [ns],w...\n1000,0,0,0,0,0,9.81\n";
  const std::vector<BadCase> cases = {
      {"gt_columns", 0, gt_ok + "2.0 0 0 0 0 0 1\n", 3, "8 columns"},
      {"gt_text", 0, gt_ok + "2.0 0 zero 0 0 0 0 1\n", 3, "not a number"},
      {"gt_nan", 0, gt_ok + "\n2.0 0 0 nan 0 0 0 1\n", 4, "non-finite"},
      {"gt_inf", 0, gt_ok + "2.0 0 0 0 0 0 0 inf\n", 3, "non-finite"},
      {"gt_quat", 0, gt_ok + "2.0 0 0 0 0 0 0 1.01\n", 3, "quaternion norm"},
      {"gt_order", 0, gt_ok + "2.5 0 0 0 0 0 0 1\n2.25 0 0 0 0 0 0 1\n", 4,
       "2.250000000 s is not after the previous one 2.500000000 s"},
      {"gt_equal", 0, gt_ok + "1.0 0 0 0 0 0 0 1\n", 3, "not after"},
      {"gt_time", 0, "1.0.0 0 0 0 0 0 0 1\n", 1, "timestamp"},
      {"gt_huge_time", 0, "99999999999999999999 0 0 0 0 0 0 1\n", 1, "out of range"},
      {"img_columns", 1, "1.0 a.png\n2.0\n", 2, "2 columns"},
      {"img_time", 1, "1.0 a.png\nabc b.png\n", 2, "timestamp"},
      {"img_order", 1, "# c\n1.0 a.png\n0.5 b.png\n", 3, "0.500000000 s is not after the previous one 1.000000000 s"},
      {"imu_columns", 2, imu_ok + "2000,0,0,0,0,0\n", 3, "7 comma-separated columns"},
      {"imu_empty_field", 2, imu_ok + "2000,0,,0,0,0,1\n", 3, "column 3"},
      {"imu_nan", 2, imu_ok + "2000,0,0,0,0,NaN,1\n", 3, "non-finite"},
      {"imu_time_float", 2, imu_ok + "2000.5,0,0,0,0,0,1\n", 3, "nanoseconds"},
      {"imu_order", 2, imu_ok + "3000,0,0,0,0,0,1\n2999,0,0,0,0,0,1\n", 4,
       "2999 ns is not after the previous one 3000 ns"},
      {"imu_second_header", 2, "t,wx,wy,wz,ax,ay,az\nt,wx,wy,wz,ax,ay,az\n", 2, "nanoseconds"},
      {"imu_first_line_nan", 2, "nan,0,0,0,0,0,1\n", 1, "nanoseconds"},
      {"prior_sigma", 3, "1,0,0,0,1,1,1\n2,0,0,0,1,-1,1\n", 2, "sigma"},
      {"prior_columns", 3, "1,0,0,0,1,1,1,7\n", 1, "columns"},
  };
  TempDir dir("seq_malformed");
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = dir.file(c.name);
    ASSERT_TRUE(writeFile(path, c.content));
    switch (c.kind) {
      case 0:
        expectLineError(loadTumTrajectory(path), path, c.line, c.contains);
        break;
      case 1:
        expectLineError(loadImageList(path), path, c.line, c.contains);
        break;
      case 2:
        expectLineError(loadImuCsv(path), path, c.line, c.contains);
        break;
      default:
        expectLineError(loadPriorCsv(path), path, c.line, c.contains);
        break;
    }
  }
}

TEST(SequenceFiles, RandomBytesAndTruncationsNeverCrash) {
  std::mt19937 rng(9);
  const Sequence s = makeSequence(rng);
  TempDir dir("seq_fuzz");
  const std::string folder = dir.file("seq");
  ASSERT_TRUE(saveSequence(s, folder).ok());
  const std::vector<std::string> names = {"sequence.yaml",   "camera.yaml", "images.txt",
                                          "groundtruth.txt", "imu.csv",     "prior.csv"};
  std::vector<std::vector<uint8_t>> originals;
  for (const std::string& n : names) originals.push_back(test::readFile((fs::path(folder) / n).string()));
  auto loadAll = [&](const std::string& path) {
    // Each loader on the damaged file; only "did not crash" and "error has a message" matter.
    const auto check = [](const auto& r) {
      if (!r.ok()) {
        EXPECT_FALSE(r.error().message.empty());
      }
    };
    check(loadTumTrajectory(path));
    check(loadImageList(path));
    check(loadImuCsv(path));
    check(loadPriorCsv(path));
    check(loadSequenceCamera(path));
  };
  const std::string scratch = dir.file("scratch");
  std::uniform_int_distribution<int> byte(0, 255);
  for (int iter = 0; iter < 40; ++iter) {
    // Pure random bytes, biased towards separators so that lines get far.
    std::vector<uint8_t> bytes(static_cast<size_t>(byte(rng)) * 2);
    const char alphabet[] = "0123456789.,-e #\n\r\t:[]{}nanif'\"";
    for (uint8_t& b : bytes)
      b = iter % 2 ? static_cast<uint8_t>(byte(rng)) : alphabet[byte(rng) % (sizeof(alphabet) - 1)];
    ASSERT_TRUE(writeFile(scratch, bytes));
    loadAll(scratch);
  }
  // Deep nesting must not overflow the YAML parser's stack.
  ASSERT_TRUE(writeFile(scratch, std::string(100000, '[')));
  auto deep = loadSequenceCamera(scratch);
  ASSERT_FALSE(deep.ok());
  EXPECT_EQ(deep.error().code, ErrorCode::kMalformedInput);
  for (size_t f = 0; f < names.size(); ++f) {
    const std::vector<uint8_t>& orig = originals[f];
    for (int iter = 0; iter < 12; ++iter) {
      std::vector<uint8_t> damaged(orig.begin(), orig.begin() + static_cast<long>(rng() % (orig.size() + 1)));
      if (iter % 2 && !damaged.empty()) damaged[rng() % damaged.size()] = static_cast<uint8_t>(byte(rng));
      ASSERT_TRUE(writeFile(scratch, damaged));
      loadAll(scratch);
      // Also the damaged file in place within a whole sequence.
      ASSERT_TRUE(writeFile((fs::path(folder) / names[f]).string(), damaged));
      auto r = loadSequence(folder);
      if (!r.ok()) {
        EXPECT_FALSE(r.error().message.empty());
      }
    }
    ASSERT_TRUE(writeFile((fs::path(folder) / names[f]).string(), orig));
  }
}

// ---------------------------------------------------------------------------------------------
// Importers.

TEST(SequenceImport, TumRgbdFreiburg1) {
  TempDir dir("seq_tumrgbd");
  const fs::path tum = dir.path() / "rgbd_dataset_freiburg1_xyz";
  fs::create_directories(tum / "rgb");
  ASSERT_TRUE(writeFile((tum / "rgb.txt").string(),
                        "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n"
                        "1305031102.175304 rgb/1305031102.175304.png\n"
                        "1305031102.211214 rgb/1305031102.211214.png\n"
                        "1305031102.243211 rgb/1305031102.243211.png\n"));
  ASSERT_TRUE(writeFile((tum / "groundtruth.txt").string(),
                        "# ground truth trajectory\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n"
                        "# timestamp tx ty tz qx qy qz qw\n"
                        "1305031102.1658 1.0 2.0 3.0 0 0 0 1\n"
                        "1305031102.1758 2.0 2.0 3.0 0 0 0 1\n"
                        "1305031102.1858 3.0 2.0 3.0 0 0 0.70710678118654757 0.70710678118654757\n"));
  auto seq = importTumRgbd(tum.string(), std::nullopt, "room");
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  EXPECT_EQ(seq->name, "rgbd_dataset_freiburg1_xyz");
  EXPECT_EQ(seq->model, "room");
  EXPECT_EQ(seq->camera.model, "pinhole");
  EXPECT_EQ(seq->camera.intrinsics.fx, 517.3);
  EXPECT_EQ(seq->camera.intrinsics.fy, 516.5);
  EXPECT_EQ(seq->camera.intrinsics.cx, 318.6);
  EXPECT_EQ(seq->camera.intrinsics.cy, 255.3);
  EXPECT_EQ(seq->camera.intrinsics.width, 640);
  EXPECT_EQ(seq->camera.distortion, (std::vector<double>{0.2624, -0.9531, -0.0054, 0.0026, 1.1633}));
  ASSERT_EQ(seq->images.size(), 3u);
  EXPECT_EQ(seq->images[1].t_ns, 1305031102211214000);
  EXPECT_EQ(seq->images[1].path, (tum / "rgb/1305031102.211214.png").string());
  EXPECT_EQ(seq->imagePath(1), (tum / "rgb/1305031102.211214.png").string());
  ASSERT_EQ(seq->groundtruth.size(), 3u);  // Kept at its own timestamps.
  EXPECT_EQ(seq->groundtruth[0].t_ns, 1305031102165800000);
  EXPECT_EQ(seq->groundtruth[2].T_world_camera.translation(), Eigen::Vector3d(3, 2, 3));
  // First image at .175304 lies between .1658 and .1758 (identity rotations): x = 1 + 0.9504.
  ASSERT_TRUE(seq->initial_T_world_camera.has_value());
  EXPECT_NEAR(seq->initial_T_world_camera->translation().x(), 1.9504, 1e-9);
  EXPECT_LE((seq->initial_T_world_camera->linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);

  // The imported sequence saves and reloads.
  ASSERT_TRUE(saveSequence(*seq, dir.file("out")).ok());
  auto reloaded = loadSequence(dir.file("out"));
  ASSERT_TRUE(reloaded.ok()) << reloaded.error().message;
  EXPECT_EQ(reloaded->imagePath(2), (tum / "rgb/1305031102.243211.png").string());

  // Other calibrations by folder name, and an unknown folder needs a camera.
  for (const auto& [folder, fx] : {std::pair<std::string, double>{"rgbd_dataset_freiburg2_desk", 520.9},
                                   std::pair<std::string, double>{"rgbd_dataset_freiburg3_long_office", 535.4}}) {
    fs::create_directories(dir.path() / folder);
    fs::copy_file(tum / "rgb.txt", dir.path() / folder / "rgb.txt");
    auto other = importTumRgbd((dir.path() / folder).string() + "/", std::nullopt);
    ASSERT_TRUE(other.ok()) << other.error().message;
    EXPECT_EQ(other->camera.intrinsics.fx, fx);
    EXPECT_EQ(other->camera.distortion.empty(), fx == 535.4);
    EXPECT_TRUE(other->groundtruth.empty());
    EXPECT_FALSE(other->initial_T_world_camera.has_value());
  }
  fs::create_directories(dir.path() / "my_recording");
  fs::copy_file(tum / "rgb.txt", dir.path() / "my_recording" / "rgb.txt");
  auto unknown = importTumRgbd((dir.path() / "my_recording").string(), std::nullopt);
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(unknown.error().message.find("--camera"), std::string::npos);
  SequenceCamera custom;
  custom.intrinsics = PinholeCamera{600, 601, 320, 240, 640, 480};
  auto overridden = importTumRgbd((dir.path() / "my_recording").string(), custom);
  ASSERT_TRUE(overridden.ok()) << overridden.error().message;
  EXPECT_EQ(overridden->camera.intrinsics.fy, 601);
  // A malformed ground truth line is reported with its file and line.
  ASSERT_TRUE(writeFile((tum / "groundtruth.txt").string(), "1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n"));
  expectLineError(importTumRgbd(tum.string(), std::nullopt), (tum / "groundtruth.txt").string(), 2, "not after");
  EXPECT_EQ(importTumRgbd(dir.file("nothing"), std::nullopt).error().code, ErrorCode::kNotFound);
}

void writeEuroc(const fs::path& root, const std::string& gt) {
  const fs::path mav0 = root / "mav0";
  fs::create_directories(mav0 / "cam0" / "data");
  fs::create_directories(mav0 / "imu0");
  fs::create_directories(mav0 / "state_groundtruth_estimate0");
  // T_BS: camera rotated 90 deg about the body z axis, at (0.1, 0.2, 0.3) m in the body frame.
  ASSERT_TRUE(writeFile((mav0 / "cam0" / "sensor.yaml").string(),
                        "%YAML:1.0\n"
                        "# General sensor definitions.\n"
                        "sensor_type: camera\n"
                        "comment: VI-Sensor cam0 (MT9M034)\n"
                        "T_BS:\n"
                        "  cols: 4\n"
                        "  rows: 4\n"
                        "  data: [0.0, -1.0, 0.0, 0.1,\n"
                        "         1.0, 0.0, 0.0, 0.2,\n"
                        "         0.0, 0.0, 1.0, 0.3,\n"
                        "         0.0, 0.0, 0.0, 1.0]\n"
                        "rate_hz: 20\n"
                        "resolution: [752, 480]\n"
                        "camera_model: pinhole\n"
                        "intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv\n"
                        "distortion_model: radial-tangential\n"
                        "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"));
  ASSERT_TRUE(writeFile((mav0 / "cam0" / "data.csv").string(),
                        "#timestamp [ns],filename\n"
                        "1403636579763555584,1403636579763555584.png\n"
                        "1403636579813555456,1403636579813555456.png\n"));
  ASSERT_TRUE(writeFile((mav0 / "imu0" / "data.csv").string(),
                        "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                        "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
                        "1403636579758555392,-0.099134701513277898,0.14730578886832138,0.02722713633111154,"
                        "8.1476917083333333,-0.37592158333333331,-2.4026292499999999\n"
                        "1403636579763555584,-0.099134701513277898,0.14032447186034408,0.029321531433504528,"
                        "8.033280791666666,-0.40861316666666664,-2.4026292499999999\n"
                        "1403636579768555520,-0.098436569812480182,0.12775810124598494,0.037699111843077518,"
                        "7.8861810416666662,-0.42495895833333328,-2.4353208333333331\n"));
  ASSERT_TRUE(writeFile((mav0 / "imu0" / "sensor.yaml").string(),
                        "sensor_type: imu\nrate_hz: 200\ngyroscope_noise_density: 1.6968e-04\n"
                        "gyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0000e-3\n"
                        "accelerometer_random_walk: 3.0000e-3\n"));
  ASSERT_TRUE(writeFile((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), gt));
}

TEST(SequenceImport, EurocConvertsBodyToCamera) {
  TempDir dir("seq_euroc");
  const fs::path root = dir.path() / "V1_01_easy";
  // Body rotated 90 deg about world x (q_w = q_x = sqrt(1/2), w first) at (1, 2, 3).
  const std::string gt =
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
      "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
      "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n"
      "1403636579758555392,1.0,2.0,3.0,0.70710678118654757,0.70710678118654757,0.0,0.0,"
      "0,0,0,-0.002,0.02,0.07,-0.01,0.1,0.09\n"
      "1403636579763555584,1.0,2.0,3.0,0.70710678118654757,0.70710678118654757,0.0,0.0,"
      "0,0,0,-0.002,0.02,0.07,-0.01,0.1,0.09\n";
  writeEuroc(root, gt);
  auto seq = importEuroc(root.string(), "/models/room.glb");
  ASSERT_TRUE(seq.ok()) << seq.error().message;
  EXPECT_EQ(seq->name, "V1_01_easy");
  EXPECT_EQ(seq->model, "/models/room.glb");
  EXPECT_EQ(seq->camera.model, "pinhole");
  EXPECT_EQ(seq->camera.intrinsics.fx, 458.654);
  EXPECT_EQ(seq->camera.intrinsics.cy, 248.375);
  EXPECT_EQ(seq->camera.intrinsics.width, 752);
  EXPECT_EQ(seq->camera.intrinsics.height, 480);
  EXPECT_EQ(seq->camera.distortion.size(), 4u);
  EXPECT_EQ(seq->camera.distortion[3], 1.76187114e-05);
  ASSERT_EQ(seq->images.size(), 2u);
  EXPECT_EQ(seq->images[1].t_ns, 1403636579813555456);
  EXPECT_EQ(seq->images[0].path, (root / "mav0/cam0/data/1403636579763555584.png").string());
  ASSERT_EQ(seq->imu.size(), 3u);
  EXPECT_EQ(seq->imu[2].accel_body.z(), -2.4353208333333331);
  ASSERT_TRUE(seq->imu_noise.has_value());
  EXPECT_EQ(seq->imu_noise->gyro_random_walk, 1.9393e-05);
  ASSERT_EQ(seq->groundtruth.size(), 2u);
  EXPECT_EQ(seq->groundtruth[0].t_ns, 1403636579758555392);
  // Hand computation: R_world_body = Rx(90) = [1 0 0; 0 0 -1; 0 1 0], R_body_camera = Rz(90) =
  // [0 -1 0; 1 0 0; 0 0 1], so R_world_camera = [0 -1 0; 0 0 -1; 1 0 0] and
  // t = R_world_body (0.1, 0.2, 0.3) + (1, 2, 3) = (1.1, 1.7, 3.2).
  Eigen::Matrix4d expected;
  expected << 0, -1, 0, 1.1, 0, 0, -1, 1.7, 1, 0, 0, 3.2, 0, 0, 0, 1;
  EXPECT_LE((seq->groundtruth[0].T_world_camera.matrix() - expected).cwiseAbs().maxCoeff(), 1e-12)
      << seq->groundtruth[0].T_world_camera.matrix();
  // The first image is at the second ground-truth time exactly.
  ASSERT_TRUE(seq->initial_T_world_camera.has_value());
  EXPECT_LE((seq->initial_T_world_camera->matrix() - expected).cwiseAbs().maxCoeff(), 1e-12);

  // The mav0 folder itself is accepted; missing optional parts are fine.
  fs::remove_all(root / "mav0" / "imu0");
  fs::remove_all(root / "mav0" / "state_groundtruth_estimate0");
  auto bare = importEuroc((root / "mav0").string());
  ASSERT_TRUE(bare.ok()) << bare.error().message;
  EXPECT_EQ(bare->name, "V1_01_easy");
  EXPECT_TRUE(bare->imu.empty());
  EXPECT_TRUE(bare->groundtruth.empty());
  EXPECT_FALSE(bare->imu_noise.has_value());
  EXPECT_FALSE(bare->initial_T_world_camera.has_value());
}

TEST(SequenceImport, EurocMalformedInputs) {
  TempDir dir("seq_euroc_bad");
  const fs::path root = dir.path() / "MH_01";
  writeEuroc(root, "#t,...\n1403636579758555392,1,2,3,0.9,0.1,0,0,0,0,0,0,0,0,0,0,0\n");
  const std::string gt_path = (root / "mav0/state_groundtruth_estimate0/data.csv").string();
  expectLineError(importEuroc(root.string()), gt_path, 2, "quaternion");
  ASSERT_TRUE(writeFile(gt_path, "#t,...\n\n1403636579758555392,1,2,3,1,0,0\n"));
  expectLineError(importEuroc(root.string()), gt_path, 3, "8 columns");
  ASSERT_TRUE(writeFile(gt_path, "1403636579758555392,1,2,3,1,0,0,0\n1403636579758555392,1,2,3,1,0,0,0\n"));
  expectLineError(importEuroc(root.string()), gt_path, 2, "not after");
  fs::remove(gt_path);
  const std::string csv = (root / "mav0/cam0/data.csv").string();
  ASSERT_TRUE(writeFile(csv, "#timestamp [ns],filename\n1403636579763555584\n"));
  expectLineError(importEuroc(root.string()), csv, 2, "2 columns");
  ASSERT_TRUE(writeFile(csv, "1403636579763555584,a.png\n"));
  const std::string yaml = (root / "mav0/cam0/sensor.yaml").string();
  ASSERT_TRUE(writeFile(yaml, "T_BS:\n  data: [1, 0, 0]\nresolution: [752, 480]\nintrinsics: [458, 457, 367, 248]\n"));
  expectLineError(importEuroc(root.string()), yaml, 2, "T_BS");
  ASSERT_TRUE(writeFile(yaml, "resolution: [752, 480]\nintrinsics: [458, 457, 367, abc]\n"));
  expectLineError(importEuroc(root.string()), yaml, 2);
  ASSERT_TRUE(writeFile(yaml, "camera_model: eucm\nresolution: [752, 480]\nintrinsics: [458, 457, 367, 248]\n"));
  auto omni = importEuroc(root.string());
  ASSERT_FALSE(omni.ok());
  EXPECT_EQ(omni.error().code, ErrorCode::kUnsupported);
  fs::remove(yaml);
  EXPECT_EQ(importEuroc(root.string()).error().code, ErrorCode::kNotFound);
}

}  // namespace
}  // namespace vkloc
