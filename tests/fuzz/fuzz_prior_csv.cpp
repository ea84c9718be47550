// prior.csv (loadPriorCsv): loaded priors are finite with sigma > 0 and increasing timestamps,
// and savePriorCsv then loadPriorCsv gives them back exactly.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/sequence.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("prior.csv");
  static const std::string saved = scratchPath("saved.csv");
  writeInput(path, data, size);
  const auto loaded = loadPriorCsv(path);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, "prior");
    return 0;
  }
  const std::vector<PositionPrior>& priors = *loaded;
  for (size_t i = 0; i < priors.size(); ++i) {
    const PositionPrior& p = priors[i];
    check(p.p_world_body.allFinite() && p.sigma.allFinite() && p.sigma.minCoeff() > 0.0, "prior.valid",
          "prior " + std::to_string(i));
    check(i == 0 || p.t_ns > priors[i - 1].t_ns, "prior.increasing", "prior " + std::to_string(i));
  }
  const Status st = savePriorCsv(priors, saved);
  check(st.ok(), "prior.save_accepts_loaded", st.ok() ? "" : st.error().message);
  if (!st.ok()) return 0;
  const auto again = loadPriorCsv(saved);
  check(again.ok(), "prior.roundtrip", again.ok() ? "" : again.error().message);
  if (!again.ok()) return 0;
  check(again->size() == priors.size(), "prior.roundtrip", "prior count differs");
  for (size_t i = 0; i < std::min(priors.size(), again->size()); ++i) {
    const PositionPrior& a = priors[i];
    const PositionPrior& b = (*again)[i];
    check(a.t_ns == b.t_ns && a.p_world_body == b.p_world_body && a.sigma == b.sigma, "prior.roundtrip",
          "prior " + std::to_string(i) + " differs");
  }
  return 0;
}
