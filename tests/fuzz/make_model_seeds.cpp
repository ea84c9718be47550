// Writes the binary and glTF seed files of the model fuzz targets (corpus/model_*): a coloured
// cube and a textured quad with two materials, saved by saveModel in every format.
// Usage: vkloc_fuzz_model_seeds <folder>
#include <cstdio>
#include <string>

#include "vkloc/model/model.hpp"
#include "vkloc/model/model_write.hpp"

using namespace vkloc;

namespace {

Model seedModel() {
  Model m;
  m.source = "seed";
  for (int i = 0; i < 8; ++i) {
    m.positions.insert(m.positions.end(), {float(i & 1), float((i >> 1) & 1), float(i >> 2)});
    m.uvs.insert(m.uvs.end(), {float(i & 1), float((i >> 1) & 1)});
    m.colors.insert(m.colors.end(), {uint8_t(30 * i), uint8_t(255 - 20 * i), uint8_t(7 * i), 255});
  }
  const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
  m.textures.push_back(Texture{"checker", 2, 2, {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 128}});
  m.materials.push_back(Material{"textured", {1, 1, 1, 1}, 0});
  m.materials.push_back(Material{"paint", {0.8f, 0.1f, 0.1f, 0.5f}, -1});
  m.ranges.push_back(DrawRange{0, 12, 0});
  m.ranges.push_back(DrawRange{12, 24, 1});
  buildBlocks(m, 32768);
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <folder>\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const Model m = seedModel();
  ModelWriteOptions draco;
  draco.draco = true;
  const std::pair<std::string, ModelWriteOptions> files[] = {
      {"cube.obj", {}}, {"cube.ply", {}},     {"cube.gltf", {}},    {"cube.glb", {}},
      {"cube.drc", {}}, {"draco.glb", draco}, {"draco.gltf", draco}};
  for (const auto& [name, options] : files) {
    const Status st = saveModel(m, dir + "/" + name, options);
    if (!st.ok()) {
      std::fprintf(stderr, "%s\n", st.error().message.c_str());
      return 1;
    }
  }
  return 0;
}
