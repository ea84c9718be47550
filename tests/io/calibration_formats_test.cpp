// Calibration files of other tools read by loadCalibration: one realistic file per format
// (Kalibr camchain and EuRoC sensor.yaml, OpenCV FileStorage, ROS camera_info, CamOdoCal, COLMAP),
// the model each maps to, camera selection, and one-line errors naming the file and the field.
// Also SequenceCamera <-> LensCamera and the double sphere camera.yaml round trip.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <string>

#include "support/test_support.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/io/calibration.hpp"

namespace vkloc {
namespace {

using test::TempDir;
using test::writeFile;

/// Writes `text` to dir/name and returns the path.
std::string fixture(const TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  EXPECT_TRUE(writeFile(path, text));
  return path;
}

/// Checks the code, that the message is one line starting with the path, and that it contains
/// every one of `parts`.
template <typename R>
void expectError(const R& result, ErrorCode code, const std::string& path, std::initializer_list<const char*> parts) {
  ASSERT_FALSE(result.ok()) << "expected an error from " << path;
  const std::string& message = result.error().message;
  EXPECT_EQ(result.error().code, code) << message;
  EXPECT_EQ(message.rfind(path, 0), 0u) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  for (const char* part : parts)
    EXPECT_NE(message.find(part), std::string::npos) << message << " (wanted " << part << ")";
}

void expectIntrinsics(const SequenceCamera& c, double fx, double fy, double cx, double cy, int width, int height) {
  EXPECT_DOUBLE_EQ(c.intrinsics.fx, fx);
  EXPECT_DOUBLE_EQ(c.intrinsics.fy, fy);
  EXPECT_DOUBLE_EQ(c.intrinsics.cx, cx);
  EXPECT_DOUBLE_EQ(c.intrinsics.cy, cy);
  EXPECT_EQ(c.intrinsics.width, width);
  EXPECT_EQ(c.intrinsics.height, height);
}

// A Kalibr camchain-imucam.yaml: cam0 pinhole-radtan (EuRoC), cam1 pinhole-equi (TUM VI),
// cam2 omni-radtan, cam3 ds-none (TUM VI's double sphere). cam0's T_cam_imu is Rz(90 deg) with a
// translation, written so that its inverse is known by hand.
const char* const kCamchain = R"(cam0:
  T_cam_imu:
  - [0.0, 1.0, 0.0, 0.1]
  - [-1.0, 0.0, 0.0, 0.2]
  - [0.0, 0.0, 1.0, 0.3]
  - [0.0, 0.0, 0.0, 1.0]
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
  distortion_model: radtan
  intrinsics: [458.654, 457.296, 367.215, 248.375]
  resolution: [752, 480]
  rostopic: /cam0/image_raw
  timeshift_cam_imu: 0.0
cam1:
  T_cam_imu:
  - [-0.9995250378696743, 0.029615343885863205, -0.008522328211654736, 0.04727988224914392]
  - [0.0075019185074052044, -0.03439736061393144, -0.9993800792498829, -0.047443232143367084]
  - [-0.02989013031643309, -0.998969345370175, 0.03415885127385616, -0.0681999605066297]
  - [0.0, 0.0, 0.0, 1.0]
  T_cn_cnm1:
  - [0.9999994457734953, -0.0008233639921576076, -0.0006669091105113867, -0.10106110275180535]
  - [0.0008226794704797, 0.9999991804942294, -0.0010256506016451943, -0.0019886675224586]
  - [0.0006677533287219, 0.0010251057325735, 0.9999992516169457, -0.0011040914475354]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_coeffs: [0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182]
  distortion_model: equidistant
  intrinsics: [190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504]
  resolution: [512, 512]
  rostopic: /cam1/image_raw
cam2:
  camera_model: omni
  distortion_coeffs: [-0.0446, 0.0231, 0.00024, -0.00011]
  distortion_model: radtan
  intrinsics: [0.9586, 695.3, 694.9, 320.8, 239.1]
  resolution: [640, 480]
  rostopic: /cam2/image_raw
cam3:
  camera_model: ds
  distortion_coeffs: []
  distortion_model: none
  intrinsics: [-0.18, 0.59, 158.2, 158.1, 254.9, 256.9]
  resolution: [512, 512]
  rostopic: /cam3/image_raw
)";

TEST(CalibrationKalibr, CamchainCamerasAndSelection) {
  TempDir dir("calib_kalibr");
  const std::string path = fixture(dir, "camchain-imucam.yaml", kCamchain);

  auto cam0 = loadCalibration(path);
  ASSERT_TRUE(cam0.ok()) << cam0.error().message;
  EXPECT_EQ(cam0->model, "pinhole");
  expectIntrinsics(*cam0, 458.654, 457.296, 367.215, 248.375, 752, 480);
  EXPECT_EQ(cam0->distortion, (std::vector<double>{-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05}));
  // T_body_camera = T_cam_imu^-1: R^T = Rz(-90)^T... by hand: R_cam_imu = [0 1 0; -1 0 0; 0 0 1],
  // so R_imu_cam = [0 -1 0; 1 0 0; 0 0 1] and t = -R_imu_cam (0.1, 0.2, 0.3) = (0.2, -0.1, -0.3).
  Eigen::Matrix4d expected;
  expected << 0, -1, 0, 0.2, 1, 0, 0, -0.1, 0, 0, 1, -0.3, 0, 0, 0, 1;
  EXPECT_LE((cam0->T_body_camera.matrix() - expected).cwiseAbs().maxCoeff(), 1e-15) << cam0->T_body_camera.matrix();

  // By index and by name, the same camera.
  for (const char* select : {"1", "cam1"}) {
    auto cam1 = loadCalibration(path, select);
    ASSERT_TRUE(cam1.ok()) << cam1.error().message;
    EXPECT_EQ(cam1->model, "kannala_brandt");
    expectIntrinsics(*cam1, 190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504, 512, 512);
    ASSERT_EQ(cam1->distortion.size(), 4u);
    EXPECT_EQ(cam1->distortion[3], 0.00020293673591811182);
    // Its T_cam_imu (not the chain) gives the mounting: T_cam_imu * T_body_camera = I.
    Eigen::Matrix4d T_cam_imu;
    T_cam_imu << -0.9995250378696743, 0.029615343885863205, -0.008522328211654736, 0.04727988224914392,
        0.0075019185074052044, -0.03439736061393144, -0.9993800792498829, -0.047443232143367084, -0.02989013031643309,
        -0.998969345370175, 0.03415885127385616, -0.0681999605066297, 0, 0, 0, 1;
    EXPECT_LE((T_cam_imu * cam1->T_body_camera.matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-6);
  }

  auto omni = loadCalibration(path, "cam2");
  ASSERT_TRUE(omni.ok()) << omni.error().message;
  EXPECT_EQ(omni->model, "mei");
  EXPECT_EQ(omni->xi, 0.9586);
  expectIntrinsics(*omni, 695.3, 694.9, 320.8, 239.1, 640, 480);
  EXPECT_EQ(omni->distortion, (std::vector<double>{-0.0446, 0.0231, 0.00024, -0.00011}));
  EXPECT_TRUE(omni->T_body_camera.isApprox(Pose::Identity()));  // No T_cam_imu and no chain to it.

  auto ds = loadCalibration(path, "3");
  ASSERT_TRUE(ds.ok()) << ds.error().message;
  EXPECT_EQ(ds->model, "double_sphere");
  EXPECT_EQ(ds->xi, -0.18);
  EXPECT_EQ(ds->alpha, 0.59);
  EXPECT_TRUE(ds->distortion.empty());
  expectIntrinsics(*ds, 158.2, 158.1, 254.9, 256.9, 512, 512);
  auto lens = lensCamera(*ds);
  ASSERT_TRUE(lens.ok()) << lens.error().message;
  EXPECT_EQ(lens->model, LensModel::kDoubleSphere);

  // A missing camera lists the available ones.
  expectError(loadCalibration(path, "cam7"), ErrorCode::kNotFound, path, {"cam7", "cam0, cam1, cam2, cam3"});
  expectError(loadCalibration(path, "left"), ErrorCode::kNotFound, path, {"left", "cam0, cam1, cam2, cam3"});
}

TEST(CalibrationKalibr, CameraOnlyChainPlacesCamerasFromCam0) {
  TempDir dir("calib_chain");
  // A stereo camchain.yaml without IMU: cam1 is 11 cm right of cam0 (T_c1_c0 translation -0.11 x).
  const std::string path = fixture(dir, "camchain.yaml", R"(cam0:
  camera_model: pinhole
  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]
  distortion_model: radtan
  intrinsics: [500.0, 500.0, 320.0, 240.0]
  resolution: [640, 480]
cam1:
  T_cn_cnm1:
  - [1.0, 0.0, 0.0, -0.11]
  - [0.0, 1.0, 0.0, 0.0]
  - [0.0, 0.0, 1.0, 0.0]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_model: none
  intrinsics: [501.0, 501.0, 321.0, 241.0]
  resolution: [640, 480]
)");
  auto cam0 = loadCalibration(path, "0");
  ASSERT_TRUE(cam0.ok()) << cam0.error().message;
  EXPECT_TRUE(cam0->distortion.empty());  // All-zero radtan is an ideal pinhole.
  EXPECT_TRUE(cam0->T_body_camera.isApprox(Pose::Identity()));
  auto cam1 = loadCalibration(path, "cam1");
  ASSERT_TRUE(cam1.ok()) << cam1.error().message;
  EXPECT_LE((cam1->T_body_camera.translation() - Eigen::Vector3d(0.11, 0, 0)).norm(), 1e-15);
  EXPECT_TRUE(cam1->T_body_camera.linear().isIdentity(0.0));
}

TEST(CalibrationKalibr, EurocSensorYaml) {
  TempDir dir("calib_euroc");
  const std::string path = fixture(dir, "sensor.yaml", R"(%YAML:1.0
# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]

# Camera specific definitions.
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)");
  auto cam = loadCalibration(path);
  ASSERT_TRUE(cam.ok()) << cam.error().message;
  EXPECT_EQ(cam->model, "pinhole");
  expectIntrinsics(*cam, 458.654, 457.296, 367.215, 248.375, 752, 480);
  EXPECT_EQ(cam->distortion.size(), 4u);
  // T_BS is T_body_camera itself (re-orthonormalised: printed with 12 digits).
  EXPECT_NEAR(cam->T_body_camera.matrix()(0, 1), -0.999880929698, 1e-9);
  EXPECT_NEAR(cam->T_body_camera.translation().y(), -0.064676986768, 1e-15);
  EXPECT_TRUE(loadCalibration(path, "cam0").ok());
  expectError(loadCalibration(path, "cam1"), ErrorCode::kNotFound, path, {"cam1"});

  // Equidistant is Kannala-Brandt.
  const std::string equi = fixture(dir, "equi.yaml",
                                   "camera_model: pinhole\nintrinsics: [190.97, 190.97, 254.93, 256.89]\n"
                                   "distortion_model: equidistant\n"
                                   "distortion_coefficients: [0.0034, 0.0007, -0.0020, 0.0002]\n"
                                   "resolution: [512, 512]\n");
  auto kb = loadCalibration(equi);
  ASSERT_TRUE(kb.ok()) << kb.error().message;
  EXPECT_EQ(kb->model, "kannala_brandt");
}

TEST(CalibrationKalibr, ErrorsNameFileAndField) {
  TempDir dir("calib_kalibr_bad");
  const std::string base = "camera_model: pinhole\ndistortion_model: radtan\n";
  const std::string missing =
      fixture(dir, "missing.yaml", "cam0:\n  camera_model: pinhole\n  intrinsics: [458.6, 457.3, 367.2, 248.4]\n");
  expectError(loadCalibration(missing), ErrorCode::kMalformedInput, missing, {"cam0", "field 'resolution'", "missing"});

  const std::string count = fixture(dir, "cam.yaml",
                                    base +
                                        "intrinsics: [458.6, 457.3, 367.2]\nresolution: [752, 480]\n"
                                        "distortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]\n");
  expectError(loadCalibration(count), ErrorCode::kMalformedInput, count,
              {"field 'intrinsics'", "expected 4 numbers for pinhole, got 3"});

  const std::string nan = fixture(dir, "nan.yaml",
                                  "cam0:\n  camera_model: pinhole\n  intrinsics: [458.6, .nan, 367.2, 248.4]\n"
                                  "  resolution: [752, 480]\n");
  expectError(loadCalibration(nan), ErrorCode::kMalformedInput, nan, {"cam0", "field 'intrinsics'"});

  const std::string coefficients = fixture(dir, "coefficients.yaml",
                                           base +
                                               "intrinsics: [458.6, 457.3, 367.2, 248.4]\nresolution: [752, 480]\n"
                                               "distortion_coeffs: [-0.28, 0.07, 0.0002]\n");
  expectError(loadCalibration(coefficients), ErrorCode::kMalformedInput, coefficients,
              {"field 'distortion_coeffs'", "got 3"});

  const std::string unknown = fixture(dir, "unknown.yaml",
                                      "cam0:\n  camera_model: fisheye62\n  intrinsics: [458.6, 457.3, 367.2, 248.4]\n"
                                      "  resolution: [752, 480]\n");
  expectError(loadCalibration(unknown), ErrorCode::kUnsupported, unknown,
              {"field 'camera_model'", "fisheye62", "pinhole, omni, ds"});

  const std::string eucm = fixture(dir, "eucm.yaml",
                                   "cam0:\n  camera_model: eucm\n  intrinsics: [0.6, 1.1, 380, 380, 320, 240]\n"
                                   "  distortion_model: none\n  resolution: [640, 480]\n");
  expectError(loadCalibration(eucm), ErrorCode::kUnsupported, eucm, {"field 'camera_model'", "eucm", "not supported"});

  const std::string fov = fixture(dir, "fov.yaml",
                                  "camera_model: pinhole\ndistortion_model: fov\ndistortion_coeffs: [0.9]\n"
                                  "intrinsics: [458.6, 457.3, 367.2, 248.4]\nresolution: [752, 480]\n");
  expectError(loadCalibration(fov), ErrorCode::kUnsupported, fov, {"field 'distortion_model'", "fov"});

  // Out of range for the model: validateLensCamera's verdict, pointed at the field.
  const std::string alpha =
      fixture(dir, "alpha.yaml",
              "cam0:\n  camera_model: ds\n  intrinsics: [-0.18, 1.5, 158.2, 158.1, 254.9, 256.9]\n"
              "  distortion_model: none\n  resolution: [512, 512]\n");
  expectError(loadCalibration(alpha), ErrorCode::kMalformedInput, alpha, {"cam0", "field 'intrinsics'", "alpha"});

  const std::string rigid = fixture(dir, "rigid.yaml",
                                    "cam0:\n  camera_model: pinhole\n  intrinsics: [458.6, 457.3, 367.2, 248.4]\n"
                                    "  resolution: [752, 480]\n  T_cam_imu:\n  - [2, 0, 0, 0]\n  - [0, 1, 0, 0]\n"
                                    "  - [0, 0, 1, 0]\n  - [0, 0, 0, 1]\n");
  expectError(loadCalibration(rigid), ErrorCode::kMalformedInput, rigid, {"field 'T_cam_imu'", "rigid"});
}

// ---------------------------------------------------------------------------------------------
// OpenCV FileStorage and ROS camera_info.

TEST(CalibrationOpenCv, FileStorageYaml) {
  TempDir dir("calib_opencv");
  // As written by OpenCV's calibration sample (cv::FileStorage): the %YAML:1.0 header and tags.
  const std::string path = fixture(dir, "out_camera_data.yml", R"(%YAML:1.0
---
calibration_time: "Wed 08 Jun 2022 10:00:00 AM CEST"
nr_of_frames: 25
image_width: 640
image_height: 480
board_width: 9
board_height: 6
square_size: 2.5000000372529030e-02
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 5.2892445374086585e+02, 0., 3.1951186034269096e+02, 0.,
       5.2899417786438362e+02, 2.3953421823402596e+02, 0., 0., 1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -9.1544307418478733e-02, 2.1556240513573453e-01,
       -1.2061924463233017e-03, 4.8651993213101541e-04,
       -1.2451015426580689e-01 ]
avg_reprojection_error: 3.3196786453069627e-01
)");
  auto cam = loadCalibration(path);
  ASSERT_TRUE(cam.ok()) << cam.error().message;
  EXPECT_EQ(cam->model, "pinhole");
  expectIntrinsics(*cam, 5.2892445374086585e+02, 5.2899417786438362e+02, 3.1951186034269096e+02, 2.3953421823402596e+02,
                   640, 480);
  ASSERT_EQ(cam->distortion.size(), 5u);
  EXPECT_EQ(cam->distortion[4], -1.2451015426580689e-01);

