// TUM trajectory files (loadTumTrajectory): a loaded trajectory has increasing timestamps and
// rigid poses, and saveTumTrajectory then loadTumTrajectory gives it back.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/sequence.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("groundtruth.txt");
  static const std::string saved = scratchPath("saved.txt");
  writeInput(path, data, size);
  const auto loaded = loadTumTrajectory(path);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, "tum");
    return 0;
  }
  const std::vector<StampedPose>& poses = *loaded;
  for (size_t i = 0; i < poses.size(); ++i) {
    check(isValidPose(poses[i].T_world_camera), "tum.valid_pose", "pose " + std::to_string(i) + " is not rigid");
    check(i == 0 || poses[i].t_ns > poses[i - 1].t_ns, "tum.increasing", "timestamp " + std::to_string(i));
  }
  const Status st = saveTumTrajectory(poses, saved);
  check(st.ok(), "tum.save_accepts_loaded", st.ok() ? "" : st.error().message);
  if (!st.ok()) return 0;
  const auto again = loadTumTrajectory(saved);
  check(again.ok(), "tum.roundtrip", again.ok() ? "" : again.error().message);
  if (!again.ok()) return 0;
  check(again->size() == poses.size(), "tum.roundtrip", "pose count differs");
  for (size_t i = 0; i < std::min(poses.size(), again->size()); ++i) {
    const StampedPose& a = poses[i];
    const StampedPose& b = (*again)[i];
    check(a.t_ns == b.t_ns, "tum.roundtrip", "timestamp " + std::to_string(i) + " differs");
    // Translations are written with 17 digits (exact); rotations pass through a quaternion.
    check(a.T_world_camera.translation() == b.T_world_camera.translation(), "tum.roundtrip",
          "translation " + std::to_string(i) + " differs");
    const double dR = (a.T_world_camera.linear() - b.T_world_camera.linear()).cwiseAbs().maxCoeff();
    check(dR <= 1e-12, "tum.roundtrip", "rotation " + std::to_string(i) + " differs by " + std::to_string(dR));
  }
  return 0;
}
