// vkloc info: what a model contains.
#include <algorithm>
#include <cstdio>

#include "common.hpp"

namespace vkloc::cli {

static void addInfoVerb(CLI::App& app) {
  auto args = std::make_shared<ModelArgs>();
  auto list_blocks = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("info", "Print a model's triangles, textures, bounds and blocks");
  args->add(*cmd);
  cmd->add_flag("--blocks", *list_blocks, "List every block");
  cmd->callback([args, list_blocks] {
    const auto t0 = std::chrono::steady_clock::now();
    const Model m = args->load();
    const double ms = msSince(t0);
    std::printf("model:      %s (loaded in %.1f ms)\n", m.source.c_str(), ms);
    std::printf("triangles:  %zu\nvertices:   %zu (uv: %s, colours: %s)\n", m.triangleCount(), m.vertexCount(),
                m.uvs.empty() ? "no" : "yes", m.colors.empty() ? "no" : "yes");
    std::printf("bounds:     [%.3f %.3f %.3f] .. [%.3f %.3f %.3f] m (size %.3f x %.3f x %.3f)\n", m.bounds.min[0],
                m.bounds.min[1], m.bounds.min[2], m.bounds.max[0], m.bounds.max[1], m.bounds.max[2],
                m.bounds.max[0] - m.bounds.min[0], m.bounds.max[1] - m.bounds.min[1],
                m.bounds.max[2] - m.bounds.min[2]);
    std::printf("materials:  %zu\n", m.materials.size());
    for (size_t i = 0; i < m.materials.size(); ++i) {
      const Material& mat = m.materials[i];
      std::printf("  [%zu] %-24s colour (%.2f %.2f %.2f %.2f) texture %d\n", i, mat.name.c_str(), mat.base_color[0],
                  mat.base_color[1], mat.base_color[2], mat.base_color[3], mat.texture);
    }
    size_t tex_bytes = 0;
    for (const auto& t : m.textures) tex_bytes += t.rgba.size();
    std::printf("textures:   %zu (%.1f MiB)\n", m.textures.size(), tex_bytes / 1048576.0);
    for (size_t i = 0; i < m.textures.size(); ++i) {
      std::printf("  [%zu] %dx%d %s\n", i, m.textures[i].width, m.textures[i].height, m.textures[i].name.c_str());
    }
    uint32_t lo = UINT32_MAX, hi = 0;
    for (const auto& b : m.blocks) {
      lo = std::min(lo, b.triangle_count);
      hi = std::max(hi, b.triangle_count);
    }
    std::printf("blocks:     %zu (triangles per block %u..%u), draw ranges %zu\n", m.blocks.size(),
                m.blocks.empty() ? 0 : lo, hi, m.ranges.size());
    if (*list_blocks) {
      for (size_t i = 0; i < m.blocks.size(); ++i) {
        const Block& b = m.blocks[i];
        std::printf("  [%zu] %u triangles, [%.2f %.2f %.2f] .. [%.2f %.2f %.2f]\n", i, b.triangle_count,
                    b.bounds.min[0], b.bounds.min[1], b.bounds.min[2], b.bounds.max[0], b.bounds.max[1],
                    b.bounds.max[2]);
      }
    }
  });
}

VKLOC_REGISTER_VERB(70, addInfoVerb);

}  // namespace vkloc::cli
