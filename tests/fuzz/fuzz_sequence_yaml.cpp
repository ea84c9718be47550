// sequence.yaml (loadSequence on a folder whose camera.yaml and images.txt are fixed and valid).
// A loaded sequence has rigid poses, finite vectors, unit_scale and IMU noise finite and > 0;
// saveSequence accepts it and loadSequence of the saved folder gives it back (exactly, except
// initial_T_world_camera's rotation, which passes through a quaternion, and
// initial_velocity_world, which is written with 9 significant digits); errors name the file.
#include <cmath>
#include <filesystem>
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/sequence.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

namespace {

constexpr const char* kCamera = "model: pinhole\nfx: 500\nfy: 500\ncx: 319.5\ncy: 239.5\nwidth: 640\nheight: 480\n";
constexpr const char* kImages = "0.05 images/000000.png\n0.1 images/000001.png\n";

const std::string& sequenceDir() {
  static const std::string dir = [] {
    const std::string d = scratchPath("sequence");
    std::filesystem::create_directories(d);
    writeInput(d + "/camera.yaml", kCamera);
    writeInput(d + "/images.txt", kImages);
    return d;
  }();
  return dir;
}

bool finitePositive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string& dir = sequenceDir();
  const std::string path = dir + "/sequence.yaml";
  static const std::string saved_dir = scratchPath("saved_sequence");
  writeInput(path, data, size);
  const auto loaded = loadSequence(dir);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, "sequence");
    return 0;
  }
  const Sequence& s = *loaded;
  check(isValidPose(s.T_world_model), "sequence.valid", "T_world_model is not rigid");
  check(!s.initial_T_world_camera || isValidPose(*s.initial_T_world_camera), "sequence.valid",
        "initial_T_world_camera is not rigid");
  check(finitePositive(s.unit_scale), "sequence.valid", "unit_scale is not finite and > 0");
  check(s.gravity_world.allFinite(), "sequence.valid", "gravity_world is not finite");
  check(!s.initial_velocity_world || s.initial_velocity_world->allFinite(), "sequence.valid",
        "initial_velocity_world is not finite");
  if (s.imu_noise) {
    const ImuNoise& n = *s.imu_noise;
    check(finitePositive(n.rate_hz) && finitePositive(n.gyro_noise_density) && finitePositive(n.accel_noise_density) &&
              finitePositive(n.gyro_random_walk) && finitePositive(n.accel_random_walk),
          "sequence.valid", "IMU noise is not finite and > 0");
  }

  const Status st = saveSequence(s, saved_dir);
  check(st.ok(), "sequence.save_accepts_loaded", st.ok() ? "" : st.error().message);
  if (!st.ok()) return 0;
  const auto again = loadSequence(saved_dir);
  check(again.ok(), "sequence.roundtrip", again.ok() ? "" : again.error().message);
  if (!again.ok()) return 0;
  const Sequence& r = *again;
  check(r.name == s.name, "sequence.roundtrip_text", "name differs: '" + s.name + "' / '" + r.name + "'");
  check(r.model == s.model, "sequence.roundtrip_text", "model differs: '" + s.model + "' / '" + r.model + "'");
  check(r.T_world_model.matrix() == s.T_world_model.matrix(), "sequence.roundtrip", "T_world_model differs");
  check(r.unit_scale == s.unit_scale, "sequence.roundtrip", "unit_scale differs");
  check(r.gravity_world == s.gravity_world, "sequence.roundtrip", "gravity_world differs");
  check(r.initial_T_world_camera.has_value() == s.initial_T_world_camera.has_value(), "sequence.roundtrip",
        "initial_T_world_camera presence differs");
  if (r.initial_T_world_camera && s.initial_T_world_camera) {
    const Pose& a = *s.initial_T_world_camera;
    const Pose& b = *r.initial_T_world_camera;
    check(a.translation() == b.translation() && (a.linear() - b.linear()).cwiseAbs().maxCoeff() <= 1e-12,
          "sequence.roundtrip", "initial_T_world_camera differs");
  }
  check(r.initial_velocity_world.has_value() == s.initial_velocity_world.has_value(), "sequence.roundtrip",
        "initial_velocity_world presence differs");
  if (r.initial_velocity_world && s.initial_velocity_world) {
    for (int k = 0; k < 3; ++k) {
      check(nearRelative((*s.initial_velocity_world)[k], (*r.initial_velocity_world)[k], 1e-8), "sequence.roundtrip",
            "initial_velocity_world differs");
    }
  }
  check(r.imu_noise.has_value() == s.imu_noise.has_value(), "sequence.roundtrip", "imu_noise presence differs");
  if (r.imu_noise && s.imu_noise) {
    const ImuNoise &a = *s.imu_noise, &b = *r.imu_noise;
    check(a.rate_hz == b.rate_hz && a.gyro_noise_density == b.gyro_noise_density &&
              a.accel_noise_density == b.accel_noise_density && a.gyro_random_walk == b.gyro_random_walk &&
              a.accel_random_walk == b.accel_random_walk,
          "sequence.roundtrip", "imu_noise differs");
  }
  const std::string camera = cameraDifference(s.camera, r.camera);
  check(camera.empty(), "sequence.roundtrip", "camera " + camera + " differs");
  check(r.images.size() == s.images.size(), "sequence.roundtrip", "image count differs");
  return 0;
}