  // K / D of OpenCV's fisheye module: Kannala-Brandt.
  const std::string fisheye = fixture(dir, "fisheye.yml", R"(%YAML:1.0
---
model: fisheye
image_width: 1280
image_height: 800
K: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 4.0e+02, 0., 6.4e+02, 0., 4.01e+02, 4.0e+02, 0., 0., 1. ]
D: !!opencv-matrix
   rows: 4
   cols: 1
   dt: d
   data: [ 5.0e-02, -1.0e-02, 2.0e-03, -3.0e-04 ]
)");
  auto kb = loadCalibration(fisheye);
  ASSERT_TRUE(kb.ok()) << kb.error().message;
  EXPECT_EQ(kb->model, "kannala_brandt");
  expectIntrinsics(*kb, 400, 401, 640, 400, 1280, 800);
  EXPECT_EQ(kb->distortion, (std::vector<double>{5.0e-02, -1.0e-02, 2.0e-03, -3.0e-04}));

  // Rational model: accepted when k4..k6 are zero, refused otherwise.
  const std::string head =
      "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\ncamera_matrix: !!opencv-matrix\n   rows: 3\n"
      "   cols: 3\n   dt: d\n   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n"
      "distortion_coefficients: !!opencv-matrix\n   rows: 8\n   cols: 1\n   dt: d\n";
  const std::string zero =
      fixture(dir, "rational0.yml", head + "   data: [ -0.1, 0.02, 0.001, 0.0, 0.003, 0., 0., 0. ]\n");
  auto rational0 = loadCalibration(zero);
  ASSERT_TRUE(rational0.ok()) << rational0.error().message;
  EXPECT_EQ(rational0->distortion, (std::vector<double>{-0.1, 0.02, 0.001, 0.0, 0.003}));
  const std::string rational =
      fixture(dir, "rational.yml", head + "   data: [ -0.1, 0.02, 0.001, 0.0, 0.003, 0.2, 0., 0. ]\n");
  expectError(loadCalibration(rational), ErrorCode::kUnsupported, rational, {"field 'distortion_coefficients'"});

  // Errors: wrong count (rows x cols disagree with data), NaN, missing size.
  const std::string wrong = fixture(dir, "wrong.yml",
                                    "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
                                    "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                                    "   data: [ 500., 0., 320., 0., 500., 240., 0., 0. ]\n");
  expectError(loadCalibration(wrong), ErrorCode::kMalformedInput, wrong, {"field 'camera_matrix'", "8"});
  // rows x cols is not computed with overflow (fuzz finding): 3689348814741910325 x 5 wraps to 9.
  const std::string huge = fixture(dir, "huge.yml",
                                   "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
                                   "camera_matrix: !!opencv-matrix\n   rows: 3689348814741910325\n   cols: 5\n"
                                   "   dt: d\n   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n");
  expectError(loadCalibration(huge), ErrorCode::kMalformedInput, huge,
              {"field 'camera_matrix'", "3689348814741910325x5 matrix but 'data' holds 9 numbers"});
  const std::string nan = fixture(dir, "nan.yml",
                                  "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n"
                                  "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                                  "   data: [ .Nan, 0., 320., 0., 500., 240., 0., 0., 1. ]\n");
  expectError(loadCalibration(nan), ErrorCode::kMalformedInput, nan, {"field 'camera_matrix'"});
  const std::string size = fixture(dir, "size.yml",
                                   "%YAML:1.0\n---\nimage_width: 640\n"
                                   "camera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
                                   "   data: [ 500., 0., 320., 0., 500., 240., 0., 0., 1. ]\n");
  expectError(loadCalibration(size), ErrorCode::kMalformedInput, size, {"field 'image_height'", "missing"});
}

TEST(CalibrationOpenCv, RosCameraInfo) {
  TempDir dir("calib_ros");
  // As written by camera_calibration_parsers (ROS camera_calibration's ost.yaml).
  const std::string path = fixture(dir, "ost.yaml", R"(image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [430.215550, 0.000000, 306.691343, 0.000000, 430.531693, 227.224800, 0.000000, 0.000000, 1.000000]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.337586, 0.111612, -0.000218, -0.000030, 0.000000]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1.000000, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000, 0.000000, 0.000000, 1.000000]
projection_matrix:
  rows: 3
  cols: 4
  data: [340.183502, 0.000000, 305.057608, 0.000000, 0.000000, 389.961487, 220.675036, 0.000000, 0.000000, 0.000000, 1.000000, 0.000000]
)");
  auto cam = loadCalibration(path);
  ASSERT_TRUE(cam.ok()) << cam.error().message;
  EXPECT_EQ(cam->model, "pinhole");
  expectIntrinsics(*cam, 430.215550, 430.531693, 306.691343, 227.224800, 640, 480);
  EXPECT_EQ(cam->distortion, (std::vector<double>{-0.337586, 0.111612, -0.000218, -0.000030}));  // k3 = 0 dropped.
  EXPECT_TRUE(loadCalibration(path, "narrow_stereo").ok());
  expectError(loadCalibration(path, "wide_stereo"), ErrorCode::kNotFound, path, {"wide_stereo", "narrow_stereo"});

  const std::string equi = fixture(dir, "equi.yaml", R"(image_width: 848
image_height: 800
camera_name: t265_fisheye1
camera_matrix:
  rows: 3
  cols: 3
  data: [286.1809, 0, 421.6230, 0, 286.3054, 403.2130, 0, 0, 1]
distortion_model: equidistant
distortion_coefficients:
  rows: 1
  cols: 4
  data: [-0.0109, 0.0468, -0.0444, 0.0083]
)");
  auto kb = loadCalibration(equi);
  ASSERT_TRUE(kb.ok()) << kb.error().message;
  EXPECT_EQ(kb->model, "kannala_brandt");
  expectIntrinsics(*kb, 286.1809, 286.3054, 421.6230, 403.2130, 848, 800);
  EXPECT_EQ(kb->distortion, (std::vector<double>{-0.0109, 0.0468, -0.0444, 0.0083}));

  const std::string unknown = fixture(dir, "unknown.yaml",
                                      "image_width: 640\nimage_height: 480\ncamera_matrix:\n  rows: 3\n  cols: 3\n"
                                      "  data: [430, 0, 306, 0, 430, 227, 0, 0, 1]\ndistortion_model: fov\n"
                                      "distortion_coefficients:\n  rows: 1\n  cols: 1\n  data: [0.9]\n");
  expectError(loadCalibration(unknown), ErrorCode::kUnsupported, unknown,
              {"field 'distortion_model'", "fov", "plumb_bob, rational_polynomial, equidistant"});
}

// ---------------------------------------------------------------------------------------------
// CamOdoCal (VINS-Mono / VINS-Fusion configs).

TEST(CalibrationCamOdoCal, MeiAndKannalaBrandt) {
  TempDir dir("calib_camodocal");
  const std::string mei = fixture(dir, "mei.yaml", R"(%YAML:1.0
---
model_type: MEI
camera_name: camera
image_width: 752
image_height: 480
mirror_parameters:
   xi: 1.8476534
distortion_parameters:
   k1: -0.0659781
   k2: 0.8559479
   p1: -0.0006446
   p2: 0.0015137
projection_parameters:
   gamma1: 1338.1845
   gamma2: 1340.1190
   u0: 378.7910
   v0: 217.6767
)");
  auto cam = loadCalibration(mei);
  ASSERT_TRUE(cam.ok()) << cam.error().message;
  EXPECT_EQ(cam->model, "mei");
  EXPECT_EQ(cam->xi, 1.8476534);
  expectIntrinsics(*cam, 1338.1845, 1340.1190, 378.7910, 217.6767, 752, 480);
  EXPECT_EQ(cam->distortion, (std::vector<double>{-0.0659781, 0.8559479, -0.0006446, 0.0015137}));
  EXPECT_TRUE(loadCalibration(mei, "camera").ok());

  const std::string kb = fixture(dir, "kb.yaml", R"(%YAML:1.0
---
model_type: KANNALA_BRANDT
camera_name: camera
image_width: 752
image_height: 480
projection_parameters:
   k2: -0.0131
   k3: 0.0214
   k4: -0.0184
   k5: 0.0057
   mu: 461.4
   mv: 460.3
   u0: 362.9
   v0: 246.6
)");
  auto fisheye = loadCalibration(kb);
  ASSERT_TRUE(fisheye.ok()) << fisheye.error().message;
  EXPECT_EQ(fisheye->model, "kannala_brandt");
  expectIntrinsics(*fisheye, 461.4, 460.3, 362.9, 246.6, 752, 480);
  EXPECT_EQ(fisheye->distortion, (std::vector<double>{-0.0131, 0.0214, -0.0184, 0.0057}));

  const std::string pinhole = fixture(dir, "pinhole.yaml",
                                      "%YAML:1.0\n---\nmodel_type: PINHOLE\ncamera_name: camera\nimage_width: 752\n"
                                      "image_height: 480\ndistortion_parameters:\n   k1: -0.2834\n   k2: 0.0740\n"
                                      "   p1: 0.0002\n   p2: 0.00002\nprojection_parameters:\n   fx: 458.654\n"
                                      "   fy: 457.296\n   cx: 367.215\n   cy: 248.375\n");
  auto radtan = loadCalibration(pinhole);
  ASSERT_TRUE(radtan.ok()) << radtan.error().message;
  EXPECT_EQ(radtan->model, "pinhole");
  EXPECT_EQ(radtan->distortion, (std::vector<double>{-0.2834, 0.0740, 0.0002, 0.00002}));

  // A missing parameter is named with its section; unknown and unsupported models by name.
  const std::string missing = fixture(dir, "missing.yaml",
                                      "model_type: MEI\nimage_width: 752\nimage_height: 480\nmirror_parameters:\n"
                                      "   xi: 1.8\ndistortion_parameters:\n   k1: 0\n   k2: 0\n   p1: 0\n   p2: 0\n"
                                      "projection_parameters:\n   gamma1: 1338\n   u0: 378\n   v0: 217\n");
  expectError(loadCalibration(missing), ErrorCode::kMalformedInput, missing,
              {"field 'projection_parameters.gamma2'", "missing"});
  const std::string negative = fixture(dir, "negative.yaml",
                                       "model_type: MEI\nimage_width: 752\nimage_height: 480\nmirror_parameters:\n"
                                       "   xi: -0.5\ndistortion_parameters:\n   k1: 0\n   k2: 0\n   p1: 0\n   p2: 0\n"
                                       "projection_parameters:\n   gamma1: 1338\n   gamma2: 1340\n   u0: 378\n"
                                       "   v0: 217\n");
  expectError(loadCalibration(negative), ErrorCode::kMalformedInput, negative, {"field 'mirror_parameters.xi'", "xi"});
  const std::string scaramuzza = fixture(dir, "scaramuzza.yaml", "model_type: SCARAMUZZA\nimage_width: 752\n");
  expectError(loadCalibration(scaramuzza), ErrorCode::kUnsupported, scaramuzza,
              {"field 'model_type'", "SCARAMUZZA", "MEI, KANNALA_BRANDT, PINHOLE"});
  const std::string unknown = fixture(dir, "unknown.yaml", "model_type: FISHEYE\nimage_width: 752\n");
  expectError(loadCalibration(unknown), ErrorCode::kUnsupported, unknown, {"FISHEYE", "MEI, KANNALA_BRANDT, PINHOLE"});
}

// ---------------------------------------------------------------------------------------------
// COLMAP cameras.txt.

TEST(CalibrationColmap, CamerasTxt) {
  TempDir dir("calib_colmap");
  const std::string path = fixture(dir, "cameras.txt", R"(# Camera list with one line of data per camera:
#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]
# Number of cameras: 5
1 PINHOLE 640 480 500.5 501.5 320 240
2 OPENCV 1920 1080 1500 1510 960 540 -0.1 0.02 0.001 -0.002

3 OPENCV_FISHEYE 1280 1024 400 401 640 512 0.05 -0.01 0.002 -0.0003
4 FOV 640 480 300 300 320 240 0.9
5 SIMPLE_RADIAL 640 480 520 320 240 -0.05
)");
  // COLMAP's pixel centres are at half-integers: cx, cy move by -0.5.
  auto first = loadCalibration(path);
  ASSERT_TRUE(first.ok()) << first.error().message;
  EXPECT_EQ(first->model, "pinhole");
  expectIntrinsics(*first, 500.5, 501.5, 319.5, 239.5, 640, 480);
  EXPECT_TRUE(first->distortion.empty());

  auto opencv = loadCalibration(path, "2");
  ASSERT_TRUE(opencv.ok()) << opencv.error().message;
  EXPECT_EQ(opencv->model, "pinhole");
  expectIntrinsics(*opencv, 1500, 1510, 959.5, 539.5, 1920, 1080);
  EXPECT_EQ(opencv->distortion, (std::vector<double>{-0.1, 0.02, 0.001, -0.002}));

  auto fisheye = loadCalibration(path, "3");
  ASSERT_TRUE(fisheye.ok()) << fisheye.error().message;
  EXPECT_EQ(fisheye->model, "kannala_brandt");
  expectIntrinsics(*fisheye, 400, 401, 639.5, 511.5, 1280, 1024);
  EXPECT_EQ(fisheye->distortion, (std::vector<double>{0.05, -0.01, 0.002, -0.0003}));

  auto radial = loadCalibration(path, "5");
  ASSERT_TRUE(radial.ok()) << radial.error().message;
  expectIntrinsics(*radial, 520, 520, 319.5, 239.5, 640, 480);
  EXPECT_EQ(radial->distortion, (std::vector<double>{-0.05, 0, 0, 0}));

  expectError(loadCalibration(path, "4"), ErrorCode::kUnsupported,
              path + ":8:", {"camera 4", "field 'MODEL'", "FOV", "PINHOLE", "OPENCV_FISHEYE"});
  expectError(loadCalibration(path, "9"), ErrorCode::kNotFound, path, {"9", "1, 2, 3, 4, 5"});

  const std::string count = fixture(dir, "count.txt", "1 PINHOLE 640 480 500 500 320\n");
  expectError(loadCalibration(count), ErrorCode::kMalformedInput,
              count + ":1:", {"field 'PARAMS'", "expected 4 numbers for PINHOLE, got 3"});
  const std::string nan = fixture(dir, "nan.txt", "# c\n1 PINHOLE 640 480 500 nan 320 240\n");
  expectError(loadCalibration(nan), ErrorCode::kMalformedInput, nan + ":2:", {"field 'PARAMS'"});
  const std::string focal = fixture(dir, "focal.txt", "1 SIMPLE_PINHOLE 640 480 -500 320 240\n");
  expectError(loadCalibration(focal), ErrorCode::kMalformedInput, focal, {"field 'PARAMS'", "fx"});
}

// ---------------------------------------------------------------------------------------------
// vkloc's own files, detection, and errors every format shares.

TEST(CalibrationFiles, VklocAndFlatFiles) {
  TempDir dir("calib_vkloc");
  SequenceCamera ds;
  ds.model = "double_sphere";
  ds.intrinsics = PinholeCamera{158.2, 158.1, 254.9, 256.9, 512, 512};
  ds.xi = -0.18;
  ds.alpha = 0.59;
  ds.max_angle_deg = 97.5;
  ds.T_body_camera.translation() = Eigen::Vector3d(0.01, -0.02, 0.03);
  ASSERT_TRUE(saveSequenceCamera(ds, dir.file("camera.yaml")).ok());
  for (auto loaded : {loadSequenceCamera(dir.file("camera.yaml")), loadCalibration(dir.file("camera.yaml"))}) {
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    EXPECT_EQ(loaded->model, "double_sphere");
    EXPECT_EQ(loaded->xi, ds.xi);
    EXPECT_EQ(loaded->alpha, ds.alpha);
    EXPECT_EQ(loaded->max_angle_deg, ds.max_angle_deg);
    expectIntrinsics(*loaded, 158.2, 158.1, 254.9, 256.9, 512, 512);
    EXPECT_TRUE(loaded->T_body_camera.isApprox(ds.T_body_camera, 1e-15));
  }

  const std::string json = fixture(
      dir, "camera.json", R"({"fx": 525.0, "fy": 525.0, "cx": 319.5, "cy": 239.5, "width": 640, "height": 480})");
  auto flat = loadCalibration(json);
  ASSERT_TRUE(flat.ok()) << flat.error().message;
  EXPECT_EQ(flat->model, "pinhole");
  expectIntrinsics(*flat, 525, 525, 319.5, 239.5, 640, 480);
  auto pinhole = loadCamera(json);  // The plain reader still reads it.
  ASSERT_TRUE(pinhole.ok()) << pinhole.error().message;
  EXPECT_EQ(pinhole->fx, 525.0);

  const std::string nested = fixture(
      dir, "nested.yaml", "intrinsics:\n  fx: 500\n  fy: 501\n  cx: 320\n  cy: 240\n  width: 640\n  height: 480\n");
  auto sub = loadCalibration(nested);
  ASSERT_TRUE(sub.ok()) << sub.error().message;
  EXPECT_EQ(sub->intrinsics.fy, 501);

  // A double sphere camera.yaml with alpha out of range names the field and its line.
  const std::string bad = fixture(dir, "bad.yaml",
                                  "model: double_sphere\nfx: 158\nfy: 158\ncx: 255\ncy: 257\nwidth: 512\nheight: 512\n"
                                  "xi: -0.18\nalpha: 1.59\n");
  expectError(loadCalibration(bad), ErrorCode::kMalformedInput, bad + ":9:", {"field 'alpha'"});
}

TEST(CalibrationFiles, UnknownMissingAndBrokenFiles) {
  TempDir dir("calib_bad");
  expectError(loadCalibration(dir.file("nothing.yaml")), ErrorCode::kNotFound, dir.file("nothing.yaml"), {});
  const std::string other = fixture(dir, "other.yaml", "name: not a camera\nvalue: 3\n");
  expectError(loadCalibration(other), ErrorCode::kUnsupported, other, {"Kalibr", "COLMAP"});
  const std::string list = fixture(dir, "list.yaml", "- 1\n- 2\n");
  expectError(loadCalibration(list), ErrorCode::kUnsupported, list, {});
  const std::string syntax = fixture(dir, "syntax.yaml", "cam0:\n  intrinsics: [1, 2\n  resolution: [3, 4]\n");
  expectError(loadCalibration(syntax), ErrorCode::kMalformedInput, syntax, {"YAML"});
  const std::string binary = fixture(dir, "binary.yaml", std::string("\x00\x01\xff\xfe[{]\t\n%", 10));
  EXPECT_FALSE(loadCalibration(binary).ok());
  // Wrong types never throw: a list where a number belongs, a mapping where a list belongs.
  const std::string types =
      fixture(dir, "types.yaml", "cam0:\n  camera_model: [pinhole]\n  intrinsics: {fu: 1}\n  resolution: 640\n");
  expectError(loadCalibration(types), ErrorCode::kMalformedInput, types, {"cam0", "field 'camera_model'"});
}

TEST(CalibrationFiles, TruncatedFilesNeverCrash) {
  TempDir dir("calib_truncated");
  const std::string colmap =
      "# c\n1 OPENCV 1920 1080 1500 1510 960 540 -0.1 0.02 0.001 -0.002\n2 PINHOLE 64 48 50 50 32 24\n";
  const std::string camodocal =
      "%YAML:1.0\n---\nmodel_type: KANNALA_BRANDT\nimage_width: 752\nimage_height: 480\nprojection_parameters:\n"
      "   k2: -0.0131\n   k3: 0.0214\n   k4: -0.0184\n   k5: 0.0057\n   mu: 461.4\n   mv: 460.3\n   u0: 362.9\n"
      "   v0: 246.6\n";
  for (const std::string& full : {std::string(kCamchain), colmap, camodocal}) {
    for (size_t n = 0; n < full.size(); n += 9) {
      const std::string path = fixture(dir, "cut.yaml", full.substr(0, n));
      for (const char* select : {"", "cam3"}) {
        auto result = loadCalibration(path, select);
        if (!result.ok()) {
          EXPECT_EQ(result.error().message.rfind(path, 0), 0u) << result.error().message;
          EXPECT_EQ(result.error().message.find('\n'), std::string::npos) << result.error().message;
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// SequenceCamera <-> LensCamera.

TEST(CalibrationLens, ConversionsRoundTripAndNameTheField) {
  SequenceCamera pinhole;
  pinhole.intrinsics = PinholeCamera{517.3, 516.5, 318.6, 255.3, 640, 480};
  pinhole.distortion = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  SequenceCamera kb = pinhole;
  kb.model = "kannala_brandt";
  kb.distortion = {0.01, -0.002, 3e-4, -4e-5};
  SequenceCamera mei = pinhole;
  mei.model = "mei";
  mei.distortion = {-0.1, 0.01, 1e-4, -2e-4};
  mei.xi = 1.7;
  SequenceCamera ds = pinhole;
  ds.model = "double_sphere";
  ds.distortion.clear();
  ds.xi = -0.2;
  ds.alpha = 0.6;
  ds.max_angle_deg = 95;
  Pose T = Pose::Identity();
  T.translation() = Eigen::Vector3d(0.1, 0.2, 0.3);
  for (SequenceCamera c : {pinhole, kb, mei, ds}) {
    c.T_body_camera = T;
    auto lens = lensCamera(c);
    ASSERT_TRUE(lens.ok()) << c.model << ": " << lens.error().message;
    EXPECT_STREQ(lensModelName(lens->model), c.model.c_str());
    const SequenceCamera back = sequenceCamera(*lens, T);
    EXPECT_EQ(back.model, c.model);
    EXPECT_EQ(back.distortion, c.distortion);
    EXPECT_EQ(back.xi, c.xi);
    EXPECT_EQ(back.alpha, c.alpha);
    EXPECT_EQ(back.max_angle_deg, c.max_angle_deg);
    EXPECT_EQ(back.intrinsics.fx, c.intrinsics.fx);
    EXPECT_TRUE(back.T_body_camera.isApprox(T));
  }

  SequenceCamera bad = pinhole;
  bad.model = "fisheye";
  auto unknown = lensCamera(bad);
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.error().message.rfind("model:", 0), 0u) << unknown.error().message;
  EXPECT_NE(unknown.error().message.find("double_sphere"), std::string::npos) << unknown.error().message;
  bad = mei;
  bad.distortion.pop_back();
  auto count = lensCamera(bad);
  ASSERT_FALSE(count.ok());
  EXPECT_EQ(count.error().message.rfind("distortion:", 0), 0u) << count.error().message;
  bad = ds;
  bad.alpha = std::numeric_limits<double>::quiet_NaN();
  auto nan = lensCamera(bad);
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.error().message.find("alpha"), std::string::npos) << nan.error().message;
  bad = pinhole;
  bad.xi = 0.5;
  auto xi = lensCamera(bad);
  ASSERT_FALSE(xi.ok());
  EXPECT_NE(xi.error().message.find("xi"), std::string::npos) << xi.error().message;
}

}  // namespace
}  // namespace vkloc
