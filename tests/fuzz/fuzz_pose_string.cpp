// Pose and number-list strings of the command line (parsePose for --pose and T_world_model,
// parseNumbers for --init-offset, --look-at, --intrinsics and the like): a parsed pose is rigid
// and formatPose then parsePose gives it back to formatPose's 9 digits; parsed numbers are
// finite; errors are one line naming the option.
#include <cstdio>
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/core/pose.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

namespace {

std::string shortNumber(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return buffer;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);

  const auto numbers = parseNumbers(text, "--opt", 0);
  if (numbers.ok()) {
    for (double v : *numbers) check(std::isfinite(v), "pose.numbers_finite", "non-finite number accepted");
  } else {
    checkErrorMessage(numbers.error(), "--opt", "pose");
  }

  const auto pose = parsePose(text);
  if (!pose.ok()) {
    checkErrorMessage(pose.error(), "pose", "pose");
    return 0;
  }
  check(isValidPose(*pose), "pose.valid", "parsePose returned a non-rigid transform");
  const std::string formatted = formatPose(*pose);
  const auto again = parsePose(formatted);
  check(again.ok(), "pose.roundtrip", again.ok() ? "" : again.error().message + " (" + formatted + ")");
  if (!again.ok()) return 0;
  // 9 significant digits: translations to 1e-8 relative, rotation entries to 1e-7. A matrix is
  // accepted up to 1e-6 from orthonormal (isValidPose) and kept as given, while formatPose writes
  // the nearest rotation: the rotation may also differ by that distance.
  for (int k = 0; k < 3; ++k) {
    check(nearRelative(pose->translation()[k], again->translation()[k], 1e-8), "pose.roundtrip",
          "translation differs: " + formatted);
  }
  const Eigen::Matrix3d& R = pose->linear();
  const double off_rotation = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double dR = (R - again->linear()).cwiseAbs().maxCoeff();
  check(dR <= 1e-7 + off_rotation, "pose.roundtrip",
        "rotation differs by " + shortNumber(dR) + " (input " + shortNumber(off_rotation) +
            " from orthonormal): " + formatted);
  return 0;
}
