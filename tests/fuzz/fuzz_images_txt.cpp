// images.txt (loadImageList): a loaded list has increasing timestamps and non-empty paths, and
// saveImageList then loadImageList gives it back exactly.
#include <string>

#include "fuzz_common.hpp"
#include "vkloc/io/sequence.hpp"

using namespace vkloc;
using namespace vkloc::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::string path = scratchPath("images.txt");
  static const std::string saved = scratchPath("saved.txt");
  writeInput(path, data, size);
  const auto loaded = loadImageList(path);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, "images");
    return 0;
  }
  const std::vector<ImageEntry>& images = *loaded;
  for (size_t i = 0; i < images.size(); ++i) {
    check(!images[i].path.empty(), "images.path_not_empty", "entry " + std::to_string(i));
    check(i == 0 || images[i].t_ns > images[i - 1].t_ns, "images.increasing", "entry " + std::to_string(i));
  }
  // What the loader accepts, the saver writes (and the reverse trip is exact).
  const Status st = saveImageList(images, saved);
  check(st.ok(), "images.save_accepts_loaded", st.ok() ? "" : st.error().message);
  if (!st.ok()) return 0;
  const auto again = loadImageList(saved);
  check(again.ok(), "images.roundtrip", again.ok() ? "" : again.error().message);
  if (!again.ok()) return 0;
  check(again->size() == images.size(), "images.roundtrip", "entry count differs");
  for (size_t i = 0; i < std::min(images.size(), again->size()); ++i) {
    check(images[i].t_ns == (*again)[i].t_ns && images[i].path == (*again)[i].path, "images.roundtrip",
          "entry " + std::to_string(i) + " differs: " + images[i].path + " / " + (*again)[i].path);
  }
  return 0;
}
