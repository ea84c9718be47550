// Calibration files of other tools (loadCalibration: Kalibr camchain and sensor.yaml, EuRoC,
// OpenCV FileStorage, ROS camera_info, CamOdoCal, COLMAP, flat YAML/JSON). Built once per
// format family, each with its own seed corpus; the format is told by content. A loaded camera
// passes lensCamera() with a rigid mounting, and saveSequenceCamera then loadCalibration gives
// it back exactly; errors are one line naming the file.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/calibration.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

namespace {

Result<SequenceCamera> reload(const std::string& path) { return loadCalibration(path); }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("calibration.yaml");
  writeInput(path, data, size);
  // The first camera, and the second of files that hold several (Kalibr name, COLMAP id).
  for (const char* select : {"", "cam1", "2"}) {
    const auto loaded = loadCalibration(path, select);
    if (loaded.ok()) {
      checkCamera(*loaded, "calibration", reload);
    } else {
      checkErrorMessage(loaded.error(), path, "calibration");
    }
  }
  return 0;
}
