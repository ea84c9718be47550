// imu.csv (loadImuCsv): loaded samples are finite with increasing timestamps, and saveImuCsv then
// loadImuCsv gives them back exactly.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/sequence.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("imu.csv");
  static const std::string saved = scratchPath("saved.csv");
  writeInput(path, data, size);
  const auto loaded = loadImuCsv(path);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, "imu");
    return 0;
  }
  const std::vector<ImuSample>& samples = *loaded;
  for (size_t i = 0; i < samples.size(); ++i) {
    check(samples[i].gyro_body.allFinite() && samples[i].accel_body.allFinite(), "imu.finite",
          "sample " + std::to_string(i));
    check(i == 0 || samples[i].t_ns > samples[i - 1].t_ns, "imu.increasing", "sample " + std::to_string(i));
  }
  const Status st = saveImuCsv(samples, saved);
  check(st.ok(), "imu.save_accepts_loaded", st.ok() ? "" : st.error().message);
  if (!st.ok()) return 0;
  const auto again = loadImuCsv(saved);
  check(again.ok(), "imu.roundtrip", again.ok() ? "" : again.error().message);
  if (!again.ok()) return 0;
  check(again->size() == samples.size(), "imu.roundtrip", "sample count differs");
  for (size_t i = 0; i < std::min(samples.size(), again->size()); ++i) {
    const ImuSample& a = samples[i];
    const ImuSample& b = (*again)[i];
    check(a.t_ns == b.t_ns && a.gyro_body == b.gyro_body && a.accel_body == b.accel_body, "imu.roundtrip",
          "sample " + std::to_string(i) + " differs");
  }
  return 0;
}
