// Model files through loadModel, built once per format (VKLOC_FUZZ_MODEL_EXT: ".obj", ".ply",
// ".gltf", ".glb", ".drc", ".cao"). A loaded model passes validateModel with finite bounds and
// at least one triangle, and its warnings are one line each; saveModel accepts it, loadModel
// accepts what saveModel wrote, and that keeps the triangle count and every corner position (sorted per axis; within
// one quantization step for Draco). .cao has no writer: parseCaoFile's geometry is checked instead (finite points,
// indices in range, faces of >= 3 points). Errors are one line naming the file.
//
// The scratch folder also holds fuzz.mtl, fuzz.png (a 2x2 RGBA image) and part.cao (a triangle)
// so that inputs can reference a material library, a texture and a .cao part by those names.
#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_common.hpp"
#include "vkloc/model/cao.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/model/model_write.hpp"

#ifndef VKLOC_FUZZ_MODEL_EXT
#error "define VKLOC_FUZZ_MODEL_EXT"
#endif

using namespace vkloc;
using namespace vkloc::fuzz;

namespace {

constexpr const char* kExt = VKLOC_FUZZ_MODEL_EXT;
const std::string kTarget = std::string("model_") + (kExt + 1);

// 2x2 RGBA PNG.
constexpr uint8_t kPng[] = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00,
    0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x06, 0x00, 0x00, 0x00, 0x72, 0xb6, 0x0d, 0x24, 0x00, 0x00, 0x00, 0x13, 0x49,
    0x44, 0x41, 0x54, 0x78, 0xda, 0x63, 0xf8, 0xcf, 0xc0, 0xf0, 0x1f, 0x0c, 0x81, 0x34, 0x08, 0x34, 0x00, 0x00, 0x49,
    0x49, 0x09, 0x78, 0x9c, 0x51, 0x17, 0x92, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
constexpr const char* kMtl = "newmtl textured\nKd 1 1 1\nmap_Kd fuzz.png\n\nnewmtl red\nKd 0.8 0.1 0.1\nd 0.5\n";
constexpr const char* kPartCao = "V1\n3\n0 0 0\n1 0 0\n0 0 1\n0\n0\n1\n3 0 1 2\n";

void prepareScratch() {
  static const bool done = [] {
    writeInput(scratchPath("fuzz.png"), kPng, sizeof kPng);
    writeInput(scratchPath("fuzz.mtl"), kMtl);
    writeInput(scratchPath("part.cao"), kPartCao);
    return true;
  }();
  (void)done;
}

/// Every triangle corner's coordinate on axis `a`, sorted.
std::vector<float> cornerCoordinates(const Model& m, int a) {
  std::vector<float> v;
  v.reserve(m.indices.size());
  for (uint32_t i : m.indices) v.push_back(m.positions[3 * size_t{i} + a]);
  std::sort(v.begin(), v.end());
  return v;
}

void checkRoundTrip(const Model& model) {
  const std::string saved = scratchPath(std::string("saved") + kExt);
  Status st = saveModel(model, saved);
  if (!st.ok() && std::string_view(kExt) == ".drc" && st.error().code == ErrorCode::kInvalidArgument) {
    // Draco refuses, with its reason, a model whose coordinates span more than a float holds
    // (its quantization range overflows) or one its quantization collapses (load would refuse
    // the file): triangles tiny against the bounds. 24 bits (the most) may still not hold it.
    if (st.error().message.find("more than a float holds") != std::string::npos) return;
    check(st.error().message.find("collapses every triangle") != std::string::npos,
          (kTarget + ".save_refusal_explained").c_str(), st.error().message);
    ModelWriteOptions fine;
    fine.draco_position_bits = 24;
    st = saveModel(model, saved, fine);
    if (!st.ok() && st.error().message.find("collapses every triangle") != std::string::npos) return;
  }
  check(st.ok(), (kTarget + ".save_accepts_loaded").c_str(), st.ok() ? "" : st.error().message);
  if (!st.ok()) return;
  const auto again = loadModel(saved);
  check(again.ok(), (kTarget + ".save_unloadable").c_str(),
        again.ok() ? "" : "saveModel wrote a file loadModel refuses: " + again.error().message);
  if (!again.ok()) return;
  check(
      again->triangleCount() == model.triangleCount(), (kTarget + ".roundtrip").c_str(),
      "triangle count " + std::to_string(model.triangleCount()) + " became " + std::to_string(again->triangleCount()));
  if (again->triangleCount() != model.triangleCount()) return;
  // Draco quantizes positions to 14 bits over the largest extent (ModelWriteOptions).
  double step = 0.0;
  if (std::string(kExt) == ".drc") {
    for (int a = 0; a < 3; ++a) step = std::max(step, double(model.bounds.max[a]) - model.bounds.min[a]);
    step = step / std::ldexp(1.0, ModelWriteOptions{}.draco_position_bits);
  }
  for (int a = 0; a < 3; ++a) {
    const std::vector<float> x = cornerCoordinates(model, a), y = cornerCoordinates(*again, a);
    for (size_t i = 0; i < x.size(); ++i) {
      const bool near = std::abs(double(x[i]) - y[i]) <= step + 1e-6 * std::max(1.0, std::abs(double(x[i])));
      check(near, (kTarget + ".roundtrip").c_str(),
            "corner coordinate " + std::to_string(x[i]) + " became " + std::to_string(y[i]));
      if (!near) return;
    }
  }
}

void checkCao(const std::string& path) {
  const auto cao = parseCaoFile(path);
  if (!cao.ok()) {
    checkErrorMessage(cao.error(), path, kTarget.c_str());
    return;
  }
  const std::string id = kTarget + ".geometry";
  const size_t n = cao->points.size();
  for (const auto& p : cao->points) check(p.allFinite(), id.c_str(), "non-finite point");
  for (const auto& s : cao->segments) check(s[0] < n && s[1] < n, id.c_str(), "segment index out of range");
  for (const auto& f : cao->faces) {
    check(f.size() >= 3, id.c_str(), "face with fewer than 3 points");
    for (uint32_t i : f) check(i < n, id.c_str(), "face index out of range");
  }
  check(cao->face_names.size() == cao->faces.size(), id.c_str(), "face_names and faces differ in count");
  for (const auto& f : cao->extra_faces) {
    check(f.size() % 3 == 0, id.c_str(), "extra face is not triangles");
    for (uint32_t i : f) check(i < n, id.c_str(), "extra face index out of range");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  prepareScratch();
  static const std::string path = scratchPath(std::string("input") + kExt);
  writeInput(path, data, size);
  std::vector<std::string> warnings;
  const auto loaded = loadModel(path, {}, &warnings);
  for (const std::string& w : warnings) {
    check(noControlCharacters(w), (kTarget + ".warning_one_line").c_str(), "warning: " + w);
  }
  if (std::string(kExt) == ".cao") checkCao(path);
  if (!loaded.ok()) {
    checkErrorMessage(loaded.error(), path, kTarget.c_str());
    return 0;
  }
  const Model& m = *loaded;
  const Status valid = validateModel(m);
  check(valid.ok(), (kTarget + ".valid").c_str(), valid.ok() ? "" : valid.error().message);
  check(m.triangleCount() > 0, (kTarget + ".valid").c_str(), "no triangles");
  for (int a = 0; a < 3; ++a) {
    check(std::isfinite(m.bounds.min[a]) && std::isfinite(m.bounds.max[a]) && m.bounds.min[a] <= m.bounds.max[a],
          (kTarget + ".valid").c_str(), "bounds are not finite");
  }
  if (valid.ok() && std::string(kExt) != ".cao") checkRoundTrip(m);
  return 0;
}
