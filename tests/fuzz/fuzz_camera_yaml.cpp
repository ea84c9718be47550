// vkloc camera.yaml (loadSequenceCamera) and plain intrinsics files (loadCamera). A loaded
// camera passes lensCamera() with a rigid mounting, and saveSequenceCamera then
// loadSequenceCamera gives it back exactly; loadCamera's cameras pass validateCamera; errors
// are one line naming the file.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/core/camera.hpp"
#include "vkloc/io/calibration.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("camera.yaml");
  writeInput(path, data, size);
  const auto loaded = loadSequenceCamera(path);
  if (loaded.ok()) {
    checkCamera(*loaded, "camera", loadSequenceCamera);
  } else {
    checkErrorMessage(loaded.error(), path, "camera");
  }
  const auto plain = loadCamera(path);
  if (plain.ok()) {
    const Status valid = validateCamera(*plain);
    check(valid.ok(), "camera.plain_valid", valid.ok() ? "" : valid.error().message);
  } else {
    checkErrorMessage(plain.error(), path, "camera_plain");
  }
  return 0;
}
