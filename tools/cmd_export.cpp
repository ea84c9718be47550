// vkloc export: write a model (e.g. a built-in demo) to a file format others can open.
#include <cstdio>

#include "common.hpp"
#include "vkloc/model/model_write.hpp"

namespace vkloc::cli {

static void addExportVerb(CLI::App& app) {
  struct Args {
    ModelArgs model;
    std::string out;
    bool draco = false;
    int position_bits = 14;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("export", "Write a model (or a built-in demo) as .obj .ply .gltf .glb or .drc");
  args->model.add(*cmd);
  cmd->add_option("--out,-o", args->out, "Output file; the extension picks the format")->required();
  cmd->add_flag("--draco", args->draco, "Compress glTF/GLB primitives with KHR_draco_mesh_compression");
  cmd->add_option("--position-bits", args->position_bits, "Draco position quantization bits")->capture_default_str();
  cmd->callback([args] {
    const Model m = args->model.load();
    ModelWriteOptions options;
    options.draco = args->draco;
    options.draco_position_bits = args->position_bits;
    check(saveModel(m, args->out, options));
    std::printf("wrote %s: %zu triangles, %zu textures\n", args->out.c_str(), m.triangleCount(), m.textures.size());
  });
}

VKLOC_REGISTER_VERB(75, addExportVerb);

}  // namespace vkloc::cli
